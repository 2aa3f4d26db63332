//! One point's share of particle to grid, one lane per node (`n`: the point's weight at each
//! node): the physics of the pass, written once over any lanes ([`Lanes`]), and taken by the
//! element kernels (four-lane vectors, or plain arrays in the portable copies) and by the
//! stencil pass (a stencil's nodes four at a time) alike.

use crate::element::Element;
use crate::four::Lanes;
use crate::material::liquid::Fluid;
use crate::real::{Real, V3};
use crate::state::pore_weights;
use crate::step::contact::maps;

use super::arrays::Points;
use super::totals::Sums;

/// Point `i`'s contributions to its element's sums, `n` its weights one lane per node, if it
/// takes part: into the node lanes, and into the element's totals the terms it takes once for
/// all its points ([`super::totals::Totals`]). `OF_LEAD`: the caller knows that the point takes
/// part and is of the totals' lead material (the same operations, without the checks).
#[inline(always)]
pub(super) fn point_sums<E, R, F, const WITH_LIQUID: bool, const OF_LEAD: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    i: usize,
    n: F,
    sums: &mut Sums<R, F>,
) where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    // (The arrays by field: `pa.x[i]` is point i's position.)
    let pa = &points.arrays;
    let splat = |v: R| F::splat(t, v);
    if !OF_LEAD && (!pa.active[i] || !maps(points.body, pa.material[i])) {
        return;
    }
    let Sums {
        solid: s4, totals, ..
    } = sums;
    debug_assert!(!OF_LEAD || (pa.active[i] && pa.material[i] == totals.lead));
    let material_i = if OF_LEAD { totals.lead } else { pa.material[i] };
    let (m, v) = (pa.mass[i], pa.vel[i]);
    let gravity = &points.gravity[material_i as usize];
    let s = volume_stress(
        points.full,
        pa.volume[i],
        &pa.stress[i],
        pa.pore.map(|p| p[i]),
        pa.bulk.map(|q| q[i]),
    );
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
    if WITH_LIQUID {
        liquid_sums::<E, R, F, OF_LEAD>(t, points, i, material_i, n, sums);
    }
}

/// The liquid's share of point `i` (of material `material`, `n` its weights one lane per node)
/// where its material has a fluid: liquid masses, drag, liquid momentum and the hoop force of
/// its pore pressure into the liquid's node lanes, its V p and V N into the totals.
#[inline(always)]
fn liquid_sums<E, R, F, const OF_LEAD: bool>(
    t: F::Token,
    points: &Points<'_, E, R>,
    i: usize,
    material: u32,
    n: F,
    sums: &mut Sums<R, F>,
) where
    E: Element,
    R: Real,
    F: Lanes<R>,
{
    let pa = &points.arrays;
    let splat = |v: R| F::splat(t, v);
    let (Some((loads, w_all, volume0)), Some(pore)) = (points.liquid, pa.pore) else {
        return;
    };
    let Some(f) = loads.fluids[material as usize] else {
        return;
    };
    let (vw, mw, pw) = liquid_volume_mass_pressure(
        &f,
        points.full,
        pa.volume[i],
        volume0.map(|v0| v0[i]),
        pore[i],
    );
    let wv = w_all[i];
    let Sums {
        liquid: w4, totals, ..
    } = sums;
    totals.pore += pw;
    // (A point of the lead material is counted once per element, by the caller.)
    totals.volume_n = totals.volume_n + splat(pa.volume[i]) * n;
    if !OF_LEAD {
        totals.saturated = pore_weights::with_point(totals.saturated, material);
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

/// A point's volume times its total stress, V (σ' + p I) (`pore` its pore pressure p, where the
/// case has one), plus V q I (`bulk` its bulk viscous pressure q, where the case has bulk
/// viscosity), as particle to grid's internal force takes it: 0 for the point of a full
/// element under mixed integration, whose element's Gauss point takes its force.
#[inline(always)]
pub(super) fn volume_stress<R: Real>(
    full: bool,
    volume: R,
    stress: &[R; 6],
    pore: Option<R>,
    bulk: Option<R>,
) -> [R; 6] {
    let vol = if full { R::ZERO } else { volume };
    let mut s = stress.map(|c| vol * c);
    for extra in [pore, bulk].into_iter().flatten() {
        let v = vol * extra;
        s[0] += v;
        s[1] += v;
        s[2] += v;
    }
    s
}

/// A saturated point's liquid volume, liquid mass and V p (0 for a full element's point under
/// mixed integration) for particle to grid. The liquid's mass, weight and drag are taken on the
/// initial volume `volume0` where the case holds the liquid mass fixed.
#[inline(always)]
pub(super) fn liquid_volume_mass_pressure<R: Real>(
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

/// The first `E::DIM` values of `s` from `at` as a 3-vector (z 0 in 2D).
#[inline(always)]
pub(super) fn vector<E: Element, R: Real>(s: &[R], at: usize) -> V3<R> {
    let mut v = [R::ZERO; 3];
    v[..E::DIM].copy_from_slice(&s[at..at + E::DIM]);
    v
}
