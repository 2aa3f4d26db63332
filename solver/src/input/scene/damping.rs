//! `[damping]`: Anura3D's local damping and the rule it follows.

use serde::Deserialize;

use super::keys::{key, Table};
use super::{refuse, Refusal};
use crate::input::case::DampingRule;

/// The keys of `[damping]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[damping]",
    about: "Local damping (none when the table is left out).",
    keys: &[
        key("local", "float", "required", "", "the local damping coefficient, in [0, 1)"),
        key("rule", "string", "\"phases\"", "", "\"phases\" (the mixture's solid and liquid parts each against its own phase's velocity, the liquid's own force undamped) or \"anura3d\" (Anura3D's rule for GOM input)"),
    ],
};

/// `[damping]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Damping {
    local: f64,
    /// "phases" (default) or "anura3d" (see `case::DampingRule`).
    #[serde(default)]
    rule: Option<String>,
}

/// The local damping coefficient (0 without damping) and its rule.
pub(super) fn resolve(damping: Option<&Damping>) -> Result<(f64, DampingRule), Refusal> {
    let local = damping.map_or(0.0, |d| d.local);
    if !(0.0..1.0).contains(&local) {
        return Err(refuse(
            "damping.local",
            format!("must be in [0, 1), got {local}"),
        ));
    }
    let rule = match damping.and_then(|d| d.rule.as_deref()) {
        None | Some("phases") => DampingRule::Phases,
        Some("anura3d") => DampingRule::Anura3d,
        Some(other) => {
            return Err(refuse(
                "damping.rule",
                format!("expected \"phases\" or \"anura3d\", got \"{other}\""),
            ))
        }
    };
    Ok((local, rule))
}
