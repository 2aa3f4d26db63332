//! The physics of grid to particle, written once over any lanes ([`Lanes`]: one lane per
//! point): the FLIP velocity update, the PIC blend, the liquid mass a point re-maps with and
//! the kinetic-energy terms of the guard rails. The element kernels take them four points at a
//! time ([`super::lanes`]), the stencil pass one point at a time ([`super::stencil`]).

use crate::element::Element;
use crate::four::Lanes;
use crate::material::liquid::Fluid;
use crate::real::{Real, V3};

/// The velocities `v` (lane q: point q) plus Δt Σ_k N_k a_k, over `n` (`n[k]`: each point's
/// weight at node k) and the nodes' accelerations `acc`, node by node as a point-by-point loop
/// sums them (from zero).
#[inline(always)]
pub(super) fn flip<E, R, F>(t: F::Token, n: &[F], acc: &[V3<R>], v: [F; 3], dt: R) -> [F; 3]
where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let zero = F::splat(t, R::ZERO);
    let mut dv = [zero; 3];
    for (nk, ak) in n.iter().zip(acc) {
        for c in 0..E::DIM {
            dv[c] = dv[c] + *nk * F::splat(t, ak[c]);
        }
    }
    let mut v = v;
    let dt = F::splat(t, dt);
    for c in 0..E::DIM {
        v[c] = v[c] + dt * dv[c];
    }
    v
}

/// What the PIC blend needs: the blend's weights and, per node of the element or stencil, its
/// velocity after the step, v + a Δt, in each component that counts (`None` at an empty node and
/// in fixed components, which add nothing).
#[derive(Clone, Copy)]
pub(super) struct Pic<R: Real> {
    /// 1 - the PIC share.
    pub flip: R,
    /// The PIC share.
    pub pic: R,
}

impl<R: Real> Pic<R> {
    /// Node `node`'s velocity after the step, by component (`None` where it counts nothing):
    /// zero where the node is empty (`mass` at most `empty_below`) or the component fixed.
    #[inline(always)]
    pub fn node_velocity<E: Element>(
        node: NodeState<'_, R>,
        dt: R,
        empty_below: R,
    ) -> [Option<R>; 3] {
        let mut v = [None; 3];
        if node.mass <= empty_below {
            return v;
        }
        for c in 0..E::DIM {
            if !node.fixed[c] {
                v[c] = Some(node.momentum[c] / node.mass + dt * node.acc[c]);
            }
        }
        v
    }

    /// The velocities `v` blended with the nodes' (`node_v`, [`Pic::node_velocity`]) at each
    /// point's weights `n`: (1 - PIC) v + PIC Σ_k N_k v_k.
    #[inline(always)]
    pub fn blend<E: Element, F: Lanes<R>>(
        &self,
        t: F::Token,
        n: &[F],
        node_v: &[[Option<R>; 3]],
        v: [F; 3],
    ) -> [F; 3] {
        let mut grid_v = [F::splat(t, R::ZERO); 3];
        for (nk, vk) in n.iter().zip(node_v) {
            for c in 0..E::DIM {
                if let Some(vc) = vk[c] {
                    grid_v[c] = grid_v[c] + *nk * F::splat(t, vc);
                }
            }
        }
        let mut v = v;
        for c in 0..E::DIM {
            v[c] = F::splat(t, self.flip) * v[c] + F::splat(t, self.pic) * grid_v[c];
        }
        v
    }
}

/// A node's state for its velocity after the step.
#[derive(Clone, Copy)]
pub(super) struct NodeState<'a, R: Real> {
    /// Its mass.
    pub mass: R,
    /// Its momentum.
    pub momentum: &'a V3<R>,
    /// Its acceleration.
    pub acc: &'a V3<R>,
    /// Its fixed components.
    pub fixed: &'a [bool; 3],
}

/// The liquid mass a saturated point re-maps with, ρw V (lanes: points' volumes): the one
/// particle to grid mapped, on the initial volume where the case holds the liquid mass fixed.
#[inline(always)]
pub(super) fn liquid_mass<R: Real, F: Lanes<R>>(t: F::Token, f: &Fluid<R>, volume: F) -> F {
    F::splat(t, f.rho_w) * volume
}

/// m v · v over the element's dimensions (twice the kinetic energy), lane by lane, the dot
/// product summed from zero.
#[inline(always)]
pub(super) fn kinetic<E: Element, R: Real, F: Lanes<R>>(t: F::Token, m: F, v: &[F; 3]) -> F {
    let mut s = F::splat(t, R::ZERO);
    for c in 0..E::DIM {
        s = s + v[c] * v[c];
    }
    m * s
}

/// n ρw V |w|² over the element's dimensions (twice the liquid's kinetic energy) from the
/// point's liquid mass `mw`, lane by lane.
#[inline(always)]
pub(super) fn liquid_kinetic<E: Element, R: Real, F: Lanes<R>>(
    t: F::Token,
    f: &Fluid<R>,
    mw: F,
    w: &[F; 3],
) -> F {
    let mut s = F::splat(t, R::ZERO);
    for c in 0..E::DIM {
        s = s + w[c] * w[c];
    }
    F::splat(t, f.n) * mw * s
}
