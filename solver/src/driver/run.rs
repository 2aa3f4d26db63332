//! The driver: time steps between output times, writing outputs and the summary, telling
//! observers (jobs, progress reporters, tests) as it goes.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::driver::checkpoint::{self, CheckpointError, Driver, Every, Fingerprint};
use crate::driver::engine::Engine;
use crate::driver::output::{self, Output};
use crate::driver::units;
use crate::element::Element;
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
    /// The moving mesh turned an element inside out.
    #[error(transparent)]
    Mesh(#[from] crate::step::moving_mesh::Inverted),
    /// A guard rail tripped: the run diverged (`run.json` says where and why).
    #[error(transparent)]
    Diverged(Box<crate::driver::guard::Divergence>),
    /// A Courant number above 1 without `force`.
    #[error(transparent)]
    Courant(#[from] crate::input::case::CourantError),
    /// Writing an output failed.
    #[error(transparent)]
    Output(#[from] mpm_shared::Error),
    /// Writing or reading the checkpoint failed, or it belongs to another case.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// A signal stopped the run after a step; the checkpoint holds its state.
    #[error("stopped by signal {signal} after step {step} (t = {time} s); the checkpoint and the outputs so far are in {}", .dir.display())]
    Interrupted {
        /// The signal's number.
        signal: usize,
        /// Steps taken.
        step: u64,
        /// Simulated time.
        time: f64,
        /// The output folder.
        dir: std::path::PathBuf,
    },
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
    #[error("no material point has id {} (probes; ids run from 1 to {last}, those of empty elements excepted); remove them or check the numbering", units::list(.unknown))]
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
            crate::driver::engine::StepError::Mesh(m) => RunError::Mesh(m),
            crate::driver::engine::StepError::Diverged(d) => RunError::Diverged(d),
        }
    }
}

/// How a run treats lost points, checkpoints and signals.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Deactivate material points that leave the mesh instead of stopping.
    pub drop_lost: bool,
    /// With `drop_lost`, the share of the points (0–1) that may leave before the run stops with
    /// an error; the run stops anyway when every point has left.
    pub max_lost: f64,
    /// Run a Courant number above 1 (refused otherwise).
    pub force: bool,
    /// When to write the checkpoint (`None`: never).
    pub checkpoint: Option<Every>,
    /// Continue from the folder's checkpoint (from the start when it has none).
    pub resume: bool,
    /// Set (to the signal's number) to stop after the current step with a checkpoint.
    pub stop: Option<Arc<AtomicUsize>>,
    /// For tests of resuming: abort the process, as a crash would, once it has taken this many
    /// steps (counted over the runs of a job, from where a resumed run starts).
    pub abort_after_step: Option<u64>,
    /// For tests of a team that changes while the run goes on: after this step, start the
    /// team again with this many threads (unpinned), as a core taken by another process does.
    pub rethread_after_step: Option<(u64, usize)>,
    /// The processes of the run (MPI ranks); `None`: this process alone.
    pub comm: Option<Arc<dyn crate::parallel::comm::Communicator>>,
    /// Over several ranks: cut the curve again when the largest rank holds more than this
    /// many times the mean number of points (0: never).
    pub rebalance: f64,
}

/// The imbalance of points between ranks past which a run re-partitions by default: a
/// rank with a fifth more points than the mean holds the others up by as much each step.
pub const DEFAULT_REBALANCE: f64 = 1.2;

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            drop_lost: false,
            max_lost: 0.1,
            force: false,
            checkpoint: None,
            resume: false,
            stop: None,
            abort_after_step: None,
            rethread_after_step: None,
            comm: None,
            rebalance: DEFAULT_REBALANCE,
        }
    }
}

/// What watches a run from outside the engine (a job such as the consolidation comparison,
/// or a test comparing with another code): told when the engine is set up and after each
/// output is written.
pub trait Observer<R: Real, E: Element = crate::element::tet4::Tet4> {
    /// The engine is set up, no step taken yet.
    fn on_start(&mut self, _engine: &Engine<R, E>) -> Result<(), RunError> {
        Ok(())
    }

    /// A step was taken (called every step: keep it cheap).
    fn on_step(&mut self, _engine: &Engine<R, E>) {}

    /// An output was written at the engine's current time.
    fn on_output(&mut self, _engine: &Engine<R, E>) {}

    /// The run reached its end time.
    fn on_end(&mut self, _engine: &Engine<R, E>) {}

    /// The observer's state that a resumed run needs (for a checkpoint; empty when none).
    fn save(&self) -> Vec<u8> {
        Vec::new()
    }

    /// Takes back the state of [`Observer::save`] (after `on_start`, when a run resumes).
    fn restore(&mut self, _state: &[u8]) -> Result<(), String> {
        Ok(())
    }
}

/// Two observers, told in turn.
pub struct Both<'a, R: Real, E: Element>(
    pub &'a mut dyn Observer<R, E>,
    pub &'a mut dyn Observer<R, E>,
);

impl<R: Real, E: Element> Observer<R, E> for Both<'_, R, E> {
    fn on_start(&mut self, engine: &Engine<R, E>) -> Result<(), RunError> {
        self.0.on_start(engine)?;
        self.1.on_start(engine)
    }

    fn on_step(&mut self, engine: &Engine<R, E>) {
        self.0.on_step(engine);
        self.1.on_step(engine);
    }

    fn on_output(&mut self, engine: &Engine<R, E>) {
        self.0.on_output(engine);
        self.1.on_output(engine);
    }

    fn on_end(&mut self, engine: &Engine<R, E>) {
        self.0.on_end(engine);
        self.1.on_end(engine);
    }

    fn save(&self) -> Vec<u8> {
        let a = self.0.save();
        let mut out = (a.len() as u64).to_le_bytes().to_vec();
        out.extend(a);
        out.extend(self.1.save());
        out
    }

    fn restore(&mut self, state: &[u8]) -> Result<(), String> {
        let n = state
            .get(..8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
            .filter(|&n| n <= (state.len() - 8) as u64)
            .ok_or("observers' state cut short")? as usize;
        self.0.restore(&state[8..8 + n])?;
        self.1.restore(&state[8 + n..])
    }
}

/// An observer that only looks at outputs.
struct OnOutput<F>(F);

impl<R: Real, E: Element, F: FnMut(&Engine<R, E>)> Observer<R, E> for OnOutput<F> {
    fn on_output(&mut self, engine: &Engine<R, E>) {
        (self.0)(engine)
    }
}

/// No observer.
pub struct Unobserved;

impl<R: Real, E: Element> Observer<R, E> for Unobserved {}

/// Runs `case` to its end time, writing into `dir`. Returns the engine's final state.
pub fn run<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
) -> Result<Engine<R, E>, RunError> {
    drive(case, dir, options, &mut Unobserved)
}

/// [`run`], handing the engine to `observe` after each output is written (e.g. to compare the
/// material points with another code's at every load step).
pub fn run_observed<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observe: &mut dyn FnMut(&Engine<R, E>),
) -> Result<Engine<R, E>, RunError> {
    drive(case, dir, options, &mut OnOutput(observe))
}

/// [`run`] with an [`Observer`].
pub fn run_with<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observer: &mut dyn Observer<R, E>,
) -> Result<Engine<R, E>, RunError> {
    drive(case, dir, options, observer)
}

/// Steps taken by this process, for [`RunOptions::abort_after_step`].
static PROCESS_STEPS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn drive<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    observer: &mut dyn Observer<R, E>,
) -> Result<Engine<R, E>, RunError> {
    let wall = Instant::now();
    case.check_courant(options.force)?;
    let fingerprint = Fingerprint::of(case, options.drop_lost);
    let saved = if options.resume {
        checkpoint::read(dir)?
    } else {
        None
    };
    if let Some(s) = &saved {
        if let Some(what) = s.fingerprint.difference(&fingerprint) {
            return Err(CheckpointError::Mismatch {
                dir: dir.to_path_buf(),
                what,
            }
            .into());
        }
    }
    let mut engine = match &options.comm {
        Some(comm) => {
            // A rank the launcher bound to cores of its own (`mpirun --bind-to socket`) pins
            // its threads there as one process does; an unbound one would pin onto the same
            // first cores as every other rank, so its threads stay unpinned.
            let bound = crate::parallel::machine::bound_to_some_cores();
            let engine_options = crate::driver::engine::Options {
                pin: if bound {
                    case.engine.pin
                } else {
                    crate::parallel::team::Pin::None
                },
                ..case.engine
            };
            Engine::<R, E>::with_communicator(
                case,
                options.drop_lost,
                engine_options,
                comm.clone(),
            )?
        }
        None => Engine::<R, E>::new(case, options.drop_lost)?,
    };
    if engine.is_distributed() && (options.checkpoint.is_some() || options.resume) {
        return Err(crate::driver::engine::SetupError::Distributed {
            ranks: engine.rank().1,
            what: "checkpoints",
        }
        .into());
    }
    observer.on_start(&engine)?;
    // Rank 0 writes the files, from every rank's points (one process: itself).
    let out = engine.on_root(|e| -> Result<Output, RunError> {
        check_probes(case, e)?;
        Ok(Output::new(dir, case, e)?)
    });
    let mut out = out.transpose()?;
    let mut d = Driver::default();
    if let Some(s) = saved {
        checkpoint::tidy(dir, &s.series, s.finished(case.output_times.len()))?;
        engine.restore(&s)?;
        observer
            .restore(&s.observer)
            .map_err(|what| s.corrupt(format!("job state: {what}")))?;
        out.as_mut()
            .expect("checkpoints run on one process")
            .resume(s.series.clone())?;
        d = s.driver;
    }
    // Wall seconds before this process, for run.json.
    let wall_before = d.wall;
    let elapsed = || wall_before + wall.elapsed().as_secs_f64();
    // run.json, written at the end, where a guard rail stops the run, or at a signal.
    let summary = |engine: &mut Engine<R, E>,
                   d: &Driver,
                   diverged: Option<&crate::driver::guard::Divergence>,
                   interrupted|
     -> Result<(), RunError> {
        let ranks = engine.rank_report().filter(|_| engine.is_distributed());
        engine
            .on_root(|e| {
                output::write_summary(
                    dir,
                    case,
                    e,
                    elapsed(),
                    d.stepping,
                    diverged,
                    interrupted,
                    ranks,
                )
            })
            .transpose()?;
        Ok(())
    };
    // Every output is written by rank 0 from every rank's points (one process: itself).
    let write = |engine: &mut Engine<R, E>, out: &mut Option<Output>| -> Result<(), RunError> {
        engine
            .on_root(|e| out.as_mut().expect("rank 0 has the output").write(e))
            .transpose()?;
        Ok(())
    };
    let save = |engine: &Engine<R, E>,
                out: &Option<Output>,
                d: &mut Driver,
                observer: &dyn Observer<R, E>| {
        d.wall = elapsed();
        let scalars = engine.checkpoint_scalars();
        let observed = observer.save();
        checkpoint::write(
            dir,
            &checkpoint::State {
                fingerprint: &fingerprint,
                driver: *d,
                scalars: &scalars,
                particles: &engine.particles,
                series: out
                    .as_ref()
                    .expect("checkpoints run on one process")
                    .series(),
                observer: &observed,
            },
        )
    };
    let mut last_checkpoint = Instant::now();
    if options.checkpoint.is_some() && engine.steps == 0 && d.next_output == 0 {
        // A run killed before its first output resumes from here, not from nothing.
        save(&engine, &out, &mut d, &*observer)?;
    }
    let stopped = |engine: &Engine<R, E>| {
        let seen = options
            .stop
            .as_ref()
            .map_or(0, |s| s.load(Ordering::SeqCst));
        // Over MPI ranks every rank stops at the same step, the outputs being collective: at
        // the signal any rank has seen (the launcher delivers it to each at its own moment).
        let seen = if engine.is_distributed() {
            engine.communicator().max(seen as f64) as usize
        } else {
            seen
        };
        Some(seen)
            .filter(|&s| s != 0)
            .map(|signal| RunError::Interrupted {
                signal,
                step: engine.steps,
                time: engine.time,
                dir: dir.to_path_buf(),
            })
    };
    for (k, &t_out) in case.output_times.iter().enumerate().skip(d.next_output) {
        let t0 = Instant::now();
        let t_start = d.stepping;
        loop {
            if let Some(qs) = &case.quasi_static {
                // Anura3D ends a quasi-static load step once converged or when its step counter,
                // which starts at 1, exceeds the limit: after `limit + 1` steps, the first of
                // the calculation being its tiny initial step. Without a limit, at the load
                // step's duration.
                let done = if d.taken == 0 {
                    false
                } else if engine.converged(qs) {
                    true
                } else if let Some(m) = qs.max_steps {
                    d.taken > m
                } else {
                    engine.time - d.begun >= (t_out - d.load_step_start) * (1.0 - 1e-12)
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
                if let crate::driver::engine::StepError::Diverged(dv) = &e {
                    // The state at the failing step, when still finite, is the most useful
                    // last output (where it went wrong); otherwise the outputs so far stand.
                    if dv.check != crate::driver::guard::Check::NonFinite {
                        write(&mut engine, &mut out)?;
                    }
                    d.stepping = t_start + t0.elapsed().as_secs_f64();
                    summary(&mut engine, &d, Some(dv), false)?;
                }
                return Err(e.into());
            }
            d.taken += 1;
            if let Some(taken) = engine.team.recheck() {
                let before = engine.team.threads;
                let team = engine.team.replacement(None, &taken);
                engine.rethread(team.map_err(crate::driver::engine::SetupError::from)?);
                log::warn!(
                    "step {}: other processes took cores {taken:?}, where worker threads were pinned; {before} threads pinned became {} {} (the results do not change)",
                    engine.steps,
                    engine.team.threads,
                    if engine.team.pinned.iter().any(Option::is_some) { "on the free cores" } else { "unpinned" }
                );
            }
            if let Some((at, threads)) = options.rethread_after_step {
                if engine.steps == at {
                    let team = engine.team.replacement(Some(threads), &[]);
                    engine.rethread(team.map_err(crate::driver::engine::SetupError::from)?);
                }
            }
            engine.rebalance(case, options.rebalance)?;
            if options.drop_lost && engine.lost > 0 {
                check_lost(&engine, options.max_lost)?;
            }
            observer.on_step(&engine);
            if let Some(n) = options.abort_after_step {
                if PROCESS_STEPS.fetch_add(1, Ordering::SeqCst) + 1 >= n {
                    std::process::abort();
                }
            }
            let interrupted = stopped(&engine);
            let due = match options.checkpoint {
                None => false,
                Some(Every::Steps(n)) => engine.steps % n.max(1) == 0,
                Some(Every::Wall(s) | Every::Outputs { max_wall: s }) => {
                    last_checkpoint.elapsed().as_secs_f64() >= s
                }
            };
            if due || interrupted.is_some() {
                d.stepping = t_start + t0.elapsed().as_secs_f64();
                save(&engine, &out, &mut d, &*observer)?;
                last_checkpoint = Instant::now();
            }
            if let Some(e) = interrupted {
                summary(&mut engine, &d, None, true)?;
                return Err(e);
            }
        }
        d.load_step_start = t_out;
        d.stepping = t_start + t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        write(&mut engine, &mut out)?;
        observer.on_output(&engine);
        // The next load step starts here.
        (d.next_output, d.taken, d.begun) = (k + 1, 0, engine.time);
        let last = k + 1 == case.output_times.len();
        // A signal during the last output lets the run complete.
        let interrupted = stopped(&engine).filter(|_| !last);
        if options.checkpoint.is_some()
            && (last
                || interrupted.is_some()
                || matches!(options.checkpoint, Some(Every::Outputs { .. })))
        {
            save(&engine, &out, &mut d, &*observer)?;
            last_checkpoint = Instant::now();
        }
        engine.phase_seconds[5] += t1.elapsed().as_secs_f64();
        if let Some(e) = interrupted {
            summary(&mut engine, &d, None, true)?;
            return Err(e);
        }
    }
    observer.on_end(&engine);
    summary(&mut engine, &d, None, false)?;
    Ok(engine)
}

/// Refuses probe ids that name no material point of the case (before any step is taken).
pub fn check_probes<R: Real, E: Element>(
    case: &Case,
    engine: &Engine<R, E>,
) -> Result<(), RunError> {
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
fn check_lost<R: Real, E: Element>(engine: &Engine<R, E>, max_lost: f64) -> Result<(), RunError> {
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
