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
/// rows). In a case with a saturated material they are modelled `with_contact` only.
pub(super) fn on_points(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    steps: LoadSteps,
    with_contact: bool,
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
    // With contact they drive the (dry) structure, whose nodes are its own.
    if !with_contact && materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return Err(unsupported(
            gfile,
            "$$PRESCRIBED_MATERIAL_POINT_VELOCITY",
            "prescribed velocities are not supported yet in cases with a saturated material (except on a dry structure with contact, $$CONTACT_FORMULATION 1)",
        ));
    }
    let (scale, curve) = velocity_curve(s.prescribed_velocity, steps, cfile)?;
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
    let (scale, curve) = velocity_curve(s.prescribed_velocity, steps, cfile)?;
    Ok(vec![NodalVelocitySet {
        name,
        rows,
        scale,
        curve,
    }])
}

/// The `$$PRESCRIBED_VELOCITY` multiplier as (scale, curve): Anura3D's `file` reads the
/// project's `.PVF` beside the CPS (rows `time multiplier`, read up to the first line that is
/// not two numbers; linear between rows, 0 after the last), the others as every multiplier.
fn velocity_curve(
    m: Multiplier,
    steps: LoadSteps,
    cfile: &str,
) -> Result<(f64, crate::step::load_curve::LoadCurve), CaseError> {
    const KEY: &str = "$$PRESCRIBED_VELOCITY";
    let Multiplier::File { .. } = m else {
        return curve(m, steps, cfile, KEY);
    };
    let path = std::path::Path::new(cfile).with_extension("PVF");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        unsupported(
            cfile,
            KEY,
            format!(
                "file: its multipliers are read from {}: {e}",
                path.display()
            ),
        )
    })?;
    let rows: Vec<(f64, f64)> = text
        .lines()
        .map_while(|line| crate::step::load_curve::parse_row(line, false))
        .collect();
    let pvf = path.display().to_string();
    match rows.first() {
        None => {
            return Err(unsupported(
                &pvf,
                KEY,
                "no rows of `time multiplier` at its start",
            ))
        }
        Some(&(t0, _)) if t0 > 0.0 => {
            return Err(unsupported(
                &pvf,
                KEY,
                format!("its first time is {t0}: Anura3D needs a row at time 0 or before"),
            ))
        }
        _ => {}
    }
    if let Some(i) = rows
        .windows(2)
        .position(|w| w[1].0 <= w[0].0 || !w[1].1.is_finite())
    {
        return Err(unsupported(
            &pvf,
            KEY,
            format!(
                "line {}: the times must increase (and the values be finite)",
                i + 2
            ),
        ));
    }
    Ok((1.0, crate::step::load_curve::LoadCurve::File(rows.into())))
}
