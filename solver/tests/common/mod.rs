//! Helpers shared by the command-line test files.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

pub mod gom;

/// A file of the workspace's `testdata/`.
pub fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// The gravity column scene on the coarse mesh, 20 ms in two outputs, edited by `edit`,
/// written as `dir/scene.toml`.
pub fn scene(dir: &Path, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata("column_gravity.toml"))
        .unwrap()
        .replace(
            "column_fine_tet4.msh",
            &testdata("column_tet4.msh").display().to_string(),
        )
        .replace("end = 0.6", "end = 0.02")
        .replace("output_interval = 0.1", "output_interval = 0.01");
    let p = dir.join("scene.toml");
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// A golden column scene (`column_dry` or `column_saturated`) with the mesh path made absolute
/// and `edit` applied, as `dir/NAME.toml`.
pub fn golden_scene(
    dir: &Path,
    golden: &str,
    name: &str,
    edit: &dyn Fn(String) -> String,
) -> PathBuf {
    let text = std::fs::read_to_string(testdata(&format!("golden/{golden}.toml")))
        .unwrap()
        .replace(
            "../column_tet4.msh",
            &testdata("column_tet4.msh").display().to_string(),
        );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// The default job's thresholds against Terzaghi, for any of its twins: from T_v = 0.05 on, the
/// default run's RMS pore-pressure error at most 0.05 of u0, and both runs' final settlement
/// within 0.5 % of Terzaghi's.
pub fn assert_terzaghi_thresholds(
    default: &mpm_solve::jobs::consolidation::Tracker,
    workshop: &mpm_solve::jobs::consolidation::Tracker,
) {
    for r in default.records.iter().filter(|r| r.tv >= 0.05 - 1e-9) {
        assert!(r.rms <= 0.05, "default at T_v {}: {}", r.tv, r.rms);
    }
    for t in [default, workshop] {
        let last = t.records.last().unwrap();
        let err = last.settlement / last.terzaghi - 1.0;
        eprintln!(
            "final settlement {:.4e} m, {:+.3}% off Terzaghi, RMS {:.4}",
            last.settlement,
            100.0 * err,
            last.rms
        );
        assert!(err.abs() <= 0.005, "settlement {err}");
    }
}

/// The Anura3D binary `ANURA3D_ORACLE` names, or `None` (the comparison `what` is reported as
/// skipped) when it is unset.
pub fn oracle(what: &str) -> Option<PathBuf> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_oracle(&workspace).unwrap_or_else(|e| panic!("{e}"));
    if found.is_none() {
        mpm_shared::suite::skipped(&format!("{what} (ANURA3D_ORACLE not set)"));
    }
    found
}

/// Runs Anura3D on `dir/NAME.GOM` + `dir/NAME.CPS_001` in `dir`; fails unless it finishes.
pub fn run_oracle(bin: &Path, dir: &Path, name: &str) {
    let out = std::process::Command::new(bin)
        .arg(name)
        .current_dir(dir)
        .output()
        .expect("run Anura3D");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Calculation finished."),
        "Anura3D did not finish:\n{}",
        &text[text.len().saturating_sub(2000)..]
    );
}

/// The files of `dir` (recursively, but `run.json`, the checkpoint, which holds timings, and
/// the lock), with their bytes.
pub fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
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
