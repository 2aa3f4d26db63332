//! The element tests of docs/validation-soil.md (`scripts/validate-soil`): Modified Cam Clay's
//! undrained and drained triaxial compressions and its oedometer loading and unloading, each
//! beside its reference (the closed form, an independent integration of the same equations);
//! hypoplastic sand's oedometer (a published UMAT's output, K0), drained triaxial compressions
//! (Herle & Gudehus's peak, the critical state) and cyclic undrained shear with and without the
//! intergranular strain; written as two-column CSVs for the plots and `summary.json` for the
//! tables.
//!
//! ```text
//! cargo run --release -p mpm-solve --example soil_elements -- OUT_DIR
//! ```

use std::error::Error;
use std::fmt::Write as _;
use std::path::Path;

use mpm_solve::jobs::{cam_clay, hypoplastic};
use mpm_solve::material::element_test::{
    cyclic_undrained, drained_triaxial, oedometer, undrained_triaxial, Sample,
};
use mpm_solve::material::hypoplastic::HypoplasticSpec;
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

/// Hochstetten sand (Herle & Gudehus 1999) at e0 `e0`, with the intergranular strain (R 1e-4,
/// m_R 5, m_T 2, β_r 0.5, χ 6, δ0 mobilised along the initial stress: `initial` 1) or
/// without (`igs` false), integrated to a relative tolerance of 1e-5.
fn sand(e0: f64, igs: bool, initial: f64) -> Result<HypoplasticSpec, Box<dyn Error>> {
    let r = if igs { 1e-4 } else { 0.0 };
    Ok(HypoplasticSpec::new(
        [33.0, 1.0e6, 0.25, 0.55, 0.95, 1.05, 0.25, 1.5],
        e0,
        [r, 5.0, 2.0, 0.5, 6.0, initial],
        1e-5,
        1.0,
        2000.0,
    )?)
}

/// The OpenSees manual's UMAT example (e0 0.70, isotropic 100 kPa, δ0 = 0, 0.5 % oedometric
/// compression in steps of 1e-4, one step back), and oedometric loading to σ'v = 400 kPa and
/// back to 20 kPa from an isotropic 10 kPa at e0 0.6 to 0.9 without the intergranular strain:
/// e against σ'v, K0 at 100, 200, 400 kPa.
fn hypo_oedometer(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    let spec = sand(0.70, true, 0.0)?;
    let mut sample = Sample::new(&LawSpec::from(spec), 100.0, 100.0);
    let path = oedometer(&mut sample, &[0.005, -1e-4], 1e-4);
    let (a, b, c) = (path[49], path[50], path[51]);
    summary.push(format!(
        "{{\"test\": \"hypo_umat\", \"sigma\": {}, \"loading\": {}, \"unloading\": {}}}",
        b.axial_stress,
        (b.axial_stress - a.axial_stress) / 1e-4,
        (b.axial_stress - c.axial_stress) / 1e-4
    ));
    for e0 in [0.6, 0.7, 0.8, 0.9] {
        let mut sample = Sample::new(&LawSpec::from(sand(e0, false, 0.0)?), 10.0, 10.0);
        let mut path = vec![sample.record()];
        while sample.record().axial_stress < 400.0 {
            sample.strain(0.0, 1e-5);
            path.push(sample.record());
        }
        let top = path.len();
        while sample.record().axial_stress > 20.0 {
            sample.strain(0.0, -1e-6);
            path.push(sample.record());
        }
        write_xy(
            dir,
            &format!("hypo_oedometer_{e0}.csv"),
            "sigma_v,e",
            path.iter().map(|r| (r.axial_stress, r.state[0])),
        )?;
        let k0: Vec<String> = [100.0, 200.0, 400.0]
            .iter()
            .map(|&sv| {
                let r = path[path[..top].partition_point(|r| r.axial_stress < sv)];
                format!(
                    "[{}, {}, {}]",
                    r.axial_stress,
                    (r.axial_stress - r.q) / r.axial_stress,
                    r.state[0]
                )
            })
            .collect();
        summary.push(format!(
            "{{\"test\": \"hypo_oedometer\", \"e0\": {e0}, \"k0\": [{}], \"e_end\": {}}}",
            k0.join(", "),
            path.last().ok_or("no path")?.state[0]
        ));
    }
    Ok(())
}

/// Drained triaxial compressions from p' = 100 kPa to 150 % axial strain at e0 0.55, 0.65,
/// 0.75 (no intergranular strain): q / p' and ε_v against ε_a, e against p', the peak beside
/// Herle & Gudehus's and the end beside the critical state.
fn hypo_drained(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    for e0 in [0.55, 0.65, 0.75] {
        let spec = sand(e0, false, 0.0)?;
        let mut sample = Sample::new(&LawSpec::from(spec), 100.0, 100.0);
        let path = drained_triaxial(&mut sample, 1e-3, 1500);
        let d = hypoplastic::drained_shear(&spec, &path).ok_or("no peak")?;
        let shown = path.iter().take_while(|r| r.axial <= 0.3 + 1e-9);
        write_xy(
            dir,
            &format!("hypo_drained_{e0}_phi.csv"),
            "eps_a,phi",
            shown.clone().map(|r| (r.axial, hypoplastic::mobilised(r))),
        )?;
        write_xy(
            dir,
            &format!("hypo_drained_{e0}_ev.csv"),
            "eps_a,eps_v",
            shown.map(|r| (r.axial, r.volumetric)),
        )?;
        write_xy(
            dir,
            &format!("hypo_drained_{e0}_e.csv"),
            "eps_a,e",
            path.iter().map(|r| (r.axial, r.state[0])),
        )?;
        summary.push(format!(
            "{{\"test\": \"hypo_drained\", \"e0\": {e0}, \"peak_phi\": {}, \"peak_axial\": {}, \"peak_e\": {}, \"peak_p\": {}, \"peak_tan_nu\": {}, \"hg_phi\": {}, \"hg_tan_nu\": {}, \"end_axial\": {}, \"end_e\": {}, \"end_ec\": {}, \"end_phi\": {}, \"end_tan_nu\": {}}}",
            d.peak_phi, d.peak_axial, d.peak_e, d.peak_p, d.peak_tan_nu, d.hg_phi, d.hg_tan_nu,
            d.end_axial, d.end_e, d.end_ec, d.end_phi, d.end_tan_nu
        ));
    }
    Ok(())
}

/// Cyclic undrained triaxial shear of loose sand (e0 0.80, p'0 = 100 kPa, q_ampl = 15 kPa),
/// with the intergranular strain (δ0 mobilised by the isotropic compression) and without:
/// the p'–q paths, the cycles to liquefaction and p' after each cycle.
fn hypo_cyclic(dir: &Path, summary: &mut Vec<String>) -> Result<(), Box<dyn Error>> {
    for igs in [true, false] {
        let mut sample = Sample::new(&LawSpec::from(sand(0.80, igs, 1.0)?), 100.0, 100.0);
        let c = cyclic_undrained(&mut sample, 15.0, 1e-5, 40);
        let tag = if igs { "igs" } else { "plain" };
        write_xy(
            dir,
            &format!("hypo_cyclic_{tag}.csv"),
            "p,q",
            c.records.iter().step_by(5).map(|r| (r.p, r.q)),
        )?;
        let after: Vec<String> = c.p_after_cycle.iter().map(|p| format!("{p}")).collect();
        summary.push(format!(
            "{{\"test\": \"hypo_cyclic\", \"igs\": {igs}, \"liquefied_at\": {}, \"p_after_cycle\": [{}]}}",
            c.liquefied_at.map_or("null".to_string(), |n| n.to_string()),
            after.join(", ")
        ));
    }
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
    hypo_oedometer(dir, &mut summary)?;
    hypo_drained(dir, &mut summary)?;
    hypo_cyclic(dir, &mut summary)?;
    std::fs::write(
        dir.join("summary.json"),
        format!("[\n{}\n]\n", summary.join(",\n")),
    )?;
    Ok(())
}
