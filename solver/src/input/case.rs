//! A case ready to run: mesh, materials, boundary conditions, loads and time controls, whether
//! it came from a TOML scene or (later) an Anura3D GOM + CPS.

use crate::material::error::MaterialError;
use mpm_shared::Model;

use crate::material::law::LawSpec;

pub use crate::step::grid_update::{DampingRule, Drag};
pub use crate::step::load_curve::LoadCurve;

/// A solid material (its constitutive law and densities), dry or saturated with a pore liquid.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialSpec {
    /// Name.
    pub name: String,
    /// Mass of solid per unit volume in t/m³ (kg/m³ ÷ 1000): (1 - n) ρs.
    pub density: f64,
    /// Weight per unit volume over g (t/m³): the mass density, except for Anura3D's single-phase
    /// saturated types (a drained soil weighs its buoyant (1 - n)(ρs - ρw)).
    pub weight_density: f64,
    /// Density of the critical wave speed sqrt(E_oed / ρ) (t/m³): the mass density, except for
    /// Anura3D's undrained-total soil, whose step Anura3D takes with the dry (1 - n) ρs.
    pub wave_density: f64,
    /// The constitutive law of the solid skeleton.
    pub law: LawSpec,
    /// The pore liquid of a saturated (two-phase) material; `None` for a dry one.
    pub liquid: Option<crate::material::liquid::LiquidSpec>,
    /// Pore pressure at t = 0 (kPa, compression negative), for saturated materials.
    pub initial_pore_pressure: f64,
}

impl MaterialSpec {
    /// A linear elastic material, checked and converted: `density_kg_m3` in kg/m³, `young` in
    /// kPa.
    pub fn new(
        name: &str,
        density_kg_m3: f64,
        young: f64,
        poisson: f64,
    ) -> Result<Self, MaterialError> {
        let law = LawSpec::linear_elastic(young, poisson)?;
        Self::with_law(name, density_kg_m3, law)
    }

    /// A dry material of density `density_kg_m3` (kg/m³) following `law`.
    pub fn with_law(name: &str, density_kg_m3: f64, law: LawSpec) -> Result<Self, MaterialError> {
        if !(density_kg_m3 > 0.0) {
            return Err(MaterialError::NotPositive {
                what: "density",
                value: density_kg_m3,
            });
        }
        Ok(MaterialSpec {
            name: name.to_string(),
            density: density_kg_m3 / 1000.0,
            weight_density: density_kg_m3 / 1000.0,
            wave_density: density_kg_m3 / 1000.0,
            law,
            liquid: None,
            initial_pore_pressure: 0.0,
        })
    }

    /// A saturated material: grains of density `grain_density_kg_m3` (kg/m³) filling 1 - n of
    /// the volume, and the pore liquid `liquid`.
    pub fn saturated(
        name: &str,
        grain_density_kg_m3: f64,
        law: LawSpec,
        liquid: crate::material::liquid::LiquidSpec,
    ) -> Result<Self, MaterialError> {
        let mut m =
            MaterialSpec::with_law(name, (1.0 - liquid.porosity) * grain_density_kg_m3, law)?;
        m.liquid = Some(liquid);
        Ok(m)
    }

    /// Anura3D's `saturated_material_drained`: a single-phase soil of solid mass (1 - n) ρs
    /// whose weight is the buoyant (1 - n) (ρs - ρw) (densities in kg/m³): effective stresses
    /// under a water table at rest, no pore pressure computed.
    pub fn drained(
        name: &str,
        porosity: f64,
        grain_density_kg_m3: f64,
        liquid_density_kg_m3: f64,
        law: LawSpec,
    ) -> Result<Self, MaterialError> {
        check_porosity(porosity)?;
        let mut m = MaterialSpec::with_law(name, (1.0 - porosity) * grain_density_kg_m3, law)?;
        m.weight_density = (1.0 - porosity) * (grain_density_kg_m3 - liquid_density_kg_m3) / 1000.0;
        Ok(m)
    }

    /// Anura3D's `saturated_material_undrained_total`: a single-phase soil of the saturated mass
    /// and weight (1 - n) ρs + n ρw (kg/m³), stresses total, no pore pressure computed (its
    /// near-incompressibility comes from the user's Poisson's ratio); the critical step uses
    /// the dry density (1 - n) ρs, as Anura3D.
    pub fn undrained_total(
        name: &str,
        porosity: f64,
        grain_density_kg_m3: f64,
        liquid_density_kg_m3: f64,
        law: LawSpec,
    ) -> Result<Self, MaterialError> {
        check_porosity(porosity)?;
        let saturated = (1.0 - porosity) * grain_density_kg_m3 + porosity * liquid_density_kg_m3;
        let mut m = MaterialSpec::with_law(name, saturated, law)?;
        m.wave_density = (1.0 - porosity) * grain_density_kg_m3 / 1000.0;
        Ok(m)
    }

    /// Oedometric modulus (kPa).
    pub fn oedometric(&self) -> f64 {
        self.law.constrained_modulus()
    }

    /// Fastest wave speed on an element of size `dx` (m/s): sqrt(E_oed / ρ) when dry; for a
    /// saturated material the two-phase speed, with the drag treated implicitly
    /// ([`crate::material::liquid::LiquidSpec::wave_speed_implicit_drag`]) or, for `anura3d_step`,
    /// Anura3D's formula with its explicit-drag and consolidation terms (smaller, so as safe).
    pub fn wave_speed_at(&self, dx: f64, anura3d_step: bool) -> f64 {
        self.step_speed(dx, anura3d_step, false)
    }

    /// The wave speed that bounds the step ([`MaterialSpec::wave_speed_at`]); under the
    /// semi-implicit scheme (`semi_implicit`), whose pore pressure is implicit, a saturated
    /// material's is its skeleton's, sqrt(E_oed / ((1 − n) ρs)): the solid moving through
    /// still water, the fastest the explicit effective stress carries.
    pub fn step_speed(&self, dx: f64, anura3d_step: bool, semi_implicit: bool) -> f64 {
        if semi_implicit && self.liquid.is_some() {
            return (self.oedometric() / self.density).sqrt();
        }
        match &self.liquid {
            None => self.wave_speed(),
            Some(l) => {
                let grains = self.density / (1.0 - l.porosity);
                if anura3d_step {
                    l.wave_speed(grains, self.oedometric(), dx)
                } else {
                    l.wave_speed_implicit_drag(grains, self.oedometric(), dx)
                }
            }
        }
    }

    /// The density (t/m³) and P-wave speed (m/s) bulk viscosity damps with, Anura3D's choice
    /// (docs/design.md §4.4a): a saturated material's mixture density (1 − n) ρs + n ρw and
    /// undrained speed sqrt((E_oed + K_w / n) / ρ_mix); otherwise the density its critical step
    /// takes and sqrt(E_oed / ρ).
    pub fn bulk_medium(&self) -> (f64, f64) {
        let (rho, modulus) = match &self.liquid {
            Some(l) => (
                self.density + l.porosity * l.density,
                self.oedometric() + l.bulk_modulus / l.porosity,
            ),
            None => (self.wave_density, self.oedometric()),
        };
        (rho, (modulus / rho).sqrt())
    }

    /// P-wave speed of the dry skeleton, sqrt(E_oed / ρ) (m/s).
    pub fn wave_speed(&self) -> f64 {
        (self.oedometric() / self.wave_density).sqrt()
    }
}

fn check_porosity(n: f64) -> Result<(), MaterialError> {
    if (0.0..1.0).contains(&n) {
        Ok(())
    } else {
        Err(MaterialError::Porosity {
            range: "[0, 1)",
            value: n,
        })
    }
}

/// A distributed load on a face, carried by the material points next to it (Anura3D's
/// `$$START_LOAD_ON_MATERIAL_POINTS_SOLID`): the face's total force is shared equally by the
/// points of the adjacent filled element(s) that lie nearest the face, and moves with them.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceLoad {
    /// Corner nodes of the face (0-based model node ids): three for a tetrahedron's face, two
    /// for a triangle's edge.
    pub corners: Vec<usize>,
    /// Total force on the face (kN) at multiplier 1.
    pub force: [f64; 3],
}

/// Quasi-static load steps (Anura3D's `QUASISTATIC_CONVERGENCE`): a load step ends when the
/// out-of-balance force and the kinetic energy are small, or after a number of steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuasiStatic {
    /// A load step ends once it has taken more than this many steps (Anura3D's
    /// `MAXIMUM_TIME_STEPS`; `None`: at the load step's end time).
    pub max_steps: Option<u64>,
    /// Tolerated ratio |free out-of-balance force| / |free external force|.
    pub force_tolerance: f64,
    /// Tolerated ratio kinetic energy / external work.
    pub energy_tolerance: f64,
    /// Tolerated ratio |free out-of-balance force| / |free external force| of the liquid
    /// (Anura3D's `TOLERATED_ERROR_LIQUID`; two-phase cases).
    pub liquid_force_tolerance: f64,
}

/// How stresses are integrated (Anura3D's `COMPUTATION_METHOD`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Integration {
    /// At the material points everywhere (`MPM-MP`).
    MaterialPoints,
    /// At the element's Gauss point in full elements, at material points elsewhere
    /// (`MPM-MIXED`).
    Mixed {
        /// Degree of filling from which an element counts as full.
        filling: f64,
        /// Which elements count as full, and which points take their element's mean stress.
        rule: MixedRule,
    },
}

/// The two readings of MPM-MIXED (docs/design.md §4.9).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MixedRule {
    /// Anura3D's, for GOM input: an element is partly filled (integrated at its points) when
    /// it holds points of two materials, or holds a boundary point (one placed beside a face
    /// shared with an element that started empty) and its points fill at most the degree of
    /// filling; every other element is full. After the points are located each step, every
    /// point of an element holding one material takes the element's volume-weighted mean
    /// stress, pore pressure and state, full or not.
    Anura3d,
    /// The scenes' rule: an element is full when its points fill at least the degree of
    /// filling, and the points of the elements that were full at the start of a step take their
    /// mean after the stress update, before they move (a partly filled element at a free
    /// surface keeps its points' own stresses).
    FullAtStart,
}

/// Everything a run needs, grouped as the input is resolved: the mesh and what fills it, what
/// holds it, what loads it, how time advances, how the equations are integrated, how the
/// points start, and what the run checks and records. Scenes ([`crate::input::scene`]) and
/// Anura3D input ([`crate::input::anura3d`]) each build one.
#[derive(Debug, Clone)]
pub struct Case {
    /// Case name (file stem).
    pub name: String,
    /// Input files, for `run.json`.
    pub inputs: Vec<String>,
    /// The mesh model.
    pub model: Model,
    /// The materials, which element holds which, and the input's numbering.
    pub body: Body,
    /// Fixities, walls, prescribed velocities, the moving mesh and contact.
    pub boundary: BoundaryConditions,
    /// Face loads, loads on points and gravity, with their multipliers.
    pub loads: Loading,
    /// The time step's Courant number and rule, end and output times, step limits.
    pub time: TimeControls,
    /// Integration, damping, drag, smoothing and precision.
    pub numerics: Numerics,
    /// Initial stresses and states, and the consolidation job.
    pub start: StartState,
    /// Guard rails, probes and threads.
    pub run: Execution,
}

/// What fills the mesh: the materials, the material and number of points of each element, and
/// the numbers the input gave elements and nodes. Every per-element and per-node list follows
/// the case's order ([`Case::reordered`]).
#[derive(Debug, Clone)]
pub struct Body {
    /// Materials by 1-based index (entry 0 unused; `None` for materials no element uses).
    pub materials: Vec<Option<MaterialSpec>>,
    /// Material of each element (0 = empty).
    pub element_material: Vec<u32>,
    /// Material points per element.
    pub points_per_element: Vec<u32>,
    /// The original input element (0-based) of each element: the GOM's
    /// `$$START_INPUT_ELEMENT_NUMBERS` when it has one (a mesh sfcb ordered), else its own
    /// order, followed through the solver's reordering. Material-point ids count the points in
    /// this original order, and messages name elements by it (plus 1).
    pub input_element: Vec<u32>,
    /// The node (0-based) of the file read for each model node, followed through the solver's
    /// reordering: messages name nodes by it (plus 1).
    pub input_node: Vec<u32>,
}

/// What holds the body: fixities of the solid and the liquid, rigid walls, velocities
/// prescribed on points and on nodes, Anura3D's moving mesh and contact.
#[derive(Debug, Clone)]
pub struct BoundaryConditions {
    /// Fixed velocity components per model node.
    pub fixed: Vec<[bool; 3]>,
    /// Fixed liquid velocity components per model node (impermeable faces); used only where a
    /// saturated material is.
    pub liquid_fixed: Vec<[bool; 3]>,
    /// Per model node and axis, the rigid wall normal to that axis the node lies on, if any
    /// ([`crate::step::wall_friction`]); empty when the case has no wall.
    pub walls: Vec<[crate::step::wall_friction::WallAxis; 3]>,
    /// Velocities prescribed on the material points of some elements (Anura3D's
    /// `$$PRESCRIBED_MATERIAL_POINT_VELOCITY_*`); `None`: none, or the multiplier is off.
    pub prescribed: Option<crate::step::prescribed::PrescribedVelocity>,
    /// Velocities prescribed on nodes (Anura3D's `$$PRESCRIBED_NODAL_VELOCITY_*`, scenes'
    /// `[[velocity]]` on surfaces and planes), one reaction each.
    pub nodal_velocity: Vec<crate::step::nodal_velocity::NodalVelocitySet>,
    /// Anura3D's moving mesh (`$$MOVING_MESH_CORNER_NODES` and its companions), when given.
    pub moving_mesh: Option<crate::step::moving_mesh::MovingMeshSpec>,
    /// Contact between a structure and the soil (Anura3D's `$$CONTACT_FORMULATION 1`), when on.
    pub contact: Option<crate::step::contact::ContactSpec>,
    /// Absorbing boundaries: a dashpot and a spring per model node, one row per node in node
    /// order (empty: none).
    pub absorbing: Vec<crate::step::absorbing::AbsorbingNode>,
    /// How the absorbing boundaries act (ours for scenes, Anura3D's for GOM input).
    pub absorbing_rule: crate::step::absorbing::AbsorbingRule,
}

/// What loads the body: face loads on nodes (on the solid and on the liquid) and on material
/// points, and gravity, each at multiplier 1 with the curve that scales it in time.
#[derive(Debug, Clone)]
pub struct Loading {
    /// Nodal face-load forces per model node (kN) at multiplier 1 (with contact, the soil's:
    /// the loads on faces of the soil's elements).
    pub traction: Vec<[f64; 3]>,
    /// With contact, the nodal face-load forces on the structure (from the loaded faces of its
    /// elements, a pile's head) per model node (kN) at multiplier 1, which act on its nodes
    /// alone; empty without.
    pub structure_traction: Vec<[f64; 3]>,
    /// Loads carried by material points.
    pub point_loads: Vec<FaceLoad>,
    /// Traction multiplier (face loads on nodes and on material points).
    pub traction_curve: LoadCurve,
    /// Face loads on the liquid per model node (kN) at multiplier 1: they act on the liquid and,
    /// as part of the total traction, on the mixture.
    pub liquid_traction: Vec<[f64; 3]>,
    /// Liquid load multiplier.
    pub liquid_curve: LoadCurve,
    /// Whether a load on the liquid also loads the mixture (a water pressure on a drained face
    /// is part of the total traction). Anura3D applies it to the liquid's equation alone, so
    /// GOM input runs without; scenes with.
    pub liquid_load_on_mixture: bool,
    /// Gravity acceleration vector (m/s²) at multiplier 1.
    pub gravity: [f64; 3],
    /// Gravity multiplier.
    pub gravity_curve: LoadCurve,
}

/// How the run steps and how long it lasts: the Courant number and the critical step's rule, the
/// first step, the end and output times, the step limit and quasi-static load steps.
#[derive(Debug, Clone)]
pub struct TimeControls {
    /// Courant number (above 1 only runs with `--force`, see [`Case::check_courant`]).
    pub courant: f64,
    /// Where the Courant number was given (file and key), for messages.
    pub courant_item: String,
    /// End time (s).
    pub end_time: f64,
    /// Output times (s), increasing, the last equal to `end_time`.
    pub output_times: Vec<f64>,
    /// Optional cap on time steps.
    pub max_steps: Option<u64>,
    /// Quasi-static load steps: each output time ends a load step, which may end earlier.
    pub quasi_static: Option<QuasiStatic>,
    /// Take Anura3D's two-phase critical time step (explicit drag and consolidation terms)
    /// rather than the implicit-drag one, so that Anura3D inputs step as Anura3D does.
    pub anura3d_time_step: bool,
    /// Over which elements, and how often, the critical time step is taken.
    pub critical_step: CriticalStepRule,
    /// Length of the calculation's very first step (s), when it differs from the critical step:
    /// Anura3D starts with a step of 1e-15 s, so that its first full step is damped against a
    /// velocity that is no longer zero.
    pub initial_step: Option<f64>,
}

/// The gradients of the points' functions on the mesh's linear elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Gradient {
    /// The element's own, constant over it (they jump where a point crosses a face).
    #[default]
    Element,
    /// The dual-domain gradients ([`crate::basis::ddmp`]): continuous across faces.
    Ddmp,
    /// The dual-domain gradients blended with the element's own towards its centroid.
    DdmpBlended,
}

/// How a two-phase case is stepped in time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Scheme {
    /// Every term explicit (Anura3D's): the step follows the undrained wave speed, the pore
    /// water's compressibility included.
    #[default]
    Explicit,
    /// The pore pressure solved for on the nodes each step, implicitly
    /// ([`crate::step::semi_implicit`], docs/design.md §4.4c): the step follows the skeleton's
    /// wave speed.
    SemiImplicit {
        /// The pressure solve's relative tolerance.
        tolerance: f64,
    },
}

impl Scheme {
    /// Whether the pore pressure is solved for implicitly.
    pub fn semi_implicit(self) -> bool {
        matches!(self, Scheme::SemiImplicit { .. })
    }
}

/// How the equations are integrated: damping, the stress rate and integration, the velocity
/// update, drag, smoothing, the liquid's mass, the axisymmetric volume and the precision.
/// Scenes and Anura3D input choose several of them differently.
#[derive(Debug, Clone)]
pub struct Numerics {
    /// Local damping factor α.
    pub damping: f64,
    /// Jaumann (objective) stress rate instead of the plain small-strain update.
    pub objective_stress: bool,
    /// Share (0–1) of PIC in the points' velocity update: v ← (1 − β) v_FLIP + β v_PIC, v_PIC
    /// the nodes' updated velocities (fixed components zero) at the point. 0, Anura3D's pure
    /// FLIP, conserves the points' kinetic energy but lets a point keep a velocity its nodes no
    /// longer have (beside a fixed rough base, or alone at a free front); a little PIC
    /// dissipates that.
    pub pic_blend: f64,
    /// Stress integration.
    pub integration: Integration,
    /// How local damping is applied (Anura3D's rule for GOM input, the mixture rule in scenes).
    pub damping_rule: DampingRule,
    /// How the Darcy drag between the phases is integrated in time.
    pub drag: Drag,
    /// Smooth pore-pressure rates through the nodes (V N-weighted averages, interpolated back
    /// with N; scenes).
    pub smooth_pressure: bool,
    /// Keep each point's liquid mass (and its weight and drag) at that of its initial volume,
    /// as Anura3D does; otherwise it follows the point's volume (n ρw V at constant porosity).
    pub fixed_liquid_mass: bool,
    /// In an axisymmetric section, whether the hoop strain changes the points' volume. It does
    /// (scenes); Anura3D's weight update sums only the in-plane normal strains (its loop runs
    /// over the two vector components though its comment asks for three), so GOM input leaves
    /// the hoop strain out of the volume as Anura3D does. No effect in plane strain and 3D.
    pub hoop_in_volume: bool,
    /// Anura3D's strain smoothing (`$$STRAIN_SMOOTHING 1`): the volumetric strain increments of
    /// both phases averaged element → node → element, material by material
    /// ([`crate::step::smoothing`]); it replaces `smooth_pressure` when on.
    pub strain_smoothing: bool,
    /// Bulk viscosity damping ([`crate::step::bulk_viscosity`]); `None`: none.
    pub bulk_viscosity: Option<crate::step::bulk_viscosity::BulkViscosity>,
    /// Anura3D's mass scaling (`$$MASS_SCALING 1 f`, a scene's `time.mass_scaling`): every
    /// nodal acceleration is the force over f times the mass, so the critical step grows by
    /// √f; 1 when off (docs/design.md §4.4b).
    pub mass_scaling: f64,
    /// How a two-phase case is stepped in time ([`Scheme`]).
    pub scheme: Scheme,
    /// The background grid the case runs on, with its basis (`None`: the mesh's elements, the
    /// linear basis).
    pub grid: Option<crate::basis::grid::GridSpec>,
    /// The gradients the points take on the mesh's elements (not on a grid).
    pub gradient: Gradient,
    /// Floating-point precision of the particle and grid state.
    pub precision: Precision,
}

/// How the points start: unstressed at rest, with initial stresses, or in the undrained state
/// a consolidation job starts from; and that job.
#[derive(Debug, Clone, Default)]
pub struct StartState {
    /// A consolidation run compared with Terzaghi (scenes with `[consolidation]`).
    pub consolidation: Option<ConsolidationSpec>,
    /// A uniform initial state of the saturated points (the undrained start of a consolidation
    /// run); `None`: at rest.
    pub initial_state: Option<UndrainedState>,
    /// Stresses (and pore pressures) the points start with: the K0 procedure or uniform
    /// stresses per material ([`crate::input::initial_stress`]); `None`: unstressed.
    pub initial_stress: Option<crate::input::initial_stress::InitialStress>,
}

/// What the run checks and records, and how it uses the machine: the guard rails, the points
/// whose history it writes, and its threads. None of them changes the computed values; the
/// guard rails may stop a run.
#[derive(Debug, Clone, Default)]
pub struct Execution {
    /// The run-time checks (guard rails) and their tolerances.
    pub guards: Guards,
    /// Material-point ids written to `history.csv`.
    pub probes: Vec<u32>,
    /// Threads, pinning and first touch of the run (not physics: results do not depend on it).
    pub engine: crate::parallel::team::Options,
}

/// The checks made at every step (docs/design.md §4.14): non-finite values, collapsing points,
/// kinetic energy growing without work, the energy balance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guards {
    /// Make the checks at all (off only to measure what they cost).
    pub enabled: bool,
    /// Largest |kinetic + strain + dissipated - work| / (largest energy term) before the run
    /// stops; `None`: not checked. Checked in single-phase runs without prescribed velocities.
    pub energy_tolerance: Option<f64>,
    /// A point whose volume falls to this share of its initial volume (or below, or to zero or
    /// less: det F <= 0) stops the run.
    pub min_volume_ratio: f64,
    /// Kinetic energy above this many times what the work done and the strain energy released
    /// could give (and still growing) stops the run as a blow-up.
    pub blow_up_factor: f64,
}

/// Default tolerance of the energy balance (`--energy-tolerance`): the error as large as the
/// largest energy term. Stable runs come near it: docs/stability.md's undamped wave with one
/// point per element rings at 0.3 to 0.9 for a million steps before its slow instability
/// (which the blow-up check then catches), so a tighter default would stop sound runs.
pub const DEFAULT_ENERGY_TOLERANCE: f64 = 1.0;

impl Default for Guards {
    fn default() -> Self {
        Guards {
            enabled: true,
            energy_tolerance: Some(DEFAULT_ENERGY_TOLERANCE),
            min_volume_ratio: 1e-3,
            blow_up_factor: 4.0,
        }
    }
}

/// A Courant number above 1 without `--force`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{item}: Courant number {courant} is above 1: the explicit step would be {courant}× the critical step and the run would blow up; use at most 1 (0.9 is usual), or --force to run it anyway")]
pub struct CourantError {
    /// File and key.
    pub item: String,
    /// The value given.
    pub courant: f64,
}

/// The precision a run computes in; sums that grow (time, work, energies) are f64 in both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Precision {
    /// Double precision (the default).
    #[default]
    F64,
    /// Single precision: half the memory traffic of the particle and grid state.
    F32,
}

impl Precision {
    /// Parses `f64` or `f32`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "f64" => Some(Precision::F64),
            "f32" => Some(Precision::F32),
            _ => None,
        }
    }

    /// Bytes of one real number.
    pub fn bytes(self) -> usize {
        match self {
            Precision::F64 => 8,
            Precision::F32 => 4,
        }
    }

    /// `f64` or `f32`, as `run.json` writes it.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }
}

/// Fixities of a laterally confined box (an oedometer): nodes on the x and z faces of the
/// bounding box may not move normal to them, nodes on the bottom (lowest y) not at all.
pub fn confined_box(model: &Model) -> Vec<[bool; 3]> {
    let d = model.dimension.coords();
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in model.coords.chunks_exact(d) {
        for a in 0..d {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let tol = 1e-9 * (0..d).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let on = |v: f64, w: f64| (v - w).abs() <= tol;
    (0..model.node_count())
        .map(|i| {
            let p = model.node(i);
            let bottom = on(p[1], lo[1]);
            [
                bottom || on(p[0], lo[0]) || on(p[0], hi[0]),
                bottom,
                bottom || on(p[2], lo[2]) || on(p[2], hi[2]),
            ]
        })
        .collect()
}

/// How the solver orders the mesh before computing (`--reorder`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reorder {
    /// Keep the input's order (e.g. a mesh sfcb already ordered).
    None,
    /// Elements along the Morton curve of their centroids, nodes by first use.
    Morton,
    /// The same along the Hilbert curve.
    Hilbert,
}

/// The mesh of a case cannot be ordered along the curve.
#[derive(Debug, thiserror::Error)]
pub enum ReorderError {
    /// The curve cannot be laid over the mesh (its extent).
    #[error("{from}: --reorder cannot order the mesh: {source}")]
    Curve {
        /// The case's input files ("the case" for built-in ones).
        from: String,
        /// What the ordering found.
        source: sfcb::order::BoundsError,
    },
    /// The model cannot be renumbered.
    #[error(transparent)]
    Model(#[from] mpm_shared::Error),
}

impl Case {
    /// Refuses a Courant number above 1 unless `force`.
    pub fn check_courant(&self, force: bool) -> Result<(), CourantError> {
        let time = &self.time;
        if time.courant > 1.0 && !force {
            return Err(CourantError {
                item: time.courant_item.clone(),
                courant: time.courant,
            });
        }
        Ok(())
    }

    /// The case with its elements ordered along a space-filling curve and its nodes renumbered
    /// by first use (sfcb's ordering), every per-element and per-node datum following, and the
    /// material-point ids and the numbers messages give kept those of the input
    /// ([`Body::input_element`], [`Body::input_node`]). `Reorder::None` returns it unchanged.
    pub fn reordered(mut self, how: Reorder) -> Result<Case, ReorderError> {
        let curve = match how {
            Reorder::None => return Ok(self),
            Reorder::Morton => sfcb::order::Curve::Morton,
            Reorder::Hilbert => sfcb::order::Curve::Hilbert,
        };
        let o = sfcb::order::order(
            &self.model,
            sfcb::order::Options {
                curve,
                levels: 21,
                cubic: true,
            },
        )
        .map_err(|source| ReorderError::Curve {
            // Built-in cases have no input files to name.
            from: if self.inputs.is_empty() {
                "the case".to_string()
            } else {
                self.inputs.join(", ")
            },
            source,
        })?;
        let model = self.model.reordered(&o.order, &o.node_new)?;
        let by_element = |v: &[u32]| o.order.iter().map(|&e| v[e as usize]).collect::<Vec<u32>>();
        let body = &mut self.body;
        body.input_element = by_element(&body.input_element);
        body.element_material = by_element(&body.element_material);
        body.points_per_element = by_element(&body.points_per_element);
        fn by_node<T: Copy>(v: &[T], node_new: &[u32]) -> Vec<T> {
            let mut out = v.to_vec();
            for (old, &new) in node_new.iter().enumerate() {
                out[new as usize] = v[old];
            }
            out
        }
        body.input_node = by_node(&body.input_node, &o.node_new);
        let boundary = &mut self.boundary;
        boundary.fixed = by_node(&boundary.fixed, &o.node_new);
        boundary.liquid_fixed = by_node(&boundary.liquid_fixed, &o.node_new);
        if !boundary.walls.is_empty() {
            boundary.walls = by_node(&boundary.walls, &o.node_new);
        }
        let loads = &mut self.loads;
        loads.traction = by_node(&loads.traction, &o.node_new);
        if !loads.structure_traction.is_empty() {
            loads.structure_traction = by_node(&loads.structure_traction, &o.node_new);
        }
        loads.liquid_traction = by_node(&loads.liquid_traction, &o.node_new);
        for load in &mut loads.point_loads {
            for n in load.corners.iter_mut() {
                *n = o.node_new[*n] as usize;
            }
        }
        if let Some(pv) = boundary.prescribed.take() {
            let mut new_of_old = vec![0u32; o.order.len()];
            for (new, &old) in o.order.iter().enumerate() {
                new_of_old[old as usize] = new as u32;
            }
            boundary.prescribed = Some(pv.renumbered(&new_of_old));
        }
        boundary.nodal_velocity = std::mem::take(&mut boundary.nodal_velocity)
            .into_iter()
            .map(|s| s.renumbered(&o.node_new))
            .collect();
        boundary.moving_mesh = boundary
            .moving_mesh
            .take()
            .map(|m| m.renumbered(&o.node_new));
        for row in &mut boundary.absorbing {
            row.node = o.node_new[row.node as usize];
        }
        boundary.absorbing =
            crate::step::absorbing::merged(std::mem::take(&mut boundary.absorbing));
        if let Some(c) = boundary.contact.take() {
            let mut new_of_old = vec![0u32; o.order.len()];
            for (new, &old) in o.order.iter().enumerate() {
                new_of_old[old as usize] = new as u32;
            }
            boundary.contact = Some(c.renumbered(&new_of_old));
        }
        self.model = model;
        Ok(self)
    }

    /// The computational mesh of the model, an inverted or flat element named by its number
    /// in the input (not in the solver's order).
    pub fn mesh<E: crate::element::Element, R: crate::real::Real>(
        &self,
    ) -> Result<crate::element::mesh::Mesh<E, R>, crate::element::mesh::MeshError> {
        crate::element::mesh::Mesh::<E, R>::new(&self.model).map_err(|e| match e {
            crate::element::mesh::MeshError::BadElement { element, volume } => {
                crate::element::mesh::MeshError::BadElement {
                    element: self.element_number(element - 1) as usize,
                    volume,
                }
            }
            e => e,
        })
    }

    /// The 1-based input number of element `e` (0-based, the case's order), for messages.
    pub fn element_number(&self, e: usize) -> u32 {
        self.body.input_element.get(e).map_or(e as u32, |&k| k) + 1
    }

    /// The 1-based input number of model node `n` (0-based, the case's order), for messages.
    pub fn node_number(&self, n: usize) -> u32 {
        self.body.input_node.get(n).map_or(n as u32, |&k| k) + 1
    }

    /// How the case's material points are numbered: by input element (see
    /// [`Body::input_element`]).
    pub fn point_ids(&self) -> mpm_shared::points::PointIds {
        mpm_shared::points::PointIds::new(
            &self.body.points_per_element,
            Some(&self.body.input_element),
        )
    }

    /// True when some material is saturated: the run then allocates and computes the liquid.
    pub fn has_liquid(&self) -> bool {
        self.body
            .materials
            .iter()
            .flatten()
            .any(|m| m.liquid.is_some())
    }

    /// The sets whose reactions `reaction.csv` records, in its order: the prescribed
    /// material-point set first, then the nodal sets as given, then, with contact, the soil's
    /// push on the structure (`contact`) and its part on the downward-facing interface
    /// (`contact_base`). With contact, the sets are reported as their means over the steps
    /// since the last output (a step's contact force is an impulse over that step).
    pub fn reactions(&self) -> Vec<crate::step::reaction::Reaction> {
        self.boundary
            .prescribed
            .iter()
            .map(|p| {
                let mut r = p.reaction();
                if self.boundary.contact.is_some() {
                    // The driven structure's reaction carries the contact's push: averaged as
                    // the push is.
                    r.window = Some(([0.0; 3], 0.0));
                }
                r
            })
            .chain(self.boundary.nodal_velocity.iter().map(|s| s.reaction()))
            .chain(self.boundary.contact.iter().flat_map(|_| {
                use crate::step::contact::{CONTACT_BASE_SET, CONTACT_SET};
                [CONTACT_SET, CONTACT_BASE_SET].map(crate::step::reaction::Reaction::averaged)
            }))
            .collect()
    }

    /// A case of one material filling every element with `points` material points each, the
    /// given fixities, no loads, Courant number 0.9, no damping, one output at t = 1 s; callers
    /// set what differs (used by benchmarks and tests that build meshes in memory).
    pub fn single_material(
        name: &str,
        model: Model,
        material: MaterialSpec,
        points: u32,
        fixed: Vec<[bool; 3]>,
    ) -> Case {
        let (n, n_el) = (model.node_count(), model.element_count());
        Case {
            name: name.to_string(),
            inputs: Vec::new(),
            model,
            body: Body {
                materials: vec![None, Some(material)],
                element_material: vec![1; n_el],
                points_per_element: vec![points; n_el],
                input_element: (0..n_el as u32).collect(),
                input_node: (0..n as u32).collect(),
            },
            boundary: BoundaryConditions {
                liquid_fixed: fixed.clone(),
                fixed,
                walls: Vec::new(),
                prescribed: None,
                nodal_velocity: Vec::new(),
                moving_mesh: None,
                contact: None,
                absorbing: Vec::new(),
                absorbing_rule: Default::default(),
            },
            loads: Loading {
                traction: vec![[0.0; 3]; n],
                structure_traction: Vec::new(),
                point_loads: Vec::new(),
                traction_curve: LoadCurve::Step,
                liquid_traction: vec![[0.0; 3]; n],
                liquid_curve: LoadCurve::Step,
                liquid_load_on_mixture: true,
                gravity: [0.0; 3],
                gravity_curve: LoadCurve::Step,
            },
            time: TimeControls {
                courant: 0.9,
                courant_item: "courant".into(),
                end_time: 1.0,
                output_times: vec![1.0],
                max_steps: None,
                quasi_static: None,
                anura3d_time_step: false,
                critical_step: CriticalStepRule::AllElements,
                initial_step: None,
            },
            numerics: Numerics {
                damping: 0.0,
                objective_stress: false,
                pic_blend: 0.0,
                integration: Integration::MaterialPoints,
                damping_rule: DampingRule::Phases,
                drag: Drag::Implicit,
                smooth_pressure: true,
                fixed_liquid_mass: false,
                hoop_in_volume: true,
                strain_smoothing: false,
                bulk_viscosity: None,
                mass_scaling: 1.0,
                scheme: Scheme::Explicit,
                grid: None,
                gradient: Gradient::Element,
                precision: Precision::F64,
            },
            start: StartState::default(),
            run: Execution::default(),
        }
    }
}

/// Over which elements, and how often, the critical time step is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CriticalStepRule {
    /// Once, at the start, over every element: an empty element at the fastest material's
    /// speed, since points may move into it (scenes).
    AllElements,
    /// After every step, over the elements that hold points then, each at the speed of the
    /// fastest material among its points (Anura3D's rule: GOM input;
    /// [`crate::step::time_step`]).
    OccupiedEachStep,
}

/// How the run starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// At rest, the load applied suddenly (Anura3D's workshop set-up): the column first responds
    /// dynamically.
    Rest,
    /// In the undrained state Terzaghi assumes at t = 0+: the load shared between pore pressure
    /// and skeleton as an undrained 1D compression, so there is no dynamic transient.
    Undrained,
}

/// A consolidation run's settings (`[consolidation]` of a scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConsolidationSpec {
    /// Top load q (kPa, compression positive).
    pub load: f64,
    /// Initial state.
    pub start: Start,
    /// Also run the workshop-style configuration (at rest, sudden load) and report both.
    pub compare_rest: bool,
}

impl ConsolidationSpec {
    /// The runs the job makes: its own and, with `compare_rest` from another start, the
    /// workshop-style twin's (from rest), as many steps again.
    pub fn runs(&self) -> usize {
        if self.compare_rest && self.start != Start::Rest {
            2
        } else {
            1
        }
    }
}

/// The undrained state of a 1D compression under a top load, which Terzaghi assumes at t = 0+:
/// every saturated point starts with vertical strain ε = -q / (E_oed + K_w/n), the effective
/// stress of that strain and pore pressure (K_w/n) ε.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UndrainedState {
    /// Vertical (y) strain ε.
    pub vertical_strain: f64,
    /// Pore pressure (kPa, compression negative).
    pub pore_pressure: f64,
}

impl UndrainedState {
    /// The undrained state of `material` (saturated) under the top load `load` (kPa,
    /// compression positive).
    pub fn under(material: &MaterialSpec, load: f64) -> Option<Self> {
        let l = material.liquid.as_ref()?;
        let kw_over_n = l.bulk_modulus / l.porosity;
        let eps = -load / (material.oedometric() + kw_over_n);
        Some(UndrainedState {
            vertical_strain: eps,
            pore_pressure: kw_over_n * eps,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bulk viscosity damps a saturated material with its mixture density and undrained speed,
    /// a dry one with its own density and P-wave speed.
    #[test]
    fn bulk_viscosity_takes_anuras_medium() {
        let law = LawSpec::linear_elastic(1.0e4, 0.3).unwrap();
        let liquid =
            crate::material::liquid::LiquidSpec::new(0.4, 1000.0, 2.0e6, 1e-12, 1e-6).unwrap();
        let spec = MaterialSpec::saturated("s", 2650.0, law, liquid).unwrap();
        let (rho, c) = spec.bulk_medium();
        let mixture = 0.6 * 2.65 + 0.4;
        assert!((rho - mixture).abs() < 1e-12);
        let undrained = ((spec.oedometric() + 2.0e6 / 0.4) / mixture).sqrt();
        assert!((c - undrained).abs() < 1e-9 * undrained);
        let dry = MaterialSpec::new("d", 2000.0, 1.0e5, 0.25).unwrap();
        assert_eq!(dry.bulk_medium(), (2.0, dry.wave_speed()));
    }
}
