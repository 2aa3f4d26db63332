//! Numbers in words and units for people: durations ("5.911 ms", "3 h 05 min"), sizes
//! ("4.9 GB"), counts ("14,168"), rates ("1.8 M/s"). Files keep full precision; these are for
//! messages, progress lines and summaries.

/// A duration in the unit that reads best: ns … s with four significant digits, then
/// min s, h min, days, years.
pub fn duration(s: f64) -> String {
    if !s.is_finite() {
        return format!("{s} s");
    }
    let a = s.abs();
    const MINUTE: f64 = 60.0;
    const HOUR: f64 = 3600.0;
    const DAY: f64 = 86400.0;
    const YEAR: f64 = 365.25 * DAY;
    if a == 0.0 {
        "0 s".into()
    } else if a < 1e-9 {
        format!("{s:.3e} s")
    } else if a < 1e-6 {
        format!("{} ns", sig4(s * 1e9))
    } else if a < 1e-3 {
        format!("{} µs", sig4(s * 1e6))
    } else if a < 1.0 {
        format!("{} ms", sig4(s * 1e3))
    } else if a < MINUTE {
        format!("{} s", sig4(s))
    } else if a < HOUR {
        let m = (a / MINUTE).floor();
        format!("{m} min {:02} s", (a - m * MINUTE).floor() as u64)
    } else if a < DAY {
        let h = (a / HOUR).floor();
        format!("{h} h {:02} min", ((a - h * HOUR) / MINUTE).floor() as u64)
    } else if a < YEAR {
        format!("{} days", sig3(a / DAY))
    } else {
        format!("{} years", sig3(a / YEAR))
    }
}

/// A byte count in B, kB, MB, GB, TB (powers of 1000), three significant digits.
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 6] = ["B", "kB", "MB", "GB", "TB", "PB"];
    let mut v = b;
    let mut k = 0;
    while v >= 1000.0 && k + 1 < UNITS.len() {
        v /= 1000.0;
        k += 1;
    }
    if k == 0 {
        format!("{} B", v.round())
    } else {
        format!("{} {}", sig3(v), UNITS[k])
    }
}

/// An integer with thousands separators: 14,168. Counts beyond u64 (predicted step counts of a
/// mistyped stiffness) are written in scientific notation.
pub fn count(n: f64) -> String {
    if !(n.is_finite() && n.abs() < 1e18) {
        return format!("{n:.2e}");
    }
    let digits = format!("{}", n.round().abs() as u64);
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    if n < 0.0 {
        out.insert(0, '-');
    }
    out
}

/// A rate of `what` per second with a k/M/G prefix: "1.82 M point-steps/s".
pub fn rate_of(per_second: f64, what: &str) -> String {
    let r = rate(per_second);
    format!("{} {what}/s", r.trim_end_matches("/s").trim_end())
}

/// A rate per second with a k/M/G prefix: "1.82 M/s".
pub fn rate(per_second: f64) -> String {
    let (v, p) = if per_second >= 1e9 {
        (per_second / 1e9, " G")
    } else if per_second >= 1e6 {
        (per_second / 1e6, " M")
    } else if per_second >= 1e3 {
        (per_second / 1e3, " k")
    } else {
        (per_second, " ")
    };
    format!("{}{p}/s", sig3(v))
}

/// Four significant digits, trailing zeros kept (5.911, 12.00, 450.0).
fn sig4(v: f64) -> String {
    sig(v, 4)
}

fn sig3(v: f64) -> String {
    sig(v, 3)
}

fn sig(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if mag >= 6 {
        return format!("{:.*e}", (digits - 1) as usize, v);
    }
    let decimals = (digits - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Ids in a message: "3, 17, 42", the first 20 and how many more.
pub fn list(ids: &[u32]) -> String {
    let mut s: Vec<String> = ids.iter().take(20).map(|i| i.to_string()).collect();
    if ids.len() > 20 {
        s.push(format!("and {} more", ids.len() - 20));
    }
    s.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_in_their_unit() {
        assert_eq!(duration(5.911345e-3), "5.911 ms");
        assert_eq!(duration(9.478e-5), "94.78 µs");
        assert_eq!(duration(2.5e-9), "2.500 ns");
        assert_eq!(duration(3.817e-151), "3.817e-151 s");
        assert_eq!(duration(12.0), "12.00 s");
        assert_eq!(duration(125.4), "2 min 05 s");
        assert_eq!(duration(3.0 * 3600.0 + 5.0 * 60.0 + 3.0), "3 h 05 min");
        assert_eq!(duration(3.0 * 86400.0), "3.00 days");
        assert_eq!(duration(1e30), "3.17e22 years");
        assert_eq!(duration(0.0), "0 s");
    }

    #[test]
    fn sizes_counts_and_rates() {
        assert_eq!(bytes(999.0), "999 B");
        assert_eq!(bytes(4.9e9), "4.90 GB");
        assert_eq!(bytes(16e12), "16.0 TB");
        assert_eq!(count(14168.0), "14,168");
        assert_eq!(count(100.0), "100");
        assert_eq!(count(1234567.0), "1,234,567");
        assert_eq!(count(1.2e150), "1.20e150");
        assert_eq!(rate(1.82e6), "1.82 M/s");
        assert_eq!(rate(950.0), "950 /s");
        assert_eq!(rate_of(1.82e6, "point-steps"), "1.82 M point-steps/s");
        assert_eq!(rate_of(950.0, "steps"), "950 steps/s");
    }
}
