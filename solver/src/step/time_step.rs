//! Anura3D's critical time step, formed again after every step (GOM input): the Courant number
//! times the shortest time a wave takes to cross an element that holds material points, the
//! wave speed that of the fastest material among the element's points, over the element's
//! smallest altitude in the initial mesh. Empty elements do not count, and a point that moves
//! into a smaller element shortens the next step. (Scenes take the step once, over every
//! element, empty ones at the fastest material's speed: [`crate::input::time_step`].)
//!
//! One pass over the points, each thread over its own range; a thread skips the points that
//! share the last one's element and material, so the work is about one division per element.
//! The minimum does not depend on how the points are split among the threads. With bulk
//! viscosity each point's crossing time shrinks by the factor of its volumetric strain rate
//! (Anura3D's, which takes an element's last point's rate; the points of a linear element
//! share it, but for an axisymmetric section's hoop term). Mass scaling by f slows every wave
//! by √f (Anura3D's c² / f).

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::input::case::{Case, MaterialSpec};
use crate::parallel::gather::Layout;
use crate::parallel::team::{Shared, Team};
use crate::real::Real;
use crate::state::particles::Particles;
use crate::step::bulk_viscosity::BulkViscosity;

/// Anura3D's floor on the step (s).
pub const SHORTEST_STEP: f64 = 1e-10;

/// The per-step critical time step of a run.
#[derive(Debug, Clone)]
pub struct CriticalStep {
    /// Per material index, what its wave speed is computed from.
    materials: Vec<Option<MaterialSpec>>,
    /// Anura3D's two-phase wave speed (see [`MaterialSpec::wave_speed_at`]).
    anura3d_speed: bool,
    /// With bulk viscosity, each point's crossing time shrinks by its factor at the point's
    /// volumetric strain rate.
    bulk: Option<BulkViscosity>,
    /// √f of mass scaling by f (1 without): every wave speed over it.
    scaling_root: f64,
    /// The semi-implicit scheme: saturated materials at their skeleton's speed.
    semi_implicit: bool,
    /// Per thread: the shortest crossing time of its points' elements and that element.
    per_thread: Vec<(f64, u32)>,
}

impl CriticalStep {
    /// The rule for `case`, with one result slot per thread of a team of `threads`.
    pub fn new(case: &Case, threads: usize) -> Self {
        CriticalStep {
            materials: case.body.materials.clone(),
            anura3d_speed: case.time.anura3d_time_step
                || case.numerics.drag == crate::input::case::Drag::Explicit,
            per_thread: vec![(f64::INFINITY, 0); threads],
            bulk: case.numerics.bulk_viscosity,
            scaling_root: case.numerics.mass_scaling.sqrt(),
            semi_implicit: case.numerics.scheme.semi_implicit(),
        }
    }

    /// The shortest time a wave takes to cross an element holding active points of this
    /// process, and that element (local index); infinite when it holds none.
    pub fn shortest_crossing<E: Element, R: Real>(
        &mut self,
        team: &Team,
        layout: &Layout<R, E>,
        mesh: &Mesh<E, R>,
        p: &Particles<R>,
    ) -> (f64, u32) {
        if self.per_thread.len() != team.threads {
            // A new team (a core was taken): its slots, once.
            self.per_thread = vec![(f64::INFINITY, 0); team.threads];
        }
        let slots = Shared::new(&mut self.per_thread);
        let (materials, anura3d, bulk) = (&self.materials, self.anura3d_speed, self.bulk);
        let (root, semi) = (self.scaling_root, self.semi_implicit);
        let rates = p.bulk.as_ref().map(|b| &b.rate[..]);
        team.run(|t| {
            let mut best = (f64::INFINITY, 0u32);
            let mut last = (u32::MAX, u32::MAX);
            for i in layout.particle_range(t) {
                if !p.active[i] {
                    continue;
                }
                let (e, m) = (p.element[i], p.material[i]);
                // (With bulk viscosity each point's own rate counts.)
                if (e, m) == last && bulk.is_none() {
                    continue;
                }
                last = (e, m);
                let Some(spec) = materials.get(m as usize).and_then(Option::as_ref) else {
                    continue;
                };
                let dx = mesh.min_altitude[e as usize].f64();
                let mut time = dx / (spec.step_speed(dx, anura3d, semi) / root);
                if let (Some(b), Some(rates)) = (&bulk, rates) {
                    time *= b.step_factor(time, rates[i].f64());
                }
                if time < best.0 || (time == best.0 && e < best.1) {
                    best = (time, e);
                }
            }
            // SAFETY: thread t alone writes slot t.
            unsafe { slots.write(t, best) };
        });
        self.per_thread
            .iter()
            .copied()
            .fold((f64::INFINITY, 0), |a, b| {
                if b.0 < a.0 || (b.0 == a.0 && b.1 < a.1) {
                    b
                } else {
                    a
                }
            })
    }
}

/// The step Anura3D takes for the shortest crossing time `crossing` at Courant number `courant`.
pub fn step_of(courant: f64, crossing: f64) -> f64 {
    (courant * crossing).max(SHORTEST_STEP)
}
