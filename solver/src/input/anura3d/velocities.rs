//! Prescribed velocities of a case: on material points (`$$PRESCRIBED_MATERIAL_POINT_VELOCITY_*`)
//! and on nodes (`$$PRESCRIBED_NODAL_VELOCITY_*`), under the CPS `$$PRESCRIBED_VELOCITY`
//! multiplier.

use mpm_shared::cps::Multiplier;

use super::{curve, unsupported, CaseError, Input, LoadSteps};
use crate::input::case::MaterialSpec;
use crate::step::nodal_velocity::NodalVelocitySet;
use crate::step::prescribed::PrescribedVelocity;

/// The prescribed material-point velocities of the GOM with the CPS `$$PRESCRIBED_VELOCITY`
/// multiplier; `None` when there are none or the multiplier is `off` (Anura3D then ignores the
/// rows).
pub(super) fn on_points(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    steps: LoadSteps,
) -> Result<Option<PrescribedVelocity>, CaseError> {
    let (model, s) = (&input.model, &input.settings);
    let (gfile, cfile) = (input.gfile.as_str(), input.cfile.as_str());
    let rows = crate::step::prescribed::read_rows(model)
        .map_err(|(item, message)| unsupported(gfile, &item, message))?;
    if rows.is_empty() {
        return Ok(None);
    }
    if s.prescribed_velocity == Multiplier::Off {
        log::warn!("{gfile}: the prescribed material-point velocities are not applied: $$PRESCRIBED_VELOCITY is off in {cfile}");
        return Ok(None);
    }
    if materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return Err(unsupported(
            gfile,
            "$$PRESCRIBED_MATERIAL_POINT_VELOCITY",
            "prescribed velocities are not supported yet in cases with a saturated material",
        ));
    }
    let (scale, curve) = curve(s.prescribed_velocity, steps, cfile, "$$PRESCRIBED_VELOCITY")?;
    Ok(Some(PrescribedVelocity {
        name: crate::step::prescribed::SECTIONS
            .iter()
            .find(|k| model.sections.iter().any(|s| s.keyword == **k))
            .map_or(String::new(), |k| format!("$${k}")),
        rows,
        scale,
        curve,
    }))
}

/// The prescribed nodal velocities of the GOM (one set, named by its section) with the CPS
/// `$$PRESCRIBED_VELOCITY` multiplier; none when there are none or the multiplier is `off`.
pub(super) fn on_nodes(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    steps: LoadSteps,
) -> Result<Vec<NodalVelocitySet>, CaseError> {
    let s = &input.settings;
    let (gfile, cfile) = (input.gfile.as_str(), input.cfile.as_str());
    let Some((keyword, rows)) = crate::step::nodal_velocity::read_rows(&input.model)
        .map_err(|(item, message)| unsupported(gfile, &item, message))?
    else {
        return Ok(Vec::new());
    };
    let name = format!("$${keyword}");
    if s.prescribed_velocity == Multiplier::Off {
        log::warn!("{gfile}: the prescribed nodal velocities are not applied: $$PRESCRIBED_VELOCITY is off in {cfile}");
        return Ok(Vec::new());
    }
    if materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return Err(unsupported(
            gfile,
            &name,
            "prescribed velocities are not supported yet in cases with a saturated material",
        ));
    }
    let (scale, curve) = curve(s.prescribed_velocity, steps, cfile, "$$PRESCRIBED_VELOCITY")?;
    Ok(vec![NodalVelocitySet {
        name,
        rows,
        scale,
        curve,
    }])
}
