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
    /// Anura3D's `step` multiplier over several load steps: constant within each, load step k
    /// of `steps` (the times in ((k - 1) T, k T], T = `load_step`) at
    /// from + (k / steps)(to - from).
    Stairs {
        /// The first number of the CPS line.
        from: f64,
        /// The second, reached in the last load step.
        to: f64,
        /// Duration of a load step (s).
        load_step: f64,
        /// Number of load steps.
        steps: u32,
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
            LoadCurve::Stairs {
                from,
                to,
                load_step,
                steps,
            } => {
                // A step that ends a load step ends at its time up to round-off (the clock is
                // a sum of steps): it still belongs to that load step.
                let k = (t / load_step - 1e-9).ceil().clamp(1.0, f64::from(steps));
                from + k / f64::from(steps) * (to - from)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stairs_hold_each_load_steps_value() {
        let c = LoadCurve::Stairs {
            from: 0.0,
            to: 1.0,
            load_step: 0.05,
            steps: 4,
        };
        assert_eq!(c.at(1e-15), 0.25);
        assert_eq!(c.at(0.05), 0.25);
        assert_eq!(c.at(0.05 * (1.0 + 1e-15)), 0.25);
        assert_eq!(c.at(0.0500001), 0.5);
        assert_eq!(c.at(0.2), 1.0);
        assert_eq!(c.at(0.3), 1.0);
        let down = LoadCurve::Stairs {
            from: 10.0,
            to: 2.0,
            load_step: 1.0,
            steps: 2,
        };
        assert_eq!(down.at(0.5), 6.0);
        assert_eq!(down.at(1.5), 2.0);
    }
}
