//! Constraints on a step's nodes and points behind one interface: rigid walls, velocities
//! prescribed on points or nodes, contact between two bodies, the moving mesh, and whatever
//! boundary comes next (absorbing boundaries) (docs/design.md §4.16).
//!
//! A constraint acts at fixed hook points of the step (see [`Constraint`]); the engine holds the
//! case's constraints in a [`Constraints`] list, in the order their hooks run, and calls each
//! hook on all of them. A case pays only for the constraints it has: a list without any is a
//! loop over nothing. Fixities are not constraints here: they are masks the grid update and the
//! re-mapping read per node (so are the velocities prescribed on nodes, which mark themselves
//! fixed at set-up and set their values through the hooks).

use std::any::Any;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::gather::Layout;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::moment::Moment;
use crate::step::reaction::Reaction;

/// What a constraint's hook may read and change: the bodies' nodal arrays, the points, the
/// mesh (which the moving mesh moves), the reactions, and the step's loads and fixities.
pub struct Hook<'a, R: Real, E: Element> {
    /// The step's clock and load multipliers.
    pub at: &'a Moment<R>,
    /// The computational mesh.
    pub mesh: &'a mut Mesh<E, R>,
    /// The threads' ranges of elements and points.
    pub layout: &'a Layout<R, E>,
    /// The material points.
    pub particles: &'a mut Particles<R>,
    /// The soil's nodal arrays (every point's, without a second body).
    pub soil: &'a mut Grid<R>,
    /// The structure's nodal arrays, in a run with contact.
    pub structure: Option<&'a mut Grid<R>>,
    /// Fixed components per node.
    pub fixed: &'a [[bool; 3]],
    /// The liquid's fixed components per node (two-phase cases).
    pub liquid_fixed: &'a [[bool; 3]],
    /// Face-load forces per node at multiplier 1 (with contact, the soil's).
    pub traction: &'a [V3<R>],
    /// With contact, the face loads on the structure's nodes at multiplier 1 (empty without).
    pub structure_traction: &'a [V3<R>],
    /// The prescribed-velocity sets' reactions, in the case's order.
    pub reactions: &'a mut [Reaction],
}

/// A constraint on the step. Its hooks run at fixed points of the step, each after the phase
/// it names and before the next one; every hook but the one it needs is a no-op by default.
///
/// - [`Constraint::after_grid_update`]: the nodes' accelerations are known (and the force
///   sums taken), the points have not moved: velocity constraints act on accelerations and on
///   the points' velocities.
/// - [`Constraint::after_remap`]: the points took the nodes' velocities and the nodal
///   velocities were mapped back from them: constraints set the nodal velocities the strains
///   are computed with.
/// - [`Constraint::after_move`]: the points moved and took their stresses, not yet located:
///   the mesh may move under them.
///
/// Between steps, [`Constraint::follow`] tells a constraint that holds point indices that the
/// points were re-sorted, and [`Constraint::saved`] / [`Constraint::restore`] carry its state
/// through a checkpoint.
pub trait Constraint<R: Real, E: Element>: std::fmt::Debug + Send + Sync {
    /// The constraint's name, for messages and for its state in a checkpoint.
    fn name(&self) -> &'static str;

    /// After the grid update.
    fn after_grid_update(&mut self, _cx: &mut Hook<'_, R, E>) {}

    /// After the points took the nodal velocities and those were mapped back.
    fn after_remap(&mut self, _cx: &mut Hook<'_, R, E>) {}

    /// After the points moved. An error is the local element the move turned inside out.
    fn after_move(&mut self, _cx: &mut Hook<'_, R, E>) -> Result<(), usize> {
        Ok(())
    }

    /// Whether the constraint moves the mesh (the points are then located after it moved, not
    /// as they move).
    fn moves_mesh(&self) -> bool {
        false
    }

    /// Whether the constraint holds point indices (then [`Constraint::follow`] must be told of
    /// every re-sort).
    fn holds_points(&self) -> bool {
        false
    }

    /// The points were re-sorted: point `i` is now `new_of_old[i]`.
    fn follow(&mut self, _new_of_old: &[u32]) {}

    /// The state a resumed run needs (none by default).
    fn saved(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Takes back the state of [`Constraint::saved`] on an engine just set up; false when it
    /// does not fit.
    fn restore(&mut self, _mesh: &mut Mesh<E, R>, state: &[f64]) -> bool {
        state.is_empty()
    }

    /// The constraint as [`Any`], for [`Constraints::find`].
    fn as_any(&self) -> &dyn Any;
}

/// The constraints of a run, in the order their hooks run.
#[derive(Debug, Default)]
pub struct Constraints<R: Real, E: Element> {
    list: Vec<Box<dyn Constraint<R, E>>>,
}

impl<R: Real, E: Element> Constraints<R, E> {
    /// A list with nothing in it.
    pub fn new() -> Self {
        Constraints { list: Vec::new() }
    }

    /// Adds `c` after the others (its hooks run after theirs).
    pub fn push(&mut self, c: impl Constraint<R, E> + 'static) {
        self.list.push(Box::new(c));
    }

    /// Puts `c` in the place of the constraint of its type (its hooks keep their turn); false
    /// when the list has none of that type.
    pub fn replace<T: Constraint<R, E> + 'static>(&mut self, c: T) -> bool {
        match self.list.iter_mut().find(|x| x.as_any().is::<T>()) {
            Some(slot) => {
                *slot = Box::new(c);
                true
            }
            None => false,
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The constraints, in hook order.
    pub fn iter(&self) -> impl Iterator<Item = &dyn Constraint<R, E>> {
        self.list.iter().map(|c| &**c)
    }

    /// The first constraint of type `T`, if any.
    pub fn find<T: 'static>(&self) -> Option<&T> {
        self.list
            .iter()
            .find_map(|c| c.as_any().downcast_ref::<T>())
    }

    /// Runs every [`Constraint::after_grid_update`] in order.
    pub fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        for c in &mut self.list {
            c.after_grid_update(cx);
        }
    }

    /// Runs every [`Constraint::after_remap`] in order.
    pub fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        for c in &mut self.list {
            c.after_remap(cx);
        }
    }

    /// Runs every [`Constraint::after_move`] in order, stopping at the first error.
    pub fn after_move(&mut self, cx: &mut Hook<'_, R, E>) -> Result<(), usize> {
        self.list.iter_mut().try_for_each(|c| c.after_move(cx))
    }

    /// Whether any constraint moves the mesh.
    pub fn move_mesh(&self) -> bool {
        self.list.iter().any(|c| c.moves_mesh())
    }

    /// Whether any constraint holds point indices.
    pub fn hold_points(&self) -> bool {
        self.list.iter().any(|c| c.holds_points())
    }

    /// Tells every constraint that holds point indices of a re-sort.
    pub fn follow(&mut self, new_of_old: &[u32]) {
        for c in &mut self.list {
            c.follow(new_of_old);
        }
    }

    /// Each constraint's state for a checkpoint, as (its name, value), in list order.
    pub fn saved(&self) -> Vec<(&'static str, f64)> {
        self.list
            .iter()
            .flat_map(|c| c.saved().into_iter().map(|x| (c.name(), x)))
            .collect()
    }

    /// Takes back [`Constraints::saved`]: `state`'s values in list order, each constraint's
    /// under its name. False when they do not fit the constraints.
    pub fn restore(&mut self, mesh: &mut Mesh<E, R>, state: &[(&str, f64)]) -> bool {
        let mut at = 0;
        for c in &mut self.list {
            let name = c.name();
            let n = state[at..].iter().take_while(|(k, _)| *k == name).count();
            let values: Vec<f64> = state[at..at + n].iter().map(|&(_, x)| x).collect();
            if !c.restore(mesh, &values) {
                return false;
            }
            at += n;
        }
        at == state.len()
    }
}
