//! One element's turn in particle to grid ([`element_sums`]): an element without points, the
//! mixed rule's element sums and Gauss point, and the walk over its points in node lanes.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::four::Four;
use crate::input::case::MixedRule;
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::state::particles::{LiquidPoints, Particles};
use crate::state::pore_weights;
use crate::step::contact::{maps, OneBody};

use super::arrays::{PointArrays, Points};
use super::lanes::node_lane_sums;
use super::totals::{traction, Sums};
use super::{node_lane_sums_avx2, LiquidLoads};

/// The mixed rule's per-element outputs (mean stresses, full flags, mean pore pressures) and
/// inputs (the filling degree, the rule and its boundary points).
pub(super) struct MixedOut<'a, R: Real> {
    pub stress: Shared<'a, [R; 6]>,
    pub full: Shared<'a, bool>,
    pub pressure: Shared<'a, R>,
    pub filling: R,
    pub rule: MixedRule,
    pub boundary: &'a [bool],
}

/// What one element's pass reads (and, through the mixed rule's and the pore-pressure rate's
/// slices, writes).
pub(super) struct Pass<'a, E: Element, R: Real> {
    pub mesh: &'a Mesh<E, R>,
    pub p: &'a Particles<R>,
    pub gravity: &'a [V3<R>],
    pub mixed: Option<MixedOut<'a, R>>,
    /// Where the liquid's pass leaves each element's weights of the pore-pressure rate, and
    /// the material of its saturated points.
    pub pore_weights: Option<(Shared<'a, [R; 4]>, Shared<'a, u32>)>,
    pub liquid: Option<(LiquidLoads<'a, R>, &'a LiquidPoints<R>)>,
    pub body: Option<OneBody>,
    /// The points' arrays, of one length.
    pub arrays: PointArrays<'a, R>,
}

/// Element `e`'s sums into `four` ([`super::particle_to_grid`]): the solid's, and the liquid's
/// with `WITH_LIQUID` (the dry variant compiles without the liquid's code), in lanes `F` (with
/// `WIDE`, in the scatter's AVX2 copy, through [`node_lane_sums_avx2`]).
#[inline(always)]
pub(super) fn element_sums<E, R, F, const WITH_LIQUID: bool, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    t: F::Token,
    e: usize,
    range: std::ops::Range<usize>,
    four: &mut [R],
) where
    E: Element,
    R: Real,
    F: Four<R>,
{
    // An element without points: its buffer holds zeros already, which the sums would store
    // ([`crate::parallel::gather::Layout::scatter`]), and under mixed integration its outputs
    // are those of no points (not full, zero means), so it returns before reading the element
    // (most of a void mesh's elements take this path at every step). (The test is of an opaque
    // copy of the count: the loops below, compiled knowing the count is not zero, took more
    // instructions per point.)
    if std::hint::black_box(range.len()) == 0 {
        leave_empty(cx, e);
        return;
    }
    let g = gradient_lanes::<E, R, F>(t, cx.mesh.grad[e].as_ref());
    // The points of the element's first point's material take their weight as g Σ m N_k,
    // formed once ([`super::totals::Totals`]); any other's, point by point with its own g.
    let lead = cx.arrays.material[range.start];
    let (full, start) = match &cx.mixed {
        Some(m) => gauss_point::<E, R, F, WITH_LIQUID>(cx, m, t, e, range.clone(), &g, lead),
        None => (false, None),
    };
    // The element's points, every array sliced to them once (one length, one check), so that
    // the loops index without bounds checks.
    let arrays = cx.arrays.element(range);
    let liquid = cx
        .liquid
        .filter(|_| WITH_LIQUID)
        .and_then(|(loads, _)| arrays.w.map(|w| (loads, w, arrays.volume0)));
    let corners = cx.mesh.corners[e].as_ref();
    let points = Points {
        arrays,
        liquid,
        map: &cx.mesh.map[e],
        first: &cx.mesh.x[corners[0] as usize],
        gravity: cx.gravity,
        body: cx.body,
        full,
    };
    let start = start.as_ref();
    let rate = if WIDE {
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in the scatter's AVX2 copy, which asserts that the processor
        // has AVX2.
        unsafe { node_lane_sums_avx2::<E, R, F, WITH_LIQUID>(t, &points, start, lead, &g, four) }
    } else {
        node_lane_sums::<E, R, F, WITH_LIQUID>(t, &points, start, lead, &g, four)
    };
    leave_pore_weights(cx, e, rate);
}

/// The element's gradients by component as lanes, `[b]` lane k = ∂N_k/∂x_b, zero past its
/// nodes.
#[inline(always)]
fn gradient_lanes<E: Element, R: Real, F: Four<R>>(t: F::Token, grad: &[V3<R>]) -> [F; 3] {
    let by_component: [[R; 4]; 3] = std::array::from_fn(|b| {
        std::array::from_fn(|k| if k < E::NODES { grad[k][b] } else { R::ZERO })
    });
    // (A loop, not `from_fn`: the intrinsics in its closure would become calls.)
    let mut g = [F::splat(t, R::ZERO); 3];
    for (gb, b) in g.iter_mut().zip(&by_component) {
        *gb = F::load(t, b);
    }
    g
}

/// An element without points: under mixed integration not full, with zero means; no
/// saturated points for the pore-pressure rate.
#[inline(always)]
fn leave_empty<E: Element, R: Real>(cx: &Pass<'_, E, R>, e: usize) {
    if let Some((weights, material)) = &cx.pore_weights {
        // SAFETY: element e is this thread's only.
        unsafe {
            weights.write(e, [R::ZERO; 4]);
            material.write(e, pore_weights::NO_POINTS);
        }
    }
    if let Some(m) = &cx.mixed {
        // SAFETY: element e is this thread's only.
        unsafe {
            m.stress.write(e, [R::ZERO; 6]);
            m.full.write(e, false);
            m.pressure.write(e, R::ZERO);
        }
    }
}

/// Mixed integration: whether element e (its points `range`) is full, its mean stress and pore
/// pressure left for the step's end ([`crate::step::mixed`]); and the sums its points start
/// from: a full element's Gauss-point forces (the internal force of its mean total stress on
/// its volume, where its points are of the body mapped; in the liquid's pass, the pore
/// pressure's), `None` where it has none.
#[inline(always)]
fn gauss_point<E, R, F, const WITH_LIQUID: bool>(
    cx: &Pass<'_, E, R>,
    m: &MixedOut<'_, R>,
    t: F::Token,
    e: usize,
    range: std::ops::Range<usize>,
    g: &[F; 3],
    lead: u32,
) -> (bool, Option<Sums<R, F>>)
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let p = cx.p;
    let (mut v, mut s, mut pm, mut qm) = (R::ZERO, [R::ZERO; 6], R::ZERO, R::ZERO);
    for i in range.clone() {
        if p.active[i] {
            v += p.volume[i];
            for c in 0..6 {
                s[c] += p.volume[i] * p.stress[i][c];
            }
            if let Some(l) = &p.liquid {
                pm += p.volume[i] * l.p[i];
            }
            if let Some(b) = &p.bulk {
                qm += p.volume[i] * b.pressure[i];
            }
        }
    }
    let ve = cx.mesh.volume[e];
    let full = crate::step::mixed::is_full(m.rule, m.boundary, m.filling, p, range.clone(), v, ve);
    if full {
        for c in s.iter_mut() {
            *c /= v;
        }
        pm /= v;
        qm /= v;
    }
    // SAFETY: element e is this thread's only.
    unsafe {
        m.stress.write(e, s);
        m.full.write(e, full);
        m.pressure.write(e, pm);
    }
    let ours = range
        .clone()
        .find(|&i| p.active[i])
        .is_some_and(|i| maps(cx.body, p.material[i]));
    if !full || !(ours || WITH_LIQUID) {
        return (full, None);
    }
    let mut sums = Sums::zero(t, lead);
    if ours {
        // The Gauss point's total stress: effective plus pore pressure, and the points' mean
        // bulk viscous pressure (Anura3D averages it over a full element as the stresses).
        let mut s = s;
        if p.liquid.is_some() {
            for c in s.iter_mut().take(3) {
                *c += pm;
            }
        }
        if p.bulk.is_some() {
            for c in s.iter_mut().take(3) {
                *c += qm;
            }
        }
        for a in 0..E::DIM {
            let f = traction::<E, R, F>(t, &s, g, a);
            sums.solid[1 + E::DIM + a] = sums.solid[1 + E::DIM + a] - F::splat(t, ve) * f;
        }
    }
    // A full element takes its pore-pressure force at the Gauss point too (its volume times
    // the mean pore pressure).
    if WITH_LIQUID {
        let vp = F::splat(t, ve * pm);
        for a in 0..E::DIM {
            sums.liquid[3 + E::DIM + a] = sums.liquid[3 + E::DIM + a] - vp * g[a];
        }
    }
    (full, Some(sums))
}

/// Leaves element `e`'s weights of the pore-pressure rate, `(Σ V N_k, material)` of its
/// saturated points, where the pass was asked for them.
#[inline(always)]
fn leave_pore_weights<E: Element, R: Real>(cx: &Pass<'_, E, R>, e: usize, rate: ([R; 4], u32)) {
    if let Some((weights, material)) = &cx.pore_weights {
        // SAFETY: element e is this thread's only.
        unsafe {
            weights.write(e, rate.0);
            material.write(e, rate.1);
        }
    }
}
