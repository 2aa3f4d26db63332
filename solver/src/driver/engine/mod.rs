//! The explicit MPM engine: state, critical time step and one MUSL step through the phases.
//!
//! One file per responsibility: `setup` builds the engine from a case, `step` takes one time
//! step through its named phases, `locate` finds the points' elements after they move,
//! `guards` sums the energies and checks the guard rails, `distributed` holds what a run
//! over MPI ranks adds (gathering to rank 0, migrating points, re-partitioning), and
//! `snapshot` takes the engine's state into a checkpoint and back.

mod distributed;
mod guards;
mod locate;
mod setup;
mod snapshot;
mod step;
#[cfg(test)]
mod tests;

use crate::element::locate::Outcome;
use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::Element;
use crate::input::case::{Case, Guards};
use crate::material::law::Law;
use crate::material::liquid::Fluid;
use crate::parallel::comm::Communicator;
use crate::parallel::gather::{Layout, Slots};
use crate::parallel::partition::Partition;
use crate::parallel::sort::SortScratch;
pub use crate::parallel::team::Options;
use crate::parallel::team::Team;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::constraint::Constraints;
use crate::step::contact::Structure;
use crate::step::grid_update;
use crate::step::grid_update::{DampingRule, Drag};
use crate::step::load_curve::LoadCurve;
use crate::step::stress::GuardSums;
use std::sync::Arc;

pub use crate::driver::guard::{Check, Divergence};

/// Why a step stopped the run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A material point left the mesh.
    #[error(transparent)]
    Lost(#[from] Lost),
    /// The moving mesh turned an element inside out.
    #[error(transparent)]
    Mesh(#[from] crate::step::moving_mesh::Inverted),
    /// A guard rail tripped (docs/design.md §4.14).
    #[error(transparent)]
    Diverged(Box<Divergence>),
    /// The semi-implicit pressure solve did not converge.
    #[error(transparent)]
    Pressure(#[from] crate::step::semi_implicit::NotConverged),
}

/// The share of the energy held by initial stresses and pore pressures that the blow-up check
/// allows as kinetic energy whatever the work done (a floor over round-off).
pub const BLOW_UP_FLOOR: f64 = 1e-3;

/// The energy checks (blow-up, balance) start after this many steps; the others from the first.
pub const BALANCE_FROM_STEP: u64 = 100;

/// Phases timed in `run.json`.
pub const PHASES: [&str; 6] = [
    "particle_to_grid",
    "grid_update",
    "grid_to_particle",
    "stress",
    "locate",
    "output",
];

/// Why an engine cannot be set up for a case.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The worker threads could not be started.
    #[error(transparent)]
    Team(#[from] crate::parallel::team::TeamError),
    /// The mesh cannot be computed on (an inverted element, not tetrahedral).
    #[error(transparent)]
    Mesh(#[from] crate::element::mesh::MeshError),
    /// The material points cannot be placed (an unsupported count per element).
    #[error(transparent)]
    Points(#[from] crate::state::particles::PlacementError),
    /// Every element is empty.
    #[error("the case has no material points (every element is empty)")]
    NoPoints,
    /// A point's start lies outside its law's bounds (a void ratio beyond hypoplasticity's).
    #[error("material point {id} of material {material:?} cannot start at its stress: {why}")]
    Start {
        /// The point's id.
        id: u64,
        /// Its material's name.
        material: String,
        /// The law's refusal.
        why: String,
    },
    /// A point on another MPI rank cannot start at its stress (that rank names it).
    #[error(
        "a material point on another rank cannot start at its stress (that rank's error names it)"
    )]
    StartElsewhere,
    /// A feature that axisymmetric sections do not model.
    #[error("{0} is not modelled for axisymmetric sections; they run with material-point integration (MPM-MP) and without strain smoothing")]
    Axisymmetric(&'static str),
    /// The critical time step is not usable.
    #[error(transparent)]
    TimeStep(#[from] crate::input::time_step::TimeStepError),
    /// The moving mesh has nothing to follow.
    #[error(transparent)]
    MovingMesh(#[from] crate::step::moving_mesh::MovingMeshError),
    /// A load on material points has no points to carry it.
    #[error("the load on material points of the face with corner nodes {} has no filled element next to it", crate::driver::units::list(.nodes))]
    UnloadedFace {
        /// Input numbers of the face's corner nodes.
        nodes: Vec<u32>,
    },
    /// A background grid, with a feature that runs on the mesh's elements only.
    #[error("a background grid ([grid]) cannot model {0} yet; run it on the mesh's elements")]
    Grid(&'static str),
    /// The background mesh is not the grid's lattice.
    #[error(transparent)]
    Lattice(#[from] crate::basis::grid::LatticeError),
    /// The dual-domain gradients reach too many nodes.
    #[error(transparent)]
    DdmpReach(#[from] crate::basis::ddmp::DdmpError),
    /// The dual-domain gradients, with a feature that runs on the elements' own only.
    #[error(
        "the dual-domain gradients (gradient = \"ddmp\", --basis ddmp) cannot model {0} yet; \
         use the elements' own (gradient = \"element\")"
    )]
    Ddmp(&'static str),
    /// Mass scaling, with a feature it is not modelled with.
    #[error("mass scaling (f = {factor}) is not modelled {what} yet; run without it")]
    MassScaling {
        /// The factor.
        factor: f64,
        /// What the case has, as the end of the sentence.
        what: &'static str,
    },
    /// The semi-implicit scheme, with a feature it does not model.
    #[error(
        "the semi-implicit scheme (--scheme semi-implicit, time.scheme) cannot model {0} yet; \
         run it with the explicit scheme"
    )]
    SemiImplicit(&'static str),
    /// More than one process, with a feature that runs on one only.
    #[error("a run over {ranks} MPI ranks cannot model {what} yet; run it on one process")]
    Distributed {
        /// Processes of the communicator.
        ranks: usize,
        /// What the case asks for.
        what: &'static str,
    },
}

/// A material point that left the mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("material point {id} left the mesh at step {step} (t = {time} s) at ({x}, {y}, {z}) from element {element}; use --drop-lost to deactivate such points instead")]
pub struct Lost {
    /// Point id (1-based, input numbering).
    pub id: u32,
    /// Time step number (1-based).
    pub step: u64,
    /// Simulated time.
    pub time: f64,
    /// Position.
    pub x: f64,
    /// Position.
    pub y: f64,
    /// Position.
    pub z: f64,
    /// Last element (1-based, input numbering).
    pub element: u32,
}

/// What a step reads of the case besides the state: loads and their curves, damping, drag and
/// the stress-update switches, resolved once when the engine is built.
#[derive(Debug, Clone)]
pub struct StepConfig {
    /// Gravity acceleration vector (m/s²) at multiplier 1.
    pub gravity: [f64; 3],
    /// Gravity multiplier.
    pub gravity_curve: LoadCurve,
    /// Traction multiplier (face loads on nodes and on material points).
    pub traction_curve: LoadCurve,
    /// Liquid load multiplier.
    pub liquid_curve: LoadCurve,
    /// Local damping factor α.
    pub damping: f64,
    /// How local damping is applied.
    pub damping_rule: DampingRule,
    /// How the Darcy drag is integrated in time.
    pub drag: Drag,
    /// Whether a load on the liquid also loads the mixture.
    pub liquid_load_on_mixture: bool,
    /// Smooth pore-pressure rates through the nodes.
    pub smooth_pressure: bool,
    /// Jaumann (objective) stress rate.
    pub objective_stress: bool,
    /// Share of PIC in the points' velocity update (0: FLIP).
    pub pic_blend: f64,
    /// Axisymmetric sections: the hoop strain changes the points' volume.
    pub hoop_in_volume: bool,
    /// Mass scaling's factor f (1: none): the nodal accelerations are the forces over f m.
    pub mass_scaling: f64,
}

impl StepConfig {
    /// The step configuration of `case`.
    pub fn of(case: &Case) -> Self {
        StepConfig {
            gravity: case.loads.gravity,
            gravity_curve: case.loads.gravity_curve.clone(),
            traction_curve: case.loads.traction_curve.clone(),
            liquid_curve: case.loads.liquid_curve.clone(),
            damping: case.numerics.damping,
            damping_rule: case.numerics.damping_rule,
            drag: case.numerics.drag,
            mass_scaling: case.numerics.mass_scaling,
            liquid_load_on_mixture: case.loads.liquid_load_on_mixture,
            smooth_pressure: case.numerics.smooth_pressure,
            objective_stress: case.numerics.objective_stress,
            pic_blend: case.numerics.pic_blend,
            hoop_in_volume: case.numerics.hoop_in_volume,
        }
    }
}

/// Solver state and preallocated buffers, for precision `R` and element type `E`.
pub struct Engine<R: Real, E: Element = Tet4> {
    /// What each step reads of the case.
    pub config: StepConfig,
    /// The global reductions (energies, work, force norms, time step, lost points).
    comm: Arc<dyn Communicator>,
    /// This process's share of the mesh (all of it on one process).
    pub partition: Partition,
    /// Computational mesh: the partition's elements, numbered locally.
    pub mesh: Mesh<E, R>,
    /// A basis of its own: a background grid's, or the dual-domain gradients (`None`: the
    /// mesh's linear elements and their kernels).
    pub basis: Option<crate::basis::background::Background>,
    /// With a basis of its own, which nodes each thread sums and which elements it visits to.
    pub reach: Option<crate::parallel::reach::Reach>,
    /// Material points.
    pub particles: Particles<R>,
    /// Nodal arrays.
    pub grid: Grid<R>,
    /// Fixed components per computational node.
    pub fixed: Vec<[bool; 3]>,
    /// Face-load forces per computational node at multiplier 1.
    pub traction: Vec<V3<R>>,
    /// Liquid face-load forces per computational node at multiplier 1.
    pub liquid_traction: Vec<V3<R>>,
    /// Constitutive law per material index.
    pub laws: Vec<Law<R>>,
    /// Critical time step × Courant number.
    pub dt: f64,
    /// Simulated time.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// External work done so far (kJ).
    pub external_work: f64,
    /// Seconds spent per phase (see [`PHASES`]).
    pub phase_seconds: [f64; 6],
    /// Per phase, where the thread team's time went in the steps (the output phase is the
    /// caller's and stays empty): the runs' wall time against their busiest and mean thread.
    pub phase_load: [crate::parallel::team::TeamLoad; 6],
    /// Points deactivated under `--drop-lost`.
    pub lost: u64,
    /// Deactivate points that leave the mesh instead of stopping.
    pub drop_lost: bool,
    /// Face loads carried by points: (point index, force at multiplier 1).
    pub point_loads: Vec<(u32, V3<R>)>,
    /// Per-element sums for mixed integration (empty under material-point integration).
    pub mixed: Option<crate::step::mixed::Mixed<R>>,
    /// Per element, the smoothed pore-pressure rate's weights that particle to grid leaves for
    /// the rate's pass (two-phase cases with the rate smoothed through the nodes).
    pore_weights: Option<crate::state::pore_weights::PoreWeights<R>>,
    /// |free out-of-balance force| / |free external force| of the last step (0 when there
    /// is no external force).
    pub force_error: f64,
    /// The same ratio for the liquid of two-phase cases (0 in dry ones).
    pub liquid_force_error: f64,
    /// Kinetic energy of the nodes after the last step, Σ M_s |v|² / 2 + Σ M̄_w |w|² / 2 at the
    /// re-mapped velocities (kJ): Anura3D's measure in its quasi-static convergence check
    /// (the points' own kinetic energy is larger).
    pub nodal_kinetic: f64,
    /// The thread team.
    pub team: Team,
    /// Per-thread ranges and the node-to-corner map of the parallel sums.
    pub layout: Layout<R, E>,
    /// Per-corner partial sums (scratch of the particle-to-grid passes).
    pub slots: Slots<R>,
    /// Scratch of the re-sort by element.
    sort_scratch: SortScratch,
    /// Per thread, from the last locate: first point found outside (index, element), count,
    /// and whether any of its points changed element.
    locate_outcome: Vec<Outcome>,
    /// Liquid constants per material index (`None` for dry materials; all `None` in a dry case).
    pub fluids: Vec<Option<Fluid<R>>>,
    /// Fixed liquid components per computational node.
    pub liquid_fixed: Vec<[bool; 3]>,
    /// Anura3D's strain smoothing, when the case asks for it.
    pub smoothing: Option<crate::step::smoothing::StrainSmoothing<R>>,
    /// The bulk viscosity's constants, when the case damps with it.
    pub bulk: Option<crate::step::bulk_viscosity::BulkDamping<R>>,
    /// The semi-implicit scheme's pressure solve, when the case is stepped with it.
    pub semi_implicit: Option<crate::step::semi_implicit::SemiImplicit>,
    /// Per material index: weight density / mass density (1 but for Anura3D's drained soil).
    weight_ratio: Vec<f64>,
    /// Per material index: the gravity acceleration of this step times its weight ratio.
    gravity_by_material: Vec<V3<R>>,
    /// The critical time step taken again after every step (Anura3D's rule, GOM input).
    critical_step: Option<crate::step::time_step::CriticalStep>,
    /// The case's constraints (walls, prescribed velocities, contact, the moving mesh), in the
    /// order their hooks run in a step.
    pub constraints: Constraints<R, E>,
    /// In a run with contact, the structure's own nodes (the soil's are [`Engine::grid`]).
    pub structure: Option<Structure<R>>,
    /// The prescribed-velocity sets' reactions and imposed displacements
    /// ([`Case::reactions`]'s order), updated every step.
    pub reactions: Vec<crate::step::reaction::Reaction>,
    /// Input element (0-based) of each local element, so that messages name elements as the
    /// input.
    input_element: Vec<u32>,
    /// Input node number (1-based) of each computational node, for messages.
    input_node: Vec<u32>,
    /// The guard rails' settings.
    pub guards: Guards,
    /// The guard rails' sums of the last step per block of elements (empty when the guards are
    /// off).
    guard_slots: Vec<GuardSums>,
    /// The grid update's per-block sums.
    grid_scratch: grid_update::GridScratch<R>,
    /// The nodal energy pass's blocks of nodes.
    energy_blocks: Vec<()>,
    /// The nodal energy pass's per-node terms.
    energy_values: Vec<[f64; 4]>,
    /// Per block of owned elements, partial sums over its owned nodes or points.
    owned_partials: Vec<[f64; 4]>,
    /// Per material index: mass per initial volume of its points (t/m³).
    initial_density: Vec<R>,
    /// Strain energy taken up so far, Σ V σ:Δε over the steps (kJ).
    pub strain_energy: f64,
    /// Energy taken out so far by local damping and, in two-phase cases, the drag (kJ).
    pub dissipated: f64,
    /// Energy the liquid's compression holds after the last step, Σ n V p² / 2 K_w over the
    /// saturated points (kJ; from the guards' sums).
    pub liquid_energy: f64,
    /// The same at the start (kJ).
    liquid_initial: f64,
    /// External work so far at the steps' mid-step nodal velocities (kJ): the energy balance's
    /// work term (`external_work` counts it at the end-of-step velocities, as Anura3D).
    pub balance_work: f64,
    /// Kinetic energy of the points (both phases) after the last step (kJ; from the guards'
    /// sums, 0 when off).
    pub step_kinetic: f64,
    /// Kinetic energy at the start (kJ).
    initial_kinetic: f64,
    /// Elastic energy the initial stresses hold (kJ), estimated as Σ V σ0:σ0 / 2M (M the
    /// constrained modulus): the energy balance's scale for an initially stressed body.
    stored_energy: f64,
    /// The Courant number and the local element whose crossing time sets the step.
    courant: (f64, usize),
    /// Whether the blow-up check and the energy balance apply (not with prescribed velocities,
    /// whose work neither counts).
    energy_checked: (bool, bool),
    /// Whether each thread first touches its points' pages (again after a re-partition).
    first_touch: bool,
    /// The ranks' balance of points and its re-partitions (all zero on one process).
    pub balance: Balance,
}

/// Steps with migrating points after which a declined re-partition is looked at again even
/// though the imbalance has not grown.
pub const RELOOK_AFTER_MIGRATIONS: u64 = 100;

/// How evenly the ranks share the material points, and what was done about it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Balance {
    /// The largest rank's points over the mean, after the last migration (1: even; 0 before
    /// the first measure).
    pub imbalance: f64,
    /// The largest imbalance measured in the run.
    pub worst: f64,
    /// Re-partitions made so far.
    pub repartitions: u64,
    /// Seconds spent re-partitioning (the weights, the partition, the points' moves and the
    /// rank's new share).
    pub seconds: f64,
    /// Points this rank sent to others in re-partitions.
    pub points_moved: u64,
    /// Whether points came or went since the imbalance was last measured.
    stale: bool,
    /// The imbalance at which the last look found no better partition (0: none), so that the
    /// element weights are not gathered again until it grows ...
    declined_at: f64,
    /// ... or until the points have migrated [`RELOOK_AFTER_MIGRATIONS`] times since.
    migrations_since_decline: u64,
    /// Halo bytes sent under earlier partitions.
    bytes_before: u64,
}

impl<R: Real, E: Element> Engine<R, E> {
    /// Whether this engine is one rank of several.
    pub fn is_distributed(&self) -> bool {
        !self.partition.is_whole()
    }

    /// This process's rank and the number of ranks.
    pub fn rank(&self) -> (usize, usize) {
        (self.comm.rank(), self.comm.ranks())
    }

    /// The communicator of the run.
    pub fn communicator(&self) -> &dyn Communicator {
        &*self.comm
    }

    /// The modelled bytes per particle-step of each step phase (`driver::traffic`), for the
    /// way this run locates its points and takes its pore-pressure rate's weights.
    pub fn modelled_bytes(&self) -> [f64; 5] {
        use crate::driver::traffic::{modelled_bytes_stencil, StencilTables};
        if let Some(basis) = &self.basis {
            let (element_bytes, node_bytes) = basis.table_bytes();
            let tables = StencilTables {
                visits: 1.0 + self.reach.as_ref().map_or(0.0, |r| r.halo_share()),
                element_bytes,
                node_bytes,
                element_map: basis.grid().is_none(),
                smoothed_rate: self.config.smooth_pressure && self.grid.liquid.is_some(),
            };
            let (elements, nodes) = (self.mesh.elements(), self.mesh.nodes());
            let bytes = modelled_bytes_stencil::<R, E>(&self.particles, elements, nodes, tables);
            return if self.locates_in_stress_pass() {
                crate::driver::traffic::locating_in_stress(bytes)
            } else {
                bytes
            };
        }
        let bytes = crate::driver::traffic::modelled_bytes::<R, E>(
            &self.particles,
            self.mesh.elements(),
            self.mesh.nodes(),
            self.layout.slot_share(),
        );
        let bytes = if self.pore_weights.is_some() {
            crate::driver::traffic::with_pore_weights::<R>(
                bytes,
                self.mesh.elements(),
                self.particles.len(),
            )
        } else {
            bytes
        };
        if self.locates_in_stress_pass() {
            crate::driver::traffic::locating_in_stress(bytes)
        } else {
            bytes
        }
    }
}
