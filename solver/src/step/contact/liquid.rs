//! The pore liquid at the structure's wall in a saturated soil: the structure is impermeable,
//! so at each interface node the liquid keeps no velocity relative to the wall along the
//! wall's normal, in either direction (it neither flows into the structure nor leaves a gap
//! behind it); along the wall it slides freely. As Anura3D's `CorrectWaterForPrescribedVelocity`,
//! before the solid's contact correction:
//!
//! 1. the liquid's end-of-step velocity w = w₀ + a_w Δt (w₀ its start-of-step velocity, zero in
//!    its fixed components) loses its normal part relative to the wall velocity V:
//!    w' = w − ((w − V)·n) n, and a_w' = (w' − w₀) / Δt;
//! 2. the soil's solid, whose acceleration took the liquid's inertia M̄_w a_w
//!    (`grid_update_two_phase`: M_s a_s = F − M̄_w a_w), takes the corrected one:
//!    a_s' = a_s − M̄_w (a_w' − a_w) / M_s. The mixture's momentum M_s v + M̄_w w is unchanged:
//!    the wall pushes the mixture through the solid's contact that follows.
//!
//! V is the structure's velocity at the node: where it is prescribed, the prescribed
//! components (the mean of its marked points, as Anura3D maps them to the nodes), elsewhere its
//! own end-of-step nodal velocity (Anura3D takes zero there: it models a driven structure
//! only). A node without structure is left alone; so are the liquid's fixed components.
//!
//! Anura3D damps the liquid part of the mixture force against the corrected liquid velocity;
//! here the damping keeps the uncorrected one (the same in undamped runs).

use crate::real::{Real, V3};
use crate::state::grid::Grid;

/// What the wall correction reads: the interface nodes and their unit normals, the solid's and
/// the liquid's fixities, the step, and the structure's prescribed velocity at a node.
pub(super) struct Wall<'a, R: Real> {
    pub nodes: &'a [u32],
    pub normal: &'a [[f64; 3]],
    pub fixed: &'a [[bool; 3]],
    pub liquid_fixed: &'a [[bool; 3]],
    pub dt: f64,
    pub prescribed: &'a dyn Fn(u32) -> Option<([bool; 3], V3<R>)>,
}

/// Corrects the soil's liquid and solid accelerations at the interface nodes holding liquid
/// (see the module's description). A dry soil (no liquid arrays) is left alone.
pub(super) fn seal<R: Real>(wall: &Wall<'_, R>, soil: &mut Grid<R>, structure: &Grid<R>) {
    let eps = soil.empty_below;
    let Some(gl) = soil.liquid.as_mut() else {
        return;
    };
    let dt = wall.dt;
    for (k, &node) in wall.nodes.iter().enumerate() {
        let n = node as usize;
        let mw = gl.mass[n];
        if mw <= eps {
            continue;
        }
        let Some(v_wall) = wall_velocity(wall, structure, node) else {
            continue;
        };
        let Some(normal) = super::free_normal(wall.normal[k], wall.liquid_fixed[n]) else {
            continue;
        };
        let mut w0 = [0.0; 3];
        let mut w = [0.0; 3];
        for d in 0..3 {
            if !wall.liquid_fixed[n][d] {
                w0[d] = (gl.momentum[n][d] / mw).f64();
                w[d] = w0[d] + gl.acc[n][d].f64() * dt;
            }
        }
        let across: f64 = (0..3).map(|d| (w[d] - v_wall[d]) * normal[d]).sum();
        let ms = soil.mass[n];
        let ratio = if ms > eps {
            (gl.mass_n[n] / ms).f64()
        } else {
            0.0
        };
        for d in 0..3 {
            if wall.liquid_fixed[n][d] {
                continue;
            }
            let a_w = R::of((w[d] - across * normal[d] - w0[d]) / dt);
            if !wall.fixed[n][d] && ratio != 0.0 {
                let change = (a_w - gl.acc[n][d]).f64();
                soil.acc[n][d] = R::of(soil.acc[n][d].f64() - ratio * change);
            }
            gl.acc[n][d] = a_w;
        }
    }
}

/// The structure's velocity at `node` at the end of the step: its prescribed components where
/// it is driven, its own nodal velocity in the others (zero in fixed components); `None`
/// where the structure has no mass and is not driven.
fn wall_velocity<R: Real>(wall: &Wall<'_, R>, structure: &Grid<R>, node: u32) -> Option<[f64; 3]> {
    let n = node as usize;
    let m = structure.mass[n];
    let held = (wall.prescribed)(node);
    if m <= structure.empty_below && held.is_none() {
        return None;
    }
    let mut v = [0.0; 3];
    for d in 0..3 {
        if m > structure.empty_below && !wall.fixed[n][d] {
            v[d] = (structure.momentum[n][d] / m + structure.acc[n][d] * R::of(wall.dt)).f64();
        }
    }
    if let Some((dirs, vp)) = held {
        for d in 0..3 {
            if dirs[d] {
                v[d] = vp[d].f64();
            }
        }
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::grid::LiquidNodes;

    /// One node of soil with liquid moving into a wall (normal +x) at rest.
    fn node() -> (Grid<f64>, Grid<f64>) {
        let mut soil = Grid::<f64>::new(1);
        soil.mass[0] = 2.0;
        soil.momentum[0] = [0.2, 0.4, 0.0];
        soil.acc[0] = [1.0, -1.0, 0.0];
        let mut gl = LiquidNodes::new(1);
        gl.mass[0] = 1.0;
        gl.mass_n[0] = 0.5;
        gl.momentum[0] = [0.3, -0.1, 0.0];
        gl.acc[0] = [2.0, 1.0, 0.0];
        soil.liquid = Some(gl);
        let mut structure = Grid::<f64>::new(1);
        structure.mass[0] = 4.0;
        (soil, structure)
    }

    #[test]
    fn the_liquid_keeps_the_walls_normal_velocity_and_the_mixtures_momentum() {
        let (mut soil, structure) = node();
        let (before_s, before_w) = (soil.acc[0], soil.liquid.as_ref().unwrap().acc[0]);
        let dt = 0.1;
        let wall = Wall {
            nodes: &[0],
            normal: &[[1.0, 0.0, 0.0]],
            fixed: &[[false; 3]],
            liquid_fixed: &[[false; 3]],
            dt,
            prescribed: &|_| None,
        };
        seal(&wall, &mut soil, &structure);
        let gl = soil.liquid.as_ref().unwrap();
        // Normal: w = 0.3 + 0.2 → the wall's 0; along the wall untouched.
        let w_end = [0, 1].map(|d| gl.momentum[0][d] / gl.mass[0] + gl.acc[0][d] * dt);
        assert!(w_end[0].abs() < 1e-15, "{w_end:?}");
        assert_eq!(gl.acc[0][1], before_w[1]);
        // M_s Δa_s + M̄_w Δa_w = 0 per component.
        for d in 0..3 {
            let change = soil.mass[0] * (soil.acc[0][d] - before_s[d])
                + gl.mass_n[0] * (gl.acc[0][d] - before_w[d]);
            assert!(change.abs() < 1e-14, "component {d}: {change}");
        }
    }

    #[test]
    fn a_driven_wall_moves_the_liquid_with_it_and_fixed_components_stay() {
        let (mut soil, structure) = node();
        let dt = 0.1;
        let wall = Wall {
            nodes: &[0],
            normal: &[[0.0, 1.0, 0.0]],
            fixed: &[[false; 3]],
            liquid_fixed: &[[true, false, false]],
            dt,
            prescribed: &|_| Some(([false, true, false], [0.0, -0.5, 0.0])),
        };
        seal(&wall, &mut soil, &structure);
        let gl = soil.liquid.as_ref().unwrap();
        let w_y = gl.momentum[0][1] / gl.mass[0] + gl.acc[0][1] * dt;
        assert!((w_y + 0.5).abs() < 1e-15, "{w_y}");
        assert_eq!(gl.acc[0][0], 2.0, "a fixed liquid component is left alone");
        // No structure and no drive: nothing to seal against.
        let (mut soil, mut structure) = node();
        structure.mass[0] = 0.0;
        let before = soil.clone();
        let wall = Wall {
            prescribed: &|_| None,
            ..wall
        };
        seal(&wall, &mut soil, &structure);
        assert_eq!(soil.acc, before.acc);
    }
}
