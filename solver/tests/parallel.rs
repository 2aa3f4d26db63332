//! The parallel engine's promise: every output file but `run.json` (which holds timings) is
//! byte-identical for any thread count and both pin modes.

use std::path::{Path, PathBuf};

use assert_cmd::Command;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// The files of `dir` (recursively, but `run.json`, the checkpoint, which holds timings, and
/// the lock), with their bytes.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap();
            if name == "checkpoint" || name == ".lock" {
                continue;
            }
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().unwrap() != "run.json" {
                let name = path.strip_prefix(dir).unwrap().display().to_string();
                out.push((name, std::fs::read(&path).unwrap()));
            }
        }
    }
    out.sort();
    out
}

fn check_identical(scene: &Path, extra: &[&str]) {
    let mut reference: Option<Vec<(String, Vec<u8>)>> = None;
    for threads in ["1", "2", "3", "4"] {
        for pin in ["none", "cores", "auto"] {
            let dir = tempfile::tempdir().unwrap();
            Command::cargo_bin("mpm-solve")
                .unwrap()
                .arg(scene)
                .args(["--out", dir.path().to_str().unwrap()])
                .args(["--threads", threads, "--pin", pin])
                .args(extra)
                .assert()
                .success();
            let files = outputs(dir.path());
            assert!(files.len() > 4, "{files:?}");
            match &reference {
                None => reference = Some(files),
                Some(r) => {
                    assert_eq!(r.len(), files.len());
                    for (a, b) in r.iter().zip(&files) {
                        assert_eq!(a.0, b.0);
                        assert!(
                            a.1 == b.1,
                            "{} differs with --threads {threads} --pin {pin}",
                            a.0
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn dry_outputs_do_not_depend_on_threads_or_pinning() {
    // A soft column falling under gravity, undamped: points cross elements (and the engine
    // re-sorts them) within the run.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("column_gravity.toml"))
        .unwrap()
        .replace(
            "mesh = \"column_fine_tet4.msh\"",
            &format!("mesh = {:?}", testdata("column_fine_tet4.msh")),
        )
        .replace("young = 10000.0", "young = 300.0")
        .replace("local = 0.75", "local = 0.0")
        .replace("end = 0.6", "end = 0.06")
        .replace("output_interval = 0.1", "output_interval = 0.02");
    let scene = dir.path().join("soft.toml");
    std::fs::write(&scene, text).unwrap();
    check_identical(&scene, &["--probe", "5,77,1000"]);
}

#[test]
fn two_phase_outputs_do_not_depend_on_threads_or_pinning() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace(
            "mesh = \"oedometer_tet4.msh\"",
            &format!("mesh = {:?}", testdata("oedometer_tet4.msh")),
        )
        .replace("end_tv = 1.0", "end_tv = 0.05")
        .replace("output_tv = 0.05", "output_tv = 0.025");
    let scene = dir.path().join("oedometer.toml");
    std::fs::write(&scene, text).unwrap();
    check_identical(&scene, &["--reorder", "hilbert"]);
}

#[test]
fn anura3d_two_phase_outputs_do_not_depend_on_threads_or_pinning() {
    // The GOM route's own kernels: Anura3D's strain smoothing and damping split, and MPM-MIXED
    // pore pressures at Gauss points, on an exported consolidation column.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oracle_column.toml"))
        .unwrap()
        .replace(
            "mesh = \"oracle_column_tet4.msh\"",
            &format!("mesh = {:?}", testdata("oracle_column_tet4.msh")),
        )
        .replace("end_tv = 0.5", "end_tv = 0.05");
    let scene = dir.path().join("column.toml");
    std::fs::write(&scene, text).unwrap();
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, dir.path()).unwrap();
    let cps = std::fs::read_to_string(&files.cps)
        .unwrap()
        .replace("MPM-MP\n", "MPM-MIXED\n");
    assert!(cps.contains("MPM-MIXED"));
    std::fs::write(&files.cps, cps).unwrap();
    check_identical(&files.gom, &["--reorder", "hilbert", "--drag", "explicit"]);
}
