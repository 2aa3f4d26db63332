//! The basis the point passes map with: for a material point, the nodes it touches, its
//! weight N_k at each and the gradient ∇N_k there. This is the seam between the passes and
//! the functions they interpolate with.
//!
//! A [`Basis`] hands the passes a point's [`Stencil`]: its nodes, as many as the basis needs
//! (the linear element's three or four corners; 9 or 27 on a background grid's quadratic
//! B-splines, 64 on cubic ones, a variable count under GIMP), with a weight and a gradient
//! per node. Particle to grid and grid to particle are written once over a stencil
//! ([`crate::step::particle_to_grid`], [`crate::step::grid_to_particle`]): each point's share
//! of each node is formed by the same small functions as in the element kernels, the nodes
//! taken four at a time in the lanes of [`crate::four::Lanes4`].
//!
//! The linear element ([`linear::Linear`], the tetrahedron and the triangle of
//! [`crate::element`]) is the first basis, and has fast paths the others do not: its stencil is
//! its element's corners, its weights the element's shape functions and its gradients one per
//! element ([`Basis::LINEAR`]). The passes then take its points element by element in the
//! element kernels, which form once per element what is the same at each of its points (the
//! internal force's Σ V σ times the element's gradients, the weight of a material's points
//! from their mass sum) and hold an element's nodes or points in four-lane vectors
//! (docs/design.md §9); the stress pass, the pore-pressure rate and the mixed integration need
//! one gradient per element, and take only this basis.
//!
//! A basis of its own ([`Basis::LINEAR`] false) goes through the stencil passes, on the team:
//! each thread sums its own range of nodes over the points within reach of them, in point order
//! ([`crate::parallel::reach`], [`Basis::reach`]), so that the sums are the same bits for any
//! thread count. The background grid ([`grid::Cartesian`]) is such a basis; a test basis whose
//! points touch their element's and its neighbours' nodes proves the seam (`spread`).

pub mod background;
pub mod ddmp;
pub mod grid;
pub mod linear;
pub mod spline;

#[cfg(test)]
pub mod spread;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// Most nodes one point's stencil holds: a cubic B-spline's 4 × 4 × 4.
pub const MOST_NODES: usize = 64;

/// The functions the point passes interpolate with, on mesh `Mesh<E, R>`.
pub trait Basis<E: Element, R: Real>: Sync {
    /// Whether this is the mesh's own linear element (a point of element e touches exactly e's
    /// corners, with e's shape functions and e's gradients, one per element): the passes then
    /// take the element kernels.
    const LINEAR: bool;

    /// The stencil of the point at `x` in element `e` into `out` (cleared first).
    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>);

    /// Every node a point of element `e` may touch, wherever in `e` it lies, into `out`
    /// (cleared first; a node at most once): what the parallel sum of
    /// [`crate::parallel::reach`] hands each element to.
    fn reach(&self, mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>);
}

/// One point's nodes, with its weight and the gradient of its weight at each (up to
/// [`MOST_NODES`]), in the order the basis gives them.
#[derive(Debug, Clone)]
pub struct Stencil<R: Real> {
    len: usize,
    nodes: [u32; MOST_NODES],
    weights: [R; MOST_NODES],
    gradients: [V3<R>; MOST_NODES],
}

impl<R: Real> Default for Stencil<R> {
    fn default() -> Self {
        Stencil {
            len: 0,
            nodes: [0; MOST_NODES],
            weights: [R::ZERO; MOST_NODES],
            gradients: [[R::ZERO; 3]; MOST_NODES],
        }
    }
}

impl<R: Real> Stencil<R> {
    /// No nodes.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Adds `node` with weight `n` and gradient `grad`.
    ///
    /// # Panics
    /// Past [`MOST_NODES`] nodes.
    pub fn push(&mut self, node: u32, n: R, grad: V3<R>) {
        assert!(self.len < MOST_NODES, "a stencil past {MOST_NODES} nodes");
        self.nodes[self.len] = node;
        self.weights[self.len] = n;
        self.gradients[self.len] = grad;
        self.len += 1;
    }

    /// The nodes.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes[..self.len]
    }

    /// The weight at each node.
    pub fn weights(&self) -> &[R] {
        &self.weights[..self.len]
    }

    /// The weight's gradient at each node.
    pub fn gradients(&self) -> &[V3<R>] {
        &self.gradients[..self.len]
    }

    /// How many nodes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}
