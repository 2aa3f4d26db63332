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
