//! `sfcb --curve none` as a converter: msh → GOM, GOM → GOM, GOM/msh → VTU, pipes, bad input.

use predicates::prelude::*;

mod common;
use common::{sfcb, testdata};

#[test]
fn msh_converts_to_the_golden_gom_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    for m in ["cube_tet4", "cube_tet10", "column_tet10", "square_tri3"] {
        let out = dir.path().join(format!("{m}.GOM"));
        sfcb()
            .arg(testdata(&format!("{m}.msh")))
            .arg(&out)
            .args(["--curve", "none"])
            .assert()
            .success();
        assert!(
            std::fs::read(&out).unwrap() == std::fs::read(testdata(&format!("{m}.GOM"))).unwrap(),
            "{m}"
        );
    }
}

#[test]
fn gom_to_gom_is_a_fixed_point_and_pipes_work() {
    let golden = std::fs::read(testdata("column_tet10.GOM")).unwrap();
    let out = sfcb()
        .args(["-", "-", "--curve", "none"])
        .write_stdin(golden.clone())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout == golden);
    // An MSH file also arrives through standard input (recognised by its content).
    let msh = std::fs::read(testdata("column_tet10.msh")).unwrap();
    let out = sfcb()
        .args(["-", "-", "--curve", "none"])
        .write_stdin(msh)
        .output()
        .unwrap();
    assert!(out.stdout == golden);
}

#[test]
fn writes_vtu_with_material_cells() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cube.vtu");
    sfcb()
        .arg(testdata("cube_tet10.GOM"))
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .success();
    let s = std::fs::read(&out).unwrap();
    let head = String::from_utf8_lossy(&s[..2000.min(s.len())]);
    assert!(head.contains("<VTKFile type=\"UnstructuredGrid\""));
    assert!(head.contains("Name=\"material\""));
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.GOM");
    // Missing file.
    sfcb()
        .arg(dir.path().join("nope.GOM"))
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("nope.GOM").and(predicate::str::contains("no such file")));
    // Truncated GOM.
    let golden = std::fs::read(testdata("cube_tet4.GOM")).unwrap();
    let cut = dir.path().join("cut.GOM");
    std::fs::write(&cut, &golden[..golden.len() / 2]).unwrap();
    sfcb()
        .arg(&cut)
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("cut.GOM"));
    // Node id out of range.
    let text = String::from_utf8(golden.clone()).unwrap();
    let start = text.find("$$STARTELEMCON\n").unwrap() + "$$STARTELEMCON\n".len();
    let bad = format!(
        "{}999999{}",
        &text[..start],
        &text[start + text[start..].find(' ').unwrap()..]
    );
    let badp = dir.path().join("bad.GOM");
    std::fs::write(&badp, bad).unwrap();
    sfcb()
        .arg(&badp)
        .arg(&out)
        .args(["--curve", "none"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("node id 999999 out of range"));
    // Impossible options.
    for opts in [
        &["--levels", "0"][..],
        &["--levels", "22"],
        &["--partitions", "0"],
        &["--threads", "0"],
    ] {
        sfcb()
            .arg(testdata("cube_tet4.GOM"))
            .arg(&out)
            .args(opts)
            .assert()
            .failure()
            .stderr(predicate::str::contains("sfcb: error"));
    }
    // Unknown output format.
    sfcb()
        .arg(testdata("cube_tet4.GOM"))
        .arg(dir.path().join("x.txt"))
        .args(["--curve", "none"])
        .assert()
        .failure();
    assert!(
        std::fs::read_dir(dir.path()).unwrap().all(|e| {
            let n = e.unwrap().file_name().to_string_lossy().to_string();
            n == "cut.GOM" || n == "bad.GOM"
        }),
        "an output file was left behind"
    );
}

#[test]
fn help_and_version() {
    sfcb().arg("--help").assert().success().stdout(
        predicate::str::contains("Examples:").and(predicate::str::contains("--partitions")),
    );
    sfcb()
        .arg("--version")
        .assert()
        .success()
        .stdout(predicate::str::contains("sfcb"));
}
