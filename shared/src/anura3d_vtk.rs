//! Reader for the material-point files Anura3D writes: legacy VTK, binary, big-endian
//! (`PROJ_MPScalar_NNN.vtk`, `PROJ_MPVector_NNN.vtk`, `PROJ_MPTensor_NNN.vtk` at the end of
//! load step NNN).
//!
//! The layout: three lines (`# vtk DataFile Version 3.0`, a title, `BINARY`), then keyword lines
//! each followed by its binary data: `DATASET UNSTRUCTURED_GRID`, `POINTS n type`,
//! `CELLS n size`, `CELL_TYPES n`, `POINT_DATA n` / `CELL_DATA n`, and per field
//! `SCALARS name type [components]` + `LOOKUP_TABLE name`, `VECTORS name type`,
//! `NORMALS name type`, `TENSORS name type` (9 values, row by row) or `FIELD name arrays` with
//! `name components tuples type` per array. Types: `double`, `float`, `int`, `unsigned_int`,
//! `long`, `unsigned_long`, `short`, `unsigned_short`, `char`, `unsigned_char` (any case).
//!
//! Every count is checked against the bytes left before anything is allocated, so a truncated
//! or corrupt file gives an error naming the file and the byte offset, never a panic or a huge
//! allocation.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Location, Result};
use crate::text;

/// One data array: `components` values per point (or cell), all as `f64`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Field {
    /// Values per tuple (1 for scalars, 3 for vectors, 9 for tensors).
    pub components: usize,
    /// The values, tuple after tuple.
    pub values: Vec<f64>,
}

impl Field {
    /// Number of tuples.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.components).unwrap_or(0)
    }

    /// True when there are no tuples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Tuple `i`.
    pub fn tuple(&self, i: usize) -> &[f64] {
        &self.values[i * self.components..(i + 1) * self.components]
    }
}

/// A legacy VTK unstructured grid as read.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LegacyVtk {
    /// The title line.
    pub title: String,
    /// `POINTS`.
    pub points: Vec<[f64; 3]>,
    /// `CELLS`: the raw list (per cell its node count, then its point indices).
    pub cells: Vec<i64>,
    /// `CELL_TYPES`.
    pub cell_types: Vec<i64>,
    /// Fields given per point (`POINT_DATA`), by name.
    pub point_data: BTreeMap<String, Field>,
    /// Fields given per cell (`CELL_DATA`), by name.
    pub cell_data: BTreeMap<String, Field>,
    /// Names that occur more than once in a section (Anura3D writes `stress_liquid` twice); the
    /// first occurrence is kept.
    pub duplicates: Vec<String>,
}

/// A binary scalar type.
#[derive(Debug, Clone, Copy)]
enum Type {
    F64,
    F32,
    I32,
    U32,
    I64,
    U64,
    I16,
    U16,
    I8,
    U8,
}

impl Type {
    /// The type named `word` (any case).
    fn parse(word: &str) -> Option<Type> {
        Some(match word.to_ascii_lowercase().as_str() {
            "double" => Type::F64,
            "float" => Type::F32,
            "int" => Type::I32,
            "unsigned_int" => Type::U32,
            "long" | "vtkidtype" => Type::I64,
            "unsigned_long" => Type::U64,
            "short" => Type::I16,
            "unsigned_short" => Type::U16,
            "char" => Type::I8,
            "unsigned_char" => Type::U8,
            _ => return None,
        })
    }

    /// Bytes per value.
    fn size(self) -> usize {
        match self {
            Type::F64 | Type::I64 | Type::U64 => 8,
            Type::F32 | Type::I32 | Type::U32 => 4,
            Type::I16 | Type::U16 => 2,
            Type::I8 | Type::U8 => 1,
        }
    }

    /// The big-endian value at the start of `b` (at least `size` bytes).
    fn decode(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut x = [0u8; 8];
            x[..n].copy_from_slice(&b[..n]);
            x
        };
        match self {
            Type::F64 => f64::from_be_bytes(a(8)),
            Type::F32 => f32::from_be_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Type::I32 => i32::from_be_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Type::U32 => u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Type::I64 => i64::from_be_bytes(a(8)) as f64,
            Type::U64 => u64::from_be_bytes(a(8)) as f64,
            Type::I16 => i16::from_be_bytes([b[0], b[1]]) as f64,
            Type::U16 => u16::from_be_bytes([b[0], b[1]]) as f64,
            Type::I8 => b[0] as i8 as f64,
            Type::U8 => b[0] as f64,
        }
    }
}

/// A cursor over the file: header lines as text, data blocks as bytes.
struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    file: &'a str,
}

impl<'a> Reader<'a> {
    /// An error at byte `at`.
    fn err(&self, at: usize, message: impl Into<String>) -> Error {
        Error::format(
            Location::new(self.file, 0, None),
            format!("at byte {at}: {}", message.into()),
        )
    }

    /// The next line (without its terminator), or `None` at the end.
    fn line(&mut self) -> Option<(usize, &'a [u8])> {
        if self.pos >= self.data.len() {
            return None;
        }
        let start = self.pos;
        let rest = &self.data[start..];
        let (mut l, adv) = match memchr::memchr(b'\n', rest) {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        if let [h @ .., b'\r'] = l {
            l = h;
        }
        self.pos += adv;
        Some((start, l))
    }

    /// The next non-blank header line split into words; `None` at the end of the file.
    fn words(&mut self) -> Option<(usize, Vec<String>)> {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let (at, l) = self.line()?;
        Some((
            at,
            String::from_utf8_lossy(l)
                .split_ascii_whitespace()
                .map(str::to_string)
                .collect(),
        ))
    }

    /// `count` tuples of `width` values of type `ty`, after checking the bytes are there.
    fn values(&mut self, at: usize, count: usize, width: usize, ty: Type) -> Result<Vec<f64>> {
        let n = count
            .checked_mul(width)
            .ok_or_else(|| self.err(at, "count too large"))?;
        let bytes = n
            .checked_mul(ty.size())
            .ok_or_else(|| self.err(at, "count too large"))?;
        let left = self.data.len() - self.pos;
        if bytes > left {
            return Err(self.err(
                at,
                format!("{n} values need {bytes} bytes, only {left} are left (truncated?)"),
            ));
        }
        let block = &self.data[self.pos..self.pos + bytes];
        self.pos += bytes;
        Ok(block
            .chunks_exact(ty.size())
            .map(|c| ty.decode(c))
            .collect())
    }

    /// `count` big-endian 32-bit integers (the `CELLS` and `CELL_TYPES` data).
    fn integers(&mut self, at: usize, count: usize) -> Result<Vec<i64>> {
        Ok(self
            .values(at, count, 1, Type::I32)?
            .into_iter()
            .map(|v| v as i64)
            .collect())
    }
}

/// Word `i` of the header line `w` (at byte `at`) as a count.
fn count(r: &Reader<'_>, at: usize, w: &[String], i: usize) -> Result<usize> {
    w.get(i)
        .and_then(|s| s.parse::<usize>().ok())
        .ok_or_else(|| r.err(at, format!("expected a count in '{}'", w.join(" "))))
}

/// Word `i` of the header line `w` (at byte `at`) as a data type.
fn ty(r: &Reader<'_>, at: usize, w: &[String], i: usize) -> Result<Type> {
    let word = w.get(i).map(String::as_str).unwrap_or("");
    Type::parse(word).ok_or_else(|| {
        r.err(
            at,
            format!("unsupported data type '{word}' in '{}'", w.join(" ")),
        )
    })
}

/// The name (second word) of the header line `w` (at byte `at`).
fn name(r: &Reader<'_>, at: usize, w: &[String]) -> Result<String> {
    w.get(1)
        .cloned()
        .ok_or_else(|| r.err(at, format!("expected a name in '{}'", w.join(" "))))
}

/// Which section the fields read belong to.
#[derive(Clone, Copy, PartialEq)]
enum Section {
    None,
    Points(usize),
    Cells(usize),
}

/// One field as read, before it is filed under its name.
type NamedField = (String, Field);

impl Reader<'_> {
    /// Reads the three header lines (`# vtk DataFile Version ...`, the title, `BINARY`) and
    /// returns the title.
    fn header(&mut self) -> Result<String> {
        let (at, magic) = self
            .line()
            .ok_or_else(|| self.err(0, "empty file: expected '# vtk DataFile Version 3.0'"))?;
        if !magic.starts_with(b"# vtk DataFile") {
            return Err(self.err(
                at,
                format!(
                    "expected '# vtk DataFile Version ...', found {}",
                    text::show(magic)
                ),
            ));
        }
        let (_, title) = self
            .line()
            .ok_or_else(|| self.err(self.pos, "file ends after its first line"))?;
        let title = String::from_utf8_lossy(title).trim().to_string();
        let (at, enc) = self
            .line()
            .ok_or_else(|| self.err(self.pos, "file ends before 'BINARY'"))?;
        match text::trim(enc) {
            b"BINARY" => Ok(title),
            b"ASCII" => Err(Error::Unsupported {
                at: Location::new(self.file, 3, None),
                message: "ASCII legacy VTK (Anura3D's material-point files are BINARY)".into(),
            }),
            other => Err(self.err(
                at,
                format!("expected BINARY or ASCII, found {}", text::show(other)),
            )),
        }
    }

    /// Reads the data of `SCALARS name type [components]` (header words `w` at byte `at`) and
    /// its `LOOKUP_TABLE` line, for `n` tuples.
    fn scalars(&mut self, at: usize, n: usize, w: &[String]) -> Result<NamedField> {
        let nm = name(self, at, w)?;
        let t = ty(self, at, w, 2)?;
        let comps = match w.get(3) {
            None => 1,
            Some(_) => count(self, at, w, 3)?,
        };
        if !(1..=4).contains(&comps) {
            return Err(self.err(at, format!("{comps} components (1 to 4 allowed)")));
        }
        let (lat, lt) = self
            .words()
            .ok_or_else(|| self.err(self.pos, "file ends before LOOKUP_TABLE"))?;
        if lt.first().map(String::as_str) != Some("LOOKUP_TABLE") {
            return Err(self.err(
                lat,
                format!("expected 'LOOKUP_TABLE name', found '{}'", lt.join(" ")),
            ));
        }
        let values = self.values(at, n, comps, t)?;
        Ok((
            nm,
            Field {
                components: comps,
                values,
            },
        ))
    }

    /// Reads the data of `VECTORS`, `NORMALS` (3 components) or `TENSORS` (9) `name type`, for
    /// `n` tuples.
    fn vectors(&mut self, at: usize, n: usize, w: &[String], tensors: bool) -> Result<NamedField> {
        let nm = name(self, at, w)?;
        let t = ty(self, at, w, 2)?;
        let comps = if tensors { 9 } else { 3 };
        let values = self.values(at, n, comps, t)?;
        Ok((
            nm,
            Field {
                components: comps,
                values,
            },
        ))
    }

    /// Reads the arrays of `FIELD name arrays`, each `name components tuples type` then its data.
    fn field_arrays(&mut self, at: usize, w: &[String]) -> Result<Vec<NamedField>> {
        let arrays = count(self, at, w, 2)?;
        let mut fields = Vec::new();
        for _ in 0..arrays {
            let (aat, aw) = self
                .words()
                .ok_or_else(|| self.err(self.pos, "file ends inside a FIELD"))?;
            let an = aw.first().cloned().unwrap_or_default();
            let comps = count(self, aat, &aw, 1)?;
            let tuples = count(self, aat, &aw, 2)?;
            let t = ty(self, aat, &aw, 3)?;
            let values = self.values(aat, tuples, comps, t)?;
            fields.push((
                an,
                Field {
                    components: comps,
                    values,
                },
            ));
        }
        Ok(fields)
    }

    /// Skips VTK 5 metadata: text lines up to a blank line.
    fn skip_metadata(&mut self) {
        while let Some((_, l)) = self.line() {
            if text::is_blank(l) {
                break;
            }
        }
    }
}

/// The keyword lines after the header, read one by one into the grid.
struct Grid<'a> {
    r: Reader<'a>,
    out: LegacyVtk,
    section: Section,
    have_points: bool,
}

/// Reads one Anura3D legacy VTK file (binary, big-endian) from memory.
pub fn read(data: &[u8], file: &str) -> Result<LegacyVtk> {
    let mut r = Reader { data, pos: 0, file };
    let title = r.header()?;
    let mut g = Grid {
        r,
        out: LegacyVtk {
            title,
            ..Default::default()
        },
        section: Section::None,
        have_points: false,
    };
    while let Some((at, w)) = g.r.words() {
        let Some(key) = w.first() else { continue };
        let key = key.to_ascii_uppercase();
        g.keyword(at, &key, &w)?;
    }
    Ok(g.out)
}

impl Grid<'_> {
    /// Reads the keyword line `w` (at byte `at`, its keyword `key` in upper case) and its data.
    fn keyword(&mut self, at: usize, key: &str, w: &[String]) -> Result<()> {
        let r = &mut self.r;
        match key {
            "DATASET" => {
                if w.get(1).map(String::as_str) != Some("UNSTRUCTURED_GRID") {
                    return Err(Error::Unsupported {
                        at: Location::new(r.file, 0, None),
                        message: format!(
                            "at byte {at}: '{}' (only UNSTRUCTURED_GRID is read)",
                            w.join(" ")
                        ),
                    });
                }
            }
            "POINTS" => {
                let n = count(r, at, w, 1)?;
                let t = ty(r, at, w, 2)?;
                let v = r.values(at, n, 3, t)?;
                self.out.points = v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                self.have_points = true;
            }
            "CELLS" => {
                count(r, at, w, 1)?;
                let size = count(r, at, w, 2)?;
                self.out.cells = r.integers(at, size)?;
            }
            "CELL_TYPES" => {
                let n = count(r, at, w, 1)?;
                self.out.cell_types = r.integers(at, n)?;
            }
            "POINT_DATA" => {
                let n = count(r, at, w, 1)?;
                if self.have_points && n != self.out.points.len() {
                    return Err(r.err(
                        at,
                        format!("POINT_DATA {n} but {} points", self.out.points.len()),
                    ));
                }
                self.section = Section::Points(n);
            }
            "CELL_DATA" => self.section = Section::Cells(count(r, at, w, 1)?),
            "LOOKUP_TABLE" => {
                // A colour table of `size` RGBA entries (4 unsigned chars each), not data.
                let n = count(r, at, w, 2)?;
                r.values(at, n, 4, Type::U8)?;
            }
            "SCALARS" | "VECTORS" | "NORMALS" | "TENSORS" | "FIELD" => {
                self.fields(at, key, w)?;
            }
            "METADATA" => r.skip_metadata(),
            _ => {
                return Err(r.err(
                    at,
                    format!("unexpected line '{}'", text::show(w.join(" ").as_bytes())),
                ))
            }
        }
        Ok(())
    }

    /// Reads the fields of a `SCALARS`, `VECTORS`, `NORMALS`, `TENSORS` or `FIELD` line into the
    /// current section; a name seen before in it keeps its first field and is noted.
    fn fields(&mut self, at: usize, key: &str, w: &[String]) -> Result<()> {
        let n = match self.section {
            Section::Points(n) | Section::Cells(n) => n,
            Section::None => {
                return Err(self.r.err(
                    at,
                    format!("'{}' before POINT_DATA or CELL_DATA", w.join(" ")),
                ))
            }
        };
        let fields = match key {
            "SCALARS" => vec![self.r.scalars(at, n, w)?],
            "VECTORS" | "NORMALS" | "TENSORS" => {
                vec![self.r.vectors(at, n, w, key == "TENSORS")?]
            }
            _ => self.r.field_arrays(at, w)?,
        };
        let map = match self.section {
            Section::Cells(_) => &mut self.out.cell_data,
            _ => &mut self.out.point_data,
        };
        for (nm, f) in fields {
            match map.entry(nm) {
                Entry::Occupied(e) => self.out.duplicates.push(e.key().clone()),
                Entry::Vacant(e) => {
                    e.insert(f);
                }
            }
        }
        Ok(())
    }
}

/// Reads one file from disk.
pub fn read_file(path: &Path) -> Result<LegacyVtk> {
    let data = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    read(&data, &path.display().to_string())
}

/// The state of one material point at the end of a load step, from Anura3D's three files.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialPointState {
    /// `material_point_id` (1-based, as in the GOM).
    pub id: u32,
    /// Position (the files' `POINTS`).
    pub position: [f64; 3],
    /// `displacement_solid`.
    pub displacement_solid: [f64; 3],
    /// `eff_stress_solid` as xx yy zz xy yz zx (tension positive).
    pub eff_stress_solid: [f64; 6],
    /// `total_stress_solid` as xx yy zz xy yz zx.
    pub total_stress_solid: [f64; 6],
    /// `pressure_liquid`, when the file has it.
    pub pressure_liquid: Option<f64>,
}

/// The names of the three files of load step `step` of project `project`
/// (`PROJ_MPScalar_001.vtk`, `PROJ_MPVector_001.vtk`, `PROJ_MPTensor_001.vtk`); step 0 is the
/// state after the first time step.
pub fn step_files(project: &str, step: u32) -> [String; 3] {
    ["MPScalar", "MPVector", "MPTensor"].map(|k| format!("{project}_{k}_{step:03}.vtk"))
}

/// The six components xx yy zz xy yz zx of a 3x3 tensor given row by row.
pub fn voigt(t: &[f64]) -> [f64; 6] {
    [t[0], t[4], t[8], t[1], t[5], t[2]]
}

/// Reads the three files of load step `step` of `project` in `dir` and returns every material
/// point, ordered by id.
pub fn read_step(dir: &Path, project: &str, step: u32) -> Result<Vec<MaterialPointState>> {
    let [s, v, t] = step_files(project, step).map(|n| dir.join(n));
    let (sv, vv, tv) = (read_file(&s)?, read_file(&v)?, read_file(&t)?);
    material_points(&sv, &vv, &tv, &s.display().to_string())
}

/// Combines a step's scalar, vector and tensor files (read already) into the material points,
/// ordered by id. `file` names the scalar file in messages.
pub fn material_points(
    scalar: &LegacyVtk,
    vector: &LegacyVtk,
    tensor: &LegacyVtk,
    file: &str,
) -> Result<Vec<MaterialPointState>> {
    let at = || Location::new(file, 0, None);
    let n = scalar.points.len();
    if vector.points != scalar.points || tensor.points != scalar.points {
        return Err(Error::invalid(
            at(),
            "the scalar, vector and tensor files have different points (not the same step?)",
        ));
    }
    let field = |vtk: &LegacyVtk, name: &str, comps: usize| -> Result<Field> {
        let f = vtk.point_data.get(name).ok_or_else(|| {
            Error::format(at(), format!("no point field '{name}' in the step's files"))
        })?;
        if f.components != comps || f.len() != n {
            return Err(Error::invalid(
                at(),
                format!(
                    "field '{name}' has {} components and {} tuples, expected {comps} and {n}",
                    f.components,
                    f.len()
                ),
            ));
        }
        Ok(f.clone())
    };
    let ids = field(scalar, "material_point_id", 1)?;
    let disp = field(vector, "displacement_solid", 3)?;
    let eff = field(tensor, "eff_stress_solid", 9)?;
    let total = field(tensor, "total_stress_solid", 9)?;
    let pressure = match scalar.point_data.get("pressure_liquid") {
        Some(_) => Some(field(scalar, "pressure_liquid", 1)?),
        None => None,
    };
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let id = ids.values[i];
        if !(id >= 1.0 && id <= u32::MAX as f64 && id.fract() == 0.0) {
            return Err(Error::invalid(
                at(),
                format!("material_point_id {id} of point {i} is not a positive whole number"),
            ));
        }
        let d = disp.tuple(i);
        out.push(MaterialPointState {
            id: id as u32,
            position: scalar.points[i],
            displacement_solid: [d[0], d[1], d[2]],
            eff_stress_solid: voigt(eff.tuple(i)),
            total_stress_solid: voigt(total.tuple(i)),
            pressure_liquid: pressure.as_ref().map(|p| p.values[i]),
        });
    }
    out.sort_by_key(|p| p.id);
    if let Some(w) = out.windows(2).find(|w| w[0].id == w[1].id) {
        return Err(Error::invalid(
            at(),
            format!("material_point_id {} occurs twice", w[0].id),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A big-endian file as Anura3D writes it: `n` points, one vertex cell each.
    struct Builder(Vec<u8>);

    impl Builder {
        fn new(n: usize) -> Self {
            let mut b = Builder(Vec::new());
            b.text("# vtk DataFile Version 3.0\nproj\nBINARY\nDATASET UNSTRUCTURED_GRID\n");
            b.text(&format!("POINTS {n} DOUBLE\n"));
            for i in 0..n {
                for d in 0..3 {
                    b.f64(i as f64 + 0.1 * d as f64);
                }
            }
            b.text(&format!("CELLS {n} {}\n", 2 * n));
            for i in 0..n {
                b.i32(1);
                b.i32(i as i32);
            }
            b.text(&format!("CELL_TYPES {n}\n"));
            for _ in 0..n {
                b.i32(1);
            }
            b.text(&format!("POINT_DATA {n}\n"));
            b
        }
        fn text(&mut self, s: &str) {
            self.0.extend_from_slice(s.as_bytes());
        }
        fn f64(&mut self, v: f64) {
            self.0.extend_from_slice(&v.to_be_bytes());
        }
        fn i32(&mut self, v: i32) {
            self.0.extend_from_slice(&v.to_be_bytes());
        }
    }

    /// Scalar, vector and tensor files of 3 points with ids 3, 1, 2.
    fn step() -> [Vec<u8>; 3] {
        let ids = [3, 1, 2];
        let mut s = Builder::new(3);
        s.text("SCALARS pressure_liquid DOUBLE 1\nLOOKUP_TABLE default\n");
        for &id in &ids {
            s.f64(-10.0 * id as f64);
        }
        s.text("SCALARS material_point_id int 1\nLOOKUP_TABLE default\n");
        for &id in &ids {
            s.i32(id);
        }
        s.text("SCALARS weight float 1\nLOOKUP_TABLE default\n");
        for _ in ids {
            s.0.extend_from_slice(&0.5f32.to_be_bytes());
        }
        let mut v = Builder::new(3);
        v.text("VECTORS displacement_solid DOUBLE\n");
        for &id in &ids {
            for d in 0..3 {
                v.f64(id as f64 * 100.0 + d as f64);
            }
        }
        v.text("\n"); // some writers end binary blocks with a newline
        v.text("VECTORS velocity_solid DOUBLE\n");
        for _ in 0..9 {
            v.f64(0.0);
        }
        let mut t = Builder::new(3);
        for name in [
            "eff_stress_solid",
            "total_stress_solid",
            "stress_liquid",
            "stress_liquid",
        ] {
            t.text(&format!("TENSORS {name} DOUBLE\n"));
            for &id in &ids {
                // xx xy xz / yx yy yz / zx zy zz, symmetric.
                let k = id as f64;
                for v in [1.0, 4.0, 6.0, 4.0, 2.0, 5.0, 6.0, 5.0, 3.0] {
                    t.f64(k * v);
                }
            }
        }
        [s.0, v.0, t.0]
    }

    #[test]
    fn reads_a_big_endian_step() {
        let [s, v, t] = step();
        let sv = read(&s, "s.vtk").unwrap();
        assert_eq!(sv.title, "proj");
        assert_eq!(sv.points.len(), 3);
        assert_eq!(sv.points[1], [1.0, 1.1, 1.2]);
        assert_eq!(sv.cells.len(), 6);
        assert_eq!(sv.cell_types, vec![1, 1, 1]);
        assert_eq!(sv.point_data["weight"].values, vec![0.5; 3]);
        assert_eq!(
            sv.point_data["material_point_id"].values,
            vec![3.0, 1.0, 2.0]
        );
        let vv = read(&v, "v.vtk").unwrap();
        assert_eq!(vv.point_data["velocity_solid"].components, 3);
        let tv = read(&t, "t.vtk").unwrap();
        assert_eq!(tv.duplicates, vec!["stress_liquid".to_string()]);
        let mp = material_points(&sv, &vv, &tv, "s.vtk").unwrap();
        assert_eq!(mp.iter().map(|p| p.id).collect::<Vec<_>>(), vec![1, 2, 3]);
        // Point 1 is the second in the files.
        assert_eq!(mp[0].position, [1.0, 1.1, 1.2]);
        assert_eq!(mp[0].displacement_solid, [100.0, 101.0, 102.0]);
        assert_eq!(mp[2].eff_stress_solid, [3.0, 6.0, 9.0, 12.0, 15.0, 18.0]);
        assert_eq!(mp[0].total_stress_solid, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(mp[1].pressure_liquid, Some(-20.0));
    }

    #[test]
    fn truncated_or_corrupt_files_are_errors_not_panics() {
        for data in step() {
            for n in 0..data.len() {
                let _ = read(&data[..n], "x");
            }
            // Flip bytes one at a time in the text and in the data.
            for i in (0..data.len()).step_by(7) {
                let mut d = data.clone();
                d[i] ^= 0x5a;
                let _ = read(&d, "x");
            }
        }
        let [s, ..] = step();
        let e = read(&s[..s.len() - 3], "s.vtk").unwrap_err().to_string();
        assert!(
            e.contains("s.vtk: at byte") && e.contains("truncated"),
            "{e}"
        );
        // A huge count is refused before anything is allocated.
        let huge = b"# vtk DataFile Version 3.0\nx\nBINARY\nPOINTS 999999999999999 double\n";
        let e = read(huge, "h.vtk").unwrap_err().to_string();
        assert!(e.contains("only 0 are left"), "{e}");
        let e = read(b"# vtk DataFile Version 3.0\nx\nASCII\n", "a.vtk")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unsupported: ASCII"), "{e}");
        let e = read(b"hello", "a.vtk").unwrap_err().to_string();
        assert!(e.contains("expected '# vtk DataFile"), "{e}");
    }

    #[test]
    fn steps_of_different_files_do_not_mix() {
        let [s, v, t] = step();
        let sv = read(&s, "s").unwrap();
        let mut vv = read(&v, "v").unwrap();
        let tv = read(&t, "t").unwrap();
        vv.points[0][0] += 1.0;
        let e = material_points(&sv, &vv, &tv, "s").unwrap_err().to_string();
        assert!(e.contains("different points"), "{e}");
        let vv = read(&v, "v").unwrap();
        let mut sv2 = sv.clone();
        sv2.point_data.remove("material_point_id");
        let e = material_points(&sv2, &vv, &tv, "s")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no point field 'material_point_id'"), "{e}");
        assert_eq!(
            step_files("p", 1),
            [
                "p_MPScalar_001.vtk".to_string(),
                "p_MPVector_001.vtk".to_string(),
                "p_MPTensor_001.vtk".to_string()
            ]
        );
    }

    /// Runs the Anura3D binary named by `ANURA3D_ORACLE` on benchmark 1005_3D and reads its
    /// step-1 files back.
    #[test]
    fn reads_the_oracle_output_of_1005_3d() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let (Some(oracle), Some(suite)) = (
            crate::suite::anura3d_oracle(&root).unwrap_or_else(|e| panic!("{e}")),
            crate::suite::anura3d_benchmarks(&root).unwrap_or_else(|e| panic!("{e}")),
        ) else {
            crate::suite::skipped(
                "reads_the_oracle_output_of_1005_3d (ANURA3D_ORACLE or ANURA3D_BENCHMARKS not set)",
            );
            return;
        };
        let case = suite.join(
            "Benchmarks/Pre-Commit_Tests/1005_Oedometer_QS_MPMMP_1Phase_NormalStress_3D/test-1005_3D.A3D",
        );
        assert!(
            oracle.is_file(),
            "ANURA3D_ORACLE={} is not a file",
            oracle.display()
        );
        let dir = tempfile::tempdir().unwrap();
        for ext in ["GOM", "CPS_001"] {
            let name = format!("test-1005_3D.{ext}");
            std::fs::write(
                dir.path().join(&name),
                std::fs::read(case.join(&name)).unwrap(),
            )
            .unwrap();
        }
        let out = std::process::Command::new(&oracle)
            .arg("test-1005_3D")
            .current_dir(dir.path())
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&out.stdout);
        assert!(
            log.trim_end().ends_with("Calculation finished."),
            "the oracle failed:\n{log}"
        );
        let mp = read_step(dir.path(), "test-1005_3D", 1).unwrap();
        assert_eq!(mp.len(), 240);
        for (i, p) in mp.iter().enumerate() {
            assert_eq!(p.id as usize, i + 1);
            // Inside the 0.1 x 1 x 0.1 column, compressed (tension positive), barely moved.
            assert!(p.position[1] > 0.0 && p.position[1] < 1.0, "{p:?}");
            assert!(p.displacement_solid.iter().all(|u| u.abs() < 1e-2), "{p:?}");
            assert!(p.eff_stress_solid[1] <= 1e-9, "{p:?}");
            // Dry: total and effective stress agree, no pore pressure.
            for c in 0..6 {
                let (e, t) = (p.eff_stress_solid[c], p.total_stress_solid[c]);
                assert!((e - t).abs() <= 1e-9 * e.abs().max(1.0), "{p:?}");
            }
            assert_eq!(p.pressure_liquid, Some(0.0));
        }
        // Point 7 as the expected BMS reports it (4 digits).
        let p = &mp[6];
        let want = [-0.2145, -0.8580, -0.2145, 0.1356e-1, 0.1150, 0.0];
        for (got, want) in p.eff_stress_solid.iter().zip(want) {
            assert!((got - want).abs() < 1e-4, "{p:?}");
        }
        assert!((p.displacement_solid[1] + 0.6674e-3).abs() < 1e-7, "{p:?}");
        eprintln!(
            "oracle step 1 of 1005_3D: {} material points read",
            mp.len()
        );
    }
}
