//! The strain of a linear element and Anura3D's objective terms: the strain and spin
//! increments from an element's velocity gradient, and the co-rotation and volume change of a
//! stress, written once over any lanes ([`Lanes`]: one point each).

use crate::element::Element;
use crate::four::{Lanes, Plain};
use crate::real::Real;

/// The strain increment sym(L) Δt of a linear element (xx yy zz xy yz zx, tensor shears) from
/// its velocity gradient `l` (L[a][b] = ∂v_a/∂x_b): the same at all its points, except an
/// axisymmetric section's ε_zz, the hoop strain, which the caller forms per point. A section's
/// out-of-plane shear increments are +0 exactly (its L has no z-row or z-column, and Δt is
/// positive and finite): written as such.
#[inline(always)]
pub(super) fn strain_increment<E: Element, R: Real>(l: &[[R; 3]; 3], dt: R) -> [R; 6] {
    let half = R::of(0.5);
    let out_of_plane = |a: usize, b: usize| {
        if E::DIM == 2 {
            R::ZERO
        } else {
            half * (l[a][b] + l[b][a]) * dt
        }
    };
    [
        l[0][0] * dt,
        l[1][1] * dt,
        l[2][2] * dt,
        half * (l[0][1] + l[1][0]) * dt,
        out_of_plane(1, 2),
        out_of_plane(2, 0),
    ]
}

/// The spin increment skew(L) Δt (ω_xy, ω_yz, ω_zx) of an element with velocity gradient
/// `l`, for Anura3D's objective terms.
#[inline(always)]
pub(super) fn spin_increment<R: Real>(l: &[[R; 3]; 3], dt: R) -> [R; 3] {
    let half = R::of(0.5);
    [
        half * (l[0][1] - l[1][0]) * dt,
        half * (l[1][2] - l[2][1]) * dt,
        half * (l[2][0] - l[0][2]) * dt,
    ]
}

/// The co-rotation Ω σ - σ Ω of each lane's stress (`s[c]`: component c, xx yy zz xy yz zx)
/// for the spin increment `w` (ω_xy, ω_yz, ω_zx): (Ωσ - σΩ)_ij = Σ_k Ω_ik σ_kj - σ_ik Ω_kj,
/// written out for the symmetric result.
#[inline(always)]
pub(super) fn rotation_of<R: Real, F: Lanes<R>>(t: F::Token, s: &[F; 6], w: &[R; 3]) -> [F; 6] {
    let [xx, yy, zz, xy, yz, zx] = *s;
    let sp = |v: R| F::splat(t, v);
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

/// Anura3D's objective update (its "Hill" rate) added to the law's stresses `s1`: the
/// co-rotation of the start-of-step stress `s0` for the spin increment `spin`, and its change
/// of volume, -tr(Δε) σ (`ev`: each lane's tr Δε), added after the law's update as Anura3D adds
/// them (for a plastic law the order matters: the return sees the unrotated trial).
#[inline(always)]
pub(super) fn add_objective<R: Real, F: Lanes<R>>(
    t: F::Token,
    s0: &[F; 6],
    s1: &mut [F; 6],
    spin: &[R; 3],
    ev: F,
) {
    let h = rotation_of::<R, F>(t, s0, spin);
    for c in 0..6 {
        s1[c] = s1[c] + (h[c] - ev * s0[c]);
    }
}

/// Adds Ω σ - σ Ω to `s` for the skew increment Ω with Ω_xy = `w[0]`, Ω_yz = `w[1]`, Ω_zx = `w[2]`
/// (Ω_yx = `-w[0]` etc.): the Jaumann co-rotation of the stress over one step.
#[inline]
pub fn rotate<R: Real>(s: &mut [R; 6], w: &[R; 3]) {
    let r = rotation(s, w);
    for (s, r) in s.iter_mut().zip(r) {
        *s += r;
    }
}

/// The co-rotation Ω σ - σ Ω of `s` (xx yy zz xy yz zx) for the spin increment `w`
/// (ω_xy, ω_yz, ω_zx).
pub fn rotation<R: Real>(s: &[R; 6], w: &[R; 3]) -> [R; 6] {
    rotation_of::<R, Plain<R, 1>>((), &s.map(|v| Plain([v])), w).map(|v| v.0[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ω σ - σ Ω by full 3×3 products.
    fn reference(s: &[f64; 6], w: &[f64; 3]) -> [f64; 6] {
        let m = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
        let o = [[0.0, w[0], -w[2]], [-w[0], 0.0, w[1]], [w[2], -w[1], 0.0]];
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    r[i][j] += o[i][k] * m[k][j] - m[i][k] * o[k][j];
                }
            }
        }
        [r[0][0], r[1][1], r[2][2], r[0][1], r[1][2], r[2][0]]
    }

    #[test]
    fn jaumann_rotation_matches_matrix_products() {
        let s0 = [1.0, -2.0, 3.5, 0.25, -0.75, 1.5];
        let w = [0.01, -0.02, 0.03];
        let mut s = s0;
        rotate(&mut s, &w);
        let r = reference(&s0, &w);
        for c in 0..6 {
            assert!((s[c] - s0[c] - r[c]).abs() < 1e-15, "component {c}");
        }
        // A rotation leaves the trace unchanged.
        assert!(((s[0] + s[1] + s[2]) - (s0[0] + s0[1] + s0[2])).abs() < 1e-15);
    }
}
