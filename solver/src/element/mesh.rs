//! The computational mesh: elements of one type ([`Element`]) on the model's nodes (the corner
//! nodes, for 10-node tetrahedra computed as 4-node ones, as Anura3D does), with what every phase
//! needs per element precomputed: the map to local coordinates, constant shape-function
//! gradients, volume, smallest altitude and face neighbours.

use mpm_shared::Model;

/// Neighbour marker of a face whose element belongs to another process and lies beyond its
/// halo (see `parallel::partition`).
pub const REMOTE: u32 = u32::MAX - 1;

use crate::element::tet4::Tet4;
use crate::element::Element;
use crate::real::{Real, V3};

/// A mesh of elements of type `E`.
#[derive(Debug, Clone)]
pub struct Mesh<E: Element, R: Real> {
    /// The model origin: the smallest corner of the computational nodes' bounding box, in the
    /// input's coordinates. Positions inside the solver are taken from it, so that single
    /// precision keeps its resolution on sites in UTM coordinates (x ≈ 5e5 m, y ≈ 6e6 m).
    pub origin: [f64; 3],
    /// Coordinates of the computational nodes, relative to [`Mesh::origin`].
    pub x: Vec<V3<R>>,
    /// Model node (0-based) of each computational node.
    pub model_node: Vec<u32>,
    /// Computational node of each model node (`u32::MAX` for mid-edge nodes).
    pub node_of_model: Vec<u32>,
    /// Nodes of each element (its corners, for the linear elements there are).
    pub corners: Vec<E::Nodes<u32>>,
    /// Map to local coordinates of each element (see [`Element::shape`]).
    pub map: Vec<E::Map<R>>,
    /// Shape-function gradients of each element's nodes.
    pub grad: Vec<E::Nodes<V3<R>>>,
    /// Element volumes.
    pub volume: Vec<R>,
    /// Smallest altitude of each element (for the Courant time step).
    pub min_altitude: Vec<R>,
    /// Element across each face (`u32::MAX` on the boundary).
    pub neighbour: Vec<E::Faces<u32>>,
}

/// The mesh of 4-node tetrahedra, the solver's element today.
pub type TetMesh<R> = Mesh<Tet4, R>;

/// Problems that make a mesh unusable for computation.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The model's elements are not of the solver's element type.
    #[error("this engine computes meshes of {wanted}; this one has {found} ({dimension})")]
    WrongElement {
        /// The engine's element.
        wanted: &'static str,
        /// The model's elements.
        found: &'static str,
        /// The model's dimension (Anura3D's keyword).
        dimension: &'static str,
    },
    /// No elements.
    #[error("the mesh has no elements")]
    Empty,
    /// A node of an axisymmetric section on the negative side of the axis (x < 0).
    #[error("node {node} lies at x = {x}: an axisymmetric section has its axis at x = 0 and its nodes at x ≥ 0")]
    NegativeRadius {
        /// 1-based model node id.
        node: usize,
        /// Its x coordinate.
        x: f64,
    },
    /// A degenerate or inverted element.
    #[error("element {element} is inverted or flat (volume {volume:e})")]
    BadElement {
        /// 1-based element id.
        element: usize,
        /// Its signed volume.
        volume: f64,
    },
}

/// Faces with at most this many nodes are matched to find neighbours.
const MAX_FACE_NODES: usize = 4;

impl<E: Element, R: Real> Mesh<E, R> {
    /// Builds the computational mesh of `model` (geometry in f64, stored in `R`).
    pub fn new(model: &Model) -> Result<Self, MeshError> {
        if !E::computes(model.dimension, model.element_type) {
            return Err(MeshError::WrongElement {
                wanted: E::NAME,
                found: model.element_type.describe(),
                dimension: model.dimension.keyword(),
            });
        }
        let n_el = model.element_count();
        if n_el == 0 {
            return Err(MeshError::Empty);
        }
        let mut node_of_model = vec![u32::MAX; model.node_count()];
        let mut model_node = Vec::new();
        let mut corners = Vec::with_capacity(n_el);
        for e in 0..n_el {
            let el = model.element(e);
            corners.push(E::nodes(|k| {
                let m = el[k] as usize;
                if node_of_model[m] == u32::MAX {
                    node_of_model[m] = model_node.len() as u32;
                    model_node.push(m as u32);
                }
                node_of_model[m]
            }));
        }
        let mut origin = [f64::INFINITY; 3];
        for &m in &model_node {
            let p = model.node(m as usize);
            for a in 0..3 {
                origin[a] = origin[a].min(p.get(a).copied().unwrap_or(0.0));
            }
        }
        if E::AXISYMMETRIC {
            // The kernels divide by the radius: it stays the coordinate itself (the axis at
            // x = 0), and no node may lie on the other side of the axis.
            if let Some(&m) = model_node
                .iter()
                .find(|&&m| model.node(m as usize)[0] < 0.0)
            {
                return Err(MeshError::NegativeRadius {
                    node: m as usize + 1,
                    x: model.node(m as usize)[0],
                });
            }
            origin[0] = 0.0;
        }
        let xf: Vec<[f64; 3]> = model_node
            .iter()
            .map(|&m| {
                // 2D models have two coordinates: they lie in z = 0.
                let p = model.node(m as usize);
                [0, 1, 2].map(|a| p.get(a).copied().unwrap_or(0.0) - origin[a])
            })
            .collect();
        let mut map = Vec::with_capacity(n_el);
        let mut grad = Vec::with_capacity(n_el);
        let mut volume = Vec::with_capacity(n_el);
        let mut min_altitude = Vec::with_capacity(n_el);
        for (e, c) in corners.iter().enumerate() {
            let c = c.as_ref();
            let g = E::geometry::<R>(&E::nodes(|k| xf[c[k] as usize])).map_err(|volume| {
                MeshError::BadElement {
                    element: e + 1,
                    volume,
                }
            })?;
            map.push(g.map);
            grad.push(g.grad);
            volume.push(g.volume);
            min_altitude.push(g.min_altitude);
        }
        // Face neighbours by sorting face keys (node lists sorted, padded with u32::MAX).
        let mut faces: Vec<([u32; MAX_FACE_NODES], u32, u8)> = Vec::with_capacity(n_el * E::FACES);
        for (e, c) in corners.iter().enumerate() {
            let c = c.as_ref();
            for k in 0..E::FACES {
                let f = E::face(k);
                debug_assert!(f.len() <= MAX_FACE_NODES);
                let mut key = [u32::MAX; MAX_FACE_NODES];
                for (slot, &j) in key.iter_mut().zip(f) {
                    *slot = c[j];
                }
                key.sort_unstable();
                faces.push((key, e as u32, k as u8));
            }
        }
        faces.sort_unstable();
        let mut neighbour = vec![E::faces(|_| u32::MAX); n_el];
        for w in faces.windows(2) {
            if w[0].0 == w[1].0 {
                neighbour[w[0].1 as usize].as_mut()[w[0].2 as usize] = w[1].1;
                neighbour[w[1].1 as usize].as_mut()[w[1].2 as usize] = w[0].1;
            }
        }
        Ok(Mesh {
            origin,
            x: xf.iter().map(|p| p.map(R::of)).collect(),
            model_node,
            node_of_model,
            corners,
            map,
            grad,
            volume,
            min_altitude,
            neighbour,
        })
    }

    /// Number of computational nodes.
    pub fn nodes(&self) -> usize {
        self.x.len()
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.corners.len()
    }

    /// A position inside the solver (relative to the origin) in the input's coordinates.
    #[inline]
    pub fn global(&self, x: &V3<R>) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + x[a].f64())
    }

    /// Shape-function values of element `e`'s nodes at `p`.
    #[inline(always)]
    pub fn shape(&self, e: usize, p: &V3<R>) -> E::Nodes<R> {
        let first = &self.x[self.corners[e].as_ref()[0] as usize];
        E::shape(&self.map[e], first, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tri3::Tri3;
    use crate::four::Four;
    use mpm_shared::{generate, ElementType};

    #[test]
    fn shape_functions_are_barycentric_and_gradients_consistent() {
        let model = generate::box_mesh([2, 2, 2], [1.0, 2.0, 0.5], ElementType::Tet10);
        let mesh = TetMesh::<f64>::new(&model).unwrap();
        assert_eq!(mesh.nodes(), 27);
        let total: f64 = mesh.volume.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        for e in 0..mesh.elements() {
            for (k, &n) in mesh.corners[e].as_ref().iter().enumerate() {
                let s = mesh.shape(e, &mesh.x[n as usize]);
                for (j, v) in s.iter().enumerate() {
                    assert!((v - if j == k { 1.0 } else { 0.0 }).abs() < 1e-12);
                }
            }
            // Gradients sum to zero and reproduce a linear field exactly.
            for d in 0..3 {
                let s: f64 = mesh.grad[e].iter().map(|g| g[d]).sum();
                assert!(s.abs() < 1e-9);
                let mut gx = [0.0; 3];
                for k in 0..4 {
                    let xn = mesh.x[mesh.corners[e][k] as usize];
                    let f = 2.0 * xn[0] - xn[1] + 3.0 * xn[2];
                    for a in 0..3 {
                        gx[a] += f * mesh.grad[e][k][a];
                    }
                }
                assert!(
                    (gx[0] - 2.0).abs() < 1e-9
                        && (gx[1] + 1.0).abs() < 1e-9
                        && (gx[2] - 3.0).abs() < 1e-9
                );
            }
        }
        // Interior faces have neighbours on both sides.
        let boundary: usize = mesh
            .neighbour
            .iter()
            .flatten()
            .filter(|&&n| n == u32::MAX)
            .count();
        // 6 sides x 4 squares x 2 triangles.
        assert_eq!(boundary, 48);
    }

    /// Each lane of [`Element::shape_lanes`] is [`Element::shape`] at that point, to the bit,
    /// in f64 and f32 and for batches of 1 and 4 (the stress loop's results must not depend on
    /// its batch width).
    fn shape_lanes_match<E: Element, R: Real, const W: usize>(mesh: &Mesh<E, R>) {
        let mut next = crate::element::samples(0x9e37_79b9_7f4a_7c15);
        for e in 0..mesh.elements() {
            let first = &mesh.x[mesh.corners[e].as_ref()[0] as usize];
            let points: [V3<R>; W] = std::array::from_fn(|_| {
                // Inside the element's box and a little beyond it.
                let mut p = [R::ZERO; 3];
                for a in 0..E::DIM {
                    p[a] = R::of(first[a].f64() + 1.2 * next() - 0.6);
                }
                p
            });
            let x: [[R; W]; 3] = std::array::from_fn(|a| points.map(|p| p[a]));
            let lanes = E::shape_lanes(&mesh.map[e], first, &x);
            // With four points, the explicit four-lane version too, where the processor runs it.
            let four = (W == 4).then(R::Four::token).flatten().map(|t| {
                let x = std::array::from_fn(|a| {
                    R::Four::load(t, &std::array::from_fn(|q| x[a][q % W]))
                });
                E::shape_four(t, &mesh.map[e], first, &x).map(|v| v.to_array())
            });
            for (q, p) in points.iter().enumerate() {
                let one = mesh.shape(e, p);
                for k in 0..4 {
                    let want = one.as_ref().get(k).map_or(0.0, |v| v.f64());
                    assert_eq!(
                        lanes[k][q].f64().to_bits(),
                        want.to_bits(),
                        "e{e} q{q} k{k}"
                    );
                    if let Some(four) = &four {
                        assert_eq!(
                            four[k][q].f64().to_bits(),
                            want.to_bits(),
                            "four e{e} q{q} k{k}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn shape_lanes_are_shape_lane_by_lane() {
        let tets = generate::box_mesh([2, 2, 2], [1.0, 2.0, 0.5], ElementType::Tet4);
        shape_lanes_match::<Tet4, f64, 1>(&TetMesh::<f64>::new(&tets).unwrap());
        shape_lanes_match::<Tet4, f64, 4>(&TetMesh::<f64>::new(&tets).unwrap());
        shape_lanes_match::<Tet4, f32, 4>(&TetMesh::<f32>::new(&tets).unwrap());
        let tris = generate::rect_mesh([3, 2], [1.5, 1.0]);
        shape_lanes_match::<Tri3, f64, 1>(&Mesh::<Tri3, f64>::new(&tris).unwrap());
        shape_lanes_match::<Tri3, f64, 4>(&Mesh::<Tri3, f64>::new(&tris).unwrap());
        shape_lanes_match::<Tri3, f32, 4>(&Mesh::<Tri3, f32>::new(&tris).unwrap());
    }
}
