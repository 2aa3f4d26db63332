//! What every point pass shares ([`Passes`]): the thread team, the data layout, the mesh, the
//! communicator and the basis the points map with. Each pass takes it beside a small struct of
//! its own inputs.

use crate::basis::linear::Linear;
use crate::basis::Basis;
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::comm::Communicator;
use crate::parallel::gather::Layout;
use crate::parallel::reach::Reach;
use crate::parallel::team::Team;
use crate::real::Real;

/// The context of the point passes: who runs them, on what, and with which basis (the mesh's
/// linear elements unless told otherwise, [`Passes::with_basis`]).
pub struct Passes<'a, R: Real, E: Element, B = Linear> {
    /// The thread team.
    pub team: &'a Team,
    /// Points sorted by element, each thread's elements, the scatter's slots' map.
    pub layout: &'a Layout<R, E>,
    /// The mesh.
    pub mesh: &'a Mesh<E, R>,
    /// The other processes (one process: [`crate::parallel::comm::SingleProcess`]).
    pub comm: &'a dyn Communicator,
    /// The functions the points interpolate with.
    pub basis: &'a B,
    /// Who sums which nodes under a basis of its own ([`Passes::with_basis`]); `None` for the
    /// linear elements, whose sums go through [`Layout`]'s scatter.
    pub reach: Option<&'a Reach>,
}

impl<R: Real, E: Element, B> Clone for Passes<'_, R, E, B> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<R: Real, E: Element, B> Copy for Passes<'_, R, E, B> {}

impl<'a, R: Real, E: Element> Passes<'a, R, E> {
    /// The passes on `mesh`'s linear elements.
    pub fn new(
        team: &'a Team,
        layout: &'a Layout<R, E>,
        mesh: &'a Mesh<E, R>,
        comm: &'a dyn Communicator,
    ) -> Self {
        Passes {
            team,
            layout,
            mesh,
            comm,
            basis: &Linear,
            reach: None,
        }
    }
}

impl<'a, R: Real, E: Element, B: Basis<E, R>> Passes<'a, R, E, B> {
    /// The same passes with `basis`, whose sums the threads split as `reach` says (built for
    /// this basis, mesh and team).
    pub fn with_basis<C: Basis<E, R>>(self, basis: &'a C, reach: &'a Reach) -> Passes<'a, R, E, C> {
        debug_assert_eq!(reach.threads(), self.team.threads);
        Passes {
            team: self.team,
            layout: self.layout,
            mesh: self.mesh,
            comm: self.comm,
            basis,
            reach: Some(reach),
        }
    }

    /// The reach of a basis of its own.
    ///
    /// # Panics
    /// On the linear elements' passes ([`Passes::new`]), which have none.
    pub fn reach(&self) -> &'a Reach {
        self.reach
            .expect("a basis of its own's passes carry its reach (Passes::with_basis)")
    }
}
