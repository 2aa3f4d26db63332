//! Golden-file comparison of two run folders, field by field (`mpm-compare`).
//!
//! Either folder may be ours (`run.pvd` and its `particles_NNNNN.vtu`) or an Anura3D run folder
//! (`PROJ.CPS_001` and the material-point VTK files of each load step). Outputs are paired by
//! time, material points by id; for each field the largest and RMS difference are reported,
//! absolute and relative to the field's largest |value| in the golden output, per output, with
//! the place of the largest (id, element, position). Outputs are read one pair at a time, so
//! memory is that of one pair whatever the length of the run.
//!
//! - [`read`]: the folders and their outputs; [`stats`]: streaming statistics;
//! - [`tolerance`]: tolerances per field and the `compare.toml` format;
//! - [`history`]: `history.csv` and `energy.csv`; [`report`]: text, summary and JSON;
//! - [`tables`]: Anura3D's benchmark tables (`.BMS`, `.BMR`) against the other side's values
//!   of the same points;
//! - [`plot`]: the worst field's difference against depth.

pub mod history;
pub mod plot;
pub mod read;
pub mod report;
pub mod stats;
pub mod table_files;
pub mod tables;
pub mod tolerance;

use std::path::{Path, PathBuf};

use serde::Serialize;

use read::{Field, Folder, OutputRef, Snapshot};
use stats::{Accumulator, FieldStats, Worst};
use tolerance::Tolerances;

/// Why two folders cannot be compared (exit status 2 of `mpm-compare`).
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A file could not be read or is malformed.
    #[error(transparent)]
    Read(#[from] mpm_shared::Error),
    /// A folder is not a run of either kind.
    #[error("{}: not a run folder: {reason}", dir.display())]
    NotARun {
        /// The folder.
        dir: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// The outputs do not pair up by time.
    #[error("outputs do not pair by time: {0}")]
    Outputs(String),
    /// The material points differ (ids, counts) or an output is unusable.
    #[error("different material points: {0}")]
    Points(String),
    /// A field required by the tolerances is missing on one side.
    #[error("field '{field}' is required but {side} has none ({file})")]
    Required {
        /// The field.
        field: String,
        /// `golden` or `candidate`.
        side: &'static str,
        /// The output or file concerned.
        file: String,
    },
    /// A tolerance is malformed.
    #[error("tolerances: {0}")]
    Tolerance(String),
    /// Nothing the two folders hold could be compared.
    #[error("nothing to compare: {0}")]
    Nothing(String),
    /// A CSV history cannot be read or paired.
    #[error("{0}")]
    Csv(String),
    /// The plot could not be drawn or written.
    #[error("plot: {0}")]
    Plot(String),
}

/// One output pair compared.
#[derive(Debug, Clone, Serialize)]
pub struct OutputReport {
    /// Simulated time (s), the golden output's; none for a CSV history (all its rows).
    pub time: Option<f64>,
    /// The golden output's file.
    pub golden: String,
    /// The candidate's file.
    pub candidate: String,
    /// Material points compared.
    pub points: usize,
    /// One entry per field both sides have.
    pub fields: Vec<FieldStats>,
}

/// A whole comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The golden folder (and what wrote it).
    pub golden: String,
    /// The candidate folder.
    pub candidate: String,
    /// Per output pair, in time order.
    pub outputs: Vec<OutputReport>,
    /// `history.csv` and `energy.csv`, each as one "output" over all its rows.
    pub histories: Vec<OutputReport>,
    /// Anura3D's `.BMS` / `.BMR` tables, each as one "output" over all its rows.
    pub tables: Vec<OutputReport>,
    /// Fields or files on one side only (not compared), and other remarks.
    pub notes: Vec<String>,
    /// True when every compared field is within its tolerance.
    pub within: bool,
}

impl Report {
    /// Every field statistic, outputs first, then histories, then tables, with its output's
    /// time and file.
    pub fn all(&self) -> impl Iterator<Item = (&OutputReport, &FieldStats)> {
        self.outputs
            .iter()
            .chain(&self.histories)
            .chain(&self.tables)
            .flat_map(|o| o.fields.iter().map(move |f| (o, f)))
    }

    /// The first field out of tolerance, in order of the outputs.
    pub fn first_failure(&self) -> Option<(&OutputReport, &FieldStats)> {
        self.all().find(|(_, f)| !f.within)
    }

    /// For each field name, the statistic with the largest relative difference over outputs.
    pub fn worst_per_field(&self) -> Vec<(&OutputReport, &FieldStats)> {
        let mut out: Vec<(&OutputReport, &FieldStats)> = Vec::new();
        for (o, f) in self.all() {
            match out.iter_mut().find(|(_, g)| g.field == f.field) {
                Some(slot) => {
                    let worse = (!f.within && slot.1.within)
                        || (f.within == slot.1.within && f.max_rel > slot.1.max_rel);
                    if worse {
                        *slot = (o, f);
                    }
                }
                None => out.push((o, f)),
            }
        }
        out
    }
}

/// True when two output times are the same output (relative 1e-6; outputs land exactly on
/// their times in both codes, so this only absorbs printing round-off).
fn same_time(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * a.abs().max(b.abs())
}

/// Pairs the outputs of both folders by time; every output needs a partner.
pub fn pair_outputs(
    golden: &Folder,
    candidate: &Folder,
) -> Result<Vec<(OutputRef, OutputRef)>, CompareError> {
    let (a, b) = (golden.outputs(), candidate.outputs());
    let mut pairs = Vec::with_capacity(a.len());
    let mut used = vec![false; b.len()];
    for oa in &a {
        let hit = b
            .iter()
            .position(|ob| same_time(oa.time, ob.time))
            .ok_or_else(|| {
                CompareError::Outputs(format!(
                    "golden {} at t = {} s has no candidate output at that time in {} (candidate times: {})",
                    oa.label,
                    oa.time,
                    candidate.dir().display(),
                    times(&b)
                ))
            })?;
        used[hit] = true;
        pairs.push((oa.clone(), b[hit].clone()));
    }
    if let Some(k) = used.iter().position(|u| !u) {
        return Err(CompareError::Outputs(format!(
            "candidate {} at t = {} s has no golden output at that time in {} (golden times: {})",
            b[k].label,
            b[k].time,
            golden.dir().display(),
            times(&a)
        )));
    }
    if pairs.is_empty() {
        return Err(CompareError::Outputs(
            "the golden folder has no outputs".into(),
        ));
    }
    Ok(pairs)
}

fn times(o: &[OutputRef]) -> String {
    let mut s: Vec<String> = o.iter().take(8).map(|o| o.time.to_string()).collect();
    if o.len() > 8 {
        s.push(format!("… {} in all", o.len()));
    }
    s.join(", ")
}

/// Checks that both outputs hold the same material points (same ids).
fn same_points(
    a: &Snapshot,
    b: &Snapshot,
    pa: &OutputRef,
    pb: &OutputRef,
) -> Result<(), CompareError> {
    let (ia, ib) = (a.ids(), b.ids());
    let mismatch = (0..a.len().min(b.len())).find(|&k| ia.get(k) != ib.get(k));
    if a.len() == b.len() && mismatch.is_none() {
        return Ok(());
    }
    let at = match mismatch {
        Some(k) => format!(
            "the {}-th point by id is id {} in the golden output, id {} in the candidate",
            k + 1,
            ia.get(k).unwrap_or(0),
            ib.get(k).unwrap_or(0)
        ),
        None => "the ids agree as far as the shorter goes".into(),
    };
    Err(CompareError::Points(format!(
        "golden {} has {} points, candidate {} has {}; {at}",
        pa.label,
        a.len(),
        pb.label,
        b.len()
    )))
}

/// Compares one output pair, field by field.
pub fn compare_output(
    a: &Snapshot,
    b: &Snapshot,
    pa: &OutputRef,
    pb: &OutputRef,
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<OutputReport, CompareError> {
    same_points(a, b, pa, pb)?;
    let ids = a.ids();
    let (ea, eb) = (a.elements(), b.elements());
    let pos = a.field(Field::Position)?;
    let mut out = OutputReport {
        time: Some(pa.time),
        golden: pa.label.clone(),
        candidate: pb.label.clone(),
        points: a.len(),
        fields: Vec::new(),
    };
    for f in Field::ALL {
        let (va, vb) = (a.field(f)?, b.field(f)?);
        let (va, vb) = match (va, vb) {
            (Some(x), Some(y)) => (x, y),
            (None, None) => continue,
            (x, _) => {
                let (side, file) = if x.is_none() {
                    ("golden", &pa.label)
                } else {
                    ("candidate", &pb.label)
                };
                if tol.required(f.name()) {
                    return Err(CompareError::Required {
                        field: f.name().into(),
                        side,
                        file: file.clone(),
                    });
                }
                let note = format!(
                    "{}: only in the {} output, not compared",
                    f.name(),
                    if side == "golden" {
                        "candidate"
                    } else {
                        "golden"
                    }
                );
                if !notes.contains(&note) {
                    notes.push(note);
                }
                continue;
            }
        };
        let names = f.components();
        let mut acc = Accumulator::default();
        for k in 0..a.len() {
            for (c, name) in names.iter().enumerate() {
                acc.add(va.get(k, c), vb.get(k, c), || Worst {
                    id: ids.get(k),
                    element: ea.get(k).or_else(|| eb.get(k)),
                    position: pos
                        .as_ref()
                        .map(|p| [p.get(k, 0), p.get(k, 1), p.get(k, 2)]),
                    time: None,
                    component: name.to_string(),
                    golden: va.get(k, c),
                    candidate: vb.get(k, c),
                });
            }
        }
        out.fields.push(acc.finish(f.name(), tol.of(f.name())));
    }
    Ok(out)
}

/// Compares the candidate folder with the golden one: every output pair, then the CSV
/// histories, then Anura3D's tables. Outputs are read one pair at a time. A folder without
/// outputs (Anura3D's benchmark folder: its tables only) has its outputs noted as one-sided.
pub fn compare(golden: &Path, candidate: &Path, tol: &Tolerances) -> Result<Report, CompareError> {
    let (fa, fb) = (Folder::open(golden)?, Folder::open(candidate)?);
    let mut report = Report {
        golden: format!("{} ({})", golden.display(), fa.kind()),
        candidate: format!("{} ({})", candidate.display(), fb.kind()),
        outputs: Vec::new(),
        histories: Vec::new(),
        tables: Vec::new(),
        notes: Vec::new(),
        within: true,
    };
    let (na, nb) = (fa.outputs().len(), fb.outputs().len());
    let pairs = if na > 0 && nb > 0 {
        pair_outputs(&fa, &fb)?
    } else {
        if na + nb > 0 {
            report.notes.push(format!(
                "material-point outputs: only in the {} folder ({} of them), not compared",
                if na > 0 { "golden" } else { "candidate" },
                na + nb
            ));
        }
        Vec::new()
    };
    for (pa, pb) in &pairs {
        let (a, b) = (fa.load(pa.index)?, fb.load(pb.index)?);
        let o = compare_output(&a, &b, pa, pb, tol, &mut report.notes)?;
        report.outputs.push(o);
    }
    for name in ["history.csv", "energy.csv"] {
        if let Some(h) = history::compare_csv(&fa, &fb, name, tol, &mut report.notes)? {
            report.histories.push(h);
        }
    }
    report.tables = tables::compare_tables(&fa, &fb, tol, &mut report.notes)?;
    if report.all().next().is_none() {
        return Err(CompareError::Nothing(format!(
            "no output, history or table of {} pairs with one of {}{}",
            golden.display(),
            candidate.display(),
            if report.notes.is_empty() {
                String::new()
            } else {
                format!(" ({})", report.notes.join("; "))
            }
        )));
    }
    let within = report.all().all(|(_, f)| f.within);
    report.within = within;
    Ok(report)
}
