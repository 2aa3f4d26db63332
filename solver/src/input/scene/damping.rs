//! `[damping]`: Anura3D's local damping and the rule it follows, and bulk viscosity.

use serde::Deserialize;

use super::keys::{key, Table};
use super::{refuse, Refusal};
use crate::input::case::DampingRule;
use crate::step::bulk_viscosity::{BulkViscosity, Quadratic};

/// The keys of `[damping]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[damping]",
    about: "Local damping and bulk viscosity (none when the table is left out).",
    keys: &[
        key("local", "float", "0", "", "the local damping coefficient, in [0, 1)"),
        key("rule", "string", "\"phases\"", "", "\"phases\" (the mixture's solid and liquid parts each against its own phase's velocity, the liquid's own force undamped) or \"anura3d\" (Anura3D's rule for GOM input)"),
        key("bulk_viscosity", "[float, float]", "none", "", "[b1, b2]: a viscous pressure b1 ρ c L ε̇_v, and ρ (b2 L ε̇_v)² resisting compression, added to each point's normal stresses in the internal force (Anura3D's BULK_VISCOSITY_DAMPING; L the element's smallest altitude); e.g. [0.06, 1.2]"),
    ],
};

/// `[damping]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Damping {
    #[serde(default)]
    local: f64,
    /// "phases" (default) or "anura3d" (see `case::DampingRule`).
    #[serde(default)]
    rule: Option<String>,
    /// [b1, b2] of the bulk viscosity.
    #[serde(default)]
    bulk_viscosity: Option<[f64; 2]>,
}

/// What `[damping]` resolves to.
pub(super) struct Resolved {
    /// The local damping coefficient (0 without damping).
    pub local: f64,
    /// Its rule.
    pub rule: DampingRule,
    /// The bulk viscosity, where asked for.
    pub bulk: Option<BulkViscosity>,
}

/// The local damping coefficient (0 without damping), its rule and the bulk viscosity.
pub(super) fn resolve(damping: Option<&Damping>) -> Result<Resolved, Refusal> {
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
    let bulk = match damping.and_then(|d| d.bulk_viscosity) {
        None => None,
        Some([b1, b2]) => {
            if !(b1 >= 0.0 && b2 >= 0.0 && b1.is_finite() && b2.is_finite() && b1 + b2 > 0.0) {
                return Err(refuse(
                    "damping.bulk_viscosity",
                    format!(
                        "expected [b1, b2], both finite and >= 0, not both 0; got [{b1}, {b2}]"
                    ),
                ));
            }
            Some(BulkViscosity {
                linear: b1,
                quadratic: b2,
                sign: Quadratic::Resisting,
            })
        }
    };
    Ok(Resolved { local, rule, bulk })
}
