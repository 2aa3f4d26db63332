//! What a scene may ask for and Anura3D cannot reproduce exactly, refused with the scene item
//! named; and the CPS values (multipliers, load steps, output points) the checks settle.

use super::{ANURA3D_POINT_COUNTS, MAX_OUTPUT_POINTS};
use crate::input::case::{Case, LoadCurve, Start};
use crate::input::scene::{Resolved, TractionInput};

/// A scene item Anura3D cannot reproduce, and why: an [`ExportError::Unsupported`] before it
/// names the file.
///
/// [`ExportError::Unsupported`]: super::ExportError::Unsupported
pub(super) struct Refusal {
    pub item: String,
    pub message: String,
}

/// The refusal of `item` for `message`.
pub(super) fn refuse(item: impl Into<String>, message: impl Into<String>) -> Refusal {
    Refusal {
        item: item.into(),
        message: message.into(),
    }
}

/// Refuses the undrained start of a consolidation run (noting that the export runs the
/// loading only), the semi-implicit scheme and a cap on the time steps.
pub(super) fn run(case: &Case, notes: &mut Vec<String>) -> Result<(), Refusal> {
    if let Some(c) = &case.start.consolidation {
        if c.start == Start::Undrained {
            return Err(refuse(
                "consolidation.start",
                "\"undrained\" starts from Terzaghi's undrained state, which Anura3D cannot set up; use start = \"rest\"",
            ));
        }
        notes.push("[consolidation]: the Terzaghi report is mpm-solve's own; the export runs the loading only".into());
    }
    if let Some(b) = case.numerics.bulk_viscosity {
        if !(b.linear > 0.0 && b.quadratic > 0.0) {
            return Err(refuse(
                "damping.bulk_viscosity",
                format!(
                    "Anura3D asks for both coefficients positive (got [{}, {}])",
                    b.linear, b.quadratic
                ),
            ));
        }
        notes.push("damping.bulk_viscosity: Anura3D (and mpm-solve on the exported GOM) adds the quadratic term as a tensile stress, helping the compression along; the scene's resists it".into());
    }
    if case.numerics.scheme.semi_implicit() {
        return Err(refuse(
            "time.scheme",
            "Anura3D steps every term explicitly; export the scene with scheme = \"explicit\"",
        ));
    }
    if let Some(n) = case.time.max_steps {
        return Err(refuse(
            "time.max_steps",
            format!("Anura3D has no cap on the time steps of a dynamic run (got {n}); remove it"),
        ));
    }
    Ok(())
}

/// The outputs as Anura3D's load steps of equal length: (the interval, their number).
pub(super) fn load_steps(case: &Case) -> Result<(f64, usize), Refusal> {
    let end = case.time.end_time;
    let n_out = case.time.output_times.len();
    let interval = case.time.output_times.first().copied().unwrap_or(end);
    let tol = 1e-9 * end;
    let equal = case
        .time
        .output_times
        .iter()
        .enumerate()
        .all(|(k, &t)| (t - (k + 1) as f64 * interval).abs() <= tol);
    if n_out == 0 || !equal {
        return Err(refuse(
            "time.output_interval",
            format!(
                "the outputs are not equally spaced (the end, {end} s, is not a whole number of intervals of {interval} s); Anura3D writes one per load step of equal length"
            ),
        ));
    }
    Ok((interval, n_out))
}

/// Anura3D's multiplier for a load on `curve` over a run ending at `end`: sudden, or a linear
/// ramp over the whole run; `item` names the scene's load in a refusal.
fn multiplier(curve: &LoadCurve, end: f64, item: &str) -> Result<&'static str, Refusal> {
    let tol = 1e-9 * end;
    match *curve {
        LoadCurve::Step => Ok("step  1.0  1.0"),
        LoadCurve::Ramp { over } if (over - end).abs() <= tol => Ok("linear  0.0  1.0"),
        LoadCurve::Ramp { over } => Err(refuse(
            item,
            format!(
                "Anura3D ramps a load linearly over the whole run only: use 0 (sudden) or {end} (the end time), not {over}"
            ),
        )),
        LoadCurve::Stairs { .. } => Err(refuse(
            item,
            "a load in stairs (from Anura3D input) is not written back",
        )),
        LoadCurve::Table(_) | LoadCurve::File(_) | LoadCurve::Blows { .. } => Err(refuse(
            item,
            "Anura3D's loads ramp or step only: a curve (a table or hammer blows) is not written",
        )),
    }
}

/// `$$GRAVITY_LOAD`: off without gravity.
pub(super) fn gravity_load(case: &Case) -> Result<&'static str, Refusal> {
    if case.loads.gravity.iter().any(|&g| g != 0.0) {
        multiplier(
            &case.loads.gravity_curve,
            case.time.end_time,
            "gravity.ramp",
        )
    } else {
        Ok("off  0.0  1.0")
    }
}

/// The tractions that load something (faces and a non-zero traction or pressure).
pub(super) fn loaded(r: &Resolved) -> Vec<&TractionInput> {
    r.tractions
        .iter()
        .filter(|t| {
            !t.faces.is_empty()
                && (t.traction.iter().any(|&v| v != 0.0) || t.pressure.is_some_and(|p| p != 0.0))
        })
        .collect()
}

/// `$$SOLID_TRACTION`: off without loads. The case ramps every traction over the longest ramp
/// given; each must fit Anura3D's.
pub(super) fn solid_traction(r: &Resolved) -> Result<&'static str, Refusal> {
    let end = r.case.time.end_time;
    for t in &r.tractions {
        multiplier(
            &LoadCurve::ramp(t.ramp),
            end,
            &format!("traction \"{}\".ramp", t.physical),
        )?;
    }
    if loaded(r).is_empty() {
        Ok("off  0.0  1.0")
    } else {
        multiplier(&r.case.loads.traction_curve, end, "traction.ramp")
    }
}

/// Refuses what only this solver models: a PIC share in the velocity update, a background
/// grid, the dual-domain gradients, frictional walls, absorbing boundaries (not yet written).
pub(super) fn solver_only(case: &Case) -> Result<(), Refusal> {
    if case.numerics.pic_blend > 0.0 {
        return Err(refuse(
            "pic_blend",
            format!(
                "Anura3D updates the points' velocities by FLIP alone; remove pic_blend = {} (or set it to 0) to export",
                case.numerics.pic_blend
            ),
        ));
    }
    if let Some(grid) = &case.numerics.grid {
        return Err(refuse(
            "grid",
            format!(
                "Anura3D computes on the mesh's elements; a background grid ({} basis) has no Anura3D counterpart: remove [grid] to export",
                grid.basis_name()
            ),
        ));
    }
    if case.numerics.gradient != crate::input::case::Gradient::Element {
        return Err(refuse(
            "gradient",
            "Anura3D takes each element's own gradients; the dual-domain gradients have no Anura3D counterpart: remove gradient to export".to_string(),
        ));
    }
    if !case.boundary.walls.is_empty() {
        return Err(refuse(
            "fixity.friction",
            "Anura3D has no frictional fixity (its friction acts between bodies in contact); \
             remove friction from the fixities to export",
        ));
    }
    if !case.boundary.absorbing.is_empty() {
        return Err(refuse(
            "absorbing",
            "the export does not write Anura3D's absorbing-boundary sections yet (its per-node \
             dashpots take the reference material's impedance and its own face areas); remove \
             [[absorbing]] to export",
        ));
    }
    Ok(())
}

/// The rows (time, multiplier) of an Anura3D multiplier file (`.PVF`).
pub(super) type Pvf = Vec<(f64, f64)>;

/// `$$PRESCRIBED_VELOCITY`: Anura3D has one multiplier for every prescribed velocity, so their
/// ramps (or curves) must agree; off without any. A curve's table goes to the project's `.PVF`
/// (returned), for which Anura3D needs a first row at time 0 and reads 0 after the last (so it
/// must end after the run). Several nodal sets are noted (one reaction for all).
pub(super) fn prescribed_velocity(
    r: &Resolved,
    notes: &mut Vec<String>,
) -> Result<(&'static str, Option<Pvf>), Refusal> {
    if let Some(LoadCurve::Table(rows)) = r.velocities.first().map(|v| &v.curve) {
        let first = &r.velocities[0];
        let item = format!("velocity \"{}\".curve", first.name);
        if let Some(v) = r.velocities.iter().find(|v| v.curve != first.curve) {
            return Err(refuse(
                format!("velocity \"{}\".curve", v.name),
                "Anura3D has one multiplier for every prescribed velocity: give every [[velocity]] the same curve",
            ));
        }
        let end = r.case.time.end_time;
        match (rows.first(), rows.last()) {
            (Some(&(t0, _)), Some(&(t1, _))) if t0 == 0.0 && t1 > end => {}
            _ => {
                return Err(refuse(
                    item,
                    format!("Anura3D's multiplier file needs a first row at time 0 and a last one after the end ({end} s); it reads 0 past its last time"),
                ))
            }
        }
        return Ok(("file  0.0  1.0", Some(rows.to_vec())));
    }
    let multiplier = match r.velocities.first() {
        None => "off  0.0  1.0",
        Some(first) => {
            if let Some(v) = r.velocities.iter().find(|v| v.curve != first.curve) {
                return Err(refuse(
                    format!("velocity \"{}\".ramp", v.name),
                    format!(
                        "Anura3D has one multiplier for every prescribed velocity: give every [[velocity]] the ramp of \"{}\" ({} s), not {} s",
                        first.name, first.ramp, v.ramp
                    ),
                ));
            }
            multiplier(
                &first.curve,
                r.case.time.end_time,
                &format!("velocity \"{}\".ramp", first.name),
            )?
        }
    };
    if r.case.boundary.nodal_velocity.len() > 1 {
        notes.push(format!(
            "[[velocity]]: the {} nodal sets go to one GOM section, so a run of the GOM records one reaction for all of them",
            r.case.boundary.nodal_velocity.len()
        ));
    }
    Ok((multiplier, None))
}

/// Refuses materials Anura3D would not run the same: missing entries, point counts it does not
/// place, the strain-softening law, uniform initial stresses, K0 out of its range or on some
/// materials only, an initial pore pressure.
pub(super) fn materials(r: &Resolved) -> Result<(), Refusal> {
    let case = &r.case;
    let n_mat = case.body.materials.len().saturating_sub(1);
    for k in 1..=n_mat {
        let Some(m) = &r.materials[k] else {
            let name = case.model.materials().get(k - 1).map(|m| m.name.clone());
            return Err(refuse(
                format!("physical volume \"{}\"", name.unwrap_or_default()),
                "has no [[material]] entry",
            ));
        };
        let item = format!("material \"{}\"", m.physical);
        if !ANURA3D_POINT_COUNTS.contains(&m.points_per_element) {
            return Err(refuse(
                format!("{item}.points_per_element"),
                format!(
                    "Anura3D places {ANURA3D_POINT_COUNTS:?} material points in a tetrahedron, not {}",
                    m.points_per_element
                ),
            ));
        }
        if m.law.name() == "strain_softening_mohr_coulomb" {
            return Err(refuse(
                format!("{item}.law"),
                "Anura3D reads strain_softening_mohr_coulomb but has no stress routine for it (its run stops with a segmentation fault)",
            ));
        }
        if m.initial_stress.is_some() {
            return Err(refuse(
                format!("{item}.initial_stress"),
                "Anura3D has no uniform initial stress ($$K0_PROCEDURE sets K0 stresses, $$MP_STRESS_INITIALIZATION_FROMFILE reads them from a results file); use k0 or none",
            ));
        }
        if let Some(k0) = m.k0 {
            if k0 > 1.0 {
                return Err(refuse(
                    format!("{item}.k0"),
                    format!("Anura3D accepts K0 in [0, 1] only, got {k0}"),
                ));
            }
        } else if r.materials.iter().flatten().any(|o| o.k0.is_some()) {
            return Err(refuse(
                item,
                "Anura3D's K0 procedure stresses every material (a material without K0 would start with its vertical stress): give it k0 too",
            ));
        }
        if let Some(l) = &m.liquid {
            if l.initial_pore_pressure != 0.0 {
                return Err(refuse(
                    format!("{item}.liquid.initial_pore_pressure"),
                    format!(
                        "Anura3D's coupled material starts without pore pressure (got {} kPa); use 0",
                        l.initial_pore_pressure
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The output material points: the case's probes, or the first, a middle and the last point;
/// at most Anura3D's limit, each an existing point.
pub(super) fn probes(case: &Case) -> Result<Vec<u32>, Refusal> {
    let total_points: u64 = case
        .body
        .element_material
        .iter()
        .zip(&case.body.points_per_element)
        .filter(|(&m, _)| m != 0)
        .map(|(_, &n)| n as u64)
        .sum();
    let mut probes: Vec<u32> = if case.run.probes.is_empty() && total_points > 0 {
        // A few points: the first, one in the middle and the last.
        vec![1, total_points.div_ceil(2) as u32, total_points as u32]
    } else {
        case.run.probes.clone()
    };
    probes.sort_unstable();
    probes.dedup();
    if probes.len() > MAX_OUTPUT_POINTS {
        return Err(refuse(
            "probes",
            format!(
                "Anura3D writes at most {MAX_OUTPUT_POINTS} output material points, got {}",
                probes.len()
            ),
        ));
    }
    if let Some(&bad) = probes.iter().find(|&&p| p == 0 || p as u64 > total_points) {
        return Err(refuse(
            "probes",
            format!("material point {bad} does not exist (ids run from 1 to {total_points})"),
        ));
    }
    Ok(probes)
}

/// Notes where the exported run differs from the scene's: the liquid's damping, and pressure
/// smoothing done as Anura3D's strain smoothing.
pub(super) fn differences(case: &Case, notes: &mut Vec<String>) {
    if case.has_liquid() && case.numerics.damping > 0.0 {
        notes.push(format!(
            "damping.local: Anura3D (and mpm-solve on the exported GOM) damps the liquid by {} too, and the mixture's solid and liquid parts separately; the scene damps the mixture against the solid's velocity only",
            case.numerics.damping
        ));
    }
    if super::smooths(case) && !case.numerics.strain_smoothing {
        notes.push("STRAIN_SMOOTHING 1: Anura3D (and mpm-solve on the exported GOM) smooths the volumetric strain of both phases element by element; the scene smooths pore-pressure rates through V N-weighted nodal averages".into());
    }
}
