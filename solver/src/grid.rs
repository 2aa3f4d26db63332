//! Nodal (grid) arrays, allocated once and cleared each step.

use crate::real::{Real, V3};

/// Nodal quantities of the computational nodes.
#[derive(Debug, Clone)]
pub struct Grid<R: Real> {
    /// Lumped mass.
    pub mass: Vec<R>,
    /// Momentum, then (after the MUSL re-mapping) momentum of the updated particle velocities.
    pub momentum: Vec<V3<R>>,
    /// Internal force.
    pub f_int: Vec<V3<R>>,
    /// External force (gravity and point loads mapped from particles).
    pub f_ext: Vec<V3<R>>,
    /// Acceleration.
    pub acc: Vec<V3<R>>,
    /// Velocity after the MUSL re-mapping.
    pub vel: Vec<V3<R>>,
    /// Nodes at or below this mass are empty this step (set by the grid update).
    pub empty_below: R,
}

impl<R: Real> Grid<R> {
    /// Arrays for `n` nodes.
    pub fn new(n: usize) -> Self {
        let z = [R::ZERO; 3];
        Grid {
            mass: vec![R::ZERO; n],
            momentum: vec![z; n],
            f_int: vec![z; n],
            f_ext: vec![z; n],
            acc: vec![z; n],
            vel: vec![z; n],
            empty_below: R::ZERO,
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.mass.len() * std::mem::size_of::<R>() * 16
    }
}
