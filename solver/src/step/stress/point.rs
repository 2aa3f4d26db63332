//! The physics of the stress pass at the points, written once over any lanes ([`Lanes`]: one
//! point each): the pore pressure's smoothed rate, the points' velocity, move and new volume,
//! and the strain-energy term of the guard rails. The linear-elastic batches take them as
//! four-lane vectors ([`super::lanes`]), the general batches as plain arrays of their width
//! ([`super::general`]): the same operations in the same order, so the same bits.

use crate::element::Element;
use crate::four::Lanes;
use crate::real::{Real, V3};

/// Δt Σ_k N_k ṗ_k at each lane's point: the pore pressure's change over the step from the
/// nodes' smoothed rates `rate` (the element's nodes) at the points' weights `n`.
#[inline(always)]
pub(super) fn pore_change<E, R, F>(t: F::Token, n: &[F; 4], rate: &[R], dt: R) -> F
where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let mut change = F::splat(t, R::ZERO);
    for k in 0..E::NODES {
        change = change + n[k] * F::splat(t, rate[k]);
    }
    change * F::splat(t, dt)
}

/// Σ_k N_k v_k at each lane's point from the element's nodal velocities `vel`, node by node (the
/// in-plane components of a 2D element, z 0).
#[inline(always)]
pub(super) fn velocity_at<E, R, F>(t: F::Token, n: &[F; 4], vel: &[V3<R>]) -> [F; 3]
where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let mut dx = [F::splat(t, R::ZERO); 3];
    for k in 0..E::NODES {
        for c in 0..E::DIM {
            dx[c] = dx[c] + n[k] * F::splat(t, vel[k][c]);
        }
    }
    dx
}

/// `x` moved by Δt `dx` in the element's [`Element::DIM`] components (the others as they
/// were): a position, or a displacement.
#[inline(always)]
pub(super) fn moved<E, R, F>(t: F::Token, x: [F; 3], dx: &[F; 3], dt: R) -> [F; 3]
where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let mut x1 = x;
    for a in 0..E::DIM {
        x1[a] = x[a] + F::splat(t, dt) * dx[a];
    }
    x1
}

/// The volume factor 1 + Δε_xx + Δε_yy + Δε_zz (`de_zz`: 0 where an axisymmetric section's hoop
/// strain leaves the volume alone).
#[inline(always)]
pub(super) fn volume_factor<R: Real, F: Lanes<R>>(t: F::Token, de_xx: F, de_yy: F, de_zz: F) -> F {
    F::splat(t, R::ONE) + de_xx + de_yy + de_zz
}

/// Twice the strain energy a point took up in the step, V0 (σ0 + σ1) : Δε (the work of the
/// mean stress, exact for a linear law; shear components twice, tensor shear strains; a
/// section's out-of-plane ones, whose increment is +0, left out: they would add ±0 to a sum
/// that starts at +0), plus 0, or NaN for a non-finite new position `x1` or volume `v1`: added
/// to the strain sum, which a non-finite stress makes non-finite too, so that one test of the
/// sums catches them all.
#[inline(always)]
pub(super) fn strain_work<E, R, F>(
    t: F::Token,
    s: (&[F; 6], &[F; 6]),
    de: &[F; 6],
    moved: (&[F; 3], F, F),
) -> F
where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let (s0, s1) = s;
    let (x1, v0, v1) = moved;
    let zero = F::splat(t, R::ZERO);
    let mut w = zero;
    for c in 0..if E::DIM == 2 { 4 } else { 6 } {
        let twice = F::splat(t, if c < 3 { R::ONE } else { R::of(2.0) });
        w = w + twice * (s0[c] + s1[c]) * de[c];
    }
    let finite = zero * (x1[0] + x1[1] + x1[2] + v1);
    w * v0 + finite
}
