//! `[consolidation]`: a one-material consolidation run compared with Terzaghi, its start
//! state, and its times given by time factor.

use serde::Deserialize;

use mpm_shared::Model;

use super::keys::{key, Table};
use super::material::Materials;
use super::{refuse, Refusal};
use crate::input::case::{ConsolidationSpec, MaterialSpec, Start, UndrainedState};

/// The keys of `[consolidation]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[consolidation]",
    about: "Compare the run with Terzaghi's consolidation (one saturated material, loaded on \
            its drained top); writes consolidation.csv.",
    keys: &[
        key("load", "float", "required", "kPa", "the top load (compression positive), as the scene's traction applies it"),
        key("start", "string", "\"undrained\"", "", "\"undrained\" (Terzaghi's state at t = 0+) or \"rest\" (at rest, the load applied suddenly)"),
        key("compare_rest", "bool", "false", "", "also run from rest and report both"),
        key("output_tv", "float", "none", "", "time factor between outputs (sets `time.output_interval`)"),
        key("end_tv", "float", "none", "", "final time factor (sets `time.end`)"),
    ],
};

/// `[consolidation]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Consolidation {
    /// Top load (kPa, compression positive), as applied by the scene's traction.
    load: f64,
    /// "undrained" (default) or "rest".
    #[serde(default = "default_start")]
    start: String,
    /// Also run the workshop-style configuration (at rest, sudden load) and report both.
    #[serde(default)]
    compare_rest: bool,
    /// Time factor between outputs (sets time.output_interval).
    #[serde(default)]
    output_tv: Option<f64>,
    /// Final time factor (sets time.end).
    #[serde(default)]
    end_tv: Option<f64>,
}

fn default_start() -> String {
    "undrained".into()
}

/// The run's consolidation settings, `None` for an ordinary run.
pub(super) fn resolve(c: Option<&Consolidation>) -> Result<Option<ConsolidationSpec>, Refusal> {
    let Some(c) = c else { return Ok(None) };
    let start = match c.start.as_str() {
        "undrained" => Start::Undrained,
        "rest" => Start::Rest,
        other => {
            return Err(refuse(
                "consolidation.start",
                format!("expected \"undrained\" or \"rest\", got \"{other}\""),
            ))
        }
    };
    if !(c.load > 0.0) {
        return Err(refuse(
            "consolidation.load",
            format!("must be positive, got {}", c.load),
        ));
    }
    Ok(Some(ConsolidationSpec {
        load: c.load,
        start,
        compare_rest: c.compare_rest,
    }))
}

/// The end time and output interval (s) that the time factors `end_tv` and `output_tv` give
/// (c_v of the saturated material, the drainage length the column's height); `None` for those
/// not given.
pub(super) fn times(
    c: Option<&Consolidation>,
    materials: &Materials,
    model: &Model,
) -> Result<(Option<f64>, Option<f64>), Refusal> {
    let Some(c) = c else { return Ok((None, None)) };
    let by_tv = |tv: Option<f64>| -> Result<Option<f64>, Refusal> {
        let Some(tv) = tv else { return Ok(None) };
        let m = the_saturated(&materials.specs).ok_or_else(|| {
            refuse(
                "consolidation",
                "times by time factor need exactly one saturated material",
            )
        })?;
        let cv = m
            .liquid
            .as_ref()
            .expect("saturated")
            .consolidation_coefficient(m.oedometric());
        let (lo, hi) = model
            .coords
            .chunks_exact(3)
            .fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p[1]), h.max(p[1])));
        Ok(Some(tv * (hi - lo) * (hi - lo) / cv))
    };
    Ok((by_tv(c.end_tv)?, by_tv(c.output_tv)?))
}

/// The saturated points' undrained start (a consolidation run from `"undrained"`), resolved
/// here; `None` otherwise.
pub(super) fn initial_state(
    spec: Option<&ConsolidationSpec>,
    materials: &Materials,
) -> Result<Option<UndrainedState>, Refusal> {
    match spec {
        Some(c) if c.start == Start::Undrained => {
            let m = the_saturated(&materials.specs).ok_or_else(|| {
                refuse(
                    "consolidation",
                    "a consolidation run needs exactly one saturated material",
                )
            })?;
            Ok(UndrainedState::under(m, c.load))
        }
        _ => Ok(None),
    }
}

/// The one saturated material of a consolidation scene, `None` when there are none or several.
fn the_saturated(materials: &[Option<MaterialSpec>]) -> Option<&MaterialSpec> {
    let mut sat = materials.iter().flatten().filter(|m| m.liquid.is_some());
    match (sat.next(), sat.next()) {
        (Some(m), None) => Some(m),
        _ => None,
    }
}
