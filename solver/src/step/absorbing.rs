//! Absorbing boundaries (docs/design.md §4.9): a dashpot and a spring at each boundary node, so
//! that waves leave the model instead of reflecting back into it (Lysmer & Kuhlemeyer's viscous
//! boundary, with the spring of the Kelvin–Voigt boundary that keeps a loaded model from
//! creeping away on its dashpots).
//!
//! A boundary face of area A (an edge's length in a plane section, ∫ r ds per radian in an
//! axisymmetric one) with outward unit normal n, in an element of mass density ρ, P-wave speed
//! V_p = sqrt(E_oed / ρ) and S-wave speed V_s = sqrt(G / ρ), gives each of its corners its
//! share w of A and the tensors
//!
//!   C = w ρ (a V_p n nᵀ + b V_s (I − n nᵀ)),   K = w ρ (V_p² n nᵀ + V_s² (I − n nᵀ)) / δ,
//!
//! with a and b the normal and shear coefficients (1 absorbs a plane wave at normal incidence
//! entirely) and δ the spring's length (no spring for δ = 0). A node's force is
//! F = −C v − K u, v its velocity and u its displacement since the start. On faces normal to an
//! axis the tensors are diagonal and these are Anura3D's per-axis dashpots and springs.
//!
//! The force is taken at the end of the step, implicitly, so that no dashpot limits the step:
//! with the grid update's acceleration a₀ (every other force, damping included) at a node of
//! mass m and start-of-step velocity v,
//!
//!   (m I + Δt C + Δt² K) a = m a₀ − C v − K (u + v Δt),
//!
//! over the node's free components (a fixed one keeps a = 0), then u ← u + (v + a Δt) Δt; after
//! the re-mapping the node keeps that end-of-step velocity, as a fixed node keeps zero, so that
//! the strains and the spring see the motion the dashpot allowed. An explicit dashpot would
//! need C Δt / m < 2, which a boundary node with little mass (a partly filled element) breaks
//! at any Courant number. Without the re-mapped velocity set, the re-mapping (which averages a
//! node with its neighbours through the points) handed back part of what the dashpot took out,
//! and a stiff dashpot or spring pumped energy in: a = 10, or δ = 0.1 m on 0.1 m cells, at
//! Courant 0.9 grew the kinetic energy of a loaded column fortyfold in 500 steps. The work is over the boundary's nodes in node
//! order on the calling thread (a boundary is a surface: few nodes), so it is the same for any
//! thread count.

use crate::element::Element;
use crate::real::{Real, V3};
use crate::step::constraint::{Constraint, Hook};

/// How a case's absorbing boundaries act.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AbsorbingRule {
    /// Ours: the dashpots and springs taken implicitly at the end of the step ([`Absorbing`]).
    #[default]
    EndOfStep,
    /// Anura3D's (GOM input): an accumulated force, one step behind, along each axis
    /// ([`crate::step::absorbing_anura3d`]); `point_sums`: its increments from sums over the
    /// points (Anura3D's default), else from the nodes' own motion (`$$APPLY_NODE_DATA_AB 1`).
    Anura3d {
        /// Increments from unnormalised sums over the points.
        point_sums: bool,
    },
}

/// A symmetric 3×3 tensor stored as xx, yy, zz, xy, yz, xz.
pub type Sym = [f64; 6];

/// One node's dashpot and spring, as the input resolved them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbsorbingNode {
    /// The model node (0-based).
    pub node: u32,
    /// The dashpot's tensor C (kN·s/m).
    pub dashpot: Sym,
    /// The spring's tensor K (kN/m).
    pub spring: Sym,
    /// The liquid's dashpot along each axis (kN·s/m; saturated elements' faces, which are
    /// normal to an axis).
    pub liquid_dashpot: [f64; 3],
    /// The liquid's spring along each axis (kN/m).
    pub liquid_spring: [f64; 3],
}

impl AbsorbingNode {
    /// The dashpot and spring of a face's share `w` (m², or m per radian) at a corner, for a face
    /// of outward normal `n` in an element of mass density `rho` (t/m³) and wave speeds `vp`,
    /// `vs` (m/s), with coefficients `a` (normal) and `b` (shear) and spring length `delta` (m;
    /// 0: none); in a saturated element also the liquid's along the normal, from its density and
    /// bulk modulus `liquid` (t/m³, kPa): a ρ_w V_w and ρ_w V_w² / δ, V_w = sqrt(K_w / ρ_w).
    #[allow(clippy::too_many_arguments)]
    pub fn of_face(
        node: u32,
        w: f64,
        n: [f64; 3],
        rho: f64,
        (vp, vs): (f64, f64),
        (a, b): (f64, f64),
        delta: f64,
        liquid: Option<(f64, f64)>,
    ) -> Self {
        let tensor = |normal: f64, shear: f64| -> Sym {
            // normal n nᵀ + shear (I − n nᵀ) = shear I + (normal − shear) n nᵀ.
            let d = normal - shear;
            [
                w * (shear + d * n[0] * n[0]),
                w * (shear + d * n[1] * n[1]),
                w * (shear + d * n[2] * n[2]),
                w * d * n[0] * n[1],
                w * d * n[1] * n[2],
                w * d * n[0] * n[2],
            ]
        };
        let dashpot = tensor(rho * a * vp, rho * b * vs);
        let spring = if delta > 0.0 {
            tensor(rho * vp * vp / delta, rho * vs * vs / delta)
        } else {
            [0.0; 6]
        };
        let (liquid_dashpot, liquid_spring) = match liquid {
            Some((rho_w, k_w)) => {
                let vw = (k_w / rho_w).sqrt();
                let along = n.map(|c| w * c * c);
                let spring = if delta > 0.0 { k_w / delta } else { 0.0 };
                (along.map(|x| x * a * rho_w * vw), along.map(|x| x * spring))
            }
            None => ([0.0; 3], [0.0; 3]),
        };
        AbsorbingNode {
            node,
            dashpot,
            spring,
            liquid_dashpot,
            liquid_spring,
        }
    }

    /// Adds `other`'s dashpot and spring to this node's.
    pub fn add(&mut self, other: &AbsorbingNode) {
        for k in 0..6 {
            self.dashpot[k] += other.dashpot[k];
            self.spring[k] += other.spring[k];
        }
        for d in 0..3 {
            self.liquid_dashpot[d] += other.liquid_dashpot[d];
            self.liquid_spring[d] += other.liquid_spring[d];
        }
    }
}

/// Sums the rows of the same node: one row per node, in node order.
pub fn merged(mut rows: Vec<AbsorbingNode>) -> Vec<AbsorbingNode> {
    rows.sort_by_key(|r| r.node);
    let mut out: Vec<AbsorbingNode> = Vec::with_capacity(rows.len());
    for r in rows {
        match out.last_mut() {
            Some(last) if last.node == r.node => last.add(&r),
            _ => out.push(r),
        }
    }
    out
}

/// The absorbing boundary of a run: its computational nodes, tensors and displacements.
#[derive(Debug, Clone)]
pub struct Absorbing {
    /// Computational nodes, ascending.
    nodes: Vec<u32>,
    /// Their dashpots.
    dashpot: Vec<Sym>,
    /// Their springs.
    spring: Vec<Sym>,
    /// Their displacements since the start (m), in f64 whatever the precision: the spring's
    /// force must not drift with round-off over millions of steps.
    displacement: Vec<[f64; 3]>,
    /// Their end-of-step velocities of this step (NaN where a node was empty or a component
    /// fixed: the re-mapping's stays).
    end_velocity: Vec<[f64; 3]>,
    /// The liquid's dashpots, springs, displacements and end-of-step velocities, as the
    /// solid's (two-phase cases).
    liquid: Vec<LiquidAbsorbing>,
}

/// The liquid's part of a boundary node.
#[derive(Debug, Clone, Copy)]
struct LiquidAbsorbing {
    dashpot: [f64; 3],
    spring: [f64; 3],
    displacement: [f64; 3],
    end_velocity: [f64; 3],
}

impl Absorbing {
    /// The boundary of `rows` (model nodes mapped by `node_of_model`; a node that is not a
    /// computational node, such as a mid-edge node, is left out).
    pub fn new(rows: &[AbsorbingNode], node_of_model: &[u32]) -> Self {
        let mut mapped: Vec<AbsorbingNode> = rows
            .iter()
            .filter_map(|r| {
                let n = *node_of_model.get(r.node as usize)?;
                (n != u32::MAX).then_some(AbsorbingNode { node: n, ..*r })
            })
            .collect();
        mapped = merged(mapped);
        Absorbing {
            nodes: mapped.iter().map(|r| r.node).collect(),
            dashpot: mapped.iter().map(|r| r.dashpot).collect(),
            spring: mapped.iter().map(|r| r.spring).collect(),
            displacement: vec![[0.0; 3]; mapped.len()],
            end_velocity: vec![[f64::NAN; 3]; mapped.len()],
            liquid: mapped
                .iter()
                .map(|r| LiquidAbsorbing {
                    dashpot: r.liquid_dashpot,
                    spring: r.liquid_spring,
                    displacement: [0.0; 3],
                    end_velocity: [f64::NAN; 3],
                })
                .collect(),
        }
    }

    /// The boundary's nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether it has none.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Applies the boundary's forces to the accelerations of the nodes in `cx.soil`, over `dim`
    /// components, for a step of `dt`.
    fn apply<R: Real>(&mut self, acc: &mut [V3<R>], grid: GridView<'_, R>, dim: usize, dt: f64) {
        for (i, &n) in self.nodes.iter().enumerate() {
            let n = n as usize;
            let m = grid.mass[n].f64();
            let u = &mut self.displacement[i];
            self.end_velocity[i] = [f64::NAN; 3];
            if m <= grid.empty_below.f64() {
                // An empty node moves with nothing: its spring keeps its stretch.
                continue;
            }
            if grid.liquid_mass.is_some_and(|l| l[n] > grid.empty_below) {
                continue;
            }
            let v: [f64; 3] = std::array::from_fn(|d| grid.momentum[n][d].f64() / m);
            let a0: [f64; 3] = std::array::from_fn(|d| acc[n][d].f64());
            let (c, k) = (full(&self.dashpot[i]), full(&self.spring[i]));
            let mut lhs = [[0.0; 3]; 3];
            let mut rhs = [0.0; 3];
            for r in 0..dim {
                rhs[r] = m * a0[r];
                for s in 0..dim {
                    lhs[r][s] = dt * c[r][s] + dt * dt * k[r][s];
                    rhs[r] -= c[r][s] * v[s] + k[r][s] * (u[s] + v[s] * dt);
                }
                lhs[r][r] += m;
            }
            // A fixed component keeps a = 0: its row and column leave the system.
            for r in 0..3 {
                if r >= dim || grid.fixed[n][r] {
                    for s in 0..3 {
                        lhs[r][s] = 0.0;
                        lhs[s][r] = 0.0;
                    }
                    lhs[r][r] = 1.0;
                    rhs[r] = 0.0;
                }
            }
            let a = solve3(&lhs, rhs);
            for d in (0..dim).filter(|&d| !grid.fixed[n][d]) {
                acc[n][d] = R::of(a[d]);
                u[d] += (v[d] + a[d] * dt) * dt;
                self.end_velocity[i][d] = v[d] + a[d] * dt;
            }
        }
    }
}

/// What [`Absorbing::apply_two_phase`] reads of the grid besides the accelerations: the
/// solid's and the liquid's masses M_s, M_w, M̄_w, the drag Q, both momenta, both fixities.
struct TwoPhaseView<'a, R: Real> {
    mass: (&'a [R], &'a [R], &'a [R]),
    drag: &'a [R],
    momentum: (&'a [V3<R>], &'a [V3<R>]),
    fixed: (&'a [[bool; 3]], &'a [[bool; 3]]),
    empty_below: R,
    implicit_drag: bool,
}

impl Absorbing {
    /// The boundary's forces at the nodes holding liquid, per component: the grid update solved
    /// A a₀ = b for (a_s, a_w), with A = [[M_s, M̄_w], [−Q Δt, M_w + Q Δt]] (Q Δt = 0 with the
    /// explicit drag); the dashpots and springs taken at the end of the step add
    /// Δt (C + K Δt) to the solid's (mixture row) and the liquid's (both rows) unknowns and
    /// −C v − K (u + v Δt) to the right-hand sides, and (A + D) a = A a₀ + c is solved. The
    /// faces of saturated elements are normal to an axis, so the components do not couple.
    fn apply_two_phase<R: Real>(
        &mut self,
        acc_s: &mut [V3<R>],
        acc_w: &mut [V3<R>],
        g: TwoPhaseView<'_, R>,
        dim: usize,
        dt: f64,
    ) {
        let eps = g.empty_below.f64();
        for (i, &n) in self.nodes.iter().enumerate() {
            let n = n as usize;
            let (ms, mw, mwn) = (g.mass.0[n].f64(), g.mass.1[n].f64(), g.mass.2[n].f64());
            if ms <= eps || mw <= eps {
                continue;
            }
            let (c, k) = (&self.dashpot[i], &self.spring[i]);
            debug_assert!(
                c[3..].iter().chain(&k[3..]).all(|&x| x == 0.0),
                "coupled components"
            );
            let l = &mut self.liquid[i];
            let u = &mut self.displacement[i];
            self.end_velocity[i] = [f64::NAN; 3];
            l.end_velocity = [f64::NAN; 3];
            let qdt = if g.implicit_drag {
                g.drag[n].f64() * dt
            } else {
                0.0
            };
            for d in 0..dim {
                let (fs, fw) = (g.fixed.0[n][d], g.fixed.1[n][d]);
                let v = if fs {
                    0.0
                } else {
                    g.momentum.0[n][d].f64() / ms
                };
                let w = if fw {
                    0.0
                } else {
                    g.momentum.1[n][d].f64() / mw
                };
                let (a0s, a0w) = (acc_s[n][d].f64(), acc_w[n][d].f64());
                let mut a = [[ms, mwn], [-qdt, mw + qdt]];
                let mut b = [ms * a0s + mwn * a0w, -qdt * a0s + (mw + qdt) * a0w];
                // The solid's boundary acts on the mixture, the liquid's on both equations.
                let (ds, dw) = (
                    dt * (c[d] + k[d] * dt),
                    dt * (l.dashpot[d] + l.spring[d] * dt),
                );
                let (cs, cw) = (
                    c[d] * v + k[d] * (u[d] + v * dt),
                    l.dashpot[d] * w + l.spring[d] * (l.displacement[d] + w * dt),
                );
                a[0][0] += ds;
                a[0][1] += dw;
                a[1][1] += dw;
                b[0] -= cs + cw;
                b[1] -= cw;
                for (j, fixed) in [fs, fw].into_iter().enumerate() {
                    if fixed {
                        a[j] = [0.0; 2];
                        a[0][j] = 0.0;
                        a[1][j] = 0.0;
                        a[j][j] = 1.0;
                        b[j] = 0.0;
                    }
                }
                let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
                let x = [
                    (b[0] * a[1][1] - a[0][1] * b[1]) / det,
                    (a[0][0] * b[1] - a[1][0] * b[0]) / det,
                ];
                if !fs {
                    acc_s[n][d] = R::of(x[0]);
                    self.end_velocity[i][d] = v + x[0] * dt;
                    u[d] += self.end_velocity[i][d] * dt;
                }
                if !fw {
                    acc_w[n][d] = R::of(x[1]);
                    l.end_velocity[d] = w + x[1] * dt;
                    l.displacement[d] += l.end_velocity[d] * dt;
                }
            }
        }
    }
}

/// What [`Absorbing::apply`] reads of the grid besides the accelerations.
struct GridView<'a, R: Real> {
    mass: &'a [R],
    /// The liquid's mass, in two-phase cases: nodes holding liquid are
    /// [`Absorbing::apply_two_phase`]'s.
    liquid_mass: Option<&'a [R]>,
    momentum: &'a [V3<R>],
    empty_below: R,
    fixed: &'a [[bool; 3]],
}

/// The full matrix of a [`Sym`].
fn full(s: &Sym) -> [[f64; 3]; 3] {
    [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]]
}

/// x with `m` x = `b` by Cramer's rule (m symmetric positive definite here: the mass on its
/// diagonal and the dashpot's and spring's positive semi-definite tensors).
fn solve3(m: &[[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det3 = |c0: [f64; 3], c1: [f64; 3], c2: [f64; 3]| {
        c0[0] * (c1[1] * c2[2] - c1[2] * c2[1]) - c1[0] * (c0[1] * c2[2] - c0[2] * c2[1])
            + c2[0] * (c0[1] * c1[2] - c0[2] * c1[1])
    };
    let col = |j: usize| [m[0][j], m[1][j], m[2][j]];
    let (c0, c1, c2) = (col(0), col(1), col(2));
    let det = det3(c0, c1, c2);
    [
        det3(b, c1, c2) / det,
        det3(c0, b, c2) / det,
        det3(c0, c1, b) / det,
    ]
}

impl<R: Real, E: Element> Constraint<R, E> for Absorbing {
    fn name(&self) -> &'static str {
        "absorbing boundary"
    }

    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        let g = &mut *cx.soil;
        let view = GridView {
            mass: &g.mass,
            liquid_mass: g.liquid.as_ref().map(|l| &l.mass[..]),
            momentum: &g.momentum,
            empty_below: g.empty_below,
            fixed: cx.fixed,
        };
        // The nodes with liquid are taken with both phases.
        self.apply(&mut g.acc, view, E::DIM, cx.at.dt);
        if let Some(l) = &mut g.liquid {
            let phases = TwoPhaseView {
                mass: (&g.mass, &l.mass, &l.mass_n),
                drag: &l.drag,
                momentum: (&g.momentum, &l.momentum),
                fixed: (cx.fixed, cx.liquid_fixed),
                empty_below: g.empty_below,
                implicit_drag: cx.at.drag == crate::step::grid_update::Drag::Implicit,
            };
            self.apply_two_phase(&mut g.acc, &mut l.acc, phases, E::DIM, cx.at.dt);
        }
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        let g = &mut *cx.soil;
        for (i, &n) in self.nodes.iter().enumerate() {
            let (n, solid, liquid) = (
                n as usize,
                self.end_velocity[i],
                self.liquid[i].end_velocity,
            );
            for d in 0..3 {
                if !solid[d].is_nan() {
                    g.vel[n][d] = R::of(solid[d]);
                }
                if let Some(l) = g.liquid.as_mut().filter(|_| !liquid[d].is_nan()) {
                    l.vel[n][d] = R::of(liquid[d]);
                }
            }
        }
    }

    fn saved(&self) -> Vec<f64> {
        self.displacement
            .iter()
            .zip(&self.liquid)
            .flat_map(|(u, l)| u.iter().chain(&l.displacement).copied())
            .collect()
    }

    fn restore(&mut self, _mesh: &mut crate::element::mesh::Mesh<E, R>, state: &[f64]) -> bool {
        if state.len() != 6 * self.displacement.len() {
            return false;
        }
        for ((u, l), s) in self
            .displacement
            .iter_mut()
            .zip(&mut self.liquid)
            .zip(state.chunks_exact(6))
        {
            *u = [s[0], s[1], s[2]];
            l.displacement = [s[3], s[4], s[5]];
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

    fn boundary(rows: &[AbsorbingNode]) -> Absorbing {
        Absorbing::new(rows, &[0, 1, 2])
    }

    /// One node of mass `m` moving at `v`, with acceleration `a0` from the other forces.
    fn step(b: &mut Absorbing, m: f64, v: [f64; 3], a0: [f64; 3], fixed: [bool; 3]) -> [f64; 3] {
        let mut acc = vec![[0.0; 3], a0];
        let mass = [0.0, m];
        let momentum = [[0.0; 3], v.map(|x| m * x)];
        let fixed = [[false; 3], fixed];
        let view = GridView {
            mass: &mass,
            liquid_mass: None,
            momentum: &momentum,
            empty_below: 1e-12,
            fixed: &fixed,
        };
        b.apply::<f64>(&mut acc, view, 3, 0.1);
        acc[1]
    }

    #[test]
    fn a_face_normal_to_an_axis_gives_anuras_per_axis_dashpot_and_spring() {
        // ρ = 2, V_p = 3, V_s = 1, a = 1, b = 0.5, δ = 4, share 0.25, face normal to y.
        let r = AbsorbingNode::of_face(
            0,
            0.25,
            [0.0, -1.0, 0.0],
            2.0,
            (3.0, 1.0),
            (1.0, 0.5),
            4.0,
            None,
        );
        assert_eq!(r.dashpot, [0.25, 1.5, 0.25, 0.0, 0.0, 0.0]);
        assert_eq!(r.spring, [0.125, 1.125, 0.125, 0.0, 0.0, 0.0]);
        let no_spring = AbsorbingNode::of_face(
            0,
            1.0,
            [1.0, 0.0, 0.0],
            1.0,
            (1.0, 1.0),
            (1.0, 1.0),
            0.0,
            None,
        );
        assert_eq!(no_spring.spring, [0.0; 6]);
    }

    #[test]
    fn an_inclined_face_gives_the_rotated_tensor() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let r = AbsorbingNode::of_face(0, 1.0, [s, s, 0.0], 1.0, (2.0, 1.0), (1.0, 1.0), 0.0, None);
        // Along n: 2; across it: 1.
        let c = full(&r.dashpot);
        let along: f64 = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| [s, s, 0.0][i] * c[i][j] * [s, s, 0.0][j])
                    .sum::<f64>()
            })
            .sum();
        let across: f64 = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| [s, -s, 0.0][i] * c[i][j] * [s, -s, 0.0][j])
                    .sum::<f64>()
            })
            .sum();
        assert!((along - 2.0).abs() < 1e-15 && (across - 1.0).abs() < 1e-15);
        assert!((c[2][2] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn rows_of_one_node_add_up_and_mid_edge_nodes_are_left_out() {
        let one = AbsorbingNode::of_face(
            1,
            1.0,
            [0.0, 1.0, 0.0],
            1.0,
            (1.0, 1.0),
            (1.0, 1.0),
            0.0,
            None,
        );
        let mid = AbsorbingNode { node: 3, ..one };
        let b = Absorbing::new(&[one, mid, one], &[0, 1, 2, u32::MAX]);
        assert_eq!(b.len(), 1);
        assert_eq!(b.dashpot[0], [2.0, 2.0, 2.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn the_dashpot_is_taken_at_the_end_of_the_step() {
        // m a = −c (v + a Δt) with m = 1, c = 10, v = 1, Δt = 0.1: a = −c v / (m + c Δt) = −5,
        // stable where the explicit −c v / m = −10 would overshoot to v = 0 and beyond.
        let node = AbsorbingNode {
            node: 1,
            dashpot: [10.0, 10.0, 10.0, 0.0, 0.0, 0.0],
            spring: [0.0; 6],
            liquid_dashpot: [0.0; 3],
            liquid_spring: [0.0; 3],
        };
        let mut b = boundary(&[node]);
        let a = step(
            &mut b,
            1.0,
            [1.0, 0.0, -2.0],
            [0.0; 3],
            [false, false, true],
        );
        assert_eq!(a, [-5.0, 0.0, 0.0]);
        // u advanced with the end-of-step velocity, and not along the fixed z.
        assert!((b.displacement[0][0] - 0.05).abs() < 1e-15);
        assert_eq!(b.displacement[0][2], 0.0);
    }

    #[test]
    fn a_spring_under_a_held_force_settles_at_f_over_k() {
        // m = 1, f = 3 (a0 = 3), k = 2, c = 1: u → 1.5.
        let node = AbsorbingNode {
            node: 1,
            dashpot: [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            spring: [2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            liquid_dashpot: [0.0; 3],
            liquid_spring: [0.0; 3],
        };
        let mut b = boundary(&[node]);
        let mut v = [0.0; 3];
        for _ in 0..2000 {
            let a = step(&mut b, 1.0, v, [3.0, 0.0, 0.0], [false; 3]);
            v[0] += a[0] * 0.1;
        }
        assert!(
            (b.displacement[0][0] - 1.5).abs() < 1e-9,
            "{:?}",
            b.displacement[0]
        );
        assert!(v[0].abs() < 1e-9);
    }

    #[test]
    fn the_state_goes_through_a_checkpoint() {
        let node = AbsorbingNode {
            node: 1,
            dashpot: [1.0; 6],
            spring: [1.0; 6],
            liquid_dashpot: [0.5; 3],
            liquid_spring: [0.5; 3],
        };
        let mut b = boundary(&[node]);
        b.displacement[0] = [0.5, -1.0, 2.0];
        let saved = <Absorbing as Constraint<f64, crate::element::tet4::Tet4>>::saved(&b);
        let mut fresh = boundary(&[node]);
        let mut mesh = crate::element::mesh::Mesh::<crate::element::tet4::Tet4, f64>::new(
            &mpm_shared::generate::box_mesh([1, 1, 1], [1.0; 3], mpm_shared::ElementType::Tet4),
        )
        .unwrap();
        assert!(Constraint::<f64, crate::element::tet4::Tet4>::restore(
            &mut fresh, &mut mesh, &saved
        ));
        assert_eq!(fresh.displacement, b.displacement);
        assert!(!Constraint::<f64, crate::element::tet4::Tet4>::restore(
            &mut fresh,
            &mut mesh,
            &saved[..2]
        ));
    }
}
