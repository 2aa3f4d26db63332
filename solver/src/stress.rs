//! Strain increments from nodal velocities, the constitutive update, and the volume and position
//! update of every particle.

use crate::grid::Grid;
use crate::linear_elastic::LinearElastic;
use crate::mesh::TetMesh;
use crate::particles::Particles;
use crate::real::Real;

/// Δε = sym(Σ v_n ⊗ ∇N_n) Δt; σ += D Δε; V *= 1 + tr Δε; x += Δt Σ N_n v_n.
pub fn update_stress_and_move<R: Real>(
    mesh: &TetMesh<R>,
    p: &mut Particles<R>,
    g: &Grid<R>,
    laws: &[LinearElastic<R>],
    dt: R,
) {
    let half = R::of(0.5);
    for i in 0..p.len() {
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let grad = &mesh.grad[e];
        let mut l = [[R::ZERO; 3]; 3]; // velocity gradient L[a][b] = ∂v_a/∂x_b
        let mut dx = [R::ZERO; 3];
        for k in 0..4 {
            let v = g.vel[mesh.corners[e][k] as usize];
            for a in 0..3 {
                dx[a] += n[k] * v[a];
                for b in 0..3 {
                    l[a][b] += v[a] * grad[k][b];
                }
            }
        }
        let de = [
            l[0][0] * dt,
            l[1][1] * dt,
            l[2][2] * dt,
            half * (l[0][1] + l[1][0]) * dt,
            half * (l[1][2] + l[2][1]) * dt,
            half * (l[2][0] + l[0][2]) * dt,
        ];
        laws[p.material[i] as usize].update(&mut p.stress[i], &de);
        p.volume[i] *= R::ONE + de[0] + de[1] + de[2];
        for a in 0..3 {
            p.x[i][a] += dt * dx[a];
            p.u[i][a] += dt * dx[a];
        }
    }
}
