//! Gmsh `.msh` reader (formats 2.2 and 4.1, ASCII) and conversion to the Anura3D model.
//!
//! Gmsh's 10-node tetrahedron (0-based) lists corners 0-3 then edges 4:(0,1) 5:(1,2) 6:(0,2)
//! 7:(0,3) 8:(2,3) 9:(1,3). Conversion flips G1 and G2 of a negatively oriented element, then maps
//! corners to Anura3D's order A1 = G0, A2 = G3, A3 = G1, A4 = G2 (so that
//! det[A3-A1, A4-A1, A2-A1] = det[G1-G0, G2-G0, G3-G0] > 0) and picks each mid-edge node by its
//! corner pair (docs/design.md §2.3).

use std::collections::BTreeMap;

use crate::error::{Error, Location, Result};
use crate::geometry::tet_det;
use crate::model::{Dimension, ElementType, Model};
use crate::text::{self, Lines, Tokens};

/// Gmsh element type codes used here.
pub mod kind {
    /// 2-node line.
    pub const LINE2: i32 = 1;
    /// 3-node triangle.
    pub const TRI3: i32 = 2;
    /// 4-node tetrahedron.
    pub const TET4: i32 = 4;
    /// 6-node triangle.
    pub const TRI6: i32 = 9;
    /// 10-node tetrahedron.
    pub const TET10: i32 = 11;
    /// 1-node point.
    pub const POINT: i32 = 15;
}

/// Nodes per element for Gmsh's element type codes 1..=31.
fn nodes_of_type(t: i32) -> Option<usize> {
    const N: [usize; 31] = [
        2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1, 8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4,
        5, 6, 20, 35, 56,
    ];
    (1..=31).contains(&t).then(|| N[(t - 1) as usize])
}

/// Topological dimension of Gmsh element type `t`.
fn dim_of_type(t: i32) -> usize {
    match t {
        15 => 0,
        1 | 8 | 26 | 27 | 28 => 1,
        2 | 3 | 9 | 10 | 16 | 20 | 21 | 22 | 23 | 24 | 25 => 2,
        _ => 3,
    }
}

/// All elements of one Gmsh type, in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ElementSet {
    /// Gmsh element type code.
    pub gmsh_type: i32,
    /// Nodes per element.
    pub nodes_per: usize,
    /// Node indices (0-based, into [`MshMesh::coords`]), `nodes_per` per element.
    pub nodes: Vec<u32>,
    /// Physical group tag of each element (0 when it belongs to none).
    pub physical: Vec<i32>,
}

/// A named physical group.
#[derive(Debug, Clone, PartialEq)]
pub struct PhysicalName {
    /// Dimension of the group.
    pub dim: usize,
    /// Tag.
    pub tag: i32,
    /// Name.
    pub name: String,
}

/// The content of a `.msh` file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MshMesh {
    /// Format version (`2.2`, `4.1`).
    pub version: String,
    /// Node coordinates, 3 per node, in file order.
    pub coords: Vec<f64>,
    /// Gmsh tag of each node.
    pub node_tags: Vec<u64>,
    /// Elements grouped by type, ordered by type code.
    pub sets: Vec<ElementSet>,
    /// Named physical groups.
    pub physical_names: Vec<PhysicalName>,
}

impl ElementSet {
    /// Topological dimension of the elements (0 points, 1 lines, 2 surfaces, 3 volumes).
    pub fn dim(&self) -> usize {
        dim_of_type(self.gmsh_type)
    }
}

impl MshMesh {
    /// The element set of Gmsh type `t`, if the file has such elements.
    pub fn set(&self, t: i32) -> Option<&ElementSet> {
        self.sets
            .iter()
            .find(|s| s.gmsh_type == t && !s.physical.is_empty())
    }

    /// Name of physical group `tag` of dimension `dim`, if named.
    pub fn physical_name(&self, dim: usize, tag: i32) -> Option<&str> {
        self.physical_names
            .iter()
            .find(|p| p.dim == dim && p.tag == tag)
            .map(|p| p.name.as_str())
    }
}

/// A line cursor over a `.msh` file that knows the section it is in, for error locations.
struct Reader<'a> {
    lines: Lines<'a>,
    file: &'a str,
    section: &'static str,
}

impl<'a> Reader<'a> {
    /// Location of line `line` in the current section.
    fn at(&self, line: usize) -> Location {
        Location::new(self.file, line, Some(self.section))
    }

    /// Next non-blank line; errors at end of file.
    fn line(&mut self, what: &str) -> Result<(usize, &'a [u8])> {
        for (n, l) in self.lines.by_ref() {
            if !text::is_blank(l) {
                return Ok((n, l));
            }
        }
        Err(Error::format(
            self.at(self.lines.line_number()),
            format!("file ends while expecting {what} (truncated?)"),
        ))
    }

    /// The next non-blank line as `N` integers (`what` names them in messages), with its number.
    fn numbers<const N: usize>(&mut self, what: &str) -> Result<(usize, [i64; N])> {
        let (n, l) = self.line(what)?;
        let mut out = [0i64; N];
        let mut t = Tokens::new(l);
        for v in out.iter_mut() {
            let tok = t.next().ok_or_else(|| {
                Error::format(
                    self.at(n),
                    format!("expected {what}, found {}", text::show(l)),
                )
            })?;
            *v = text::parse_int(tok).ok_or_else(|| {
                Error::format(
                    self.at(n),
                    format!("expected {what}, found {}", text::show(l)),
                )
            })?;
        }
        Ok((n, out))
    }

    /// `v` as a count of `what` at line `n`: negative counts are refused.
    fn count(&self, n: usize, v: i64, what: &str) -> Result<usize> {
        usize::try_from(v)
            .map_err(|_| Error::format(self.at(n), format!("{what} is {v}, must not be negative")))
    }

    /// Reads the end marker `end` of the current section.
    fn expect_end(&mut self, end: &str) -> Result<()> {
        let (n, l) = self.line(end)?;
        if text::trim(l) != end.as_bytes() {
            return Err(Error::format(
                self.at(n),
                format!("expected '{end}', found {}", text::show(l)),
            ));
        }
        Ok(())
    }

    /// Skips lines up to and including the end marker `end`.
    fn skip_to(&mut self, end: &str) -> Result<()> {
        loop {
            let (_, l) = self.line(end)?;
            if text::trim(l) == end.as_bytes() {
                return Ok(());
            }
        }
    }

    /// Reads the `$MeshFormat` section: the format version and whether it is 4.1 (else 2.x).
    /// Binary files and other versions are refused.
    fn mesh_format(&mut self) -> Result<(String, bool)> {
        let (n, l) = self.line("'$MeshFormat'")?;
        if text::trim(l) != b"$MeshFormat" {
            return Err(Error::format(
                Location::new(self.file, n, None),
                format!(
                    "expected '$MeshFormat' (a Gmsh .msh file), found {}",
                    text::show(l)
                ),
            ));
        }
        let (n, l) = self.line("the format line")?;
        let toks: Vec<&[u8]> = Tokens::new(l).collect();
        let version =
            String::from_utf8_lossy(toks.first().copied().unwrap_or_default()).into_owned();
        let binary = toks.get(1).and_then(|t| text::parse_int(t));
        if binary != Some(0) {
            if binary == Some(1) {
                return Err(Error::Unsupported {
                    at: self.at(n),
                    message: "binary .msh; save it as ASCII (gmsh -save_all -format msh41 with Mesh.Binary=0)".into(),
                });
            }
            return Err(Error::format(
                self.at(n),
                format!("expected 'version 0 8', found {}", text::show(l)),
            ));
        }
        let v4 = match version.as_str() {
            "2.2" | "2" | "2.0" | "2.1" => false,
            "4.1" => true,
            other => {
                return Err(Error::Unsupported {
                    at: self.at(n),
                    message: format!("MSH format {other} (supported: 2.2 and 4.1)"),
                })
            }
        };
        self.expect_end("$EndMeshFormat")?;
        Ok((version, v4))
    }

    /// Skips a section not needed here (`$Periodic`, `$NodeData`, ...) whose start marker is
    /// `t`, up to its end marker.
    fn skip_section(&mut self, t: &[u8]) -> Result<()> {
        let name = String::from_utf8_lossy(&t[1..]).into_owned();
        self.section = "(skipped section)";
        self.skip_to(&format!("$End{name}"))
    }
}

/// One element as read from `$Elements`, its nodes still named by tag.
struct RawElement {
    gmsh_type: i32,
    physical: i32,
    tags: Vec<u64>,
    /// Line of the element, for errors found when its tags are resolved.
    line: usize,
}

/// The sections after `$MeshFormat`, read one by one into a mesh whose elements still name their
/// nodes by tag until [`Sections::into_mesh`].
struct Sections<'a> {
    r: Reader<'a>,
    /// The whole input, to weigh counts in headers against the bytes left.
    data: &'a [u8],
    /// Format 4.1 (else 2.x).
    v4: bool,
    mesh: MshMesh,
    /// Index of each node tag, where the tags are not 1..=N in order.
    tag_index: BTreeMap<u64, u32>,
    /// `Some(N)` where the tags are 1..=N in order: index = tag - 1.
    dense_tags: Option<u64>,
    /// Physical tag of each (dim, entity) in 4.1 files.
    entity_physical: BTreeMap<(usize, i32), i32>,
    raw_elements: Vec<RawElement>,
    have_nodes: bool,
    have_elements: bool,
}

/// Reads a `.msh` file from memory. `file` names the input in error messages.
pub fn read(data: &[u8], file: &str) -> Result<MshMesh> {
    let mut r = Reader {
        lines: Lines::new(data, 1),
        file,
        section: "$MeshFormat",
    };
    let (version, v4) = r.mesh_format()?;
    let mut s = Sections {
        r,
        data,
        v4,
        mesh: MshMesh {
            version,
            ..Default::default()
        },
        tag_index: BTreeMap::new(),
        dense_tags: None,
        entity_physical: BTreeMap::new(),
        raw_elements: Vec::new(),
        have_nodes: false,
        have_elements: false,
    };
    while let Some((n, l)) = s.r.lines.next() {
        if !text::trim(l).is_empty() {
            s.section(n, l)?;
        }
    }
    s.into_mesh()
}

impl Sections<'_> {
    /// Reads the section that starts at line `n`, `l`.
    fn section(&mut self, n: usize, l: &[u8]) -> Result<()> {
        let t = text::trim(l);
        match t {
            b"$PhysicalNames" => self.physical_names(),
            b"$Entities" if self.v4 => self.entities(),
            b"$Nodes" => self.nodes(),
            b"$Elements" => self.elements(),
            _ if t.starts_with(b"$") && !t.starts_with(b"$End") => self.r.skip_section(t),
            _ => Err(Error::format(
                Location::new(self.r.file, n, None),
                format!(
                    "expected a section such as '$Nodes', found {}",
                    text::show(l)
                ),
            )),
        }
    }

    /// Reads `$PhysicalNames`: lines `dim tag "name"`.
    fn physical_names(&mut self) -> Result<()> {
        let r = &mut self.r;
        r.section = "$PhysicalNames";
        let (n0, [count]) = r.numbers::<1>("the number of names")?;
        let count = r.count(n0, count, "the number of names")?;
        for _ in 0..count {
            let (n, l) = r.line("a physical name")?;
            let toks: Vec<&[u8]> = Tokens::new(l).collect();
            let ok = toks.len() >= 3;
            let dim = toks.first().and_then(|t| text::parse_int(t));
            let tag = toks.get(1).and_then(|t| text::parse_int(t));
            match (ok, dim, tag) {
                (true, Some(d), Some(tag)) => {
                    let name = String::from_utf8_lossy(toks[2])
                        .trim_matches('"')
                        .to_string();
                    self.mesh.physical_names.push(PhysicalName {
                        dim: d as usize,
                        tag: tag as i32,
                        name,
                    });
                }
                _ => {
                    return Err(Error::format(
                        r.at(n),
                        format!("expected 'dim tag \"name\"', found {}", text::show(l)),
                    ))
                }
            }
        }
        r.expect_end("$EndPhysicalNames")
    }

    /// Reads `$Entities` (4.1): the first physical tag of each point, curve, surface and volume,
    /// which the element blocks of that entity take.
    fn entities(&mut self) -> Result<()> {
        let r = &mut self.r;
        r.section = "$Entities";
        let (n0, [np, nc, ns, nv]) =
            r.numbers::<4>("'numPoints numCurves numSurfaces numVolumes'")?;
        let what = "an entity count";
        let [np, nc, ns, nv] = [np, nc, ns, nv].map(|v| r.count(n0, v, what));
        let (np, nc, ns, nv) = (np?, nc?, ns?, nv?);
        for (dim, count) in [(0usize, np), (1, nc), (2, ns), (3, nv)] {
            for _ in 0..count {
                let (n, l) = r.line("an entity")?;
                let toks: Vec<&[u8]> = Tokens::new(l).collect();
                // point: tag x y z nphys phys...; others: tag 6 box values nphys phys...
                let k = if dim == 0 { 4 } else { 7 };
                let bad =
                    || Error::format(r.at(n), format!("malformed entity line {}", text::show(l)));
                let tag = toks
                    .first()
                    .and_then(|t| text::parse_int(t))
                    .ok_or_else(bad)?;
                let nphys = toks
                    .get(k)
                    .and_then(|t| text::parse_int(t))
                    .ok_or_else(bad)?;
                if nphys > 0 {
                    let p = toks
                        .get(k + 1)
                        .and_then(|t| text::parse_int(t))
                        .ok_or_else(bad)?;
                    self.entity_physical.insert((dim, tag as i32), p as i32);
                }
            }
        }
        r.expect_end("$EndEntities")
    }

    /// Reads `$Nodes` in either format, then indexes the node tags.
    fn nodes(&mut self) -> Result<()> {
        self.r.section = "$Nodes";
        self.have_nodes = true;
        if self.v4 {
            self.nodes_v4()?;
        } else {
            self.nodes_v2()?;
        }
        self.r.expect_end("$EndNodes")?;
        self.index_node_tags()
    }

    /// Reads the body of a 4.1 `$Nodes`: a header, then blocks of tags followed by coordinates.
    fn nodes_v4(&mut self) -> Result<()> {
        let (n0, [blocks, total, _min, _max]) = self
            .r
            .numbers::<4>("'numEntityBlocks numNodes minNodeTag maxNodeTag'")?;
        let blocks = self.r.count(n0, blocks, "the number of node blocks")?;
        let total = self.r.count(n0, total, "the number of nodes")?;
        // A node takes at least 8 bytes ("1\n0 0 0\n"): a header that claims more
        // nodes than the rest of the file can hold is refused before anything is
        // allocated for them.
        let room = self.data.len().saturating_sub(self.r.lines.offset()) / 8;
        if total > room {
            return Err(Error::format(
                self.r.at(n0),
                format!(
                    "the header claims {total} nodes, but the rest of the file can hold at most {room} (truncated?)"
                ),
            ));
        }
        self.mesh.coords.reserve(total * 3);
        self.mesh.node_tags.reserve(total);
        for _ in 0..blocks {
            self.node_block_v4()?;
        }
        if self.mesh.node_tags.len() != total {
            return Err(Error::invalid(
                self.r.at(n0),
                format!(
                    "the header says {total} nodes, its blocks hold {}",
                    self.mesh.node_tags.len()
                ),
            ));
        }
        Ok(())
    }

    /// Reads one 4.1 node block: its header, its node tags, then their coordinates.
    fn node_block_v4(&mut self) -> Result<()> {
        let r = &mut self.r;
        let mesh = &mut self.mesh;
        let (n, [_d, _e, parametric, count]) =
            r.numbers::<4>("'entityDim entityTag parametric numNodesInBlock'")?;
        if parametric != 0 {
            return Err(Error::Unsupported {
                at: r.at(n),
                message: "parametric node coordinates".into(),
            });
        }
        let count = r.count(n, count, "numNodesInBlock")?;
        let start = mesh.node_tags.len();
        for _ in 0..count {
            let (n, [tag]) = r.numbers::<1>("a node tag")?;
            if tag <= 0 {
                return Err(Error::format(
                    r.at(n),
                    format!("node tag {tag} must be positive"),
                ));
            }
            mesh.node_tags.push(tag as u64);
        }
        for _ in 0..count {
            let (n, l) = r.line("node coordinates")?;
            push_xyz(&mut mesh.coords, l, &r.at(n))?;
        }
        debug_assert_eq!(mesh.node_tags.len() - start, count);
        Ok(())
    }

    /// Reads the body of a 2.2 `$Nodes`: a count, then lines `tag x y z`.
    fn nodes_v2(&mut self) -> Result<()> {
        let r = &mut self.r;
        let mesh = &mut self.mesh;
        let (n0, [count]) = r.numbers::<1>("the number of nodes")?;
        let count = r.count(n0, count, "the number of nodes")?;
        for _ in 0..count {
            let (n, l) = r.line("a node line 'tag x y z'")?;
            let mut t = Tokens::new(l);
            let tag = t
                .next()
                .and_then(text::parse_u32)
                .filter(|&v| v > 0)
                .ok_or_else(|| {
                    Error::format(
                        r.at(n),
                        format!("expected 'tag x y z', found {}", text::show(l)),
                    )
                })?;
            mesh.node_tags.push(tag as u64);
            let xyz: Vec<&[u8]> = t.collect();
            push_xyz_tokens(&mut mesh.coords, &xyz, l, &r.at(n))?;
        }
        Ok(())
    }

    /// Notes how node tags map to indices: by arithmetic where they are 1..=N in order, else
    /// through a table, refusing a tag that appears twice.
    fn index_node_tags(&mut self) -> Result<()> {
        let n = self.mesh.node_tags.len();
        if self
            .mesh
            .node_tags
            .iter()
            .enumerate()
            .all(|(i, &t)| t == i as u64 + 1)
        {
            self.dense_tags = Some(n as u64);
        } else {
            for (i, &t) in self.mesh.node_tags.iter().enumerate() {
                if self.tag_index.insert(t, i as u32).is_some() {
                    return Err(Error::invalid(
                        self.r.at(0),
                        format!("node tag {t} appears twice"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Reads `$Elements` in either format.
    fn elements(&mut self) -> Result<()> {
        self.r.section = "$Elements";
        self.have_elements = true;
        if self.v4 {
            let (n0, [blocks, _total, _min, _max]) = self
                .r
                .numbers::<4>("'numEntityBlocks numElements minElementTag maxElementTag'")?;
            let blocks = self.r.count(n0, blocks, "the number of element blocks")?;
            for _ in 0..blocks {
                self.element_block_v4()?;
            }
        } else {
            let (n0, [count]) = self.r.numbers::<1>("the number of elements")?;
            let count = self.r.count(n0, count, "the number of elements")?;
            for _ in 0..count {
                let (n, l) = self.r.line("an element line")?;
                let element = self.element_v2(n, l)?;
                self.raw_elements.push(element);
            }
        }
        self.r.expect_end("$EndElements")
    }

    /// Reads one 4.1 element block: a header naming the entity and element type, then lines
    /// `tag node...`. The elements take the entity's physical tag.
    fn element_block_v4(&mut self) -> Result<()> {
        let r = &mut self.r;
        let (n, [edim, etag, etype, count]) =
            r.numbers::<4>("'entityDim entityTag elementType numElementsInBlock'")?;
        let count = r.count(n, count, "numElementsInBlock")?;
        let per = nodes_of_type(etype as i32).ok_or_else(|| Error::Unsupported {
            at: r.at(n),
            message: format!("Gmsh element type {etype}"),
        })?;
        let phys = self
            .entity_physical
            .get(&(edim as usize, etag as i32))
            .copied()
            .unwrap_or(0);
        for _ in 0..count {
            let (n, l) = r.line("an element line")?;
            let toks: Vec<&[u8]> = Tokens::new(l).collect();
            if toks.len() != per + 1 {
                return Err(Error::format(
                    r.at(n),
                    format!(
                        "expected an element tag and {per} node tags, found {} values",
                        toks.len()
                    ),
                ));
            }
            let tags = parse_tags(&toks[1..], l, &r.at(n))?;
            self.raw_elements.push(RawElement {
                gmsh_type: etype as i32,
                physical: phys,
                tags,
                line: n,
            });
        }
        Ok(())
    }

    /// Reads one 2.2 element line `id type ntags tags... nodes...` at line `n`; its physical tag
    /// is the first of its tags.
    fn element_v2(&self, n: usize, l: &[u8]) -> Result<RawElement> {
        let r = &self.r;
        let toks: Vec<&[u8]> = Tokens::new(l).collect();
        let bad = |m: String| Error::format(r.at(n), m);
        if toks.len() < 3 {
            return Err(bad(format!(
                "expected 'id type ntags tags... nodes...', found {}",
                text::show(l)
            )));
        }
        let etype = text::parse_int(toks[1]).ok_or_else(|| {
            bad(format!(
                "expected an element type, found {}",
                text::show(toks[1])
            ))
        })? as i32;
        let ntags = text::parse_u32(toks[2]).ok_or_else(|| {
            bad(format!(
                "expected a tag count, found {}",
                text::show(toks[2])
            ))
        })? as usize;
        let per = nodes_of_type(etype).ok_or_else(|| Error::Unsupported {
            at: r.at(n),
            message: format!("Gmsh element type {etype}"),
        })?;
        if toks.len() != 3 + ntags + per {
            return Err(bad(format!(
                "expected {} values for an element of type {etype} with {ntags} tags, found {}",
                3 + ntags + per,
                toks.len()
            )));
        }
        let physical = if ntags > 0 {
            text::parse_int(toks[3]).unwrap_or(0) as i32
        } else {
            0
        };
        let tags = parse_tags(&toks[3 + ntags..], l, &r.at(n))?;
        Ok(RawElement {
            gmsh_type: etype,
            physical,
            tags,
            line: n,
        })
    }

    /// Checks that the file had nodes and elements, then groups the elements by type with their
    /// node tags resolved to indices.
    fn into_mesh(mut self) -> Result<MshMesh> {
        let file = self.r.file;
        if !self.have_nodes || !self.have_elements {
            return Err(Error::format(
                Location::new(file, 0, None),
                if self.have_nodes {
                    "no $Elements section"
                } else {
                    "no $Nodes section"
                },
            ));
        }
        let mut sets: BTreeMap<i32, ElementSet> = BTreeMap::new();
        for e in std::mem::take(&mut self.raw_elements) {
            let set = sets.entry(e.gmsh_type).or_insert_with(|| ElementSet {
                gmsh_type: e.gmsh_type,
                nodes_per: e.tags.len(),
                ..Default::default()
            });
            for t in e.tags {
                let idx = self.node_index(t).ok_or_else(|| {
                    Error::invalid(
                        Location::new(file, e.line, Some("$Elements")),
                        format!("node tag {t} is not in $Nodes"),
                    )
                })?;
                set.nodes.push(idx);
            }
            set.physical.push(e.physical);
        }
        self.mesh.sets = sets.into_values().collect();
        Ok(self.mesh)
    }

    /// The index of the node tagged `t`, if there is one.
    fn node_index(&self, t: u64) -> Option<u32> {
        match self.dense_tags {
            Some(n) if t >= 1 && t <= n => Some((t - 1) as u32),
            Some(_) => None,
            None => self.tag_index.get(&t).copied(),
        }
    }
}

/// Node tags (positive integers) of an element line `l`.
fn parse_tags(toks: &[&[u8]], l: &[u8], at: &Location) -> Result<Vec<u64>> {
    toks.iter()
        .map(|t| {
            text::parse_u32(t)
                .filter(|&v| v > 0)
                .map(u64::from)
                .ok_or_else(|| {
                    Error::format(
                        at.clone(),
                        format!("expected node tags, found {}", text::show(l)),
                    )
                })
        })
        .collect()
}

/// Appends the three coordinates on line `l` to `coords`.
fn push_xyz(coords: &mut Vec<f64>, l: &[u8], at: &Location) -> Result<()> {
    let toks: Vec<&[u8]> = Tokens::new(l).collect();
    push_xyz_tokens(coords, &toks, l, at)
}

/// Appends three coordinates, the tokens `toks` of line `l`, to `coords`.
fn push_xyz_tokens(coords: &mut Vec<f64>, toks: &[&[u8]], l: &[u8], at: &Location) -> Result<()> {
    if toks.len() != 3 {
        return Err(Error::format(
            at.clone(),
            format!("expected 3 coordinates, found {}", text::show(l)),
        ));
    }
    for t in toks {
        coords.push(text::parse_real(t).ok_or_else(|| {
            Error::format(
                at.clone(),
                format!("expected a coordinate, found {}", text::show(t)),
            )
        })?);
    }
    Ok(())
}

/// Maps one Gmsh tetrahedron (4 or 10 node indices) to Anura3D's order with det J > 0.
pub fn gmsh_tet_to_anura(g: &[u32], coords: &[f64]) -> Vec<u32> {
    let p = |i: u32| &coords[i as usize * 3..i as usize * 3 + 3];
    let mut g: Vec<u32> = g.to_vec();
    if tet_det(p(g[0]), p(g[1]), p(g[2]), p(g[3])) < 0.0 {
        g.swap(1, 2);
        if g.len() == 10 {
            g.swap(4, 6); // (0,1) <-> (0,2)
            g.swap(8, 9); // (2,3) <-> (1,3)
        }
    }
    let mut a = vec![g[0], g[3], g[1], g[2]];
    if g.len() == 10 {
        // A5:(A1,A2)=(G0,G3)=G7  A6:(A2,A3)=(G3,G1)=G9  A7:(A1,A3)=(G0,G1)=G4
        // A8:(A1,A4)=(G0,G2)=G6  A9:(A2,A4)=(G3,G2)=G8  A10:(A3,A4)=(G1,G2)=G5
        a.extend_from_slice(&[g[7], g[9], g[4], g[6], g[8], g[5]]);
    }
    a
}

/// Converts the volume elements of a `.msh` to an Anura3D model: tetrahedra (4- or 10-node) give
/// a 3D model, otherwise 3-node triangles give a 2D plane-strain model (z must be constant).
/// Nodes used by no volume element are dropped; the others keep their file order. Each physical
/// group of the volume dimension becomes a material (index by ascending tag, named after the
/// group), written in `$$STARTELMMAT`.
pub fn to_model(mesh: &MshMesh, file: &str) -> Result<Model> {
    to_model_with_map(mesh, file).map(|(m, _)| m)
}

/// Like [`to_model`], also returning for each `.msh` node (file order) its 0-based node in the
/// model, or `u32::MAX` for nodes no volume element uses (so boundary groups can be mapped).
pub fn to_model_with_map(mesh: &MshMesh, file: &str) -> Result<(Model, Vec<u32>)> {
    let at = Location::new(file, 0, None);
    let (set, element_type) = volume_set(mesh, &at)?;
    let dim = element_type.dim();
    let mut conn = oriented_connectivity(mesh, set, element_type);
    let (coords, new_id) = used_nodes(mesh, &conn, dim, at)?;
    for c in conn.iter_mut() {
        *c = new_id[*c as usize];
    }
    let (names, element_material) = materials(mesh, set, dim);
    let dimension = if dim == 3 {
        Dimension::Cartesian3D
    } else {
        Dimension::PlaneStrain
    };
    let model = Model::from_mesh(
        dimension,
        element_type,
        coords,
        conn,
        &names,
        &element_material,
    );
    Ok((model, new_id))
}

/// The elements to convert and their Anura3D type: the tetrahedra (of one kind), else the 3-node
/// triangles.
fn volume_set<'m>(mesh: &'m MshMesh, at: &Location) -> Result<(&'m ElementSet, ElementType)> {
    let tet4 = mesh.set(kind::TET4);
    let tet10 = mesh.set(kind::TET10);
    let tri3 = mesh.set(kind::TRI3);
    match (tet4, tet10, tri3) {
        (Some(_), Some(_), _) => Err(Error::Unsupported {
            at: at.clone(),
            message: "a mesh that mixes 4- and 10-node tetrahedra".into(),
        }),
        (Some(s), None, _) => Ok((s, ElementType::Tet4)),
        (None, Some(s), _) => Ok((s, ElementType::Tet10)),
        (None, None, Some(s)) => Ok((s, ElementType::Tri3)),
        _ => {
            if mesh.set(kind::TRI6).is_some() {
                return Err(Error::Unsupported {
                    at: at.clone(),
                    message: "6-node triangles (use 3-node triangles or tetrahedra)".into(),
                });
            }
            Err(Error::invalid(
                at.clone(),
                "no tetrahedra or triangles to convert",
            ))
        }
    }
}

/// The elements' node indices (into the `.msh` nodes) in Anura3D's order, each element turned
/// to a positive orientation.
fn oriented_connectivity(mesh: &MshMesh, set: &ElementSet, element_type: ElementType) -> Vec<u32> {
    let per = element_type.nodes();
    let n_el = set.physical.len();
    let mut conn = Vec::with_capacity(n_el * per);
    for e in 0..n_el {
        let g = &set.nodes[e * per..(e + 1) * per];
        match element_type {
            ElementType::Tri3 => {
                let p = |i: u32| &mesh.coords[i as usize * 3..i as usize * 3 + 3];
                let (a, b, c) = (p(g[0]), p(g[1]), p(g[2]));
                let area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                if area2 < 0.0 {
                    conn.extend_from_slice(&[g[0], g[2], g[1]]);
                } else {
                    conn.extend_from_slice(g);
                }
            }
            _ => conn.extend(gmsh_tet_to_anura(g, &mesh.coords)),
        }
    }
    conn
}

/// The `dim` coordinates of the nodes that `conn` uses, in file order, and each `.msh` node's
/// new index (`u32::MAX` where unused). A 2D mesh must lie in a plane z = const.
fn used_nodes(
    mesh: &MshMesh,
    conn: &[u32],
    dim: usize,
    at: Location,
) -> Result<(Vec<f64>, Vec<u32>)> {
    let n_nodes = mesh.node_tags.len();
    let mut new_id = vec![u32::MAX; n_nodes];
    for &i in conn {
        new_id[i as usize] = 0;
    }
    let mut coords = Vec::new();
    let mut next = 0u32;
    let mut z0: Option<f64> = None;
    for (i, slot) in new_id.iter_mut().enumerate() {
        if *slot == u32::MAX {
            continue;
        }
        *slot = next;
        next += 1;
        let p = &mesh.coords[i * 3..i * 3 + 3];
        coords.extend_from_slice(&p[..dim]);
        if dim == 2 {
            let z = *z0.get_or_insert(p[2]);
            if (p[2] - z).abs() > 1e-12 * (1.0 + z.abs()) {
                return Err(Error::invalid(
                    at,
                    format!("a 2D mesh must lie in a plane z = const; node tag {} has z = {} (first z = {z})", mesh.node_tags[i], p[2]),
                ));
            }
        }
    }
    Ok((coords, new_id))
}

/// The material names and each element's material: one per physical group of the element
/// dimension (by ascending tag, named after the group), or a single `material_1` where the
/// elements belong to no group.
fn materials(mesh: &MshMesh, set: &ElementSet, dim: usize) -> (Vec<String>, Vec<i64>) {
    let mut groups: Vec<i32> = set.physical.iter().copied().filter(|&p| p != 0).collect();
    groups.sort_unstable();
    groups.dedup();
    let mat_of = |p: i32| -> i64 {
        if groups.is_empty() {
            1
        } else {
            groups.binary_search(&p).map_or(0, |i| i as i64 + 1)
        }
    };
    let element_material: Vec<i64> = set.physical.iter().map(|&p| mat_of(p)).collect();
    let names: Vec<String> = if groups.is_empty() {
        vec!["material_1".to_string()]
    } else {
        groups
            .iter()
            .map(|&g| {
                mesh.physical_name(dim, g)
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("physical_{g}"))
            })
            .collect()
    };
    (names, element_material)
}

#[cfg(test)]
mod tests {
    use super::*;

    const V22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 7 \"soil\"\n$EndPhysicalNames\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n$Elements\n3\n1 2 2 9 1 1 2 3\n2 4 2 7 1 1 2 3 4\n3 4 2 7 1 2 3 4 5\n$EndElements\n";

    #[test]
    fn reads_22_and_converts_with_positive_orientation() {
        let m = read(V22.as_bytes(), "a.msh").unwrap();
        assert_eq!(m.node_tags.len(), 5);
        let tets = m.set(kind::TET4).unwrap();
        assert_eq!(tets.physical, vec![7, 7]);
        let model = to_model(&m, "a.msh").unwrap();
        assert_eq!(model.element_type, ElementType::Tet4);
        assert_eq!(model.element_count(), 2);
        for e in 0..2 {
            let c = model.element(e);
            let p = |i: u32| model.node(i as usize);
            // Anura3D: J = [x3-x1, x4-x1, x2-x1]
            assert!(tet_det(p(c[0]), p(c[2]), p(c[3]), p(c[1])) > 0.0);
        }
        assert_eq!(model.materials()[0].name, "soil");
        assert_eq!(model.element_materials(), Some(vec![1, 1]));
    }

    /// Fuzz finds (issue 15): counts in a 4.1 `$Nodes` header are checked before use.
    #[test]
    fn v41_node_counts_are_checked_before_use() {
        const V41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n3 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n";
        assert!(
            read(V41.as_bytes(), "a.msh").is_err_and(|e| e.to_string().contains("no $Elements"))
        );
        // A header claiming 10^12 nodes is refused before anything is reserved for them.
        let huge = V41.replace("1 2 1 2\n", "1 1000000000000 1 2\n");
        let e = read(huge.as_bytes(), "a.msh").unwrap_err().to_string();
        assert!(
            e.starts_with("a.msh:5") && e.contains("claims 1000000000000 nodes"),
            "{e}"
        );
        // A negative block size was read as an empty block, then failed a debug assertion.
        let neg = V41.replace("3 1 0 2\n", "3 1 0 -2147483648\n");
        let e = read(neg.as_bytes(), "a.msh").unwrap_err().to_string();
        assert!(
            e.starts_with("a.msh:6") && e.contains("must not be negative"),
            "{e}"
        );
        // Blocks that hold fewer nodes than the header says.
        let short = V41.replace("1 2 1 2\n", "1 3 1 2\n");
        let e = read(short.as_bytes(), "a.msh").unwrap_err().to_string();
        assert!(
            e.contains("the header says 3 nodes, its blocks hold 2"),
            "{e}"
        );
    }

    #[test]
    fn errors_are_located() {
        let e = read(V22.replace("5 1 1 1\n", "5 1 x 1\n").as_bytes(), "a.msh")
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.msh:14 (in $Nodes)"), "{e}");
        let e = read(
            V22.replace("1 2 3 4 5\n", "1 2 3 4 9\n").as_bytes(),
            "a.msh",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("node tag 9 is not in $Nodes"), "{e}");
        let e = read(&V22.as_bytes()[..100], "a.msh")
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated") || e.contains("expected"), "{e}");
        let e = read(b"$MeshFormat\n4.1 1 8\n", "b.msh")
            .unwrap_err()
            .to_string();
        assert!(e.contains("binary"), "{e}");
    }
}
