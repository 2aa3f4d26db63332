//! Anura3D benchmark tables: `.BMS` (material points, 4 significant digits) and `.BMR` (nodal
//! displacements and material-point positions, 10 significant digits).
//!
//! Both files are a sequence of blocks, each opened by a marker line such as
//! ` ---material point data-----`:
//!
//! - `general project data`: `Number of load steps   1` lines (a description and a number);
//! - `material point data` and `nodal data`: a header naming the columns, then one row of
//!   numbers per line. In a `.BMS` the header is blank-separated and starts with `LoadStep`
//!   (`LoadStep TimeStep Time PA PGravity ID_MP X Y Z Ux ... WPressure ... MatID`); in a `.BMR`
//!   it is comma-separated (`LoadStep,TimeStep,MP_ID,X,Y,Z`);
//! - `end-of-file`.
//!
//! Anura3D's 2D `.BMS` header wraps over two lines and glues some names together (`TimePA`,
//! `WPressureEpsilonXX`): names that are not known columns are split into known ones when they
//! can be. Its 2D `.BMR` header names `Z` and `U_Z`, which the rows leave out: such columns are
//! dropped when the rows are that much shorter. Columns are kept by name, never by position.

use crate::error::{Error, Location, Result};
use crate::text::{self, Lines, Tokens};

/// One table: column names and rows of numbers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names in file order.
    pub columns: Vec<String>,
    /// Rows, each with one value per column.
    pub rows: Vec<Vec<f64>>,
    /// 1-based line number of each row in the file read.
    pub lines: Vec<usize>,
}

impl Table {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Index of the column called `name` (exact match), if any.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// Index of the first of `names` that is a column.
    pub fn column_of(&self, names: &[&str]) -> Option<usize> {
        names.iter().find_map(|n| self.column(n))
    }

    /// The value of column `name` in row `row`, if both exist.
    pub fn get(&self, row: usize, name: &str) -> Option<f64> {
        let c = self.column(name)?;
        self.rows.get(row)?.get(c).copied()
    }

    /// Every value of column `name`, if it exists.
    pub fn values(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.column(name)?;
        Some(self.rows.iter().map(|r| r[c]).collect())
    }
}

/// One data block of a benchmark file.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// The marker's name (`material point data`, `nodal data`, ...).
    pub name: String,
    /// Its table.
    pub table: Table,
}

/// A benchmark file read block by block.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tables {
    /// The `general project data` lines: description and value (`Number of nodes`, 207).
    pub project: Vec<(String, f64)>,
    /// The data blocks in file order.
    pub blocks: Vec<Block>,
}

impl Tables {
    /// The rows of every block called `name`, in file order, as one table. Blocks with
    /// different columns cannot be merged: an error names the first one that differs.
    pub fn merged(&self, name: &str, file: &str) -> Result<Table> {
        let mut out: Option<Table> = None;
        for b in self.blocks.iter().filter(|b| b.name == name) {
            match &mut out {
                None => out = Some(b.table.clone()),
                Some(t) if t.columns == b.table.columns => {
                    t.rows.extend(b.table.rows.iter().cloned());
                    t.lines.extend(&b.table.lines);
                }
                Some(t) => {
                    return Err(Error::invalid(
                        Location::new(file, b.table.lines.first().copied().unwrap_or(0), None),
                        format!(
                            "this '{name}' block has columns {:?}, an earlier one {:?}",
                            b.table.columns, t.columns
                        ),
                    ))
                }
            }
        }
        Ok(out.unwrap_or_default())
    }

    /// The value of the project line `description` (`Number of material points`), if present.
    pub fn project_value(&self, description: &str) -> Option<f64> {
        self.project
            .iter()
            .find(|(d, _)| d == description)
            .map(|(_, v)| *v)
    }
}

/// A `.BMS` file: the material points Anura3D reports, at the end of each load step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Bms {
    /// The `general project data` lines (empty when the file has none).
    pub project: Vec<(String, f64)>,
    /// The `material point data` rows (empty when the file reports no material points, as for
    /// Anura3D's FEM runs). When there are rows, the columns `LoadStep`, `TimeStep`, `Time`,
    /// `ID_MP`, `X` and `Y` are present.
    pub material_points: Table,
}

/// One row of a `.BMS` table with its common columns typed. Columns a file does not have (`Z`
/// and the out-of-plane components in 2D, `WPressure` in old files) read as 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialPointRecord {
    /// `LoadStep`.
    pub load_step: u32,
    /// `TimeStep`: the time step within the load step.
    pub time_step: u64,
    /// `Time` (s), from the start of the load step's stage.
    pub time: f64,
    /// `ID_MP`: the 1-based material point id.
    pub id: u32,
    /// `X`, `Y`, `Z`.
    pub position: [f64; 3],
    /// `Ux`, `Uy`, `Uz`.
    pub displacement: [f64; 3],
    /// `SigmaXX`, `SigmaYY`, `SigmaZZ`, `SigmaXY`, `SigmaYZ`, `SigmaZX` (effective stress,
    /// tension positive).
    pub stress: [f64; 6],
    /// `WPressure`: the pore (water) pressure.
    pub pore_pressure: f64,
}

/// The stress columns of a `.BMS` table, in the order of [`MaterialPointRecord::stress`].
pub const STRESS_COLUMNS: [&str; 6] = [
    "SigmaXX", "SigmaYY", "SigmaZZ", "SigmaXY", "SigmaYZ", "SigmaZX",
];

impl Bms {
    /// The rows with their common columns typed.
    pub fn records(&self) -> Vec<MaterialPointRecord> {
        let t = &self.material_points;
        let col = |n: &str| t.column(n);
        let (ls, ts, time, id) = (col("LoadStep"), col("TimeStep"), col("Time"), col("ID_MP"));
        let pos = ["X", "Y", "Z"].map(col);
        let disp = ["Ux", "Uy", "Uz"].map(col);
        let stress = STRESS_COLUMNS.map(col);
        let wp = col("WPressure");
        let at = |r: &[f64], c: Option<usize>| c.map_or(0.0, |c| r[c]);
        t.rows
            .iter()
            .map(|r| MaterialPointRecord {
                load_step: at(r, ls) as u32,
                time_step: at(r, ts) as u64,
                time: at(r, time),
                id: at(r, id) as u32,
                position: pos.map(|c| at(r, c)),
                displacement: disp.map(|c| at(r, c)),
                stress: stress.map(|c| at(r, c)),
                pore_pressure: at(r, wp),
            })
            .collect()
    }
}

/// A `.BMR` file: nodal displacements and material-point positions at full precision.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Bmr {
    /// The `general project data` lines (empty when the file has none).
    pub project: Vec<(String, f64)>,
    /// The `nodal data` rows (`LoadStep`, `TimeStep`, `Node_ID`, `U_X`, `U_Y`[, `U_Z`]).
    pub nodes: Table,
    /// The `material point data` rows (`LoadStep`, `TimeStep`, `MP_ID`, `X`, `Y`[, `Z`]).
    pub material_points: Table,
}

/// One row of a `.BMR` table: an id and a vector (a node's displacement or a material point's
/// position; the third component is 0 in 2D).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VectorRecord {
    /// `LoadStep`.
    pub load_step: u32,
    /// `TimeStep`.
    pub time_step: u64,
    /// `Node_ID` or `MP_ID` (1-based).
    pub id: u32,
    /// `U_X U_Y U_Z` or `X Y Z`.
    pub value: [f64; 3],
}

impl Bmr {
    /// The nodal displacements, typed.
    pub fn node_records(&self) -> Vec<VectorRecord> {
        vector_records(&self.nodes, "Node_ID", ["U_X", "U_Y", "U_Z"])
    }

    /// The material-point positions, typed.
    pub fn material_point_records(&self) -> Vec<VectorRecord> {
        vector_records(&self.material_points, "MP_ID", ["X", "Y", "Z"])
    }
}

fn vector_records(t: &Table, id: &str, names: [&str; 3]) -> Vec<VectorRecord> {
    let (ls, ts, idc) = (t.column("LoadStep"), t.column("TimeStep"), t.column(id));
    let v = names.map(|n| t.column(n));
    let at = |r: &[f64], c: Option<usize>| c.map_or(0.0, |c| r[c]);
    t.rows
        .iter()
        .map(|r| VectorRecord {
            load_step: at(r, ls) as u32,
            time_step: at(r, ts) as u64,
            id: at(r, idc) as u32,
            value: v.map(|c| at(r, c)),
        })
        .collect()
}

/// Reads a `.BMS` file. Errors name `file` and the line.
pub fn read_bms(data: &[u8], file: &str) -> Result<Bms> {
    let tables = read_tables(data, file)?;
    let mp = tables.merged("material point data", file)?;
    if !mp.is_empty() {
        require(
            &mp,
            file,
            &["LoadStep", "TimeStep", "Time", "ID_MP", "X", "Y"],
        )?;
        check_whole(&mp, file, &["LoadStep", "TimeStep"], false)?;
        check_whole(&mp, file, &["ID_MP"], true)?;
    }
    Ok(Bms {
        project: tables.project,
        material_points: mp,
    })
}

/// Reads a `.BMR` file. Errors name `file` and the line.
pub fn read_bmr(data: &[u8], file: &str) -> Result<Bmr> {
    let tables = read_tables(data, file)?;
    let nodes = tables.merged("nodal data", file)?;
    let mp = tables.merged("material point data", file)?;
    for (t, id) in [(&nodes, "Node_ID"), (&mp, "MP_ID")] {
        if !t.is_empty() {
            require(t, file, &["LoadStep", "TimeStep", id])?;
            check_whole(t, file, &["LoadStep", "TimeStep"], false)?;
            check_whole(t, file, &[id], true)?;
        }
    }
    Ok(Bmr {
        project: tables.project,
        nodes,
        material_points: mp,
    })
}

/// An error unless every one of `names` is a column of `t`.
fn require(t: &Table, file: &str, names: &[&str]) -> Result<()> {
    for n in names {
        if t.column(n).is_none() {
            return Err(Error::format(
                Location::new(file, t.lines.first().copied().unwrap_or(0), None),
                format!(
                    "the table has no column '{n}' (columns: {})",
                    t.columns.join(" ")
                ),
            ));
        }
    }
    Ok(())
}

/// An error unless the columns `names` hold whole numbers in the range of `u32` (ids: positive).
fn check_whole(t: &Table, file: &str, names: &[&str], positive: bool) -> Result<()> {
    for n in names {
        let Some(c) = t.column(n) else { continue };
        for (r, &line) in t.rows.iter().zip(&t.lines) {
            let v = r[c];
            let min = if positive { 1.0 } else { 0.0 };
            if !(v.fract() == 0.0 && v >= min && v <= u32::MAX as f64) {
                return Err(Error::invalid(
                    Location::new(file, line, None),
                    format!(
                        "column '{n}' must hold a whole number{}, found {v}",
                        if positive { " of at least 1" } else { "" }
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Column names Anura3D writes, used to split names its 2D header glues together.
const KNOWN: &[&str] = &[
    "LoadStep",
    "TimeStep",
    "Time",
    "PA",
    "PGravity",
    "ID_MP",
    "MP_ID",
    "Node_ID",
    "X",
    "Y",
    "Z",
    "Ux",
    "Uy",
    "Uz",
    "U_X",
    "U_Y",
    "U_Z",
    "SigmaXX",
    "SigmaYY",
    "SigmaZZ",
    "SigmaXY",
    "SigmaYZ",
    "SigmaZX",
    "WPressure",
    "GPressure",
    "EpsilonXX",
    "EpsilonYY",
    "EpsilonZZ",
    "GammaXY",
    "GammaYZ",
    "GammaZX",
    "IntWeight",
    "MatID",
];

/// Length of the known name `s` starts with, trying the longest first; `PA(n)` is known.
fn known_prefixes(s: &str) -> Vec<usize> {
    let mut out: Vec<usize> = KNOWN
        .iter()
        .filter(|k| s.starts_with(*k))
        .map(|k| k.len())
        .collect();
    if let Some(rest) = s.strip_prefix("PA(") {
        if let Some(close) = rest.find(')') {
            if close > 0 && rest[..close].bytes().all(|b| b.is_ascii_digit()) {
                out.push(3 + close + 1);
            }
        }
    }
    out.sort_unstable_by(|a, b| b.cmp(a));
    out
}

/// `name` as a sequence of known names, if it is one (`TimePA(1)` → `Time`, `PA(1)`).
fn split_known(name: &str) -> Option<Vec<String>> {
    if name.is_empty() {
        return Some(Vec::new());
    }
    for n in known_prefixes(name) {
        if let Some(mut rest) = split_known(&name[n..]) {
            rest.insert(0, name[..n].to_string());
            return Some(rest);
        }
    }
    None
}

fn is_known(name: &str) -> bool {
    split_known(name).is_some_and(|v| v.len() == 1)
}

/// Header names of a token: itself when known or not splittable, else its known parts.
fn header_names(tok: &str) -> Vec<String> {
    if is_known(tok) {
        return vec![tok.to_string()];
    }
    match split_known(tok) {
        Some(parts) if parts.len() > 1 => parts,
        _ => vec![tok.to_string()],
    }
}

/// A number as Anura3D prints it; Fortran drops the `E` of three-digit exponents
/// (`0.1234-100`), which is read too.
fn number(tok: &[u8]) -> Option<f64> {
    if let Some(v) = text::parse_real(tok) {
        return Some(v);
    }
    let p = tok
        .iter()
        .enumerate()
        .skip(1)
        .find(|&(i, &b)| (b == b'-' || b == b'+') && tok[i - 1].is_ascii_digit())
        .map(|(i, _)| i)?;
    let mut s = Vec::with_capacity(tok.len() + 1);
    s.extend_from_slice(&tok[..p]);
    s.push(b'E');
    s.extend_from_slice(&tok[p..]);
    text::parse_real(&s)
}

/// The name of a marker line (` ---material point data---`), if `line` is one.
fn marker(line: &[u8]) -> Option<String> {
    let t = text::trim(line);
    let inner = t.strip_prefix(b"---")?;
    let s = String::from_utf8_lossy(inner);
    Some(s.trim_matches('-').trim().to_string())
}

/// Reads any benchmark file (`.BMS`, `.BMR`) block by block.
pub fn read_tables(data: &[u8], file: &str) -> Result<Tables> {
    let at = |n: usize| Location::new(file, n, None);
    let mut out = Tables::default();
    let mut lines = Lines::new(data, 1).peekable();
    let mut current: Option<String> = None;
    let mut ended = false;
    while let Some((n, line)) = lines.next() {
        if let Some(name) = marker(line) {
            if name == "end-of-file" {
                ended = true;
                break;
            }
            if name != "general project data" {
                // A data block: its header, possibly over several lines, then its rows.
                let table = read_block(&mut lines, n, file)?;
                out.blocks.push(Block { name, table });
                current = None;
            } else {
                current = Some(name);
            }
            continue;
        }
        if text::is_blank(line) {
            continue;
        }
        match current.as_deref() {
            Some("general project data") => {
                let toks: Vec<&[u8]> = Tokens::new(line).collect();
                let Some((last, desc)) = toks.split_last() else {
                    continue;
                };
                let v = number(last).ok_or_else(|| {
                    Error::format(
                        at(n),
                        format!(
                            "expected a description and a number, found {}",
                            text::show(line)
                        ),
                    )
                })?;
                let desc: Vec<String> = desc
                    .iter()
                    .map(|t| String::from_utf8_lossy(t).into_owned())
                    .collect();
                out.project.push((desc.join(" "), v));
            }
            _ => {
                return Err(Error::format(
                    at(n),
                    format!(
                        "expected a block marker such as ' ---material point data---', found {}",
                        text::show(line)
                    ),
                ))
            }
        }
    }
    if !ended {
        return Err(Error::format(
            at(0),
            "file ends without ' ---end-of-file---' (truncated?)",
        ));
    }
    Ok(out)
}

/// Reads a data block after its marker at line `marker_line`: the header (up to the first line
/// that starts with a number), then rows up to the next marker.
fn read_block(
    lines: &mut std::iter::Peekable<Lines<'_>>,
    marker_line: usize,
    file: &str,
) -> Result<Table> {
    let at = |n: usize| Location::new(file, n, None);
    let mut names: Vec<String> = Vec::new();
    let mut header_line = 0;
    let mut table = Table::default();
    // Header lines: the first must start with LoadStep.
    while let Some(&(n, line)) = lines.peek() {
        if marker(line).is_some() {
            break;
        }
        if text::is_blank(line) {
            lines.next();
            continue;
        }
        let first = Tokens::new(line).next().unwrap_or_default();
        if number(first).is_some() {
            break;
        }
        if names.is_empty() && first != b"LoadStep" {
            return Err(Error::format(
                at(n),
                format!(
                    "expected the column header ('LoadStep ...'), found {}",
                    text::show(line)
                ),
            ));
        }
        if header_line == 0 {
            header_line = n;
        }
        for tok in Tokens::new(line) {
            names.extend(header_names(&String::from_utf8_lossy(tok)));
        }
        lines.next();
    }
    // Rows.
    let mut dropped = false;
    while let Some(&(n, line)) = lines.peek() {
        if marker(line).is_some() {
            break;
        }
        lines.next();
        if text::is_blank(line) {
            continue;
        }
        if names.is_empty() {
            return Err(Error::format(
                at(n),
                format!(
                    "a row before the column header of the block at line {marker_line}: {}",
                    text::show(line)
                ),
            ));
        }
        let mut row = Vec::with_capacity(names.len());
        for tok in Tokens::new(line) {
            let v = number(tok).ok_or_else(|| {
                Error::format(
                    at(n),
                    format!("expected a number, found {}", text::show(tok)),
                )
            })?;
            row.push(v);
        }
        if row.len() != names.len() && !dropped && table.rows.is_empty() {
            // 2D files name Z columns their rows leave out.
            let z = |c: &String| matches!(c.as_str(), "Z" | "Uz" | "U_Z");
            let nz = names.iter().filter(|c| z(c)).count();
            if nz > 0 && row.len() == names.len() - nz {
                names.retain(|c| !z(c));
                dropped = true;
            }
        }
        if row.len() != names.len() {
            return Err(Error::format(
                at(n),
                format!(
                    "expected {} values (the columns of line {header_line}: {}), found {}",
                    names.len(),
                    names.join(" "),
                    row.len()
                ),
            ));
        }
        table.rows.push(row);
        table.lines.push(n);
    }
    table.columns = names;
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BMS_3D: &str = " ---general project data-----------\n\
Number of load steps                               1          \n\
Number of material points                        240          \n\
 ---material point data------------\n\
                  LoadStep   TimeStep   Time   PA   PGravity   ID_MP   X   Y   Z   Ux   Uy   Uz   SigmaXX   SigmaYY   SigmaZZ   SigmaXY   SigmaYZ   SigmaZX   WPressure   IntWeight   MatID \n\
           1           2  0.5911E-02   1.000       0.000               7  0.7236E-01  0.9579     -0.1382E-01   0.000     -0.6674E-03   0.000     -0.2145     -0.8580     -0.2145      0.1356E-01  0.1150       0.000       0.000      0.4134E-04           1\n\
           1           2  0.5911E-02   1.000       0.000             140  0.7236E-01  0.8137     -0.4146E-01   0.000     -0.9307E-04   0.000     -0.1284     -0.5137     -0.1284     -0.6030E-02 -0.3015E-02   0.000       0.1234-100  0.4147E-04           1\n\
 ---end-of-file-------------------\n";

    #[test]
    fn reads_a_3d_table_by_name() {
        let b = read_bms(BMS_3D.as_bytes(), "t.BMS").unwrap();
        assert_eq!(b.project.len(), 2);
        assert_eq!(b.project[1], ("Number of material points".into(), 240.0));
        let t = &b.material_points;
        assert_eq!(t.len(), 2);
        assert_eq!(t.columns.len(), 21);
        assert_eq!(t.lines, vec![6, 7]);
        assert_eq!(t.get(1, "ID_MP"), Some(140.0));
        let r = b.records();
        assert_eq!(r[0].id, 7);
        assert_eq!(r[0].load_step, 1);
        assert_eq!(r[0].time_step, 2);
        assert_eq!(r[0].time, 0.5911e-2);
        assert_eq!(r[0].position, [0.07236, 0.9579, -0.01382]);
        assert_eq!(r[0].displacement, [0.0, -0.6674e-3, 0.0]);
        assert_eq!(r[0].stress, [-0.2145, -0.858, -0.2145, 0.01356, 0.115, 0.0]);
        // Fortran's exponent without E.
        assert_eq!(r[1].pore_pressure, 0.1234e-100);
    }

    #[test]
    fn reads_the_wrapped_and_glued_2d_header() {
        let src = " ---material point data-----\n\
 LoadStep TimeStep TimePA(1) PA(2) PGravity ID_MP X Y Ux Uy SigmaXX SigmaYY \n\
 SigmaZZ SigmaXY WPressureEpsilonXX EpsilonYY EpsilonZZ GammaXY IntWeight MatID \n\
           2           2  0.4663       0.000       0.000       1.000            1376  0.1736       2.658     -0.4637E-08 -0.8637E-02  -11.31      -45.24      -11.31     -0.2895E-02   0.000     -0.7926E-3 1 2 3  0.1E-1  1\n\
 ---end-of-file-----\n";
        let b = read_bms(src.as_bytes(), "t").unwrap();
        let t = &b.material_points;
        assert_eq!(
            &t.columns[..5],
            &["LoadStep", "TimeStep", "Time", "PA(1)", "PA(2)"]
        );
        assert_eq!(t.column("WPressure"), Some(15));
        assert_eq!(t.column("EpsilonXX"), Some(16));
        let r = b.records()[0];
        assert_eq!(r.id, 1376);
        assert_eq!(r.position, [0.1736, 2.658, 0.0]);
        assert_eq!(r.stress, [-11.31, -45.24, -11.31, -0.2895e-2, 0.0, 0.0]);
    }

    #[test]
    fn reads_a_bmr_and_drops_the_z_columns_2d_rows_leave_out() {
        let src = " ---general project data-----\n\
Number of load steps                               1                                      \n\
 ---nodal data-------\n\
 LoadStep,TimeStep,Node_ID,U_X,U_Y,U_Z\n\
    1         2         4    0.000000000       -0.4320000000E-002\n\
    1         2         5    0.000000000       -0.5274725275E-028\n\
 ---material point data-------\n\
 LoadStep,TimeStep,MP_ID,X,Y,Z\n\
    1         2         1    0.3333333333E-01    0.3333333333E-01\n\
 ---end-of-file------\n";
        let b = read_bmr(src.as_bytes(), "t.BMR").unwrap();
        assert_eq!(
            b.nodes.columns,
            vec!["LoadStep", "TimeStep", "Node_ID", "U_X", "U_Y"]
        );
        let n = b.node_records();
        assert_eq!(n.len(), 2);
        assert_eq!(n[0].id, 4);
        assert_eq!(n[0].value, [0.0, -0.432e-2, 0.0]);
        let m = b.material_point_records();
        assert_eq!(m[0].id, 1);
        assert_eq!(m[0].value[1], 0.3333333333e-1);
    }

    #[test]
    fn a_file_without_material_points_is_empty_not_an_error() {
        let src = " ---general project data---\nNumber of nodes   27\n ---end-of-file---\n";
        let b = read_bms(src.as_bytes(), "t").unwrap();
        assert!(b.material_points.is_empty());
        assert_eq!(b.project, vec![("Number of nodes".into(), 27.0)]);
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases: &[(&str, &str)] = &[
            (
                " ---material point data---\n LoadStep TimeStep Time ID_MP X Y\n 1 2 0.1 3 0.5\n ---end-of-file---\n",
                "t.BMS:3: expected 6 values",
            ),
            (
                " ---material point data---\n LoadStep TimeStep Time ID_MP X Y\n 1 2 0.1 x 0.5 1\n ---end-of-file---\n",
                "t.BMS:3: expected a number, found 'x'",
            ),
            (
                " ---material point data---\n LoadStep TimeStep Time ID_MP X Y\n 1 2 0.1 3.5 0.5 1\n ---end-of-file---\n",
                "t.BMS:3: column 'ID_MP' must hold a whole number",
            ),
            (
                " ---material point data---\n LoadStep TimeStep Time X Y\n 1 2 0.1 0.5 1\n ---end-of-file---\n",
                "t.BMS:3: the table has no column 'ID_MP'",
            ),
            (
                " ---material point data---\n Step TimeStep\n ---end-of-file---\n",
                "t.BMS:2: expected the column header",
            ),
            (
                " ---material point data---\n LoadStep TimeStep Time ID_MP X Y\n 1 2 0.1 3 0.5 1\n",
                "t.BMS: file ends without",
            ),
            ("hello\n", "t.BMS:1: expected a block marker"),
            (
                " ---general project data---\nNumber of nodes  many\n ---end-of-file---\n",
                "t.BMS:2: expected a description and a number",
            ),
        ];
        for (src, want) in cases {
            let e = read_bms(src.as_bytes(), "t.BMS").unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
        }
    }

    #[test]
    fn never_panics_on_truncated_input() {
        let full = BMS_3D.as_bytes();
        for n in 0..full.len() {
            let _ = read_bms(&full[..n], "t");
            let _ = read_bmr(&full[..n], "t");
        }
    }

    fn suite() -> Option<std::path::PathBuf> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        crate::suite::anura3d_benchmarks(&root).unwrap_or_else(|e| panic!("{e}"))
    }

    fn walk(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else {
                out.push(p);
            }
        }
    }

    #[test]
    fn reads_every_expected_file_of_the_suite() {
        let Some(root) = suite() else {
            crate::suite::skipped("the suite's BMS/BMR files (ANURA3D_BENCHMARKS not set)");
            return;
        };
        let mut files = Vec::new();
        walk(&root, &mut files);
        let (mut bms, mut bmr, mut rows) = (0, 0, 0);
        for f in &files {
            let name = f.to_string_lossy();
            if !(name.ends_with("_expected.BMS") || name.ends_with("_expected.BMR")) {
                continue;
            }
            let data = std::fs::read(f).unwrap();
            if name.ends_with(".BMS") {
                let b = read_bms(&data, &name).unwrap_or_else(|e| panic!("{e}"));
                // Glued 2D header names are all resolved into known columns.
                for c in &b.material_points.columns {
                    assert!(is_known(c), "{name}: column {c:?}");
                }
                for r in b.records() {
                    assert!(r.id >= 1 && r.time >= 0.0, "{name}: {r:?}");
                }
                // The project block, where present, counts the material points.
                if let Some(n) = b
                    .project
                    .iter()
                    .find(|(d, _)| d == "Number of material points")
                {
                    assert!(b.records().iter().all(|r| (r.id as f64) <= n.1), "{name}");
                }
                rows += b.material_points.len();
                bms += 1;
            } else {
                let b = read_bmr(&data, &name).unwrap_or_else(|e| panic!("{e}"));
                rows += b.nodes.len() + b.material_points.len();
                bmr += 1;
            }
        }
        assert!(
            bms > 0 && bmr > 0,
            "no expected files under {}",
            root.display()
        );
        eprintln!("read {bms} BMS and {bmr} BMR files, {rows} rows");
    }
}
