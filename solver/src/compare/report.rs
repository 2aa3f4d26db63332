//! The comparison as text: a table (one row per output and field), a summary of one line per
//! field for CI logs, the one-line verdict, and JSON.

use std::fmt::Write as _;

use super::stats::{FieldStats, Worst};
use super::{OutputReport, Report};

/// `1.23e-4` style, `0` for zero, for tables.
fn e(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.2e}")
    }
}

fn when(o: &OutputReport) -> String {
    match o.time {
        Some(t) => format!("t = {t} s ({})", o.golden),
        None => o.golden.clone(),
    }
}

/// Where a worst value is, in words: `id 57, element 12, at (0.05, 0.41, 0.05), yy`.
pub fn place(w: &Worst) -> String {
    let mut s = Vec::new();
    if let Some(t) = w.time {
        s.push(format!("t = {t} s"));
    }
    if let Some(id) = w.id {
        s.push(format!("id {id}"));
    }
    if let Some(el) = w.element {
        s.push(format!("element {el}"));
    }
    if let Some([x, y, z]) = w.position {
        s.push(format!("at ({x:.4}, {y:.4}, {z:.4})"));
    }
    s.push(format!(
        "{}: golden {}, candidate {}",
        w.component, w.golden, w.candidate
    ));
    s.join(", ")
}

fn allowed(f: &FieldStats) -> f64 {
    f.tolerance.atol + f.tolerance.rtol * f.scale
}

/// The table: a heading naming both folders, then one row per output and field.
pub fn table(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "golden:    {}\ncandidate: {}", r.golden, r.candidate);
    let _ = writeln!(
        s,
        "{:<10} {:<24} {:<22} {:>9} {:>9} {:>9} {:>9} {:>9}  {:<4}  worst at",
        "time (s)", "output", "field", "max abs", "max rel", "RMS rel", "scale", "allowed", ""
    );
    for (o, f) in r.all() {
        let name = std::path::Path::new(&o.golden)
            .file_name()
            .map_or(o.golden.clone(), |n| n.to_string_lossy().to_string());
        let _ = writeln!(
            s,
            "{:<10} {:<24} {:<22} {:>9} {:>9} {:>9} {:>9} {:>9}  {:<4}  {}",
            o.time.map_or("-".into(), |t| t.to_string()),
            name,
            f.field,
            e(f.max_abs),
            e(f.max_rel),
            e(f.rms_rel),
            e(f.scale),
            e(allowed(f)),
            if f.within { "ok" } else { "FAIL" },
            f.worst.as_ref().map_or(String::new(), place)
        );
    }
    for n in &r.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// One line per field: its worst output, for CI logs.
pub fn summary(r: &Report) -> String {
    let mut s = String::new();
    for (o, f) in r.worst_per_field() {
        let _ = writeln!(
            s,
            "{:<4} {:<22} max {} (rel {}, allowed {}) RMS rel {} at {}{}",
            if f.within { "ok" } else { "FAIL" },
            f.field,
            e(f.max_abs),
            e(f.max_rel),
            e(allowed(f)),
            e(f.rms_rel),
            when(o),
            f.worst
                .as_ref()
                .map_or(String::new(), |w| format!(", {}", place(w)))
        );
    }
    for n in &r.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// The one-line verdict: what was compared, or the first field out of tolerance and where.
pub fn verdict(r: &Report) -> String {
    match r.first_failure() {
        None => format!(
            "within tolerances: {} output(s), {} history file(s) and {} table(s), {} field comparisons",
            r.outputs.len(),
            r.histories.len(),
            r.tables.len(),
            r.all().count()
        ),
        Some((o, f)) => format!(
            "{} differs at {}: max |difference| {} ({} of the field's largest golden |value| {}) > allowed {}{}",
            f.field,
            when(o),
            e(f.max_abs),
            e(f.max_rel),
            e(f.scale),
            e(allowed(f)),
            f.worst
                .as_ref()
                .map_or(String::new(), |w| format!(", worst point {}", place(w)))
        ),
    }
}

/// Version of the layout of `mpm-compare --json`: raised whenever a key is renamed or changes
/// meaning.
pub const JSON_SCHEMA: u32 = 1;

/// The whole report as strict JSON, with `schema_version` first.
pub fn json(r: &Report) -> String {
    /// The report under its layout's version (serde_json writes a non-finite number as null,
    /// so the text stays strict JSON).
    #[derive(serde::Serialize)]
    struct Versioned<'a> {
        schema_version: u32,
        #[serde(flatten)]
        report: &'a Report,
    }
    let v = Versioned {
        schema_version: JSON_SCHEMA,
        report: r,
    };
    let mut s = serde_json::to_string_pretty(&v).expect("plain data serialises");
    s.push('\n');
    s
}
