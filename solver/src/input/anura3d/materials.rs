//! The case's materials (the GOM's material blocks: type, law and densities) and the element
//! tables that refer to them (`$$STARTELMMAT`, the input element numbers, the material points
//! per element).

use mpm_shared::model::Material as GomMaterial;

use super::k0::K0Input;
use super::{unsupported, CaseError, Input};
use crate::input::case::MaterialSpec;
use crate::input::initial_stress::K0Pores;
use crate::material::law::{self, LawError, LawSpec};
use crate::material::liquid::LiquidSpec;

/// A material's `MATERIAL_TYPE`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Dry,
    Coupled,
    Drained,
    UndrainedTotal,
}

/// The case's materials by material index (entry 0 and gaps unused).
pub(super) struct Materials {
    /// The materials as the case runs them.
    pub specs: Vec<Option<MaterialSpec>>,
    /// What the K0 procedure reads of each (used only when it is on).
    pub k0: Vec<K0Input>,
    /// Some material is saturated and drained (Anura3D's submerged calculation).
    pub drained: bool,
    /// Some material is saturated and coupled (Anura3D's two-phase calculation).
    pub coupled: bool,
}

/// The GOM's materials; a drained material together with a coupled one is refused.
pub(super) fn read(input: &Input) -> Result<Materials, CaseError> {
    let mats = input.model.materials();
    let max_index = mats.iter().map(|m| m.index).max().unwrap_or(0).max(0) as usize;
    let mut out = Materials {
        specs: vec![None; max_index + 1],
        k0: Vec::new(),
        drained: false,
        coupled: false,
    };
    for m in &mats {
        let item = format!("material {} \"{}\"", m.index, m.name);
        let kind = kind(m, &input.gfile, &item)?;
        let (spec, k0) = material(m, kind, &input.gfile, &item)?;
        out.drained |= kind == Kind::Drained;
        out.coupled |= kind == Kind::Coupled;
        out.k0.push(k0);
        out.specs[m.index.max(0) as usize] = Some(spec);
    }
    if out.drained && out.coupled {
        // Anura3D turns on its submerged calculation for the whole run when it reads a drained
        // material, which changes how coupled materials weigh and build pore pressure.
        return Err(unsupported(
            &input.gfile,
            "MATERIAL_TYPE",
            "saturated_material_drained together with saturated_material_coupled is not supported (Anura3D then runs a submerged calculation)",
        ));
    }
    Ok(out)
}

/// The material's `MATERIAL_TYPE`; the types this solver does not model are refused.
fn kind(m: &GomMaterial, gfile: &str, item: &str) -> Result<Kind, CaseError> {
    Ok(match m.kind.as_str() {
        "dry_material" => Kind::Dry,
        "saturated_material_coupled" => Kind::Coupled,
        "saturated_material_drained" => Kind::Drained,
        "saturated_material_undrained_total" => Kind::UndrainedTotal,
        other => {
            return Err(unsupported(
                gfile,
                item,
                format!(
                    "MATERIAL_TYPE {other} is not supported yet (dry_material, saturated_material_coupled, saturated_material_drained and saturated_material_undrained_total are)"
                ),
            ))
        }
    })
}

/// The material as the case runs it, and what the K0 procedure reads of it.
fn material(
    m: &GomMaterial,
    kind: Kind,
    gfile: &str,
    item: &str,
) -> Result<(MaterialSpec, K0Input), CaseError> {
    // The law by its name, from the block's own keys (the factory).
    let model_name = m.get("MATERIAL_MODEL_SOLID").unwrap_or("");
    let law = LawSpec::by_name(model_name, &|k| m.get_f64(k)).map_err(|e| match e {
        LawError::Unknown(_) => unsupported(
            gfile,
            item,
            format!(
                "MATERIAL_MODEL_SOLID {model_name} is not supported yet ({} are)",
                law::KNOWN.join(", ")
            ),
        ),
        LawError::Parameter(p) => unsupported(gfile, item, p),
    })?;
    let get = |k: &str| {
        m.get_f64(k)
            .ok_or_else(|| unsupported(gfile, item, format!("missing or non-numeric $${k}")))
    };
    let n = get("POROSITY_SOLID").unwrap_or(0.0);
    let spec = match kind {
        Kind::Coupled => {
            let liquid = LiquidSpec::new(
                n,
                get("DENSITY_LIQUID")?,
                get("BULK_MODULUS_LIQUID")?,
                get("INTRINSIC_PERMEABILITY_LIQUID")?,
                get("DYNAMIC_VISCOSITY_LIQUID")?,
            )
            .map_err(|e| unsupported(gfile, item, e.to_string()))?;
            MaterialSpec::saturated(&m.name, get("DENSITY_SOLID")?, law, liquid)
        }
        // A dry material's mass is that of its solid grains: (1 - n) ρs.
        Kind::Dry => MaterialSpec::with_law(&m.name, (1.0 - n) * get("DENSITY_SOLID")?, law),
        Kind::Drained => MaterialSpec::drained(
            &m.name,
            n,
            get("DENSITY_SOLID")?,
            get("DENSITY_LIQUID")?,
            law,
        ),
        Kind::UndrainedTotal => MaterialSpec::undrained_total(
            &m.name,
            n,
            get("DENSITY_SOLID")?,
            get("DENSITY_LIQUID")?,
            law,
        ),
    }
    .map_err(|e| unsupported(gfile, item, e.to_string()))?;
    let k0 = K0Input {
        index: m.index.max(0) as usize,
        item: item.to_string(),
        k0: m.get_f64("K0_VALUE_SOLID"),
        porosity: n,
        grains: get("DENSITY_SOLID")?,
        // Anura3D does not read a dry material's liquid density: 0.
        liquid: if kind == Kind::Dry {
            0.0
        } else {
            get("DENSITY_LIQUID")?
        },
        pores: match kind {
            Kind::Dry => K0Pores::Dry,
            Kind::UndrainedTotal => K0Pores::Total,
            Kind::Coupled | Kind::Drained => K0Pores::Effective,
        },
        coupled: kind == Kind::Coupled,
    };
    Ok((spec, k0))
}

/// The element tables of the case.
pub(super) struct Elements {
    /// Each element's material index (0: none).
    pub element_material: Vec<u32>,
    /// Each element's number in the original input (0-based).
    pub input_element: Vec<u32>,
    /// Each element's material points.
    pub points_per_element: Vec<u32>,
}

/// The element tables of the GOM; an element of a material the GOM does not define is refused.
pub(super) fn elements(
    input: &Input,
    materials: &[Option<MaterialSpec>],
) -> Result<Elements, CaseError> {
    let (model, gfile) = (&input.model, input.gfile.as_str());
    let element_material: Vec<u32> = model
        .element_materials()
        .ok_or_else(|| unsupported(gfile, "$$STARTELMMAT", "missing"))?
        .iter()
        .map(|&m| m.max(0) as u32)
        .collect();
    let input_element: Vec<u32> = match model.input_elements() {
        Ok(m) => m.unwrap_or_else(|| (0..model.element_count() as u32).collect()),
        Err(e) => {
            return Err(unsupported(
                gfile,
                &format!("$${}", mpm_shared::points::INPUT_ELEMENTS),
                e.to_string(),
            ))
        }
    };
    for (e, &m) in element_material.iter().enumerate() {
        if m as usize >= materials.len() || (m != 0 && materials[m as usize].is_none()) {
            return Err(unsupported(
                gfile,
                "$$STARTELMMAT",
                format!(
                    "element {} refers to material {m}, which is not defined",
                    input_element[e] + 1
                ),
            ));
        }
    }
    let points_per_element = model
        .material_points_per_element()
        .ok_or_else(|| unsupported(gfile, "$$START_NUMBER_OF_MATERIAL_POINTS", "missing"))?;
    Ok(Elements {
        element_material,
        input_element,
        points_per_element,
    })
}
