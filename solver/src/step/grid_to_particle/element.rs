//! One element's turn in grid to particle ([`element_remap`]): its points' arrays sliced, its
//! nodes' values into lanes, the walk over its points ([`super::lanes`]); and, with the guard
//! rails, its kinetic-energy sums into its block's slot ([`guarded`]).

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::parallel::gather::ELEMENT_BLOCK;
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::step::contact::OneBody;
use crate::step::stress::GuardSums;

use super::element_lanes_avx2;
use super::lanes::{element_lanes, ElementPoints, Kernel, LiquidPoints, NodeVelocities};
use super::point::{NodeState, Pic};

/// What every element's turn reads and writes: the mesh, the points' arrays (their
/// velocities written, each element's by the thread that has it), the nodes' values, and the
/// guard's slots.
pub(super) struct Remapping<'a, E: Element, R: Real> {
    pub mesh: &'a Mesh<E, R>,
    pub x: &'a [V3<R>],
    pub mass: &'a [R],
    pub active: &'a [bool],
    pub material: &'a [u32],
    pub volume: &'a [R],
    pub volume0: Option<&'a [R]>,
    pub vel: Shared<'a, V3<R>>,
    /// The liquid's velocities, fluids and nodal accelerations, in the liquid's pass.
    pub liquid: Option<LiquidRemapping<'a, R>>,
    /// The nodes' accelerations.
    pub acc: &'a [V3<R>],
    /// What the PIC blend reads of the nodes, with a blend.
    pub pic: Option<PicNodes<'a, R>>,
    pub body: Option<OneBody>,
    pub dt: R,
    /// The guard's slots (one per block), where its first element begins them (`begin`), and
    /// the mesh's element count.
    pub guard: Option<(Shared<'a, GuardSums>, bool, usize)>,
}

/// The liquid's share of [`Remapping`].
pub(super) struct LiquidRemapping<'a, R: Real> {
    pub w: Shared<'a, V3<R>>,
    pub fluids: &'a [Option<Fluid<R>>],
    pub acc: &'a [V3<R>],
}

/// What the PIC blend reads of the nodes: its weights, and the nodes' masses, momenta,
/// fixities and the empty-node threshold.
pub(super) struct PicNodes<'a, R: Real> {
    pub blend: Pic<R>,
    pub mass: &'a [R],
    pub momentum: &'a [V3<R>],
    pub fixed: &'a [[bool; 3]],
    pub empty_below: R,
}

/// Element `e`'s points (`range`): their velocities updated and their momentum re-mapped into
/// `four`, and with `WANT` (the guard rails) their kinetic-energy terms added to the block's
/// slot ([`remap_element`], in lanes `F`; with `WIDE` in the scatter's AVX2 copy, through
/// [`element_lanes_avx2`], so that the scatter's closure stays small enough to be inlined into
/// its AVX2 copy). An element without points adds nothing (the scatter's contract), but takes
/// its turn in its block's kinetic sums.
#[inline(always)]
pub(super) fn element_remap<E, R, F, const WANT: bool, const WITH_LIQUID: bool, const WIDE: bool>(
    cx: &Remapping<'_, E, R>,
    t: F::Token,
    e: usize,
    (range, four): (std::ops::Range<usize>, &mut [R]),
    pending: &mut [f64; ELEMENT_BLOCK],
) where
    E: Element,
    R: Real,
    F: Four<R>,
{
    if !WANT && range.is_empty() {
        return;
    }
    if WIDE {
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in the scatter's AVX2 copy, which runs where the processor has
        // AVX2.
        unsafe {
            element_lanes_avx2::<E, R, F, WANT, WITH_LIQUID>(cx, t, e, (range, four), pending)
        }
    } else {
        remap_element::<E, R, F, WANT, WITH_LIQUID>(cx, t, e, (range, four), pending)
    }
}

/// [`element_remap`]'s work: the element's points ([`remap_points`], none for an element
/// without points), and with `WANT` their kinetic sums into the block's slot ([`add_kinetic`]).
#[inline(always)]
pub(super) fn remap_element<E, R, F, const WANT: bool, const WITH_LIQUID: bool>(
    cx: &Remapping<'_, E, R>,
    t: F::Token,
    e: usize,
    (range, four): (std::ops::Range<usize>, &mut [R]),
    pending: &mut [f64; ELEMENT_BLOCK],
) where
    E: Element,
    R: Real,
    F: Four<R>,
{
    let kinetic = if range.is_empty() {
        (0.0, 0.0)
    } else {
        remap_points::<E, R, F, WANT, WITH_LIQUID>(cx, t, e, range, four)
    };
    if WANT {
        add_kinetic::<E, R, WITH_LIQUID>(cx, e, kinetic, pending);
    }
}

/// [`element_remap`] of an element with points: its points' arrays sliced, its nodes' values
/// gathered, the walk over its points ([`element_lanes`]).
#[inline(always)]
pub(super) fn remap_points<E, R, F, const WANT: bool, const WITH_LIQUID: bool>(
    cx: &Remapping<'_, E, R>,
    t: F::Token,
    e: usize,
    range: std::ops::Range<usize>,
    four: &mut [R],
) -> (f64, f64)
where
    E: Element,
    R: Real,
    F: Four<R>,
{
    // The element's points, each array sliced to them once (one length): the loop then indexes
    // without bounds checks.
    let (count, r) = (range.len(), range);
    let (x, mass) = (&cx.x[r.clone()][..count], &cx.mass[r.clone()][..count]);
    let (active, material) = (
        &cx.active[r.clone()][..count],
        &cx.material[r.clone()][..count],
    );
    // SAFETY: the points of element e belong to this thread only.
    let vel = unsafe { &mut cx.vel.range(r.clone())[..count] };
    let corners = cx.mesh.corners[e].as_ref();
    let acc = E::nodes(|k| cx.acc[corners[k] as usize]);
    let acc_w = cx
        .liquid
        .as_ref()
        .filter(|_| WITH_LIQUID)
        .map(|l| E::nodes(|k| l.acc[corners[k] as usize]));
    let liquid = cx
        .liquid
        .as_ref()
        .filter(|_| WITH_LIQUID)
        .map(|l| LiquidPoints {
            // SAFETY: as above.
            w: unsafe { &mut l.w.range(r.clone())[..count] },
            volume: &cx.volume[r.clone()],
            volume0: cx.volume0.map(|v0| &v0[r.clone()]),
            fluids: l.fluids,
        });
    let points = ElementPoints::<E, R> {
        x,
        mass,
        active,
        material,
        vel,
        liquid,
        map: &cx.mesh.map[e],
        first: &cx.mesh.x[corners[0] as usize],
    };
    let pic = match &cx.pic {
        Some(pic) => Some((pic.blend, pic_nodes::<E, R>(pic, corners, cx.acc, cx.dt))),
        None => None,
    };
    let kernel = Kernel::<R, F> {
        t,
        dt: cx.dt,
        body: cx.body,
        acc: acc.as_ref(),
        acc_w: acc_w.as_ref().map(|a| a.as_ref()),
        pic,
    };
    element_lanes::<E, R, F, WANT, WITH_LIQUID>(&kernel, points, four)
}

/// The element's nodes' velocities after the step for the PIC blend ([`Pic::node_velocity`]),
/// zero past its nodes.
fn pic_nodes<E: Element, R: Real>(
    pic: &PicNodes<'_, R>,
    corners: &[u32],
    acc: &[V3<R>],
    dt: R,
) -> NodeVelocities<R> {
    let mut v = [[None; 3]; 4];
    for (vk, &node) in v.iter_mut().zip(corners) {
        let n = node as usize;
        let state = NodeState {
            mass: pic.mass[n],
            momentum: &pic.momentum[n],
            acc: &acc[n],
            fixed: &pic.fixed[n],
        };
        *vk = Pic::node_velocity::<E>(state, dt, pic.empty_below);
    }
    v
}

/// Element `e`'s kinetic sums (solid, liquid) into its block's slot, begun anew at the block's
/// first element where this pass begins them (the second body's pass adds to the slots the
/// first began), the liquid's (`pending`, the block's elements so far) after the block's last
/// element (after the solid's sums of the block).
#[inline(always)]
fn add_kinetic<E: Element, R: Real, const WITH_LIQUID: bool>(
    cx: &Remapping<'_, E, R>,
    e: usize,
    (kinetic, kinetic_w): (f64, f64),
    pending: &mut [f64; ELEMENT_BLOCK],
) {
    let Some((guard, begin, elements)) = &cx.guard else {
        return;
    };
    let b = e / ELEMENT_BLOCK;
    // SAFETY: the scatter hands element e to one thread only, once, in element order, and its
    // pieces hold whole blocks: no other thread touches block b, and its first element comes
    // first.
    let slot = unsafe { &mut guard.range(b..b + 1)[0] };
    if *begin && e % ELEMENT_BLOCK == 0 {
        *slot = GuardSums {
            kinetic,
            ..GuardSums::EMPTY
        };
    } else {
        slot.kinetic += kinetic;
    }
    if WITH_LIQUID {
        pending[e % ELEMENT_BLOCK] = kinetic_w;
        if e % ELEMENT_BLOCK == ELEMENT_BLOCK - 1 || e + 1 == *elements {
            for &k in &pending[..=e % ELEMENT_BLOCK] {
                slot.kinetic += k;
            }
        }
    }
}
