//! `[gravity]`: the body force, its ramp, and the ground surface of the K0 procedure.

use serde::Deserialize;

use super::keys::{key, Table};
use super::mesh::Mesh;
use super::{refuse, Refusal};

/// The keys of `[gravity]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[gravity]",
    about: "The gravity acceleration (none when the table is left out).",
    keys: &[
        key("vector", "[float, float, float]", "required", "m/s²", "the acceleration (z = 0 in a 2D section, which lies in the x-y plane)"),
        key("ramp", "float", "0 (sudden)", "s", "time to reach the full weight"),
        key("k0_surface", "float", "the highest node", "m", "height (y) of the ground surface for the K0 procedure (materials' `k0`)"),
    ],
};

/// `[gravity]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Gravity {
    pub vector: [f64; 3],
    #[serde(default)]
    pub ramp: f64,
    /// Height (y, m) of the ground surface for the K0 procedure; default: the highest node.
    #[serde(default)]
    pub k0_surface: Option<f64>,
}

/// Refuses a gravity out of the x-y plane of a 2D section.
pub(super) fn check_plane(gravity: Option<&Gravity>, mesh: &Mesh) -> Result<(), Refusal> {
    let two_d = mesh.model.dimension.coords() == 2;
    if let Some(g) = gravity.filter(|g| two_d && g.vector[2] != 0.0) {
        return Err(refuse(
            "gravity.vector",
            format!(
                "a 2D section lies in the x-y plane: its z component must be 0, got {}",
                g.vector[2]
            ),
        ));
    }
    Ok(())
}

/// The acceleration (m/s², zero without gravity) and its ramp (s).
pub(super) fn resolve(gravity: Option<&Gravity>) -> ([f64; 3], f64) {
    (
        gravity.map_or([0.0; 3], |g| g.vector),
        gravity.map_or(0.0, |g| g.ramp),
    )
}
