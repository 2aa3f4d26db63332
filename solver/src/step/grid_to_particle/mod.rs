//! Grid to particle, MUSL: FLIP velocity update, then momentum re-mapped to the nodes for the
//! velocities that drive strain, stress, volume and position (docs/design.md §4, step 3), on
//! the team.
//!
//! The files, top-down: the pass here; one element's turn and the guard's sums (`element.rs`);
//! the walk over an element's points in lanes (`lanes.rs`); the pass's physics (`point.rs`); the
//! nodal velocities (`nodal.rs`); and the pass over any other basis's stencils (`stencil.rs`).

mod element;
mod lanes;
mod nodal;
mod point;
mod stencil;

use crate::basis::Basis;
use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{Slots, ELEMENT_BLOCK};
use crate::parallel::team::Shared;
use crate::real::Real;
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::batch::Portable;
use crate::step::contact::OneBody;
use crate::step::passes::Passes;
use crate::step::stress::GuardSums;

use element::{element_remap, LiquidRemapping, PicNodes, Remapping};
use nodal::{nodal_velocity, PhaseNodes};
use point::Pic;

/// What the liquid's share of grid to particle needs (two-phase cases): each material's fluid
/// (`None` for a dry material) and the liquid's fixities.
#[derive(Clone, Copy)]
pub struct LiquidRemap<'a, R: Real> {
    /// Per material, its fluid.
    pub fluids: &'a [Option<Fluid<R>>],
    /// Per node, the liquid's fixed components.
    pub fixed: &'a [[bool; 3]],
}

/// What grid to particle updates, and from which nodes.
pub struct Remap<'a, R: Real> {
    /// The points, their velocities updated.
    pub particles: &'a mut Particles<R>,
    /// The nodes: their accelerations read, their re-mapped velocities written.
    pub grid: &'a mut Grid<R>,
    /// Per node, the solid's fixed components.
    pub fixed: &'a [[bool; 3]],
    /// The step.
    pub dt: R,
    /// The PIC share of the velocity update (0: FLIP).
    pub pic: R,
    /// With the guard rails, one slot per block of [`ELEMENT_BLOCK`] elements for the kinetic
    /// energy.
    pub guard: Option<&'a mut [GuardSums]>,
    /// Only the points of this body (all for `None`; one body of a contact pair,
    /// [`crate::step::contact`]).
    pub body: Option<OneBody>,
    /// Whether this pass begins the guard's slots (the second body's adds to them).
    pub begin: bool,
    /// In a two-phase case, the liquid's share.
    pub liquid: Option<LiquidRemap<'a, R>>,
}

/// Updates particle velocities from nodal accelerations (FLIP; with `pic` > 0 blended with
/// the nodes' updated velocities, PIC), then re-maps momentum to get the nodal velocities
/// (fixed components and empty nodes zero) that drive strain, stress, volume and position
/// (see [`crate::step::stress`]). With `guard` (one slot per block of
/// [`ELEMENT_BLOCK`] elements), each block's slot is begun anew at its
/// first element and summed over its elements in order with their points' Σ m |v|² (twice
/// their kinetic energy), the velocities at hand. Only the points of `body` take part; the
/// second body's pass adds its kinetic energy to the slots the first began (`begin` false).
///
/// With `liquid` (a two-phase case), the same pass updates the liquid velocities of the points
/// of materials with a fluid from the nodal liquid accelerations (FLIP) and re-maps the liquid
/// momentum to nodal liquid velocities (zero in the liquid's fixed components and at empty
/// nodes); with `guard`, each block's slot then takes the liquid's n ρw V_w |w|² (twice its
/// kinetic energy) element by element after the solid's sums of the block, the order of a
/// liquid pass of its own. One pass computes each point's shape functions and reads its
/// position once for both phases. The liquid goes with every point (`body` `None`) or with the
/// soil's (a contact pair's structure is dry).
///
/// The linear element's basis takes the element kernels; any other, its stencils
/// ([`crate::basis`]).
pub fn grid_to_particle<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    remap: Remap<'_, R>,
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    if B::LINEAR {
        remap_elements(passes, slots, remap);
    } else {
        stencil::remap_stencils(passes, slots, remap);
    }
}

/// The element kernels' grid to particle ([`grid_to_particle`]).
fn remap_elements<E, R, B>(passes: &Passes<'_, R, E, B>, slots: &mut Slots<R>, remap: Remap<'_, R>)
where
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
        guard,
        body,
        begin,
        liquid,
    } = remap;
    let liquid = liquid.filter(|_| p.liquid.is_some() && g.liquid.is_some());
    debug_assert!(
        liquid.is_none() || body.map_or(true, |b| !b.structure),
        "the liquid re-mapped with the structure of a contact pair"
    );
    let with_guard = guard.is_some();
    let (liquid_vel, volume0) = match &mut p.liquid {
        Some(lp) => (Some(Shared::new(&mut lp.w)), lp.volume0.as_deref()),
        None => (None, None),
    };
    let cx = Remapping {
        mesh: passes.mesh,
        x: &p.x,
        mass: &p.mass,
        active: &p.active,
        material: &p.material,
        volume: &p.volume,
        volume0,
        vel: Shared::new(&mut p.v),
        liquid: liquid
            .zip(liquid_vel)
            .zip(g.liquid.as_ref())
            .map(|((l, w), gl)| LiquidRemapping {
                w,
                fluids: l.fluids,
                acc: &gl.acc[..],
            }),
        acc: &g.acc,
        pic: (pic > R::ZERO).then_some(PicNodes {
            blend: Pic {
                flip: R::ONE - pic,
                pic,
            },
            mass: &g.mass,
            momentum: &g.momentum,
            fixed,
            empty_below: g.empty_below,
        }),
        body,
        dt,
        guard: guard.map(|s| (Shared::new(s), begin, passes.mesh.elements())),
    };
    scatter(passes, slots, &cx, with_guard, liquid.is_some());
    let solid = PhaseNodes {
        mass: &g.mass,
        fixed,
        vel: &mut g.vel,
    };
    let liquid_nodes = g.liquid.as_mut().zip(liquid).map(|(gl, l)| PhaseNodes {
        mass: &gl.mass,
        fixed: l.fixed,
        vel: &mut gl.vel,
    });
    let team_layout = (passes.team, passes.layout);
    nodal_velocity::<E, R>(team_layout, slots, g.empty_below, solid, liquid_nodes);
}

/// The scatter of every element's turn: each variant (the guard's kinetic sums, the liquid's
/// share) a closure of its own at its re-map width (a literal: the solid's 3 or 2 values per
/// node, then as many for the liquid), so that each compiles without the code it does not need
/// and, with one caller, is inlined into its scatter; once for each instruction set (the
/// baseline, and where the processor has it and the build does not assume it, AVX2: the same
/// bits).
fn scatter<E, R, B>(
    passes: &Passes<'_, R, E, B>,
    slots: &mut Slots<R>,
    cx: &Remapping<'_, E, R>,
    with_guard: bool,
    with_liquid: bool,
) where
    E: Element,
    R: Real,
    B: Basis<E, R>,
{
    let (team, layout) = (passes.team, passes.layout);
    let wide = use_avx2();
    // The liquid's kinetic sums of the block's elements so far, added to the block's slot
    // after its last element (after the solid's sums of the block).
    let init = |_| [0.0f64; ELEMENT_BLOCK];
    macro_rules! run {
        ($want:literal, $liquid:literal, $width:literal) => {{
            if wide {
                let t = R::Four::token().expect("AVX2, asked for");
                layout.scatter_with::<$width, true, true, _, _>(team, slots, init, |e, r, f, k| {
                    element_remap::<E, R, R::Four, $want, $liquid, true>(cx, t, e, (r, f), k)
                })
            } else {
                let t = <Portable<R> as Four<R>>::token().expect("the portable lanes");
                layout.scatter_with::<$width, false, true, _, _>(team, slots, init, |e, r, f, k| {
                    element_remap::<E, R, Portable<R>, $want, $liquid, false>(cx, t, e, (r, f), k)
                })
            }
        }};
    }
    match (with_guard, with_liquid, E::DIM) {
        (false, false, 3) => run!(false, false, 3),
        (false, false, _) => run!(false, false, 2),
        (false, true, 3) => run!(false, true, 6),
        (false, true, _) => run!(false, true, 4),
        (true, false, 3) => run!(true, false, 3),
        (true, false, _) => run!(true, false, 2),
        (true, true, 3) => run!(true, true, 6),
        (true, true, _) => run!(true, true, 4),
    }
}

/// [`element::remap_element`] compiled with AVX2 (a function of its own: inlined into the
/// scatter's element closure, the closure grew past what the compiler inlines into its AVX2
/// copy, and was compiled for the baseline).
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn element_lanes_avx2<E, R, F, const WANT: bool, const WITH_LIQUID: bool>(
    cx: &Remapping<'_, E, R>,
    t: F::Token,
    e: usize,
    points: (std::ops::Range<usize>, &mut [R]),
    pending: &mut [f64; ELEMENT_BLOCK],
) where
    E: Element,
    R: Real,
    F: Four<R>,
{
    element::remap_element::<E, R, F, WANT, WITH_LIQUID>(cx, t, e, points, pending)
}
