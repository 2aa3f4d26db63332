//! The driver: time steps between output times, writing outputs and the summary, telling
//! observers (jobs, progress reporters, tests) as it goes.

use std::path::Path;
use std::time::Instant;

use crate::driver::engine::Engine;
use crate::driver::output::{self, Output};
use crate::driver::units;
use crate::input::case::Case;
use crate::real::Real;

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Set-up failed (mesh, material points, time step).
    #[error(transparent)]
    Setup(#[from] crate::driver::engine::SetupError),
    /// A job could not start (e.g. a consolidation comparison on a case without one saturated
    /// material).
    #[error(transparent)]
    Job(Box<dyn std::error::Error + Send + Sync>),
    /// A material point left the mesh.
    #[error(transparent)]
    Lost(#[from] crate::driver::engine::Lost),
    /// A guard rail tripped: the run diverged (`run.json` says where and why).
    #[error(transparent)]
    Diverged(Box<crate::driver::guard::Divergence>),
    /// A Courant number above 1 without `force`.
    #[error(transparent)]
    Courant(#[from] crate::input::case::CourantError),
    /// Writing an output failed.
    #[error(transparent)]
    Output(#[from] mpm_shared::Error),
    /// The step limit was reached before the end time.
    #[error("stopped after the maximum of {0} time steps at t = {1} s")]
    MaxSteps(u64, f64),
    /// Under `--drop-lost`, more points left the mesh than allowed.
    #[error("{lost} of {points} material points ({percent:.1} %) have left the mesh by t = {}, more than --max-lost allows ({allowed:.1} %); the body is leaving the mesh (missing supports or fixities, a mesh too small for the run-out, or an unstable run): the outputs so far are in the output folder", units::duration(*.time))]
    TooManyLost {
        /// Points deactivated so far.
        lost: u64,
        /// Points placed.
        points: usize,
        /// Their share, percent.
        percent: f64,
        /// The limit, percent.
        allowed: f64,
        /// Simulated time (s).
        time: f64,
    },
    /// Probe ids that name no material point.
    #[error("no material point has id {} (probes; ids run from 1 to {last}, those of empty elements excepted); remove them or check the numbering", list(.unknown))]
    UnknownProbes {
        /// The ids not found.
        unknown: Vec<u32>,
        /// The largest id of the case.
        last: u32,
    },
}

impl From<crate::driver::engine::StepError> for RunError {
    fn from(e: crate::driver::engine::StepError) -> Self {
        match e {
            crate::driver::engine::StepError::Lost(l) => RunError::Lost(l),
            crate::driver::engine::StepError::Diverged(d) => RunError::Diverged(d),
        }
    }
}

fn list(ids: &[u32]) -> String {
    let mut s: Vec<String> = ids.iter().take(20).map(|i| i.to_string()).collect();
    if ids.len() > 20 {
        s.push(format!("and {} more", ids.len() - 20));
    }
    s.join(", ")
}

/// How a run treats lost points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOptions {
    /// Deactivate material points that leave the mesh instead of stopping.
    pub drop_lost: bool,
    /// With `drop_lost`, the share of the points (0–1) that may leave before the run stops with
    /// an error; the run stops anyway when every point has left.
    pub max_lost: f64,
    /// Run a Courant number above 1 (refused otherwise).
    pub force: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            drop_lost: false,
            max_lost: 0.1,
            force: false,
        }
    }
}

/// What watches a run from outside the engine (a job such as the consolidation comparison,
/// or a test comparing with another code): told when the engine is set up and after each
/// output is written.
pub trait Observer<R: Real> {
    /// The engine is set up, no step taken yet.
    fn on_start(&mut self, _engine: &Engine<R>) -> Result<(), RunError> {
        Ok(())
    }

    /// A step was taken (called every step: keep it cheap).
    fn on_step(&mut self, _engine: &Engine<R>) {}

    /// An output was written at the engine's current time.
    fn on_output(&mut self, _engine: &Engine<R>) {}

    /// The run reached its end time.
    fn on_end(&mut self, _engine: &Engine<R>) {}
}

/// Two observers, told in turn.
pub struct Both<'a, R: Real>(pub &'a mut dyn Observer<R>, pub &'a mut dyn Observer<R>);

impl<R: Real> Observer<R> for Both<'_, R> {
    fn on_start(&mut self, engine: &Engine<R>) -> Result<(), RunError> {
        self.0.on_start(engine)?;
        self.1.on_start(engine)
    }

    fn on_step(&mut self, engine: &Engine<R>) {
        self.0.on_step(engine);
        self.1.on_step(engine);
    }

    fn on_output(&mut self, engine: &Engine<R>) {
        self.0.on_output(engine);
        self.1.on_output(engine);
    }

    fn on_end(&mut self, engine: &Engine<R>) {
        self.0.on_end(engine);
        self.1.on_end(engine);
    }
}

/// An observer that only looks at outputs.
struct OnOutput<F>(F);

impl<R: Real, F: FnMut(&Engine<R>)> Observer<R> for OnOutput<F> {
    fn on_output(&mut self, engine: &Engine<R>) {
        (self.0)(engine)
    }
}

/// No observer.
pub struct Unobserved;

impl<R: Real> Observer<R> for Unobserved {}

/// Runs `case` to its end time, writing into `dir`. Returns the engine's final state.
pub fn run<R: Real>(case: &Case, dir: &Path, options: &RunOptions) -> Result<Engine<R>, RunError> {
    drive(case, dir, options, &mut Unobserved)
}

/// [`run`], handing the engine to `observe` after each output is written (e.g. to compare the
/// material points with another code's at every load step).
pub fn run_observed<R: Real>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observe: &mut dyn FnMut(&Engine<R>),
) -> Result<Engine<R>, RunError> {
    drive(case, dir, options, &mut OnOutput(observe))
}

/// [`run`] with an [`Observer`].
pub fn run_with<R: Real>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observer: &mut dyn Observer<R>,
) -> Result<Engine<R>, RunError> {
    drive(case, dir, options, observer)
}

fn drive<R: Real>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observer: &mut dyn Observer<R>,
) -> Result<Engine<R>, RunError> {
    let wall = Instant::now();
    // run.json, written at the end or where a guard rail stops the run.
    let summary = |engine: &Engine<R>, stepping: f64, diverged| {
        output::write_summary(
            dir,
            case,
            engine,
            wall.elapsed().as_secs_f64(),
            stepping,
            diverged,
        )
    };
    case.check_courant(options.force)?;
    let mut engine = Engine::<R>::new(case, options.drop_lost)?;
    check_probes(case, &engine)?;
    observer.on_start(&engine)?;
    let mut out = Output::new(dir, case, &engine)?;
    let mut stepping = 0.0;
    let mut load_step_start = 0.0;
    for &t_out in &case.output_times {
        let t0 = Instant::now();
        let mut taken = 0u64;
        let begun = engine.time;
        loop {
            if let Some(qs) = &case.quasi_static {
                // Anura3D ends a quasi-static load step once converged or when its step counter,
                // which starts at 1, exceeds the limit: after `limit + 1` steps, the first of
                // the calculation being its tiny initial step. Without a limit, at the load
                // step's duration.
                let done = if taken == 0 {
                    false
                } else if engine.converged(qs) {
                    true
                } else if let Some(m) = qs.max_steps {
                    taken > m
                } else {
                    engine.time - begun >= (t_out - load_step_start) * (1.0 - 1e-12)
                };
                if done {
                    break;
                }
            } else if engine.time >= t_out * (1.0 - 1e-12) {
                break;
            }
            if case.max_steps.is_some_and(|m| engine.steps >= m) {
                return Err(RunError::MaxSteps(engine.steps, engine.time));
            }
            let left = t_out - engine.time;
            let step = match case.initial_step {
                Some(h) if engine.steps == 0 => h.min(engine.dt),
                _ => engine.dt,
            };
            let (dt, snap) = if case.quasi_static.is_some() || step < left {
                (step, None)
            } else {
                (left, Some(t_out))
            };
            if let Err(e) = engine.step(dt, snap) {
                if let crate::driver::engine::StepError::Diverged(d) = &e {
                    // The state at the failing step, when still finite, is the most useful
                    // last output (where it went wrong); otherwise the outputs so far stand.
                    if d.check != crate::driver::guard::Check::NonFinite {
                        out.write(&engine)?;
                    }
                    stepping += t0.elapsed().as_secs_f64();
                    summary(&engine, stepping, Some(d))?;
                }
                return Err(e.into());
            }
            taken += 1;
            if options.drop_lost && engine.lost > 0 {
                check_lost(&engine, options.max_lost)?;
            }
            observer.on_step(&engine);
        }
        load_step_start = t_out;
        stepping += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        out.write(&engine)?;
        observer.on_output(&engine);
        engine.phase_seconds[5] += t1.elapsed().as_secs_f64();
    }
    observer.on_end(&engine);
    summary(&engine, stepping, None)?;
    Ok(engine)
}

/// Refuses probe ids that name no material point of the case (before any step is taken).
pub fn check_probes<R: Real>(case: &Case, engine: &Engine<R>) -> Result<(), RunError> {
    if case.probes.is_empty() {
        return Ok(());
    }
    let mut ids = engine.particles.id.clone();
    ids.sort_unstable();
    let unknown: Vec<u32> = case
        .probes
        .iter()
        .copied()
        .filter(|p| ids.binary_search(p).is_err())
        .collect();
    if unknown.is_empty() {
        Ok(())
    } else {
        Err(RunError::UnknownProbes {
            unknown,
            last: ids.last().copied().unwrap_or(0),
        })
    }
}

/// Stops a `--drop-lost` run once more than `max_lost` of its points (or all) have left.
fn check_lost<R: Real>(engine: &Engine<R>, max_lost: f64) -> Result<(), RunError> {
    let points = engine.particles.len();
    let share = engine.lost as f64 / points.max(1) as f64;
    if engine.lost as usize >= points || share > max_lost {
        return Err(RunError::TooManyLost {
            lost: engine.lost,
            points,
            percent: 100.0 * share,
            allowed: 100.0 * max_lost,
            time: engine.time,
        });
    }
    Ok(())
}
