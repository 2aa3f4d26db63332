//! The guard rails (docs/design.md §4.14): a case built to trip each, checking the message, the
//! exit code, `run.json`'s status and diagnosis, and that the last output reads back.

mod common;

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use common::testdata;
use mpm_shared::vtu_read;

/// The golden dry column (461 tetrahedra, one point each) edited by `edit`, as `dir/NAME.toml`.
fn column(dir: &Path, name: &str, edit: &dyn Fn(String) -> String) -> PathBuf {
    common::golden_scene(dir, "column_dry", name, edit)
}

fn solve(scene: &Path, out: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--quiet", "--threads", "2"])
        .args(extra)
        .assert()
}

fn run_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap()
}

/// The last particle file of `run.pvd` reads back with finite stresses and positions; returns
/// its time.
fn last_output_reads_back(out: &Path) -> f64 {
    let sets = vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
    let last = sets.last().expect("at least one output");
    let vtu = vtu_read::read_vtu_file(&out.join(&last.file)).unwrap();
    let stress = vtu.point_data("stress").expect("stress");
    let xyz = vtu.coordinates().expect("points");
    assert!(!stress.is_empty());
    for i in 0..stress.len() {
        for c in 0..6 {
            assert!(stress.get(i, c).is_finite(), "stress of point {i}");
        }
        for c in 0..3 {
            assert!(xyz.get(i, c).is_finite(), "position of point {i}");
        }
    }
    last.time
}

fn stderr_of(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stderr).into_owned()
}

#[test]
fn a_normal_run_completes_and_reports_its_energy_balance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    solve(&testdata("golden/column_dry.toml"), &out, &[]).success();
    let j = run_json(&out);
    assert_eq!(j["status"], "completed");
    assert_eq!(j["reason"], "reached the last output time");
    assert!(j["diagnosis"].is_null());
    let e = &j["energy"];
    for k in [
        "kinetic",
        "strain",
        "dissipated",
        "external_work",
        "balance_error",
    ] {
        assert!(e[k].as_f64().is_some(), "{k}");
    }
    // Kinetic + strain + dissipated balances the work within a few per mille here.
    assert!(e["balance_error"].as_f64().unwrap() < 0.01, "{e}");
    assert!(e["strain"].as_f64().unwrap() > 0.0 && e["dissipated"].as_f64().unwrap() > 0.0);
    let csv = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    assert!(csv.starts_with("time,kinetic,external_work,strain,dissipated,balance_error\n"));
}

/// Two-phase: the liquid's kinetic energy, the energy its compression holds and the drag
/// are counted, so the balance closes at every output and the checks apply.
#[test]
fn a_saturated_run_balances_its_energy_with_the_liquid() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    solve(&testdata("golden/column_saturated.toml"), &out, &[]).success();
    let e = &run_json(&out)["energy"];
    // Without the liquid's terms this column's balance was off by 0.75.
    assert!(e["balance_error"].as_f64().unwrap() < 0.01, "{e}");
    let liquid = e["liquid_compression"].as_f64().unwrap();
    assert!(
        liquid > 0.0 && liquid < e["strain"].as_f64().unwrap(),
        "{e}"
    );
    assert!(e["dissipated"].as_f64().unwrap() > 0.0, "{e}");
    let csv = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    for row in csv.lines().skip(1) {
        let balance: f64 = row.rsplit(',').next().unwrap().parse().unwrap();
        assert!(balance < 0.01, "{row}");
    }
    // The balance is checked in two-phase runs: a tolerance no run meets trips it.
    let out = dir.path().join("p");
    solve(
        &testdata("golden/column_saturated.toml"),
        &out,
        &["--energy-tolerance", "1e-9"],
    )
    .code(3);
    assert_eq!(run_json(&out)["diagnosis"]["check"], "energy_balance");
}

#[test]
fn a_courant_number_above_one_is_refused_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let scene = column(dir.path(), "c3", &|t| {
        t.replace("courant = 0.5", "courant = 3.0")
    });
    let a = solve(&scene, &dir.path().join("o"), &[]).code(1);
    let err = stderr_of(&a);
    assert!(err.contains("c3.toml: time.courant"), "{err}");
    assert!(err.contains("Courant number 3 is above 1") && err.contains("--force"));
    // --check refuses it too.
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&scene)
        .arg("--check")
        .assert()
        .code(1);
}

/// Courant 3 under --force on the oracle column: the unstable step flings a point out of the
/// mesh at step 6, before any other check trips. That is the instability, not a body leaving
/// its mesh: the run stops as diverged (exit 3), naming the step, the point and the Courant
/// number, with `run.json`.
#[test]
fn a_point_flung_out_by_a_forced_courant_number_is_an_instability() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oracle_column.toml"))
        .unwrap()
        .replace(
            "\"oracle_column_tet4.msh\"",
            &format!("{:?}", testdata("oracle_column_tet4.msh")),
        )
        .replace("courant = 0.5", "courant = 3.0");
    let scene = dir.path().join("c3.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("o");
    let a = solve(&scene, &out, &["--force"]).code(3);
    let err = stderr_of(&a);
    let j = run_json(&out);
    assert_eq!(j["status"], "diverged", "{j}");
    let d = &j["diagnosis"];
    assert_eq!(d["check"], "escaped", "{d}");
    assert_eq!(d["field"], "step_displacement", "{d}");
    assert!(d["value"].as_f64().unwrap() > 0.0, "{d}");
    assert!(d["step"].as_u64().unwrap() >= 1, "{d}");
    assert!(
        d["point"].as_u64().is_some() && d["element"].as_u64().is_some(),
        "{d}"
    );
    let cause = d["cause"].as_str().unwrap();
    assert!(
        cause.contains("forced past Courant 1 (Courant number 3)")
            && cause.contains("left the mesh"),
        "{cause}"
    );
    assert_eq!(j["reason"], d["message"], "{j}");
    assert!(err.contains("check escaped tripped"), "{err}");
    assert!(!err.contains("--drop-lost"), "{err}");
}

/// Courant 5, undamped, under --force: points collapse or the kinetic energy outgrows the work
/// done, and the cause named is the time step.
#[test]
fn a_forced_courant_number_of_five_is_caught() {
    let dir = tempfile::tempdir().unwrap();
    let scene = column(dir.path(), "c5", &|t| {
        t.replace("courant = 0.5", "courant = 5.0")
            .replace("local = 0.75", "local = 0.0")
            .replace("end = 0.01", "end = 0.2")
    });
    let out = dir.path().join("o");
    let a = solve(&scene, &out, &["--force", "--energy-tolerance", "off"]).code(3);
    let err = stderr_of(&a);
    let j = run_json(&out);
    assert_eq!(j["status"], "diverged", "{j}");
    let d = &j["diagnosis"];
    let check = d["check"].as_str().unwrap();
    assert!(
        check == "blow_up" || check == "non_finite" || check == "volume",
        "{d}"
    );
    assert!(d["step"].as_u64().unwrap() >= 1);
    assert!(d["time"].as_f64().unwrap() > 0.0);
    assert!(
        d["point"].as_u64().is_some() && d["element"].as_u64().is_some(),
        "{d}"
    );
    let cause = d["cause"].as_str().unwrap();
    assert!(
        cause.starts_with("time step 5× the critical step of element "),
        "{cause}"
    );
    assert!(
        err.contains("run diverged at step") && err.contains(cause),
        "{err}"
    );
    assert!(err.contains("\"status\": \"diverged\""), "{err}");
    let t = last_output_reads_back(&out);
    assert!(t <= d["time"].as_f64().unwrap());
}

/// A tolerance no explicit run meets trips the energy balance at the first step it is checked
/// at; the failing state, still finite, is the last output.
#[test]
fn a_tiny_energy_tolerance_trips_the_balance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let a = solve(
        &testdata("golden/column_dry.toml"),
        &out,
        &["--energy-tolerance", "1e-9"],
    )
    .code(3);
    let j = run_json(&out);
    let d = &j["diagnosis"];
    assert_eq!(
        (d["check"].as_str(), d["step"].as_u64()),
        (
            Some("energy_balance"),
            Some(mpm_solve::driver::engine::BALANCE_FROM_STEP + 1)
        )
    );
    assert_eq!(d["field"], "energy_balance");
    assert!(d["value"].as_f64().unwrap() > 1e-9);
    assert!(d["cause"].as_str().unwrap().contains("--energy-tolerance"));
    assert!(stderr_of(&a).contains("check energy_balance tripped"));
    // The particle file's time, as the PVD prints it, is the failing step's.
    let t = d["time"].as_f64().unwrap();
    assert!((last_output_reads_back(&out) - t).abs() <= 1e-12 * t);
    // Off: the same run completes.
    solve(
        &testdata("golden/column_dry.toml"),
        &dir.path().join("p"),
        &["--energy-tolerance", "off"],
    )
    .success();
}

/// A material far too soft for its weight (E = 1 kPa under 20 kPa): the bottom points are
/// crushed.
#[test]
fn a_collapsing_material_trips_the_volume_check() {
    let dir = tempfile::tempdir().unwrap();
    let scene = column(dir.path(), "soft", &|t| {
        t.replace("young = 10000.0", "young = 1.0")
            .replace("end = 0.01", "end = 2.0")
            .replace("output_interval = 0.005", "output_interval = 0.1")
    });
    let out = dir.path().join("o");
    let a = solve(&scene, &out, &[]).code(3);
    let d = run_json(&out)["diagnosis"].clone();
    assert_eq!(d["check"], "volume", "{d}");
    assert_eq!(d["field"], "volume_ratio");
    assert!(d["value"].as_f64().unwrap() <= 1e-3);
    let (p, e) = (d["point"].as_u64().unwrap(), d["element"].as_u64().unwrap());
    assert!((1..=461).contains(&p) && (1..=461).contains(&e));
    let err = stderr_of(&a);
    assert!(
        err.contains(&format!("at material point {p} in element {e}")),
        "{err}"
    );
    assert!(err.contains("crushed"));
    last_output_reads_back(&out);
}

/// A non-finite stress (injected) is found at the next step and named by point, element and
/// field.
#[test]
fn a_non_finite_stress_is_named() {
    use mpm_solve::driver::engine::{Check, Engine, StepError};
    let case = mpm_solve::input::scene::load(&testdata("golden/column_dry.toml")).unwrap();
    let mut engine = Engine::<f64, Tet4>::new(&case, false).unwrap();
    engine.step(engine.dt, None).unwrap();
    let i = 100;
    engine.particles.stress[i][1] = f64::NAN;
    let id = engine.particles.id[i];
    match engine.step(engine.dt, None) {
        Err(StepError::Diverged(d)) => {
            assert_eq!((d.check, d.step), (Check::NonFinite, 2));
            assert!(d.value.is_nan());
            assert!(d.point.is_some() && d.element.is_some());
            assert!(["stress", "velocity", "position"].contains(&d.field), "{d}");
            // The injected point is reported when its stress is still the only bad value.
            if d.field == "stress" {
                assert_eq!(d.point, Some(id));
            }
            assert!(d.to_string().contains("check non_finite tripped"));
        }
        other => panic!("expected a divergence, got {other:?}"),
    }
}

/// Guards switched off (a library caller's choice: `case.run.guards.enabled`) run the same steps
/// to the same state, in both precisions and on both the dry and the two-phase column: the
/// stress pass's batches once read the guards' per-material values unconditionally.
#[test]
fn guards_off_run_to_the_same_state() {
    use mpm_solve::driver::engine::Engine;
    fn run<R: mpm_solve::real::Real>(scene: &str, guards: bool) -> Vec<f64> {
        let mut case = mpm_solve::input::scene::load(&testdata(scene)).unwrap();
        case.run.guards.enabled = guards;
        let mut engine = Engine::<R, Tet4>::new(&case, false).unwrap();
        for _ in 0..5 {
            engine.step(engine.dt, None).unwrap();
        }
        let p = &engine.particles;
        p.stress
            .iter()
            .flatten()
            .chain(p.x.iter().flatten())
            .map(|v| v.f64())
            .collect()
    }
    for scene in ["golden/column_dry.toml", "golden/column_saturated.toml"] {
        let on = run::<f64>(scene, true);
        assert_eq!(on, run::<f64>(scene, false), "{scene} f64");
        let on = run::<f32>(scene, true);
        assert_eq!(on, run::<f32>(scene, false), "{scene} f32");
    }
}
