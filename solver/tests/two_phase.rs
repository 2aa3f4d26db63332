//! Two-phase (saturated) runs: Terzaghi consolidation against Anura3D's figures, the
//! permeability sweep at the Courant step, and what a dry scene does not allocate.

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_solve::driver::engine::Engine;
use mpm_solve::input::scene;
use mpm_solve::jobs::consolidation::{self, Start};

mod common;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// Anura3D (gfortran build) on the same 1,026-tet column, 4 points per tet, Courant 0.5, local
/// damping 0.05, sudden 10 kPa: RMS pore-pressure errors / u0 at these time factors.
const ANURA3D: [(f64, f64); 5] = [
    (0.05, 0.437),
    (0.1, 0.265),
    (0.2, 0.098),
    (0.5, 0.016),
    (1.0, 0.014),
];

#[test]
fn default_job_beats_anura3d_and_matches_terzaghi() {
    let case = scene::load(&testdata("oedometer.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (_, default, workshop) =
        consolidation::run_job::<f64, Tet4>(&case, dir.path(), &Default::default()).unwrap();
    let workshop = workshop.expect("the job also runs the workshop set-up");
    let at = |t: &consolidation::Tracker, tv: f64| {
        *t.records
            .iter()
            .find(|r| (r.tv - tv).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no output at T_v = {tv}"))
    };
    for (tv, anura) in ANURA3D {
        let (d, w) = (at(&default, tv), at(&workshop, tv));
        eprintln!(
            "T_v {tv}: RMS default {:.4}, workshop set-up {:.4} (Anura3D {anura})",
            d.rms, w.rms
        );
        assert!(
            w.rms <= anura,
            "workshop set-up at T_v {tv}: {} > {anura}",
            w.rms
        );
        assert!(d.rms <= 0.05, "default at T_v {tv}: {}", d.rms);
    }
    common::assert_terzaghi_thresholds(&default, &workshop);
    let csv = std::fs::read_to_string(dir.path().join("consolidation.csv")).unwrap();
    assert_eq!(csv.lines().count(), 21);
    assert!(csv.starts_with("tv,time,settlement,terzaghi_settlement,rms_error,max_error,workshop_"));
    assert!(dir.path().join("consolidation.png").exists());
}

/// The oedometer scene with another permeability, from the undrained state, for `end` seconds.
fn sweep_case(kappa: f64, end: f64) -> mpm_solve::input::case::Case {
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace("1.0214e-9", &format!("{kappa:e}"))
        .replace("compare_rest = true", "compare_rest = false")
        .replace("output_tv = 0.05", "")
        .replace("end_tv = 1.0", "")
        .replace(
            "courant = 0.5",
            &format!(
                "courant = 0.5\nend = {end}\noutput_interval = {}",
                end / 5.0
            ),
        )
        .replace(
            "mesh = \"oedometer_tet4.msh\"",
            &format!("mesh = {:?}", testdata("oedometer_tet4.msh")),
        );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sweep.toml");
    std::fs::write(&path, text).unwrap();
    scene::load(&path).unwrap()
}

#[test]
fn permeability_sweep_is_stable_at_the_courant_step_and_undrained_at_the_low_end() {
    let mut steps = Vec::new();
    for kappa in [1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 1e-16] {
        let case = sweep_case(kappa, 0.03);
        let dir = tempfile::tempdir().unwrap();
        let (engine, tracker) = mpm_solve::jobs::consolidation::run_tracked::<f64, Tet4>(
            &case,
            dir.path(),
            &Default::default(),
        )
        .unwrap();
        let u0 = tracker.layer.u0;
        steps.push(engine.dt);
        let p = engine.particles.liquid.as_ref().unwrap();
        assert!(
            p.p.iter().all(|x| x.is_finite()),
            "κ = {kappa}: non-finite pressure"
        );
        // Bounded energy: the kinetic energy never exceeds the work the load could do on the
        // whole undrained-to-drained settlement.
        let bound = tracker.layer.load * tracker.layer.area * 7.5e-3;
        let energy = std::fs::read_to_string(dir.path().join("energy.csv")).unwrap();
        for line in energy.lines().skip(1) {
            let ke: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
            assert!(
                ke.is_finite() && ke <= bound,
                "κ = {kappa}: kinetic energy {ke}"
            );
        }
        if kappa <= 1e-14 {
            // Undrained: every output keeps the excess pressure at u0 away from the top row.
            for r in &tracker.records {
                assert!(r.rms < 0.05, "κ = {kappa}, t = {}: RMS {}", r.time, r.rms);
            }
            let deep: Vec<f64> = (0..engine.particles.len())
                .filter(|&i| engine.particles.x[i][1] < 0.9)
                .map(|i| -p.p[i] / u0)
                .collect();
            let mean = deep.iter().sum::<f64>() / deep.len() as f64;
            assert!(
                (mean - 1.0).abs() < 0.01,
                "κ = {kappa}: mean excess pressure {mean} u0"
            );
        }
    }
    // The step does not depend on the permeability (the drag is implicit).
    assert!(
        steps.iter().all(|&d| (d - steps[0]).abs() <= 1e-12 * d),
        "{steps:?}"
    );
}

#[test]
fn dry_scenes_allocate_no_liquid_and_use_fewer_bytes_per_point() {
    let dry = scene::load(&testdata("column_gravity.toml")).unwrap();
    let wet = scene::load(&testdata("oedometer.toml")).unwrap();
    assert!(!dry.has_liquid() && wet.has_liquid());
    let d = Engine::<f64, Tet4>::new(&dry, false).unwrap();
    let w = Engine::<f64, Tet4>::new(&wet, false).unwrap();
    assert!(d.particles.liquid.is_none() && d.grid.liquid.is_none());
    assert!(w.particles.liquid.is_some() && w.grid.liquid.is_some());
    assert!(d.particles.bytes_per_point() < w.particles.bytes_per_point());
    assert!(d.grid.bytes() / d.grid.mass.len() < w.grid.bytes() / w.grid.mass.len());
    assert_eq!(wet.start.consolidation.unwrap().start, Start::Undrained);
}

#[test]
fn a_load_on_the_liquid_raises_the_pore_pressure_and_not_the_effective_stress() {
    // The oedometer with its 10 kPa moved from the skeleton to the liquid (a water pressure on
    // the drained top): at equilibrium the pore pressure carries all of it.
    let mut case = scene::load(&testdata("oedometer.toml")).unwrap();
    let zero = vec![[0.0; 3]; case.loads.traction.len()];
    case.loads.liquid_traction = std::mem::replace(&mut case.loads.traction, zero);
    case.start.consolidation = None;
    case.time.end_time = 0.75;
    case.time.output_times = vec![0.75];
    let dir = tempfile::tempdir().unwrap();
    let engine =
        mpm_solve::driver::run::run::<f64, Tet4>(&case, dir.path(), &Default::default()).unwrap();
    let p = &engine.particles;
    let l = p.liquid.as_ref().unwrap();
    let n = p.len() as f64;
    let pore = -l.p.iter().sum::<f64>() / n;
    let effective = p.stress.iter().map(|s| s[1]).sum::<f64>() / n;
    eprintln!(
        "mean excess pore pressure {pore:.4} kPa, mean effective sigma_yy {effective:.4} kPa"
    );
    assert!((pore - 10.0).abs() < 0.2, "pore pressure {pore}");
    assert!(effective.abs() < 0.2, "effective stress {effective}");
}
