//! Anura3D's K0 procedure (`$$K0_PROCEDURE 1`) resolved into initial stresses: the ground as a
//! horizontal line at `$$SURFACE_ELEVATION`, each material's K0 and unit weights.

use mpm_shared::cps::{Cps, Multiplier};

use super::keys::section_lines;
use super::{unsupported, CaseError, Input};
use crate::input::initial_stress::{
    k0_unit_weights, InitialStress, K0Material, K0Pores, K0Procedure, MaterialStart,
    DEFAULT_MAX_SUCTION,
};

/// What the K0 procedure reads of one GOM material.
pub(super) struct K0Input {
    /// Its material index.
    pub index: usize,
    /// The material as messages name it.
    pub item: String,
    /// `$$K0_VALUE_SOLID`, if a number.
    pub k0: Option<f64>,
    /// Porosity n.
    pub porosity: f64,
    /// Density of the grains (kg/m³).
    pub grains: f64,
    /// Density of the liquid (kg/m³; 0 for a dry material, which Anura3D does not read it of).
    pub liquid: f64,
    /// Whose stress the procedure sets.
    pub pores: K0Pores,
    /// A saturated coupled material (its pore pressure is set too).
    pub coupled: bool,
}

/// What the K0 procedure reads of the case as a whole.
pub(super) struct K0Case {
    /// Some material is saturated and coupled (Anura3D's two-phase calculation).
    pub coupled: bool,
    /// Some material is drained (Anura3D's submerged calculation).
    pub submerged: bool,
    /// Length of the case's material table.
    pub materials: usize,
}

/// The K0 procedure's initial stresses; `None` when it is off. What Anura3D's procedure would
/// compute otherwise (soil or phreatic surfaces given by nodes, a water surface from a file,
/// several soil layers) is refused by name.
pub(super) fn procedure(
    input: &Input,
    materials: &[K0Input],
    case: K0Case,
) -> Result<Option<InitialStress>, CaseError> {
    if !switched_on(input)? {
        return Ok(None);
    }
    refuse_other_grounds(input)?;
    let k0 = ground(input)?;
    let materials = material_starts(input, materials, &case)?;
    Ok(Some(InitialStress {
        k0: Some(k0),
        materials,
    }))
}

/// Whether `$$K0_PROCEDURE` is 1 (0 or absent: off; anything else is refused).
fn switched_on(input: &Input) -> Result<bool, CaseError> {
    match cps_number(&input.cps, "K0_PROCEDURE", &input.cfile)? {
        None | Some(0.0) => Ok(false),
        Some(1.0) => Ok(true),
        Some(v) => Err(unsupported(
            &input.cfile,
            "$$K0_PROCEDURE",
            format!("must be 0 or 1, got {v}"),
        )),
    }
}

/// Refuses the grounds other than one horizontal line: surfaces given by nodes or from a
/// file, several soil layers, and a gravity without an x-y direction to measure depth along.
fn refuse_other_grounds(input: &Input) -> Result<(), CaseError> {
    let (gfile, cfile) = (input.gfile.as_str(), input.cfile.as_str());
    for sec in &input.model.sections {
        let key = sec.keyword.as_str();
        let given = match key {
            "START_SOIL_SURFACE_NODES" | "START_PHREATIC_SURFACE_NODES" => {
                section_lines(&sec.body).is_some_and(|l| !l.is_empty())
            }
            // Anura3D switches the water surface from a file on by the section alone.
            "INITIAL_WATER_SURFACE_FROM_FILE" => true,
            _ => false,
        };
        if given {
            return Err(unsupported(
                gfile,
                &format!("$${key}"),
                "the K0 procedure with a soil or phreatic surface other than the horizontal line at $$SURFACE_ELEVATION is not modelled",
            ));
        }
    }
    if let Some(layers) = cps_number(&input.cps, "NUMBER_SOIL_LAYERS", cfile)? {
        if layers > 1.0 {
            return Err(unsupported(
                cfile,
                "$$NUMBER_SOIL_LAYERS",
                format!("{layers} soil layers: Anura3D's multi-layer K0 (borehole) set-up is not modelled; use 1"),
            ));
        }
    }
    let g = input.settings.gravity_vector;
    if g[0] == 0.0 && g[1] == 0.0 {
        return Err(unsupported(
            cfile,
            "$$GRAVITY_VECTOR",
            "the K0 procedure measures depth along gravity's x-y direction, and this gravity has none",
        ));
    }
    Ok(())
}

/// The ground of the procedure: its height, gravity's direction and initial multiplier, the
/// load on the surface, the largest suction.
fn ground(input: &Input) -> Result<K0Procedure, CaseError> {
    let (cps, cfile, s) = (&input.cps, input.cfile.as_str(), &input.settings);
    // INITIAL_VERTICAL_LOAD_K0 and CONSIDERED_LOAD_K0 set the same value: the last one read wins.
    let mut load = 0.0;
    for e in cps
        .entries
        .iter()
        .filter(|e| e.keyword == "INITIAL_VERTICAL_LOAD_K0" || e.keyword == "CONSIDERED_LOAD_K0")
    {
        let word = e
            .lines
            .first()
            .and_then(|l| l.split_whitespace().next())
            .unwrap_or("");
        load = word.parse::<f64>().map_err(|_| {
            unsupported(
                cfile,
                &format!("$${}", e.keyword),
                format!("expected a number, got {word:?}"),
            )
        })?;
    }
    let traction = initial_multiplier(s.solid_traction);
    let g = s.gravity_vector;
    Ok(K0Procedure {
        surface_point: [
            0.0,
            cps_number(cps, "SURFACE_ELEVATION", cfile)?.unwrap_or(0.0),
        ],
        gravity_direction: [g[0], g[1]],
        gravity_factor: initial_multiplier(s.gravity_load),
        surface_load: load * traction,
        max_suction: cps_number(cps, "K0_MAX_SUCTION", cfile)?.unwrap_or(DEFAULT_MAX_SUCTION),
    })
}

/// Each material's K0 start (by material index): its K0, in [0, 1], and unit weights.
fn material_starts(
    input: &Input,
    inputs: &[K0Input],
    case: &K0Case,
) -> Result<Vec<Option<MaterialStart>>, CaseError> {
    let gfile = input.gfile.as_str();
    let mut materials = vec![None; case.materials];
    for m in inputs {
        let k0 = m.k0.ok_or_else(|| {
            unsupported(
                gfile,
                &m.item,
                "missing or non-numeric $$K0_VALUE_SOLID (the K0 procedure is on)",
            )
        })?;
        if !(0.0..=1.0).contains(&k0) {
            return Err(unsupported(
                gfile,
                &m.item,
                format!("$$K0_VALUE_SOLID must be in [0, 1] (Anura3D's check), got {k0}"),
            ));
        }
        let (unit_weight, liquid_unit_weight) = k0_unit_weights(
            m.porosity,
            m.grains,
            m.liquid,
            input.settings.gravity_acceleration,
            case.coupled,
            case.submerged,
            m.pores != K0Pores::Dry,
        );
        materials[m.index] = Some(MaterialStart::K0(K0Material {
            k0,
            unit_weight,
            liquid_unit_weight,
            pores: m.pores,
            sets_pore_pressure: m.coupled,
        }));
    }
    Ok(materials)
}

/// The first number of CPS key `key`'s value, `None` when the key is absent.
fn cps_number(cps: &Cps, key: &str, file: &str) -> Result<Option<f64>, CaseError> {
    let Some(e) = cps.get(key) else {
        return Ok(None);
    };
    let word = e
        .lines
        .first()
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("");
    word.parse::<f64>().map(Some).map_err(|_| {
        unsupported(
            file,
            &format!("$${key}"),
            format!("expected a number, got {word:?}"),
        )
    })
}

/// A load multiplier's value at the start of the calculation, as Anura3D sets it when it reads
/// the key: the first of its two numbers (0 when off or absent).
fn initial_multiplier(m: Multiplier) -> f64 {
    match m {
        Multiplier::Off => 0.0,
        Multiplier::Linear { start, .. }
        | Multiplier::File { start, .. }
        | Multiplier::Step { start, .. } => start,
    }
}
