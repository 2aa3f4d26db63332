//! `mpm-solve` from the command line: outputs, determinism, bad input.

use std::path::Path;

use assert_cmd::Command;
use predicates::prelude::*;

mod common;
use common::scene;

/// `mpm-solve INPUT --out OUT`, expected to fail.
fn fails(input: &Path, out: &Path) -> assert_cmd::assert::Assert {
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(input)
        .arg("--out")
        .arg(out)
        .assert()
        .failure()
}

#[test]
fn writes_every_output_and_repeats_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for out in [&a, &b] {
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&s)
            .arg("--out")
            .arg(out)
            .args(["--probe", "1,5"])
            .assert()
            .success();
    }
    let mut names: Vec<String> = std::fs::read_dir(&a)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n != "checkpoint" && n != ".lock")
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "energy.csv",
            "history.csv",
            "mesh.vtu",
            "particles_00000.vtu",
            "particles_00001.vtu",
            "run.json",
            "run.pvd"
        ]
    );
    for n in &names {
        if n != "run.json" {
            assert!(
                std::fs::read(a.join(n)).unwrap() == std::fs::read(b.join(n)).unwrap(),
                "{n} differs between runs"
            );
        }
    }
    let history = std::fs::read_to_string(a.join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), 1 + 2 * 2);
    assert!(history.starts_with("time,id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,syz,szx\n0.01,1,"));
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("run.json")).unwrap()).unwrap();
    for key in [
        "particles",
        "elements",
        "steps",
        "threads",
        "precision",
        "wall_seconds",
        "particle_steps_per_second",
        "phase_seconds",
        "phase_ns_per_particle_step",
        "phase_threads_ns_per_particle_step",
        "modelled_bytes_per_particle_step",
        "bytes_per_particle",
        "peak_rss_bytes",
    ] {
        assert!(run.get(key).is_some(), "run.json lacks {key}");
    }
    // Every step phase has a positive modelled traffic but the grid update, which may be
    // small, and locate: this scene's points are located in the stress pass (no moving mesh,
    // one body, lost points stop the run), which leaves the locate phase no point data of its
    // own to move. All are finite.
    for phase in ["particle_to_grid", "grid_to_particle", "stress"] {
        let b = run["modelled_bytes_per_particle_step"][phase]
            .as_f64()
            .unwrap();
        assert!(b > 0.0 && b.is_finite(), "{phase}: {b}");
    }
    assert_eq!(run["modelled_bytes_per_particle_step"]["locate"], 0.0);
    // Where the threads' time went: the mean thread's work is positive in every step phase,
    // and no part is negative beyond the clocks' resolution.
    for phase in [
        "particle_to_grid",
        "grid_update",
        "grid_to_particle",
        "stress",
        "locate",
    ] {
        let t = &run["phase_threads_ns_per_particle_step"][phase];
        let work = t["work"].as_f64().unwrap();
        // The locate phase's team passes are the re-sort's, when points changed element.
        let least = if phase == "locate" {
            0.0
        } else {
            f64::MIN_POSITIVE
        };
        assert!(work >= least && work.is_finite(), "{phase}: {t}");
        for part in ["imbalance", "pool"] {
            let v = t[part].as_f64().unwrap();
            assert!(v >= 0.0 && v.is_finite(), "{phase} {part}: {t}");
        }
    }
    assert_eq!(run["precision"], "f64");
    // Whether the point passes took their AVX2 copies: never in a build that assumes AVX2.
    let copies = run["avx2_copies"].as_bool().unwrap();
    assert!(!(copies && run["instruction_set"] != "x86-64"), "{run}");
}

#[test]
fn bad_scenes_fail_with_a_clear_message_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&dyn Fn(String) -> String, &str); 6] = [
        (
            &|t| t.replace("courant = 0.5", "courant = 0.0"),
            "time.courant",
        ),
        (
            &|t| t.replace("courant = 0.5", "courant = 1.5"),
            "time.courant",
        ),
        (
            &|t| t.replace("density = 2000.0", "density = -1.0"),
            "density must be positive",
        ),
        (
            &|t| t.replace("young = 10000.0", "young = 0.0"),
            "Young's modulus must be positive",
        ),
        (
            &|t| t.replace("physical = \"soil\"", "physical = \"rock\""),
            "material \"rock\"",
        ),
        (
            &|t| {
                t.replace(
                    "[[fixity]]\nphysical = \"bottom\"",
                    "[[fixity]]\nphysical = \"floor\"",
                )
            },
            "fixity \"floor\"",
        ),
    ];
    for (i, (edit, message)) in cases.iter().enumerate() {
        let sub = dir.path().join(format!("case{i}"));
        std::fs::create_dir(&sub).unwrap();
        let s = scene(&sub, edit);
        let out = sub.join("out");
        fails(&s, &out)
            .stderr(predicate::str::contains(*message).and(predicate::str::contains("scene.toml")));
        assert!(!out.exists(), "case {i} wrote outputs");
    }
    // A consolidation table with a start it does not know, and a porosity out of range.
    for (edit, message) in [
        (
            "[consolidation]\nload = 10.0\nstart = \"sudden\"\n",
            "consolidation.start",
        ),
        (
            "[material.liquid]\nporosity = 1.5\ndensity = 1000.0\nbulk_modulus = 2e4\nintrinsic_permeability = 1e-9\nviscosity = 1e-6\n",
            "porosity must be in (0, 1)",
        ),
    ] {
        let sub = dir.path().join(message.replace(' ', "_"));
        std::fs::create_dir(&sub).unwrap();
        let s = scene(&sub, &|t| format!("{t}\n{edit}"));
        let out = sub.join("out");
        fails(&s, &out).stderr(predicate::str::contains(message));
        assert!(!out.exists());
    }
    // Zero threads is refused before anything is written.
    let s = scene(dir.path(), &|t| t);
    let out = dir.path().join("t0");
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&s)
        .args(["--out", out.to_str().unwrap(), "--threads", "0"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("--threads must be at least 1"));
    assert!(!out.exists());
    // A mistyped count is refused at once, before its threads are started (there were minutes
    // of them before the message).
    let started = std::time::Instant::now();
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&s)
        .args(["--out", out.to_str().unwrap(), "--threads", "99999"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("--threads 99999: at most 1024"));
    assert!(started.elapsed().as_secs() < 20);
    assert!(!out.exists());
    // Unknown keys are refused with their line.
    let s = scene(dir.path(), &|t| t.replace("[time]", "[time]\nspeed = 3"));
    fails(&s, &dir.path().join("o")).stderr(
        predicate::str::contains("unknown field `speed`").and(predicate::str::contains("line")),
    );
}

#[test]
fn anura3d_cases_are_checked() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(root) = found else {
        mpm_shared::suite::skipped("anura3d_cases_are_checked (ANURA3D_BENCHMARKS not set)");
        return;
    };
    let gom = root.join("Benchmarks/Pre-Commit_Tests/1005_Oedometer_QS_MPMMP_1Phase_NormalStress_3D/test-1005_3D.A3D/test-1005_3D.GOM");
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&gom)
        .arg("--check")
        .assert()
        .success()
        .stdout(predicate::str::contains("66 tetrahedral_old elements"));
}

#[test]
fn bad_anura3d_cases_name_the_item() {
    use mpm_shared::{generate, ElementType};
    let dir = tempfile::tempdir().unwrap();
    let model = generate::box_mesh([1, 2, 1], [1.0; 3], ElementType::Tet10);
    let gom = dir.path().join("box.GOM");
    mpm_shared::write_gom_file(&model, &gom).unwrap();
    // No CPS beside the GOM.
    fails(&gom, &dir.path().join("o")).stderr(predicate::str::contains("box.CPS_001"));
    // A CPS, but the material has no type this solver knows.
    std::fs::write(
        dir.path().join("box.CPS_001"),
        "### Anura3D_2021 ###\n$$COMPUTATION_METHOD\nMPM-MP\n$$TIME_PER_LOADSTEP\n0.1\n$$END\n",
    )
    .unwrap();
    fails(&gom, &dir.path().join("o")).stderr(
        predicate::str::contains("material 1 \"soil\"")
            .and(predicate::str::contains("MATERIAL_TYPE")),
    );
    // Courant number out of range (a positive one above 1 is refused after reading, unless
    // --force: tests/guard_rails.rs).
    std::fs::write(dir.path().join("box.CPS_001"), "### Anura3D_2021 ###\n$$COMPUTATION_METHOD\nMPM-MP\n$$TIME_PER_LOADSTEP\n0.1\n$$COURANT_NUMBER\n0\n$$END\n").unwrap();
    fails(&gom, &dir.path().join("o")).stderr(predicate::str::contains("$$COURANT_NUMBER"));
    assert!(!dir.path().join("o").exists());
    // A GOM on standard input needs --cps.
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg("-")
        .arg("--out")
        .arg(dir.path().join("o"))
        .write_stdin(std::fs::read(&gom).unwrap())
        .assert()
        .failure()
        .stderr(predicate::str::contains("--cps"));
}

/// A scene or a CPS that never ends (a link to `/dev/zero`) is refused at once, naming the
/// file, instead of being read until memory runs out.
#[cfg(unix)]
#[test]
fn parameter_files_without_end_are_refused() {
    use mpm_shared::{generate, ElementType};
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("endless.toml");
    std::os::unix::fs::symlink("/dev/zero", &scene).unwrap();
    fails(&scene, &dir.path().join("o")).stderr(
        predicate::str::contains("endless.toml").and(predicate::str::contains("longer than")),
    );
    let model = generate::box_mesh([1, 1, 1], [1.0; 3], ElementType::Tet10);
    let gom = dir.path().join("box.GOM");
    mpm_shared::write_gom_file(&model, &gom).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("box.CPS_001")).unwrap();
    fails(&gom, &dir.path().join("o")).stderr(
        predicate::str::contains("box.CPS_001").and(predicate::str::contains("longer than")),
    );
    assert!(!dir.path().join("o").exists());
}

/// A report on standard output whose reader goes away (`| head -1`) ends the printing, not the
/// command (no panic, exit 0); one that cannot be written (a full device) fails the command with
/// a message, not a panic.
#[cfg(unix)]
#[test]
fn standard_output_that_closes_or_fills_is_not_a_panic() {
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    let bin = assert_cmd::cargo::cargo_bin("mpm-solve");
    // A reader that takes nothing: the pipe is closed before the plan is printed.
    let mut child = std::process::Command::new(&bin)
        .arg(&s)
        .arg("--check")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    if std::path::Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = std::process::Command::new(&bin)
            .arg(&s)
            .arg("--check")
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains("cannot write to standard output"),
            "{stderr}"
        );
    }
}
