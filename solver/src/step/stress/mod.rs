//! Strain increments from nodal velocities, the constitutive update, and the volume and position
//! update of every particle.
//!
//! The files, top-down: the pass and each chunk's and element's turn here; the general batches
//! (`general.rs`) and the linear-elastic four-lane ones (`lanes.rs`); the physics at the points
//! (`point.rs`) and the strain and objective terms (`strain.rs`) they share; the laws' dispatch
//! (`laws.rs`); the guard rails' sums (`guard.rs`); locating the points as they move
//! (`locate.rs`); and the pore pressure's rate (`pore_rate.rs`).

mod general;
mod guard;
mod lanes;
mod laws;
mod locate;
mod point;
mod pore_rate;
mod stencil;
mod strain;

pub use guard::{Guard, GuardSums};
pub use pore_rate::{update_pore_pressure, PorePressure, PoreRate};
pub use stencil::smooth_rates;
pub use strain::{rotate, rotation};

use crate::basis::background::Background;
use crate::element::locate::{merge, Outcome, NOTHING_FOUND};
use crate::element::mesh::Mesh;
use crate::element::{batch_width, Element};
use crate::four::{Four, Lanes};
use crate::material::law::Law;
use crate::material::liquid::Fluid;
use crate::material::mohr_coulomb::MohrCoulomb;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{Layout, ELEMENT_BLOCK};
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::bulk_viscosity::BulkDamping;
use crate::step::contact::OneBody;
use crate::step::passes::Passes;
use crate::step::smoothing::StrainSmoothing;

use guard::Open;

/// Points per batch of the elements of a Mohr-Coulomb or hypoplastic material, whatever the
/// element type and precision (docs/design.md §5.3); [`update_stress_and_move`] expands widths
/// 1 and 4 only.
pub const PLASTIC_WIDTH: usize = 4;

/// What the stress pass reads and updates.
pub struct StressUpdate<'a, R: Real> {
    /// The points: stresses, states, volumes, positions, displacements (and pore pressures,
    /// with a smoothed rate) updated.
    pub particles: &'a mut Particles<R>,
    /// The nodes whose velocities the points strain and move with.
    pub grid: &'a Grid<R>,
    /// Per material index, its law.
    pub laws: &'a [Law<R>],
    /// Anura3D's objective terms.
    pub objective: bool,
    /// Whether an axisymmetric section's hoop strain changes a point's volume.
    pub hoop_in_volume: bool,
    /// Anura3D's strain smoothing, where the case asks for it.
    pub smoothing: Option<&'a StrainSmoothing<R>>,
    /// The step.
    pub dt: R,
    /// With the guard rails, their sums.
    pub guard: Option<Guard<'a, R>>,
    /// Only the points of this body move (all for `None`).
    pub body: Option<OneBody>,
    /// The smoothed pore-pressure rates at the nodes, where [`update_pore_pressure`] left them.
    pub pore_rate: Option<PoreRate<'a, R>>,
    /// Where the moved points are located too, one [`Outcome`] per thread.
    pub located: Option<&'a mut [Outcome]>,
    /// A basis of its own (a background grid's, or the dual-domain gradients): each point
    /// strains with its own stencil.
    pub background: Option<&'a Background>,
    /// Each saturated point's pore-pressure rate from its own stencil (on a grid), per
    /// material index its liquid.
    pub point_rates: Option<&'a [Option<Fluid<R>>]>,
    /// The bulk viscosity, where the case damps with it: each point's viscous pressure and
    /// volumetric strain rate are formed ([`crate::step::bulk_viscosity`]).
    pub bulk: Option<&'a BulkDamping<R>>,
}

/// Δε = sym(Σ v_n ⊗ ∇N_n) Δt; σ += D Δε (plus, when `objective`, Anura3D's objective terms:
/// the rotation Δω σ - σ Δω with Δω = skew(L) Δt and -tr(Δε) σ); V *= 1 + tr Δε;
/// x += Δt Σ N_n v_n. With `smoothing`, the
/// normal increments (the two in-plane ones in plane strain) are shifted equally so that
/// tr Δε is the smoothed volumetric increment ([`crate::step::smoothing`]). In an axisymmetric
/// section (x the radius) Δε_zz is the hoop increment Δt Σ N_n v_n,x / x, and `hoop_in_volume`
/// says whether it changes V. Each thread updates the particles of its elements.
///
/// With `guard`, the [`GuardSums`] of the active points of each block of
/// [`ELEMENT_BLOCK`] elements are completed in its slot, point by point in order (strain-energy
/// increment, the liquid's compression energy, the volume check; grid to particle began it with
/// the kinetic energy): the guard rails' sums, formed in passes that read the points anyway so
/// that they cost no pass of their own. Only the points of `body` move, with `g`'s velocities
/// (all of them for `None`; one body of a contact pair, [`crate::step::contact`]).
///
/// With `located` (one [`Outcome`] per thread, each added to), each moved point is also
/// located: tested against its element with the position it was just given, and walked from
/// there where it left it, as the locate pass would (the same test and walk, so the same
/// elements), which then needs no pass of its own over the points. For runs in which nothing
/// happens between the two passes that a point's element depends on: no mesh motion, one
/// body, and lost points stopping the run (a point that leaves is recorded, and the rest of
/// its chunk still walked).
///
/// The linear element's pass: its strain is one per element ([`crate::basis`]).
pub fn update_stress_and_move<E: Element, R: Real>(
    passes: &Passes<'_, R, E>,
    update: StressUpdate<'_, R>,
) {
    let StressUpdate {
        particles: p,
        grid: g,
        laws,
        objective,
        hoop_in_volume,
        smoothing,
        dt,
        guard,
        body,
        pore_rate,
        located,
        background,
        point_rates,
        bulk,
    } = update;
    debug_assert!(
        pore_rate.is_none() || body.is_none(),
        "pore pressures moved with one body of a contact pair"
    );
    let (guard_slots, initial_density, fluids, min_ratio) = match guard {
        Some(g) => (
            Some(Shared::new(g.slots)),
            g.initial_density,
            g.fluids,
            g.min_volume_ratio,
        ),
        None => (None, &[][..], &[][..], R::ZERO),
    };
    let wide = use_avx2();
    debug_assert!(!wide || crate::parallel::avx2::present());
    let cx = Pass {
        four: if wide || cfg!(target_feature = "avx2") {
            R::Four::token()
        } else {
            None
        },
        layout: passes.layout,
        mesh: passes.mesh,
        g,
        laws,
        objective,
        tensor_state: laws.iter().any(|l| !l.state_tensors().is_empty()),
        hoop_in_volume,
        smoothing,
        dt,
        guard_slots,
        initial_density,
        fluids,
        min_ratio,
        body,
        pore_rate,
        mass: &p.mass,
        pores: p.liquid.as_mut().map(|l| Shared::new(&mut l.p)),
        xs: Shared::new(&mut p.x),
        us: Shared::new(&mut p.u),
        stresses: Shared::new(&mut p.stress),
        volumes: Shared::new(&mut p.volume),
        k: p.state_len,
        states: Shared::new(&mut p.state),
        active: &p.active,
        material: &p.material,
        elements: Shared::new(&mut p.element),
        located: located.map(Shared::new),
        background,
        point_rates,
        bulk: bulk.zip(p.bulk.as_mut()).map(|(b, points)| BulkPass {
            damping: b,
            pressure: Shared::new(&mut points.pressure),
            rate: Shared::new(&mut points.rate),
        }),
    };
    // In chunks handed out while the pass runs: a thread slowed by its core leaves the rest of
    // its chunks to the others (each point's update and each block's sums are the same
    // whichever thread computes them). Each chunk in the baseline instruction set or, where the
    // processor has it and the build does not assume it, with AVX2 (the same bits).
    passes
        .team
        .run_chunks(passes.layout.thread_chunks(), |t, c| {
            if wide {
                // SAFETY: `wide` only where the processor has AVX2 (`use_avx2`).
                unsafe { chunk_avx2(&cx, t, c) }
            } else {
                chunk::<E, R, false>(&cx, t, c)
            }
        });
}

/// What [`update_stress_and_move`]'s chunks read and write: its inputs, and the particle
/// arrays each chunk takes its own range of.
struct Pass<'a, E: Element, R: Real> {
    /// Where the pass runs its AVX2 copy (or the build assumes AVX2): the token of
    /// [`Real::Four`]'s instructions, for the linear-elastic points' explicit lanes.
    four: Option<<R::Four as Lanes<R>>::Token>,
    layout: &'a Layout<R, E>,
    mesh: &'a Mesh<E, R>,
    g: &'a Grid<R>,
    laws: &'a [Law<R>],
    objective: bool,
    /// Whether a law keeps tensors in its state, which the objective terms turn too.
    tensor_state: bool,
    hoop_in_volume: bool,
    smoothing: Option<&'a StrainSmoothing<R>>,
    dt: R,
    /// The guard's slots (one per block), or `None` without guards.
    guard_slots: Option<Shared<'a, GuardSums>>,
    initial_density: &'a [R],
    fluids: &'a [Option<Fluid<R>>],
    min_ratio: R,
    body: Option<OneBody>,
    pore_rate: Option<PoreRate<'a, R>>,
    mass: &'a [R],
    pores: Option<Shared<'a, R>>,
    xs: Shared<'a, [R; 3]>,
    us: Shared<'a, [R; 3]>,
    stresses: Shared<'a, [R; 6]>,
    volumes: Shared<'a, R>,
    /// State values per point.
    k: usize,
    states: Shared<'a, R>,
    active: &'a [bool],
    material: &'a [u32],
    elements: Shared<'a, u32>,
    /// One outcome per thread.
    located: Option<Shared<'a, Outcome>>,
    /// A basis of its own.
    background: Option<&'a Background>,
    /// Per material index its liquid, where each point takes its own pore-pressure rate.
    point_rates: Option<&'a [Option<Fluid<R>>]>,
    /// The bulk viscosity and the points' arrays it forms.
    bulk: Option<BulkPass<'a, R>>,
}

/// The bulk viscosity in the stress pass: its constants, and the points' viscous pressures and
/// volumetric strain rates each chunk takes its own range of.
struct BulkPass<'a, R: Real> {
    damping: &'a BulkDamping<R>,
    pressure: Shared<'a, R>,
    rate: Shared<'a, R>,
}

/// A chunk's point arrays, each sliced to the chunk's range and indexed by the position in it
/// (all of one length: the compiler then drops the bounds checks in the loops).
struct ChunkPoints<'s, R: Real> {
    /// Positions.
    x: &'s mut [V3<R>],
    /// Displacements.
    u: &'s mut [V3<R>],
    /// Stresses (xx yy zz xy yz zx).
    stress: &'s mut [[R; 6]],
    /// Volumes.
    volume: &'s mut [R],
    /// The pore pressures, in a two-phase run.
    pore: Option<&'s mut [R]>,
    /// Whether each point is active.
    active: &'s [bool],
    /// Material indices.
    material: &'s [u32],
    /// Masses.
    mass: &'s [R],
    /// Each point's element, which the located points' walks update.
    element: &'s mut [u32],
    /// The laws' states, `k` values a point.
    state: &'s mut [R],
    k: usize,
    /// With bulk viscosity, the points' viscous pressures and volumetric strain rates.
    bulk: Option<(&'s mut [R], &'s mut [R])>,
}

/// What one element shares among its points: its index, velocity gradient `l` (∂v_a/∂x_b),
/// nodal velocities, map and first corner, and its corners.
struct ElementView<'e, E: Element, R: Real> {
    /// The element's index.
    e: usize,
    /// Its velocity gradient, L[a][b] = ∂v_a/∂x_b.
    l: &'e [[R; 3]; 3],
    /// Its nodes' velocities.
    vel: &'e [V3<R>],
    /// Its map from global to local coordinates.
    map: &'e E::Map<R>,
    /// Its first corner's position.
    first: &'e V3<R>,
    /// Its corner nodes.
    corners: &'e [u32],
}

/// Where a chunk's points leave what they add besides their own values: the guard's sums of
/// the block they are in (added to with the guards: `guard`; always there, so that the
/// compiler keeps them in registers), and where the pass locates them, the chunk's walks'
/// outcome and its first point's index.
struct Sinks<'a> {
    open: &'a mut Open,
    guard: bool,
    locate: Option<(&'a mut Outcome, usize)>,
}

impl Sinks<'_> {
    /// The same sinks, borrowed for a while.
    #[inline(always)]
    fn reborrow(&mut self) -> Sinks<'_> {
        Sinks {
            open: &mut *self.open,
            guard: self.guard,
            locate: self
                .locate
                .as_mut()
                .map(|(found, offset)| (&mut **found, *offset)),
        }
    }
}

impl<E: Element, R: Real> Pass<'_, E, R> {
    /// The point arrays of the chunk's points `r`.
    ///
    /// # Safety
    /// `r` must be a chunk's particle range, taken by one thread at a time.
    #[inline(always)]
    unsafe fn chunk_points(&self, r: std::ops::Range<usize>) -> ChunkPoints<'_, R> {
        let (x, u, stress, volume, element) = (
            self.xs.range(r.clone()),
            self.us.range(r.clone()),
            self.stresses.range(r.clone()),
            self.volumes.range(r.clone()),
            self.elements.range(r.clone()),
        );
        let n = x.len();
        ChunkPoints {
            x,
            u: &mut u[..n],
            stress: &mut stress[..n],
            volume: &mut volume[..n],
            pore: self.pores.as_ref().map(|p| &mut p.range(r.clone())[..n]),
            active: &self.active[r.clone()][..n],
            material: &self.material[r.clone()][..n],
            mass: &self.mass[r.clone()][..n],
            element: &mut element[..n],
            // Each point's state is its own `k` values.
            state: self.states.range(self.k * r.start..self.k * r.end),
            k: self.k,
            bulk: self.bulk.as_ref().map(|b| {
                (
                    &mut b.pressure.range(r.clone())[..n],
                    &mut b.rate.range(r.clone())[..n],
                )
            }),
        }
    }
}

/// Chunk `c`'s points, on thread `t` ([`update_stress_and_move`]): element by element (the
/// points are sorted by element), each block's guard sums kept in registers ([`Open`]) and
/// written to its slot when the points pass to the next block.
#[inline(always)]
fn chunk<E: Element, R: Real, const WIDE: bool>(cx: &Pass<'_, E, R>, t: usize, c: usize) {
    let r = cx.layout.chunk_particles(c);
    // SAFETY: the particle ranges of the chunks are disjoint, and each chunk runs once.
    let mut p = unsafe { cx.chunk_points(r.clone()) };
    // What this chunk's walks found, added to the thread's outcome at the end.
    let mut found = NOTHING_FOUND;
    let blocks = cx.layout.chunk_blocks(c);
    // SAFETY: the chunks' element ranges are disjoint and hold whole blocks; this chunk's
    // points lie in its own elements.
    let mut sums = cx
        .guard_slots
        .as_ref()
        .map(|g| unsafe { g.range(blocks.clone()) });
    let mut open = Open::new(blocks.start);
    for e in cx.layout.chunk_elements(c) {
        let points = cx.layout.particles_of(e);
        if points.is_empty() {
            continue;
        }
        if let Some(sums) = sums.as_mut() {
            // A new block of elements: the last one's sums go to its slot.
            let b = e / ELEMENT_BLOCK;
            if b != open.block {
                open.close(&mut sums[open.block - blocks.start..]);
                open = Open::new(b);
            }
        }
        let sinks = Sinks {
            open: &mut open,
            guard: sums.is_some(),
            locate: cx.located.is_some().then_some((&mut found, r.start)),
        };
        let at = (points.start - r.start, points.end - r.start);
        element::<E, R, WIDE>(cx, e, &mut p, at, sinks);
    }
    if let Some(sums) = sums.as_mut() {
        if open.block < blocks.end {
            open.close(&mut sums[open.block - blocks.start..]);
        }
    }
    if let Some(outcomes) = &cx.located {
        // SAFETY: slot t is this thread's only (a thread runs its chunks one after another).
        merge(unsafe { &mut outcomes.range(t..t + 1)[0] }, found);
    }
}

/// Element `e`'s points `from..end` of the chunk: its velocity gradient (a linear element's is
/// the same at all its points, so it is formed once, from its nodes' velocities gathered once);
/// its linear-elastic points four at a time in explicit lanes where they run ([`lanes`]), the
/// rest in the general batches ([`general`]); then, where the pass locates, the points that
/// the lanes did not locate.
#[inline(always)]
fn element<E: Element, R: Real, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    e: usize,
    p: &mut ChunkPoints<'_, R>,
    (from, end): (usize, usize),
    mut sinks: Sinks<'_>,
) {
    if let Some(basis) = cx.background {
        stencil::element::<E, R, WIDE>(cx, basis, e, p, (from, end), sinks);
        return;
    }
    let mesh = cx.mesh;
    let grad = mesh.grad[e].as_ref();
    let corners = mesh.corners[e].as_ref();
    let vel = E::nodes(|k| cx.g.vel[corners[k] as usize]);
    let vel = vel.as_ref();
    // The velocity gradient L[a][b] = ∂v_a/∂x_b; a 2D element's velocities and gradients
    // have no z-part: the in-plane block only.
    let mut l = [[R::ZERO; 3]; 3];
    for k in 0..E::NODES {
        for a in 0..E::DIM {
            for b in 0..E::DIM {
                l[a][b] += vel[k][a] * grad[k][b];
            }
        }
    }
    let el = ElementView {
        e,
        l: &l,
        vel,
        map: &mesh.map[e],
        first: &mesh.x[corners[0] as usize],
        corners,
    };
    let mut j = from;
    // Linear-elastic points of a tetrahedron or a plane-strain triangle four at a time in
    // explicit four-lane vectors, in the AVX2 copy and in a build that assumes AVX2 (the same
    // bits). They stop at the first batch they do not take, and the general loop goes on from
    // there; the points before it are located.
    if let Some(t) = cx.four.filter(|_| WIDE || cfg!(target_feature = "avx2")) {
        // (Bulk viscosity forms each point's viscous pressure in the general batches.)
        if !E::AXISYMMETRIC && cx.smoothing.is_none() && cx.bulk.is_none() {
            j = lanes::elastic_batches(cx, t, &el, p, (j, end), sinks.reborrow());
            // The lanes took every point and located those that left (the common case):
            // nothing of the general loop below is left to do.
            if j == end {
                return;
            }
        }
    }
    let located_from = j;
    // Mohr-Coulomb points go in batches of [`PLASTIC_WIDTH`] whatever the element and
    // precision: their return's decompositions side by side (a long chain of dependent square
    // roots and divisions each) outweigh the spills of the rest. So do the hypoplastic law's
    // (each point's update on its own, the batch's strain and motion in lanes). Other laws in
    // the width of the element type and precision ([`batch_width`]).
    let plastic = matches!(
        cx.laws[p.material[from] as usize],
        Law::MohrCoulomb(_) | Law::Hypoplasticity(_)
    );
    let width = if plastic {
        PLASTIC_WIDTH
    } else {
        batch_width::<E, R>()
    };
    // The guard's sums only: the points are located below, after their batches.
    let open = (&mut *sinks.open, sinks.guard);
    match width {
        1 => general::general_batches::<E, R, 1, WIDE>(cx, &el, p, (j, end), open),
        _ => general::general_batches::<E, R, 4, WIDE>(cx, &el, p, (j, end), open),
    }
    if let Some((found, offset)) = sinks.locate {
        locate::locate_moved(mesh, e, p, (located_from, end), (found, offset));
    }
}

/// [`chunk`] compiled with AVX2 (on x86-64; elsewhere AVX2 is never chosen, and this is
/// [`chunk`]). A function of its own with `chunk` inlined (always): a closure around `chunk`
/// handed to [`crate::parallel::avx2::call`] is too large for the compiler to inline there, and
/// would be compiled for the baseline.
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn chunk_avx2<E: Element, R: Real>(cx: &Pass<'_, E, R>, t: usize, c: usize) {
    chunk::<E, R, { cfg!(target_arch = "x86_64") }>(cx, t, c)
}

/// [`MohrCoulomb::update_lanes`] compiled with AVX2 (on x86-64; elsewhere AVX2 is never
/// chosen, and this is the plain update).
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn plastic_lanes_avx2<R: Real, const W: usize>(
    mc: &MohrCoulomb<R>,
    s: &mut [[R; W]; 6],
    de: &[[R; W]; 6],
    on: &[bool; W],
) {
    mc.update_lanes(s, de, on)
}
