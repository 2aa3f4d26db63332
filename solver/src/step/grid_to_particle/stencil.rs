//! Grid to particle over any basis's stencils ([`crate::basis`]): each point's velocity
//! updated from its nodes' accelerations and its momentum re-mapped to them by the element
//! kernels' physics ([`super::point`], one lane: the point), summed point by point in point
//! order on the calling thread (the team's scatter holds an element's corners only), then the
//! nodal velocities ([`velocity`]).

use std::ops::Range;

use crate::basis::{Basis, Stencil, MOST_NODES};
use crate::element::Element;
use crate::four::{Lanes, Plain};
use crate::real::{Real, V3};
use crate::step::contact::maps;
use crate::step::passes::Passes;

use super::nodal::velocity;
use super::point::{flip, kinetic, liquid_mass, NodeState, Pic};
use super::{LiquidRemap, Remap};
use crate::parallel::gather::{scratch, Slots, ELEMENT_BLOCK};
use crate::parallel::team::Shared;
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::contact::OneBody;
use crate::step::stress::GuardSums;

/// One lane: one point.
type One<R> = Plain<R, 1>;

/// [`super::grid_to_particle`] with `passes.basis`'s stencils: the active points of the body
/// take their velocity update (FLIP, blended with PIC), chunk by chunk on the team; with the
/// guard rails, each point's kinetic terms into its element's block's slot (begun anew with
/// `begin`) in point order. Then each thread re-maps the momenta of the points within reach of
/// its nodes into them, point by point in point order ([`crate::parallel::reach`]), with the
/// liquid's too, and forms its nodes' velocities.
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
    if let (Some(slots), true) = (guard.as_deref_mut(), begin) {
        slots.fill(GuardSums::EMPTY);
    }
    let liquid = liquid.filter(|_| p.liquid.is_some() && g.liquid.is_some());
    let (mesh, layout) = (passes.mesh, passes.layout);
    let blend = (pic > R::ZERO).then_some(Pic {
        flip: R::ONE - pic,
        pic,
    });
    // The velocity update: each point once, by the chunk that holds its element.
    {
        let v = Shared::new(&mut p.v);
        let (w, volume0) = match p.liquid.as_mut() {
            Some(lp) => (Some(Shared::new(&mut lp.w)), lp.volume0.as_deref()),
            None => (None, None),
        };
        let guard = guard.map(Shared::new);
        let (x, material) = (&p.x, &p.material);
        let (active, mass, volume) = (&p.active, &p.mass, &p.volume);
        let g = &*g;
        passes.team.run_chunks(layout.thread_chunks(), |_, c| {
            let mut stencil = Stencil::default();
            let mut at_nodes = [[R::ZERO; 3]; MOST_NODES];
            let mut weights = Weights::new();
            for e in layout.chunk_elements(c) {
                for i in layout.particles_of(e) {
                    if !active[i] || !maps(body, material[i]) {
                        continue;
                    }
                    passes.basis.stencil(mesh, e, &x[i], &mut stencil);
                    let n = weights.set(&stencil);
                    // SAFETY: point i and its element's block are chunk c's, which one
                    // thread runs.
                    let (vi, block) = unsafe {
                        (
                            &mut v.array::<1>(i)[0],
                            guard
                                .as_ref()
                                .map(|s| &mut s.array::<1>(e / ELEMENT_BLOCK)[0]),
                        )
                    };
                    let acc = nodes_of(&stencil, &g.acc, &mut at_nodes);
                    let mut vn = flip::<E, R, One<R>>((), n, acc, lanes_of(vi), dt);
                    if let Some(b) = &blend {
                        let node_v = pic_velocities::<E, R>(&stencil, g, fixed, dt);
                        vn = b.blend::<E, One<R>>((), n, &node_v[..stencil.len()], vn);
                    }
                    *vi = point_of::<E, R>(vn, vi);
                    let mut block = block;
                    if let Some(block) = block.as_deref_mut() {
                        let m = One::splat((), mass[i]);
                        block.kinetic += kinetic::<E, R, One<R>>((), m, &lanes_of(vi)).0[0].f64();
                    }
                    let (Some(l), Some(w), Some(gl)) = (&liquid, &w, &g.liquid) else {
                        continue;
                    };
                    let Some(f) = l.fluids[material[i] as usize] else {
                        continue;
                    };
                    // SAFETY: as the point's velocity above.
                    let wi = unsafe { &mut w.array::<1>(i)[0] };
                    let acc = nodes_of(&stencil, &gl.acc, &mut at_nodes);
                    let wn = flip::<E, R, One<R>>((), n, acc, lanes_of(wi), dt);
                    *wi = point_of::<E, R>(wn, wi);
                    if let Some(block) = block {
                        let vol = volume0.map_or(volume[i], |v0| v0[i]);
                        let mw = liquid_mass((), &f, One::splat((), vol));
                        block.kinetic += kinetic::<E, R, One<R>>((), mw, &lanes_of(wi)).0[0].f64();
                    }
                }
            }
        });
    }
    remap_momenta(passes, slots, (p, g), (fixed, body, liquid));
}

/// The second half of [`remap_stencils`]: each thread re-maps into its own nodes the momenta
/// of the body's points within their reach (the liquid's too), point by point in point order,
/// and forms its nodes' velocities.
fn remap_momenta<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    (p, g): (&Particles<R>, &mut Grid<R>),
    (fixed, body, liquid): (&[[bool; 3]], Option<OneBody>, Option<LiquidRemap<'_, R>>),
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    let (mesh, layout, reach) = (passes.mesh, passes.layout, passes.reach());
    let nodes = mesh.x.len();
    let (momentum, momentum_w) = scratch(slots, 6 * nodes).split_at_mut(3 * nodes);
    let (momentum, momentum_w) = (Shared::new(momentum), Shared::new(momentum_w));
    let (mass, empty_below) = (&g.mass, g.empty_below);
    let vel = Shared::new(&mut g.vel);
    let liquid_nodes = g
        .liquid
        .as_mut()
        .filter(|_| liquid.is_some())
        .map(|gl| (&gl.mass, Shared::new(&mut gl.vel)));
    passes.team.run(|t| {
        let own = reach.nodes(t);
        let span = 3 * own.start..3 * own.end;
        // SAFETY: the threads' node ranges are disjoint (`Reach`).
        let (mine, mine_w) = unsafe { (momentum.range(span.clone()), momentum_w.range(span)) };
        let mut at = Weights::new();
        let takes_part = |i: usize| p.active[i] && maps(body, p.material[i]);
        let on = (passes.basis, mesh, layout);
        reach.visit(t, on, (&p.x, takes_part), |_, i, stencil| {
            at.set(stencil);
            let nodes = stencil.nodes();
            at.add::<E>(nodes, One::splat((), p.mass[i]), &p.v[i], mine, &own);
            let (Some(l), Some(lp)) = (&liquid, &p.liquid) else {
                return;
            };
            let Some(f) = l.fluids[p.material[i] as usize] else {
                return;
            };
            let volume = lp.volume0.as_ref().map_or(p.volume[i], |v0| v0[i]);
            let mw = liquid_mass((), &f, One::splat((), volume));
            at.add::<E>(nodes, mw, &lp.w[i], mine_w, &own);
        });
        for n in own.clone() {
            let m = vector(mine, n - own.start);
            // SAFETY: node n is this thread's only.
            unsafe { vel.write(n, velocity::<E, R>(&m, mass[n], empty_below, &fixed[n])) };
            if let (Some(l), Some((mass_w, vel_w))) = (&liquid, &liquid_nodes) {
                let m = vector(mine_w, n - own.start);
                let v = velocity::<E, R>(&m, mass_w[n], empty_below, &l.fixed[n]);
                // SAFETY: as above.
                unsafe { vel_w.write(n, v) };
            }
        }
    });
}

/// The values of `field` at `stencil`'s nodes, into the front of `out`.
fn nodes_of<'o, R: Real>(
    stencil: &Stencil<R>,
    field: &[V3<R>],
    out: &'o mut [V3<R>; MOST_NODES],
) -> &'o [V3<R>] {
    for (o, &node) in out.iter_mut().zip(stencil.nodes()) {
        *o = field[node as usize];
    }
    &out[..stencil.len()]
}

/// The velocities after the step of `stencil`'s nodes (PIC's; `None` in a fixed component or
/// at an empty node).
fn pic_velocities<E: Element, R: Real>(
    stencil: &Stencil<R>,
    g: &Grid<R>,
    fixed: &[[bool; 3]],
    dt: R,
) -> [[Option<R>; 3]; MOST_NODES] {
    let mut out = [[None; 3]; MOST_NODES];
    for (o, &node) in out.iter_mut().zip(stencil.nodes()) {
        let node = node as usize;
        let state = NodeState {
            mass: g.mass[node],
            momentum: &g.momentum[node],
            acc: &g.acc[node],
            fixed: &fixed[node],
        };
        *o = Pic::node_velocity::<E>(state, dt, g.empty_below);
    }
    out
}

/// A point's weights as one-lane values.
struct Weights<R: Real> {
    n: [One<R>; MOST_NODES],
}

impl<R: Real> Weights<R> {
    /// Room for a stencil's weights (one per thread and pass, reused point after point).
    fn new() -> Self {
        Weights {
            n: [One::splat((), R::ZERO); MOST_NODES],
        }
    }

    /// The weights of `stencil`, into the front of the room.
    fn set(&mut self, stencil: &Stencil<R>) -> &[One<R>] {
        for (nk, &w) in self.n.iter_mut().zip(stencil.weights()) {
            *nk = Plain([w]);
        }
        &self.n[..stencil.len()]
    }

    /// Adds `m` N_k v to the momentum of each node in `own` (`momentum`: three values a
    /// node, from `own`'s first).
    fn add<E: Element>(
        &self,
        nodes: &[u32],
        m: One<R>,
        v: &V3<R>,
        momentum: &mut [R],
        own: &Range<usize>,
    ) {
        for (nk, &node) in self.n.iter().zip(nodes) {
            let node = node as usize;
            if !own.contains(&node) {
                continue;
            }
            let mn = m * *nk;
            for c in 0..E::DIM {
                momentum[3 * (node - own.start) + c] += (mn * One::splat((), v[c])).0[0];
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
