//! Reader for what [`crate::vtu`] writes in its default encoding: `.vtu` files with raw
//! appended binary data (little-endian, `UInt64` block headers), and `.pvd` collections.
//!
//! The file is memory-mapped and every array is checked against the bytes present when the file
//! is opened, so values are then read straight from the page cache without copies (a 10-million
//! point output costs no more memory than its mapping) and a truncated or corrupt file is an
//! error naming the file and the byte offset, never a panic. Only the appended encoding is read:
//! it is what the solver writes; ASCII and base64 files are refused by name.

use std::path::Path;

use crate::error::{Error, Location, Result};
use crate::io::{map_input, Input};

/// Where an array sits in the document.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// `<PointData>`.
    PointData,
    /// `<CellData>`.
    CellData,
    /// `<Points>` (the coordinates).
    Points,
    /// `<Cells>` (connectivity, offsets, types).
    Cells,
}

/// A binary value type of a `DataArray`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarType {
    /// `Float64`.
    F64,
    /// `Float32`.
    F32,
    /// `Int64`.
    I64,
    /// `Int32`.
    I32,
    /// `UInt8`.
    U8,
}

impl ScalarType {
    /// The type named `s` in a `type` attribute.
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "Float64" => ScalarType::F64,
            "Float32" => ScalarType::F32,
            "Int64" => ScalarType::I64,
            "Int32" => ScalarType::I32,
            "UInt8" => ScalarType::U8,
            _ => return None,
        })
    }

    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            ScalarType::F64 | ScalarType::I64 => 8,
            ScalarType::F32 | ScalarType::I32 => 4,
            ScalarType::U8 => 1,
        }
    }
}

/// One array as declared in the header, its data located in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayInfo {
    /// `Name`.
    pub name: String,
    /// The section it belongs to.
    pub section: Section,
    /// `type`.
    pub ty: ScalarType,
    /// `NumberOfComponents`.
    pub components: usize,
    /// Number of tuples (points or cells of the piece).
    pub tuples: usize,
    /// Absolute byte offset of the first value in the file.
    pub start: usize,
}

/// An opened `.vtu` file: its header parsed, its data mapped and checked.
pub struct VtuFile {
    /// The file name as shown in messages.
    pub file: String,
    /// `NumberOfPoints` of the (single) piece.
    pub points: usize,
    /// `NumberOfCells` of the piece.
    pub cells: usize,
    /// Every array, in the order of the header.
    pub arrays: Vec<ArrayInfo>,
    data: Input,
}

/// A view of one array's values, decoded on access.
#[derive(Debug, Clone, Copy)]
pub struct ArrayView<'a> {
    bytes: &'a [u8],
    ty: ScalarType,
    /// Values per tuple.
    pub components: usize,
}

impl ArrayView<'_> {
    /// Number of tuples.
    pub fn len(&self) -> usize {
        (self.bytes.len() / self.ty.size())
            .checked_div(self.components)
            .unwrap_or(0)
    }

    /// True when the array has no tuples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Component `c` of tuple `i` as `f64`; panics when out of range, like slice indexing.
    pub fn get(&self, i: usize, c: usize) -> f64 {
        let k = (i * self.components + c) * self.ty.size();
        let b = &self.bytes[k..k + self.ty.size()];
        match self.ty {
            ScalarType::F64 => f64::from_le_bytes(b.try_into().expect("8 bytes")),
            ScalarType::F32 => f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64,
            ScalarType::I64 => i64::from_le_bytes(b.try_into().expect("8 bytes")) as f64,
            ScalarType::I32 => i32::from_le_bytes(b.try_into().expect("4 bytes")) as f64,
            ScalarType::U8 => b[0] as f64,
        }
    }
}

impl VtuFile {
    /// The array `name` of `section`, if the file has it.
    pub fn array(&self, section: Section, name: &str) -> Option<ArrayView<'_>> {
        let a = self
            .arrays
            .iter()
            .find(|a| a.section == section && a.name == name)?;
        let len = a.tuples * a.components * a.ty.size();
        Some(ArrayView {
            bytes: &self.data[a.start..a.start + len],
            ty: a.ty,
            components: a.components,
        })
    }

    /// The point coordinates (3 components).
    pub fn coordinates(&self) -> Option<ArrayView<'_>> {
        self.array(Section::Points, "Points")
    }

    /// The point-data array `name`.
    pub fn point_data(&self, name: &str) -> Option<ArrayView<'_>> {
        self.array(Section::PointData, name)
    }
}

/// Opens and checks a `.vtu` file (see [`parse`]).
pub fn read_vtu_file(path: &Path) -> Result<VtuFile> {
    let data = map_input(path)?;
    parse(data, &crate::display_name(path))
}

/// The value of attribute `name` in the tag text `tag` (`<DataArray type="Float64" ...`).
fn attr<'t>(tag: &'t str, name: &str) -> Option<&'t str> {
    let key = format!(" {name}=\"");
    let at = tag.find(&key)? + key.len();
    let len = tag[at..].find('"')?;
    Some(&tag[at..at + len])
}

/// Replaces the five XML entities the writer produces.
fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// An error at byte `at` of `file`.
fn at_byte(file: &str, at: usize, m: String) -> Error {
    Error::format(Location::new(file, 0, None), format!("at byte {at}: {m}"))
}

/// Parses a `.vtu` document held in `data`; `file` names it in messages.
pub fn parse(data: Input, file: &str) -> Result<VtuFile> {
    let (mark, raw) = appended_block(&data, file)?;
    let head = xml_header(&data[..mark], file)?;
    let mut out = VtuFile {
        file: file.to_string(),
        points: 0,
        cells: 0,
        arrays: Vec::new(),
        data: Input::Buffer(Vec::new()),
    };
    read_declarations(head, file, &mut out)?;
    for a in &mut out.arrays {
        locate_block(a, &data, raw, file)?;
    }
    out.data = data;
    Ok(out)
}

/// Finds the raw appended data: the offset of its `<AppendedData>` tag, which ends the XML
/// header, and of its first byte (after the `_`).
fn appended_block(data: &[u8], file: &str) -> Result<(usize, usize)> {
    const MARK: &[u8] = b"<AppendedData encoding=\"raw\">";
    let Some(mark) = memchr::memmem::find(data, MARK) else {
        let head = String::from_utf8_lossy(&data[..data.len().min(4096)]).into_owned();
        if head.contains("format=\"ascii\"") || head.contains("format=\"binary\"") {
            return Err(Error::Unsupported {
                at: Location::new(file, 0, None),
                message:
                    "ASCII or base64 VTU (only raw appended data, the solver's default, is read)"
                        .into(),
            });
        }
        return Err(at_byte(
            file,
            data.len(),
            "no '<AppendedData encoding=\"raw\">' block (not a particle file of mpm-solve, or truncated?)".into(),
        ));
    };
    let underscore = memchr::memchr(b'_', &data[mark + MARK.len()..])
        .map(|i| mark + MARK.len() + i)
        .ok_or_else(|| {
            at_byte(
                file,
                mark,
                "no '_' opening the appended data (truncated?)".into(),
            )
        })?;
    Ok((mark, underscore + 1))
}

/// The XML header as text, checked to be an unstructured grid in the layout read here
/// (little-endian, 64-bit block headers).
fn xml_header<'d>(head: &'d [u8], file: &str) -> Result<&'d str> {
    let head = std::str::from_utf8(head)
        .map_err(|e| at_byte(file, e.valid_up_to(), "the XML header is not UTF-8".into()))?;
    if !head.contains("<VTKFile type=\"UnstructuredGrid\"") {
        return Err(at_byte(file, 0, "not a VTK UnstructuredGrid file".into()));
    }
    if !head.contains("byte_order=\"LittleEndian\"") || !head.contains("header_type=\"UInt64\"") {
        return Err(Error::Unsupported {
            at: Location::new(file, 0, None),
            message: "byte order or block headers other than LittleEndian with UInt64".into(),
        });
    }
    Ok(head)
}

/// Walks the tags of the XML header into `out`: the piece's point and cell counts and each
/// array's declaration, its `start` still the offset in the appended data.
fn read_declarations(head: &str, file: &str, out: &mut VtuFile) -> Result<()> {
    let mut section = None;
    let mut pieces = 0;
    let mut pos = 0;
    while let Some(lt) = head[pos..].find('<') {
        let at = pos + lt;
        let end = head[at..]
            .find('>')
            .map(|i| at + i)
            .ok_or_else(|| at_byte(file, at, "unclosed tag".into()))?;
        let text = &head[at..end];
        pos = end + 1;
        let (closing, inner) = match text[1..].strip_prefix('/') {
            Some(rest) => (true, rest),
            None => (false, &text[1..]),
        };
        let name = inner.split([' ', '/', '\n']).next().unwrap_or("");
        if closing {
            if matches!(name, "PointData" | "CellData" | "Points" | "Cells") {
                section = None;
            }
            continue;
        }
        let tag = Tag {
            file,
            at,
            text,
            name,
        };
        match name {
            "Piece" => {
                pieces += 1;
                if pieces > 1 {
                    return Err(Error::Unsupported {
                        at: Location::new(file, 0, None),
                        message: "more than one Piece".into(),
                    });
                }
                out.points = tag.count("NumberOfPoints")?;
                out.cells = tag.count("NumberOfCells")?;
            }
            "PointData" => section = Some(Section::PointData),
            "CellData" => section = Some(Section::CellData),
            "Points" => section = Some(Section::Points),
            "Cells" => section = Some(Section::Cells),
            "DataArray" => {
                let a = tag.data_array(section, out.points, out.cells)?;
                out.arrays.push(a);
            }
            _ => {}
        }
    }
    if pieces == 0 {
        return Err(at_byte(file, 0, "no <Piece>".into()));
    }
    Ok(())
}

/// One opening tag of the XML header.
struct Tag<'t> {
    file: &'t str,
    /// Byte offset of its `<`.
    at: usize,
    /// Its text, from `<` up to (without) `>`.
    text: &'t str,
    name: &'t str,
}

impl Tag<'_> {
    /// The attribute `key` as a whole number.
    fn count(&self, key: &str) -> Result<usize> {
        attr(self.text, key)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| {
                at_byte(
                    self.file,
                    self.at,
                    format!("<{}> without a whole {key}", self.name),
                )
            })
    }

    /// The declaration of a `<DataArray>` in `section` of a piece of `points` points and
    /// `cells` cells.
    fn data_array(
        &self,
        section: Option<Section>,
        points: usize,
        cells: usize,
    ) -> Result<ArrayInfo> {
        let a_name = unescape(attr(self.text, "Name").unwrap_or(""));
        let Some(sec) = section else {
            return Err(at_byte(
                self.file,
                self.at,
                format!("DataArray '{a_name}' outside a section"),
            ));
        };
        if attr(self.text, "format") != Some("appended") {
            return Err(Error::Unsupported {
                at: Location::new(self.file, 0, None),
                message: format!(
                    "array '{a_name}' is not in the appended block (only raw appended data, the solver's default, is read)"
                ),
            });
        }
        let ty_name = attr(self.text, "type").unwrap_or("");
        let ty = ScalarType::parse(ty_name).ok_or_else(|| {
            at_byte(
                self.file,
                self.at,
                format!("array '{a_name}': unsupported type '{ty_name}'"),
            )
        })?;
        let components = self.count("NumberOfComponents")?.max(1);
        let offset = self.count("offset")?;
        let tuples = match sec {
            Section::PointData | Section::Points => points,
            Section::CellData => cells,
            // connectivity has as many values as its block says; checked below.
            Section::Cells => 0,
        };
        Ok(ArrayInfo {
            name: a_name,
            section: sec,
            ty,
            components,
            tuples,
            start: offset,
        })
    }
}

/// Locates the block of array `a` in the appended data that starts at byte `raw` of `data`:
/// an 8-byte length, then exactly the declared values. Sets `a.start` to the first value (and
/// the tuple count of a `<Cells>` array from its length).
fn locate_block(a: &mut ArrayInfo, data: &[u8], raw: usize, file: &str) -> Result<()> {
    let err = |at: usize, m: String| at_byte(file, at, m);
    let header = raw
        .checked_add(a.start)
        .filter(|&h| h.checked_add(8).is_some_and(|e| e <= data.len()))
        .ok_or_else(|| {
            err(
                raw.saturating_add(a.start),
                format!(
                    "the block of array '{}' starts past the end of the file ({} bytes; truncated?)",
                    a.name,
                    data.len()
                ),
            )
        })?;
    let bytes = u64::from_le_bytes(data[header..header + 8].try_into().expect("8 bytes"));
    let size = a.ty.size().checked_mul(a.components).ok_or_else(|| {
        err(
            header,
            format!(
                "array '{}' claims {} components per tuple, far more than any file holds",
                a.name, a.components
            ),
        )
    })?;
    if a.section == Section::Cells {
        a.tuples = (bytes / size as u64) as usize;
    }
    let want = (a.tuples as u64).checked_mul(size as u64);
    if want != Some(bytes) {
        return Err(err(
            header,
            format!(
                "array '{}' holds {bytes} bytes, expected {} tuples of {} x {} bytes",
                a.name,
                a.tuples,
                a.components,
                a.ty.size()
            ),
        ));
    }
    let start = header + 8;
    let left = data.len() - start;
    if bytes > left as u64 {
        return Err(err(
            start,
            format!(
                "array '{}' needs {bytes} bytes, only {left} are left (truncated?)",
                a.name
            ),
        ));
    }
    a.start = start;
    Ok(())
}

/// One entry of a `.pvd` collection.
#[derive(Debug, Clone, PartialEq)]
pub struct DataSet {
    /// `timestep`.
    pub time: f64,
    /// `file`, as written (relative to the collection's folder).
    pub file: String,
}

/// Reads a `.pvd` collection: its `DataSet` entries in file order.
pub fn read_pvd_file(path: &Path) -> Result<Vec<DataSet>> {
    let data = crate::io::read_input(path)?;
    read_pvd(&data, &crate::display_name(path))
}

/// Parses a `.pvd` collection held in `data`; `file` names it in messages.
pub fn read_pvd(data: &[u8], file: &str) -> Result<Vec<DataSet>> {
    let text = String::from_utf8_lossy(data);
    if !text.contains("<VTKFile type=\"Collection\"") {
        return Err(Error::format(
            Location::new(file, 1, None),
            "not a ParaView collection (no '<VTKFile type=\"Collection\"')",
        ));
    }
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let Some(at) = line.find("<DataSet ") else {
            continue;
        };
        let tag = &line[at..];
        let here = || Location::new(file, k + 1, None);
        let time = attr(tag, "timestep")
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| Error::format(here(), "DataSet without a numeric timestep"))?;
        let name =
            attr(tag, "file").ok_or_else(|| Error::format(here(), "DataSet without a file"))?;
        out.push(DataSet {
            time,
            file: unescape(name),
        });
    }
    if !text.contains("</Collection>") {
        return Err(Error::format(
            Location::new(file, text.lines().count(), None),
            "no '</Collection>' (truncated?)",
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vtu::{write_pvd, write_vtu, Cells, DataArray, Encoding, Piece, Values};

    fn sample() -> Vec<u8> {
        let pts = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let cells = Cells::vertices(2);
        let s = [
            1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0, -1.0, -2.0, -3.0, -4.0, -5.0, -6.0,
        ];
        let f = [0.5f32, -0.25];
        let id = [7i32, 3];
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![
                DataArray {
                    name: "stress",
                    components: 6,
                    values: Values::F64(&s),
                },
                DataArray {
                    name: "f",
                    components: 1,
                    values: Values::F32(&f),
                },
                DataArray {
                    name: "id",
                    components: 1,
                    values: Values::I32(&id),
                },
            ],
            cell_data: vec![],
        };
        let mut out = Vec::new();
        write_vtu(&mut out, &piece, Encoding::Appended).unwrap();
        out
    }

    #[test]
    fn reads_back_what_the_writer_writes() {
        let v = parse(Input::Buffer(sample()), "p.vtu").unwrap();
        assert_eq!((v.points, v.cells), (2, 2));
        let s = v.point_data("stress").unwrap();
        assert_eq!((s.len(), s.components), (2, 6));
        assert_eq!(s.get(1, 5), -6.0);
        assert_eq!(v.point_data("f").unwrap().get(1, 0), -0.25);
        assert_eq!(v.point_data("id").unwrap().get(0, 0), 7.0);
        let x = v.coordinates().unwrap();
        assert_eq!((x.get(1, 0), x.get(1, 2)), (3.0, 5.0));
        assert_eq!(v.array(Section::Cells, "types").unwrap().get(1, 0), 1.0);
        assert_eq!(v.array(Section::Cells, "connectivity").unwrap().len(), 2);
        assert!(v.point_data("nothing").is_none());
    }

    #[test]
    fn truncated_or_corrupt_files_are_errors_naming_file_and_offset() {
        let full = sample();
        for n in 0..full.len() - "\n  </AppendedData>\n</VTKFile>\n".len() {
            let r = parse(Input::Buffer(full[..n].to_vec()), "p.vtu");
            let e = r
                .err()
                .unwrap_or_else(|| panic!("{n} bytes accepted"))
                .to_string();
            assert!(e.starts_with("p.vtu"), "{e}");
        }
        for i in (0..full.len()).step_by(3) {
            let mut d = full.clone();
            d[i] ^= 0x5a;
            let _ = parse(Input::Buffer(d), "p.vtu");
        }
        let cut = full.len() - 40;
        let e = parse(Input::Buffer(full[..cut].to_vec()), "p.vtu")
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("p.vtu: at byte") && e.contains("truncated"),
            "{e}"
        );
        let mut ascii = Vec::new();
        let cells = Cells::vertices(1);
        let piece = Piece {
            points: &[0.0; 3],
            cells: &cells,
            point_data: vec![],
            cell_data: vec![],
        };
        write_vtu(&mut ascii, &piece, Encoding::Ascii).unwrap();
        let e = parse(Input::Buffer(ascii), "a.vtu")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("a.vtu: unsupported: ASCII"), "{e}");
    }

    /// Fuzz find (issue 15): a huge `NumberOfComponents` overflowed the tuple size (a panic
    /// with overflow checks, a division by zero or a wrong size without).
    #[test]
    fn huge_component_counts_are_errors() {
        let good = std::fs::read(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../testdata/golden/column_dry/mesh.vtu"
        ))
        .unwrap();
        for n in [
            "9223372036854775807",
            "2305843009213693952",
            "18446744073709551615",
        ] {
            let mut bad = Vec::new();
            let at = memchr::memmem::find(&good, b"NumberOfComponents=\"1\"").unwrap();
            bad.extend_from_slice(&good[..at]);
            bad.extend_from_slice(format!("NumberOfComponents=\"{n}\"").as_bytes());
            bad.extend_from_slice(&good[at + 22..]);
            let e = match parse(Input::Buffer(bad), "m.vtu") {
                Ok(_) => panic!("{n} components accepted"),
                Err(e) => e.to_string(),
            };
            assert!(
                e.starts_with("m.vtu: at byte") && e.contains("'material'"),
                "{e}"
            );
        }
    }

    #[test]
    fn pvd_round_trip_and_errors() {
        let mut out = Vec::new();
        write_pvd(&mut out, &[(0.1, "a&b.vtu".into()), (0.25, "c.vtu".into())]).unwrap();
        let sets = read_pvd(&out, "run.pvd").unwrap();
        assert_eq!(
            sets,
            vec![
                DataSet {
                    time: 0.1,
                    file: "a&b.vtu".into()
                },
                DataSet {
                    time: 0.25,
                    file: "c.vtu".into()
                }
            ]
        );
        let e = read_pvd(&out[..out.len() - 30], "run.pvd")
            .unwrap_err()
            .to_string();
        assert!(e.contains("run.pvd") && e.contains("truncated"), "{e}");
        let bad = String::from_utf8(out).unwrap().replace("0.25", "x");
        let e = read_pvd(bad.as_bytes(), "run.pvd").unwrap_err().to_string();
        assert!(e.starts_with("run.pvd:5") && e.contains("timestep"), "{e}");
    }
}
