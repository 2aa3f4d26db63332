//! The stress pass for plane-strain triangles four elements at a time, one lane per element
//! ([`crate::four`]).
//!
//! [`super::lanes`] puts an element's points into the lanes, so a triangle's three points fill
//! three of four lanes, and everything the element shares (its velocity gradient, strain and
//! stress increments, spin, map) is formed in scalars, once per element, for only three points:
//! a triangle ran as many instructions per point as a tetrahedron (docs/design.md §9). Here four
//! consecutive triangles, each of its usual three points of one linear-elastic material, take one
//! lane each: the element's terms are formed once for the four, and each of the three point
//! slots updates four points at once. Each lane does the operations of the per-element code in
//! the same order, so the bits are those of [`super::lanes`] (and of the general batches).

use crate::element::locate::{relocate, tolerance, Outcome};
use crate::element::Element;
use crate::four::Four;
use crate::material::law::Law;
use crate::real::{Real, V3};
use crate::step::contact::maps;

use super::lanes::{rotation_four, GuardTerms, Points};
use super::{Open, Pass};

/// Elements per group: one per lane.
pub(super) const GROUP: usize = 4;

/// A triangle's usual points (those of a group's elements).
const POINTS: usize = 3;

/// Updates the triangles `e..e + 4`, whose twelve points (three each, in element order) start
/// at position `j` of the chunk's arrays, if all twelve take part and are of one
/// linear-elastic material: stress, position, displacement, volume, the pore pressure's rate,
/// with `open` the guard's sums (the caller has checked that the four lie in one block), and
/// with `locate` (the chunk's outcome and its first point's index) the elements of the points
/// of each triangle one of whose points left it. Returns whether it took the group (if not,
/// nothing is changed).
///
/// For plane-strain triangles without strain smoothing, each of exactly three points (the
/// caller's checks).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn four_triangles<E: Element, R: Real, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    t: <R::Four as Four<R>>::Token,
    e: usize,
    p: Points<'_, R>,
    j: usize,
    open: Option<&mut Open>,
    locate: Option<(&mut Outcome, usize)>,
) -> bool {
    if WIDE {
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in the chunk's AVX2 copy, which runs where the processor has
        // AVX2.
        unsafe { group_avx2(cx, t, e, p, j, open, locate) }
    } else {
        group(cx, t, e, p, j, open, locate)
    }
}

/// [`group`] compiled with AVX2 (on x86-64; elsewhere AVX2 is never chosen, and this is
/// [`group`]): a function of its own, since inlined into the chunk's long AVX2 copy its
/// closures were left calls, compiled for the baseline.
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
#[allow(clippy::too_many_arguments)]
#[inline(never)]
unsafe fn group_avx2<E: Element, R: Real>(
    cx: &Pass<'_, E, R>,
    t: <R::Four as Four<R>>::Token,
    e: usize,
    p: Points<'_, R>,
    j: usize,
    open: Option<&mut Open>,
    locate: Option<(&mut Outcome, usize)>,
) -> bool {
    group(cx, t, e, p, j, open, locate)
}

/// The update of [`four_triangles`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn group<E: Element, R: Real>(
    cx: &Pass<'_, E, R>,
    t: <R::Four as Four<R>>::Token,
    e: usize,
    p: Points<'_, R>,
    j: usize,
    open: Option<&mut Open>,
    locate: Option<(&mut Outcome, usize)>,
) -> bool {
    debug_assert!(E::DIM == 2 && E::NODES == 3 && !E::AXISYMMETRIC);
    debug_assert!(cx.smoothing.is_none());
    let Points {
        x,
        u,
        stress,
        volume,
        pore,
        active,
        material,
        mass,
        element,
    } = p;
    let span = j..j + GROUP * POINTS;
    let (Some(act), Some(mat)) = (active.get(span.clone()), material.get(span.clone())) else {
        return false;
    };
    let lead = mat[0];
    if !(act.iter().all(|&a| a) && mat.iter().all(|&m| m == lead) && maps(cx.body, lead)) {
        return false;
    }
    let Law::LinearElastic(law) = &cx.laws[lead as usize] else {
        return false;
    };
    // The group's points, one array of twelve each (one bounds check per array).
    let x: &mut [V3<R>; 12] = (&mut x[span.clone()]).try_into().expect("twelve");
    let u: &mut [V3<R>; 12] = (&mut u[span.clone()]).try_into().expect("twelve");
    let stress: &mut [[R; 6]; 12] = (&mut stress[span.clone()]).try_into().expect("twelve");
    let volume: &mut [R; 12] = (&mut volume[span.clone()]).try_into().expect("twelve");
    let mass: &[R; 12] = mass[span.clone()].try_into().expect("twelve");
    let mut pore: Option<&mut [R; 12]> =
        pore.map(|p| (&mut p[span.clone()]).try_into().expect("twelve"));
    debug_assert!(
        (0..GROUP * POINTS).all(|i| element[j + i] as usize == e + i / POINTS),
        "points not sorted by element"
    );
    let sp = |v: R| R::Four::splat(t, v);
    let zero = sp(R::ZERO);
    let (mesh, dt) = (cx.mesh, cx.dt);
    // (Written out: `from_fn` was left a call here.)
    let corner = |i: usize| mesh.corners[e + i].as_ref();
    let corners: [&[u32]; GROUP] = [corner(0), corner(1), corner(2), corner(3)];
    let grad = |i: usize| mesh.grad[e + i].as_ref();
    let grads: [&[V3<R>]; GROUP] = [grad(0), grad(1), grad(2), grad(3)];
    let maps_: [&E::Map<R>; GROUP] = [
        &mesh.map[e],
        &mesh.map[e + 1],
        &mesh.map[e + 2],
        &mesh.map[e + 3],
    ];
    // Node k's velocity component c, and its gradient's component b, per element.
    let vel: [[R::Four; 2]; 3] = fill([zero; 2], |k| {
        fill(zero, |c| {
            of_group::<R>(t, |i| cx.g.vel[corners[i][k] as usize][c])
        })
    });
    let grad: [[R::Four; 2]; 3] = fill([zero; 2], |k| {
        fill(zero, |b| of_group::<R>(t, |i| grads[i][k][b]))
    });
    // The velocity gradient L[a][b] = ∂v_a/∂x_b, summed over the nodes from 0 as the chunk's
    // loop sums it (its out-of-plane entries stay 0).
    let mut l = [[zero; 3]; 3];
    for k in 0..3 {
        for a in 0..2 {
            for b in 0..2 {
                l[a][b] = l[a][b] + vel[k][a] * grad[k][b];
            }
        }
    }
    // `strain_increment`, `LinearElastic::increment` and `spin_increment`, lane by lane.
    let (half, sdt) = (sp(R::of(0.5)), sp(dt));
    let de = [
        l[0][0] * sdt,
        l[1][1] * sdt,
        l[2][2] * sdt,
        half * (l[0][1] + l[1][0]) * sdt,
        zero,
        zero,
    ];
    let (g2, lambda) = (sp(law.shear + law.shear), sp(law.lambda));
    let tr = lambda * (de[0] + de[1] + de[2]);
    let increment: [R::Four; 6] = fill(zero, |c| if c < 3 { tr + g2 * de[c] } else { g2 * de[c] });
    let spin = cx.objective.then(|| {
        [
            half * (l[0][1] - l[1][0]) * sdt,
            half * (l[1][2] - l[2][1]) * sdt,
            half * (l[2][0] - l[0][2]) * sdt,
        ]
    });
    let ev = de[0] + de[1] + de[2];
    let grow = sp(R::ONE) + de[0] + de[1] + de[2];
    // The pore pressure's nodal rates, where the material has a liquid and the run one.
    let rate: Option<[R::Four; 3]> = cx
        .pore_rate
        .as_ref()
        .filter(|r| r.fluids[lead as usize].is_some())
        .map(|r| {
            fill(zero, |k| {
                of_group::<R>(t, |i| r.nodal[corners[i][k] as usize])
            })
        });
    // The map from global to local coordinates and the first corner, per element.
    let first: [R::Four; 2] = fill(zero, |a| {
        of_group::<R>(t, |i| mesh.x[corners[i][0] as usize][a])
    });
    let m: [[R::Four; 2]; 2] = fill([zero; 2], |r| {
        fill(zero, |c| of_group::<R>(t, |i| E::map_entry(maps_[i], r, c)))
    });
    let one = sp(R::ONE);
    let tol = R::of(-tolerance::<R>());
    let guard = open.is_some();
    // Per point slot q, each lane's strain-energy term, new volume and pore pressure (for the
    // guard's sums), and per element whether one of its points left it.
    let mut strain = [[R::ZERO; GROUP]; POINTS];
    let mut v1s = [[R::ZERO; GROUP]; POINTS];
    let mut p1s = [[R::ZERO; GROUP]; POINTS];
    let mut outside = [false; GROUP];
    for q in 0..POINTS {
        let at = |i: usize| POINTS * i + q;
        let xl: [R::Four; 3] = fill(zero, |a| of_group::<R>(t, |i| x[at(i)][a]));
        let n = shape::<R>(&xl, &first, &m, one);
        if let Some(p) = pore.as_deref_mut() {
            let p0 = of_group::<R>(t, |i| p[at(i)]);
            let p1 = match &rate {
                Some(rate) => {
                    let mut change = zero;
                    for k in 0..3 {
                        change = change + n[k] * rate[k];
                    }
                    let p1 = p0 + change * sdt;
                    let v = p1.to_array();
                    for i in 0..GROUP {
                        p[at(i)] = v[i];
                    }
                    p1
                }
                None => p0,
            };
            p1s[q] = p1.to_array();
        }
        let mut dx = [zero; 2];
        for k in 0..3 {
            for c in 0..2 {
                dx[c] = dx[c] + n[k] * vel[k][c];
            }
        }
        let s0: [R::Four; 6] = fill(zero, |c| of_group::<R>(t, |i| stress[at(i)][c]));
        let mut s1: [R::Four; 6] = fill(zero, |c| s0[c] + increment[c]);
        if let Some(spin) = spin {
            let h = rotation_four::<R>(&s0, spin, sp(R::of(2.0)));
            for c in 0..6 {
                s1[c] = s1[c] + (h[c] - ev * s0[c]);
            }
        }
        let v0 = of_group::<R>(t, |i| volume[at(i)]);
        let v1 = v0 * grow;
        let u0: [R::Four; 2] = fill(zero, |a| of_group::<R>(t, |i| u[at(i)][a]));
        // (The out-of-plane components are not written: they keep their bits.)
        let mut x1 = xl;
        let mut u1 = u0;
        for a in 0..2 {
            x1[a] = xl[a] + sdt * dx[a];
            u1[a] = u0[a] + sdt * dx[a];
        }
        let none = [R::ZERO; GROUP];
        let x1a: [[R; GROUP]; 2] = fill(none, |a| x1[a].to_array());
        let u1a: [[R; GROUP]; 2] = fill(none, |a| u1[a].to_array());
        let s1a: [[R; GROUP]; 6] = fill(none, |c| s1[c].to_array());
        let v1a = v1.to_array();
        for i in 0..GROUP {
            let k = at(i);
            for a in 0..2 {
                x[k][a] = x1a[a][i];
                u[k][a] = u1a[a][i];
            }
            stress[k] = std::array::from_fn(|c| s1a[c][i]);
            volume[k] = v1a[i];
        }
        v1s[q] = v1a;
        if locate.is_some() {
            let n1 = shape::<R>(&x1, &first, &m, one);
            let n1: [[R; GROUP]; 3] = fill([R::ZERO; GROUP], |k| n1[k].to_array());
            for (i, out) in outside.iter_mut().enumerate() {
                // (As `Four::any_lt`: false for a NaN.)
                *out |= n1.iter().any(|nk| nk[i] < tol);
            }
        }
        if guard {
            // The point loop's work of the mean stress on the start volume (shear components
            // twice, tensor shear strains; the out-of-plane ones, +0, left out), and a NaN for a
            // non-finite position or volume.
            let mut w = zero;
            for c in 0..4 {
                let twice = sp(if c < 3 { R::ONE } else { R::of(2.0) });
                w = w + twice * (s0[c] + s1[c]) * de[c];
            }
            let finite = zero * (x1[0] + x1[1] + x1[2] + v1);
            strain[q] = (w * v0 + finite).to_array();
        }
    }
    if let Some(open) = open {
        let sums = GuardTerms {
            rho0: cx.initial_density[lead as usize],
            min_ratio: cx.min_ratio,
            n_over_kw: cx.fluids[lead as usize]
                .as_ref()
                .map_or(R::ZERO, |f| f.n_over_kw),
        };
        // Element by element, point by point, as the per-element passes add them.
        let on = [true, true, true, false];
        for i in 0..GROUP {
            let of = |v: &[[R; GROUP]; POINTS]| std::array::from_fn(|q| v[q.min(2)][i]);
            let m4 = std::array::from_fn(|q| mass[POINTS * i + q.min(2)]);
            let p4 = pore.is_some().then(|| of(&p1s));
            sums.add(open, on, of(&strain), of(&v1s), m4, p4);
        }
    }
    if let Some((found, offset)) = locate {
        for (i, &out) in outside.iter().enumerate() {
            if out {
                for q in 0..POINTS {
                    let k = j + POINTS * i + q;
                    relocate(mesh, found, offset + k, &mut element[k], &x[k - j]);
                }
            }
        }
    }
    true
}

/// `Tri3::shape_four` with one element's map `m` and first corner `first` per lane: the same
/// operations.
#[inline(always)]
fn shape<R: Real>(
    x: &[R::Four; 3],
    first: &[R::Four; 2],
    m: &[[R::Four; 2]; 2],
    one: R::Four,
) -> [R::Four; 3] {
    let d = [x[0] - first[0], x[1] - first[1]];
    let xi = m[0][0] * d[0] + m[0][1] * d[1];
    let eta = m[1][0] * d[0] + m[1][1] * d[1];
    [one - xi - eta, xi, eta]
}

/// `[f(0), f(1), …]`, filled in place from `zero` by a loop the compiler unrolls: in a pass
/// this long `std::array::from_fn` was left a call, and the intrinsics in its closures calls
/// too.
#[inline(always)]
fn fill<F: Copy, const N: usize>(zero: F, mut f: impl FnMut(usize) -> F) -> [F; N] {
    let mut a = [zero; N];
    for (i, v) in a.iter_mut().enumerate() {
        *v = f(i);
    }
    a
}

/// One vector of `f(i)` in lane i: lane i of a group value is element e + i's.
#[inline(always)]
fn of_group<R: Real>(t: <R::Four as Four<R>>::Token, f: impl Fn(usize) -> R) -> R::Four {
    R::Four::load(t, &fill(R::ZERO, f))
}
