//! The driver: time steps between output times, writing outputs, progress and the summary.

use std::path::Path;
use std::time::Instant;

use crate::case::Case;
use crate::consolidation::{apply_undrained_start, Layer, Start, Tracker};
use crate::engine::Engine;
use crate::output::{self, Output};
use crate::real::Real;

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Set-up failed (mesh, material points, time step).
    #[error("{0}")]
    Setup(String),
    /// A material point left the mesh.
    #[error(transparent)]
    Lost(#[from] crate::engine::Lost),
    /// Writing an output failed.
    #[error(transparent)]
    Output(#[from] mpm_shared::Error),
    /// The step limit was reached before the end time.
    #[error("stopped after the maximum of {0} time steps at t = {1} s")]
    MaxSteps(u64, f64),
}

/// Runs `case` to its end time, writing into `dir`. Returns the engine's final state.
pub fn run<R: Real>(
    case: &Case,
    dir: &Path,
    drop_lost: bool,
    progress: bool,
) -> Result<Engine<R>, RunError> {
    run_tracked(case, dir, drop_lost, progress).map(|(e, _)| e)
}

/// [`run`], handing the engine to `observe` after each output is written (e.g. to compare the
/// material points with another code's at every load step).
pub fn run_observed<R: Real>(
    case: &Case,
    dir: &Path,
    drop_lost: bool,
    progress: bool,
    observe: &mut dyn FnMut(&Engine<R>),
) -> Result<Engine<R>, RunError> {
    drive(case, dir, drop_lost, progress, observe).map(|(e, _)| e)
}

/// [`run`], and for a consolidation case (`case.consolidation`) its start state and the
/// record of every output time against Terzaghi.
pub fn run_tracked<R: Real>(
    case: &Case,
    dir: &Path,
    drop_lost: bool,
    progress: bool,
) -> Result<(Engine<R>, Option<Tracker>), RunError> {
    drive(case, dir, drop_lost, progress, &mut |_| {})
}

fn drive<R: Real>(
    case: &Case,
    dir: &Path,
    drop_lost: bool,
    progress: bool,
    observe: &mut dyn FnMut(&Engine<R>),
) -> Result<(Engine<R>, Option<Tracker>), RunError> {
    let wall = Instant::now();
    let mut engine = Engine::<R>::new(case, drop_lost).map_err(RunError::Setup)?;
    let mut tracker = match &case.consolidation {
        None => None,
        Some(spec) => {
            let layer = Layer::of(case, spec).map_err(RunError::Setup)?;
            if spec.start == Start::Undrained {
                apply_undrained_start(&mut engine, &layer);
            }
            Some(Tracker::new(&engine, layer, spec.start))
        }
    };
    let mut out = Output::new(dir, case, &engine)?;
    let total_steps = (case.end_time / engine.dt).ceil() as u64;
    let bar = progress.then(|| {
        let b = indicatif::ProgressBar::new(total_steps);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} steps, {per_sec}, ETA {eta}",
            )
            .expect("valid template"),
        );
        b
    });
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
            engine.step(case, dt, snap)?;
            taken += 1;
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
        load_step_start = t_out;
        stepping += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        out.write(&engine)?;
        if let Some(t) = &mut tracker {
            t.record(&engine);
        }
        observe(&engine);
        engine.phase_seconds[5] += t1.elapsed().as_secs_f64();
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    output::write_summary(dir, case, &engine, wall.elapsed().as_secs_f64(), stepping)?;
    Ok((engine, tracker))
}
