//! The stress pass's general batches: an element's points in batches of up to `W`, each value
//! held across the batch's points as a plain lane array ([`crate::four::Plain`]: `[c]` lane
//! q, value c of point q), so that each operation is one over the points, which the compiler
//! turns into vector instructions. Each point's arithmetic is the one a point-by-point loop
//! does ([`super::point`], [`super::strain`]), in the same order, so the results are the same
//! bits whatever the width; lanes past the batch's points or of points that do not move repeat
//! a moving point's values and are never stored. Every law, strain smoothing and axisymmetric
//! sections go this way.

use crate::element::Element;
use crate::four::{Lanes, Plain};
use crate::real::Real;
use crate::step::batch::Batch;
use crate::step::contact::maps;

use super::guard::{GuardTerms, Open};
use super::laws::update_batch;
use super::point::{moved, pore_change, strain_work, velocity_at, volume_factor};
use super::strain::{add_objective, rotate, spin_increment, strain_increment};
use super::{ChunkPoints, ElementView, Pass};

/// `W` lanes of plain values.
type L<R, const W: usize> = Plain<R, W>;

/// The points of element `el` from `j` up to `end` in batches of `W`: each batch that has a
/// point taking part ([`batch`]), its points added to the guard's sums `open` with `guard`.
#[inline(always)]
pub(super) fn general_batches<E: Element, R: Real, const W: usize, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    el: &ElementView<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    (mut j, end): (usize, usize),
    (open, guard): (&mut Open, bool),
) {
    let (active, material) = (p.active, p.material);
    while j < end {
        let b = match Batch::<W>::new(j, end, |i| active[i] && maps(cx.body, material[i])) {
            Ok(b) => b,
            Err(skip) => {
                j += skip;
                continue;
            }
        };
        debug_assert!(
            (j..j + b.len).all(|i| p.element[i] as usize == el.e),
            "points not sorted by element"
        );
        batch::<E, R, W, WIDE>(cx, el, p, &b, (&mut *open, guard));
        j += b.len;
    }
}

/// One batch `b` of the element's points: the pore pressure's smoothed rate, the strain
/// increment (the element's, with an axisymmetric section's hoop strain and strain smoothing's
/// correction point by point), the law's update ([`update_batch`]) and the objective terms,
/// the new volume, position and displacement, and the guard's sums.
#[inline(always)]
fn batch<E: Element, R: Real, const W: usize, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    el: &ElementView<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    b: &Batch<W>,
    (open, guard): (&mut Open, bool),
) {
    let (t, dt) = ((), cx.dt);
    let xl = b.gather(p.x);
    let nl = E::shape_lanes(el.map, el.first, &xl);
    let n: [L<R, W>; 4] = std::array::from_fn(|k| Plain(nl[k]));
    let xl: [L<R, W>; 3] = std::array::from_fn(|a| Plain(xl[a]));
    // The pore pressure's smoothed rate, from the nodes at the start-of-step position (the
    // points move below).
    if let (Some(rate), Some(pore)) = (&cx.pore_rate, p.pore.as_deref_mut()) {
        // The element's nodal rates, read once per batch (once per element in a
        // tetrahedron's batch of four): held across the whole element they cost the dry step
        // registers.
        let nodal = E::nodes(|k| rate.nodal[el.corners[k] as usize]);
        let change = pore_change::<E, R, L<R, W>>(t, &n, nodal.as_ref(), dt);
        for i in b.points() {
            if rate.fluids[p.material[i] as usize].is_some() {
                pore[i] += change.0[i - b.start];
            }
        }
    }
    let dx = velocity_at::<E, R, L<R, W>>(t, &n, el.vel);
    let de = strain_of::<E, R, W>(cx, el, p, b, (&dx, &xl));
    finish::<E, R, W, WIDE>(
        cx,
        p,
        b,
        Motion {
            x: xl,
            dx,
            de,
            l: el.l,
        },
        (open, guard),
    );
}

/// The Jaumann co-rotation of the tensors among the batch's points' law state (the
/// intergranular strain; [`crate::material::law::Law::state_tensors`]) for the spin
/// increment `spin`, as their stresses turn.
fn co_rotate_state<E: Element, R: Real, const W: usize>(
    cx: &Pass<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    b: &Batch<W>,
    spin: &[R; 3],
) {
    let k = p.k;
    for i in b.points() {
        for &at in cx.laws[p.material[i] as usize].state_tensors() {
            let t: &mut [R; 6] = (&mut p.state[k * i + at..k * i + at + 6])
                .try_into()
                .expect("a state tensor has six values");
            rotate(t, spin);
        }
    }
}

/// A batch's motion in the step: its points' positions `x` and velocities `dx`, their strain
/// increments `de`, and the velocity gradient `l` the objective terms' spin is taken from.
pub(super) struct Motion<'l, R: Real, const W: usize> {
    pub x: [L<R, W>; 3],
    pub dx: [L<R, W>; 3],
    pub de: [L<R, W>; 6],
    pub l: &'l [[R; 3]; 3],
}

/// The rest of a batch's update once its motion is known (the element's batches here, a
/// stencil's point in [`super::stencil`]): the law's update ([`update_batch`]) and the
/// objective terms, the new volume, position and displacement, and the guard's sums.
#[inline(always)]
pub(super) fn finish<E: Element, R: Real, const W: usize, const WIDE: bool>(
    cx: &Pass<'_, E, R>,
    p: &mut ChunkPoints<'_, R>,
    b: &Batch<W>,
    motion: Motion<'_, R, W>,
    (open, guard): (&mut Open, bool),
) {
    let (t, dt) = ((), cx.dt);
    let Motion { x: xl, dx, de, l } = motion;
    let s = b.gather(p.stress);
    let s0: [L<R, W>; 6] = std::array::from_fn(|c| Plain(s[c]));
    let mut s1 = s0;
    update_batch::<E, R, W, WIDE>(cx, p, b, &mut s1, &de);
    if cx.objective {
        let ev = de[0] + de[1] + de[2];
        let spin = spin_increment(l, dt);
        add_objective::<R, L<R, W>>(t, &s0, &mut s1, &spin, ev);
        if cx.tensor_state {
            co_rotate_state(cx, p, b, &spin);
        }
    }
    let v0: L<R, W> = Plain(b.at.map(|i| p.volume[i]));
    // The hoop strain changes an axisymmetric point's volume unless the case follows
    // Anura3D, which leaves it out ([`crate::input::case::Numerics::hoop_in_volume`]).
    let de_zz = if E::AXISYMMETRIC && !cx.hoop_in_volume {
        L::<R, W>::splat(t, R::ZERO)
    } else {
        de[2]
    };
    let v1 = v0 * volume_factor::<R, L<R, W>>(t, de[0], de[1], de_zz);
    if let (Some(bulk), Some((q, rate))) = (&cx.bulk, p.bulk.as_mut()) {
        // Anura3D's rate tr Δε / Δt (the hoop strain included) and the viscous pressure of
        // it, in the element the point strained in.
        for i in b.points() {
            let k = i - b.start;
            let r = (de[0].0[k] + de[1].0[k] + de[2].0[k]) / dt;
            let length = cx.mesh.min_altitude[p.element[i] as usize];
            rate[i] = r;
            q[i] = bulk.damping.pressure(p.material[i], length, r);
        }
    }
    let x1 = moved::<E, R, L<R, W>>(t, xl, &dx, dt);
    let u = b.gather(p.u);
    let u0: [L<R, W>; 3] = std::array::from_fn(|a| Plain(u[a]));
    let u1 = moved::<E, R, L<R, W>>(t, u0, &dx, dt);
    for i in b.points() {
        let q = i - b.start;
        p.x[i] = std::array::from_fn(|a| x1[a].0[q]);
        for a in 0..E::DIM {
            p.u[i][a] = u1[a].0[q];
        }
        p.stress[i] = std::array::from_fn(|c| s1[c].0[q]);
        p.volume[i] = v1.0[q];
    }
    if !guard {
        return;
    }
    let strain = strain_work::<E, R, L<R, W>>(t, (&s0, &s1), &de, (&x1, v0, v1));
    // Point by point in order: the block's sums are those of adding in place.
    for i in b.points() {
        let q = i - b.start;
        let g = GuardTerms::of(p.material[i], cx.initial_density, cx.fluids, cx.min_ratio);
        let pore = p.pore.as_deref().map(|pore| pore[i]);
        g.add_point(open, strain.0[q], v1.0[q], p.mass[i], pore);
    }
}

/// The batch's strain increments: the element's, an axisymmetric section's ε_zz the hoop
/// strain u_r / r point by point (`dx`: the points' velocities, `xl` their positions, x the
/// radius), and with strain smoothing the normal increments in the section's plane shifted
/// equally so that their trace is the smoothed volumetric increment (all three in 3D, the two
/// in-plane ones in plane strain: Anura3D's rule; its ε_zz stays zero; axisymmetric sections
/// do not smooth).
#[inline(always)]
fn strain_of<E: Element, R: Real, const W: usize>(
    cx: &Pass<'_, E, R>,
    el: &ElementView<'_, E, R>,
    p: &ChunkPoints<'_, R>,
    b: &Batch<W>,
    (dx, xl): (&[L<R, W>; 3], &[L<R, W>; 3]),
) -> [L<R, W>; 6] {
    let dt = cx.dt;
    let element_de = strain_increment::<E, R>(el.l, dt);
    let mut de: [L<R, W>; 6] = std::array::from_fn(|c| Plain([element_de[c]; W]));
    if E::AXISYMMETRIC {
        de[2] = dx[0] / xl[0] * L::<R, W>::splat((), dt);
    }
    if let Some(sm) = cx.smoothing {
        let (half, third) = (R::of(0.5), R::ONE / R::of(3.0));
        for q in 0..W {
            let [es, _] = sm.element_mean(cx.mesh, el.e, p.material[b.at[q]]);
            let c = if E::DIM == 2 {
                (de[0].0[q] + de[1].0[q] - es) * half
            } else {
                (de[0].0[q] + de[1].0[q] + de[2].0[q] - es) * third
            };
            for d in de.iter_mut().take(E::DIM) {
                d.0[q] -= c;
            }
        }
    }
    de
}
