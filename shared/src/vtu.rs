//! ParaView output: VTK XML unstructured grids (`.vtu`) and time-series collections (`.pvd`).
//!
//! Written by hand rather than through a VTK crate so that the bytes are fully determined by the
//! data (golden files compare byte for byte) and large particle files stream out as raw appended
//! binary without intermediate copies. Three encodings: ASCII (reals in shortest round-trip
//! form), inline base64 binary, and raw appended binary (the fastest; default for the solver).
//! All binary data is little-endian with 64-bit block headers (`header_type="UInt64"`).

use std::io::{self, Write};

use base64::Engine;

use crate::model::{ElementType, Model};
use crate::text;

/// How data arrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    /// Human-readable values inside each `DataArray`.
    Ascii,
    /// Base64 of header + data inside each `DataArray`.
    Base64,
    /// Raw binary in one `AppendedData` block at the end of the file.
    #[default]
    Appended,
}

/// Values of a data array, borrowed.
#[derive(Debug, Clone, Copy)]
pub enum Values<'a> {
    /// `Float64`.
    F64(&'a [f64]),
    /// `Float32`.
    F32(&'a [f32]),
    /// `Int64`.
    I64(&'a [i64]),
    /// `Int32`.
    I32(&'a [i32]),
    /// `UInt8`.
    U8(&'a [u8]),
}

impl Values<'_> {
    /// Number of values.
    fn len(&self) -> usize {
        match self {
            Values::F64(v) => v.len(),
            Values::F32(v) => v.len(),
            Values::I64(v) => v.len(),
            Values::I32(v) => v.len(),
            Values::U8(v) => v.len(),
        }
    }

    /// VTK's name of the value type.
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::F32(_) => "Float32",
            Values::I64(_) => "Int64",
            Values::I32(_) => "Int32",
            Values::U8(_) => "UInt8",
        }
    }

    /// Bytes of the values in binary.
    fn byte_len(&self) -> usize {
        match self {
            Values::F64(v) => v.len() * 8,
            Values::F32(v) => v.len() * 4,
            Values::I64(v) => v.len() * 8,
            Values::I32(v) => v.len() * 4,
            Values::U8(v) => v.len(),
        }
    }

    /// Writes the values in binary, little-endian.
    fn write_le(&self, w: &mut dyn Write) -> io::Result<()> {
        // Little-endian hosts can write the slices as they are; others convert per value.
        /// Writes `v` converted by `f`, a chunk at a time.
        fn put<T: Copy, const N: usize>(
            w: &mut dyn Write,
            v: &[T],
            f: impl Fn(T) -> [u8; N],
        ) -> io::Result<()> {
            let mut buf = Vec::with_capacity(64 * 1024);
            for chunk in v.chunks(8192) {
                buf.clear();
                for &x in chunk {
                    buf.extend_from_slice(&f(x));
                }
                w.write_all(&buf)?;
            }
            Ok(())
        }
        match *self {
            Values::F64(v) => put(w, v, f64::to_le_bytes),
            Values::F32(v) => put(w, v, f32::to_le_bytes),
            Values::I64(v) => put(w, v, i64::to_le_bytes),
            Values::I32(v) => put(w, v, i32::to_le_bytes),
            Values::U8(v) => w.write_all(v),
        }
    }

    /// Appends the values as text, `components` to a line.
    fn write_ascii(&self, out: &mut Vec<u8>, components: usize) {
        let n = self.len();
        for i in 0..n {
            if i > 0 {
                out.push(if components > 0 && i % components == 0 {
                    b'\n'
                } else {
                    b' '
                });
            }
            match *self {
                Values::F64(v) => text::push_real(out, v[i]),
                Values::F32(v) => {
                    let mut b = ryu::Buffer::new();
                    if v[i].is_finite() {
                        out.extend_from_slice(b.format_finite(v[i]).as_bytes());
                    } else {
                        text::push_real(out, v[i] as f64);
                    }
                }
                Values::I64(v) => text::push_int(out, v[i]),
                Values::I32(v) => text::push_int(out, v[i]),
                Values::U8(v) => text::push_int(out, v[i]),
            }
        }
    }
}

/// A named data array with `components` values per point or cell.
#[derive(Debug, Clone, Copy)]
pub struct DataArray<'a> {
    /// Name shown in ParaView.
    pub name: &'a str,
    /// Values per tuple (1 scalar, 3 vector, 6 symmetric tensor, ...).
    pub components: usize,
    /// The values, `components` per tuple.
    pub values: Values<'a>,
}

/// Cell topology in VTK's layout.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Cells {
    /// Point ids of all cells, concatenated.
    pub connectivity: Vec<i64>,
    /// End offset of each cell in `connectivity`.
    pub offsets: Vec<i64>,
    /// VTK cell type of each cell.
    pub types: Vec<u8>,
}

/// VTK cell type codes.
pub mod cell_type {
    /// `VTK_VERTEX`.
    pub const VERTEX: u8 = 1;
    /// `VTK_TRIANGLE`.
    pub const TRIANGLE: u8 = 5;
    /// `VTK_TETRA`.
    pub const TETRA: u8 = 10;
    /// `VTK_QUADRATIC_TETRA`.
    pub const QUADRATIC_TETRA: u8 = 24;
}

/// Position in the Anura3D node list of each VTK quadratic-tetrahedron node: VTK corners are
/// (A1, A3, A4, A2) so that VTK's orientation is positive, then its edges (0,1) (1,2) (0,2) (0,3)
/// (1,3) (2,3) taken by corner pair.
pub const ANURA_TET10_TO_VTK: [usize; 10] = [0, 2, 3, 1, 6, 9, 7, 4, 5, 8];

impl Cells {
    /// The mesh elements of `model` as VTK cells (10-node tetrahedra stay quadratic).
    pub fn from_model(model: &Model) -> Cells {
        let n = model.element_count();
        let per = model.element_type.nodes();
        let (ty, order): (u8, &[usize]) = match model.element_type {
            ElementType::Tri3 => (cell_type::TRIANGLE, &[0, 1, 2]),
            ElementType::Tet4 => (cell_type::TETRA, &[0, 2, 3, 1]),
            ElementType::Tet10 => (cell_type::QUADRATIC_TETRA, &ANURA_TET10_TO_VTK),
        };
        let mut c = Cells {
            connectivity: Vec::with_capacity(n * per),
            offsets: Vec::with_capacity(n),
            types: vec![ty; n],
        };
        for e in 0..n {
            let el = model.element(e);
            c.connectivity.extend(order.iter().map(|&k| el[k] as i64));
            c.offsets.push(c.connectivity.len() as i64);
        }
        c
    }

    /// One `VTK_VERTEX` cell per point (particle clouds).
    pub fn vertices(points: usize) -> Cells {
        Cells {
            connectivity: (0..points as i64).collect(),
            offsets: (1..=points as i64).collect(),
            types: vec![cell_type::VERTEX; points],
        }
    }
}

/// The node coordinates of `model` as 3D points (z = 0 for 2D models).
pub fn model_points(model: &Model) -> Vec<f64> {
    let d = model.dimension.coords();
    if d == 3 {
        return model.coords.clone();
    }
    let mut p = Vec::with_capacity(model.node_count() * 3);
    for xy in model.coords.chunks_exact(d) {
        p.extend_from_slice(xy);
        p.push(0.0);
    }
    p
}

/// One unstructured-grid piece.
#[derive(Debug, Clone)]
pub struct Piece<'a> {
    /// Point coordinates, 3 per point.
    pub points: &'a [f64],
    /// Cells.
    pub cells: &'a Cells,
    /// Point data arrays.
    pub point_data: Vec<DataArray<'a>>,
    /// Cell data arrays.
    pub cell_data: Vec<DataArray<'a>>,
}

/// `s` with the five XML special characters escaped.
fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c => o.push(c),
        }
    }
    o
}

/// Refuses an array of `arrays` whose value count is not `tuples` times its (nonzero) component
/// count; `what` names the kind of data ("point", "cell") in the message.
fn check_arrays(arrays: &[DataArray], tuples: usize, what: &str) -> io::Result<()> {
    for a in arrays {
        if a.components == 0 || a.values.len() != tuples * a.components {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "{what} array '{}' has {} values, expected {} x {}",
                    a.name,
                    a.values.len(),
                    tuples,
                    a.components
                ),
            ));
        }
    }
    Ok(())
}

/// The XML part of a VTU document, built in memory: with [`Encoding::Appended`] it holds each
/// array's declaration and its offset in the appended block, otherwise the values too.
struct XmlHead {
    bytes: Vec<u8>,
    encoding: Encoding,
    /// Offset in the appended block of the next array's data.
    offset: u64,
}

impl XmlHead {
    /// Writes the `<DataArray>` of `a`.
    fn array(&mut self, a: &DataArray) -> io::Result<()> {
        let head = &mut self.bytes;
        write!(
            head,
            "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"",
            a.values.type_name(),
            escape(a.name),
            a.components
        )?;
        match self.encoding {
            Encoding::Ascii => {
                head.extend_from_slice(b" format=\"ascii\">\n");
                a.values.write_ascii(head, a.components);
                head.extend_from_slice(b"\n        </DataArray>\n");
            }
            Encoding::Base64 => {
                head.extend_from_slice(b" format=\"binary\">\n");
                let mut raw = Vec::with_capacity(8 + a.values.byte_len());
                raw.extend_from_slice(&(a.values.byte_len() as u64).to_le_bytes());
                a.values.write_le(&mut raw)?;
                head.extend_from_slice(
                    base64::engine::general_purpose::STANDARD
                        .encode(&raw)
                        .as_bytes(),
                );
                head.extend_from_slice(b"\n        </DataArray>\n");
            }
            Encoding::Appended => {
                let offset = self.offset;
                writeln!(head, " format=\"appended\" offset=\"{offset}\"/>")?;
                self.offset += 8 + a.values.byte_len() as u64;
            }
        }
        Ok(())
    }

    /// Writes the `<PointData>` or `<CellData>` section (`tag`) holding `arrays`.
    fn data_section(&mut self, tag: &str, arrays: &[DataArray]) -> io::Result<()> {
        if arrays.is_empty() {
            writeln!(self.bytes, "      <{tag}/>")?;
            return Ok(());
        }
        writeln!(self.bytes, "      <{tag}>")?;
        for a in arrays {
            self.array(a)?;
        }
        writeln!(self.bytes, "      </{tag}>")
    }
}

/// Writes `piece` as a VTU document.
pub fn write_vtu(w: &mut dyn Write, piece: &Piece, encoding: Encoding) -> io::Result<()> {
    let n_points = piece.points.len() / 3;
    let n_cells = piece.cells.types.len();
    check_arrays(&piece.point_data, n_points, "point")?;
    check_arrays(&piece.cell_data, n_cells, "cell")?;
    let points = DataArray {
        name: "Points",
        components: 3,
        values: Values::F64(piece.points),
    };
    let conn = DataArray {
        name: "connectivity",
        components: 1,
        values: Values::I64(&piece.cells.connectivity),
    };
    let offs = DataArray {
        name: "offsets",
        components: 1,
        values: Values::I64(&piece.cells.offsets),
    };
    let types = DataArray {
        name: "types",
        components: 1,
        values: Values::U8(&piece.cells.types),
    };

    let mut head = XmlHead {
        bytes: Vec::with_capacity(4096),
        encoding,
        offset: 0,
    };
    head.bytes.extend_from_slice(
        b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n",
    );
    writeln!(
        head.bytes,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    )?;
    head.data_section("PointData", &piece.point_data)?;
    head.data_section("CellData", &piece.cell_data)?;
    head.bytes.extend_from_slice(b"      <Points>\n");
    head.array(&points)?;
    head.bytes
        .extend_from_slice(b"      </Points>\n      <Cells>\n");
    head.array(&conn)?;
    head.array(&offs)?;
    head.array(&types)?;
    head.bytes
        .extend_from_slice(b"      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    let mut appended: Vec<&DataArray> = piece.point_data.iter().chain(&piece.cell_data).collect();
    appended.extend([&points, &conn, &offs, &types]);
    finish_vtu(w, head, &appended)
}

/// Writes the XML part `head` and, with [`Encoding::Appended`], the raw block of `appended`
/// (each array's byte length, then its values), then closes the document.
fn finish_vtu(w: &mut dyn Write, mut head: XmlHead, appended: &[&DataArray]) -> io::Result<()> {
    if head.encoding == Encoding::Appended {
        head.bytes
            .extend_from_slice(b"  <AppendedData encoding=\"raw\">\n   _");
        w.write_all(&head.bytes)?;
        for a in appended {
            w.write_all(&(a.values.byte_len() as u64).to_le_bytes())?;
            a.values.write_le(w)?;
        }
        w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")?;
    } else {
        head.bytes.extend_from_slice(b"</VTKFile>\n");
        w.write_all(&head.bytes)?;
    }
    Ok(())
}

/// Writes a `.pvd` collection: one `DataSet` per `(time, file)` in the given order.
pub fn write_pvd(w: &mut dyn Write, entries: &[(f64, String)]) -> io::Result<()> {
    let mut out = Vec::new();
    out.extend_from_slice(
        b"<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, f) in entries {
        out.extend_from_slice(b"    <DataSet timestep=\"");
        text::push_real(&mut out, *t);
        writeln!(out, "\" group=\"\" part=\"0\" file=\"{}\"/>", escape(f))?;
    }
    out.extend_from_slice(b"  </Collection>\n</VTKFile>\n");
    w.write_all(&out)
}

/// Writes the mesh of `model` with its `material` cell data (from `$$STARTELMMAT`) and, when
/// given, a `partition` cell field.
pub fn write_model(
    w: &mut dyn Write,
    model: &Model,
    partition: Option<&[i32]>,
    encoding: Encoding,
) -> io::Result<()> {
    let points = model_points(model);
    let cells = Cells::from_model(model);
    let material: Vec<i32> = model
        .element_materials()
        .map(|m| m.into_iter().map(|v| v as i32).collect())
        .unwrap_or_else(|| vec![0; model.element_count()]);
    let mut cell_data = vec![DataArray {
        name: "material",
        components: 1,
        values: Values::I32(&material),
    }];
    if let Some(p) = partition {
        cell_data.push(DataArray {
            name: "partition",
            components: 1,
            values: Values::I32(p),
        });
    }
    let piece = Piece {
        points: &points,
        cells: &cells,
        point_data: Vec::new(),
        cell_data,
    };
    write_vtu(w, &piece, encoding)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_vtu_is_exact() {
        let pts = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let cells = Cells {
            connectivity: vec![0, 1, 2],
            offsets: vec![3],
            types: vec![cell_type::TRIANGLE],
        };
        let id = [1i32, 2, 3];
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![DataArray {
                name: "id",
                components: 1,
                values: Values::I32(&id),
            }],
            cell_data: vec![],
        };
        let mut out = Vec::new();
        write_vtu(&mut out, &piece, Encoding::Ascii).unwrap();
        let s = String::from_utf8(out).unwrap();
        assert!(s.contains("<Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">"));
        assert!(s.contains("format=\"ascii\">\n0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n"));
        assert!(s.contains("<CellData/>"));
    }

    #[test]
    fn appended_offsets_account_for_headers() {
        let pts = [0.0; 6];
        let cells = Cells::vertices(2);
        let v = [1.5f64, 2.5];
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![DataArray {
                name: "v",
                components: 1,
                values: Values::F64(&v),
            }],
            cell_data: vec![],
        };
        let mut out = Vec::new();
        write_vtu(&mut out, &piece, Encoding::Appended).unwrap();
        let s = String::from_utf8_lossy(&out);
        assert!(s.contains("Name=\"v\" NumberOfComponents=\"1\" format=\"appended\" offset=\"0\""));
        assert!(s.contains(
            "Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"24\""
        ));
        // 4 arrays + points: headers 8 bytes each; data 16 + 48 + 16 + 16 + 2.
        let marker = b"<AppendedData encoding=\"raw\">\n   _";
        let start = out.windows(marker.len()).position(|w| w == marker).unwrap() + marker.len();
        let raw = &out[start..out.len() - "\n  </AppendedData>\n</VTKFile>\n".len()];
        assert_eq!(raw.len(), 5 * 8 + 16 + 48 + 16 + 16 + 2);
        assert_eq!(&raw[..8], &16u64.to_le_bytes());
        assert_eq!(&raw[8..16], &1.5f64.to_le_bytes());
    }

    #[test]
    fn mismatched_array_is_refused() {
        let pts = [0.0; 6];
        let cells = Cells::vertices(2);
        let v = [1.0f64];
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![DataArray {
                name: "v",
                components: 1,
                values: Values::F64(&v),
            }],
            cell_data: vec![],
        };
        assert!(write_vtu(&mut Vec::new(), &piece, Encoding::Ascii).is_err());
    }

    #[test]
    fn pvd_lists_times() {
        let mut out = Vec::new();
        write_pvd(
            &mut out,
            &[(0.0, "p_0.vtu".into()), (0.5, "p_1.vtu".into())],
        )
        .unwrap();
        let s = String::from_utf8(out).unwrap();
        assert!(s.contains("<DataSet timestep=\"0.5\" group=\"\" part=\"0\" file=\"p_1.vtu\"/>"));
    }
}
