//! Grid to particle, MUSL: FLIP velocity update, momentum re-mapping, strain and stress update,
//! volume and position update (DESIGN §4, step 3).

use crate::grid::Grid;
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
