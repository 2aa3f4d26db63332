//! `mpm-solve`: explicit material point method on tetrahedral meshes.
//!
//! `mpm-solve SCENE.toml --out DIR` runs a TOML scene on a Gmsh mesh; `mpm-solve CASE.GOM --out
//! DIR` runs an Anura3D case (features it does not model are refused by name);
//! `mpm-solve SCENE.toml --export-anura3d DIR` writes the scene as an Anura3D case instead.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
mod console;
mod progress;
use console::say;

use mpm_solve::driver::dispatch::{dispatch, Generic};
use mpm_solve::driver::units;
use mpm_solve::element::Element;
use mpm_solve::input::case::{Case, Precision};
use mpm_solve::input::overrides::Overrides;
use mpm_solve::real::Real;
use progress::{Progress, Reporter};

/// Run an explicit MPM simulation.
///
/// Examples:
///   mpm-solve testdata/column_gravity.toml --out out/column
///   mpm-solve case.GOM --check
///   mpm-solve testdata/column_gravity.toml --export-anura3d out/a3d
#[derive(Debug, Parser)]
#[command(version, verbatim_doc_comment)]
struct Args {
    /// A TOML scene (`.toml`), or an Anura3D geometry CASE.GOM (`-` for standard input, then
    /// --cps is required).
    input: PathBuf,
    /// Calculation parameters for a GOM [default: CASE.CPS_001 beside it].
    #[arg(long)]
    cps: Option<PathBuf>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Material-point ids (1-based) written to history.csv, e.g. --probe 3,17.
    #[arg(long, value_delimiter = ',')]
    probe: Vec<u32>,
    /// Deactivate material points that leave the mesh (counted in run.json) instead of stopping.
    #[arg(long)]
    drop_lost: bool,
    /// With --drop-lost, the share of the material points (0 to 1) that may leave the mesh
    /// before the run stops with an error (it stops anyway when every point has left).
    #[arg(long, default_value_t = 0.1, value_name = "FRACTION", value_parser = fraction)]
    max_lost: f64,
    /// Refuse to start a run whose outputs are predicted to take more than this on disk
    /// (e.g. 500MB, 20GB); a run is also refused when they would not fit in the free space.
    #[arg(long, default_value = "4GB", value_name = "SIZE", value_parser = size)]
    max_output: f64,
    /// Refuse to start a run predicted to take more time steps than this (the critical step
    /// follows the stiffest, lightest material and the smallest element).
    #[arg(long, default_value = "1e8", value_name = "N", value_parser = positive)]
    max_steps: f64,
    /// Read and check the input, print what a run would cost (material points, time step,
    /// steps, output volume, memory, and the wall time from a few of its steps timed here:
    /// at most about 0.3 s after the set-up) and exit without running.
    #[arg(long)]
    check: bool,
    /// No progress on standard error.
    #[arg(long, short)]
    quiet: bool,
    /// Seconds between progress lines when standard error is not a terminal (a log file of a
    /// batch job); on a terminal a progress bar is drawn instead.
    #[arg(long, default_value_t = 5.0, value_name = "SECONDS", value_parser = positive)]
    progress_every: f64,
    /// Write the scene as an Anura3D case, DIR/NAME.GOM and DIR/NAME.CPS_001 (NAME: the scene
    /// file's stem), and exit without running; what Anura3D cannot reproduce is refused by name.
    #[arg(long, value_name = "DIR")]
    export_anura3d: Option<PathBuf>,
    /// Worker threads, 1 to 1024 [default: one per core available to the process that no
    /// other process keeps busy at the start]. Results are byte-identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Thread placement: `auto` pins one thread per free core when each thread has one and
    /// leaves them to the OS otherwise; `cores` pins thread k to the k-th core whatever runs
    /// there; `none` leaves placement to the OS.
    #[arg(long, value_enum, default_value = "auto")]
    pin: PinArg,
    /// Let each thread first touch (and so place) the data it computes on; `off` initialises
    /// everything on the main thread (for measurement).
    #[arg(long, value_enum, default_value = "on")]
    first_touch: OnOff,
    /// Ask Linux to back the large arrays with 2 MiB pages (transparent huge pages, where the
    /// kernel leaves them to programs that ask; for measurement: on the machines measured so
    /// far they did not pay, docs/design.md §5.4). Results do not depend on it.
    #[arg(long, value_enum, default_value = "off")]
    huge_pages: OnOff,
    /// Order the mesh along a space-filling curve before computing (skip with `none` for a
    /// mesh sfcb already ordered); material-point ids stay those of the input.
    #[arg(long, value_enum, default_value = "morton")]
    reorder: ReorderArg,
    /// Time integration of the Darcy drag in two-phase cases: `implicit` (per node, at the
    /// end-of-step velocities: stable at any permeability) or `explicit` (at the start-of-step
    /// velocities with Mieremet's critical step, as Anura3D: reproduces Anura3D to round-off).
    #[arg(long, value_enum, default_value = "implicit")]
    drag: DragArg,
    /// Precision of the particle and grid state: `f32` halves the memory traffic and is faster,
    /// `f64` is more accurate (docs/accuracy.md measures the trade) [default: the scene's
    /// `precision`, else f64]. Time, work and energies are summed in f64 either way.
    #[arg(long, value_enum)]
    precision: Option<PrecisionArg>,
    /// The points' gradients on the mesh's elements: `element` (their own, Anura3D's) or the
    /// dual-domain gradients, continuous across faces (`ddmp`, `ddmp-blended`; their error
    /// falls with refinement where the element's does not: docs/accuracy-ddmp.md)
    /// [default: the scene's `gradient`, else element].
    #[arg(long, value_enum)]
    basis: Option<BasisArg>,
    /// How a two-phase case is stepped: `explicit` (every term, as Anura3D: the step follows the
    /// pore water's wave speed) or `semi-implicit` (the pore pressure solved for on the nodes
    /// each step: the step follows the skeleton's, several times longer; docs/design.md §4.4c)
    /// [default: the scene's `time.scheme`, else explicit].
    #[arg(long, value_enum)]
    scheme: Option<SchemeArg>,
    /// Run a Courant number above 1 (refused otherwise: the explicit step is unstable; the
    /// guard rails then stop the run when it blows up).
    #[arg(long)]
    force: bool,
    /// Stop the run when |kinetic + strain + dissipated - work| exceeds this share of the
    /// largest energy term (single-phase runs; `off`: not checked) [default: 1].
    #[arg(long, value_name = "SHARE|off", value_parser = tolerance)]
    energy_tolerance: Option<Tolerance>,
    /// Write the run's complete state to OUT/checkpoint/ every N steps, or every DURATION of
    /// wall time (500, 30s, 10m, 2h) [default: at every output, and at most 10 minutes apart].
    /// It is written at the end and when a signal stops the run too.
    #[arg(long, value_name = "N|DURATION", value_parser = every)]
    checkpoint_every: Option<Every>,
    /// Continue the run in DIR from its last checkpoint, instead of --out DIR: give the case and
    /// the options of that run (a different case or result-changing option is refused by name).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "overwrite", "check", "export_anura3d"])]
    resume: Option<PathBuf>,
    /// Replace what the --out folder holds. Without it a non-empty folder is refused unless it
    /// holds a completed run of the same case and options (which is then replaced).
    #[arg(long)]
    overwrite: bool,
    /// Over MPI ranks: cut the curve again, balanced by the points each element holds, when
    /// the rank with the most material points holds more than RATIO times the mean (points
    /// migrate as the soil deforms); 0 never re-partitions. The results do not depend on it.
    #[arg(long, value_name = "RATIO", default_value_t = mpm_solve::driver::run::DEFAULT_REBALANCE, value_parser = ratio)]
    rebalance: f64,
    /// For tests of --resume: abort, as a crash would, once this process has taken STEP steps.
    #[arg(long, hide = true, value_name = "STEP")]
    abort_after_step: Option<u64>,
    /// For tests of a team started again mid-run (as when a core is taken): after step STEP,
    /// carry on with THREADS unpinned threads.
    #[arg(long, hide = true, value_name = "STEP:THREADS", value_parser = step_and_threads)]
    rethread_after_step: Option<(u64, usize)>,
}

/// `STEP:THREADS` of `--rethread-after-step`.
fn step_and_threads(s: &str) -> Result<(u64, usize), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("expected STEP:THREADS, not {s:?}"))?;
    let step = a.parse().map_err(|e| format!("STEP {a:?}: {e}"))?;
    let threads: usize = b.parse().map_err(|e| format!("THREADS {b:?}: {e}"))?;
    if threads == 0 {
        return Err("THREADS must be at least 1".into());
    }
    Ok((step, threads))
}

use mpm_solve::driver::checkpoint::{self, Every, Holds};

/// `--checkpoint-every`: a step count, or a duration with s, m or h.
fn every(s: &str) -> Result<Every, String> {
    let t = s.trim();
    let bad =
        || format!("expected a step count (500) or a wall-clock duration (30s, 10m, 2h), got {s}");
    if let Ok(n) = t.parse::<u64>() {
        return if n > 0 {
            Ok(Every::Steps(n))
        } else {
            Err(bad())
        };
    }
    let (num, scale) = match t.char_indices().last() {
        Some((i, 's')) => (&t[..i], 1.0),
        Some((i, 'm')) => (&t[..i], 60.0),
        Some((i, 'h')) => (&t[..i], 3600.0),
        _ => return Err(bad()),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(Every::Wall(v * scale)),
        _ => Err(bad()),
    }
}

/// The command that resumes this run: this one's arguments, `--out DIR` (and `--overwrite`)
/// replaced by `--resume DIR`.
fn resume_command(dir: &std::path::Path) -> String {
    let mut words = Vec::new();
    let mut args = std::env::args_os();
    words.push(
        args.next()
            .map_or("mpm-solve".into(), |a| a.to_string_lossy().into_owned()),
    );
    let mut rest = args.map(|a| a.to_string_lossy().into_owned());
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--out" | "--resume" | "--abort-after-step" => {
                rest.next();
            }
            "--overwrite" => {}
            _ if a.starts_with("--out=")
                || a.starts_with("--resume=")
                || a.starts_with("--abort-after-step=") => {}
            _ => words.push(a),
        }
    }
    words.push("--resume".into());
    words.push(dir.to_string_lossy().into_owned());
    words
        .iter()
        .map(|w| {
            if !w.is_empty()
                && w.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c))
            {
                w.clone()
            } else {
                format!("'{}'", w.replace('\'', "'\\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// `--energy-tolerance`: a positive share, or off.
#[derive(Debug, Clone, Copy)]
struct Tolerance(Option<f64>);

fn tolerance(s: &str) -> Result<Tolerance, String> {
    if s.eq_ignore_ascii_case("off") {
        return Ok(Tolerance(None));
    }
    positive(s).map(|v| Tolerance(Some(v)))
}

/// Exit status of a run stopped by a guard rail (docs/design.md §4.14, docs/guide/running.md "Exit codes").
const EXIT_DIVERGED: u8 = 3;

/// Exit status of a run stopped by signal `n` (130 for SIGINT, 143 for SIGTERM).
fn exit_signal(n: usize) -> u8 {
    (128 + n).min(255) as u8
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum PrecisionArg {
    F64,
    F32,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum DragArg {
    Implicit,
    Explicit,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum BasisArg {
    Element,
    Ddmp,
    DdmpBlended,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum SchemeArg {
    Explicit,
    SemiImplicit,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum PinArg {
    None,
    Cores,
    Auto,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum OnOff {
    On,
    Off,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum ReorderArg {
    None,
    Morton,
    Hilbert,
}

/// The library's messages (`log`) on standard error, as `mpm-solve: LEVEL: message`.
struct Messages;

impl log::Log for Messages {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }

    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            let level = match r.level() {
                log::Level::Error => "error",
                _ => "warning",
            };
            eprintln!("mpm-solve: {level}: {}", r.args());
        }
    }

    fn flush(&self) {}
}

static MESSAGES: Messages = Messages;

/// Large arrays on huge pages (`--huge-pages`).
#[global_allocator]
static ALLOC: mpm_solve::parallel::huge_pages::HugePageAlloc =
    mpm_solve::parallel::huge_pages::HugePageAlloc;

fn main() -> ExitCode {
    // The team's look at which cores are free overlaps reading the input.
    mpm_solve::parallel::machine::begin_early();
    // Only fails when a logger is already set, which nothing else does.
    let _ = log::set_logger(&MESSAGES).map(|()| log::set_max_level(log::LevelFilter::Warn));
    match run(Args::parse()) {
        // (A report that could not be written to standard output, other than to a reader
        // that went away, fails the command: `console`.)
        Ok(()) if console::failed() => ExitCode::FAILURE,
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if let Some(mpm_solve::driver::run::RunError::Interrupted { signal, dir, .. }) = e
                .chain()
                .find_map(|c| c.downcast_ref::<mpm_solve::driver::run::RunError>())
            {
                eprintln!("mpm-solve: {e:#}");
                eprintln!(
                    "mpm-solve: the outputs so far are valid; to continue the run:\n  {}",
                    resume_command(dir)
                );
                return ExitCode::from(exit_signal(*signal));
            }
            eprintln!("mpm-solve: error: {e:#}");
            let diverged = e.chain().any(|c| {
                c.downcast_ref::<mpm_solve::driver::guard::Divergence>()
                    .is_some()
                    || matches!(
                        c.downcast_ref::<mpm_solve::driver::run::RunError>(),
                        Some(mpm_solve::driver::run::RunError::Diverged(_))
                    )
            });
            // A calibration's divergence (`--check`) wrote no outputs.
            let calibration = e
                .chain()
                .find_map(|c| c.downcast_ref::<mpm_solve::driver::calibrate::CalibrationError>());
            let calibrating = calibration.is_some();
            let diverged = diverged || calibration.is_some_and(|c| c.diverged());
            if diverged && calibrating {
                ExitCode::from(EXIT_DIVERGED)
            } else if diverged {
                eprintln!(
                    "mpm-solve: the outputs stop at the last good state (run.pvd); run.json has \"status\": \"diverged\" and the diagnosis"
                );
                ExitCode::from(EXIT_DIVERGED)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// `--max-lost`: a share in [0, 1].
fn fraction(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "expected a fraction from 0 to 1 (0.1 = 10 %), got {s}"
        )),
    }
}

/// `--rebalance`: 0 (never) or a ratio of at least 1.
fn ratio(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v == 0.0 || (v >= 1.0 && v.is_finite()) => Ok(v),
        _ => Err(format!(
            "expected 0 (never) or a ratio of at least 1 (1.2: a fifth above the mean), got {s}"
        )),
    }
}

/// A positive number (`1e8` allowed).
fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a positive number, got {s}")),
    }
}

/// `--max-output`: bytes, with an optional k, M, G or T (powers of 1000) and an optional B.
fn size(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let t = t.strip_suffix(['B', 'b']).unwrap_or(t);
    let (num, scale) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let scale = match c.to_ascii_uppercase() {
                'K' => 1e3,
                'M' => 1e6,
                'G' => 1e9,
                'T' => 1e12,
                _ => return Err(format!("expected a size such as 500MB or 20GB, got {s}")),
            };
            (&t[..i], scale)
        }
        _ => (t, 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v * scale),
        _ => Err(format!("expected a size such as 500MB or 20GB, got {s}")),
    }
}

/// What the input file is, from its name.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Input {
    Scene,
    Gom,
}

fn input_kind(path: &std::path::Path) -> anyhow::Result<Input> {
    if mpm_shared::io::is_stdio(path) {
        return Ok(Input::Gom);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "toml" => Ok(Input::Scene),
        e if e == "gom" || e.starts_with("gom_stage") => Ok(Input::Gom),
        "msh" => {
            bail!(
            "{} is a Gmsh mesh; mpm-solve runs a scene or an Anura3D case. Either write a scene \
             that names it (a TOML file with `mesh = \"{}\"`, materials and fixities by physical \
             group, times: see testdata/column_gravity.toml and the README's \"Your first hour\"), \
             or convert it with `sfcb {} CASE.GOM` and give the GOM with a CPS",
            path.display(),
            path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default(),
            path.display()
        )
        }
        "cps_001" | "cps" => bail!(
            "{} holds calculation parameters; give the geometry CASE.GOM (its CPS beside it, or \
             --cps {})",
            path.display(),
            path.display()
        ),
        _ => bail!(
            "{}: expected a TOML scene (.toml) or an Anura3D geometry (.GOM), or `-` for a GOM on \
             standard input",
            path.display()
        ),
    }
}

/// The options that override the case's settings, as the library takes them.
fn overrides(args: &Args) -> Overrides {
    use mpm_solve::input::case::{Drag, Gradient, Reorder, Scheme};
    use mpm_solve::parallel::team::Pin;
    Overrides {
        threads: args.threads,
        pin: match args.pin {
            PinArg::None => Pin::None,
            PinArg::Cores => Pin::Cores,
            PinArg::Auto => Pin::Auto,
        },
        first_touch: matches!(args.first_touch, OnOff::On),
        huge_pages: matches!(args.huge_pages, OnOff::On),
        reorder: match args.reorder {
            ReorderArg::None => Reorder::None,
            ReorderArg::Morton => Reorder::Morton,
            ReorderArg::Hilbert => Reorder::Hilbert,
        },
        drag: match args.drag {
            DragArg::Implicit => Drag::Implicit,
            DragArg::Explicit => Drag::Explicit,
        },
        precision: args.precision.map(|p| match p {
            PrecisionArg::F64 => Precision::F64,
            PrecisionArg::F32 => Precision::F32,
        }),
        gradient: args.basis.map(|b| match b {
            BasisArg::Element => Gradient::Element,
            BasisArg::Ddmp => Gradient::Ddmp,
            BasisArg::DdmpBlended => Gradient::DdmpBlended,
        }),
        scheme: args.scheme.map(|s| match s {
            SchemeArg::Explicit => Scheme::Explicit,
            SchemeArg::SemiImplicit => Scheme::SemiImplicit {
                tolerance: mpm_solve::step::semi_implicit::DEFAULT_TOLERANCE,
            },
        }),
        energy_tolerance: args.energy_tolerance.map(|Tolerance(t)| t),
        probes: args.probe.clone(),
        force: args.force,
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    let overrides = overrides(&args);
    // Before the input is read: a mistyped thread count is refused before its threads start,
    // and the large arrays are allocated from here on.
    overrides.prepare_process()?;
    let kind = input_kind(&args.input)?;
    let is_scene = kind == Input::Scene;
    if let Some(dir) = &args.export_anura3d {
        if !is_scene {
            bail!(
                "--export-anura3d needs a TOML scene; {} is not one",
                args.input.display()
            );
        }
        let done = mpm_solve::input::export_anura3d::export_scene(&args.input, dir)?;
        for n in &done.notes {
            eprintln!("mpm-solve: warning: {n}");
        }
        say!("wrote {} and {}", done.gom.display(), done.cps.display());
        return Ok(());
    }
    let case = if is_scene {
        let case = mpm_solve::input::scene::load(&args.input)?;
        say!(
            "{}: {} elements, {} nodes; {} simulated in {} output(s)",
            args.input.display(),
            units::count(case.model.element_count() as f64),
            units::count(case.model.node_count() as f64),
            units::duration(case.time.end_time),
            case.time.output_times.len()
        );
        case
    } else {
        let cps_path = match (&args.cps, mpm_shared::io::is_stdio(&args.input)) {
            (Some(p), _) => p.clone(),
            (None, true) => bail!("reading the GOM from standard input needs --cps FILE"),
            (None, false) => {
                let p = args.input.with_extension("CPS_001");
                if !p.exists() {
                    bail!(
                        "{}: no calculation parameters beside it: expected {}; give them with --cps FILE",
                        args.input.display(),
                        p.display()
                    );
                }
                p
            }
        };
        let (case, settings) = mpm_solve::input::anura3d::load(&args.input, &cps_path)?;
        say!(
            "{}: {} {} elements, {} nodes, {} materials; {} load step(s) of {} s, Courant {}",
            mpm_shared::display_name(&args.input),
            case.model.element_count(),
            case.model.element_type.keyword(),
            case.model.node_count(),
            case.model.materials().len(),
            settings.load_steps,
            settings.time_per_load_step,
            settings.courant
        );
        case
    };
    solve(case, &args, &overrides)
}

/// Runs `case` with the command line's overrides, output folder and options (or, with
/// `--check`, predicts what a run would cost).
fn solve(case: Case, args: &Args, overrides: &Overrides) -> anyhow::Result<()> {
    let out = output_folder(args)?;
    let case = mpm_solve::input::overrides::apply(case, overrides)?;
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let plan = mpm_solve::input::preflight::plan(&case, threads).map_err(anyhow::Error::msg)?;
    let limits = mpm_solve::input::preflight::Limits {
        max_output_bytes: args.max_output,
        max_steps: args.max_steps,
    };
    let Some(out) = out else {
        return check_only(&case, plan, &limits);
    };
    plan.check(&limits, Some(out))?;
    if let Some(m) = &plan.mesh_limits {
        say!("{}", m.to_string().trim_start());
    }
    run_in(&case, &plan, out, args)
}

/// The run's output folder (`--out`, or `--resume`'s); `None` under `--check`.
fn output_folder(args: &Args) -> anyhow::Result<Option<&std::path::Path>> {
    match (args.out.as_ref().or(args.resume.as_ref()), args.check) {
        (_, true) => Ok(None),
        (Some(out), false) => {
            if out.exists() && !out.is_dir() {
                bail!(
                    "--out {}: is a file; --out names a folder for the outputs (created if missing)",
                    out.display()
                );
            }
            Ok(Some(out.as_path()))
        }
        (None, false) => bail!(
            "--out DIR is required to run a case (a folder for the outputs, created if missing; \
             --resume DIR continues an interrupted run); --check only predicts what a run would cost"
        ),
    }
}

/// `--check`: prints the plan of a run of `case` (with the wall time from a few of its steps
/// timed here, and cheaper settings), refused when over the limits.
fn check_only(
    case: &Case,
    plan: mpm_solve::input::preflight::Plan,
    limits: &mpm_solve::input::preflight::Limits,
) -> anyhow::Result<()> {
    let print = |plan: &mpm_solve::input::preflight::Plan| {
        say!("{plan}");
        let cheaper = mpm_solve::input::preflight::cheaper_settings(case);
        if !cheaper.is_empty() {
            say!("  cheaper at similar error on the accuracy map (docs/accuracy.md):");
            for line in cheaper {
                say!("    - {line}");
            }
        }
    };
    if let Err(e) = plan.check(limits, None) {
        print(&plan);
        return Err(e.into());
    }
    // The engine a run would build (its threads, pinning, first touch), which checks the
    // probes against the points it places and times a few steps of the case.
    struct Calibrate<'a>(&'a Case, u64);
    impl Generic for Calibrate<'_> {
        type Output = anyhow::Result<Option<mpm_solve::input::preflight::Calibration>>;
        fn call<R: Real, E: Element>(self) -> Self::Output {
            use mpm_solve::driver::calibrate;
            let mut engine = mpm_solve::driver::engine::Engine::<R, E>::new(self.0, false)?;
            mpm_solve::driver::run::check_probes(self.0, &engine)?;
            Ok(calibrate::calibrate(
                &mut engine,
                self.1,
                calibrate::BUDGET,
            )?)
        }
    }
    // (A float beyond u64 saturates.)
    let run_steps = plan.steps as u64;
    match dispatch(case, Calibrate(case, run_steps))? {
        Ok(Some(c)) => print(&plan.calibrated(c)),
        Ok(None) => print(&plan),
        Err(e) => {
            print(&plan);
            return Err(e);
        }
    }
    Ok(())
}

/// Runs `case` into the folder `out` (over MPI ranks when launched so), its plan `plan`.
fn run_in(
    case: &Case,
    plan: &mpm_solve::input::preflight::Plan,
    out: &std::path::Path,
    args: &Args,
) -> anyhow::Result<()> {
    let comm = communicator()?;
    let root = comm.as_ref().map_or(true, |c| c.rank() == 0);
    // A rank that fails leaves without MPI's finalisation (which would wait for the others):
    // the launcher then stops the job.
    let fail = |e: anyhow::Error| {
        std::mem::forget(comm.clone());
        Err(e)
    };
    if comm.is_some() && case.start.consolidation.is_some() {
        return fail(anyhow::anyhow!(
            "the consolidation job runs on one process; start it without mpirun"
        ));
    }
    let created = !out.exists();
    // Rank 0 alone owns the output folder of a run over MPI ranks.
    let _lock = if root {
        match take_folder(case, out, args) {
            Ok(lock) => Some(lock),
            Err(e) => return fail(e),
        }
    } else {
        None
    };
    let stop = stop_on_signals()?;
    let options = mpm_solve::driver::run::RunOptions {
        drop_lost: args.drop_lost,
        max_lost: args.max_lost,
        force: args.force,
        // A run over MPI ranks keeps no checkpoint (not modelled there yet).
        checkpoint: comm
            .is_none()
            .then(|| args.checkpoint_every.unwrap_or_default()),
        resume: args.resume.is_some(),
        stop: Some(stop),
        abort_after_step: args.abort_after_step,
        rethread_after_step: args.rethread_after_step,
        comm,
        rebalance: args.rebalance,
    };
    let mode = if args.quiet || !root {
        Progress::Off
    } else if std::io::stderr().is_terminal() {
        Progress::Bar
    } else {
        Progress::Lines {
            every: args.progress_every,
        }
    };
    let reporter = Reporter::new(
        mode,
        plan.steps.min(u64::MAX as f64) as u64,
        case.time.end_time,
    );
    // One code path, compiled once per precision and element type.
    let result = dispatch(
        case,
        Execute {
            case,
            out,
            options: &options,
            reporter,
        },
    )
    .map_err(anyhow::Error::from)
    .and_then(|r| r);
    if result.is_err() {
        // A failing rank of several must not wait in MPI's finalisation for ranks that may be
        // waiting for it: it leaves without, and the launcher stops the others.
        std::mem::forget(options.comm.clone());
    }
    // A run refused at set-up (before its first output) leaves no folder it created.
    if result.is_err() && created {
        remove_unused(out);
    }
    result
}

/// Installs the handlers of SIGINT and SIGTERM: a first one stops the run after its step, with
/// a checkpoint (the flag returned holds the signal); a second one ends the process at once.
fn stop_on_signals() -> anyhow::Result<std::sync::Arc<std::sync::atomic::AtomicUsize>> {
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let twice = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(
            sig,
            i32::from(exit_signal(sig as usize)),
            std::sync::Arc::clone(&twice),
        )
        .and_then(|_| signal_hook::flag::register(sig, std::sync::Arc::clone(&twice)))
        .and_then(|_| {
            signal_hook::flag::register_usize(sig, std::sync::Arc::clone(&stop), sig as usize)
        })
        .context("installing the signal handlers")?;
    }
    Ok(stop)
}

/// Removes the output folder `out` of a refused run when it holds nothing but its lock.
fn remove_unused(out: &std::path::Path) {
    let only_lock = std::fs::read_dir(out)
        .map(|d| d.flatten().all(|e| e.file_name() == checkpoint::LOCK))
        .unwrap_or(false);
    if only_lock {
        let _ = std::fs::remove_file(out.join(checkpoint::LOCK));
        let _ = std::fs::remove_dir(out);
    }
}

/// Takes the output folder for this run under its lock: a new or empty folder, a completed run
/// of the same case and options (replaced), anything under `--overwrite` (emptied), or, under
/// `--resume`, the run to continue. Anything else is refused by name.
fn take_folder(
    case: &mpm_solve::input::case::Case,
    out: &std::path::Path,
    args: &Args,
) -> anyhow::Result<checkpoint::FolderLock> {
    let shown = out.display();
    if args.resume.is_some() && !out.is_dir() {
        bail!("--resume {shown}: no such folder");
    }
    let fingerprint = checkpoint::Fingerprint::of(case, args.drop_lost);
    let lock = checkpoint::lock(out)?;
    let holds = checkpoint::holds(out, &fingerprint, case.time.output_times.len())?;
    if args.resume.is_some() {
        match holds {
            Holds::Other(what) => {
                return Err(checkpoint::CheckpointError::Mismatch {
                    dir: out.to_path_buf(),
                    what,
                }
                .into())
            }
            // Killed before its first checkpoint: nothing done is lost by starting again.
            Holds::Unknown if !checkpoint::path(out).exists() => {
                eprintln!("mpm-solve: {shown} holds no checkpoint yet (the run stopped during its set-up); starting from the beginning");
                checkpoint::clear(out)?;
            }
            // A damaged checkpoint: the library's read names the problem.
            Holds::Unknown => {
                checkpoint::read(out)?;
            }
            Holds::Nothing => {}
            Holds::SameFinished => {
                eprintln!("mpm-solve: the run in {shown} had already completed; its outputs are rewritten as they were");
            }
            Holds::SameUnfinished => {}
        }
        return Ok(lock);
    }
    if args.overwrite {
        checkpoint::clear(out)?;
        return Ok(lock);
    }
    match holds {
        Holds::Nothing => {}
        Holds::SameFinished => {
            eprintln!("mpm-solve: replacing the completed run of this case in {shown}");
            checkpoint::clear(out)?;
        }
        Holds::SameUnfinished => bail!(
            "--out {shown}: holds an interrupted run of this case; continue it with\n  {}\nor replace it with --overwrite",
            resume_command(out)
        ),
        Holds::Other(what) => bail!(
            "--out {shown}: holds a run of another case or with other options ({what}); choose another folder, or replace it with --overwrite"
        ),
        Holds::Unknown => bail!(
            "--out {shown}: is not empty and holds no run of this case (no readable checkpoint); choose another folder, or replace what it holds with --overwrite"
        ),
    }
    Ok(lock)
}

/// A run of `case` (or its consolidation job), in the precision and element type
/// [`dispatch`] chooses.
struct Execute<'a> {
    case: &'a mpm_solve::input::case::Case,
    out: &'a std::path::Path,
    options: &'a mpm_solve::driver::run::RunOptions,
    reporter: Reporter,
}

impl Generic for Execute<'_> {
    type Output = anyhow::Result<()>;
    fn call<R: Real, E: Element>(self) -> anyhow::Result<()> {
        execute::<R, E>(self.case, self.out, self.options, self.reporter)
    }
}

/// Runs `case` (or its consolidation job) in precision `R` with elements `E`.
fn execute<R: Real, E: Element>(
    case: &mpm_solve::input::case::Case,
    out: &std::path::Path,
    options: &mpm_solve::driver::run::RunOptions,
    mut reporter: Reporter,
) -> anyhow::Result<()> {
    if case.start.consolidation.is_some() {
        let (engine, t, w) = mpm_solve::jobs::consolidation::run_job_with::<R, E>(
            case,
            out,
            options,
            &mut reporter,
        )?;
        done(&engine, engine.particles.len() as u64, out);
        for (name, tr) in
            std::iter::once(("default", &t)).chain(w.as_ref().map(|w| ("workshop", w)))
        {
            let last = tr.records.last().expect("at least one output");
            say!(
                "{name}: T_v {:.3}, settlement {:.4e} m (Terzaghi {:.4e}), RMS pore-pressure error {:.4} of u0",
                last.tv, last.settlement, last.terzaghi, last.rms
            );
        }
        say!(
            "consolidation report: {}",
            out.join("consolidation.csv").display()
        );
        return Ok(());
    }
    if let Some(mut report) = mpm_solve::jobs::driving::Report::of(case, out) {
        use mpm_solve::driver::run::Both;
        let engine = mpm_solve::driver::run::run_with::<R, E>(
            case,
            out,
            options,
            &mut Both(&mut report, &mut reporter),
        )?;
        if let Some(e) = report.take_error() {
            return Err(e).context("writing the driving report");
        }
        done(&engine, engine.particles.len() as u64, out);
        if let Some(b) = report.blows.last() {
            say!(
                "driving: {} blow{}, tip {:.3} m below the ground, last set {:.1} mm; report: {}",
                b.blow,
                if b.blow == 1 { "" } else { "s" },
                b.tip_depth,
                b.set * 1e3,
                out.join("driving.csv").display()
            );
        }
        return Ok(());
    }
    let engine = mpm_solve::driver::run::run_with::<R, E>(case, out, options, &mut reporter)?;
    let points = engine
        .communicator()
        .sum_count(engine.particles.len() as u64);
    if engine.rank().0 == 0 {
        done(&engine, points, out);
    }
    Ok(())
}

/// The run's MPI ranks when an MPI launcher started this process with more than one (cargo
/// feature `mpi`); `None` otherwise.
fn communicator(
) -> anyhow::Result<Option<std::sync::Arc<dyn mpm_solve::parallel::comm::Communicator>>> {
    #[cfg(feature = "mpi")]
    {
        use mpm_solve::parallel::comm::Communicator as _;
        let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
            .iter()
            .any(|v| std::env::var_os(v).is_some());
        if launched {
            let world = mpm_solve::parallel::mpi_comm::MpiWorld::init()
                .context("initialising MPI (funneled threads)")?;
            if world.ranks() > 1 {
                return Ok(Some(std::sync::Arc::new(world)));
            }
        }
    }
    Ok(None)
}

/// The closing line of a run.
fn done<R: Real, E: Element>(
    engine: &mpm_solve::driver::engine::Engine<R, E>,
    points: u64,
    out: &std::path::Path,
) {
    let lost = if engine.lost > 0 {
        format!(", {} left the mesh", units::count(engine.lost as f64))
    } else {
        String::new()
    };
    say!(
        "done: {} simulated in {} step{} of {}, {} material points{lost}; outputs in {}",
        units::duration(engine.time),
        units::count(engine.steps as f64),
        if engine.steps == 1 { "" } else { "s" },
        units::duration(engine.dt),
        units::count(points as f64),
        out.display()
    );
}
