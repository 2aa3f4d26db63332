//! Building an engine from a case: the mesh and its partition, the material points and their
//! initial state, the nodes' inputs, the constraints, the threads' layout and every buffer a step
//! uses, so that the step allocates nothing.

use std::sync::Arc;

use crate::basis::background::Background;
use crate::basis::ddmp::Ddmp;
use crate::basis::grid::Cartesian;
use crate::element::locate::NOTHING_FOUND;
use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::input::case::{Case, CriticalStepRule, Integration, MaterialSpec, MixedRule};
use crate::input::case::{Drag, Gradient};
use crate::material::law::Law;
use crate::material::liquid::Fluid;
use crate::parallel::comm::{Communicator, SingleProcess};
use crate::parallel::gather::Layout;
use crate::parallel::partition::Partition;
use crate::parallel::reach::Reach;
use crate::parallel::sort::SortScratch;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::{Grid, LiquidNodes};
use crate::state::particles;
use crate::state::particles::{Field, FieldVisitor, Particles, Value};
use crate::state::pore_weights::PoreWeights;
use crate::step::absorbing::{Absorbing, AbsorbingRule};
use crate::step::absorbing_anura3d::AbsorbingAnura3d;
use crate::step::bulk_viscosity::BulkDamping;
use crate::step::constraint::Constraints;
use crate::step::contact::{Contact, Structure};
use crate::step::mixed::Mixed;
use crate::step::moving_mesh::MovingMesh;
use crate::step::nodal_velocity::NodalVelocity;
use crate::step::prescribed::Prescribed;
use crate::step::semi_implicit::SemiImplicit;
use crate::step::smoothing::StrainSmoothing;
use crate::step::stress::GuardSums;
use crate::step::time_step::CriticalStep;
use crate::step::wall_friction::Walls;
use crate::step::{grid_update, nodal_energy};

use super::{Balance, Engine, Options, SetupError, StepConfig};

impl<R: Real, E: Element> Engine<R, E> {
    /// Sets up the mesh, places the material points and computes the time step, with the
    /// case's engine options.
    pub fn new(case: &Case, drop_lost: bool) -> Result<Self, SetupError> {
        Self::with_options(case, drop_lost, case.run.engine)
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
        refuse_unmodelled::<E>(case, comm.ranks())?;
        let team = Team::new(options.threads, options.pin)?;
        let global = case.mesh::<E, R>()?;
        // Element-indexed input is read through the partition: `own` is the global range.
        let partition = partition_of(case, &global, &*comm)?;
        let own = partition.elements();
        let mesh = partition.local_mesh(global);
        let basis = basis_of(case, &mesh)?;
        let (mut particles, boundary) = points_of(case, &partition, &mesh, &basis, &*comm)?;
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
        let (constraints, structure) =
            constraints_of(case, &partition, &mesh, &particles, walls, &mut fixed)?;
        let dt = comm.min(crate::input::time_step::critical(case, own.clone(), |e| {
            mesh.min_altitude[e - own.start].f64()
        })?);
        let critical_element = critical_element(case, &partition, &mesh);
        let point_loads = resolve_point_loads(&mesh, &particles, case, comm.as_ref())?;
        let layout = layout_of(&partition, &mesh, &particles, team.threads, &comm);
        if options.first_touch {
            particles = first_touch(&team, &layout, particles);
        }
        let tables = MaterialTables::of(case);
        let energy_checked = energy_counted(case, &reactions);
        let two_phase = case.has_liquid();
        let mut engine = Engine {
            input_node,
            guards: case.run.guards,
            guard_slots: vec![
                GuardSums::EMPTY;
                if case.run.guards.enabled {
                    layout.blocks()
                } else {
                    0
                }
            ],
            grid_scratch: grid_update::GridScratch::new(mesh.nodes()),
            energy_blocks: vec![(); mesh.nodes().div_ceil(nodal_energy::NODE_BLOCK)],
            energy_values: vec![[0.0; 4]; mesh.nodes()],
            owned_partials: vec![[0.0; 4]; layout.owned_blocks()],
            initial_density: tables.initial_density,
            strain_energy: 0.0,
            dissipated: 0.0,
            liquid_energy: 0.0,
            liquid_initial: 0.0,
            balance_work: 0.0,
            step_kinetic: 0.0,
            initial_kinetic: 0.0,
            stored_energy: 0.0,
            courant: (case.time.courant, critical_element),
            energy_checked: (energy_checked, energy_checked),
            comm,
            config: StepConfig::of(case),
            input_element,
            smoothing: case.numerics.strain_smoothing.then(|| {
                StrainSmoothing::new(mesh.nodes(), &case.body.element_material[own.clone()])
            }),
            bulk: bulk_of(case),
            semi_implicit: SemiImplicit::of(case, &mesh),
            gravity_by_material: vec![[R::ZERO; 3]; tables.weight_ratio.len()],
            weight_ratio: tables.weight_ratio,
            grid: grid_of(mesh.nodes(), two_phase),
            mixed: mixed_of(case, mesh.elements(), boundary),
            pore_weights: pore_weights_of::<E, R>(case, mesh.elements()),
            partition,
            reach: (basis.as_ref()).map(|b| Reach::new(b, &mesh, &layout, team.threads)),
            basis,
            mesh,
            particles,
            fixed,
            traction,
            liquid_traction,
            laws: tables.laws,
            dt,
            time: 0.0,
            steps: 0,
            external_work: 0.0,
            phase_seconds: [0.0; 6],
            phase_load: Default::default(),
            lost: 0,
            drop_lost,
            point_loads,
            force_error: 0.0,
            liquid_force_error: 0.0,
            nodal_kinetic: 0.0,
            fluids: tables.fluids,
            liquid_fixed,
            constraints,
            structure,
            critical_step: (case.time.critical_step == CriticalStepRule::OccupiedEachStep)
                .then(|| CriticalStep::new(case, team.threads)),
            reactions,
            locate_outcome: vec![NOTHING_FOUND; team.threads],
            team,
            slots: layout.new_slots(),
            layout,
            sort_scratch: SortScratch::default(),
            first_touch: options.first_touch,
            balance: Balance {
                stale: true,
                ..Balance::default()
            },
        };
        engine.take_starting_energies(case);
        Ok(engine)
    }

    /// The energies at the start that the guard rails measure against: what the initial
    /// stresses hold, the kinetic energy and what the liquid's compression holds, summed over
    /// the points in their global order (on one rank, as one process forms them).
    fn take_starting_energies(&mut self, case: &Case) {
        let whole = self.on_root(|e| {
            let stored = if case.start.initial_stress.is_some() {
                e.comm.sum(stored_energy(case, &e.particles))
            } else {
                0.0
            };
            let (liquid_kinetic, liquid_energy) = e.liquid_energies();
            vec![stored, e.kinetic_energy() + liquid_kinetic, liquid_energy]
        });
        let mut sums = Vec::new();
        self.comm.all_gather(&whole.unwrap_or_default(), &mut sums);
        self.stored_energy = sums[0];
        self.initial_kinetic = sums[1];
        self.step_kinetic = self.initial_kinetic;
        self.liquid_initial = sums[2];
        self.liquid_energy = sums[2];
    }
}

/// The bulk viscosity's constants, where the case has it.
fn bulk_of<R: Real>(case: &Case) -> Option<BulkDamping<R>> {
    let b = case.numerics.bulk_viscosity.as_ref()?;
    let media: Vec<_> = case
        .body
        .materials
        .iter()
        .map(|m| m.as_ref().map(MaterialSpec::bulk_medium))
        .collect();
    Some(BulkDamping::new(b, &media))
}

/// Whether the energy checks can run: they need every energy term, and prescribed velocities
/// do work that is not counted, while contact, absorbing boundaries and bulk viscosity take
/// energy out that is not counted either.
fn energy_counted(case: &Case, reactions: &[crate::step::reaction::Reaction]) -> bool {
    reactions.is_empty()
        && case.boundary.contact.is_none()
        && case.boundary.absorbing.is_empty()
        && case.numerics.bulk_viscosity.is_none()
}

/// Refuses what the element type `E` or a run over `ranks` processes does not model.
fn refuse_unmodelled<E: Element>(case: &Case, ranks: usize) -> Result<(), SetupError> {
    let mixed = matches!(case.numerics.integration, Integration::Mixed { .. });
    if E::AXISYMMETRIC {
        // Both average over an element, where the radius weighting of an axisymmetric
        // section would enter (Anura3D's own MPM-MIXED integrates such an element at its
        // first point): not modelled.
        if mixed {
            return Err(SetupError::Axisymmetric(
                "mixed integration (MPM-MIXED, Gauss points in full elements)",
            ));
        }
        if case.numerics.strain_smoothing {
            return Err(SetupError::Axisymmetric("strain smoothing"));
        }
    }
    let first = |list: &[(bool, &'static str)]| list.iter().find(|(on, _)| *on).map(|f| f.1);
    if case.numerics.grid.is_some() {
        let more = [
            (ranks > 1, "a run over several MPI ranks"),
            (!case.boundary.walls.is_empty(), "walls with friction"),
        ];
        if let Some(what) = first(&more).or(first(&one_process_only(case))) {
            return Err(SetupError::Grid(what));
        }
    }
    if case.numerics.gradient != Gradient::Element {
        let more = [
            (ranks > 1, "a run over several MPI ranks"),
            (!case.boundary.walls.is_empty(), "walls with friction"),
        ];
        if let Some(what) = first(&more).or(first(&one_process_only(case))) {
            return Err(SetupError::Ddmp(what));
        }
    }
    let factor = case.numerics.mass_scaling;
    if factor != 1.0 {
        // Anura3D scales the two-phase system's terms unevenly (its critical step's a, b and
        // d), and its contact from the scaled rates of momentum: neither is followed yet.
        let with = [
            (
                case.body
                    .materials
                    .iter()
                    .flatten()
                    .any(|m| m.liquid.is_some()),
                "with saturated materials (dry materials only)",
            ),
            (case.boundary.contact.is_some(), "with contact"),
        ];
        if let Some(what) = first(&with) {
            return Err(SetupError::MassScaling { factor, what });
        }
    }
    if case.numerics.scheme.semi_implicit() {
        refuse_for_semi_implicit::<E>(case, ranks)?;
    }
    if ranks > 1 {
        if let Some(what) = first(&one_process_only(case)) {
            return Err(SetupError::Distributed { ranks, what });
        }
    }
    Ok(())
}

/// Refuses what the semi-implicit scheme does not model: it solves for the pore pressure of
/// saturated materials, on one process, on the mesh's linear elements (plane or 3D), with the
/// implicit drag, and nothing after the grid update may change the accelerations it corrected.
fn refuse_for_semi_implicit<E: Element>(case: &Case, ranks: usize) -> Result<(), SetupError> {
    let n = &case.numerics;
    let saturated = case
        .body
        .materials
        .iter()
        .flatten()
        .any(|m| m.liquid.is_some());
    let list = [
        (
            !saturated,
            "a case without saturated materials (it solves for their pore pressure)",
        ),
        (ranks > 1, "a run over several MPI ranks"),
        (E::AXISYMMETRIC, "an axisymmetric section"),
        (n.grid.is_some(), "a background grid"),
        (n.gradient != Gradient::Element, "the dual-domain gradients"),
        (
            n.drag == Drag::Explicit,
            "the explicit drag (--drag explicit)",
        ),
        (n.bulk_viscosity.is_some(), "bulk viscosity"),
        (n.mass_scaling != 1.0, "mass scaling"),
    ];
    let first = |list: &[(bool, &'static str)]| list.iter().find(|(on, _)| *on).map(|f| f.1);
    match first(&list).or(first(&one_process_only(case))) {
        Some(what) => Err(SetupError::SemiImplicit(what)),
        None => Ok(()),
    }
}

/// What runs on one process, on the mesh's elements only: whether the case asks for each.
fn one_process_only(case: &Case) -> [(bool, &'static str); 8] {
    let b = &case.boundary;
    [
        (
            matches!(case.numerics.integration, Integration::Mixed { .. }),
            "mixed integration (MPM-MIXED)",
        ),
        (case.numerics.strain_smoothing, "strain smoothing"),
        (b.prescribed.is_some(), "prescribed velocities on points"),
        (
            !b.nodal_velocity.is_empty(),
            "prescribed velocities on nodes",
        ),
        (
            !case.loads.point_loads.is_empty(),
            "loads carried by material points",
        ),
        (b.moving_mesh.is_some(), "a moving mesh"),
        (b.contact.is_some(), "contact between bodies"),
        (!b.absorbing.is_empty(), "absorbing boundaries"),
    ]
}

/// A basis of its own: on a background grid, its basis on the grid's mesh; with the
/// dual-domain gradients, their averages on the mesh.
fn basis_of<E: Element, R: Real>(
    case: &Case,
    mesh: &Mesh<E, R>,
) -> Result<Option<Background>, SetupError> {
    let n = &case.numerics;
    Ok(match (&n.grid, n.gradient) {
        (Some(spec), _) => Some(Background::Grid(Cartesian::new(spec.clone(), mesh)?)),
        (None, Gradient::Element) => None,
        (None, g) => Some(Background::Ddmp(Ddmp::new(
            mesh,
            g == Gradient::DdmpBlended,
        )?)),
    })
}

/// This process's share of `global`: all of it on one process, else its range of the curve
/// cut by the points each element holds.
fn partition_of<E: Element, R: Real>(
    case: &Case,
    global: &Mesh<E, R>,
    comm: &dyn Communicator,
) -> Result<Partition, SetupError> {
    if comm.ranks() == 1 {
        return Ok(Partition::whole(global));
    }
    let weight: Vec<u64> = case
        .body
        .points_per_element
        .iter()
        .map(|&n| u64::from(n))
        .collect();
    let mut parts = Partition::along_curve(global, &weight, comm.ranks());
    if parts.len() != comm.ranks() || parts.iter().any(|p| p.owned() == 0) {
        return Err(SetupError::Distributed {
            ranks: comm.ranks(),
            what: "more ranks than blocks of 64 elements",
        });
    }
    Ok(parts.swap_remove(comm.rank()))
}

/// The material points of the partition's elements, as placed, in their initial state (the
/// laws' state slab, the liquid, the initial undrained state and stresses), and Anura3D's
/// boundary points of the mixed rule (found as placed, before the points are reordered).
fn points_of<E: Element, R: Real>(
    case: &Case,
    partition: &Partition,
    mesh: &Mesh<E, R>,
    basis: &Option<Background>,
    comm: &dyn Communicator,
) -> Result<(Particles<R>, Vec<bool>), SetupError> {
    let basis = basis.as_ref();
    let own = partition.elements();
    let density = |m: u32| {
        case.body.materials[m as usize]
            .as_ref()
            .map_or(0.0, |s| s.density)
    };
    let ids = case.point_ids();
    let first_id: Vec<u32> = own.clone().map(|e| ids.input_first(e) as u32).collect();
    let (points, material) = (
        &case.body.points_per_element[own.clone()],
        &case.body.element_material[own.clone()],
    );
    let mut particles = match basis
        .and_then(|b| b.grid())
        .and_then(|b| Some((b, b.spec().points_per_axis?)))
    {
        // A grid's regular points, seeded cell by cell.
        Some((b, k)) => {
            let centroid = |e: usize| {
                let c = mesh.corners[e].as_ref();
                std::array::from_fn(|a| {
                    c.iter().map(|&n| mesh.x[n as usize][a].f64()).sum::<f64>() / c.len() as f64
                })
            };
            let per_cell = k.pow(E::DIM as u32) as f64;
            particles::place_at(
                mesh,
                (points, material, Some(&first_id)),
                &|e, out| b.cell_points(&centroid(e), k, out),
                // Per radian in an axisymmetric section, as on elements.
                &|_, x| b.cell_volume() / per_cell * if E::AXISYMMETRIC { x[0].f64() } else { 1.0 },
                density,
            )
        }
        None => particles::place(
            mesh,
            points,
            material,
            Some(&first_id),
            &|e| case.element_number(partition.global_element(e)),
            density,
        )?,
    };
    if particles.is_empty() {
        return Err(SetupError::NoPoints);
    }
    let boundary = match case.numerics.integration {
        Integration::Mixed {
            rule: MixedRule::Anura3d,
            ..
        } => crate::step::mixed::boundary_points(mesh, &particles),
        _ => Vec::new(),
    };
    // The laws' state slab: as many values per point as the most demanding law keeps.
    particles.state_len = case
        .body
        .materials
        .iter()
        .flatten()
        .map(|m| m.law.state_len())
        .max()
        .unwrap_or(0);
    particles.state = vec![R::ZERO; particles.state_len * particles.len()];
    if case.has_liquid() {
        particles.add_liquid(
            |m| {
                case.body.materials[m as usize]
                    .as_ref()
                    .map_or(0.0, |s| s.initial_pore_pressure)
            },
            case.numerics.fixed_liquid_mass,
        );
    }
    if case.numerics.bulk_viscosity.is_some() {
        particles.add_bulk();
    }
    apply_undrained_state(case, &mut particles);
    if let Some(init) = &case.start.initial_stress {
        apply_initial_stress::<E, R>(init, case, partition, &mut particles);
    }
    check_starts(case, &particles, comm)?;
    Ok((particles, boundary))
}

/// Each point's start admitted by its law ([`crate::material::law::LawSpec::check_start`]), on
/// every rank: each refuses if one does (the others would wait for it at the first sum).
fn check_starts<R: Real>(
    case: &Case,
    particles: &Particles<R>,
    comm: &dyn Communicator,
) -> Result<(), SetupError> {
    let here = first_refused_start(case, particles);
    if comm.min(if here.is_ok() { 1.0 } else { 0.0 }) < 1.0 {
        here?;
        return Err(SetupError::StartElsewhere);
    }
    Ok(())
}

/// The first of this process's points whose start its law refuses.
fn first_refused_start<R: Real>(case: &Case, particles: &Particles<R>) -> Result<(), SetupError> {
    for (i, stress) in particles.stress.iter().enumerate() {
        let Some(m) = case.body.materials[particles.material[i] as usize].as_ref() else {
            continue;
        };
        if let Err(why) = m.law.check_start(&stress.map(R::f64)) {
            return Err(SetupError::Start {
                id: particles.id[i] as u64,
                material: m.name.clone(),
                why: why.to_string(),
            });
        }
    }
    Ok(())
}

/// Saturated points start in the case's undrained state, when it gives one.
fn apply_undrained_state<R: Real>(case: &Case, particles: &mut Particles<R>) {
    let (Some(s), Some(lp)) = (&case.start.initial_state, particles.liquid.as_mut()) else {
        return;
    };
    for i in 0..particles.x.len() {
        let m = particles.material[i] as usize;
        let Some(spec) = case.body.materials[m]
            .as_ref()
            .filter(|s| s.liquid.is_some())
        else {
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

/// The case's constraints, in the order their hooks run: walls, velocities prescribed on
/// points (with contact: the structure's, inside the contact), contact, velocities
/// prescribed on nodes (their components marked in `fixed`), the moving mesh; and, with
/// contact, the structure's own nodes (with its face loads, when the case gives them).
fn constraints_of<E: Element, R: Real>(
    case: &Case,
    partition: &Partition,
    mesh: &Mesh<E, R>,
    particles: &Particles<R>,
    walls: Vec<crate::step::wall_friction::WallNode<R>>,
    fixed: &mut [[bool; 3]],
) -> Result<ConstraintsAndStructure<R, E>, SetupError> {
    let mut list = Constraints::new();
    // First: the velocities prescribed after it win on the nodes they share.
    let rows = &case.boundary.absorbing;
    match case.boundary.absorbing_rule {
        _ if rows.is_empty() => {}
        AbsorbingRule::EndOfStep => list.push(Absorbing::new(rows, &mesh.node_of_model)),
        AbsorbingRule::Anura3d { point_sums } => list.push(AbsorbingAnura3d::new(
            rows,
            point_sums,
            mesh,
            particles.len(),
        )),
    }
    if !case.boundary.walls.is_empty() {
        list.push(Walls(walls));
    }
    let prescribed = case.boundary.prescribed.as_ref().map(|pv| {
        let pv = pv.clone().owned_by(partition);
        Prescribed::new(&pv, mesh, particles)
    });
    let structure = match &case.boundary.contact {
        Some(spec) => {
            list.push(Contact::new(
                spec,
                mesh,
                &case.body.element_material,
                prescribed,
            ));
            let mut structure = Structure::new(spec.material, mesh.nodes());
            let loads = &case.loads.structure_traction;
            if !loads.is_empty() {
                let of = |m: &u32| loads[*m as usize].map(R::of);
                structure.traction = mesh.model_node.iter().map(of).collect();
            }
            Some(structure)
        }
        None => {
            if let Some(pr) = prescribed {
                list.push(pr);
            }
            None
        }
    };
    if !case.boundary.nodal_velocity.is_empty() {
        let nv = NodalVelocity::new(
            &case.boundary.nodal_velocity,
            &mesh.node_of_model,
            usize::from(case.boundary.prescribed.is_some()),
        );
        // The grid update and the re-mapping treat them as fixed; they are set after each.
        nv.constrain(fixed);
        list.push(nv);
    }
    if let Some(spec) = &case.boundary.moving_mesh {
        list.push(MovingMesh::new(
            spec,
            &case.model,
            mesh,
            &case.body.element_material,
            &case.body.points_per_element,
            &case.body.input_node,
        )?);
    }
    Ok((list, structure))
}

/// What [`constraints_of`] resolves: the constraints and the structure's nodes.
type ConstraintsAndStructure<R, E> = (Constraints<R, E>, Option<Structure<R>>);

/// The per-material tables of the engine, indexed by material.
struct MaterialTables<R: Real> {
    /// The constitutive law (`Law::Void` for the empty elements' index).
    laws: Vec<Law<R>>,
    /// The liquid's constants (`None` for dry materials).
    fluids: Vec<Option<Fluid<R>>>,
    /// Weight density / mass density (1 but for Anura3D's drained soil).
    weight_ratio: Vec<f64>,
    /// Mass per initial volume of the points (t/m³).
    initial_density: Vec<R>,
}

impl<R: Real> MaterialTables<R> {
    fn of(case: &Case) -> Self {
        let materials = &case.body.materials;
        let each = |f: &dyn Fn(&crate::input::case::MaterialSpec) -> f64, empty: f64| {
            materials
                .iter()
                .map(|m| m.as_ref().map_or(empty, f))
                .collect::<Vec<f64>>()
        };
        MaterialTables {
            laws: materials
                .iter()
                .map(|m| m.as_ref().map_or(Law::Void, |s| s.law.build()))
                .collect(),
            fluids: materials
                .iter()
                .map(|m| m.as_ref().and_then(|s| s.liquid.as_ref()).map(Fluid::new))
                .collect(),
            weight_ratio: each(&|s| s.weight_density / s.density, 1.0),
            initial_density: each(&|s| s.density, 0.0).into_iter().map(R::of).collect(),
        }
    }
}

/// The nodal arrays of a mesh of `nodes` nodes, with the liquid's in a two-phase case.
fn grid_of<R: Real>(nodes: usize, two_phase: bool) -> Grid<R> {
    let mut grid = Grid::new(nodes);
    if two_phase {
        grid.liquid = Some(LiquidNodes::new(nodes));
    }
    grid
}

/// Per element, the smoothed pore-pressure rate's weights that particle to grid leaves for the
/// rate's pass, in two-phase cases with the rate smoothed through the nodes (not in an
/// axisymmetric section, whose points' hoop rates differ: the rate's pass goes point by point
/// there).
fn pore_weights_of<E: Element, R: Real>(case: &Case, elements: usize) -> Option<PoreWeights<R>> {
    (case.has_liquid()
        && case.numerics.smooth_pressure
        && !case.numerics.strain_smoothing
        && !E::AXISYMMETRIC)
        .then(|| PoreWeights::new(elements))
}

/// The mixed rule's per-element sums, under mixed integration.
fn mixed_of<R: Real>(case: &Case, elements: usize, boundary: Vec<bool>) -> Option<Mixed<R>> {
    match case.numerics.integration {
        Integration::MaterialPoints => None,
        Integration::Mixed { filling, rule } => Some(Mixed::new(elements, filling, rule, boundary)),
    }
}

/// Σ V σ:σ / 2M over the points (shear components twice, M the constrained modulus of the
/// point's material): the elastic energy their stresses hold, as a scale (kJ).
pub(super) fn stored_energy<R: Real>(case: &Case, particles: &Particles<R>) -> f64 {
    let mut sum = 0.0;
    for i in 0..particles.len() {
        let Some(m) = case.body.materials[particles.material[i] as usize].as_ref() else {
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
pub(super) fn apply_initial_stress<E: Element, R: Real>(
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
pub(super) fn resolve_point_loads<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    p: &Particles<R>,
    case: &Case,
    comm: &dyn Communicator,
) -> Result<Vec<(u32, V3<R>)>, SetupError> {
    if case.loads.point_loads.is_empty() {
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
    for load in &case.loads.point_loads {
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

/// What a rank's nodes and elements take from the case: fixities and face loads per local
/// node, and the input numbers of its elements and nodes (for messages). Read at set-up and
/// again whenever the ranks are re-partitioned.
pub(super) struct NodeInputs<R: Real> {
    pub(super) fixed: Vec<[bool; 3]>,
    pub(super) liquid_fixed: Vec<[bool; 3]>,
    pub(super) walls: Vec<crate::step::wall_friction::WallNode<R>>,
    pub(super) traction: Vec<V3<R>>,
    pub(super) liquid_traction: Vec<V3<R>>,
    pub(super) input_element: Vec<u32>,
    pub(super) input_node: Vec<u32>,
}

impl<R: Real> NodeInputs<R> {
    pub(super) fn of<E: Element>(case: &Case, mesh: &Mesh<E, R>, partition: &Partition) -> Self {
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
            fixed: by_node(&|m| case.boundary.fixed[m]),
            liquid_fixed: by_node(&|m| case.boundary.liquid_fixed[m]),
            walls: crate::step::wall_friction::wall_nodes(&case.boundary.walls, &mesh.model_node),
            traction: loads(&case.loads.traction),
            liquid_traction: loads(&case.loads.liquid_traction),
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
pub(super) fn critical_element<E: Element, R: Real>(
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
pub(super) fn layout_of<E: Element, R: Real>(
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
pub(super) fn first_touch<E: Element, R: Real>(
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
