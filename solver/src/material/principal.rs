//! Principal values and directions of a symmetric 3×3 tensor (stress, strain), generic over the
//! run's precision: cyclic Jacobi rotations in a fixed order, so the result is deterministic and
//! exact for repeated eigenvalues (no characteristic cubic, whose roots lose half their digits
//! when two eigenvalues meet, as they do on the edges of a Mohr–Coulomb pyramid).

use crate::real::Real;

/// Sweeps after which Jacobi stops whatever the remainder (it converges quadratically: four to
/// six sweeps reach round-off in f64).
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
pub fn principal<R: Real>(s: &[R; 6]) -> Principal<R> {
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
    // Stop once the off-diagonal part is below round-off squared of the largest entry: the
    // next rotation would change nothing that can be represented.
    let tol = R::of(R::EPSILON * R::EPSILON) * largest;
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
    let mut order = [0usize, 1, 2];
    let d = [a[0][0], a[1][1], a[2][2]];
    // Three compare-swaps sort three values.
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if d[order[j]] < d[order[i]] {
            order.swap(i, j);
        }
    }
    Principal {
        values: order.map(|k| d[k]),
        vectors: order.map(|k| [v[0][k], v[1][k], v[2][k]]),
    }
}

/// Σ values[i] n_i ⊗ n_i with n_i = `vectors[i]`, as xx yy zz xy yz zx.
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
        let p = principal(s);
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
        // Eigenvalues 1, 2, 4 of a known matrix: [[2,1,0],[1,2,0],[0,0,4]] has 1, 3, 4.
        let p = principal(&[2.0, 2.0, 4.0, 1.0, 0.0, 0.0]);
        for (got, want) in p.values.iter().zip([1.0, 3.0, 4.0]) {
            assert!((got - want).abs() < 1e-14, "{:?}", p.values);
        }
        let f = principal(&[2.0f32, 2.0, 4.0, 1.0, 0.0, 0.0]);
        assert!((f.values[1] - 3.0).abs() < 1e-6);
    }

    #[test]
    fn non_finite_input_ends() {
        let p = principal(&[f64::NAN, 1.0, 2.0, 0.5, 0.0, 0.0]);
        assert!(p.values.iter().any(|v| v.is_nan()));
        let _ = principal(&[f64::INFINITY, 1.0, 2.0, 1e300, 0.0, 0.0]);
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
