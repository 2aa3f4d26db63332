//! `[grid]`: a Cartesian background grid in place of the mesh's elements, with the basis its
//! nodes carry (docs/design.md §4.20).
//!
//! The scene's mesh still names the materials and the boundary groups; the case then runs on
//! the *background mesh*: the mesh's bounding box cut into cells of the given size (each cube
//! into 6 tetrahedra, each square into 2 triangles, which locate the points as the mesh's
//! elements do), whose nodes are the grid's lattice. Each of its elements takes the material
//! of the mesh's element around its centroid (none outside the mesh) and that material's
//! points per element; each of its boundary faces takes the boundary groups of the mesh's face
//! it lies on, so that fixities and tractions by physical group or by plane resolve on the
//! grid's nodes as on a mesh's.

use serde::Deserialize;

use mpm_shared::msh::{ElementSet, MshMesh};
use mpm_shared::{generate, Dimension, ElementType, Model};

use super::keys::{key, Table};
use super::material::Materials;
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::basis::grid::GridSpec;
use crate::basis::spline::Shape;

/// The keys of `[grid]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[grid]",
    about: "A Cartesian background grid in place of the mesh's elements (the mesh still names the materials and the boundary groups); its bounding box must be a whole number of cells along each axis.",
    keys: &[
        key("cell", "float or [float, ...]", "required", "m", "the cells' edge (cubes or squares), or one edge per axis"),
        key("basis", "string", "\"bspline2\"", "", "the nodes' functions: \"linear\" (trilinear cells), \"gimp\" (uniform GIMP) or \"bspline2\" (quadratic B-splines, modified at the box's faces)"),
        key("gimp_half_width", "float", "0.25", "cells", "with \"gimp\": a point's half-width, in (0, 0.5]"),
        key("points_per_axis", "integer", "none", "", "material points per cell along each axis on a regular sub-lattice (k³ a cell in 3D, k² in 2D), in place of the materials' points per element; a cell takes the material at its centre"),
    ],
};

/// `[grid]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Grid {
    cell: Cell,
    #[serde(default)]
    basis: Option<String>,
    #[serde(default)]
    gimp_half_width: Option<f64>,
    #[serde(default)]
    points_per_axis: Option<usize>,
}

/// One edge for all axes, or one per axis.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Cell {
    All(f64),
    PerAxis(Vec<f64>),
}

impl Grid {
    /// The basis the scene names.
    fn shape(&self) -> Result<Shape, Refusal> {
        let a = self.gimp_half_width.unwrap_or(0.25);
        match self.basis.as_deref() {
            None | Some("bspline2") => Ok(Shape::Bspline2),
            Some("linear") => Ok(Shape::Linear),
            Some("gimp") if a > 0.0 && a <= 0.5 => Ok(Shape::Gimp { a }),
            Some("gimp") => Err(refuse(
                "grid.gimp_half_width",
                format!("must be in (0, 0.5] cells, got {a}"),
            )),
            Some(other) => Err(refuse(
                "grid.basis",
                format!("expected \"linear\", \"gimp\" or \"bspline2\", got \"{other}\""),
            )),
        }
    }

    /// The cell's edge along each of `dim` axes.
    fn edges(&self, dim: usize) -> Result<[f64; 3], Refusal> {
        let given = match &self.cell {
            Cell::All(h) => vec![*h; dim],
            Cell::PerAxis(v) if v.len() == dim => v.clone(),
            Cell::PerAxis(v) => {
                return Err(refuse(
                    "grid.cell",
                    format!("give one edge or {dim} (one per axis), got {}", v.len()),
                ))
            }
        };
        if let Some(h) = given.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
            return Err(refuse("grid.cell", format!("must be positive, got {h}")));
        }
        Ok(std::array::from_fn(|a| {
            given.get(a).copied().unwrap_or(1.0)
        }))
    }
}

/// The case's mesh and materials moved onto the background grid of `grid`, and the grid.
pub(super) fn background(
    grid: &Grid,
    mesh: Mesh,
    materials: Materials,
) -> Result<(Mesh, Materials, GridSpec), Refusal> {
    let model = &mesh.model;
    let dim = model.dimension.coords();
    let shape = grid.shape()?;
    let cell = grid.edges(dim)?;
    let (lo, hi) = bounds(model);
    let mut cells = [1usize; 3];
    for a in 0..dim {
        let extent = hi[a] - lo[a];
        let n = (extent / cell[a]).round();
        if n < 1.0 || (n * cell[a] - extent).abs() > 1e-6 * cell[a] {
            return Err(refuse(
                "grid.cell",
                format!(
                    "{} spans {extent} m along {}, not a whole number of {} m cells (the grid's planes must hold the bounding box's faces)",
                    mesh.name,
                    ["x", "y", "z"][a],
                    cell[a]
                ),
            ));
        }
        cells[a] = n as usize;
    }
    let spec = GridSpec {
        origin: std::array::from_fn(|a| if a < dim { lo[a] } else { 0.0 }),
        cell,
        cells,
        dim,
        shape,
        points_per_axis: match grid.points_per_axis {
            Some(0) => return Err(refuse("grid.points_per_axis", "must be at least 1")),
            k => k,
        },
    };
    let lattice = lattice_model(&spec, model.dimension);
    let finder = Finder::new(&spec, model);
    // Elements of a cell (consecutive in the lattice's order).
    let per_cell = if dim == 3 { 6 } else { 2 };
    let material_at = |c: &[f64; 3]| {
        finder
            .element_at(c)
            .map_or(0, |k| materials.element_material[k])
    };
    let (element_material, points_per_element): (Vec<u32>, Vec<u32>) = match spec.points_per_axis {
        // Every element of a cell takes the material at the cell's centre; its first element
        // seeds the cell's regular points.
        Some(k) => (0..lattice.element_count())
            .map(|e| {
                let first = e - e % per_cell;
                let nodes: Vec<u32> = (first..first + per_cell)
                    .flat_map(|f| lattice.element(f).to_vec())
                    .collect();
                let m = material_at(&box_centre(&lattice, &nodes));
                let seeds = e % per_cell == 0 && m != 0;
                (m, if seeds { k.pow(dim as u32) as u32 } else { 0 })
            })
            .unzip(),
        None => {
            let element_material: Vec<u32> = (0..lattice.element_count())
                .map(|e| material_at(&centroid(&lattice, lattice.element(e))))
                .collect();
            // Each material's points per element, as the input's elements of that material
            // have them.
            let mut points = vec![0u32; materials.specs.len()];
            for (&m, &k) in materials
                .element_material
                .iter()
                .zip(&materials.points_per_element)
            {
                points[m as usize] = k;
            }
            let per_element = element_material
                .iter()
                .map(|&m| points[m as usize])
                .collect();
            (element_material, per_element)
        }
    };
    let em: Vec<i64> = element_material.iter().map(|&m| m as i64).collect();
    let model = Model::from_mesh(
        lattice.dimension,
        lattice.element_type,
        lattice.coords.clone(),
        lattice.connectivity.clone(),
        &mesh.volumes,
        &em,
    );
    let msh = boundary_groups(&mesh, &model, &spec, &finder);
    let nodes = model.node_count() as u32;
    let background = Mesh {
        msh,
        node_map: (0..nodes).collect(),
        name: format!("{} on a grid of {:?} cells", mesh.name, &spec.cells[..dim]),
        volumes: mesh.volumes.clone(),
        groups: mesh.groups,
        model,
    };
    Ok((
        background,
        Materials {
            element_material,
            points_per_element,
            ..materials
        },
        spec,
    ))
}

/// The lowest and highest coordinate along each axis of `model`'s nodes.
fn bounds(model: &Model) -> ([f64; 3], [f64; 3]) {
    let dim = model.dimension.coords();
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in model.coords.chunks_exact(dim) {
        for a in 0..dim {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

/// The lattice as a mesh: 6 tetrahedra a cube or 2 triangles a square, nodes lexicographic
/// (x fastest), at the grid's origin.
fn lattice_model(spec: &GridSpec, dimension: Dimension) -> Model {
    let size: [f64; 3] = std::array::from_fn(|a| spec.cell[a] * spec.cells[a] as f64);
    let mut model = if spec.dim == 3 {
        generate::box_mesh(spec.cells, size, ElementType::Tet4)
    } else {
        generate::rect_mesh([spec.cells[0], spec.cells[1]], [size[0], size[1]])
    };
    model.dimension = dimension;
    for p in model.coords.chunks_exact_mut(spec.dim) {
        for (a, c) in p.iter_mut().enumerate() {
            *c += spec.origin[a];
        }
    }
    model
}

/// The centre of the bounding box of `nodes` in `model` (z 0 in 2D).
fn box_centre(model: &Model, nodes: &[u32]) -> [f64; 3] {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for &n in nodes {
        for (a, &v) in model.node(n as usize).iter().enumerate() {
            lo[a] = lo[a].min(v);
            hi[a] = hi[a].max(v);
        }
    }
    std::array::from_fn(|a| {
        if lo[a] <= hi[a] {
            0.5 * (lo[a] + hi[a])
        } else {
            0.0
        }
    })
}

/// The mean of `nodes`' positions in `model` (z 0 in 2D).
fn centroid(model: &Model, nodes: &[u32]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for &n in nodes {
        for (a, v) in model.node(n as usize).iter().enumerate() {
            c[a] += v / nodes.len() as f64;
        }
    }
    c
}

/// The input mesh's elements and boundary faces bucketed by the grid's cells they overlap.
struct Finder<'m> {
    spec: GridSpec,
    model: &'m Model,
    /// Per cell, the elements whose bounding box overlaps it.
    elements: Vec<Vec<u32>>,
}

impl<'m> Finder<'m> {
    fn new(spec: &GridSpec, model: &'m Model) -> Self {
        let cells = spec.cells[0] * spec.cells[1] * spec.cells[2];
        let mut elements = vec![Vec::new(); cells];
        let corners = spec.dim + 1;
        for e in 0..model.element_count() {
            let nodes = &model.element(e)[..corners];
            for c in Self::cells_over(spec, model, nodes) {
                elements[c].push(e as u32);
            }
        }
        Finder {
            spec: spec.clone(),
            model,
            elements,
        }
    }

    /// The cells the bounding box of `nodes` overlaps (a little widened).
    fn cells_over(spec: &GridSpec, model: &Model, nodes: &[u32]) -> Vec<usize> {
        let mut range = [(0usize, 0usize); 3];
        for (a, r) in range.iter_mut().enumerate().take(spec.dim) {
            let (mut lo, mut hi) = (f64::MAX, f64::MIN);
            for &n in nodes {
                let s = (model.node(n as usize)[a] - spec.origin[a]) / spec.cell[a];
                lo = lo.min(s);
                hi = hi.max(s);
            }
            let last = spec.cells[a] - 1;
            let clamp = |s: f64| (s.max(0.0) as usize).min(last);
            *r = (clamp((lo - 1e-6).floor()), clamp((hi + 1e-6).floor()));
        }
        let mut out = Vec::new();
        for k in range[2].0..=range[2].1 {
            for j in range[1].0..=range[1].1 {
                for i in range[0].0..=range[0].1 {
                    out.push(i + spec.cells[0] * (j + spec.cells[1] * k));
                }
            }
        }
        out
    }

    /// The cell holding `x`.
    fn cell_of(&self, x: &[f64; 3]) -> usize {
        let s = &self.spec;
        let mut ijk = [0usize; 3];
        for a in 0..s.dim {
            let v = ((x[a] - s.origin[a]) / s.cell[a]).floor().max(0.0) as usize;
            ijk[a] = v.min(s.cells[a] - 1);
        }
        ijk[0] + s.cells[0] * (ijk[1] + s.cells[1] * ijk[2])
    }

    /// The lowest-numbered input element that holds `x` (its corners' simplex, a billionth
    /// widened), if any.
    fn element_at(&self, x: &[f64; 3]) -> Option<usize> {
        let corners = self.spec.dim + 1;
        self.elements[self.cell_of(x)]
            .iter()
            .map(|&e| e as usize)
            .find(|&e| {
                let pts: Vec<&[f64]> = self.model.element(e)[..corners]
                    .iter()
                    .map(|&n| self.model.node(n as usize))
                    .collect();
                inside_simplex(&pts, x, 1e-9)
            })
    }
}

/// Whether `x` lies in the simplex `pts` (3 points in 2D, 4 in 3D; barycentric coordinates
/// all ≥ −`tol`).
fn inside_simplex(pts: &[&[f64]], x: &[f64; 3], tol: f64) -> bool {
    let dim = pts.len() - 1;
    let d = |k: usize, a: usize| pts[k][a] - pts[0][a];
    let r: Vec<f64> = (0..dim).map(|a| x[a] - pts[0][a]).collect();
    // Solve [d1 d2 (d3)] λ = r by Cramer's rule.
    let det = |m: &dyn Fn(usize, usize) -> f64| {
        if dim == 2 {
            m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0)
        } else {
            m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
                - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
                + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0))
        }
    };
    // m(row a, column k): component a of edge k + 1.
    let whole = det(&|a, k| d(k + 1, a));
    if whole == 0.0 {
        return false;
    }
    let mut sum = 0.0;
    for col in 0..dim {
        let l = det(&|a, k| if k == col { r[a] } else { d(k + 1, a) }) / whole;
        if l < -tol {
            return false;
        }
        sum += l;
    }
    sum <= 1.0 + tol
}

/// The background's boundary faces (triangles on the box's faces in 3D, edges in 2D), each
/// carrying every boundary group of the input mesh whose face it lies on, as a Gmsh mesh of
/// the background's nodes (what the fixity and traction selectors read).
fn boundary_groups(input: &Mesh, model: &Model, spec: &GridSpec, finder: &Finder) -> MshMesh {
    let dim = spec.dim;
    let (lo, hi) = bounds(model);
    let on_face =
        |n: u32, a: usize, v: f64| (model.node(n as usize)[a] - v).abs() <= 1e-9 * spec.cell[a];
    // Every element face (dim corners) whose corners all lie on one face of the box.
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for e in 0..model.element_count() {
        let nodes = model.element(e);
        for skip in 0..=dim {
            let f: Vec<u32> = (0..=dim).filter(|&k| k != skip).map(|k| nodes[k]).collect();
            let boundary = (0..dim).any(|a| {
                [lo[a], hi[a]]
                    .iter()
                    .any(|&v| f.iter().all(|&n| on_face(n, a, v)))
            });
            if boundary {
                faces.push(f);
            }
        }
    }
    // The input's boundary faces, by group, bucketed by cell.
    // (group, face) pairs by cell.
    let mut by_cell: Vec<Vec<(usize, usize)>> = vec![Vec::new(); finder.elements.len()];
    let mut group_faces: Vec<Vec<Vec<u32>>> = Vec::new();
    let names: Vec<_> = input
        .msh
        .physical_names
        .iter()
        .filter(|p| p.dim == input.groups.dim)
        .cloned()
        .collect();
    for (g, p) in names.iter().enumerate() {
        let fs = input.boundary_faces(&p.name).unwrap_or_default();
        for (k, f) in fs.iter().enumerate() {
            if f.contains(&u32::MAX) {
                continue;
            }
            for c in Finder::cells_over(spec, &input.model, f) {
                by_cell[c].push((g, k));
            }
        }
        group_faces.push(fs);
    }
    let tol = 1e-9 * spec.cell.iter().take(dim).fold(0.0f64, |m, &h| m.max(h));
    let mut nodes = Vec::new();
    let mut physical = Vec::new();
    for f in &faces {
        let c = centroid(model, f);
        let mut tags: Vec<i32> = by_cell[finder.cell_of(&c)]
            .iter()
            .filter(|&&(g, k)| {
                let pts: Vec<&[f64]> = group_faces[g][k]
                    .iter()
                    .map(|&n| input.model.node(n as usize))
                    .collect();
                on_simplex_face(&pts, &c, tol)
            })
            .map(|&(g, _)| names[g].tag)
            .collect();
        tags.sort_unstable();
        tags.dedup();
        for tag in tags {
            nodes.extend_from_slice(f);
            physical.push(tag);
        }
    }
    let coords = (0..model.node_count())
        .flat_map(|n| {
            let p = model.node(n);
            [p[0], p[1], p.get(2).copied().unwrap_or(0.0)]
        })
        .collect();
    MshMesh {
        version: "4.1".into(),
        coords,
        node_tags: (1..=model.node_count() as u64).collect(),
        sets: vec![ElementSet {
            gmsh_type: if dim == 3 { 2 } else { 1 },
            nodes_per: dim,
            nodes,
            physical,
        }],
        physical_names: names,
    }
}

/// A face's load is integrated over its halves (a triangle cut into 4 at its edges' midpoints,
/// a segment into 2): the grid's cells and their halves then hold each piece whole, where the
/// hat and the quadratic spline are polynomials of degree 2 at most along each axis, which
/// the rules below integrate exactly (GIMP's kinks at a cells from a node fall inside pieces:
/// near exact).
const FACE_DIVISIONS: usize = 2;

/// Dunavant's 7-point rule on a triangle (degree 5): barycentric coordinates (of the 2nd
/// and 3rd corners) and weights summing to 1.
const TRIANGLE_RULE: [([f64; 2], f64); 7] = [
    ([1.0 / 3.0, 1.0 / 3.0], 0.225),
    (
        [0.059_715_871_789_770, 0.470_142_064_105_115],
        0.132_394_152_788_506,
    ),
    (
        [0.470_142_064_105_115, 0.059_715_871_789_770],
        0.132_394_152_788_506,
    ),
    (
        [0.470_142_064_105_115, 0.470_142_064_105_115],
        0.132_394_152_788_506,
    ),
    (
        [0.797_426_985_353_087, 0.101_286_507_323_456],
        0.125_939_180_544_827,
    ),
    (
        [0.101_286_507_323_456, 0.797_426_985_353_087],
        0.125_939_180_544_827,
    ),
    (
        [0.101_286_507_323_456, 0.101_286_507_323_456],
        0.125_939_180_544_827,
    ),
];

/// Gauss's 3-point rule on [0, 1] (degree 5): positions and weights summing to 1.
const SEGMENT_RULE: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// Adds the nodal forces of tractions `t` (kPa, one per face, uniform on it) on `faces` (the
/// background model's node ids of their corners) integrated with the grid's functions:
/// ∫ N_k t dA over each face (per radian, ∫ N_k t r ds, in an axisymmetric section). The
/// linear faces' rule ([`super::add_face_loads`]) would give a square face's corners unequal
/// shares (each triangle's third), which the grid's cells, unlike tetrahedra, turn into a
/// twisting mode. The background model's nodes are the lattice's, in its order.
pub(super) fn add_face_loads(
    spec: &GridSpec,
    model: &Model,
    faces: &[Vec<u32>],
    t: &[[f64; 3]],
    out: &mut [[f64; 3]],
) {
    let axisymmetric = model.dimension == Dimension::Axisymmetric;
    let m = FACE_DIVISIONS;
    let n = spec.nodes_along();
    let pos = |k: u32| {
        let p = model.node(k as usize);
        [p[0], p[1], p.get(2).copied().unwrap_or(0.0)]
    };
    for (f, t) in faces.iter().zip(t) {
        let corners: Vec<[f64; 3]> = f.iter().map(|&k| pos(k)).collect();
        let size =
            crate::input::faces::size(model, &f.iter().map(|&k| k as usize).collect::<Vec<_>>());
        // Quadrature points and their shares of the face.
        let mut samples: Vec<([f64; 3], f64)> = Vec::new();
        let at = |u: f64, v: f64| -> [f64; 3] {
            std::array::from_fn(|a| {
                let far = corners.get(2).map_or(0.0, |c| v * c[a]);
                (1.0 - u - v) * corners[0][a] + u * corners[1][a] + far
            })
        };
        let mf = m as f64;
        if corners.len() == 2 {
            for i in 0..m {
                for (q, w) in SEGMENT_RULE {
                    samples.push((at((i as f64 + q) / mf, 0.0), w * size / mf));
                }
            }
        } else {
            let share = size / (mf * mf);
            for i in 0..m {
                for j in 0..m - i {
                    // The upright sub-triangle at (i, j) and, but for the last in a row, the
                    // inverted one beside it: corners in the face's (u, v).
                    let (a, b) = (i as f64, j as f64);
                    let mut pieces = vec![[[a, b], [a + 1.0, b], [a, b + 1.0]]];
                    if j + 1 < m - i {
                        pieces.push([[a + 1.0, b], [a + 1.0, b + 1.0], [a, b + 1.0]]);
                    }
                    for [p0, p1, p2] in pieces {
                        for ([l1, l2], w) in TRIANGLE_RULE {
                            let l0 = 1.0 - l1 - l2;
                            let u = (l0 * p0[0] + l1 * p1[0] + l2 * p2[0]) / mf;
                            let v = (l0 * p0[1] + l1 * p1[1] + l2 * p2[1]) / mf;
                            samples.push((at(u, v), w * share));
                        }
                    }
                }
            }
        }
        for (x, w) in samples {
            let w = if axisymmetric { w * x[0] } else { w };
            let along: Vec<_> = (0..3)
                .map(|a| {
                    if a < spec.dim {
                        spec.shape
                            .along((x[a] - spec.origin[a]) / spec.cell[a], spec.cells[a])
                    } else {
                        crate::basis::spline::Along {
                            first: 0,
                            len: 1,
                            n: [1.0, 0.0, 0.0],
                            dn: [0.0; 3],
                        }
                    }
                })
                .collect();
            for k in 0..along[2].len {
                for j in 0..along[1].len {
                    for i in 0..along[0].len {
                        let nk = along[0].n[i] * along[1].n[j] * along[2].n[k];
                        if nk == 0.0 {
                            continue;
                        }
                        let ijk = [along[0].first + i, along[1].first + j, along[2].first + k];
                        debug_assert!((0..3).all(|a| ijk[a] < n[a]));
                        let node = spec.lattice_index(ijk);
                        for d in 0..3 {
                            out[node][d] += nk * w * t[d];
                        }
                    }
                }
            }
        }
    }
}

/// Whether `x` lies on the face `pts` (a triangle in 3D, a segment in 2D), within `tol`.
fn on_simplex_face(pts: &[&[f64]], x: &[f64; 3], tol: f64) -> bool {
    let p = |k: usize, a: usize| pts[k].get(a).copied().unwrap_or(0.0);
    if pts.len() == 2 {
        let (dx, dy) = (p(1, 0) - p(0, 0), p(1, 1) - p(0, 1));
        let (rx, ry) = (x[0] - p(0, 0), x[1] - p(0, 1));
        let len2 = dx * dx + dy * dy;
        let t = (rx * dx + ry * dy) / len2;
        let off = (rx * dy - ry * dx).abs() / len2.sqrt();
        return off <= tol && (-1e-9..=1.0 + 1e-9).contains(&t);
    }
    let u: [f64; 3] = std::array::from_fn(|a| p(1, a) - p(0, a));
    let v: [f64; 3] = std::array::from_fn(|a| p(2, a) - p(0, a));
    let r: [f64; 3] = std::array::from_fn(|a| x[a] - p(0, a));
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let area2 = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if area2 == 0.0 {
        return false;
    }
    let off = (r[0] * n[0] + r[1] * n[1] + r[2] * n[2]).abs() / area2;
    if off > tol {
        return false;
    }
    // Barycentric coordinates in the plane.
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (uu, uv, vv, ru, rv) = (
        dot(&u, &u),
        dot(&u, &v),
        dot(&v, &v),
        dot(&r, &u),
        dot(&r, &v),
    );
    let det = uu * vv - uv * uv;
    let s = (ru * vv - rv * uv) / det;
    let t = (rv * uu - ru * uv) / det;
    s >= -1e-9 && t >= -1e-9 && s + t <= 1.0 + 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform traction on the box's top face loads its nodes with the grid's functions'
    /// integrals: the total is the traction times the area, the corners alike (the linear
    /// faces' rule gives a square's diagonal corners twice the others' share).
    #[test]
    fn face_loads_follow_the_grid_s_functions() {
        for shape in [Shape::Linear, Shape::Bspline2] {
            let spec = GridSpec {
                origin: [0.0; 3],
                cell: [0.1, 0.1, 0.1],
                cells: [3, 2, 3],
                dim: 3,
                shape,
                points_per_axis: None,
            };
            let model = lattice_model(&spec, Dimension::Cartesian3D);
            // The triangles on y = 0.2.
            let mut faces = Vec::new();
            for e in 0..model.element_count() {
                let nodes = model.element(e);
                for skip in 0..4 {
                    let f: Vec<u32> = (0..4).filter(|&k| k != skip).map(|k| nodes[k]).collect();
                    if f.iter()
                        .all(|&n| (model.node(n as usize)[1] - 0.2).abs() < 1e-12)
                    {
                        faces.push(f);
                    }
                }
            }
            assert_eq!(faces.len(), 18);
            let mut out = vec![[0.0; 3]; model.node_count()];
            add_face_loads(
                &spec,
                &model,
                &faces,
                &vec![[0.0, -10.0, 0.0]; 18],
                &mut out,
            );
            let total: f64 = out.iter().map(|f| f[1]).sum();
            assert!((total + 10.0 * 0.09).abs() < 1e-12, "{shape:?}: {total}");
            let at = |i: usize, k: usize| out[spec.lattice_index([i, 2, k])][1];
            let corners = [at(0, 0), at(3, 0), at(0, 3), at(3, 3)];
            for c in corners {
                assert!((c - corners[0]).abs() < 1e-12, "{shape:?}: {corners:?}");
            }
            // Mirror symmetry across the face's middle.
            assert!((at(1, 0) - at(2, 0)).abs() < 1e-12 && (at(1, 1) - at(2, 2)).abs() < 1e-12);
            // Nothing below the face.
            for k in 0..4 {
                for j in 0..2 {
                    for i in 0..4 {
                        let f = out[spec.lattice_index([i, j, k])];
                        assert!(f.iter().all(|c| c.abs() < 1e-15), "{f:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn simplex_tests() {
        let tri: [&[f64]; 3] = [&[0.0, 0.0], &[1.0, 0.0], &[0.0, 1.0]];
        assert!(inside_simplex(&tri, &[0.2, 0.2, 0.0], 1e-9));
        assert!(!inside_simplex(&tri, &[0.6, 0.6, 0.0], 1e-9));
        let tet: [&[f64]; 4] = [
            &[0.0, 0.0, 0.0],
            &[1.0, 0.0, 0.0],
            &[0.0, 1.0, 0.0],
            &[0.0, 0.0, 1.0],
        ];
        assert!(inside_simplex(&tet, &[0.1, 0.2, 0.3], 1e-9));
        assert!(!inside_simplex(&tet, &[0.5, 0.4, 0.3], 1e-9));
        let face: [&[f64]; 3] = [&[0.0, 0.0, 1.0], &[1.0, 0.0, 1.0], &[0.0, 1.0, 1.0]];
        assert!(on_simplex_face(&face, &[0.2, 0.2, 1.0], 1e-9));
        assert!(!on_simplex_face(&face, &[0.2, 0.2, 1.1], 1e-9));
        assert!(!on_simplex_face(&face, &[0.8, 0.8, 1.0], 1e-9));
        let seg: [&[f64]; 2] = [&[0.0, 1.0], &[2.0, 1.0]];
        assert!(on_simplex_face(&seg, &[1.5, 1.0, 0.0], 1e-9));
        assert!(!on_simplex_face(&seg, &[2.5, 1.0, 0.0], 1e-9));
    }
}
