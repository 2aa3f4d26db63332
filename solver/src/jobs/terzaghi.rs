//! Terzaghi's 1D consolidation (docs/design.md §6): single drainage at the top of a layer of height H,
//! z measured down from the drained top, T_v = c_v t / H².

use std::f64::consts::PI;

/// Terms summed at most; the series is cut once its terms fall below 1e-14 of the leading one.
const MAX_TERMS: usize = 20_000;

/// Excess pore pressure u(z, T_v) / u0 at relative depth `zeta` = z / H in [0, 1].
pub fn excess_pressure(zeta: f64, tv: f64) -> f64 {
    if tv <= 0.0 {
        return if zeta > 0.0 { 1.0 } else { 0.0 };
    }
    let mut sum = 0.0;
    for m in 0..MAX_TERMS {
        let big_m = PI * (2 * m + 1) as f64 / 2.0;
        let decay = (-big_m * big_m * tv).exp();
        sum += 2.0 / big_m * (big_m * zeta).sin() * decay;
        if decay < 1e-14 {
            break;
        }
    }
    sum
}

/// Average degree of consolidation U(T_v) = 1 - Σ 2/M² exp(-M² T_v).
pub fn degree(tv: f64) -> f64 {
    if tv <= 0.0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for m in 0..MAX_TERMS {
        let big_m = PI * (2 * m + 1) as f64 / 2.0;
        let term = 2.0 / (big_m * big_m) * (-big_m * big_m * tv).exp();
        sum += term;
        if term < 1e-16 {
            break;
        }
    }
    1.0 - sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Classical table: U = 0.5 at T_v = 0.197, U = 0.9 at T_v = 0.848.
        assert!((degree(0.197) - 0.5).abs() < 1e-3);
        assert!((degree(0.848) - 0.9).abs() < 1e-3);
        // Early times: U ≈ sqrt(4 T_v / π).
        let tv = 1e-3;
        assert!((degree(tv) - (4.0 * tv / PI).sqrt()).abs() < 1e-6);
        // Drained top, full pressure deep at early times, zero everywhere late.
        assert!(excess_pressure(0.0, 0.1).abs() < 1e-12);
        assert!((excess_pressure(1.0, 1e-4) - 1.0).abs() < 1e-6);
        assert!(excess_pressure(1.0, 5.0) < 1e-4);
    }

    #[test]
    fn pressure_integrates_to_one_minus_degree() {
        for tv in [0.01, 0.1, 0.5] {
            let n = 2000;
            let mean: f64 = (0..n)
                .map(|k| excess_pressure((k as f64 + 0.5) / n as f64, tv))
                .sum::<f64>()
                / n as f64;
            assert!((mean - (1.0 - degree(tv))).abs() < 1e-5, "T_v = {tv}");
        }
    }
}
