//! The clock and the load multipliers of one step, formed once at its start for every phase.

use crate::real::{Real, V3};
use crate::step::grid_update::{DampingRule, Drag};

/// What a step's phases read of the clock and the loads: the step's start, its length and
/// the load multipliers at its end, formed once at the start of the step.
#[derive(Debug, Clone, Copy)]
pub struct Moment<R: Real> {
    /// Simulated time at the start of the step (s).
    pub time: f64,
    /// The step's length (s).
    pub dt: f64,
    /// The gravity acceleration at the step's end (its curve applied).
    pub gravity: V3<R>,
    /// The face loads' multiplier at the step's end.
    pub traction: R,
    /// The liquid face loads' multiplier at the step's end.
    pub liquid: R,
    /// Local damping factor α.
    pub damping: R,
    /// How local damping is applied.
    pub damping_rule: DampingRule,
    /// How the drag is integrated (two-phase cases).
    pub drag: Drag,
}

impl<R: Real> Moment<R> {
    /// The time at the step's end.
    pub fn end(&self) -> f64 {
        self.time + self.dt
    }
}
