//! The stress pass for the points of a linear-elastic material, four points at a time as
//! explicit four-lane vectors ([`crate::four`]), one lane per point.
//!
//! In a linear element the strain increment, the law's stress increment, the spin and the
//! volume factor are the same at every point, so they are formed once per element; each point
//! then needs its shape values, its velocity, the co-rotation of its stress and its guard
//! terms, which four points side by side take as single vector operations ([`super::point`],
//! [`super::strain`]). Left to the compiler the same batch ran more instructions than one point
//! at a time (docs/design.md §9), so the f64 pass went point by point. Each lane does the point
//! loop's operations in the same order, so the bits are those of [`super::general`]'s batches,
//! whatever the width.
//!
//! An element's last one to three points (a triangle's three, the last two of a tetrahedron's
//! ten) load four lanes in place too, the lanes past the element reading the next element's
//! points, which are computed and never stored: copied into a batch of their own, a
//! triangle's three ran more instructions than the point loop.

use crate::element::locate::{relocate, tolerance};
use crate::element::Element;
use crate::four::{Four, Lanes, Plain};
use crate::material::law::Law;
use crate::material::linear_elastic::LinearElastic;
use crate::real::{Real, V3};
use crate::step::batch::{usual_count, usual_of, Batch};
use crate::step::contact::maps;

use super::guard::GuardTerms;
use super::point::{moved, pore_change, strain_work, velocity_at, volume_factor};
use super::strain::{add_objective, spin_increment, strain_increment};
use super::{ChunkPoints, ElementView, Pass, Sinks};

/// Updates the points of element `el` from position `j` up to `end`, four at a time, as
/// [`super::general`]'s batches do, for as long as each batch's points that take part are of
/// one linear-elastic material (that of the first point taking part): the stress, position,
/// displacement and volume, the pore pressure's rate, with the sinks' guard sums, and where
/// they locate, the points' new elements, as the chunk's locate test and walk find them: a
/// batch whose new shape values all lie within the tolerance stays, the points of any other
/// are walked. Returns where it stopped: `end`, or the first batch it does not take, which the
/// general loop continues from (the points before it updated and located).
///
/// For tetrahedra and plane-strain triangles (not axisymmetric sections, whose hoop strain
/// differs from point to point), without strain smoothing (the caller's check).
#[inline(always)]
pub(super) fn elastic_batches<E: Element, R: Real>(
    cx: &Pass<'_, E, R>,
    t: <R::Four as Lanes<R>>::Token,
    el: &ElementView<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    (mut j, end): (usize, usize),
    mut sinks: Sinks<'_>,
) -> usize {
    debug_assert!(!E::AXISYMMETRIC && cx.smoothing.is_none());
    let (active, material) = (p.active, p.material);
    let takes_part = |i: usize| active[i] && maps(cx.body, material[i]);
    let Some(lead) = (j..end).find(|&i| takes_part(i)).map(|i| material[i]) else {
        return j;
    };
    let Law::LinearElastic(law) = &cx.laws[lead as usize] else {
        return j;
    };
    let run = Run {
        terms: Terms::new::<E>(cx, t, el, law, lead),
        el,
        mesh: cx.mesh,
        // The guard's per-material values exist only with the guards.
        guard: sinks
            .guard
            .then(|| GuardTerms::of(lead, cx.initial_density, cx.fluids, cx.min_ratio)),
    };
    // The chunk's points: a batch's lanes may read past the element's points (never past
    // these).
    let n = p.x.len();
    // An element of exactly a tetrahedron's usual four points or a triangle's three, all
    // taking part (the common case), outside the batch loop: its terms go into lanes where
    // they are used, not hoisted out of the loop into lanes and spilled.
    if j + 4 <= n && usual_of::<E>(active, material, j, end, lead) {
        if usual_count::<E>() == 4 {
            run.in_place::<4>(p, &mut sinks, j);
        } else {
            run.in_place::<3>(p, &mut sinks, j);
        }
        return j + usual_count::<E>();
    }
    while j < end {
        // The next four points, or the element's last one to three, if all take part (the
        // common case), are updated in place: four lanes loaded from the chunk's arrays, the
        // lanes past the element's points (the next element's) computed and never stored.
        // The others go through copies, of which only the points taking part are written back.
        let live = (end - j).min(4);
        let all_take_part = |live: usize| {
            active[j..j + live].iter().all(|&a| a)
                && material[j..j + live].iter().all(|&m| m == lead)
        };
        if j + 4 <= n && all_take_part(live) {
            match live {
                4 => run.in_place::<4>(p, &mut sinks, j),
                3 => run.in_place::<3>(p, &mut sinks, j),
                2 => run.in_place::<2>(p, &mut sinks, j),
                _ => run.in_place::<1>(p, &mut sinks, j),
            }
            j += live;
            continue;
        }
        let b = match Batch::<4>::new(j, end, takes_part) {
            Ok(b) => b,
            Err(skip) => {
                j += skip;
                continue;
            }
        };
        if b.points().any(|i| material[i] != lead) {
            break;
        }
        run.copied(p, &mut sinks, &b);
        j += b.len;
    }
    j
}

/// One element's linear-elastic batches: its terms, and what the batches read beside them.
struct Run<'r, E: Element, R: Real> {
    terms: Terms<R>,
    el: &'r ElementView<'r, E, R>,
    mesh: &'r crate::element::mesh::Mesh<E, R>,
    /// The guard's terms of the material, with the guards.
    guard: Option<GuardTerms<R>>,
}

impl<E: Element, R: Real> Run<'_, E, R> {
    /// Points `j..j + LIVE` (all taking part) updated in place: four lanes loaded from the
    /// chunk's arrays, `LIVE` a constant in each copy (a count known only at run time made
    /// loops of the stores and of the guard's sums).
    #[inline(always)]
    fn in_place<const LIVE: usize>(
        &self,
        p: &mut ChunkPoints<'_, R>,
        sinks: &mut Sinks<'_>,
        j: usize,
    ) {
        debug_assert!(
            p.element[j..j + LIVE]
                .iter()
                .all(|&h| h as usize == self.el.e),
            "points not sorted by element"
        );
        let r = j..j + 4;
        let volume4: &mut [R; 4] = (&mut p.volume[r.clone()]).try_into().unwrap();
        let mut pore4 = p
            .pore
            .as_deref_mut()
            .map(|p| <&mut [R; 4]>::try_from(&mut p[r.clone()]).unwrap());
        let four = FourPoints {
            x: (&mut p.x[r.clone()]).try_into().unwrap(),
            u: (&mut p.u[r.clone()]).try_into().unwrap(),
            stress: (&mut p.stress[r.clone()]).try_into().unwrap(),
            volume: &mut *volume4,
            pore: pore4.as_deref_mut(),
        };
        let wants = (self.guard.is_some(), sinks.locate.is_some());
        let (strain, outside) = self.four_points::<LIVE>(four, wants);
        let mass4 = *<&[R; 4]>::try_from(&p.mass[r]).unwrap();
        if let Some(g) = &self.guard {
            let on = std::array::from_fn(|q| q < LIVE);
            g.add_four(sinks.open, on, strain, *volume4, mass4, pore4.map(|p| *p));
        }
        if let Some((found, offset)) = sinks.locate.as_mut().filter(|_| outside) {
            for i in j..j + LIVE {
                relocate(self.mesh, found, *offset + i, &mut p.element[i], &p.x[i]);
            }
        }
    }

    /// The points of batch `b` (of the lead material, some lanes past its points or of points
    /// that do not take part) through copies, of which only the points taking part are written
    /// back, added to the guard's sums and located.
    #[inline(always)]
    fn copied(&self, p: &mut ChunkPoints<'_, R>, sinks: &mut Sinks<'_>, b: &Batch<4>) {
        debug_assert!(
            b.points().all(|i| p.element[i] as usize == self.el.e),
            "points not sorted by element"
        );
        let (mut x4, mut u4) = (b.at.map(|i| p.x[i]), b.at.map(|i| p.u[i]));
        let (mut s4, mut v4) = (b.at.map(|i| p.stress[i]), b.at.map(|i| p.volume[i]));
        let mut p4 = p.pore.as_deref().map(|pore| b.at.map(|i| pore[i]));
        let four = FourPoints {
            x: &mut x4,
            u: &mut u4,
            stress: &mut s4,
            volume: &mut v4,
            pore: p4.as_mut(),
        };
        let wants = (self.guard.is_some(), sinks.locate.is_some());
        let (strain, outside) = self.four_points::<4>(four, wants);
        for i in b.points() {
            let q = i - b.start;
            (p.x[i], p.u[i], p.stress[i], p.volume[i]) = (x4[q], u4[q], s4[q], v4[q]);
            if let (Some(pore), Some(p4)) = (p.pore.as_deref_mut(), &p4) {
                pore[i] = p4[q];
            }
        }
        if let Some(g) = &self.guard {
            g.add_four(sinks.open, b.on, strain, v4, b.at.map(|i| p.mass[i]), p4);
        }
        // (The lanes past the batch's points repeat one of its points.)
        if let Some((found, offset)) = sinks.locate.as_mut().filter(|_| outside) {
            for i in b.points() {
                relocate(self.mesh, found, *offset + i, &mut p.element[i], &p.x[i]);
            }
        }
    }

    /// One batch of four points of the element (`four`, updated in place in the first `LIVE`
    /// lanes, the others computed and left as they were): the point loop's update, lane by
    /// lane. Returns each point's strain-energy term for the guard's sums (with `guard`; zeros
    /// without), and with `locate` whether one of the `LIVE` points' new shape values put it
    /// outside the element (beyond the locate tolerance,
    /// [`crate::element::locate::run_inside`]'s test).
    #[inline(always)]
    fn four_points<const LIVE: usize>(
        &self,
        four: FourPoints<'_, R>,
        (guard, locate): (bool, bool),
    ) -> ([R; 4], bool) {
        const { assert!(LIVE >= 1 && LIVE <= 4) };
        let k = &self.terms;
        let t = k.t;
        let lanes = |v: [R; 4]| R::Four::load(t, &v);
        let sp = |v: R| R::Four::splat(t, v);
        let FourPoints {
            x,
            u,
            stress,
            volume,
            pore,
        } = four;
        let xl = R::Four::load_points3(t, x);
        let n = E::shape_four(t, self.el.map, self.el.first, &xl);
        // The pore pressure's smoothed rate, from the nodes at the start-of-step position.
        if let (Some(p), Some(rate)) = (pore, &k.rate) {
            let p1 = lanes(*p) + pore_change::<E, R, R::Four>(t, &n, rate, k.dt);
            store_live::<R, LIVE>(t, p1, p);
        }
        let dx = velocity_at::<E, R, R::Four>(t, &n, &k.vel);
        let s0 = R::Four::load_points6(t, stress);
        let mut s1: [R::Four; 6] = std::array::from_fn(|c| s0[c] + sp(k.increment[c]));
        if let Some(spin) = &k.spin {
            add_objective::<R, R::Four>(t, &s0, &mut s1, spin, sp(k.ev));
        }
        let v0 = lanes(*volume);
        let v1 = v0 * sp(k.grow);
        let u0 = R::Four::load_points3(t, u);
        // (A section's out-of-plane components as loaded: stored back, they keep their bits.)
        let x1 = moved::<E, R, R::Four>(t, xl, &dx, k.dt);
        let u1 = moved::<E, R, R::Four>(t, u0, &dx, k.dt);
        store_moved::<E, R, LIVE>(
            Moved {
                x: x1,
                u: u1,
                stress: s1,
            },
            x,
            u,
            stress,
        );
        store_live::<R, LIVE>(t, v1, volume);
        let outside = locate && self.outside::<LIVE>(&x1);
        if !guard {
            return ([R::ZERO; 4], outside);
        }
        let de = [
            sp(k.de[0]),
            sp(k.de[1]),
            sp(k.de[2]),
            sp(k.de[3]),
            sp(k.de[4]),
            sp(k.de[5]),
        ];
        let w = strain_work::<E, R, R::Four>(t, (&s0, &s1), &de, (&x1, v0, v1));
        (w.to_array(), outside)
    }

    /// Whether one of the first `LIVE` lanes' positions `x1` lies outside the element, beyond
    /// the locate tolerance.
    #[inline(always)]
    fn outside<const LIVE: usize>(&self, x1: &[R::Four; 3]) -> bool {
        let t = self.terms.t;
        // The lanes past `LIVE` never outside: -∞ (no value is below it, NaN neither).
        let tol = if LIVE == 4 {
            R::Four::splat(t, self.terms.tol)
        } else {
            let below = R::of(f64::NEG_INFINITY);
            R::Four::load(
                t,
                &std::array::from_fn(|q| {
                    if q < LIVE {
                        R::of(-tolerance::<R>())
                    } else {
                        below
                    }
                }),
            )
        };
        let n1 = E::shape_four(t, self.el.map, self.el.first, x1);
        let mut out = false;
        for nk in n1.iter().take(E::NODES) {
            out |= nk.any_lt(tol);
        }
        out
    }
}

/// Four points' arrays, updated in place.
struct FourPoints<'a, R: Real> {
    x: &'a mut [V3<R>; 4],
    u: &'a mut [V3<R>; 4],
    stress: &'a mut [[R; 6]; 4],
    volume: &'a mut [R; 4],
    pore: Option<&'a mut [R; 4]>,
}

/// Four points' new positions, displacements and stresses, as lanes.
struct Moved<F> {
    x: [F; 3],
    u: [F; 3],
    stress: [F; 6],
}

/// The first `LIVE` lanes' new positions, displacements and stresses back into the points'
/// arrays (a section's out-of-plane components as they were).
#[inline(always)]
fn store_moved<E: Element, R: Real, const LIVE: usize>(
    moved: Moved<R::Four>,
    x: &mut [V3<R>; 4],
    u: &mut [V3<R>; 4],
    stress: &mut [[R; 6]; 4],
) {
    let Moved {
        x: x1,
        u: u1,
        stress: s1,
    } = moved;
    if LIVE == 4 {
        // Four points' values back to one point after another, moved in registers.
        R::Four::store_points3(x1, x);
        R::Four::store_points3(u1, u);
        R::Four::store_points6(s1, stress);
        return;
    }
    // (`from_fn`, not `map`: `map` is not inlined here, and the intrinsics in its closure
    // would become calls.)
    let x1a: [[R; 4]; 3] = std::array::from_fn(|a| x1[a].to_array());
    let u1a: [[R; 4]; 3] = std::array::from_fn(|a| u1[a].to_array());
    let s1a: [[R; 4]; 6] = std::array::from_fn(|c| s1[c].to_array());
    for q in 0..LIVE {
        for a in 0..E::DIM {
            x[q][a] = x1a[a][q];
            u[q][a] = u1a[a][q];
        }
        stress[q] = std::array::from_fn(|c| s1a[c][q]);
    }
}

/// An element's terms, each formed as the point loop forms it at every point, and put into all
/// four lanes where a batch uses it (formed into lanes here, the thirty-odd vectors were
/// spilled and reloaded: docs/design.md §9).
struct Terms<R: Real> {
    t: <R::Four as Lanes<R>>::Token,
    /// Nodal velocities (`[k][c]`; zero past the element's nodes).
    vel: [[R; 3]; 4],
    /// The strain increment (xx yy zz xy yz zx).
    de: [R; 6],
    /// The law's stress increment.
    increment: [R; 6],
    /// The spin increment (ω_xy, ω_yz, ω_zx), with the objective terms.
    spin: Option<[R; 3]>,
    /// tr Δε.
    ev: R,
    /// The volume factor 1 + tr Δε.
    grow: R,
    dt: R,
    /// The pore pressure's nodal rates, where the material has a liquid and the run one.
    rate: Option<[R; 4]>,
    /// The locate tolerance, negative: a shape value below it is outside.
    tol: R,
}

impl<R: Real> Terms<R> {
    #[inline(always)]
    fn new<E: Element>(
        cx: &Pass<'_, E, R>,
        t: <R::Four as Lanes<R>>::Token,
        el: &ElementView<'_, E, R>,
        law: &LinearElastic<R>,
        lead: u32,
    ) -> Self {
        let dt = cx.dt;
        let de = strain_increment::<E, R>(el.l, dt);
        let increment = law.increment(&de);
        let rate = cx
            .pore_rate
            .as_ref()
            .filter(|r| r.fluids[lead as usize].is_some())
            .map(|r| {
                std::array::from_fn(|k| {
                    if k < E::NODES {
                        r.nodal[el.corners[k] as usize]
                    } else {
                        R::ZERO
                    }
                })
            });
        // The point loop's volume factor, formed once: a lane of its own.
        let one = |v: R| Plain::<R, 1>([v]);
        let grow = volume_factor::<R, Plain<R, 1>>((), one(de[0]), one(de[1]), one(de[2])).0[0];
        Terms {
            t,
            vel: std::array::from_fn(|k| {
                std::array::from_fn(|c| if k < E::NODES { el.vel[k][c] } else { R::ZERO })
            }),
            increment,
            spin: cx.objective.then(|| spin_increment(el.l, dt)),
            ev: de[0] + de[1] + de[2],
            grow,
            de,
            dt,
            rate,
            tol: R::of(-tolerance::<R>()),
        }
    }
}

/// Stores the first `LIVE` lanes of `v` into `to`, leaving the others: one vector store, of the
/// others' values as they are past `LIVE`.
#[inline(always)]
fn store_live<R: Real, const LIVE: usize>(
    t: <R::Four as Lanes<R>>::Token,
    v: R::Four,
    to: &mut [R; 4],
) {
    *to = v.first_of(R::Four::load(t, to), LIVE).to_array();
}
