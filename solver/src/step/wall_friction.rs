//! Rigid walls with Coulomb friction (docs/design.md §4.9): a fixity with `friction = μ` is a
//! wall normal to its one fixed axis that the body may press on, slide along against friction,
//! or leave, rather than a fixed velocity component.
//!
//! After the grid update, at a wall node of mass m whose velocity would become
//! v* = p/m + a Δt, with n the unit normal from the body into the wall and d = v*·n: a node
//! that approaches the wall (d > 0) loses its normal velocity, and its tangential velocity
//! v*_t is cut by μ d, down to zero (stick): v = v*_t (1 - min(1, μ d / |v*_t|)). Its
//! acceleration becomes (v - p/m) / Δt, so that the points take the wall's impulse (FLIP). A
//! node that leaves the wall (d ≤ 0) is left free. After the re-mapping, a wall node's
//! velocity into the wall is set to zero, so that strains and positions do not cross it.
//! This is the two-body contact of [`crate::step::contact`] with the structure a wall at rest,
//! and the friction acts on the normal impulse, whatever its cause (weight, load or impact).
//!
//! A rough base made of fixed nodes sticks every node whatever its load, and as a bilateral
//! constraint it holds a node that the body pulls on; a point that leaves the bulk alone keeps
//! sliding on it under FLIP (its nodes' accelerations are zero and nothing else acts). A wall
//! slows such a point at μ g, as a grain on a rough base, and sticks or slips a loaded node by
//! Coulomb's rule. The work is over the walls' nodes in node order, on the calling thread (a
//! wall is a surface: few nodes), so it is the same for any thread count.

use crate::element::Element;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::step::constraint::{Constraint, Hook};

/// A wall normal to one axis at a node: which side of it the body lies on, and its friction.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WallAxis {
    /// +1 where the body lies on the wall's + side (it presses on the wall along -axis), -1 on
    /// its - side, 0 where no wall is normal to this axis.
    pub side: f64,
    /// Coulomb's friction coefficient μ.
    pub friction: f64,
}

/// One node on a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallNode<R> {
    /// The computational node.
    pub node: u32,
    /// Per axis: the side of the body (±1, 0 for no wall normal to that axis).
    pub side: [R; 3],
    /// Per axis: the wall's friction coefficient.
    pub friction: [R; 3],
}

/// The wall nodes of the nodes `model_node` (computational node → model node), from the
/// per-model-node walls `per_model_node` (empty: no wall), in node order.
pub fn wall_nodes<R: Real>(
    per_model_node: &[[WallAxis; 3]],
    model_node: &[u32],
) -> Vec<WallNode<R>> {
    if per_model_node.is_empty() {
        return Vec::new();
    }
    model_node
        .iter()
        .enumerate()
        .filter_map(|(n, &m)| {
            let w = per_model_node[m as usize];
            w.iter().any(|a| a.side != 0.0).then(|| WallNode {
                node: n as u32,
                side: w.map(|a| R::of(a.side)),
                friction: w.map(|a| R::of(a.friction)),
            })
        })
        .collect()
}

/// Applies the walls to the accelerations of `g` after the grid update of a step of `dt`
/// (`fixed`: the fixed components per node; a wall axis that is also fixed is left to the
/// fixity). Nodes where no wall acts keep their accelerations bit for bit.
pub fn apply_walls<R: Real>(walls: &[WallNode<R>], g: &mut Grid<R>, fixed: &[[bool; 3]], dt: R) {
    for w in walls {
        let n = w.node as usize;
        let m = g.mass[n];
        if m <= g.empty_below {
            continue;
        }
        let free = fixed[n].map(|f| !f);
        let start: V3<R> = std::array::from_fn(|a| {
            if free[a] {
                g.momentum[n][a] / m
            } else {
                R::ZERO
            }
        });
        let mut v: V3<R> = std::array::from_fn(|a| start[a] + g.acc[n][a] * dt);
        let mut acted = false;
        for axis in 0..3 {
            let side = w.side[axis];
            if side == R::ZERO || !free[axis] {
                continue;
            }
            // The speed into the wall (the body presses along -side).
            let d = -side * v[axis];
            if d <= R::ZERO {
                continue;
            }
            v[axis] = R::ZERO;
            acted = true;
            let mu = w.friction[axis];
            let slip2 = (0..3)
                .filter(|&a| a != axis && free[a])
                .fold(R::ZERO, |s, a| s + v[a] * v[a]);
            if mu == R::ZERO || slip2 == R::ZERO {
                continue;
            }
            let keep = (R::ONE - mu * d / slip2.sqrt()).max(R::ZERO);
            for a in (0..3).filter(|&a| a != axis && free[a]) {
                v[a] *= keep;
            }
        }
        if acted {
            for a in (0..3).filter(|&a| free[a]) {
                g.acc[n][a] = (v[a] - start[a]) / dt;
            }
        }
    }
}

/// After the re-mapping: a wall node's velocity into the wall (in `vel`, the re-mapped nodal
/// velocities) is set to zero.
pub fn hold_remapped<R: Real>(walls: &[WallNode<R>], vel: &mut [V3<R>]) {
    for w in walls {
        let v = &mut vel[w.node as usize];
        for axis in 0..3 {
            if -w.side[axis] * v[axis] > R::ZERO {
                v[axis] = R::ZERO;
            }
        }
    }
}

/// The rigid walls of a run as a constraint: friction on the accelerations after the grid
/// update, no re-mapped velocity into a wall, on each body's nodes.
#[derive(Debug, Clone, Default)]
pub struct Walls<R>(pub Vec<WallNode<R>>);

impl<R: Real, E: Element> Constraint<R, E> for Walls<R> {
    fn name(&self) -> &'static str {
        "walls"
    }

    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        let dt = R::of(cx.at.dt);
        apply_walls(&self.0, cx.soil, cx.fixed, dt);
        if let Some(structure) = cx.structure.as_deref_mut() {
            apply_walls(&self.0, structure, cx.fixed, dt);
        }
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        hold_remapped(&self.0, &mut cx.soil.vel);
        if let Some(structure) = cx.structure.as_deref_mut() {
            hold_remapped(&self.0, &mut structure.vel);
        }
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One node of mass 2 above a base normal to y, moving along x at 1 m/s and down at `vy`,
    /// with the force (`fx`, `fy`) on it.
    fn node(fx: f64, fy: f64, vy: f64) -> Grid<f64> {
        let mut g = Grid::new(1);
        g.mass[0] = 2.0;
        g.momentum[0] = [2.0, 2.0 * vy, 0.0];
        g.f_int[0] = [fx, fy, 0.0];
        g.acc[0] = [fx / 2.0, fy / 2.0, 0.0];
        g
    }

    fn base(mu: f64) -> [WallNode<f64>; 1] {
        [WallNode {
            node: 0,
            side: [0.0, 1.0, 0.0],
            friction: [0.0, mu, 0.0],
        }]
    }

    #[test]
    fn a_node_pressed_on_the_wall_stops_normally_and_slows_by_mu_times_its_normal_impulse() {
        // Pressed by 10 kN over 0.01 s and arriving at 0.1 m/s: the normal speed lost is
        // 0.05 + 0.1 m/s, the tangential 0.5 × 0.15.
        let mut g = node(0.0, -10.0, -0.1);
        apply_walls(&base(0.5), &mut g, &[[false; 3]], 0.01);
        let v = g.acc[0].map(|a| a * 0.01);
        assert!((v[0] + 0.075).abs() < 1e-12, "{v:?}");
        assert!((v[1] - 0.1).abs() < 1e-12, "{v:?}");
        assert_eq!(v[2], 0.0);
    }

    #[test]
    fn friction_stops_a_node_and_does_not_reverse_it() {
        let mut g = node(0.0, -10.0, 0.0);
        // 0.5 × 5 m/s of normal speed against 1 m/s of slip: it sticks.
        apply_walls(&base(0.5), &mut g, &[[false; 3]], 1.0);
        assert!((g.acc[0][0] + 1.0).abs() < 1e-12, "{:?}", g.acc[0]);
        assert!((g.acc[0][1]).abs() < 1e-12, "{:?}", g.acc[0]);
    }

    #[test]
    fn a_node_leaving_the_wall_is_free() {
        let mut g = node(3.0, 10.0, 0.0);
        apply_walls(&base(0.5), &mut g, &[[false; 3]], 0.01);
        assert_eq!(g.acc[0], [1.5, 5.0, 0.0]);
        // The body below the wall, pushed up into it: stopped and slowed.
        let mut g = node(0.0, 10.0, 0.0);
        let mut w = base(0.5);
        w[0].side[1] = -1.0;
        apply_walls(&w, &mut g, &[[false; 3]], 0.01);
        assert!((g.acc[0][0] + 2.5).abs() < 1e-12 && g.acc[0][1].abs() < 1e-12);
    }

    #[test]
    fn the_friction_acts_along_the_slip_and_leaves_fixed_components_alone() {
        let mut g = node(0.0, -10.0, 0.0);
        g.momentum[0] = [2.0, 0.0, 2.0];
        apply_walls(&base(0.5), &mut g, &[[false; 3]], 0.01);
        let s = 2.5 / 2f64.sqrt();
        assert!((g.acc[0][0] + s).abs() < 1e-12 && (g.acc[0][2] + s).abs() < 1e-12);
        // z fixed too (a symmetry plane): the slip is along x alone.
        let mut g = node(0.0, -10.0, 0.0);
        g.momentum[0] = [2.0, 0.0, 2.0];
        g.acc[0][2] = 0.0;
        apply_walls(&base(0.5), &mut g, &[[false, false, true]], 0.01);
        assert!((g.acc[0][0] + 2.5).abs() < 1e-12);
        assert_eq!(g.acc[0][2], 0.0);
        // A smooth wall stops the normal motion alone.
        let mut g = node(0.0, -10.0, 0.0);
        apply_walls(&base(0.0), &mut g, &[[false; 3]], 0.01);
        assert_eq!(g.acc[0][0], 0.0);
        assert!(g.acc[0][1].abs() < 1e-12);
    }

    #[test]
    fn empty_nodes_and_fixed_axes_are_left_alone() {
        let mut g = node(0.0, -10.0, 0.0);
        g.empty_below = 2.0;
        apply_walls(&base(0.5), &mut g, &[[false; 3]], 0.01);
        assert_eq!(g.acc[0], [0.0, -5.0, 0.0]);
        let mut g = node(0.0, -10.0, 0.0);
        g.acc[0][1] = 0.0;
        apply_walls(&base(0.5), &mut g, &[[false, true, false]], 0.01);
        assert_eq!(g.acc[0], [0.0; 3]);
    }

    #[test]
    fn remapped_velocities_do_not_cross_the_wall() {
        let mut vel = vec![[0.3, -0.2, 0.1], [0.3, 0.2, 0.1]];
        let w = [
            WallNode {
                node: 0,
                side: [0.0, 1.0, 0.0],
                friction: [0.0; 3],
            },
            WallNode {
                node: 1,
                side: [0.0, 1.0, 0.0],
                friction: [0.0; 3],
            },
        ];
        hold_remapped(&w, &mut vel);
        assert_eq!(vel, vec![[0.3, 0.0, 0.1], [0.3, 0.2, 0.1]]);
    }

    #[test]
    fn wall_nodes_follow_the_computational_numbering() {
        let none = WallAxis::default();
        let base = WallAxis {
            side: 1.0,
            friction: 0.5,
        };
        let per_model = [
            [none; 3],
            [none, base, none],
            [none; 3],
            [
                WallAxis {
                    side: -1.0,
                    friction: 0.0,
                },
                none,
                none,
            ],
        ];
        let w: Vec<WallNode<f64>> = wall_nodes(&per_model, &[3, 0, 1]);
        assert_eq!(
            w,
            vec![
                WallNode {
                    node: 0,
                    side: [-1.0, 0.0, 0.0],
                    friction: [0.0; 3]
                },
                WallNode {
                    node: 2,
                    side: [0.0, 1.0, 0.0],
                    friction: [0.0, 0.5, 0.0]
                }
            ]
        );
        assert!(wall_nodes::<f64>(&[], &[0, 1]).is_empty());
    }
}
