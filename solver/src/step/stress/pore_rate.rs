//! The pore-pressure update of saturated points ([`update_pore_pressure`]): the rate from both
//! phases' volumetric strain rates, point by point, smoothed through the nodes, or from
//! Anura3D's smoothed strains.

use std::ops::Range;

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::four::Four;
use crate::material::liquid::Fluid;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{node_slots, Slots};
use crate::parallel::team::Shared;
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::state::pore_weights::{self, PoreWeights};
use crate::step::batch::{node_lane_shapes, store_nodes, Portable};
use crate::step::passes::Passes;
use crate::step::smoothing::StrainSmoothing;

/// Smoothed pore-pressure rates at the nodes that [`update_pore_pressure`] left for the stress
/// pass to interpolate to the points (Δp = Δt Σ N_k ṗ_k), which visits each point with its
/// shape functions anyway.
#[derive(Clone, Copy)]
pub struct PoreRate<'a, R: Real> {
    /// Per node, the smoothed rate.
    pub nodal: &'a [R],
    /// Per material index, its liquid (dry materials' points keep their pressure).
    pub fluids: &'a [Option<Fluid<R>>],
}

/// What the pore-pressure update reads and writes.
pub struct PorePressure<'a, R: Real> {
    /// The points, their pore pressures updated (or, smoothed, left for the stress pass).
    pub particles: &'a mut Particles<R>,
    /// The nodes' velocities of both phases (read), and the smoothed rates (written).
    pub grid: &'a mut Grid<R>,
    /// Per material index, its liquid.
    pub fluids: &'a [Option<Fluid<R>>],
    /// Whether the rate is smoothed through the nodes.
    pub smooth: bool,
    /// Anura3D's strain smoothing, where the case asks for it.
    pub smoothing: Option<&'a StrainSmoothing<R>>,
    /// The rate's weights particle to grid left this step, where it did.
    pub weights: Option<&'a mut PoreWeights<R>>,
    /// The step.
    pub dt: R,
}

/// Pore-pressure update of saturated points (docs/design.md §4): Δp = (K_w / n) (n Δε_vol,w +
/// (1 - n) Δε_vol,s), the volumetric strain increments from the nodal liquid and solid velocities
/// (compression negative, so compression lowers p). Call before the points move.
///
/// Linear tetrahedra give one volumetric strain per element, and with a stiff liquid
/// (K_w / n ≫ E_oed) the pressure then shows spurious element-to-element (checkerboard) modes
/// that grow near drained faces. The rate is therefore smoothed through the nodes: each point's
/// rate is averaged to its element's nodes (weight V N) and interpolated back with N, as
/// Anura3D's strain smoothing does for the volumetric strain (`smooth`; without it each point
/// takes its element's rate, as Anura3D without `STRAIN_SMOOTHING`). With Anura3D's strain
/// `smoothing` both increments are its smoothed ones instead. Returns whether the smoothed
/// rates wait at the nodes for the stress pass ([`PoreRate`]).
///
/// With `weights` that particle to grid left this step ([`PoreWeights`]), an element whose
/// saturated points share one material adds r_e W_ek and W_ek to its nodes without reading its
/// points (the same W_ek, the rate's products summed once instead of point by point: the
/// bits of before with one point per element); the others go point by point.
pub fn update_pore_pressure<E: Element, R: Real>(
    passes: &Passes<'_, R, E>,
    slots: &mut Slots<R>,
    pp: PorePressure<'_, R>,
) -> bool {
    let PorePressure {
        particles: p,
        grid: g,
        fluids,
        smooth,
        smoothing,
        weights,
        dt,
    } = pp;
    if p.liquid.is_none() || g.liquid.is_none() {
        return false;
    }
    // This step's weights, taken once; a section's rate differs from point to point (its hoop
    // rate), so it always goes point by point.
    let weights = weights
        .filter(|w| w.fresh && w.weights.len() == passes.mesh.elements() && !E::AXISYMMETRIC)
        .map(|w| {
            w.fresh = false;
            &*w
        });
    if let Some(sm) = smoothing {
        smoothed_strains(passes, p, fluids, sm);
        return false;
    }
    if !smooth {
        element_rates(passes, p, g, fluids, dt);
        return false;
    }
    smoothed_rates(passes, slots, p, g, (fluids, weights));
    // The points take their rate in the stress pass ([`PoreRate`]).
    true
}

/// Each saturated point's pore pressure from Anura3D's smoothed strain increments of its
/// element: Δp = (K_w / n) (n Δε_w + (1 - n) Δε_s).
fn smoothed_strains<E: Element, R: Real>(
    passes: &Passes<'_, R, E>,
    p: &mut Particles<R>,
    fluids: &[Option<Fluid<R>>],
    sm: &StrainSmoothing<R>,
) {
    let lp = p.liquid.as_mut().expect("a two-phase case's points");
    let pressure = Shared::new(&mut lp.p);
    let (active, material, element) = (&p.active, &p.material, &p.element);
    let (mesh, layout) = (passes.mesh, passes.layout);
    passes.team.run(|t| {
        for i in layout.particle_range(t) {
            if let (true, Some(f)) = (active[i], &fluids[material[i] as usize]) {
                let [es, ew] = sm.element_mean(mesh, element[i] as usize, material[i]);
                // SAFETY: particle i belongs to this thread only.
                unsafe {
                    pressure.range(i..i + 1)[0] += f.kw_over_n * (f.n * ew + (R::ONE - f.n) * es)
                };
            }
        }
    });
}

/// Each saturated point's pore pressure from its element's rate (and, in an axisymmetric
/// section, its own hoop rates), unsmoothed.
fn element_rates<E: Element, R: Real>(
    passes: &Passes<'_, R, E>,
    p: &mut Particles<R>,
    g: &Grid<R>,
    fluids: &[Option<Fluid<R>>],
    dt: R,
) {
    let gl = g.liquid.as_ref().expect("a two-phase case's nodes");
    let lp = p.liquid.as_mut().expect("a two-phase case's points");
    let pressure = Shared::new(&mut lp.p);
    let (x, active, material, element) = (&p.x, &p.active, &p.material, &p.element);
    let (mesh, layout) = (passes.mesh, passes.layout);
    passes.team.run(|t| {
        for i in layout.particle_range(t) {
            if let (true, Some(f)) = (active[i], &fluids[material[i] as usize]) {
                let e = element[i] as usize;
                let nodal = NodalVelocities::of(mesh, &g.vel, &gl.vel, e);
                let rate = if E::AXISYMMETRIC {
                    let n = mesh.shape(e, &x[i]);
                    nodal.rate(f, |k| n.as_ref()[k], x[i][0])
                } else {
                    nodal.rate(f, |_| R::ZERO, R::ONE)
                };
                // SAFETY: particle i belongs to this thread only.
                unsafe { pressure.range(i..i + 1)[0] += rate * dt };
            }
        }
    });
}

/// The smoothed rates at the nodes, Σ V N r / Σ V N over each node's saturated points, into the
/// liquid's nodal `rate` (0 at a node without them): the elements' sums ([`rate_sums`], each
/// copy with a closure of its own, so that it is inlined into it and compiled with its
/// instruction set, [`crate::parallel::avx2`]), then each node's.
fn smoothed_rates<E: Element, R: Real>(
    passes: &Passes<'_, R, E>,
    slots: &mut Slots<R>,
    p: &Particles<R>,
    g: &mut Grid<R>,
    (fluids, weights): (&[Option<Fluid<R>>], Option<&PoreWeights<R>>),
) {
    let gl = g.liquid.as_mut().expect("a two-phase case's nodes");
    let pass = RatePass {
        mesh: passes.mesh,
        x: &p.x,
        volume: &p.volume,
        active: &p.active,
        material: &p.material,
        fluids,
        vel: &g.vel,
        wvel: &gl.vel,
        weights,
    };
    if use_avx2() {
        scatter_rates::<E, R, R::Four, true>(passes, slots, &pass);
    } else {
        scatter_rates::<E, R, Portable<R>, false>(passes, slots, &pass);
    }
    let (team, layout) = (passes.team, passes.layout);
    let nodal = Shared::new(&mut gl.rate);
    layout.gather::<2, _>(team, slots, |n, s| {
        let r = if s[1] > R::ZERO { s[0] / s[1] } else { R::ZERO };
        // SAFETY: node n is this thread's only.
        unsafe { nodal.write(n, r) };
    });
}

/// The elements' sums of the smoothed rates into the slots, in lanes `F` (with `WIDE`, in the
/// scatter's AVX2 copy).
fn scatter_rates<E: Element, R: Real, F: Four<R>, const WIDE: bool>(
    passes: &Passes<'_, R, E>,
    slots: &mut Slots<R>,
    pass: &RatePass<'_, E, R>,
) {
    let t = F::token().expect("the lanes' instructions, asked for");
    passes.layout.scatter_with::<2, WIDE, true, (), _>(
        passes.team,
        slots,
        |_| (),
        |e, points, two, _| rate_sums::<E, R, F>(pass, t, e, points, two),
    );
}

/// Both phases' velocities at an element's nodes and their divergences in it (one per
/// element for linear elements): what a saturated point's pore-pressure rate needs.
struct NodalVelocities<E: Element, R: Real> {
    /// The solid's nodal velocities.
    vel: E::Nodes<V3<R>>,
    /// The liquid's nodal velocities.
    wvel: E::Nodes<V3<R>>,
    /// ∇·v of the solid and of the liquid.
    div: (R, R),
}

impl<E: Element, R: Real> NodalVelocities<E, R> {
    /// Element `e`'s, from the nodal velocities `vel` (solid) and `wvel` (liquid).
    #[inline(always)]
    fn of(mesh: &Mesh<E, R>, vel: &[V3<R>], wvel: &[V3<R>], e: usize) -> Self {
        let (grad, corners) = (mesh.grad[e].as_ref(), mesh.corners[e].as_ref());
        let vel = E::nodes(|k| vel[corners[k] as usize]);
        let wvel = E::nodes(|k| wvel[corners[k] as usize]);
        let (mut div_v, mut div_w) = (R::ZERO, R::ZERO);
        for k in 0..E::NODES {
            let (v, w) = (vel.as_ref()[k], wvel.as_ref()[k]);
            for a in 0..E::DIM {
                div_v += v[a] * grad[k][a];
                div_w += w[a] * grad[k][a];
            }
        }
        NodalVelocities {
            vel,
            wvel,
            div: (div_v, div_w),
        }
    }

    /// The pore-pressure rate (K_w / n)(n ∇·w + (1 - n) ∇·v) of a point of liquid `f`, plus, in
    /// an axisymmetric section, each phase's hoop rate u_r / r at the point from its shape
    /// values `n` and radius `r` (neither read otherwise).
    #[inline(always)]
    fn rate(&self, f: &Fluid<R>, n: impl Fn(usize) -> R, r: R) -> R {
        let (mut div_v, mut div_w) = self.div;
        if E::AXISYMMETRIC {
            let (vel, wvel) = (self.vel.as_ref(), self.wvel.as_ref());
            for k in 0..E::NODES {
                div_v += n(k) * vel[k][0] / r;
                div_w += n(k) * wvel[k][0] / r;
            }
        }
        f.kw_over_n * (f.n * div_w + (R::ONE - f.n) * div_v)
    }
}

/// What [`rate_sums`] reads: the points, the mesh and both phases' nodal velocities.
struct RatePass<'a, E: Element, R: Real> {
    mesh: &'a Mesh<E, R>,
    x: &'a [V3<R>],
    volume: &'a [R],
    active: &'a [bool],
    material: &'a [u32],
    fluids: &'a [Option<Fluid<R>>],
    vel: &'a [V3<R>],
    wvel: &'a [V3<R>],
    /// The weights particle to grid left this step, where it did.
    weights: Option<&'a PoreWeights<R>>,
}

/// Element `e`'s two sums per node for the smoothed pore-pressure rate: Σ V N r and Σ V N over
/// its saturated active points (r the point's rate), into `two` (2 values per node): from the
/// weights particle to grid left where its saturated points share one material, else point by
/// point ([`rate_lane_sums`], in lanes `F`).
#[inline(always)]
fn rate_sums<E: Element, R: Real, F: Four<R>>(
    cx: &RatePass<'_, E, R>,
    t: F::Token,
    e: usize,
    points: Range<usize>,
    two: &mut [R],
) {
    if points.is_empty() {
        return;
    }
    let weights = cx.weights.map(|w| (w.material[e], &w.weights[e]));
    // No saturated point: nothing to add, and no nodes to read.
    if let Some((pore_weights::NO_POINTS, _)) = weights {
        two.fill(R::ZERO);
        return;
    }
    let nodal = NodalVelocities::of(cx.mesh, cx.vel, cx.wvel, e);
    // Saturated points of one material (`MIXED` names none, and goes point by point below):
    // the element's rate once, none of its points read.
    if let Some((m, w)) = weights {
        if let Some(f) = cx.fluids.get(m as usize).and_then(Option::as_ref) {
            let rate = nodal.rate(f, |_| R::ZERO, R::ONE);
            // (0 + W r: from zero as the point-by-point sum, so that one point gives its bits,
            // the sign of a zero included.)
            for (slot, &wk) in node_slots::<E, R>(two, 2).zip(w) {
                slot[0] = R::ZERO + wk * rate;
                slot[1] = wk;
            }
            return;
        }
    }
    let [s0, s1] = rate_lane_sums::<E, R, F>(t, cx, &nodal, e, points);
    if E::NODES == 4 {
        // The four nodes' slots of two, one after another: node k's (s0, s1) is lanes k.
        let pairs: &mut [R; 8] = two.try_into().expect("a tetrahedron's four slots of two");
        F::store_pairs(s0, s1, pairs);
    } else {
        store_nodes::<E, R, F, 2>(t, &[s0, s1], two, 2, 0);
    }
}

/// [`rate_sums`] point by point, as lanes, one per node: Σ V N r and Σ V N. A tetrahedron's
/// shape values four points at a time, one lane per point, turned into one lane per node for
/// each point by a transpose (each point's own bits, as particle to grid takes them), a
/// triangle's point by point; each point's V N and V N r added point by point in order, from
/// zero.
#[inline(always)]
fn rate_lane_sums<E: Element, R: Real, F: Four<R>>(
    t: F::Token,
    cx: &RatePass<'_, E, R>,
    nodal: &NodalVelocities<E, R>,
    e: usize,
    points: Range<usize>,
) -> [F; 2] {
    let corners = cx.mesh.corners[e].as_ref();
    let (first, map) = (&cx.mesh.x[corners[0] as usize], &cx.mesh.map[e]);
    // The element's points, sliced once: the loop indexes them without bounds checks.
    let x = &cx.x[points.clone()];
    let count = x.len();
    let volume = &cx.volume[points.clone()][..count];
    let (active, material) = (
        &cx.active[points.clone()][..count],
        &cx.material[points][..count],
    );
    let splat = |v: R| F::splat(t, v);
    let (mut s0, mut s1) = (splat(R::ZERO), splat(R::ZERO));
    // The rate of the last material seen (one per material in a linear element, but for a
    // section's hoop rates): formed again only where the material changes, to the same bits.
    let mut last: Option<(u32, F)> = None;
    let mut j = 0;
    while j < count {
        let live = if E::DIM == 3 { (count - j).min(4) } else { 1 };
        let per_point: [F; 4] = if E::DIM == 3 {
            node_lane_shapes::<E, R, F>(t, map, first, x, j, live)
        } else {
            let nl = E::shape_lanes::<R, 1>(map, first, &x[j].map(|c| [c]));
            [F::load(t, &std::array::from_fn(|k| nl[k][0])); 4]
        };
        for (i, &n) in (j..j + live).zip(per_point.iter()) {
            if !active[i] {
                continue;
            }
            let rate = match last {
                Some((m, r)) if m == material[i] && !E::AXISYMMETRIC => r,
                _ => {
                    let Some(f) = &cx.fluids[material[i] as usize] else {
                        continue;
                    };
                    let r = if E::AXISYMMETRIC {
                        let nk = n.to_array();
                        splat(nodal.rate(f, |k| nk[k], x[i][0]))
                    } else {
                        splat(nodal.rate(f, |_| R::ZERO, R::ONE))
                    };
                    last = Some((material[i], r));
                    r
                }
            };
            let vn = splat(volume[i]) * n;
            s0 = s0 + vn * rate;
            s1 = s1 + vn;
        }
        j += live;
    }
    [s0, s1]
}
