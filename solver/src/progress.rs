//! Progress of a run on standard error, for the command line: a bar on a terminal, or a line
//! every few seconds for a batch job's log. The library reports nothing itself; this observer
//! is told of every step.

use std::time::Instant;

use mpm_solve::driver::engine::Engine;
use mpm_solve::driver::run::{Observer, RunError};
use mpm_solve::driver::units;
use mpm_solve::element::Element;
use mpm_solve::real::Real;

/// How a run reports its progress on standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Progress {
    /// Silent.
    Off,
    /// A progress bar (for a terminal).
    Bar,
    /// One line every so many seconds (for logs of batch jobs): step, simulated time, rate, ETA.
    Lines {
        /// Seconds between lines.
        every: f64,
    },
}

/// Progress on standard error: a bar, or a line every few seconds; an observer of the run.
pub struct Reporter {
    mode: Progress,
    bar: Option<indicatif::ProgressBar>,
    total_steps: u64,
    end_time: f64,
    start: Instant,
    last: Instant,
    steps: u64,
}

impl Reporter {
    /// A reporter in `mode` for runs of about `total_steps` steps to `end_time` (s).
    pub fn new(mode: Progress, total_steps: u64, end_time: f64) -> Self {
        let now = Instant::now();
        Reporter {
            mode,
            bar: None,
            total_steps,
            end_time,
            start: now,
            last: now,
            steps: 0,
        }
    }
}

impl<R: Real, E: Element> Observer<R, E> for Reporter {
    /// Each run (a consolidation job makes two) starts its own count and bar.
    fn on_start(&mut self, _engine: &Engine<R, E>) -> Result<(), RunError> {
        let now = Instant::now();
        (self.start, self.last, self.steps) = (now, now, 0);
        self.bar = (self.mode == Progress::Bar).then(|| {
            let b = indicatif::ProgressBar::new(self.total_steps);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:40} {pos}/{len} steps, {per_sec}, ETA {eta}",
                )
                .expect("valid template"),
            );
            b
        });
        Ok(())
    }

    fn on_step(&mut self, engine: &Engine<R, E>) {
        let points = engine.particles.len();
        self.steps += 1;
        match self.mode {
            Progress::Off => {}
            Progress::Bar => {
                if let Some(b) = &self.bar {
                    b.inc(1);
                }
            }
            Progress::Lines { every } => {
                if self.last.elapsed().as_secs_f64() < every {
                    return;
                }
                self.last = Instant::now();
                let wall = self.start.elapsed().as_secs_f64();
                let per_step = wall / self.steps as f64;
                // The ETA follows simulated time (quasi-static load steps may end early).
                let left = if engine.time > 0.0 {
                    wall * (self.end_time - engine.time).max(0.0) / engine.time
                } else {
                    per_step * self.total_steps.saturating_sub(self.steps) as f64
                };
                eprintln!(
                    "mpm-solve: step {} of about {}, t = {} of {}, {} ({}), ETA {}",
                    units::count(self.steps as f64),
                    units::count(self.total_steps as f64),
                    units::duration(engine.time),
                    units::duration(self.end_time),
                    units::rate_of(1.0 / per_step, "steps"),
                    units::rate_of(points as f64 / per_step, "point-steps"),
                    units::duration(left)
                );
            }
        }
    }

    fn on_end(&mut self, _engine: &Engine<R, E>) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}
