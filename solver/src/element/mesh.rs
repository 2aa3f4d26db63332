//! The computational mesh: linear tetrahedra on the corner nodes of the model (10-node files are
//! computed with their corners, as Anura3D does), with what every phase needs per element
//! precomputed: the inverse affine map (barycentric coordinates and constant shape-function
//! gradients), volume, smallest altitude and face neighbours.

use mpm_shared::{ElementType, Model};

use crate::real::{Real, V3};

/// Linear tetrahedral mesh in Anura3D corner order (N1 = 1-ξ-η-ζ, N2 = ζ, N3 = ξ, N4 = η, i.e.
/// barycentric coordinates of corners 1-4).
#[derive(Debug, Clone)]
pub struct TetMesh<R: Real> {
    /// Coordinates of the computational (corner) nodes.
    pub x: Vec<V3<R>>,
    /// Model node (0-based) of each computational node.
    pub model_node: Vec<u32>,
    /// Computational node of each model node (`u32::MAX` for mid-edge nodes).
    pub node_of_model: Vec<u32>,
    /// Corner nodes of each element.
    pub corners: Vec<[u32; 4]>,
    /// Rows 2-4 of the barycentric map: `λ(k+2) = inv[k] · (x - x1)` for k = 0..3, and
    /// `λ1 = 1 - λ2 - λ3 - λ4`.
    pub inv: Vec<[V3<R>; 3]>,
    /// Shape-function gradients of the four corners.
    pub grad: Vec<[V3<R>; 4]>,
    /// Element volumes.
    pub volume: Vec<R>,
    /// Smallest altitude of each element (for the Courant time step).
    pub min_altitude: Vec<R>,
    /// Element across the face opposite each corner (`u32::MAX` on the boundary).
    pub neighbour: Vec<[u32; 4]>,
}

/// Problems that make a mesh unusable for computation.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// Not a tetrahedral model.
    #[error("the solver needs a 3D tetrahedral mesh; this one has {0}")]
    NotTetrahedral(&'static str),
    /// No elements.
    #[error("the mesh has no elements")]
    Empty,
    /// A degenerate or inverted element.
    #[error("element {element} is inverted or flat (volume {volume:e})")]
    BadElement {
        /// 1-based element id.
        element: usize,
        /// Its signed volume.
        volume: f64,
    },
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Corners of the face opposite corner `k`.
pub const FACE_OPPOSITE: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

impl<R: Real> TetMesh<R> {
    /// Builds the computational mesh of `model` (geometry in f64, stored in `R`).
    pub fn new(model: &Model) -> Result<Self, MeshError> {
        if model.element_type == ElementType::Tri3 {
            return Err(MeshError::NotTetrahedral("triangles"));
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
            let mut c = [0u32; 4];
            for k in 0..4 {
                let m = el[k] as usize;
                if node_of_model[m] == u32::MAX {
                    node_of_model[m] = model_node.len() as u32;
                    model_node.push(m as u32);
                }
                c[k] = node_of_model[m];
            }
            corners.push(c);
        }
        let xf: Vec<[f64; 3]> = model_node
            .iter()
            .map(|&m| {
                let p = model.node(m as usize);
                [p[0], p[1], p[2]]
            })
            .collect();
        let mut inv = Vec::with_capacity(n_el);
        let mut grad = Vec::with_capacity(n_el);
        let mut volume = Vec::with_capacity(n_el);
        let mut min_altitude = Vec::with_capacity(n_el);
        for (e, c) in corners.iter().enumerate() {
            let p = c.map(|i| xf[i as usize]);
            // Columns of J: corners 2, 3, 4 relative to corner 1.
            let (a, b, d) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
            let det = dot(a, cross(b, d));
            // Anura3D's orientation: det[x3-x1, x4-x1, x2-x1] = det[a, b, d] by cyclic shift.
            if det <= 0.0 || !det.is_finite() {
                return Err(MeshError::BadElement {
                    element: e + 1,
                    volume: det / 6.0,
                });
            }
            // Rows of J^-1 = (b×d, d×a, a×b) / det give λ2, λ3, λ4.
            let rows = [cross(b, d), cross(d, a), cross(a, b)].map(|r| r.map(|v| v / det));
            inv.push(rows.map(|r| r.map(R::of)));
            let g1 = [0, 1, 2].map(|k| -(rows[0][k] + rows[1][k] + rows[2][k]));
            grad.push([g1, rows[0], rows[1], rows[2]].map(|g| g.map(R::of)));
            volume.push(R::of(det / 6.0));
            let max_area2 = FACE_OPPOSITE
                .iter()
                .map(|f| {
                    let n = cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]]));
                    dot(n, n).sqrt()
                })
                .fold(0.0, f64::max);
            // Altitude over the largest face: 3V / A = det / |n|.
            min_altitude.push(R::of(det / max_area2));
        }
        // Face neighbours by sorting face keys.
        let mut faces: Vec<([u32; 3], u32, u8)> = Vec::with_capacity(n_el * 4);
        for (e, c) in corners.iter().enumerate() {
            for (k, f) in FACE_OPPOSITE.iter().enumerate() {
                let mut key = [c[f[0]], c[f[1]], c[f[2]]];
                key.sort_unstable();
                faces.push((key, e as u32, k as u8));
            }
        }
        faces.sort_unstable();
        let mut neighbour = vec![[u32::MAX; 4]; n_el];
        for w in faces.windows(2) {
            if w[0].0 == w[1].0 {
                neighbour[w[0].1 as usize][w[0].2 as usize] = w[1].1;
                neighbour[w[1].1 as usize][w[1].2 as usize] = w[0].1;
            }
        }
        Ok(TetMesh {
            x: xf.iter().map(|p| p.map(R::of)).collect(),
            model_node,
            node_of_model,
            corners,
            inv,
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

    /// Barycentric coordinates (shape-function values N1..N4) of `p` in element `e`.
    #[inline]
    pub fn shape(&self, e: usize, p: &V3<R>) -> [R; 4] {
        let x1 = &self.x[self.corners[e][0] as usize];
        let d = [p[0] - x1[0], p[1] - x1[1], p[2] - x1[2]];
        let m = &self.inv[e];
        let l2 = m[0][0] * d[0] + m[0][1] * d[1] + m[0][2] * d[2];
        let l3 = m[1][0] * d[0] + m[1][1] * d[1] + m[1][2] * d[2];
        let l4 = m[2][0] * d[0] + m[2][1] * d[1] + m[2][2] * d[2];
        [R::ONE - l2 - l3 - l4, l2, l3, l4]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpm_shared::generate;

    #[test]
    fn shape_functions_are_barycentric_and_gradients_consistent() {
        let model = generate::box_mesh([2, 2, 2], [1.0, 2.0, 0.5], ElementType::Tet10);
        let mesh = TetMesh::<f64>::new(&model).unwrap();
        assert_eq!(mesh.nodes(), 27);
        let total: f64 = mesh.volume.iter().sum();
        assert!((total - 1.0).abs() < 1e-12);
        for e in 0..mesh.elements() {
            for (k, &n) in mesh.corners[e].iter().enumerate() {
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
}
