//! Reference values of the hypoplastic law's element tests, computed apart from its stress
//! update ([`crate::material::hypoplastic`]) so that they check it:
//!
//! - the critical void ratio e_c(p) = e_c0 exp(−(3p / h_s)^n) (Bauer's law) that a sample
//!   sheared at constant cell pressure reaches, at φ_c;
//! - the peak state of a drained triaxial compression (Herle & Gudehus 1999): where the stress
//!   rate vanishes (with F = 1 in triaxial compression), the principal stress ratio
//!   K_p = σ1 / σ3, the dilatancy tan ν_p = −ε̇_v / ε̇_1 and the density factor
//!   f_d = ((e − e_d) / (e_c − e_d))^α at the peak are tied by
//!   A = (a / (2 + K_p))² (1 − K_p (4 − K_p) / (5 K_p − 2)),
//!   tan ν_p = 2 (K_p − 4 + 5 A K_p² − 2 A K_p) / ((5 K_p − 2)(1 + 2A)) − 1,
//!   f_d = 6 ((2 + K_p)² + a² K_p (K_p − 1 − tan ν_p)) /
//!   (a (2 + K_p)(5 K_p − 2) √(4 + 2 (1 + tan ν_p)²)),
//!   so the peak friction angle follows from the void ratio and pressure at the peak.

use crate::material::element_test::Record;
use crate::material::hypoplastic::HypoplasticSpec;

/// The critical void ratio at mean effective stress `p` (kPa).
pub fn critical_void_ratio(law: &HypoplasticSpec, p: f64) -> f64 {
    law.e_c0 * (-(3.0 * p / law.hardness).powf(law.exponent)).exp()
}

/// The densest void ratio at mean effective stress `p` (kPa).
pub fn densest_void_ratio(law: &HypoplasticSpec, p: f64) -> f64 {
    law.e_d0 * (-(3.0 * p / law.hardness).powf(law.exponent)).exp()
}

/// The peak state of Herle & Gudehus: the dilatancy tan ν_p and the density factor f_d at the
/// principal stress ratio `kp` = σ1 / σ3 (> 1).
pub fn peak_relation(law: &HypoplasticSpec, kp: f64) -> (f64, f64) {
    let sin = law.friction.to_radians().sin();
    let a = 3f64.sqrt() * (3.0 - sin) / (2.0 * 2f64.sqrt() * sin);
    let big_a = (a / (2.0 + kp)).powi(2) * (1.0 - kp * (4.0 - kp) / (5.0 * kp - 2.0));
    let tan_nu = 2.0 * (kp - 4.0 + 5.0 * big_a * kp * kp - 2.0 * big_a * kp)
        / ((5.0 * kp - 2.0) * (1.0 + 2.0 * big_a))
        - 1.0;
    let fd = 6.0 * ((2.0 + kp).powi(2) + a * a * kp * (kp - 1.0 - tan_nu))
        / (a * (2.0 + kp) * (5.0 * kp - 2.0) * (4.0 + 2.0 * (1.0 + tan_nu).powi(2)).sqrt());
    (tan_nu, fd)
}

/// The peak friction angle (degrees) and dilatancy tan ν_p of the peak state at void ratio
/// `e` and mean effective stress `p` (kPa): the K_p whose f_d is the density's, by bisection
/// between φ_c and 60°; `None` where no peak with φ below 60° exists.
pub fn peak_at(law: &HypoplasticSpec, e: f64, p: f64) -> Option<(f64, f64)> {
    let (ec, ed) = (critical_void_ratio(law, p), densest_void_ratio(law, p));
    let want = ((e - ed) / (ec - ed)).max(0.0).powf(law.alpha);
    let k_of = |phi: f64| {
        let s = phi.to_radians().sin();
        (1.0 + s) / (1.0 - s)
    };
    // f_d falls from 1 at φ_c as K_p grows.
    let gap = |phi: f64| peak_relation(law, k_of(phi)).1 - want;
    let (mut lo, mut hi) = (law.friction, 60.0);
    if gap(hi) > 0.0 || gap(lo) < 0.0 {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let phi = 0.5 * (lo + hi);
    Some((phi, peak_relation(law, k_of(phi)).0))
}

/// What a drained triaxial compression of the hypoplastic law shows: its peak, Herle &
/// Gudehus's peak at the same void ratio and pressure, and its end against the critical state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrainedShear {
    /// The peak's mobilised friction angle (degrees).
    pub peak_phi: f64,
    /// The axial strain at the peak.
    pub peak_axial: f64,
    /// The void ratio at the peak.
    pub peak_e: f64,
    /// p' at the peak (kPa).
    pub peak_p: f64,
    /// The dilatancy tan ν = −dε_v / dε_a at the peak.
    pub peak_tan_nu: f64,
    /// Herle & Gudehus's φ_p at the peak's void ratio and pressure ([`peak_at`]).
    pub hg_phi: f64,
    /// Herle & Gudehus's tan ν_p there.
    pub hg_tan_nu: f64,
    /// The axial strain at the end.
    pub end_axial: f64,
    /// The void ratio at the end.
    pub end_e: f64,
    /// The critical void ratio at the end's p'.
    pub end_ec: f64,
    /// The friction angle mobilised at the end (degrees).
    pub end_phi: f64,
    /// The dilatancy at the end.
    pub end_tan_nu: f64,
}

/// The mobilised friction angle (degrees) of a triaxial record: sin φ = (σ1 − σ3)/(σ1 + σ3).
pub fn mobilised(r: &Record) -> f64 {
    let radial = r.axial_stress - r.q;
    ((r.axial_stress - radial) / (r.axial_stress + radial))
        .asin()
        .to_degrees()
}

/// The drained compression `path` of `law` (void ratio in `state[0]`) summed up; `None` for a
/// path too short to have a peak inside it.
pub fn drained_shear(law: &HypoplasticSpec, path: &[Record]) -> Option<DrainedShear> {
    let n = path.len();
    if n < 3 {
        return None;
    }
    let peak = (1..n - 1).max_by(|&a, &b| mobilised(&path[a]).total_cmp(&mobilised(&path[b])))?;
    let tan_nu = |i: usize| {
        let (a, b) = (&path[i - 1], &path[i + 1]);
        -(b.volumetric - a.volumetric) / (b.axial - a.axial)
    };
    let r = &path[peak];
    let (hg_phi, hg_tan_nu) = peak_at(law, r.state[0], r.p)?;
    let end = &path[n - 1];
    Some(DrainedShear {
        peak_phi: mobilised(r),
        peak_axial: r.axial,
        peak_e: r.state[0],
        peak_p: r.p,
        peak_tan_nu: tan_nu(peak),
        hg_phi,
        hg_tan_nu,
        end_axial: end.axial,
        end_e: end.state[0],
        end_ec: critical_void_ratio(law, end.p),
        end_phi: mobilised(end),
        end_tan_nu: tan_nu(n - 2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hochstetten() -> HypoplasticSpec {
        HypoplasticSpec::new(
            [33.0, 1.0e6, 0.25, 0.55, 0.95, 1.05, 0.25, 1.5],
            0.7,
            [0.0, 5.0, 2.0, 0.5, 6.0, 0.0],
            1e-4,
            1.0,
            1000.0,
        )
        .unwrap()
    }

    #[test]
    fn the_peak_relation_gives_phi_c_at_the_critical_density() {
        let law = hochstetten();
        // At φ_c: f_d = 1 and no dilatancy.
        let s = 33f64.to_radians().sin();
        let (tan_nu, fd) = peak_relation(&law, (1.0 + s) / (1.0 - s));
        assert!(
            tan_nu.abs() < 1e-12 && (fd - 1.0).abs() < 1e-12,
            "{tan_nu} {fd}"
        );
        // Herle & Gudehus's table for Hochstetten (r_e = 0.5 at the peak: 45.35°, 0.618).
        let p = 200.0;
        let (ec, ed) = (critical_void_ratio(&law, p), densest_void_ratio(&law, p));
        let (phi, tan_nu) = peak_at(&law, ed + 0.5 * (ec - ed), p).unwrap();
        assert!(
            (phi - 45.35).abs() < 0.01 && (tan_nu - 0.618).abs() < 1e-3,
            "{phi} {tan_nu}"
        );
    }
}
