//! The CSV time series of our runs, `history.csv` (probed material points) and `energy.csv`,
//! compared row by row: rows pair in order and must agree on time (and probe id); columns are
//! grouped into fields (`history.stress` is `sxx` … `szx`). Rows are streamed, never collected.

use std::path::Path;

use super::read::Folder;
use super::stats::{Accumulator, Worst};
use super::{same_time, CompareError, OutputReport, Tolerances};

/// The fields of each CSV file: a name and its columns.
fn groups(file: &str) -> &'static [(&'static str, &'static [&'static str])] {
    match file {
        "history.csv" => &[
            ("history.position", &["x", "y", "z"]),
            ("history.displacement", &["ux", "uy", "uz"]),
            (
                "history.stress",
                &["sxx", "syy", "szz", "sxy", "syz", "szx"],
            ),
            ("history.pore_pressure", &["pore_pressure"]),
        ],
        _ => &[
            ("energy.kinetic", &["kinetic"]),
            ("energy.external_work", &["external_work"]),
        ],
    }
}

/// A field being compared: its name, its columns (name, index in the golden and the candidate
/// file) and its statistics so far.
type Group = (&'static str, Vec<(&'static str, usize, usize)>, Accumulator);

fn open(path: &Path) -> Result<csv::Reader<std::fs::File>, CompareError> {
    csv::ReaderBuilder::new()
        .from_path(path)
        .map_err(|e| CompareError::Csv(format!("{}: {e}", path.display())))
}

fn headers(r: &mut csv::Reader<std::fs::File>, path: &Path) -> Result<Vec<String>, CompareError> {
    Ok(r.headers()
        .map_err(|e| CompareError::Csv(format!("{}: {e}", path.display())))?
        .iter()
        .map(str::to_string)
        .collect())
}

fn number(rec: &csv::StringRecord, col: usize, path: &Path) -> Result<f64, CompareError> {
    let line = rec.position().map_or(0, |p| p.line());
    let s = rec.get(col).unwrap_or("");
    s.trim().parse::<f64>().map_err(|_| {
        CompareError::Csv(format!(
            "{}:{line}: column {} is '{s}', not a number",
            path.display(),
            col + 1
        ))
    })
}

/// Compares `name` of both folders; `None` when neither has it (Anura3D's folders never do)
/// or it has no rows, with a note when only one has it.
pub fn compare_csv(
    golden: &Folder,
    candidate: &Folder,
    name: &str,
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Option<OutputReport>, CompareError> {
    let (pa, pb) = (golden.dir().join(name), candidate.dir().join(name));
    match (pa.is_file(), pb.is_file()) {
        (true, true) => {}
        (false, false) => return Ok(None),
        (has_a, _) => {
            notes.push(format!(
                "{name}: only in the {} folder, not compared",
                if has_a { "golden" } else { "candidate" }
            ));
            return Ok(None);
        }
    }
    let (mut ra, mut rb) = (open(&pa)?, open(&pb)?);
    let (ha, hb) = (headers(&mut ra, &pa)?, headers(&mut rb, &pb)?);
    let (ta, tb) = match (column(&ha, "time"), column(&hb, "time")) {
        (Some(x), Some(y)) => (x, y),
        _ => {
            return Err(CompareError::Csv(format!(
                "{name}: no 'time' column on both sides"
            )))
        }
    };
    let keys = Keys {
        name,
        paths: (&pa, &pb),
        time: (ta, tb),
        id: (column(&ha, "id"), column(&hb, "id")),
    };
    let mut fields = common_fields(name, (&ha, &hb), tol, notes)?;
    let (mut a, mut b) = (csv::StringRecord::new(), csv::StringRecord::new());
    let mut rows = 0u64;
    loop {
        let more_a = ra
            .read_record(&mut a)
            .map_err(|e| CompareError::Csv(format!("{}: {e}", pa.display())))?;
        let more_b = rb
            .read_record(&mut b)
            .map_err(|e| CompareError::Csv(format!("{}: {e}", pb.display())))?;
        if more_a != more_b {
            return Err(CompareError::Csv(format!(
                "{name}: the golden file has {} rows than the candidate's (after {rows} rows)",
                if more_a { "more" } else { "fewer" }
            )));
        }
        if !more_a {
            break;
        }
        rows += 1;
        compare_row(&keys, rows, (&a, &b), &mut fields)?;
    }
    if rows == 0 || fields.is_empty() {
        return Ok(None);
    }
    Ok(Some(OutputReport {
        time: None,
        golden: pa.display().to_string(),
        candidate: pb.display().to_string(),
        points: rows as usize,
        fields: fields
            .into_iter()
            .map(|(f, _, acc)| acc.finish(f, tol.of(f)))
            .collect(),
    }))
}

/// The index of column `c` in `header`.
fn column(header: &[String], c: &str) -> Option<usize> {
    header.iter().position(|x| x == c)
}

/// What pairs the rows of the two files: the file's name, both paths, and the index of the
/// time column and of the probe id column (where there is one) on each side.
struct Keys<'a> {
    name: &'a str,
    paths: (&'a Path, &'a Path),
    time: (usize, usize),
    id: (Option<usize>, Option<usize>),
}

/// The fields of `name` whose columns both headers (golden, candidate) hold. A field whose
/// columns only one side holds, in part or whole, is an error when `tol` requires it, else a
/// note.
fn common_fields(
    name: &str,
    (ha, hb): (&[String], &[String]),
    tol: &Tolerances,
    notes: &mut Vec<String>,
) -> Result<Vec<Group>, CompareError> {
    let mut fields: Vec<Group> = Vec::new();
    for &(field, cols) in groups(name) {
        let found: Vec<_> = cols
            .iter()
            .filter_map(|c| Some((*c, column(ha, c)?, column(hb, c)?)))
            .collect();
        if found.len() == cols.len() {
            fields.push((field, found, Accumulator::default()));
        } else if cols
            .iter()
            .any(|c| column(ha, c).is_some() || column(hb, c).is_some())
        {
            if tol.required(field) {
                return Err(CompareError::Required {
                    field: field.into(),
                    side: if cols.iter().all(|c| column(ha, c).is_some()) {
                        "candidate"
                    } else {
                        "golden"
                    },
                    file: name.into(),
                });
            }
            notes.push(format!("{field}: on one side of {name} only, not compared"));
        }
    }
    Ok(fields)
}

/// Row `row` (1-based) of both files: checks that they agree on the probe id and the time,
/// and adds every field's values to its statistics.
fn compare_row(
    keys: &Keys,
    row: u64,
    (a, b): (&csv::StringRecord, &csv::StringRecord),
    fields: &mut [Group],
) -> Result<(), CompareError> {
    let (name, (pa, pb)) = (keys.name, keys.paths);
    let (t, tc) = (number(a, keys.time.0, pa)?, number(b, keys.time.1, pb)?);
    let id = match keys.id {
        (Some(x), Some(y)) => {
            let (i, j) = (number(a, x, pa)?, number(b, y, pb)?);
            if i != j {
                return Err(CompareError::Csv(format!(
                    "{name} row {row}: probe id {i} in the golden file, {j} in the candidate's (different --probe?)"
                )));
            }
            Some(i as u64)
        }
        _ => None,
    };
    if !same_time(t, tc) {
        return Err(CompareError::Csv(format!(
            "{name} row {row}: time {t} in the golden file, {tc} in the candidate's"
        )));
    }
    for (_, cols, acc) in fields {
        for &(c, ia, ib) in cols.iter() {
            let (x, y) = (number(a, ia, pa)?, number(b, ib, pb)?);
            acc.add(x, y, || Worst {
                id,
                element: None,
                position: None,
                time: Some(t),
                component: c.to_string(),
                golden: x,
                candidate: y,
            });
        }
    }
    Ok(())
}
