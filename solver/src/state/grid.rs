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
    /// Liquid arrays, present only when the case has a saturated material.
    pub liquid: Option<LiquidNodes<R>>,
}

/// Nodal arrays of the liquid (docs/design.md §4, two-phase).
#[derive(Debug, Clone)]
pub struct LiquidNodes<R: Real> {
    /// M_w = Σ ρw V N.
    pub mass: Vec<R>,
    /// M̄_w = Σ n ρw V N, the liquid's share of the mixture's inertia.
    pub mass_n: Vec<R>,
    /// Lumped drag Q = Σ (n ρw g / k) V N.
    pub drag: Vec<R>,
    /// Liquid momentum Σ ρw V w N, then that of the updated velocities.
    pub momentum: Vec<V3<R>>,
    /// Liquid force: -Σ V p ∇N + M_w g.
    pub force: Vec<V3<R>>,
    /// Liquid acceleration.
    pub acc: Vec<V3<R>>,
    /// Liquid velocity after the re-mapping.
    pub vel: Vec<V3<R>>,
    /// Smoothed pore-pressure rate per node.
    pub rate: Vec<R>,
}

impl<R: Real> LiquidNodes<R> {
    /// Arrays for `n` nodes.
    pub fn new(n: usize) -> Self {
        let z = [R::ZERO; 3];
        LiquidNodes {
            mass: vec![R::ZERO; n],
            mass_n: vec![R::ZERO; n],
            drag: vec![R::ZERO; n],
            momentum: vec![z; n],
            force: vec![z; n],
            acc: vec![z; n],
            vel: vec![z; n],
            rate: vec![R::ZERO; n],
        }
    }
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
            liquid: None,
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        let per_node = if self.liquid.is_some() { 16 + 16 } else { 16 };
        self.mass.len() * std::mem::size_of::<R>() * per_node
    }
}
