//! `mpm-solve`: explicit material point method on tetrahedral meshes.
//!
//! This release reads and checks a case (GOM + CPS, or a GOM from standard input with `--cps`)
//! and prints what it holds; the time integration arrives with the solver issue.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Parser;
use mpm_shared::cps::Cps;

/// Check an Anura3D case (GOM + CPS) and summarise it.
#[derive(Debug, Parser)]
#[command(version)]
struct Args {
    /// The case geometry: CASE.GOM, or `-` for standard input (then --cps is required).
    case: PathBuf,
    /// Calculation parameters [default: CASE.CPS_001 beside the GOM].
    #[arg(long)]
    cps: Option<PathBuf>,
    /// Only read and check the input, print a summary and exit.
    #[arg(long)]
    check: bool,
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
    let cps_path = match (&args.cps, mpm_shared::io::is_stdio(&args.case)) {
        (Some(p), _) => p.clone(),
        (None, true) => bail!("reading the GOM from standard input needs --cps FILE"),
        (None, false) => args.case.with_extension("CPS_001"),
    };
    let model = mpm_shared::read_model(&args.case)?;
    let data =
        std::fs::read(&cps_path).with_context(|| format!("reading {}", cps_path.display()))?;
    let (cps, warnings) = Cps::read(&data, &cps_path.display().to_string())?;
    for w in warnings {
        eprintln!("mpm-solve: warning: {w}");
    }
    let settings = cps.settings()?;
    println!(
        "{}: {} {} elements, {} nodes, {} materials; {} load step(s) of {} s, Courant {}",
        mpm_shared::display_name(&args.case),
        model.element_count(),
        model.element_type.keyword(),
        model.node_count(),
        model.materials().len(),
        settings.load_steps,
        settings.time_per_load_step,
        settings.courant
    );
    if !args.check {
        bail!("time integration is not available in this release; run with --check to validate a case");
    }
    Ok(())
}
