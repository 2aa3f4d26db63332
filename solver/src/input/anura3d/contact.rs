//! The contact between a structure and the soil (CPS `$$CONTACT_FORMULATION 1` with GOM
//! `$$START_CONTACT_VOLUME`; [`crate::step::contact`]).

use super::materials::Elements;
use super::{strain_smoothing, unsupported, CaseError, Input};
use crate::input::case::MaterialSpec;
use crate::step::contact::ContactSpec;

/// The CPS key that switches the contact on.
const KEY: &str = "$$CONTACT_FORMULATION";

/// What the loader knows of the case when it reads the contact.
pub(super) struct ContactCase {
    pub has_nodal_load: bool,
    pub has_point_load: bool,
    pub has_nodal_velocity: bool,
    /// Elements (0-based) whose points have a prescribed velocity.
    pub prescribed_elements: Vec<u32>,
}

/// The contact, `None` when it is off. Refused by name what it does not model with it: 2D
/// models, saturated materials, loads on nodes or on material points, prescribed nodal
/// velocities and strain smoothing (Anura3D gives each of them rules of its own for the two
/// bodies), and velocities prescribed on the soil.
pub(super) fn read(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    elements: &Elements,
    with: ContactCase,
) -> Result<Option<ContactSpec>, CaseError> {
    if !switched_on(input)? {
        return Ok(None);
    }
    if let Some(what) = not_modelled_with(input, materials, &with) {
        return Err(unsupported(
            &input.cfile,
            KEY,
            format!("contact is not modelled {what}"),
        ));
    }
    let model = &input.model;
    let names: Vec<(u32, String)> = model
        .materials()
        .iter()
        .map(|m| (m.index.max(0) as u32, m.name.clone()))
        .collect();
    let element_material = &elements.element_material;
    let spec = crate::step::contact::read(
        model,
        element_material,
        &names,
        &elements.points_per_element,
    )
    .map_err(|(item, why)| unsupported(&input.gfile, &item, why))?;
    // The prescribed velocity acts on the structure's nodes (Anura3D's hard entity).
    if let Some(e) = with
        .prescribed_elements
        .iter()
        .find(|&&e| element_material[e as usize] != spec.material)
    {
        return Err(unsupported(
            &input.gfile,
            "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
            format!(
                "element {} is not of the structure's material {}: with contact, velocities are prescribed on the structure only",
                e + 1,
                spec.material
            ),
        ));
    }
    Ok(Some(spec))
}

/// Whether `$$CONTACT_FORMULATION` is 1 (0 or absent: off; anything else is refused).
fn switched_on(input: &Input) -> Result<bool, CaseError> {
    let value = input
        .cps
        .get("CONTACT_FORMULATION")
        .and_then(|e| e.lines.first())
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("0");
    match value {
        "0" => Ok(false),
        "1" => Ok(true),
        other => Err(unsupported(
            &input.cfile,
            KEY,
            format!("expected 0 or 1, got {other:?}"),
        )),
    }
}

/// What of the case the contact is not modelled with, as the end of the refusal's sentence;
/// `None` when there is nothing.
fn not_modelled_with(
    input: &Input,
    materials: &[Option<MaterialSpec>],
    with: &ContactCase,
) -> Option<&'static str> {
    if input.model.dimension.coords() != 3 {
        Some("in 2D models (3D only)")
    } else if materials.iter().flatten().any(|m| m.liquid.is_some()) {
        Some("with saturated materials (dry materials only)")
    } else if with.has_nodal_load {
        Some("with loads on nodes")
    } else if with.has_point_load {
        Some("with loads on material points")
    } else if with.has_nodal_velocity {
        Some("with prescribed nodal velocities")
    } else if strain_smoothing(&input.cps) {
        Some("with $$STRAIN_SMOOTHING 1")
    } else {
        None
    }
}
