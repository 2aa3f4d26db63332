//! Runs over MPI ranks give the files of the threaded run, byte for byte (cargo feature `mpi`,
//! with `mpirun` on the path): `cargo test --release -p mpm-solve --features mpi --test mpi`.
#![cfg(feature = "mpi")]

mod common;

use common::outputs;
use std::path::Path;
use std::process::Command;

fn mpirun(ranks: usize, case: &str, out: &Path, rebalance: &str) {
    let status = Command::new("mpirun")
        .args(["--oversubscribe", "-np", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_mpm-solve"))
        .arg(case)
        .arg("--out")
        .arg(out)
        .args(["--threads", "1", "-q", "--rebalance", rebalance])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .status()
        .expect("mpirun on the path");
    assert!(status.success(), "{case} on {ranks} ranks: {status}");
}

fn same_for_any_rank_count(case: &str, migrates: bool) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let case = root.join(case);
    let case = case.to_str().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let threaded = tmp.path().join("threaded");
    let status = Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
        .arg(case)
        .arg("--out")
        .arg(&threaded)
        .args(["--threads", "2", "-q"])
        .status()
        .unwrap();
    assert!(status.success());
    let want = outputs(&threaded);
    assert!(want.iter().any(|(n, _)| n.starts_with("particles_")));
    // `--rebalance 0` keeps the first cut (points migrate across it); `1` cuts the curve
    // again whenever a rank holds more points than the mean and a cut can do better.
    for (ranks, rebalance) in [(1, "0"), (2, "0"), (3, "0"), (4, "0"), (2, "1"), (3, "1")] {
        let dir = tmp.path().join(format!("np{ranks}-{rebalance}"));
        mpirun(ranks, case, &dir, rebalance);
        let got = outputs(&dir);
        assert_eq!(
            got.iter().map(|f| &f.0).collect::<Vec<_>>(),
            want.iter().map(|f| &f.0).collect::<Vec<_>>(),
            "{ranks} ranks: the same files"
        );
        for ((name, a), (_, b)) in got.iter().zip(&want) {
            assert!(
                a == b,
                "{case}, {ranks} ranks: {name} differs from the threaded run's"
            );
        }
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("run.json")).unwrap()).unwrap();
        if ranks > 1 {
            let per_rank = json["ranks"].as_array().expect("per-rank report");
            assert_eq!(per_rank.len(), ranks);
            let now: Vec<u64> = per_rank
                .iter()
                .map(|r| r["points"].as_u64().unwrap())
                .collect();
            assert!(per_rank
                .iter()
                .all(|r| r["bytes_sent"].as_u64().unwrap() > 0));
            let repartitions = json["balance"]["repartitions"].as_u64().unwrap();
            if rebalance == "0" {
                assert_eq!(repartitions, 0);
            } else if migrates {
                assert!(repartitions > 0, "{ranks} ranks: never re-partitioned");
                assert!(per_rank
                    .iter()
                    .any(|r| r["points_moved_by_repartitions"].as_u64().unwrap() > 0));
            }
            if migrates && rebalance == "0" {
                // 4 points per element at the start: points have changed rank since.
                let started: Vec<u64> = per_rank
                    .iter()
                    .map(|r| 4 * r["elements"].as_u64().unwrap())
                    .collect();
                assert_ne!(now, started, "no point migrated");
                assert_eq!(now.iter().sum::<u64>(), started.iter().sum::<u64>());
            }
        }
    }
}

#[test]
fn a_two_phase_column_is_the_same_on_one_to_four_ranks() {
    same_for_any_rank_count("testdata/golden/column_saturated.toml", false);
}

#[test]
fn points_migrating_between_ranks_give_the_threaded_results() {
    same_for_any_rank_count("testdata/mc_column_soft.toml", true);
}

/// Bulk viscosity: each point's viscous pressure and strain rate travel with it between ranks,
/// and the critical step is the same minimum.
#[test]
fn bulk_viscosity_is_the_same_on_one_to_four_ranks() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let golden = root.join("testdata/golden");
    let text = std::fs::read_to_string(golden.join("column_saturated.toml")).unwrap();
    let mesh = golden.join("../column_tet4.msh");
    let text = text
        .replace("\"../column_tet4.msh\"", &format!("{:?}", mesh))
        .replace("[damping]\n", "[damping]\nbulk_viscosity = [0.2, 1.5]\n");
    assert!(text.contains("bulk_viscosity") && !text.contains("\"../"));
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("bulk.toml");
    std::fs::write(&scene, text).unwrap();
    same_for_any_rank_count(scene.to_str().unwrap(), false);
}

/// The stencil passes keep no slots to exchange (docs/design.md §4.20): a background grid or
/// the dual-domain gradients over several ranks stop before the run, naming what is refused.
#[test]
fn a_grid_or_dual_domain_run_over_ranks_is_refused_by_name() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let testdata = root.join("testdata");
    let text = std::fs::read_to_string(testdata.join("oedometer.toml")).unwrap();
    let mesh = testdata.join("oedometer_tet4.msh");
    // A plain timed run: the consolidation job itself runs on one process only.
    let text = text.split("[consolidation]").next().unwrap();
    let text = text
        .replace("\"oedometer_tet4.msh\"", &format!("{mesh:?}"))
        .replace("[time]\n", "[time]\nend = 0.001\noutput_interval = 0.001\n");
    assert!(!text.contains("\"oedometer_tet4.msh\"") && text.contains("end = 0.001"));
    let tmp = tempfile::tempdir().unwrap();
    let grid = tmp.path().join("grid.toml");
    std::fs::write(
        &grid,
        text.replacen("[time]", "[grid]\ncell = 0.1\n[time]", 1),
    )
    .unwrap();
    let plain = tmp.path().join("plain.toml");
    std::fs::write(&plain, &text).unwrap();
    for (scene, extra, named) in [
        (
            &grid,
            None,
            "background grid ([grid]) cannot model a run over several MPI ranks",
        ),
        (&plain, Some("ddmp"), "dual-domain gradients"),
    ] {
        let mut cmd = Command::new("mpirun");
        cmd.args(["--oversubscribe", "-np", "2"])
            .arg(env!("CARGO_BIN_EXE_mpm-solve"))
            .arg(scene)
            .arg("--out")
            .arg(tmp.path().join("out"))
            .args(["--threads", "1", "-q"])
            .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        if let Some(basis) = extra {
            cmd.args(["--basis", basis]);
        }
        let out = cmd.output().expect("mpirun on the path");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{scene:?} ran over 2 ranks");
        assert!(stderr.contains(named), "{scene:?}: {stderr}");
        assert!(stderr.contains("MPI ranks"), "{scene:?}: {stderr}");
    }
}
