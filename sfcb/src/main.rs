//! `sfcb`: the space-filling-curve blackbox. Reads a mesh (Anura3D GOM or Gmsh MSH), orders its
//! elements along a Morton or Hilbert curve of their centroids, renumbers vertices in order of
//! first use, and writes it back (GOM, or VTU for viewing). `--curve none` makes it a converter.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::{Parser, ValueEnum};
use mpm_shared::cps::Cps;
use mpm_shared::Model;
use sfcb::{metrics, order};
use std::collections::BTreeMap;
use std::time::Instant;

/// Version of the `--report` JSON layout; raised when a field is renamed, removed or changes
/// meaning (new fields keep it).
const REPORT_SCHEMA_VERSION: u32 = 1;

/// Which curve orders the elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Curve {
    /// Z-order: bit interleaving of the quantised centroid (docs/design.md §3).
    Morton,
    /// Hilbert curve on the same grid.
    Hilbert,
    /// Keep the input order (plain format conversion).
    None,
}

/// Reorder a mesh along a space-filling curve, or convert it.
///
/// Reads IN (Anura3D .GOM or .GOM_stageN, Gmsh .msh; `-` reads a GOM or MSH from standard input)
/// and writes OUT (.GOM, .GOM_stageN, or .vtu for ParaView; `-` writes a GOM to standard output).
/// Elements are sorted by the curve key of their centroid, vertices renumbered in order of first
/// use, and every section that refers to nodes or elements follows.
///
/// Examples:
///   sfcb in.GOM out.GOM --levels 21
///   sfcb column.msh column.GOM --curve none
///   sfcb in.GOM - | mpm-solve - --cps in.CPS_001 --out run
///   sfcb in.GOM parts.vtu --partitions 16 --report -
#[derive(Debug, Parser)]
#[command(version, verbatim_doc_comment)]
struct Args {
    /// Input mesh: .GOM, .GOM_stageN or .msh; `-` for standard input.
    input: PathBuf,
    /// Output: .GOM, .GOM_stageN or .vtu; `-` for a GOM on standard output.
    output: PathBuf,
    /// Curve refinement levels: 1..=21 in 3D, 1..=31 in 2D [default: 21 in 3D, 31 in 2D].
    #[arg(long)]
    levels: Option<u32>,
    /// Curve used to order the elements.
    #[arg(long, value_enum, default_value_t = Curve::Morton)]
    curve: Curve,
    /// Scale each axis to its own extent instead of one cube for all axes (not recommended for
    /// elongated domains).
    #[arg(long)]
    no_cubic: bool,
    /// Cut the ordered elements into P contiguous, weight-balanced parts (written as the
    /// `partition` cell field of a .vtu output and summarised in the report).
    #[arg(long, value_name = "P")]
    partitions: Option<u32>,
    /// With --partitions: move every face-detached piece of a part to the neighbouring part it
    /// touches most, so each part is one connected piece (parts are then no longer contiguous
    /// ranges of the curve; meant for process partitions).
    #[arg(long, requires = "partitions")]
    merge_pieces: bool,
    /// Write a JSON report (timings, locality before and after) to FILE, `-` for standard output.
    #[arg(long, value_name = "FILE")]
    report: Option<PathBuf>,
    /// Remap the material-point ids of a CPS file to the new element order, for running OUT in
    /// Anura3D: --cps IN.CPS OUT.CPS. OUT.CPS is marked ($$OUTPUT_MATERIAL_POINTS_GOM_ORDER) so
    /// that mpm-solve still reports the points by their input ids. Not needed for mpm-solve
    /// alone: the GOM keeps each element's input number, so the original CPS fits it.
    #[arg(long, num_args = 2, value_names = ["IN.CPS", "OUT.CPS"])]
    cps: Option<Vec<PathBuf>>,
    /// Worker threads [default: all available cores]. The output does not depend on it.
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sfcb: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Reads the mesh, orders it, writes it (and the remapped CPS and the report).
fn run(args: Args) -> anyhow::Result<()> {
    check_options(&args)?;
    let t_start = Instant::now();
    let model = mpm_shared::read_model(&args.input)?;
    let t_read = t_start.elapsed().as_secs_f64();
    warn_duplicates(&args, &model);
    check_levels_for(&args, &model)?;
    let cps_in = read_cps(&args, &model)?;
    let dim = model.dimension.coords();
    let levels = args.levels.unwrap_or(if dim == 3 { 21 } else { 31 });
    let mut facts = Facts {
        elements: model.element_count(),
        nodes: model.node_count(),
        levels,
        shared_keys: 0,
        seconds: BTreeMap::from([("read", t_read)]),
        before: args.report.is_some().then(|| metrics::locality(&model)),
    };
    let model = reorder(&args, model, &mut facts)?;
    let (partition, neighbours) = partition(&args, &model);
    let mut cps_out = None;
    if let (Some((mut cps, ids)), Some(paths)) = (cps_in, &args.cps) {
        // File ids of the written GOM, so that Anura3D picks the same points, marked so that
        // mpm-solve still reports them by their input ids.
        mpm_shared::points::remap_cps(&mut cps, &ids, &model)?;
        cps_out = Some((paths[1].clone(), cps.write()));
    }
    let t = Instant::now();
    mpm_shared::write_model(&model, &args.output, partition.as_deref())?;
    facts.seconds.insert("write", t.elapsed().as_secs_f64());
    if let Some((path, bytes)) = cps_out {
        mpm_shared::io::write_output(&path, &bytes)?;
    }
    facts
        .seconds
        .insert("total", t_start.elapsed().as_secs_f64());
    if let Some(report_path) = &args.report {
        let outcome = Outcome {
            model: &model,
            partition: partition.as_deref(),
            neighbours,
        };
        write_report(report_path, &args, &facts, outcome)?;
    }
    Ok(())
}

/// Checks the options that need no input, and starts the thread pool of `--threads`.
fn check_options(args: &Args) -> anyhow::Result<()> {
    if let Some(t) = args.threads {
        if t == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("starting the thread pool")?;
    }
    if args.partitions == Some(0) {
        bail!("--partitions must be at least 1");
    }
    if let Some(l) = args.levels {
        if l == 0 || l > 31 {
            bail!("--levels must be in 1..=21 (3D) or 1..=31 (2D), got {l}");
        }
    }
    if mpm_shared::io::is_stdio(&args.output)
        && args.report.as_deref().is_some_and(mpm_shared::io::is_stdio)
    {
        bail!("the mesh and the report cannot both go to standard output");
    }
    Ok(())
}

/// Warns about coincident nodes of the input mesh.
fn warn_duplicates(args: &Args, model: &Model) {
    // Duplicates do not stop the ordering, but they disconnect the elements around them.
    let duplicates = mpm_shared::coincident::pairs(model);
    if let Some(w) =
        mpm_shared::coincident::warning(&mpm_shared::display_name(&args.input), &duplicates)
    {
        eprintln!("sfcb: warning: {w}");
    }
}

/// Checks `--levels` against the maximum for the mesh's dimension.
fn check_levels_for(args: &Args, model: &Model) -> anyhow::Result<()> {
    if let Some(l) = args.levels {
        let max = if model.dimension.coords() == 3 {
            21
        } else {
            31
        };
        if l > max {
            bail!(
                "--levels {l} is above the maximum {max} for a {}D mesh",
                model.dimension.coords()
            );
        }
    }
    Ok(())
}

/// Reads the CPS of `--cps`, if given, with the input id of each of its material points.
fn read_cps(args: &Args, model: &Model) -> anyhow::Result<Option<(Cps, Vec<u32>)>> {
    let Some(p) = &args.cps else {
        return Ok(None);
    };
    let data = mpm_shared::io::read_input(&p[0])?;
    let (cps, warnings) = Cps::read(&data, &mpm_shared::display_name(&p[0]))?;
    for w in warnings {
        eprintln!("sfcb: warning: {w}");
    }
    // Points are named by their input ids from here on, whatever order the input
    // GOM's elements are in (see mpm_shared::points).
    let ids = mpm_shared::points::cps_input_ids(&cps, model)?;
    Ok(Some((cps, ids)))
}

/// What the report tells beside the final mesh, gathered on the way.
struct Facts {
    /// Elements of the input.
    elements: usize,
    /// Nodes of the input.
    nodes: usize,
    /// Curve refinement levels.
    levels: u32,
    /// Elements whose curve key another element also has.
    shared_keys: usize,
    /// Seconds per phase.
    seconds: BTreeMap<&'static str, f64>,
    /// Locality of the input order (with `--report`).
    before: Option<metrics::Locality>,
}

/// Orders the elements of `model` along the curve of `--curve` (none: keeps them), noting the
/// timings and the elements that share a key in `facts`.
fn reorder(args: &Args, model: Model, facts: &mut Facts) -> anyhow::Result<Model> {
    let curve = match args.curve {
        Curve::None => return Ok(model),
        Curve::Hilbert => order::Curve::Hilbert,
        Curve::Morton => order::Curve::Morton,
    };
    let ord = order::order(
        &model,
        order::Options {
            curve,
            levels: facts.levels,
            cubic: !args.no_cubic,
        },
    )
    .with_context(|| {
        format!(
            "{}: cannot order the elements along the curve",
            mpm_shared::display_name(&args.input)
        )
    })?;
    let seconds = &mut facts.seconds;
    seconds.insert("keys", ord.seconds[0]);
    seconds.insert("sort", ord.seconds[1]);
    seconds.insert("renumber", ord.seconds[2]);
    facts.shared_keys = ord.shared_keys;
    let t = Instant::now();
    let reordered = model.reordered(&ord.order, &ord.node_new)?;
    seconds.insert("remap", t.elapsed().as_secs_f64());
    Ok(reordered)
}

/// Pairs of elements that share a face (see [`metrics::face_neighbours`]).
type Neighbours = Vec<(u32, u32)>;

/// The part of each element with `--partitions` (merged into connected pieces with
/// `--merge-pieces`, which also returns the face neighbours it found).
fn partition(args: &Args, model: &Model) -> (Option<Vec<i32>>, Option<Neighbours>) {
    let mut neighbours = None;
    let partition = args.partitions.map(|p| {
        let w = order::weights(model);
        let mut part = order::partitions(&w, p);
        if args.merge_pieces {
            let nb = metrics::face_neighbours(model);
            metrics::merge_pieces(model.element_count(), &nb, &mut part, &w, 20);
            neighbours = Some(nb);
        }
        part.into_iter().map(|v| v as i32).collect()
    });
    (partition, neighbours)
}

/// The mesh as written, for the report.
struct Outcome<'m> {
    model: &'m Model,
    /// The part of each element (with `--partitions`).
    partition: Option<&'m [i32]>,
    /// Face neighbours, where partitioning found them already.
    neighbours: Option<Neighbours>,
}

/// Writes the JSON report to `path`.
fn write_report(path: &Path, args: &Args, facts: &Facts, outcome: Outcome) -> anyhow::Result<()> {
    let model = outcome.model;
    let partitions = args.partitions.map(|p| {
        let part: Vec<u32> = outcome
            .partition
            .expect("computed with --partitions")
            .iter()
            .map(|&v| v as u32)
            .collect();
        let nb = outcome
            .neighbours
            .unwrap_or_else(|| metrics::face_neighbours(model));
        metrics::partition_quality(model, &nb, &part, &order::weights(model), p)
    });
    // serde_json writes a NaN or infinite f64 as null, so the report is strict JSON
    // whatever the numbers (metrics::tests::non_finite_numbers_become_null checks it).
    let report = serde_json::json!({
        "schema_version": REPORT_SCHEMA_VERSION,
        "input": mpm_shared::display_name(&args.input),
        "output": mpm_shared::display_name(&args.output),
        "dimension": model.dimension.coords(),
        "element_type": model.element_type.keyword(),
        "elements": facts.elements,
        "nodes": facts.nodes,
        "curve": format!("{:?}", args.curve).to_lowercase(),
        "levels": facts.levels,
        "cubic": !args.no_cubic,
        "threads": rayon::current_num_threads(),
        "elements_sharing_a_key": facts.shared_keys,
        "seconds": facts.seconds,
        "locality": { "before": facts.before, "after": metrics::locality(model) },
        "partitions": partitions,
    });
    let mut text = serde_json::to_string_pretty(&report)?;
    text.push('\n');
    mpm_shared::io::write_output(path, text.as_bytes())?;
    Ok(())
}
