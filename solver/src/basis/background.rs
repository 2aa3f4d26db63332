//! The basis a case's points map with when it is not the mesh's linear elements
//! ([`Background`]): a background grid's splines, or the dual-domain gradients on the mesh's
//! own elements. One value chosen at set-up; the passes take it as any [`Basis`].

use crate::basis::ddmp::Ddmp;
use crate::basis::grid::Cartesian;
use crate::basis::{Basis, Stencil};
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::real::{Real, V3};

/// A basis of its own (not the element kernels').
#[derive(Debug, Clone)]
pub enum Background {
    /// A background grid's functions (the scene's `[grid]`).
    Grid(Cartesian),
    /// The dual-domain gradients on the mesh's elements (the scene's `gradient = "ddmp"`).
    Ddmp(Ddmp),
}

impl Background {
    /// The background grid, if this is one.
    pub fn grid(&self) -> Option<&Cartesian> {
        match self {
            Background::Grid(g) => Some(g),
            Background::Ddmp(_) => None,
        }
    }

    /// Bytes of the tables a stencil reads: in all the elements (read once per element whose
    /// points a pass visits) and in all the nodes (gathered, read once per node).
    pub fn table_bytes(&self) -> (usize, usize) {
        match self {
            Background::Grid(g) => (0, g.table_bytes()),
            Background::Ddmp(d) => d.table_bytes(),
        }
    }
}

impl<E: Element, R: Real> Basis<E, R> for Background {
    const LINEAR: bool = false;

    #[inline]
    fn stencil(&self, mesh: &Mesh<E, R>, e: usize, x: &V3<R>, out: &mut Stencil<R>) {
        match self {
            Background::Grid(g) => g.stencil(mesh, e, x, out),
            Background::Ddmp(d) => d.stencil(mesh, e, x, out),
        }
    }

    fn reach(&self, mesh: &Mesh<E, R>, e: usize, out: &mut Vec<u32>) {
        match self {
            Background::Grid(g) => g.reach(mesh, e, out),
            Background::Ddmp(d) => d.reach(mesh, e, out),
        }
    }
}
