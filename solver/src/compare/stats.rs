//! Streaming statistics of one field's differences: largest and RMS difference and where the
//! largest is, accumulated value by value so that no output is held twice.

use serde::Serialize;

use super::tolerance::Tolerance;

/// Where a field's largest difference is.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Worst {
    /// The material point's id (for a history row, the probe's id), when known.
    pub id: Option<u64>,
    /// The element holding the point (1-based), when a side reports it.
    pub element: Option<u64>,
    /// The point's position in the golden output, when known.
    pub position: Option<[f64; 3]>,
    /// The time of the row, for CSV histories.
    pub time: Option<f64>,
    /// The component (`yy`, `x`, ...) or CSV column.
    pub component: String,
    /// The golden value.
    pub golden: f64,
    /// The candidate's value.
    pub candidate: f64,
}

/// Accumulates one field over the points of an output (or the rows of a CSV file).
#[derive(Debug, Clone, Default)]
pub struct Accumulator {
    count: u64,
    sum_sq: f64,
    max_abs: f64,
    scale: f64,
    worst: Option<Worst>,
}

impl Accumulator {
    /// Adds one golden value `a` and its candidate `b`; `at` describes the place, called only
    /// when this is the largest difference so far (NaN counts as the largest possible).
    pub fn add(&mut self, a: f64, b: f64, at: impl FnOnce() -> Worst) {
        let d = (a - b).abs();
        let d = if d.is_nan() { f64::INFINITY } else { d };
        self.count += 1;
        self.sum_sq += d * d;
        self.scale = self.scale.max(a.abs());
        if d > self.max_abs || (self.worst.is_none() && d > 0.0) {
            self.max_abs = d;
            self.worst = Some(at());
        }
    }

    /// The statistics, judged against `tol`.
    pub fn finish(self, field: &str, tol: Tolerance) -> FieldStats {
        let rms_abs = if self.count > 0 {
            (self.sum_sq / self.count as f64).sqrt()
        } else {
            0.0
        };
        // An all-zero golden field: relative figures are absolute ones (scale 1).
        let unit = if self.scale > 0.0 { self.scale } else { 1.0 };
        FieldStats {
            field: field.to_string(),
            values: self.count,
            max_abs: self.max_abs,
            rms_abs,
            scale: self.scale,
            max_rel: self.max_abs / unit,
            rms_rel: rms_abs / unit,
            tolerance: tol,
            within: tol.allows(self.max_abs, self.scale),
            worst: self.worst,
        }
    }
}

/// One field of one output compared.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldStats {
    /// The field's name (see [`super::tolerance::FIELDS`]).
    pub field: String,
    /// Values compared (points × components).
    pub values: u64,
    /// Largest |golden - candidate|.
    pub max_abs: f64,
    /// Root mean square of the differences.
    pub rms_abs: f64,
    /// The field's largest |value| in the golden output.
    pub scale: f64,
    /// `max_abs / scale` (scale 1 when the golden field is all zeros).
    pub max_rel: f64,
    /// `rms_abs / scale`.
    pub rms_rel: f64,
    /// The tolerance applied.
    pub tolerance: Tolerance,
    /// True when `max_abs <= atol + rtol × scale`.
    pub within: bool,
    /// Where the largest difference is (none when every value agrees).
    pub worst: Option<Worst>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn here(c: &str) -> impl FnOnce() -> Worst + '_ {
        move || Worst {
            id: Some(1),
            element: None,
            position: None,
            time: None,
            component: c.into(),
            golden: 0.0,
            candidate: 0.0,
        }
    }

    #[test]
    fn max_rms_scale_and_worst() {
        let mut a = Accumulator::default();
        a.add(10.0, 10.0, here("x"));
        a.add(-20.0, -19.0, here("y"));
        a.add(5.0, 5.5, here("z"));
        let s = a.finish(
            "displacement",
            Tolerance {
                rtol: 0.04,
                atol: 0.0,
            },
        );
        assert_eq!((s.max_abs, s.scale, s.values), (1.0, 20.0, 3));
        assert!((s.rms_abs - (1.25f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(s.max_rel, 0.05);
        assert!(!s.within);
        assert_eq!(s.worst.unwrap().component, "y");
        let mut z = Accumulator::default();
        z.add(1.0, f64::NAN, here("x"));
        let s = z.finish(
            "stress",
            Tolerance {
                rtol: 1.0,
                atol: 1.0,
            },
        );
        assert!(!s.within && s.max_abs.is_infinite());
        let s = Accumulator::default().finish("stress", Tolerance::default());
        assert!(s.within && s.worst.is_none());
    }
}
