//! `[gravity]`: the body force, its ramp, and the ground surface of the K0 procedure.

use serde::Deserialize;

use super::keys::{key, Table};
use super::mesh::Mesh;
use super::{refuse, Refusal};
use crate::step::load_curve::LoadCurve;

/// The keys of `[gravity]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[gravity]",
    about: "The gravity acceleration (none when the table is left out).",
    keys: &[
        key("vector", "[float, float, float]", "required", "m/s²", "the acceleration (z = 0 in a 2D section, which lies in the x-y plane)"),
        key("ramp", "float", "0 (sudden)", "s", "time to reach the full weight"),
        key("curve", "[[float, float], ...] or string", "none", "s, –", super::curve::CURVE_HELP),
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
    /// A multiplier over time instead of the ramp.
    #[serde(default)]
    pub curve: Option<toml::Value>,
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

/// The acceleration (m/s², zero without gravity) and its multiplier over time (its ramp's,
/// or the `curve` given, a CSV file relative to `scene_dir`).
pub(super) fn resolve(
    gravity: Option<&Gravity>,
    scene_dir: &std::path::Path,
) -> Result<([f64; 3], LoadCurve), Refusal> {
    let Some(g) = gravity else {
        return Ok(([0.0; 3], LoadCurve::Step));
    };
    let curve = match &g.curve {
        Some(_) if g.ramp != 0.0 => {
            return Err(refuse("gravity", "give a ramp or a curve, not both"))
        }
        Some(v) => super::curve::resolve(v, scene_dir, "gravity.curve")?,
        None => LoadCurve::ramp(g.ramp),
    };
    Ok((g.vector, curve))
}
