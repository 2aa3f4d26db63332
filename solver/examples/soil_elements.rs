//! The element tests of docs/validation-soil.md (`scripts/validate-soil`): Modified Cam Clay's
//! undrained and drained triaxial compressions and its oedometer loading and unloading, each
//! beside its reference (the closed form, an independent integration of the same equations),
//! written as two-column CSVs for the plots and `summary.json` for the tables.
//!
//! ```text
//! cargo run --release -p mpm-solve --example soil_elements -- OUT_DIR
//! ```

use std::error::Error;
use std::fmt::Write as _;
use std::path::Path;

use mpm_solve::jobs::cam_clay;
use mpm_solve::material::element_test::{drained_triaxial, oedometer, undrained_triaxial, Sample};
use mpm_solve::material::law::LawSpec;
use mpm_solve::material::modified_cam_clay::ModifiedCamClaySpec;

/// The clay of the tests: λ = 0.2, κ = 0.04, M = 1, e0 = 1.2, ν = 0.3 (G from ν) or a
/// constant `shear`, isotropically over-consolidated to `ocr`.
fn clay(ocr: f64, shear: f64) -> Result<ModifiedCamClaySpec, Box<dyn Error>> {
    Ok(ModifiedCamClaySpec::new(
        0.3, shear, 0.2, 0.04, 1.0, 1.2, 0.0, ocr, 0.0, 1.0, 2000.0,
    )?)
}

/// Writes the (x, y) rows under `header` to `dir/name`.
fn write_xy(
    dir: &Path,
    name: &str,
    header: &str,
    rows: impl Iterator<Item = (f64, f64)>,
) -> Result<(), Box<dyn Error>> {
    let mut s = format!("{header}\n");
    for (x, y) in rows {
        writeln!(s, "{x:?},{y:?}")?;
    }
    std::fs::write(dir.join(name), s)?;
    Ok(())
}

/// The start's mean stress (kPa).
const P0: f64 = 100.0;

/// Undrained compressions: the law's p'–q path and the closed form's at the same p', the
/// undrained strength against Wood's, the worst difference along the path.
fn undrained(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    for ocr in [1.0, 1.5, 2.0] {
        let spec = clay(ocr, 0.0)?;
        let mut sample = Sample::new(&LawSpec::from(spec), P0, P0);
        let path = undrained_triaxial(&mut sample, 2e-4, 1500);
        let pc0 = ocr * P0;
        let yielded: Vec<_> = path
            .iter()
            .filter(|r| r.state[0] > 0.0 && (r.state[0] / pc0 - 1.0).abs() > 1e-12)
            .collect();
        let worst = yielded
            .iter()
            .map(|r| {
                let want = cam_clay::undrained_q(&spec, P0, pc0, r.p);
                (r.q - want).abs() / want
            })
            .fold(0.0f64, f64::max);
        write_xy(
            dir,
            &format!("undrained_{ocr}_law.csv"),
            "p,q",
            path.iter().map(|r| (r.p, r.q)),
        )?;
        write_xy(
            dir,
            &format!("undrained_{ocr}_closed.csv"),
            "p,q",
            yielded
                .iter()
                .map(|r| (r.p, cam_clay::undrained_q(&spec, P0, pc0, r.p))),
        )?;
        write_xy(
            dir,
            &format!("undrained_{ocr}_strain.csv"),
            "eps_a,q",
            path.iter().map(|r| (r.axial, r.q)),
        )?;
        let last = path.last().ok_or("no path")?;
        summary.push(format!(
            "{{\"test\": \"undrained\", \"ocr\": {ocr}, \"su\": {}, \"su_closed\": {}, \"at_axial\": {}, \"worst_path\": {worst:e}, \"p_end\": {}}}",
            last.q / 2.0,
            cam_clay::undrained_strength(&spec, P0, pc0),
            last.axial,
            last.p
        ));
    }
    Ok(())
}

/// Drained compressions against the Runge–Kutta integration: q and ε_v against ε_a, the
/// worst differences at axial steps of 1e-4 and 5e-5.
fn drained(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    for (ocr, shear) in [(1.0, 0.0), (1.5, 0.0), (1.0, 2000.0)] {
        let spec = clay(ocr, shear)?;
        let reference = cam_clay::drained_triaxial(&spec, P0, ocr * P0, 0.95, 200_000);
        let end = reference.last().ok_or("no reference")?.axial;
        let tag = format!("drained_{ocr}_{shear}");
        let mut errors = Vec::new();
        for step in [1e-4, 5e-5] {
            let mut sample = Sample::new(&LawSpec::from(spec), P0, P0);
            let path = drained_triaxial(&mut sample, step, (end / step) as usize);
            let (eq, ev) = cam_clay::drained_errors(&path, &reference);
            errors.push(format!(
                "{{\"step\": {step}, \"steps\": {}, \"worst_q\": {eq:e}, \"worst_ev\": {ev:e}}}",
                path.len() - 1
            ));
            if step == 1e-4 {
                write_xy(
                    dir,
                    &format!("{tag}_law.csv"),
                    "eps_a,q",
                    path.iter().map(|r| (r.axial, r.q)),
                )?;
                write_xy(
                    dir,
                    &format!("{tag}_law_ev.csv"),
                    "eps_a,eps_v",
                    path.iter().map(|r| (r.axial, r.volumetric)),
                )?;
            }
        }
        let every = reference.len() / 400;
        write_xy(
            dir,
            &format!("{tag}_ref.csv"),
            "eps_a,q",
            reference.iter().step_by(every).map(|r| (r.axial, r.q)),
        )?;
        write_xy(
            dir,
            &format!("{tag}_ref_ev.csv"),
            "eps_a,eps_v",
            reference
                .iter()
                .step_by(every)
                .map(|r| (r.axial, r.volumetric)),
        )?;
        let last = reference.last().ok_or("no reference")?;
        summary.push(format!(
            "{{\"test\": \"drained\", \"ocr\": {ocr}, \"shear\": {shear}, \"to_axial\": {end}, \"q_end\": {}, \"errors\": [{}]}}",
            last.q,
            errors.join(", ")
        ));
    }
    Ok(())
}

/// The oedometer from (σ'v, σ'h) = (100, 50) kPa to 20 % axial strain and back by 2 %: e
/// against ln σ'v, the slopes of the loading's last fifth and of the unloading.
fn oedometer_test(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    let spec = clay(1.0, 0.0)?;
    let mut sample = Sample::new(&LawSpec::from(spec), 50.0, 100.0);
    let path = oedometer(&mut sample, &[0.2, -0.02], 1e-4);
    write_xy(
        dir,
        "oedometer.csv",
        "ln_sigma_v,e",
        path.iter()
            .skip(1)
            .map(|r| (r.axial_stress.ln(), r.state[1])),
    )?;
    let slope = |a: usize, b: usize| {
        let (ra, rb) = (path[a], path[b]);
        -(rb.state[1] - ra.state[1]) / (rb.p / ra.p).ln()
    };
    let last = path.len() - 1;
    let top = path[2000];
    summary.push(format!(
        "{{\"test\": \"oedometer\", \"loading_slope\": {}, \"unloading_slope\": {}, \"k0_loading\": {}, \"sigma_v_top\": {}}}",
        slope(1600, 2000),
        slope(2001, last),
        (top.p * 3.0 - top.axial_stress) / 2.0 / top.axial_stress,
        top.axial_stress
    ));
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = std::env::args()
        .nth(1)
        .ok_or("usage: soil_elements OUT_DIR")?;
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let mut summary = Vec::new();
    undrained(dir, &mut summary)?;
    drained(dir, &mut summary)?;
    oedometer_test(dir, &mut summary)?;
    std::fs::write(
        dir.join("summary.json"),
        format!("[\n{}\n]\n", summary.join(",\n")),
    )?;
    Ok(())
}
