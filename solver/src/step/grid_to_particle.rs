//! Grid to particle, MUSL: FLIP velocity update, then momentum re-mapped to the nodes for the
//! velocities that drive strain, stress, volume and position (docs/design.md §4, step 3), on the team.

use crate::element::mesh::Mesh;
use crate::element::Element;
use crate::material::liquid::Fluid;
use crate::parallel::gather::{node_slots, Layout, Slots, ELEMENT_BLOCK};
use crate::parallel::team::{Shared, Team};
use crate::real::{Real, V3};
use crate::state::grid::Grid;
use crate::state::particles::Particles;
use crate::step::contact::{maps, OneBody};
use crate::step::stress::GuardSums;

/// Updates particle velocities from nodal accelerations (FLIP; with `pic` > 0 blended with
/// the nodes' updated velocities, PIC), then re-maps momentum to get the nodal velocities
/// (fixed components and empty nodes zero) that drive strain, stress, volume and position
/// (see [`crate::step::stress`]). With `guard` (one slot per block of
/// [`crate::parallel::gather::ELEMENT_BLOCK`] elements), each block's slot is begun anew at its
/// first element and summed over its elements in order with their points' Σ m |v|² (twice
/// their kinetic energy), the velocities at hand. Only the points of `body` take part (all of
/// them for `None`; one body of a contact pair, [`crate::step::contact`]); the second body's
/// pass adds its kinetic energy to the slots the first began (`begin` false).
#[allow(clippy::too_many_arguments)]
pub fn grid_to_particle<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &mut Slots<R>,
    mesh: &Mesh<E, R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fixed: &[[bool; 3]],
    dt: R,
    pic: R,
    guard: Option<&mut [GuardSums]>,
    body: Option<OneBody>,
    begin: bool,
) {
    let guard = guard.map(Shared::new);
    let vel = Shared::new(&mut p.v);
    let (x, mass, active, material) = (&p.x, &p.mass, &p.active, &p.material);
    let (acc, momentum, node_mass, empty) = (&g.acc, &g.momentum, &g.mass, g.empty_below);
    let flip = R::ONE - pic;
    // One element's points; with `want`, their kinetic energy. Two scatters below, each with
    // `want` fixed, so that the run without guards keeps the loop it had without them.
    let element = |e: usize, four: &mut [R], want: bool| {
        let mut kinetic = 0.0;
        // The element's points, each array sliced to them once (one length): the loop then
        // indexes without bounds checks.
        let range = layout.particles_of(e);
        let count = range.len();
        let (x, mass, active, material) = (
            &x[range.clone()][..count],
            &mass[range.clone()][..count],
            &active[range.clone()][..count],
            &material[range.clone()][..count],
        );
        // SAFETY: the points of element e belong to this thread only.
        let vel = unsafe { &mut vel.range(range)[..count] };
        for i in 0..count {
            if !active[i] || !maps(body, material[i]) {
                continue;
            }
            let n = mesh.shape(e, &x[i]);
            let n = n.as_ref();
            let dv = interpolate(mesh, e, n, acc);
            let v = &mut vel[i];
            for c in 0..E::DIM {
                v[c] += dt * dv[c];
            }
            if pic > R::ZERO {
                // The nodes' velocities after the step, v + a Δt (zero where fixed or empty).
                let mut grid_v = [R::ZERO; 3];
                for (k, &nk) in n.iter().enumerate().take(E::NODES) {
                    let node = mesh.corners[e].as_ref()[k] as usize;
                    let m = node_mass[node];
                    if m <= empty {
                        continue;
                    }
                    for c in 0..E::DIM {
                        if !fixed[node][c] {
                            grid_v[c] += nk * (momentum[node][c] / m + dt * acc[node][c]);
                        }
                    }
                }
                for c in 0..E::DIM {
                    v[c] = flip * v[c] + pic * grid_v[c];
                }
            }
            for (k, slot) in node_slots::<E, R>(four, E::DIM).enumerate() {
                let w = mass[i] * n[k];
                for c in 0..E::DIM {
                    slot[c] += w * v[c];
                }
            }
            if want {
                kinetic += (mass[i] * dot::<E, R>(v, v)).f64();
            }
        }
        kinetic
    };
    match &guard {
        None => scatter::<E, R>(layout, team, slots, |e, four| {
            element(e, four, false);
        }),
        Some(guard) => scatter::<E, R>(layout, team, slots, |e, four| {
            let kinetic = element(e, four, true);
            let b = e / ELEMENT_BLOCK;
            // SAFETY: the scatter hands element e to one thread only, once, in element order,
            // and the thread's elements hold whole blocks (aligned ranges): no other thread
            // touches block b, and its first element comes first.
            let slot = unsafe { &mut guard.range(b..b + 1)[0] };
            if begin && e % ELEMENT_BLOCK == 0 {
                *slot = GuardSums {
                    kinetic,
                    ..GuardSums::EMPTY
                };
            } else {
                slot.kinetic += kinetic;
            }
        }),
    }
    nodal_velocity(
        team,
        layout,
        slots,
        &g.mass,
        g.empty_below,
        fixed,
        &mut g.vel,
    );
}

/// Σ N_k a_k over the nodes of element `e` (the in-plane components of a 2D element, z 0).
#[inline]
fn interpolate<E: Element, R: Real>(
    mesh: &Mesh<E, R>,
    e: usize,
    n: &[R],
    nodal: &[V3<R>],
) -> V3<R> {
    let mut out = [R::ZERO; 3];
    for k in 0..E::NODES {
        let a = nodal[mesh.corners[e].as_ref()[k] as usize];
        for c in 0..E::DIM {
            out[c] += n[k] * a[c];
        }
    }
    out
}

/// v · w over the element's dimensions.
#[inline(always)]
fn dot<E: Element, R: Real>(v: &V3<R>, w: &V3<R>) -> R {
    let mut s = R::ZERO;
    for c in 0..E::DIM {
        s += v[c] * w[c];
    }
    s
}

/// A scatter of one vector per node, as wide as the element's dimension.
fn scatter<E: Element, R: Real>(
    layout: &Layout<R, E>,
    team: &Team,
    slots: &mut Slots<R>,
    element: impl Fn(usize, &mut [R]) + Sync,
) {
    if E::DIM == 2 {
        layout.scatter::<2, _>(team, slots, element);
    } else {
        layout.scatter::<3, _>(team, slots, element);
    }
}

/// Nodal velocities from the re-mapped momentum in `slots`: zero at empty nodes and in fixed
/// components.
fn nodal_velocity<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &Slots<R>,
    mass: &[R],
    empty_below: R,
    fixed: &[[bool; 3]],
    vel: &mut [V3<R>],
) {
    let out = Shared::new(vel);
    let node = |n: usize, momentum: &[R]| {
        let mut v = [R::ZERO; 3];
        if mass[n] > empty_below {
            for c in 0..E::DIM {
                if !fixed[n][c] {
                    v[c] = momentum[c] / mass[n];
                }
            }
        }
        // SAFETY: node n is this thread's only.
        unsafe { out.write(n, v) };
    };
    if E::DIM == 2 {
        layout.gather::<2, _>(team, slots, |n, m| node(n, &m));
    } else {
        layout.gather::<3, _>(team, slots, |n, m| node(n, &m));
    }
}

/// The liquid's share of grid to particle: liquid velocities of the points updated from the
/// nodal liquid accelerations (FLIP), then the liquid momentum re-mapped to nodal liquid
/// velocities (zero in fixed components and at nodes without liquid). With `guard`, the
/// liquid's n ρw V_w |w|² (twice its kinetic energy) is added, element by element, to each
/// block's slot, which [`grid_to_particle`] began.
#[allow(clippy::too_many_arguments)]
pub fn liquid_to_particles<E: Element, R: Real>(
    team: &Team,
    layout: &Layout<R, E>,
    slots: &mut Slots<R>,
    mesh: &Mesh<E, R>,
    p: &mut Particles<R>,
    g: &mut Grid<R>,
    fluids: &[Option<Fluid<R>>],
    liquid_fixed: &[[bool; 3]],
    dt: R,
    guard: Option<&mut [GuardSums]>,
) {
    let (Some(lp), Some(gl)) = (&mut p.liquid, &mut g.liquid) else {
        return;
    };
    let guard = guard.map(Shared::new);
    let w_out = Shared::new(&mut lp.w);
    let (x, volume, active, material) = (&p.x, &p.volume, &p.active, &p.material);
    let acc = &gl.acc;
    scatter::<E, R>(layout, team, slots, |e, four| {
        let mut kinetic = 0.0;
        for i in layout.particles_of(e) {
            let Some(f) = fluids[material[i] as usize] else {
                continue;
            };
            if !active[i] {
                continue;
            }
            let n = mesh.shape(e, &x[i]);
            let n = n.as_ref();
            let dw = interpolate(mesh, e, n, acc);
            // SAFETY: particle i (of element e) belongs to this thread only.
            let w = unsafe { &mut w_out.range(i..i + 1)[0] };
            for c in 0..E::DIM {
                w[c] += dt * dw[c];
            }
            // The same liquid mass as particle to grid mapped (see `LiquidPoints::volume0`).
            let mw = f.rho_w * lp.volume0.as_ref().map_or(volume[i], |v0| v0[i]);
            for (k, slot) in node_slots::<E, R>(four, E::DIM).enumerate() {
                for c in 0..E::DIM {
                    slot[c] += mw * n[k] * w[c];
                }
            }
            if guard.is_some() {
                kinetic += (f.n * mw * dot::<E, R>(w, w)).f64();
            }
        }
        if let Some(guard) = &guard {
            let b = e / ELEMENT_BLOCK;
            // SAFETY: as in `grid_to_particle`: block b belongs to this thread alone.
            unsafe { guard.range(b..b + 1)[0].kinetic += kinetic };
        }
    });
    nodal_velocity(
        team,
        layout,
        slots,
        &gl.mass,
        g.empty_below,
        liquid_fixed,
        &mut gl.vel,
    );
}
