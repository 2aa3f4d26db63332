//! Particle to grid over any basis's stencils ([`crate::basis`]): each point's nodes four at a
//! time in the lanes of [`Lanes4`], its share of each formed by the element kernels' physics
//! ([`point_sums`], then [`Sums::close`] with the point's own gradients), and summed into the
//! nodes point by point in point order, each thread its own nodes' sums
//! ([`crate::parallel::reach`]).

use std::ops::Range;

use crate::basis::{Basis, Stencil};
use crate::element::Element;
use crate::four::{Four, Lanes4};
use crate::parallel::gather::{scratch, Slots};
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::step::contact::maps;
use crate::step::passes::Passes;

use super::arrays::{PointArrays, Points};
use super::point::point_sums;
use super::totals::Sums;
use super::{liquid_width, solid_width, MapToGrid, NodeSums};

/// No material's points take their weight from the totals: each point adds its own.
const NO_LEAD: u32 = u32::MAX;

/// [`super::particle_to_grid`] with `passes.basis`'s stencils: the mass, momentum, internal
/// force and weight of every active point of the body, and the liquid's share in its pass.
/// Mixed integration and the pore-pressure rate's weights are the linear element's (one
/// gradient per element): refused, and not formed.
///
/// # Panics
/// Under mixed integration.
pub(super) fn map_stencils<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    to: MapToGrid<'_, R>,
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    let MapToGrid {
        particles: p,
        gravity,
        grid: g,
        body,
        mixed,
        liquid,
        pore_weights,
    } = to;
    assert!(
        mixed.is_none(),
        "mixed integration takes the linear element's kernels"
    );
    if let Some(w) = pore_weights {
        // Not formed: the rate's pass takes its points one by one.
        w.fresh = false;
    }
    let liquid = liquid.filter(|_| p.liquid.is_some() && g.liquid.is_some());
    let (mesh, layout, reach) = (passes.mesh, passes.layout, passes.reach());
    let (sw, lw) = (solid_width::<E>(), liquid_width::<E>());
    let width = if liquid.is_some() { sw + lw } else { sw };
    // The nodes' sums in the scatter's slots (grown on the first step only).
    let nodes = Shared::new(scratch(slots, width * mesh.x.len()));
    let arrays = PointArrays::new(p, liquid.is_some());
    let liquid_gravity = liquid.map(|l| l.gravity);
    let out = NodeSums::new(g, liquid.is_some());
    passes.team.run(|t| {
        let own = reach.nodes(t);
        // SAFETY: the threads' node ranges are disjoint (`Reach`): these sums are this
        // thread's only.
        let mine = unsafe { nodes.range(width * own.start..width * own.end) };
        let takes_part = |i: usize| p.active[i] && maps(body, p.material[i]);
        let on = (passes.basis, mesh, layout);
        reach.visit(t, on, (&p.x, takes_part), |e, i, stencil| {
            let corners = mesh.corners[e].as_ref();
            let one = arrays.element(i..i + 1);
            let points = Points::<E, R> {
                arrays: one,
                liquid: liquid.and_then(|l| one.w.map(|w| (l, w, one.volume0))),
                map: &mesh.map[e],
                first: &mesh.x[corners[0] as usize],
                gravity,
                body,
                full: false,
            };
            let share = PointShare {
                points: &points,
                stencil,
                liquid_gravity,
            };
            if liquid.is_some() {
                share.add::<true>(mine, width, own.clone());
            } else {
                share.add::<false>(mine, width, own.clone());
            }
        });
        for (k, s) in mine.chunks_exact(width).enumerate() {
            out.write::<E>(own.start + k, s);
        }
    });
}

/// One point with its stencil, and the liquid's gravity in the liquid's pass.
struct PointShare<'a, E: Element, R: Real> {
    points: &'a Points<'a, E, R>,
    stencil: &'a Stencil<R>,
    liquid_gravity: Option<V3<R>>,
}

impl<E: Element, R: Real> PointShare<'_, E, R> {
    /// Adds the point's share of each of its nodes in `own` to their sums in `nodes` (from
    /// `own`'s first; `width` values a node: the solid's, then the liquid's with
    /// `WITH_LIQUID`), four nodes at a time.
    fn add<const WITH_LIQUID: bool>(&self, nodes: &mut [R], width: usize, own: Range<usize>) {
        let t = ();
        let (sw, lw) = (solid_width::<E>(), liquid_width::<E>());
        let (node, weight, grad) = (
            self.stencil.nodes(),
            self.stencil.weights(),
            self.stencil.gradients(),
        );
        for from in (0..node.len()).step_by(4) {
            let live = (node.len() - from).min(4);
            let (mut n, mut g) = ([R::ZERO; 4], [[R::ZERO; 4]; 3]);
            for k in 0..live {
                n[k] = weight[from + k];
                for (b, gb) in g.iter_mut().enumerate() {
                    gb[k] = grad[from + k][b];
                }
            }
            let n = Lanes4::load(t, &n);
            let g = g.map(|gb| Lanes4::load(t, &gb));
            let mut sums = Sums::<R, Lanes4<R>>::zero(t, NO_LEAD);
            point_sums::<E, R, Lanes4<R>, WITH_LIQUID, false>(t, self.points, 0, n, &mut sums);
            sums.close::<E, WITH_LIQUID>(t, &g, [R::ZERO; 3], self.liquid_gravity);
            let solid = sums.solid.map(|v| v.to_array());
            let liquid = sums.liquid.map(|v| v.to_array());
            for k in 0..live {
                let n = node[from + k] as usize;
                if !own.contains(&n) {
                    continue;
                }
                let at = width * (n - own.start);
                let values = &mut nodes[at..at + width];
                for c in 0..sw {
                    values[c] += solid[c][k];
                }
                if WITH_LIQUID {
                    for c in 0..lw {
                        values[sw + c] += liquid[c][k];
                    }
                }
            }
        }
    }
}
