//! TOML scenes for Gmsh meshes: materials per physical volume, fixities per physical surface or
//! plane selector, tractions, gravity, time, Courant number, damping and output interval.
//!
//! Units are Anura3D's: kN, m, s, t; densities are given in kg/m³ (divided by 1000 here), moduli
//! and tractions in kPa. Example (`testdata/column_gravity.toml` with a Mohr–Coulomb law):
//!
//! ```toml
//! mesh = "column_tet4.msh"        # relative to the scene file
//! integration = "points"          # or "mixed" (Anura3D's MPM-MP / MPM-MIXED); optional
//! objective_stress = false        # Anura3D's objective stress rate, for large rotations
//! strain_smoothing = false        # Anura3D's strain smoothing (eases volumetric locking)
//! pic_blend = 0.0                 # share of PIC in the points' velocity update (0: FLIP)
//! gradient = "element"            # or "ddmp", "ddmp_blended" (dual-domain gradients)
//! [time]
//! end = 0.5                       # s
//! courant = 0.5
//! output_interval = 0.05
//! [gravity]
//! vector = [0.0, -9.81, 0.0]      # m/s²
//! [damping]
//! local = 0.75
//! [[material]]
//! physical = "soil"
//! density = 2000.0                # kg/m³
//! young = 10000.0                 # kPa
//! poisson = 0.3
//! law = "mohr_coulomb"            # default "linear_elasticity"
//! friction_angle = 30.0           # degrees
//! cohesion = 5.0                  # kPa
//! dilatancy_angle = 0.0           # degrees (default 0)
//! tensile_strength = 0.0          # kPa (default 0)
//! points_per_element = 4
//! [[fixity]]
//! physical = "bottom"
//! fixed = [true, true, true]      # x y z
//! [[fixity]]
//! plane = "x = 0"
//! fixed = [true, false, false]
//! [[fixity]]                      # a rigid wall normal to the one "fixed" axis: the body
//! plane = "x = 2.0"               # presses on it, slides along it against Coulomb friction
//! fixed = [true, false, false]    # (0: smooth) or leaves it (dry scenes; the mesh must lie
//! friction = 0.5                  # on one side of it)
//! [[traction]]
//! physical = "top"
//! traction = [0.0, -10.0, 0.0]    # kPa; or pressure = 10.0 (kPa, normal to each face,
//!                                 # pushing into the body: a tunnel's or a pile's wall)
//! ramp = 0.0                      # s to reach full load (0: sudden)
//! [[velocity]]                    # a rough rigid platen pushed down (nodes of a surface)
//! physical = "top"                # or plane = "y = 1.0"; a physical volume: its points
//! velocity = [0.0, -0.01, 0.0]    # m/s
//! components = [true, true, true] # prescribed components (default: all three)
//! ramp = 0.0                      # s to reach full velocity (0: at once)
//! name = "platen"                 # in reaction.csv (default: the physical or plane)
//! ```
//!
//! Each law takes its own parameters, Anura3D's keys in lower case
//! ([`crate::material::law::keys`]; `law = "strain_softening_mohr_coulomb"` takes
//! `peak_cohesion`, `residual_cohesion`, `peak_friction_angle`, ... instead); a key of another
//! law is refused.
//! Initial stresses, per material: `k0 = 0.5` starts its points from Anura3D's K0 procedure
//! (gravity along -y, no ramp): σ'yy = depth below the ground (`[gravity] k0_surface`, default
//! the highest node) × the material's *own* unit weight (not the weight of the materials
//! actually above it), less the hydrostatic pore pressure when saturated, at each element's
//! centroid, σ'xx = σ'zz = K0 σ'yy; `initial_stress = [sxx, syy, szz, sxy, syz, szx]` (kPa,
//! tension positive) a uniform effective stress instead ([`crate::input::initial_stress`]).
//!
//! Each table of the scene has a file here with its reader, its checks and the table of its
//! keys ([`reference::Table`]); [`reference_markdown`] renders them all as the scene reference.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::input::case::{
    Body, BoundaryConditions, Case, CriticalStepRule, Drag, Execution, LoadCurve, Loading,
    Numerics, StartState, TimeControls,
};

mod absorbing;
mod consolidation;
mod contact;
mod curve;
mod damping;
mod fixity;
mod gravity;
mod grid;
mod initial_stress;
mod keys;
mod material;
mod mesh;
mod moving_mesh;
mod numerics;
pub mod reference;
mod time;
mod traction;
mod velocity;

pub use material::{LiquidInput, MaterialInput};
pub use reference::reference_markdown;
pub use traction::{add_face_loads, TractionInput};
pub use velocity::{VelocityInput, VelocityTarget};

use keys::{key, Table};

/// The keys at the top level of a scene (the tables among them have sections of their own).
#[rustfmt::skip]
pub(crate) const TOP_LEVEL: Table = Table {
    header: "",
    about: "The mesh, the numerical choices, and the tables below.",
    keys: &[
        key("mesh", "string", "required", "", "the Gmsh mesh (.msh), relative to the scene file"),
        key("precision", "string", "\"f64\"", "", "precision of the particle and grid state: \"f64\" or \"f32\" (--precision overrides it)"),
        key("integration", "string", "\"points\"", "", "\"points\" (Anura3D's MPM-MP) or \"mixed\" (MPM-MIXED, degree of filling 0.9)"),
        key("section", "string", "\"plane_strain\" (2D)", "", "a triangle mesh's section: \"plane_strain\" or \"axisymmetric\" (x the radius, y the axis)"),
        key("objective_stress", "bool", "false", "", "Anura3D's objective stress rate (APPLY_OBJECTIVE_STRESS), for large rotations"),
        key("strain_smoothing", "bool", "false", "", "Anura3D's strain smoothing (STRAIN_SMOOTHING): eases volumetric locking of linear elements"),
        key("pic_blend", "float", "0 (FLIP)", "", "share of PIC in the points' velocity update, in [0, 1]"),
        key("gradient", "string", "\"element\"", "", "the points' gradients on the mesh's elements: \"element\" (their own), \"ddmp\" (dual-domain: continuous across faces) or \"ddmp_blended\" (with the element's own towards its centroid); a study option (docs/design.md §4.21)"),
        key("time", "table", "required", "", "`[time]`"),
        key("gravity", "table", "none", "", "`[gravity]`"),
        key("damping", "table", "none", "", "`[damping]`"),
        key("grid", "table", "none (the mesh's elements)", "", "`[grid]`"),
        key("material", "array of tables", "required", "", "`[[material]]`, one per material group"),
        key("fixity", "array of tables", "none", "", "`[[fixity]]`"),
        key("traction", "array of tables", "none", "", "`[[traction]]`"),
        key("velocity", "array of tables", "none", "", "`[[velocity]]`"),
        key("absorbing", "array of tables", "none", "", "`[[absorbing]]`"),
        key("contact", "array of tables", "none", "", "`[[contact]]`"),
        key("moving_mesh", "table", "none", "", "`[moving_mesh]`"),
        key("probes", "[integer, ...]", "none", "", "material-point ids (1-based) written to history.csv"),
        key("consolidation", "table", "none", "", "`[consolidation]`"),
    ],
};

/// The scene file's content.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Scene {
    mesh: PathBuf,
    /// "f64" (default) or "f32".
    #[serde(default)]
    precision: Option<String>,
    /// "points" (default; Anura3D's MPM-MP) or "mixed" (MPM-MIXED).
    #[serde(default)]
    integration: Option<String>,
    /// A 2D (triangle) mesh's section: "plane_strain" (default) or "axisymmetric" (x the
    /// radius, y the axis).
    #[serde(default)]
    section: Option<String>,
    /// Anura3D's objective stress rate (`APPLY_OBJECTIVE_STRESS`): on for large rotations.
    #[serde(default)]
    objective_stress: bool,
    /// Anura3D's strain smoothing (`STRAIN_SMOOTHING`): each element's volumetric strain
    /// increment replaced by a nodal average (eases volumetric locking of linear tetrahedra).
    #[serde(default)]
    strain_smoothing: bool,
    /// Share of PIC in the points' velocity update (0, the default, is Anura3D's FLIP).
    #[serde(default)]
    pic_blend: f64,
    /// The points' gradients on the mesh's elements: "element" (default), "ddmp" or
    /// "ddmp_blended".
    #[serde(default)]
    gradient: Option<String>,
    time: time::Time,
    #[serde(default)]
    gravity: Option<gravity::Gravity>,
    #[serde(default)]
    damping: Option<damping::Damping>,
    #[serde(default)]
    grid: Option<grid::Grid>,
    material: Vec<material::Material>,
    #[serde(default)]
    fixity: Vec<fixity::Fixity>,
    #[serde(default)]
    traction: Vec<traction::Traction>,
    #[serde(default)]
    velocity: Vec<velocity::Velocity>,
    #[serde(default)]
    absorbing: Vec<absorbing::Absorbing>,
    #[serde(default)]
    contact: Vec<contact::Contact>,
    #[serde(default)]
    moving_mesh: Option<moving_mesh::MovingMesh>,
    #[serde(default)]
    probes: Vec<u32>,
    #[serde(default)]
    consolidation: Option<consolidation::Consolidation>,
}

/// Errors in a scene, naming the file and the item.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// TOML syntax or an unknown/missing key (the message carries line and column).
    #[error("{file}: {message}")]
    Parse {
        /// Scene file.
        file: String,
        /// What the TOML reader said.
        message: String,
    },
    /// A value or reference that cannot be used.
    #[error("{file}: {item}: {message}")]
    Invalid {
        /// Scene file.
        file: String,
        /// The offending item, e.g. `material "soil"`.
        item: String,
        /// What is wrong.
        message: String,
    },
    /// The mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] mpm_shared::Error),
}

/// A scene item that cannot be used, and why: a [`SceneError::Invalid`] before it names the
/// file.
#[derive(Debug)]
struct Refusal {
    item: String,
    message: String,
}

/// The refusal of `item` for `message`.
fn refuse(item: impl Into<String>, message: impl Into<String>) -> Refusal {
    Refusal {
        item: item.into(),
        message: message.into(),
    }
}

impl Refusal {
    /// The refusal as an error of the scene file `file`.
    fn in_file(self, file: &str) -> SceneError {
        SceneError::Invalid {
            file: file.to_string(),
            item: self.item,
            message: self.message,
        }
    }
}

/// A scene resolved against its mesh: the case it runs, plus the scene's own values that the
/// case no longer holds as written (for exporting it to another program).
#[derive(Debug, Clone)]
pub struct Resolved {
    /// The case the scene runs.
    pub case: Case,
    /// The scene's material entries by model material index (entry 0 unused).
    pub materials: Vec<Option<MaterialInput>>,
    /// The scene's tractions in file order.
    pub tractions: Vec<TractionInput>,
    /// The scene's prescribed velocities in file order.
    pub velocities: Vec<VelocityInput>,
}

/// Reads a scene file and builds the case it describes.
pub fn load(path: &Path) -> Result<Case, SceneError> {
    resolve(path).map(|r| r.case)
}

/// Reads a scene file into the case it describes and the scene values behind it.
pub fn resolve(path: &Path) -> Result<Resolved, SceneError> {
    let file = path.display().to_string();
    let scene = read(path, &file)?;
    let mesh = mesh::Mesh::read(path, &scene.mesh)?;
    resolve_sections(path, &scene, mesh).map_err(|r| r.in_file(&file))
}

/// The scene file's text as TOML.
fn read(path: &Path, file: &str) -> Result<Scene, SceneError> {
    // (The error names the file itself: only the reason goes in its message.)
    let text = mpm_shared::io::read_parameter_text(path).map_err(|e| SceneError::Parse {
        file: file.to_string(),
        message: e.reason(),
    })?;
    toml::from_str(&text).map_err(|e| SceneError::Parse {
        file: file.to_string(),
        message: e.to_string(),
    })
}

/// The scene's sections resolved against the mesh, section by section in the order their
/// refusals are reported, then put together as the case.
fn resolve_sections(path: &Path, scene: &Scene, mut mesh: mesh::Mesh) -> Result<Resolved, Refusal> {
    mesh.set_section(scene.section.as_deref())?;
    gravity::check_plane(scene.gravity.as_ref(), &mesh)?;
    time::check_courant(&scene.time)?;
    numerics::check_pic_blend(scene.pic_blend, !scene.velocity.is_empty())?;
    let materials = material::resolve(&scene.material, &mesh)?;
    // On a background grid everything below resolves on the grid's mesh.
    let (mesh, materials, grid) = match &scene.grid {
        Some(g) => {
            let (mesh, materials, spec) = grid::background(g, mesh, materials)?;
            (mesh, materials, Some(spec))
        }
        None => (mesh, materials, None),
    };
    let supports = fixity::resolve(&scene.fixity, &mesh, &materials)?;
    let scene_dir = path.parent().unwrap_or(Path::new("."));
    let with_contact = !scene.contact.is_empty();
    let velocities = velocity::resolve(
        &scene.velocity,
        &mesh,
        &materials,
        (scene_dir, with_contact),
    )?;
    let contact = contact::resolve(
        &scene.contact,
        &mesh,
        &materials,
        contact::With {
            grid: grid.is_some(),
            nodal_velocity: !velocities.nodal.is_empty(),
            driven: velocities.points.as_ref(),
        },
    )?;
    let gravity = gravity::resolve(scene.gravity.as_ref(), scene_dir)?;
    let structure = contact.as_ref().map(|c| traction::Structure {
        element_material: &materials.element_material,
        points_per_element: &materials.points_per_element,
        material: c.material,
    });
    let loads = traction::resolve(
        &scene.traction,
        &mesh,
        (grid.as_ref(), structure),
        scene_dir,
    )?;
    let absorbing = match (&scene.absorbing[..], &grid) {
        ([], _) => Vec::new(),
        (_, Some(_)) => {
            return Err(refuse(
                "absorbing",
                "not on a background grid ([grid]) yet; run it on the mesh's elements",
            ))
        }
        (entries, None) => absorbing::resolve(entries, &mesh, &materials)?,
    };
    let moving_mesh = moving_mesh::resolve(scene.moving_mesh.as_ref(), &mesh, grid.is_some())?;
    let damping = damping::resolve(scene.damping.as_ref())?;
    let consolidation = consolidation::resolve(scene.consolidation.as_ref())?;
    let by_time_factor =
        consolidation::times(scene.consolidation.as_ref(), &materials, &mesh.model)?;
    let times = time::resolve(&scene.time, by_time_factor)?;
    let initial_state = consolidation::initial_state(consolidation.as_ref(), &materials)?;
    let initial_stress = initial_stress::resolve(
        &materials.inputs,
        initial_stress::Context {
            gravity: scene.gravity.as_ref(),
            consolidation: consolidation.as_ref(),
            model: &mesh.model,
        },
    )?;
    Ok(Sections {
        materials,
        supports,
        velocities,
        gravity,
        loads,
        absorbing,
        contact,
        moving_mesh,
        damping,
        times,
        consolidation,
        initial_state,
        initial_stress,
        precision: numerics::precision(scene.precision.as_deref())?,
        integration: numerics::integration(scene.integration.as_deref())?,
        gradient: numerics::gradient(scene.gradient.as_deref(), grid.is_some())?,
        grid,
    }
    .resolved(path, scene, mesh))
}

/// The scene's sections, resolved: what [`Sections::resolved`] puts together.
struct Sections {
    materials: material::Materials,
    supports: fixity::Supports,
    velocities: velocity::Velocities,
    gravity: ([f64; 3], LoadCurve),
    loads: traction::Loads,
    absorbing: Vec<crate::step::absorbing::AbsorbingNode>,
    contact: Option<crate::step::contact::ContactSpec>,
    moving_mesh: Option<crate::step::moving_mesh::MovingMeshSpec>,
    damping: damping::Resolved,
    times: time::Times,
    consolidation: Option<crate::input::case::ConsolidationSpec>,
    initial_state: Option<crate::input::case::UndrainedState>,
    initial_stress: Option<crate::input::initial_stress::InitialStress>,
    precision: crate::input::case::Precision,
    integration: crate::input::case::Integration,
    gradient: crate::input::case::Gradient,
    grid: Option<crate::basis::grid::GridSpec>,
}

impl Sections {
    /// The case the scene at `path` runs on `mesh`, with the solver's choices for scenes, and
    /// the scene's entries behind it.
    fn resolved(self, path: &Path, scene: &Scene, mesh: mesh::Mesh) -> Resolved {
        let (gravity, gravity_curve) = self.gravity;
        let model = mesh.model;
        let (elements, nodes) = (model.element_count(), model.node_count());
        let case = Case {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default(),
            inputs: vec![path.display().to_string(), mesh.name],
            model,
            body: Body {
                materials: self.materials.specs,
                element_material: self.materials.element_material,
                points_per_element: self.materials.points_per_element,
                input_element: (0..elements as u32).collect(),
                input_node: (0..nodes as u32).collect(),
            },
            boundary: BoundaryConditions {
                fixed: self.supports.fixed,
                liquid_fixed: self.supports.liquid_fixed,
                walls: self.supports.walls,
                prescribed: self.velocities.points,
                nodal_velocity: self.velocities.nodal,
                moving_mesh: self.moving_mesh,
                contact: self.contact,
                absorbing: self.absorbing,
                absorbing_rule: Default::default(),
            },
            loads: Loading {
                traction: self.loads.traction,
                structure_traction: self.loads.structure_traction,
                point_loads: Vec::new(),
                traction_curve: self.loads.curve,
                liquid_traction: vec![[0.0; 3]; nodes],
                liquid_curve: LoadCurve::Step,
                liquid_load_on_mixture: true,
                gravity,
                gravity_curve,
            },
            time: TimeControls {
                courant: scene.time.courant,
                courant_item: format!("{}: time.courant", path.display()),
                end_time: self.times.end,
                output_times: self.times.outputs,
                max_steps: scene.time.max_steps,
                quasi_static: None,
                anura3d_time_step: false,
                critical_step: CriticalStepRule::AllElements,
                initial_step: None,
            },
            numerics: Numerics {
                damping: self.damping.local,
                objective_stress: scene.objective_stress,
                pic_blend: scene.pic_blend,
                integration: self.integration,
                damping_rule: self.damping.rule,
                drag: Drag::Implicit,
                smooth_pressure: true,
                fixed_liquid_mass: false,
                hoop_in_volume: true,
                strain_smoothing: scene.strain_smoothing,
                bulk_viscosity: self.damping.bulk,
                mass_scaling: scene.time.mass_scaling,
                scheme: scene.time.scheme(),
                precision: self.precision,
                grid: self.grid,
                gradient: self.gradient,
            },
            start: StartState {
                consolidation: self.consolidation,
                initial_state: self.initial_state,
                initial_stress: self.initial_stress,
            },
            run: Execution {
                guards: Default::default(),
                probes: scene.probes.clone(),
                engine: Default::default(),
            },
        };
        Resolved {
            case,
            materials: self.materials.inputs,
            tractions: self.loads.inputs,
            velocities: self.velocities.inputs,
        }
    }
}
