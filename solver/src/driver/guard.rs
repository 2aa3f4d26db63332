//! The guard rails' diagnosis (docs/design.md §4.14): once a check has tripped, which point,
//! element or node, which field and value, and the likely cause. Detection is folded into the
//! step's passes (`Engine::check_step`); this runs only on a failure, so it may be slow.

use std::fmt;

use crate::real::Real;
use crate::state::grid::Grid;
use crate::state::particles::Particles;

/// Which guard rail tripped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// A non-finite value in a point or node field.
    NonFinite,
    /// A point whose volume collapsed (V/V0 at most the limit, det F <= 0 included).
    Volume,
    /// Kinetic energy beyond what the work done could give, and growing.
    BlowUp,
    /// The energy balance off by more than the tolerance.
    EnergyBalance,
    /// A point flung out of the mesh by an unstable step (a run forced past Courant 1, or a
    /// point that moved more than its element's size in one step), found by the locate pass
    /// whether or not the guard rails are on.
    Escaped,
}

impl Check {
    /// The name in messages and `run.json`.
    pub fn name(self) -> &'static str {
        match self {
            Check::NonFinite => "non_finite",
            Check::Volume => "volume",
            Check::BlowUp => "blow_up",
            Check::EnergyBalance => "energy_balance",
            Check::Escaped => "escaped",
        }
    }
}

/// Why and where a run diverged.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    /// The check that tripped.
    pub check: Check,
    /// Time step number (1-based).
    pub step: u64,
    /// Simulated time at the end of that step (s).
    pub time: f64,
    /// Material point id (input numbering), where one is to blame.
    pub point: Option<u32>,
    /// Element (1-based, input numbering) of that point.
    pub element: Option<u32>,
    /// Node (input number), for a non-finite nodal value.
    pub node: Option<u32>,
    /// The field (`stress`, `velocity`, `position`, `pore_pressure`, `volume_ratio`,
    /// `kinetic_energy`, `energy_balance`, `node_velocity`, ...).
    pub field: &'static str,
    /// Its value (the first non-finite component; the volume ratio; the total kinetic energy
    /// in kJ; the relative balance error).
    pub value: f64,
    /// The likely cause, in words.
    pub cause: String,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "run diverged at step {} (t = {} s): check {} tripped, {} = {}",
            self.step,
            self.time,
            self.check.name(),
            self.field,
            self.value
        )?;
        if let (Some(p), Some(e)) = (self.point, self.element) {
            write!(f, " at material point {p} in element {e}")?;
        }
        if let Some(n) = self.node {
            write!(f, " at node {n}")?;
        }
        write!(f, "; likely cause: {}", self.cause)
    }
}

impl std::error::Error for Divergence {}

/// |kinetic + strain + dissipated - work - initial kinetic| over the largest of |work|,
/// kinetic + |strain| + dissipated, the initial kinetic energy and `stored`, the elastic energy
/// the initial stresses hold (0 while all are 0). An initially stressed body at rest balances
/// the work of its loads against σ0 : Δε, both at round-off there: measured against them alone
/// the balance would be noise; `stored` is the scale of what it could release.
pub fn balance_error(
    kinetic: f64,
    strain: f64,
    dissipated: f64,
    work: f64,
    k0: f64,
    stored: f64,
) -> f64 {
    let scale = work
        .abs()
        .max(kinetic + strain.abs() + dissipated)
        .max(k0)
        .max(stored);
    if scale > 0.0 {
        (kinetic + strain + dissipated - work - k0).abs() / scale
    } else {
        0.0
    }
}

/// What the diagnosis reads of the engine.
pub struct View<'a, R: Real> {
    /// The points.
    pub particles: &'a Particles<R>,
    /// The nodes.
    pub grid: &'a Grid<R>,
    /// Input element (0-based) per local element.
    pub input_element: &'a [u32],
    /// Input node number per computational node.
    pub input_node: &'a [u32],
    /// Mass per initial volume per material.
    pub initial_density: &'a [R],
    /// The Courant number.
    pub courant: f64,
    /// The element (input number) that sets the critical step.
    pub critical_element: u32,
    /// Step number.
    pub step: u64,
    /// Time (s).
    pub time: f64,
    /// Kinetic energy after the step (kJ).
    pub kinetic: f64,
    /// The relative energy-balance error.
    pub balance_error: f64,
    /// The balance tolerance.
    pub tolerance: Option<f64>,
}

/// The first non-finite value among a point's fields.
fn bad_point_field<R: Real>(p: &Particles<R>, i: usize) -> Option<(&'static str, f64)> {
    let first = |vals: &[R]| vals.iter().map(|v| v.f64()).find(|v| !v.is_finite());
    if let Some(v) = first(&p.x[i]) {
        return Some(("position", v));
    }
    if let Some(v) = first(&p.v[i]) {
        return Some(("velocity", v));
    }
    if let Some(v) = first(&p.stress[i]) {
        return Some(("stress", v));
    }
    if let Some(l) = &p.liquid {
        if let Some(v) = first(&[l.p[i]]) {
            return Some(("pore_pressure", v));
        }
    }
    if let Some(v) = first(&[p.volume[i]]) {
        return Some(("volume", v));
    }
    None
}

/// The first non-finite value among a node's fields.
fn bad_node_field<R: Real>(g: &Grid<R>, n: usize) -> Option<(&'static str, f64)> {
    let first = |vals: &[R]| vals.iter().map(|v| v.f64()).find(|v| !v.is_finite());
    let fields: [(&'static str, &[R]); 6] = [
        ("node_mass", std::slice::from_ref(&g.mass[n])),
        ("node_momentum", &g.momentum[n]),
        ("node_internal_force", &g.f_int[n]),
        ("node_external_force", &g.f_ext[n]),
        ("node_acceleration", &g.acc[n]),
        ("node_velocity", &g.vel[n]),
    ];
    fields
        .into_iter()
        .find_map(|(name, vals)| first(vals).map(|v| (name, v)))
}

fn short(x: f64) -> String {
    let r = (x * 100.0).round() / 100.0;
    format!("{r}")
}

/// Which point, element or node, which field and value, and the likely cause.
pub fn diagnose<R: Real>(check: Check, v: &View<'_, R>) -> Divergence {
    let p = v.particles;
    let active = || (0..p.len()).filter(|&i| p.active[i]);
    let mut out = Divergence {
        check,
        step: v.step,
        time: v.time,
        point: None,
        element: None,
        node: None,
        field: "",
        value: f64::NAN,
        cause: String::new(),
    };
    let at_point = |out: &mut Divergence, i: usize| {
        out.point = Some(p.id[i]);
        out.element = Some(v.input_element[p.element[i] as usize] + 1);
    };
    let ratio =
        |i: usize| (p.volume[i] * v.initial_density[p.material[i] as usize] / p.mass[i]).f64();
    match check {
        Check::NonFinite => {
            if let Some((i, (field, value))) =
                active().find_map(|i| bad_point_field(p, i).map(|b| (i, b)))
            {
                at_point(&mut out, i);
                (out.field, out.value) = (field, value);
            } else if let Some((n, (field, value))) =
                (0..v.grid.mass.len()).find_map(|n| bad_node_field(v.grid, n).map(|b| (n, b)))
            {
                out.node = Some(v.input_node[n]);
                (out.field, out.value) = (field, value);
            }
        }
        Check::Volume => {
            let i = active()
                .min_by(|&a, &b| ratio(a).total_cmp(&ratio(b)))
                .unwrap_or(0);
            at_point(&mut out, i);
            (out.field, out.value) = ("volume_ratio", ratio(i));
        }
        Check::BlowUp => {
            let k = |i: usize| {
                0.5 * p.mass[i].f64() * p.v[i].iter().map(|x| x.f64() * x.f64()).sum::<f64>()
            };
            if let Some(i) = active().max_by(|&a, &b| k(a).total_cmp(&k(b))) {
                at_point(&mut out, i);
            }
            (out.field, out.value) = ("kinetic_energy", v.kinetic);
        }
        Check::EnergyBalance => {
            (out.field, out.value) = ("energy_balance", v.balance_error);
        }
        // Diagnosed where the point is found outside (the engine's locate), not here.
        Check::Escaped => out.field = "step_displacement",
    }
    let (c, el) = (short(v.courant), v.critical_element);
    // Under a forced Courant number above 1, whatever trips first (a collapsing point, a
    // blow-up, a NaN) is the step's doing.
    out.cause = if v.courant > 1.0 {
        format!(
            "time step {c}× the critical step of element {el} (Courant number above 1, run under --force)"
        )
    } else {
        match check {
            Check::NonFinite | Check::BlowUp => format!(
                "an instability the time step ({c}× the critical step of element {el}) does not explain: a material too soft for its load, a badly shaped element, or loads applied too fast"
            ),
            Check::Volume => format!(
                "the point is crushed to {:.3e} of its initial volume (det F <= 0 when not positive): the material is too soft for its load, or the mesh too coarse where it is loaded",
                out.value
            ),
            Check::EnergyBalance => format!(
                "energy not conserved within the tolerance {}: the time step ({c}× the critical step of element {el}) may be too close to the limit, or one point per element too few for a sudden load (docs/stability.md); lower the Courant number, add points or damping, or loosen --energy-tolerance",
                v.tolerance.map_or("off".into(), |t| t.to_string())
            ),
            Check::Escaped => format!(
                "a point flung out of the mesh by an unstable step ({c}× the critical step of element {el})"
            ),
        }
    };
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_energy_sets_the_scale_of_a_body_at_rest() {
        // Work and σ0 : Δε at round-off, a little apart: noise against each other, nothing
        // against the energy the initial stresses hold.
        let (work, strain) = (-1.0e-21, -1.4e-21);
        assert!(balance_error(0.0, strain, 0.0, work, 0.0, 0.0) > 0.2);
        assert!(balance_error(0.0, strain, 0.0, work, 0.0, 5e-5) < 1e-15);
        // A real imbalance of the stored energy's size still shows.
        assert!((balance_error(1e-4, 0.0, 0.0, 0.0, 0.0, 5e-5) - 1.0).abs() < 1e-12);
    }
}
