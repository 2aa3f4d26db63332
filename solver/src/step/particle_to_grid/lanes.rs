//! An element's points walked for their sums in node lanes ([`node_lane_sums`]): each point's
//! weights formed and turned into one lane per node, its share added by [`point_sums`], the
//! element's totals closed and its sums stored into the scatter's buffer. The same walk in the
//! passes' four-lane copies ([`crate::four::Four`] vectors) and their portable ones (plain
//! arrays): the same operations in the same order, so the same bits.

use crate::element::Element;
use crate::four::Four;
use crate::real::{Real, V3};
use crate::state::pore_weights;
use crate::step::batch::{four_of, node_lane_shapes, store_nodes, usual_count, usual_of};
use crate::step::contact::maps;

use super::arrays::Points;
use super::point::point_sums;
use super::totals::Sums;
use super::{liquid_width, solid_width};

/// An element's sums over its points ([`super::element::element_sums`]), from `start` (a full
/// element's Gauss-point terms under mixed integration; zeros for `None`): each point's
/// contribution as lanes, one per node (a triangle's fourth lane carries zeros and is never
/// stored), added point by point in order. `lead`: the material whose points' weight is
/// formed once ([`super::totals::Totals`]); `g[b]`: the element's ∂N_k/∂x_b by node. The sums
/// are stored from their lanes into the scatter's buffer `four` ([`store_nodes`]). Returns the
/// saturated points' Σ V N_k and their material (formed where the pass leaves the
/// pore-pressure rate's weights).
#[inline(always)]
pub(super) fn node_lane_sums<E, R, F, const WITH_LIQUID: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    start: Option<&Sums<R, F>>,
    lead: u32,
    g: &[F; 3],
    four: &mut [R],
) -> ([R; 4], u32)
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    // Every array cut to the element's points again (one length), so that `point_sums`
    // indexes them without bounds checks.
    let points = &points.cut();
    let mut sums = match start {
        Some(s) => *s,
        None => Sums::zero(t, lead),
    };
    // Whether points of the lead material took part through the paths that skip each point's
    // checks (`OF_LEAD`), whose material the totals then take once, below.
    let lead_took_part = if E::DIM == 2 {
        triangle_points::<E, R, F, WITH_LIQUID>(t, points, &mut sums)
    } else {
        tetrahedron_points::<E, R, F, WITH_LIQUID>(t, points, &mut sums)
    };
    let liquid_gravity = points.liquid.map(|(loads, _, _)| loads.gravity);
    sums.close::<E, WITH_LIQUID>(t, g, points.gravity[lead as usize], liquid_gravity);
    store::<E, R, F, WITH_LIQUID>(t, &sums, four);
    let totals = &sums.totals;
    let saturated = match points.liquid {
        Some((loads, _, _)) if lead_took_part && loads.fluids[lead as usize].is_some() => {
            pore_weights::with_point(totals.saturated, lead)
        }
        _ => totals.saturated,
    };
    (totals.volume_n.to_array(), saturated)
}

/// A triangle's points into `sums`, their weights point by point (in four lanes and
/// transposed, as a tetrahedron's, the 2D dry column ran 30 instructions per particle-step
/// more). Returns whether points of the lead material took part unchecked.
#[inline(always)]
fn triangle_points<E, R, F, const WITH_LIQUID: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    sums: &mut Sums<R, F>,
) -> bool
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let (map, first) = (points.map, points.first);
    let (x, count, lead) = (points.arrays.x, points.arrays.len, sums.totals.lead);
    let shape = |xi: &V3<R>| {
        let nl = E::shape_lanes::<R, 1>(map, first, &xi.map(|c| [c]));
        F::load(t, &std::array::from_fn(|k| nl[k][0]))
    };
    // A triangle of exactly its usual three points, all taking part and of the lead material
    // (the common case), by a loop of a constant count, which the compiler unrolls: as the
    // tetrahedra's below, the element's values are not hoisted and spilled.
    if usual_of::<E>(points.arrays.active, points.arrays.material, 0, count, lead)
        && maps(points.body, lead)
    {
        for i in 0..usual_count::<E>() {
            let n = shape(&x[i]);
            point_sums::<E, R, F, WITH_LIQUID, true>(t, points, i, n, sums);
        }
        return true;
    }
    for (i, xi) in x.iter().enumerate() {
        if !points.arrays.active[i] || !maps(points.body, points.arrays.material[i]) {
            continue;
        }
        point_sums::<E, R, F, WITH_LIQUID, false>(t, points, i, shape(xi), sums);
    }
    false
}

/// A tetrahedron's points into `sums`, four points' weights at a time, one lane per point,
/// turned into one lane per node for each point by a transpose (the same bits as each point's
/// own: the 3D dry column 13 instructions per particle-step fewer than point by point).
/// Returns whether points of the lead material took part unchecked.
#[inline(always)]
fn tetrahedron_points<E, R, F, const WITH_LIQUID: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    sums: &mut Sums<R, F>,
) -> bool
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let (map, first) = (points.map, points.first);
    let (x, count, lead) = (points.arrays.x, points.arrays.len, sums.totals.lead);
    let (active, material) = (points.arrays.active, points.arrays.material);
    // A tetrahedron of exactly its usual four points, all taking part and of the lead
    // material (the common case), outside the batch loop: the map's values go into lanes
    // where they are used, not hoisted out of the loop into lanes and spilled.
    if usual_of::<E>(active, material, 0, count, lead) && maps(points.body, lead) {
        debug_assert_eq!(count, 4, "a tetrahedron's usual count");
        let per_point = node_lane_shapes::<E, R, F>(t, map, first, x, 0, 4);
        for (i, &n) in per_point.iter().enumerate() {
            point_sums::<E, R, F, WITH_LIQUID, true>(t, points, i, n, sums);
        }
        return true;
    }
    let mut lead_took_part = false;
    let mut j = 0;
    while j < count {
        let live = (count - j).min(4);
        let per_point = node_lane_shapes::<E, R, F>(t, map, first, x, j, live);
        // Four points that all take part, of the lead material (the common case), skip each
        // point's checks.
        if live == 4 && four_of(active, material, j, lead) && maps(points.body, lead) {
            lead_took_part = true;
            for (i, &n) in (j..j + 4).zip(per_point.iter()) {
                point_sums::<E, R, F, WITH_LIQUID, true>(t, points, i, n, sums);
            }
        } else {
            for (i, &n) in (j..j + live).zip(per_point.iter()) {
                point_sums::<E, R, F, WITH_LIQUID, false>(t, points, i, n, sums);
            }
        }
        j += live;
    }
    lead_took_part
}

/// The element's sums into the scatter's buffer `four`, the pass's values per node as a
/// constant of the element and phases (the pass's `stride`, a field read at run time, is the
/// same), so that the stores index by constants; [`store_nodes`] checks it against the buffer.
#[inline(always)]
fn store<E, R, F, const WITH_LIQUID: bool>(t: F::Token, sums: &Sums<R, F>, four: &mut [R])
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let (s4, w4) = (&sums.solid, &sums.liquid);
    let (sw, lw) = (solid_width::<E>(), liquid_width::<E>());
    let width = if WITH_LIQUID { sw + lw } else { sw };
    if E::NODES == 4 {
        const { assert!(solid_width::<crate::element::tet4::Tet4>() == 10) };
        store_nodes::<E, R, F, 10>(t, s4, four, width, 0);
        if WITH_LIQUID {
            store_nodes::<E, R, F, 12>(t, w4, four, width, 10);
        }
    } else {
        const { assert!(solid_width::<crate::element::tri3::Tri3>() == 7) };
        let (solid, liquid) = (&s4[..7], &w4[..9]);
        store_nodes::<E, R, F, 7>(t, solid.try_into().expect("seven"), four, width, 0);
        if WITH_LIQUID {
            store_nodes::<E, R, F, 9>(t, liquid.try_into().expect("nine"), four, width, 7);
        }
    }
}
