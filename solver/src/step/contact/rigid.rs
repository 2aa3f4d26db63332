//! A rigid structure (`[[contact]] rigid = true`): the structure moves as one body, in
//! translation, under its weight, its loads (a hammer's blows) and the soil's push, which the
//! contact correction carries.
//!
//! After the structure's grid update, the body's trial acceleration is A = damp(F, P) / M: F the
//! sum of its nodal forces (internal, external and its face loads; the internal ones cancel),
//! P and M its momentum and mass, over the nodes holding its mass; every such node takes A. In the correction the body is the stiffer one at every interface node: the soil that
//! approaches it takes the body's velocity there (its normal part, and the tangential part
//! friction and adhesion allow), as at a driven structure's nodes, and the body is not
//! corrected; the soil's push F_c, the momentum the soil lost per unit time, then moves the
//! whole body: A' = damp(F + F_c, P) / M, local damping acting on the body's net force (on F
//! alone it is a Coulomb friction α |F| that lets the body creep: measured, a rigid pile
//! loaded on its head kept rising at 0.025 m/s under a push 5 % above its load). (A per-node two-body correction followed by the mean lets the
//! body sink through the soil: the soil is brought to each node's centre-of-mass velocity
//! while the body, whose interface nodes carry a small share of its mass, keeps nearly its
//! own; measured: a rigid pile loaded on its head sank 1.6 m in 5.5 s and crushed the soil.)
//! A component fixed at any of the body's nodes is fixed for the body (a pile on the axis of
//! an axisymmetric section has no radial motion). The points then all take the same
//! acceleration and velocity, so they neither strain nor ring. Rotation is not modelled (as
//! Anura3D's rigid body). The sums run over all nodes in a fixed order on the calling thread.

use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::step::grid_update::{damp, DampingRule};

/// The body's mass, its forces (without the soil's push) and momentum, and per component
/// whether a node of it holds it fixed; the damping it takes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Body {
    pub mass: f64,
    force: [f64; 3],
    momentum: [f64; 3],
    held: [bool; 3],
    damping: (DampingRule, f64),
}

/// Sets every node holding the structure's mass to the body's acceleration (see the module's
/// description): `loads`, its face loads at multiplier 1 and the multiplier; `damping`, the
/// rule and factor. Returns the body and that acceleration.
pub(super) fn as_one_body<R: Real>(
    g: &mut Grid<R>,
    fixed: &[[bool; 3]],
    (traction, scale): (&[V3<R>], R),
    (rule, alpha): (DampingRule, R),
) -> (Body, [f64; 3]) {
    let eps = g.empty_below;
    let (mut mass, mut force, mut momentum) = (0.0, [0.0; 3], [0.0; 3]);
    let mut held = [false; 3];
    for (n, &m) in g.mass.iter().enumerate() {
        if m <= eps {
            continue;
        }
        mass += m.f64();
        for d in 0..3 {
            held[d] |= fixed[n][d];
            let f = g.f_int[n][d] + g.f_ext[n][d] + scale * traction[n][d];
            force[d] += f.f64();
            momentum[d] += g.momentum[n][d].f64();
        }
    }
    let b = Body {
        mass,
        force,
        momentum,
        held,
        damping: (rule, alpha.f64()),
    };
    if mass == 0.0 {
        return (b, [0.0; 3]);
    }
    let body = b.acceleration([0.0; 3]);
    let at = body.map(R::of);
    for (&m, a) in g.mass.iter().zip(&mut g.acc) {
        if m > eps {
            *a = at;
        }
    }
    (b, body)
}

impl Body {
    /// The body's acceleration under its forces and the soil's push `push`, damped.
    fn acceleration(&self, push: [f64; 3]) -> [f64; 3] {
        let (rule, alpha) = self.damping;
        [0, 1, 2].map(|d| {
            if self.held[d] {
                0.0
            } else {
                damp(rule, alpha, self.force[d] + push[d], self.momentum[d]) / self.mass
            }
        })
    }
}

/// Sets every node holding the body's mass to its acceleration under its forces and the
/// soil's push `push` (kN).
pub(super) fn pushed<R: Real>(g: &mut Grid<R>, b: &Body, push: [f64; 3]) {
    if b.mass == 0.0 {
        return;
    }
    let at = b.acceleration(push).map(R::of);
    let eps = g.empty_below;
    for (&m, a) in g.mass.iter().zip(&mut g.acc) {
        if m > eps {
            *a = at;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_body_takes_its_forces_over_its_mass_and_a_fixed_component_holds_it() {
        let mut g = Grid::<f64>::new(3);
        g.mass = vec![1.0, 3.0, 0.0];
        g.f_int = vec![[1.0, 2.0, 0.0], [-1.0, -2.0, 0.0], [5.0, 5.0, 5.0]];
        g.f_ext = vec![[4.0, 1.0, 0.0], [0.0, -3.0, 0.0], [9.0, 9.0, 9.0]];
        g.acc = vec![[9.0, 9.0, 9.0]; 3];
        let traction = [[0.0; 3], [0.0, -6.0, 0.0], [1.0; 3]];
        let (loads, undamped) = ((&traction[..], 0.5), (DampingRule::Anura3d, 0.0));
        let (body, a) = as_one_body(&mut g, &[[false; 3]; 3], loads, undamped);
        // Forces (5, 3) and (-1, -8) over the mass 4; the third node holds no mass.
        assert_eq!(a, [1.0, -1.25, 0.0]);
        assert_eq!(body.mass, 4.0);
        pushed(&mut g, &body, [4.0, 0.0, 0.0]);
        assert_eq!(g.acc[0], [2.0, -1.25, 0.0]);
        assert_eq!(g.acc[1], g.acc[0]);
        assert_eq!(g.acc[0], g.acc[1]);
        assert_eq!(
            g.acc[2],
            [9.0, 9.0, 9.0],
            "a node without the body's mass is left"
        );
        // One node fixed in x (on an axis): the body does not move in x.
        let mut fixed = [[false; 3]; 3];
        fixed[1][0] = true;
        let (_, a) = as_one_body(&mut g, &fixed, loads, undamped);
        assert_eq!(a, [0.0, -1.25, 0.0]);
        // Damping acts on the body's force against its momentum.
        g.momentum = vec![[0.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.0; 3]];
        let (_, a) = as_one_body(&mut g, &fixed, loads, (DampingRule::Anura3d, 0.5));
        assert_eq!(a, [0.0, -0.625, 0.0]);
    }
}
