//! Grid update: nodal accelerations with local damping and fixities (DESIGN §4, step 2).

use crate::grid::Grid;
use crate::real::{Real, V3};

/// Nodes lighter than this (relative to the heaviest) are treated as empty.
pub const MASS_EPS: f64 = 1e-12;

/// a = (f_int + f_ext + traction) / m, with local damping f ← f - α |f| sign(v) per component
/// and zero acceleration in fixed directions. `traction` holds nodal face loads with their
/// multiplier applied; `fixed[n][a]` marks fixed components.
pub fn grid_update<R: Real>(
    g: &mut Grid<R>,
    traction: &[V3<R>],
    scale: R,
    fixed: &[[bool; 3]],
    alpha: R,
) {
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
            let mut f = g.f_int[n][a] + g.f_ext[n][a] + scale * traction[n][a];
            let v = g.momentum[n][a] / m;
            f -= alpha * f.abs() * v.sign();
            g.acc[n][a] = f / m;
        }
    }
}
