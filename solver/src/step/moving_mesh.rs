//! Anura3D's moving mesh (`$$MOVING_MESH_CORNER_NODES`, `$$EXTENDING_MESH_CORNER_NODES`,
//! `$$COMPRESSING_MESH_CORNER_NODES`, `$$MOVING_MESH_DIRECTION` and
//! `$$MOVING_MESH_REFERENCE_MATERIAL_INDEX`): the part of the mesh around a structure (a
//! footing, a pile) follows the structure along one axis, so that the structure keeps its
//! elements and its faces stay on element faces, while the mesh ahead of it is compressed and
//! the mesh behind it stretched.
//!
//! Three boxes, each the axis-aligned bounding box of its corner nodes (initial coordinates, with
//! Anura3D's 1e-10 tolerance), divide the mesh: the *moving* box and up to two *storage* boxes,
//! the extending one (storage 1, or the only one given) and the compressing one (storage 2). Each
//! node takes a code, the sum of the codes of the boxes that hold it (storage 1: 5, storage 2:
//! 4, moving: 3), once, at set-up. In every step, after the stresses and before the points are
//! located:
//!
//! 1. the shift Δ is the plain mean, over the *structure nodes* (the corners of the elements of
//!    the reference material that hold points at the start), of the nodes' displacement in the
//!    step along the axis, v Δt with the re-mapped nodal velocities;
//! 2. each storage box's length L along the axis is measured between its corners, where they
//!    are now;
//! 3. the nodes of the moving box and of its faces shared with a storage box (codes 3, 7, 8,
//!    12) move by Δ; when the storage boxes touch each other (some node has code 9) only the
//!    nodes of that shared face do;
//! 4. each node strictly inside storage box a (code 5 or 4 alone) at distance r > 1e-5 from
//!    the box's fixed corner (its first corner not also a corner of the moving box) moves by
//!    (Δ / L) r: the box stretches or shrinks linearly about its fixed end, and stays
//!    conforming with the moving box.
//!
//! The material points keep their global positions (moved by the step's displacement with the
//! shape functions before the move) and are located again in the moved mesh; the elements with
//! a moved node get their geometry (the map to local coordinates, the gradients, the volume)
//! recomputed. The smallest altitudes, and so the time step, stay those of the initial mesh,
//! as Anura3D's do. Fixities do not stop a node from moving. The work per step is over the
//! moved nodes and their elements, on the calling thread, in a fixed order.

use mpm_shared::model::{Body, Token};
use mpm_shared::Model;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};
use crate::step::constraint::{Constraint, Hook};

/// The GOM sections read here.
pub const SECTIONS: [&str; 5] = [
    "MOVING_MESH_CORNER_NODES",
    "EXTENDING_MESH_CORNER_NODES",
    "COMPRESSING_MESH_CORNER_NODES",
    "MOVING_MESH_DIRECTION",
    "MOVING_MESH_REFERENCE_MATERIAL_INDEX",
];

/// Code of a node in storage box 1 (Anura3D's `STORAGE1`).
const STORAGE1: u8 = 5;
/// Code of a node in storage box 2 (`STORAGE2`).
const STORAGE2: u8 = 4;
/// Code of a node in the moving box (`FIXEDMESH`).
const MOVING: u8 = 3;
/// Storage box 1 and the moving box.
const STORAGE1_MOVING: u8 = STORAGE1 + MOVING;
/// Storage box 2 and the moving box.
const STORAGE2_MOVING: u8 = STORAGE2 + MOVING;
/// Both storage boxes (they touch).
const STORAGE1_STORAGE2: u8 = STORAGE1 + STORAGE2;
/// All three boxes (a flat moving box).
const ALL_BOXES: u8 = STORAGE1 + STORAGE2 + MOVING;

/// The tolerance of Anura3D's box test.
const INSIDE_TOLERANCE: f64 = 1e-10;
/// Below this length a storage box is taken as flat and not stretched, and nodes this close to
/// its fixed corner stay (Anura3D's 1e-5).
const FLAT: f64 = 1e-5;

/// The moving mesh as the input gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingMeshSpec {
    /// The storage boxes' corners (model nodes, 0-based), in Anura3D's order: the extending box
    /// then the compressing one, or the only one given; each with its fixed corner first.
    pub storage: Vec<Vec<u32>>,
    /// The moving box's corners (model nodes, 0-based).
    pub moving: Vec<u32>,
    /// The axis the mesh moves along (0: x, 1: y, 2: z).
    pub axis: usize,
    /// The reference material (its index), whose elements' nodes the mesh follows.
    pub material: u32,
}

impl MovingMeshSpec {
    /// The spec with its nodes renumbered: `new_of_old[n]` is model node n's new index.
    pub fn renumbered(mut self, new_of_old: &[u32]) -> Self {
        for n in self.storage.iter_mut().flatten().chain(&mut self.moving) {
            *n = new_of_old[*n as usize];
        }
        self
    }
}

/// Reads the moving mesh of `model`: `None` when none of the three corner lists is given (or
/// all are empty), else the spec, or the section and what is wrong with it. Anura3D reads
/// `dim (dim - 1) + 2` corners per list (8 in 3D, 4 in 2D).
pub fn read(model: &Model) -> Result<Option<MovingMeshSpec>, (String, String)> {
    let moving = corner_list(model, "MOVING_MESH_CORNER_NODES")?;
    let extending = corner_list(model, "EXTENDING_MESH_CORNER_NODES")?;
    let compressing = corner_list(model, "COMPRESSING_MESH_CORNER_NODES")?;
    if moving.is_none() && extending.is_none() && compressing.is_none() {
        return Ok(None);
    }
    let Some(moving) = moving else {
        return Err((
            "$$MOVING_MESH_CORNER_NODES".into(),
            "missing: a moving mesh needs the corners of the box that moves".into(),
        ));
    };
    let axis = read_axis(model)?;
    let material = first_line(model, "MOVING_MESH_REFERENCE_MATERIAL_INDEX")
        .and_then(|t| {
            t.split_whitespace()
                .next()
                .and_then(|w| w.parse::<u32>().ok())
        })
        .filter(|&m| m > 0)
        .ok_or_else(|| {
            (
                "$$MOVING_MESH_REFERENCE_MATERIAL_INDEX".to_string(),
                "missing, or not a positive material index".to_string(),
            )
        })?;
    let storage = storage_boxes(&moving, extending, compressing)?;
    Ok(Some(MovingMeshSpec {
        storage,
        moving,
        axis,
        material,
    }))
}

/// The corner nodes (0-based) of the box of section `key`: `None` when the section is missing
/// or empty, else `dim (dim - 1) + 2` nodes of the mesh.
fn corner_list(model: &Model, key: &str) -> Result<Option<Vec<u32>>, (String, String)> {
    let dim = model.dimension.coords();
    let corners = dim * (dim - 1) + 2;
    let Some(s) = model.section(key) else {
        return Ok(None);
    };
    let item = format!("$${key}");
    let Body::Table { rows, .. } = &s.body else {
        return Err((item, "expected one node number per line".into()));
    };
    let mut out = Vec::new();
    for r in rows.rows() {
        let node = r.first().and_then(Token::as_int).unwrap_or(0);
        if node < 1 || node as usize > model.node_count() {
            return Err((
                item,
                format!(
                    "node {} is not in the mesh (1..={})",
                    r.first()
                        .map_or(f64::NAN, |t| t.as_f64().unwrap_or(f64::NAN)),
                    model.node_count()
                ),
            ));
        }
        out.push(node as u32 - 1);
    }
    if out.is_empty() {
        return Ok(None);
    }
    if out.len() != corners {
        return Err((
            item,
            format!(
                "{} corner nodes; a {dim}D box has {corners} (one node number per line)",
                out.len()
            ),
        ));
    }
    Ok(Some(out))
}

/// The first non-blank line of the text section `key`, trimmed (`None` when the section is
/// missing, not text, or blank).
fn first_line(model: &Model, key: &str) -> Option<String> {
    match &model.section(key)?.body {
        Body::Text(lines) => lines
            .iter()
            .map(|l| l.trim())
            .find(|l| !l.is_empty())
            .map(str::to_string),
        _ => None,
    }
}

/// The axis of `$$MOVING_MESH_DIRECTION` (0: x, 1: y, 2: z), one of the model's.
fn read_axis(model: &Model) -> Result<usize, (String, String)> {
    let dim = model.dimension.coords();
    let direction = first_line(model, "MOVING_MESH_DIRECTION").ok_or_else(|| {
        (
            "$$MOVING_MESH_DIRECTION".to_string(),
            "missing: give x-direction, y-direction or z-direction".to_string(),
        )
    })?;
    let axis = match direction.trim_matches('"') {
        "x-direction" => 0,
        "y-direction" => 1,
        "z-direction" => 2,
        other => {
            return Err((
                "$$MOVING_MESH_DIRECTION".into(),
                format!("\"{other}\": expected x-direction, y-direction or z-direction"),
            ))
        }
    };
    if axis >= dim {
        return Err((
            "$$MOVING_MESH_DIRECTION".into(),
            format!("{direction} in a {dim}D model"),
        ));
    }
    Ok(axis)
}

/// The storage boxes' corners, the extending box's then the compressing one's (those given,
/// at least one), each with its fixed end first: its first corner that is not also a corner
/// of the moving box (`moving`).
fn storage_boxes(
    moving: &[u32],
    extending: Option<Vec<u32>>,
    compressing: Option<Vec<u32>>,
) -> Result<Vec<Vec<u32>>, (String, String)> {
    let mut storage = Vec::new();
    for (key, box_corners) in [
        ("EXTENDING_MESH_CORNER_NODES", extending),
        ("COMPRESSING_MESH_CORNER_NODES", compressing),
    ] {
        let Some(mut c) = box_corners else { continue };
        let Some(k) = c.iter().position(|n| !moving.contains(n)) else {
            return Err((
                format!("$${key}"),
                "every corner is also a corner of the moving box: the box has no fixed end".into(),
            ));
        };
        c.swap(0, k);
        storage.push(c);
    }
    if storage.is_empty() {
        return Err((
            "$$EXTENDING_MESH_CORNER_NODES".into(),
            "a moving mesh needs an extending or a compressing box (or both)".into(),
        ));
    }
    Ok(storage)
}

/// A step of the moving mesh turned an element inside out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the moving mesh turned element {element} inside out at step {step} (t = {time} s): a storage box is used up (the structure has moved about as far as the box is long); give the mesh more room ahead of the structure")]
pub struct Inverted {
    /// The element (1-based, input numbering).
    pub element: u32,
    /// Time step number (1-based).
    pub step: u64,
    /// Simulated time.
    pub time: f64,
}

/// Why a moving mesh cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MovingMeshError {
    /// No element of the reference material holds points.
    #[error("the moving mesh follows material {0}, but no element of that material holds material points ($$MOVING_MESH_REFERENCE_MATERIAL_INDEX)")]
    NoStructure(u32),
}

/// A storage box, as the step moves it.
#[derive(Debug, Clone)]
struct Storage {
    /// Its corners (model nodes), the fixed one first.
    corners: Vec<u32>,
    /// The nodes strictly inside it (model nodes with its code alone), ascending.
    nodes: Vec<u32>,
}

/// The moving mesh of a run, resolved on its mesh.
#[derive(Debug, Clone)]
pub struct MovingMesh {
    axis: usize,
    /// Structure nodes (computational), by ascending model node.
    structure: Vec<u32>,
    /// The nodes the moving box carries along (model nodes), ascending.
    carried: Vec<u32>,
    storage: Vec<Storage>,
    /// Current coordinate along the axis of every model node, in the input's coordinates.
    along: Vec<f64>,
    /// The model nodes' other coordinates, relative to the mesh origin (for the geometry).
    model_xyz: Vec<[f64; 3]>,
    /// Elements (local) with a node that moves, ascending.
    elements: Vec<u32>,
}

impl MovingMesh {
    /// Resolves `spec` on `mesh` (the whole mesh, elements in the case's order): box codes from
    /// `model`'s initial coordinates, structure nodes from the elements of the reference
    /// material that hold points (`material[e]`, `points[e]`), summed in the order of their
    /// input numbers (`input_node[n]` of model node n), as Anura3D sums them.
    pub fn new<E: Element, R: Real>(
        spec: &MovingMeshSpec,
        model: &Model,
        mesh: &Mesh<E, R>,
        material: &[u32],
        points: &[u32],
        input_node: &[u32],
    ) -> Result<Self, MovingMeshError> {
        let dim = model.dimension.coords();
        let coord = |n: usize, a: usize| model.node(n).get(a).copied().unwrap_or(0.0);
        let bounds = |corners: &[u32]| {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for &c in corners {
                for a in 0..dim {
                    lo[a] = lo[a].min(coord(c as usize, a));
                    hi[a] = hi[a].max(coord(c as usize, a));
                }
            }
            (lo, hi)
        };
        let n_model = model.node_count();
        let mut code = vec![0u8; n_model];
        let boxes = spec
            .storage
            .iter()
            .zip([STORAGE1, STORAGE2])
            .map(|(c, k)| (c.as_slice(), k))
            .chain(std::iter::once((spec.moving.as_slice(), MOVING)));
        for (corners, k) in boxes {
            let (lo, hi) = bounds(corners);
            for (n, c) in code.iter_mut().enumerate() {
                if (0..dim).all(|a| {
                    let x = coord(n, a);
                    x >= lo[a] - INSIDE_TOLERANCE && x <= hi[a] + INSIDE_TOLERANCE
                }) {
                    *c += k;
                }
            }
        }
        let modified = code.contains(&STORAGE1_STORAGE2);
        let carried: Vec<u32> = (0..n_model as u32)
            .filter(|&n| {
                let c = code[n as usize];
                if modified {
                    c == STORAGE1_STORAGE2
                } else {
                    matches!(c, MOVING | STORAGE1_MOVING | STORAGE2_MOVING | ALL_BOXES)
                }
            })
            .collect();
        let storage: Vec<Storage> = spec
            .storage
            .iter()
            .zip([STORAGE1, STORAGE2])
            .map(|(corners, k)| Storage {
                corners: corners.clone(),
                nodes: (0..n_model as u32)
                    .filter(|&n| code[n as usize] == k)
                    .collect(),
            })
            .collect();
        let mut structure: Vec<u32> = Vec::new();
        for e in 0..mesh.elements() {
            if material[e] == spec.material && points[e] > 0 {
                structure.extend_from_slice(mesh.corners[e].as_ref());
            }
        }
        structure.sort_unstable_by_key(|&n| input_node[mesh.model_node[n as usize] as usize]);
        structure.dedup();
        if structure.is_empty() {
            return Err(MovingMeshError::NoStructure(spec.material));
        }
        let mut moves = vec![false; mesh.nodes()];
        for &n in carried.iter().chain(storage.iter().flat_map(|s| &s.nodes)) {
            let c = mesh.node_of_model[n as usize];
            if c != u32::MAX {
                moves[c as usize] = true;
            }
        }
        let elements = (0..mesh.elements() as u32)
            .filter(|&e| {
                mesh.corners[e as usize]
                    .as_ref()
                    .iter()
                    .any(|&c| moves[c as usize])
            })
            .collect();
        let origin = mesh.origin;
        Ok(MovingMesh {
            axis: spec.axis,
            structure,
            carried,
            storage,
            along: (0..n_model).map(|n| coord(n, spec.axis)).collect(),
            model_xyz: (0..n_model)
                .map(|n| [0, 1, 2].map(|a| coord(n, a) - origin[a]))
                .collect(),
            elements,
        })
    }

    /// The shift of this step: the mean over the structure nodes of their displacement along
    /// the axis, `vel` Δt (each node's as Anura3D forms it: its position moved, less its
    /// position).
    pub fn shift<E: Element, R: Real>(&self, mesh: &Mesh<E, R>, vel: &[V3<R>], dt: f64) -> f64 {
        let a = self.axis;
        let mut sum = 0.0;
        for &c in &self.structure {
            let x = self.along[mesh.model_node[c as usize] as usize];
            sum += (x + vel[c as usize][a].f64() * dt) - x;
        }
        sum / self.structure.len() as f64
    }

    /// Moves the mesh by the step's shift (see the module's description) and recomputes the
    /// geometry of the elements it changes. `vel`: the re-mapped nodal velocities of the step.
    /// Fails with the first element (local index) the move turns inside out or flattens; the
    /// others are moved all the same.
    pub fn advance<E: Element, R: Real>(
        &mut self,
        mesh: &mut Mesh<E, R>,
        vel: &[V3<R>],
        dt: f64,
    ) -> Result<(), usize> {
        let delta = self.shift(mesh, vel, dt);
        // The storage boxes' lengths before this step's move (at most two boxes: no
        // allocation in the step).
        let mut lengths = [-1.0f64; 2];
        for (s, length) in self.storage.iter().zip(&mut lengths) {
            for &i in &s.corners {
                for &j in &s.corners {
                    if i != j {
                        *length =
                            length.max((self.along[i as usize] - self.along[j as usize]).abs());
                    }
                }
            }
        }
        for &n in &self.carried {
            self.along[n as usize] += delta;
        }
        for (s, &length) in self.storage.iter().zip(&lengths) {
            if length <= FLAT {
                continue;
            }
            let fixed = self.along[s.corners[0] as usize];
            for &n in &s.nodes {
                let x = &mut self.along[n as usize];
                let r = (*x - fixed).abs();
                if r > FLAT {
                    *x += delta / length * r;
                }
            }
        }
        self.place(mesh)
    }

    /// Puts the computational nodes where [`MovingMesh::along`] has them and recomputes the
    /// geometry of the elements that hold moved nodes.
    fn place<E: Element, R: Real>(&self, mesh: &mut Mesh<E, R>) -> Result<(), usize> {
        let a = self.axis;
        let origin = mesh.origin[a];
        for n in self.moved() {
            let c = mesh.node_of_model[n as usize];
            if c != u32::MAX {
                mesh.x[c as usize][a] = R::of(self.along[n as usize] - origin);
            }
        }
        let mut inverted = None;
        for &e in &self.elements {
            let e = e as usize;
            let corners = mesh.corners[e];
            let x = E::nodes(|k| {
                let m = mesh.model_node[corners.as_ref()[k] as usize] as usize;
                let mut p = self.model_xyz[m];
                p[a] = self.along[m] - origin;
                p
            });
            match E::geometry::<R>(&x) {
                Ok(g) => {
                    mesh.map[e] = g.map;
                    mesh.grad[e] = g.grad;
                    mesh.volume[e] = g.volume;
                }
                Err(_) => {
                    inverted.get_or_insert(e);
                }
            }
        }
        inverted.map_or(Ok(()), Err)
    }

    /// The current coordinate along the axis of model node `n` (input coordinates).
    pub fn position(&self, n: usize) -> f64 {
        self.along[n]
    }

    /// The moved nodes' coordinates along the axis, in a fixed order: what a checkpoint keeps
    /// of the moving mesh.
    pub fn state(&self) -> Vec<f64> {
        self.moved().map(|n| self.along[n as usize]).collect()
    }

    /// Puts back a [`MovingMesh::state`] on the mesh it was set up on (at the start of a
    /// resumed run): the nodes where they were, the elements' geometry recomputed. `false` when
    /// `state` does not have one value per moved node or turns an element inside out.
    pub fn restore<E: Element, R: Real>(&mut self, mesh: &mut Mesh<E, R>, state: &[f64]) -> bool {
        let moved: Vec<u32> = self.moved().collect();
        if moved.len() != state.len() {
            return false;
        }
        for (&n, &x) in moved.iter().zip(state) {
            self.along[n as usize] = x;
        }
        self.place(mesh).is_ok()
    }

    /// Model nodes that can move: those the moving box carries, then each storage box's.
    fn moved(&self) -> impl Iterator<Item = u32> + '_ {
        self.carried
            .iter()
            .chain(self.storage.iter().flat_map(|s| &s.nodes))
            .copied()
    }
}

impl<R: Real, E: Element> Constraint<R, E> for MovingMesh {
    /// As a checkpoint names its state.
    fn name(&self) -> &'static str {
        "moving_mesh"
    }

    /// After the stresses and the points' move (with the shape functions of the mesh before it
    /// moves), before the points are located in the moved mesh: Anura3D's order. With contact
    /// the mesh follows the structure's nodes.
    fn after_move(&mut self, cx: &mut Hook<'_, R, E>) -> Result<(), usize> {
        let vel = cx.structure.as_deref().map_or(&cx.soil.vel, |g| &g.vel);
        self.advance(cx.mesh, vel, cx.at.dt)
    }

    fn moves_mesh(&self) -> bool {
        true
    }

    fn saved(&self) -> Vec<f64> {
        self.state()
    }

    fn restore(&mut self, mesh: &mut Mesh<E, R>, state: &[f64]) -> bool {
        MovingMesh::restore(self, mesh, state)
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use mpm_shared::{generate, ElementType};

    /// A column of 1 × 6 × 1 cells (y from 0 to 6): storage box 1 (extending) from y = 4 to 6,
    /// the moving box from 2 to 4 (its material, 2, in cells 2 and 3), storage box 2
    /// (compressing) from 0 to 2.
    fn column() -> (Model, MovingMeshSpec, Vec<u32>) {
        let model = generate::box_mesh([1, 6, 1], [1.0, 6.0, 1.0], ElementType::Tet4);
        let at = |y: f64| -> Vec<u32> {
            (0..model.node_count() as u32)
                .filter(|&n| (model.node(n as usize)[1] - y).abs() < 1e-12)
                .collect()
        };
        let (y0, y2, y4, y6) = (at(0.0), at(2.0), at(4.0), at(6.0));
        let spec = MovingMeshSpec {
            storage: vec![
                [y6.clone(), y4.clone()].concat(),
                [y0.clone(), y2.clone()].concat(),
            ],
            moving: [y2, y4].concat(),
            axis: 1,
            material: 2,
        };
        let material = (0..model.element_count())
            .map(|e| {
                let c: f64 = model
                    .element(e)
                    .iter()
                    .map(|&n| model.node(n as usize)[1])
                    .sum();
                let y = c / 4.0;
                if (2.0..4.0).contains(&y) {
                    2
                } else {
                    1
                }
            })
            .collect();
        (model, spec, material)
    }

    #[test]
    fn the_moving_box_shifts_and_the_storage_boxes_stretch_linearly() {
        let (model, spec, material) = column();
        let mut mesh = Mesh::<Tet4, f64>::new(&model).unwrap();
        let points = vec![4; model.element_count()];
        let input: Vec<u32> = (0..model.node_count() as u32).collect();
        let mut mm = MovingMesh::new(&spec, &model, &mesh, &material, &points, &input).unwrap();
        let volume0: f64 = mesh.volume.iter().sum();
        // Every node moves down at 0.5 m/s; the structure's mean is that.
        let vel = vec![[0.0, -0.5, 0.0]; mesh.nodes()];
        mm.advance(&mut mesh, &vel, 0.2).unwrap();
        for (c, x) in mesh.x.iter().enumerate() {
            let y0 = model.node(mesh.model_node[c] as usize)[1];
            let expected = if (2.0 - 1e-12..=4.0 + 1e-12).contains(&y0) {
                y0 - 0.1
            } else if y0 > 4.0 {
                // Extending: fixed at y = 6, length 2.
                y0 - 0.1 * (6.0 - y0) / 2.0
            } else {
                // Compressing: fixed at y = 0.
                y0 - 0.1 * y0 / 2.0
            };
            assert!(
                (x[1] - expected).abs() < 1e-14,
                "node {c}: {} vs {expected}",
                x[1]
            );
        }
        // The mesh stays conforming: its volume is unchanged, every element's positive.
        let volume1: f64 = mesh.volume.iter().sum();
        assert!((volume1 - volume0).abs() < 1e-12);
        assert!(mesh.volume.iter().all(|&v| v > 0.0));
        // The next step measures the boxes as they are now: lengths 2.1 and 1.9.
        mm.advance(&mut mesh, &vel, 0.2).unwrap();
        let top = mesh.x.iter().map(|x| x[1]).fold(f64::MIN, f64::max);
        assert!((top - 6.0).abs() < 1e-14);
        let y_mid = mm.position(spec.moving[0] as usize);
        assert!((y_mid - 1.8).abs() < 1e-14);
        // Geometry follows: gradients reproduce a linear field on a moved element.
        let e = mm.elements[0] as usize;
        let mut gy = 0.0;
        for k in 0..4 {
            gy += mesh.x[mesh.corners[e][k] as usize][1] * mesh.grad[e][k][1];
        }
        assert!((gy - 1.0).abs() < 1e-12);
    }

    /// `model` with the GOM sections `extra` added.
    fn with_sections(model: &Model, extra: &str) -> Model {
        let text = String::from_utf8(mpm_shared::gom::write(model)).unwrap();
        let text = text.replace("$$FINISH", &format!("{extra}$$FINISH"));
        mpm_shared::gom::read(text.as_bytes(), "test.GOM").unwrap()
    }

    #[test]
    fn the_spec_is_read_with_the_fixed_corner_first_and_bad_lists_named() {
        let (model, spec, _) = column();
        let lines = |ns: &[u32]| -> String { ns.iter().map(|n| format!("{}\n", n + 1)).collect() };
        let moving_first: Vec<u32> =
            [spec.moving[..1].to_vec(), spec.storage[0][..7].to_vec()].concat();
        let gom = format!(
            "$$EXTENDING_MESH_CORNER_NODES\n{}$$MOVING_MESH_CORNER_NODES\n{}$$MOVING_MESH_DIRECTION\ny-direction\n$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n2\n",
            lines(&moving_first),
            lines(&spec.moving)
        );
        let got = read(&with_sections(&model, &gom)).unwrap().unwrap();
        assert_eq!(got.axis, 1);
        assert_eq!(got.material, 2);
        assert_eq!(got.storage.len(), 1);
        // The moving box's corner was listed first; the fixed corner is swapped before it.
        assert_eq!(got.storage[0][0], spec.storage[0][0]);
        assert!(spec.moving.contains(&got.storage[0][1]));
        let short = with_sections(&model, "$$MOVING_MESH_CORNER_NODES\n1\n2\n");
        let (item, why) = read(&short).unwrap_err();
        assert_eq!(item, "$$MOVING_MESH_CORNER_NODES");
        assert!(why.contains("a 3D box has 8"), "{why}");
    }
}
