//! Grid to particle, MUSL: FLIP velocity update, momentum re-mapping, strain and stress update,
//! volume and position update (DESIGN §4, step 3).

use crate::grid::Grid;
use crate::liquid::Fluid;
use crate::mesh::TetMesh;
use crate::particles::Particles;
use crate::real::Real;

/// Updates particle velocities from nodal accelerations (FLIP), then re-maps momentum to get
/// the nodal velocities (fixed components zero) that drive strain, stress, volume and position
/// (see [`crate::stress`]).
pub fn grid_to_particle<R: Real>(
    mesh: &TetMesh<R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fixed: &[[bool; 3]],
    dt: R,
) {
    // FLIP velocity update, and the momentum of the new velocities.
    g.momentum.fill([R::ZERO; 3]);
    for i in 0..p.len() {
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let mut dv = [R::ZERO; 3];
        for k in 0..4 {
            let a = g.acc[mesh.corners[e][k] as usize];
            for c in 0..3 {
                dv[c] += n[k] * a[c];
            }
        }
        for c in 0..3 {
            p.v[i][c] += dt * dv[c];
        }
        for k in 0..4 {
            let node = mesh.corners[e][k] as usize;
            let w = p.mass[i] * n[k];
            for c in 0..3 {
                g.momentum[node][c] += w * p.v[i][c];
            }
        }
    }
    let eps = g.empty_below;
    for n in 0..g.mass.len() {
        for c in 0..3 {
            g.vel[n][c] = if g.mass[n] <= eps || fixed[n][c] {
                R::ZERO
            } else {
                g.momentum[n][c] / g.mass[n]
            };
        }
    }
}

/// The liquid's share of grid to particle: liquid velocities of the points updated from the
/// nodal liquid accelerations (FLIP), then the liquid momentum re-mapped to nodal liquid
/// velocities (zero in fixed components and at nodes without liquid).
pub fn liquid_to_particles<R: Real>(
    mesh: &TetMesh<R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fluids: &[Option<Fluid<R>>],
    liquid_fixed: &[[bool; 3]],
    dt: R,
) {
    let (Some(lp), Some(gl)) = (&mut p.liquid, &mut g.liquid) else {
        return;
    };
    gl.momentum.fill([R::ZERO; 3]);
    for i in 0..p.x.len() {
        let Some(f) = fluids[p.material[i] as usize] else {
            continue;
        };
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let mut dw = [R::ZERO; 3];
        for k in 0..4 {
            let a = gl.acc[mesh.corners[e][k] as usize];
            for c in 0..3 {
                dw[c] += n[k] * a[c];
            }
        }
        for c in 0..3 {
            lp.w[i][c] += dt * dw[c];
        }
        let mw = f.rho_w * p.volume[i];
        for k in 0..4 {
            let node = mesh.corners[e][k] as usize;
            for c in 0..3 {
                gl.momentum[node][c] += mw * n[k] * lp.w[i][c];
            }
        }
    }
    let eps = g.empty_below;
    for n in 0..gl.mass.len() {
        for c in 0..3 {
            gl.vel[n][c] = if gl.mass[n] <= eps || liquid_fixed[n][c] {
                R::ZERO
            } else {
                gl.momentum[n][c] / gl.mass[n]
            };
        }
    }
}
