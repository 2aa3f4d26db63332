//! Anura3D's benchmark tables, compared with the other folder's values of the same points.
//!
//! An Anura3D run writes `PROJ.BMS` (the material points its CPS lists under
//! `$$OUTPUT_MATERIAL_POINTS`, at the end of each load step: position, displacement, effective
//! stress, pore pressure, 4 significant digits) and `PROJ.BMR` (the same points' positions and,
//! when reported, nodal displacements, 10 digits); its benchmark folders hold them as
//! `PROJ_expected.BMS` / `PROJ_expected.BMR`. A folder's own run tables are preferred to the
//! expected ones when it has both (a run in a copy of a benchmark folder).
//!
//! Each row pairs with the other side's value of the same point id at the same time: the other
//! side's table when it has one (row by row, every row must pair), else our `history.csv`
//! (probed points), else our particle file at that time, else Anura3D's load-step files of the
//! row's load step. Times pair as output times do (relative 1e-6), widened by half a unit
//! of the 4th significant digit a `.BMS` prints them with. `.BMR` rows carry no time: they take
//! that of the `.BMS` rows of the same load and time step of their folder. A row whose point the
//! other side does not have (not probed) is noted, not failed, with the ids to probe.
//!
//! Fields: `bms.position`, `bms.displacement`, `bms.stress`, `bms.pore_pressure`,
//! `bmr.position` and `bmr.node_displacement` (only between two `.BMR`: we write no nodal
//! values). Each is one "output" over all its rows, like the CSV histories.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use mpm_shared::bms;

use super::read::{Field, Folder, Snapshot};
use super::stats::{Accumulator, Worst};
use super::table_files::TableFiles;
use super::{same_time, CompareError, OutputReport, Tolerances};

/// A compared field: its name, its components and its slot in a [`Sample`].
struct Spec {
    name: &'static str,
    components: &'static [&'static str],
    slot: usize,
}

const XYZ: &[&str] = &["x", "y", "z"];

/// The `.BMS` fields.
const BMS_SPECS: [Spec; 4] = [
    Spec {
        name: "bms.position",
        components: XYZ,
        slot: 0,
    },
    Spec {
        name: "bms.displacement",
        components: XYZ,
        slot: 1,
    },
    Spec {
        name: "bms.stress",
        components: &["xx", "yy", "zz", "xy", "yz", "zx"],
        slot: 2,
    },
    Spec {
        name: "bms.pore_pressure",
        components: &["p"],
        slot: 3,
    },
];

/// The `.BMR` material-point field.
const BMR_POINT_SPECS: [Spec; 1] = [Spec {
    name: "bmr.position",
    components: XYZ,
    slot: 0,
}];

/// The `.BMR` nodal field.
const BMR_NODE_SPECS: [Spec; 1] = [Spec {
    name: "bmr.node_displacement",
    components: XYZ,
    slot: 1,
}];

/// A point's values: position, displacement, stress, pore pressure (each when known).
type Sample = [Option<Vec<f64>>; 4];

/// One table row.
#[derive(Debug, Clone)]
struct Row {
    load_step: u32,
    time_step: u64,
    /// Simulated time (s); none for a `.BMR` row without a `.BMS` beside it.
    time: Option<f64>,
    id: u32,
    /// 1-based line in its file.
    line: usize,
    sample: Sample,
}

/// A table file's rows.
struct Table {
    file: PathBuf,
    rows: Vec<Row>,
}

impl Table {
    fn at(&self, r: &Row) -> String {
        format!("{}:{}", self.file.display(), r.line)
    }
}

fn read(path: &Path) -> Result<Vec<u8>, CompareError> {
    Ok(std::fs::read(path).map_err(|e| mpm_shared::Error::io(path, e))?)
}

/// The rows of a `.BMS`.
fn read_bms(path: &Path) -> Result<Table, CompareError> {
    let b = bms::read_bms(&read(path)?, &path.display().to_string())?;
    let t = &b.material_points;
    let has = |n: &str| t.column(n).is_some();
    let (disp, stress, pore) = (has("Ux"), has("SigmaXX"), has("WPressure"));
    let rows = b
        .records()
        .into_iter()
        .zip(&t.lines)
        .map(|(r, &line)| Row {
            load_step: r.load_step,
            time_step: r.time_step,
            time: Some(r.time),
            id: r.id,
            line,
            sample: [
                Some(r.position.to_vec()),
                disp.then(|| r.displacement.to_vec()),
                stress.then(|| r.stress.to_vec()),
                pore.then_some(vec![r.pore_pressure]),
            ],
        })
        .collect();
    Ok(Table {
        file: path.to_path_buf(),
        rows,
    })
}

/// The material-point and nodal rows of a `.BMR`; times from the `.BMS` beside it, if any.
fn read_bmr(path: &Path, beside: Option<&Table>) -> Result<(Table, Table), CompareError> {
    let b = bms::read_bmr(&read(path)?, &path.display().to_string())?;
    let times: HashMap<(u32, u64), f64> = beside
        .map(|t| {
            t.rows
                .iter()
                .filter_map(|r| Some(((r.load_step, r.time_step), r.time?)))
                .collect()
        })
        .unwrap_or_default();
    let rows = |recs: Vec<bms::VectorRecord>, lines: &[usize], slot: usize| -> Vec<Row> {
        recs.into_iter()
            .zip(lines)
            .map(|(r, &line)| {
                let mut sample: Sample = Default::default();
                sample[slot] = Some(r.value.to_vec());
                Row {
                    load_step: r.load_step,
                    time_step: r.time_step,
                    time: times.get(&(r.load_step, r.time_step)).copied(),
                    id: r.id,
                    line,
                    sample,
                }
            })
            .collect()
    };
    let points = rows(b.material_point_records(), &b.material_points.lines, 0);
    let nodes = rows(b.node_records(), &b.nodes.lines, 1);
    let t = |rows| Table {
        file: path.to_path_buf(),
        rows,
    };
    Ok((t(points), t(nodes)))
}

/// Half a unit of the 4th significant digit of `t`: how far a time printed in a `.BMS` may be
/// from the true one.
fn half_unit(t: f64) -> f64 {
    if t == 0.0 || !t.is_finite() {
        return 0.0;
    }
    0.5 * 10f64.powi(t.abs().log10().floor() as i32 - 3) * (1.0 + 1e-9)
}

/// True when times `a` and `b` are the same output; a printed time (`.BMS`) may be off by the
/// rounding of its printing.
fn pair_time(a: f64, a_printed: bool, b: f64, b_printed: bool) -> bool {
    let slack = |t: f64, printed: bool| if printed { half_unit(t) } else { 0.0 };
    same_time(a, b) || (a - b).abs() <= slack(a, a_printed) + slack(b, b_printed)
}

/// Which side of the comparison a table is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Golden,
    Candidate,
}

impl Side {
    fn name(self) -> &'static str {
        match self {
            Side::Golden => "golden",
            Side::Candidate => "candidate",
        }
    }

    fn other(self) -> Side {
        match self {
            Side::Golden => Side::Candidate,
            Side::Candidate => Side::Golden,
        }
    }
}

/// A paired row: time (s), id, golden and candidate values.
type Pair = (Option<f64>, u32, Sample, Sample);

/// Compares the benchmark tables of both folders (see the module notes).
pub fn compare_tables(
    golden: &Folder,
    candidate: &Folder,
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Vec<OutputReport>, CompareError> {
    let (fa, fb) = (
        TableFiles::find(golden.dir())?,
        TableFiles::find(candidate.dir())?,
    );
    let load_bms = |p: &Option<PathBuf>| p.as_deref().map(read_bms).transpose();
    let (sa, sb) = (load_bms(&fa.bms)?, load_bms(&fb.bms)?);
    let load_bmr = |p: &Option<PathBuf>, beside: Option<&Table>| {
        p.as_deref().map(|p| read_bmr(p, beside)).transpose()
    };
    let (ra, rb) = (
        load_bmr(&fa.bmr, sa.as_ref())?,
        load_bmr(&fb.bmr, sb.as_ref())?,
    );
    let mut out = Vec::new();
    let folders = [golden, candidate];
    let tables = [(sa.as_ref(), sb.as_ref(), &BMS_SPECS[..], true)];
    let bmr_points = [(
        ra.as_ref().map(|r| &r.0),
        rb.as_ref().map(|r| &r.0),
        &BMR_POINT_SPECS[..],
        // Their times are those of the `.BMS` beside them.
        true,
    )];
    for (a, b, specs, printed) in tables.into_iter().chain(bmr_points) {
        let report = match (a, b) {
            (Some(a), Some(b)) => both(a, b, printed, specs, tol, notes)?,
            (Some(t), None) => one(t, Side::Golden, folders, printed, specs, tol, notes)?,
            (None, Some(t)) => one(t, Side::Candidate, folders, printed, specs, tol, notes)?,
            (None, None) => None,
        };
        out.extend(report);
    }
    match (ra.as_ref().map(|r| &r.1), rb.as_ref().map(|r| &r.1)) {
        (Some(a), Some(b)) => out.extend(both(a, b, false, &BMR_NODE_SPECS, tol, notes)?),
        (Some(t), None) | (None, Some(t)) if !t.rows.is_empty() => {
            let side = if ra.is_some() { "golden" } else { "candidate" };
            if tol.required("bmr.node_displacement") {
                return Err(CompareError::Required {
                    field: "bmr.node_displacement".into(),
                    side: if side == "golden" {
                        "candidate"
                    } else {
                        "golden"
                    },
                    file: t.file.display().to_string(),
                });
            }
            notes.push(format!(
                "bmr.node_displacement: only in the {side} folder ({}; mpm-solve writes no nodal values), not compared",
                t.file.display()
            ));
        }
        _ => {}
    }
    Ok(out)
}

/// Two tables, row by row: every row pairs with one of the same id (and load and time step for
/// rows without a time) at the same time, or the tables cannot be compared.
fn both(
    a: &Table,
    b: &Table,
    printed: bool,
    specs: &[Spec],
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Option<OutputReport>, CompareError> {
    let mut by_id: HashMap<u32, Vec<usize>> = HashMap::new();
    for (k, r) in b.rows.iter().enumerate() {
        by_id.entry(r.id).or_default().push(k);
    }
    let mut used = vec![false; b.rows.len()];
    let mut pairs: Vec<Pair> = Vec::with_capacity(a.rows.len());
    for ra in &a.rows {
        let same = |rb: &Row| match (ra.time, rb.time) {
            (Some(x), Some(y)) => pair_time(x, printed, y, printed),
            _ => (ra.load_step, ra.time_step) == (rb.load_step, rb.time_step),
        };
        let hit = by_id
            .get(&ra.id)
            .and_then(|ks| ks.iter().copied().find(|&k| !used[k] && same(&b.rows[k])))
            .ok_or_else(|| {
                CompareError::Points(format!(
                    "{}: point {} at {} has no row of that point and time in {}",
                    a.at(ra),
                    ra.id,
                    when(ra),
                    b.file.display()
                ))
            })?;
        used[hit] = true;
        pairs.push((
            ra.time,
            ra.id,
            ra.sample.clone(),
            b.rows[hit].sample.clone(),
        ));
    }
    if let Some(k) = used.iter().position(|u| !u) {
        let rb = &b.rows[k];
        return Err(CompareError::Points(format!(
            "{}: point {} at {} has no row of that point and time in {}",
            b.at(rb),
            rb.id,
            when(rb),
            a.file.display()
        )));
    }
    accumulate(
        &pairs,
        specs,
        a.file.display().to_string(),
        b.file.display().to_string(),
        tol,
        notes,
    )
}

fn when(r: &Row) -> String {
    match r.time {
        Some(t) => format!("t = {t} s"),
        None => format!("load step {}, time step {}", r.load_step, r.time_step),
    }
}

/// A table on `side`, its rows looked up in the other folder.
fn one(
    t: &Table,
    side: Side,
    folders: [&Folder; 2],
    printed: bool,
    specs: &[Spec],
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Option<OutputReport>, CompareError> {
    let other = match side {
        Side::Golden => folders[1],
        Side::Candidate => folders[0],
    };
    let (found, sources) = lookup(other, &t.rows, printed)?;
    let mut pairs = Vec::with_capacity(t.rows.len());
    let mut missing: Vec<&Row> = Vec::new();
    for (r, f) in t.rows.iter().zip(found) {
        match f {
            Some(s) => pairs.push(match side {
                Side::Golden => (r.time, r.id, r.sample.clone(), s),
                Side::Candidate => (r.time, r.id, s, r.sample.clone()),
            }),
            None => missing.push(r),
        }
    }
    let table = specs.first().map_or("", |s| &s.name[..3]);
    if !missing.is_empty() {
        if let Some(s) = specs.iter().find(|s| tol.required(s.name)) {
            return Err(CompareError::Required {
                field: s.name.into(),
                side: side.other().name(),
                file: format!(
                    "no value of point {} at {} ({})",
                    missing[0].id,
                    when(missing[0]),
                    t.at(missing[0])
                ),
            });
        }
        let mut ids: Vec<u32> = missing.iter().map(|r| r.id).collect();
        ids.sort_unstable();
        ids.dedup();
        let list = ids.iter().map(u32::to_string).collect::<Vec<_>>().join(",");
        let untimed = missing.iter().any(|r| r.time.is_none());
        notes.push(format!(
            "{table}: {} of {} rows of {} have no value of their point at their time in the {} folder ({}): not compared; {}",
            missing.len(),
            t.rows.len(),
            t.file.display(),
            side.other().name(),
            other.dir().display(),
            if untimed {
                "the table gives no time (no .BMS beside it)".to_string()
            } else {
                format!(
                    "probe those ids (mpm-solve --probe {list}, or the CPS's $$OUTPUT_MATERIAL_POINTS) and write an output at {}",
                    when(missing[0])
                )
            }
        ));
    }
    if pairs.is_empty() {
        return Ok(None);
    }
    let mut sources = sources;
    sources.sort();
    sources.dedup();
    let other_label = format!("{} ({})", other.dir().display(), sources.join(", "));
    let (ga, gb) = match side {
        Side::Golden => (t.file.display().to_string(), other_label),
        Side::Candidate => (other_label, t.file.display().to_string()),
    };
    accumulate(&pairs, specs, ga, gb, tol, notes)
}

/// Our `history.csv`: per probe id, its rows (time, values).
type History = HashMap<u32, Vec<(f64, Sample)>>;

fn read_history(path: &Path) -> Result<History, CompareError> {
    let bad = |m: String| CompareError::Csv(format!("{}: {m}", path.display()));
    let mut r = csv::ReaderBuilder::new()
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let h: Vec<String> = r
        .headers()
        .map_err(|e| bad(e.to_string()))?
        .iter()
        .map(str::to_string)
        .collect();
    let col = |c: &str| h.iter().position(|x| x == c);
    let cols = |names: &[&str]| -> Option<Vec<usize>> { names.iter().map(|c| col(c)).collect() };
    let (Some(tc), Some(ic)) = (col("time"), col("id")) else {
        return Err(bad("no 'time' and 'id' columns".into()));
    };
    let groups = [
        cols(&["x", "y", "z"]),
        cols(&["ux", "uy", "uz"]),
        cols(&["sxx", "syy", "szz", "sxy", "syz", "szx"]),
        cols(&["pore_pressure"]),
    ];
    let mut out = History::new();
    let mut rec = csv::StringRecord::new();
    while r.read_record(&mut rec).map_err(|e| bad(e.to_string()))? {
        let line = rec.position().map_or(0, |p| p.line());
        let num = |c: usize| -> Result<f64, CompareError> {
            let s = rec.get(c).unwrap_or("");
            s.trim().parse::<f64>().map_err(|_| {
                CompareError::Csv(format!(
                    "{}:{line}: column {} is '{s}', not a number",
                    path.display(),
                    c + 1
                ))
            })
        };
        let id = num(ic)?;
        if !(id.fract() == 0.0 && id >= 1.0 && id <= u32::MAX as f64) {
            return Err(CompareError::Csv(format!(
                "{}:{line}: id {id} is not a point id",
                path.display()
            )));
        }
        let mut sample: Sample = Default::default();
        for (slot, g) in groups.iter().enumerate() {
            if let Some(g) = g {
                sample[slot] = Some(g.iter().map(|&c| num(c)).collect::<Result<_, _>>()?);
            }
        }
        out.entry(id as u32).or_default().push((num(tc)?, sample));
    }
    Ok(out)
}

/// The values of point rank `k` of an output.
fn sample_of(s: &Snapshot, k: usize) -> Result<Sample, CompareError> {
    let mut out: Sample = Default::default();
    let fields = [
        Field::Position,
        Field::Displacement,
        Field::Stress,
        Field::PorePressure,
    ];
    for (slot, f) in fields.into_iter().enumerate() {
        if let Some(v) = s.field(f)? {
            out[slot] = Some((0..f.components().len()).map(|c| v.get(k, c)).collect());
        }
    }
    Ok(out)
}

/// Looks each row's point up in `folder`: its `history.csv`, then its outputs (one loaded at a
/// time). Returns the values found and the files they came from.
fn lookup(
    folder: &Folder,
    rows: &[Row],
    printed: bool,
) -> Result<(Vec<Option<Sample>>, Vec<String>), CompareError> {
    let mut found: Vec<Option<Sample>> = vec![None; rows.len()];
    let mut sources = Vec::new();
    let hist = folder.dir().join("history.csv");
    if hist.is_file() {
        let h = read_history(&hist)?;
        for (r, f) in rows.iter().zip(found.iter_mut()) {
            let (Some(t), Some(series)) = (r.time, h.get(&r.id)) else {
                continue;
            };
            let best = series
                .iter()
                .filter(|(u, _)| pair_time(t, printed, *u, false))
                .min_by(|x, y| (x.0 - t).abs().total_cmp(&(y.0 - t).abs()));
            if let Some((_, s)) = best {
                *f = Some(s.clone());
            }
        }
        if found.iter().any(Option::is_some) {
            sources.push("history.csv".to_string());
        }
    }
    let outputs = folder.outputs();
    for o in &outputs {
        let step = folder.load_step(o.index);
        let wanted: Vec<usize> = (0..rows.len())
            .filter(|&k| found[k].is_none())
            .filter(|&k| {
                let r = &rows[k];
                match step {
                    // Anura3D's load-step files: the row's load step.
                    Some(s) => r.load_step == s,
                    None => r.time.is_some_and(|t| {
                        pair_time(t, printed, o.time, false)
                            && outputs
                                .iter()
                                .filter(|p| pair_time(t, printed, p.time, false))
                                .min_by(|x, y| (x.time - t).abs().total_cmp(&(y.time - t).abs()))
                                .is_some_and(|p| p.index == o.index)
                    }),
                }
            })
            .collect();
        if wanted.is_empty() {
            continue;
        }
        let snap = folder.load(o.index)?;
        let mut any = false;
        for k in wanted {
            if let Some(rank) = snap.rank_of(rows[k].id as u64) {
                found[k] = Some(sample_of(&snap, rank)?);
                any = true;
            }
        }
        if any {
            sources.push(o.label.clone());
        }
    }
    Ok((found, sources))
}

/// The statistics of every field of `specs` over the paired rows; fields on one side only are
/// noted (or an error when required).
fn accumulate(
    pairs: &[Pair],
    specs: &[Spec],
    golden: String,
    candidate: String,
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Option<OutputReport>, CompareError> {
    let mut fields = Vec::new();
    for s in specs {
        let (mut only_a, mut only_b) = (0usize, 0usize);
        let mut acc = Accumulator::default();
        let mut compared = false;
        for (time, id, a, b) in pairs {
            match (&a[s.slot], &b[s.slot]) {
                (Some(va), Some(vb)) => {
                    compared = true;
                    for (c, name) in s.components.iter().enumerate() {
                        let (x, y) = (va[c], vb[c]);
                        acc.add(x, y, || Worst {
                            id: Some(*id as u64),
                            element: None,
                            position: a[0].as_ref().map(|p| [p[0], p[1], p[2]]),
                            time: *time,
                            component: name.to_string(),
                            golden: x,
                            candidate: y,
                        });
                    }
                }
                (Some(_), None) => only_a += 1,
                (None, Some(_)) => only_b += 1,
                (None, None) => {}
            }
        }
        if only_a + only_b > 0 {
            let (has, lacks, file) = if only_a > 0 {
                ("golden", "candidate", &candidate)
            } else {
                ("candidate", "golden", &golden)
            };
            if tol.required(s.name) {
                return Err(CompareError::Required {
                    field: s.name.into(),
                    side: if lacks == "golden" {
                        "golden"
                    } else {
                        "candidate"
                    },
                    file: file.clone(),
                });
            }
            let note = format!(
                "{}: only in the {has} folder's values, not compared",
                s.name
            );
            if !notes.contains(&note) {
                notes.push(note);
            }
        }
        if compared {
            fields.push(acc.finish(s.name, tol.of(s.name)));
        }
    }
    if fields.is_empty() {
        return Ok(None);
    }
    Ok(Some(OutputReport {
        time: None,
        golden,
        candidate,
        points: pairs.len(),
        fields,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn printed_times_pair_within_their_rounding() {
        // 0.5911E-02 printed, 0.005911345 computed.
        assert!(pair_time(0.5911e-2, true, 0.005911345024612572, false));
        assert!(!pair_time(0.5911e-2, false, 0.005911345024612572, false));
        assert!(!pair_time(0.5911e-2, true, 0.0059116, false));
        assert!(pair_time(0.4663, true, 0.46634, false));
        assert!(pair_time(0.0, true, 0.0, false));
        assert!(pair_time(1.0, true, 1.0, true));
        assert!(!pair_time(1.0, true, 1.002, true));
    }
}
