//! Reaction forces of prescribed-velocity sets (`reaction.csv`, docs/design.md §4.9).
//!
//! The reaction of a set is the force its prescription exerts on the body: over the set's
//! constrained nodal components (in ascending node order, then x, y, z),
//! Σ (m a_prescribed - f), with f = f_int + f_ext + face loads the force the rest of the body
//! and the loads put on that component. Local damping never acts on a constrained component
//! (its acceleration is prescribed, not computed), so it is not part of f. For a quasi-static
//! push this is the resultant of the soil's stresses on the footing, less the weight of the
//! nodes' own share of mass.

use crate::step::load_curve::LoadCurve;

/// One prescribed-velocity set's reaction and the displacement imposed so far.
#[derive(Debug, Clone, PartialEq)]
pub struct Reaction {
    /// The set's name (the scene entry's `name`, or the GOM section's keyword).
    pub name: String,
    /// Velocity (m/s) at multiplier 1 in the prescribed components, 0 in the others (for sets
    /// whose rows differ, the first row's).
    pub velocity: [f64; 3],
    /// Multiplier value at full load.
    pub scale: f64,
    /// How the multiplier grows with time.
    pub curve: LoadCurve,
    /// The reaction (kN) of the last step.
    pub force: [f64; 3],
    /// ∫ multiplier dt so far (s), summed step by step at each step's end-of-step multiplier,
    /// as the nodes move.
    pub travel: f64,
    /// For a set reported as its mean over the steps since the last output (contact's, whose
    /// step-by-step values are impulses over one step, and so noisy): ∫ force dt and the time
    /// summed since then.
    pub window: Option<([f64; 3], f64)>,
}

impl Reaction {
    /// A set at rest, before any step.
    pub fn new(
        name: &str,
        velocity: [f64; 3],
        directions: [bool; 3],
        scale: f64,
        curve: LoadCurve,
    ) -> Self {
        Reaction {
            name: name.to_string(),
            velocity: [0, 1, 2].map(|d| if directions[d] { velocity[d] } else { 0.0 }),
            scale,
            curve,
            force: [0.0; 3],
            travel: 0.0,
            window: None,
        }
    }

    /// A set of forces only (no prescribed motion), reported as the mean over the steps
    /// since the last output.
    pub fn averaged(name: &str) -> Self {
        Reaction {
            window: Some(([0.0; 3], 0.0)),
            ..Reaction::new(name, [0.0; 3], [false; 3], 1.0, LoadCurve::Step)
        }
    }

    /// The force `reaction.csv` reports: the last step's, or for an averaged set the mean
    /// over the steps since the last output (the last step's when none has passed).
    pub fn reported(&self) -> [f64; 3] {
        match self.window {
            Some((impulse, elapsed)) if elapsed > 0.0 => impulse.map(|i| i / elapsed),
            _ => self.force,
        }
    }

    /// Starts an averaged set's next window (after an output).
    pub fn restart_window(&mut self) {
        if let Some(w) = &mut self.window {
            *w = ([0.0; 3], 0.0);
        }
    }

    /// The multiplier at time `t`.
    pub fn multiplier(&self, t: f64) -> f64 {
        self.scale * self.curve.at(t)
    }

    /// The multiplier's rate over the step from `t` to `t + dt`: its change over `dt` (0 past
    /// an Anura3D file's end, [`LoadCurve::stopped`]).
    pub fn rate(&self, t: f64, dt: f64) -> f64 {
        if self.curve.stopped(t + dt) {
            return 0.0;
        }
        (self.multiplier(t + dt) - self.multiplier(t)) / dt
    }

    /// The displacement prescribed so far (m), per component.
    pub fn displacement(&self) -> [f64; 3] {
        self.velocity.map(|v| v * self.travel)
    }

    /// Accounts one step of length `dt` ending at `t_end`.
    pub fn advance(&mut self, t_end: f64, dt: f64) {
        self.travel += self.multiplier(t_end) * dt;
        if let Some((impulse, elapsed)) = &mut self.window {
            for (i, f) in impulse.iter_mut().zip(self.force) {
                *i += f * dt;
            }
            *elapsed += dt;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn travel_sums_the_end_of_step_multiplier() {
        let mut r = Reaction::new(
            "top",
            [0.0, -2.0, 1.0],
            [false, true, true],
            1.0,
            LoadCurve::ramp(1.0),
        );
        assert_eq!(r.velocity, [0.0, -2.0, 1.0]);
        let mut r0 = Reaction::new(
            "top",
            [3.0, -2.0, 1.0],
            [false, true, false],
            1.0,
            LoadCurve::Step,
        );
        assert_eq!(r0.velocity, [0.0, -2.0, 0.0]);
        for k in 1..=4 {
            r.advance(0.25 * k as f64, 0.25);
            r0.advance(0.25 * k as f64, 0.25);
        }
        // 0.25 (0.25 + 0.5 + 0.75 + 1.0) = 0.625 under the ramp, 1.0 under the step.
        assert_eq!(r.travel, 0.625);
        assert_eq!(r.displacement(), [0.0, -1.25, 0.625]);
        assert_eq!(r0.displacement(), [0.0, -2.0, 0.0]);
    }
}
