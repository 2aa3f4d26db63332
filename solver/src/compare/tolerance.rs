//! Tolerances per field: a default and per-field overrides, from the command line or from a
//! small TOML file kept with the golden files (`compare.toml`):
//!
//! ```toml
//! [default]
//! rtol = 1e-6          # relative to the field's largest |value| in the golden output
//! atol = 0.0           # in the field's unit
//!
//! [field.stress]
//! rtol = 1e-4
//!
//! [field.pore_pressure]
//! require = true       # fail (cannot compare) when either side lacks it
//! ```
//!
//! A field is within when its largest difference is at most `atol + rtol × scale`, the scale
//! being the field's largest |value| in the golden output (an `allclose` on the whole field).

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::CompareError;

/// Every field name the comparison knows: material-point fields, CSV column groups, then
/// Anura3D's table fields.
pub const FIELDS: [&str; 17] = [
    "position",
    "displacement",
    "velocity",
    "stress",
    "pore_pressure",
    "history.position",
    "history.displacement",
    "history.stress",
    "history.pore_pressure",
    "energy.kinetic",
    "energy.external_work",
    "bms.position",
    "bms.displacement",
    "bms.stress",
    "bms.pore_pressure",
    "bmr.position",
    "bmr.node_displacement",
];

/// The tolerance applied to one field.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Tolerance {
    /// Relative to the field's largest |value| in the golden output.
    pub rtol: f64,
    /// Absolute, in the field's unit.
    pub atol: f64,
}

impl Tolerance {
    /// True when a largest difference `max_abs` of a field of golden scale `scale` is within.
    /// NaN is never within.
    pub fn allows(&self, max_abs: f64, scale: f64) -> bool {
        max_abs <= self.atol + self.rtol * scale
    }
}

/// One table of the file: any of its keys may be left out.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    rtol: Option<f64>,
    atol: Option<f64>,
    require: Option<bool>,
}

/// The tolerance file's layout.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    default: Entry,
    #[serde(default)]
    field: BTreeMap<String, Entry>,
}

/// The tolerances of a comparison. The default is exact equality: golden files of this solver
/// are byte-reproducible for any thread count.
#[derive(Debug, Clone, Default)]
pub struct Tolerances {
    default: Entry,
    fields: BTreeMap<String, Entry>,
}

fn known(field: &str, origin: &str) -> Result<(), CompareError> {
    if FIELDS.contains(&field) {
        Ok(())
    } else {
        Err(CompareError::Tolerance(format!(
            "{origin}: unknown field '{field}' (known: {})",
            FIELDS.join(", ")
        )))
    }
}

fn check(v: f64, what: &str, origin: &str) -> Result<f64, CompareError> {
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(CompareError::Tolerance(format!(
            "{origin}: {what} must be a finite number ≥ 0, got {v}"
        )))
    }
}

impl Tolerances {
    /// Reads a tolerance file (see the module notes); errors name the file and the key.
    pub fn from_file(path: &Path) -> Result<Self, CompareError> {
        let text = mpm_shared::io::read_parameter_text(path).map_err(|e| {
            let why = e.reason();
            CompareError::Tolerance(format!("{}: cannot read: {why}", path.display()))
        })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Parses a tolerance file's text; `origin` names it in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, CompareError> {
        let f: File = toml::from_str(text)
            .map_err(|e| CompareError::Tolerance(format!("{origin}: {}", e.message())))?;
        let mut t = Tolerances {
            default: f.default,
            fields: BTreeMap::new(),
        };
        for (what, v) in [("rtol", t.default.rtol), ("atol", t.default.atol)] {
            if let Some(v) = v {
                check(v, &format!("[default] {what}"), origin)?;
            }
        }
        for (name, e) in f.field {
            known(&name, origin)?;
            for (what, v) in [("rtol", e.rtol), ("atol", e.atol)] {
                if let Some(v) = v {
                    check(v, &format!("[field.{name}] {what}"), origin)?;
                }
            }
            t.fields.insert(name, e);
        }
        Ok(t)
    }

    /// Sets `rtol` (`atol` when `absolute`) for `field`, or the default when `None`; a value from
    /// the command line replaces the file's at the same level.
    pub fn set(
        &mut self,
        field: Option<&str>,
        absolute: bool,
        value: f64,
    ) -> Result<(), CompareError> {
        let what = if absolute { "--atol" } else { "--rtol" };
        check(value, what, "command line")?;
        let e = match field {
            None => &mut self.default,
            Some(f) => {
                known(f, &format!("command line {what}"))?;
                self.fields.entry(f.to_string()).or_default()
            }
        };
        if absolute {
            e.atol = Some(value);
        } else {
            e.rtol = Some(value);
        }
        Ok(())
    }

    /// Marks `field` as required on both sides.
    pub fn require(&mut self, field: &str) -> Result<(), CompareError> {
        known(field, "command line --require")?;
        self.fields.entry(field.to_string()).or_default().require = Some(true);
        Ok(())
    }

    /// The tolerance for `field`: its own values, else the default's, else 0.
    pub fn of(&self, field: &str) -> Tolerance {
        let own = self.fields.get(field).copied().unwrap_or_default();
        Tolerance {
            rtol: own.rtol.or(self.default.rtol).unwrap_or(0.0),
            atol: own.atol.or(self.default.atol).unwrap_or(0.0),
        }
    }

    /// True when `field` must exist on both sides.
    pub fn required(&self, field: &str) -> bool {
        self.fields
            .get(field)
            .and_then(|e| e.require)
            .or(self.default.require)
            .unwrap_or(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_values_defaults_and_overrides() {
        let mut t = Tolerances::from_toml(
            "[default]\nrtol = 1e-6\n[field.stress]\nrtol = 1e-3\natol = 0.5\n[field.pore_pressure]\nrequire = true\n",
            "compare.toml",
        )
        .unwrap();
        assert_eq!(
            t.of("displacement"),
            Tolerance {
                rtol: 1e-6,
                atol: 0.0
            }
        );
        assert_eq!(
            t.of("stress"),
            Tolerance {
                rtol: 1e-3,
                atol: 0.5
            }
        );
        assert!(t.required("pore_pressure") && !t.required("stress"));
        t.set(None, false, 1e-2).unwrap();
        t.set(Some("stress"), true, 2.0).unwrap();
        assert_eq!(t.of("velocity").rtol, 1e-2);
        assert_eq!(
            t.of("stress"),
            Tolerance {
                rtol: 1e-3,
                atol: 2.0
            }
        );
        assert!(Tolerance {
            rtol: 0.1,
            atol: 0.0
        }
        .allows(1.0, 10.0));
        assert!(!Tolerance {
            rtol: 0.1,
            atol: 0.0
        }
        .allows(f64::NAN, 10.0));
    }

    #[test]
    fn bad_files_name_the_file_and_key() {
        let e = Tolerances::from_toml("[field.strain]\nrtol = 1\n", "g/compare.toml").unwrap_err();
        assert!(
            e.to_string()
                .contains("g/compare.toml: unknown field 'strain'"),
            "{e}"
        );
        let e = Tolerances::from_toml("[default]\nrtol = -1\n", "c.toml").unwrap_err();
        assert!(e.to_string().contains("[default] rtol must be"), "{e}");
        let e = Tolerances::from_toml("[default]\nrtl = 1\n", "c.toml").unwrap_err();
        assert!(e.to_string().contains("c.toml: unknown field `rtl`"), "{e}");
    }
}
