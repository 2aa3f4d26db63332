//! The nodal velocities of the re-mapped momentum: zero at empty nodes and in fixed
//! components.

use crate::element::Element;
use crate::parallel::gather::{Layout, Slots};
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};

/// The velocity of a node of `mass` from its re-mapped `momentum`: zero at an empty node and in
/// fixed components.
#[inline(always)]
pub(super) fn velocity<E: Element, R: Real>(
    momentum: &[R],
    mass: R,
    empty_below: R,
    fixed: &[bool; 3],
) -> V3<R> {
    let mut v = [R::ZERO; 3];
    if mass > empty_below {
        for c in 0..E::DIM {
            if !fixed[c] {
                v[c] = momentum[c] / mass;
            }
        }
    }
    v
}

/// A phase's nodal masses, fixities and velocities (the velocities written).
pub(super) struct PhaseNodes<'a, R: Real> {
    /// Nodal masses.
    pub mass: &'a [R],
    /// Fixed components.
    pub fixed: &'a [[bool; 3]],
    /// Velocities, written.
    pub vel: &'a mut [V3<R>],
}

/// Nodal velocities from the re-mapped momentum in `slots` (the scatter's, gathered on
/// `team`): the solid's from the first [`Element::DIM`] values of each node, and with
/// `liquid` the liquid's from the values after them. Nodes at most `empty_below` are empty.
pub(super) fn nodal_velocity<E: Element, R: Real>(
    (team, layout): (&Team, &Layout<R, E>),
    slots: &Slots<R>,
    empty_below: R,
    solid: PhaseNodes<'_, R>,
    liquid: Option<PhaseNodes<'_, R>>,
) {
    let (mass, fixed) = (solid.mass, solid.fixed);
    let out = Shared::new(solid.vel);
    let liquid = liquid.map(|l| (l.mass, l.fixed, Shared::new(l.vel)));
    let node = |n: usize, momentum: &[R]| {
        let v = velocity::<E, R>(momentum, mass[n], empty_below, &fixed[n]);
        // SAFETY: node n is this thread's only.
        unsafe { out.write(n, v) };
        if let Some((mass, fixed, out)) = &liquid {
            let w = velocity::<E, R>(&momentum[E::DIM..], mass[n], empty_below, &fixed[n]);
            // SAFETY: as above.
            unsafe { out.write(n, w) };
        }
    };
    match (E::DIM, liquid.is_some()) {
        (2, false) => layout.gather::<2, _>(team, slots, |n, m| node(n, &m)),
        (3, false) => layout.gather::<3, _>(team, slots, |n, m| node(n, &m)),
        (2, true) => layout.gather::<4, _>(team, slots, |n, m| node(n, &m)),
        _ => layout.gather::<6, _>(team, slots, |n, m| node(n, &m)),
    }
}
