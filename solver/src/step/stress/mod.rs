//! Strain increments from nodal velocities, the constitutive update, and the volume and position
//! update of every particle.

use std::ops::Range;

use crate::element::locate::{locate_width, merge, relocate, run_inside, Outcome, NOTHING_FOUND};
use crate::element::mesh::Mesh;
use crate::element::{batch_width, Element};
use crate::four::Four;
use crate::material::law::Law;
use crate::material::liquid::Fluid;
use crate::material::mohr_coulomb::MohrCoulomb;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{node_slots, Layout, Slots, ELEMENT_BLOCK};
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::state::pore_weights::{self, PoreWeights};
use crate::step::batch::{interpolate, node_lane_shapes, Batch, TETRAHEDRA};
use crate::step::contact::{maps, OneBody};
use crate::step::smoothing::StrainSmoothing;

mod lanes;

/// Points per batch of the elements of a Mohr-Coulomb material, whatever the element type and
/// precision (docs/design.md §5.3); [`update_stress_and_move`] expands widths 1 and 4 only.
pub const PLASTIC_WIDTH: usize = 4;

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
#[allow(clippy::too_many_arguments)]
pub fn update_stress_and_move<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    mesh: &Mesh<E, R>,
    p: &mut Particles<R>,
    g: &Grid<R>,
    laws: &[Law<R>],
    objective: bool,
    hoop_in_volume: bool,
    smoothing: Option<&StrainSmoothing<R>>,
    dt: R,
    guard: Option<Guard<'_, R>>,
    body: Option<OneBody>,
    pore_rate: Option<PoreRate<'_, R>>,
    located: Option<&mut [Outcome]>,
) {
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
        layout,
        mesh,
        g,
        laws,
        objective,
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
    };
    // In chunks handed out while the pass runs: a thread slowed by its core leaves the rest of
    // its chunks to the others (each point's update and each block's sums are the same
    // whichever thread computes them). Each chunk in the baseline instruction set or, where the
    // processor has it and the build does not assume it, with AVX2 (the same bits).
    team.run_chunks(layout.thread_chunks(), |t, c| {
        if wide {
            // SAFETY: `wide` only where the processor has AVX2 (`use_avx2`).
            unsafe { chunk_avx2(&cx, t, c) }
        } else {
            chunk::<E, R, false>(&cx, t, c)
        }
    });
}

/// What [`update_stress_and_move`]'s chunks read and write: its arguments, and the particle
/// arrays each chunk takes its own range of.
struct Pass<'a, E: Element, R: Real> {
    /// Where the pass runs its AVX2 copy (or the build assumes AVX2): the token of
    /// [`Real::Four`]'s instructions, for the linear-elastic points' explicit lanes.
    four: Option<<R::Four as Four<R>>::Token>,
    layout: &'a Layout<R, E>,
    mesh: &'a Mesh<E, R>,
    g: &'a Grid<R>,
    laws: &'a [Law<R>],
    objective: bool,
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
}

/// Chunk `c`'s points, on thread `t` ([`update_stress_and_move`]).
#[inline(always)]
fn chunk<E: Element, R: Real, const WIDE: bool>(cx: &Pass<'_, E, R>, t: usize, c: usize) {
    // The values the loop uses most, by name; the others as `cx.` fields.
    let Pass {
        mesh,
        dt,
        initial_density,
        fluids,
        min_ratio,
        body,
        pore_rate,
        mass,
        k,
        active,
        material,
        ..
    } = *cx;
    let (guard_slots, pores, located) = (&cx.guard_slots, &cx.pores, &cx.located);
    let (xs, us, stresses, volumes, states, elements) = (
        &cx.xs,
        &cx.us,
        &cx.stresses,
        &cx.volumes,
        &cx.states,
        &cx.elements,
    );
    let half = R::of(0.5);
    let third = R::ONE / R::of(3.0);
    let r = cx.layout.chunk_particles(c);
    // SAFETY: the particle ranges of the chunks are disjoint, and each chunk runs once.
    let (x, u, stress, volume, element) = unsafe {
        (
            xs.range(r.clone()),
            us.range(r.clone()),
            stresses.range(r.clone()),
            volumes.range(r.clone()),
            elements.range(r.clone()),
        )
    };
    // What this chunk's walks found, added to the thread's outcome at the end.
    let mut found = NOTHING_FOUND;
    // SAFETY: as above; each point's state is its own `k` values.
    let state = unsafe { states.range(k * r.start..k * r.end) };
    let blocks = cx.layout.chunk_blocks(c);
    // SAFETY: the chunks' element ranges are disjoint and hold whole blocks; this chunk's
    // points lie in its own elements.
    let mut sums = guard_slots
        .as_ref()
        .map(|g| unsafe { g.range(blocks.clone()) });
    // The current block's sums, kept in registers and written to its slot when the points
    // pass to the next block (adding to the slot point by point would chain every point's
    // sum through memory). Points come sorted by element, so blocks come in order; the
    // slot's own strain and liquid terms start at 0 (grid to particle began it), so the
    // sums are those of adding in place, point by point.
    let mut open = Open::new(blocks.start);
    // The point arrays sliced to this thread's range, all of one length, and indexed by
    // the position in it: the compiler then drops the bounds checks in the loop.
    let n = x.len();
    let (u, stress, volume) = (&mut u[..n], &mut stress[..n], &mut volume[..n]);
    let (active, material) = (&active[r.clone()], &material[r.clone()]);
    let (active, element, material) = (&active[..n], &mut element[..n], &material[..n]);
    let mass = &mass[r.clone()][..n];
    // SAFETY: as above.
    let mut pore = pores
        .as_ref()
        .map(|p| unsafe { &mut p.range(r.clone())[..n] });
    // Element by element (the points are sorted by element): a linear element's velocity
    // gradient is the same at all its points, so it is formed once per element, from its
    // nodes' velocities gathered once.
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
        // The element's points in batches of up to `W` ([`batch_width`]), each value held
        // across the batch's points (`[c][q]`: value c of point q) so that each operation
        // is one over the points, which the compiler turns into vector instructions. Each
        // point's arithmetic is the one a point-by-point loop does, in the same order, so
        // the results are the same bits whatever the width; lanes past the batch's points
        // or of points that do not move repeat a moving point's values and are never
        // stored.
        let first = &mesh.x[corners[0] as usize];
        let map = &mesh.map[e];
        let (end, mut j) = (points.end - r.start, points.start - r.start);
        // The points before this one are located (with `located`).
        let mut located_from = j;
        // Linear-elastic points of a tetrahedron or a plane-strain triangle four at a time in
        // explicit four-lane vectors, in the AVX2 copy and in a build that assumes AVX2
        // ([`lanes`]; the same bits). They stop at the first batch they do not take, and the
        // general loop below goes on from there.
        if let Some(t) = cx.four.filter(|_| WIDE || cfg!(target_feature = "avx2")) {
            if !E::AXISYMMETRIC && cx.smoothing.is_none() {
                let el = lanes::ElementView {
                    e,
                    l: &l,
                    vel,
                    map,
                    first,
                    corners,
                };
                let points = lanes::Points {
                    x: &mut *x,
                    u: &mut *u,
                    stress: &mut *stress,
                    volume: &mut *volume,
                    pore: pore.as_deref_mut(),
                    active,
                    material,
                    mass,
                    element: &mut *element,
                };
                let open = sums.is_some().then_some(&mut open);
                let locate = located.is_some().then_some((&mut found, r.start));
                j = lanes::elastic_batches(cx, t, &el, points, j, end, open, locate);
                located_from = j;
                // The lanes took every point and located those that left (the common case):
                // nothing of the general loop below is left to do.
                if j == end {
                    continue;
                }
            }
        }
        // The batch loop, expanded once per batch width (one is used per element type
        // and precision, [`batch_width`]).
        macro_rules! batches {
            ($w:literal) => {{
                const W: usize = $w;
                while j < end {
                    let b = match Batch::<W>::new(j, end, |i| {
                        active[i] && maps(body, material[i])
                    }) {
                        Ok(b) => b,
                        Err(skip) => {
                            j += skip;
                            continue;
                        }
                    };
                    debug_assert!(
                        (j..j + b.len).all(|i| element[i] as usize == e),
                        "points not sorted by element"
                    );
                    let xl = b.gather(x);
                    let n = E::shape_lanes(map, first, &xl);
                    // The pore pressure's smoothed rate, from the nodes at the start-of-step
                    // position (the points move below).
                    if let (Some(rate), Some(pore)) = (&pore_rate, pore.as_mut()) {
                        // The element's nodal rates, read once per batch (once per element
                        // in a tetrahedron's batch of four): held across the whole element
                        // they cost the dry step registers.
                        let nodal = E::nodes(|k| rate.nodal[corners[k] as usize]);
                        let nodal = nodal.as_ref();
                        for i in b.points() {
                            if rate.fluids[material[i] as usize].is_some() {
                                let mut change = R::ZERO;
                                for k in 0..E::NODES {
                                    change += n[k][i - j] * nodal[k];
                                }
                                pore[i] += change * dt;
                            }
                        }
                    }
                    let dx = interpolate::<E, R, W>(&n, vel);
                    let element_de = strain_increment::<E, R>(&l, dt);
                    let mut de: [[R; W]; 6] = std::array::from_fn(|c| [element_de[c]; W]);
                    if E::AXISYMMETRIC {
                        // In an axisymmetric section ε_zz is the hoop strain u_r / r (x is the
                        // radius), point by point.
                        de[2] = std::array::from_fn(|q| dx[0][q] / xl[0][q] * dt);
                    }
                    if let Some(sm) = cx.smoothing {
                        // The normal increments in the section's plane take the correction: all
                        // three in 3D, the two in-plane ones in plane strain (Anura3D's rule;
                        // its ε_zz stays zero). Axisymmetric sections do not smooth.
                        for q in 0..W {
                            let [es, _] = sm.element_mean(mesh, e, material[b.at[q]]);
                            let c = if E::DIM == 2 {
                                (de[0][q] + de[1][q] - es) * half
                            } else {
                                (de[0][q] + de[1][q] + de[2][q] - es) * third
                            };
                            for d in de.iter_mut().take(E::DIM) {
                                d[q] -= c;
                            }
                        }
                    }
                    let s0 = b.gather(stress);
                    let mut s1 = s0;
                    // A batch of one linear-elastic or Mohr-Coulomb material takes the
                    // update across its points; any other law goes point by point.
                    let lead = material[b.at[0]];
                    let one = b.points().all(|i| material[i] == lead);
                    match &cx.laws[lead as usize] {
                        Law::LinearElastic(le) if one => le.update_lanes(&mut s1, &de),
                        // (A lone point goes by the scalar update: the same bits.)
                        Law::MohrCoulomb(mc) if one && W > 1 => {
                            plastic_lanes::<R, W, WIDE>(mc, &mut s1, &de, &b.on)
                        }
                        _ => {
                            for i in b.points() {
                                let q = i - j;
                                let mut s: [R; 6] = std::array::from_fn(|c| s1[c][q]);
                                let d: [R; 6] = std::array::from_fn(|c| de[c][q]);
                                cx.laws[material[i] as usize].update(
                                    &mut s,
                                    &d,
                                    &mut state[k * i..k * i + k],
                                );
                                for c in 0..6 {
                                    s1[c][q] = s[c];
                                }
                            }
                        }
                    }
                    // Anura3D's objective update (its "Hill" rate): the co-rotation and the
                    // change of volume, -tr(Δε) σ, of the start-of-step stress, added after the
                    // law's update as Anura3D adds them (for a plastic law the order matters:
                    // the return sees the unrotated trial).
                    if cx.objective {
                        let mut h = rotation_lanes(&s0, &spin_increment(&l, dt));
                        for q in 0..W {
                            let ev = de[0][q] + de[1][q] + de[2][q];
                            for c in 0..6 {
                                h[c][q] -= ev * s0[c][q];
                                s1[c][q] += h[c][q];
                            }
                        }
                    }
                    let v0: [R; W] = b.at.map(|i| volume[i]);
                    // The hoop strain changes an axisymmetric point's volume unless the case
                    // follows Anura3D, which leaves it out
                    // ([`crate::input::case::Case::hoop_in_volume`]).
                    let de_zz = if E::AXISYMMETRIC && !cx.hoop_in_volume {
                        [R::ZERO; W]
                    } else {
                        de[2]
                    };
                    let v1: [R; W] =
                        std::array::from_fn(|q| {
                            v0[q] * (R::ONE + de[0][q] + de[1][q] + de_zz[q])
                        });
                    let mut x1 = xl;
                    for a in 0..E::DIM {
                        for q in 0..W {
                            x1[a][q] += dt * dx[a][q];
                        }
                    }
                    for i in b.points() {
                        let q = i - j;
                        x[i] = std::array::from_fn(|a| x1[a][q]);
                        for a in 0..E::DIM {
                            u[i][a] += dt * dx[a][q];
                        }
                        stress[i] = std::array::from_fn(|c| s1[c][q]);
                        volume[i] = v1[q];
                    }
                    if sums.is_some() {
                        // Work of the mean stress over the step (exact for a linear law) on the
                        // start volume; shear components count twice (tensor shear strains).
                        let mut w = [R::ZERO; W];
                        // (A section's out-of-plane shears add (σ0 + σ1) · +0 = ±0 to a sum
                        // that starts at +0 and so is never -0: left out, the same bits.)
                        for c in 0..if E::DIM == 2 { 4 } else { 6 } {
                            let twice = if c < 3 { R::ONE } else { R::of(2.0) };
                            for q in 0..W {
                                w[q] += twice * (s0[c][q] + s1[c][q]) * de[c][q];
                            }
                        }
                        // 0, or NaN for a non-finite position or new volume: added to the
                        // strain sum, which a non-finite stress makes non-finite too, so one
                        // test of the sums catches them all.
                        let finite: [R; W] = std::array::from_fn(|q| {
                            R::ZERO * (x1[0][q] + x1[1][q] + x1[2][q] + v1[q])
                        });
                        let strain: [R; W] = std::array::from_fn(|q| w[q] * v0[q] + finite[q]);
                        // Point by point in order: the block's sums are those of adding in
                        // place.
                        for i in b.points() {
                            let q = i - j;
                            // V/V0 ≤ r is V ρ0 - r m ≤ 0 (the mass is constant, m = ρ0 V0): no
                            // division per point.
                            let rho0 = initial_density[material[i] as usize];
                            let margin = v1[q] * rho0 - min_ratio * mass[i];
                            // Twice the energies: the engine halves the sums (exactly, a power
                            // of two).
                            open.strain += strain[q].f64();
                            if let Some(pore) = pore.as_deref() {
                                // A saturated point's liquid holds n V p² / 2 K_w: the pore
                                // pressure's work on Δp = (K_w/n) Δε_mix. A non-finite pore
                                // pressure makes the sum NaN.
                                let p = pore[i];
                                let c = fluids[material[i] as usize]
                                    .as_ref()
                                    .map_or(R::ZERO, |f| f.n_over_kw);
                                open.liquid += (v1[q] * p * p * c + R::ZERO * p).f64();
                            }
                            // A plain comparison (one instruction): NaN is caught by the strain
                            // sum.
                            let m = margin.f64();
                            if m < open.volume_margin {
                                open.volume_margin = m;
                            }
                        }
                    }
                    j += b.len;
                }
            }};
        }
        // Mohr-Coulomb points go in batches of [`PLASTIC_WIDTH`] whatever the element
        // and precision: their return's decompositions side by side (a long chain of
        // dependent square roots and divisions each) outweigh the spills of the rest.
        let plastic = matches!(
            cx.laws[material[points.start - r.start] as usize],
            Law::MohrCoulomb(_)
        );
        match if plastic {
            PLASTIC_WIDTH
        } else {
            batch_width::<E, R>()
        } {
            1 => batches!(1),
            _ => batches!(4),
        }
        if located.is_some() {
            // The element's points at their new positions, still in the nearest cache:
            // runs of `w` of them tested at once (most points stay in their element), the
            // others walked, as the locate pass does.
            let (end, w) = (points.end - r.start, locate_width::<E, R>());
            let mut i = located_from;
            while i < end {
                if w > 1 && i + w <= end && active[i..i + w].iter().all(|&a| a) {
                    let inside = match w {
                        4 => run_inside::<E, R, 4>(mesh, e, &x[i..i + 4]),
                        3 => run_inside::<E, R, 3>(mesh, e, &x[i..i + 3]),
                        _ => run_inside::<E, R, 2>(mesh, e, &x[i..i + 2]),
                    };
                    if inside {
                        i += w;
                        continue;
                    }
                }
                if active[i] {
                    relocate(mesh, &mut found, r.start + i, &mut element[i], &x[i]);
                }
                i += 1;
            }
        }
    }
    if let Some(sums) = sums.as_mut() {
        if open.block < blocks.end {
            open.close(&mut sums[open.block - blocks.start..]);
        }
    }
    if let Some(outcomes) = &located {
        // SAFETY: slot t is this thread's only (a thread runs its chunks one after another).
        merge(unsafe { &mut outcomes.range(t..t + 1)[0] }, found);
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

/// [`MohrCoulomb::update_lanes`] in a function of its own, so that the long return does not
/// crowd the registers of the chunk's loop that every other law runs through; with `WIDE`
/// ([`chunk_avx2`]'s) compiled with AVX2.
#[inline(never)]
fn plastic_lanes<R: Real, const W: usize, const WIDE: bool>(
    mc: &MohrCoulomb<R>,
    s: &mut [[R; W]; 6],
    de: &[[R; W]; 6],
    on: &[bool; W],
) {
    if WIDE {
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in [`chunk_avx2`]'s expansion, which runs where the processor
        // has AVX2.
        unsafe { plastic_lanes_avx2(mc, s, de, on) }
    } else {
        mc.update_lanes(s, de, on)
    }
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

/// The strain increment sym(L) Δt of a linear element (xx yy zz xy yz zx, tensor shears) from
/// its velocity gradient `l` (L[a][b] = ∂v_a/∂x_b): the same at all its points, except an
/// axisymmetric section's ε_zz, the hoop strain, which the caller forms per point. A section's
/// out-of-plane shear increments are +0 exactly (its L has no z-row or z-column, and Δt is
/// positive and finite): written as such.
#[inline(always)]
fn strain_increment<E: Element, R: Real>(l: &[[R; 3]; 3], dt: R) -> [R; 6] {
    let half = R::of(0.5);
    let out_of_plane = |a: usize, b: usize| {
        if E::DIM == 2 {
            R::ZERO
        } else {
            half * (l[a][b] + l[b][a]) * dt
        }
    };
    [
        l[0][0] * dt,
        l[1][1] * dt,
        l[2][2] * dt,
        half * (l[0][1] + l[1][0]) * dt,
        out_of_plane(1, 2),
        out_of_plane(2, 0),
    ]
}

/// The spin increment skew(L) Δt (ω_xy, ω_yz, ω_zx) of an element with velocity gradient
/// `l`, for Anura3D's objective terms.
#[inline(always)]
fn spin_increment<R: Real>(l: &[[R; 3]; 3], dt: R) -> [R; 3] {
    let half = R::of(0.5);
    [
        half * (l[0][1] - l[1][0]) * dt,
        half * (l[1][2] - l[2][1]) * dt,
        half * (l[2][0] - l[0][2]) * dt,
    ]
}

/// [`rotation`] of each point's stress in a batch of `W`: (Ωσ - σΩ)_ij = Σ_k Ω_ik σ_kj - σ_ik Ω_kj,
/// written out for the symmetric result, point by point.
#[inline(always)]
fn rotation_lanes<R: Real, const W: usize>(s: &[[R; W]; 6], w: &[R; 3]) -> [[R; W]; 6] {
    let [xx, yy, zz, xy, yz, zx] = s;
    let (wxy, wyz, wzx) = (w[0], w[1], w[2]);
    let two = R::of(2.0);
    [
        std::array::from_fn(|q| two * (wxy * xy[q] - wzx * zx[q])),
        std::array::from_fn(|q| two * (wyz * yz[q] - wxy * xy[q])),
        std::array::from_fn(|q| two * (wzx * zx[q] - wyz * yz[q])),
        std::array::from_fn(|q| wxy * (yy[q] - xx[q]) + wyz * zx[q] - wzx * yz[q]),
        std::array::from_fn(|q| wyz * (zz[q] - yy[q]) + wzx * xy[q] - wxy * zx[q]),
        std::array::from_fn(|q| wzx * (xx[q] - zz[q]) + wxy * yz[q] - wyz * xy[q]),
    ]
}

/// The guard sums of the block the stress loop is in.
struct Open {
    block: usize,
    strain: f64,
    liquid: f64,
    volume_margin: f64,
}

impl Open {
    fn new(block: usize) -> Self {
        Open {
            block,
            strain: 0.0,
            liquid: 0.0,
            volume_margin: f64::INFINITY,
        }
    }

    /// Adds these sums to the block's slot, `slots[0]`.
    fn close(&self, slots: &mut [GuardSums]) {
        let slot = &mut slots[0];
        slot.strain += self.strain;
        slot.liquid += self.liquid;
        slot.volume_margin = slot.volume_margin.min(self.volume_margin);
    }
}

/// Per block of [`ELEMENT_BLOCK`] elements, the guard rails' sums over its active points after
/// the stress update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuardSums {
    /// Σ V0 (σ0 + σ1) : Δε, twice the strain energy taken up in the step (kJ; the energies are
    /// summed doubled and halved once, by the engine); NaN when a position or volume is not
    /// finite.
    pub strain: f64,
    /// Σ m |v|² (kJ), twice the kinetic energy with the step's new point velocities (written by
    /// grid to particle); for saturated points with the liquid's n ρw V_w |w|².
    pub kinetic: f64,
    /// Σ n V p² / K_w over saturated points (kJ): twice the energy the liquid's compression
    /// holds after the step; NaN when a pore pressure is not finite.
    pub liquid: f64,
    /// Smallest V ρ0 - r m of the points (t), r the guard's smallest volume ratio: ≤ 0 when a
    /// point's V / V0 has fallen to r.
    pub volume_margin: f64,
}

impl GuardSums {
    /// A block without points.
    pub const EMPTY: GuardSums = GuardSums {
        strain: 0.0,
        kinetic: 0.0,
        liquid: 0.0,
        volume_margin: f64::INFINITY,
    };
}

/// Smoothed pore-pressure rates at the nodes that [`update_pore_pressure`] left for the stress
/// pass to interpolate to the points (Δp = Δt Σ N_k ṗ_k), which visits each point with its
/// shape functions anyway.
#[derive(Clone, Copy)]
pub struct PoreRate<'a, R: Real> {
    /// Per node, the smoothed rate.
    pub nodal: &'a [R],
    /// Per material index, its liquid (dry materials' points keep their pressure).
    pub fluids: &'a [Option<Fluid<R>>],
}

/// What [`update_stress_and_move`] needs to form the guard rails' sums.
pub struct Guard<'a, R: Real> {
    /// One slot per element.
    pub slots: &'a mut [GuardSums],
    /// Per material index, mass per initial volume of its points (ρ0, t/m³; 0 for none).
    pub initial_density: &'a [R],
    /// Per material index, its liquid (saturated materials).
    pub fluids: &'a [Option<Fluid<R>>],
    /// The smallest V / V0 allowed.
    pub min_volume_ratio: R,
}

/// Pore-pressure update of saturated points (docs/design.md §4): Δp = (K_w / n) (n Δε_vol,w +
/// (1 - n) Δε_vol,s), the volumetric strain increments from the nodal liquid and solid velocities
/// (compression negative, so compression lowers p). Call before the points move.
///
/// Linear tetrahedra give one volumetric strain per element, and with a stiff liquid
/// (K_w / n ≫ E_oed) the pressure then shows spurious element-to-element (checkerboard) modes
/// that grow near drained faces. The rate is therefore smoothed through the nodes: each point's
/// rate is averaged to its element's nodes (weight V N) and interpolated back with N, as
/// Anura3D's strain smoothing does for the volumetric strain (`smooth`; without it each point
/// takes its element's rate, as Anura3D without `STRAIN_SMOOTHING`). With Anura3D's strain
/// `smoothing` both increments are its smoothed ones instead.
///
/// With `weights` that particle to grid left this step ([`PoreWeights`]), an element whose
/// saturated points share one material adds r_e W_ek and W_ek to its nodes without reading its
/// points (the same W_ek, the rate's products summed once instead of point by point: the
/// bits of before with one point per element); the others go point by point.
#[allow(clippy::too_many_arguments)]
pub fn update_pore_pressure<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &mut Slots<R>,
    mesh: &Mesh<E, R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fluids: &[Option<Fluid<R>>],
    smooth: bool,
    smoothing: Option<&StrainSmoothing<R>>,
    weights: Option<&mut PoreWeights<R>>,
    dt: R,
) -> bool {
    let (Some(lp), Some(gl)) = (&mut p.liquid, &mut g.liquid) else {
        return false;
    };
    // This step's weights, taken once; a section's rate differs from point to point (its hoop
    // rate), so it always goes point by point.
    let weights = weights
        .filter(|w| w.fresh && w.weights.len() == mesh.elements() && !E::AXISYMMETRIC)
        .map(|w| {
            w.fresh = false;
            &*w
        });
    if let Some(sm) = smoothing {
        let pressure = Shared::new(&mut lp.p);
        let (active, material, element) = (&p.active, &p.material, &p.element);
        team.run(|t| {
            for i in layout.particle_range(t) {
                if let (true, Some(f)) = (active[i], &fluids[material[i] as usize]) {
                    let [es, ew] = sm.element_mean(mesh, element[i] as usize, material[i]);
                    // SAFETY: particle i belongs to this thread only.
                    unsafe {
                        pressure.range(i..i + 1)[0] +=
                            f.kw_over_n * (f.n * ew + (R::ONE - f.n) * es)
                    };
                }
            }
        });
        return false;
    }
    let (x, volume, active, material) = (&p.x, &p.volume, &p.active, &p.material);
    let (vel, wvel) = (&g.vel, &gl.vel);
    let pressure = Shared::new(&mut lp.p);
    if !smooth {
        team.run(|t| {
            for i in layout.particle_range(t) {
                if let (true, Some(f)) = (active[i], &fluids[material[i] as usize]) {
                    let e = p.element[i] as usize;
                    let nodal = NodalVelocities::of(mesh, vel, wvel, e);
                    let rate = if E::AXISYMMETRIC {
                        let n = mesh.shape(e, &x[i]);
                        nodal.rate(f, |k| n.as_ref()[k], x[i][0])
                    } else {
                        nodal.rate(f, |_| R::ZERO, R::ONE)
                    };
                    // SAFETY: particle i belongs to this thread only.
                    unsafe { pressure.range(i..i + 1)[0] += rate * dt };
                }
            }
        });
        return false;
    }
    let wide = use_avx2();
    let pass = RatePass {
        mesh,
        x,
        volume,
        active,
        material,
        fluids,
        vel,
        wvel,
        weights,
        four: if wide || cfg!(target_feature = "avx2") {
            R::Four::token()
        } else {
            None
        },
    };
    // Each copy ([`crate::parallel::avx2`]) with a closure of its own, so that `rate_sums` is
    // inlined into it and compiled with its instruction set.
    if wide {
        layout.scatter_with::<2, true, true, (), _>(
            team,
            slots,
            |_| (),
            |e, points, two, _| rate_sums::<E, R, true>(&pass, e, points, two),
        );
    } else {
        layout.scatter_with::<2, false, true, (), _>(
            team,
            slots,
            |_| (),
            |e, points, two, _| rate_sums::<E, R, false>(&pass, e, points, two),
        );
    }
    let nodal = Shared::new(&mut gl.rate);
    layout.gather::<2, _>(team, slots, |n, s| {
        let r = if s[1] > R::ZERO { s[0] / s[1] } else { R::ZERO };
        // SAFETY: node n is this thread's only.
        unsafe { nodal.write(n, r) };
    });
    // The points take their rate in the stress pass ([`PoreRate`]).
    true
}

/// Both phases' velocities at an element's nodes and their divergences in it (one per
/// element for linear elements): what a saturated point's pore-pressure rate needs.
struct NodalVelocities<E: Element, R: Real> {
    /// The solid's nodal velocities.
    vel: E::Nodes<V3<R>>,
    /// The liquid's nodal velocities.
    wvel: E::Nodes<V3<R>>,
    /// ∇·v of the solid and of the liquid.
    div: (R, R),
}

impl<E: Element, R: Real> NodalVelocities<E, R> {
    /// Element `e`'s, from the nodal velocities `vel` (solid) and `wvel` (liquid).
    #[inline(always)]
    fn of(mesh: &Mesh<E, R>, vel: &[V3<R>], wvel: &[V3<R>], e: usize) -> Self {
        let (grad, corners) = (mesh.grad[e].as_ref(), mesh.corners[e].as_ref());
        let vel = E::nodes(|k| vel[corners[k] as usize]);
        let wvel = E::nodes(|k| wvel[corners[k] as usize]);
        let (mut div_v, mut div_w) = (R::ZERO, R::ZERO);
        for k in 0..E::NODES {
            let (v, w) = (vel.as_ref()[k], wvel.as_ref()[k]);
            for a in 0..E::DIM {
                div_v += v[a] * grad[k][a];
                div_w += w[a] * grad[k][a];
            }
        }
        NodalVelocities {
            vel,
            wvel,
            div: (div_v, div_w),
        }
    }

    /// The pore-pressure rate (K_w / n)(n ∇·w + (1 - n) ∇·v) of a point of liquid `f`, plus, in
    /// an axisymmetric section, each phase's hoop rate u_r / r at the point from its shape
    /// values `n` and radius `r` (neither read otherwise).
    #[inline(always)]
    fn rate(&self, f: &Fluid<R>, n: impl Fn(usize) -> R, r: R) -> R {
        let (mut div_v, mut div_w) = self.div;
        if E::AXISYMMETRIC {
            let (vel, wvel) = (self.vel.as_ref(), self.wvel.as_ref());
            for k in 0..E::NODES {
                div_v += n(k) * vel[k][0] / r;
                div_w += n(k) * wvel[k][0] / r;
            }
        }
        f.kw_over_n * (f.n * div_w + (R::ONE - f.n) * div_v)
    }
}

/// What [`rate_sums`] reads: the points, the mesh and both phases' nodal velocities.
struct RatePass<'a, E: Element, R: Real> {
    mesh: &'a Mesh<E, R>,
    x: &'a [V3<R>],
    volume: &'a [R],
    active: &'a [bool],
    material: &'a [u32],
    fluids: &'a [Option<Fluid<R>>],
    vel: &'a [V3<R>],
    wvel: &'a [V3<R>],
    /// The weights particle to grid left this step, where it did.
    weights: Option<&'a PoreWeights<R>>,
    /// Where the pass runs its AVX2 copy (or a build for AVX2): the token of [`Real::Four`]'s
    /// instructions.
    four: Option<<R::Four as Four<R>>::Token>,
}

/// Element `e`'s two sums per node for the smoothed pore-pressure rate: Σ V N r and Σ V N over
/// its saturated active points (r the point's rate), into `two` (zero on entry; 2 values per
/// node). The shape values go in batches of the element's points ([`Batch`]: four in
/// tetrahedra, one in triangles), each point's arithmetic as a point-by-point loop does it,
/// and the sums are added point by point in order, in registers, from 0: the bits of adding
/// into the slots in place.
///
/// In the AVX2 copy (`WIDE`) a tetrahedron's sums are four-lane vectors, one lane per node
/// ([`rate_lane_sums`]): the same operations in the same order, so the same bits.
#[inline(always)]
fn rate_sums<E: Element, R: Real, const WIDE: bool>(
    cx: &RatePass<'_, E, R>,
    e: usize,
    points: Range<usize>,
    two: &mut [R],
) {
    if points.is_empty() {
        return;
    }
    let mesh = cx.mesh;
    let weights = cx.weights.map(|w| (w.material[e], &w.weights[e]));
    // No saturated point: nothing to add, and no nodes to read.
    if let Some((pore_weights::NO_POINTS, _)) = weights {
        two.fill(R::ZERO);
        return;
    }
    let nodal = NodalVelocities::of(mesh, cx.vel, cx.wvel, e);
    // Saturated points of one material (`MIXED` names none, and goes point by point below):
    // the element's rate once, none of its points read.
    if let Some((m, w)) = weights {
        if let Some(f) = cx.fluids.get(m as usize).and_then(Option::as_ref) {
            let rate = nodal.rate(f, |_| R::ZERO, R::ONE);
            // (0 + W r: from zero as the point-by-point sum, so that one point gives its bits,
            // the sign of a zero included.)
            for (slot, &wk) in node_slots::<E, R>(two, 2).zip(w) {
                slot[0] = R::ZERO + wk * rate;
                slot[1] = wk;
            }
            return;
        }
    }
    let corners = mesh.corners[e].as_ref();
    let first = &mesh.x[corners[0] as usize];
    let map = &mesh.map[e];
    // The element's points, sliced once: the loop indexes them without bounds checks.
    let (x, volume) = (&cx.x[points.clone()], &cx.volume[points.clone()]);
    let end = x.len();
    let (active, material) = (
        &cx.active[points.clone()][..end],
        &cx.material[points][..end],
    );
    let volume = &volume[..end];
    if E::DIM == 3 && !E::AXISYMMETRIC {
        if let Some(t) = cx.four.filter(|_| WIDE || cfg!(target_feature = "avx2")) {
            let points = RatePoints {
                x,
                volume,
                active,
                material,
            };
            let [s0, s1] = rate_lane_sums::<E, R>(t, cx, &nodal, map, first, &points);
            // The four nodes' slots of two, one after another: node k's (s0, s1) is lanes k.
            debug_assert_eq!(node_slots::<E, R>(two, 2).len(), 4);
            let pairs: &mut [R; 8] = two.try_into().expect("a tetrahedron's four slots of two");
            R::Four::store_pairs(s0, s1, pairs);
            return;
        }
    }
    let mut sums = [[R::ZERO; 2]; 4];
    let mut j = 0;
    macro_rules! batches {
        ($w:expr) => {{
            const W: usize = $w;
            while j < end {
                let b = match Batch::<W>::new(j, end, |i| {
                    active[i] && cx.fluids[material[i] as usize].is_some()
                }) {
                    Ok(b) => b,
                    Err(skip) => {
                        j += skip;
                        continue;
                    }
                };
                let n = E::shape_lanes(map, first, &b.gather(x));
                for i in b.points() {
                    let q = i - j;
                    let Some(f) = &cx.fluids[material[i] as usize] else {
                        continue;
                    };
                    let rate = nodal.rate(f, |k| n[k][q], x[i][0]);
                    for (k, s) in sums.iter_mut().enumerate().take(E::NODES) {
                        s[0] += volume[i] * n[k][q] * rate;
                        s[1] += volume[i] * n[k][q];
                    }
                }
                j += b.len;
            }
        }};
    }
    // Tetrahedra take their points side by side as particle to grid's shape values do; a
    // triangle's three go one by one (as in the other point passes, docs/design.md §5.3).
    if E::DIM == 3 {
        batches!(TETRAHEDRA)
    } else {
        batches!(1)
    }
    for (slot, s) in node_slots::<E, R>(two, 2).zip(sums) {
        slot.copy_from_slice(&s);
    }
}

/// An element's points for [`rate_lane_sums`], each array sliced to them (one length).
struct RatePoints<'a, R: Real> {
    x: &'a [V3<R>],
    volume: &'a [R],
    active: &'a [bool],
    material: &'a [u32],
}

/// [`rate_sums`] of a tetrahedron as four-lane vectors, one lane per node: Σ V N r and Σ V N.
/// The shape values of four points at a time, one lane per point, turned into one lane per
/// node for each point by a transpose (each point's own bits, as particle to grid takes
/// them); each point's V N and V N r added point by point in order, from zero, as the point
/// loop adds them.
#[inline(always)]
fn rate_lane_sums<E: Element, R: Real>(
    t: <R::Four as Four<R>>::Token,
    cx: &RatePass<'_, E, R>,
    nodal: &NodalVelocities<E, R>,
    map: &E::Map<R>,
    first: &V3<R>,
    p: &RatePoints<'_, R>,
) -> [R::Four; 2] {
    let count = p.x.len();
    let (x, volume) = (p.x, &p.volume[..count]);
    let (active, material) = (&p.active[..count], &p.material[..count]);
    let splat = |v: R| R::Four::splat(t, v);
    let (mut s0, mut s1) = (splat(R::ZERO), splat(R::ZERO));
    // The rate of the last material seen (one per material in a linear element): formed again
    // only where the material changes, to the same bits.
    let mut last: Option<(u32, R::Four)> = None;
    let mut j = 0;
    while j < count {
        let live = (count - j).min(4);
        let per_point = node_lane_shapes::<E, R>(t, map, first, x, j, live);
        for (i, &n) in (j..j + live).zip(per_point.iter()) {
            if !active[i] {
                continue;
            }
            let rate = match last {
                Some((m, r)) if m == material[i] => r,
                _ => {
                    let Some(f) = &cx.fluids[material[i] as usize] else {
                        continue;
                    };
                    let r = splat(nodal.rate(f, |_| R::ZERO, R::ONE));
                    last = Some((material[i], r));
                    r
                }
            };
            let vn = splat(volume[i]) * n;
            s0 = s0 + vn * rate;
            s1 = s1 + vn;
        }
        j += live;
    }
    [s0, s1]
}

/// Adds Ω σ - σ Ω to `s` for the skew increment Ω with Ω_xy = `w[0]`, Ω_yz = `w[1]`, Ω_zx = `w[2]`
/// (Ω_yx = `-w[0]` etc.): the Jaumann co-rotation of the stress over one step.
#[inline]
pub fn rotate<R: Real>(s: &mut [R; 6], w: &[R; 3]) {
    let r = rotation(s, w);
    for (s, r) in s.iter_mut().zip(r) {
        *s += r;
    }
}

/// The co-rotation Ω σ - σ Ω of `s` (xx yy zz xy yz zx) for the spin increment `w`
/// (ω_xy, ω_yz, ω_zx).
pub fn rotation<R: Real>(s: &[R; 6], w: &[R; 3]) -> [R; 6] {
    rotation_lanes(&s.map(|v| [v]), w).map(|[v]| v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ω σ - σ Ω by full 3×3 products.
    fn reference(s: &[f64; 6], w: &[f64; 3]) -> [f64; 6] {
        let m = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
        let o = [[0.0, w[0], -w[2]], [-w[0], 0.0, w[1]], [w[2], -w[1], 0.0]];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    r[i][j] += o[i][k] * m[k][j] - m[i][k] * o[k][j];
                }
            }
        }
        [r[0][0], r[1][1], r[2][2], r[0][1], r[1][2], r[2][0]]
    }

    #[test]
    fn jaumann_rotation_matches_matrix_products() {
        let s0 = [1.0, -2.0, 3.5, 0.25, -0.75, 1.5];
        let w = [0.01, -0.02, 0.03];
        let mut s = s0;
        rotate(&mut s, &w);
        let r = reference(&s0, &w);
        for c in 0..6 {
            assert!((s[c] - s0[c] - r[c]).abs() < 1e-15, "component {c}");
        }
        // A rotation leaves the trace unchanged.
        assert!(((s[0] + s[1] + s[2]) - (s0[0] + s0[1] + s0[2])).abs() < 1e-15);
    }
}
