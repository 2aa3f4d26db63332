//! Grid to particle over any basis's stencils ([`crate::basis`]): each point's velocity
//! updated from its nodes' accelerations and its momentum re-mapped to them by the element
//! kernels' physics ([`super::point`], one lane: the point), summed point by point in point
//! order on the calling thread (the team's scatter holds an element's corners only), then the
//! nodal velocities ([`velocity`]).

use crate::basis::{Basis, Stencil, MOST_NODES};
use crate::element::Element;
use crate::four::{Lanes, Plain};
use crate::real::{Real, V3};
use crate::step::contact::maps;
use crate::step::passes::Passes;

use super::nodal::velocity;
use super::point::{flip, kinetic, liquid_mass, NodeState, Pic};
use super::Remap;
use crate::parallel::gather::{scratch, Slots, ELEMENT_BLOCK};
use crate::step::stress::GuardSums;

/// One lane: one point.
type One<R> = Plain<R, 1>;

/// [`super::grid_to_particle`] with `passes.basis`'s stencils: the active points of the body
/// take their velocity update (FLIP, blended with PIC) and re-map their momentum; with the
/// liquid, its too; with the guard rails, each point's kinetic terms into its element's
/// block's slot (begun anew with `begin`).
pub(super) fn remap_stencils<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    remap: Remap<'_, R>,
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    let Remap {
        particles: p,
        grid: g,
        fixed,
        dt,
        pic,
        mut guard,
        body,
        liquid,
        begin,
    } = remap;
    // The guard rails' kinetic sums, block by block, point by point in order.
    if let (Some(slots), true) = (guard.as_deref_mut(), begin) {
        slots.fill(GuardSums::EMPTY);
    }
    let liquid = liquid.filter(|_| p.liquid.is_some() && g.liquid.is_some());
    let (mesh, layout) = (passes.mesh, passes.layout);
    let nodes = mesh.x.len();
    let blend = (pic > R::ZERO).then_some(Pic {
        flip: R::ONE - pic,
        pic,
    });
    // Both phases' re-mapped momenta in the scatter's slots (grown on the first step only).
    let (momentum, momentum_w) = scratch(slots, 6 * nodes).split_at_mut(3 * nodes);
    let mut stencil = Stencil::default();
    for e in 0..mesh.elements() {
        for i in layout.particles_of(e) {
            if !p.active[i] || !maps(body, p.material[i]) {
                continue;
            }
            passes.basis.stencil(mesh, e, &p.x[i], &mut stencil);
            let at = Weights::of(&stencil);
            let n = &at.n[..stencil.len()];
            // The nodes' accelerations, and with PIC their velocities after the step.
            let mut acc = [[R::ZERO; 3]; MOST_NODES];
            let mut node_v = [[None; 3]; MOST_NODES];
            for (k, &node) in stencil.nodes().iter().enumerate() {
                let node = node as usize;
                acc[k] = g.acc[node];
                let state = NodeState {
                    mass: g.mass[node],
                    momentum: &g.momentum[node],
                    acc: &g.acc[node],
                    fixed: &fixed[node],
                };
                node_v[k] = Pic::node_velocity::<E>(state, dt, g.empty_below);
            }
            let mut v = flip::<E, R, One<R>>((), n, &acc, lanes_of(&p.v[i]), dt);
            if let Some(b) = &blend {
                v = b.blend::<E, One<R>>((), n, &node_v[..stencil.len()], v);
            }
            p.v[i] = point_of::<E, R>(v, &p.v[i]);
            if let Some(slots) = guard.as_deref_mut() {
                let m = One::splat((), p.mass[i]);
                let twice = kinetic::<E, R, One<R>>((), m, &lanes_of(&p.v[i]));
                slots[e / ELEMENT_BLOCK].kinetic += twice.0[0].f64();
            }
            at.add::<E>(
                stencil.nodes(),
                One::splat((), p.mass[i]),
                &p.v[i],
                momentum,
            );
            let (Some(l), Some(lp), Some(gl)) = (&liquid, &mut p.liquid, &g.liquid) else {
                continue;
            };
            let Some(f) = l.fluids[p.material[i] as usize] else {
                continue;
            };
            for (k, &node) in stencil.nodes().iter().enumerate() {
                acc[k] = gl.acc[node as usize];
            }
            let w = flip::<E, R, One<R>>((), n, &acc, lanes_of(&lp.w[i]), dt);
            lp.w[i] = point_of::<E, R>(w, &lp.w[i]);
            let volume = lp.volume0.as_ref().map_or(p.volume[i], |v0| v0[i]);
            let mw = liquid_mass((), &f, One::splat((), volume));
            at.add::<E>(stencil.nodes(), mw, &lp.w[i], momentum_w);
            if let Some(slots) = guard.as_deref_mut() {
                let twice = kinetic::<E, R, One<R>>((), mw, &lanes_of(&lp.w[i]));
                slots[e / ELEMENT_BLOCK].kinetic += twice.0[0].f64();
            }
        }
    }
    for n in 0..nodes {
        g.vel[n] = velocity::<E, R>(&vector(momentum, n), g.mass[n], g.empty_below, &fixed[n]);
    }
    if let (Some(l), Some(gl)) = (liquid, g.liquid.as_mut()) {
        for n in 0..nodes {
            gl.vel[n] = velocity::<E, R>(
                &vector(momentum_w, n),
                gl.mass[n],
                g.empty_below,
                &l.fixed[n],
            );
        }
    }
}

/// A point's weights as one-lane values.
struct Weights<R: Real> {
    n: [One<R>; MOST_NODES],
}

impl<R: Real> Weights<R> {
    /// The weights of `stencil`.
    fn of(stencil: &Stencil<R>) -> Self {
        let mut n = [One::splat((), R::ZERO); MOST_NODES];
        for (nk, &w) in n.iter_mut().zip(stencil.weights()) {
            *nk = Plain([w]);
        }
        Weights { n }
    }

    /// Adds `m` N_k v to each node's momentum (`momentum`: three values a node).
    fn add<E: Element>(&self, nodes: &[u32], m: One<R>, v: &V3<R>, momentum: &mut [R]) {
        for (nk, &node) in self.n.iter().zip(nodes) {
            let mn = m * *nk;
            for c in 0..E::DIM {
                momentum[3 * node as usize + c] += (mn * One::splat((), v[c])).0[0];
            }
        }
    }
}

/// A point's 3-vector as one-lane values.
fn lanes_of<R: Real>(v: &V3<R>) -> [One<R>; 3] {
    v.map(|c| Plain([c]))
}

/// One-lane values back into a point's 3-vector: its first [`Element::DIM`] components, the
/// others as they were.
fn point_of<E: Element, R: Real>(v: [One<R>; 3], old: &V3<R>) -> V3<R> {
    let mut out = *old;
    for c in 0..E::DIM {
        out[c] = v[c].0[0];
    }
    out
}

/// Node `n`'s 3-vector of `values` (three a node).
fn vector<R: Real>(values: &[R], n: usize) -> V3<R> {
    [values[3 * n], values[3 * n + 1], values[3 * n + 2]]
}
