//! Grid to particle, MUSL: FLIP velocity update, then momentum re-mapped to the nodes for the
//! velocities that drive strain, stress, volume and position (docs/design.md §4, step 3), on the team.

use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::tri3::Tri3;
use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{Layout, Slots, ELEMENT_BLOCK};
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::batch::{interpolate, lanes, store, Batch, Lanes, LANES, TETRAHEDRA};
use crate::step::contact::{maps, OneBody};
use crate::step::stress::GuardSums;

mod lanes;

/// What the liquid's share of grid to particle needs (two-phase cases): each material's fluid
/// (`None` for a dry material) and the liquid's fixities.
#[derive(Clone, Copy)]
pub struct LiquidRemap<'a, R: Real> {
    /// Per material, its fluid.
    pub fluids: &'a [Option<Fluid<R>>],
    /// Per node, the liquid's fixed components.
    pub fixed: &'a [[bool; 3]],
}

/// Updates particle velocities from nodal accelerations (FLIP; with `pic` > 0 blended with
/// the nodes' updated velocities, PIC), then re-maps momentum to get the nodal velocities
/// (fixed components and empty nodes zero) that drive strain, stress, volume and position
/// (see [`crate::step::stress`]). With `guard` (one slot per block of
/// [`crate::parallel::gather::ELEMENT_BLOCK`] elements), each block's slot is begun anew at its
/// first element and summed over its elements in order with their points' Σ m |v|² (twice
/// their kinetic energy), the velocities at hand. Only the points of `body` take part (all of
/// them for `None`; one body of a contact pair, [`crate::step::contact`]); the second body's
/// pass adds its kinetic energy to the slots the first began (`begin` false).
///
/// With `liquid` (a two-phase case), the same pass updates the liquid velocities of the points
/// of materials with a fluid from the nodal liquid accelerations (FLIP) and re-maps the liquid
/// momentum to nodal liquid velocities (zero in the liquid's fixed components and at empty
/// nodes); with `guard`, each block's slot then takes the liquid's n ρw V_w |w|² (twice its
/// kinetic energy) element by element after the solid's sums of the block, the order of a
/// liquid pass of its own. One pass computes each point's shape functions and reads its
/// position once for both phases. The liquid goes with every body (`body` `None`): contact
/// refuses saturated materials.
#[allow(clippy::too_many_arguments)]
pub fn grid_to_particle<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &mut Slots<R>,
    mesh: &Mesh<E, R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fixed: &[[bool; 3]],
    dt: R,
    pic: R,
    guard: Option<&mut [GuardSums]>,
    body: Option<OneBody>,
    begin: bool,
    liquid: Option<LiquidRemap<'_, R>>,
) {
    let liquid = liquid.filter(|_| p.liquid.is_some() && g.liquid.is_some());
    debug_assert!(
        liquid.is_none() || body.is_none(),
        "the liquid re-mapped with one body of a contact pair"
    );
    let guard = guard.map(Shared::new);
    let vel = Shared::new(&mut p.v);
    let (x, mass, active, material, volume) = (&p.x, &p.mass, &p.active, &p.material, &p.volume);
    let (liquid_vel, volume0) = match &mut p.liquid {
        Some(lp) => (Some(Shared::new(&mut lp.w)), lp.volume0.as_deref()),
        None => (None, None),
    };
    let liquid_acc = g.liquid.as_ref().map(|gl| &gl.acc[..]);
    let (acc, momentum, node_mass, empty) = (&g.acc, &g.momentum, &g.mass, g.empty_below);
    let flip = R::ONE - pic;
    // Values per node of the re-map: the solid's momentum, then the liquid's.
    let width = |with_liquid: bool| if with_liquid { 2 * E::DIM } else { E::DIM };
    let elements = mesh.elements();
    // Each thread's elements in the baseline instruction set or, where the processor has it and
    // the build does not assume it, with AVX2 (the same bits): each variant's closure written
    // twice, one for each scatter, so that each is inlined into its own.
    let wide = use_avx2();
    // One element's points; with `want`, their kinetic energy (solid, liquid). Two scatters
    // below, each with `want` fixed, so that the run without guards keeps the loop it had
    // without them.
    // One element's points, written once and expanded for each variant (`want` the guard's
    // kinetic sums, `with_liquid` the liquid's share), constants in each, so that every
    // variant compiles without the code it does not need and, with one caller, is inlined
    // into its scatter (one closure for four variants was left a call, its re-map width a
    // value at run time).
    // Where the AVX2 copy (or a build that assumes AVX2) takes an element's points in
    // explicit four-lane vectors ([`lanes`]; FLIP only: the PIC blend goes point by point).
    let lane_token = if (wide || cfg!(target_feature = "avx2")) && pic == R::ZERO {
        R::Four::token()
    } else {
        None
    };
    macro_rules! element_pass {
        ($want:literal, $with_liquid:literal, $w:expr, $wide:literal) => {
            |e: usize, range: std::ops::Range<usize>, four: &mut [R]| {
                const W: usize = $w;
                let (want, with_liquid): (bool, bool) = ($want, $with_liquid);
                let (mut kinetic, mut kinetic_w) = (0.0, 0.0);
                // The element's points, each array sliced to them once (one length): the loop then
                // indexes without bounds checks.
                let count = range.len();
                // An element without points adds nothing (the scatter's contract).
                if count == 0 {
                    return (kinetic, kinetic_w);
                }
                let (x, mass, active, material) = (
                    &x[range.clone()][..count],
                    &mass[range.clone()][..count],
                    &active[range.clone()][..count],
                    &material[range.clone()][..count],
                );
                // SAFETY: the points of element e belong to this thread only.
                let vel = unsafe { &mut vel.range(range.clone())[..count] };
                // SAFETY: as above.
                let mut w_pts = liquid_vel
                    .as_ref()
                    .filter(|_| with_liquid)
                    .map(|w| unsafe { &mut w.range(range.clone())[..count] });
                // The element's points in batches of `W`, each value held across the batch's
                // points (`[c][q]`: value c of point q), so that shape values, interpolation and
                // the velocity update are operations over the points; each point's arithmetic
                // is a point-by-point loop's, in the same order (the same bits whatever the
                // width), and each point's sums follow in point order.
                let corners = mesh.corners[e].as_ref();
                let first = &mesh.x[corners[0] as usize];
                let map = &mesh.map[e];
                let acc_e = E::nodes(|k| acc[corners[k] as usize]);
                let acc_e = acc_e.as_ref();
                // The liquid's, likewise.
                let acc_w_e = liquid_acc
                    .filter(|_| with_liquid)
                    .map(|a| E::nodes(|k| a[corners[k] as usize]));
                // The element's re-mapped momenta (the solid's, then the liquid's), value by
                // value across its nodes, stored into `four` at the end.
                let mut sums: Lanes<R, 6> = [[R::ZERO; LANES]; 6];
                let mut j = 0;
                // The points in four-lane vectors as far as they go (all of them, commonly),
                // the point loop below from where they stop.
                if let Some(t) = lane_token.filter(|_| $wide || cfg!(target_feature = "avx2")) {
                    let points = lanes::ElementPoints::<E, R> {
                        x,
                        mass,
                        active,
                        material,
                        vel: &mut *vel,
                        liquid: match (liquid, w_pts.as_deref_mut(), acc_w_e.as_ref()) {
                            (Some(l), Some(w), Some(a)) if with_liquid => {
                                Some(lanes::LiquidPoints {
                                    w,
                                    volume: &volume[range.clone()],
                                    volume0: volume0.map(|v0| &v0[range.clone()]),
                                    fluids: l.fluids,
                                    acc: a.as_ref(),
                                })
                            }
                            _ => None,
                        },
                        map,
                        first,
                        acc: acc_e,
                    };
                    debug_assert!(crate::parallel::avx2::present());
                    // SAFETY: `$wide` only in the scatter's AVX2 copy, which runs where the
                    // processor has AVX2; a build that assumes AVX2 runs only where it has it.
                    j = unsafe {
                        element_lanes_avx2::<E, R, $want, $with_liquid>(
                            t,
                            body,
                            dt,
                            points,
                            &mut sums,
                            &mut *four,
                            &mut kinetic,
                            &mut kinetic_w,
                        )
                    };
                }
                let stored = lanes::stores_sums(j, count);
                while j < count {
                    let b =
                        match Batch::<W>::new(j, count, |i| active[i] && maps(body, material[i])) {
                            Ok(b) => b,
                            Err(skip) => {
                                j += skip;
                                continue;
                            }
                        };
                    let nl = E::shape_lanes(map, first, &b.gather(x));
                    // Σ N_k a_k, node by node.
                    let dv = interpolate::<E, R, W>(&nl, acc_e);
                    let mut vl = b.gather(vel);
                    for c in 0..E::DIM {
                        for q in 0..W {
                            vl[c][q] += dt * dv[c][q];
                        }
                    }
                    // The liquid's Σ N_k a_w,k (used by the points with a fluid).
                    let dwl = acc_w_e.as_ref().map_or([[R::ZERO; W]; 3], |aw| {
                        interpolate::<E, R, W>(&nl, aw.as_ref())
                    });
                    for i in b.points() {
                        let q = i - j;
                        let nq: [R; 4] = std::array::from_fn(|k| nl[k][q]);
                        let n = &nq[..E::NODES];
                        let v = &mut vel[i];
                        for c in 0..E::DIM {
                            v[c] = vl[c][q];
                        }
                        if pic > R::ZERO {
                            // The nodes' velocities after the step, v + a Δt (zero where fixed or
                            // empty).
                            let mut grid_v = [R::ZERO; 3];
                            for (k, &nk) in n.iter().enumerate().take(E::NODES) {
                                let node = corners[k] as usize;
                                let mass_n = node_mass[node];
                                if mass_n <= empty {
                                    continue;
                                }
                                for c in 0..E::DIM {
                                    if !fixed[node][c] {
                                        let v_n = momentum[node][c] / mass_n + dt * acc[node][c];
                                        grid_v[c] += nk * v_n;
                                    }
                                }
                            }
                            for c in 0..E::DIM {
                                v[c] = flip * v[c] + pic * grid_v[c];
                            }
                        }
                        // Node by node the operations of a loop over the nodes.
                        let w = lanes::<E, R>(|k| mass[i] * n[k]);
                        for c in 0..E::DIM {
                            for k in 0..LANES {
                                sums[c][k] += w[k] * v[c];
                            }
                        }
                        if want {
                            kinetic += (mass[i] * dot::<E, R>(v, v)).f64();
                        }
                        // The liquid of the point, if its material has one.
                        if !with_liquid {
                            continue;
                        }
                        let (Some(l), Some(w_pts), Some(_)) =
                            (liquid, w_pts.as_mut(), acc_w_e.as_ref())
                        else {
                            continue;
                        };
                        let Some(f) = l.fluids[material[i] as usize] else {
                            continue;
                        };
                        let dw: [R; 3] = std::array::from_fn(|c| dwl[c][q]);
                        let w = &mut w_pts[i];
                        for c in 0..E::DIM {
                            w[c] += dt * dw[c];
                        }
                        // The same liquid mass as particle to grid mapped (see
                        // `LiquidPoints::volume0`).
                        let g = range.start + i;
                        let mw = f.rho_w * volume0.map_or(volume[g], |v0| v0[g]);
                        let wl = lanes::<E, R>(|k| mw * n[k]);
                        for c in 0..E::DIM {
                            for k in 0..LANES {
                                sums[E::DIM + c][k] += wl[k] * w[c];
                            }
                        }
                        if want {
                            kinetic_w += (f.n * mw * dot::<E, R>(w, w)).f64();
                        }
                    }
                    j += b.len;
                }
                if !stored {
                    let width = width(with_liquid);
                    store::<E, R, 6>(&sums, four, width, 0, width);
                }
                (kinetic, kinetic_w)
            }
        };
    }
    // The liquid's kinetic sums of the block's elements so far, added to the block's slot
    // after its last element (after the solid's sums of the block).
    let init = |_| [0.0f64; ELEMENT_BLOCK];
    // The guarded variants: each element's kinetic sums into its block's slot, the liquid's
    // after the block's last element.
    macro_rules! guarded_pass {
        ($guard:expr, $with_liquid:literal, $w:expr, $wide:literal) => {
            |e: usize,
             range: std::ops::Range<usize>,
             four: &mut [R],
             pending: &mut [f64; ELEMENT_BLOCK]| {
                let element = element_pass!(true, $with_liquid, $w, $wide);
                let (kinetic, kinetic_w) = element(e, range, four);
                let b = e / ELEMENT_BLOCK;
                // SAFETY: the scatter hands element e to one thread only, once, in element
                // order, and its pieces hold whole blocks: no other thread touches block b,
                // and its first element comes first.
                let slot = unsafe { &mut $guard.range(b..b + 1)[0] };
                if begin && e % ELEMENT_BLOCK == 0 {
                    *slot = GuardSums {
                        kinetic,
                        ..GuardSums::EMPTY
                    };
                } else {
                    slot.kinetic += kinetic;
                }
                if $with_liquid {
                    pending[e % ELEMENT_BLOCK] = kinetic_w;
                    if e % ELEMENT_BLOCK == ELEMENT_BLOCK - 1 || e + 1 == elements {
                        for &k in &pending[..=e % ELEMENT_BLOCK] {
                            slot.kinetic += k;
                        }
                    }
                }
            }
        };
    }
    // Each variant with the batch width of the element type ([`TETRAHEDRA`]) and at its re-map
    // width (a literal, so that each closure has one caller: the solid's 3 or 2 values per
    // node, then as many for the liquid), once for each instruction set.
    macro_rules! run {
        (None, $with_liquid:literal, $w:expr, $width:literal) => {{
            debug_assert_eq!(width($with_liquid), $width);
            if wide {
                let element = element_pass!(false, $with_liquid, $w, true);
                layout.scatter_with::<$width, true, true, _, _>(team, slots, init, |e, r, f, _| {
                    element(e, r, f);
                })
            } else {
                let element = element_pass!(false, $with_liquid, $w, false);
                layout.scatter_with::<$width, false, true, _, _>(team, slots, init, |e, r, f, _| {
                    element(e, r, f);
                })
            }
        }};
        ($g:expr, $with_liquid:literal, $w:expr, $width:literal) => {{
            debug_assert_eq!(width($with_liquid), $width);
            if wide {
                let element = guarded_pass!($g, $with_liquid, $w, true);
                layout.scatter_with::<$width, true, true, _, _>(team, slots, init, element)
            } else {
                let element = guarded_pass!($g, $with_liquid, $w, false);
                layout.scatter_with::<$width, false, true, _, _>(team, slots, init, element)
            }
        }};
    }
    const { assert!(Tet4::DIM == 3 && Tri3::DIM == 2) };
    let tetrahedra = E::DIM == 3;
    match (&guard, liquid.is_some(), tetrahedra) {
        (None, false, true) => run!(None, false, TETRAHEDRA, 3),
        (None, false, false) => run!(None, false, 1, 2),
        (None, true, true) => run!(None, true, TETRAHEDRA, 6),
        (None, true, false) => run!(None, true, 1, 4),
        (Some(g), false, true) => run!(g, false, TETRAHEDRA, 3),
        (Some(g), false, false) => run!(g, false, 1, 2),
        (Some(g), true, true) => run!(g, true, TETRAHEDRA, 6),
        (Some(g), true, false) => run!(g, true, 1, 4),
    }
    nodal_velocity(
        team,
        layout,
        slots,
        &g.mass,
        g.empty_below,
        fixed,
        &mut g.vel,
        g.liquid
            .as_mut()
            .filter(|_| liquid.is_some())
            .zip(liquid)
            .map(|(gl, l)| (&gl.mass[..], l.fixed, &mut gl.vel[..])),
    );
}

/// [`lanes::element_lanes`] compiled with AVX2 (a function of its own: inlined into the
/// scatter's element closure, the saturated pass's closure would grow past what the compiler
/// inlines into its AVX2 copy, as particle to grid's did).
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
#[allow(clippy::too_many_arguments)]
unsafe fn element_lanes_avx2<E: Element, R: Real, const WANT: bool, const WITH_LIQUID: bool>(
    t: <R::Four as Four<R>>::Token,
    body: Option<OneBody>,
    dt: R,
    points: lanes::ElementPoints<'_, E, R>,
    sums: &mut Lanes<R, 6>,
    four: &mut [R],
    kinetic: &mut f64,
    kinetic_w: &mut f64,
) -> usize {
    lanes::element_lanes::<E, R, WANT, WITH_LIQUID>(
        t, body, dt, points, sums, four, kinetic, kinetic_w,
    )
}

/// v · w over the element's dimensions.
#[inline(always)]
fn dot<E: Element, R: Real>(v: &V3<R>, w: &V3<R>) -> R {
    let mut s = R::ZERO;
    for c in 0..E::DIM {
        s += v[c] * w[c];
    }
    s
}

/// The velocity of a node of `mass` from its re-mapped `momentum`: zero at an empty node and in
/// fixed components.
#[inline(always)]
fn velocity<E: Element, R: Real>(
    momentum: &[R],
    mass: R,
    empty_below: R,
    fixed: &[bool; 3],
) -> V3<R> {
    let mut v = [R::ZERO; 3];
    if mass > empty_below {
        for c in 0..E::DIM {
            if !fixed[c] {
                v[c] = momentum[c] / mass;
            }
        }
    }
    v
}

/// A phase's nodal masses, fixities and velocities (the velocities written).
type PhaseNodes<'a, R> = (&'a [R], &'a [[bool; 3]], &'a mut [V3<R>]);

/// Nodal velocities from the re-mapped momentum in `slots`: zero at empty nodes and in fixed
/// components; with `liquid` (its nodal masses, fixities and velocities), the liquid's from the
/// values after the solid's.
#[allow(clippy::too_many_arguments)]
fn nodal_velocity<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &Slots<R>,
    mass: &[R],
    empty_below: R,
    fixed: &[[bool; 3]],
    vel: &mut [V3<R>],
    liquid: Option<PhaseNodes<'_, R>>,
) {
    let out = Shared::new(vel);
    let liquid = liquid.map(|(m, f, v)| (m, f, Shared::new(v)));
    let node = |n: usize, momentum: &[R]| {
        let v = velocity::<E, R>(momentum, mass[n], empty_below, &fixed[n]);
        // SAFETY: node n is this thread's only.
        unsafe { out.write(n, v) };
        if let Some((mass, fixed, out)) = &liquid {
            let w = velocity::<E, R>(&momentum[E::DIM..], mass[n], empty_below, &fixed[n]);
            // SAFETY: as above.
            unsafe { out.write(n, w) };
        }
    };
    match (E::DIM, liquid.is_some()) {
        (2, false) => layout.gather::<2, _>(team, slots, |n, m| node(n, &m)),
        (3, false) => layout.gather::<3, _>(team, slots, |n, m| node(n, &m)),
        (2, true) => layout.gather::<4, _>(team, slots, |n, m| node(n, &m)),
        _ => layout.gather::<6, _>(team, slots, |n, m| node(n, &m)),
    }
}
