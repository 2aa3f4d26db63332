//! Anura3D's absorbing boundaries (GOM input, docs/design.md §4.9): per boundary node and axis a
//! dashpot c and a spring k ([`crate::input`] resolves them from the GOM's rows as Anura3D
//! does), whose force is accumulated and one step behind,
//!
//!   F ← F + k ΔU + c a Δt,
//!
//! ΔU and a the last step's displacement increment and acceleration, Δt this step's. At the
//! start of the grid update's solution F is subtracted from the node's force: a single-phase
//! node's acceleration loses F / m; at a node with liquid, the liquid's F_w comes off the
//! liquid's equation and F_s + F_w off the mixture's, solved with the same two-by-two system
//! the grid update solved. A node outside the filled elements (no mass) drops its force.
//!
//! ΔU and a are Anura3D's choice (`$$APPLY_NODE_DATA_AB`):
//!
//! - 1: the node's own, v Δt with v its re-mapped velocity, and its acceleration;
//! - 0 (the default): sums over the points of the elements around the node, Σ_p N_i(x_p) ΔU_p
//!   and Σ_p N_i(x_p) a_p, each point's ΔU_p and a_p interpolated from the nodes at its position
//!   before it moved, the sums taken with its shape values after it moved. The sums are not
//!   normalised (a node with four points around it takes about four times its own motion): that
//!   is Anura3D's rule, kept for the point-by-point match.
//!
//! The liquid always takes its node's own motion. Fixed components keep a = 0. The work is over
//! the boundary's nodes in node order on the calling thread (and, with point sums, over the
//! points: one pass in the re-mapping's hook to form each point's ΔU_p and a_p, one over the
//! boundary's elements' points in the grid update's hook), so it is the same for any thread
//! count.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};
use crate::step::absorbing::AbsorbingNode;
use crate::step::constraint::{Constraint, Hook};

/// What a boundary node saw in the last step: the solid's acceleration and re-mapped velocity,
/// the liquid's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Last {
    a: [f64; 3],
    v: [f64; 3],
    a_w: [f64; 3],
    w: [f64; 3],
}

/// Anura3D's absorbing boundary on the computational nodes.
#[derive(Debug, Clone)]
pub struct AbsorbingAnura3d {
    /// ΔU and a from sums over the points (else from the nodes).
    point_sums: bool,
    /// The boundary's computational nodes, in node order.
    nodes: Vec<u32>,
    /// Per computational node, its place in `nodes` (`u32::MAX`: none).
    slot: Vec<u32>,
    /// Per boundary node and axis: the solid's dashpot and spring, the liquid's.
    dashpot: Vec<[f64; 3]>,
    spring: Vec<[f64; 3]>,
    liquid_dashpot: Vec<[f64; 3]>,
    liquid_spring: Vec<[f64; 3]>,
    /// The accumulated forces, solid and liquid.
    force: Vec<[f64; 3]>,
    liquid_force: Vec<[f64; 3]>,
    /// The last step's motion of each boundary node, and that step's length.
    last: Vec<Last>,
    last_dt: f64,
    /// The elements that have a boundary node (point sums).
    elements: Vec<u32>,
    /// Per point, its last step's acceleration and displacement increment (point sums).
    per_point: Vec<[f64; 6]>,
}

impl AbsorbingAnura3d {
    /// The boundary of `rows` (diagonal dashpots and springs; model nodes mapped by
    /// `node_of_model`, those that are not computational nodes left out) on `mesh`, for a run of
    /// `points` points.
    pub fn new<E: Element, R: Real>(
        rows: &[AbsorbingNode],
        point_sums: bool,
        mesh: &Mesh<E, R>,
        points: usize,
    ) -> Self {
        let mut slot = vec![u32::MAX; mesh.nodes()];
        let mut kept = Vec::new();
        for r in rows {
            let Some(&n) = mesh.node_of_model.get(r.node as usize) else {
                continue;
            };
            if n != u32::MAX && slot[n as usize] == u32::MAX {
                slot[n as usize] = 0;
                kept.push((n, r));
            }
        }
        kept.sort_by_key(|(n, _)| *n);
        for (k, (n, _)) in kept.iter().enumerate() {
            slot[*n as usize] = k as u32;
        }
        let diagonal = |s: &[f64; 6]| [s[0], s[1], s[2]];
        let elements = (0..mesh.elements() as u32)
            .filter(|&e| {
                mesh.corners[e as usize]
                    .as_ref()
                    .iter()
                    .any(|&c| slot[c as usize] != u32::MAX)
            })
            .collect();
        let n = kept.len();
        AbsorbingAnura3d {
            point_sums,
            nodes: kept.iter().map(|(n, _)| *n).collect(),
            slot,
            dashpot: kept.iter().map(|(_, r)| diagonal(&r.dashpot)).collect(),
            spring: kept.iter().map(|(_, r)| diagonal(&r.spring)).collect(),
            liquid_dashpot: kept.iter().map(|(_, r)| r.liquid_dashpot).collect(),
            liquid_spring: kept.iter().map(|(_, r)| r.liquid_spring).collect(),
            force: vec![[0.0; 3]; n],
            liquid_force: vec![[0.0; 3]; n],
            last: vec![Last::default(); n],
            last_dt: 0.0,
            elements,
            per_point: if point_sums {
                vec![[0.0; 6]; points]
            } else {
                Vec::new()
            },
        }
    }

    /// Per boundary node, Σ_p N_i(x_p) (a_p, ΔU_p) over the points of the boundary's elements
    /// at their present positions.
    fn point_sums<E: Element, R: Real>(&self, cx: &Hook<'_, R, E>) -> Vec<[f64; 6]> {
        let (mesh, p) = (&*cx.mesh, &*cx.particles);
        let mut sums = vec![[0.0; 6]; self.nodes.len()];
        for &e in &self.elements {
            let e = e as usize;
            let corners = mesh.corners[e].as_ref();
            let first = &mesh.x[corners[0] as usize];
            for i in cx.layout.particles_of(e) {
                if !p.active[i] {
                    continue;
                }
                let n = E::shape(&mesh.map[e], first, &p.x[i]);
                for (k, &c) in corners.iter().enumerate() {
                    let s = self.slot[c as usize];
                    if s == u32::MAX {
                        continue;
                    }
                    let nk = n.as_ref()[k].f64();
                    for (sum, v) in sums[s as usize].iter_mut().zip(&self.per_point[i]) {
                        *sum += nk * v;
                    }
                }
            }
        }
        sums
    }

    /// Each point's acceleration and displacement increment of this step, from the nodes at
    /// its position before it moves.
    fn take_points<E: Element, R: Real>(&mut self, cx: &Hook<'_, R, E>, dt: f64) {
        let (mesh, p, g) = (&*cx.mesh, &*cx.particles, &*cx.soil);
        self.per_point.resize(p.len(), [0.0; 6]);
        for (i, out) in self.per_point.iter_mut().enumerate() {
            if !p.active[i] {
                continue;
            }
            let e = p.element[i] as usize;
            let corners = mesh.corners[e].as_ref();
            let n = E::shape(&mesh.map[e], &mesh.x[corners[0] as usize], &p.x[i]);
            *out = [0.0; 6];
            for (k, &c) in corners.iter().enumerate() {
                let (nk, c) = (n.as_ref()[k].f64(), c as usize);
                for d in 0..E::DIM {
                    out[d] += nk * g.acc[c][d].f64();
                    out[3 + d] += nk * (g.vel[c][d].f64() * dt);
                }
            }
        }
    }
}

/// Δa solving [[m_s, m̄_w], [−q, m_w + q]] Δa = rhs for (solid, liquid), a fixed component's
/// row and column dropped (its Δa 0).
fn two_phase(m: (f64, f64, f64), q: f64, rhs: [f64; 2], fixed: (bool, bool)) -> [f64; 2] {
    let (ms, mw, mwn) = m;
    match fixed {
        (true, true) => [0.0, 0.0],
        (true, false) => [0.0, rhs[1] / (mw + q)],
        (false, true) => [rhs[0] / ms, 0.0],
        (false, false) => {
            let det = ms * (mw + q) + mwn * q;
            [
                (rhs[0] * (mw + q) - mwn * rhs[1]) / det,
                (ms * rhs[1] + q * rhs[0]) / det,
            ]
        }
    }
}

/// `v` of a nodal array as f64.
fn f64s<R: Real>(v: &V3<R>) -> [f64; 3] {
    v.map(|c| c.f64())
}

impl<R: Real, E: Element> Constraint<R, E> for AbsorbingAnura3d {
    fn name(&self) -> &'static str {
        "absorbing boundary (Anura3D)"
    }

    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        let dt = cx.at.dt;
        let sums = if self.point_sums {
            self.point_sums(cx)
        } else {
            Vec::new()
        };
        let implicit = cx.at.drag == crate::step::grid_update::Drag::Implicit;
        let g = &mut *cx.soil;
        let eps = g.empty_below.f64();
        for (s, &n) in self.nodes.iter().enumerate() {
            let n = n as usize;
            let m = g.mass[n].f64();
            if m <= eps {
                // Outside the filled elements: Anura3D drops the force.
                self.force[s] = [0.0; 3];
                self.liquid_force[s] = [0.0; 3];
                continue;
            }
            let last = &self.last[s];
            let (du, a) = if self.point_sums {
                let t = &sums[s];
                ([t[3], t[4], t[5]], [t[0], t[1], t[2]])
            } else {
                (last.v.map(|v| v * self.last_dt), last.a)
            };
            let (f, fw) = (&mut self.force[s], &mut self.liquid_force[s]);
            for d in 0..E::DIM {
                // Anura3D's order of operations: (k ΔU) + ((c a) Δt).
                f[d] += self.spring[s][d] * du[d] + self.dashpot[s][d] * a[d] * dt;
                fw[d] += self.liquid_spring[s][d] * (last.w[d] * self.last_dt)
                    + self.liquid_dashpot[s][d] * last.a_w[d] * dt;
            }
            let liquid = g.liquid.as_mut().filter(|l| l.mass[n].f64() > eps);
            match liquid {
                None => {
                    for d in (0..E::DIM).filter(|&d| !cx.fixed[n][d]) {
                        g.acc[n][d] = R::of(g.acc[n][d].f64() - f[d] / m);
                    }
                }
                Some(l) => {
                    let masses = (m, l.mass[n].f64(), l.mass_n[n].f64());
                    let q = if implicit { l.drag[n].f64() * dt } else { 0.0 };
                    for d in 0..E::DIM {
                        let fixed = (cx.fixed[n][d], cx.liquid_fixed[n][d]);
                        let da = two_phase(masses, q, [-(f[d] + fw[d]), -fw[d]], fixed);
                        g.acc[n][d] = R::of(g.acc[n][d].f64() + da[0]);
                        l.acc[n][d] = R::of(l.acc[n][d].f64() + da[1]);
                    }
                }
            }
        }
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        let dt = cx.at.dt;
        let g = &*cx.soil;
        for (s, &n) in self.nodes.iter().enumerate() {
            let n = n as usize;
            let l = g.liquid.as_ref();
            self.last[s] = Last {
                a: f64s(&g.acc[n]),
                v: f64s(&g.vel[n]),
                a_w: l.map_or([0.0; 3], |l| f64s(&l.acc[n])),
                w: l.map_or([0.0; 3], |l| f64s(&l.vel[n])),
            };
        }
        self.last_dt = dt;
        if self.point_sums {
            self.take_points(cx, dt);
        }
    }

    fn holds_points(&self) -> bool {
        self.point_sums
    }

    fn follow(&mut self, new_of_old: &[u32]) {
        if self.per_point.is_empty() {
            return;
        }
        let mut moved = vec![[0.0; 6]; self.per_point.len()];
        for (old, &new) in new_of_old.iter().enumerate() {
            // (A point a restored checkpoint does not hold maps nowhere; the restore refuses
            // the file.)
            if let (Some(to), Some(&v)) = (moved.get_mut(new as usize), self.per_point.get(old)) {
                *to = v;
            }
        }
        self.per_point = moved;
    }

    fn saved(&self) -> Vec<f64> {
        let mut out = vec![self.last_dt];
        for s in 0..self.nodes.len() {
            let l = &self.last[s];
            for v in [self.force[s], self.liquid_force[s], l.a, l.v, l.a_w, l.w] {
                out.extend(v);
            }
        }
        out.extend(self.per_point.iter().flatten());
        out
    }

    fn restore(&mut self, _mesh: &mut Mesh<E, R>, state: &[f64]) -> bool {
        let n = self.nodes.len();
        if state.len() != 1 + 18 * n + 6 * self.per_point.len() {
            return false;
        }
        self.last_dt = state[0];
        let three = |k: usize| [state[k], state[k + 1], state[k + 2]];
        for s in 0..n {
            let at = 1 + 18 * s;
            self.force[s] = three(at);
            self.liquid_force[s] = three(at + 3);
            self.last[s] = Last {
                a: three(at + 6),
                v: three(at + 9),
                a_w: three(at + 12),
                w: three(at + 15),
            };
        }
        for (p, c) in self
            .per_point
            .iter_mut()
            .zip(state[1 + 18 * n..].chunks_exact(6))
        {
            p.copy_from_slice(c);
        }
        true
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-by-two solution satisfies both rows, and fixed components drop out.
    #[test]
    fn the_two_phase_correction_solves_both_rows() {
        let (ms, mw, mwn, q) = (2.0, 0.5, 0.2, 0.3);
        let rhs = [-1.5, -0.25];
        let [das, daw] = two_phase((ms, mw, mwn), q, rhs, (false, false));
        assert!((ms * das + mwn * daw - rhs[0]).abs() < 1e-15);
        assert!((-q * das + (mw + q) * daw - rhs[1]).abs() < 1e-15);
        assert_eq!(two_phase((ms, mw, mwn), q, rhs, (true, true)), [0.0, 0.0]);
        assert_eq!(
            two_phase((ms, mw, mwn), q, rhs, (true, false)),
            [0.0, rhs[1] / (mw + q)]
        );
        assert_eq!(
            two_phase((ms, mw, mwn), q, rhs, (false, true)),
            [rhs[0] / ms, 0.0]
        );
        // Explicit drag (q = 0): the liquid row alone gives the liquid's.
        let [das, daw] = two_phase((ms, mw, mwn), 0.0, rhs, (false, false));
        assert!((daw - rhs[1] / mw).abs() < 1e-15);
        assert!((das - (rhs[0] - mwn * daw) / ms).abs() < 1e-15);
    }
}
