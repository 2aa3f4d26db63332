//! The stress pass on a background grid's basis ([`crate::basis::grid`]): each point's own
//! velocity gradient, velocity and (saturated) pore-pressure rate from its stencil, then the
//! rest of the update as the element batches do it, one point a batch
//! ([`super::general::finish`]). The points of a chunk are updated by one thread, as on the
//! mesh's elements: each point's result is the same whichever thread computes it.

use crate::basis::background::Background;
use crate::basis::{Basis, Stencil};
use crate::element::Element;
use crate::four::Plain;
use crate::material::liquid::Fluid;
use crate::parallel::reach::Reach;
use crate::parallel::team::Shared;
use crate::real::Real;
use crate::real::V3;
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::batch::Batch;
use crate::step::contact::maps;
use crate::step::passes::Passes;

use super::general::{finish, Motion};
use super::locate::locate_moved;
use super::strain::strain_increment;
use super::{ChunkPoints, Pass, Sinks};

/// Element `e`'s points `from..end` of the chunk on `grid`: each active point of the body
/// strains, takes its pore pressure's rate (with `cx.point_rates`), updates its stress and
/// moves; then, where the pass locates, the moved points are located.
pub(super) fn element<E: Element, R: Real, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    basis: &Background,
    e: usize,
    p: &mut ChunkPoints<'_, R>,
    (from, end): (usize, usize),
    sinks: Sinks<'_>,
) {
    let dt = cx.dt;
    let mut st = Stencil::<R>::default();
    let dim = E::DIM;
    for j in from..end {
        if !(p.active[j] && maps(cx.body, p.material[j])) {
            continue;
        }
        let x = p.x[j];
        basis.stencil(cx.mesh, e, &x, &mut st);
        // L[a][b] = ∂v_a/∂x_b and the velocity at the point (in-plane only in 2D).
        let mut l = [[R::ZERO; 3]; 3];
        let mut v = [R::ZERO; 3];
        for ((&node, &n), g) in st.nodes().iter().zip(st.weights()).zip(st.gradients()) {
            let vel = &cx.g.vel[node as usize];
            for a in 0..dim {
                v[a] += n * vel[a];
                for b in 0..dim {
                    l[a][b] += vel[a] * g[b];
                }
            }
        }
        if let (Some(pore), Some(gl)) = (p.pore.as_deref_mut(), cx.g.liquid.as_ref()) {
            let m = p.material[j] as usize;
            if let Some(smoothed) = &cx.pore_rate {
                // The nodes' smoothed rates ([`smooth_rates`]), interpolated.
                if smoothed.fluids[m].is_some() {
                    let rate = st
                        .nodes()
                        .iter()
                        .zip(st.weights())
                        .fold(R::ZERO, |r, (&node, &n)| {
                            r + n * smoothed.nodal[node as usize]
                        });
                    pore[j] += rate * dt;
                }
            } else if let Some(f) = cx.point_rates.and_then(|fl| fl[m].as_ref()) {
                pore[j] += point_rate::<E, R>(f, &st, (&cx.g.vel, &gl.vel), &x) * dt;
            }
        }
        let one = |c: R| Plain([c]);
        let mut de = strain_increment::<E, R>(&l, dt).map(one);
        if E::AXISYMMETRIC {
            de[2] = one(v[0] / x[0] * dt);
        }
        let b = Batch::<1> {
            start: j,
            len: 1,
            on: [true],
            at: [j],
        };
        let motion = Motion {
            x: x.map(one),
            dx: v.map(one),
            de,
            l: &l,
        };
        finish::<E, R, 1, WIDE>(cx, p, &b, motion, (&mut *sinks.open, sinks.guard));
    }
    if let Some((found, offset)) = sinks.locate {
        locate_moved(cx.mesh, e, p, (from, end), (found, offset));
    }
}

/// The pore pressure's rate at a point with stencil `st` at `x`:
/// (K_w / n) (n ∇·w + (1 − n) ∇·v), both phases' divergences from their nodal velocities
/// `(vel, wvel)` (with an axisymmetric section's hoop rates u_r / r).
fn point_rate<E: Element, R: Real>(
    f: &Fluid<R>,
    st: &Stencil<R>,
    (vel, wvel): (&[V3<R>], &[V3<R>]),
    x: &V3<R>,
) -> R {
    let (mut div_v, mut div_w) = (R::ZERO, R::ZERO);
    for ((&node, &n), g) in st.nodes().iter().zip(st.weights()).zip(st.gradients()) {
        let (vs, vw) = (&vel[node as usize], &wvel[node as usize]);
        for a in 0..E::DIM {
            div_v += vs[a] * g[a];
            div_w += vw[a] * g[a];
        }
        if E::AXISYMMETRIC {
            div_v += n * vs[0] / x[0];
            div_w += n * vw[0] / x[0];
        }
    }
    f.kw_over_n * (f.n * div_w + (R::ONE - f.n) * div_v)
}

/// The pore pressure's rate smoothed through the grid's nodes, as on the mesh's elements
/// ([`super::update_pore_pressure`]): each saturated point's own rate averaged to its nodes
/// with weights V N, Σ V N r / Σ V N, into the liquid's nodal `rate` (0 at a node without
/// saturated points), for the stress pass to interpolate back ([`super::PoreRate`]). Each
/// thread sums its own nodes over their points in point order ([`Reach`]); `weights` is the
/// nodes' Σ V N, rewritten.
pub fn smooth_rates<E: Element, R: Real>(
    (basis, reach, passes): (&Background, &Reach, &Passes<'_, R, E>),
    p: &Particles<R>,
    g: &mut Grid<R>,
    fluids: &[Option<Fluid<R>>],
    weights: &mut Vec<R>,
) {
    let gl = g.liquid.as_mut().expect("a two-phase case's nodes");
    // Grown on the first step only.
    weights.resize(gl.rate.len(), R::ZERO);
    let (rate, weights) = (Shared::new(&mut gl.rate), Shared::new(weights));
    let velocities = (&g.vel[..], &gl.vel[..]);
    passes.team.run(|t| {
        let own = reach.nodes(t);
        // SAFETY: the threads' node ranges are disjoint (`Reach`).
        let (rate, weights) = unsafe { (rate.range(own.clone()), weights.range(own.clone())) };
        rate.fill(R::ZERO);
        weights.fill(R::ZERO);
        let saturated = |i: usize| p.active[i] && fluids[p.material[i] as usize].is_some();
        let on = (basis, passes.mesh, passes.layout);
        reach.visit(t, on, (&p.x, saturated), |_, i, st| {
            let Some(f) = &fluids[p.material[i] as usize] else {
                return;
            };
            let r = point_rate::<E, R>(f, st, velocities, &p.x[i]);
            for (&node, &n) in st.nodes().iter().zip(st.weights()) {
                let Some(k) = (node as usize)
                    .checked_sub(own.start)
                    .filter(|&k| k < own.len())
                else {
                    continue;
                };
                let w = p.volume[i] * n;
                rate[k] += w * r;
                weights[k] += w;
            }
        });
        for (rate, &w) in rate.iter_mut().zip(weights.iter()) {
            if w > R::ZERO {
                *rate /= w;
            }
        }
    });
}
