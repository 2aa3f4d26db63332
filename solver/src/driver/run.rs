//! The driver: time steps between output times, writing outputs and the summary, telling
//! observers (jobs, progress reporters, tests) as it goes.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::driver::checkpoint::{self, CheckpointError, Driver, Every, Fingerprint};
use crate::driver::engine::Engine;
use crate::driver::guard::Check;
use crate::driver::output::{self, Output, Stop, Summary};
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
    /// The semi-implicit pressure solve did not converge.
    #[error(transparent)]
    Pressure(crate::step::semi_implicit::NotConverged),
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

impl RunError {
    /// Whether every rank of a run over MPI ranks stops with this error at the same step (the
    /// step's own failures, signals, limits), rather than one rank alone (its files).
    pub fn is_collective(&self) -> bool {
        !matches!(
            self,
            RunError::Job(_) | RunError::Output(_) | RunError::Checkpoint(_)
        )
    }
}

impl From<crate::driver::engine::StepError> for RunError {
    fn from(e: crate::driver::engine::StepError) -> Self {
        match e {
            crate::driver::engine::StepError::Lost(l) => RunError::Lost(l),
            crate::driver::engine::StepError::Mesh(m) => RunError::Mesh(m),
            crate::driver::engine::StepError::Diverged(d) => RunError::Diverged(d),
            crate::driver::engine::StepError::Pressure(p) => RunError::Pressure(p),
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
    let saved = saved_checkpoint(dir, options, &fingerprint)?;
    let mut engine = set_up::<R, E>(case, options)?;
    observer.on_start(&engine)?;
    // Rank 0 writes the files, from every rank's points (one process: itself).
    let out = engine.on_root(|e| -> Result<Output, RunError> {
        check_probes(case, e)?;
        Ok(Output::new(dir, case, e)?)
    });
    let mut run = Run {
        case,
        dir,
        options,
        fingerprint,
        out: out.transpose()?,
        d: Driver::default(),
        wall,
        wall_before: 0.0,
        last_checkpoint: Instant::now(),
    };
    run.start(&mut engine, observer, saved)?;
    match run.outputs(&mut engine, observer) {
        Ok(()) => {
            observer.on_end(&engine);
            run.summary(&mut engine, Stop::Completed)?;
            Ok(engine)
        }
        Err(e) => {
            run.stopped(&mut engine, &e);
            Err(e)
        }
    }
}

/// The folder's checkpoint when the run resumes, checked against the case and options now.
fn saved_checkpoint(
    dir: &Path,
    options: &RunOptions,
    fingerprint: &Fingerprint,
) -> Result<Option<checkpoint::Saved>, RunError> {
    if !options.resume {
        return Ok(None);
    }
    let saved = checkpoint::read(dir)?;
    if let Some(what) = saved
        .as_ref()
        .and_then(|s| s.fingerprint.difference(fingerprint))
    {
        return Err(CheckpointError::Mismatch {
            dir: dir.to_path_buf(),
            what,
        }
        .into());
    }
    Ok(saved)
}

/// The engine of a run: over MPI ranks with the run's communicator, else on this process.
fn set_up<R: Real, E: Element>(
    case: &Case,
    options: &RunOptions,
) -> Result<Engine<R, E>, RunError> {
    let engine = match &options.comm {
        Some(comm) => {
            // A rank the launcher bound to cores of its own (`mpirun --bind-to socket`) pins
            // its threads there as one process does; an unbound one would pin onto the same
            // first cores as every other rank, so its threads stay unpinned.
            let bound = crate::parallel::machine::bound_to_some_cores();
            let engine_options = crate::driver::engine::Options {
                pin: if bound {
                    case.run.engine.pin
                } else {
                    crate::parallel::team::Pin::None
                },
                ..case.run.engine
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
    Ok(engine)
}

/// A run under way: what it writes to, its bookkeeping between outputs, and its wall clock.
struct Run<'a> {
    case: &'a Case,
    dir: &'a Path,
    options: &'a RunOptions,
    fingerprint: Fingerprint,
    /// The outputs (rank 0's; `None` on the other ranks).
    out: Option<Output>,
    /// Output times done, steps of the load step, wall seconds (what a checkpoint keeps).
    d: Driver,
    /// When this process started the run.
    wall: Instant,
    /// Wall seconds of the run before this process (a resumed run's earlier ones).
    wall_before: f64,
    last_checkpoint: Instant,
}

impl Run<'_> {
    /// Wall seconds of the run so far.
    fn elapsed(&self) -> f64 {
        self.wall_before + self.wall.elapsed().as_secs_f64()
    }

    /// Resumes from `saved` (the engine, the observer, the outputs, the bookkeeping), or, for a
    /// run that takes checkpoints, writes the first one now: a run killed before its first
    /// output resumes from here, not from nothing.
    fn start<R: Real, E: Element>(
        &mut self,
        engine: &mut Engine<R, E>,
        observer: &mut dyn Observer<R, E>,
        saved: Option<checkpoint::Saved>,
    ) -> Result<(), RunError> {
        if let Some(s) = saved {
            let outputs = self.case.time.output_times.len();
            checkpoint::tidy(self.dir, &s.series, s.finished(outputs))?;
            engine.restore(&s)?;
            observer
                .restore(&s.observer)
                .map_err(|what| s.corrupt(format!("job state: {what}")))?;
            self.out
                .as_mut()
                .expect("checkpoints run on one process")
                .resume(s.series.clone())?;
            self.d = s.driver;
        }
        self.wall_before = self.d.wall;
        if self.options.checkpoint.is_some() && engine.steps == 0 && self.d.next_output == 0 {
            self.save(engine, &*observer)?;
        }
        Ok(())
    }

    /// Steps to each output time left and writes its outputs.
    fn outputs<R: Real, E: Element>(
        &mut self,
        engine: &mut Engine<R, E>,
        observer: &mut dyn Observer<R, E>,
    ) -> Result<(), RunError> {
        let times = &self.case.time.output_times;
        for (k, &t_out) in times.iter().enumerate().skip(self.d.next_output) {
            self.load_step(engine, observer, t_out)?;
            self.output(engine, observer, k)?;
        }
        Ok(())
    }

    /// Steps until the load step that ends at `t_out` is done.
    fn load_step<R: Real, E: Element>(
        &mut self,
        engine: &mut Engine<R, E>,
        observer: &mut dyn Observer<R, E>,
        t_out: f64,
    ) -> Result<(), RunError> {
        let t0 = Instant::now();
        let t_start = self.d.stepping;
        while !self.load_step_done(engine, t_out) {
            if self.case.time.max_steps.is_some_and(|m| engine.steps >= m) {
                return Err(RunError::MaxSteps(engine.steps, engine.time));
            }
            let (dt, snap) = self.next_step(engine, t_out);
            let stepped = engine.step(dt, snap);
            self.d.stepping = t_start + t0.elapsed().as_secs_f64();
            stepped?;
            self.d.taken += 1;
            self.after_step(engine, observer)?;
        }
        self.d.load_step_start = t_out;
        self.d.stepping = t_start + t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Whether the load step ending at `t_out` is done: at its time, or, quasi-static, as
    /// Anura3D ends one.
    fn load_step_done<R: Real, E: Element>(&self, engine: &Engine<R, E>, t_out: f64) -> bool {
        let d = &self.d;
        let Some(qs) = &self.case.time.quasi_static else {
            return engine.time >= t_out * (1.0 - 1e-12);
        };
        // Anura3D ends a quasi-static load step once converged or when its step counter, which
        // starts at 1, exceeds the limit: after `limit + 1` steps, the first of the
        // calculation being its tiny initial step. Without a limit, at the load step's
        // duration.
        if d.taken == 0 {
            false
        } else if engine.converged(qs) {
            true
        } else if let Some(m) = qs.max_steps {
            d.taken > m
        } else {
            engine.time - d.begun >= (t_out - d.load_step_start) * (1.0 - 1e-12)
        }
    }

    /// The next step's length, and the output time it ends on exactly, if it does.
    fn next_step<R: Real, E: Element>(
        &self,
        engine: &Engine<R, E>,
        t_out: f64,
    ) -> (f64, Option<f64>) {
        let left = t_out - engine.time;
        let step = match self.case.time.initial_step {
            Some(h) if engine.steps == 0 => h.min(engine.dt),
            _ => engine.dt,
        };
        if self.case.time.quasi_static.is_some() || step < left {
            (step, None)
        } else {
            (left, Some(t_out))
        }
    }

    /// Between steps: a new team where cores were taken, a new cut of the curve where the ranks'
    /// shares drifted apart, the lost points' limit, the observer, and a checkpoint when due or
    /// when a signal asks to stop (then the run stops, `Interrupted`).
    fn after_step<R: Real, E: Element>(
        &mut self,
        engine: &mut Engine<R, E>,
        observer: &mut dyn Observer<R, E>,
    ) -> Result<(), RunError> {
        self.rethread(engine)?;
        engine.rebalance(self.case, self.options.rebalance)?;
        if self.options.drop_lost && engine.lost > 0 {
            check_lost(engine, self.options.max_lost)?;
        }
        observer.on_step(engine);
        if let Some(n) = self.options.abort_after_step {
            if PROCESS_STEPS.fetch_add(1, Ordering::SeqCst) + 1 >= n {
                std::process::abort();
            }
        }
        let interrupted = self.interrupted(engine);
        let due = match self.options.checkpoint {
            None => false,
            Some(Every::Steps(n)) => engine.steps % n.max(1) == 0,
            Some(Every::Wall(s) | Every::Outputs { max_wall: s }) => {
                self.last_checkpoint.elapsed().as_secs_f64() >= s
            }
        };
        if due || interrupted.is_some() {
            self.save(engine, &*observer)?;
        }
        interrupted.map_or(Ok(()), Err)
    }

    /// A new team when other processes took cores where worker threads were pinned, or when a
    /// test asks for one after a given step (the results do not change).
    fn rethread<R: Real, E: Element>(&self, engine: &mut Engine<R, E>) -> Result<(), RunError> {
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
        if let Some((at, threads)) = self.options.rethread_after_step {
            if engine.steps == at {
                let team = engine.team.replacement(Some(threads), &[]);
                engine.rethread(team.map_err(crate::driver::engine::SetupError::from)?);
            }
        }
        Ok(())
    }

    /// The outputs of output time `k` (the load step done), and a checkpoint where the run
    /// takes one at outputs, at its last, or at a signal (which then stops it, unless it came
    /// during the last output).
    fn output<R: Real, E: Element>(
        &mut self,
        engine: &mut Engine<R, E>,
        observer: &mut dyn Observer<R, E>,
        k: usize,
    ) -> Result<(), RunError> {
        let t1 = Instant::now();
        self.write(engine)?;
        observer.on_output(engine);
        for r in &mut engine.reactions {
            r.restart_window();
        }
        // The next load step starts here.
        (self.d.next_output, self.d.taken, self.d.begun) = (k + 1, 0, engine.time);
        let last = k + 1 == self.case.time.output_times.len();
        let interrupted = self.interrupted(engine).filter(|_| !last);
        let at_outputs = matches!(self.options.checkpoint, Some(Every::Outputs { .. }));
        if self.options.checkpoint.is_some() && (last || interrupted.is_some() || at_outputs) {
            self.save(engine, &*observer)?;
        }
        engine.phase_seconds[5] += t1.elapsed().as_secs_f64();
        interrupted.map_or(Ok(()), Err)
    }

    /// Writes the outputs of the engine's state, by rank 0 from every rank's points (one
    /// process: itself).
    fn write<R: Real, E: Element>(&mut self, engine: &mut Engine<R, E>) -> Result<(), RunError> {
        let out = &mut self.out;
        engine
            .on_root(|e| out.as_mut().expect("rank 0 has the output").write(e))
            .transpose()?;
        Ok(())
    }

    /// Writes the checkpoint of the run's state now.
    fn save<R: Real, E: Element>(
        &mut self,
        engine: &Engine<R, E>,
        observer: &dyn Observer<R, E>,
    ) -> Result<(), RunError> {
        self.d.wall = self.elapsed();
        let scalars = engine.checkpoint_scalars();
        let observed = observer.save();
        let series = self
            .out
            .as_ref()
            .expect("checkpoints run on one process")
            .series();
        checkpoint::write(
            self.dir,
            &checkpoint::State {
                fingerprint: &self.fingerprint,
                driver: self.d,
                scalars: &scalars,
                particles: &engine.particles,
                series,
                observer: &observed,
            },
        )?;
        self.last_checkpoint = Instant::now();
        Ok(())
    }

    /// The stop a signal asks for, if any. Over MPI ranks every rank stops at the same step,
    /// the outputs being collective: at the signal any rank has seen (the launcher delivers it
    /// to each at its own moment).
    fn interrupted<R: Real, E: Element>(&self, engine: &Engine<R, E>) -> Option<RunError> {
        let seen = self
            .options
            .stop
            .as_ref()
            .map_or(0, |s| s.load(Ordering::SeqCst));
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
                dir: self.dir.to_path_buf(),
            })
    }

    /// Writes `run.json` for a run stopped as `stop` (collective).
    fn summary<R: Real, E: Element>(
        &self,
        engine: &mut Engine<R, E>,
        stop: Stop<'_>,
    ) -> Result<(), RunError> {
        let ranks = engine.rank_report().filter(|_| engine.is_distributed());
        let (dir, case, wall, stepping) = (self.dir, self.case, self.elapsed(), self.d.stepping);
        engine
            .on_root(|e| {
                let summary = Summary {
                    dir,
                    case,
                    wall,
                    stepping,
                    stop,
                    ranks,
                };
                output::write_summary(summary, e)
            })
            .transpose()?;
        Ok(())
    }

    /// After an error stopped the run mid-way: the state of a diverged step as the last
    /// output where it is still finite (where it went wrong; otherwise the outputs so far
    /// stand), and `run.json` saying how the run stopped and why. Over MPI ranks only for the
    /// errors every rank stops with (the rest may be one rank's, and the summary is
    /// collective). A failure to write these is reported, and the run's own error returned.
    fn stopped<R: Real, E: Element>(&mut self, engine: &mut Engine<R, E>, e: &RunError) {
        if engine.is_distributed() && !e.is_collective() {
            return;
        }
        let message = e.to_string();
        let stop = match e {
            RunError::Diverged(dv) => {
                let finite = !matches!(dv.check, Check::NonFinite | Check::Escaped);
                if finite {
                    if let Err(w) = self.write(engine) {
                        log::warn!("the diverged step's state could not be written: {w}");
                    }
                }
                Stop::Diverged(dv)
            }
            RunError::Interrupted { .. } => Stop::Interrupted(&message),
            _ => Stop::Failed(&message),
        };
        if let Err(w) = self.summary(engine, stop) {
            log::warn!("run.json could not be written: {w}");
        }
    }
}

/// Refuses probe ids that name no material point of the case (before any step is taken).
pub fn check_probes<R: Real, E: Element>(
    case: &Case,
    engine: &Engine<R, E>,
) -> Result<(), RunError> {
    if case.run.probes.is_empty() {
        return Ok(());
    }
    let mut ids = engine.particles.id.clone();
    ids.sort_unstable();
    let unknown: Vec<u32> = case
        .run
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
