//! Element tests of the soil laws against closed forms and independent integrations
//! (docs/validation-soil.md gives the same comparisons with plots, `scripts/validate-soil`).

use mpm_solve::jobs::cam_clay;
use mpm_solve::material::element_test::{drained_triaxial, oedometer, undrained_triaxial, Sample};
use mpm_solve::material::law::LawSpec;
use mpm_solve::material::modified_cam_clay::ModifiedCamClaySpec;

/// A soft clay (λ = 0.2, κ = 0.04, M = 1, e0 = 1.2, ν = 0.3), isotropically over-consolidated
/// to `ocr`.
fn clay(ocr: f64) -> ModifiedCamClaySpec {
    ModifiedCamClaySpec::new(0.3, 0.0, 0.2, 0.04, 1.0, 1.2, 0.0, ocr, 0.0, 1.0, 2000.0).unwrap()
}

#[test]
fn undrained_triaxial_follows_the_closed_form_path_to_the_undrained_strength() {
    for ocr in [1.0, 1.5, 2.0] {
        let spec = clay(ocr);
        let p0 = 100.0;
        let mut sample = Sample::new(&LawSpec::from(spec), p0, p0);
        let path = undrained_triaxial(&mut sample, 2e-4, 1500);
        let pc0 = ocr * p0;
        let mut worst: f64 = 0.0;
        for r in path.iter().filter(|r| r.state[0] > 0.0) {
            // Still elastic (p unchanged) or on the path.
            let yielded = r.state[0] > pc0 * (1.0 + 1e-12) || r.state[0] < pc0 * (1.0 - 1e-12);
            if yielded {
                let want = cam_clay::undrained_q(&spec, p0, pc0, r.p);
                worst = worst.max((r.q - want).abs() / want);
            } else {
                assert!((r.p - p0).abs() < 1e-9 * p0, "OCR {ocr}: {r:?}");
            }
        }
        let su = cam_clay::undrained_strength(&spec, p0, pc0);
        let last = path.last().unwrap();
        let got = last.q / 2.0;
        println!(
            "OCR {ocr}: s_u {got:.4} kPa at ε_a = {:.2} against {su:.4} ({:+.3} %); worst path error {:.2e}",
            last.axial,
            100.0 * (got / su - 1.0),
            worst
        );
        assert!(worst < 1e-3, "OCR {ocr}: the path is {worst:e} off");
        assert!(
            (got / su - 1.0).abs() < 0.01,
            "OCR {ocr}: s_u {got} against {su}"
        );
    }
}

#[test]
fn drained_triaxial_follows_the_integrated_equations() {
    for (ocr, g) in [(1.0, 0.0), (1.5, 0.0), (1.0, 2000.0)] {
        let mut spec = clay(ocr);
        spec.shear_modulus = g;
        let p0 = 100.0;
        let reference = cam_clay::drained_triaxial(&spec, p0, ocr * p0, 0.95, 200_000);
        let end = reference.last().unwrap().axial;
        let mut sample = Sample::new(&LawSpec::from(spec), p0, p0);
        // Backward Euler's error is first order in the step: 4.6e-3 at 1e-4, 2.3e-3 here.
        let step = 5e-5;
        let steps = (end / step) as usize;
        let path = drained_triaxial(&mut sample, step, steps);
        assert_eq!(path.len(), steps + 1, "the drained test stopped early");
        let worst = cam_clay::drained_errors(&path, &reference);
        println!(
            "OCR {ocr}, G {g}: to ε_a = {end:.3}, worst q error {:.2e}, worst ε_v error {:.2e}",
            worst.0, worst.1
        );
        assert!(worst.0 < 5e-3 && worst.1 < 5e-3, "OCR {ocr}: {worst:?}");
    }
}

#[test]
fn the_oedometer_recovers_lambda_on_loading_and_kappa_on_unloading() {
    let spec = clay(1.0);
    let mut sample = Sample::new(&LawSpec::from(spec), 50.0, 100.0);
    // Load to 20 % axial strain, unload by 2 %.
    let path = oedometer(&mut sample, &[0.2, -0.02], 1e-4);
    let at = |n: usize| path[n];
    let slope = |a: usize, b: usize| {
        let (ra, rb) = (at(a), at(b));
        -(rb.state[1] - ra.state[1]) / (rb.p / ra.p).ln()
    };
    let loading = slope(1600, 2000);
    let unloading = slope(2001, path.len() - 1);
    println!(
        "oedometer: e–ln p' slope {loading:.5} loading (λ 0.2), {unloading:.5} unloading (κ 0.04)"
    );
    assert!((loading / 0.2 - 1.0).abs() < 0.01, "{loading}");
    assert!((unloading / 0.04 - 1.0).abs() < 0.01, "{unloading}");
}
