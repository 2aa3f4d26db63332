//! Anura3D's contact between a structure and the soil (CPS `$$CONTACT_FORMULATION 1` with the
//! structure's elements in the GOM's `$$START_CONTACT_VOLUME`, in 2D
//! `$$START_BODY_CONTACT_2D`): Bardenhagen's two-body correction of the nodal velocities, so that a pile or a footing pushed into the soil
//! neither sticks to it nor pulls it back, with Coulomb friction and adhesion on the interface.
//!
//! The points of the structure's material form one body (the *structure*), every other point
//! the other (the *soil*); each body is mapped to nodal arrays of its own (mass, momentum,
//! forces, accelerations, re-mapped velocities: [`crate::state::grid::Grid`]), the soil's being
//! the engine's usual grid, and the grid update runs on each (local damping against each
//! body's own velocity). Then, at every *interface node* (a corner of a face of the structure
//! that borders an empty element or another material, found once, at the start):
//!
//! 1. the system's velocity v_s = (p₁ + p₂ + (R₁ + R₂) Δt) / (m₁ + m₂) (R the damped nodal
//!    forces; fixed components zero) is formed beside each body's own v_b = p_b / m_b + a_b Δt,
//!    and where the structure's velocity is prescribed both take the prescribed velocity;
//! 2. for each body at the node whose velocity differs from the system's: with n the unit
//!    normal out of that body (the structure's outward normal, from its interface faces by
//!    [`interface`]'s rules and fixed at the start; reversed for the soil), Δv = v_b - v_s
//!    and d = Δv·n, a body that approaches (d > 0) loses its normal relative velocity and,
//!    along the tangential direction t of its relative velocity, d (μ + c A Δt / (m_b d)) of
//!    the tangential one, at most all of it (full stick): v_b ← v_b - d (n + min(μ + c A Δt / (m_b d), |Δv × n| / d) t),
//!    μ and c the friction and adhesion between the structure and the node's soil material,
//!    A the node's share of the interface faces' area; its acceleration becomes
//!    (v_b - p_b / m_b) / Δt. A body that moves away is left alone.
//!
//! The bodies' points then take their own nodes' accelerations (FLIP) and re-map their own
//! momentum; strains, stresses and positions follow each body's nodal velocities. As Anura3D:
//! the normals, areas and interface nodes are those of the initial mesh; a node with no soil
//! material around it sticks (μ = 10, c = 1000 kPa), and the friction of the node's soil
//! material is the one of the lowest material index present around it.
//!
//! Every input: the normal is taken within the node's free directions (`free_normal`: a
//! symmetry plane through the structure). A scene's: at the structure's nodes off the
//! interface (in a section, more than one cell inside it), where soil points have slipped in,
//! both bodies take the system velocity.
//!
//! Modelled in 3D and in plane-strain and axisymmetric sections (the interface itself:
//! [`interface`]), for a dry structure in a dry or saturated soil: the correction acts on the
//! soil's solid, and before it the pore liquid is held at the impermeable wall (`liquid.rs`).
//! The work is over the interface nodes, in a fixed order, on the calling thread.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::parallel::gather::Layout;
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::constraint::{Constraint, Hook};
use crate::step::grid_update::NODE_BLOCK;
use crate::step::moment::Moment;
use crate::step::prescribed::Prescribed;

pub mod interface;
mod liquid;
mod rigid;

use interface::Interface;
pub use interface::InterfaceRule;

/// The name of the contact's set in `reaction.csv` (the soil's push on the structure).
pub const CONTACT_SET: &str = "contact";

/// The name of the set of the push's part at the interface nodes whose normal points down
/// (n_y ≤ −1/2; a pile's base resistance) in `reaction.csv`.
pub const CONTACT_BASE_SET: &str = "contact_base";

/// One body of a contact pair: the points of the structure's material, or all the others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OneBody {
    /// The structure's material index.
    pub structure_material: u32,
    /// The structure (else the soil).
    pub structure: bool,
}

impl OneBody {
    /// Whether a point of material `material` belongs to this body.
    #[inline(always)]
    pub fn keeps(&self, material: u32) -> bool {
        (material == self.structure_material) == self.structure
    }
}

/// Whether a pass of `body` (`None`: a run without contact, every point) maps a point of
/// `material`: one predictable branch on a material the kernels read anyway, or beside it.
#[inline(always)]
pub fn maps(body: Option<OneBody>, material: u32) -> bool {
    body.map_or(true, |b| b.keeps(material))
}

/// The contact as the input gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSpec {
    /// The structure's material index (that of the first listed element).
    pub material: u32,
    /// The structure's elements (0-based, the case's order) in the order the input lists them
    /// (a 2D node's normal is that of the last side in this order that faces the soil).
    pub listed: Vec<u32>,
    /// Per material index: (friction coefficient, adhesion in kPa) between that material and
    /// the structure (0 for a material the rows do not name).
    pub interfaces: Vec<(f64, f64)>,
    /// How a 2D interface node's normal and share of the interface are taken.
    pub rule: InterfaceRule,
    /// The structure moves as one rigid body (in translation), not as a deformable one.
    pub rigid: bool,
}

impl ContactSpec {
    /// The spec with its elements renumbered: `new_of_old[e]` is element e's new index.
    pub fn renumbered(mut self, new_of_old: &[u32]) -> Self {
        for e in &mut self.listed {
            *e = new_of_old[*e as usize];
        }
        self
    }
}

/// The structure's own nodal arrays in a run with contact: the second body the point passes
/// map, the soil's being the engine's grid.
#[derive(Debug, Clone)]
pub struct Structure<R: Real> {
    /// Which points are the structure.
    pub body: OneBody,
    /// The structure's nodal arrays.
    pub grid: Grid<R>,
    /// The face loads on the structure's nodes at multiplier 1 (its loaded faces'; the soil's
    /// are the engine's).
    pub traction: Vec<V3<R>>,
    /// The grid update's scratch for the structure's arrays.
    pub scratch: crate::step::grid_update::GridScratch<R>,
    /// The force sums' blocks of nodes (scratch).
    blocks: Vec<()>,
}

impl<R: Real> Structure<R> {
    /// The points of `material` as a body of their own, on a mesh of `nodes` nodes.
    pub fn new(material: u32, nodes: usize) -> Self {
        Structure {
            body: OneBody {
                structure_material: material,
                structure: true,
            },
            grid: Grid::new(nodes),
            traction: vec![[R::ZERO; 3]; nodes],
            scratch: crate::step::grid_update::GridScratch::new(nodes),
            blocks: vec![(); nodes.div_ceil(NODE_BLOCK)],
        }
    }

    /// The soil's body (every point not of the structure's material).
    pub fn soil(&self) -> OneBody {
        OneBody {
            structure: false,
            ..self.body
        }
    }

    /// The per-node force sums of Anura3D's convergence check over both bodies: |f₁ + f₂| and
    /// |f_ext,1 + f_ext,2| over the free components of every node, each body's face loads
    /// (`soil_traction`, the structure's own) at multiplier `scale` in its external force
    /// (written to `sums[0..2]` over the soil's grid update's; a saturated soil's liquid terms
    /// `sums[2..4]` kept), on the team in the grid update's blocks of nodes.
    pub fn force_sums(
        &mut self,
        team: &Team,
        (soil, soil_traction, scale): (&Grid<R>, &[V3<R>], R),
        fixed: &[[bool; 3]],
        sums: &mut [[f64; 4]],
    ) {
        let (structure, traction) = (&self.grid, &self.traction);
        let out = Shared::new(sums);
        team.for_blocks(soil.mass.len(), NODE_BLOCK, &mut self.blocks, |r| {
            // SAFETY: the nodes of this block are this call's only.
            let sums = unsafe { out.range(r.clone()) };
            for (n, sum) in r.zip(sums) {
                let (mut out2, mut ext2) = (0.0, 0.0);
                let any = [soil, structure].iter().any(|g| g.mass[n] > g.empty_below);
                if !any {
                    *sum = [0.0; 4];
                    continue;
                }
                for d in 0..3 {
                    if fixed[n][d] {
                        continue;
                    }
                    let loads = scale * (soil_traction[n][d] + traction[n][d]);
                    let ext = soil.f_ext[n][d].f64() + structure.f_ext[n][d].f64() + loads.f64();
                    let f = soil.f_int[n][d].f64() + structure.f_int[n][d].f64() + ext;
                    out2 += f * f;
                    ext2 += ext * ext;
                }
                // The liquid's terms (a saturated soil's) stay the soil's.
                *sum = [out2.sqrt(), ext2.sqrt(), sum[2], sum[3]];
            }
        });
    }
}

/// What the contact correction reads besides the two bodies' nodes: each body's face loads
/// at multiplier 1 (the soil's, the structure's), which the step's `at.traction` scales.
struct Within<'a, R: Real, E: Element> {
    layout: &'a Layout<R, E>,
    particles: &'a Particles<R>,
    fixed: &'a [[bool; 3]],
    at: &'a Moment<R>,
    loads: [&'a [V3<R>]; 2],
}

/// The contact of a run, resolved on its mesh: the interface between the structure
/// ([`Structure`]) and the soil, and the correction of their nodes' accelerations there.
#[derive(Debug, Clone)]
pub struct Contact<R: Real> {
    /// Which points are the structure.
    structure: OneBody,
    /// The structure moves as one rigid body (`rigid.rs`).
    rigid: bool,
    /// The velocity prescribed on the structure's points, when the case drives it (a pile
    /// pushed at a given speed): its overrides run around the correction, in Anura3D's order.
    driven: Option<Prescribed<R>>,
    /// Interface nodes (computational), ascending.
    nodes: Vec<u32>,
    /// Per interface node: the structure's outward unit normal.
    normal: Vec<[f64; 3]>,
    /// Per interface node: its share of the interface faces' area (m²).
    area: Vec<f64>,
    /// Per material index: (friction, adhesion) with the structure.
    interfaces: Vec<(f64, f64)>,
    /// Elements around each interface node: `around[start[k]..start[k + 1]]`.
    around: Vec<u32>,
    start: Vec<u32>,
    /// The structure's nodes that hold soil to it, ascending: in 3D all off the interface, in
    /// a section those more than one cell inside (a scene's; none for Anura3D's inputs, whose
    /// bodies pass through each other there).
    inside: Vec<u32>,
    /// The index of the contact's own set among the run's reactions.
    reaction: usize,
    /// The soil's push on the structure in the last step (kN; per radian in an axisymmetric
    /// section): the opposite of the soil's corrections' m Δv / Δt.
    force: [f64; 3],
    /// Its part at the nodes whose normal points down (n_y ≤ −1/2): a pile's base.
    on_base: [f64; 3],
    /// Its part at the nodes where the structure's velocity is prescribed, which the
    /// prescribed velocity's reaction carries.
    on_driven: [f64; 3],
}

impl<R: Real> Contact<R> {
    /// Resolves `spec` on `mesh` (the whole mesh, the case's element order):
    /// `element_material` says which elements are filled (material 0: empty); `driven`: the
    /// velocity prescribed on the structure's points, if any.
    pub fn new<E: Element>(
        spec: &ContactSpec,
        mesh: &Mesh<E, R>,
        element_material: &[u32],
        driven: Option<Prescribed<R>>,
    ) -> Self {
        let Interface {
            nodes,
            normal,
            area,
        } = Interface::of(spec, mesh, element_material);
        // The structure's nodes that hold soil to it: in 3D every node off the interface; in
        // a section those more than one cell inside it (the corners of its elements that
        // share no element with an interface node): design §4.19.
        let mut inside: Vec<u32> = Vec::new();
        if spec.rule == InterfaceRule::Tributary {
            let mut near: Vec<u32> = Vec::new();
            for &e in &spec.listed {
                let c = mesh.corners[e as usize].as_ref();
                if E::DIM == 2 && c.iter().any(|n| nodes.binary_search(n).is_ok()) {
                    near.extend(c);
                } else {
                    inside.extend(c);
                }
            }
            near.sort_unstable();
            near.dedup();
            inside.sort_unstable();
            inside.dedup();
            inside.retain(|n| nodes.binary_search(n).is_err() && near.binary_search(n).is_err());
        }
        // The elements around each interface node.
        let mut start = vec![0u32; nodes.len() + 1];
        let mut pairs: Vec<(usize, u32)> = Vec::new();
        for e in 0..mesh.elements() {
            for &n in mesh.corners[e].as_ref() {
                if let Ok(k) = nodes.binary_search(&n) {
                    pairs.push((k, e as u32));
                }
            }
        }
        pairs.sort_unstable();
        for &(k, _) in &pairs {
            start[k + 1] += 1;
        }
        for k in 0..nodes.len() {
            start[k + 1] += start[k];
        }
        Contact {
            structure: OneBody {
                structure_material: spec.material,
                structure: true,
            },
            rigid: spec.rigid,
            // The run's reactions are the prescribed points' set, if any, then the contact's
            // (`Case::reactions`; contact refuses velocities prescribed on nodes).
            reaction: usize::from(driven.is_some()),
            force: [0.0; 3],
            on_base: [0.0; 3],
            on_driven: [0.0; 3],
            driven,
            inside,
            nodes,
            normal,
            area,
            interfaces: spec.interfaces.clone(),
            around: pairs.into_iter().map(|p| p.1).collect(),
            start,
        }
    }

    /// Number of interface nodes.
    pub fn interface_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Which bodies have active points in the elements around interface node `k`, and the
    /// lowest soil material among them (`u32::MAX` for none).
    fn bodies_around<E: Element>(
        &self,
        k: usize,
        layout: &Layout<R, E>,
        p: &Particles<R>,
    ) -> ([bool; 2], u32) {
        let (mut bodies, mut lowest) = ([false; 2], u32::MAX);
        for &e in &self.around[self.start[k] as usize..self.start[k + 1] as usize] {
            for i in layout.particles_of(e as usize) {
                if !p.active[i] {
                    continue;
                }
                let m = p.material[i];
                let b = usize::from(self.structure.keeps(m));
                bodies[b] = true;
                if b == 0 {
                    lowest = lowest.min(m);
                }
            }
        }
        (bodies, lowest)
    }

    /// The friction coefficient and the adhesion force (adhesion times the node's area) at
    /// interface node `k` with soil material `lowest`.
    fn interface_at(&self, k: usize, lowest: u32) -> (f64, f64) {
        if lowest == u32::MAX {
            // No soil material around: stick (Anura3D's values).
            return (10.0, 1000.0);
        }
        let (mu, c) = self
            .interfaces
            .get(lowest as usize)
            .copied()
            .unwrap_or((0.0, 0.0));
        (mu, c * self.area[k])
    }

    /// Adds the soil's correction `change` (its velocity's decrease), of soil mass `m`, to the
    /// push on the structure: m Δv / Δt on the soil is its opposite on the structure. `base`:
    /// the node's normal points down (the base's set); `masked`: the structure's velocity is
    /// prescribed there.
    fn account(&mut self, m: f64, change: [f64; 3], dt: f64, base: bool, masked: bool) {
        for d in 0..3 {
            let on_structure = m * change[d] / dt;
            self.force[d] += on_structure;
            if base {
                self.on_base[d] += on_structure;
            }
            if masked {
                self.on_driven[d] += on_structure;
            }
        }
    }

    /// Each body's start-of-step and updated velocity at node `n`, the system's velocity and
    /// the structure's prescribed components there (module description, step 1): what the
    /// correction starts from at an interface node and at a node inside the structure.
    fn at_node(
        &self,
        n: usize,
        bodies: [&Grid<R>; 2],
        cx: &Within<'_, R, impl Element>,
        prescribed: &dyn Fn(u32) -> Option<([bool; 3], V3<R>)>,
    ) -> AtNode<R> {
        let (fixed, at, loads) = (cx.fixed, cx.at, cx.loads);
        let dtr = R::of(at.dt);
        let mut out = AtNode {
            before: [[0.0; 3]; 2],
            v: [[R::ZERO; 3]; 2],
            system: [R::ZERO; 3],
            masses: [bodies[0].mass[n], bodies[1].mass[n]],
            masked: prescribed(n as u32),
        };
        let mut force = [[R::ZERO; 3]; 2];
        let (mut mass, mut momentum) = (R::ZERO, [R::ZERO; 3]);
        for (b, g) in bodies.into_iter().enumerate() {
            let m = g.mass[n];
            mass += m;
            for d in 0..3 {
                momentum[d] += g.momentum[n][d];
            }
            if m <= g.empty_below {
                continue;
            }
            for d in 0..3 {
                if fixed[n][d] {
                    continue;
                }
                let prev = g.momentum[n][d] / m;
                out.before[b][d] = prev.f64();
                force[b][d] = if g.liquid.is_some() {
                    // A saturated soil's solid took the liquid's inertia and the two-phase
                    // damping with its acceleration (and the liquid's wall correction).
                    m * g.acc[n][d]
                } else {
                    // As the grid update forms it: the face loads are the body's own.
                    let ext = g.f_ext[n][d] + at.traction * loads[b][n][d];
                    let f = g.f_int[n][d] + ext;
                    crate::step::grid_update::damp(at.damping_rule, at.damping, f, g.momentum[n][d])
                };
                out.v[b][d] = prev + g.acc[n][d] * dtr;
            }
        }
        if mass > R::ZERO {
            for d in 0..3 {
                if !fixed[n][d] {
                    out.system[d] = momentum[d] / mass + (force[0][d] + force[1][d]) / mass * dtr;
                }
            }
        }
        if let Some((dirs, vp)) = out.masked {
            for d in 0..3 {
                if dirs[d] {
                    out.v[1][d] = vp[d];
                    out.system[d] = vp[d];
                }
            }
        }
        out
    }

    /// The contact correction after the grid update of both bodies (`soil`, `structure`) and
    /// the first override of prescribed velocities (`prescribed(node)`: the structure's
    /// prescribed velocity there and its components, for a masked node). Corrects the bodies'
    /// accelerations at the interface nodes and, for a scene, inside the structure (see the
    /// module's description), with the local damping of the step `at`.
    fn correct<E: Element>(
        &mut self,
        soil: &mut Grid<R>,
        structure_grid: &mut Grid<R>,
        cx: Within<'_, R, E>,
        prescribed: &dyn Fn(u32) -> Option<([bool; 3], V3<R>)>,
    ) {
        let dt = cx.at.dt;
        self.force = [0.0; 3];
        self.on_base = [0.0; 3];
        self.on_driven = [0.0; 3];
        for k in 0..self.nodes.len() {
            let n = self.nodes[k] as usize;
            let (bodies, lowest) = self.bodies_around(k, cx.layout, cx.particles);
            if !bodies[0] && !bodies[1] {
                continue;
            }
            let node = self.at_node(n, [soil, structure_grid], &cx, prescribed);
            let AtNode { v, mut system, .. } = node;
            if self.rigid && bodies[1] {
                // The rigid body is the stiffer one: the soil meets its velocity (`rigid.rs`).
                system = v[1];
            }
            let (mu, c) = self.interface_at(k, lowest);
            for b in 0..2 {
                if !bodies[b] || (0..3).all(|d| v[b][d] == system[d]) {
                    continue;
                }
                let Some(free) = free_normal(self.normal[k], cx.fixed[n]) else {
                    continue;
                };
                let sign = if b == 0 { -1.0 } else { 1.0 };
                let normal = free.map(|c| sign * c);
                let dv: [f64; 3] = [0, 1, 2].map(|d| (v[b][d] - system[d]).f64());
                let approach = dv[0] * normal[0] + dv[1] * normal[1] + dv[2] * normal[2];
                if approach <= 0.0 {
                    continue;
                }
                let m = node.masses[b].f64();
                let adhesion = c * dt / (m * (approach + 1e-60));
                let change = velocity_change(dv, normal, approach, mu + adhesion);
                let g: &mut Grid<R> = if b == 0 { soil } else { structure_grid };
                for d in 0..3 {
                    let corrected = v[b][d].f64() - change[d];
                    g.acc[n][d] = R::of((corrected - node.before[b][d]) / dt);
                }
                if b == 0 {
                    let base = self.normal[k][1] <= -0.5;
                    self.account(m, change, dt, base, node.masked.is_some());
                }
            }
        }
        // Inside the structure the soil has no place: soil points that slipped past the
        // interface move with the structure there (single-velocity nodes), rather than
        // through it on a grid of their own few points' mass.
        for i in 0..self.inside.len() {
            let n = self.inside[i] as usize;
            let grids: [&Grid<R>; 2] = [soil, structure_grid];
            if grids.iter().any(|g| g.mass[n] <= g.empty_below) {
                continue;
            }
            let AtNode {
                before,
                v,
                mut system,
                masses,
                masked,
            } = self.at_node(n, grids, &cx, prescribed);
            if self.rigid {
                system = v[1];
            }
            for b in 0..2 {
                let change: [f64; 3] = [0, 1, 2].map(|d| (v[b][d] - system[d]).f64());
                let g: &mut Grid<R> = if b == 0 { soil } else { structure_grid };
                for d in 0..3 {
                    if !cx.fixed[n][d] {
                        g.acc[n][d] = R::of((system[d].f64() - before[b][d]) / dt);
                    }
                }
                if b == 0 {
                    self.account(masses[0].f64(), change, dt, false, masked.is_some());
                }
            }
        }
    }
}

/// Each body's velocities at a node, as [`Contact::at_node`] forms them.
#[derive(Debug, Clone, Copy)]
struct AtNode<R: Real> {
    /// Start-of-step velocities (zero in fixed components).
    before: [[f64; 3]; 2],
    /// Updated velocities (the structure's prescribed components where it is driven).
    v: [V3<R>; 2],
    /// The system's velocity.
    system: V3<R>,
    /// The bodies' nodal masses.
    masses: [R; 2],
    /// The structure's prescribed components and velocity, where it is driven.
    masked: Option<([bool; 3], V3<R>)>,
}

/// The unit normal `normal` within the node's free directions (its components along the
/// `fixed` ones removed, the rest rescaled), or `None` when it has none there.
///
/// A fixed component is one no body moves in, so the non-penetration condition lives in the
/// others: where a symmetry plane or an axis cuts the structure, the wall's normal at the
/// nodes on it leans across the plane (the faces beside it), and the whole normal would both
/// leave part of the approach uncorrected and write an acceleration into the fixed component,
/// which the points then take (FLIP) and keep, step after step, across the plane. Anura3D
/// keeps the whole normal (its inputs' interface nodes on a fixed component lean the same way).
pub(super) fn free_normal(normal: [f64; 3], fixed: [bool; 3]) -> Option<[f64; 3]> {
    if !fixed.iter().any(|&f| f) {
        return Some(normal);
    }
    let kept = [0, 1, 2].map(|d| if fixed[d] { 0.0 } else { normal[d] });
    let size = (kept[0] * kept[0] + kept[1] * kept[1] + kept[2] * kept[2]).sqrt();
    // A normal all but across the fixed directions leaves no direction to correct along.
    (size > 1e-6).then(|| kept.map(|c| c / size))
}

/// The decrease of an approaching body's velocity (relative velocity `dv` to the system,
/// outward unit normal `normal`, normal approach d = `approach` > 0): its normal part and, along
/// the tangential direction t of `dv`, `limit` d of the tangential part, at most all of it:
/// d (n + min(limit, |dv × n| / d) t).
fn velocity_change(dv: [f64; 3], normal: [f64; 3], approach: f64, limit: f64) -> [f64; 3] {
    let cross = [
        dv[1] * normal[2] - dv[2] * normal[1],
        dv[2] * normal[0] - dv[0] * normal[2],
        dv[0] * normal[1] - dv[1] * normal[0],
    ];
    let size = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
    let omega = if size != 0.0 {
        cross.map(|c| c / size)
    } else {
        [0.0; 3]
    };
    let slip = limit.min(size / approach);
    let t = [
        normal[1] * omega[2] - normal[2] * omega[1],
        normal[2] * omega[0] - normal[0] * omega[2],
        normal[0] * omega[1] - normal[1] * omega[0],
    ];
    [0, 1, 2].map(|d| approach * (normal[d] + slip * t[d]))
}

impl<R: Real, E: Element> Constraint<R, E> for Contact<R> {
    fn name(&self) -> &'static str {
        "contact"
    }

    /// The driven structure's first override and reaction, the correction, and the driven
    /// structure's second override (Anura3D's order), on the structure's nodes.
    fn after_grid_update(&mut self, cx: &mut Hook<'_, R, E>) {
        let structure = cx
            .structure
            .as_deref_mut()
            .expect("a run with contact maps the structure to nodes of its own");
        let pm = self
            .driven
            .as_ref()
            .map_or(R::ZERO, |pr| R::of(pr.multiplier(cx.at.end())));
        let body = self.rigid.then(|| {
            let (loads, damping) = (
                (cx.structure_traction, cx.at.traction),
                (cx.at.damping_rule, cx.at.damping),
            );
            rigid::as_one_body(structure, cx.fixed, loads, damping)
        });
        if cx.soil.liquid.is_some() {
            // The liquid is held at the wall first, the wall driven at the marked points'
            // velocity before this step's prescribed velocity reaches them (Anura3D's order).
            if let Some(pr) = &mut self.driven {
                pr.mean_of_marked(cx.mesh, cx.particles);
            }
            let driven = &self.driven;
            let wall = liquid::Wall {
                nodes: &self.nodes,
                normal: &self.normal,
                fixed: cx.fixed,
                liquid_fixed: cx.liquid_fixed,
                dt: cx.at.dt,
                prescribed: &|n| driven.as_ref().and_then(|pr| pr.masked(n)),
            };
            liquid::seal(&wall, cx.soil, structure);
        }
        if let Some(pr) = &mut self.driven {
            pr.override_accelerations(structure, cx.particles, pm);
            let loads = cx.structure_traction;
            cx.reactions[0].force = pr.reaction(structure, loads, cx.at.traction);
            pr.mean_of_marked(cx.mesh, cx.particles);
        }
        // Out of `self` while the correction reads its masked nodes.
        let driven = self.driven.take();
        let prescribed = |n| driven.as_ref().and_then(|pr| pr.masked(n));
        let within = Within {
            layout: cx.layout,
            particles: cx.particles,
            fixed: cx.fixed,
            at: cx.at,
            loads: [cx.traction, cx.structure_traction],
        };
        self.correct(cx.soil, structure, within, &prescribed);
        if let Some(pr) = &driven {
            pr.override_accelerations(structure, cx.particles, pm);
            // The second override holds the structure against the soil's push too.
            let held = &mut cx.reactions[0].force;
            for (d, on) in pr.directions().iter().enumerate() {
                if *on {
                    held[d] -= self.on_driven[d];
                }
            }
        }
        self.driven = driven;
        if let Some((body, _)) = &body {
            // The soil's push moves the whole body.
            rigid::pushed(structure, body, self.force);
        }
        let sets = &mut cx.reactions[self.reaction..self.reaction + 2];
        debug_assert_eq!(sets[0].name, CONTACT_SET);
        debug_assert_eq!(sets[1].name, CONTACT_BASE_SET);
        sets[0].force = self.force;
        sets[1].force = self.on_base;
    }

    fn after_remap(&mut self, cx: &mut Hook<'_, R, E>) {
        if let Some(pr) = &mut self.driven {
            let structure = cx
                .structure
                .as_deref_mut()
                .expect("a run with contact maps the structure to nodes of its own");
            let pm = R::of(pr.multiplier(cx.at.end()));
            pr.override_velocities(cx.mesh, structure, cx.particles, pm);
        }
    }

    fn holds_points(&self) -> bool {
        self.driven.is_some()
    }

    fn follow(&mut self, new_of_old: &[u32]) {
        if let Some(pr) = &mut self.driven {
            pr.follow(new_of_old);
        }
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_normal_keeps_only_its_free_directions() {
        let n = [0.6, 0.0, 0.8];
        assert_eq!(
            free_normal(n, [false; 3]),
            Some(n),
            "nothing fixed: unchanged"
        );
        // On a symmetry plane z = 0 the wall's normal lies in the plane.
        assert_eq!(free_normal(n, [false, false, true]), Some([1.0, 0.0, 0.0]));
        let got = free_normal([0.6, -0.48, 0.64], [false, false, true]).unwrap();
        assert!(
            (got[0] - 0.78086880944).abs() < 1e-9 && got[2] == 0.0,
            "{got:?}"
        );
        assert!((got[0] * got[0] + got[1] * got[1] - 1.0).abs() < 1e-12);
        // On the axis (x and z fixed) a radial normal leaves nothing to correct.
        assert_eq!(free_normal([0.6, 0.0, 0.8], [true, false, true]), None);
        assert_eq!(
            free_normal([0.0, -1.0, 0.0], [true, false, true]),
            Some([0.0, -1.0, 0.0])
        );
    }

    #[test]
    fn an_approaching_body_loses_its_normal_relative_velocity() {
        // Normal approach only: the whole relative velocity goes.
        let c = velocity_change([0.0, -2.0, 0.0], [0.0, -1.0, 0.0], 2.0, 0.0);
        assert_eq!(c, [0.0, -2.0, 0.0]);
        // With slip along x, frictionless: the tangential part stays.
        let c = velocity_change([1.0, -2.0, 0.0], [0.0, -1.0, 0.0], 2.0, 0.0);
        assert_eq!(c, [0.0, -2.0, 0.0]);
        // Friction 0.25 takes 0.25 × 2 of the tangential 1; friction 1 takes all of it.
        let c = velocity_change([1.0, -2.0, 0.0], [0.0, -1.0, 0.0], 2.0, 0.25);
        assert!((c[0] - 0.5).abs() < 1e-15 && c[1] == -2.0, "{c:?}");
        let c = velocity_change([1.0, -2.0, 0.0], [0.0, -1.0, 0.0], 2.0, 1.0);
        assert!((c[0] - 1.0).abs() < 1e-15, "{c:?}");
    }
}
