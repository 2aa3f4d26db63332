//! Particle to grid: lumped masses, momentum, internal and gravity forces (docs/design.md §4, step 1),
//! summed element by element and then node by node on the team (see [`crate::parallel::gather`]).

use crate::element::mesh::Mesh;
use crate::element::tet4::Tet4;
use crate::element::tri3::Tri3;
use crate::element::Element;
use crate::four::{Four, Lanes4};
use crate::material::liquid::Fluid;
use crate::parallel::avx2::use_avx2;
use crate::parallel::gather::{Layout, Slots};
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::state::pore_weights::{self, PoreWeights};
use crate::step::batch::{
    four_of, lanes, node_lane_shapes, store, store_nodes, usual_count, usual_of, Lanes, LANES,
    TETRAHEDRA,
};
use crate::step::contact::{maps, OneBody};
use crate::step::mixed::Mixed;

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

/// The first `E::DIM` values of `s` from `at` as a 3-vector (z 0 in 2D).
#[inline(always)]
fn vector<E: Element, R: Real>(s: &[R], at: usize) -> V3<R> {
    let mut v = [R::ZERO; 3];
    v[..E::DIM].copy_from_slice(&s[at..at + E::DIM]);
    v
}

/// Component `a` of f = σ ∇N_k (σ symmetric, xx yy zz xy yz zx) for every node k, from the
/// gradients by component (`grad[b][k]` = ∂N_k/∂x_b); in a 2D element (∂N/∂z = 0) the sum runs
/// over the in-plane components only.
#[inline(always)]
fn tractions<E: Element, R: Real>(s: &[R; 6], grad: &[[R; LANES]; 3], a: usize) -> [R; LANES] {
    // Row a of the symmetric σ (xx yy zz xy yz zx).
    const ROWS: [[usize; 3]; 3] = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
    let r = ROWS[a];
    std::array::from_fn(|k| {
        if E::DIM == 2 {
            s[r[0]] * grad[0][k] + s[r[1]] * grad[1][k]
        } else {
            s[r[0]] * grad[0][k] + s[r[1]] * grad[1][k] + s[r[2]] * grad[2][k]
        }
    })
}

/// The element's gradients by component, `[b][k]` = ∂N_k/∂x_b, padded with zeros.
#[inline(always)]
fn gradients_by_component<E: Element, R: Real>(grad: &[V3<R>]) -> [[R; LANES]; 3] {
    std::array::from_fn(|b| lanes::<E, R>(|k| grad[k][b]))
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

/// Maps every active particle to the nodes of its element: mass, momentum, internal force
/// -Σ V (σ' + p I) ∇N and gravity. `gravity[m]` is the acceleration (multiplier applied) that
/// gives the weight of material m's points from their mass.
/// With `pore_weights` (a two-phase case whose pore-pressure rate is smoothed), the liquid's
/// pass also leaves each element's Σ_p V_p N_k over its saturated points and their material
/// for that rate ([`crate::state::pore_weights`]).
/// Under mixed integration the effective-stress force of full elements comes from their Gauss
/// point instead of their points (the element sums are formed here too, over all the element's
/// points). Only the points of `body` are mapped (all for `None`; one body of a contact pair,
/// [`crate::step::contact`]); a full element's Gauss point belongs to the body of its first
/// active point (a full element holds one material).
///
/// With `liquid` (a two-phase case), the same pass over the points also forms the liquid's
/// share (two-phase, docs/design.md §4): liquid masses M_w and M̄_w, drag Q, liquid momentum,
/// the liquid force -Σ V p ∇N + M_w g, and the liquid's weight added to the mixture's external
/// force, from the points of materials with a fluid. Under mixed integration, full elements
/// integrate the pore-pressure force at their Gauss point. One pass for both phases computes
/// each point's shape functions and reads its position once, and each node's values are summed
/// as the two passes summed them. The liquid is mapped with every body (`body` `None`): contact
/// refuses saturated materials.
#[allow(clippy::too_many_arguments)]
pub fn particle_to_grid<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &mut Slots<R>,
    mesh: &Mesh<E, R>,
    p: &Particles<R>,
    gravity: &[V3<R>],
    mixed: Option<&mut Mixed<R>>,
    g: &mut Grid<R>,
    body: Option<OneBody>,
    liquid: Option<LiquidLoads<'_, R>>,
    pore_weights: Option<&mut PoreWeights<R>>,
) {
    let wide = use_avx2();
    let liquid = match (liquid, &p.liquid) {
        (Some(l), Some(lp)) if g.liquid.is_some() => Some((l, lp)),
        _ => None,
    };
    debug_assert!(
        liquid.is_none() || body.is_none(),
        "the liquid mapped with one body of a contact pair"
    );
    // Values per node: the solid's, then the liquid's when there is one.
    let (sw, lw) = (solid_width::<E>(), liquid_width::<E>());
    let stride = |with_liquid: bool| if with_liquid { sw + lw } else { sw };
    let mixed_sums = mixed.map(|m| {
        let filling = R::of(m.filling);
        (
            Shared::new(&mut m.stress),
            Shared::new(&mut m.full),
            filling,
            Shared::new(&mut m.pressure),
            (m.rule, &m.boundary[..]),
        )
    });
    // What each element's pass reads ([`element_sums`]): the dry variant compiles without the
    // liquid's code, and each variant is a closure of its own with one caller, which the
    // compiler inlines into its scatter (one closure called from two variants was left a call,
    // at 6 % more instructions per point-step).
    // The rate's weights come with the liquid's pass only.
    let pore_weights = pore_weights.filter(|_| liquid.is_some()).map(|w| {
        w.fit(mesh.elements());
        w.fresh = true;
        (Shared::new(&mut w.weights), Shared::new(&mut w.material))
    });
    let pass = Pass {
        mesh,
        p,
        gravity,
        mixed: mixed_sums,
        pore_weights,
        liquid,
        body,
        arrays: PointArrays::new(p, liquid.is_some()),
        stride: stride(liquid.is_some()),
        four: if wide || cfg!(target_feature = "avx2") {
            R::Four::token()
        } else {
            None
        },
    };
    let mass = Shared::new(&mut g.mass);
    let momentum = Shared::new(&mut g.momentum);
    let f_int = Shared::new(&mut g.f_int);
    let f_ext = Shared::new(&mut g.f_ext);
    let liquid_nodes = g.liquid.as_mut().filter(|_| liquid.is_some()).map(|gl| {
        (
            Shared::new(&mut gl.mass),
            Shared::new(&mut gl.mass_n),
            Shared::new(&mut gl.drag),
            Shared::new(&mut gl.momentum),
            Shared::new(&mut gl.force),
        )
    });
    let node = |n: usize, s: &[R]| {
        let mut fe = vector::<E, R>(s, 1 + 2 * E::DIM);
        // SAFETY: node n is this thread's only.
        unsafe {
            mass.write(n, s[0]);
            momentum.write(n, vector::<E, R>(s, 1));
            f_int.write(n, vector::<E, R>(s, 1 + E::DIM));
            if let Some((mass, mass_n, drag, momentum, force)) = &liquid_nodes {
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
            f_ext.write(n, fe);
        }
    };
    // The pass as wide as the element's dimension and the phases need: 7 or 10 values for the
    // solid in 2D or 3D, 7 + 9 or 10 + 12 with the liquid.
    const {
        assert!(solid_width::<Tri3>() == 7 && solid_width::<Tet4>() == 10);
        assert!(liquid_width::<Tri3>() == 9 && liquid_width::<Tet4>() == 12);
    };
    // Triangles (7 and 16 values) take their points one by one, tetrahedra in batches; each
    // in the baseline instruction set or, where the processor has them and the build does not
    // assume them, with AVX2's 256-bit registers (four f64 node lanes in one; the same bits).
    macro_rules! pass {
        ($width:literal, $liquid:literal, $points:expr) => {
            if wide {
                layout.sum_to_nodes::<$width, true, _, _>(
                    team,
                    slots,
                    |e, points, four| {
                        element_sums::<E, R, $liquid, { $points }, true>(&pass, e, points, four)
                    },
                    node,
                )
            } else {
                layout.sum_to_nodes::<$width, false, _, _>(
                    team,
                    slots,
                    |e, points, four| {
                        element_sums::<E, R, $liquid, { $points }, false>(&pass, e, points, four)
                    },
                    node,
                )
            }
        };
    }
    match (pass.stride, liquid.is_some()) {
        (7, false) => pass!(7, false, 1),
        (10, false) => pass!(10, false, TETRAHEDRA),
        (16, true) => pass!(16, true, 1),
        (22, true) => pass!(22, true, TETRAHEDRA),
        (w, _) => unreachable!("a pass {w} values wide"),
    }
}

/// The per-point arrays particle to grid reads, all of one length (checked once, when they are
/// taken), so that an element's points are sliced out of every one of them with one check of
/// their range ([`PointArrays::element`]) rather than one per array: per element, those checks
/// were about a tenth of a triangle's instructions in this pass.
#[derive(Clone, Copy)]
struct PointArrays<'a, R: Real> {
    len: usize,
    active: &'a [bool],
    material: &'a [u32],
    x: &'a [V3<R>],
    mass: &'a [R],
    vel: &'a [V3<R>],
    volume: &'a [R],
    stress: &'a [[R; 6]],
    pore: Option<&'a [R]>,
    w: Option<&'a [V3<R>]>,
    volume0: Option<&'a [R]>,
}

impl<'a, R: Real> PointArrays<'a, R> {
    /// The arrays of `p` (its liquid's with `liquid`).
    ///
    /// # Panics
    /// If they are not all of one length (a [`Particles`] whose arrays were resized apart).
    fn new(p: &'a Particles<R>, liquid: bool) -> Self {
        let len = p.x.len();
        let lp = p.liquid.as_ref();
        let a = PointArrays {
            len,
            active: &p.active,
            material: &p.material,
            x: &p.x,
            mass: &p.mass,
            vel: &p.v,
            volume: &p.volume,
            stress: &p.stress,
            pore: lp.map(|l| &l.p[..]),
            w: lp.filter(|_| liquid).map(|l| &l.w[..]),
            volume0: lp.filter(|_| liquid).and_then(|l| l.volume0.as_deref()),
        };
        let lens = [
            a.active.len(),
            a.material.len(),
            a.mass.len(),
            a.vel.len(),
            a.volume.len(),
            a.stress.len(),
            a.pore.map_or(len, <[R]>::len),
            a.w.map_or(len, <[V3<R>]>::len),
            a.volume0.map_or(len, <[R]>::len),
        ];
        assert!(
            lens.iter().all(|&l| l == len),
            "particle arrays of different lengths"
        );
        a
    }

    /// Every array cut to the first `len` values (all of them: a no-op on the values), by
    /// slicing the compiler sees, so that the loops over an element's points index without
    /// bounds checks.
    #[inline(always)]
    fn cut(&self) -> Self {
        let n = self.len;
        PointArrays {
            len: n,
            active: &self.active[..n],
            material: &self.material[..n],
            x: &self.x[..n],
            mass: &self.mass[..n],
            vel: &self.vel[..n],
            volume: &self.volume[..n],
            stress: &self.stress[..n],
            pore: self.pore.map(|a| &a[..n]),
            w: self.w.map(|a| &a[..n]),
            volume0: self.volume0.map(|a| &a[..n]),
        }
    }

    /// The points `r` of every array (arrays of `r`'s length).
    ///
    /// # Panics
    /// If `r` is not a range within the arrays (one check for all of them).
    #[inline(always)]
    fn element(&self, r: std::ops::Range<usize>) -> Self {
        assert!(
            r.start <= r.end && r.end <= self.len,
            "points past the arrays"
        );
        /// `a[r]`.
        #[inline(always)]
        fn sub<T>(a: &[T], r: std::ops::Range<usize>) -> &[T] {
            debug_assert!(r.start <= r.end && r.end <= a.len());
            // SAFETY: every array is `len` long (checked in `new`, and the fields are this
            // type's own), and `r` lies within `len` (checked above).
            unsafe { a.get_unchecked(r) }
        }
        PointArrays {
            len: r.len(),
            active: sub(self.active, r.clone()),
            material: sub(self.material, r.clone()),
            x: sub(self.x, r.clone()),
            mass: sub(self.mass, r.clone()),
            vel: sub(self.vel, r.clone()),
            volume: sub(self.volume, r.clone()),
            stress: sub(self.stress, r.clone()),
            pore: self.pore.map(|a| sub(a, r.clone())),
            w: self.w.map(|a| sub(a, r.clone())),
            volume0: self.volume0.map(|a| sub(a, r.clone())),
        }
    }
}

/// The mixed rule's per-element outputs and inputs: mean stresses, full flags, the filling
/// degree, mean pore pressures, and the rule with its boundary points.
type MixedSums<'a, R> = (
    Shared<'a, [R; 6]>,
    Shared<'a, bool>,
    R,
    Shared<'a, R>,
    (crate::input::case::MixedRule, &'a [bool]),
);

/// What one element's pass reads (and, through the mixed rule's slices, writes).
struct Pass<'a, E: Element, R: Real> {
    mesh: &'a Mesh<E, R>,
    p: &'a Particles<R>,
    gravity: &'a [V3<R>],
    mixed: Option<MixedSums<'a, R>>,
    /// Where the liquid's pass leaves each element's weights of the pore-pressure rate, and
    /// the material of its saturated points.
    pore_weights: Option<(Shared<'a, [R; 4]>, Shared<'a, u32>)>,
    liquid: Option<(
        LiquidLoads<'a, R>,
        &'a crate::state::particles::LiquidPoints<R>,
    )>,
    body: Option<OneBody>,
    /// The points' arrays, of one length.
    arrays: PointArrays<'a, R>,
    /// Values per node of the pass.
    stride: usize,
    /// Where the pass runs its AVX2 copy: the token of [`Real::Four`]'s instructions.
    four: Option<<R::Four as Four<R>>::Token>,
}

/// Element `e`'s sums into `four` ([`particle_to_grid`]): the solid's, and the liquid's with
/// `WITH_LIQUID` (the dry variant compiles without the liquid's code); its points' shape values
/// in batches of `W`.
#[inline(always)]
fn element_sums<E: Element, R: Real, const WITH_LIQUID: bool, const W: usize, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    e: usize,
    range: std::ops::Range<usize>,
    four: &mut [R],
) {
    let count = range.len();
    // An element without points: its buffer holds zeros already, which the sums would store
    // ([`Layout::scatter`]), and under mixed integration its outputs are those of no points
    // (not full, zero means), so it returns before reading the element (most of a void mesh's
    // elements take this path at every step). (The test is of an opaque copy of the count:
    // the loops below, compiled knowing the count is not zero, took more instructions per
    // point.)
    // (The scatter checks in debug builds that the buffer stays zero.)
    if std::hint::black_box(count) == 0 {
        if let Some((weights, material)) = &cx.pore_weights {
            // SAFETY: element e is this thread's only.
            unsafe {
                weights.write(e, [R::ZERO; 4]);
                material.write(e, pore_weights::NO_POINTS);
            }
        }
        if let Some((stress, flags, _, pressure, _)) = &cx.mixed {
            // SAFETY: element e is this thread's only.
            unsafe {
                stress.write(e, [R::ZERO; 6]);
                flags.write(e, false);
                pressure.write(e, R::ZERO);
            }
        }
        return;
    }
    let grad = cx.mesh.grad[e].as_ref();
    let by_component = gradients_by_component::<E, R>(grad);
    // The element's sums, value by value across its nodes (stored into `four` at the end).
    let mut sums: Lanes<R, 10> = [[R::ZERO; LANES]; 10];
    const { assert!(solid_width::<Tet4>() <= 10) };
    // The liquid's, likewise.
    let mut wet: Lanes<R, 12> = [[R::ZERO; LANES]; 12];
    const { assert!(liquid_width::<Tet4>() <= 12) };
    // Mixed integration: is the element full, and its mean stress.
    let mut full = false;
    if let Some((stress, flags, filling, pressure, (rule, boundary))) = &cx.mixed {
        let (mut v, mut s, mut pm) = (R::ZERO, [R::ZERO; 6], R::ZERO);
        for i in range.clone() {
            if cx.p.active[i] {
                v += cx.p.volume[i];
                for c in 0..6 {
                    s[c] += cx.p.volume[i] * cx.p.stress[i][c];
                }
                if let Some(l) = &cx.p.liquid {
                    pm += cx.p.volume[i] * l.p[i];
                }
            }
        }
        full = crate::step::mixed::is_full(
            *rule,
            boundary,
            *filling,
            cx.p,
            range.clone(),
            v,
            cx.mesh.volume[e],
        );
        if full {
            for c in s.iter_mut() {
                *c /= v;
            }
            pm /= v;
        }
        // SAFETY: element e is this thread's only.
        unsafe {
            stress.write(e, s);
            flags.write(e, full);
            pressure.write(e, pm);
        }
        let ours = range
            .clone()
            .find(|&i| cx.p.active[i])
            .is_some_and(|i| maps(cx.body, cx.p.material[i]));
        if full && ours {
            let ve = cx.mesh.volume[e];
            // The Gauss point's total stress: effective plus pore pressure.
            let mut s = s;
            if cx.p.liquid.is_some() {
                for c in s.iter_mut().take(3) {
                    *c += pm;
                }
            }
            for a in 0..E::DIM {
                let f = tractions::<E, R>(&s, &by_component, a);
                for k in 0..LANES {
                    sums[1 + E::DIM + a][k] -= ve * f[k];
                }
            }
        }
        // A full element takes its pore-pressure force at the Gauss point too (its volume
        // times the mean pore pressure).
        if full && WITH_LIQUID {
            let vp = cx.mesh.volume[e] * pm;
            for k in 0..E::NODES {
                for a in 0..E::DIM {
                    wet[3 + E::DIM + a][k] -= vp * grad[k][a];
                }
            }
        }
    }
    // The element's points, every array sliced to them once (one length, one check), so that
    // the loop indexes without bounds checks.
    let arrays = cx.arrays.element(range.clone());
    let PointArrays {
        active,
        material,
        x,
        mass,
        vel,
        volume,
        stress,
        pore,
        w,
        volume0,
        ..
    } = arrays;
    let liquid_points = cx
        .liquid
        .filter(|_| WITH_LIQUID)
        .and_then(|(loads, _)| w.map(|w| (loads, w, volume0)));
    // The element's shape values in batches of `W` points, each held across the
    // batch (the same bits as point by point); each point's sums then follow in
    // point order.
    let corners = cx.mesh.corners[e].as_ref();
    let (first, map) = (&cx.mesh.x[corners[0] as usize], &cx.mesh.map[e]);
    // The points of the element's first point's material take their weight as g Σ m N_k,
    // formed once ([`Totals`]); any other's, point by point with its own g.
    let lead = material[0];
    // The AVX2 copy, or a build for AVX2: each point's sums as explicit four-lane
    // vectors, one lane per node ([`crate::four`]): the same operations in the same
    // order as the loop below, so the same bits, without the shuffles and stack traffic the
    // compiler made of that loop (docs/design.md §9).
    if let Some(t) = cx.four.filter(|_| WIDE || cfg!(target_feature = "avx2")) {
        let points = Points {
            arrays,
            liquid: liquid_points,
            map,
            first,
        };
        debug_assert!(crate::parallel::avx2::present());
        // SAFETY: `WIDE` only in the scatter's AVX2 copy, which asserts that the processor
        // has AVX2; a build that assumes AVX2 (x86-64-v3) runs only where it has it.
        let rate = unsafe {
            node_lane_sums_avx2::<E, R, WITH_LIQUID>(
                t,
                cx,
                &points,
                (full, lead),
                &by_component,
                (&sums, &wet),
                four,
            )
        };
        // The sums went into the buffer straight from their vectors.
        leave_pore_weights(cx, e, rate);
        return;
    } else {
        let mut j = 0;
        // (Not `Batch`, which the stress and grid-to-particle passes share: the batch
        // here takes every point and skips inside, measured 15 % faster on the
        // saturated f64 column's particle to grid.)
        let mut totals = Totals::<R, Lanes4<R>>::new((), lead);
        while j < count {
            let batch = (count - j).min(W);
            // Lanes past the element's last point repeat it (computed, never used).
            let xl: [[R; W]; 3] =
                std::array::from_fn(|a| std::array::from_fn(|q| x[j + q.min(batch - 1)][a]));
            let nl = E::shape_lanes(map, first, &xl);
            for i in j..j + batch {
                if !active[i] || !maps(cx.body, material[i]) {
                    continue;
                }
                let nq: [R; 4] = std::array::from_fn(|k| nl[k][i - j]);
                let n = &nq[..E::NODES];
                let (m, v) = (mass[i], vel[i]);
                let gravity = &cx.gravity[material[i] as usize];
                let s = volume_stress(full, volume[i], &stress[i], pore.map(|p| p[i]));
                totals.add_stress(&s);
                // An axisymmetric section's hoop stress pulls each node towards the axis:
                // f_r -= V σ_θθ N / r (x the radius; V per radian).
                let hoop = if E::AXISYMMETRIC {
                    s[2] / x[i][0]
                } else {
                    R::ZERO
                };
                // Node by node the same operations as m N_k (v, g) node after node.
                let w = lanes::<E, R>(|k| m * n[k]);
                for k in 0..LANES {
                    sums[0][k] += w[k];
                }
                for a in 0..E::DIM {
                    for k in 0..LANES {
                        sums[1 + a][k] += w[k] * v[a];
                    }
                }
                if material[i] == lead {
                    totals.lead_mass = totals.lead_mass + Lanes4::load((), &w);
                } else {
                    for a in 0..E::DIM {
                        for k in 0..LANES {
                            sums[1 + 2 * E::DIM + a][k] += w[k] * gravity[a];
                        }
                    }
                }
                if E::AXISYMMETRIC {
                    let nk = lanes::<E, R>(|k| n[k]);
                    for k in 0..LANES {
                        sums[1 + E::DIM][k] -= hoop * nk[k];
                    }
                }
                if !WITH_LIQUID {
                    continue;
                }
                let Some((loads, w_all, volume0)) = liquid_points else {
                    continue;
                };
                let (Some(f), Some(pore)) = (loads.fluids[material[i] as usize], pore) else {
                    continue;
                };
                let (vw, mw, pw) = liquid_volume_mass_pressure(
                    &f,
                    full,
                    volume[i],
                    volume0.map(|v0| v0[i]),
                    pore[i],
                );
                let w = w_all[i];
                totals.pore += pw;
                if cx.pore_weights.is_some() {
                    let vn = lanes::<E, R>(|k| volume[i] * n[k]);
                    totals.add_saturated(Lanes4::load((), &vn), material[i]);
                }
                // The pore pressure's hoop force, as the solid's (axisymmetric sections).
                let hoop = if E::AXISYMMETRIC {
                    pw / x[i][0]
                } else {
                    R::ZERO
                };
                // Node by node the same operations as a loop over the nodes.
                let nk = lanes::<E, R>(|k| n[k]);
                let (mn, nmw) = (
                    lanes::<E, R>(|k| mw * n[k]),
                    lanes::<E, R>(|k| f.n * mw * n[k]),
                );
                for k in 0..LANES {
                    wet[0][k] += mn[k];
                    wet[1][k] += nmw[k];
                    wet[2][k] += f.drag * vw * nk[k];
                }
                for a in 0..E::DIM {
                    for k in 0..LANES {
                        wet[3 + a][k] += mn[k] * w[a];
                    }
                }
                if E::AXISYMMETRIC {
                    for k in 0..LANES {
                        wet[3 + E::DIM][k] -= hoop * nk[k];
                    }
                }
            }
            j += batch;
        }
        // The element's totals into its node lanes, as the four-lane path forms them (plain
        // lanes: the same operations, lane by lane).
        let liquid_gravity = liquid_points.map(|(loads, _, _)| loads.gravity);
        let g = by_component.map(|b| Lanes4::load((), &b));
        let mut s4 = sums.map(|c| Lanes4::load((), &c));
        let mut w4 = wet.map(|c| Lanes4::load((), &c));
        let gravity = (cx.gravity[lead as usize], liquid_gravity);
        totals.close::<E, WITH_LIQUID>((), &g, gravity, &mut s4, &mut w4);
        sums = s4.map(Lanes4::to_array);
        wet = w4.map(Lanes4::to_array);
        leave_pore_weights(cx, e, (totals.volume_n.to_array(), totals.saturated));
    }
    store::<E, R, 10>(&sums, four, cx.stride, 0, solid_width::<E>());
    if WITH_LIQUID {
        store::<E, R, 12>(
            &wet,
            four,
            cx.stride,
            solid_width::<E>(),
            liquid_width::<E>(),
        );
    }
}

/// What an element's points add up beside their node lanes, for the terms whose node factor is
/// the same at every point. A linear element's ∇N_k is one per element, so the internal force
/// -Σ_p V_p (σ'_p + p_p I) ∇N_k is -(Σ_p V_p (σ'_p + p_p I)) ∇N_k, and the liquid's pressure
/// force -Σ_p V_p p_p ∇N_k is -(Σ_p V_p p_p) ∇N_k; the weight Σ_p m_p N_k g of the points of
/// one material is g Σ_p m_p N_k (the liquid's weight likewise, from the liquid mass sum).
/// Each is then formed once per element rather than once per point (docs/design.md §9): the
/// sums are taken in another order than point by point, so the bits differ from that order's,
/// not the value (and not at all with one point per element).
/// `F`: the node lanes' type (four-lane vectors, or plain lanes where the pass runs without
/// them: the same operations).
struct Totals<R, F> {
    /// Σ V (σ' + p I) over the points that take part (0 for a full element's points under
    /// mixed integration), in point order.
    stress: [R; 6],
    /// Σ V p over the saturated points, in point order.
    pore: R,
    /// The material whose points' weight is formed from their mass sum: the element's first
    /// point's (all of them, nearly always); the others' weight is added point by point.
    lead: u32,
    /// Σ m N_k over the points of `lead` that take part, one lane per node, in point order.
    lead_mass: F,
    /// Σ V N_k over the saturated points, one lane per node, in point order (formed where
    /// the pore-pressure rate's weights are wanted: [`crate::state::pore_weights`]).
    volume_n: F,
    /// The material of the saturated points added to `volume_n`
    /// ([`pore_weights::with_point`]).
    saturated: u32,
}

impl<R: Real, F: Four<R>> Totals<R, F> {
    fn new(t: F::Token, lead: u32) -> Self {
        Totals {
            stress: [R::ZERO; 6],
            pore: R::ZERO,
            lead,
            lead_mass: F::splat(t, R::ZERO),
            volume_n: F::splat(t, R::ZERO),
            saturated: pore_weights::NO_POINTS,
        }
    }

    /// Adds a saturated point's V N_k (`vn`, one lane per node) of `material`.
    #[inline(always)]
    fn add_saturated(&mut self, vn: F, material: u32) {
        self.volume_n = self.volume_n + vn;
        self.saturated = pore_weights::with_point(self.saturated, material);
    }

    /// Adds a point's V (σ' + p I).
    #[inline(always)]
    fn add_stress(&mut self, s: &[R; 6]) {
        for (t, v) in self.stress.iter_mut().zip(s) {
            *t += *v;
        }
    }

    /// Adds the totals' terms to the element's node lanes (`g[b]`: ∂N_k/∂x_b by node), once
    /// every point has added its own: the internal force; the weight of `lead`'s points
    /// (`gravity` that material's); with `WITH_LIQUID` and the liquid's gravity, the liquid
    /// force (its weight from the liquid mass sum `w4[0]`, less the pressure's) and the
    /// liquid's weight on the mixture (from `w4[1]`).
    #[inline(always)]
    fn close<E: Element, const WITH_LIQUID: bool>(
        &self,
        t: F::Token,
        g: &[F; 3],
        (gravity, liquid_gravity): (V3<R>, Option<V3<R>>),
        s4: &mut [F; 10],
        w4: &mut [F; 12],
    ) {
        let splat = |v: R| F::splat(t, v);
        // Row a of the symmetric σ (xx yy zz xy yz zx), as [`tractions`] sums it (the
        // in-plane components only in 2D).
        const ROWS: [[usize; 3]; 3] = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
        let s = &self.stress;
        for a in 0..E::DIM {
            let r = ROWS[a];
            let f = if E::DIM == 2 {
                splat(s[r[0]]) * g[0] + splat(s[r[1]]) * g[1]
            } else {
                splat(s[r[0]]) * g[0] + splat(s[r[1]]) * g[1] + splat(s[r[2]]) * g[2]
            };
            s4[1 + E::DIM + a] = s4[1 + E::DIM + a] - f;
            s4[1 + 2 * E::DIM + a] = s4[1 + 2 * E::DIM + a] + self.lead_mass * splat(gravity[a]);
        }
        let Some(lg) = liquid_gravity.filter(|_| WITH_LIQUID) else {
            return;
        };
        for a in 0..E::DIM {
            let force = w4[0] * splat(lg[a]) - splat(self.pore) * g[a];
            w4[3 + E::DIM + a] = w4[3 + E::DIM + a] + force;
            w4[3 + 2 * E::DIM + a] = w4[3 + 2 * E::DIM + a] + w4[1] * splat(lg[a]);
        }
    }
}

/// A point's volume times its total stress, V (σ' + p I) (`pore` its pore pressure p, where the
/// case has one), as particle to grid's internal force takes it: 0 for the point of a full
/// element under mixed integration, whose element's Gauss point takes its force.
#[inline(always)]
fn volume_stress<R: Real>(full: bool, volume: R, stress: &[R; 6], pore: Option<R>) -> [R; 6] {
    let vol = if full { R::ZERO } else { volume };
    let mut s = stress.map(|c| vol * c);
    if let Some(p) = pore {
        let vp = vol * p;
        s[0] += vp;
        s[1] += vp;
        s[2] += vp;
    }
    s
}

/// A saturated point's liquid volume, liquid mass and V p (0 for a full element's point under
/// mixed integration) for particle to grid. The liquid's mass, weight and drag are taken on the
/// initial volume `volume0` where the case holds the liquid mass fixed.
#[inline(always)]
fn liquid_volume_mass_pressure<R: Real>(
    f: &Fluid<R>,
    full: bool,
    volume: R,
    volume0: Option<R>,
    pore: R,
) -> (R, R, R) {
    let vw = volume0.unwrap_or(volume);
    let pw = if full { R::ZERO } else { pore * volume };
    (vw, f.rho_w * vw, pw)
}

/// The liquid's loads, and an element's points' liquid velocities and (where the liquid mass is
/// held fixed) initial volumes.
type LiquidSlices<'a, R> = (LiquidLoads<'a, R>, &'a [V3<R>], Option<&'a [R]>);

/// An element's points ([`PointArrays::element`]), and what [`node_lane_sums`] reads beside
/// them: in the liquid's pass the liquid's loads with the points' liquid arrays (one value, so
/// that a point asks once whether there is a liquid), and the element's map and first corner.
struct Points<'a, E: Element, R: Real> {
    arrays: PointArrays<'a, R>,
    liquid: Option<LiquidSlices<'a, R>>,
    map: &'a E::Map<R>,
    first: &'a V3<R>,
}

/// [`node_lane_sums`] compiled with AVX2, where the four-lane operations are single
/// instructions (a function of its own: inlined into the scatter's element closure, the
/// saturated pass's closure grew too large for the compiler to inline into its AVX2 copy).
///
/// # Safety
/// On x86-64 the processor must have AVX2 ([`crate::parallel::avx2::present`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
#[allow(clippy::too_many_arguments)]
unsafe fn node_lane_sums_avx2<E: Element, R: Real, const WITH_LIQUID: bool>(
    t: <R::Four as Four<R>>::Token,
    cx: &Pass<'_, E, R>,
    points: &Points<'_, E, R>,
    element: (bool, u32),
    by_component: &[[R; LANES]; 3],
    sums: (&Lanes<R, 10>, &Lanes<R, 12>),
    four: &mut [R],
) -> ([R; 4], u32) {
    node_lane_sums::<E, R, WITH_LIQUID>(t, cx, points, element, by_component, sums, four)
}

/// An element's sums over its points ([`element_sums`]), from `sums` (the solid's) and, with
/// `WITH_LIQUID`, `wet` (the liquid's; both zero, or a full element's Gauss-point terms under
/// mixed integration): each point's contribution as four-lane vectors, one lane per node (a
/// triangle's fourth lane carries zeros and is never stored), with the operations of the point
/// loop of [`element_sums`] in its order (the same bits). `element`: whether the element is
/// full (mixed integration), and the material whose points' weight is formed once
/// ([`Totals`]). The sums are stored from their vectors into the scatter's buffer `four`
/// ([`store_nodes`]). Returns the saturated points' Σ V N_k and their material (formed where
/// the pass leaves the pore-pressure rate's weights, [`leave_pore_weights`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn node_lane_sums<E: Element, R: Real, const WITH_LIQUID: bool>(
    t: <R::Four as Four<R>>::Token,
    cx: &Pass<'_, E, R>,
    points: &Points<'_, E, R>,
    (full, lead): (bool, u32),
    by_component: &[[R; LANES]; 3],
    (sums, wet): (&Lanes<R, 10>, &Lanes<R, 12>),
    four: &mut [R],
) -> ([R; 4], u32) {
    let (map, first) = (points.map, points.first);
    // Every array cut to the element's points again (one length, `count`), so that
    // `point_sums` indexes them without bounds checks.
    let arrays = points.arrays.cut();
    let count = arrays.len;
    let points = &Points {
        arrays,
        liquid: points
            .liquid
            .map(|(l, w, v0)| (l, &w[..count], v0.map(|v| &v[..count]))),
        ..*points
    };
    let x = points.arrays.x;
    let g: [R::Four; 3] = std::array::from_fn(|b| R::Four::load(t, &by_component[b]));
    let mut s4: [R::Four; 10] = std::array::from_fn(|c| R::Four::load(t, &sums[c]));
    let mut w4: [R::Four; 12] = std::array::from_fn(|c| R::Four::load(t, &wet[c]));
    let mut totals = Totals::<R, R::Four>::new(t, lead);
    // Whether points of the lead material took part through the paths that skip each point's
    // checks (`OF_LEAD`), whose material the totals then take once, below.
    let mut lead_took_part = false;
    // A triangle's shape values point by point (in four lanes and transposed, as below, the
    // 2D dry column ran 30 instructions per particle-step more).
    if E::DIM == 2 {
        let shape = |xi: &V3<R>| {
            let nl = E::shape_lanes::<R, 1>(map, first, &xi.map(|c| [c]));
            R::Four::load(t, &std::array::from_fn(|k| nl[k][0]))
        };
        // A triangle of exactly its usual three points, all taking part and of the lead
        // material (the common case), by a loop of a constant count, which the compiler
        // unrolls: as the tetrahedra's below, the element's values are not hoisted and spilled.
        if usual_of::<E>(points.arrays.active, points.arrays.material, 0, count, lead)
            && maps(cx.body, lead)
        {
            lead_took_part = true;
            for i in 0..usual_count::<E>() {
                let (s, w, sum) = (&mut s4, &mut w4, &mut totals);
                let n = shape(&x[i]);
                point_sums::<E, R, WITH_LIQUID, true>(t, cx, points, i, n, full, s, w, sum);
            }
        } else {
            for (i, xi) in x.iter().enumerate() {
                if !points.arrays.active[i] || !maps(cx.body, points.arrays.material[i]) {
                    continue;
                }
                let (s, w, sum) = (&mut s4, &mut w4, &mut totals);
                point_sums::<E, R, WITH_LIQUID, false>(
                    t,
                    cx,
                    points,
                    i,
                    shape(xi),
                    full,
                    s,
                    w,
                    sum,
                );
            }
        }
    }
    // A tetrahedron's four points' shape values at a time, one lane per point, turned into one
    // lane per node for each point by a transpose (the same bits as each point's own: the 3D
    // dry column 13 instructions per particle-step fewer than point by point).
    let mut j = if E::DIM == 2 { count } else { 0 };
    // A tetrahedron of exactly its usual four points, all taking part and of the lead
    // material (the common case), outside the batch loop: the map's values go into lanes
    // where they are used, not hoisted out of the loop into lanes and spilled.
    if E::DIM == 3
        && usual_of::<E>(points.arrays.active, points.arrays.material, 0, count, lead)
        && maps(cx.body, lead)
    {
        debug_assert_eq!(count, 4, "a tetrahedron's usual count");
        lead_took_part = true;
        let per_point = node_lane_shapes::<E, R>(t, map, first, x, 0, 4);
        for (i, &n) in per_point.iter().enumerate() {
            let (s, w, sum) = (&mut s4, &mut w4, &mut totals);
            point_sums::<E, R, WITH_LIQUID, true>(t, cx, points, i, n, full, s, w, sum);
        }
        j = count;
    }
    while j < count {
        let live = (count - j).min(4);
        let per_point = node_lane_shapes::<E, R>(t, map, first, x, j, live);
        // Four points that all take part, of the lead material (the common case), skip each
        // point's checks.
        let of_lead = live == 4
            && four_of(points.arrays.active, points.arrays.material, j, lead)
            && maps(cx.body, lead);
        if of_lead {
            lead_took_part = true;
            for (i, &n) in (j..j + 4).zip(per_point.iter()) {
                let (s, w, sum) = (&mut s4, &mut w4, &mut totals);
                point_sums::<E, R, WITH_LIQUID, true>(t, cx, points, i, n, full, s, w, sum);
            }
        } else {
            for (i, &n) in (j..j + live).zip(per_point.iter()) {
                let (s, w, sum) = (&mut s4, &mut w4, &mut totals);
                point_sums::<E, R, WITH_LIQUID, false>(t, cx, points, i, n, full, s, w, sum);
            }
        }
        j += live;
    }
    let liquid_gravity = points.liquid.map(|(loads, _, _)| loads.gravity);
    let gravity = (cx.gravity[lead as usize], liquid_gravity);
    totals.close::<E, WITH_LIQUID>(t, &g, gravity, &mut s4, &mut w4);
    // The pass's values per node as a constant of the element and phases (the pass's
    // `stride`, a field read at run time, is the same), so that the stores index by
    // constants; `store_nodes` checks it against the buffer.
    let (sw, lw) = (solid_width::<E>(), liquid_width::<E>());
    let width = if WITH_LIQUID { sw + lw } else { sw };
    if E::NODES == 4 {
        const { assert!(solid_width::<Tet4>() == 10 && liquid_width::<Tet4>() == 12) };
        store_nodes::<E, R, 10>(t, &s4, four, width, 0);
        if WITH_LIQUID {
            store_nodes::<E, R, 12>(t, &w4, four, width, 10);
        }
    } else {
        const { assert!(solid_width::<Tri3>() == 7 && liquid_width::<Tri3>() == 9) };
        let (solid, liquid) = (&s4[..7], &w4[..9]);
        store_nodes::<E, R, 7>(t, solid.try_into().expect("seven"), four, width, 0);
        if WITH_LIQUID {
            store_nodes::<E, R, 9>(t, liquid.try_into().expect("nine"), four, width, 7);
        }
    }
    let saturated = match points.liquid {
        Some((loads, _, _)) if lead_took_part && loads.fluids[lead as usize].is_some() => {
            pore_weights::with_point(totals.saturated, lead)
        }
        _ => totals.saturated,
    };
    (totals.volume_n.to_array(), saturated)
}

/// Leaves element `e`'s weights of the pore-pressure rate, `(Σ V N_k, material)` of its
/// saturated points, where the pass was asked for them.
#[inline(always)]
fn leave_pore_weights<E: Element, R: Real>(cx: &Pass<'_, E, R>, e: usize, rate: ([R; 4], u32)) {
    if let Some((weights, material)) = &cx.pore_weights {
        // SAFETY: element e is this thread's only.
        unsafe {
            weights.write(e, rate.0);
            material.write(e, rate.1);
        }
    }
}

/// Point `i`'s contributions to its element's sums ([`node_lane_sums`]), its shape values `n`
/// one lane per node, if it takes part: into the node lanes, and into the element's totals the
/// terms it takes once for all its points ([`Totals`]). `full`: whether the element is full
/// (mixed integration). `OF_LEAD`: the caller knows that the point takes part and is of the
/// totals' lead material (the same operations, without the checks).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn point_sums<E: Element, R: Real, const WITH_LIQUID: bool, const OF_LEAD: bool>(
    t: <R::Four as Four<R>>::Token,
    cx: &Pass<'_, E, R>,
    points: &Points<'_, E, R>,
    i: usize,
    n: R::Four,
    full: bool,
    s4: &mut [R::Four; 10],
    w4: &mut [R::Four; 12],
    totals: &mut Totals<R, R::Four>,
) {
    // (The arrays by field: `pa.x[i]` is point i's position.)
    let pa = &points.arrays;
    let (liquid, pore) = (points.liquid, pa.pore);
    let splat = |v: R| R::Four::splat(t, v);
    if !OF_LEAD && (!pa.active[i] || !maps(cx.body, pa.material[i])) {
        return;
    }
    debug_assert!(!OF_LEAD || (pa.active[i] && pa.material[i] == totals.lead));
    let material_i = if OF_LEAD { totals.lead } else { pa.material[i] };
    let (m, v) = (pa.mass[i], pa.vel[i]);
    let gravity = &cx.gravity[material_i as usize];
    let s = volume_stress(full, pa.volume[i], &pa.stress[i], pore.map(|p| p[i]));
    totals.add_stress(&s);
    let w = splat(m) * n;
    s4[0] = s4[0] + w;
    for a in 0..E::DIM {
        s4[1 + a] = s4[1 + a] + w * splat(v[a]);
    }
    if OF_LEAD || material_i == totals.lead {
        totals.lead_mass = totals.lead_mass + w;
    } else {
        for a in 0..E::DIM {
            s4[1 + 2 * E::DIM + a] = s4[1 + 2 * E::DIM + a] + w * splat(gravity[a]);
        }
    }
    if E::AXISYMMETRIC {
        // An axisymmetric section's hoop stress pulls each node towards the axis:
        // f_r -= V σ_θθ N / r (x the radius; V per radian), after the point's traction.
        let hoop = s[2] / pa.x[i][0];
        s4[1 + E::DIM] = s4[1 + E::DIM] - splat(hoop) * n;
    }
    if !WITH_LIQUID {
        return;
    }
    let (Some((loads, w_all, volume0)), Some(pore)) = (liquid, pore) else {
        return;
    };
    let Some(f) = loads.fluids[material_i as usize] else {
        return;
    };
    let (vw, mw, pw) =
        liquid_volume_mass_pressure(&f, full, pa.volume[i], volume0.map(|v0| v0[i]), pore[i]);
    let wv = w_all[i];
    totals.pore += pw;
    // (A point of the lead material is counted once per element, by the caller.)
    totals.volume_n = totals.volume_n + splat(pa.volume[i]) * n;
    if !OF_LEAD {
        totals.saturated = pore_weights::with_point(totals.saturated, material_i);
    }
    let mn = splat(mw) * n;
    w4[0] = w4[0] + mn;
    w4[1] = w4[1] + splat(f.n * mw) * n;
    w4[2] = w4[2] + splat(f.drag * vw) * n;
    for a in 0..E::DIM {
        w4[3 + a] = w4[3 + a] + mn * splat(wv[a]);
    }
    if E::AXISYMMETRIC {
        // The pore pressure's hoop force, as the solid's.
        let hoop = pw / pa.x[i][0];
        w4[3 + E::DIM] = w4[3 + E::DIM] - splat(hoop) * n;
    }
}

/// Adds the face loads carried by points, `scale` times their force, at the points' positions
/// (a short list, in its fixed order).
pub fn add_point_loads<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    p: &Particles<R>,
    loads: &[(u32, V3<R>)],
    scale: R,
    g: &mut Grid<R>,
) {
    for &(i, f) in loads {
        let i = i as usize;
        if !p.active[i] {
            continue;
        }
        let e = p.element[i] as usize;
        let n = mesh.shape(e, &p.x[i]);
        let n = n.as_ref();
        for k in 0..E::NODES {
            let node = mesh.corners[e].as_ref()[k] as usize;
            for a in 0..3 {
                g.f_ext[node][a] += n[k] * scale * f[a];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::mesh::TetMesh;
    use crate::parallel::team::Pin;
    use crate::state::grid::LiquidNodes;
    use crate::state::particles::LiquidPoints;
    use mpm_shared::{generate, ElementType};

    /// Points of 0 to 6 per element, inside it, with masses, velocities, stresses and pore
    /// pressures of magnitudes that differ from point to point; every third element with a
    /// point of material 1 (dry, its own gravity) among those of material 0 (saturated).
    fn points(mesh: &TetMesh<f64>) -> Particles<f64> {
        let mut rng = crate::test_rng::uniform(11);
        let element: Vec<u32> = (0..mesh.elements() as u32)
            .flat_map(|e| std::iter::repeat_n(e, (e as usize * 5 + 3) % 7))
            .collect();
        let mut p = Particles::<f64>::at_rest(element);
        let n = p.len();
        for i in 0..n {
            let e = p.element[i] as usize;
            let corners = mesh.corners[e];
            // A point inside: barycentric weights from 0.05 up, normalised.
            let w: [f64; 4] = std::array::from_fn(|_| 0.05 + rng());
            let total: f64 = w.iter().sum();
            p.x[i] = std::array::from_fn(|a| {
                (0..4)
                    .map(|k| w[k] / total * mesh.x[corners[k] as usize][a])
                    .sum()
            });
            p.mass[i] = 0.5 + rng();
            p.volume[i] = 1e-3 * (0.5 + rng());
            p.v[i] = std::array::from_fn(|_| rng() - 0.5);
            p.stress[i] = std::array::from_fn(|_| 1e3 * (rng() - 0.5));
            if e % 3 == 0 && i % 2 == 1 {
                p.material[i] = 1;
            }
        }
        p.liquid = Some(LiquidPoints {
            w: (0..n)
                .map(|_| std::array::from_fn(|_| rng() - 0.5))
                .collect(),
            p: (0..n).map(|_| -1e2 * rng()).collect(),
            volume0: None,
        });
        p
    }

    /// Each node's mass, momentum, internal and external force, then the liquid's mass,
    /// porosity-weighted mass, drag, momentum and force, summed point by point as the
    /// equations of docs/design.md §4.2 write them: V (σ' + p I) ∇N for each point, and each
    /// point's weight with its own material's gravity.
    fn reference(
        mesh: &TetMesh<f64>,
        p: &Particles<f64>,
        gravity: &[V3<f64>],
        fluids: &[Option<Fluid<f64>>],
        liquid_gravity: V3<f64>,
    ) -> Vec<Vec<f64>> {
        let nodes = mesh.x.len();
        let mut out = vec![vec![0.0; nodes]; 19];
        let l = p.liquid.as_ref().unwrap();
        for i in 0..p.len() {
            let e = p.element[i] as usize;
            let n = mesh.shape(e, &p.x[i]);
            let (grad, corners) = (&mesh.grad[e], &mesh.corners[e]);
            let material = p.material[i] as usize;
            let fluid = fluids[material];
            // (A dry material's points carry pore pressure 0 in a run; here they do not, and
            // their total stress takes it as the pass does.)
            let mut s = p.stress[i];
            for c in s.iter_mut().take(3) {
                *c += l.p[i];
            }
            const ROWS: [[usize; 3]; 3] = [[0, 3, 5], [3, 1, 4], [5, 4, 2]];
            for k in 0..4 {
                let node = corners[k] as usize;
                let w = p.mass[i] * n[k];
                out[0][node] += w;
                for a in 0..3 {
                    let traction: f64 = (0..3).map(|b| s[ROWS[a][b]] * grad[k][b]).sum();
                    out[1 + a][node] += w * p.v[i][a];
                    out[4 + a][node] -= p.volume[i] * traction;
                    out[7 + a][node] += w * gravity[material][a];
                }
                let Some(f) = fluid else { continue };
                let mw = f.rho_w * p.volume[i];
                out[10][node] += mw * n[k];
                out[11][node] += f.n * mw * n[k];
                out[12][node] += f.drag * p.volume[i] * n[k];
                for a in 0..3 {
                    out[13 + a][node] += mw * n[k] * l.w[i][a];
                    let pressure = p.volume[i] * l.p[i] * grad[k][a];
                    out[16 + a][node] += mw * n[k] * liquid_gravity[a] - pressure;
                    // The liquid's weight, on the mixture's external force.
                    out[7 + a][node] += f.n * mw * n[k] * liquid_gravity[a];
                }
            }
        }
        out
    }

    /// The pass's node values in [`reference`]'s order.
    fn of_grid(g: &Grid<f64>) -> Vec<Vec<f64>> {
        let l = g.liquid.as_ref().unwrap();
        let v3 = |v: &[V3<f64>], a: usize| v.iter().map(|x| x[a]).collect::<Vec<_>>();
        let mut out = vec![g.mass.clone()];
        for field in [&g.momentum, &g.f_int, &g.f_ext] {
            out.extend((0..3).map(|a| v3(field, a)));
        }
        out.extend([l.mass.clone(), l.mass_n.clone(), l.drag.clone()]);
        for field in [&l.momentum, &l.force] {
            out.extend((0..3).map(|a| v3(field, a)));
        }
        out
    }

    /// An element's points of every array are the arrays' runs over its range, liquid ones
    /// included; a range past the arrays and arrays of different lengths are refused.
    #[test]
    fn point_arrays_slice_every_array_alike_and_refuse_what_does_not_fit() {
        let mesh = TetMesh::<f64>::new(&generate::box_mesh([2, 2, 2], [1.0; 3], ElementType::Tet4))
            .unwrap();
        let mut p = points(&mesh);
        let n = p.len();
        let arrays = PointArrays::new(&p, true);
        for r in [0..0, 0..n, 3..7, n - 1..n] {
            let e = arrays.element(r.clone());
            assert_eq!(e.x, &p.x[r.clone()]);
            assert_eq!(e.stress, &p.stress[r.clone()]);
            assert_eq!(e.material, &p.material[r.clone()]);
            let l = p.liquid.as_ref().unwrap();
            assert_eq!(e.pore.unwrap(), &l.p[r.clone()]);
            assert_eq!(e.w.unwrap(), &l.w[r.clone()]);
        }
        // Without the liquid's pass, no liquid velocities.
        assert!(PointArrays::new(&p, false).element(0..n).w.is_none());
        let past =
            std::panic::catch_unwind(|| PointArrays::new(&p, true).element(n - 1..n + 1).x.len());
        assert!(past.is_err());
        p.volume.pop();
        let uneven = std::panic::catch_unwind(|| PointArrays::new(&p, true).len);
        assert!(uneven.is_err());
    }

    /// The element totals (the stress, pore-pressure and mass sums formed once per element)
    /// give the nodal values of the point-by-point equations to round-off, with several
    /// points per element and two materials in some elements (one saturated, one dry, with
    /// different gravity), on one and two threads, in the AVX2 and the portable copies, which
    /// agree bit for bit.
    #[test]
    fn element_totals_give_the_point_by_point_sums() {
        let mesh =
            TetMesh::new(&generate::box_mesh([3, 4, 3], [1.0; 3], ElementType::Tet4)).unwrap();
        let p = points(&mesh);
        let gravity = vec![[0.0, -9.81, 0.0], [1.5, -4.0, 0.5]];
        let spec = crate::material::liquid::LiquidSpec::new(0.4, 1000.0, 2e6, 1e-12, 1e-6).unwrap();
        let fluids = vec![Some(Fluid::new(&spec)), None];
        let liquid_gravity = [0.0, -9.81, 0.0];
        let want = reference(&mesh, &p, &gravity, &fluids, liquid_gravity);
        let mut first: Option<Vec<Vec<u64>>> = None;
        for (threads, portable) in [(1, true), (1, false), (2, false), (2, true)] {
            let team = Team::new(threads, Pin::None).unwrap();
            let layout = Layout::new(&mesh, &p, threads);
            let mut slots = layout.new_slots();
            let mut g = Grid::<f64>::new(mesh.x.len());
            g.liquid = Some(LiquidNodes::new(mesh.x.len()));
            let loads = LiquidLoads {
                fluids: &fluids,
                gravity: liquid_gravity,
            };
            crate::parallel::avx2::with_portable(portable, || {
                particle_to_grid(
                    &team,
                    &layout,
                    &mut slots,
                    &mesh,
                    &p,
                    &gravity,
                    None,
                    &mut g,
                    None,
                    Some(loads),
                    None,
                )
            });
            let got = of_grid(&g);
            for (field, (w, v)) in want.iter().zip(&got).enumerate() {
                let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (node, (a, b)) in w.iter().zip(v).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-12 * scale,
                        "field {field} node {node}: {b} against {a} ({threads} threads, \
                         portable {portable})"
                    );
                }
            }
            let bits: Vec<Vec<u64>> = got
                .iter()
                .map(|f| f.iter().map(|x| x.to_bits()).collect())
                .collect();
            match &first {
                None => first = Some(bits),
                Some(b) => assert!(
                    *b == bits,
                    "{threads} threads, portable {portable}: other bits"
                ),
            }
        }
    }
}
