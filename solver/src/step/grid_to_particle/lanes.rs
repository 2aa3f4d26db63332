//! Grid to particle for an element's points four at a time as explicit four-lane vectors
//! ([`crate::four`]), one lane per point: the velocity update and the re-mapped momentum.
//!
//! A point's shape values, its velocity change Σ N_k a_k and its new velocity are the same
//! operations at every point, so four points side by side take them as single vector
//! operations. The re-map then adds each point's m N_k v to its element's sums, which are held
//! one lane per node: the four points' m N_k are turned from point lanes into node lanes by one
//! transpose, and added point after point in order. Each lane does the point loop's
//! operations in the same order, so the bits are those of [`super::grid_to_particle`]'s
//! batches. Left to the compiler, that loop's batches of four points were mostly shuffles and
//! stack traffic (docs/design.md §9).

use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::real::{Real, V3};
use crate::step::batch::{
    four_of, node_rows, point_lanes, point_lanes3, store_nodes, usual_count, usual_of, Lanes,
};
use crate::step::contact::{maps, OneBody};

/// An element's points, each array sliced to them (one length), and what grid to particle
/// reads of the element.
pub(super) struct ElementPoints<'a, E: Element, R: Real> {
    /// Positions.
    pub x: &'a [V3<R>],
    /// Masses.
    pub mass: &'a [R],
    /// Whether each point is active.
    pub active: &'a [bool],
    /// Material indices.
    pub material: &'a [u32],
    /// Velocities, updated.
    pub vel: &'a mut [V3<R>],
    /// The liquid's share, in a two-phase pass.
    pub liquid: Option<LiquidPoints<'a, R>>,
    /// The element's map from global to local coordinates.
    pub map: &'a E::Map<R>,
    /// Its first corner's position.
    pub first: &'a V3<R>,
    /// Its nodes' accelerations (the solid's).
    pub acc: &'a [V3<R>],
}

/// The liquid's share of an element's points.
pub(super) struct LiquidPoints<'a, R: Real> {
    /// Liquid velocities, updated.
    pub w: &'a mut [V3<R>],
    /// Volumes.
    pub volume: &'a [R],
    /// Initial volumes, where the case holds the liquid mass fixed.
    pub volume0: Option<&'a [R]>,
    /// Per material, its fluid.
    pub fluids: &'a [Option<Fluid<R>>],
    /// The element's nodes' liquid accelerations.
    pub acc: &'a [V3<R>],
}

/// Runs of the element's points from the first, as many as take part one after another with
/// one material (`body`'s; FLIP, no PIC blend), four at a time and the last one to three
/// together: each point's velocity (and, with `WITH_LIQUID`, a saturated point's liquid
/// velocity) updated with Δt Σ N_k a_k, its momentum added to `sums` (the solid's in rows
/// 0..DIM, the liquid's after them), and with `WANT` its m |v|² to `kinetic` (and n ρw V_w |w|²
/// to `kinetic_w`), point by point in order. Returns the first point it did not take (the
/// element's point count when it took them all), which the point loop goes on from. A
/// element whose points it took all has its sums stored into the scatter's buffer `four` from
/// their vectors, node by node, where [`store`] puts them (values moved: the same bits; value
/// by value, a tetrahedron's store ran 7.5 instructions per particle-step); `sums` are then
/// left as they were.
///
/// [`store`]: crate::step::batch::store
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn element_lanes<E: Element, R: Real, const WANT: bool, const WITH_LIQUID: bool>(
    t: <R::Four as Four<R>>::Token,
    body: Option<OneBody>,
    dt: R,
    mut p: ElementPoints<'_, E, R>,
    sums: &mut Lanes<R, 6>,
    four: &mut [R],
    kinetic: &mut f64,
    kinetic_w: &mut f64,
) -> usize {
    let count = p.x.len();
    let (active, material) = (&p.active[..count], &p.material[..count]);
    let k = Kernel::<E, R> {
        t,
        dt,
        acc: p.acc,
        acc_w: p.liquid.as_ref().map(|l| l.acc),
        _element: std::marker::PhantomData,
    };
    let mut s4 = [R::Four::splat(t, R::ZERO); 6];
    for (v, sum) in s4.iter_mut().zip(sums.iter()) {
        *v = R::Four::load(t, sum);
    }
    // The liquid's fluid of material `lead`, where it has one.
    let fluids = p.liquid.as_ref().filter(|_| WITH_LIQUID).map(|l| l.fluids);
    let fluid_of = |lead: u32| fluids.and_then(|f| f[lead as usize]);
    let mut j = 0;
    // An element of exactly a tetrahedron's usual four points or a triangle's three, all
    // taking part (the common case), outside the batch loop: the nodal values go into lanes
    // where they are used, not hoisted out of the loop into lanes and spilled.
    let lead = material.first().copied().unwrap_or(0);
    if usual_of::<E>(active, material, 0, count, lead) && maps(body, lead) {
        let fluid = fluid_of(lead);
        if usual_count::<E>() == 4 {
            k.batch::<4, WANT>(&mut p, 0, fluid, &mut s4, kinetic, kinetic_w);
        } else {
            k.batch::<3, WANT>(&mut p, 0, fluid, &mut s4, kinetic, kinetic_w);
        }
        j = count;
    }
    while j < count {
        let live = (count - j).min(4);
        let lead = material[j];
        // All of the batch's points take part when each is active and of `lead`, which the
        // body maps (four, the common case, by one compare of each array's four).
        let all_of_lead = if live == 4 {
            four_of(active, material, j, lead)
        } else {
            (j..j + live).all(|i| active[i] && material[i] == lead)
        };
        if !(all_of_lead && maps(body, lead)) {
            break;
        }
        let fluid = fluid_of(lead);
        macro_rules! run {
            ($live:literal) => {
                k.batch::<$live, WANT>(&mut p, j, fluid, &mut s4, kinetic, kinetic_w)
            };
        }
        match live {
            4 => run!(4),
            3 => run!(3),
            2 => run!(2),
            _ => run!(1),
        }
        j += live;
    }
    if stores_sums(j, count) {
        // The scatter's slots of the element's nodes: the solid's DIM values of each node, and
        // with the liquid its DIM after them.
        if E::NODES == 4 {
            if WITH_LIQUID {
                R::Four::store_points6(s4, node_rows::<R, 6>(four));
            } else {
                R::Four::store_points3([s4[0], s4[1], s4[2]], node_rows::<R, 3>(four));
            }
        } else if WITH_LIQUID {
            store_nodes::<E, R, 4>(t, &[s4[0], s4[1], s4[2], s4[3]], four, 4, 0);
        } else {
            store_nodes::<E, R, 2>(t, &[s4[0], s4[1]], four, 2, 0);
        }
        return j;
    }
    for (sum, v) in sums.iter_mut().zip(s4) {
        *sum = v.to_array();
    }
    j
}

/// Whether [`element_lanes`], having taken `taken` of the element's `count` points, stored
/// the element's sums into the scatter's buffer itself: when it took them all.
#[inline(always)]
pub(super) fn stores_sums(taken: usize, count: usize) -> bool {
    taken == count
}

/// An element's values, put into all four lanes where a batch uses them (formed into lanes
/// once per element, they were spilled and reloaded: docs/design.md §9).
struct Kernel<'a, E: Element, R: Real> {
    t: <R::Four as Four<R>>::Token,
    dt: R,
    /// Nodal accelerations (`[k][c]`, the element's nodes).
    acc: &'a [V3<R>],
    /// The liquid's, in a two-phase pass.
    acc_w: Option<&'a [V3<R>]>,
    _element: std::marker::PhantomData<E>,
}

impl<E: Element, R: Real> Kernel<'_, E, R> {
    /// Points `j..j + LIVE` of the element (which all take part, of one material whose fluid
    /// is `fluid`): lane q reads point j + q, the lanes past `LIVE` the last of them again
    /// (computed, never stored or summed).
    #[inline(always)]
    fn batch<const LIVE: usize, const WANT: bool>(
        &self,
        p: &mut ElementPoints<'_, E, R>,
        j: usize,
        fluid: Option<Fluid<R>>,
        s4: &mut [R::Four; 6],
        kinetic: &mut f64,
        kinetic_w: &mut f64,
    ) {
        const { assert!(LIVE >= 1 && LIVE <= 4) };
        let t = self.t;
        let xl = point_lanes3::<R>(t, p.x, j, LIVE);
        let n = E::shape_four(t, p.map, p.first, &xl);
        let m = point_lanes::<R>(t, p.mass, j, LIVE);
        // The shape values times the mass, one lane per node for each point.
        let mn = R::Four::transpose(t, [m * n[0], m * n[1], m * n[2], m * n[3]]);
        let v = self.update(&n, self.acc, p.vel, j, LIVE);
        self.remap(&mn, &v, &mut s4[..3], LIVE);
        if WANT {
            let e = (m * dot::<E, R>(t, &v)).to_array();
            for q in 0..LIVE {
                *kinetic += e[q].f64();
            }
        }
        let (Some(f), Some(l), Some(acc_w)) = (fluid, p.liquid.as_mut(), self.acc_w.as_ref())
        else {
            return;
        };
        // The same liquid mass as particle to grid mapped (see `LiquidPoints::volume0`).
        let vol = l.volume0.unwrap_or(l.volume);
        let mw = R::Four::splat(t, f.rho_w) * point_lanes::<R>(t, vol, j, LIVE);
        let mnw = R::Four::transpose(t, [mw * n[0], mw * n[1], mw * n[2], mw * n[3]]);
        let w = self.update(&n, acc_w, l.w, j, LIVE);
        self.remap(&mnw, &w, &mut s4[E::DIM..E::DIM + 3], LIVE);
        if WANT {
            let e = (R::Four::splat(t, f.n) * mw * dot::<E, R>(t, &w)).to_array();
            for q in 0..LIVE {
                *kinetic_w += e[q].f64();
            }
        }
    }

    /// The velocities `vel[j..j + live]` (lane q: point j + q, the lanes past `live` the last
    /// again) plus Δt Σ N_k a_k, stored, and returned as lanes.
    #[inline(always)]
    fn update(
        &self,
        n: &[R::Four; 4],
        acc: &[V3<R>],
        vel: &mut [V3<R>],
        j: usize,
        live: usize,
    ) -> [R::Four; 3] {
        let t = self.t;
        let zero = R::Four::splat(t, R::ZERO);
        let mut dv = [zero; 3];
        for (nk, ak) in n.iter().zip(acc).take(E::NODES) {
            for c in 0..E::DIM {
                dv[c] = dv[c] + *nk * R::Four::splat(t, ak[c]);
            }
        }
        let mut v = point_lanes3::<R>(t, vel, j, live);
        let dt = R::Four::splat(t, self.dt);
        for c in 0..E::DIM {
            v[c] = v[c] + dt * dv[c];
        }
        if live == 4 {
            // Four points' velocities back one point after another, moved in registers (a
            // section's z-components as loaded, so they keep their bits).
            let to: &mut [V3<R>; 4] = (&mut vel[j..j + 4]).try_into().expect("four points");
            R::Four::store_points3(v, to);
        } else {
            let va: [[R; 4]; 3] = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
            for q in 0..live {
                for c in 0..E::DIM {
                    vel[j + q][c] = va[c][q];
                }
            }
        }
        v
    }

    /// Adds the first `live` points' momenta to the sums (`mn[q]`: point q's m N_k, one lane
    /// per node; `v[c]`: component c of each point's velocity), point after point.
    #[inline(always)]
    fn remap(&self, mn: &[R::Four; 4], v: &[R::Four; 3], sums: &mut [R::Four], live: usize) {
        let va: [[R; 4]; 3] = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
        for q in 0..live {
            for c in 0..E::DIM {
                sums[c] = sums[c] + mn[q] * R::Four::splat(self.t, va[c][q]);
            }
        }
    }
}

/// v · v of each lane over the element's dimensions, as the point loop sums it (from zero).
#[inline(always)]
fn dot<E: Element, R: Real>(t: <R::Four as Four<R>>::Token, v: &[R::Four; 3]) -> R::Four {
    let mut s = R::Four::splat(t, R::ZERO);
    for c in 0..E::DIM {
        s = s + v[c] * v[c];
    }
    s
}
