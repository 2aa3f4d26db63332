//! A run against the material points Anura3D reports in a benchmark's `*_expected.BMS`: for
//! every reported point, position, displacement, the six stresses and the pore pressure at the
//! reported time.
//!
//! Each difference is taken relative to the expected value, or, for values near zero, to 1e-3
//! of the largest |value| of its field (the position, displacement or stress columns together;
//! Anura3D prints round-off such as 1e-27 where the answer is 0), with a floor of 1e-10
//! (1e-20 m for displacements). The report prints 4 significant digits, so 1 % is the
//! usual tolerance.

use mpm_shared::bms::{Bms, MaterialPointRecord};

use crate::driver::engine::Engine;
use crate::element::Element;
use crate::real::Real;

/// The compared columns of the `.BMS`, in the order of [`values_of`].
pub const COLUMNS: [&str; 13] = [
    "X",
    "Y",
    "Z",
    "Ux",
    "Uy",
    "Uz",
    "SigmaXX",
    "SigmaYY",
    "SigmaZZ",
    "SigmaXY",
    "SigmaYZ",
    "SigmaZX",
    "WPressure",
];

/// The columns of the field column `c` belongs to (indices into [`COLUMNS`]).
fn field_columns(c: usize) -> std::ops::Range<usize> {
    match c {
        0..3 => 0..3,
        3..6 => 3..6,
        6..12 => 6..12,
        _ => 12..13,
    }
}

/// The compared values of a reported point, in the order of [`COLUMNS`].
pub fn values_of(r: &MaterialPointRecord) -> [f64; 13] {
    let mut v = [0.0; 13];
    v[..3].copy_from_slice(&r.position);
    v[3..6].copy_from_slice(&r.displacement);
    v[6..12].copy_from_slice(&r.stress);
    v[12] = r.pore_pressure;
    v
}

/// Where the largest deviation is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worst {
    /// The material point id.
    pub id: u32,
    /// The column ([`COLUMNS`]).
    pub column: &'static str,
    /// This solver's value.
    pub ours: f64,
    /// Anura3D's value.
    pub expected: f64,
}

/// The outcome of [`compare`].
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Reported points compared (those of the last load step in the file).
    pub points: usize,
    /// The time the report is for (s).
    pub expected_time: f64,
    /// The run's time (s).
    pub time: f64,
    /// The largest deviation, each relative to its value or, near zero, to 1e-3 of the
    /// largest |value| of its field (see the module notes); 0 when nothing was compared.
    pub worst: f64,
    /// Where [`Comparison::worst`] is.
    pub worst_at: Option<Worst>,
    /// The largest plain relative difference among values that are not near zero.
    pub worst_plain: f64,
    /// Reported ids the run does not have.
    pub missing: Vec<u32>,
}

impl Comparison {
    /// True when the run ended within 0.1 % of the reported time.
    pub fn time_matches(&self) -> bool {
        (self.time - self.expected_time).abs() <= 1e-3 * self.expected_time.abs().max(1e-300)
    }

    /// True when every reported point is there, at the reported time, within `tolerance`
    /// (0.01 for 1 %).
    pub fn reproduced(&self, tolerance: f64) -> bool {
        self.points > 0 && self.missing.is_empty() && self.time_matches() && self.worst <= tolerance
    }
}

/// Compares the final state of `engine` with the points `expected` reports at its last load
/// step.
pub fn compare<R: Real, E: Element>(engine: &Engine<R, E>, expected: &Bms) -> Comparison {
    let records = expected.records();
    let last = records.iter().map(|r| r.load_step).max().unwrap_or(0);
    let rows: Vec<&MaterialPointRecord> = records.iter().filter(|r| r.load_step == last).collect();
    // Each field's scale (position, displacement, stress, pore pressure: the largest |value|
    // of its columns): values far below it are round-off in Anura3D's report, such as the
    // 1e-21 m a 2D footing case reports for the horizontal displacement of points that move
    // down by 1e-3 m.
    let mut scale = [0.0f64; 13];
    for r in &rows {
        for (c, v) in values_of(r).into_iter().enumerate() {
            for s in &mut scale[field_columns(c)] {
                *s = s.max(v.abs());
            }
        }
    }
    let p = &engine.particles;
    let index: std::collections::HashMap<u32, usize> =
        p.id.iter().enumerate().map(|(i, &id)| (id, i)).collect();
    let mut out = Comparison {
        points: rows.len(),
        expected_time: rows.first().map_or(0.0, |r| r.time),
        time: engine.time,
        worst: 0.0,
        worst_at: None,
        worst_plain: 0.0,
        missing: Vec::new(),
    };
    for r in rows {
        let Some(&i) = index.get(&r.id) else {
            out.missing.push(r.id);
            continue;
        };
        let pore = p.liquid.as_ref().map_or(0.0, |l| l.p[i].f64());
        let mut ours = [0.0; 13];
        let x = engine.mesh.global(&p.x[i]);
        for d in 0..3 {
            ours[d] = x[d];
            ours[3 + d] = p.u[i][d].f64();
        }
        for c in 0..6 {
            ours[6 + c] = p.stress[i][c].f64();
        }
        ours[12] = pore;
        for (c, want) in values_of(r).into_iter().enumerate() {
            let err = (ours[c] - want).abs();
            // Displacements get a far lower absolute floor than the other columns: 4006's are
            // 2e-16 m after its 1e-15 s step, while its stresses of 1e-28 kPa are round-off.
            let absolute = if (3..6).contains(&c) { 1e-20 } else { 1e-10 };
            let floor = (1e-3 * scale[c]).max(absolute);
            let d = err / want.abs().max(floor);
            // NaN counts as the worst possible.
            if d.is_nan() || d > out.worst {
                out.worst = if d.is_nan() { f64::INFINITY } else { d };
                out.worst_at = Some(Worst {
                    id: r.id,
                    column: COLUMNS[c],
                    ours: ours[c],
                    expected: want,
                });
            }
            if want.abs() > floor {
                out.worst_plain = out.worst_plain.max(err / want.abs());
            }
        }
    }
    out
}
