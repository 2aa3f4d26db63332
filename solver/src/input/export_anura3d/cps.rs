//! The exported CPS: the scene's controls, every other key at the inert value of Anura3D's
//! template.

use mpm_shared::cps::{Cps, Entry};
use mpm_shared::model::LineEnding;
use mpm_shared::text::real_to_string;

use super::VERSION;
use crate::input::case::{Case, Integration};

/// The CPS values that come from the checks in [`build`](super::build).
pub(super) struct CpsValues<'a> {
    /// Time between outputs (s): the load step.
    pub interval: f64,
    /// Outputs: the load steps.
    pub load_steps: usize,
    /// `$$GRAVITY_LOAD`.
    pub gravity_load: &'static str,
    /// `$$SOLID_TRACTION`.
    pub solid_traction: &'static str,
    /// `$$STRAIN_SMOOTHING` on.
    pub smoothing: bool,
    /// Output material points (1-based).
    pub probes: &'a [u32],
    /// `$$PRESCRIBED_VELOCITY`.
    pub prescribed_velocity: &'static str,
    /// Height of the ground surface when the K0 procedure is on.
    pub k0_surface: Option<f64>,
}

/// `$$BULK_VISCOSITY_DAMPING`'s line: `0 0.0 0.0` (off) or `1 b1 b2`.
fn bulk_line(case: &Case) -> String {
    match case.numerics.bulk_viscosity {
        Some(b) => format!(
            "1 {} {}",
            real_to_string(b.linear),
            real_to_string(b.quadratic)
        ),
        None => "0 0.0 0.0".into(),
    }
}

/// `$$MASS_SCALING`'s line: `0 1.0` (off) or `1 f`.
fn mass_scaling(f: f64) -> String {
    if f == 1.0 {
        "0 1.0".to_string()
    } else {
        format!("1 {}", real_to_string(f))
    }
}

/// The CPS: the scene's controls, every other key at the inert value of Anura3D's template.
pub(super) fn cps_file(case: &Case, v: CpsValues) -> Cps {
    let g = case.loads.gravity;
    let g_abs = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    // Without gravity the load is off, but the acceleration keeps Anura3D's default: Anura3D
    // turns the intrinsic permeability into a hydraulic conductivity with it (ρw g κ / μ), and
    // 0 there makes a saturated material's drag infinite.
    let (g_abs, dir) = if g_abs > 0.0 {
        (g_abs, g.map(|c| c / g_abs))
    } else {
        // Without gravity (GRAVITY_LOAD off) Anura3D still needs g: it turns intrinsic
        // permeability into conductivity with it (a 0 makes its drag 0/0).
        (crate::material::liquid::G, [0.0, -1.0, 0.0])
    };
    let r = real_to_string;
    let damping = if case.numerics.damping > 0.0 {
        format!("1 {}", r(case.numerics.damping))
    } else {
        "0 0.0".into()
    };
    let (bulk, scaling) = (bulk_line(case), mass_scaling(case.numerics.mass_scaling));
    let probes: Vec<String> = if v.probes.is_empty() {
        vec!["-1".into()]
    } else {
        v.probes.iter().map(|p| p.to_string()).collect()
    };
    let one = |s: &str| vec![s.to_string()];
    let mut entries: Vec<(&str, Vec<String>)> = vec![
        ("NUMBER_OF_LOADSTEPS", one(&v.load_steps.to_string())),
        ("TIME_PER_LOADSTEP", one(&r(v.interval))),
        ("TOTAL_TIME", one("0.0")),
        ("COURANT_NUMBER", one(&r(case.time.courant))),
        (
            "COMPUTATION_METHOD",
            one(match case.numerics.integration {
                Integration::MaterialPoints => "MPM-MP",
                Integration::Mixed { .. } => "MPM-MIXED",
            }),
        ),
        ("GRAVITY_ACCELERATION", one(&r(g_abs))),
        (
            "GRAVITY_VECTOR",
            one(&format!("{} {} {}", r(dir[0]), r(dir[1]), r(dir[2]))),
        ),
        ("GRAVITY_LOAD", one(v.gravity_load)),
        ("SOLID_TRACTION", one(v.solid_traction)),
        ("SOLID_TRACTION_B", one("off  0.0  1.0")),
        ("LIQUID_PRESSURE", one("off  0.0  1.0")),
        ("LIQUID_PRESSURE_B", one("off  0.0  1.0")),
        ("PRESCRIBED_VELOCITY", one(v.prescribed_velocity)),
        ("QUASISTATIC_CONVERGENCE", one("0")),
        ("TOLERATED_ERROR_SOLID", one("0.01 0.01")),
        ("TOLERATED_ERROR_LIQUID", one("0.01 0.01")),
        ("MAXIMUM_TIME_STEPS", one("10000")),
        ("MASS_SCALING", one(&scaling)),
        ("HOMOGENEOUS_LOCAL_DAMPING", one(&damping)),
        ("BULK_VISCOSITY_DAMPING", one(&bulk)),
        ("FIX_SOLID_SKELETON", one("0")),
        ("STRAIN_SMOOTHING", one(if v.smoothing { "1" } else { "0" })),
        ("CONTACT_FORMULATION", one("0")),
        ("EXCAVATION", one("0")),
        ("INITIAL_WATER_PRESSURE", one("0.0")),
        ("APPLY_POROSITY_UPDATE", one("0")),
        ("INITIAL_VELOCITY", one("0")),
        ("RESET_DISPLACEMENTS", one("0")),
        ("REMOVE_FIXITIES", one("0 0 0")),
        (
            "K0_PROCEDURE",
            one(if v.k0_surface.is_some() { "1" } else { "0" }),
        ),
        ("SUBMERGED_CALCULATION", one("0 1")),
        (
            "APPLY_OBJECTIVE_STRESS",
            one(if case.numerics.objective_stress {
                "1"
            } else {
                "0"
            }),
        ),
        (
            "DEGREE_OF_FILLING",
            one(&match case.numerics.integration {
                Integration::Mixed { filling, .. } => r(filling),
                Integration::MaterialPoints => "0.9".into(),
            }),
        ),
        ("NUMBER_OF_ACTIVE_ELEMENTS", one("0")),
        (
            "OUTPUT_NUMBER_OF_MATERIAL_POINTS",
            one(&v.probes.len().to_string()),
        ),
        ("OUTPUT_MATERIAL_POINTS", probes),
    ];
    if let Some(y) = v.k0_surface {
        // Anura3D reads the surface's height as the first number.
        let at = entries
            .iter()
            .position(|e| e.0 == "K0_PROCEDURE")
            .expect("listed")
            + 1;
        entries.insert(at, ("SURFACE_ELEVATION", one(&r(y))));
    }
    Cps {
        file: String::new(),
        version: VERSION.into(),
        line_ending: LineEnding::Lf,
        entries: entries
            .into_iter()
            .map(|(k, lines)| Entry {
                keyword: k.into(),
                lines,
                line: 0,
            })
            .collect(),
    }
}
