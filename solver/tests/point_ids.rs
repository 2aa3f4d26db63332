//! Material-point identity across reorderings: every route from one input case (the GOM file,
//! `sfcb GOM - | mpm-solve -`, the `sfcb --cps` pair, `--reorder none|hilbert`, sfcb twice)
//! reports the same points under the same ids, and messages name elements by their input
//! numbers.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use mpm_shared::model::{Body, Table, Token};
use mpm_shared::{generate, ElementType};

/// The `sfcb` binary, built first (it belongs to another package of the workspace, so cargo
/// does not build it for this package's tests; building an up-to-date one is quick).
fn sfcb() -> Command {
    let exe = std::env::current_exe().unwrap();
    let release = exe.components().any(|c| c.as_os_str() == "release");
    let status = std::process::Command::new(env!("CARGO"))
        .args(["build", "-q", "-p", "sfcb", "--bin", "sfcb"])
        .args(if release {
            ["--profile", "release"]
        } else {
            ["--profile", "test"]
        })
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .unwrap();
    assert!(status.success(), "building sfcb failed");
    Command::cargo_bin("sfcb").unwrap()
}

/// Ids spread over the whole domain (the mesh has 1536 points).
const PROBES: [u32; 8] = [1, 7, 200, 513, 777, 1030, 1299, 1536];

/// A dry elastic 8 × 4 × 3 box of 384 elements (4 points each) under gravity, its bottom fixed,
/// as GOM and CPS files in `dir`; the CPS names [`PROBES`].
fn case(dir: &Path) -> (PathBuf, PathBuf) {
    let mut model = generate::box_mesh([8, 4, 3], [2.0, 1.0, 0.75], ElementType::Tet4);
    let mut fixed = Table::new();
    for n in 0..model.node_count() {
        if model.node(n)[1] == 0.0 {
            fixed.push_row([n as i64 + 1, 1, 1, 1].map(Token::Int));
        }
    }
    let Some(Body::Table { rows, .. }) = model
        .section_mut("START_FIXITY_SURFACE_SOLID")
        .map(|s| &mut s.body)
    else {
        panic!("box_mesh writes fixity sections")
    };
    *rows = fixed;
    let gom = dir.join("box.GOM");
    mpm_shared::write_gom_file(&model, &gom).unwrap();
    let text = std::fs::read_to_string(&gom).unwrap();
    let material = "$$MATERIAL_TYPE\ndry_material\n$$POROSITY_SOLID\n0.0\n$$DENSITY_SOLID\n2000\n$$MATERIAL_MODEL_SOLID\nlinear_elasticity\n$$YOUNG_MODULUS\n10000\n$$POISSON_RATIO\n0.3\n$$STARTELMMAT";
    std::fs::write(&gom, text.replacen("$$STARTELMMAT", material, 1)).unwrap();
    let mut cps = String::from(
        "### Anura3D_2021 ###\n$$NUMBER_OF_LOADSTEPS\n2\n$$TIME_PER_LOADSTEP\n0.004\n$$COMPUTATION_METHOD\nMPM-MP\n$$GRAVITY_LOAD\nstep 1.0 1.0\n",
    );
    cps += &format!(
        "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n{}\n$$OUTPUT_MATERIAL_POINTS\n",
        PROBES.len()
    );
    for id in PROBES {
        cps += &format!("{id}\n");
    }
    cps += "$$END\n";
    let cps_path = dir.join("box.CPS_001");
    std::fs::write(&cps_path, cps).unwrap();
    (gom, cps_path)
}

/// The rows of `history.csv` in `out`: (time, id, values).
fn history(out: &Path) -> Vec<(String, u32, Vec<f64>)> {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].to_string(),
                f[1].parse().unwrap(),
                f[2..].iter().map(|v| v.parse().unwrap()).collect(),
            )
        })
        .collect()
}

/// Asserts that two histories track the same points: same times and ids, values within 1e-9
/// of each column's largest magnitude (summation order differs between element orders).
fn same_points(a: &[(String, u32, Vec<f64>)], b: &[(String, u32, Vec<f64>)], route: &str) {
    assert_eq!(a.len(), b.len(), "{route}: row count");
    assert_eq!(
        a.len(),
        2 * PROBES.len(),
        "{route}: one row per probe and output"
    );
    let columns = a[0].2.len();
    for c in 0..columns {
        let scale = a.iter().map(|r| r.2[c].abs()).fold(0.0, f64::max);
        for (ra, rb) in a.iter().zip(b) {
            assert_eq!((&ra.0, ra.1), (&rb.0, rb.1), "{route}: time and id");
            let (x, y) = (ra.2[c], rb.2[c]);
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(scale),
                "{route}: point {} column {c} at t = {}: {x} vs {y}",
                ra.1,
                ra.0
            );
        }
    }
}

fn solve(dir: &Path, name: &str, args: &[&std::ffi::OsStr], stdin: Option<Vec<u8>>) -> PathBuf {
    let out = dir.join(name);
    let mut cmd = Command::cargo_bin("mpm-solve").unwrap();
    cmd.args(args)
        .arg("--out")
        .arg(&out)
        .args(["--threads", "1"]);
    if let Some(data) = stdin {
        cmd.write_stdin(data);
    }
    cmd.assert().success();
    out
}

#[test]
fn every_route_reports_the_same_points_under_the_same_ids() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (gom, cps) = case(d);
    let os = |s: &str| std::ffi::OsString::from(s);
    let (g, c) = (gom.clone().into_os_string(), cps.clone().into_os_string());
    let file = history(&solve(d, "file", &[&g, &os("--cps"), &c], None));
    // Initial positions are those of the input's numbering: point 1 is in element 1.
    let model = mpm_shared::read_gom_file(&gom).unwrap();
    let first = model.element(0);
    let x1: Vec<f64> = file[0].2[..3].to_vec();
    let inside = (0..3).all(|a| {
        let v: Vec<f64> = first[..4]
            .iter()
            .map(|&n| model.node(n as usize)[a])
            .collect();
        let (lo, hi) = v
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &x| (l.min(x), h.max(x)));
        x1[a] > lo && x1[a] < hi
    });
    assert!(
        file[0].1 == 1 && inside,
        "point 1 lies in element 1: {x1:?}"
    );
    for how in ["none", "hilbert"] {
        let got = history(&solve(
            d,
            how,
            &[&g, &os("--cps"), &c, &os("--reorder"), &os(how)],
            None,
        ));
        same_points(&file, &got, &format!("--reorder {how}"));
    }
    // The pipe: the ordered GOM on standard input, the original CPS.
    let ordered = sfcb().arg(&gom).arg("-").output().unwrap();
    assert!(ordered.status.success());
    let pipe = history(&solve(
        d,
        "pipe",
        &[&os("-"), &os("--cps"), &c],
        Some(ordered.stdout.clone()),
    ));
    same_points(&file, &pipe, "sfcb GOM - | mpm-solve -");
    // The Anura3D pair: the ordered GOM file and the CPS sfcb remapped for it.
    let (og, oc) = (d.join("ordered.GOM"), d.join("ordered.CPS_001"));
    sfcb()
        .args([&gom, &og])
        .arg("--cps")
        .args([&cps, &oc])
        .assert()
        .success();
    let remapped = mpm_shared::cps::Cps::read(&std::fs::read(&oc).unwrap(), "oc")
        .unwrap()
        .0
        .output_material_points()
        .unwrap();
    assert_ne!(remapped, PROBES, "the reorder moves the probes' file ids");
    let pair = history(&solve(
        d,
        "pair",
        &[og.as_os_str(), &os("--cps"), oc.as_os_str()],
        None,
    ));
    same_points(&file, &pair, "sfcb --cps pair");
    // sfcb applied twice, the second time along another curve; the original CPS.
    let twice = d.join("twice.GOM");
    sfcb()
        .args([&og, &twice])
        .args(["--curve", "hilbert"])
        .assert()
        .success();
    let got = history(&solve(
        d,
        "twice",
        &[
            twice.as_os_str(),
            &os("--cps"),
            &c,
            &os("--reorder"),
            &os("none"),
        ],
        None,
    ));
    same_points(&file, &got, "sfcb twice");
}

#[test]
fn a_remapped_cps_with_a_gom_it_does_not_fit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (gom, cps) = case(d);
    let (og, oc) = (d.join("ordered.GOM"), d.join("ordered.CPS_001"));
    sfcb()
        .args([&gom, &og])
        .arg("--cps")
        .args([&cps, &oc])
        .assert()
        .success();
    // With the original GOM: its ids cannot be recovered.
    let out = d.join("out");
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&gom)
        .arg("--cps")
        .arg(&oc)
        .arg("--out")
        .arg(&out)
        .assert()
        .failure()
        .stderr(predicates::str::contains("ordered.CPS_001"))
        .stderr(predicates::str::contains(
            "carries no $$START_INPUT_ELEMENT_NUMBERS",
        ))
        .stderr(predicates::str::contains(
            "use the GOM sfcb wrote with this CPS",
        ));
    assert!(!out.exists(), "nothing is written");
    // With a GOM ordered along another curve: refused as well.
    let other = d.join("other.GOM");
    sfcb()
        .args([&gom, &other])
        .args(["--curve", "hilbert"])
        .assert()
        .success();
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&other)
        .arg("--cps")
        .arg(&oc)
        .arg("--out")
        .arg(&out)
        .assert()
        .failure()
        .stderr(predicates::str::contains("another ordered GOM"));
}

#[test]
fn an_inverted_element_is_named_by_its_input_number() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (gom, cps) = case(d);
    // Swap two corners of element 1: it turns inside out.
    let text = std::fs::read_to_string(&gom).unwrap();
    let at = text.find("$$STARTELEMCON\n").unwrap() + "$$STARTELEMCON\n".len();
    let end = at + text[at..].find('\n').unwrap();
    let mut ids: Vec<&str> = text[at..end].split_whitespace().collect();
    ids.swap(1, 2);
    let bad = format!("{}{}{}", &text[..at], ids.join(" "), &text[end..]);
    std::fs::write(&gom, bad).unwrap();
    for how in ["morton", "hilbert", "none"] {
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&gom)
            .arg("--cps")
            .arg(&cps)
            .args(["--reorder", how, "--out"])
            .arg(d.join(how))
            .assert()
            .failure()
            .stderr(predicates::str::contains("element 1 is inverted"));
    }
    // Through sfcb, it keeps its input number.
    let ordered = sfcb().arg(&gom).arg("-").output().unwrap();
    assert!(ordered.status.success());
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .args(["-", "--cps"])
        .arg(&cps)
        .arg("--out")
        .arg(d.join("pipe"))
        .write_stdin(ordered.stdout)
        .assert()
        .failure()
        .stderr(predicates::str::contains("element 1 is inverted"));
}
