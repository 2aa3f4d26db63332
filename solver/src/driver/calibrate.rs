//! A short calibration for `--check`: a few time steps of the case itself, on the engine a run
//! would build (its threads, pinning and first touch), timed, so that the predicted wall time
//! is this machine's and this case's rather than the benchmarks' (docs/design.md §7.6). The
//! first step is left out of the timing: it faults in the pages first touch did not and warms
//! the caches, which a run pays once.

use std::time::{Duration, Instant};

use crate::driver::engine::{Engine, StepError};
use crate::element::Element;
use crate::input::preflight::Calibration;
use crate::real::Real;

/// The longest a calibration times steps for (after its first, untimed step).
pub const BUDGET: Duration = Duration::from_millis(300);

/// Fewest steps a calibration times, however long they take, where the run has as many.
pub const MIN_TIMED: u64 = 2;

/// Why a calibration measured nothing.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// A step failed: the run would fail there too.
    #[error("--check: step {step} of its calibration failed, as a run's would")]
    Step {
        /// The failing step, from 1.
        step: u64,
        /// Why.
        #[source]
        source: StepError,
    },
}

impl CalibrationError {
    /// Whether a guard rail tripped (a run would end as diverged).
    pub fn diverged(&self) -> bool {
        matches!(
            self,
            CalibrationError::Step {
                source: StepError::Diverged(_),
                ..
            }
        )
    }
}

/// Steps `engine` at its time step: one untimed step, then timed steps until `budget` has
/// passed (at least [`MIN_TIMED`]), never more than `run_steps` in all (the steps the run
/// would take). `None` when the run has fewer than two steps, which leave nothing to time.
/// The engine is left stepped: a calibration's engine is not the run's.
pub fn calibrate<R: Real, E: Element>(
    engine: &mut Engine<R, E>,
    run_steps: u64,
    budget: Duration,
) -> Result<Option<Calibration>, CalibrationError> {
    if run_steps < 2 {
        return Ok(None);
    }
    let mut taken = 0u64;
    let mut step = |engine: &mut Engine<R, E>| {
        taken += 1;
        let dt = engine.dt;
        engine
            .step(dt, None)
            .map_err(|source| CalibrationError::Step {
                step: taken,
                source,
            })
    };
    step(engine)?;
    let (start, mut timed) = (Instant::now(), 0u64);
    while 1 + timed < run_steps && (timed < MIN_TIMED || start.elapsed() < budget) {
        step(engine)?;
        timed += 1;
    }
    Ok(Some(Calibration {
        steps: timed,
        seconds: start.elapsed().as_secs_f64(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;

    fn engine() -> Engine<f64, Tet4> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata");
        let case = crate::input::scene::load(&dir.join("column_gravity.toml")).unwrap();
        Engine::new(&case, false).unwrap()
    }

    #[test]
    fn a_calibration_times_its_steps_after_the_first() {
        let mut e = engine();
        let c = calibrate(&mut e, 1_000, Duration::ZERO).unwrap().unwrap();
        // A zero budget still times the fewest steps, and the engine took one more.
        assert_eq!(c.steps, MIN_TIMED);
        assert_eq!(e.steps, MIN_TIMED + 1);
        assert!(c.seconds > 0.0 && c.per_step() > 0.0);
    }

    #[test]
    fn a_calibration_never_steps_past_the_run() {
        let mut e = engine();
        let c = calibrate(&mut e, 3, Duration::from_secs(60))
            .unwrap()
            .unwrap();
        assert_eq!((c.steps, e.steps), (2, 3));
        let mut e = engine();
        assert!(calibrate(&mut e, 1, Duration::from_secs(60))
            .unwrap()
            .is_none());
        assert_eq!(e.steps, 0);
    }
}
