//! An element's sums in node lanes ([`Sums`]), with the terms its points add up once for the
//! element ([`Totals`]) and the forces formed from them and the element's gradients when its
//! points are all in ([`Sums::close`]).

use crate::element::Element;
use crate::four::Lanes;
use crate::real::{Real, V3};
use crate::state::pore_weights;

/// What an element's points add up beside their node lanes, for the terms whose node factor is
/// the same at every point. A linear element's ∇N_k is one per element, so the internal force
/// -Σ_p V_p (σ'_p + p_p I) ∇N_k is -(Σ_p V_p (σ'_p + p_p I)) ∇N_k, and the liquid's pressure
/// force -Σ_p V_p p_p ∇N_k is -(Σ_p V_p p_p) ∇N_k; the weight Σ_p m_p N_k g of the points of
/// one material is g Σ_p m_p N_k (the liquid's weight likewise, from the liquid mass sum).
/// Each is then formed once per element rather than once per point (docs/design.md §9): the
/// sums are taken in another order than point by point, so the bits differ from that order's,
/// not the value (and not at all with one point per element). A stencil's point closes its own
/// totals with its own gradients ([`super::stencil`]).
/// `F`: the node lanes' type (four-lane vectors, or plain lanes where the pass runs without
/// them: the same operations).
#[derive(Clone, Copy)]
pub(super) struct Totals<R, F> {
    /// Σ V (σ' + p I) over the points that take part (0 for a full element's points under
    /// mixed integration), in point order.
    pub stress: [R; 6],
    /// Σ V p over the saturated points, in point order.
    pub pore: R,
    /// The material whose points' weight is formed from their mass sum: the element's first
    /// point's (all of them, nearly always); the others' weight is added point by point.
    pub lead: u32,
    /// Σ m N_k over the points of `lead` that take part, one lane per node, in point order.
    pub lead_mass: F,
    /// Σ V N_k over the saturated points, one lane per node, in point order (formed where
    /// the pore-pressure rate's weights are wanted: [`crate::state::pore_weights`]).
    pub volume_n: F,
    /// The material of the saturated points added to `volume_n`
    /// ([`pore_weights::with_point`]).
    pub saturated: u32,
}

impl<R: Real, F: Lanes<R>> Totals<R, F> {
    /// Adds a point's V (σ' + p I).
    #[inline(always)]
    pub fn add_stress(&mut self, s: &[R; 6]) {
        for (t, v) in self.stress.iter_mut().zip(s) {
            *t += *v;
        }
    }
}

/// An element's sums, value by value, one lane per node: the solid's (mass, then momentum,
/// internal force and weight with [`Element::DIM`] components each) and the liquid's (its two
/// masses and the drag, then momentum, force and weight on the mixture), with the totals its
/// points add up once.
#[derive(Clone, Copy)]
pub(super) struct Sums<R, F> {
    /// The solid's values.
    pub solid: [F; 10],
    /// The liquid's values.
    pub liquid: [F; 12],
    /// The terms formed once per element.
    pub totals: Totals<R, F>,
}

impl<R: Real, F: Lanes<R>> Sums<R, F> {
    /// Zero sums, with the weight of `lead`'s points formed from their mass sum.
    #[inline(always)]
    pub fn zero(t: F::Token, lead: u32) -> Self {
        let z = F::splat(t, R::ZERO);
        Sums {
            solid: [z; 10],
            liquid: [z; 12],
            totals: Totals {
                stress: [R::ZERO; 6],
                pore: R::ZERO,
                lead,
                lead_mass: z,
                volume_n: z,
                saturated: pore_weights::NO_POINTS,
            },
        }
    }

    /// Adds the totals' terms to the node lanes (`g[b]`: ∂N_k/∂x_b by node), once every point
    /// has added its own: the internal force; the weight of the lead material's points
    /// (`gravity` that material's); with `WITH_LIQUID` and the liquid's gravity, the liquid
    /// force (its weight from the liquid mass sum, less the pressure's) and the liquid's weight
    /// on the mixture (from the porosity-weighted liquid mass sum).
    #[inline(always)]
    pub fn close<E: Element, const WITH_LIQUID: bool>(
        &mut self,
        t: F::Token,
        g: &[F; 3],
        gravity: V3<R>,
        liquid_gravity: Option<V3<R>>,
    ) {
        let splat = |v: R| F::splat(t, v);
        let (totals, s4, w4) = (&self.totals, &mut self.solid, &mut self.liquid);
        for a in 0..E::DIM {
            let f = traction::<E, R, F>(t, &totals.stress, g, a);
            s4[1 + E::DIM + a] = s4[1 + E::DIM + a] - f;
            s4[1 + 2 * E::DIM + a] = s4[1 + 2 * E::DIM + a] + totals.lead_mass * splat(gravity[a]);
        }
        let Some(lg) = liquid_gravity.filter(|_| WITH_LIQUID) else {
            return;
        };
        for a in 0..E::DIM {
            let force = w4[0] * splat(lg[a]) - splat(totals.pore) * g[a];
            w4[3 + E::DIM + a] = w4[3 + E::DIM + a] + force;
            w4[3 + 2 * E::DIM + a] = w4[3 + 2 * E::DIM + a] + w4[1] * splat(lg[a]);
        }
    }
}

/// Component `a` of σ ∇N_k for every node k (σ symmetric, xx yy zz xy yz zx; `g[b]`:
/// ∂N_k/∂x_b by node); in a 2D element (∂N/∂z = 0) over the in-plane components only.
#[inline(always)]
pub(super) fn traction<E: Element, R: Real, F: Lanes<R>>(
    t: F::Token,
    s: &[R; 6],
    g: &[F; 3],
    a: usize,
) -> F {
    // Row a of the symmetric σ (xx yy zz xy yz zx).
    const ROWS: [[usize; 3]; 3] = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
    let r = ROWS[a];
    let splat = |v: R| F::splat(t, v);
    if E::DIM == 2 {
        splat(s[r[0]]) * g[0] + splat(s[r[1]]) * g[1]
    } else {
        splat(s[r[0]]) * g[0] + splat(s[r[1]]) * g[1] + splat(s[r[2]]) * g[2]
    }
}
