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
//! `law = "strain_softening_mohr_coulomb"` takes `peak_cohesion`, `residual_cohesion`,
//! `peak_friction_angle`, `residual_friction_angle`, `peak_dilatancy_angle`,
//! `residual_dilatancy_angle` and `shape_factor` instead; a key of another law is refused.
//! Initial stresses, per material: `k0 = 0.5` starts its points from Anura3D's K0 procedure
//! (gravity along -y, no ramp): σ'yy = depth below the ground (`[gravity] k0_surface`, default
//! the highest node) × the material's *own* unit weight (not the weight of the materials
//! actually above it), less the hydrostatic pore pressure when saturated, at each element's
//! centroid, σ'xx = σ'zz = K0 σ'yy; `initial_stress = [sxx, syy, szz, sxy, syz, szx]` (kPa,
//! tension positive) a uniform effective stress instead ([`crate::input::initial_stress`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use mpm_shared::msh::{self, MshMesh};
use mpm_shared::Model;

use crate::input::case::{Case, Integration, LoadCurve, MaterialSpec};
use crate::input::case::{ConsolidationSpec, Start, UndrainedState};
use crate::input::initial_stress::{
    k0_unit_weights, InitialStress, K0Material, K0Pores, K0Procedure, MaterialStart,
    DEFAULT_MAX_SUCTION,
};
use crate::material::law::LawSpec;
use crate::material::liquid::LiquidSpec;
use crate::step::nodal_velocity::{NodalVelocitySet, PrescribedNode};
use crate::step::prescribed::{PrescribedElement, PrescribedVelocity};
use crate::step::wall_friction::WallAxis;

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
    time: Time,
    #[serde(default)]
    gravity: Option<Gravity>,
    #[serde(default)]
    damping: Option<Damping>,
    material: Vec<Material>,
    #[serde(default)]
    fixity: Vec<Fixity>,
    #[serde(default)]
    traction: Vec<Traction>,
    #[serde(default)]
    velocity: Vec<Velocity>,
    #[serde(default)]
    probes: Vec<u32>,
    #[serde(default)]
    consolidation: Option<Consolidation>,
}

/// `[consolidation]`: compare with Terzaghi (one saturated material, load on the drained top).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Consolidation {
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

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Time {
    #[serde(default)]
    end: Option<f64>,
    #[serde(default = "default_courant")]
    courant: f64,
    #[serde(default)]
    output_interval: Option<f64>,
    #[serde(default)]
    max_steps: Option<u64>,
}

fn default_courant() -> f64 {
    0.9
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Gravity {
    vector: [f64; 3],
    #[serde(default)]
    ramp: f64,
    /// Height (y, m) of the ground surface for the K0 procedure; default: the highest node.
    #[serde(default)]
    k0_surface: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Damping {
    local: f64,
    /// "phases" (default) or "anura3d" (see `case::DampingRule`).
    #[serde(default)]
    rule: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Material {
    physical: String,
    density: f64,
    young: f64,
    poisson: f64,
    /// The law by Anura3D's name (`crate::material::law::KNOWN`).
    #[serde(default = "default_law")]
    law: String,
    // The plastic laws' parameters: Anura3D's keys in lower case (angles in degrees, kPa).
    friction_angle: Option<f64>,
    cohesion: Option<f64>,
    dilatancy_angle: Option<f64>,
    tensile_strength: Option<f64>,
    peak_cohesion: Option<f64>,
    residual_cohesion: Option<f64>,
    peak_friction_angle: Option<f64>,
    residual_friction_angle: Option<f64>,
    peak_dilatancy_angle: Option<f64>,
    residual_dilatancy_angle: Option<f64>,
    shape_factor: Option<f64>,
    /// Points per element; default 4 in tetrahedra, 3 in triangles.
    #[serde(default)]
    points_per_element: Option<u32>,
    #[serde(default)]
    liquid: Option<Liquid>,
    /// K0: the points start with Anura3D's K0 stresses.
    #[serde(default)]
    k0: Option<f64>,
    /// A uniform initial effective stress (kPa, tension positive; xx yy zz xy yz zx).
    #[serde(default)]
    initial_stress: Option<[f64; 6]>,
}

fn default_law() -> String {
    "linear_elasticity".into()
}

/// The scene's name of Anura3D's law parameter `key`.
fn scene_key(key: &str) -> String {
    match key {
        "YOUNG_MODULUS" => "young".into(),
        "POISSON_RATIO" => "poisson".into(),
        k => k.to_ascii_lowercase(),
    }
}

impl Material {
    /// The law with its parameters: each given key must belong to the law, each key of the law
    /// must be given (Mohr–Coulomb's dilatancy angle and tensile strength default to 0).
    fn law(&self) -> Result<LawSpec, String> {
        let keys = crate::material::law::keys(&self.law).ok_or_else(|| {
            format!(
                "law {:?} is not known (known: {})",
                self.law,
                crate::material::law::KNOWN.join(", ")
            )
        })?;
        let given = [
            ("YOUNG_MODULUS", Some(self.young)),
            ("POISSON_RATIO", Some(self.poisson)),
            ("FRICTION_ANGLE", self.friction_angle),
            ("COHESION", self.cohesion),
            ("DILATANCY_ANGLE", self.dilatancy_angle),
            ("TENSILE_STRENGTH", self.tensile_strength),
            ("PEAK_COHESION", self.peak_cohesion),
            ("RESIDUAL_COHESION", self.residual_cohesion),
            ("PEAK_FRICTION_ANGLE", self.peak_friction_angle),
            ("RESIDUAL_FRICTION_ANGLE", self.residual_friction_angle),
            ("PEAK_DILATANCY_ANGLE", self.peak_dilatancy_angle),
            ("RESIDUAL_DILATANCY_ANGLE", self.residual_dilatancy_angle),
            ("SHAPE_FACTOR", self.shape_factor),
        ];
        for (key, value) in given {
            if value.is_some() && !keys.contains(&key) {
                return Err(format!(
                    "{} does not belong to law {} (its keys: {})",
                    scene_key(key),
                    self.law,
                    keys.iter()
                        .map(|k| scene_key(k))
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
        let mohr_coulomb = self.law == "mohr_coulomb";
        let get = |k: &str| {
            given
                .iter()
                .find(|g| g.0 == k)
                .and_then(|g| g.1)
                .or(match k {
                    "DILATANCY_ANGLE" | "TENSILE_STRENGTH" if mohr_coulomb => Some(0.0),
                    _ => None,
                })
        };
        if let Some(k) = keys.iter().find(|k| get(k).is_none()) {
            return Err(format!("law {} needs {}", self.law, scene_key(k)));
        }
        LawSpec::by_name(&self.law, &get).map_err(|e| e.to_string())
    }
}

/// The pore liquid of a saturated material (`[material.liquid]`); `density` of the material is
/// then the grains' density ρs.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Liquid {
    porosity: f64,
    density: f64,
    bulk_modulus: f64,
    intrinsic_permeability: f64,
    viscosity: f64,
    #[serde(default)]
    initial_pore_pressure: f64,
}

/// Points per element when a material does not say: the 4-point rule of tetrahedra, the
/// 3-point rule of triangles (Anura3D's usual choices).
fn default_points(model: &Model) -> u32 {
    if model.dimension.coords() == 2 {
        3
    } else {
        4
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Fixity {
    #[serde(default)]
    physical: Option<String>,
    #[serde(default)]
    plane: Option<String>,
    fixed: [bool; 3],
    /// Liquid fixities (impermeable directions); default: those of the solid.
    #[serde(default)]
    liquid: Option<[bool; 3]>,
    /// Coulomb friction coefficient μ of a rigid wall: the one "fixed" component is the wall's
    /// normal, which the body may press on or leave, the others slide against friction
    /// ([`crate::step::wall_friction`]).
    #[serde(default)]
    friction: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Traction {
    physical: String,
    /// A uniform traction vector (kPa).
    #[serde(default)]
    traction: Option<[f64; 3]>,
    /// Or a pressure (kPa) normal to each face, pushing into the body.
    #[serde(default)]
    pressure: Option<f64>,
    #[serde(default)]
    ramp: f64,
}

/// `[[velocity]]`: a prescribed velocity on the nodes of a physical surface or a plane, or on
/// the material points of a physical volume.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Velocity {
    #[serde(default)]
    physical: Option<String>,
    #[serde(default)]
    plane: Option<String>,
    velocity: [f64; 3],
    #[serde(default)]
    components: Option<[bool; 3]>,
    #[serde(default)]
    ramp: f64,
    #[serde(default)]
    name: Option<String>,
}

/// What a `[[velocity]]` entry prescribes.
#[derive(Debug, Clone, PartialEq)]
pub enum VelocityTarget {
    /// Nodes (model ids, 0-based, ascending) of a physical surface or a plane.
    Nodes(Vec<u32>),
    /// The material points of a physical volume's elements (the case's material-point set).
    Volume(String),
}

/// A `[[velocity]]` entry resolved against the mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct VelocityInput {
    /// The set's name (`name`, else the physical or plane string).
    pub name: String,
    /// What it prescribes.
    pub target: VelocityTarget,
    /// Velocity (m/s).
    pub velocity: [f64; 3],
    /// Prescribed components.
    pub components: [bool; 3],
    /// Seconds to full velocity (0: at once).
    pub ramp: f64,
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

/// What a mesh's physical groups are called: materials fill groups of the elements' own
/// dimension (volumes in 3D, surfaces in 2D), loads and fixities sit on groups one below
/// (surfaces in 3D, curves in 2D).
#[derive(Debug, Clone, Copy)]
struct Groups {
    /// The boundary groups' dimension.
    dim: usize,
    /// Name of a material group in messages.
    material: &'static str,
    /// Name of a boundary group in messages.
    boundary: &'static str,
}

impl Groups {
    fn of(model: &Model) -> Self {
        if model.dimension.coords() == 2 {
            Groups {
                dim: 1,
                material: "physical surface",
                boundary: "physical curve",
            }
        } else {
            Groups {
                dim: 2,
                material: "physical volume",
                boundary: "physical surface",
            }
        }
    }
}

/// The node lists (`.msh` node indices, corners first) of the boundary elements (triangles in
/// 3D, lines in 2D) in the physical group `name` of dimension `dim`, or `None` if the mesh has
/// no such group.
fn physical_boundary<'m>(mesh: &'m MshMesh, name: &str, dim: usize) -> Option<Vec<&'m [u32]>> {
    let tag = mesh
        .physical_names
        .iter()
        .find(|p| p.dim == dim && p.name == name)?
        .tag;
    let mut out = Vec::new();
    for set in mesh.sets.iter().filter(|s| s.dim() == dim) {
        for (e, &phys) in set.physical.iter().enumerate() {
            if phys == tag {
                out.push(&set.nodes[e * set.nodes_per..(e + 1) * set.nodes_per]);
            }
        }
    }
    Some(out)
}

/// The faces (model node ids of their corners: three of a triangle in 3D, two of a line in 2D;
/// `u32::MAX` for a corner no element uses) of the boundary group `name`.
fn physical_faces(
    mesh: &MshMesh,
    node_map: &[u32],
    name: &str,
    groups: Groups,
) -> Option<Vec<Vec<u32>>> {
    let faces = physical_boundary(mesh, name, groups.dim)?;
    Some(
        faces
            .iter()
            .map(|f| (0..=groups.dim).map(|k| node_map[f[k] as usize]).collect())
            .collect(),
    )
}

/// For each of the wall's `nodes`, the side of the mesh along `axis`: +1 where the elements
/// around the node lie on its + side, -1 on its - side; `Err(node)` for a node with elements on
/// both sides (or none), which no wall can bound.
fn wall_sides(model: &Model, nodes: &[u32], axis: usize) -> Result<Vec<f64>, u32> {
    // Per node, the lowest and highest element centroid along the axis, relative to the node.
    let mut range = vec![(f64::INFINITY, f64::NEG_INFINITY); model.node_count()];
    let mut on_wall = vec![false; model.node_count()];
    for &n in nodes {
        on_wall[n as usize] = true;
    }
    let corners = model.element_type.corners();
    for e in 0..model.element_count() {
        let el = &model.element(e)[..corners];
        if !el.iter().any(|&n| on_wall[n as usize]) {
            continue;
        }
        let centroid = el
            .iter()
            .map(|&n| model.node(n as usize)[axis])
            .sum::<f64>()
            / corners as f64;
        for &n in el {
            let r = &mut range[n as usize];
            let d = centroid - model.node(n as usize)[axis];
            *r = (r.0.min(d), r.1.max(d));
        }
    }
    nodes
        .iter()
        .map(|&n| match range[n as usize] {
            (lo, _) if lo > 0.0 => Ok(1.0),
            (_, hi) if hi < 0.0 => Ok(-1.0),
            _ => Err(n),
        })
        .collect()
}

/// All nodes (model numbering, corner and mid-edge) of the boundary group `name`.
fn physical_nodes(
    mesh: &MshMesh,
    node_map: &[u32],
    name: &str,
    groups: Groups,
) -> Option<Vec<u32>> {
    let mut out: Vec<u32> = physical_boundary(mesh, name, groups.dim)?
        .iter()
        .flat_map(|f| f.iter().map(|&n| node_map[n as usize]))
        .filter(|&n| n != u32::MAX)
        .collect();
    out.sort_unstable();
    out.dedup();
    Some(out)
}

/// Parses `x = 0.5` style selectors: (axis, value).
fn parse_plane(s: &str) -> Option<(usize, f64)> {
    let (a, v) = s.split_once('=')?;
    let axis = match a.trim() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    Some((axis, v.trim().parse().ok()?))
}

/// A `[[material]]` entry as the scene gives it (densities in kg/m³, as written).
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialInput {
    /// The physical volume it fills (also the material's name).
    pub physical: String,
    /// Density (kg/m³): of the material when dry, of its grains when saturated.
    pub density: f64,
    /// Young's modulus (kPa).
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// The law with all its parameters (defaults filled in).
    pub law: LawSpec,
    /// Material points per element.
    pub points_per_element: u32,
    /// The pore liquid of a saturated material.
    pub liquid: Option<LiquidInput>,
    /// K0 of the K0 procedure, when the material starts from it.
    pub k0: Option<f64>,
    /// A uniform initial effective stress (kPa; xx yy zz xy yz zx).
    pub initial_stress: Option<[f64; 6]>,
}

/// A `[material.liquid]` entry as the scene gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct LiquidInput {
    /// Porosity n.
    pub porosity: f64,
    /// Liquid density (kg/m³).
    pub density: f64,
    /// Bulk modulus of the liquid (kPa).
    pub bulk_modulus: f64,
    /// Intrinsic permeability (m²).
    pub intrinsic_permeability: f64,
    /// Dynamic viscosity (kPa·s).
    pub viscosity: f64,
    /// Pore pressure at t = 0 (kPa).
    pub initial_pore_pressure: f64,
}

/// A `[[traction]]` entry with the faces its physical surface resolved to.
#[derive(Debug, Clone, PartialEq)]
pub struct TractionInput {
    /// The physical surface.
    pub physical: String,
    /// Its faces: model node ids (0-based) of their corners (three of a triangle in 3D, two of
    /// an edge in 2D), in the mesh file's order.
    pub faces: Vec<Vec<u32>>,
    /// Traction vector (kPa; zero for a pressure).
    pub traction: [f64; 3],
    /// Pressure normal to each face, pushing into the body (kPa), instead of `traction`.
    pub pressure: Option<f64>,
    /// Seconds to full load (0: sudden).
    pub ramp: f64,
}

impl TractionInput {
    /// The traction on each face (kPa): the vector, or the pressure along the face's inward
    /// normal (`outward`: the faces' outward unit normals).
    pub fn on_faces(&self, outward: &[[f64; 3]]) -> Vec<[f64; 3]> {
        match self.pressure {
            Some(p) => outward.iter().map(|n| n.map(|c| -p * c)).collect(),
            None => vec![self.traction; self.faces.len()],
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
    // (The error names the file itself: only the reason goes in its message.)
    let text = mpm_shared::io::read_parameter_text(path).map_err(|e| SceneError::Parse {
        file: file.clone(),
        message: e.reason(),
    })?;
    let scene: Scene = toml::from_str(&text).map_err(|e| SceneError::Parse {
        file: file.clone(),
        message: e.to_string(),
    })?;
    let invalid = |item: String, message: String| SceneError::Invalid {
        file: file.clone(),
        item,
        message,
    };
    let mesh_path = path.parent().unwrap_or(Path::new(".")).join(&scene.mesh);
    let data = mpm_shared::io::read_input(&mesh_path)?;
    let mesh_name = mesh_path.display().to_string();
    let msh_mesh = msh::read(&data, &mesh_name)?;
    let (mut model, node_map) = msh::to_model_with_map(&msh_mesh, &mesh_name)?;
    // Triangles make a 2D section, plane strain unless the scene says axisymmetric.
    match (scene.section.as_deref(), model.dimension.coords()) {
        (None | Some("plane_strain"), 2) => {}
        (Some("axisymmetric"), 2) => model.dimension = mpm_shared::Dimension::Axisymmetric,
        (None, _) => {}
        (Some(s @ ("plane_strain" | "axisymmetric")), _) => {
            return Err(invalid(
                "section".into(),
                format!("\"{s}\" is for 2D (triangle) meshes; {mesh_name} is 3D"),
            ))
        }
        (Some(other), _) => {
            return Err(invalid(
                "section".into(),
                format!("expected \"plane_strain\" or \"axisymmetric\", got \"{other}\""),
            ))
        }
    }
    let groups = Groups::of(&model);
    let dim = model.dimension.coords();
    if let Some(g) = scene
        .gravity
        .as_ref()
        .filter(|g| dim == 2 && g.vector[2] != 0.0)
    {
        return Err(invalid(
            "gravity.vector".into(),
            format!(
                "a 2D section lies in the x-y plane: its z component must be 0, got {}",
                g.vector[2]
            ),
        ));
    }
    let t = &scene.time;
    // Above 1 is refused before the run unless --force (Case::check_courant).
    if !(t.courant > 0.0 && t.courant.is_finite()) {
        return Err(invalid(
            "time.courant".into(),
            format!("must be in (0, 1], got {}", t.courant),
        ));
    }
    if !(0.0..=1.0).contains(&scene.pic_blend) {
        return Err(invalid(
            "pic_blend".into(),
            format!("must be in [0, 1], got {}", scene.pic_blend),
        ));
    }
    if scene.pic_blend > 0.0 && !scene.velocity.is_empty() {
        // The PIC part would read a prescribed component as a fixed one (zero).
        return Err(invalid(
            "pic_blend".into(),
            "is not modelled together with [[velocity]] prescriptions; leave it 0 (FLIP)".into(),
        ));
    }
    // Materials: model material k is the k-th physical volume group by tag (see msh::to_model).
    let names: Vec<String> = model.materials().iter().map(|m| m.name.clone()).collect();
    let mut materials = vec![None; names.len() + 1];
    let mut inputs: Vec<Option<MaterialInput>> = vec![None; names.len() + 1];
    let mut points = vec![0u32; names.len() + 1];
    for m in &scene.material {
        let item = format!("material \"{}\"", m.physical);
        let k = names.iter().position(|n| *n == m.physical).ok_or_else(|| {
            invalid(
                item.clone(),
                format!(
                    "no {} of that name in {mesh_name} (it has {names:?})",
                    groups.material
                ),
            )
        })? + 1;
        let law = m.law().map_err(|e| invalid(item.clone(), e))?;
        let spec = match &m.liquid {
            None => MaterialSpec::with_law(&m.physical, m.density, law),
            Some(l) => LiquidSpec::new(
                l.porosity,
                l.density,
                l.bulk_modulus,
                l.intrinsic_permeability,
                l.viscosity,
            )
            .and_then(|liquid| {
                let mut s = MaterialSpec::saturated(&m.physical, m.density, law, liquid)?;
                s.initial_pore_pressure = l.initial_pore_pressure;
                Ok(s)
            }),
        }
        .map_err(|e| invalid(item.clone(), e.to_string()))?;
        materials[k] = Some(spec);
        let count = m.points_per_element.unwrap_or(default_points(&model));
        points[k] = count;
        inputs[k] = Some(MaterialInput {
            physical: m.physical.clone(),
            density: m.density,
            young: m.young,
            poisson: m.poisson,
            law,
            points_per_element: count,
            liquid: m.liquid.as_ref().map(|l| LiquidInput {
                porosity: l.porosity,
                density: l.density,
                bulk_modulus: l.bulk_modulus,
                intrinsic_permeability: l.intrinsic_permeability,
                viscosity: l.viscosity,
                initial_pore_pressure: l.initial_pore_pressure,
            }),
            k0: m.k0,
            initial_stress: m.initial_stress,
        });
    }
    let element_material: Vec<u32> = model
        .element_materials()
        .unwrap_or_default()
        .iter()
        .map(|&m| m as u32)
        .collect();
    for (k, m) in materials.iter().enumerate().skip(1) {
        if m.is_none() && element_material.contains(&(k as u32)) {
            return Err(invalid(
                format!("{} \"{}\"", groups.material, names[k - 1]),
                "has elements but no [[material]] entry".into(),
            ));
        }
    }
    let points_per_element: Vec<u32> = element_material
        .iter()
        .map(|&m| points[m as usize])
        .collect();
    let mut fixed = vec![[false; 3]; model.node_count()];
    let mut liquid_fixed = vec![[false; 3]; model.node_count()];
    let mut walls: Vec<[WallAxis; 3]> = Vec::new();
    let size = (0..3)
        .map(|a| {
            let (lo, hi) = model
                .coords
                .chunks_exact(dim)
                .filter_map(|p| p.get(a))
                .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
            hi - lo
        })
        .fold(0.0, f64::max);
    for f in &scene.fixity {
        let nodes: Vec<u32> = match (&f.physical, &f.plane) {
            (Some(name), None) => {
                physical_nodes(&msh_mesh, &node_map, name, groups).ok_or_else(|| {
                    invalid(
                        format!("fixity \"{name}\""),
                        format!("no {} of that name in {mesh_name}", groups.boundary),
                    )
                })?
            }
            (None, Some(plane)) => {
                let (axis, value) = parse_plane(plane).ok_or_else(|| {
                    invalid(
                        format!("fixity plane \"{plane}\""),
                        "expected 'x = value', 'y = value' or 'z = value'".into(),
                    )
                })?;
                let tol = 1e-9 * size.max(1e-300);
                let found: Vec<u32> = (0..model.node_count() as u32)
                    .filter(|&n| (coordinate(&model, n, axis) - value).abs() <= tol)
                    .collect();
                if found.is_empty() {
                    return Err(invalid(
                        format!("fixity plane \"{plane}\""),
                        "selects no node".into(),
                    ));
                }
                found
            }
            _ => {
                return Err(invalid(
                    "fixity".into(),
                    "give exactly one of physical = \"name\" or plane = \"x = value\"".into(),
                ))
            }
        };
        let liquid = f.liquid.unwrap_or(f.fixed);
        if let Some(mu) = f.friction {
            let item = match (&f.physical, &f.plane) {
                (Some(name), _) => format!("fixity \"{name}\".friction"),
                (_, Some(plane)) => format!("fixity plane \"{plane}\".friction"),
                _ => unreachable!("checked above"),
            };
            let axes: Vec<usize> = (0..3).filter(|&a| f.fixed[a]).collect();
            let &[axis] = axes.as_slice() else {
                return Err(invalid(
                    item,
                    format!(
                        "a frictional wall fixes its normal component alone; fixed = {:?} has {} \
                         fixed components",
                        f.fixed,
                        axes.len()
                    ),
                ));
            };
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(invalid(
                    item,
                    format!("must be a finite coefficient >= 0, got {mu}"),
                ));
            }
            if materials.iter().flatten().any(|m| m.liquid.is_some()) {
                return Err(invalid(
                    item,
                    "is modelled for dry scenes only (this one has a saturated material)".into(),
                ));
            }
            if axis >= model.dimension.coords() {
                return Err(invalid(
                    item,
                    format!("the wall's normal, axis {axis}, is not an axis of this 2D mesh"),
                ));
            }
            let sides = wall_sides(&model, &nodes, axis).map_err(|n| {
                invalid(
                    item.clone(),
                    format!(
                        "the node at {:?} has elements on both sides along the wall's normal \
                         ({}): a wall must bound the mesh",
                        model.node(n as usize),
                        ["x", "y", "z"][axis]
                    ),
                )
            })?;
            if walls.is_empty() {
                walls = vec![[WallAxis::default(); 3]; model.node_count()];
            }
            for (&n, side) in nodes.iter().zip(sides) {
                walls[n as usize][axis] = WallAxis { side, friction: mu };
            }
            // The wall holds the normal, not the fixity (the body may leave it).
            continue;
        }
        for n in nodes {
            for a in 0..3 {
                fixed[n as usize][a] |= f.fixed[a];
                liquid_fixed[n as usize][a] |= liquid[a];
            }
        }
    }
    let (prescribed, nodal_velocity, velocities) = velocities(
        &scene.velocity,
        &msh_mesh,
        &node_map,
        &model,
        &names,
        &element_material,
        &materials,
        size,
        &mesh_name,
        groups,
    )
    .map_err(|(item, message)| invalid(item, message))?;
    let nodes = model.node_count();
    let mut traction = vec![[0.0; 3]; nodes];
    let mut traction_ramp = 0.0f64;
    let mut tractions = Vec::with_capacity(scene.traction.len());
    for tr in &scene.traction {
        let faces =
            physical_faces(&msh_mesh, &node_map, &tr.physical, groups).ok_or_else(|| {
                invalid(
                    format!("traction \"{}\"", tr.physical),
                    format!("no {} of that name in {mesh_name}", groups.boundary),
                )
            })?;
        // A face corner that no volume element uses has no model node to load.
        if let Some(k) = faces.iter().position(|f| f.contains(&u32::MAX)) {
            return Err(invalid(
                format!("traction \"{}\"", tr.physical),
                format!(
                    "face {} of the {} in {mesh_name} has a node that no element uses (it must lie on the meshed {})",
                    k + 1,
                    groups.boundary,
                    if dim == 2 { "surface" } else { "volume" }
                ),
            ));
        }
        let item = || format!("traction \"{}\"", tr.physical);
        let input = TractionInput {
            physical: tr.physical.clone(),
            faces,
            traction: match (tr.traction, tr.pressure) {
                (Some(t), None) => t,
                (None, Some(_)) => [0.0; 3],
                _ => return Err(invalid(
                    item(),
                    "give either traction = [tx, ty, tz] (kPa) or pressure = p (kPa, normal to each face, pushing into the body)".into(),
                )),
            },
            pressure: tr.pressure,
            ramp: tr.ramp,
        };
        // Only a pressure needs the faces' normals.
        let outward = if input.pressure.is_some() {
            let corners: Vec<Vec<usize>> = input
                .faces
                .iter()
                .map(|f| f.iter().map(|&n| n as usize).collect())
                .collect();
            crate::input::faces::outward_normals(&model, &corners)
                .map_err(|m| invalid(item(), format!("{m} in {mesh_name}")))?
        } else {
            Vec::new()
        };
        add_face_loads(
            &model,
            &input.faces,
            &input.on_faces(&outward),
            &mut traction,
        );
        traction_ramp = traction_ramp.max(tr.ramp);
        tractions.push(input);
    }
    let gravity = scene.gravity.as_ref().map_or([0.0; 3], |g| g.vector);
    let gravity_ramp = scene.gravity.as_ref().map_or(0.0, |g| g.ramp);
    let damping = scene.damping.as_ref().map_or(0.0, |d| d.local);
    if !(0.0..1.0).contains(&damping) {
        return Err(invalid(
            "damping.local".into(),
            format!("must be in [0, 1), got {damping}"),
        ));
    }
    let damping_rule = match scene.damping.as_ref().and_then(|d| d.rule.as_deref()) {
        None | Some("phases") => crate::input::case::DampingRule::Phases,
        Some("anura3d") => crate::input::case::DampingRule::Anura3d,
        Some(other) => {
            return Err(invalid(
                "damping.rule".into(),
                format!("expected \"phases\" or \"anura3d\", got \"{other}\""),
            ))
        }
    };
    // Consolidation runs may set their times by time factor (c_v of the saturated material).
    let consolidation = match &scene.consolidation {
        None => None,
        Some(c) => {
            let start = match c.start.as_str() {
                "undrained" => Start::Undrained,
                "rest" => Start::Rest,
                other => {
                    return Err(invalid(
                        "consolidation.start".into(),
                        format!("expected \"undrained\" or \"rest\", got \"{other}\""),
                    ))
                }
            };
            if !(c.load > 0.0) {
                return Err(invalid(
                    "consolidation.load".into(),
                    format!("must be positive, got {}", c.load),
                ));
            }
            Some(ConsolidationSpec {
                load: c.load,
                start,
                compare_rest: c.compare_rest,
            })
        }
    };
    let by_tv = |tv: Option<f64>| -> Result<Option<f64>, SceneError> {
        let Some(tv) = tv else { return Ok(None) };
        let m = the_saturated(&materials).ok_or_else(|| {
            invalid(
                "consolidation".into(),
                "times by time factor need exactly one saturated material".into(),
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
    let (c_end, c_out) = match &scene.consolidation {
        Some(c) => (by_tv(c.end_tv)?, by_tv(c.output_tv)?),
        None => (None, None),
    };
    let end = c_end.or(t.end).unwrap_or(0.0);
    let interval = c_out.or(t.output_interval).unwrap_or(0.0);
    if !(end > 0.0) {
        return Err(invalid(
            "time.end".into(),
            format!("must be given and positive, got {end}"),
        ));
    }
    if !(interval > 0.0) {
        return Err(invalid(
            "time.output_interval".into(),
            format!("must be given and positive, got {interval}"),
        ));
    }
    let n_out = (end / interval).round().max(1.0);
    if n_out > crate::input::preflight::MAX_OUTPUTS {
        return Err(invalid(
            "time.output_interval".into(),
            format!(
                "{} asks for {} outputs over {}; at most {} are allowed (each writes a particle file): give a longer interval",
                crate::driver::units::duration(interval),
                crate::driver::units::count(n_out),
                crate::driver::units::duration(end),
                crate::driver::units::count(crate::input::preflight::MAX_OUTPUTS)
            ),
        ));
    }
    let n_out = n_out as usize;
    let output_times = (1..=n_out)
        .map(|k| {
            if k == n_out {
                end
            } else {
                (k as f64 * interval).min(end)
            }
        })
        .collect();
    let element_count = model.element_count();
    // The undrained start is an initial state of the saturated points, resolved here.
    let initial_state = match &consolidation {
        Some(c) if c.start == Start::Undrained => {
            let m = the_saturated(&materials).ok_or_else(|| {
                invalid(
                    "consolidation".into(),
                    "a consolidation run needs exactly one saturated material".into(),
                )
            })?;
            UndrainedState::under(m, c.load)
        }
        _ => None,
    };
    let initial_stress = initial_stresses(&scene, &inputs, &model, &consolidation)
        .map_err(|(item, message)| invalid(item, message))?;
    let precision = match scene.precision.as_deref() {
        None => crate::input::case::Precision::F64,
        Some(s) => crate::input::case::Precision::parse(s).ok_or_else(|| {
            invalid(
                "precision".into(),
                format!("{s:?} is not a precision; use \"f64\" or \"f32\""),
            )
        })?,
    };
    let integration = match scene.integration.as_deref() {
        None | Some("points") => Integration::MaterialPoints,
        // Anura3D's default degree of filling (CPS `DEGREE_OF_FILLING`).
        Some("mixed") => Integration::Mixed {
            filling: 0.9,
            rule: crate::input::case::MixedRule::FullAtStart,
        },
        Some(s) => {
            return Err(invalid(
                "integration".into(),
                format!("{s:?} is not an integration; use \"points\" or \"mixed\""),
            ))
        }
    };
    let case = Case {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default(),
        inputs: vec![file.clone(), mesh_name],
        model,
        materials,
        element_material,
        points_per_element,
        input_element: (0..element_count as u32).collect(),
        input_node: (0..nodes as u32).collect(),
        fixed,
        liquid_fixed,
        walls,
        traction,
        point_loads: Vec::new(),
        traction_curve: LoadCurve::ramp(traction_ramp),
        liquid_traction: vec![[0.0; 3]; nodes],
        liquid_curve: LoadCurve::Step,
        liquid_load_on_mixture: true,
        gravity,
        gravity_curve: LoadCurve::ramp(gravity_ramp),
        courant: t.courant,
        courant_item: format!("{}: time.courant", path.display()),
        guards: Default::default(),
        damping,
        end_time: end,
        output_times,
        max_steps: t.max_steps,
        quasi_static: None,
        objective_stress: scene.objective_stress,
        pic_blend: scene.pic_blend,
        integration,
        anura3d_time_step: false,
        critical_step: crate::input::case::CriticalStepRule::AllElements,
        damping_rule,
        drag: crate::input::case::Drag::Implicit,
        initial_step: None,
        smooth_pressure: true,
        strain_smoothing: scene.strain_smoothing,
        fixed_liquid_mass: false,
        hoop_in_volume: true,
        consolidation,
        initial_state,
        initial_stress,
        probes: scene.probes.clone(),
        prescribed,
        nodal_velocity,
        moving_mesh: None,
        contact: None,
        engine: Default::default(),
        precision,
    };
    Ok(Resolved {
        case,
        materials: inputs,
        tractions,
        velocities,
    })
}

/// The case's prescribed velocities from the `[[velocity]]` entries: at most one material-point
/// set (a physical volume's elements), the nodal sets in file order, and the entries as
/// resolved. Errors name the entry.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn velocities(
    entries: &[Velocity],
    msh_mesh: &MshMesh,
    node_map: &[u32],
    model: &Model,
    volumes: &[String],
    element_material: &[u32],
    materials: &[Option<MaterialSpec>],
    size: f64,
    mesh_name: &str,
    groups: Groups,
) -> Result<
    (
        Option<PrescribedVelocity>,
        Vec<NodalVelocitySet>,
        Vec<VelocityInput>,
    ),
    (String, String),
> {
    let (mut points, mut nodal, mut out) = (None::<PrescribedVelocity>, Vec::new(), Vec::new());
    for v in entries {
        let label = v
            .physical
            .as_ref()
            .or(v.plane.as_ref())
            .cloned()
            .unwrap_or_default();
        let name = v.name.clone().unwrap_or_else(|| label.clone());
        let item = format!("velocity \"{name}\"");
        let components = v.components.unwrap_or([true; 3]);
        if !components.iter().any(|&c| c) {
            return Err((item, "components = [false, false, false] prescribes nothing; mark at least one component true".into()));
        }
        if !v.velocity.iter().all(|x| x.is_finite()) {
            return Err((
                item,
                format!("velocity must be three numbers, got {:?}", v.velocity),
            ));
        }
        if !(v.ramp >= 0.0 && v.ramp.is_finite()) {
            return Err((
                item,
                format!("ramp must be 0 or more seconds, got {}", v.ramp),
            ));
        }
        if materials.iter().flatten().any(|m| m.liquid.is_some()) {
            return Err((
                item,
                "prescribed velocities are not supported yet in scenes with a saturated material"
                    .into(),
            ));
        }
        let curve = LoadCurve::ramp(v.ramp);
        let target = match (&v.physical, &v.plane) {
            (Some(p), None) => {
                let surface = physical_nodes(msh_mesh, node_map, p, groups);
                let volume = volumes.iter().position(|n| n == p);
                let (b, m) = (groups.boundary, groups.material);
                match (surface, volume) {
                    (Some(_), Some(_)) => {
                        return Err((
                            item,
                            format!("\"{p}\" names both a {b} and a {m}; rename one"),
                        ))
                    }
                    (Some(nodes), None) => VelocityTarget::Nodes(nodes),
                    (None, Some(_)) => VelocityTarget::Volume(p.clone()),
                    (None, None) => {
                        return Err((
                            item,
                            format!("no {b} or {m} \"{p}\" in {mesh_name} ({m}s: {volumes:?})"),
                        ))
                    }
                }
            }
            (None, Some(plane)) => {
                let (axis, value) = parse_plane(plane).ok_or_else(|| {
                    (
                        item.clone(),
                        format!(
                            "plane \"{plane}\": expected 'x = value', 'y = value' or 'z = value'"
                        ),
                    )
                })?;
                let tol = 1e-9 * size.max(1e-300);
                let found: Vec<u32> = (0..model.node_count() as u32)
                    .filter(|&n| (coordinate(model, n, axis) - value).abs() <= tol)
                    .collect();
                if found.is_empty() {
                    return Err((item, format!("plane \"{plane}\" selects no node")));
                }
                VelocityTarget::Nodes(found)
            }
            _ => {
                return Err((
                    item,
                    "give exactly one of physical = \"name\" or plane = \"x = value\"".into(),
                ))
            }
        };
        match &target {
            VelocityTarget::Nodes(nodes) => nodal.push(NodalVelocitySet {
                name: name.clone(),
                rows: nodes
                    .iter()
                    .map(|&node| PrescribedNode {
                        node,
                        directions: components,
                        velocity: v.velocity,
                    })
                    .collect(),
                scale: 1.0,
                curve,
            }),
            VelocityTarget::Volume(p) => {
                if let Some(first) = &points {
                    return Err((item, format!("a second material-point velocity (after \"{}\"); give one {} per scene, or prescribe nodes", first.name, groups.material)));
                }
                let k = volumes.iter().position(|n| n == p).expect("found above") as u32 + 1;
                let rows: Vec<PrescribedElement> = (0..element_material.len() as u32)
                    .filter(|&e| element_material[e as usize] == k)
                    .map(|element| PrescribedElement {
                        element,
                        directions: components,
                        velocity: v.velocity,
                    })
                    .collect();
                if rows.is_empty() {
                    return Err((item, format!("{} \"{p}\" has no elements", groups.material)));
                }
                points = Some(PrescribedVelocity {
                    name: name.clone(),
                    rows,
                    scale: 1.0,
                    curve,
                });
            }
        }
        out.push(VelocityInput {
            name,
            target,
            velocity: v.velocity,
            components,
            ramp: v.ramp,
        });
    }
    Ok((points, nodal, out))
}

/// The scene's initial stresses: per material `k0` (Anura3D's K0 procedure under gravity
/// along -y, the ground at `gravity.k0_surface`) or `initial_stress`; `None` when no material
/// has either. Errors name the item.
fn initial_stresses(
    scene: &Scene,
    inputs: &[Option<MaterialInput>],
    model: &Model,
    consolidation: &Option<ConsolidationSpec>,
) -> Result<Option<InitialStress>, (String, String)> {
    let surface = scene.gravity.as_ref().and_then(|g| g.k0_surface);
    if surface.is_some() && inputs.iter().flatten().all(|m| m.k0.is_none()) {
        return Err((
            "gravity.k0_surface".into(),
            "no material has k0: the ground surface is only used by the K0 procedure".into(),
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
    let mut k0_used = false;
    for (k, m) in inputs.iter().enumerate() {
        let Some(m) = m else { continue };
        let item = format!("material \"{}\"", m.physical);
        if (m.k0.is_some() || m.initial_stress.is_some())
            && consolidation
                .as_ref()
                .is_some_and(|c| c.start == Start::Undrained)
        {
            return Err((
                item,
                "k0 and initial_stress cannot be combined with consolidation.start = \"undrained\", which sets the initial stresses itself".into(),
            ));
        }
        materials[k] = match (m.k0, m.initial_stress) {
            (None, None) => None,
            (Some(_), Some(_)) => {
                return Err((
                    item,
                    "give k0 or initial_stress, not both: each sets the initial stresses".into(),
                ))
            }
            (None, Some(s)) => {
                if let Some(v) = s.iter().find(|v| !v.is_finite()) {
                    return Err((
                        format!("{item}.initial_stress"),
                        format!("must be finite, got {v}"),
                    ));
                }
                Some(MaterialStart::Uniform(s))
            }
            (Some(k0), None) => {
                if !(k0 >= 0.0 && k0.is_finite()) {
                    return Err((
                        format!("{item}.k0"),
                        format!("must be finite and at least 0, got {k0}"),
                    ));
                }
                if m.liquid
                    .as_ref()
                    .is_some_and(|l| l.initial_pore_pressure != 0.0)
                {
                    return Err((
                        format!("{item}.k0"),
                        "the K0 procedure sets the pore pressure (hydrostatic below the ground): remove liquid.initial_pore_pressure".into(),
                    ));
                }
                k0_used = true;
                let g = scene.gravity.as_ref().map_or(0.0, |g| -g.vector[1]);
                let down = scene
                    .gravity
                    .as_ref()
                    .is_some_and(|g| g.vector[0] == 0.0 && g.vector[2] == 0.0 && g.vector[1] < 0.0);
                if !down {
                    return Err((
                        format!("{item}.k0"),
                        "the K0 procedure needs gravity along -y ([gravity] vector = [0, -g, 0])"
                            .into(),
                    ));
                }
                let (unit_weight, liquid_unit_weight) = match &m.liquid {
                    None => k0_unit_weights(0.0, m.density, 0.0, g, coupled, false, false),
                    Some(l) => {
                        k0_unit_weights(l.porosity, m.density, l.density, g, coupled, false, true)
                    }
                };
                Some(MaterialStart::K0(K0Material {
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
        };
    }
    let k0 = if k0_used {
        let gravity = scene.gravity.as_ref().expect("checked: k0 needs gravity");
        if gravity.ramp != 0.0 {
            return Err((
                "gravity.ramp".into(),
                format!(
                    "the K0 stresses carry the full weight from the start; a gravity ramped from 0 (over {} s) would leave them unbalanced: use ramp = 0",
                    gravity.ramp
                ),
            ));
        }
        let top = model
            .coords
            .chunks_exact(model.dimension.coords())
            .fold(f64::MIN, |h, p| h.max(p[1]));
        let surface = gravity.k0_surface.unwrap_or(top);
        if !surface.is_finite() {
            return Err((
                "gravity.k0_surface".into(),
                format!("must be finite, got {surface}"),
            ));
        }
        Some(K0Procedure {
            surface_point: [0.0, surface],
            gravity_direction: [0.0, -1.0],
            gravity_factor: 1.0,
            surface_load: 0.0,
            max_suction: DEFAULT_MAX_SUCTION,
        })
    } else {
        None
    };
    Ok(Some(InitialStress { k0, materials }))
}

/// The one saturated material of a consolidation scene, `None` when there are none or several.
fn the_saturated(materials: &[Option<MaterialSpec>]) -> Option<&MaterialSpec> {
    let mut sat = materials.iter().flatten().filter(|m| m.liquid.is_some());
    match (sat.next(), sat.next()) {
        (Some(m), None) => Some(m),
        _ => None,
    }
}

/// Adds the nodal forces of tractions `t` (kPa, one per face, uniform on it) on `faces`
/// (model node ids of their corners), integrated exactly: each corner of a triangle (3D) takes
/// a third of its area times the traction, each end of an edge (2D) half its length; in an
/// axisymmetric section the edge's load is per radian, ∫ N_a t r ds = t L (2 r_a + r_b) / 6.
pub fn add_face_loads(model: &Model, faces: &[Vec<u32>], t: &[[f64; 3]], out: &mut [[f64; 3]]) {
    let axisymmetric = model.dimension == mpm_shared::Dimension::Axisymmetric;
    for (f, t) in faces.iter().zip(t) {
        let corners: Vec<usize> = f.iter().map(|&n| n as usize).collect();
        let size = crate::input::faces::size(model, &corners);
        for (i, &n) in corners.iter().enumerate() {
            let share = match corners.len() {
                2 if axisymmetric => {
                    let (ra, rb) = (model.node(n)[0], model.node(corners[1 - i])[0]);
                    size * (2.0 * ra + rb) / 6.0
                }
                k => size / k as f64,
            };
            for d in 0..3 {
                out[n][d] += share * t[d];
            }
        }
    }
}

/// Coordinate `axis` of model node `n` (0 for z in a 2D model).
fn coordinate(model: &Model, n: u32, axis: usize) -> f64 {
    model.node(n as usize).get(axis).copied().unwrap_or(0.0)
}
