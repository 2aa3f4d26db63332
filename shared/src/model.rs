//! The mesh model: an Anura3D geometry (GOM) held section by section.
//!
//! Geometry (nodes, connectivity) lives in typed arrays; every other section is kept in file order
//! with its rows parsed into [`Token`]s and tagged with what its ids refer to ([`Refs`]), so that
//! node ids can be remapped and element-ordered sections permuted. Sections this crate does not
//! understand are kept verbatim as [`Body::Opaque`] and make renumbering refuse to run.

use rayon::prelude::*;

use crate::text;

/// Spatial setting of the model (`$$DIMENSION`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dimension {
    /// `2D-plane_strain`.
    PlaneStrain,
    /// `2D-axisymmetric`.
    Axisymmetric,
    /// `3D-cartesian`.
    Cartesian3D,
    /// `3D-cylindric`.
    Cylindric3D,
}

impl Dimension {
    /// The GOM keyword value.
    pub fn keyword(self) -> &'static str {
        match self {
            Dimension::PlaneStrain => "2D-plane_strain",
            Dimension::Axisymmetric => "2D-axisymmetric",
            Dimension::Cartesian3D => "3D-cartesian",
            Dimension::Cylindric3D => "3D-cylindric",
        }
    }

    /// Parses a GOM keyword value.
    pub fn from_keyword(s: &str) -> Option<Self> {
        Some(match s {
            "2D-plane_strain" => Dimension::PlaneStrain,
            "2D-axisymmetric" => Dimension::Axisymmetric,
            "3D-cartesian" => Dimension::Cartesian3D,
            "3D-cylindric" => Dimension::Cylindric3D,
            _ => return None,
        })
    }

    /// Number of coordinates per node (2 or 3).
    pub fn coords(self) -> usize {
        match self {
            Dimension::PlaneStrain | Dimension::Axisymmetric => 2,
            Dimension::Cartesian3D | Dimension::Cylindric3D => 3,
        }
    }
}

/// Element type (`$$ELEMENTTYPE`), with Anura3D's node order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElementType {
    /// `triangular_3-noded`.
    Tri3,
    /// `tetrahedral_4-noded`: linear tetrahedron (corners only).
    Tet4,
    /// `tetrahedral_old`: 10-node tetrahedron, corners 1-4 then mid-edge nodes
    /// 5:(1,2) 6:(2,3) 7:(1,3) 8:(1,4) 9:(2,4) 10:(3,4). Anura3D computes with the corners.
    Tet10,
}

impl ElementType {
    /// The GOM keyword value.
    pub fn keyword(self) -> &'static str {
        match self {
            ElementType::Tri3 => "triangular_3-noded",
            ElementType::Tet4 => "tetrahedral_4-noded",
            ElementType::Tet10 => "tetrahedral_old",
        }
    }

    /// Plain-words name for messages ("3-node triangles").
    pub fn describe(self) -> &'static str {
        match self {
            ElementType::Tri3 => "3-node triangles",
            ElementType::Tet4 => "4-node tetrahedra",
            ElementType::Tet10 => "10-node tetrahedra",
        }
    }

    /// Parses a GOM keyword value.
    pub fn from_keyword(s: &str) -> Option<Self> {
        Some(match s {
            "triangular_3-noded" => ElementType::Tri3,
            "tetrahedral_4-noded" => ElementType::Tet4,
            "tetrahedral_old" => ElementType::Tet10,
            _ => return None,
        })
    }

    /// Node ids per element in the connectivity.
    pub fn nodes(self) -> usize {
        match self {
            ElementType::Tri3 => 3,
            ElementType::Tet4 => 4,
            ElementType::Tet10 => 10,
        }
    }

    /// Corner (vertex) nodes per element; they come first in the connectivity.
    pub fn corners(self) -> usize {
        match self {
            ElementType::Tri3 => 3,
            ElementType::Tet4 | ElementType::Tet10 => 4,
        }
    }

    /// Node ids that name one boundary face (3D) or edge (2D) in load and surface sections.
    pub fn face_nodes(self) -> usize {
        match self {
            ElementType::Tri3 => 2,
            ElementType::Tet4 => 3,
            ElementType::Tet10 => 6,
        }
    }

    /// Spatial dimension the element lives in.
    pub fn dim(self) -> usize {
        match self {
            ElementType::Tri3 => 2,
            ElementType::Tet4 | ElementType::Tet10 => 3,
        }
    }
}

/// Line terminator used when writing text formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineEnding {
    /// `\n`.
    #[default]
    Lf,
    /// `\r\n` (files written on Windows by GiD).
    CrLf,
}

impl LineEnding {
    /// The terminator's bytes.
    pub fn bytes(self) -> &'static [u8] {
        match self {
            LineEnding::Lf => b"\n",
            LineEnding::CrLf => b"\r\n",
        }
    }
}

/// One value of a table row, typed by its spelling so that a write keeps integers integers
/// (Fortran reads `1.0` into an integer as an error) and reals exact.
#[derive(Debug, Clone, PartialEq)]
pub enum Token {
    /// An integer (`12`, `-1`).
    Int(i64),
    /// A real (`0.5`, `1e-3`, `1.0E+000`), written back in shortest round-trip form.
    Real(f64),
    /// Anything else (`"Column"`, `NAN`, `x-direction`), written back verbatim.
    Text(Box<str>),
}

impl Token {
    /// Classifies one token of input.
    pub fn parse(tok: &[u8]) -> Token {
        if let Some(i) = text::parse_int(tok) {
            Token::Int(i)
        } else if let Some(r) = text::parse_real(tok) {
            Token::Real(r)
        } else {
            Token::Text(String::from_utf8_lossy(tok).into())
        }
    }

    /// The numeric value, if any.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Token::Int(i) => Some(*i as f64),
            Token::Real(r) => Some(*r),
            Token::Text(_) => None,
        }
    }

    /// The integer value, if the token is an integer.
    pub fn as_int(&self) -> Option<i64> {
        match self {
            Token::Int(i) => Some(*i),
            _ => None,
        }
    }

    /// Appends the token's text.
    pub fn push_to(&self, out: &mut Vec<u8>) {
        match self {
            Token::Int(i) => text::push_int(out, *i),
            Token::Real(r) => text::push_real(out, *r),
            Token::Text(s) => out.extend_from_slice(s.as_bytes()),
        }
    }
}

/// Rows of tokens stored flat (one allocation for the whole section).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    tokens: Vec<Token>,
    row_ends: Vec<u32>,
}

impl Table {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty table with room for `rows` rows of about `width` tokens.
    pub fn with_capacity(rows: usize, width: usize) -> Self {
        Table {
            tokens: Vec::with_capacity(rows * width),
            row_ends: Vec::with_capacity(rows),
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.row_ends.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.row_ends.is_empty()
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> &[Token] {
        let start = if i == 0 {
            0
        } else {
            self.row_ends[i - 1] as usize
        };
        &self.tokens[start..self.row_ends[i] as usize]
    }

    /// All rows in order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &[Token]> + '_ {
        (0..self.len()).map(move |i| self.row(i))
    }

    /// The rows in the order `order` (new position → old row), built in parallel pieces.
    pub fn permuted(&self, order: &[u32]) -> Table {
        // Rows of one width (the usual case) are gathered straight into place.
        let w = self.row_ends.first().copied().unwrap_or(0) as usize;
        if w > 0 && self.tokens.len() == w * self.len() && order.len() == self.len() {
            let tokens: Vec<Token> = (0..order.len() * w)
                .into_par_iter()
                .with_min_len(1 << 14)
                .map(|k| self.tokens[order[k / w] as usize * w + k % w].clone())
                .collect();
            let row_ends = (1..=order.len() as u32).map(|i| i * w as u32).collect();
            return Table { tokens, row_ends };
        }
        let parts: Vec<Table> = order
            .par_chunks(1 << 16)
            .map(|olds| {
                let mut t = Table::with_capacity(olds.len(), 2);
                for &o in olds {
                    t.push_row(self.row(o as usize).iter().cloned());
                }
                t
            })
            .collect();
        let mut out = Table::with_capacity(self.len(), 2);
        for p in parts {
            out.append(p);
        }
        out
    }

    /// Moves all rows of `other` to the end of this table.
    pub fn append(&mut self, other: Table) {
        let base = self.tokens.len() as u32;
        self.tokens.extend(other.tokens);
        self.row_ends
            .extend(other.row_ends.into_iter().map(|e| e + base));
    }

    /// Appends a row.
    pub fn push_row<I: IntoIterator<Item = Token>>(&mut self, row: I) {
        self.tokens.extend(row);
        self.row_ends.push(self.tokens.len() as u32);
    }
}

/// Which columns of a table's rows are ids, and of what.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refs {
    /// The first `n` columns are 1-based node ids.
    Nodes(usize),
    /// The first column is a 1-based element id.
    Element,
    /// Column `c` (0-based) is a 1-based element id (`$$START_EXCAVATION_SOLID`: stage, element).
    ElementAt(usize),
    /// A quoted label, a 1-based element id, then `n` node ids of one of its faces
    /// (`$$START_OUTPUT_REACTION_FORCES`).
    LabelElementNodes(usize),
}

/// What an id column refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdKind {
    /// A node.
    Node,
    /// An element.
    Element,
}

impl Refs {
    /// The id columns of a row: `(column, kind)`.
    pub fn columns(self) -> Vec<(usize, IdKind)> {
        match self {
            Refs::Nodes(n) => (0..n).map(|c| (c, IdKind::Node)).collect(),
            Refs::Element => vec![(0, IdKind::Element)],
            Refs::ElementAt(c) => vec![(c, IdKind::Element)],
            Refs::LabelElementNodes(n) => std::iter::once((1, IdKind::Element))
                .chain((2..2 + n).map(|c| (c, IdKind::Node)))
                .collect(),
        }
    }
}

/// The content of one section.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// `$$DIMENSION`: value in [`Model::dimension`].
    Dimension,
    /// `$$ELEMENTTYPE`: value in [`Model::element_type`].
    ElementType,
    /// `$$STARTCOUNTERS`: element and node counts, derived from the geometry.
    Counters,
    /// `$$STARTNODES`: coordinates in [`Model::coords`].
    Nodes,
    /// `$$STARTELEMCON`: connectivity in [`Model::connectivity`].
    Connectivity,
    /// A list of rows whose leading columns are ids (fixities, loads, contact elements, ...).
    Table {
        /// Whether the rows are preceded by a count line.
        counted: bool,
        /// What the ids refer to.
        refs: Refs,
        /// The rows.
        rows: Table,
    },
    /// One row per element, in element order (`$$STARTELMMAT`, `$$STARTDAMPING`,
    /// `$$START_NUMBER_OF_MATERIAL_POINTS`, `$$START_INPUT_ELEMENT_NUMBERS`).
    PerElement(Table),
    /// A section that holds no ids (material properties, scalars, file names), kept line by line.
    Text(Vec<String>),
    /// A section this crate does not understand, kept verbatim; renumbering refuses it unless
    /// it is an empty list.
    Opaque(Vec<String>),
}

/// One `$$KEYWORD` section.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Keyword without the leading `$$` and without surrounding blanks.
    pub keyword: String,
    /// Content.
    pub body: Body,
}

/// How a keyword is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `$$DIMENSION`.
    Dimension,
    /// `$$ELEMENTTYPE`.
    ElementType,
    /// `$$STARTCOUNTERS`.
    Counters,
    /// `$$STARTNODES`.
    Nodes,
    /// `$$STARTELEMCON`.
    Connectivity,
    /// A table with a count line.
    Counted(Refs),
    /// A table without count line, one row per line up to the next keyword.
    Uncounted(Refs),
    /// One row per element.
    PerElement,
    /// Id-free text.
    Text,
    /// Not understood.
    Opaque,
}

/// Per-element GOM section holding each element's 1-based number in the original input (see
/// [`crate::points`]).
pub const INPUT_ELEMENTS: &str = "START_INPUT_ELEMENT_NUMBERS";

/// How the section `keyword` is read for a mesh of `et` elements.
pub fn classify(keyword: &str, et: ElementType) -> Kind {
    let face = Refs::Nodes(et.face_nodes());
    let one = Refs::Nodes(1);
    match keyword {
        "DIMENSION" => Kind::Dimension,
        "ELEMENTTYPE" => Kind::ElementType,
        "STARTCOUNTERS" => Kind::Counters,
        "STARTNODES" => Kind::Nodes,
        "STARTELEMCON" => Kind::Connectivity,
        "STARTELMMAT" | "STARTDAMPING" | "START_NUMBER_OF_MATERIAL_POINTS" | INPUT_ELEMENTS => {
            Kind::PerElement
        }
        k if k.starts_with("START_FIXITY_") || k.starts_with("START_REMOVE_FIXITY_") => {
            Kind::Counted(one)
        }
        k if k.starts_with("START_LOAD_ON_NODES_")
            || k.starts_with("START_LOAD_ON_MATERIAL_POINTS_") =>
        {
            Kind::Counted(face)
        }
        "START_SOIL_SURFACE_NODES" | "START_PHREATIC_SURFACE_NODES" => Kind::Counted(face),
        "START_OUTPUT_REACTION_FORCES" => Kind::Counted(Refs::LabelElementNodes(et.face_nodes())),
        "START_EXCAVATION_SOLID" => Kind::Uncounted(Refs::ElementAt(1)),
        k if k.starts_with("PRESCRIBED_NODAL_VELOCITY_") => Kind::Counted(one),
        k if k.starts_with("ABSORBING_BOUNDARY_SURFACE_")
            || k.starts_with("ABSORBING_BOUNDARY_LINE_")
            || k.starts_with("ABSORBING_BOUNDARY_POINT_") =>
        {
            Kind::Counted(one)
        }
        "MOVING_MESH_CORNER_NODES"
        | "COMPRESSING_MESH_CORNER_NODES"
        | "EXTENDING_MESH_CORNER_NODES" => Kind::Uncounted(one),
        "START_BODY_CONTACT_2D"
        | "START_BOUNDARY_CONTACT_2D"
        | "START_CONTACT_VOLUME"
        | "PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME"
        | "PRESCRIBED_MATERIAL_POINT_VELOCITY_SURFACE"
        | "INITIAL_VELOCITY_MATERIAL_POINT" => Kind::Counted(Refs::Element),
        "FORMULATION"
        | "NUMBER_OF_MATERIALS"
        | "MOVING_MESH_DIRECTION"
        | "MOVING_MESH_REFERENCE_MATERIAL_INDEX"
        | "ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX"
        | "INITIAL_WATER_SURFACE_FROM_FILE"
        | "BOUNDARY_SEEPAGE_AREA"
        | "BOUNDARY_INFILTRATION_AREA"
        | "BOUNDARY_HYDRAULIC_HEAD_AREA"
        | "INFILTRATION_RATE" => Kind::Text,
        k if is_material_key(k) => Kind::Text,
        _ => Kind::Opaque,
    }
}

/// Keys that occur inside a material block (after `$$MATERIAL_INDEX`). They hold one value each.
pub fn is_material_key(k: &str) -> bool {
    const KEYS: &[&str] = &[
        "MATERIAL_INDEX",
        "MATERIAL_NAME",
        "MATERIAL_TYPE",
        "MATERIAL_MODEL_SOLID",
        "MATERIAL_MODEL_LIQUID",
        "MATERIAL_MODEL_DLL",
        "UMAT_DIMENSION",
        "POROSITY_SOLID",
        "DENSITY_SOLID",
        "DENSITY_LIQUID",
        "DENSITY_GAS",
        "K0_VALUE_SOLID",
        "YOUNG_MODULUS",
        "POISSON_RATIO",
        "POISSON_RATIO_UNDRAINED",
        "INTRINSIC_PERMEABILITY_LIQUID",
        "INTRINSIC_PERMEABILITY_GAS",
        "BULK_MODULUS_LIQUID",
        "BULK_MODULUS_GAS",
        "DYNAMIC_VISCOSITY_LIQUID",
        "DYNAMIC_VISCOSITY_GAS",
        "FRICTION_ANGLE",
        "COHESION",
        "DILATANCY_ANGLE",
        "TENSILE_STRENGTH",
        "PEAK_COHESION",
        "RESIDUAL_COHESION",
        "PEAK_FRICTION_ANGLE",
        "RESIDUAL_FRICTION_ANGLE",
        "PEAK_DILATANCY_ANGLE",
        "RESIDUAL_DILATANCY_ANGLE",
        "SHAPE_FACTOR",
        // Modified Cam Clay (this project's keys: Anura3D reads none for the law).
        "SHEAR_MODULUS",
        "LAMBDA",
        "KAPPA",
        "CRITICAL_STATE_SLOPE",
        "INITIAL_VOID_RATIO",
        "NCL_INTERCEPT",
        "OCR",
        "PRECONSOLIDATION_PRESSURE",
        "MINIMUM_PRESSURE",
        "MAXIMUM_PRESSURE",
        // Hypoplasticity (this project's keys, as for Modified Cam Clay; INITIAL_VOID_RATIO and
        // the pressures shared).
        "CRITICAL_FRICTION_ANGLE",
        "GRANULAR_HARDNESS",
        "EXPONENT_N",
        "MINIMUM_VOID_RATIO",
        "CRITICAL_VOID_RATIO",
        "MAXIMUM_VOID_RATIO",
        "EXPONENT_ALPHA",
        "EXPONENT_BETA",
        "IGS_R",
        "IGS_MR",
        "IGS_MT",
        "IGS_BETA_R",
        "IGS_CHI",
        "IGS_INITIAL",
        "INTEGRATION_TOLERANCE",
        "WATER_RETENTION_CURVE",
        "HYDR_CONDUCTIVITY_CURVE",
        "av",
        "Smin",
        "Smax",
        "P0",
        "L",
        "lambda",
        "n_vg",
        "m_vg",
        "alpha_vg",
    ];
    KEYS.contains(&k)
        || k.starts_with("MATERIAL_PARAMETER_SOLID_")
        || k.starts_with("INITIAL_STATE_VARIABLE_SOLID_")
}

/// One material block of the GOM (`$$MATERIAL_INDEX` and the keys that follow it).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// `MATERIAL_INDEX` (1-based; elements refer to it in `$$STARTELMMAT`).
    pub index: i64,
    /// `MATERIAL_NAME`.
    pub name: String,
    /// `MATERIAL_TYPE` (`dry_material`, `saturated_material_coupled`, ...).
    pub kind: String,
    /// Every key of the block in file order with its value line (including the three above).
    pub properties: Vec<(String, String)>,
}

impl Material {
    /// The value line of `key`, if present.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.properties
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// The value of `key` as a number, if present and numeric.
    pub fn get_f64(&self, key: &str) -> Option<f64> {
        let v = self.get(key)?;
        let tok = text::Tokens::new(v.as_bytes()).next()?;
        text::parse_real(tok)
    }
}

/// An Anura3D model: geometry plus every other section of the GOM file in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Version tag line, e.g. `### Anura3D_2021 ###` (surrounding blanks removed).
    pub version: String,
    /// Line terminator to write.
    pub line_ending: LineEnding,
    /// `$$DIMENSION`.
    pub dimension: Dimension,
    /// `$$ELEMENTTYPE`.
    pub element_type: ElementType,
    /// Node coordinates, [`Dimension::coords`] per node.
    pub coords: Vec<f64>,
    /// Element node ids, 0-based, [`ElementType::nodes`] per element in Anura3D's order.
    pub connectivity: Vec<u32>,
    /// Every section in file order (the geometry ones as placeholders).
    pub sections: Vec<Section>,
}

impl Model {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.coords.len() / self.dimension.coords()
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.connectivity.len() / self.element_type.nodes()
    }

    /// Node ids (0-based) of element `e`.
    pub fn element(&self, e: usize) -> &[u32] {
        let n = self.element_type.nodes();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// Coordinates of node `i` (0-based).
    pub fn node(&self, i: usize) -> &[f64] {
        let d = self.dimension.coords();
        &self.coords[i * d..(i + 1) * d]
    }

    /// The first section with `keyword`.
    pub fn section(&self, keyword: &str) -> Option<&Section> {
        self.sections.iter().find(|s| s.keyword == keyword)
    }

    /// Mutable access to the first section with `keyword`.
    pub fn section_mut(&mut self, keyword: &str) -> Option<&mut Section> {
        self.sections.iter_mut().find(|s| s.keyword == keyword)
    }

    /// The rows of an element-ordered section, if present.
    pub fn per_element(&self, keyword: &str) -> Option<&Table> {
        match &self.section(keyword)?.body {
            Body::PerElement(t) => Some(t),
            _ => None,
        }
    }

    /// The rows of an id table, if present.
    pub fn table(&self, keyword: &str) -> Option<&Table> {
        match &self.section(keyword)?.body {
            Body::Table { rows, .. } => Some(rows),
            _ => None,
        }
    }

    /// Material index of every element (`$$STARTELMMAT`, first column), if present.
    pub fn element_materials(&self) -> Option<Vec<i64>> {
        let t = self.per_element("STARTELMMAT")?;
        Some(
            t.rows()
                .map(|r| r.first().and_then(Token::as_int).unwrap_or(0))
                .collect(),
        )
    }

    /// Solid material points per element (`$$START_NUMBER_OF_MATERIAL_POINTS`, first column).
    pub fn material_points_per_element(&self) -> Option<Vec<u32>> {
        let t = self.per_element("START_NUMBER_OF_MATERIAL_POINTS")?;
        Some(
            t.rows()
                .map(|r| {
                    r.first()
                        .and_then(Token::as_int)
                        .map_or(0, |v| v.clamp(0, u32::MAX as i64) as u32)
                })
                .collect(),
        )
    }

    /// The material blocks in file order.
    pub fn materials(&self) -> Vec<Material> {
        let mut out: Vec<Material> = Vec::new();
        let mut open = false;
        for s in &self.sections {
            let lines = match &s.body {
                Body::Text(lines) if is_material_key(&s.keyword) => lines,
                _ => {
                    open = false;
                    continue;
                }
            };
            let value = lines
                .first()
                .map(|l| l.trim().to_string())
                .unwrap_or_default();
            if s.keyword == "MATERIAL_INDEX" {
                out.push(Material {
                    index: value.parse().unwrap_or(0),
                    name: String::new(),
                    kind: String::new(),
                    properties: Vec::new(),
                });
                open = true;
            }
            if !open {
                continue;
            }
            let m = out.last_mut().expect("a block is open");
            match s.keyword.as_str() {
                "MATERIAL_NAME" => m.name = value.clone(),
                "MATERIAL_TYPE" => m.kind = value.clone(),
                _ => {}
            }
            m.properties.push((s.keyword.clone(), value));
        }
        out
    }

    /// True when every section can follow a renumbering of nodes and elements; otherwise the
    /// keyword of the first section that cannot.
    pub fn first_unremappable(&self) -> Option<&str> {
        self.sections
            .iter()
            .find(|s| match &s.body {
                Body::Opaque(lines) => !opaque_is_empty(lines),
                _ => false,
            })
            .map(|s| s.keyword.as_str())
    }
}

/// An opaque section is harmless to carry through a renumbering when it holds no rows: no lines,
/// or a single count line that says 0.
pub fn opaque_is_empty(lines: &[String]) -> bool {
    let data: Vec<&str> = lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect();
    data.is_empty() || (data.len() == 1 && data[0] == "0")
}

impl Model {
    /// The model with elements in the order `order` (new position → old element, 0-based) and
    /// nodes renumbered by `node_new` (old node → new node, 0-based). Coordinates move with their
    /// nodes, element-ordered sections are permuted, node ids and element ids in every table are
    /// remapped. Refuses to run when a section that may hold ids is not understood.
    ///
    /// Each element's number in the original input is kept in
    /// [`INPUT_ELEMENTS`]: added (from `order`) when the model has none, permuted
    /// with the other per-element sections when it has one, so that chained reorders keep the
    /// first input's numbers and material-point ids survive (see [`crate::points`]).
    ///
    /// Both maps must be permutations (checked).
    pub fn reordered(&self, order: &[u32], node_new: &[u32]) -> crate::Result<Model> {
        if let Some(k) = self.first_unremappable() {
            return Err(crate::Error::Unremappable {
                section: format!("$${k}"),
                reason: "is not understood by this tool, so its ids could not follow the new numbering; remove it or reorder with --curve none".into(),
            });
        }
        let n_el = self.element_count();
        let n_nodes = self.node_count();
        let elem_new = inverse(order, n_el).ok_or_else(|| crate::Error::Unremappable {
            section: "$$STARTELEMCON".into(),
            reason: "element order is not a permutation".into(),
        })?;
        let node_old = inverse(node_new, n_nodes).ok_or_else(|| crate::Error::Unremappable {
            section: "$$STARTNODES".into(),
            reason: "node numbering is not a permutation".into(),
        })?;
        let d = self.dimension.coords();
        let mut coords = vec![0.0; self.coords.len()];
        coords
            .par_chunks_mut(d * 8192)
            .zip(node_old.par_chunks(8192))
            .for_each(|(dst, olds)| {
                for (x, &old) in dst.chunks_exact_mut(d).zip(olds) {
                    x.copy_from_slice(self.node(old as usize));
                }
            });
        let per = self.element_type.nodes();
        let mut connectivity = vec![0u32; self.connectivity.len()];
        connectivity
            .par_chunks_mut(per * 4096)
            .zip(order.par_chunks(4096))
            .for_each(|(dst, olds)| {
                for (el, &old) in dst.chunks_exact_mut(per).zip(olds) {
                    for (x, &n) in el.iter_mut().zip(self.element(old as usize)) {
                        *x = node_new[n as usize];
                    }
                }
            });
        let map_id = |t: &Token, map: &[u32]| -> Token {
            match t {
                Token::Int(i) if *i >= 1 && (*i as usize) <= map.len() => {
                    Token::Int(map[*i as usize - 1] as i64 + 1)
                }
                other => other.clone(),
            }
        };
        let mut sections = Vec::with_capacity(self.sections.len());
        for s in &self.sections {
            let body = match &s.body {
                Body::PerElement(t) => Body::PerElement(t.permuted(order)),
                Body::Table {
                    counted,
                    refs,
                    rows,
                } => {
                    let mut out = Table::with_capacity(rows.len(), 4);
                    let cols = refs.columns();
                    for r in rows.rows() {
                        out.push_row(r.iter().enumerate().map(|(j, t)| {
                            match cols.iter().find(|c| c.0 == j) {
                                Some((_, IdKind::Node)) => map_id(t, node_new),
                                Some((_, IdKind::Element)) => map_id(t, &elem_new),
                                None => t.clone(),
                            }
                        }));
                    }
                    Body::Table {
                        counted: *counted,
                        refs: *refs,
                        rows: out,
                    }
                }
                other => other.clone(),
            };
            sections.push(Section {
                keyword: s.keyword.clone(),
                body,
            });
        }
        let mut model = Model {
            version: self.version.clone(),
            line_ending: self.line_ending,
            dimension: self.dimension,
            element_type: self.element_type,
            coords,
            connectivity,
            sections,
        };
        if self.per_element(INPUT_ELEMENTS).is_none() {
            model.set_input_elements(order);
        }
        Ok(model)
    }
}

/// The inverse of a permutation of `0..n`, or `None` if `p` is not one.
pub fn inverse(p: &[u32], n: usize) -> Option<Vec<u32>> {
    if p.len() != n {
        return None;
    }
    let mut inv = vec![u32::MAX; n];
    for (i, &v) in p.iter().enumerate() {
        let slot = inv.get_mut(v as usize)?;
        if *slot != u32::MAX {
            return None;
        }
        *slot = i as u32;
    }
    Some(inv)
}

/// The sections every GOM opens with, in Anura3D's order: dimension, element type, the
/// single-point formulation, counters, nodes and connectivity (their values come from the
/// model's own fields when it is written).
pub fn geometry_sections() -> Vec<Section> {
    let placeholder = |k: &str, body: Body| Section {
        keyword: k.into(),
        body,
    };
    vec![
        placeholder("DIMENSION", Body::Dimension),
        placeholder("ELEMENTTYPE", Body::ElementType),
        Section {
            keyword: "FORMULATION".into(),
            body: Body::Text(vec!["single-point".into()]),
        },
        placeholder("STARTCOUNTERS", Body::Counters),
        placeholder("STARTNODES", Body::Nodes),
        placeholder("STARTELEMCON", Body::Connectivity),
    ]
}

impl Model {
    /// A mesh-only model in Anura3D's layout: header and geometry sections, empty fixity lists
    /// for the three phases, one material block (index and name) per entry of `materials`, and
    /// `$$STARTELMMAT` from `element_material` (1-based indices, 0 for an empty element).
    pub fn from_mesh(
        dimension: Dimension,
        element_type: ElementType,
        coords: Vec<f64>,
        connectivity: Vec<u32>,
        materials: &[String],
        element_material: &[i64],
    ) -> Model {
        let text = |k: &str, v: &str| Section {
            keyword: k.into(),
            body: Body::Text(vec![v.into()]),
        };
        let placeholder = |k: &str, body: Body| Section {
            keyword: k.into(),
            body,
        };
        let mut sections = geometry_sections();
        for kind in ["SURFACE", "LINE", "POINT"] {
            for phase in ["SOLID", "LIQUID", "GAS"] {
                sections.push(placeholder(
                    &format!("START_FIXITY_{kind}_{phase}"),
                    Body::Table {
                        counted: true,
                        refs: Refs::Nodes(1),
                        rows: Table::new(),
                    },
                ));
            }
        }
        sections.push(text("NUMBER_OF_MATERIALS", &materials.len().to_string()));
        for (i, name) in materials.iter().enumerate() {
            sections.push(text("MATERIAL_INDEX", &(i + 1).to_string()));
            sections.push(text("MATERIAL_NAME", name));
        }
        let mut elmmat = Table::with_capacity(element_material.len(), 1);
        for &m in element_material {
            elmmat.push_row([Token::Int(m)]);
        }
        sections.push(placeholder("STARTELMMAT", Body::PerElement(elmmat)));
        Model {
            version: "### Anura3D_2021 ###".into(),
            line_ending: LineEnding::Lf,
            dimension,
            element_type,
            coords,
            connectivity,
            sections,
        }
    }

    /// Checks element shapes: every tetrahedron has det J > 0 with Anura3D's
    /// J = [x3-x1, x4-x1, x2-x1], every triangle is counter-clockwise, and every mid-edge node of
    /// a 10-node tetrahedron lies at its edge's midpoint (relative tolerance `tol`). Returns the
    /// first problem found.
    pub fn check_shapes(&self, tol: f64) -> Result<(), String> {
        const EDGES: [(usize, (usize, usize)); 6] = [
            (4, (0, 1)),
            (5, (1, 2)),
            (6, (0, 2)),
            (7, (0, 3)),
            (8, (1, 3)),
            (9, (2, 3)),
        ];
        for e in 0..self.element_count() {
            let el = self.element(e);
            let x = |k: usize| self.node(el[k] as usize);
            let signed = match self.element_type {
                ElementType::Tri3 => {
                    let (a, b, c) = (x(0), x(1), x(2));
                    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
                }
                _ => crate::geometry::tet_det(x(0), x(2), x(3), x(1)),
            };
            if signed <= 0.0 {
                return Err(format!(
                    "element {} is inverted or flat (det J = {signed})",
                    e + 1
                ));
            }
            if self.element_type == ElementType::Tet10 {
                let scale = signed.abs().cbrt();
                for (mid, (a, b)) in EDGES {
                    for d in 0..3 {
                        let want = 0.5 * (x(a)[d] + x(b)[d]);
                        if (x(mid)[d] - want).abs() > tol * scale {
                            return Err(format!(
                                "element {}: node {} is not the midpoint of corners {} and {}",
                                e + 1,
                                mid + 1,
                                a + 1,
                                b + 1
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
