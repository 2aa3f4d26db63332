//! What sfcb does with inputs a new user meets first: coordinates too far apart to order,
//! coincident duplicate nodes, and the `--report` JSON a script reads.

use std::path::{Path, PathBuf};

use mpm_shared::{gom, Model};
use predicates::prelude::*;

mod common;
use common::{sfcb, testdata};

fn cube() -> Model {
    let name = "cube_tet4.GOM";
    gom::read(&std::fs::read(testdata(name)).unwrap(), name).unwrap()
}

/// Writes `model` as `name` in `dir`.
fn write(dir: &Path, name: &str, model: &Model) -> PathBuf {
    let p = dir.join(name);
    mpm_shared::write_gom_file(model, &p).unwrap();
    p
}

#[test]
fn coordinates_too_far_apart_are_refused_naming_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = cube();
    // Node 1 at x = -1e308 and node 2 at x = +1e308: both finite, their distance is not.
    m.coords[0] = -1e308;
    m.coords[3] = 1e308;
    let far = write(dir.path(), "far.GOM", &m);
    let out = dir.path().join("out.GOM");
    for curve in ["morton", "hilbert"] {
        for extra in [&[][..], &["--no-cubic"]] {
            sfcb()
                .arg(&far)
                .arg(&out)
                .args(["--curve", curve])
                .args(extra)
                .assert()
                .failure()
                .stderr(
                    predicate::str::starts_with("sfcb: error: ")
                        .and(predicate::str::contains("far.GOM"))
                        .and(predicate::str::contains("the x extent"))
                        .and(predicate::str::contains("1e308"))
                        .and(predicate::str::contains("panicked").not()),
                );
            assert!(!out.exists(), "{curve}: an output was written");
        }
    }
    // Plain conversion needs no extent: the coordinates are finite and written back as read.
    sfcb()
        .arg(&far)
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .success();
    assert!(std::fs::read(&out).unwrap() == std::fs::read(&far).unwrap());
}

#[test]
fn library_ordering_names_a_non_finite_node() {
    // A model built in code (not read from a file, whose reader refuses NaN) reaches the
    // ordering itself, as mpm-solve's --reorder does.
    let mut m = cube();
    m.coords[3 * 6 + 2] = f64::NAN;
    let e = sfcb::order::order(
        &m,
        sfcb::order::Options {
            curve: sfcb::order::Curve::Morton,
            levels: 21,
            cubic: true,
        },
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "node 7 has z = NaN; coordinates must be finite numbers"
    );
}

#[test]
fn non_numbers_in_the_file_are_refused_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("cube_tet4.GOM")).unwrap();
    // Line 12 holds node 2.
    let bad = text.replacen("0.0 0.0 0.0\n", "0.0 NaN 0.0\n", 1);
    assert_ne!(bad, text);
    let p = dir.path().join("nan.GOM");
    std::fs::write(&p, bad).unwrap();
    let out = dir.path().join("out.GOM");
    for curve in ["morton", "none"] {
        sfcb()
            .arg(&p)
            .arg(&out)
            .args(["--curve", curve])
            .assert()
            .failure()
            .stderr(predicate::str::contains("nan.GOM:12").and(predicate::str::contains("NaN")));
        assert!(!out.exists());
    }
}

#[test]
fn coincident_nodes_are_warned_about_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = cube();
    let n = m.node_count();
    // Copies of nodes 1..=13 appended after the last node: 13 pairs.
    let copies = m.coords[..13 * 3].to_vec();
    m.coords.extend_from_slice(&copies);
    let dup = write(dir.path(), "dup.GOM", &m);
    let out = dir.path().join("out.GOM");
    let first = format!("nodes 1 and {}, 2 and {}, ", n + 1, n + 2);
    let tenth = format!("10 and {}, and 3 more", n + 10);
    sfcb()
        .arg(&dup)
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .success()
        .stderr(
            predicate::str::starts_with("sfcb: warning: ")
                .and(predicate::str::contains("dup.GOM: "))
                .and(predicate::str::contains("13 node(s)"))
                .and(predicate::str::contains(first))
                .and(predicate::str::contains(tenth))
                .and(predicate::str::contains(format!("11 and {}", n + 11)).not()),
        );
    // Nothing merged or dropped: a conversion gives the input back.
    assert!(std::fs::read(&out).unwrap() == std::fs::read(&dup).unwrap());
    // Ordering keeps every node too.
    sfcb().arg(&dup).arg(&out).assert().success();
    let r = gom::read(&std::fs::read(&out).unwrap(), "out.GOM").unwrap();
    assert_eq!(r.node_count(), n + 13);
    // A mesh without copies gets no warning.
    sfcb()
        .arg(testdata("cube_tet4.GOM"))
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("warning").not());
}

/// Every number in `v` (recursively).
fn numbers(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(x) => out.push(x.as_f64().unwrap()),
        serde_json::Value::Array(a) => a.iter().for_each(|x| numbers(x, out)),
        serde_json::Value::Object(o) => o.values().for_each(|x| numbers(x, out)),
        _ => {}
    }
}

#[test]
fn report_is_strict_json_with_a_schema_version() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("report.json");
    sfcb()
        .arg(testdata("column_tet10.GOM"))
        .arg(dir.path().join("out.vtu"))
        .args(["--partitions", "4", "--merge-pieces", "--report"])
        .arg(&report)
        .assert()
        .success();
    let text = std::fs::read_to_string(&report).unwrap();
    // serde_json refuses NaN and Infinity tokens: parsing is the strictness check.
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema_version"], 1, "{text}");
    assert_eq!(v["partitions"]["parts"], 4, "{text}");
    assert!(
        v["locality"]["after"]["mean_id_spread"].is_number(),
        "{text}"
    );
    let mut all = Vec::new();
    numbers(&v, &mut all);
    assert!(
        all.len() > 10 && all.iter().all(|x| x.is_finite()),
        "{text}"
    );
    // On standard output, next to a mesh written to a file.
    let out = sfcb()
        .arg(testdata("square_tri3.GOM"))
        .arg(dir.path().join("sq.GOM"))
        .args(["--report", "-"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["schema_version"], 1);
    assert_eq!(v["dimension"], 2);
}

/// An output named through a symbolic link is written to the link's target, and the link stays
/// (devices are written in place: `mpm_shared::io`'s tests).
#[cfg(unix)]
#[test]
fn outputs_are_written_through_links() {
    let dir = tempfile::tempdir().unwrap();
    let input = testdata("cube_tet4.GOM");
    let (target, link) = (dir.path().join("ordered.GOM"), dir.path().join("link.GOM"));
    std::os::unix::fs::symlink("ordered.GOM", &link).unwrap();
    sfcb().arg(&input).arg(&link).assert().success();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let ordered = std::fs::read(&target).unwrap();
    assert!(gom::read(&ordered, "ordered.GOM").is_ok());
}
