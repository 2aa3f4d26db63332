//! Reference solutions of Modified Cam Clay's element tests, computed apart from the law's
//! stress update ([`crate::material::modified_cam_clay`]) so that they check it:
//!
//! - the undrained effective stress path in closed form (Wood 1990, §7): the volume held,
//!   κ ln(p / p0) + (λ − κ) ln(p_c / p_c0) = 0 on yielding, so p_c = p_c0 (p0 / p)^(κ / (λ − κ))
//!   and q = M p √(p_c / p − 1); its end, the undrained strength
//!   s_u = q_f / 2 = M p0 (R / 2)^Λ / 2, Λ = (λ − κ) / λ, R = p_c0 / p0;
//! - the drained triaxial compression (constant cell pressure, dq = 3 dp) as an ODE in p,
//!   integrated by the classical Runge–Kutta method: elastic up to the surface, then on it
//!   (consistency: p_c = p + q² / (M² p)) with the flow rule's strains.

use crate::material::modified_cam_clay::ModifiedCamClaySpec;

/// The undrained path's q at mean stress `p` (kPa), from the isotropic start `p0` with
/// preconsolidation `pc0`, once yielding (p below p0 on the wet side, above on the dry).
pub fn undrained_q(law: &ModifiedCamClaySpec, p0: f64, pc0: f64, p: f64) -> f64 {
    let pc = pc0 * (p0 / p).powf(law.kappa / (law.lambda - law.kappa));
    law.slope * p * (pc / p - 1.0).max(0.0).sqrt()
}

/// The undrained strength s_u (kPa) from the isotropic start `p0` with preconsolidation `pc0`.
pub fn undrained_strength(law: &ModifiedCamClaySpec, p0: f64, pc0: f64) -> f64 {
    let big_lambda = (law.lambda - law.kappa) / law.lambda;
    law.slope * p0 * (pc0 / (2.0 * p0)).powf(big_lambda) / 2.0
}

/// A point of the drained reference: axial and volumetric strain, p and q (compression
/// positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrainedPoint {
    /// Axial strain.
    pub axial: f64,
    /// Volumetric strain.
    pub volumetric: f64,
    /// Mean effective stress (kPa).
    pub p: f64,
    /// Deviator (kPa).
    pub q: f64,
}

/// The drained triaxial compression from the isotropic `p0` with preconsolidation `pc0`,
/// until q / p reaches `eta_end` (below M), in `steps` Runge–Kutta steps of p (half of them
/// on the elastic part when there is one). The void ratio starts at the law's e0.
pub fn drained_triaxial(
    law: &ModifiedCamClaySpec,
    p0: f64,
    pc0: f64,
    eta_end: f64,
    steps: usize,
) -> Vec<DrainedPoint> {
    let m2 = law.slope * law.slope;
    // Where the path q = 3 (p − p0) meets the surface: 9 (p − p0)² / M² + p² − p pc0 = 0.
    let (a, b, c) = (9.0 / m2 + 1.0, -18.0 * p0 / m2 - pc0, 9.0 * p0 * p0 / m2);
    let p_yield = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    // The end: q = η p with q = 3 (p − p0).
    let p_end = 3.0 * p0 / (3.0 - eta_end);
    let mut y = [0.0, 0.0, 1.0 + law.void_ratio]; // ε_v, ε_q, v
    let mut out = vec![DrainedPoint {
        axial: 0.0,
        volumetric: 0.0,
        p: p0,
        q: 0.0,
    }];
    let legs: [(f64, f64, bool, usize); 2] = if p_yield > p0 {
        [
            (p0, p_yield, false, steps / 2),
            (p_yield, p_end, true, steps - steps / 2),
        ]
    } else {
        [(p0, p0, false, 0), (p0, p_end, true, steps)]
    };
    for (from, to, plastic, n) in legs {
        let h = (to - from) / n.max(1) as f64;
        for i in 0..n {
            let p = from + h * i as f64;
            let f = |p: f64, y: &[f64; 3]| rates(law, p0, p, y, plastic);
            let k1 = f(p, &y);
            let k2 = f(p + h / 2.0, &step(&y, &k1, h / 2.0));
            let k3 = f(p + h / 2.0, &step(&y, &k2, h / 2.0));
            let k4 = f(p + h, &step(&y, &k3, h));
            y = std::array::from_fn(|j| {
                y[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            });
            let p = p + h;
            out.push(DrainedPoint {
                axial: y[0] / 3.0 + y[1],
                volumetric: y[0],
                p,
                q: 3.0 * (p - p0),
            });
        }
    }
    out
}

/// The worst relative differences of q and ε_v between the element test `path` (its start
/// left out) and the drained `reference` interpolated linearly at each record's axial strain:
/// q over max(q, 1 kPa), ε_v over max(|ε_v|, 1e-4).
pub fn drained_errors(
    path: &[crate::material::element_test::Record],
    reference: &[DrainedPoint],
) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for r in path.iter().skip(1) {
        let i = reference
            .partition_point(|x| x.axial < r.axial)
            .clamp(1, reference.len() - 1);
        let (a, b) = (&reference[i - 1], &reference[i]);
        let t = (r.axial - a.axial) / (b.axial - a.axial);
        let q = a.q + t * (b.q - a.q);
        let ev = a.volumetric + t * (b.volumetric - a.volumetric);
        worst.0 = worst.0.max((r.q - q).abs() / q.max(1.0));
        worst.1 = worst.1.max((r.volumetric - ev).abs() / ev.abs().max(1e-4));
    }
    worst
}

/// y + h k.
fn step(y: &[f64; 3], k: &[f64; 3], h: f64) -> [f64; 3] {
    std::array::from_fn(|j| y[j] + h * k[j])
}

/// d(ε_v, ε_q, v) / dp on the drained path at `p` (q = 3 (p − p0)), elastic or on the surface.
fn rates(law: &ModifiedCamClaySpec, p0: f64, p: f64, y: &[f64; 3], plastic: bool) -> [f64; 3] {
    let (m2, v) = (law.slope * law.slope, y[2]);
    let q = 3.0 * (p - p0);
    let k = v * p / law.kappa;
    let g = if law.shear_modulus > 0.0 {
        law.shear_modulus
    } else {
        3.0 * (1.0 - 2.0 * law.poisson) / (2.0 * (1.0 + law.poisson)) * k
    };
    let mut ev = 1.0 / k;
    let mut eq = 1.0 / g; // dq / (3G) with dq = 3 dp
    if plastic {
        // p_c = p + q² / (M² p): its rate along the path, and the flow rule.
        let pc = p + q * q / (m2 * p);
        let dpc = 1.0 + (6.0 * q * p - q * q) / (m2 * p * p);
        let evp = (law.lambda - law.kappa) / (v * pc) * dpc;
        ev += evp;
        eq += evp * (2.0 * q / m2) / (2.0 * p - pc);
    }
    [ev, eq, -v * ev]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clay() -> ModifiedCamClaySpec {
        ModifiedCamClaySpec::new(0.3, 0.0, 0.2, 0.04, 1.0, 1.2, 0.0, 1.0, 0.0, 1.0, 2000.0).unwrap()
    }

    #[test]
    fn the_closed_form_path_ends_at_the_undrained_strength() {
        let law = clay();
        // Normally consolidated: p_f = p0 2^(−Λ).
        let su = undrained_strength(&law, 100.0, 100.0);
        let pf = 100.0 * 0.5f64.powf(0.8);
        assert!((su - pf / 2.0).abs() < 1e-12);
        assert!((undrained_q(&law, 100.0, 100.0, pf) - law.slope * pf).abs() < 1e-9);
        assert_eq!(undrained_q(&law, 100.0, 100.0, 100.0), 0.0);
    }

    #[test]
    fn the_drained_reference_starts_elastic_and_approaches_the_critical_state() {
        let law = clay();
        let path = drained_triaxial(&law, 100.0, 150.0, 0.95, 2000);
        let first = path[1];
        // Elastic: ε_q = q / (3G), ε_v = p / K to first order.
        let k = 2.2 * 100.0 / 0.04;
        let g = 3.0 * 0.4 / 2.6 * k;
        assert!((first.volumetric / ((first.p - 100.0) / k) - 1.0).abs() < 1e-2);
        assert!(
            ((first.axial - first.volumetric / 3.0) / (first.q / (3.0 * g)) - 1.0).abs() < 1e-2
        );
        let last = path.last().unwrap();
        assert!((last.q / last.p - 0.95).abs() < 1e-9);
        assert!(path.windows(2).all(|w| w[1].axial > w[0].axial));
    }
}
