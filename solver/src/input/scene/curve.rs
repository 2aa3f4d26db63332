//! Load curves in scenes: a `curve` key (a table of [time, multiplier] pairs, or a CSV file of
//! them) on `[[traction]]`, `[gravity]` and `[[velocity]]`, and the `hammer` of `[[traction]]`
//! ([`crate::step::load_curve`]).

use std::path::Path;
use std::sync::Arc;

use serde::Deserialize;

use super::{refuse, Refusal};
use crate::step::load_curve::{Blow, LoadCurve};

/// The `curve` key's help, shared by the tables that take it.
pub(super) const CURVE_HELP: &str = "a multiplier over time instead of `ramp`: [[t, m], ...] \
    (s, multiplier; linear between, held before the first and after the last) or the path of a \
    CSV file of such rows, relative to the scene";

/// The curve a `curve` key gives: inline rows, or a CSV file relative to `scene_dir`; `item`
/// names the key in refusals.
pub(super) fn resolve(
    value: &toml::Value,
    scene_dir: &Path,
    item: &str,
) -> Result<LoadCurve, Refusal> {
    let rows = match value {
        toml::Value::Array(rows) => rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                inline_row(row).ok_or_else(|| {
                    refuse(
                        item,
                        format!(
                            "row {}: expected [time, multiplier], two numbers, got {row}",
                            i + 1
                        ),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?,
        toml::Value::String(file) => read_csv(&scene_dir.join(file), item)?,
        other => {
            return Err(refuse(
                item,
                format!("expected [[t, m], ...] or the name of a CSV file, got {other}"),
            ))
        }
    };
    checked(rows, item)
}

/// An inline `[t, m]` row (integers or floats).
fn inline_row(row: &toml::Value) -> Option<(f64, f64)> {
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    match row.as_array()?.as_slice() {
        [t, m] => Some((number(t)?, number(m)?)),
        _ => None,
    }
}

/// The rows of a CSV file: `time, multiplier` per line (commas or white space), `#` comments
/// and blank lines skipped, a header allowed on the first line.
fn read_csv(path: &Path, item: &str) -> Result<Vec<(f64, f64)>, Refusal> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| refuse(item, format!("{}: {e}", path.display())))?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        match crate::step::load_curve::parse_row(line, true) {
            Some(row) => rows.push(row),
            // A header: only before any row.
            None if rows.is_empty() && i == 0 => {}
            None => {
                return Err(refuse(
                    item,
                    format!(
                        "{}:{}: expected two numbers, time and multiplier, got \"{line}\"",
                        path.display(),
                        i + 1
                    ),
                ))
            }
        }
    }
    Ok(rows)
}

/// The table of `rows`, refused unless it has a row, every value is finite and the times
/// increase.
fn checked(rows: Vec<(f64, f64)>, item: &str) -> Result<LoadCurve, Refusal> {
    if rows.is_empty() {
        return Err(refuse(
            item,
            "no rows: give at least one [time, multiplier]",
        ));
    }
    if let Some(i) = rows
        .iter()
        .position(|(t, m)| !(t.is_finite() && m.is_finite()))
    {
        return Err(refuse(
            item,
            format!("row {}: {:?} is not finite", i + 1, rows[i]),
        ));
    }
    if let Some(i) = rows.windows(2).position(|w| w[1].0 <= w[0].0) {
        return Err(refuse(
            item,
            format!(
                "row {}: time {} does not follow {}: times must increase",
                i + 2,
                rows[i + 1].0,
                rows[i].0
            ),
        ));
    }
    Ok(LoadCurve::Table(Arc::from(rows)))
}

/// A `[[traction]]`'s `hammer`: blows of a ram on the group, as a pressure pushing into the
/// body whose peak is Z v₀ / A (A the group's area).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Hammer {
    /// The ram's mass (t).
    pub ram_mass: f64,
    /// Its speed at impact (m/s).
    pub velocity: f64,
    /// The pile's impedance Z = E A / c (kN·s/m).
    pub impedance: f64,
    /// Stiffness of a cushion between ram and pile (kN/m); none by default.
    #[serde(default)]
    pub cushion: Option<f64>,
    /// Blows.
    #[serde(default = "one_blow")]
    pub blows: u32,
    /// Seconds between blows (required with more than one).
    #[serde(default)]
    pub interval: Option<f64>,
    /// The time of the first blow (s): the model may settle under its weight before it.
    #[serde(default)]
    pub first: f64,
}

fn one_blow() -> u32 {
    1
}

impl Hammer {
    /// The blows' multiplier and their peak force Z v₀ (kN), refused when a value is out of
    /// range.
    pub fn resolve(&self, item: &str) -> Result<(LoadCurve, f64), Refusal> {
        for (name, v) in [
            ("ram_mass", self.ram_mass),
            ("velocity", self.velocity),
            ("impedance", self.impedance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(refuse(
                    format!("{item}.{name}"),
                    format!("{v}: expected a positive number"),
                ));
            }
        }
        if let Some(k) = self.cushion.filter(|k| !(k.is_finite() && *k > 0.0)) {
            return Err(refuse(
                format!("{item}.cushion"),
                format!("{k}: expected a positive stiffness"),
            ));
        }
        let interval = match (self.blows, self.interval) {
            (0, _) => {
                return Err(refuse(
                    format!("{item}.blows"),
                    "expected at least one blow",
                ))
            }
            (_, Some(t)) if t.is_finite() && t > 0.0 => t,
            (_, Some(t)) => {
                return Err(refuse(
                    format!("{item}.interval"),
                    format!("{t}: expected a positive time"),
                ))
            }
            (1, None) => f64::INFINITY,
            (n, None) => {
                return Err(refuse(
                    format!("{item}.interval"),
                    format!("{n} blows need the seconds between them"),
                ))
            }
        };
        if !(self.first.is_finite() && self.first >= 0.0) {
            return Err(refuse(
                format!("{item}.first"),
                format!("{}: expected a time of 0 or more", self.first),
            ));
        }
        let curve = LoadCurve::Blows {
            blow: Blow::new(self.ram_mass, self.impedance, self.cushion),
            first: self.first,
            interval,
            count: self.blows,
        };
        Ok((curve, self.impedance * self.velocity))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(text: &str) -> toml::Value {
        text.parse::<toml::Table>().unwrap()["curve"].clone()
    }

    #[test]
    fn inline_rows_and_csv_files_make_the_same_table() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("c.csv"),
            "time,multiplier\n0, 0\n# rise\n0.5 1\n\n1,0.25\n",
        )
        .unwrap();
        let inline = resolve(
            &value("curve = [[0, 0], [0.5, 1.0], [1, 0.25]]"),
            dir.path(),
            "c",
        )
        .unwrap();
        let file = resolve(&value("curve = \"c.csv\""), dir.path(), "c").unwrap();
        assert_eq!(inline, file);
        assert_eq!(file.at(0.75), 0.625);
    }

    #[test]
    fn bad_tables_are_refused_naming_the_row() {
        let dir = tempfile::tempdir().unwrap();
        let err = |text: &str| {
            let e = resolve(&value(text), dir.path(), "traction \"top\".curve").unwrap_err();
            format!("{}: {}", e.item, e.message)
        };
        assert!(err("curve = [[0, 0], [0, 1]]").contains("row 2: time 0 does not follow 0"));
        assert!(err("curve = [[0, 0, 1]]").contains("row 1: expected [time, multiplier]"));
        assert!(err("curve = []").contains("no rows"));
        assert!(err("curve = 3").contains("expected [[t, m], ...]"));
        assert!(err("curve = \"missing.csv\"").contains("missing.csv"));
        std::fs::write(dir.path().join("bad.csv"), "0,0\n1,x\n").unwrap();
        assert!(err("curve = \"bad.csv\"").contains("bad.csv:2: expected two numbers"));
    }

    #[test]
    fn a_hammer_gives_blows_and_their_peak() {
        let h: Hammer = toml::from_str(
            "ram_mass = 2.0\nvelocity = 3.0\nimpedance = 400.0\nblows = 2\ninterval = 0.5",
        )
        .unwrap();
        let (curve, peak) = h.resolve("traction \"head\".hammer").unwrap();
        assert_eq!(peak, 1200.0);
        assert_eq!(curve.at(0.5), 1.0);
        let many: Hammer =
            toml::from_str("ram_mass = 2.0\nvelocity = 3.0\nimpedance = 400.0\nblows = 2").unwrap();
        let e = many.resolve("h").unwrap_err();
        assert!(e.message.contains("2 blows need"), "{}", e.message);
    }
}
