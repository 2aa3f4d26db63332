//! Element tests of the soil laws against closed forms and independent integrations
//! (docs/validation-soil.md gives the same comparisons with plots, `scripts/validate-soil`).

use mpm_solve::jobs::cam_clay;
use mpm_solve::jobs::hypoplastic;
use mpm_solve::material::element_test::{
    cyclic_undrained, drained_triaxial, oedometer, undrained_triaxial, Sample,
};
use mpm_solve::material::hypoplastic::HypoplasticSpec;
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

/// Hochstetten sand (Herle & Gudehus 1999) at e0 `e0`, with the intergranular strain
/// (R = 1e-4, m_R 5, m_T 2, β_r 0.5, χ 6, mobilised along the initial stress) or without,
/// integrated to a relative tolerance of 1e-5.
fn sand(e0: f64, igs: bool) -> HypoplasticSpec {
    let r = if igs { 1e-4 } else { 0.0 };
    HypoplasticSpec::new(
        [33.0, 1.0e6, 0.25, 0.55, 0.95, 1.05, 0.25, 1.5],
        e0,
        [r, 5.0, 2.0, 0.5, 6.0, 1.0],
        1e-5,
        1.0,
        2000.0,
    )
    .unwrap()
}

#[test]
fn drained_hypoplastic_shear_peaks_as_herle_and_gudehus_and_ends_at_the_critical_state() {
    // e0, and the peak friction angle of an independent integration of the same equations
    // (docs/research/hypoplasticity.md, table 5c).
    for (e0, published) in [(0.55, 52.91), (0.65, 42.00), (0.75, 36.35)] {
        let spec = sand(e0, false);
        let mut sample = Sample::new(&LawSpec::from(spec), 100.0, 100.0);
        // To 150 % axial strain (the critical state is approached slowly).
        let path = drained_triaxial(&mut sample, 1e-3, 1500);
        assert_eq!(path.len(), 1501, "e0 {e0}: the drained test stopped early");
        let d = hypoplastic::drained_shear(&spec, &path).unwrap();
        println!("e0 {e0}: {d:?}");
        assert!(
            (d.peak_phi / published - 1.0).abs() < 0.05,
            "e0 {e0}: {d:?}"
        );
        assert!((d.peak_phi - d.hg_phi).abs() < 0.1, "e0 {e0}: {d:?}");
        assert!((d.peak_tan_nu - d.hg_tan_nu).abs() < 0.01, "e0 {e0}: {d:?}");
        assert!((d.end_e / d.end_ec - 1.0).abs() < 0.01, "e0 {e0}: {d:?}");
        assert!((d.end_phi - 33.0).abs() < 0.1, "e0 {e0}: {d:?}");
    }
}

#[test]
fn the_intergranular_strain_delays_cyclic_liquefaction() {
    // Loose (e0 0.80) from p' = 100 kPa, q_ampl = 15 kPa.
    let run = |igs: bool| {
        let mut sample = Sample::new(&LawSpec::from(sand(0.80, igs)), 100.0, 100.0);
        cyclic_undrained(&mut sample, 15.0, 1e-5, 40)
    };
    let (with, without) = (run(true), run(false));
    println!(
        "with IGS: liquefied at {:?}, p' after the cycles {:?}",
        with.liquefied_at, &with.p_after_cycle
    );
    println!(
        "without: liquefied at {:?}, p' after the cycles {:?}",
        without.liquefied_at, &without.p_after_cycle
    );
    let (w, wo) = (with.liquefied_at.unwrap(), without.liquefied_at.unwrap());
    assert!(w >= 1.5 * wo, "{w} against {wo}");
    assert!(with.p_after_cycle[0] > without.p_after_cycle[0]);
}

#[test]
fn the_hypoplastic_oedometer_reproduces_the_published_umat_and_k0() {
    // The OpenSees manual's worked example of the soilmodels.com UMAT: e0 0.70, isotropic
    // 100 kPa, δ0 = 0, 0.5 % of oedometric compression in steps of 1e-4 and one step back:
    // σ_axial 294.3 kPa, the last loading step's stiffness 29,080 kPa, the first unloading
    // step's 316,559 kPa.
    let spec = HypoplasticSpec {
        igs_initial: 0.0,
        ..sand(0.70, true)
    };
    let mut sample = Sample::new(&LawSpec::from(spec), 100.0, 100.0);
    let path = oedometer(&mut sample, &[0.005, -1e-4], 1e-4);
    let (a, b, c) = (path[49], path[50], path[51]);
    let loading = (b.axial_stress - a.axial_stress) / 1e-4;
    let unloading = (b.axial_stress - c.axial_stress) / 1e-4;
    println!(
        "UMAT example: σ_axial {:.2} kPa, loading {loading:.0} kPa, unloading {unloading:.0} kPa",
        b.axial_stress
    );
    for (got, want) in [
        (b.axial_stress, 294.3),
        (loading, 29080.0),
        (unloading, 316559.0),
    ] {
        assert!((got / want - 1.0).abs() < 1e-3, "{got} against {want}");
    }
    // K0 = σ'h / σ'v of oedometric loading from an isotropic 10 kPa without the intergranular
    // strain, near 1 − sin φc = 0.455 (an independent integration: 0.461, 0.450, 0.446 at
    // σ'v = 100, 200, 400 kPa for e0 0.70, with e = 0.6801, 0.6708, 0.6600).
    let mut sample = Sample::new(&LawSpec::from(sand(0.70, false)), 10.0, 10.0);
    let path = oedometer(&mut sample, &[0.05], 1e-5);
    for (sv, k0, e) in [
        (100.0, 0.461, 0.6801),
        (200.0, 0.450, 0.6708),
        (400.0, 0.446, 0.6600),
    ] {
        let i = path.partition_point(|r| r.axial_stress < sv);
        let r = path[i];
        let got = (r.axial_stress - r.q) / r.axial_stress;
        println!(
            "σ'v {:.1}: K0 {got:.4} ({k0}), e {:.4} ({e})",
            r.axial_stress, r.state[0]
        );
        assert!((got / k0 - 1.0).abs() < 0.01, "σ'v {sv}: K0 {got}");
        assert!(
            (r.state[0] / e - 1.0).abs() < 1e-3,
            "σ'v {sv}: e {}",
            r.state[0]
        );
    }
}
