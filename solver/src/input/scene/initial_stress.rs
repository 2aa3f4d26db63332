//! The scene's initial stresses: per `[[material]]`, `k0` (Anura3D's K0 procedure under gravity
//! along -y, the ground at `[gravity] k0_surface`) or a uniform `initial_stress`
//! ([`crate::input::initial_stress`]).

use mpm_shared::Model;

use super::gravity::Gravity;
use super::material::MaterialInput;
use super::{refuse, Refusal};
use crate::input::case::{ConsolidationSpec, Start};
use crate::input::initial_stress::{
    k0_unit_weights, InitialStress, K0Material, K0Pores, K0Procedure, MaterialStart,
    DEFAULT_MAX_SUCTION,
};

/// What the initial stresses read of the scene besides the materials.
pub(super) struct Context<'a> {
    /// `[gravity]`, if given.
    pub gravity: Option<&'a Gravity>,
    /// The run's consolidation settings, if any.
    pub consolidation: Option<&'a ConsolidationSpec>,
    /// The model (the K0 ground defaults to its highest node).
    pub model: &'a Model,
}

/// The initial stresses of the materials `inputs` (by model material index); `None` when no
/// material has `k0` or `initial_stress`. Errors name the item.
pub(super) fn resolve(
    inputs: &[Option<MaterialInput>],
    scene: Context,
) -> Result<Option<InitialStress>, Refusal> {
    let surface = scene.gravity.and_then(|g| g.k0_surface);
    if surface.is_some() && inputs.iter().flatten().all(|m| m.k0.is_none()) {
        return Err(refuse(
            "gravity.k0_surface",
            "no material has k0: the ground surface is only used by the K0 procedure",
        ));
    }
    if inputs
        .iter()
        .flatten()
        .all(|m| m.k0.is_none() && m.initial_stress.is_none())
    {
        return Ok(None);
    }
    let coupled = inputs.iter().flatten().any(|m| m.liquid.is_some());
    let mut materials = vec![None; inputs.len()];
    for (k, m) in inputs.iter().enumerate() {
        if let Some(m) = m {
            materials[k] = material_start(m, &scene, coupled)?;
        }
    }
    let k0 = if materials
        .iter()
        .any(|m| matches!(m, Some(MaterialStart::K0(_))))
    {
        Some(k0_procedure(&scene)?)
    } else {
        None
    };
    Ok(Some(InitialStress { k0, materials }))
}

/// How material `m`'s points start: from its `k0`, its `initial_stress`, or neither (`None`).
/// `coupled`: some material of the scene is saturated.
fn material_start(
    m: &MaterialInput,
    scene: &Context,
    coupled: bool,
) -> Result<Option<MaterialStart>, Refusal> {
    let item = format!("material \"{}\"", m.physical);
    let undrained = scene
        .consolidation
        .is_some_and(|c| c.start == Start::Undrained);
    if (m.k0.is_some() || m.initial_stress.is_some()) && undrained {
        return Err(refuse(
            item,
            "k0 and initial_stress cannot be combined with consolidation.start = \"undrained\", which sets the initial stresses itself",
        ));
    }
    match (m.k0, m.initial_stress) {
        (None, None) => Ok(None),
        (Some(_), Some(_)) => Err(refuse(
            item,
            "give k0 or initial_stress, not both: each sets the initial stresses",
        )),
        (None, Some(s)) => {
            if let Some(v) = s.iter().find(|v| !v.is_finite()) {
                return Err(refuse(
                    format!("{item}.initial_stress"),
                    format!("must be finite, got {v}"),
                ));
            }
            Ok(Some(MaterialStart::Uniform(s)))
        }
        (Some(k0), None) => k0_start(m, k0, scene.gravity, coupled)
            .map(Some)
            .map_err(|message| refuse(format!("{item}.k0"), message)),
    }
}

/// Material `m`'s K0 start: its unit weights under gravity along -y, its pore pressure set by
/// the procedure when saturated.
fn k0_start(
    m: &MaterialInput,
    k0: f64,
    gravity: Option<&Gravity>,
    coupled: bool,
) -> Result<MaterialStart, String> {
    if !(k0 >= 0.0 && k0.is_finite()) {
        return Err(format!("must be finite and at least 0, got {k0}"));
    }
    if m.liquid
        .as_ref()
        .is_some_and(|l| l.initial_pore_pressure != 0.0)
    {
        return Err("the K0 procedure sets the pore pressure (hydrostatic below the ground): remove liquid.initial_pore_pressure".into());
    }
    let g = gravity.map_or(0.0, |g| -g.vector[1]);
    let down =
        gravity.is_some_and(|g| g.vector[0] == 0.0 && g.vector[2] == 0.0 && g.vector[1] < 0.0);
    if !down {
        return Err(
            "the K0 procedure needs gravity along -y ([gravity] vector = [0, -g, 0])".into(),
        );
    }
    let (unit_weight, liquid_unit_weight) = match &m.liquid {
        None => k0_unit_weights(0.0, m.density, 0.0, g, coupled, false, false),
        Some(l) => k0_unit_weights(l.porosity, m.density, l.density, g, coupled, false, true),
    };
    Ok(MaterialStart::K0(K0Material {
        k0,
        unit_weight,
        liquid_unit_weight,
        pores: if m.liquid.is_some() {
            K0Pores::Effective
        } else {
            K0Pores::Dry
        },
        sets_pore_pressure: m.liquid.is_some(),
    }))
}

/// The K0 procedure of a scene: gravity along -y from the start, the ground at
/// `k0_surface` (default: the highest node).
fn k0_procedure(scene: &Context) -> Result<K0Procedure, Refusal> {
    let gravity = scene.gravity.expect("checked: k0 needs gravity");
    if gravity.ramp != 0.0 {
        return Err(refuse(
            "gravity.ramp",
            format!(
                "the K0 stresses carry the full weight from the start; a gravity ramped from 0 (over {} s) would leave them unbalanced: use ramp = 0",
                gravity.ramp
            ),
        ));
    }
    let model = scene.model;
    let top = model
        .coords
        .chunks_exact(model.dimension.coords())
        .fold(f64::MIN, |h, p| h.max(p[1]));
    let surface = gravity.k0_surface.unwrap_or(top);
    if !surface.is_finite() {
        return Err(refuse(
            "gravity.k0_surface",
            format!("must be finite, got {surface}"),
        ));
    }
    Ok(K0Procedure {
        surface_point: [0.0, surface],
        gravity_direction: [0.0, -1.0],
        gravity_factor: 1.0,
        surface_load: 0.0,
        max_suction: DEFAULT_MAX_SUCTION,
    })
}
