//! The background grid's basis ([`Cartesian`]): tensor products of the one-dimensional
//! functions of [`super::spline`] on a uniform Cartesian lattice whose nodes are the nodes of
//! the background mesh (the scene's `[grid]` table, `input/scene/grid.rs`). A point's nodes
//! follow from its position alone (no connectivity is read per point): its lattice indices
//! along each axis, then one table lookup per node from lattice index to the mesh's node
//! number (the mesh's nodes are renumbered along the space-filling curve like any mesh's).

use crate::basis::spline::{Along, Shape};
use std::ops::Range;

use crate::basis::{Basis, Stencil};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// The background grid a case runs on: its lattice and the function of its nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct GridSpec {
    /// The lattice's first corner (the bounding box's lowest corner).
    pub origin: [f64; 3],
    /// The cell's edge along each axis (m).
    pub cell: [f64; 3],
    /// Cells along each axis (1 along z in 2D).
    pub cells: [usize; 3],
    /// Axes of the lattice: 2 (a section) or 3.
    pub dim: usize,
    /// The nodes' function.
    pub shape: Shape,
    /// Material points per cell along each axis on a regular sub-lattice (`None`: the
    /// materials' points per element, placed in the cells' tetrahedra or triangles).
    pub points_per_axis: Option<usize>,
}

impl GridSpec {
    /// Nodes along each axis.
    pub fn nodes_along(&self) -> [usize; 3] {
        std::array::from_fn(|a| if a < self.dim { self.cells[a] + 1 } else { 1 })
    }

    /// The lattice index of lattice node (i, j, k).
    pub fn lattice_index(&self, ijk: [usize; 3]) -> usize {
        let n = self.nodes_along();
        ijk[0] + n[0] * (ijk[1] + n[1] * ijk[2])
    }

    /// The lattice node at `x`, if `x` lies on one (within a millionth of a cell).
    pub fn node_at(&self, x: &[f64]) -> Option<[usize; 3]> {
        let mut ijk = [0usize; 3];
        for a in 0..self.dim {
            let s = (x[a] - self.origin[a]) / self.cell[a];
            let k = s.round();
            if (s - k).abs() > 1e-6 || k < 0.0 || k > self.cells[a] as f64 {
                return None;
            }
            ijk[a] = k as usize;
        }
        Some(ijk)
    }

    /// The basis's name, as the scene writes it.
    pub fn basis_name(&self) -> &'static str {
        match self.shape {
            Shape::Linear => "linear",
            Shape::Gimp { .. } => "gimp",
            Shape::Bspline2 => "bspline2",
        }
    }
}

/// The background grid's basis on a mesh whose nodes are the lattice's.
#[derive(Debug, Clone)]
pub struct Cartesian {
    spec: GridSpec,
    /// The lattice index's step along each axis.
    stride: [usize; 3],
    /// Per lattice index, the mesh's node there.
    node: Vec<u32>,
}

/// A mesh that is not the grid's lattice.
#[derive(Debug, Clone, thiserror::Error)]
pub enum LatticeError {
    /// A node off the lattice.
    #[error("background grid: mesh node {node} at {at:?} is not on the grid's lattice")]
    OffLattice {
        /// The node (0-based, the mesh's order).
        node: usize,
        /// Where it is.
        at: [f64; 3],
    },
    /// A lattice node without a mesh node.
    #[error("background grid: no mesh node at lattice node {ijk:?}")]
    Missing {
        /// The lattice node.
        ijk: [usize; 3],
    },
}

impl Cartesian {
    /// Bytes of the table a stencil reads (the mesh's node at each lattice index): for the
    /// traffic model.
    pub fn table_bytes(&self) -> usize {
        4 * self.node.len()
    }

    /// The basis of `spec` on `mesh`, whose nodes must be the lattice's, each once.
    pub fn new<E: Element, R: Real>(
        mut spec: GridSpec,
        mesh: &Mesh<E, R>,
    ) -> Result<Self, LatticeError> {
        // The grid in the mesh's frame (positions relative to its origin), the points'.
        for (o, m) in spec.origin.iter_mut().zip(mesh.origin) {
            *o -= m;
        }
        let n = spec.nodes_along();
        let mut node = vec![u32::MAX; n[0] * n[1] * n[2]];
        for (m, x) in mesh.x.iter().enumerate() {
            let at = x.map(|c| c.f64());
            let ijk = spec.node_at(&at).ok_or(LatticeError::OffLattice {
                node: m,
                at: mesh.global(x),
            })?;
            node[spec.lattice_index(ijk)] = m as u32;
        }
        if let Some(k) = node.iter().position(|&m| m == u32::MAX) {
            let ijk = [k % n[0], k / n[0] % n[1], k / (n[0] * n[1])];
            return Err(LatticeError::Missing { ijk });
        }
        let stride = [1, n[0], n[0] * n[1]];
        Ok(Cartesian { spec, stride, node })
    }

    /// The lattice.
    pub fn spec(&self) -> &GridSpec {
        &self.spec
    }

    /// The regular points (`k` a cell along each axis, at the centres of its sub-cells) of the
    /// cell holding `inside` (in the mesh's frame), into `out`.
    pub fn cell_points<R: Real>(&self, inside: &[f64; 3], k: usize, out: &mut Vec<V3<R>>) {
        let s = &self.spec;
        let mut first = [0.0; 3];
        for (a, f) in first.iter_mut().enumerate().take(s.dim) {
            let c = ((inside[a] - s.origin[a]) / s.cell[a]).floor().max(0.0);
            let c = c.min(s.cells[a] as f64 - 1.0);
            *f = s.origin[a] + c * s.cell[a];
        }
        let along = |a: usize| if a < s.dim { k } else { 1 };
        for r in 0..along(2) {
            for q in 0..along(1) {
                for p in 0..along(0) {
                    let at = |a: usize, i: usize| {
                        if a < s.dim {
                            first[a] + (i as f64 + 0.5) / k as f64 * s.cell[a]
                        } else {
                            0.0
                        }
                    };
                    out.push([R::of(at(0, p)), R::of(at(1, q)), R::of(at(2, r))]);
                }
            }
        }
    }

    /// A cell's volume (its area in 2D).
    pub fn cell_volume(&self) -> f64 {
        self.spec.cell[..self.spec.dim].iter().product()
    }

    /// Each axis's nodes and functions at `x`.
    #[inline(always)]
    fn along(&self, x: &[f64; 3]) -> [Along; 3] {
        let s = &self.spec;
        let on = |a: usize| s.shape.along((x[a] - s.origin[a]) / s.cell[a], s.cells[a]);
        let z = if s.dim == 3 {
            on(2)
        } else {
            Along {
                first: 0,
                len: 1,
                n: [1.0, 0.0, 0.0],
                dn: [0.0; 3],
            }
        };
        [on(0), on(1), z]
    }

    /// The stencil at `x` (in f64), in lattice order (x fastest), into `out`.
    pub fn stencil_at<R: Real>(&self, x: &[f64; 3], out: &mut Stencil<R>) {
        out.clear();
        let [ax, ay, az] = self.along(x);
        let h = self.spec.cell;
        let dim = self.spec.dim;
        // The derivatives per metre, and the lattice's strides.
        let slope = |along: &Along, a: usize| along.dn.map(|d| d / h[a]);
        let (dx, dy) = (slope(&ax, 0), slope(&ay, 1));
        let dz = if dim == 3 { slope(&az, 2) } else { [0.0; 3] };
        let (sy, sz) = (self.stride[1], self.stride[2]);
        for k in 0..az.len {
            let (nz, dz) = (az.n[k], dz[k]);
            for j in 0..ay.len {
                // What the row's nodes share: N_y N_z, N_y' N_z, N_y N_z'.
                let (nyz, dyz, nydz) = (ay.n[j] * nz, dy[j] * nz, ay.n[j] * dz);
                let row = (ay.first + j) * sy + (az.first + k) * sz + ax.first;
                for i in 0..ax.len {
                    let nx = ax.n[i];
                    let n = nx * nyz;
                    let grad = [dx[i] * nyz, nx * dyz, nx * nydz];
                    // A node whose function and gradient both vanish at x adds nothing.
                    if n == 0.0 && grad.iter().all(|&g| g == 0.0) {
                        continue;
                    }
                    out.push(self.node[row + i], R::of(n), grad.map(R::of));
                }
            }
        }
    }
}

impl<E: Element, R: Real> Basis<E, R> for Cartesian {
    const LINEAR: bool = false;

    fn stencil(&self, _mesh: &Mesh<E, R>, _e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        self.stencil_at(&x.map(|c| c.f64()), out);
    }

    /// The nodes of every stencil taken in the cell that holds `e`'s centroid, from a
    /// hundredth of a cell below it to a hundredth above (a point on a face, or a rounding
    /// past it): along each axis, from the first node at the low end to the last at the high
    /// end (a stencil's first and last node never move back as the point moves up).
    fn reach(&self, mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        out.clear();
        let s = &self.spec;
        let corners = mesh.corners[e].as_ref();
        let span: [Range<usize>; 3] = std::array::from_fn(|a| {
            if a >= s.dim {
                return 0..1;
            }
            let centroid = corners
                .iter()
                .map(|&n| mesh.x[n as usize][a].f64())
                .sum::<f64>()
                / corners.len() as f64;
            let cell = ((centroid - s.origin[a]) / s.cell[a]).floor();
            let cell = cell.clamp(0.0, s.cells[a] as f64 - 1.0);
            let (lo, hi) = (
                s.shape.along(cell - 0.01, s.cells[a]),
                s.shape.along(cell + 1.01, s.cells[a]),
            );
            lo.first..hi.first + hi.len
        });
        for k in span[2].clone() {
            for j in span[1].clone() {
                for i in span[0].clone() {
                    out.push(self.node[s.lattice_index([i, j, k])]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use crate::element::tri3::Tri3;
    use mpm_shared::{generate, ElementType};

    fn spec(dim: usize, cells: [usize; 3], shape: Shape) -> GridSpec {
        GridSpec {
            origin: [0.0; 3],
            cell: [
                1.0 / cells[0] as f64,
                2.0 / cells[1] as f64,
                0.5 / cells[2] as f64,
            ],
            cells,
            dim,
            shape,
            points_per_axis: None,
        }
    }

    /// Every basis reproduces constants and linear fields through its stencil, with gradients
    /// that sum to zero and reproduce the identity, at points all over the box (edges too).
    #[test]
    fn stencils_reproduce_linear_fields_in_3d_and_2d() {
        let shapes = [Shape::Linear, Shape::Gimp { a: 0.25 }, Shape::Bspline2];
        let box3 = generate::box_mesh([3, 4, 2], [1.0, 2.0, 0.5], ElementType::Tet4);
        let mesh3 = Mesh::<Tet4, f64>::new(&box3).unwrap();
        let rect = generate::rect_mesh([3, 4], [1.0, 2.0]);
        let mesh2 = Mesh::<Tri3, f64>::new(&rect).unwrap();
        let mut rng = crate::test_rng::uniform(7);
        for shape in shapes {
            for dim in [2, 3] {
                let cells = if dim == 3 { [3, 4, 2] } else { [3, 4, 1] };
                let mut s = spec(dim, cells, shape);
                if dim == 2 {
                    s.cell[2] = 1.0;
                }
                let (basis, x_of): (Cartesian, Vec<V3<f64>>) = if dim == 3 {
                    (Cartesian::new(s.clone(), &mesh3).unwrap(), mesh3.x.clone())
                } else {
                    (Cartesian::new(s.clone(), &mesh2).unwrap(), mesh2.x.clone())
                };
                let mut st = Stencil::<f64>::default();
                for t in 0..500 {
                    let mut x = [rng() + 0.5, 2.0 * (rng() + 0.5), 0.5 * (rng() + 0.5)];
                    if t % 10 == 0 {
                        x[t % 3] = 0.0;
                    }
                    if dim == 2 {
                        x[2] = 0.0;
                    }
                    basis.stencil_at(&x, &mut st);
                    let sum: f64 = st.weights().iter().sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{shape:?} {dim}D {x:?}");
                    for a in 0..dim {
                        let back: f64 = st
                            .nodes()
                            .iter()
                            .zip(st.weights())
                            .map(|(&n, w)| w * x_of[n as usize][a])
                            .sum();
                        assert!((back - x[a]).abs() < 1e-12, "{shape:?} {dim}D {x:?}");
                        for b in 0..dim {
                            let d: f64 = st
                                .nodes()
                                .iter()
                                .zip(st.gradients())
                                .map(|(&n, g)| g[b] * x_of[n as usize][a])
                                .sum();
                            let expect = if a == b { 1.0 } else { 0.0 };
                            assert!((d - expect).abs() < 1e-10, "{shape:?} {dim}D {x:?}");
                        }
                    }
                    let most = if shape == Shape::Linear { 2 } else { 3 };
                    assert!(st.len() <= most * most * if dim == 3 { most } else { 1 });
                }
            }
        }
    }

    /// A mesh whose nodes are not the lattice's is refused, naming the node.
    #[test]
    fn a_mesh_off_the_lattice_is_refused() {
        let box3 = generate::box_mesh([3, 4, 2], [1.0, 2.0, 0.5], ElementType::Tet4);
        let mesh = Mesh::<Tet4, f64>::new(&box3).unwrap();
        let coarse = spec(3, [2, 4, 2], Shape::Bspline2);
        let e = Cartesian::new(coarse, &mesh).unwrap_err();
        assert!(matches!(e, LatticeError::OffLattice { .. }), "{e}");
    }
}
