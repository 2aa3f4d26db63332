//! `mpm-compare GOLDEN CANDIDATE`: golden-file comparison of two run folders (ours or
//! Anura3D's), field by field, for CI. Exit status 0 within tolerances, 1 out of them, 2 when
//! the folders cannot be compared (also for usage errors, as clap does); one line on standard
//! error says why.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mpm_solve::compare::{self, report, tolerance::Tolerances};

/// Compare a candidate run folder with a golden one, field by field.
///
/// Outputs are paired by time, material points by id; the rows of Anura3D's
/// benchmark tables (PROJ.BMS / PROJ.BMR, or PROJ_expected.*) with the other side's
/// table, history.csv or outputs, by point id and time. Differences are absolute and relative to
/// the field's largest |value| in the golden output; a field is within when its largest
/// difference is at most atol + rtol × that value. Default: exact equality.
///
/// Examples:
///   mpm-compare golden/column out/column
///   mpm-compare golden/column out/column --rtol 1e-6 --rtol stress=1e-4 --summary
///   mpm-compare anura3d/case out/case --json report.json --plot worst.png
///
/// Exit status: 0 within tolerances, 1 not within, 2 cannot be compared.
#[derive(Debug, Parser)]
#[command(version, verbatim_doc_comment)]
struct Args {
    /// The reference folder: an mpm-solve output folder (run.pvd), an Anura3D run folder
    /// (PROJ.CPS_001 with PROJ_MPScalar/MPVector/MPTensor_NNN.vtk, PROJ.BMS, PROJ.BMR) or an
    /// Anura3D benchmark folder (PROJ_expected.BMS / .BMR).
    golden: PathBuf,
    /// The folder compared with it (either kind).
    candidate: PathBuf,
    /// Relative tolerance, for every field or as FIELD=VALUE for one (repeatable).
    #[arg(long, value_name = "[FIELD=]VALUE")]
    rtol: Vec<String>,
    /// Absolute tolerance in the field's unit, for every field or as FIELD=VALUE (repeatable).
    #[arg(long, value_name = "[FIELD=]VALUE")]
    atol: Vec<String>,
    /// Tolerance file [default: GOLDEN/compare.toml when there]; --rtol/--atol override it.
    #[arg(long, value_name = "FILE")]
    tolerances: Option<PathBuf>,
    /// Fail (status 2) when a side lacks this field instead of noting it (repeatable).
    #[arg(long, value_name = "FIELD")]
    require: Vec<String>,
    /// Write the report as JSON to FILE (standard output when no FILE is given; the table is
    /// then left out).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    json: Option<PathBuf>,
    /// One line per field (its worst output) instead of the full table.
    #[arg(long)]
    summary: bool,
    /// Draw the worst material-point field's difference against y and against time as a PNG.
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("mpm-compare: cannot compare: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// Splits `stress=1e-4` into a field and a value; a bare value is for every field.
fn field_value(s: &str) -> anyhow::Result<(Option<&str>, f64)> {
    let (field, v) = match s.split_once('=') {
        Some((f, v)) => (Some(f.trim()), v),
        None => (None, s),
    };
    let v = v
        .trim()
        .parse::<f64>()
        .map_err(|_| anyhow::anyhow!("'{s}' is not VALUE or FIELD=VALUE"))?;
    Ok((field, v))
}

/// Compares; `Ok(true)` when within tolerances.
fn run(args: Args) -> anyhow::Result<bool> {
    let beside = args.golden.join("compare.toml");
    let mut tol = match &args.tolerances {
        Some(f) => Tolerances::from_file(f)?,
        None if beside.is_file() => Tolerances::from_file(&beside)?,
        None => Tolerances::default(),
    };
    for (list, absolute) in [(&args.rtol, false), (&args.atol, true)] {
        for s in list {
            let (field, v) = field_value(s)?;
            tol.set(field, absolute, v)?;
        }
    }
    for f in &args.require {
        tol.require(f)?;
    }
    let r = compare::compare(&args.golden, &args.candidate, &tol)?;
    let json_to_stdout = args.json.as_deref().is_some_and(mpm_shared::io::is_stdio);
    if !json_to_stdout {
        let text = if args.summary {
            report::summary(&r)
        } else {
            report::table(&r)
        };
        // A reader that went away (`| head`) ends the table, not the comparison, whose verdict
        // goes to standard error and the exit status; any other write error fails it.
        use std::io::Write;
        match std::io::stdout().lock().write_all(text.as_bytes()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                return Err(
                    anyhow::Error::new(e).context("cannot write the report to standard output")
                );
            }
            _ => {}
        }
    }
    if let Some(path) = &args.json {
        mpm_shared::io::write_output(path, report::json(&r).as_bytes())?;
    }
    if let Some(path) = &args.plot {
        compare::plot::write_png(path, &args.golden, &args.candidate, &r)?;
    }
    let line = report::verdict(&r);
    if r.within {
        eprintln!("mpm-compare: {line}");
    } else {
        eprintln!("mpm-compare: FAIL: {line}");
    }
    Ok(r.within)
}
