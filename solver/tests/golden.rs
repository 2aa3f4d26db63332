//! Golden files: small cases whose outputs (all but `run.json`, which holds timings) must stay
//! byte-identical to those committed in `testdata/golden/CASE/`, for 1 and 3 threads. A change
//! of results, deliberate or not, fails here; after a deliberate one, regenerate with
//! `UPDATE_GOLDEN=1 cargo test --release -p mpm-solve --test golden` and commit the files with
//! the change that explains them.

use std::path::{Path, PathBuf};

use assert_cmd::Command;

fn golden() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata/golden")
}

/// The cases: name, input file in `testdata/golden/`, extra arguments.
const CASES: [(&str, &str, &[&str]); 5] = [
    ("column_dry", "column_dry.toml", &[]),
    ("column_saturated", "column_saturated.toml", &[]),
    // Single precision is deterministic too, per precision.
    ("column_dry_f32", "column_dry.toml", &["--precision", "f32"]),
    (
        "column_saturated_f32",
        "column_saturated.toml",
        &["--precision", "f32"],
    ),
    (
        "column_anura3d",
        "column_anura3d.GOM",
        &["--drag", "explicit"],
    ),
];

/// The output files: `run.json` (timings), the checkpoint and the lock left out.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !matches!(n.as_str(), "run.json" | "checkpoint" | ".lock"))
        .collect();
    names.sort();
    names
}

#[test]
fn outputs_match_the_golden_files_for_any_thread_count() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some_and(|v| !v.is_empty());
    for (name, input, extra) in CASES {
        let expected = golden().join(name);
        for threads in ["1", "3"] {
            let tmp = tempfile::tempdir().unwrap();
            let out = tmp.path().join("out");
            Command::cargo_bin("mpm-solve")
                .unwrap()
                .arg(golden().join(input))
                .arg("--out")
                .arg(&out)
                .args(["--quiet", "--threads", threads])
                .args(extra)
                .assert()
                .success();
            if update && threads == "1" {
                let _ = std::fs::remove_dir_all(&expected);
                std::fs::create_dir_all(&expected).unwrap();
                for f in files(&out) {
                    std::fs::copy(out.join(&f), expected.join(&f)).unwrap();
                }
                eprintln!("golden: rewrote {}", expected.display());
                continue;
            }
            assert_eq!(
                files(&out),
                files(&expected),
                "{name}: the set of output files changed"
            );
            for f in files(&out) {
                let (a, b) = (
                    std::fs::read(out.join(&f)).unwrap(),
                    std::fs::read(expected.join(&f)).unwrap(),
                );
                assert!(
                    a == b,
                    "{name} ({threads} threads): {f} differs from testdata/golden/{name}/{f}; if the change is meant, regenerate with UPDATE_GOLDEN=1 cargo test --release -p mpm-solve --test golden"
                );
            }
        }
    }
}
