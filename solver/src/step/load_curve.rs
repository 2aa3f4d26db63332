//! Load multipliers over time (gravity, tractions, liquid loads, prescribed velocities).

/// How a load grows with time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadCurve {
    /// Full value from the first step.
    Step,
    /// Linear from 0 at t = 0 to 1 at t = `over`, then 1.
    Ramp {
        /// Seconds to full load.
        over: f64,
    },
}

impl LoadCurve {
    /// A ramp over `over` seconds, or a step when `over` is 0.
    pub fn ramp(over: f64) -> Self {
        if over > 0.0 {
            LoadCurve::Ramp { over }
        } else {
            LoadCurve::Step
        }
    }

    /// Multiplier at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            LoadCurve::Step => 1.0,
            LoadCurve::Ramp { over } => (t / over).min(1.0),
        }
    }
}
