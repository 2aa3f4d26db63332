//! The explicit MPM engine: state, critical time step and one MUSL step through the phases.

use std::ops::Range;
use std::time::Instant;

use crate::element::locate::{
    locate_width, merge, relocate, run_inside, Found, Outcome, NOTHING_FOUND,
};
use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::Element;
use crate::input::case::{Case, Guards, Integration, MixedRule};
use crate::material::law::Law;
use crate::material::liquid::Fluid;
use crate::parallel::comm::{Communicator, SingleProcess};
use crate::parallel::gather::exact_total;
use crate::parallel::gather::{Layout, Slots};
use crate::parallel::partition::Partition;
use crate::parallel::sort::SortScratch;
pub use crate::parallel::team::Options;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::{Grid, LiquidNodes};
use crate::state::particles::{self, Field, FieldVisitor, Particles, Value};
use crate::step::grid_update::{DampingRule, Drag};
use crate::step::load_curve::LoadCurve;
use crate::step::nodal_energy::NodalEnergy;
use crate::step::stress::{Guard, GuardSums};
use crate::step::tail::{self, Nodal};
use crate::step::{grid_to_particle, grid_update, nodal_energy, particle_to_grid, stress};
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
}

impl StepConfig {
    /// The step configuration of `case`.
    pub fn of(case: &Case) -> Self {
        StepConfig {
            gravity: case.gravity,
            gravity_curve: case.gravity_curve,
            traction_curve: case.traction_curve,
            liquid_curve: case.liquid_curve,
            damping: case.damping,
            damping_rule: case.damping_rule,
            drag: case.drag,
            liquid_load_on_mixture: case.liquid_load_on_mixture,
            smooth_pressure: case.smooth_pressure,
            objective_stress: case.objective_stress,
            pic_blend: case.pic_blend,
            hoop_in_volume: case.hoop_in_volume,
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
    /// Material points.
    pub particles: Particles<R>,
    /// Nodal arrays.
    pub grid: Grid<R>,
    /// Fixed components per computational node.
    pub fixed: Vec<[bool; 3]>,
    /// Face-load forces per computational node at multiplier 1.
    pub traction: Vec<V3<R>>,
    /// The nodes on rigid walls (empty without them).
    pub walls: Vec<crate::step::wall_friction::WallNode<R>>,
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
    /// Per material index: weight density / mass density (1 but for Anura3D's drained soil).
    weight_ratio: Vec<f64>,
    /// Per material index: the gravity acceleration of this step times its weight ratio.
    gravity_by_material: Vec<V3<R>>,
    /// Velocities prescribed on material points (only when the case has them).
    pub prescribed: Option<crate::step::prescribed::Prescribed<R>>,
    /// Velocities prescribed on nodes (only when the case has them).
    pub nodal_velocity: Option<crate::step::nodal_velocity::NodalVelocity<R>>,
    /// Anura3D's moving mesh (only when the case has one).
    pub moving_mesh: Option<crate::step::moving_mesh::MovingMesh>,
    /// The critical time step taken again after every step (Anura3D's rule, GOM input).
    critical_step: Option<crate::step::time_step::CriticalStep>,
    /// Contact between a structure and the soil (only when the case has it): the structure's
    /// nodal arrays, the soil's being [`Engine::grid`].
    pub contact: Option<crate::step::contact::Contact<R>>,
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
    /// Sets up the mesh, places the material points and computes the time step, with the
    /// case's engine options.
    pub fn new(case: &Case, drop_lost: bool) -> Result<Self, SetupError> {
        Self::with_options(case, drop_lost, case.engine)
    }

    /// [`Engine::new`] with the given thread options.
    pub fn with_options(
        case: &Case,
        drop_lost: bool,
        options: Options,
    ) -> Result<Self, SetupError> {
        Self::with_communicator(case, drop_lost, options, Arc::new(SingleProcess))
    }

    /// [`Engine::with_options`] with the reductions of `comm` (one process: [`SingleProcess`]).
    pub fn with_communicator(
        case: &Case,
        drop_lost: bool,
        options: Options,
        comm: Arc<dyn Communicator>,
    ) -> Result<Self, SetupError> {
        if E::AXISYMMETRIC {
            // Both average over an element, where the radius weighting of an axisymmetric
            // section would enter (Anura3D's own MPM-MIXED integrates such an element at its
            // first point): not modelled.
            if matches!(case.integration, Integration::Mixed { .. }) {
                return Err(SetupError::Axisymmetric(
                    "mixed integration (MPM-MIXED, Gauss points in full elements)",
                ));
            }
            if case.strain_smoothing {
                return Err(SetupError::Axisymmetric("strain smoothing"));
            }
        }
        let team = Team::new(options.threads, options.pin)?;
        let global = case.mesh::<E, R>()?;
        // Element-indexed input is read through the partition: `own` is the global range.
        let partition = if comm.ranks() > 1 {
            let unmodelled = [
                (
                    matches!(case.integration, Integration::Mixed { .. }),
                    "mixed integration (MPM-MIXED)",
                ),
                (case.strain_smoothing, "strain smoothing"),
                (case.prescribed.is_some(), "prescribed velocities on points"),
                (
                    !case.nodal_velocity.is_empty(),
                    "prescribed velocities on nodes",
                ),
                (
                    !case.point_loads.is_empty(),
                    "loads carried by material points",
                ),
                (case.moving_mesh.is_some(), "a moving mesh"),
                (case.contact.is_some(), "contact between bodies"),
            ];
            if let Some((_, what)) = unmodelled.iter().find(|(on, _)| *on) {
                return Err(SetupError::Distributed {
                    ranks: comm.ranks(),
                    what,
                });
            }
            let weight: Vec<u64> = case
                .points_per_element
                .iter()
                .map(|&n| u64::from(n))
                .collect();
            let mut parts = Partition::along_curve(&global, &weight, comm.ranks());
            if parts.len() != comm.ranks() || parts.iter().any(|p| p.owned() == 0) {
                return Err(SetupError::Distributed {
                    ranks: comm.ranks(),
                    what: "more ranks than blocks of 64 elements",
                });
            }
            parts.swap_remove(comm.rank())
        } else {
            Partition::whole(&global)
        };
        let own = partition.elements();
        let mesh = partition.local_mesh(global);
        let density = |m: u32| {
            case.materials[m as usize]
                .as_ref()
                .map_or(0.0, |s| s.density)
        };
        let ids = case.point_ids();
        let first_id: Vec<u32> = own.clone().map(|e| ids.input_first(e) as u32).collect();
        let mut particles = particles::place(
            &mesh,
            &case.points_per_element[own.clone()],
            &case.element_material[own.clone()],
            Some(&first_id),
            &|e| case.element_number(partition.global_element(e)),
            density,
        )?;
        if particles.is_empty() {
            return Err(SetupError::NoPoints);
        }
        // Anura3D's boundary points are found as placed, before the points are reordered.
        let boundary = match case.integration {
            Integration::Mixed {
                rule: MixedRule::Anura3d,
                ..
            } => crate::step::mixed::boundary_points(&mesh, &particles),
            _ => Vec::new(),
        };
        // The laws' state slab: as many values per point as the most demanding law keeps.
        particles.state_len = case
            .materials
            .iter()
            .flatten()
            .map(|m| m.law.state_len())
            .max()
            .unwrap_or(0);
        particles.state = vec![R::ZERO; particles.state_len * particles.len()];
        let two_phase = case.has_liquid();
        if two_phase {
            particles.add_liquid(
                |m| {
                    case.materials[m as usize]
                        .as_ref()
                        .map_or(0.0, |s| s.initial_pore_pressure)
                },
                case.fixed_liquid_mass,
            );
        }
        if let (Some(s), Some(lp)) = (&case.initial_state, particles.liquid.as_mut()) {
            // Saturated points start in the given undrained state.
            for i in 0..particles.x.len() {
                let m = particles.material[i] as usize;
                let Some(spec) = case.materials[m].as_ref().filter(|s| s.liquid.is_some()) else {
                    continue;
                };
                let law = spec.law.build::<R>();
                let mut stress = [R::ZERO; 6];
                let eps = R::of(s.vertical_strain);
                let de = [R::ZERO, eps, R::ZERO, R::ZERO, R::ZERO, R::ZERO];
                law.update(&mut stress, &de, &mut []);
                particles.stress[i] = stress;
                lp.p[i] = R::of(s.pore_pressure);
            }
        }
        if let Some(init) = &case.initial_stress {
            apply_initial_stress::<E, R>(init, case, &partition, &mut particles);
        }
        let fluids: Vec<Option<Fluid<R>>> = case
            .materials
            .iter()
            .map(|m| m.as_ref().and_then(|s| s.liquid.as_ref()).map(Fluid::new))
            .collect();
        let NodeInputs {
            mut fixed,
            liquid_fixed,
            walls,
            traction,
            liquid_traction,
            input_element,
            input_node,
        } = NodeInputs::of(case, &mesh, &partition);
        let reactions = case.reactions();
        let nodal_velocity = (!case.nodal_velocity.is_empty()).then(|| {
            let nv = crate::step::nodal_velocity::NodalVelocity::new(
                &case.nodal_velocity,
                &mesh.node_of_model,
                usize::from(case.prescribed.is_some()),
            );
            // The grid update and the re-mapping treat them as fixed; they are set after each.
            nv.constrain(&mut fixed);
            nv
        });
        let laws = case
            .materials
            .iter()
            .map(|m| m.as_ref().map_or(Law::Void, |s| s.law.build()))
            .collect();
        let dt = comm.min(crate::input::time_step::critical(case, own.clone(), |e| {
            mesh.min_altitude[e - own.start].f64()
        })?);
        let critical_element = critical_element(case, &partition, &mesh);
        let mut grid = Grid::new(mesh.nodes());
        if two_phase {
            grid.liquid = Some(LiquidNodes::new(mesh.nodes()));
        }
        let point_loads = resolve_point_loads(&mesh, &particles, case, comm.as_ref())?;
        let prescribed = case.prescribed.as_ref().map(|pv| {
            let pv = pv.clone().owned_by(&partition);
            crate::step::prescribed::Prescribed::new(&pv, &mesh, &particles)
        });
        let moving_mesh = case
            .moving_mesh
            .as_ref()
            .map(|spec| {
                crate::step::moving_mesh::MovingMesh::new(
                    spec,
                    &case.model,
                    &mesh,
                    &case.element_material,
                    &case.points_per_element,
                    &case.input_node,
                )
            })
            .transpose()?;
        let contact = case
            .contact
            .as_ref()
            .map(|spec| crate::step::contact::Contact::new(spec, &mesh, &case.element_material));
        let layout = layout_of(&partition, &mesh, &particles, team.threads, &comm);
        if options.first_touch {
            particles = first_touch(&team, &layout, particles);
        }
        let slots = layout.new_slots();
        let mixed = match case.integration {
            Integration::MaterialPoints => None,
            Integration::Mixed { filling, rule } => Some(crate::step::mixed::Mixed::new(
                mesh.elements(),
                filling,
                rule,
                boundary,
            )),
        };
        let weight_ratio: Vec<f64> = case
            .materials
            .iter()
            .map(|m| m.as_ref().map_or(1.0, |s| s.weight_density / s.density))
            .collect();
        let smoothing = case.strain_smoothing.then(|| {
            crate::step::smoothing::StrainSmoothing::new(
                mesh.nodes(),
                &case.element_material[own.clone()],
            )
        });
        let guard_slots = if case.guards.enabled {
            vec![GuardSums::EMPTY; layout.blocks()]
        } else {
            Vec::new()
        };
        let initial_density = case
            .materials
            .iter()
            .map(|m| R::of(m.as_ref().map_or(0.0, |s| s.density)))
            .collect();
        // (Not in an axisymmetric section, whose points' hoop rates differ: the rate's pass goes
        // point by point there.)
        let pore_weights =
            (two_phase && case.smooth_pressure && !case.strain_smoothing && !E::AXISYMMETRIC)
                .then(|| crate::state::pore_weights::PoreWeights::new(mesh.elements()));
        let mut engine = Engine {
            input_node,
            guards: case.guards,
            guard_slots,
            grid_scratch: grid_update::GridScratch::new(mesh.nodes()),
            energy_blocks: vec![(); mesh.nodes().div_ceil(nodal_energy::NODE_BLOCK)],
            energy_values: vec![[0.0; 4]; mesh.nodes()],
            owned_partials: vec![[0.0; 4]; layout.owned_blocks()],
            initial_density,
            strain_energy: 0.0,
            dissipated: 0.0,
            liquid_energy: 0.0,
            liquid_initial: 0.0,
            balance_work: 0.0,
            step_kinetic: 0.0,
            initial_kinetic: 0.0,
            stored_energy: 0.0,
            courant: (case.courant, critical_element),
            // Both energy checks need every energy term; prescribed velocities do work that is
            // not counted, and contact takes energy out that is not counted either.
            energy_checked: (
                reactions.is_empty() && case.contact.is_none(),
                reactions.is_empty() && case.contact.is_none(),
            ),
            comm,
            config: StepConfig::of(case),
            input_element,
            partition,
            smoothing,
            gravity_by_material: vec![[R::ZERO; 3]; weight_ratio.len()],
            weight_ratio,
            mesh,
            particles,
            grid,
            fixed,
            traction,
            liquid_traction,
            laws,
            dt,
            time: 0.0,
            steps: 0,
            external_work: 0.0,
            phase_seconds: [0.0; 6],
            phase_load: Default::default(),
            lost: 0,
            drop_lost,
            point_loads,
            mixed,
            pore_weights,
            force_error: 0.0,
            liquid_force_error: 0.0,
            nodal_kinetic: 0.0,
            fluids,
            liquid_fixed,
            walls,
            prescribed,
            nodal_velocity,
            moving_mesh,
            contact,
            critical_step: (case.critical_step
                == crate::input::case::CriticalStepRule::OccupiedEachStep)
                .then(|| crate::step::time_step::CriticalStep::new(case, team.threads)),
            reactions,
            locate_outcome: vec![NOTHING_FOUND; team.threads],
            team,
            layout,
            slots,
            sort_scratch: SortScratch::default(),
            first_touch: options.first_touch,
            balance: Balance {
                stale: true,
                ..Balance::default()
            },
        };
        // Sums over the points in their global order (on one rank, as one process forms them).
        let whole = engine.on_root(|e| {
            let stored = if case.initial_stress.is_some() {
                e.comm.sum(stored_energy(case, &e.particles))
            } else {
                0.0
            };
            let (liquid_kinetic, liquid_energy) = e.liquid_energies();
            vec![stored, e.kinetic_energy() + liquid_kinetic, liquid_energy]
        });
        let mut sums = Vec::new();
        engine
            .comm
            .all_gather(&whole.unwrap_or_default(), &mut sums);
        engine.stored_energy = sums[0];
        engine.initial_kinetic = sums[1];
        engine.step_kinetic = engine.initial_kinetic;
        engine.liquid_initial = sums[2];
        engine.liquid_energy = sums[2];
        Ok(engine)
    }

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

    /// Runs `f` on rank 0 with every rank's points gathered there in their global order (the
    /// order one process keeps, elements numbered globally) and the reductions of one process,
    /// so that the output files and sums over points are those of a one-process run; the other
    /// ranks get `None`. On one process, `f(self)`. Collective.
    pub fn on_root<T>(&mut self, f: impl FnOnce(&Self) -> T) -> Option<T> {
        if self.partition.is_whole() {
            return Some(f(self));
        }
        let mut bytes = Vec::with_capacity(self.particles.len() * self.particles.encoded_len());
        for i in 0..self.particles.len() {
            let local = self.particles.element[i];
            self.particles.element[i] = self.partition.global_element(local as usize) as u32;
            self.particles.put_point(i, &mut bytes);
            self.particles.element[i] = local;
        }
        let all = self.comm.gather_bytes(&bytes)?;
        let mut everyone = self.particles.clone();
        everyone.retain(&vec![false; everyone.len()]);
        for part in &all {
            if !part.is_empty() {
                everyone.push_encoded(part);
            }
        }
        let own = std::mem::replace(&mut self.particles, everyone);
        let comm = std::mem::replace(&mut self.comm, Arc::new(SingleProcess));
        let out = f(self);
        self.particles = own;
        self.comm = comm;
        Some(out)
    }

    /// Per rank (on rank 0; `None` elsewhere): its points, seconds per phase, and halo: the
    /// elements it sends and receives per exchange and the bytes it has sent. Collective.
    pub fn rank_report(&self) -> Option<Vec<serde_json::Value>> {
        let halo = self.layout.halo();
        let mine = serde_json::json!({
            "rank": self.comm.rank(),
            "elements": self.partition.owned(),
            "halo_elements": self.partition.halo().len(),
            "points": self.particles.len(),
            "phase_seconds": self.phase_seconds,
            "neighbours": halo.map(|h| h.sizes().iter().map(|&(r, s, g)| serde_json::json!({"rank": r, "sends": s, "receives": g})).collect::<Vec<_>>()).unwrap_or_default(),
            "bytes_sent": self.balance.bytes_before + halo.map_or(0, |h| h.bytes_sent()),
            "pinned_cores": self.team.pinned,
            "steps": self.steps,
            "communicator_calls": self.comm.traffic().calls,
            "messages": self.comm.traffic().messages,
            "message_bytes": self.comm.traffic().bytes,
            "points_moved_by_repartitions": self.balance.points_moved,
            "repartition_seconds": self.balance.seconds,
        });
        let all = self.comm.gather_bytes(mine.to_string().as_bytes())?;
        Some(
            all.iter()
                .map(|b| serde_json::from_slice(b).expect("a rank's report"))
                .collect(),
        )
    }

    /// The engine's state between steps that is not in the particle arrays and that later steps
    /// or outputs read, by name, for a checkpoint (f64 values as their bits). Every field is taken
    /// apart here, so a field added to the engine does not compile until it is placed in or out.
    pub fn checkpoint_scalars(&self) -> Vec<(&'static str, u64)> {
        let Engine {
            // Rebuilt from the case at set-up, or scratch that each step rewrites before reading.
            config: _,
            comm: _,
            partition: _,
            mesh: _,
            grid: _,
            fixed: _,
            traction: _,
            liquid_traction: _,
            laws: _,
            drop_lost: _,
            mixed: _,
            pore_weights: _,
            team: _,
            // How the threads spent their time: this run's, like the team.
            phase_load: _,
            layout: _,
            slots: _,
            sort_scratch: _,
            locate_outcome: _,
            fluids: _,
            liquid_fixed: _,
            walls: _,
            smoothing: _,
            weight_ratio: _,
            gravity_by_material: _,
            input_element: _,
            input_node: _,
            guards: _,
            guard_slots: _,
            grid_scratch: _,
            energy_blocks: _,
            energy_values: _,
            owned_partials: _,
            initial_density: _,
            courant: _,
            energy_checked: _,
            stored_energy: _,
            first_touch: _,
            // Distributed runs take no checkpoints.
            balance: _,
            // Saved through the field list.
            particles: _,
            // Indices of points: they follow the points (by id) when restored.
            point_loads: _,
            prescribed: _,
            nodal_velocity: _,
            // Saved below, by set.
            reactions,
            // Saved below: the moved nodes' coordinates.
            moving_mesh,
            // Its scratch; the step it set is `dt`.
            critical_step: _,
            // Rebuilt at set-up; its arrays are each step's scratch.
            contact: _,
            // Saved, the time step to check that the set-up matches.
            dt,
            time,
            steps,
            external_work,
            phase_seconds,
            lost,
            force_error,
            liquid_force_error,
            nodal_kinetic,
            strain_energy,
            dissipated,
            liquid_energy,
            liquid_initial,
            balance_work,
            step_kinetic,
            initial_kinetic,
        } = self;
        let mut out = vec![
            ("dt", dt.to_bits()),
            ("time", time.to_bits()),
            ("steps", *steps),
            ("external_work", external_work.to_bits()),
            ("lost", *lost),
            ("force_error", force_error.to_bits()),
            ("liquid_force_error", liquid_force_error.to_bits()),
            ("strain_energy", strain_energy.to_bits()),
            ("dissipated", dissipated.to_bits()),
            ("balance_work", balance_work.to_bits()),
            ("step_kinetic", step_kinetic.to_bits()),
            ("initial_kinetic", initial_kinetic.to_bits()),
            ("liquid_energy", liquid_energy.to_bits()),
            ("liquid_initial", liquid_initial.to_bits()),
            ("nodal_kinetic", nodal_kinetic.to_bits()),
        ];
        out.extend(
            PHASES
                .iter()
                .zip(phase_seconds)
                .map(|(&n, s)| (n, s.to_bits())),
        );
        for r in reactions {
            out.push(("reaction_travel", r.travel.to_bits()));
            out.extend(
                ["reaction_fx", "reaction_fy", "reaction_fz"]
                    .into_iter()
                    .zip(r.force.map(f64::to_bits)),
            );
        }
        if let Some(mm) = moving_mesh {
            out.extend(mm.state().into_iter().map(|x| ("moving_mesh", x.to_bits())));
        }
        out
    }

    /// Carries on with `team` (between steps): the threads' ranges are laid out again for its
    /// thread count. The results do not change (they never depend on the threads); the
    /// points stay where the old team first touched them.
    pub fn rethread(&mut self, team: Team) {
        self.layout = self
            .layout
            .for_threads(&self.mesh, &self.particles, team.threads);
        self.slots = self.layout.new_slots();
        self.locate_outcome = vec![NOTHING_FOUND; team.threads];
        self.team = team;
    }

    /// Restores a checkpoint into an engine just set up for the same case: the scalars of
    /// [`Engine::checkpoint_scalars`] and the particle arrays; the point loads and prescribed
    /// points follow their points, and the threads' ranges the points' elements.
    pub fn restore(
        &mut self,
        saved: &crate::driver::checkpoint::Saved,
    ) -> Result<(), crate::driver::checkpoint::CheckpointError> {
        let expected = self.checkpoint_scalars();
        let names: Vec<&str> = saved.scalars.iter().map(|(n, _)| n.as_str()).collect();
        if names != expected.iter().map(|(n, _)| *n).collect::<Vec<_>>() {
            return Err(saved.corrupt(format!("engine state [{}]", names.join(", "))));
        }
        let v = |k: usize| saved.scalars[k].1;
        let f = |k: usize| f64::from_bits(v(k));
        if self.critical_step.is_some() {
            // Taken again after every step: the saved one is the next step's.
            self.dt = f(0);
        } else if v(0) != self.dt.to_bits() {
            return Err(saved.corrupt(format!(
                "time step {} s, the case now gives {} s",
                f(0),
                self.dt
            )));
        }
        // Old index (as placed) of each id, to carry point indices over.
        let placed = self.particles.id.clone();
        saved.load_particles(&mut self.particles)?;
        let top = placed.iter().copied().max().unwrap_or(0) as usize;
        let mut index_of = vec![u32::MAX; top + 1];
        for (i, &id) in placed.iter().enumerate() {
            index_of[id as usize] = i as u32;
        }
        let mut new_of_old = vec![u32::MAX; placed.len()];
        for (new, &id) in self.particles.id.iter().enumerate() {
            let old = index_of.get(id as usize).copied().unwrap_or(u32::MAX);
            if old == u32::MAX || new_of_old[old as usize] != u32::MAX {
                return Err(saved.corrupt(format!("point id {id} unknown or repeated")));
            }
            new_of_old[old as usize] = new as u32;
        }
        for load in &mut self.point_loads {
            load.0 = new_of_old[load.0 as usize];
        }
        if let Some(pr) = &mut self.prescribed {
            pr.follow(&new_of_old);
        }
        let el = &self.particles.element;
        if el.iter().any(|&e| e as usize >= self.mesh.elements())
            || !el.windows(2).all(|w| w[0] <= w[1])
        {
            return Err(
                saved.corrupt("points not sorted by element, or an element beyond the mesh".into())
            );
        }
        // Every per-material table is indexed by it (a file re-signed after an edit passes
        // the checksum).
        let materials = self.laws.len();
        if let Some((i, &m)) = self
            .particles
            .material
            .iter()
            .enumerate()
            .find(|(_, &m)| m as usize >= materials)
        {
            return Err(saved.corrupt(format!(
                "material point {} of material {m}; the case has {materials}",
                self.particles.id[i]
            )));
        }
        self.layout.set_particle_elements(&self.particles.element);
        self.time = f(1);
        self.steps = v(2);
        self.external_work = f(3);
        self.lost = v(4);
        self.force_error = f(5);
        self.liquid_force_error = f(6);
        self.strain_energy = f(7);
        self.dissipated = f(8);
        self.balance_work = f(9);
        self.step_kinetic = f(10);
        self.initial_kinetic = f(11);
        self.liquid_energy = f(12);
        self.liquid_initial = f(13);
        self.nodal_kinetic = f(14);
        for (k, s) in self.phase_seconds.iter_mut().enumerate() {
            *s = f(15 + k);
        }
        let at = 15 + PHASES.len();
        for (k, r) in self.reactions.iter_mut().enumerate() {
            r.travel = f(at + 4 * k);
            r.force = [1, 2, 3].map(|j| f(at + 4 * k + j));
        }
        if let Some(mm) = &mut self.moving_mesh {
            let at = at + 4 * self.reactions.len();
            let state: Vec<f64> = (at..saved.scalars.len()).map(f).collect();
            if !mm.restore(&mut self.mesh, &state) {
                return Err(saved.corrupt("the moving mesh's node positions".into()));
            }
        }
        Ok(())
    }

    /// One explicit MUSL step of length `dt`; `snap_to` sets the clock exactly when the step
    /// ends on an output time (so times print as given, not as sums of steps).
    pub fn step(&mut self, dt: f64, snap_to: Option<f64>) -> Result<(), StepError> {
        let t0 = Instant::now();
        // Team runs between steps (energies, output) are not the step's.
        self.team.take_load();
        let case = &self.config;
        let gm = case.gravity_curve.at(self.time + dt);
        let gravity = case.gravity.map(|g| R::of(g * gm));
        for (gv, &ratio) in self.gravity_by_material.iter_mut().zip(&self.weight_ratio) {
            *gv = case.gravity.map(|g| R::of(g * gm * ratio));
        }
        let tm = R::of(case.traction_curve.at(self.time + dt));
        // Each body to its own nodes (one pass of every point without contact): the soil to the
        // engine's grid, the structure to the contact's.
        let soil = self.contact.as_ref().map(|c| c.soil());
        let structure = self
            .contact
            .as_mut()
            .map(|c| (&mut c.grid, Some(c.structure)));
        // The liquid goes with the soil's pass (contact refuses saturated materials).
        let mut liquid = Some(particle_to_grid::LiquidLoads {
            fluids: &self.fluids,
            gravity,
        });
        for (grid, body) in std::iter::once((&mut self.grid, soil)).chain(structure) {
            particle_to_grid::particle_to_grid(
                &self.team,
                &self.layout,
                &mut self.slots,
                &self.mesh,
                &self.particles,
                &self.gravity_by_material,
                self.mixed.as_mut(),
                grid,
                body,
                liquid.take(),
                // (Asked of the liquid's pass only, the first.)
                self.pore_weights.as_mut(),
            );
        }
        particle_to_grid::add_point_loads(
            &self.mesh,
            &self.particles,
            &self.point_loads,
            tm,
            &mut self.grid,
        );
        let t1 = Instant::now();
        self.phase_load[0] += self.team.take_load();
        let liquid_scale = R::of(case.liquid_curve.at(self.time + dt));
        if self.grid.liquid.is_some() {
            grid_update::grid_update_two_phase::<E, R>(
                &self.team,
                &mut self.grid_scratch,
                &mut self.grid,
                &self.traction,
                tm,
                &self.liquid_traction,
                liquid_scale,
                &self.fixed,
                &self.liquid_fixed,
                R::of(case.damping),
                case.damping_rule,
                case.drag,
                case.liquid_load_on_mixture,
                gravity,
                R::of(dt),
                &*self.comm,
            );
            tail::cut_grid(
                &self.team,
                &*self.comm,
                &mut self.grid_scratch,
                &mut self.grid,
                Nodal::Acceleration,
            );
        } else {
            // Each body's nodes (no loads on nodes with contact: the soil's traction array is
            // zero for the structure too), then, with contact, the force sums over both.
            let structure = self.contact.as_mut().map(|c| (&mut c.scratch, &mut c.grid));
            let bodies = std::iter::once((&mut self.grid_scratch, &mut self.grid)).chain(structure);
            for (scratch, grid) in bodies {
                grid_update::grid_update::<E, R>(
                    &self.team,
                    scratch,
                    grid,
                    &self.traction,
                    tm,
                    &self.fixed,
                    R::of(case.damping),
                    case.damping_rule,
                    &*self.comm,
                );
                tail::cut_grid(&self.team, &*self.comm, scratch, grid, Nodal::Acceleration);
                crate::step::wall_friction::apply_walls(&self.walls, grid, &self.fixed, R::of(dt));
            }
            if let Some(c) = &mut self.contact {
                c.force_sums(
                    &self.team,
                    &self.grid,
                    &self.fixed,
                    &mut self.grid_scratch.node_sums,
                );
            }
        }
        let (forces, liquid_forces) = {
            let (layout, team, comm) = (&self.layout, &self.team, &*self.comm);
            let partials = &mut self.owned_partials;
            self.grid_scratch.totals(|values| {
                layout.sum_owned(team, values, partials);
                exact_total(comm, &partials[..layout.owned_blocks()])
            })
        };
        self.force_error = forces.ratio();
        self.liquid_force_error = liquid_forces.ratio();
        let t2 = Instant::now();
        self.phase_load[1] += self.team.take_load();
        let pm = self
            .prescribed
            .as_ref()
            .map_or(R::ZERO, |pr| R::of(pr.multiplier(self.time + dt)));
        if let Some(pr) = &self.prescribed {
            // With contact the prescribed points are the structure's: its nodes are the masked
            // ones.
            let g = self
                .contact
                .as_mut()
                .map_or(&mut self.grid, |c| &mut c.grid);
            pr.after_grid_update(g, &mut self.particles, pm);
            self.reactions[0].force = pr.reaction(g, &self.traction, tm);
        }
        if let Some(c) = &mut self.contact {
            if let Some(pr) = &mut self.prescribed {
                pr.mean_of_marked(&self.mesh, &self.particles);
            }
            let pr = self.prescribed.as_ref();
            c.correct(
                &mut self.grid,
                &self.layout,
                &self.particles,
                &self.fixed,
                &|n| pr.and_then(|pr| pr.masked(n)),
                R::of(case.damping),
                case.damping_rule,
                dt,
            );
            if let Some(pr) = pr {
                // Anura3D's second override, before the points take the accelerations.
                pr.after_grid_update(&mut c.grid, &mut self.particles, pm);
            }
        }
        if let Some(nv) = &mut self.nodal_velocity {
            nv.after_grid_update(
                &mut self.grid,
                &self.traction,
                tm,
                &mut self.reactions,
                self.time,
                dt,
            );
        }
        for r in &mut self.reactions {
            r.advance(self.time + dt, dt);
        }
        let soil = self.contact.as_ref().map(|c| c.soil());
        let structure = self
            .contact
            .as_mut()
            .map(|c| (&mut c.grid, Some(c.structure)));
        for (k, (grid, body)) in std::iter::once((&mut self.grid, soil))
            .chain(structure)
            .enumerate()
        {
            grid_to_particle::grid_to_particle(
                &self.team,
                &self.layout,
                &mut self.slots,
                &self.mesh,
                &mut self.particles,
                grid,
                &self.fixed,
                R::of(dt),
                R::of(case.pic_blend),
                self.guards.enabled.then_some(&mut self.guard_slots[..]),
                body,
                k == 0,
                // The liquid goes with the soil's pass (contact refuses saturated materials).
                (k == 0).then_some(grid_to_particle::LiquidRemap {
                    fluids: &self.fluids,
                    fixed: &self.liquid_fixed,
                }),
            );
        }
        // Each body's re-mapped velocities, their precursor cut before walls and prescribed
        // velocities set theirs.
        let structure = self.contact.as_mut().map(|c| (&mut c.scratch, &mut c.grid));
        for (scratch, grid) in
            std::iter::once((&mut self.grid_scratch, &mut self.grid)).chain(structure)
        {
            tail::cut_grid(&self.team, &*self.comm, scratch, grid, Nodal::Velocity);
        }
        // Walls: no re-mapped velocity into a wall (each body's).
        crate::step::wall_friction::hold_remapped(&self.walls, &mut self.grid.vel);
        if let Some(c) = &mut self.contact {
            crate::step::wall_friction::hold_remapped(&self.walls, &mut c.grid.vel);
        }
        if let Some(pr) = &mut self.prescribed {
            let g = self
                .contact
                .as_mut()
                .map_or(&mut self.grid, |c| &mut c.grid);
            pr.after_remap(&self.mesh, g, &mut self.particles, pm);
        }
        if let Some(nv) = &self.nodal_velocity {
            nv.after_remap(&mut self.grid);
        }
        let t3 = Instant::now();
        self.phase_load[2] += self.team.take_load();
        if let Some(sm) = &mut self.smoothing {
            sm.compute(
                &self.team,
                &self.layout,
                &mut self.slots,
                &self.mesh,
                &self.particles,
                &self.grid,
                R::of(dt),
            );
        }
        let rate_pending = stress::update_pore_pressure(
            &self.team,
            &self.layout,
            &mut self.slots,
            &self.mesh,
            &mut self.particles,
            &mut self.grid,
            &self.fluids,
            case.smooth_pressure,
            self.smoothing.as_ref(),
            self.pore_weights.as_mut(),
            R::of(dt),
        );
        let fused_locate = self.locates_in_stress_pass();
        if fused_locate {
            self.locate_outcome.fill(NOTHING_FOUND);
        }
        // Each body's points strain and move with its own nodes' velocities.
        let soil = self.contact.as_ref().map(|c| c.soil());
        let structure = self.contact.as_ref().map(|c| (&c.grid, Some(c.structure)));
        // The smoothed pore-pressure rates reach the points in the stress pass.
        let pore_rate = self
            .grid
            .liquid
            .as_ref()
            .filter(|_| rate_pending)
            .map(|gl| stress::PoreRate {
                nodal: &gl.rate,
                fluids: &self.fluids,
            });
        for (k, (grid, body)) in std::iter::once((&self.grid, soil))
            .chain(structure)
            .enumerate()
        {
            stress::update_stress_and_move(
                &self.team,
                &self.layout,
                &self.mesh,
                &mut self.particles,
                grid,
                &self.laws,
                case.objective_stress,
                case.hoop_in_volume,
                self.smoothing.as_ref(),
                R::of(dt),
                self.guards.enabled.then_some(Guard {
                    slots: &mut self.guard_slots,
                    initial_density: &self.initial_density,
                    fluids: &self.fluids,
                    min_volume_ratio: R::of(self.guards.min_volume_ratio),
                }),
                body,
                pore_rate.filter(|_| k == 0),
                (fused_locate && k == 0).then_some(&mut self.locate_outcome[..]),
            );
        }
        if let Some(m) = &self.mixed {
            m.after_stress(&self.team, &self.layout, &mut self.particles);
        }
        // The step's energy terms at the nodes, with the remapped velocities: Anura3D's
        // external power and nodal kinetic energy, and the guard's work and dissipation. With
        // contact the structure's nodes add their power, work and dissipation; Anura3D's nodal
        // kinetic energy (its convergence check) is the soil's alone.
        let loads = nodal_energy::Loads {
            traction: (&self.traction, tm),
            liquid_traction: (&self.liquid_traction, liquid_scale),
            liquid_load_on_mixture: case.liquid_load_on_mixture,
            fixed: &self.fixed,
            liquid_fixed: &self.liquid_fixed,
            gravity,
        };
        let mut energy = NodalEnergy::default();
        let grids = std::iter::once(&self.grid).chain(self.contact.as_ref().map(|c| &c.grid));
        for (k, grid) in grids.enumerate() {
            nodal_energy::nodal_energy::<E, R>(
                &self.team,
                &mut self.energy_values,
                &mut self.energy_blocks,
                grid,
                &loads,
            );
            self.layout
                .sum_owned(&self.team, &self.energy_values, &mut self.owned_partials);
            let body = NodalEnergy::of_sums(
                exact_total(
                    &*self.comm,
                    &self.owned_partials[..self.layout.owned_blocks()],
                ),
                dt,
            );
            energy = if k == 0 {
                body
            } else {
                NodalEnergy {
                    power_end: energy.power_end + body.power_end,
                    kinetic: energy.kinetic,
                    work: energy.work + body.work,
                    dissipated: energy.dissipated + body.dissipated,
                }
            };
        }
        let w = energy.power_end;
        self.nodal_kinetic = energy.kinetic;
        self.external_work += w * dt;
        self.steps += 1;
        self.time += dt;
        if let Some(t) = snap_to {
            self.time = t;
        }
        if self.guards.enabled {
            self.check_step(dt, w, &forces, &energy)?;
        }
        let t4 = Instant::now();
        self.phase_load[3] += self.team.take_load();
        if let Some(mm) = &mut self.moving_mesh {
            // After the stresses and the points' move (with the shape functions of the mesh
            // before it moves), before the points are located in the moved mesh: Anura3D's
            // order.
            // With contact the mesh follows the structure's nodes.
            let vel = self
                .contact
                .as_ref()
                .map_or(&self.grid.vel, |c| &c.grid.vel);
            if let Err(e) = mm.advance(&mut self.mesh, vel, dt) {
                return Err(crate::step::moving_mesh::Inverted {
                    element: self.input_element[e] + 1,
                    step: self.steps,
                    time: self.time,
                }
                .into());
            }
        }
        if fused_locate {
            self.settle_located()?;
        } else {
            self.locate()?;
        }
        if let Some(m) = &self.mixed {
            m.after_locate(&self.team, &self.layout, &mut self.particles);
        }
        if let Some(cs) = &mut self.critical_step {
            let (crossing, element) =
                cs.shortest_crossing(&self.team, &self.layout, &self.mesh, &self.particles);
            let shortest = self.comm.min(crossing);
            // With no point left in the mesh the last step stands.
            if shortest.is_finite() {
                self.dt = crate::step::time_step::step_of(self.courant.0, shortest);
                if crossing == shortest {
                    self.courant.1 = element as usize;
                }
            }
        }
        let t5 = Instant::now();
        self.phase_load[4] += self.team.take_load();
        for (k, (a, b)) in [(t0, t1), (t1, t2), (t2, t3), (t3, t4), (t4, t5)]
            .into_iter()
            .enumerate()
        {
            self.phase_seconds[k] += (b - a).as_secs_f64();
        }
        Ok(())
    }

    /// The guard rails after a step: sums the per-block slots in block order (so the result
    /// does not depend on the threads), updates the energy terms and checks them. `w`:
    /// the external power summed over the nodes this step; `forces`: the grid update's sums;
    /// `energy`: the step's nodal energy terms (this process's).
    fn check_step(
        &mut self,
        dt: f64,
        w: f64,
        forces: &grid_update::ForceSums,
        energy: &nodal_energy::NodalEnergy,
    ) -> Result<(), StepError> {
        // The owned blocks' sums of every rank, exact; the smallest margin.
        let mut margin = f64::INFINITY;
        for (p, s) in self
            .owned_partials
            .iter_mut()
            .zip(&self.guard_slots[..self.layout.owned_blocks()])
        {
            *p = [s.strain, s.kinetic, s.liquid, 0.0];
            margin = margin.min(s.volume_margin);
        }
        let [strain, kinetic, liquid, _] = exact_total(
            &*self.comm,
            &self.owned_partials[..self.layout.owned_blocks()],
        );
        let margin = self.comm.min(margin);
        // The slots hold twice each energy (see `GuardSums`).
        let (strain, kinetic, liquid) = (0.5 * strain, 0.5 * kinetic, 0.5 * liquid);
        let previous = self.step_kinetic;
        self.strain_energy += strain;
        self.liquid_energy = liquid;
        self.step_kinetic = kinetic;
        let (work, dissipated) = (energy.work, energy.dissipated);
        self.dissipated += dissipated;
        self.balance_work += work;
        let nodal = w * dt + work + dissipated + forces.unbalanced;
        let fail = |check| Err(StepError::Diverged(Box::new(self.diagnose(check))));
        // A non-finite stress, velocity, position, volume or pore pressure makes the energies'
        // sums NaN or infinite (the passes fold the last three in); nodal values the nodal
        // sums.
        if !(strain + kinetic + liquid).is_finite() || !nodal.is_finite() {
            return fail(Check::NonFinite);
        }
        if margin <= 0.0 {
            return fail(Check::Volume);
        }
        // Both energy checks compare energies: over the first steps they are near zero and
        // their ratios are start-up and round-off (Anura3D's first step lasts 1e-15 s).
        if self.energy_checked.0 && self.steps > BALANCE_FROM_STEP {
            let released = (-self.internal_energy()).max(0.0);
            // A body that starts in equilibrium under initial stresses or pore pressures has a
            // budget of round-off (no work, nothing released), which its round-off kinetic
            // energy can outgrow (f32, an undrained column): a thousandth of the energy those
            // hold is the floor; a real blow-up passes it within a few steps.
            let floor = BLOW_UP_FLOOR * (self.stored_energy + self.liquid_initial);
            let budget = self.initial_kinetic + self.balance_work.max(0.0) + released + floor;
            if kinetic > self.guards.blow_up_factor * budget && kinetic > previous {
                return fail(Check::BlowUp);
            }
        }
        if self.energy_checked.1 && self.steps > BALANCE_FROM_STEP {
            if let Some(tol) = self.guards.energy_tolerance {
                if self.balance_error() > tol {
                    return fail(Check::EnergyBalance);
                }
            }
        }
        Ok(())
    }

    /// |kinetic + internal + dissipated - work - initial kinetic| over the largest of those
    /// terms (0 while all are 0), with the kinetic energy of the last step.
    pub fn balance_error(&self) -> f64 {
        crate::driver::guard::balance_error(
            self.step_kinetic,
            self.internal_energy(),
            self.dissipated,
            self.balance_work,
            self.initial_kinetic,
            self.stored_energy + self.liquid_initial,
        )
    }

    /// Energy taken up by the material since the start (kJ): the skeleton's strain energy and
    /// the change of what the liquid's compression holds.
    pub fn internal_energy(&self) -> f64 {
        self.strain_energy + (self.liquid_energy - self.liquid_initial)
    }

    /// What tripped, where: the point, element or node and the value, and the likely cause.
    fn diagnose(&self, check: Check) -> Divergence {
        crate::driver::guard::diagnose(
            check,
            &crate::driver::guard::View {
                particles: &self.particles,
                grid: &self.grid,
                input_element: &self.input_element,
                input_node: &self.input_node,
                initial_density: &self.initial_density,
                courant: self.courant.0,
                critical_element: self.input_element[self.courant.1] + 1,
                step: self.steps,
                time: self.time,
                kinetic: self.step_kinetic,
                balance_error: self.balance_error(),
                tolerance: self.guards.energy_tolerance,
            },
        )
    }

    /// Anura3D's quasi-static convergence test: out-of-balance forces of the mixture and of the
    /// liquid and the nodes' kinetic energy (per unit of external work) within the tolerances.
    pub fn converged(&self, qs: &crate::input::case::QuasiStatic) -> bool {
        let (force_tolerance, energy_tolerance) = (qs.force_tolerance, qs.energy_tolerance);
        let kinetic = if self.external_work != 0.0 {
            (self.nodal_kinetic / self.external_work).abs()
        } else {
            0.0
        };
        self.force_error <= force_tolerance
            && self.liquid_force_error <= qs.liquid_force_tolerance
            && kinetic <= energy_tolerance
    }

    /// Finds every point's element (each thread walks its own points), stops at the first
    /// point (by index) that left the mesh unless such points are dropped, and keeps the points
    /// sorted by element.
    /// Whether the points are located in the stress pass as they move (docs/design.md §4.10):
    /// unless something between the two passes bears on their elements, the mesh moving, a
    /// second body, or lost points dropped (deactivated before the mixed rule's averages and
    /// the guards read them).
    pub fn locates_in_stress_pass(&self) -> bool {
        self.moving_mesh.is_none() && self.contact.is_none() && !self.drop_lost
    }

    /// The modelled bytes per particle-step of each step phase (`driver::traffic`), for the
    /// way this run locates its points and takes its pore-pressure rate's weights.
    pub fn modelled_bytes(&self) -> [f64; 5] {
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

    fn locate(&mut self) -> Result<(), Lost> {
        self.walk_points();
        self.settle_located()
    }

    /// Walks every active point from its element to the one holding it now, in chunks,
    /// recording per thread what [`locate`](Self::locate) needs ([`Outcome`]).
    fn walk_points(&mut self) {
        let mesh = &self.mesh;
        let layout = &self.layout;
        let p = &mut self.particles;
        let elements = Shared::new(&mut p.element);
        let actives = Shared::new(&mut p.active);
        let x = &p.x;
        // Per thread: the first point it found outside (index, element), how many, and whether
        // a point changed element, over the chunks it walked.
        for o in &mut self.locate_outcome {
            *o = NOTHING_FOUND;
        }
        let outcomes = Shared::new(&mut self.locate_outcome);
        let drop_lost = self.drop_lost;
        // In chunks handed out while the walk runs (a thread slowed by its core leaves the rest
        // of its chunks to the others): the lowest lost point, the count and the moved flag
        // are the same whichever thread walks a chunk.
        self.team.run_chunks(layout.thread_chunks(), |t, c| {
            let r = layout.chunk_particles(c);
            // SAFETY: the particle ranges of the chunks are disjoint, and each chunk runs once.
            let (el, active) = unsafe { (elements.range(r.clone()), actives.range(r.clone())) };
            let mut o = NOTHING_FOUND;
            let w = locate_width::<E, R>();
            let mut skip = 0;
            for (j, i) in r.clone().enumerate() {
                if skip > 0 {
                    skip -= 1;
                    continue;
                }
                // A batch of `w` active points of one element that are all still inside it
                // (most points, most steps) is checked at once; the rest walk one by one.
                if w > 1 && j + w <= el.len() {
                    let e = el[j];
                    if (0..w).all(|q| active[j + q] && el[j + q] == e) {
                        let inside = match w {
                            4 => run_inside::<E, R, 4>(mesh, e as usize, &x[i..i + 4]),
                            3 => run_inside::<E, R, 3>(mesh, e as usize, &x[i..i + 3]),
                            _ => run_inside::<E, R, 2>(mesh, e as usize, &x[i..i + 2]),
                        };
                        if inside {
                            skip = w - 1;
                            continue;
                        }
                    }
                }
                if !active[j] {
                    continue;
                }
                match relocate(mesh, &mut o, i, &mut el[j], &x[i]) {
                    Found::In(_) => {}
                    Found::Outside(_) if drop_lost => active[j] = false,
                    Found::Outside(_) | Found::Beyond(_) => break,
                }
            }
            // SAFETY: slot t is this thread's only (a thread runs its chunks one after another).
            let mine = unsafe { &mut outcomes.range(t..t + 1)[0] };
            merge(mine, o);
        });
    }

    /// After the walk (its own pass, or fused into the stress pass): stops the run on a point
    /// that left the mesh (unless lost points are dropped), exchanges the points that crossed
    /// to other ranks, and re-sorts the points by element where any moved.
    fn settle_located(&mut self) -> Result<(), Lost> {
        let mesh = &self.mesh;
        let p = &mut self.particles;
        let drop_lost = self.drop_lost;
        let outside = self.locate_outcome.iter().map(|o| o.1).sum::<u64>();
        let outside_anywhere = self.comm.sum_count(outside);
        if !drop_lost && outside_anywhere > 0 {
            // Every rank stops, naming the first rank's first lost point.
            let mine = self
                .locate_outcome
                .iter()
                .filter(|o| o.1 > 0)
                .min()
                .map(|&((i, e), _, _)| {
                    let g = mesh.global(&p.x[i]);
                    vec![
                        f64::from(p.id[i]),
                        g[0],
                        g[1],
                        g[2],
                        f64::from(self.input_element[e as usize] + 1),
                    ]
                })
                .unwrap_or_default();
            let mut all = Vec::new();
            self.comm.all_gather(&mine, &mut all);
            return Err(Lost {
                id: all[0] as u32,
                step: self.steps,
                time: self.time,
                x: all[1],
                y: all[2],
                z: all[3],
                element: all[4] as u32,
            });
        }
        self.lost += outside_anywhere;
        let mut moved = self.locate_outcome.iter().any(|o| o.2);
        if !self.partition.is_whole() {
            moved |= self.migrate();
        }
        // `moved` even when the order holds: a point moving into the next element stays in
        // order, but its element's point range must follow it (design.md §5.2).
        let permuted = self.layout.resort(
            &self.team,
            &mut self.particles,
            moved,
            &mut self.sort_scratch,
        );
        if permuted {
            // Point loads and prescribed points follow their points: old index → new index.
            if !self.point_loads.is_empty() || self.prescribed.is_some() {
                let sc = &mut self.sort_scratch;
                sc.inverse.resize(sc.order.len(), 0);
                for (new, &old) in sc.order.iter().enumerate() {
                    sc.inverse[old as usize] = new as u32;
                }
                for load in &mut self.point_loads {
                    load.0 = sc.inverse[load.0 as usize];
                }
                if let Some(pr) = &mut self.prescribed {
                    pr.follow(&sc.inverse);
                }
            }
        }
        Ok(())
    }

    /// Sends the points that moved into halo elements to the ranks owning those elements and
    /// takes in the points coming here, in the global point order (see [`exchange_points`]).
    /// Returns whether any point came or went. Collective.
    fn migrate(&mut self) -> bool {
        let owned = self.partition.owned() as u32;
        let p = &mut self.particles;
        let leaving = p.element.iter().filter(|&&e| e >= owned).count() as u64;
        if self.comm.sum_count(leaving) == 0 {
            return false;
        }
        let partition = &self.partition;
        exchange_points(
            self.comm.as_ref(),
            p,
            |e| {
                (e >= owned).then(|| {
                    let g = partition.global_element(e as usize);
                    (partition.rank_of(g), g as u32)
                })
            },
            |g| {
                partition
                    .local_element(g as usize)
                    .expect("a point sent to the rank owning its element") as u32
            },
        );
        self.balance.stale = true;
        self.balance.migrations_since_decline += 1;
        true
    }

    /// Between steps of a run over several ranks: measures how evenly the ranks share the
    /// points (after points migrated) and, when the largest rank holds more than `threshold`
    /// times the mean, cuts the curve again, balanced by the points each element holds now,
    /// and moves the points and the rank's share to it. Nothing in the results changes (the
    /// sums are formed per block of elements, in global order, for any cut). Returns whether
    /// it re-partitioned. Collective.
    pub fn rebalance(&mut self, case: &Case, threshold: f64) -> Result<bool, SetupError> {
        if self.partition.is_whole() || !self.balance.stale {
            return Ok(false);
        }
        self.balance.stale = false;
        let mut counts = Vec::new();
        self.comm
            .all_gather(&[self.particles.len() as f64], &mut counts);
        let imbalance = imbalance_of(&counts);
        self.balance.imbalance = imbalance;
        self.balance.worst = self.balance.worst.max(imbalance);
        // After a declined look, look again once the imbalance has grown or the points have
        // migrated for a while (they may have spread so that a cut can do better now).
        let relook = imbalance > self.balance.declined_at
            || self.balance.migrations_since_decline >= RELOOK_AFTER_MIGRATIONS;
        if !(threshold > 0.0 && imbalance > threshold && relook) {
            return Ok(false);
        }
        let t0 = Instant::now();
        // Every element's points, in global element order (the ranks' ranges follow each other).
        let mut mine = vec![0.0; self.partition.owned()];
        for &e in &self.particles.element {
            mine[e as usize] += 1.0;
        }
        let mut weights = Vec::new();
        self.comm.all_gather(&mine, &mut weights);
        let weight: Vec<u64> = weights.iter().map(|&w| w as u64).collect();
        let (me, ranks) = (self.comm.rank(), self.comm.ranks());
        // The cut `Partition::along_curve` will make, judged before the mesh is built for it:
        // taken when it at least halves the excess over an even share (a smaller gain does not
        // pay for the move).
        let ranges = crate::parallel::team::aligned_to_blocks(
            crate::parallel::team::balanced_ranges(weight.iter().copied(), ranks),
            weight.len(),
        );
        let predicted = imbalance_of(
            &ranges
                .iter()
                .map(|r| weight[r.clone()].iter().sum::<u64>() as f64)
                .collect::<Vec<_>>(),
        );
        if ranges.len() != ranks
            || ranges.iter().any(|r| r.is_empty())
            || predicted - 1.0 > 0.5 * (imbalance - 1.0)
        {
            self.balance.declined_at = imbalance;
            self.balance.migrations_since_decline = 0;
            self.balance.seconds += t0.elapsed().as_secs_f64();
            return Ok(false);
        }
        let global = case.mesh::<E, R>()?;
        let mut parts = Partition::along_curve(&global, &weight, ranks);
        debug_assert!(parts.iter().zip(&ranges).all(|(p, r)| p.elements() == *r));
        let new = parts.swap_remove(me);
        let old = std::mem::replace(&mut self.partition, new);
        let partition = &self.partition;
        let p = &mut self.particles;
        let mut sent = 0;
        let kept = exchange_points(
            self.comm.as_ref(),
            p,
            |e| {
                let g = old.global_element(e as usize);
                let to = partition.rank_of(g);
                (to != me).then(|| {
                    sent += 1;
                    (to, g as u32)
                })
            },
            |g| {
                partition
                    .local_element(g as usize)
                    .expect("a point sent to the rank owning its element") as u32
            },
        );
        for e in &mut p.element[kept] {
            let g = old.global_element(*e as usize);
            *e = partition.local_element(g).expect("a point kept here") as u32;
        }
        self.balance.points_moved += sent;
        self.balance.bytes_before += self.layout.halo().map_or(0, |h| h.bytes_sent());
        self.share(case, global);
        self.balance.repartitions += 1;
        self.balance.declined_at = 0.0;
        self.balance.migrations_since_decline = 0;
        self.balance.stale = true;
        self.balance.seconds += t0.elapsed().as_secs_f64();
        log::info!(
            "step {}: points per rank {:.3}× the mean; re-partitioned along the curve (rank {me} now owns global elements {:?}, {} points)",
            self.steps,
            imbalance,
            self.partition.elements(),
            self.particles.len(),
        );
        Ok(true)
    }

    /// Sets up this rank's share of `global` for the (new) partition, with the points already
    /// there: the local mesh, its nodes' inputs, the layout and halo, and every buffer sized by
    /// elements, nodes or blocks.
    fn share(&mut self, case: &Case, global: Mesh<E, R>) {
        self.mesh = self.partition.local_mesh(global);
        let mesh = &self.mesh;
        let inputs = NodeInputs::of(case, mesh, &self.partition);
        self.fixed = inputs.fixed;
        self.liquid_fixed = inputs.liquid_fixed;
        self.walls = inputs.walls;
        self.traction = inputs.traction;
        self.liquid_traction = inputs.liquid_traction;
        self.input_element = inputs.input_element;
        self.input_node = inputs.input_node;
        self.courant.1 = critical_element(case, &self.partition, mesh);
        let two_phase = self.grid.liquid.is_some();
        self.grid = Grid::new(mesh.nodes());
        if two_phase {
            self.grid.liquid = Some(LiquidNodes::new(mesh.nodes()));
        }
        self.layout = layout_of(
            &self.partition,
            mesh,
            &self.particles,
            self.team.threads,
            &self.comm,
        );
        if self.first_touch {
            let p = std::mem::take(&mut self.particles);
            self.particles = first_touch(&self.team, &self.layout, p);
        }
        self.slots = self.layout.new_slots();
        if !self.guard_slots.is_empty() {
            self.guard_slots = vec![GuardSums::EMPTY; self.layout.blocks()];
        }
        self.grid_scratch = grid_update::GridScratch::new(mesh.nodes());
        self.energy_blocks = vec![(); mesh.nodes().div_ceil(nodal_energy::NODE_BLOCK)];
        self.energy_values = vec![[0.0; 4]; mesh.nodes()];
        self.owned_partials = vec![[0.0; 4]; self.layout.owned_blocks()];
    }

    /// The liquid's kinetic energy Σ n ρw V_w |w|² / 2 and the energy its compression holds,
    /// Σ n V p² / 2 K_w, over the active saturated points (kJ; as the guard rails' sums).
    fn liquid_energies(&self) -> (f64, f64) {
        let p = &self.particles;
        let Some(l) = &p.liquid else {
            return (0.0, 0.0);
        };
        let sum = |part: &(dyn Fn(usize, &Fluid<R>) -> f64 + Sync)| {
            self.comm.sum(self.team.sum_blocks(p.len(), |r| {
                r.filter(|&i| p.active[i])
                    .filter_map(|i| self.fluids[p.material[i] as usize].map(|f| part(i, &f)))
                    .sum()
            }))
        };
        let kinetic = sum(&|i, f| {
            let vw = l.volume0.as_ref().map_or(p.volume[i], |v0| v0[i]);
            let ww: R = l.w[i].iter().map(|&w| w * w).fold(R::ZERO, |a, b| a + b);
            0.5 * (f.n * f.rho_w * vw * ww).f64()
        });
        let stored = sum(&|i, f| 0.5 * (p.volume[i] * l.p[i] * l.p[i] / f.kw_over_n).f64());
        (kinetic, stored)
    }

    /// Kinetic energy of the active points, with their liquid's in two-phase cases (kJ).
    pub fn total_kinetic_energy(&self) -> f64 {
        self.kinetic_energy() + self.liquid_energies().0
    }

    /// Kinetic energy of the active points (kJ; the solid's), summed in fixed blocks of points.
    pub fn kinetic_energy(&self) -> f64 {
        let p = &self.particles;
        self.comm.sum(self.team.sum_blocks(p.len(), |r| {
            r.filter(|&i| p.active[i])
                .map(|i| {
                    0.5 * p.mass[i].f64() * p.v[i].iter().map(|v| v.f64() * v.f64()).sum::<f64>()
                })
                .sum()
        }))
    }
}

/// Σ V σ:σ / 2M over the points (shear components twice, M the constrained modulus of the
/// point's material): the elastic energy their stresses hold, as a scale (kJ).
fn stored_energy<R: Real>(case: &Case, particles: &Particles<R>) -> f64 {
    let mut sum = 0.0;
    for i in 0..particles.len() {
        let Some(m) = case.materials[particles.material[i] as usize].as_ref() else {
            continue;
        };
        let s = particles.stress[i].map(|v| v.f64());
        let ss = s[0] * s[0]
            + s[1] * s[1]
            + s[2] * s[2]
            + 2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
        sum += particles.volume[i].f64() * ss / (2.0 * m.oedometric());
    }
    sum
}

/// Sets the initial stresses (and, for saturated points of a K0 material, pore pressures) of
/// the points just placed. The K0 procedure reads the element's corners from the case's model
/// (global coordinates, as the input gives them), not from the computational mesh.
fn apply_initial_stress<E: Element, R: Real>(
    init: &crate::input::initial_stress::InitialStress,
    case: &Case,
    partition: &Partition,
    particles: &mut Particles<R>,
) {
    for i in 0..particles.len() {
        let e = partition.global_element(particles.element[i] as usize);
        let nodes = &case.model.element(e)[..E::NODES];
        let corners: E::Nodes<[f64; 3]> = E::nodes(|k| {
            let p = case.model.node(nodes[k] as usize);
            [0, 1, 2].map(|d| p.get(d).copied().unwrap_or(0.0))
        });
        let Some(s) = init.at(particles.material[i] as usize, corners.as_ref()) else {
            continue;
        };
        particles.stress[i] = s.stress.map(R::of);
        if let (Some(p), Some(lp)) = (s.pore_pressure, particles.liquid.as_mut()) {
            lp.p[i] = R::of(p);
        }
    }
}

/// Finds the points that carry each face load: in every element with points that has the face,
/// the points nearest its three corners (the one point of a 1-point element). The face's force
/// is shared equally among all of them (Anura3D gives each adjacent element the full share, which
/// doubles loads on faces between two filled elements; such faces are rare and we keep the total).
fn resolve_point_loads<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    p: &Particles<R>,
    case: &Case,
    comm: &dyn Communicator,
) -> Result<Vec<(u32, V3<R>)>, SetupError> {
    if case.point_loads.is_empty() {
        return Ok(Vec::new());
    }
    // Points are placed in element order: the first point of each element.
    let mut first = vec![0u32; mesh.elements() + 1];
    for &e in &p.element {
        first[e as usize + 1] += 1;
    }
    for e in 0..mesh.elements() {
        first[e + 1] += first[e];
    }
    let mut out = Vec::new();
    for load in &case.point_loads {
        let c: Vec<u32> = load
            .corners
            .iter()
            .map(|&m| mesh.node_of_model[m])
            .collect();
        let mut carriers = Vec::new();
        for e in 0..mesh.elements() {
            let corners = mesh.corners[e].as_ref();
            let Some(face) = (0..E::FACES).find(|&k| {
                let f = E::face(k);
                f.len() == c.len() && c.iter().all(|n| f.iter().any(|&j| corners[j] == *n))
            }) else {
                continue;
            };
            let (a, b) = (first[e] as usize, first[e + 1] as usize);
            carriers.extend(E::face_load_points(b - a, face).into_iter().map(|k| a + k));
        }
        // Another process may carry the load: only no carrier anywhere is an error.
        if comm.sum_count(carriers.len() as u64) == 0 {
            return Err(SetupError::UnloadedFace {
                nodes: load.corners.iter().map(|&m| case.node_number(m)).collect(),
            });
        }
        let share = load.force.map(|f| R::of(f / carriers.len() as f64));
        out.extend(carriers.into_iter().map(|i| (i as u32, share)));
    }
    Ok(out)
}

/// The largest of `counts` over their mean (1 for an even share, 0 for none at all).
fn imbalance_of(counts: &[f64]) -> f64 {
    let total: f64 = counts.iter().sum();
    if total == 0.0 {
        return 0.0;
    }
    counts.iter().copied().fold(0.0, f64::max) * counts.len() as f64 / total
}

/// Sends every point `to` names, as (rank, global element), to that rank with its element
/// numbered globally, keeps the rest in order, and takes in the points sent here, their
/// elements numbered by `local`. The points end in the global order one process keeps: those
/// from lower ranks (earlier along the curve), the kept ones, those from higher ranks, so that
/// a stable sort by element orders them as one process would. Returns the kept points' new
/// index range. Collective.
fn exchange_points<R: Real>(
    comm: &dyn Communicator,
    p: &mut Particles<R>,
    mut to: impl FnMut(u32) -> Option<(usize, u32)>,
    local: impl Fn(u32) -> u32,
) -> Range<usize> {
    let (me, ranks) = (comm.rank(), comm.ranks());
    let mut sends = vec![Vec::new(); ranks];
    let mut keep = vec![true; p.len()];
    let mut leaving = false;
    for i in 0..p.len() {
        let Some((rank, g)) = to(p.element[i]) else {
            continue;
        };
        let e = std::mem::replace(&mut p.element[i], g);
        p.put_point(i, &mut sends[rank]);
        p.element[i] = e;
        keep[i] = false;
        leaving = true;
    }
    if leaving {
        p.retain(&keep);
    }
    let got = comm.all_to_all_bytes(&sends);
    let kept = p.len();
    let mut before = 0;
    for (q, bytes) in got.iter().enumerate() {
        if q == me || bytes.is_empty() {
            continue;
        }
        let n = p.push_encoded(bytes);
        if q < me {
            before += n;
        }
    }
    // [kept, lower ranks', higher ranks'] → [lower ranks', kept, higher ranks'].
    p.rotate_front(kept + before, before);
    for i in (0..before).chain(kept + before..p.len()) {
        p.element[i] = local(p.element[i]);
    }
    before..before + kept
}

/// What a rank's nodes and elements take from the case: fixities and face loads per local
/// node, and the input numbers of its elements and nodes (for messages). Read at set-up and
/// again whenever the ranks are re-partitioned.
struct NodeInputs<R: Real> {
    fixed: Vec<[bool; 3]>,
    liquid_fixed: Vec<[bool; 3]>,
    walls: Vec<crate::step::wall_friction::WallNode<R>>,
    traction: Vec<V3<R>>,
    liquid_traction: Vec<V3<R>>,
    input_element: Vec<u32>,
    input_node: Vec<u32>,
}

impl<R: Real> NodeInputs<R> {
    fn of<E: Element>(case: &Case, mesh: &Mesh<E, R>, partition: &Partition) -> Self {
        let by_node = |f: &dyn Fn(usize) -> [bool; 3]| -> Vec<[bool; 3]> {
            mesh.model_node.iter().map(|&m| f(m as usize)).collect()
        };
        let loads = |f: &[[f64; 3]]| -> Vec<V3<R>> {
            mesh.model_node
                .iter()
                .map(|&m| f[m as usize].map(R::of))
                .collect()
        };
        NodeInputs {
            fixed: by_node(&|m| case.fixed[m]),
            liquid_fixed: by_node(&|m| case.liquid_fixed[m]),
            walls: crate::step::wall_friction::wall_nodes(&case.walls, &mesh.model_node),
            traction: loads(&case.traction),
            liquid_traction: loads(&case.liquid_traction),
            input_element: (0..mesh.elements())
                .map(|e| case.element_number(partition.global_element(e)) - 1)
                .collect(),
            input_node: mesh
                .model_node
                .iter()
                .map(|&m| case.node_number(m as usize))
                .collect(),
        }
    }
}

/// The local element of `partition` whose crossing time is the shortest among its owned ones
/// (named by the time-step messages).
fn critical_element<E: Element, R: Real>(
    case: &Case,
    partition: &Partition,
    mesh: &Mesh<E, R>,
) -> usize {
    let own = partition.elements();
    let (e, _) = crate::input::time_step::shortest_crossing(case, own.clone(), |e| {
        mesh.min_altitude[e - own.start].f64()
    });
    e - own.start
}

/// The threads' ranges and the nodes' sums for `partition`: on one rank of several, each node
/// adds its elements' slots in global element order after the halo exchange.
fn layout_of<E: Element, R: Real>(
    partition: &Partition,
    mesh: &Mesh<E, R>,
    particles: &Particles<R>,
    threads: usize,
    comm: &Arc<dyn Communicator>,
) -> Layout<R, E> {
    if partition.is_whole() {
        return Layout::new(mesh, particles, threads);
    }
    let halo = Arc::new(crate::parallel::halo::Halo::new(
        comm.clone(),
        partition.neighbours(),
    ));
    Layout::ordered(
        mesh,
        particles,
        threads,
        Some(&partition.elements_in_global_order()),
        partition.owned(),
        Some(halo),
    )
}

/// The particle arrays copied range by range on the threads that own the ranges, so that each
/// range's pages are first touched (and placed) by its thread.
fn first_touch<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    mut p: Particles<R>,
) -> Particles<R> {
    struct Copy<'a, R: Real, E: Element> {
        team: &'a Team,
        layout: &'a Layout<R, E>,
    }
    impl<R: Real, E: Element> FieldVisitor for Copy<'_, R, E> {
        fn field<T: Value>(&mut self, field: Field, v: &mut Vec<T>) {
            let k = field.per_point;
            let mut out: Vec<T> = Vec::with_capacity(v.len());
            let spare = out.spare_capacity_mut();
            let dst = Shared::new(spare);
            let src = &v[..];
            let layout = self.layout;
            self.team.run(|t| {
                let r = layout.particle_range(t);
                let r = k * r.start..k * r.end;
                // SAFETY: the particle ranges are disjoint and cover 0..len, so their k-value
                // chunks are disjoint and cover 0..k len.
                let d = unsafe { dst.range(r.clone()) };
                for (slot, &x) in d.iter_mut().zip(&src[r]) {
                    slot.write(x);
                }
            });
            debug_assert_eq!(
                v.len(),
                k * layout.particle_range(self.team.threads - 1).end
            );
            // SAFETY: every element was written above (the ranges cover all particles).
            unsafe { out.set_len(v.len()) };
            *v = out;
        }
    }
    p.visit_fields(&mut Copy { team, layout });
    p
}

#[cfg(test)]
mod tests {
    use super::imbalance_of;

    #[test]
    fn imbalance_is_the_largest_share_over_the_mean() {
        assert_eq!(imbalance_of(&[10.0, 10.0, 10.0]), 1.0);
        assert_eq!(imbalance_of(&[30.0, 10.0, 20.0]), 1.5);
        // A rank with every point of four.
        assert_eq!(imbalance_of(&[0.0, 8.0, 0.0, 0.0]), 4.0);
        assert_eq!(imbalance_of(&[0.0, 0.0]), 0.0);
    }

    /// The particle state of `scene` (in testdata) after `steps` steps, as bits, with the point
    /// passes on their portable copies or as the processor allows.
    fn state_bits<R: crate::real::Real, E: crate::element::Element>(
        scene: &str,
        steps: usize,
        portable: bool,
    ) -> Vec<u64> {
        state_bits_with::<R, E>(scene, steps, portable, true).concat()
    }

    /// [`state_bits`] field by field (the elements last), with the pore-pressure rate's
    /// weights from particle to grid (`weights`) or the rate's pass point by point.
    fn state_bits_with<R: crate::real::Real, E: crate::element::Element>(
        scene: &str,
        steps: usize,
        portable: bool,
        weights: bool,
    ) -> Vec<Vec<u64>> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata");
        // A suffix of the scene's name, taken off: whether it was there.
        let flag = |scene: &mut &str, suffix: &str| match scene.strip_suffix(suffix) {
            Some(s) => {
                *scene = s;
                true
            }
            None => false,
        };
        let mut scene = scene;
        // `NAME+objective`: the scene with Anura3D's objective stress terms on, started
        // shearing; `+ten`: with ten points per element (a tetrahedron's batches of four,
        // four and two).
        let objective = flag(&mut scene, "+objective");
        let ten = flag(&mut scene, "+ten");
        // `+shear`: started moving down fast enough (a half sine over the height: a column's
        // walls hold v_x) that the middle points cross some two elements in the steps, so
        // that the passes' locate paths walk.
        let shear = flag(&mut scene, "+shear");
        // `+dry`: the scene's materials without their liquid.
        let dry = flag(&mut scene, "+dry");
        let mut case = crate::input::scene::load(&dir.join(scene)).unwrap();
        case.objective_stress |= objective;
        if ten {
            case.points_per_element.iter_mut().for_each(|n| *n = 10);
        }
        if dry {
            case.materials
                .iter_mut()
                .flatten()
                .for_each(|m| m.liquid = None);
        }
        crate::parallel::avx2::with_portable(portable, || {
            let mut engine = super::Engine::<R, E>::new(&case, false).unwrap();
            if !weights {
                engine.pore_weights = None;
            }
            if objective {
                // A shearing start (v_x growing with y), so that the spin, and with it the
                // co-rotation, is not zero.
                let p = &mut engine.particles;
                for (v, x) in p.v.iter_mut().zip(&p.x) {
                    v[0] += x[1] * R::of(0.05);
                }
            }
            if shear {
                // The element size from the mesh's extent and element count (a square
                // element's side; a triangle's area is half its square's).
                let (lo, hi) = engine.mesh.x.iter().fold(
                    ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                    |(lo, hi), x| {
                        let (a, b) = (x[0].f64(), x[1].f64());
                        ([lo[0].min(a), lo[1].min(b)], [hi[0].max(a), hi[1].max(b)])
                    },
                );
                let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
                let h = (2.0 * area / engine.mesh.elements() as f64).sqrt();
                // Fastest at mid-height, still at the top and the bottom (a faster top
                // surface left the mesh).
                let fastest = 2.0 * h / (steps as f64 * engine.dt);
                let p = &mut engine.particles;
                for (v, x) in p.v.iter_mut().zip(&p.x) {
                    let y = (x[1].f64() - lo[1]) / (hi[1] - lo[1]);
                    v[1] -= R::of(fastest * (std::f64::consts::PI * y).sin());
                }
            }
            let start = engine.particles.element.clone();
            for _ in 0..steps {
                engine.step(engine.dt, None).unwrap();
            }
            let p = &engine.particles;
            assert!(
                !shear || p.element != start,
                "{scene}: no point left its element"
            );
            let mut bits: Vec<Vec<u64>> = Vec::new();
            let mut add = |v: &[R]| bits.push(v.iter().map(|x| x.f64().to_bits()).collect());
            add(p.x.as_flattened());
            add(p.v.as_flattened());
            add(p.stress.as_flattened());
            add(&p.volume);
            add(&p.state);
            if let Some(l) = &p.liquid {
                add(&l.p);
                add(l.w.as_flattened());
            }
            bits.push(p.element.iter().map(|&e| e as u64).collect());
            bits
        })
    }

    /// The smoothed pore-pressure rate formed from particle to grid's weights (an element's
    /// saturated points of one material summed once, `state::pore_weights`) gives the state of
    /// the rate taken point by point: the same bits with one point per element, round-off with
    /// three, four and ten (the products summed in another order), in both precisions and in the
    /// portable copies as in the AVX2 ones.
    #[test]
    fn the_pore_rate_s_weights_give_the_point_by_point_rate() {
        use crate::element::{tet4::Tet4, tri3::Tri3};
        type Fields = Vec<Vec<u64>>;
        fn compare(scene: &str, with: &Fields, without: &Fields, exact: bool, tolerance: f64) {
            assert_eq!(with.len(), without.len(), "{scene}");
            if exact {
                assert!(with == without, "{scene}: not the same bits");
                return;
            }
            assert!(with != without, "{scene}: the weights were not taken");
            let (elements, values) = with.split_last().unwrap();
            assert_eq!(elements, without.last().unwrap(), "{scene}: elements");
            // Each field's values (as f64 bits) against its largest.
            for (field, (w, wo)) in values.iter().zip(without).enumerate() {
                let largest = wo
                    .iter()
                    .map(|&b| f64::from_bits(b).abs())
                    .fold(0.0f64, f64::max);
                for (i, (&a, &b)) in w.iter().zip(wo).enumerate() {
                    let (x, y) = (f64::from_bits(a), f64::from_bits(b));
                    assert!(
                        a == b || (x - y).abs() <= tolerance * largest,
                        "{scene}: field {field} value {i}: {x} against {y}"
                    );
                }
            }
        }
        for portable in [false, true] {
            for (scene, steps, exact) in [
                ("golden/column_saturated.toml", 60, true),
                ("oedometer.toml", 40, false),
                ("oedometer.toml+ten", 30, false),
            ] {
                let with = state_bits_with::<f64, Tet4>(scene, steps, portable, true);
                let without = state_bits_with::<f64, Tet4>(scene, steps, portable, false);
                compare(scene, &with, &without, exact, 1e-12);
                let with = state_bits_with::<f32, Tet4>(scene, steps, portable, true);
                let without = state_bits_with::<f32, Tet4>(scene, steps, portable, false);
                compare(scene, &with, &without, exact, 1e-4);
            }
            let scene = "oedometer_2d.toml";
            let with = state_bits_with::<f64, Tri3>(scene, 60, portable, true);
            let without = state_bits_with::<f64, Tri3>(scene, 60, portable, false);
            compare(scene, &with, &without, false, 1e-12);
        }
    }

    /// A checkpoint whose points name a material the case does not have (an edited file,
    /// re-signed so that its checksum holds) is refused as corrupt, not indexed with.
    #[test]
    fn a_checkpoint_with_a_material_past_the_case_s_is_refused() {
        use crate::driver::checkpoint::{
            self, CheckpointError, Driver, Fingerprint, Series, State,
        };
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata");
        let case = crate::input::scene::load(&dir.join("golden/column_dry.toml")).unwrap();
        let mut engine =
            super::Engine::<f64, crate::element::tet4::Tet4>::new(&case, false).unwrap();
        let out = tempfile::tempdir().unwrap();
        let scalars = engine.checkpoint_scalars();
        let series = Series {
            pvd: vec![],
            history: String::new(),
            energy: String::new(),
            reaction: String::new(),
        };
        let save = |p: &crate::state::particles::Particles<f64>| {
            let state = State {
                fingerprint: &Fingerprint(vec![]),
                driver: Driver::default(),
                scalars: &scalars,
                particles: p,
                series: &series,
                observer: b"",
            };
            checkpoint::write(out.path(), &state).unwrap();
            checkpoint::read(out.path()).unwrap().unwrap()
        };
        // As saved, it restores.
        let saved = save(&engine.particles);
        engine.restore(&saved).unwrap();
        let mut edited = engine.particles.clone();
        let last = edited.material.len() - 1;
        edited.material[last] = engine.laws.len() as u32;
        let saved = save(&edited);
        match engine.restore(&saved) {
            Err(CheckpointError::Corrupt { what, .. }) => {
                assert!(what.contains("of material"), "{what}")
            }
            other => panic!("restored: {:?}", other.err()),
        }
    }

    /// The AVX2 copies of particle to grid, grid to particle and the stress pass give the bits
    /// of the portable ones: dry, two-phase, Mohr-Coulomb, mixed integration and plane strain,
    /// one, three, four and ten points per element, with and without the objective terms, in both
    /// precisions,
    /// stepped until stresses, velocities and (in the Mohr-Coulomb column) returns are well
    /// under way.
    #[test]
    fn the_avx2_passes_give_the_portable_bits() {
        use crate::element::{tet4::Tet4, tri3::Tri3};
        if !crate::parallel::avx2::detected() {
            eprintln!("skipped: this processor has no AVX2, or the build assumes it");
            return;
        }
        for (scene, steps) in [
            ("golden/column_dry.toml", 60),
            ("golden/column_saturated.toml", 60),
            ("mc_column.toml", 60),
            // MPM-MIXED: full elements' Gauss-point tractions before their points' sums.
            ("oracle_mc_footing.toml", 20),
            // Four points per element: the stress pass's linear-elastic lanes take whole
            // batches (the columns above hold one point per element), dry and saturated, with
            // the objective terms.
            ("column_gravity.toml+objective", 40),
            ("oedometer.toml+objective", 40),
            // Ten points per element: the last two of each element in the lanes too.
            ("column_gravity.toml+ten+objective", 30),
            ("oedometer.toml+ten", 30),
        ] {
            let portable = state_bits::<f64, Tet4>(scene, steps, true);
            assert!(portable.iter().any(|&b| b != 0), "{scene}: no state");
            assert!(
                portable == state_bits::<f64, Tet4>(scene, steps, false),
                "{scene} f64"
            );
            let portable = state_bits::<f32, Tet4>(scene, steps, true);
            assert!(
                portable == state_bits::<f32, Tet4>(scene, steps, false),
                "{scene} f32"
            );
        }
        // Plane strain, three points per element: the stress pass's lanes take each
        // element's three in four lanes; dry and saturated, and with `+shear` points leave
        // their elements and are walked.
        for scene in [
            "oedometer_2d.toml",
            "oedometer_2d.toml+objective",
            "oedometer_2d.toml+shear",
            "oedometer_2d.toml+dry+shear",
        ] {
            let portable = state_bits::<f64, Tri3>(scene, 60, true);
            assert!(
                portable == state_bits::<f64, Tri3>(scene, 60, false),
                "{scene} f64"
            );
            let portable = state_bits::<f32, Tri3>(scene, 60, true);
            assert!(
                portable == state_bits::<f32, Tri3>(scene, 60, false),
                "{scene} f32"
            );
        }
    }
}
