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
use mpm_shared::cps::Cps;

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
    /// Only read and check the input, print a summary and exit.
    #[arg(long)]
    check: bool,
    /// Write the scene as an Anura3D case, DIR/NAME.GOM and DIR/NAME.CPS_001 (NAME: the scene
    /// file's stem), and exit without running; what Anura3D cannot reproduce is refused by name.
    #[arg(long, value_name = "DIR")]
    export_anura3d: Option<PathBuf>,
    /// Worker threads [default: all cores available to the process]. Results are
    /// byte-identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Thread placement: one thread per core, or left to the OS.
    #[arg(long, value_enum, default_value = "cores")]
    pin: PinArg,
    /// Let each thread first touch (and so place) the data it computes on; `off` initialises
    /// everything on the main thread (for measurement).
    #[arg(long, value_enum, default_value = "on")]
    first_touch: OnOff,
    /// Order the mesh along a space-filling curve before computing (skip with `none` for a
    /// mesh sfcb already ordered); material-point ids stay those of the input.
    #[arg(long, value_enum, default_value = "morton")]
    reorder: ReorderArg,
    /// Time integration of the Darcy drag in two-phase cases: `implicit` (per node, at the
    /// end-of-step velocities: stable at any permeability) or `explicit` (at the start-of-step
    /// velocities with Mieremet's critical step, as Anura3D: reproduces Anura3D to round-off).
    #[arg(long, value_enum, default_value = "implicit")]
    drag: DragArg,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum DragArg {
    Implicit,
    Explicit,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum PinArg {
    None,
    Cores,
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

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mpm-solve: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    let is_scene = args
        .input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if let Some(dir) = &args.export_anura3d {
        if !is_scene {
            bail!(
                "--export-anura3d needs a TOML scene; {} is not one",
                args.input.display()
            );
        }
        let done = mpm_solve::export_anura3d::export_scene(&args.input, dir)?;
        for n in &done.notes {
            eprintln!("mpm-solve: warning: {n}");
        }
        println!("wrote {} and {}", done.gom.display(), done.cps.display());
        return Ok(());
    }
    if is_scene {
        let case = mpm_solve::scene::load(&args.input)?;
        println!(
            "{}: {} elements, {} nodes, {} s in outputs of {} s",
            args.input.display(),
            case.model.element_count(),
            case.model.node_count(),
            case.end_time,
            case.output_times.first().copied().unwrap_or(0.0)
        );
        if args.check {
            return Ok(());
        }
        return solve(case, &args);
    }
    let cps_path = match (&args.cps, mpm_shared::io::is_stdio(&args.input)) {
        (Some(p), _) => p.clone(),
        (None, true) => bail!("reading the GOM from standard input needs --cps FILE"),
        (None, false) => args.input.with_extension("CPS_001"),
    };
    if args.check {
        let model = mpm_shared::read_model(&args.input)?;
        let data =
            std::fs::read(&cps_path).with_context(|| format!("reading {}", cps_path.display()))?;
        let (cps, warnings) = Cps::read(&data, &cps_path.display().to_string())?;
        for w in warnings {
            eprintln!("mpm-solve: warning: {w}");
        }
        let settings = cps.settings()?;
        println!(
            "{}: {} {} elements, {} nodes, {} materials; {} load step(s) of {} s, Courant {}",
            mpm_shared::display_name(&args.input),
            model.element_count(),
            model.element_type.keyword(),
            model.node_count(),
            model.materials().len(),
            settings.load_steps,
            settings.time_per_load_step,
            settings.courant
        );
        return Ok(());
    }
    let (case, _settings) = mpm_solve::anura3d::load(&args.input, &cps_path)?;
    solve(case, &args)
}

/// Runs `case` with the command line's probes, output folder and options.
fn solve(mut case: mpm_solve::case::Case, args: &Args) -> anyhow::Result<()> {
    let Some(out) = &args.out else {
        bail!("--out DIR is required to run a case")
    };
    case.drag = match args.drag {
        DragArg::Implicit => mpm_solve::case::Drag::Implicit,
        DragArg::Explicit => mpm_solve::case::Drag::Explicit,
    };
    case.probes.extend(&args.probe);
    case.probes.sort_unstable();
    case.probes.dedup();
    if args.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    case.engine = mpm_solve::engine::Options {
        threads: args.threads.unwrap_or(0),
        pin: match args.pin {
            PinArg::None => mpm_solve::team::Pin::None,
            PinArg::Cores => mpm_solve::team::Pin::Cores,
        },
        first_touch: matches!(args.first_touch, OnOff::On),
    };
    let how = match args.reorder {
        ReorderArg::None => mpm_solve::case::Reorder::None,
        ReorderArg::Morton => mpm_solve::case::Reorder::Morton,
        ReorderArg::Hilbert => mpm_solve::case::Reorder::Hilbert,
    };
    // A GOM with sections this tool does not understand cannot be renumbered: compute it in
    // its own order rather than refuse it.
    let how = match case.model.first_unremappable() {
        Some(k) if how != mpm_solve::case::Reorder::None => {
            eprintln!(
                "mpm-solve: warning: section $${k} cannot follow a renumbering; computing in the input's order"
            );
            mpm_solve::case::Reorder::None
        }
        _ => how,
    };
    let case = case.reordered(how).map_err(anyhow::Error::msg)?;
    let progress = std::io::stderr().is_terminal();
    if case.consolidation.is_some() {
        let (engine, t, w) =
            mpm_solve::consolidation::run_job::<f64>(&case, out, args.drop_lost, progress)?;
        done(&engine, out);
        for (name, tr) in
            std::iter::once(("default", &t)).chain(w.as_ref().map(|w| ("workshop", w)))
        {
            let last = tr.records.last().expect("at least one output");
            println!(
                "{name}: T_v {:.3}, settlement {:.4e} m (Terzaghi {:.4e}), RMS pore-pressure error {:.4} of u0",
                last.tv, last.settlement, last.terzaghi, last.rms
            );
        }
        println!(
            "consolidation report: {}",
            out.join("consolidation.csv").display()
        );
        return Ok(());
    }
    let engine = mpm_solve::run::run::<f64>(&case, out, args.drop_lost, progress)?;
    done(&engine, out);
    Ok(())
}

/// The closing line of a run.
fn done(engine: &mpm_solve::engine::Engine<f64>, out: &std::path::Path) {
    println!(
        "done: {} steps of {:.3e} s, {} material points, outputs in {}",
        engine.steps,
        engine.dt,
        engine.particles.len(),
        out.display()
    );
}
