//! The critical time step of a case: the Courant number times the shortest time a wave takes
//! to cross an element. The engine steps with it and the pre-flight check predicts the step
//! count from it, so both read it from here.

use crate::input::case::{Case, CriticalStepRule, Drag};

/// The critical time step is not a positive number.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("critical time step is not positive ({dt})")]
pub struct TimeStepError {
    /// What it came to (s).
    pub dt: f64,
}

/// Courant number × min over `elements` (the case's numbering) of (smallest altitude / fastest
/// wave speed), in s; `min_altitude(e)` is element `e`'s smallest altitude (m). An error when it
/// is not positive and finite (a degenerate element, or a material without stiffness or mass).
pub fn critical(
    case: &Case,
    elements: std::ops::Range<usize>,
    min_altitude: impl Fn(usize) -> f64,
) -> Result<f64, TimeStepError> {
    let (_, crossing) = shortest_crossing(case, elements, min_altitude);
    let dt = case.time.courant * crossing;
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(TimeStepError { dt });
    }
    Ok(dt)
}

/// The element (the case's numbering) a wave crosses fastest, and that time (s): the critical
/// step is the Courant number times it. `(elements.start, ∞)` for no elements. Under
/// [`CriticalStepRule::OccupiedEachStep`] only the elements that hold points at the start count
/// (the engine takes the step again after every step: [`crate::step::time_step`]). Mass
/// scaling by f lengthens each crossing time by √f; the semi-implicit scheme takes the
/// skeleton's speed ([`crate::input::case::MaterialSpec::step_speed`]); bulk
/// viscosity shortens it by its factor at rest
/// ([`crate::step::bulk_viscosity::BulkViscosity::step_factor`]).
pub fn shortest_crossing(
    case: &Case,
    elements: std::ops::Range<usize>,
    min_altitude: impl Fn(usize) -> f64,
) -> (usize, f64) {
    // Empty elements may fill: they take the fastest material's speed. An explicit drag must
    // be resolved by the step too: Mieremet's speed has its term.
    let anura3d_step = case.time.anura3d_time_step || case.numerics.drag == Drag::Explicit;
    let mut best = (elements.start, f64::INFINITY);
    let occupied_only = case.time.critical_step == CriticalStepRule::OccupiedEachStep;
    let semi = case.numerics.scheme.semi_implicit();
    for e in elements {
        if occupied_only && case.body.points_per_element[e] == 0 {
            // Anura3D's rule: only elements that hold points count.
            continue;
        }
        let dx = min_altitude(e);
        let m = case.body.element_material[e] as usize;
        let c = match case.body.materials.get(m).and_then(|s| s.as_ref()) {
            Some(s) => s.step_speed(dx, anura3d_step, semi),
            None => case
                .body
                .materials
                .iter()
                .flatten()
                .map(|s| s.step_speed(dx, anura3d_step, semi))
                .fold(0.0, f64::max),
        };
        // Mass scaling slows every wave by √f (Anura3D's c² / f); dividing by 1 changes no bit.
        let mut t = dx / (c / case.numerics.mass_scaling.sqrt());
        if let Some(b) = &case.numerics.bulk_viscosity {
            // Bulk viscosity shortens the step; the points are at rest here.
            t *= b.step_factor(t, 0.0);
        }
        // `<` keeps the first of equal ones and skips a NaN, as `f64::min` did.
        if t < best.1 {
            best = (e, t);
        }
    }
    best
}
