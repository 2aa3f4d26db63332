//! The stress pass for the points of a linear-elastic material, four points at a time as
//! explicit four-lane vectors ([`crate::four`]), one lane per point.
//!
//! In a linear element the strain increment, the law's stress increment, the spin and the
//! volume factor are the same at every point, so they are formed once per element; each point
//! then needs its shape values, its velocity, the co-rotation of its stress and its guard
//! terms, which four points side by side take as single vector operations. Left to the
//! compiler the same batch ran more instructions than one point at a time (docs/design.md §9),
//! so the f64 pass went point by point. Each lane does the point loop's operations in the same
//! order, so the bits are those of [`super::chunk`]'s general batches, whatever the width.
//!
//! An element's last one to three points (a triangle's three, the last two of a tetrahedron's
//! ten) load four lanes in place too, the lanes past the element reading the next element's
//! points, which are computed and never stored: copied into a batch of their own, a
//! triangle's three ran more instructions than the point loop.

use crate::element::locate::{relocate, tolerance, Outcome};
use crate::element::Element;
use crate::four::Four;
use crate::material::law::Law;
use crate::real::{Real, V3};
use crate::step::batch::{usual_count, usual_of, Batch};
use crate::step::contact::maps;

use super::{spin_increment, strain_increment, Open, Pass};

/// A chunk's point arrays, each sliced to the chunk's range and indexed by the position in it.
pub(super) struct Points<'s, R: Real> {
    /// Positions.
    pub x: &'s mut [V3<R>],
    /// Displacements.
    pub u: &'s mut [V3<R>],
    /// Stresses (xx yy zz xy yz zx).
    pub stress: &'s mut [[R; 6]],
    /// Volumes.
    pub volume: &'s mut [R],
    /// The pore pressures, in a two-phase run.
    pub pore: Option<&'s mut [R]>,
    /// Whether each point is active.
    pub active: &'s [bool],
    /// Material indices.
    pub material: &'s [u32],
    /// Masses.
    pub mass: &'s [R],
    /// Each point's element, which the located points' walks update.
    pub element: &'s mut [u32],
}

/// What one element shares among its points: its index, velocity gradient `l` (∂v_a/∂x_b),
/// nodal velocities, map and first corner, and its corners.
pub(super) struct ElementView<'e, E: Element, R: Real> {
    /// The element's index.
    pub e: usize,
    /// Its velocity gradient, L[a][b] = ∂v_a/∂x_b.
    pub l: &'e [[R; 3]; 3],
    /// Its nodes' velocities.
    pub vel: &'e [V3<R>],
    /// Its map from global to local coordinates.
    pub map: &'e E::Map<R>,
    /// Its first corner's position.
    pub first: &'e V3<R>,
    /// Its corner nodes.
    pub corners: &'e [u32],
}

/// Updates the points of element `el` from position `j` up to `end`, four at a time, as
/// [`super::chunk`]'s batches do, for as long as each batch's points that take part are of one
/// linear-elastic material (that of the first point taking part): the stress, position,
/// displacement and volume, the pore pressure's rate, with `open` the guard's sums, and with
/// `locate` (the chunk's outcome and its first point's index) the points' new elements, as
/// the chunk's locate test and walk find them: a batch whose new shape values all lie within
/// the tolerance stays, the points of any other are walked. Returns where it stopped: `end`,
/// or the first batch it does not take, which the general loop continues from (the points
/// before it updated and located).
///
/// For tetrahedra and plane-strain triangles (not axisymmetric sections, whose hoop strain
/// differs from point to point), without strain smoothing (the caller's check).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn elastic_batches<E: Element, R: Real>(
    cx: &Pass<'_, E, R>,
    t: <R::Four as Four<R>>::Token,
    el: &ElementView<'_, E, R>,
    p: Points<'_, R>,
    mut j: usize,
    end: usize,
    mut open: Option<&mut Open>,
    mut locate: Option<(&mut Outcome, usize)>,
) -> usize {
    debug_assert!(!E::AXISYMMETRIC && cx.smoothing.is_none());
    let Points {
        x,
        u,
        stress,
        volume,
        mut pore,
        active,
        material,
        mass,
        element,
    } = p;
    let takes_part = |i: usize| active[i] && maps(cx.body, material[i]);
    let Some(lead) = (j..end).find(|&i| takes_part(i)).map(|i| material[i]) else {
        return j;
    };
    let Law::LinearElastic(law) = &cx.laws[lead as usize] else {
        return j;
    };
    let terms = Terms::new::<E>(cx, t, el, law, lead);
    let guard = open.is_some();
    // The guard's per-material values exist only with the guards (empty slices without).
    let sums = guard.then(|| GuardTerms {
        rho0: cx.initial_density[lead as usize],
        min_ratio: cx.min_ratio,
        n_over_kw: cx.fluids[lead as usize]
            .as_ref()
            .map_or(R::ZERO, |f| f.n_over_kw),
    });
    // The chunk's points: a batch's lanes may read past the element's points (never past
    // these).
    let n = x.len();
    // One batch in place, `$live` a constant in each copy (a count known only at run time
    // made loops of the stores and of the guard's sums).
    macro_rules! in_place {
        ($live:literal) => {{
            const LIVE: usize = $live;
            debug_assert!(
                element[j..j + LIVE].iter().all(|&h| h as usize == el.e),
                "points not sorted by element"
            );
            let r = j..j + 4;
            let volume4: &mut [R; 4] = (&mut volume[r.clone()]).try_into().unwrap();
            let mut pore4 = pore
                .as_deref_mut()
                .map(|p| <&mut [R; 4]>::try_from(&mut p[r.clone()]).unwrap());
            let (strain, outside) = four_points::<E, R, LIVE>(
                &terms,
                el.map,
                el.first,
                (&mut x[r.clone()]).try_into().unwrap(),
                (&mut u[r.clone()]).try_into().unwrap(),
                (&mut stress[r.clone()]).try_into().unwrap(),
                volume4,
                pore4.as_deref_mut(),
                guard,
                locate.is_some(),
            );
            let mass4 = *<&[R; 4]>::try_from(&mass[r]).unwrap();
            if let (Some(open), Some(sums)) = (open.as_deref_mut(), &sums) {
                let on = std::array::from_fn(|q| q < LIVE);
                sums.add(open, on, strain, *volume4, mass4, pore4.map(|p| *p));
            }
            if let Some((found, offset)) = locate.as_mut().filter(|_| outside) {
                for i in j..j + LIVE {
                    relocate(cx.mesh, found, *offset + i, &mut element[i], &x[i]);
                }
            }
            j += LIVE;
        }};
    }
    // An element of exactly a tetrahedron's usual four points or a triangle's three, all
    // taking part (the common case), outside the batch loop: its terms go into lanes where
    // they are used, not hoisted out of the loop into lanes and spilled.
    if j + 4 <= n && usual_of::<E>(active, material, j, end, lead) {
        if usual_count::<E>() == 4 {
            in_place!(4);
        } else {
            in_place!(3);
        }
        return j;
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
        if j + 4 <= n {
            // (Four by a constant count, the common case: one compare of each array's four.)
            if live == 4 && all_take_part(4) {
                in_place!(4);
                continue;
            }
            if live < 4 && all_take_part(live) {
                match live {
                    3 => in_place!(3),
                    2 => in_place!(2),
                    _ => in_place!(1),
                }
                continue;
            }
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
        debug_assert!(
            b.points().all(|i| element[i] as usize == el.e),
            "points not sorted by element"
        );
        let (mut x4, mut u4) = (b.at.map(|i| x[i]), b.at.map(|i| u[i]));
        let (mut s4, mut v4) = (b.at.map(|i| stress[i]), b.at.map(|i| volume[i]));
        let mut p4 = pore.as_deref().map(|p| b.at.map(|i| p[i]));
        let (strain, outside) = four_points::<E, R, 4>(
            &terms,
            el.map,
            el.first,
            &mut x4,
            &mut u4,
            &mut s4,
            &mut v4,
            p4.as_mut(),
            guard,
            locate.is_some(),
        );
        for i in b.points() {
            let q = i - j;
            (x[i], u[i], stress[i], volume[i]) = (x4[q], u4[q], s4[q], v4[q]);
            if let (Some(p), Some(p4)) = (pore.as_deref_mut(), &p4) {
                p[i] = p4[q];
            }
        }
        if let (Some(open), Some(sums)) = (open.as_deref_mut(), &sums) {
            sums.add(open, b.on, strain, v4, b.at.map(|i| mass[i]), p4);
        }
        // (The lanes past the batch's points repeat one of its points.)
        if let Some((found, offset)) = locate.as_mut().filter(|_| outside) {
            for i in b.points() {
                relocate(cx.mesh, found, *offset + i, &mut element[i], &x[i]);
            }
        }
        j += b.len;
    }
    j
}

/// What the guard's sums take of a batch besides its points' values (for one material).
struct GuardTerms<R: Real> {
    rho0: R,
    min_ratio: R,
    n_over_kw: R,
}

impl<R: Real> GuardTerms<R> {
    /// Adds the batch's points (`on`: the lanes whose point takes part) to `open`, point by
    /// point in order, as the point loop adds them: the strain-energy term, the liquid's
    /// energy, and the volume check's margin (V ρ0 - r m).
    #[inline(always)]
    fn add(
        &self,
        open: &mut Open,
        on: [bool; 4],
        strain: [R; 4],
        v1: [R; 4],
        mass: [R; 4],
        pore: Option<[R; 4]>,
    ) {
        for q in 0..4 {
            if !on[q] {
                continue;
            }
            let margin = v1[q] * self.rho0 - self.min_ratio * mass[q];
            open.strain += strain[q].f64();
            if let Some(pore) = pore {
                let p = pore[q];
                open.liquid += (v1[q] * p * p * self.n_over_kw + R::ZERO * p).f64();
            }
            let m = margin.f64();
            if m < open.volume_margin {
                open.volume_margin = m;
            }
        }
    }
}

/// An element's terms, each formed as the point loop forms it at every point, and put into all
/// four lanes where a batch uses it (formed into lanes here, the thirty-odd vectors were
/// spilled and reloaded: docs/design.md §9).
struct Terms<R: Real> {
    t: <R::Four as Four<R>>::Token,
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
        t: <R::Four as Four<R>>::Token,
        el: &ElementView<'_, E, R>,
        law: &crate::material::linear_elastic::LinearElastic<R>,
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
        Terms {
            t,
            vel: std::array::from_fn(|k| {
                std::array::from_fn(|c| if k < E::NODES { el.vel[k][c] } else { R::ZERO })
            }),
            increment,
            spin: cx.objective.then(|| spin_increment(el.l, dt)),
            ev: de[0] + de[1] + de[2],
            grow: R::ONE + de[0] + de[1] + de[2],
            de,
            dt,
            rate,
            tol: R::of(-tolerance::<R>()),
        }
    }
}

/// One batch of four points of the element (`x`, `u`, `stress`, `volume` and the pore
/// pressures, updated in place in the first `LIVE` lanes, the others computed and left as they
/// were): the point loop's update, lane by lane. Returns each point's strain-energy term for
/// the guard's sums (with `guard`; zeros without), and with `locate` whether one of the `LIVE`
/// points' new shape values put it outside the element (beyond the locate tolerance,
/// [`crate::element::locate::run_inside`]'s test).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn four_points<E: Element, R: Real, const LIVE: usize>(
    k: &Terms<R>,
    map: &E::Map<R>,
    first: &V3<R>,
    x: &mut [V3<R>; 4],
    u: &mut [V3<R>; 4],
    stress: &mut [[R; 6]; 4],
    volume: &mut [R; 4],
    pore: Option<&mut [R; 4]>,
    guard: bool,
    locate: bool,
) -> ([R; 4], bool) {
    const { assert!(LIVE >= 1 && LIVE <= 4) };
    let t = k.t;
    let lanes = |v: [R; 4]| R::Four::load(t, &v);
    let sp = |v: R| R::Four::splat(t, v);
    let zero = R::Four::splat(t, R::ZERO);
    let xl = R::Four::load_points3(t, x);
    let n = E::shape_four(t, map, first, &xl);
    // The pore pressure's smoothed rate, from the nodes at the start-of-step position.
    if let (Some(p), Some(rate)) = (pore, &k.rate) {
        let mut change = zero;
        for kk in 0..E::NODES {
            change = change + n[kk] * sp(rate[kk]);
        }
        let p1 = lanes(*p) + change * sp(k.dt);
        store_live::<R, LIVE>(t, p1, p);
    }
    let mut dx = [zero; 3];
    for kk in 0..E::NODES {
        for c in 0..E::DIM {
            dx[c] = dx[c] + n[kk] * sp(k.vel[kk][c]);
        }
    }
    let s0 = R::Four::load_points6(t, stress);
    let mut s1: [R::Four; 6] = std::array::from_fn(|c| s0[c] + sp(k.increment[c]));
    if let Some(spin) = &k.spin {
        // Anura3D's objective terms, after the law's update: the co-rotation and -tr(Δε) σ
        // of the start-of-step stress.
        let h = rotation_four::<R>(t, &s0, spin);
        for c in 0..6 {
            s1[c] = s1[c] + (h[c] - sp(k.ev) * s0[c]);
        }
    }
    let v0 = lanes(*volume);
    let v1 = v0 * sp(k.grow);
    let u0 = R::Four::load_points3(t, u);
    // (A section's out-of-plane components as loaded: stored back, they keep their bits.)
    let (mut x1, mut u1) = (xl, u0);
    for a in 0..E::DIM {
        x1[a] = xl[a] + sp(k.dt) * dx[a];
        u1[a] = u0[a] + sp(k.dt) * dx[a];
    }
    if LIVE == 4 {
        // Four points' values back to one point after another, moved in registers.
        R::Four::store_points3(x1, x);
        R::Four::store_points3(u1, u);
        R::Four::store_points6(s1, stress);
    } else {
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
    store_live::<R, LIVE>(t, v1, volume);
    let outside = locate && {
        // The lanes past `LIVE` never outside: -∞ (no value is below it, NaN neither).
        let tol = if LIVE == 4 {
            sp(k.tol)
        } else {
            let below = R::of(f64::NEG_INFINITY);
            lanes(std::array::from_fn(|q| {
                if q < LIVE {
                    R::of(-tolerance::<R>())
                } else {
                    below
                }
            }))
        };
        let n1 = E::shape_four(t, map, first, &x1);
        let mut out = false;
        for nk in n1.iter().take(E::NODES) {
            out |= nk.any_lt(tol);
        }
        out
    };
    if !guard {
        return ([R::ZERO; 4], outside);
    }
    // As the point loop: the work of the mean stress on the start volume (shear components
    // twice, tensor shear strains; a section's out-of-plane ones, +0, left out), and a NaN for
    // a non-finite position or volume.
    let mut w = zero;
    for c in 0..if E::DIM == 2 { 4 } else { 6 } {
        let twice = R::Four::splat(t, if c < 3 { R::ONE } else { R::of(2.0) });
        w = w + twice * (s0[c] + s1[c]) * sp(k.de[c]);
    }
    let finite = zero * (x1[0] + x1[1] + x1[2] + v1);
    ((w * v0 + finite).to_array(), outside)
}

/// Stores the first `LIVE` lanes of `v` into `to`, leaving the others: one vector store, of the
/// others' values as they are past `LIVE`.
#[inline(always)]
fn store_live<R: Real, const LIVE: usize>(
    t: <R::Four as Four<R>>::Token,
    v: R::Four,
    to: &mut [R; 4],
) {
    *to = v.first_of(R::Four::load(t, to), LIVE).to_array();
}

/// [`super::rotation_lanes`] of four points' stresses (`s[c]`: component c, lane q: point q)
/// for the spin increment `w` (ω_xy, ω_yz, ω_zx): the same operations.
#[inline(always)]
fn rotation_four<R: Real>(
    t: <R::Four as Four<R>>::Token,
    s: &[R::Four; 6],
    w: &[R; 3],
) -> [R::Four; 6] {
    let [xx, yy, zz, xy, yz, zx] = *s;
    let sp = |v: R| R::Four::splat(t, v);
    let (wxy, wyz, wzx, two) = (sp(w[0]), sp(w[1]), sp(w[2]), sp(R::of(2.0)));
    [
        two * (wxy * xy - wzx * zx),
        two * (wyz * yz - wxy * xy),
        two * (wzx * zx - wyz * yz),
        wxy * (yy - xx) + wyz * zx - wzx * yz,
        wyz * (zz - yy) + wzx * xy - wxy * zx,
        wzx * (xx - zz) + wxy * yz - wyz * xy,
    ]
}
