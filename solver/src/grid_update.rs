//! Grid update: nodal accelerations with local damping and fixities (DESIGN §4, step 2).

use crate::grid::Grid;
use crate::real::{Real, V3};

/// Nodes lighter than this (relative to the heaviest) are treated as empty.
pub const MASS_EPS: f64 = 1e-12;

/// a = (f_int + f_ext + traction) / m, with local damping f ← f - α |f| sign(v) per component
/// (sign(f) where v = 0)
/// and zero acceleration in fixed directions. `traction` holds nodal face loads at multiplier 1,
/// `scale` the multiplier; `fixed[n][a]` marks fixed components.
///
/// Returns the out-of-balance force ratio of Anura3D's quasi-static convergence check,
/// |f_int + f_ext| / |f_ext| over the free components (0 without external force).
pub fn grid_update<R: Real>(
    g: &mut Grid<R>,
    traction: &[V3<R>],
    scale: R,
    fixed: &[[bool; 3]],
    alpha: R,
) -> f64 {
    let (mut unbalanced, mut external) = (0.0, 0.0);
    let heaviest = g.mass.iter().fold(R::ZERO, |a, &b| a.max(b));
    let eps = heaviest * R::of(MASS_EPS);
    g.empty_below = eps;
    for n in 0..g.mass.len() {
        let m = g.mass[n];
        if m <= eps {
            g.acc[n] = [R::ZERO; 3];
            continue;
        }
        for a in 0..3 {
            if fixed[n][a] {
                g.acc[n][a] = R::ZERO;
                continue;
            }
            let ext = g.f_ext[n][a] + scale * traction[n][a];
            let mut f = g.f_int[n][a] + ext;
            unbalanced += f.f64() * f.f64();
            external += ext.f64() * ext.f64();
            // A node at rest is damped against the motion the force is about to cause (sign of
            // f), as Anura3D's results show (its first step's force is scaled by 1 - α).
            let v = g.momentum[n][a];
            let s = if v != R::ZERO { v.sign() } else { f.sign() };
            f -= alpha * f.abs() * s;
            g.acc[n][a] = f / m;
        }
    }
    if external > 0.0 {
        (unbalanced / external).sqrt()
    } else {
        0.0
    }
}

/// Two-phase grid update (DESIGN §4) with the drag treated implicitly per node: with the solid
/// force F_s (mixture: total-stress internal force, mixture weight, loads) and the liquid force
/// F_w (pore-pressure gradient and weight; the solid's force locally damped against its
/// velocity),
///
///   M_w a_w = F_w - Q (w + a_w Δt - v - a_s Δt),   M_s a_s = F_s - M̄_w a_w,
///
/// is solved exactly per component, so the drag never limits the step; fixed components of a
/// phase have zero acceleration (a fixed solid takes the reaction; a fixed liquid is an
/// impermeable face). Loads on the liquid (`liquid_traction` × `liquid_scale`) act on the liquid
/// and, being part of the total traction, on the mixture. Nodes without liquid mass follow the
/// dry update. Returns the out-of-balance
/// force ratio of the mixture, as [`grid_update`].
#[allow(clippy::too_many_arguments)]
pub fn grid_update_two_phase<R: Real>(
    g: &mut Grid<R>,
    traction: &[V3<R>],
    scale: R,
    liquid_traction: &[V3<R>],
    liquid_scale: R,
    fixed: &[[bool; 3]],
    liquid_fixed: &[[bool; 3]],
    alpha: R,
    damp_liquid: bool,
    dt: R,
) -> f64 {
    let (mut unbalanced, mut external) = (0.0, 0.0);
    let heaviest = g.mass.iter().fold(R::ZERO, |a, &b| a.max(b));
    let eps = heaviest * R::of(MASS_EPS);
    g.empty_below = eps;
    let gl = g.liquid.as_mut().expect("liquid arrays");
    let damp = |f: R, momentum: R| {
        let s = if momentum != R::ZERO {
            momentum.sign()
        } else {
            f.sign()
        };
        f - alpha * f.abs() * s
    };
    for n in 0..g.mass.len() {
        let ms = g.mass[n];
        if ms <= eps {
            g.acc[n] = [R::ZERO; 3];
            gl.acc[n] = [R::ZERO; 3];
            continue;
        }
        let (mw, mwn, q) = (gl.mass[n], gl.mass_n[n], gl.drag[n]);
        let wet = mw > eps;
        for a in 0..3 {
            // A load on the liquid is part of the total traction too.
            let lt = liquid_scale * liquid_traction[n][a];
            let ext = g.f_ext[n][a] + scale * traction[n][a] + lt;
            let fs_raw = g.f_int[n][a] + ext;
            if !fixed[n][a] {
                unbalanced += fs_raw.f64() * fs_raw.f64();
                external += ext.f64() * ext.f64();
            }
            let fs = damp(fs_raw, g.momentum[n][a]);
            if !wet {
                g.acc[n][a] = if fixed[n][a] { R::ZERO } else { fs / ms };
                gl.acc[n][a] = R::ZERO;
                continue;
            }
            // The liquid's force is not damped by default: in seepage it is balanced by the
            // drag, which is dissipative already, and damping it would slow the flow
            // (c_v × (1 - α)). Anura3D damps it; `damp_liquid` follows Anura3D.
            let fw = if damp_liquid {
                damp(gl.force[n][a] + lt, gl.momentum[n][a])
            } else {
                gl.force[n][a] + lt
            };
            // Relative velocity w - v at the start of the step.
            let dv = gl.momentum[n][a] / mw - g.momentum[n][a] / ms;
            let qdt = q * dt;
            let (a_s, a_w) = match (fixed[n][a], liquid_fixed[n][a]) {
                (true, true) => (R::ZERO, R::ZERO),
                (true, false) => (R::ZERO, (fw - q * dv) / (mw + qdt)),
                (false, true) => (fs / ms, R::ZERO),
                (false, false) => {
                    let a_w = (fw - q * dv + qdt * fs / ms) / (mw + qdt * (R::ONE + mwn / ms));
                    ((fs - mwn * a_w) / ms, a_w)
                }
            };
            g.acc[n][a] = a_s;
            gl.acc[n][a] = a_w;
        }
    }
    if external > 0.0 {
        (unbalanced / external).sqrt()
    } else {
        0.0
    }
}
