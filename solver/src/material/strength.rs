//! The strength parameters of the Mohr–Coulomb laws (friction angle φ, dilatancy angle ψ,
//! cohesion c): their ranges and checks, shared by [`crate::material::mohr_coulomb`] and
//! [`crate::material::strain_softening_mohr_coulomb`] (its peak and residual strengths).

use crate::material::definition::{Bound, ParameterError};

/// A friction angle's range on its own.
pub const FRICTION: (Bound, Bound) = (Bound::Closed(0.0), Bound::Open(90.0));
/// A dilatancy angle's range on its own (it is at most the friction angle).
pub const DILATANCY: (Bound, Bound) = (Bound::Closed(0.0), Bound::Open(90.0));
/// A cohesion's (or a shape factor's) range.
pub const NON_NEGATIVE: (Bound, Bound) = (Bound::Closed(0.0), Bound::Open(f64::INFINITY));

/// Checks a friction angle, a dilatancy angle no larger and a cohesion (`what`: "peak ",
/// "residual " or "").
pub fn check_strength(
    what: &str,
    friction: f64,
    dilatancy: f64,
    cohesion: f64,
) -> Result<(), ParameterError> {
    if !(0.0..90.0).contains(&friction) {
        return Err(ParameterError(format!(
            "{what}friction angle must be in [0, 90) degrees, got {friction}"
        )));
    }
    if !(dilatancy >= 0.0 && dilatancy <= friction) {
        return Err(ParameterError(format!(
            "{what}dilatancy angle must be in [0, {what}friction angle {friction}] degrees, got {dilatancy}"
        )));
    }
    if !(cohesion >= 0.0 && cohesion.is_finite()) {
        return Err(ParameterError(format!(
            "{what}cohesion must be non-negative, got {cohesion}"
        )));
    }
    Ok(())
}
