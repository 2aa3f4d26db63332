//! Particle to grid: lumped masses, momentum, internal and gravity forces (DESIGN §4, step 1).

use crate::grid::Grid;
use crate::liquid::Fluid;
use crate::mesh::TetMesh;
use crate::mixed::Mixed;
use crate::particles::Particles;
use crate::real::{Real, V3};

/// Maps every active particle to the nodes of its element. `gravity` is the acceleration vector
/// with the current load multiplier applied. Under mixed integration the internal force of full
/// elements comes from their Gauss point instead of their points.
pub fn particle_to_grid<R: Real>(
    mesh: &TetMesh<R>,
    p: &Particles<R>,
    gravity: V3<R>,
    mixed: Option<&Mixed<R>>,
    g: &mut Grid<R>,
) {
    let z = [R::ZERO; 3];
    g.mass.fill(R::ZERO);
    g.momentum.fill(z);
    g.f_int.fill(z);
    g.f_ext.fill(z);
    for i in 0..p.len() {
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let grad = &mesh.grad[e];
        let (m, v) = (p.mass[i], p.v[i]);
        // A full element's points carry no effective-stress force of their own (see below).
        let vol = match mixed {
            Some(mx) if mx.full[e] => R::ZERO,
            _ => p.volume[i],
        };
        // Total stress V σ' + V p I (pore pressure p only where the liquid is modelled).
        let mut s = p.stress[i].map(|c| vol * c);
        if let Some(l) = &p.liquid {
            let vp = p.volume[i] * l.p[i];
            s[0] += vp;
            s[1] += vp;
            s[2] += vp;
        }
        for k in 0..4 {
            let node = mesh.corners[e][k] as usize;
            let w = m * n[k];
            g.mass[node] += w;
            let dn = grad[k];
            // f_int = -V σ ∇N (σ symmetric: xx yy zz xy yz zx).
            let f = [
                s[0] * dn[0] + s[3] * dn[1] + s[5] * dn[2],
                s[3] * dn[0] + s[1] * dn[1] + s[4] * dn[2],
                s[5] * dn[0] + s[4] * dn[1] + s[2] * dn[2],
            ];
            for a in 0..3 {
                g.momentum[node][a] += w * v[a];
                g.f_int[node][a] -= f[a];
                g.f_ext[node][a] += w * gravity[a];
            }
        }
    }
    if let Some(mx) = mixed {
        mx.internal_forces(mesh, g);
    }
}

/// Adds the face loads carried by points, `scale` times their force, at the points' positions.
pub fn add_point_loads<R: Real>(
    mesh: &TetMesh<R>,
    p: &Particles<R>,
    loads: &[(u32, V3<R>)],
    scale: R,
    g: &mut Grid<R>,
) {
    for &(i, f) in loads {
        let i = i as usize;
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        for k in 0..4 {
            let node = mesh.corners[e][k] as usize;
            for a in 0..3 {
                g.f_ext[node][a] += n[k] * scale * f[a];
            }
        }
    }
}

/// The liquid's share of particle to grid (two-phase, DESIGN §4): liquid masses M_w and M̄_w,
/// drag Q, liquid momentum, the liquid force -Σ V p ∇N + M_w g, and the liquid's weight added to
/// the mixture's external force. Points of dry materials (`fluids[m]` is `None`) add nothing.
pub fn liquid_to_grid<R: Real>(
    mesh: &TetMesh<R>,
    p: &Particles<R>,
    fluids: &[Option<Fluid<R>>],
    gravity: V3<R>,
    g: &mut Grid<R>,
) {
    let (Some(lp), Some(gl)) = (&p.liquid, &mut g.liquid) else {
        return;
    };
    let z = [R::ZERO; 3];
    gl.mass.fill(R::ZERO);
    gl.mass_n.fill(R::ZERO);
    gl.drag.fill(R::ZERO);
    gl.momentum.fill(z);
    gl.force.fill(z);
    for i in 0..p.len() {
        let Some(f) = fluids[p.material[i] as usize] else {
            continue;
        };
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let grad = &mesh.grad[e];
        let vol = p.volume[i];
        let mw = f.rho_w * vol;
        let (pw, w) = (lp.p[i] * vol, lp.w[i]);
        for k in 0..4 {
            let node = mesh.corners[e][k] as usize;
            let nk = n[k];
            gl.mass[node] += mw * nk;
            gl.mass_n[node] += f.n * mw * nk;
            gl.drag[node] += f.drag * vol * nk;
            for a in 0..3 {
                gl.momentum[node][a] += mw * nk * w[a];
                gl.force[node][a] += mw * nk * gravity[a] - pw * grad[k][a];
                g.f_ext[node][a] += f.n * mw * nk * gravity[a];
            }
        }
    }
}
