//! Anura3D cases (GOM + CPS) turned into a [`Case`]: dry and saturated
//! (`saturated_material_coupled`) materials with the laws of [`crate::material::law::KNOWN`]
//! (linear elasticity, Mohr–Coulomb, strain-softening Mohr–Coulomb), fixities of both phases,
//! face loads on nodes and on material points, gravity, local damping, load steps, quasi-static
//! convergence, objective stress, MPM-MP and MPM-MIXED integration, with Anura3D's two-phase
//! time step, liquid damping and (per `STRAIN_SMOOTHING`) pressure smoothing. Features this
//! solver does not model yet are refused with the item named, never silently ignored.

use std::path::Path;

use mpm_shared::cps::{Cps, Method, Multiplier, Settings};
use mpm_shared::model::{Body, Token};
use mpm_shared::{Dimension, Model};

use crate::input::case::{Case, FaceLoad, Integration, LoadCurve, MaterialSpec, QuasiStatic};
use crate::input::initial_stress::{
    k0_unit_weights, InitialStress, K0Material, K0Pores, K0Procedure, MaterialStart,
    DEFAULT_MAX_SUCTION,
};
use crate::material::law::{LawError, LawSpec};
use crate::material::liquid::LiquidSpec;

/// Anura3D's first time step (s): its time increment starts at this value and becomes the
/// critical step only after the first step.
pub const ANURA3D_FIRST_STEP: f64 = 1e-15;

/// Why a case cannot run here.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// Reading the files failed.
    #[error(transparent)]
    Read(#[from] mpm_shared::Error),
    /// A key that can change results holds a value this solver does not model.
    #[error(transparent)]
    Key(#[from] crate::input::anura3d_keys::Refusal),
    /// The case asks for something this solver does not model (yet).
    #[error("{file}: {item}: {message}")]
    Unsupported {
        /// The file holding the item.
        file: String,
        /// The section or key.
        item: String,
        /// What is not supported and what is.
        message: String,
    },
}

fn unsupported(file: &str, item: &str, message: impl Into<String>) -> CaseError {
    CaseError::Unsupported {
        file: file.into(),
        item: item.into(),
        message: message.into(),
    }
}

/// How the load steps of a calculation run: how many, how long each, and whether they end on
/// convergence (quasi-static) rather than at their end time.
#[derive(Debug, Clone, Copy)]
struct LoadSteps {
    count: u32,
    duration: f64,
    quasi_static: bool,
}

/// A multiplier as a load curve over the calculation's load steps: (scale, curve), the
/// multiplier at time t being scale × curve(t).
fn curve(
    m: Multiplier,
    steps: LoadSteps,
    file: &str,
    key: &str,
) -> Result<(f64, LoadCurve), CaseError> {
    let total = f64::from(steps.count) * steps.duration;
    Ok(match m {
        Multiplier::Off => (0.0, LoadCurve::Step),
        Multiplier::Step { start, value } if start == value || steps.count == 1 => {
            (value, LoadCurve::Step)
        }
        Multiplier::Step { start, value } => {
            if steps.quasi_static {
                // Its load steps end on convergence, not at a time the curve could read.
                return Err(unsupported(
                    file,
                    key,
                    format!(
                        "a step multiplier that changes from load step to load step ({start} to {value} over {} load steps) is not supported with $$QUASISTATIC_CONVERGENCE 1",
                        steps.count
                    ),
                ));
            }
            (
                1.0,
                LoadCurve::Stairs {
                    from: start,
                    to: value,
                    load_step: steps.duration,
                    steps: steps.count,
                },
            )
        }
        // A "linear" multiplier that does not change is a constant one.
        Multiplier::Linear { start, end } if start == end => (end, LoadCurve::Step),
        Multiplier::Linear { start, end } => {
            if start != 0.0 {
                return Err(unsupported(
                    file,
                    key,
                    format!("linear multipliers must start at 0 here (got {start})"),
                ));
            }
            (end, LoadCurve::ramp(total))
        }
        Multiplier::File { .. } => {
            return Err(unsupported(
                file,
                key,
                "load multipliers from files are not supported",
            ))
        }
    })
}

/// Reads `gom` and `cps` into a case. Returns the case and the CPS settings.
pub fn load(gom: &Path, cps_path: &Path) -> Result<(Case, Settings), CaseError> {
    let gfile = mpm_shared::display_name(gom);
    let cfile = cps_path.display().to_string();
    let model = mpm_shared::read_model(gom)?;
    if let Some(w) = mpm_shared::coincident::warning(&gfile, &mpm_shared::coincident::pairs(&model))
    {
        log::warn!("{w}");
    }
    let data = mpm_shared::io::read_parameters(cps_path)?;
    let (cps, warnings) = Cps::read(&data, &cfile)?;
    for w in warnings {
        log::warn!("{w}");
    }
    let s = cps.settings()?;
    if crate::element::ElementKind::of(model.dimension, model.element_type).is_none() {
        return Err(unsupported(
            &gfile,
            "$$DIMENSION",
            format!(
                "{} models of {} are not computed (3D-cartesian tetrahedra, 2D-plane_strain and 2D-axisymmetric triangles are)",
                model.dimension.keyword(),
                model.element_type.describe()
            ),
        ));
    }
    let integration = match &s.method {
        Method::MpmMp => Integration::MaterialPoints,
        Method::MpmMixed => {
            if !(s.degree_of_filling > 0.0 && s.degree_of_filling <= 1.0) {
                return Err(unsupported(
                    &cfile,
                    "$$DEGREE_OF_FILLING",
                    format!("must be in (0, 1], got {}", s.degree_of_filling),
                ));
            }
            Integration::Mixed {
                filling: s.degree_of_filling,
                rule: crate::input::case::MixedRule::Anura3d,
            }
        }
        Method::Other(m) => {
            return Err(unsupported(
                &cfile,
                "$$COMPUTATION_METHOD",
                format!("{m} is not an MPM method"),
            ))
        }
    };
    // Above 1 is refused before the run unless --force (Case::check_courant).
    if !(s.courant > 0.0 && s.courant.is_finite()) {
        return Err(unsupported(
            &cfile,
            "$$COURANT_NUMBER",
            format!("must be in (0, 1], got {}", s.courant),
        ));
    }
    if !(s.time_per_load_step > 0.0) {
        return Err(unsupported(
            &cfile,
            "$$TIME_PER_LOADSTEP",
            format!("must be positive, got {}", s.time_per_load_step),
        ));
    }
    // Every other key: modelled, irrelevant, or refused unless inert.
    check_keys(&model, &cps, gom, &gfile, &cfile)?;
    // Materials.
    let mats = model.materials();
    let max_index = mats.iter().map(|m| m.index).max().unwrap_or(0).max(0) as usize;
    let mut materials: Vec<Option<MaterialSpec>> = vec![None; max_index + 1];
    let (mut drained, mut coupled) = (false, false);
    let mut k0_inputs = Vec::new();
    for m in &mats {
        let item = format!("material {} \"{}\"", m.index, m.name);
        #[derive(PartialEq)]
        enum Kind {
            Dry,
            Coupled,
            Drained,
            UndrainedTotal,
        }
        let kind = match m.kind.as_str() {
            "dry_material" => Kind::Dry,
            "saturated_material_coupled" => Kind::Coupled,
            "saturated_material_drained" => Kind::Drained,
            "saturated_material_undrained_total" => Kind::UndrainedTotal,
            other => {
                return Err(unsupported(
                    &gfile,
                    &item,
                    format!(
                        "MATERIAL_TYPE {other} is not supported yet (dry_material, saturated_material_coupled, saturated_material_drained and saturated_material_undrained_total are)"
                    ),
                ))
            }
        };
        // The law by its name, from the block's own keys (the factory).
        let model_name = m.get("MATERIAL_MODEL_SOLID").unwrap_or("");
        let law = LawSpec::by_name(model_name, &|k| m.get_f64(k)).map_err(|e| match e {
            LawError::Unknown(_) => unsupported(
                &gfile,
                &item,
                format!(
                    "MATERIAL_MODEL_SOLID {model_name} is not supported yet ({} are)",
                    crate::material::law::KNOWN.join(", ")
                ),
            ),
            LawError::Parameter(p) => unsupported(&gfile, &item, p),
        })?;
        let get = |k: &str| {
            m.get_f64(k)
                .ok_or_else(|| unsupported(&gfile, &item, format!("missing or non-numeric $${k}")))
        };
        let n = get("POROSITY_SOLID").unwrap_or(0.0);
        match kind {
            Kind::Drained => drained = true,
            Kind::Coupled => coupled = true,
            _ => {}
        }
        let spec = match kind {
            Kind::Coupled => {
                let liquid = LiquidSpec::new(
                    n,
                    get("DENSITY_LIQUID")?,
                    get("BULK_MODULUS_LIQUID")?,
                    get("INTRINSIC_PERMEABILITY_LIQUID")?,
                    get("DYNAMIC_VISCOSITY_LIQUID")?,
                )
                .map_err(|e| unsupported(&gfile, &item, e.to_string()))?;
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
        .map_err(|e| unsupported(&gfile, &item, e.to_string()))?;
        // What the K0 procedure reads of the material (used only when it is on).
        k0_inputs.push(K0Input {
            index: m.index.max(0) as usize,
            item: item.clone(),
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
        });
        materials[m.index.max(0) as usize] = Some(spec);
    }
    if drained && coupled {
        // Anura3D turns on its submerged calculation for the whole run when it reads a drained
        // material, which changes how coupled materials weigh and build pore pressure.
        return Err(unsupported(
            &gfile,
            "MATERIAL_TYPE",
            "saturated_material_drained together with saturated_material_coupled is not supported (Anura3D then runs a submerged calculation)",
        ));
    }
    let element_material: Vec<u32> = model
        .element_materials()
        .ok_or_else(|| unsupported(&gfile, "$$STARTELMMAT", "missing"))?
        .iter()
        .map(|&m| m.max(0) as u32)
        .collect();
    let input_element: Vec<u32> = match model.input_elements() {
        Ok(m) => m.unwrap_or_else(|| (0..model.element_count() as u32).collect()),
        Err(e) => {
            return Err(unsupported(
                &gfile,
                &format!("$${}", mpm_shared::points::INPUT_ELEMENTS),
                e.to_string(),
            ))
        }
    };
    for (e, &m) in element_material.iter().enumerate() {
        if m as usize >= materials.len() || (m != 0 && materials[m as usize].is_none()) {
            return Err(unsupported(
                &gfile,
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
        .ok_or_else(|| unsupported(&gfile, "$$START_NUMBER_OF_MATERIAL_POINTS", "missing"))?;
    // Point ids and messages follow the original input's element numbers (a GOM sfcb ordered
    // carries them); the CPS's ids are input ids unless sfcb --cps marked them as file ids.
    let probes = mpm_shared::points::cps_input_ids(&cps, &model)?;
    // Fixities and loads.
    let n = model.node_count();
    let mut fixed = vec![[false; 3]; n];
    let mut liquid_fixed = vec![[false; 3]; n];
    let mut traction = vec![[0.0; 3]; n];
    let mut liquid_traction = vec![[0.0; 3]; n];
    let mut point_loads = Vec::new();
    for sec in &model.sections {
        let k = sec.keyword.as_str();
        let Body::Table { rows, .. } = &sec.body else {
            continue;
        };
        if rows.is_empty() {
            continue;
        }
        let phase = if k.ends_with("_SOLID") {
            Some(&mut fixed)
        } else if k.ends_with("_LIQUID") {
            Some(&mut liquid_fixed)
        } else {
            None
        };
        if let (true, Some(target)) = (k.starts_with("START_FIXITY_"), phase) {
            for r in rows.rows() {
                let node = r[0].as_int().unwrap_or(0) as usize - 1;
                for a in 0..3 {
                    target[node][a] |= r.get(1 + a).and_then(Token::as_int) == Some(1);
                }
            }
        } else if k == "START_LOAD_ON_NODES_SOLID" {
            add_nodal_face_loads(&model, rows, false, &mut traction)
                .map_err(|e| unsupported(&gfile, &format!("$${k}"), e))?;
        } else if k == "START_LOAD_ON_NODES_LIQUID" {
            add_nodal_face_loads(&model, rows, true, &mut liquid_traction)
                .map_err(|e| unsupported(&gfile, &format!("$${k}"), e))?;
        } else if k == "START_LOAD_ON_MATERIAL_POINTS_SOLID" {
            point_loads.extend(face_loads_on_points(&model, rows));
        } else if k.starts_with("START_REMOVE_FIXITY_")
            || k.starts_with("START_LOAD_ON_")
            || (k.starts_with("PRESCRIBED_")
                && !crate::step::prescribed::SECTIONS.contains(&k)
                && !crate::step::nodal_velocity::SECTIONS.contains(&k))
            || k.starts_with("ABSORBING_")
            || k.starts_with("START_FIXITY_")
            || k == "START_EXCAVATION_SOLID"
        {
            return Err(unsupported(&gfile, &format!("$${k}"), "not supported yet (supported: fixities of either phase, $$START_LOAD_ON_NODES_SOLID, $$START_LOAD_ON_NODES_LIQUID, $$START_LOAD_ON_MATERIAL_POINTS_SOLID, $$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME or _SURFACE and $$PRESCRIBED_NODAL_VELOCITY_VOLUME, _SURFACE, _LINE or _POINT)"));
        }
    }
    let total = s.load_steps as f64 * s.time_per_load_step;
    let steps = LoadSteps {
        count: s.load_steps,
        duration: s.time_per_load_step,
        quasi_static: s.quasi_static,
    };
    let (tm, traction_curve) = curve(s.solid_traction, steps, &cfile, "$$SOLID_TRACTION")?;
    for t in traction.iter_mut() {
        for v in t.iter_mut() {
            *v *= tm;
        }
    }
    // The multiplier scales the loads carried by material points as it scales those on nodes.
    for load in &mut point_loads {
        for v in load.force.iter_mut() {
            *v *= tm;
        }
    }
    let (lm, liquid_curve) = curve(s.liquid_pressure, steps, &cfile, "$$LIQUID_PRESSURE")?;
    for t in liquid_traction.iter_mut() {
        for v in t.iter_mut() {
            *v *= lm;
        }
    }
    let has_liquid_load = liquid_traction.iter().flatten().any(|&v| v != 0.0);
    if has_liquid_load && !materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return Err(unsupported(
            &gfile,
            "$$START_LOAD_ON_NODES_LIQUID",
            "loads the liquid, but no material is saturated",
        ));
    }
    let prescribed = prescribed_velocity(&model, &s, &materials, steps, &gfile, &cfile)?;
    let nodal_velocity = nodal_velocity(&model, &s, &materials, steps, &gfile, &cfile)?;
    let moving_mesh = crate::step::moving_mesh::read(&model)
        .map_err(|(item, why)| unsupported(&gfile, &item, why))?;
    if let Some(mm) = &moving_mesh {
        if !matches!(materials.get(mm.material as usize), Some(Some(_))) {
            return Err(unsupported(
                &gfile,
                "$$MOVING_MESH_REFERENCE_MATERIAL_INDEX",
                format!("material {} is not defined", mm.material),
            ));
        }
    }
    let contact = contact(
        &model,
        &cps,
        &materials,
        &element_material,
        &points_per_element,
        ContactCase {
            has_nodal_load: traction.iter().flatten().any(|&v| v != 0.0),
            has_point_load: !point_loads.is_empty(),
            has_nodal_velocity: !nodal_velocity.is_empty(),
            prescribed_elements: prescribed
                .as_ref()
                .map(|p| p.rows.iter().map(|r| r.element).collect())
                .unwrap_or_default(),
        },
        &gfile,
        &cfile,
    )?;
    let initial_stress = k0_procedure(
        &model,
        &cps,
        &s,
        &k0_inputs,
        K0Case {
            coupled,
            submerged: drained,
            materials: materials.len(),
        },
        &gfile,
        &cfile,
    )?;
    let (gm, gravity_curve) = curve(s.gravity_load, steps, &cfile, "$$GRAVITY_LOAD")?;
    let g = s.gravity_vector.map(|v| v * s.gravity_acceleration * gm);
    let output_times = (1..=s.load_steps)
        .map(|k| k as f64 * s.time_per_load_step)
        .collect();
    let case = Case {
        name: gom
            .file_stem()
            .map(|x| x.to_string_lossy().to_string())
            .unwrap_or_default(),
        inputs: vec![gfile, cfile.clone()],
        model,
        materials,
        element_material,
        points_per_element,
        input_element,
        input_node: (0..n as u32).collect(),
        fixed,
        liquid_fixed,
        walls: Vec::new(),
        traction,
        point_loads,
        traction_curve,
        liquid_traction,
        liquid_curve,
        liquid_load_on_mixture: false,
        gravity: g,
        gravity_curve,
        courant: s.courant,
        courant_item: format!("{cfile}: $$COURANT_NUMBER"),
        guards: Default::default(),
        damping: s.local_damping.unwrap_or(0.0),
        end_time: total,
        output_times,
        max_steps: None,
        quasi_static: s.quasi_static.then_some(QuasiStatic {
            max_steps: s.max_time_steps,
            force_tolerance: s.tolerated_error_solid[0],
            energy_tolerance: s.tolerated_error_solid[1],
            liquid_force_tolerance: s.tolerated_error_liquid[0],
        }),
        objective_stress: s.objective_stress,
        pic_blend: 0.0,
        integration,
        anura3d_time_step: true,
        critical_step: crate::input::case::CriticalStepRule::OccupiedEachStep,
        damping_rule: crate::input::case::DampingRule::Anura3d,
        drag: crate::input::case::Drag::Implicit,
        initial_step: Some(ANURA3D_FIRST_STEP),
        smooth_pressure: false,
        fixed_liquid_mass: true,
        hoop_in_volume: false,
        strain_smoothing: cps.get("STRAIN_SMOOTHING").is_some_and(|e| {
            e.lines
                .first()
                .and_then(|l| l.split_whitespace().next())
                .is_some_and(|w| w != "0")
        }),
        consolidation: None,
        initial_state: None,
        initial_stress,
        probes,
        prescribed,
        nodal_velocity,
        moving_mesh,
        contact,
        engine: Default::default(),
        precision: crate::input::case::Precision::F64,
    };
    Ok((case, s))
}

/// What the loader knows of the case when it reads the contact.
struct ContactCase {
    has_nodal_load: bool,
    has_point_load: bool,
    has_nodal_velocity: bool,
    /// Elements (0-based) whose points have a prescribed velocity.
    prescribed_elements: Vec<u32>,
}

/// The contact between a structure and the soil (CPS `$$CONTACT_FORMULATION 1` with GOM
/// `$$START_CONTACT_VOLUME`; `step::contact`), `None` when it is off. Refused by name what it
/// does not model with it: 2D models, saturated materials, loads on nodes or on material points,
/// prescribed nodal velocities and strain smoothing (Anura3D gives each of them rules of its own
/// for the two bodies).
#[allow(clippy::too_many_arguments)]
fn contact(
    model: &Model,
    cps: &Cps,
    materials: &[Option<MaterialSpec>],
    element_material: &[u32],
    points: &[u32],
    with: ContactCase,
    gfile: &str,
    cfile: &str,
) -> Result<Option<crate::step::contact::ContactSpec>, CaseError> {
    let key = "$$CONTACT_FORMULATION";
    let value = cps
        .get("CONTACT_FORMULATION")
        .and_then(|e| e.lines.first())
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("0");
    match value {
        "0" => return Ok(None),
        "1" => {}
        other => {
            return Err(unsupported(
                cfile,
                key,
                format!("expected 0 or 1, got {other:?}"),
            ))
        }
    }
    let refuse = |what: &str| {
        Err(unsupported(
            cfile,
            key,
            format!("contact is not modelled {what}"),
        ))
    };
    if model.dimension.coords() != 3 {
        return refuse("in 2D models (3D only)");
    }
    if materials.iter().flatten().any(|m| m.liquid.is_some()) {
        return refuse("with saturated materials (dry materials only)");
    }
    if with.has_nodal_load {
        return refuse("with loads on nodes");
    }
    if with.has_point_load {
        return refuse("with loads on material points");
    }
    if with.has_nodal_velocity {
        return refuse("with prescribed nodal velocities");
    }
    if cps.get("STRAIN_SMOOTHING").is_some_and(|e| {
        e.lines
            .first()
            .and_then(|l| l.split_whitespace().next())
            .is_some_and(|w| w != "0")
    }) {
        return refuse("with $$STRAIN_SMOOTHING 1");
    }
    let names: Vec<(u32, String)> = model
        .materials()
        .iter()
        .map(|m| (m.index.max(0) as u32, m.name.clone()))
        .collect();
    let spec = crate::step::contact::read(model, element_material, &names, points)
        .map_err(|(item, why)| unsupported(gfile, &item, why))?;
    // The prescribed velocity acts on the structure's nodes (Anura3D's hard entity).
    if let Some(e) = with
        .prescribed_elements
        .iter()
        .find(|&&e| element_material[e as usize] != spec.material)
    {
        return Err(unsupported(
            gfile,
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

/// What the K0 procedure reads of one GOM material.
struct K0Input {
    index: usize,
    item: String,
    k0: Option<f64>,
    porosity: f64,
    grains: f64,
    liquid: f64,
    pores: K0Pores,
    coupled: bool,
}

/// What the K0 procedure reads of the case as a whole.
struct K0Case {
    /// Some material is saturated and coupled (Anura3D's two-phase calculation).
    coupled: bool,
    /// Some material is drained (Anura3D's submerged calculation).
    submerged: bool,
    /// Length of the case's material table.
    materials: usize,
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

/// Anura3D's K0 procedure (`$$K0_PROCEDURE 1`) resolved into initial stresses; `None` when it
/// is off. What Anura3D's procedure would compute otherwise (soil or phreatic surfaces given by
/// nodes, a water surface from a file, several soil layers) is refused by name.
fn k0_procedure(
    model: &Model,
    cps: &Cps,
    s: &Settings,
    inputs: &[K0Input],
    case: K0Case,
    gfile: &str,
    cfile: &str,
) -> Result<Option<InitialStress>, CaseError> {
    match cps_number(cps, "K0_PROCEDURE", cfile)? {
        None => return Ok(None),
        Some(0.0) => return Ok(None),
        Some(1.0) => {}
        Some(v) => {
            return Err(unsupported(
                cfile,
                "$$K0_PROCEDURE",
                format!("must be 0 or 1, got {v}"),
            ))
        }
    }
    for sec in &model.sections {
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
    if let Some(layers) = cps_number(cps, "NUMBER_SOIL_LAYERS", cfile)? {
        if layers > 1.0 {
            return Err(unsupported(
                cfile,
                "$$NUMBER_SOIL_LAYERS",
                format!("{layers} soil layers: Anura3D's multi-layer K0 (borehole) set-up is not modelled; use 1"),
            ));
        }
    }
    let g = s.gravity_vector;
    if g[0] == 0.0 && g[1] == 0.0 {
        return Err(unsupported(
            cfile,
            "$$GRAVITY_VECTOR",
            "the K0 procedure measures depth along gravity's x-y direction, and this gravity has none",
        ));
    }
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
    let k0 = K0Procedure {
        surface_point: [
            0.0,
            cps_number(cps, "SURFACE_ELEVATION", cfile)?.unwrap_or(0.0),
        ],
        gravity_direction: [g[0], g[1]],
        gravity_factor: initial_multiplier(s.gravity_load),
        surface_load: load * traction,
        max_suction: cps_number(cps, "K0_MAX_SUCTION", cfile)?.unwrap_or(DEFAULT_MAX_SUCTION),
    };
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
            s.gravity_acceleration,
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
    Ok(Some(InitialStress {
        k0: Some(k0),
        materials,
    }))
}

/// Checks every GOM section (outside material blocks) and every CPS key against the key table
/// ([`crate::input::anura3d_keys`]): keys that would change results and are not modelled stop the case
/// unless they hold their inert value. GOM sections the table does not know are named in a
/// warning (unknown CPS keys are, when the CPS is read).
fn check_keys(
    model: &Model,
    cps: &Cps,
    gom: &Path,
    gfile: &str,
    cfile: &str,
) -> Result<(), CaseError> {
    use crate::input::anura3d_keys::{check, status, KeyKind, KeyStatus};
    for sec in &model.sections {
        let key = sec.keyword.as_str();
        if mpm_shared::model::is_material_key(key) {
            continue;
        }
        let Some(lines) = section_lines(&sec.body) else {
            continue;
        };
        if status(KeyKind::GomSection, key) == KeyStatus::Unknown {
            log::warn!("{gfile}: section $${key} is not known to this solver and is ignored");
        }
        // The model does not keep line numbers; a refusal looks its section up in the file.
        check(KeyKind::GomSection, key, &lines, gfile, 0)
            .map_err(|r| r.at_line(section_line(gom, key)))?;
    }
    for e in &cps.entries {
        check(KeyKind::CpsKey, &e.keyword, &e.lines, cfile, e.line)?;
    }
    Ok(())
}

/// A GOM section's content as the key table checks it: nothing for an empty list, a summary
/// line for tables, the text otherwise; `None` for the geometry sections.
fn section_lines(body: &Body) -> Option<Vec<String>> {
    Some(match body {
        Body::Table { rows, .. } if rows.is_empty() => Vec::new(),
        Body::Table { rows, .. } => vec![format!("{} rows", rows.len())],
        Body::PerElement(t) => {
            let nonzero = t
                .rows()
                .flatten()
                .filter(|v| v.as_f64().is_some_and(|x| x != 0.0))
                .count();
            if nonzero == 0 {
                Vec::new()
            } else {
                vec![format!("{nonzero} non-zero values")]
            }
        }
        Body::Text(l) => l.clone(),
        Body::Opaque(l) if mpm_shared::model::opaque_is_empty(l) => Vec::new(),
        Body::Opaque(l) => l.clone(),
        _ => return None,
    })
}

/// The 1-based line of the section `$$key` in the GOM file `path` (0 when it cannot be read
/// again, as from standard input).
fn section_line(path: &Path, key: &str) -> usize {
    if mpm_shared::io::is_stdio(path) {
        return 0;
    }
    let Ok(data) = std::fs::read(path) else {
        return 0;
    };
    let head = format!("$${key}");
    data.split(|&b| b == b'\n')
        .position(|l| String::from_utf8_lossy(l).trim() == head)
        .map_or(0, |i| i + 1)
}

/// The prescribed material-point velocities of the GOM with the CPS `$$PRESCRIBED_VELOCITY`
/// multiplier; `None` when there are none or the multiplier is `off` (Anura3D then ignores the
/// rows).
fn prescribed_velocity(
    model: &Model,
    s: &Settings,
    materials: &[Option<MaterialSpec>],
    steps: LoadSteps,
    gfile: &str,
    cfile: &str,
) -> Result<Option<crate::step::prescribed::PrescribedVelocity>, CaseError> {
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
    Ok(Some(crate::step::prescribed::PrescribedVelocity {
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
fn nodal_velocity(
    model: &Model,
    s: &Settings,
    materials: &[Option<MaterialSpec>],
    steps: LoadSteps,
    gfile: &str,
    cfile: &str,
) -> Result<Vec<crate::step::nodal_velocity::NodalVelocitySet>, CaseError> {
    let Some((keyword, rows)) = crate::step::nodal_velocity::read_rows(model)
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
    Ok(vec![crate::step::nodal_velocity::NodalVelocitySet {
        name,
        rows,
        scale,
        curve,
    }])
}

/// One row of a face-load table: the loaded face's corner nodes (0-based; three of a
/// tetrahedron's face, two of a triangle's edge) and the traction (kPa) given at each corner
/// (z = 0 in 2D). A row lists all the face's nodes (six of a 10-node tetrahedron's face), then a
/// vector per node; the corners come first.
struct LoadedFace {
    corners: Vec<usize>,
    traction: Vec<[f64; 3]>,
}

fn loaded_faces(model: &Model, rows: &mpm_shared::model::Table) -> Vec<LoadedFace> {
    let k = model.element_type.face_nodes();
    let dim = model.dimension.coords();
    rows.rows()
        .map(|r| {
            let corners = (0..dim)
                .map(|i| r[i].as_int().unwrap_or(1) as usize - 1)
                .collect();
            let traction = (0..dim)
                .map(|c| {
                    let mut t = [0.0; 3];
                    for (d, v) in t.iter_mut().enumerate().take(dim) {
                        *v = r
                            .get(k + dim * c + d)
                            .and_then(Token::as_f64)
                            .unwrap_or(0.0);
                    }
                    t
                })
                .collect();
            LoadedFace { corners, traction }
        })
        .collect()
}

/// The radius of model node `n` in an axisymmetric model (its x), 1 otherwise: Anura3D's loads
/// on an axisymmetric section are per radian.
fn radius(model: &Model, n: usize) -> f64 {
    if model.dimension == Dimension::Axisymmetric {
        model.node(n)[0]
    } else {
        1.0
    }
}

/// The nodal forces of edge `[a, b]` of length `size` with tractions `t` at its ends, by
/// Anura3D's one Gauss point: each end takes L/2 (t_a r_a + t_b r_b)/2 (r the radius in an
/// axisymmetric section, else 1), and an end on the axis gives 7/8 of it to the other end.
fn edge_forces(
    model: &Model,
    [a, b]: [usize; 2],
    size: f64,
    t: [[f64; 3]; 2],
) -> [(usize, [f64; 3]); 2] {
    let (ra, rb) = (radius(model, a), radius(model, b));
    let half = [0, 1, 2].map(|d| size / 2.0 * (t[0][d] * ra + t[1][d] * rb) / 2.0);
    let on_axis = |r: f64| model.dimension == Dimension::Axisymmetric && r < f64::MIN_POSITIVE;
    // The share each end gives or takes: 0 unless one end is on the axis.
    let shift = match (on_axis(ra), on_axis(rb)) {
        (true, false) => -7.0 / 8.0,
        (false, true) => 7.0 / 8.0,
        _ => 0.0,
    };
    [
        (a, half.map(|h| h * (1.0 + shift))),
        (b, half.map(|h| h * (1.0 - shift))),
    ]
}

/// The loads of `$$START_LOAD_ON_MATERIAL_POINTS_SOLID` rows: Anura3D takes the traction at the
/// face's centroid (one Gauss point), the mean of the corner values (times the radius in an
/// axisymmetric section), times the face's area (an edge's length in 2D) as the face's total
/// force.
fn face_loads_on_points(model: &Model, rows: &mpm_shared::model::Table) -> Vec<FaceLoad> {
    loaded_faces(model, rows)
        .into_iter()
        .map(|f| {
            let size = crate::input::faces::size(model, &f.corners);
            let n = f.corners.len() as f64;
            let mut force = [0.0; 3];
            for (&c, t) in f.corners.iter().zip(&f.traction) {
                for (d, v) in force.iter_mut().enumerate() {
                    *v += size / n * t[d] * radius(model, c);
                }
            }
            FaceLoad {
                corners: f.corners,
                force,
            }
        })
        .collect()
}

/// Adds the nodal forces of `$$START_LOAD_ON_NODES_SOLID` (or `_LIQUID`) rows.
///
/// 3D: the corner tractions are interpolated linearly over the face and integrated exactly:
/// F_a = A/12 (2 t_a + t_b + t_c). For the liquid (`normal`), Anura3D applies the load normal
/// to the face: each component is multiplied by that of the face's outward unit normal, so
/// negative values push into the body.
///
/// 2D: Anura3D integrates an edge with one Gauss point at its middle, so each of its two nodes
/// takes half the edge's force, L/2 (t_a + t_b)/2 (in an axisymmetric section the traction
/// times the node's radius, and when a node lies on the axis 7/8 of that half moves to the other
/// node, as Anura3D does). For the liquid the first component of each node's value is a
/// pressure, applied along the edge's outward normal.
fn add_nodal_face_loads(
    model: &Model,
    rows: &mpm_shared::model::Table,
    normal: bool,
    out: &mut [[f64; 3]],
) -> Result<(), String> {
    let faces = loaded_faces(model, rows);
    let corners: Vec<Vec<usize>> = faces.iter().map(|f| f.corners.clone()).collect();
    let normals = if normal {
        crate::input::faces::outward_normals(model, &corners)?
    } else {
        vec![[1.0; 3]; faces.len()]
    };
    for (f, n) in faces.iter().zip(&normals) {
        let size = crate::input::faces::size(model, &f.corners);
        if let [a, b] = f.corners[..] {
            // A liquid row's first value is a pressure along the normal.
            let t = [0, 1].map(|c| {
                let t = f.traction[c];
                if normal {
                    n.map(|v| v * t[0])
                } else {
                    t
                }
            });
            for (node, force) in edge_forces(model, [a, b], size, t) {
                for d in 0..3 {
                    out[node][d] += force[d];
                }
            }
            continue;
        }
        let t: Vec<[f64; 3]> = f
            .traction
            .iter()
            .map(|t| [0, 1, 2].map(|d| n[d] * t[d]))
            .collect();
        let ids = &f.corners;
        for i in 0..3 {
            let (j, l) = ((i + 1) % 3, (i + 2) % 3);
            for d in 0..3 {
                out[ids[i]][d] += size / 12.0 * (2.0 * t[i][d] + t[j][d] + t[l][d]);
            }
        }
    }
    Ok(())
}
