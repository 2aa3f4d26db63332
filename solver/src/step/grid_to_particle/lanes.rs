//! Grid to particle for an element's points in lanes, one per point ([`crate::four::Four`]
//! vectors in the AVX2 copy, plain arrays in the portable one): the velocity update and the
//! re-mapped momentum.
//!
//! A point's shape values, its velocity change Σ N_k a_k and its new velocity are the same
//! operations at every point, so four points side by side take them as single vector
//! operations. The re-map then adds each point's m N_k v to its element's sums, which are held
//! one lane per node: the four points' m N_k are turned from point lanes into node lanes by one
//! transpose, and added point after point in order. Each lane does a point-by-point loop's
//! operations in the same order ([`super::point`]), so the bits do not depend on the lanes.
//! Left to the compiler, that loop's batches of four points were mostly shuffles and stack
//! traffic (docs/design.md §9).

use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::real::{Real, V3};
use crate::step::batch::{
    four_of, node_rows, point_lanes, point_lanes3, store_nodes, usual_count, usual_of,
};
use crate::step::contact::{maps, OneBody};

use super::point::{flip, kinetic, liquid_kinetic, liquid_mass, Pic};

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
}

/// An element's values, put into lanes where a batch uses them (formed into lanes once per
/// element, they were spilled and reloaded: docs/design.md §9).
pub(super) struct Kernel<'a, R: Real, F: Four<R>> {
    /// The lanes' token.
    pub t: F::Token,
    /// The step.
    pub dt: R,
    /// Only the points of this body take part (all for `None`).
    pub body: Option<OneBody>,
    /// Nodal accelerations (`[k][c]`, the element's nodes).
    pub acc: &'a [V3<R>],
    /// The liquid's, in a two-phase pass.
    pub acc_w: Option<&'a [V3<R>]>,
    /// With a PIC blend, its weights and the element's nodes' velocities after the step.
    pub pic: Option<(Pic<R>, NodeVelocities<R>)>,
}

/// Per node of an element, its velocity after the step in each component that counts
/// ([`Pic::node_velocity`]; zero past its nodes).
pub(super) type NodeVelocities<R> = [[Option<R>; 3]; 4];

/// The element's points, four at a time as far as they take part one after another with one
/// material (the common case) and the others one by one: each point's velocity (and, with
/// `WITH_LIQUID`, a saturated point's liquid velocity) updated with Δt Σ N_k a_k (blended
/// with the nodes' with PIC), its momentum added to the element's sums (the solid's in rows
/// 0..DIM, the liquid's after them), and with `WANT` its m |v|² to the first sum returned (and
/// n ρw V_w |w|² to the second), point by point in order. The sums are stored into the
/// scatter's buffer `four` from their vectors, node by node (values moved: the same bits;
/// value by value, a tetrahedron's store ran 7.5 instructions per particle-step).
#[inline(always)]
pub(super) fn element_lanes<E, R, F, const WANT: bool, const WITH_LIQUID: bool>(
    k: &Kernel<'_, R, F>,
    mut p: ElementPoints<'_, E, R>,
    four: &mut [R],
) -> (f64, f64)
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let t = k.t;
    let count = p.x.len();
    let (active, material) = (&p.active[..count], &p.material[..count]);
    let mut sums = Sums {
        s4: [F::splat(t, R::ZERO); 6],
        kinetic: (0.0, 0.0),
    };
    // The liquid's fluid of material `lead`, where it has one.
    let fluids = p.liquid.as_ref().filter(|_| WITH_LIQUID).map(|l| l.fluids);
    let fluid_of = |lead: u32| fluids.and_then(|f| f[lead as usize]);
    // An element of exactly a tetrahedron's usual four points or a triangle's three, all
    // taking part (the common case), outside the batch loop: the nodal values go into lanes
    // where they are used, not hoisted out of the loop into lanes and spilled.
    let lead = material.first().copied().unwrap_or(0);
    if usual_of::<E>(active, material, 0, count, lead) && maps(k.body, lead) {
        let fluid = fluid_of(lead);
        if usual_count::<E>() == 4 {
            k.batch::<E, 4, WANT>(&mut p, 0, fluid, &mut sums);
        } else {
            k.batch::<E, 3, WANT>(&mut p, 0, fluid, &mut sums);
        }
    } else {
        let mut j = 0;
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
            if all_of_lead && maps(k.body, lead) {
                let fluid = fluid_of(lead);
                match live {
                    4 => k.batch::<E, 4, WANT>(&mut p, j, fluid, &mut sums),
                    3 => k.batch::<E, 3, WANT>(&mut p, j, fluid, &mut sums),
                    2 => k.batch::<E, 2, WANT>(&mut p, j, fluid, &mut sums),
                    _ => k.batch::<E, 1, WANT>(&mut p, j, fluid, &mut sums),
                }
            } else {
                // Points of several materials, or some not taking part: one by one.
                for i in (j..j + live).filter(|&i| active[i] && maps(k.body, material[i])) {
                    let fluid = fluid_of(material[i]);
                    k.batch::<E, 1, WANT>(&mut p, i, fluid, &mut sums);
                }
            }
            j += live;
        }
    }
    store::<E, R, F, WITH_LIQUID>(t, &sums.s4, four);
    sums.kinetic
}

/// An element's re-mapped momenta (the solid's, then the liquid's), value by value, one lane
/// per node, and its points' kinetic-energy terms (solid, liquid).
struct Sums<F> {
    s4: [F; 6],
    kinetic: (f64, f64),
}

/// The scatter's slots of the element's nodes: the solid's DIM values of each node, and with
/// the liquid its DIM after them.
#[inline(always)]
fn store<E, R, F, const WITH_LIQUID: bool>(t: F::Token, s4: &[F; 6], four: &mut [R])
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    if E::NODES == 4 {
        if WITH_LIQUID {
            F::store_points6(*s4, node_rows::<R, 6>(four));
        } else {
            F::store_points3([s4[0], s4[1], s4[2]], node_rows::<R, 3>(four));
        }
    } else if WITH_LIQUID {
        store_nodes::<E, R, F, 4>(t, &[s4[0], s4[1], s4[2], s4[3]], four, 4, 0);
    } else {
        store_nodes::<E, R, F, 2>(t, &[s4[0], s4[1]], four, 2, 0);
    }
}

impl<R: Real, F: Four<R>> Kernel<'_, R, F> {
    /// Points `j..j + LIVE` of the element (which all take part, of one material whose fluid
    /// is `fluid`): lane q reads point j + q, the lanes past `LIVE` the last of them again
    /// (computed, never stored or summed).
    #[inline(always)]
    fn batch<E: Element, const LIVE: usize, const WANT: bool>(
        &self,
        p: &mut ElementPoints<'_, E, R>,
        j: usize,
        fluid: Option<Fluid<R>>,
        sums: &mut Sums<F>,
    ) {
        const { assert!(LIVE >= 1 && LIVE <= 4) };
        let t = self.t;
        let xl = point_lanes3::<R, F>(t, p.x, j, LIVE);
        let n = E::shape_four(t, p.map, p.first, &xl);
        let m = point_lanes::<R, F>(t, p.mass, j, LIVE);
        // The shape values times the mass, one lane per node for each point.
        let mn = F::transpose(t, [m * n[0], m * n[1], m * n[2], m * n[3]]);
        let mut v = flip::<E, R, F>(
            t,
            &n[..E::NODES],
            self.acc,
            self.old(p.vel, j, LIVE),
            self.dt,
        );
        if let Some((pic, node_v)) = &self.pic {
            v = pic.blend::<E, F>(t, &n[..E::NODES], &node_v[..E::NODES], v);
        }
        self.keep::<E>(v, p.vel, j, LIVE);
        self.remap::<E>(&mn, &v, &mut sums.s4[..3], LIVE);
        if WANT {
            let e = kinetic::<E, R, F>(t, m, &v).to_array();
            for q in 0..LIVE {
                sums.kinetic.0 += e[q].f64();
            }
        }
        let (Some(f), Some(l), Some(acc_w)) = (fluid, p.liquid.as_mut(), self.acc_w.as_ref())
        else {
            return;
        };
        let vol = l.volume0.unwrap_or(l.volume);
        let mw = liquid_mass(t, &f, point_lanes::<R, F>(t, vol, j, LIVE));
        let mnw = F::transpose(t, [mw * n[0], mw * n[1], mw * n[2], mw * n[3]]);
        let w = flip::<E, R, F>(t, &n[..E::NODES], acc_w, self.old(l.w, j, LIVE), self.dt);
        self.keep::<E>(w, l.w, j, LIVE);
        self.remap::<E>(&mnw, &w, &mut sums.s4[E::DIM..E::DIM + 3], LIVE);
        if WANT {
            let e = liquid_kinetic::<E, R, F>(t, &f, mw, &w).to_array();
            for q in 0..LIVE {
                sums.kinetic.1 += e[q].f64();
            }
        }
    }

    /// The velocities `vel[j..j + live]` as lanes (lane q: point j + q, the lanes past `live`
    /// the last again).
    #[inline(always)]
    fn old(&self, vel: &[V3<R>], j: usize, live: usize) -> [F; 3] {
        point_lanes3::<R, F>(self.t, vel, j, live)
    }

    /// Stores the first `live` lanes of `v` into `vel[j..]`.
    #[inline(always)]
    fn keep<E: Element>(&self, v: [F; 3], vel: &mut [V3<R>], j: usize, live: usize) {
        if live == 4 {
            // Four points' velocities back one point after another, moved in registers (a
            // section's z-components as loaded, so they keep their bits).
            let to: &mut [V3<R>; 4] = (&mut vel[j..j + 4]).try_into().expect("four points");
            F::store_points3(v, to);
        } else {
            let va: [[R; 4]; 3] = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
            for q in 0..live {
                for c in 0..E::DIM {
                    vel[j + q][c] = va[c][q];
                }
            }
        }
    }

    /// Adds the first `live` points' momenta to the sums (`mn[q]`: point q's m N_k, one lane
    /// per node; `v[c]`: component c of each point's velocity), point after point.
    #[inline(always)]
    fn remap<E: Element>(&self, mn: &[F; 4], v: &[F; 3], sums: &mut [F], live: usize) {
        let va: [[R; 4]; 3] = [v[0].to_array(), v[1].to_array(), v[2].to_array()];
        for q in 0..live {
            for c in 0..E::DIM {
                sums[c] = sums[c] + mn[q] * F::splat(self.t, va[c][q]);
            }
        }
    }
}
