//! Particle to grid: lumped masses, momentum, internal and gravity forces (DESIGN §4, step 1).

use crate::grid::Grid;
use crate::mesh::TetMesh;
use crate::particles::Particles;
use crate::real::{Real, V3};

/// Maps every active particle to the nodes of its element. `gravity` is the acceleration vector
/// with the current load multiplier applied.
pub fn particle_to_grid<R: Real>(
    mesh: &TetMesh<R>,
    p: &Particles<R>,
    gravity: V3<R>,
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
        let (m, vol, v, s) = (p.mass[i], p.volume[i], p.v[i], p.stress[i]);
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
                g.f_int[node][a] -= vol * f[a];
                g.f_ext[node][a] += w * gravity[a];
            }
        }
    }
}
