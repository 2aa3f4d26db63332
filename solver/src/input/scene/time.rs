//! `[time]`: the simulated time, the output times and the Courant number.

use serde::Deserialize;

use super::keys::{key, Table};
use super::{refuse, Refusal};
use crate::driver::units;
use crate::input::preflight::MAX_OUTPUTS;

/// The keys of `[time]`.
#[rustfmt::skip]
pub(super) const TABLE: Table = Table {
    header: "[time]",
    about: "How long to simulate and when to write outputs (a consolidation scene may give \
            both by time factor instead: `[consolidation]`).",
    keys: &[
        key("end", "float", "required (or `consolidation.end_tv`)", "s", "the simulated time"),
        key("courant", "float", "0.9", "", "Courant number of the time step, in (0, 1] (above 1 only with --force)"),
        key("output_interval", "float", "required (or `consolidation.output_tv`)", "s", "time between outputs (the last one is at `end`)"),
        key("max_steps", "integer", "none", "", "stop after this many time steps"),
        key("mass_scaling", "float", "1", "", "Anura3D's mass scaling: the nodal accelerations are the forces over this factor times the mass, so the step grows by its square root; ≥ 1, dry materials only (run.json reports the physical kinetic energy and, under `energy.mass_scaling`, the scaled mass's)"),
        key("scheme", "string", "\"explicit\"", "", "`explicit` or `semi-implicit`: the pore pressure solved for on the nodes each step, so that the step follows the skeleton's wave speed instead of the pore water's (saturated materials; docs/design.md §4.4c); the command line's `--scheme` overrides it"),
        key("pressure_tolerance", "float", "1e-8", "", "the semi-implicit pressure solve's relative residual, in (0, 1e-3]"),
    ],
};

/// `[time]` as the scene gives it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Time {
    #[serde(default)]
    end: Option<f64>,
    #[serde(default = "default_courant")]
    pub courant: f64,
    #[serde(default)]
    output_interval: Option<f64>,
    #[serde(default)]
    pub max_steps: Option<u64>,
    #[serde(default = "no_scaling")]
    pub mass_scaling: f64,
    #[serde(default)]
    scheme: SchemeName,
    #[serde(default = "default_tolerance")]
    pressure_tolerance: f64,
}

/// `time.scheme`'s values.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum SchemeName {
    #[default]
    Explicit,
    SemiImplicit,
}

fn default_tolerance() -> f64 {
    crate::step::semi_implicit::DEFAULT_TOLERANCE
}

impl Time {
    /// The scheme the scene asks for.
    pub fn scheme(&self) -> crate::input::case::Scheme {
        use crate::input::case::Scheme;
        match self.scheme {
            SchemeName::Explicit => Scheme::Explicit,
            SchemeName::SemiImplicit => Scheme::SemiImplicit {
                tolerance: self.pressure_tolerance,
            },
        }
    }
}

fn no_scaling() -> f64 {
    1.0
}

fn default_courant() -> f64 {
    0.9
}

/// Refuses a Courant number that is not positive and finite (above 1 is refused before the
/// run unless --force: `Case::check_courant`).
pub(super) fn check_courant(t: &Time) -> Result<(), Refusal> {
    if !(t.courant > 0.0 && t.courant.is_finite()) {
        return Err(refuse(
            "time.courant",
            format!("must be in (0, 1], got {}", t.courant),
        ));
    }
    if !(t.mass_scaling >= 1.0 && t.mass_scaling.is_finite()) {
        return Err(refuse(
            "time.mass_scaling",
            format!("must be a finite factor ≥ 1, got {}", t.mass_scaling),
        ));
    }
    if !(t.pressure_tolerance > 0.0 && t.pressure_tolerance <= 1e-3) {
        return Err(refuse(
            "time.pressure_tolerance",
            format!("must be in (0, 1e-3], got {}", t.pressure_tolerance),
        ));
    }
    Ok(())
}

/// The run's end and output times.
pub(super) struct Times {
    /// End time (s).
    pub end: f64,
    /// Output times (s), the last one at `end`.
    pub outputs: Vec<f64>,
}

/// The end and output times: `by_time_factor`'s (end, interval) where a consolidation scene
/// gives them, else `[time]`'s; at most [`MAX_OUTPUTS`] outputs.
pub(super) fn resolve(
    t: &Time,
    by_time_factor: (Option<f64>, Option<f64>),
) -> Result<Times, Refusal> {
    let end = by_time_factor.0.or(t.end).unwrap_or(0.0);
    let interval = by_time_factor.1.or(t.output_interval).unwrap_or(0.0);
    if !(end > 0.0) {
        return Err(refuse(
            "time.end",
            format!("must be given and positive, got {end}"),
        ));
    }
    if !(interval > 0.0) {
        return Err(refuse(
            "time.output_interval",
            format!("must be given and positive, got {interval}"),
        ));
    }
    let n_out = (end / interval).round().max(1.0);
    if n_out > MAX_OUTPUTS {
        return Err(refuse(
            "time.output_interval",
            format!(
                "{} asks for {} outputs over {}; at most {} are allowed (each writes a particle file): give a longer interval",
                units::duration(interval),
                units::count(n_out),
                units::duration(end),
                units::count(MAX_OUTPUTS)
            ),
        ));
    }
    let n_out = n_out as usize;
    let outputs = (1..=n_out)
        .map(|k| {
            if k == n_out {
                end
            } else {
                (k as f64 * interval).min(end)
            }
        })
        .collect();
    Ok(Times { end, outputs })
}
