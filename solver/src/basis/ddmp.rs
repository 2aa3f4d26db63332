//! The dual-domain gradient on the mesh's own linear elements ([`Ddmp`], after Zhang, Ma &
//! Giguere 2011): a point keeps its element's shape functions as weights, but takes gradients
//! that are continuous across the elements' faces, so that a point crossing a face no longer
//! jumps from one element's constant gradients to the next one's (the cell-crossing error of
//! linear elements).
//!
//! Each node j holds, for every node i of the elements around it, the volume average of those
//! elements' gradients of N_i:
//!
//! G_ij = Σ_{e ∋ i, j} V_e ∇N_i|_e / Σ_{e ∋ j} V_e,
//!
//! and a point at x in element e takes ∇S_i(x) = α ∇N_i|_e + (1 − α) Σ_{c ∈ e} N_c(x) G_ci over
//! its corners c: a point then touches its element's corners' neighbours too (its reach: the
//! nodes of every element around a corner). With `blend`, α = (d + 1) min_c N_c(x) (1 at the
//! element's centroid, 0 on its faces: the gradient stays continuous where points cross, and
//! the element's own gradient resists the modes the averaged one alone leaves free); without,
//! α = 0. Σ_i ∇S_i = 0 and linear fields keep exact gradients (both G and ∇N_i|_e have these
//! properties), so momentum is conserved and a uniform strain is reproduced.

use crate::basis::{Basis, Stencil, MOST_NODES};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// The dual-domain gradients of a mesh.
#[derive(Debug, Clone)]
pub struct Ddmp {
    /// Each node's row: where its entries start in `column` and `average` (`nodes + 1`).
    row_start: Vec<u32>,
    /// Each entry's node i.
    column: Vec<u32>,
    /// Each entry's G_ij (of the row's node j).
    average: Vec<[f64; 3]>,
    /// Each element's reach: where its nodes start in `reach` (`elements + 1`).
    reach_start: Vec<u32>,
    /// Each element's nodes: its corners first, in order, then its corners' neighbours.
    reach: Vec<u32>,
    /// For each element, per corner in order, per entry of the corner's row: the entry's
    /// place in the element's reach (`slot_start[e]` onwards).
    slot: Vec<u8>,
    /// Where each element's slots start (`elements + 1`).
    slot_start: Vec<u32>,
    /// Blend with the element's own gradient (α = (d + 1) min N_c).
    blend: bool,
}

/// A mesh whose points would touch more nodes than a stencil holds.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "dual-domain gradients: element {element}'s points would touch {nodes} nodes, more than a \
     stencil's {most}; refine the mesh more evenly around it"
)]
pub struct DdmpError {
    /// The element (0-based, the solver's order).
    pub element: usize,
    /// Nodes its points would touch.
    pub nodes: usize,
    /// The most a stencil holds.
    pub most: usize,
}

impl Ddmp {
    /// The averages of `mesh` (α blended where `blend`).
    pub fn new<E: Element, R: Real>(mesh: &Mesh<E, R>, blend: bool) -> Result<Self, DdmpError> {
        let nodes = mesh.x.len();
        // Each node's elements, then its row: the nodes of those elements, each with its
        // volume-weighted gradient.
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); nodes];
        for e in 0..mesh.elements() {
            for &c in mesh.corners[e].as_ref() {
                around[c as usize].push(e as u32);
            }
        }
        let (mut row_start, mut column, mut average) = (vec![0u32], Vec::new(), Vec::new());
        for elements in &around {
            let first = column.len();
            let mut volume = 0.0;
            for &e in elements {
                let e = e as usize;
                let v = mesh.volume[e].f64();
                volume += v;
                for (&i, g) in mesh.corners[e].as_ref().iter().zip(mesh.grad[e].as_ref()) {
                    let at = match column[first..].iter().position(|&c| c == i) {
                        Some(k) => first + k,
                        None => {
                            column.push(i);
                            average.push([0.0; 3]);
                            column.len() - 1
                        }
                    };
                    for a in 0..3 {
                        average[at][a] += v * g[a].f64();
                    }
                }
            }
            for g in &mut average[first..] {
                *g = g.map(|c| if volume > 0.0 { c / volume } else { 0.0 });
            }
            row_start.push(column.len() as u32);
        }
        let mut out = Ddmp {
            row_start,
            column,
            average,
            reach_start: vec![0],
            reach: Vec::new(),
            slot: Vec::new(),
            slot_start: vec![0],
            blend,
        };
        for e in 0..mesh.elements() {
            let corners = mesh.corners[e].as_ref();
            let first = out.reach.len();
            out.reach.extend_from_slice(corners);
            for &c in corners {
                for k in out.row(c as usize) {
                    let i = out.column[k];
                    let slot = match out.reach[first..].iter().position(|&n| n == i) {
                        Some(s) => s,
                        None => {
                            out.reach.push(i);
                            out.reach.len() - 1 - first
                        }
                    };
                    if slot >= MOST_NODES {
                        return Err(DdmpError {
                            element: e,
                            nodes: out.reach.len() - first,
                            most: MOST_NODES,
                        });
                    }
                    out.slot.push(slot as u8);
                }
            }
            out.reach_start.push(out.reach.len() as u32);
            out.slot_start.push(out.slot.len() as u32);
        }
        Ok(out)
    }

    /// Node j's row's entries.
    fn row(&self, j: usize) -> std::ops::Range<usize> {
        self.row_start[j] as usize..self.row_start[j + 1] as usize
    }

    /// Bytes of the tables a stencil reads, per element (its reach, slots and their starts)
    /// and in all the nodes' rows (entries and their starts): for the traffic model.
    pub fn table_bytes(&self) -> (usize, usize) {
        let per_element = 4 * (self.reach.len() + 2 * self.reach_start.len()) + self.slot.len();
        let rows = 4 * (self.row_start.len() + self.column.len()) + 24 * self.average.len();
        (per_element, rows)
    }

    /// The most nodes an element's points touch.
    pub fn widest(&self) -> usize {
        self.reach_start
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }
}

impl<E: Element, R: Real> Basis<E, R> for Ddmp {
    const LINEAR: bool = false;

    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        out.clear();
        let n = mesh.shape(e, x);
        let n = n.as_ref();
        let corners = mesh.corners[e].as_ref();
        let reach = &self.reach[self.reach_start[e] as usize..self.reach_start[e + 1] as usize];
        let mut grad = [[0.0f64; 3]; MOST_NODES];
        let alpha = if self.blend {
            let least = n.iter().fold(f64::INFINITY, |m, v| m.min(v.f64()));
            ((E::NODES as f64) * least).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut slot = self.slot_start[e] as usize;
        for (k, &c) in corners.iter().enumerate() {
            let w = (1.0 - alpha) * n[k].f64();
            for entry in self.row(c as usize) {
                let g = &self.average[entry];
                let s = self.slot[slot] as usize;
                for a in 0..3 {
                    grad[s][a] += w * g[a];
                }
                slot += 1;
            }
        }
        let own = mesh.grad[e].as_ref();
        for (k, &node) in reach.iter().enumerate() {
            let mut g = grad[k];
            let weight = if k < E::NODES {
                for a in 0..3 {
                    g[a] += alpha * own[k][a].f64();
                }
                n[k]
            } else {
                R::ZERO
            };
            out.push(node, weight, g.map(R::of));
        }
    }

    fn reach(&self, _mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        out.clear();
        out.extend_from_slice(
            &self.reach[self.reach_start[e] as usize..self.reach_start[e + 1] as usize],
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::tet4::Tet4;
    use crate::element::tri3::Tri3;
    use mpm_shared::{generate, ElementType};

    /// Weights are the element's; gradients sum to zero and reproduce a linear field's
    /// gradient exactly, blended or not, at points all over every element (boundary elements
    /// too), in 3D and 2D.
    fn reproduces_linear_fields<E: Element>(mesh: &Mesh<E, f64>) {
        let mut rng = crate::test_rng::uniform(11);
        let mut st = Stencil::<f64>::default();
        for blend in [false, true] {
            let basis = Ddmp::new(mesh, blend).unwrap();
            assert!(basis.widest() <= MOST_NODES);
            for e in 0..mesh.elements() {
                let c = mesh.corners[e].as_ref();
                for _ in 0..4 {
                    let w: Vec<f64> = (0..E::NODES).map(|_| rng() + 0.51).collect();
                    let total: f64 = w.iter().sum();
                    let x: V3<f64> = std::array::from_fn(|a| {
                        (0..E::NODES)
                            .map(|k| w[k] / total * mesh.x[c[k] as usize][a])
                            .sum()
                    });
                    basis.stencil(mesh, e, &x, &mut st);
                    let sum: f64 = st.weights().iter().sum();
                    assert!((sum - 1.0).abs() < 1e-12);
                    for a in 0..E::DIM {
                        for b in 0..E::DIM {
                            // ∂x_a/∂x_b = Σ x_a,i ∂S_i/∂x_b.
                            let d: f64 = st
                                .nodes()
                                .iter()
                                .zip(st.gradients())
                                .map(|(&i, g)| mesh.x[i as usize][a] * g[b])
                                .sum();
                            let want = if a == b { 1.0 } else { 0.0 };
                            assert!((d - want).abs() < 1e-9, "e {e} blend {blend}: {d}");
                        }
                        let zero: f64 = st.gradients().iter().map(|g| g[a]).sum();
                        assert!(zero.abs() < 1e-9);
                    }
                }
            }
        }
    }

    #[test]
    fn gradients_reproduce_linear_fields_in_3d_and_2d() {
        let model = generate::box_mesh([3, 4, 2], [1.0, 2.0, 0.5], ElementType::Tet4);
        reproduces_linear_fields(&Mesh::<Tet4, f64>::new(&model).unwrap());
        let model = generate::rect_mesh([3, 5], [1.0, 2.0]);
        reproduces_linear_fields(&Mesh::<Tri3, f64>::new(&model).unwrap());
    }

    /// Unblended, a point on a face between two elements takes the same gradients from
    /// either side: the gradient is continuous where points cross.
    #[test]
    fn gradients_are_continuous_across_faces() {
        let model = generate::box_mesh([3, 3, 3], [1.0; 3], ElementType::Tet4);
        let mesh = Mesh::<Tet4, f64>::new(&model).unwrap();
        let basis = Ddmp::new(&mesh, false).unwrap();
        let (mut a, mut b) = (Stencil::<f64>::default(), Stencil::<f64>::default());
        let mut checked = 0;
        for e in 0..mesh.elements() {
            for (f, &across) in mesh.neighbour[e].iter().enumerate() {
                if across as usize >= mesh.elements() {
                    continue;
                }
                // The shared face's centroid.
                let other = mesh.corners[across as usize];
                let on: Vec<usize> = mesh.corners[e]
                    .iter()
                    .filter(|n| other.contains(n))
                    .map(|&n| n as usize)
                    .collect();
                assert_eq!(on.len(), 3);
                let x: V3<f64> =
                    std::array::from_fn(|d| on.iter().map(|&n| mesh.x[n][d]).sum::<f64>() / 3.0);
                basis.stencil(&mesh, e, &x, &mut a);
                basis.stencil(&mesh, across as usize, &x, &mut b);
                let of = |s: &Stencil<f64>, node: u32| {
                    s.nodes()
                        .iter()
                        .position(|&n| n == node)
                        .map_or([0.0; 3], |k| s.gradients()[k])
                };
                for &node in a.nodes().iter().chain(b.nodes()) {
                    let (ga, gb) = (of(&a, node), of(&b, node));
                    for d in 0..3 {
                        assert!((ga[d] - gb[d]).abs() < 1e-9, "e {e} face {f} node {node}");
                    }
                }
                checked += 1;
            }
        }
        assert!(checked > 100);
    }
}
