//! Particle to grid: lumped masses, momentum, internal and gravity forces (docs/design.md §4,
//! step 1), summed element by element and then node by node on the team (see
//! [`crate::parallel::gather`]).
//!
//! The files, top-down: the pass and its nodes' values here; one element's turn
//! (`element.rs`: an empty element, the mixed rule's Gauss point); the walk over an element's
//! points in node lanes (`lanes.rs`); one point's share, the pass's physics (`point.rs`); the
//! terms formed once per element (`totals.rs`); the point arrays (`arrays.rs`); the loads
//! carried by points (`loads.rs`); and the pass over any other basis's stencils (`stencil.rs`).

mod arrays;
mod element;
mod lanes;
mod loads;
mod point;
mod stencil;
#[cfg(test)]
mod tests;
mod totals;

pub use loads::add_point_loads;

use crate::basis::Basis;
use crate::element::tet4::Tet4;
use crate::element::tri3::Tri3;
use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::Slots;
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::state::pore_weights::PoreWeights;
use crate::step::batch::{Portable, TETRAHEDRA};
use crate::step::contact::OneBody;
use crate::step::mixed::Mixed;
use crate::step::passes::Passes;

use arrays::{PointArrays, Points};
use element::{element_sums, MixedOut, Pass};
use point::vector;
use totals::Sums;

/// Values per node of the solid pass: the mass, then momentum, internal force and weight with
/// [`Element::DIM`] components each (a 2D element's z-components are 0 and not summed).
const fn solid_width<E: Element>() -> usize {
    1 + 3 * E::DIM
}

/// Values per node of the liquid pass: the two liquid masses and the drag, then liquid
/// momentum, liquid force and the liquid's weight, [`Element::DIM`] components each.
const fn liquid_width<E: Element>() -> usize {
    3 + 3 * E::DIM
}

/// What the liquid's share of particle to grid needs (two-phase cases): each material's fluid
/// (`None` for a dry material) and the gravity acceleration (multiplier applied).
#[derive(Clone, Copy)]
pub struct LiquidLoads<'a, R: Real> {
    /// Per material, its fluid.
    pub fluids: &'a [Option<Fluid<R>>],
    /// The acceleration that gives the liquid's weight.
    pub gravity: V3<R>,
}

/// What particle to grid maps, and where to.
pub struct MapToGrid<'a, R: Real> {
    /// The points.
    pub particles: &'a Particles<R>,
    /// Per material, the acceleration (multiplier applied) that gives its points' weight from
    /// their mass.
    pub gravity: &'a [V3<R>],
    /// The nodes' sums, written.
    pub grid: &'a mut Grid<R>,
    /// Only the points of this body (all for `None`; one body of a contact pair,
    /// [`crate::step::contact`]).
    pub body: Option<OneBody>,
    /// Under mixed integration, the rule's element sums (formed here).
    pub mixed: Option<&'a mut Mixed<R>>,
    /// In a two-phase case, the liquid's share.
    pub liquid: Option<LiquidLoads<'a, R>>,
    /// Where the liquid's pass leaves the pore-pressure rate's weights (a two-phase case whose
    /// rate is smoothed).
    pub pore_weights: Option<&'a mut PoreWeights<R>>,
}

/// Maps every active particle to the nodes its basis gives it: mass, momentum, internal force
/// -Σ V (σ' + p I) ∇N and gravity. With `pore_weights` (a two-phase case whose pore-pressure
/// rate is smoothed), the liquid's pass also leaves each element's Σ_p V_p N_k over its
/// saturated points and their material for that rate ([`crate::state::pore_weights`]).
/// Under mixed integration the effective-stress force of full elements comes from their Gauss
/// point instead of their points (the element sums are formed here too, over all the element's
/// points). Only the points of `body` are mapped; a full element's Gauss point belongs to the
/// body of its first active point (a full element holds one material).
///
/// With `liquid` (a two-phase case), the same pass over the points also forms the liquid's
/// share (two-phase, docs/design.md §4): liquid masses M_w and M̄_w, drag Q, liquid momentum,
/// the liquid force -Σ V p ∇N + M_w g, and the liquid's weight added to the mixture's external
/// force, from the points of materials with a fluid. Under mixed integration, full elements
/// integrate the pore-pressure force at their Gauss point. One pass for both phases computes
/// each point's shape functions and reads its position once, and each node's values are summed
/// as the two passes summed them. The liquid is mapped with every point (`body` `None`) or with the
/// soil's (a contact pair's structure is dry).
///
/// The linear element's basis takes the element kernels; any other, its stencils
/// ([`crate::basis`]).
pub fn particle_to_grid<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    to: MapToGrid<'_, R>,
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    if B::LINEAR {
        map_elements(passes, slots, to);
    } else {
        stencil::map_stencils(passes, slots, to);
    }
}

/// The element kernels' particle to grid ([`particle_to_grid`]).
fn map_elements<E, R, B>(passes: &Passes<'_, R, E, B>, slots: &mut Slots<R>, to: MapToGrid<'_, R>)
where
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
    let liquid = match (liquid, &p.liquid) {
        (Some(l), Some(lp)) if g.liquid.is_some() => Some((l, lp)),
        _ => None,
    };
    debug_assert!(
        liquid.is_none() || body.map_or(true, |b| !b.structure),
        "the liquid mapped with the structure of a contact pair"
    );
    // The rate's weights come with the liquid's pass only.
    let pore_weights = pore_weights.filter(|_| liquid.is_some()).map(|w| {
        w.fit(passes.mesh.elements());
        w.fresh = true;
        (Shared::new(&mut w.weights), Shared::new(&mut w.material))
    });
    let pass = Pass {
        mesh: passes.mesh,
        p,
        gravity,
        mixed: mixed.map(|m| MixedOut {
            stress: Shared::new(&mut m.stress),
            full: Shared::new(&mut m.full),
            pressure: Shared::new(&mut m.pressure),
            filling: R::of(m.filling),
            rule: m.rule,
            boundary: &m.boundary[..],
        }),
        pore_weights,
        liquid,
        body,
        arrays: PointArrays::new(p, liquid.is_some()),
    };
    let nodes = NodeSums::new(g, liquid.is_some());
    let node = |n: usize, s: &[R]| nodes.write::<E>(n, s);
    let wide = use_avx2();
    // What each element's pass reads ([`element_sums`]): the dry variant compiles without the
    // liquid's code, and each variant is a closure of its own with one caller, which the
    // compiler inlines into its scatter (one closure called from two variants was left a call,
    // at 6 % more instructions per point-step). Each in the baseline instruction set or, where
    // the processor has them and the build does not assume them, with AVX2's 256-bit
    // registers (four f64 node lanes in one; the same bits).
    macro_rules! pass {
        ($width:literal, $liquid:literal) => {
            if wide {
                let t = R::Four::token().expect("AVX2, asked for");
                passes.layout.sum_to_nodes::<$width, true, _, _>(
                    passes.team,
                    slots,
                    |e, points, four| {
                        element_sums::<E, R, R::Four, $liquid, true>(&pass, t, e, points, four)
                    },
                    node,
                )
            } else {
                let t = <Portable<R> as Four<R>>::token().expect("the portable lanes");
                passes.layout.sum_to_nodes::<$width, false, _, _>(
                    passes.team,
                    slots,
                    |e, points, four| {
                        element_sums::<E, R, Portable<R>, $liquid, false>(&pass, t, e, points, four)
                    },
                    node,
                )
            }
        };
    }
    // The pass as wide as the element's dimension and the phases need: 7 or 10 values for the
    // solid in 2D or 3D, 7 + 9 or 10 + 12 with the liquid.
    const {
        assert!(solid_width::<Tri3>() == 7 && solid_width::<Tet4>() == 10);
        assert!(liquid_width::<Tri3>() == 9 && liquid_width::<Tet4>() == 12);
        assert!(TETRAHEDRA == 4);
    };
    match (E::DIM, liquid.is_some()) {
        (2, false) => pass!(7, false),
        (3, false) => pass!(10, false),
        (2, true) => pass!(16, true),
        (3, true) => pass!(22, true),
        (d, _) => unreachable!("a pass in {d} dimensions"),
    }
}

/// Where the pass's node values go: the grid's arrays (the liquid's, in its pass), each node
/// written by the thread that sums it.
struct NodeSums<'a, R: Real> {
    mass: Shared<'a, R>,
    momentum: Shared<'a, V3<R>>,
    f_int: Shared<'a, V3<R>>,
    f_ext: Shared<'a, V3<R>>,
    liquid: Option<LiquidNodeSums<'a, R>>,
}

/// The liquid's node arrays: its two masses, drag, momentum and force.
type LiquidNodeSums<'a, R> = (
    Shared<'a, R>,
    Shared<'a, R>,
    Shared<'a, R>,
    Shared<'a, V3<R>>,
    Shared<'a, V3<R>>,
);

impl<'a, R: Real> NodeSums<'a, R> {
    /// The arrays of `g` (its liquid's, `with_liquid`).
    fn new(g: &'a mut Grid<R>, with_liquid: bool) -> Self {
        NodeSums {
            mass: Shared::new(&mut g.mass),
            momentum: Shared::new(&mut g.momentum),
            f_int: Shared::new(&mut g.f_int),
            f_ext: Shared::new(&mut g.f_ext),
            liquid: g.liquid.as_mut().filter(|_| with_liquid).map(|gl| {
                (
                    Shared::new(&mut gl.mass),
                    Shared::new(&mut gl.mass_n),
                    Shared::new(&mut gl.drag),
                    Shared::new(&mut gl.momentum),
                    Shared::new(&mut gl.force),
                )
            }),
        }
    }

    /// Node n's values `s` (the solid's, then the liquid's) into the arrays, the liquid's
    /// weight added to the mixture's external force.
    #[inline(always)]
    fn write<E: Element>(&self, n: usize, s: &[R]) {
        let sw = solid_width::<E>();
        let mut fe = vector::<E, R>(s, 1 + 2 * E::DIM);
        // SAFETY: node n is this thread's only.
        unsafe {
            self.mass.write(n, s[0]);
            self.momentum.write(n, vector::<E, R>(s, 1));
            self.f_int.write(n, vector::<E, R>(s, 1 + E::DIM));
            if let Some((mass, mass_n, drag, momentum, force)) = &self.liquid {
                let l = &s[sw..];
                mass.write(n, l[0]);
                mass_n.write(n, l[1]);
                drag.write(n, l[2]);
                momentum.write(n, vector::<E, R>(l, 3));
                force.write(n, vector::<E, R>(l, 3 + E::DIM));
                // The liquid's weight, added to the mixture's.
                for a in 0..E::DIM {
                    fe[a] += l[3 + 2 * E::DIM + a];
                }
            }
            self.f_ext.write(n, fe);
        }
    }
}

/// [`lanes::node_lane_sums`] compiled with AVX2, where the four-lane operations are single
/// instructions (a function of its own: inlined into the scatter's element closure, the
/// saturated pass's closure grew too large for the compiler to inline into its AVX2 copy).
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn node_lane_sums_avx2<E, R, F, const WITH_LIQUID: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    start: Option<&Sums<R, F>>,
    lead: u32,
    g: &[F; 3],
    four: &mut [R],
) -> ([R; 4], u32)
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    lanes::node_lane_sums::<E, R, F, WITH_LIQUID>(t, points, start, lead, g, four)
}
