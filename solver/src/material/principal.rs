//! Principal values and directions of a symmetric 3×3 tensor (stress, strain), generic over the
//! run's precision, deterministic and exact for repeated eigenvalues.
//!
//! The closed form first: the characteristic cubic of the deviator (trigonometric solution)
//! gives the eigenvalue farthest from the middle one, whose vector is then a cross product of
//! two rows of σ - λI (well conditioned: its gap is at least half the spread). The two others
//! follow from the 2×2 problem in the plane normal to it, solved by one exact rotation, so a
//! nearly repeated pair, whose cubic roots lose half their digits (the edges of a Mohr–Coulomb
//! pyramid), never comes from the cubic. A nearly isotropic tensor goes to cyclic Jacobi
//! rotations in a fixed order instead (200 against 148 ns of CPU time per tensor measured on the
//! shared development machine). A return needs less ([`split`]: 80 ns).
//!
//! The cost is latency: a chain of square roots and divisions each waiting on the last. The
//! code keeps that chain short where it can (independent square root and reciprocal of J2,
//! Estrin's scheme for the cubic's root, projectors scaled by one division instead of a
//! normalised vector, branch-free choices where the outcome follows the tensor's orientation).

use crate::real::Real;

/// Sweeps after which Jacobi stops whatever the remainder (it converges quadratically: two to
/// four sweeps reach round-off in f64).
const MAX_SWEEPS: usize = 50;

/// A symmetric tensor's eigen decomposition: `values` ascending, `vectors[i]` the unit vector of
/// `values[i]`; the vectors form a right- or left-handed orthonormal basis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Principal<R: Real> {
    /// Eigenvalues, smallest first (for a stress with tension positive: most compressive first).
    pub values: [R; 3],
    /// Unit eigenvectors, one per value.
    pub vectors: [[R; 3]; 3],
}

/// The eigen decomposition of the symmetric tensor `s` (xx yy zz xy yz zx).
#[inline]
pub fn principal<R: Real>(s: &[R; 6]) -> Principal<R> {
    closed_form(s).unwrap_or_else(|| jacobi(s))
}

#[inline]
fn dot3<R: Real>(a: &[R; 3], b: &[R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn cross<R: Real>(a: &[R; 3], b: &[R; 3]) -> [R; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// [`cross`] lane by lane (`a[k][q]`: component k of lane q), each lane's arithmetic the
/// one-lane product's.
#[inline(always)]
fn cross_lanes<R: Real, const W: usize>(a: &[&[R; W]; 3], b: &[&[R; W]; 3]) -> [[R; W]; 3] {
    let mut out = [[R::ZERO; W]; 3];
    for q in 0..W {
        out[0][q] = a[1][q] * b[2][q] - a[2][q] * b[1][q];
        out[1][q] = a[2][q] * b[0][q] - a[0][q] * b[2][q];
        out[2][q] = a[0][q] * b[1][q] - a[1][q] * b[0][q];
    }
    out
}

/// [`dot3`] lane by lane.
#[inline(always)]
fn dot_lanes<R: Real, const W: usize>(a: &[[R; W]; 3], b: &[[R; W]; 3]) -> [R; W] {
    std::array::from_fn(|q| a[0][q] * b[0][q] + a[1][q] * b[1][q] + a[2][q] * b[2][q])
}

/// Sorts three (value, vector) pairs by value.
fn sorted<R: Real>(values: [R; 3], vectors: [[R; 3]; 3]) -> Principal<R> {
    let mut order = [0usize, 1, 2];
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if values[order[j]] < values[order[i]] {
            order.swap(i, j);
        }
    }
    Principal {
        values: order.map(|k| values[k]),
        vectors: order.map(|k| vectors[k]),
    }
}

/// The eigenvalue of `s` farthest from the middle one, from the characteristic cubic of the
/// deviator (a well-conditioned root: its gap is at least half the spread, so the cubic gives it
/// to round-off), less the mean p; an eigenvector of it, not normalised (the longest cross
/// product of two rows of s - λI), its squared length, and p. `None` for a tensor isotropic
/// to round-off, or a non-finite one.
#[inline]
fn far_root<R: Real>(s: &[R; 6]) -> Option<(R, [R; 3], R, R)> {
    let largest = s.iter().fold(R::ZERO, |m, x| m.max(x.abs()));
    let f = far_root_lanes::<R, 1>(&s.map(|x| [x]), &[largest]);
    f.ok[0].then(|| (f.far[0], f.n.map(|c| c[0]), f.size[0], f.p[0]))
}

/// [`far_root`] of `W` tensors at once (`s[c][q]`: component c of tensor q), each lane's
/// arithmetic the one-tensor loop's in the same order (the same bits whatever `W`).
struct FarLanes<R: Real, const W: usize> {
    /// The far eigenvalue less the mean.
    far: [R; W],
    /// Its eigenvector, not normalised (`n[c][q]`).
    n: [[R; W]; 3],
    /// The vector's squared length.
    size: [R; W],
    /// The mean.
    p: [R; W],
    /// False where [`far_root`] gives `None` (the other values are then meaningless).
    ok: [bool; W],
}

/// The lanes of [`far_root`]: the long chain of dependent square roots, divisions and products
/// is latency, so several tensors side by side keep the core busy (and go to vector
/// instructions where the compiler can). `largest`: each tensor's largest entry in magnitude.
#[inline(always)]
fn far_root_lanes<R: Real, const W: usize>(s: &[[R; W]; 6], largest: &[R; W]) -> FarLanes<R, W> {
    let third = R::of(1.0 / 3.0);
    let (xy, yz, zx) = (&s[3], &s[4], &s[5]);
    let mut p = [R::ZERO; W];
    let mut d = [[R::ZERO; W]; 3];
    let mut j2 = [R::ZERO; W];
    let mut j3 = [R::ZERO; W];
    let mut far = [R::ZERO; W];
    let mut ok = [true; W];
    for q in 0..W {
        p[q] = (s[0][q] + s[1][q] + s[2][q]) * third;
        for c in 0..3 {
            d[c][q] = s[c][q] - p[q];
        }
        let (d0, d1, d2) = (d[0][q], d[1][q], d[2][q]);
        let (xy, yz, zx) = (xy[q], yz[q], zx[q]);
        j2[q] = R::of(0.5) * (d0 * d0 + d1 * d1 + d2 * d2) + xy * xy + yz * yz + zx * zx;
        let small = R::of(1e3 * R::EPSILON) * largest[q];
        ok[q] = j2[q] > small * small;
        j3[q] = d0 * (d1 * d2 - yz * yz) - xy * (xy * d2 - yz * zx) + zx * (xy * yz - d1 * zx);
    }
    // Deviatoric eigenvalues 2 r cos(θ - 2πk/3), r = sqrt(J2/3), cos 3θ = J3 / (2 r³). The
    // square root and the reciprocal of J2 are independent (1/r = 3r/J2), which shortens the
    // chain of dependent operations: cos 3θ = 4.5 J3 r / J2².
    for q in 0..W {
        let (j2f, j3f) = (j2[q].f64(), j3[q].f64());
        let r = (j2f * (1.0 / 3.0)).sqrt();
        let inv = 1.0 / j2f;
        let c3 = (4.5 * j3f * r * (inv * inv)).clamp(-1.0, 1.0);
        // The largest root is the far one for cos 3θ ≥ 0, the smallest (the largest of -s,
        // negated) otherwise: either way ± 2r · t(|cos 3θ|).
        let t = 2.0 * r * largest_cubic_root(c3.abs());
        far[q] = R::of(if c3 >= 0.0 { t } else { -t });
    }
    // The rows of s - λI, each value held across the lanes, so that the cross products below
    // are operations over the lanes.
    let diag: [[R; W]; 3] = std::array::from_fn(|c| std::array::from_fn(|q| d[c][q] - far[q]));
    let rows = [[&diag[0], xy, zx], [xy, &diag[1], yz], [zx, yz, &diag[2]]];
    // The longest of the three cross products, chosen without branches (which one wins
    // depends on the tensor's orientation, which branch prediction cannot learn).
    let mut n = cross_lanes(&rows[0], &rows[1]);
    let mut size = dot_lanes(&n, &n);
    for c in [
        cross_lanes(&rows[0], &rows[2]),
        cross_lanes(&rows[1], &rows[2]),
    ] {
        let cc = dot_lanes(&c, &c);
        for q in 0..W {
            let longer = cc[q] > size[q];
            for k in 0..3 {
                n[k][q] = if longer { c[k][q] } else { n[k][q] };
            }
            size[q] = if longer { cc[q] } else { size[q] };
        }
    }
    // The rows span a plane (rank 2) when the eigenvalue is simple: their cross product is
    // of the order of J2.
    for q in 0..W {
        let tiny = R::of(1e-6) * j2[q];
        ok[q] = ok[q] && size[q] > tiny * tiny;
    }
    FarLanes {
        far,
        n,
        size,
        p,
        ok,
    }
}

/// [`far_root`] with the vector normalised and the eigenvalue refined as its Rayleigh
/// quotient.
#[inline]
fn far_pair<R: Real>(s: &[R; 6]) -> Option<(R, [R; 3], R)> {
    let (_, mut n, size, p) = far_root(s)?;
    let d = [s[0] - p, s[1] - p, s[2] - p];
    let (xy, yz, zx) = (s[3], s[4], s[5]);
    let inv = R::ONE / size.sqrt();
    n = n.map(|x| x * inv);
    let an = [
        d[0] * n[0] + xy * n[1] + zx * n[2],
        xy * n[0] + d[1] * n[1] + yz * n[2],
        zx * n[0] + yz * n[1] + d[2] * n[2],
    ];
    Some((dot3(&n, &an), n, p))
}

/// cos(arccos(x) / 3) for x in [0, 1]: the largest root t of 4t³ - 3t = x, in [√3/2, 1], where
/// the cubic is steep (slope ≥ 6), so a least-squares polynomial of degree 8 (error below 5e-9;
/// t(x) is analytic on [0, 1], its nearest branch point at x = -1) and one Newton step reach
/// round-off; cheaper than the arc cosine and the cosine it replaces. Estrin's scheme keeps the
/// chain of dependent operations short.
#[inline]
fn largest_cubic_root(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.8660254080339653,
        0.16666626797140022,
        -0.04810327827531805,
        0.02459885460999916,
        -0.015095325514813938,
        0.009372156692529285,
        -0.004929591698563008,
        0.0017714085638008321,
        -0.00030590350061488944,
    ];
    let x2 = x * x;
    let x4 = x2 * x2;
    let low = (C[0] + C[1] * x) + (C[2] + C[3] * x) * x2;
    let high = (C[4] + C[5] * x) + (C[6] + C[7] * x) * x2;
    let t = low + (high + C[8] * x4) * x4;
    t - (4.0 * t * t * t - 3.0 * t - x) / (12.0 * t * t - 3.0)
}

/// The closed form described in the module's comment; `None` for a tensor isotropic to
/// round-off, or a non-finite one.
fn closed_form<R: Real>(s: &[R; 6]) -> Option<Principal<R>> {
    let (ln, n, p) = far_pair(s)?;
    let d = [s[0] - p, s[1] - p, s[2] - p];
    let (xy, yz, zx) = (s[3], s[4], s[5]);
    // A unit vector normal to n: the axis least along n, less its part along n.
    let k = if n[0].abs() <= n[1].abs() && n[0].abs() <= n[2].abs() {
        0
    } else if n[1].abs() <= n[2].abs() {
        1
    } else {
        2
    };
    let mut u = [-n[k] * n[0], -n[k] * n[1], -n[k] * n[2]];
    u[k] += R::ONE;
    let inv = R::ONE / dot3(&u, &u).sqrt();
    u = u.map(|x| x * inv);
    let w = cross(&n, &u);
    let apply = |v: &[R; 3]| {
        [
            d[0] * v[0] + xy * v[1] + zx * v[2],
            xy * v[0] + d[1] * v[1] + yz * v[2],
            zx * v[0] + yz * v[1] + d[2] * v[2],
        ]
    };
    let (au, aw) = (apply(&u), apply(&w));
    let (a, b, c) = (dot3(&u, &au), dot3(&w, &au), dot3(&w, &aw));
    // One rotation diagonalises the 2×2 block [[a, b], [b, c]].
    let (mut lu, mut lw, mut vu, mut vw) = (a, c, u, w);
    if b != R::ZERO {
        let half = R::of(0.5);
        let theta = (c - a) * half / b;
        let t = if theta.abs() > R::of(1e15) {
            half / theta
        } else {
            let sign = if theta < R::ZERO { -R::ONE } else { R::ONE };
            sign / (theta.abs() + (R::ONE + theta * theta).sqrt())
        };
        let cr = R::ONE / (R::ONE + t * t).sqrt();
        let sr = t * cr;
        lu = a - t * b;
        lw = c + t * b;
        for i in 0..3 {
            vu[i] = cr * u[i] - sr * w[i];
            vw[i] = sr * u[i] + cr * w[i];
        }
    }
    Some(sorted([ln + p, lu + p, lw + p], [n, vu, vw]))
}

/// Cyclic Jacobi rotations in the fixed order (xy, yz, xz) until the off-diagonal part is at
/// round-off.
pub(crate) fn jacobi<R: Real>(s: &[R; 6]) -> Principal<R> {
    let mut a = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    // Columns of v are the eigenvectors as they form.
    let mut v = [[R::ZERO; 3]; 3];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = R::ONE;
    }
    let mut largest = R::ZERO;
    for x in s {
        largest = largest.max(x.abs());
    }
    // Stop once the off-diagonal part is at round-off of the largest entry: the eigenvalues
    // then carry an error of that size at most (Weyl), and where a remaining rotation would still
    // turn the vectors (nearly equal eigenvalues) it would not change Σ λ n ⊗ n beyond it.
    let tol = R::of(R::EPSILON) * largest;
    let half = R::of(0.5);
    for _ in 0..MAX_SWEEPS {
        let off = a[0][1].abs() + a[1][2].abs() + a[0][2].abs();
        // `!(off > tol)` also stops on NaN: a non-finite tensor ends after one look.
        if !(off > tol) {
            break;
        }
        for (p, q) in [(0, 1), (1, 2), (0, 2)] {
            let apq = a[p][q];
            if apq == R::ZERO {
                continue;
            }
            // tan of the angle that zeroes a_pq: the smaller root of t² + 2θt - 1 = 0.
            let theta = (a[q][q] - a[p][p]) * half / apq;
            let t = if theta.abs() > R::of(1e15) {
                // θ² would overflow; t = 1/(2θ) to within round-off there.
                half / theta
            } else {
                let sign = if theta < R::ZERO { -R::ONE } else { R::ONE };
                sign / (theta.abs() + (R::ONE + theta * theta).sqrt())
            };
            let c = R::ONE / (R::ONE + t * t).sqrt();
            let sn = t * c;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = R::ZERO;
            a[q][p] = R::ZERO;
            let r = 3 - p - q;
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = c * arp - sn * arq;
            a[p][r] = a[r][p];
            a[r][q] = sn * arp + c * arq;
            a[q][r] = a[r][q];
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - sn * vq;
                row[q] = sn * vp + c * vq;
            }
        }
    }
    sorted(
        [a[0][0], a[1][1], a[2][2]],
        [0, 1, 2].map(|k| [v[0][k], v[1][k], v[2][k]]),
    )
}

/// A symmetric tensor split along its best separated eigenvalue: that eigenpair, and the rest
/// as a multiple of the identity on the plane normal to it plus a traceless part there. This
/// is all a coaxial return needs when it moves the other two eigenvalues: their mean and half
/// gap carry over, and their vectors never have to be formed (for a nearly repeated pair, the
/// edges of a Mohr–Coulomb pyramid, they are the ill-conditioned and the costly part).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Split<R: Real> {
    /// Eigenvalues, smallest first (as [`Principal::values`]).
    pub values: [R; 3],
    /// Which of `values` (0 or 2) belongs to `outer`.
    pub far: usize,
    /// n ⊗ n for the unit eigenvector n of `values[far]` (xx yy zz xy yz zx): the projector
    /// onto its direction, all a coaxial rebuild needs of it.
    pub outer: [R; 6],
    /// The traceless part of the tensor in the plane normal to n (xx yy zz xy yz zx): half the
    /// gap of the other two eigenvalues times (w ⊗ w - u ⊗ u), u and w their vectors.
    pub plane: [R; 6],
    /// 1 / (half that gap), 0 for a pair repeated exactly.
    inv_gap: R,
}

/// w n ⊗ n (xx yy zz xy yz zx).
#[inline]
fn outer<R: Real>(n: &[R; 3], w: R) -> [R; 6] {
    outer_lanes(&n.map(|x| [x]), &[w]).map(|[x]| x)
}

/// [`outer`] of `W` vectors at once (`n[i][q]`: component i of lane q), as loops over the
/// lanes.
#[inline(always)]
fn outer_lanes<R: Real, const W: usize>(n: &[[R; W]; 3], w: &[R; W]) -> [[R; W]; 6] {
    let nw: [[R; W]; 3] = std::array::from_fn(|i| std::array::from_fn(|q| n[i][q] * w[q]));
    let mut o = [[R::ZERO; W]; 6];
    for (c, (i, j)) in [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)]
        .into_iter()
        .enumerate()
    {
        for q in 0..W {
            o[c][q] = nw[i][q] * n[j][q];
        }
    }
    o
}

/// The [`Split`] of the symmetric tensor `s` (xx yy zz xy yz zx): the closed form's best
/// separated eigenvalue (from the cubic) and its projector (a cross product over its squared
/// length: no square root), or the Jacobi decomposition's extreme pair for a nearly isotropic
/// tensor.
#[inline]
pub fn split<R: Real>(s: &[R; 6]) -> Split<R> {
    split_lanes::<R, 1>(&s.map(|x| [x])).lane(0)
}

/// The tensors of `s` brought into range for [`split_lanes`], each lane's factor back to its
/// scale (1 in range, a power of two outside it) and each lane's largest entry after scaling.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn in_range_lanes<R: Real, const W: usize>(s: &[[R; W]; 6]) -> ([[R; W]; 6], [R; W], [R; W]) {
    // A tensor whose largest entry lies outside [2^-16, 2^16] is decomposed scaled by a power
    // of two that brings it to about 1: the eigenvector's squared length there is a fourth
    // power of the entries, which f32 underflows for stresses of order 1e-10 (a load ramped up
    // from zero) and overflows above 1e9. Scaling by a power of two is exact, and the factor
    // is 1 in range, so the bits are those of the unscaled arithmetic wherever it was finite.
    let mut largest = [R::ZERO; W];
    for c in s {
        for q in 0..W {
            largest[q] = largest[q].max(c[q].abs());
        }
    }
    const LOW: f64 = 1.0 / 65536.0;
    const HIGH: f64 = 65536.0;
    // Outside the range, above 0 and finite (false for NaN), as a test without branches
    // (`contains` would branch).
    #[allow(clippy::manual_range_contains)]
    let scaled = |l: R| {
        let l = l.f64();
        ((l < LOW) | (l > HIGH)) & (l > 0.0) & (l < f64::INFINITY)
    };
    let mut t = *s;
    let mut up = [R::ONE; W];
    if largest.iter().fold(false, |any, &l| any | scaled(l)) {
        for q in 0..W {
            if !scaled(largest[q]) {
                continue;
            }
            // As far as the precision's exponent range allows (a lone point in free flight
            // carries stresses of 1e-100 kPa and less, which an f64 clamp at f32's range left
            // to underflow into 0/0).
            let reach = if R::BYTES == 4 { 120 } else { 1000 };
            let e = (largest[q].f64().log2().round() as i32).clamp(-reach, reach);
            let down = R::of(2f64.powi(-e));
            up[q] = R::of(2f64.powi(e));
            largest[q] = R::ZERO;
            for c in 0..6 {
                t[c][q] = s[c][q] * down;
                largest[q] = largest[q].max(t[c][q].abs());
            }
        }
    }
    (t, up, largest)
}

/// [`split`] of `W` tensors at once (`s[c][q]`: component c of tensor q), each lane the bits
/// of [`split`] of that tensor alone: the decomposition is a chain of dependent square roots
/// and divisions, so tensors side by side overlap their latencies, and each step is one
/// operation over the lanes (vector instructions) rather than one per tensor. The rare cases
/// (a tensor to scale, one nearly isotropic) are fixed up lane by lane afterwards.
#[inline(always)]
pub fn split_lanes<R: Real, const W: usize>(s: &[[R; W]; 6]) -> SplitLanes<R, W> {
    let (t, up, largest) = in_range_lanes(s);
    let s = &t;
    let f = far_root_lanes(s, &largest);
    // The far eigenvalue and its projector n ⊗ n / |n|² ([`outer`]) for every lane, then the
    // Jacobi decomposition's extreme pair where the closed form failed (a tensor isotropic to
    // round-off: what the lanes hold there is discarded).
    let mut lambda: [R; W] = std::array::from_fn(|q| f.far[q] + f.p[q]);
    let mut o = outer_lanes(&f.n, &f.size.map(|size| R::ONE / size));
    if f.ok.contains(&false) {
        for q in (0..W).filter(|&q| !f.ok[q]) {
            let p = jacobi(&s.map(|c| c[q]));
            // The extreme eigenvalue farther from the middle one.
            let k = if p.values[2] - p.values[1] >= p.values[1] - p.values[0] {
                2
            } else {
                0
            };
            lambda[q] = p.values[k];
            for (c, v) in outer(&p.vectors[k], R::ONE).into_iter().enumerate() {
                o[c][q] = v;
            }
        }
    }
    // From here each step is a loop over the lanes alone, which the compiler turns into
    // vector instructions (choices included, as blends).
    let half = R::of(0.5);
    let two = R::of(2.0);
    let mut m = [R::ZERO; W];
    for q in 0..W {
        m[q] = half * (s[0][q] + s[1][q] + s[2][q] - lambda[q]);
    }
    let k: [R; W] = std::array::from_fn(|q| m[q] - lambda[q]);
    // s - λ n ⊗ n - m (I - n ⊗ n): exact to the round-off of s itself, whatever the gap.
    let mut plane = [[R::ZERO; W]; 6];
    for c in 0..3 {
        for q in 0..W {
            plane[c][q] = s[c][q] - m[q] + k[q] * o[c][q];
        }
    }
    for c in 3..6 {
        for q in 0..W {
            plane[c][q] = s[c][q] + k[q] * o[c][q];
        }
    }
    // |plane| = sqrt(2) g for the half gap g.
    let mut g = [R::ZERO; W];
    for q in 0..W {
        let p = &plane;
        let norm2 = p[0][q] * p[0][q]
            + p[1][q] * p[1][q]
            + p[2][q] * p[2][q]
            + two * (p[3][q] * p[3][q] + p[4][q] * p[4][q] + p[5][q] * p[5][q]);
        g[q] = (half * norm2).sqrt();
    }
    // The far value above the pair, or below it; only round-off puts it between them (a
    // tensor isotropic to it), where the three are sorted and it counts as the top one when
    // above the pair's mean.
    let mut out = SplitLanes {
        values: [[R::ZERO; W]; 3],
        far_top: [false; W],
        outer: o,
        plane,
        inv_gap: [R::ZERO; W],
    };
    for q in 0..W {
        let (lambda, m, g) = (lambda[q], m[q], g[q]);
        let (lo, hi) = (m - g, m + g);
        let top = lambda >= hi;
        let bottom = lambda <= lo;
        let (a, b) = (lambda.min(lo), lambda.max(lo));
        let (mid_lo, mid_mid, mid_hi) = (a, b.min(hi), b.max(hi));
        let v0 = if bottom { lambda } else { mid_lo };
        let v1 = if bottom { lo } else { mid_mid };
        let v2 = if bottom { hi } else { mid_hi };
        out.values[0][q] = if top { lo } else { v0 };
        out.values[1][q] = if top { hi } else { v1 };
        out.values[2][q] = if top { lambda } else { v2 };
        out.far_top[q] = top || (!bottom && !(lambda <= m));
        // Off the critical path: the return runs beside it.
        let inv = R::ONE / (g * up[q]);
        out.inv_gap[q] = if g > R::ZERO { inv } else { R::ZERO };
    }
    // Back to the tensor's scale (exact: a power of two).
    if up.iter().any(|&u| u != R::ONE) {
        for q in 0..W {
            for i in 0..3 {
                out.values[i][q] *= up[q];
            }
            for c in 0..6 {
                out.plane[c][q] *= up[q];
            }
        }
    }
    out
}

/// The [`Split`]s of `W` tensors lane by lane (`values[i][q]`: value i of lane q), as
/// [`split_lanes`] forms them, so that a return and its rebuild run over the lanes too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitLanes<R: Real, const W: usize> {
    /// Each lane's [`Split::values`].
    pub values: [[R; W]; 3],
    /// Whether each lane's far value is its largest ([`Split::far`] 2) rather than its
    /// smallest (0).
    pub far_top: [bool; W],
    /// Each lane's [`Split::outer`].
    pub outer: [[R; W]; 6],
    /// Each lane's [`Split::plane`].
    pub plane: [[R; W]; 6],
    /// Each lane's 1 / (half the pair's gap).
    inv_gap: [R; W],
}

impl<R: Real, const W: usize> SplitLanes<R, W> {
    /// Lane `q`'s [`Split`].
    #[inline(always)]
    pub fn lane(&self, q: usize) -> Split<R> {
        Split {
            values: self.values.map(|v| v[q]),
            far: if self.far_top[q] { 2 } else { 0 },
            outer: self.outer.map(|v| v[q]),
            plane: self.plane.map(|v| v[q]),
            inv_gap: self.inv_gap[q],
        }
    }

    /// [`Split::rebuild`] of every lane with its eigenvalues `values` (`values[i][q]`), each
    /// lane the bits of its own rebuild.
    #[inline(always)]
    pub fn rebuild(&self, values: &[[R; W]; 3]) -> [[R; W]; 6] {
        let half = R::of(0.5);
        let (mut m, mut r, mut c) = ([R::ZERO; W], [R::ZERO; W], [R::ZERO; W]);
        for q in 0..W {
            let top = self.far_top[q];
            let (v0, v1, v2) = (values[0][q], values[1][q], values[2][q]);
            let lambda = if top { v2 } else { v0 };
            let lo = if top { v0 } else { v1 };
            let hi = if top { v1 } else { v2 };
            m[q] = half * (lo + hi);
            r[q] = half * (hi - lo) * self.inv_gap[q];
            c[q] = lambda - m[q];
        }
        let mut out = [[R::ZERO; W]; 6];
        for k in 0..3 {
            for q in 0..W {
                out[k][q] = m[q] + c[q] * self.outer[k][q] + r[q] * self.plane[k][q];
            }
        }
        for k in 3..6 {
            for q in 0..W {
                out[k][q] = c[q] * self.outer[k][q] + r[q] * self.plane[k][q];
            }
        }
        out
    }
}

impl<R: Real> Split<R> {
    /// The coaxial tensor with eigenvalues `values` (ascending, in the order of
    /// [`Split::values`]), as xx yy zz xy yz zx.
    #[inline]
    pub fn rebuild(&self, values: &[R; 3]) -> [R; 6] {
        let half = R::of(0.5);
        let (lambda, lo, hi) = if self.far == 2 {
            (values[2], values[0], values[1])
        } else {
            (values[0], values[1], values[2])
        };
        let (m, g) = (half * (lo + hi), half * (hi - lo));
        // The pair's traceless part scales with its half gap; a pair that was exactly repeated
        // and is split now has no direction to split along: keep it repeated (the returns that
        // reach here move a repeated pair together).
        let r = g * self.inv_gap;
        let (c, o) = (lambda - m, &self.outer);
        [
            m + c * o[0] + r * self.plane[0],
            m + c * o[1] + r * self.plane[1],
            m + c * o[2] + r * self.plane[2],
            c * o[3] + r * self.plane[3],
            c * o[4] + r * self.plane[4],
            c * o[5] + r * self.plane[5],
        ]
    }
}

/// Σ `values[i]` n_i ⊗ n_i with n_i = `vectors[i]`, as xx yy zz xy yz zx.
#[inline]
pub fn rebuild<R: Real>(values: &[R; 3], vectors: &[[R; 3]; 3]) -> [R; 6] {
    let mut s = [R::ZERO; 6];
    for (&l, n) in values.iter().zip(vectors) {
        s[0] += l * n[0] * n[0];
        s[1] += l * n[1] * n[1];
        s[2] += l * n[2] * n[2];
        s[3] += l * n[0] * n[1];
        s[4] += l * n[1] * n[2];
        s[5] += l * n[2] * n[0];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn apply(s: &[f64; 6], n: &[f64; 3]) -> [f64; 3] {
        [
            s[0] * n[0] + s[3] * n[1] + s[5] * n[2],
            s[3] * n[0] + s[1] * n[1] + s[4] * n[2],
            s[5] * n[0] + s[4] * n[1] + s[2] * n[2],
        ]
    }

    fn check(s: &[f64; 6]) {
        check_with(s, &principal(s));
        check_with(s, &jacobi(s));
        check_split(s);
    }

    /// The split has the decomposition's eigenvalues, rebuilds the tensor, and moving its
    /// eigenvalues gives what the full decomposition's vectors give (where the moved pair's
    /// directions are defined: a pair that stays repeated, or one that was distinct).
    fn check_split(s: &[f64; 6]) {
        let scale = s.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let sp = split(s);
        let p = principal(s);
        for i in 0..3 {
            assert!(
                (sp.values[i] - p.values[i]).abs() < 1e-13 * scale,
                "{s:?}: {:?} against {:?}",
                sp.values,
                p.values
            );
        }
        // Each column of n ⊗ n is along n: A (n ⊗ n) = λ n ⊗ n.
        let o = sp.outer;
        for col in [[o[0], o[3], o[5]], [o[3], o[1], o[4]], [o[5], o[4], o[2]]] {
            let an = apply(s, &col);
            for k in 0..3 {
                assert!((an[k] - sp.values[sp.far] * col[k]).abs() < 1e-13 * scale);
            }
        }
        assert!((o[0] + o[1] + o[2] - 1.0).abs() < 1e-14);
        let same = sp.rebuild(&sp.values);
        for c in 0..6 {
            assert!((same[c] - s[c]).abs() < 1e-13 * scale, "{s:?} -> {same:?}");
        }
        // A return-like move: every value shifted, the pair's gap halved.
        let (a, b) = if sp.far == 2 { (0, 1) } else { (1, 2) };
        let mut moved = sp.values.map(|v| v - 0.3 * scale);
        let mid = 0.5 * (moved[a] + moved[b]);
        moved[a] = 0.5 * (moved[a] + mid);
        moved[b] = 0.5 * (moved[b] + mid);
        let got = sp.rebuild(&moved);
        let want = rebuild(&moved, &p.vectors);
        for c in 0..6 {
            assert!(
                (got[c] - want[c]).abs() < 1e-12 * scale,
                "{s:?}: {got:?} against {want:?}"
            );
        }
    }

    fn check_with(s: &[f64; 6], p: &Principal<f64>) {
        let p = *p;
        let scale = s.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        assert!(p.values[0] <= p.values[1] && p.values[1] <= p.values[2]);
        for i in 0..3 {
            let n = p.vectors[i];
            let an = apply(s, &n);
            for k in 0..3 {
                assert!(
                    (an[k] - p.values[i] * n[k]).abs() < 1e-13 * scale,
                    "{s:?}: A n - λ n = {}",
                    an[k] - p.values[i] * n[k]
                );
            }
            for j in 0..3 {
                let d: f64 = (0..3).map(|k| n[k] * p.vectors[j][k]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((d - want).abs() < 1e-14, "n{i}·n{j} = {d}");
            }
        }
        let back = rebuild(&p.values, &p.vectors);
        for c in 0..6 {
            assert!((back[c] - s[c]).abs() < 1e-13 * scale, "{s:?} -> {back:?}");
        }
    }

    #[test]
    fn diagonal_repeated_and_known_tensors() {
        check(&[3.0, 1.0, 2.0, 0.0, 0.0, 0.0]);
        check(&[5.0, 5.0, 5.0, 0.0, 0.0, 0.0]);
        check(&[0.0; 6]);
        // Two equal eigenvalues (a triaxial state rotated off the axes).
        check(&[-100.0, -100.0, -300.0, 0.0, 0.0, 0.0]);
        check(&[-200.0, -200.0, -100.0, 100.0, 0.0, 0.0]);
        // A pair split by round-off only (a state on a Mohr–Coulomb edge after a return).
        check(&[-100.0, -200.0, -100.0 * (1.0 + 1e-15), 1e-14, 0.0, 0.0]);
        // The split's pair kept together when it was repeated.
        let sp = split(&[-100.0, -300.0, -100.0, 0.0, 0.0, 0.0]);
        assert_eq!((sp.far, sp.values), (0, [-300.0, -100.0, -100.0]));
        let back = sp.rebuild(&[-250.0, -90.0, -90.0]);
        assert_eq!(back, [-90.0, -250.0, -90.0, 0.0, 0.0, 0.0]);
        // Eigenvalues 1, 2, 4 of a known matrix: [[2,1,0],[1,2,0],[0,0,4]] has 1, 3, 4.
        let p = principal(&[2.0, 2.0, 4.0, 1.0, 0.0, 0.0]);
        for (got, want) in p.values.iter().zip([1.0, 3.0, 4.0]) {
            assert!((got - want).abs() < 1e-14, "{:?}", p.values);
        }
        let f = principal(&[2.0f32, 2.0, 4.0, 1.0, 0.0, 0.0]);
        assert!((f.values[1] - 3.0).abs() < 1e-6);
    }

    #[test]
    fn largest_cubic_root_is_the_trigonometric_one() {
        for i in 0..=10_000 {
            let x = i as f64 / 10_000.0;
            let want = (x.acos() / 3.0).cos();
            let got = largest_cubic_root(x);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON,
                "{x}: {got} against {want}"
            );
        }
    }

    #[test]
    fn non_finite_input_ends() {
        let p = principal(&[f64::NAN, 1.0, 2.0, 0.5, 0.0, 0.0]);
        assert!(p.values.iter().any(|v| v.is_nan()));
        let _ = principal(&[f64::INFINITY, 1.0, 2.0, 1e300, 0.0, 0.0]);
    }

    /// Tensors of every kind the returns meet, of magnitude `scale`: random ones, pairs
    /// repeated exactly and to round-off, isotropic ones, zero.
    fn tensors<R: Real>(scale: f64, seed: u64) -> Vec<[R; 6]> {
        let mut rand = crate::test_rng::uniform(seed);
        let mut out = vec![[R::ZERO; 6], [R::of(-scale); 3].repeat_six()];
        for k in 0..64 {
            let mut t: [f64; 6] = std::array::from_fn(|_| scale * rand());
            match k % 4 {
                // diag(a, a, b) rotated about z, to round-off.
                1 => {
                    let (a, b, c) = (t[0], t[1], 0.6);
                    let sn = 0.8;
                    t = [
                        a * c * c + a * sn * sn,
                        a * sn * sn + a * c * c,
                        b,
                        0.0,
                        0.0,
                        0.0,
                    ];
                }
                // Exactly repeated.
                2 => t = [t[0], t[0], t[1], 0.0, 0.0, 0.0],
                // Nearly isotropic.
                3 => {
                    let m = t[0];
                    t = [m, m * (1.0 + 1e-14), m, m * 1e-15, 0.0, 0.0];
                }
                _ => {}
            }
            out.push(t.map(R::of));
        }
        out
    }

    trait RepeatSix<R> {
        fn repeat_six(self) -> [R; 6];
    }
    impl<R: Real> RepeatSix<R> for [R; 3] {
        fn repeat_six(self) -> [R; 6] {
            [self[0], self[1], self[2], R::ZERO, R::ZERO, R::ZERO]
        }
    }

    fn same_bits<R: Real>(a: &Split<R>, b: &Split<R>) -> bool {
        let bits = |v: &[R]| v.iter().map(|x| x.f64().to_bits()).collect::<Vec<_>>();
        bits(&a.values) == bits(&b.values)
            && a.far == b.far
            && bits(&a.outer) == bits(&b.outer)
            && bits(&a.plane) == bits(&b.plane)
            && a.inv_gap.f64().to_bits() == b.inv_gap.f64().to_bits()
    }

    /// Four tensors side by side give each tensor's own split, to the bit, in both precisions
    /// and at magnitudes inside and outside the range that needs no scaling.
    fn lanes_are_split_lane_by_lane<R: Real>() {
        for scale in [1e-12, 1e-3, 1.0, 300.0, 1e7, 1e12] {
            let t = tensors::<R>(scale, 7);
            for group in t.chunks_exact(4) {
                let lanes: [[R; 4]; 6] =
                    std::array::from_fn(|c| std::array::from_fn(|q| group[q][c]));
                let got = split_lanes(&lanes);
                for q in 0..4 {
                    let want = split(&group[q]);
                    assert!(
                        same_bits(&got.lane(q), &want),
                        "{:?}: {:?} against {:?}",
                        group[q],
                        got.lane(q),
                        want
                    );
                }
            }
        }
    }

    #[test]
    fn split_lanes_are_split_lane_by_lane() {
        lanes_are_split_lane_by_lane::<f64>();
        lanes_are_split_lane_by_lane::<f32>();
    }

    /// The split of a tensor scaled by a power of two is the tensor's split scaled, bit for
    /// bit, at stresses f32 cannot square twice (1e-10 kPa: a load ramped up from zero), at
    /// those of a lone point in free flight (f64 down to 2^-900) and far beyond any soil's, so
    /// no magnitude ends in infinities or NaN.
    fn scales_exactly<R: Real>() {
        for t in tensors::<R>(1.0, 11) {
            let base = split(&t);
            // (f32 keeps the round-off of a nearly repeated pair, 1e-8 of the stress, normal
            // down to stresses of 1e-30: below it the result itself is subnormal.)
            let (far, wide) = if R::BYTES == 4 { (60, 60) } else { (200, 900) };
            for e in [-wide, -far, -33, -17, 17, 40, far, wide] {
                let k = R::of(2f64.powi(e));
                let scaled = t.map(|x| x * k);
                if scaled.iter().zip(&t).any(|(&y, &x)| y / k != x) {
                    // An entry under- or overflowed: not the same tensor scaled.
                    continue;
                }
                let sp = split(&scaled);
                let up = Split {
                    values: base.values.map(|v| v * k),
                    far: base.far,
                    outer: base.outer,
                    plane: base.plane.map(|v| v * k),
                    inv_gap: base.inv_gap / k,
                };
                assert!(same_bits(&sp, &up), "{t:?} x 2^{e}: {sp:?} against {up:?}");
            }
        }
    }

    #[test]
    fn split_is_exact_under_scaling_by_powers_of_two() {
        scales_exactly::<f64>();
        scales_exactly::<f32>();
    }

    proptest! {
        #[test]
        fn decomposes_random_symmetric_tensors(
            d in prop::array::uniform3(-1e3f64..1e3),
            o in prop::array::uniform3(-1e3f64..1e3),
            equal in 0usize..3,
        ) {
            let mut s = [d[0], d[1], d[2], o[0], o[1], o[2]];
            // Some cases with repeated eigenvalues: rotate diag(a, a, b).
            if equal == 0 {
                let n = o[0].hypot(o[1]).hypot(o[2]).max(1e-9);
                let u = [o[0] / n, o[1] / n, o[2] / n];
                let (a, b) = (d[0], d[1]);
                s = [
                    a + (b - a) * u[0] * u[0],
                    a + (b - a) * u[1] * u[1],
                    a + (b - a) * u[2] * u[2],
                    (b - a) * u[0] * u[1],
                    (b - a) * u[1] * u[2],
                    (b - a) * u[2] * u[0],
                ];
            }
            check(&s);
        }
    }
}

#[cfg(test)]
mod cost {
    use super::*;
    use std::hint::black_box;

    fn states() -> Vec<[f64; 6]> {
        let mut rand = crate::test_rng::uniform(99);
        (0..100_000)
            .map(|_| {
                [
                    -100.0 + 10.0 * rand(),
                    -60.0 + 10.0 * rand(),
                    -60.0 + 10.0 * rand(),
                    10.0 * rand(),
                    10.0 * rand(),
                    10.0 * rand(),
                ]
            })
            .collect()
    }

    /// Cost of each solver alone, for `perf stat`: `PRINCIPAL=jacobi|closed cargo test --release
    /// -p mpm-solve --lib material::principal::cost -- --ignored`.
    #[test]
    #[ignore]
    fn principal_cost() {
        let s = states();
        let which = std::env::var("PRINCIPAL").unwrap_or_default();
        let mut acc = 0.0;
        for _ in 0..50 {
            for t in &s {
                let p = if which == "jacobi" {
                    jacobi(black_box(t))
                } else {
                    principal(black_box(t))
                };
                acc += p.values[0] + p.vectors[2][1];
            }
        }
        black_box(acc);
    }
}
