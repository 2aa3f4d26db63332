//! Anura3D cases (GOM + CPS) turned into a [`Case`]: dry and saturated
//! (`saturated_material_coupled`) materials with the laws of [`crate::material::law::KNOWN`]
//! (linear elasticity, Mohr–Coulomb, strain-softening Mohr–Coulomb), fixities of both phases,
//! face loads on nodes and on material points, gravity, local damping, load steps, quasi-static
//! convergence, objective stress, MPM-MP and MPM-MIXED integration, with Anura3D's two-phase
//! time step, liquid damping and (per `STRAIN_SMOOTHING`) pressure smoothing. Features this
//! solver does not model yet are refused with the item named, never silently ignored.

use std::path::Path;

use mpm_shared::cps::{Cps, Method, Multiplier, Settings};
use mpm_shared::Model;

use crate::input::case::{
    Body, BoundaryConditions, Case, Execution, Integration, LoadCurve, Loading, Numerics,
    QuasiStatic, StartState, TimeControls,
};

mod absorbing;
mod contact;
mod k0;
mod keys;
mod loads;
mod materials;
mod velocities;

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

impl LoadSteps {
    /// The load steps the CPS settings ask for.
    fn of(s: &Settings) -> Self {
        LoadSteps {
            count: s.load_steps,
            duration: s.time_per_load_step,
            quasi_static: s.quasi_static,
        }
    }
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

/// The case's two files as read, and their names in messages.
struct Input<'a> {
    /// The GOM's path (a refused section's line is looked up in the file).
    gom: &'a Path,
    /// The GOM's model.
    model: Model,
    /// The CPS's entries.
    cps: Cps,
    /// The CPS's typed settings.
    settings: Settings,
    /// The GOM as messages name it.
    gfile: String,
    /// The CPS as messages name it.
    cfile: String,
}

impl<'a> Input<'a> {
    /// Reads the GOM `gom` and the CPS `cps_path`, warning of coincident nodes and of CPS keys
    /// the reader does not know.
    fn read(gom: &'a Path, cps_path: &Path) -> Result<Self, CaseError> {
        let gfile = mpm_shared::display_name(gom);
        let cfile = cps_path.display().to_string();
        let model = mpm_shared::read_model(gom)?;
        let pairs = mpm_shared::coincident::pairs(&model);
        if let Some(w) = mpm_shared::coincident::warning(&gfile, &pairs) {
            log::warn!("{w}");
        }
        let data = mpm_shared::io::read_parameters(cps_path)?;
        let (cps, warnings) = Cps::read(&data, &cfile)?;
        for w in warnings {
            log::warn!("{w}");
        }
        let settings = cps.settings()?;
        Ok(Input {
            gom,
            model,
            cps,
            settings,
            gfile,
            cfile,
        })
    }
}

/// Whether the CPS switches `$$STRAIN_SMOOTHING` on (its first word other than 0).
fn strain_smoothing(cps: &Cps) -> bool {
    cps.get("STRAIN_SMOOTHING").is_some_and(|e| {
        e.lines
            .first()
            .and_then(|l| l.split_whitespace().next())
            .is_some_and(|w| w != "0")
    })
}

/// Reads `gom` and `cps` into a case. Returns the case and the CPS settings.
pub fn load(gom: &Path, cps_path: &Path) -> Result<(Case, Settings), CaseError> {
    let input = Input::read(gom, cps_path)?;
    let integration = check_settings(&input)?;
    // Every other key: modelled, irrelevant, or refused unless inert.
    keys::check_keys(&input)?;
    let materials = materials::read(&input)?;
    let elements = materials::elements(&input, &materials.specs)?;
    // Point ids and messages follow the original input's element numbers (a GOM sfcb ordered
    // carries them); the CPS's ids are input ids unless sfcb --cps marked them as file ids.
    let probes = mpm_shared::points::cps_input_ids(&input.cps, &input.model)?;
    let steps = LoadSteps::of(&input.settings);
    let loads = loads::read(&input, steps, &materials.specs)?;
    let with_contact = contact::switched_on(&input)?;
    let prescribed = velocities::on_points(&input, &materials.specs, steps, with_contact)?;
    let nodal_velocity = velocities::on_nodes(&input, &materials.specs, steps)?;
    let moving_mesh = moving_mesh(&input, &materials.specs)?;
    let with = contact::ContactCase {
        has_nodal_load: (loads.traction.iter().chain(&loads.liquid_traction))
            .flatten()
            .any(|&v| v != 0.0),
        has_point_load: !loads.point_loads.is_empty(),
        has_nodal_velocity: !nodal_velocity.is_empty(),
        moving_mesh_follows: moving_mesh.as_ref().map(|m| m.material),
        prescribed_elements: prescribed
            .as_ref()
            .map(|p| p.rows.iter().map(|r| r.element).collect())
            .unwrap_or_default(),
    };
    let contact = contact::read(&input, &materials.specs, &elements, with)?;
    let absorbing = absorbing::read(&input, &materials.specs)?;
    let k0_case = k0::K0Case {
        coupled: materials.coupled,
        submerged: materials.drained,
        materials: materials.specs.len(),
    };
    let initial_stress = k0::procedure(&input, &materials.k0, k0_case)?;
    if absorbing.is_some() && initial_stress.is_some() {
        // Anura3D presets the boundary's forces from the K0 stresses through an array it never
        // allocates: no defined behaviour to follow.
        return Err(unsupported(
            &input.cfile,
            "$$K0_PROCEDURE",
            "with absorbing boundaries ($$ABSORBING_BOUNDARY_*) Anura3D's start is undefined (it presets their forces from an unallocated array); not modelled",
        ));
    }
    let s = &input.settings;
    let (gm, gravity_curve) = curve(s.gravity_load, steps, &input.cfile, "$$GRAVITY_LOAD")?;
    let gravity = s.gravity_vector.map(|v| v * s.gravity_acceleration * gm);
    let parts = Parts {
        integration,
        materials,
        elements,
        probes,
        loads,
        prescribed,
        nodal_velocity,
        moving_mesh,
        contact,
        absorbing,
        initial_stress,
        gravity: (gravity, gravity_curve),
    };
    Ok(parts.case(input))
}

/// Refuses what the CPS's settings ask for and this solver does not compute: element types
/// of other dimensions, methods other than MPM-MP and MPM-MIXED, a Courant number or load step
/// out of range. Returns the integration.
fn check_settings(input: &Input) -> Result<Integration, CaseError> {
    let (model, s) = (&input.model, &input.settings);
    let (gfile, cfile) = (input.gfile.as_str(), input.cfile.as_str());
    if crate::element::ElementKind::of(model.dimension, model.element_type).is_none() {
        return Err(unsupported(
            gfile,
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
                    cfile,
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
                cfile,
                "$$COMPUTATION_METHOD",
                format!("{m} is not an MPM method"),
            ))
        }
    };
    // Above 1 is refused before the run unless --force (Case::check_courant).
    if !(s.courant > 0.0 && s.courant.is_finite()) {
        return Err(unsupported(
            cfile,
            "$$COURANT_NUMBER",
            format!("must be in (0, 1], got {}", s.courant),
        ));
    }
    if let (Some(_), Some(alpha)) = (s.bulk_viscosity, s.local_damping.filter(|&a| a > 0.0)) {
        // Anura3D damps the force before it subtracts the viscous one; here the viscous
        // pressure is part of the internal force the damping acts on.
        return Err(unsupported(
            cfile,
            "$$BULK_VISCOSITY_DAMPING",
            format!("with $$HOMOGENEOUS_LOCAL_DAMPING on ({alpha}) is not modelled: Anura3D damps the force before it subtracts the viscous one; switch one of them off"),
        ));
    }
    if let Some(f) = s.mass_scaling {
        // Anura3D's own range check is commented out; a factor must at least divide.
        if !(f > 0.0 && f.is_finite()) {
            return Err(unsupported(
                cfile,
                "$$MASS_SCALING",
                format!("expected '1 f' with a positive factor f, got 1 {f}"),
            ));
        }
    }
    if let Some([b1, b2]) = s.bulk_viscosity {
        // Anura3D asserts both coefficients positive.
        if !(b1 > 0.0 && b2 > 0.0 && b1.is_finite() && b2.is_finite()) {
            return Err(unsupported(
                cfile,
                "$$BULK_VISCOSITY_DAMPING",
                format!("expected '1 b1 b2' with b1 and b2 positive (as Anura3D), got 1 {b1} {b2}"),
            ));
        }
    }
    if !(s.time_per_load_step > 0.0) {
        return Err(unsupported(
            cfile,
            "$$TIME_PER_LOADSTEP",
            format!("must be positive, got {}", s.time_per_load_step),
        ));
    }
    Ok(integration)
}

/// The GOM's moving mesh, whose reference material must be defined; `None` without one.
fn moving_mesh(
    input: &Input,
    materials: &[Option<crate::input::case::MaterialSpec>],
) -> Result<Option<crate::step::moving_mesh::MovingMeshSpec>, CaseError> {
    let gfile = input.gfile.as_str();
    let moving_mesh = crate::step::moving_mesh::read(&input.model)
        .map_err(|(item, why)| unsupported(gfile, &item, why))?;
    if let Some(mm) = &moving_mesh {
        if !matches!(materials.get(mm.material as usize), Some(Some(_))) {
            return Err(unsupported(
                gfile,
                "$$MOVING_MESH_REFERENCE_MATERIAL_INDEX",
                format!("material {} is not defined", mm.material),
            ));
        }
    }
    Ok(moving_mesh)
}

/// The parts of a case read from its files: what [`Parts::case`] puts together.
struct Parts {
    integration: Integration,
    materials: materials::Materials,
    elements: materials::Elements,
    probes: Vec<u32>,
    loads: loads::Loads,
    prescribed: Option<crate::step::prescribed::PrescribedVelocity>,
    nodal_velocity: Vec<crate::step::nodal_velocity::NodalVelocitySet>,
    moving_mesh: Option<crate::step::moving_mesh::MovingMeshSpec>,
    contact: Option<crate::step::contact::ContactSpec>,
    /// The absorbing boundaries' rows and rule.
    absorbing: Option<(
        Vec<crate::step::absorbing::AbsorbingNode>,
        crate::step::absorbing::AbsorbingRule,
    )>,
    initial_stress: Option<crate::input::initial_stress::InitialStress>,
    /// The gravity acceleration at full multiplier, and its curve.
    gravity: ([f64; 3], LoadCurve),
}

impl Parts {
    /// The case, with Anura3D's choices where the files leave them to the program, and the
    /// CPS's settings.
    fn case(self, input: Input) -> (Case, Settings) {
        let s = input.settings;
        let n = input.model.node_count();
        let (absorbing, absorbing_rule) = self.absorbing.unwrap_or_default();
        // With absorbing boundaries Anura3D fixes the liquid where the solid is fixed, whatever
        // the liquid's own fixities (its PBoundaryWater becomes PBoundary).
        let liquid_fixed = if absorbing.is_empty() {
            self.loads.liquid_fixed
        } else {
            self.loads.fixed.clone()
        };
        let case = Case {
            name: input
                .gom
                .file_stem()
                .map(|x| x.to_string_lossy().to_string())
                .unwrap_or_default(),
            inputs: vec![input.gfile, input.cfile.clone()],
            model: input.model,
            body: Body {
                materials: self.materials.specs,
                element_material: self.elements.element_material,
                points_per_element: self.elements.points_per_element,
                input_element: self.elements.input_element,
                input_node: (0..n as u32).collect(),
            },
            boundary: BoundaryConditions {
                fixed: self.loads.fixed,
                liquid_fixed,
                walls: Vec::new(),
                prescribed: self.prescribed,
                nodal_velocity: self.nodal_velocity,
                moving_mesh: self.moving_mesh,
                contact: self.contact,
                absorbing,
                absorbing_rule,
            },
            loads: Loading {
                traction: self.loads.traction,
                structure_traction: Vec::new(),
                point_loads: self.loads.point_loads,
                traction_curve: self.loads.traction_curve,
                liquid_traction: self.loads.liquid_traction,
                liquid_curve: self.loads.liquid_curve,
                liquid_load_on_mixture: false,
                gravity: self.gravity.0,
                gravity_curve: self.gravity.1,
            },
            time: TimeControls {
                courant: s.courant,
                courant_item: format!("{}: $$COURANT_NUMBER", input.cfile),
                end_time: s.load_steps as f64 * s.time_per_load_step,
                output_times: (1..=s.load_steps)
                    .map(|k| k as f64 * s.time_per_load_step)
                    .collect(),
                max_steps: None,
                quasi_static: s.quasi_static.then_some(QuasiStatic {
                    max_steps: s.max_time_steps,
                    force_tolerance: s.tolerated_error_solid[0],
                    energy_tolerance: s.tolerated_error_solid[1],
                    liquid_force_tolerance: s.tolerated_error_liquid[0],
                }),
                anura3d_time_step: true,
                critical_step: crate::input::case::CriticalStepRule::OccupiedEachStep,
                initial_step: Some(ANURA3D_FIRST_STEP),
            },
            numerics: Numerics {
                damping: s.local_damping.unwrap_or(0.0),
                objective_stress: s.objective_stress,
                pic_blend: 0.0,
                integration: self.integration,
                damping_rule: crate::input::case::DampingRule::Anura3d,
                drag: crate::input::case::Drag::Implicit,
                smooth_pressure: false,
                fixed_liquid_mass: true,
                hoop_in_volume: false,
                strain_smoothing: strain_smoothing(&input.cps),
                bulk_viscosity: s.bulk_viscosity.map(|[linear, quadratic]| {
                    crate::step::bulk_viscosity::BulkViscosity {
                        linear,
                        quadratic,
                        sign: crate::step::bulk_viscosity::Quadratic::Anura3d,
                    }
                }),
                mass_scaling: s.mass_scaling.unwrap_or(1.0),
                scheme: crate::input::case::Scheme::Explicit,
                grid: None,
                gradient: crate::input::case::Gradient::Element,
                precision: crate::input::case::Precision::F64,
            },
            start: StartState {
                consolidation: None,
                initial_state: None,
                initial_stress: self.initial_stress,
            },
            run: Execution {
                guards: Default::default(),
                probes: self.probes,
                engine: Default::default(),
            },
        };
        (case, s)
    }
}
