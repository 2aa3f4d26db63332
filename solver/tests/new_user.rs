//! What a new user hits first (one test per plain mistake): each gets a plain error before any
//! work, naming what was wrong and what to do, with a non-zero exit and no output folder; and a
//! batch job sees its progress.

use std::path::Path;

use assert_cmd::Command;
use predicates::prelude::*;

mod common;
use common::{scene, testdata};

fn solve() -> Command {
    Command::cargo_bin("mpm-solve").unwrap()
}

/// Runs `mpm-solve INPUT --out DIR ARGS`, expects failure and no output folder.
fn refused(input: &Path, dir: &Path, args: &[&str]) -> assert_cmd::assert::Assert {
    let out = dir.join("out");
    let a = solve()
        .arg(input)
        .arg("--out")
        .arg(&out)
        .args(args)
        .assert()
        .failure();
    assert!(!out.exists(), "a refused run wrote {}", out.display());
    a
}

#[test]
fn keys_that_change_results_and_are_not_modelled_stop_the_case() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    solve()
        .arg(&s)
        .arg("--export-anura3d")
        .arg(dir.path())
        .assert()
        .success();
    let (gom, cps) = (
        dir.path().join("scene.GOM"),
        dir.path().join("scene.CPS_001"),
    );
    let base = std::fs::read_to_string(&cps).unwrap();
    for (key, value) in [("APPLY_POROSITY_UPDATE", "1"), ("FIX_SOLID_SKELETON", "1")] {
        // The export writes each key with its inert value: set it as a user would.
        let head = format!("$${key}\n");
        let at = base.find(&head).expect("the export writes the key") + head.len();
        let end = at + base[at..].find('\n').unwrap();
        let text = format!("{}{value}{}", &base[..at], &base[end..]);
        let line = base[..at].lines().count(); // the key's line
        std::fs::write(&cps, &text).unwrap();
        refused(&gom, dir.path(), &[]).stderr(
            predicate::str::contains(format!("$${key}"))
                .and(predicate::str::contains(value))
                .and(predicate::str::contains(format!("line {line}")))
                .and(predicate::str::contains("not modelled")),
        );
    }
    // A key given twice is refused too (Anura3D would silently take the last value).
    let at = base.rfind("$$END").unwrap();
    std::fs::write(
        &cps,
        format!("{}$$MASS_SCALING\n1 100\n{}", &base[..at], &base[at..]),
    )
    .unwrap();
    refused(&gom, dir.path(), &[]).stderr(
        predicate::str::contains("'$$MASS_SCALING' is given twice")
            .and(predicate::str::contains("keep one")),
    );
    // The exported case itself runs.
    std::fs::write(&cps, &base).unwrap();
    solve().arg(&gom).arg("--check").assert().success();
}

#[test]
fn unknown_probe_ids_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    refused(&s, dir.path(), &["--probe", "999999,7,0"]).stderr(
        predicate::str::contains("999999")
            .and(predicate::str::contains("id 0, 999999"))
            .and(predicate::str::contains("ids run from 1 to 1844")),
    );
    // --check finds them too.
    solve()
        .arg(&s)
        .args(["--check", "--probe", "999999"])
        .assert()
        .failure()
        .stderr(predicate::str::contains("999999"));
}

#[test]
fn drop_lost_stops_when_the_body_leaves_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    // No supports: the column falls out of its mesh.
    let s = scene(dir.path(), &|t| {
        let at = t.find("[[fixity]]").unwrap();
        t[..at].replace("end = 0.02", "end = 0.6")
    });
    let out = dir.path().join("out");
    solve()
        .arg(&s)
        .arg("--out")
        .arg(&out)
        .args(["--drop-lost", "--max-lost", "0.02", "--quiet"])
        .assert()
        .failure()
        .stderr(
            predicate::str::contains("have left the mesh")
                .and(predicate::str::contains("--max-lost allows (2.0 %)")),
        );
    // Without --drop-lost the first lost point stops the run, naming it.
    solve()
        .arg(&s)
        .arg("--out")
        .arg(dir.path().join("strict"))
        .arg("--quiet")
        .assert()
        .failure()
        .stderr(
            predicate::str::contains("left the mesh").and(predicate::str::contains("--drop-lost")),
        );
    // Either way run.json says the run failed, and why: a body leaving a mesh too small for
    // it at the speed it has is no instability.
    for (folder, says) in [("out", "have left the mesh"), ("strict", "left the mesh")] {
        let text = std::fs::read_to_string(dir.path().join(folder).join("run.json")).unwrap();
        let j: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(j["status"], "failed", "{folder}: {j}");
        assert!(
            j["reason"].as_str().unwrap().contains(says),
            "{folder}: {j}"
        );
        assert!(j["diagnosis"].is_null(), "{folder}: {j}");
        assert!(j["steps"].as_u64().unwrap() > 0, "{folder}: {j}");
    }
}

#[test]
fn mistyped_output_intervals_are_refused_with_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    // So many outputs that their times alone would not fit in memory.
    let s = scene(dir.path(), &|t| {
        t.replace("output_interval = 0.01", "output_interval = 1e-12")
    });
    refused(&s, dir.path(), &[]).stderr(
        predicate::str::contains("time.output_interval")
            .and(predicate::str::contains("20,000,000,000 outputs")),
    );
    // Fewer, but still far more than --max-output.
    let s = scene(dir.path(), &|t| {
        t.replace("output_interval = 0.01", "output_interval = 1e-7")
    });
    refused(&s, dir.path(), &[]).stderr(
        predicate::str::contains("200,000 outputs")
            .and(predicate::str::contains("one every 100.0 ns"))
            .and(predicate::str::contains("GB"))
            .and(predicate::str::contains("--max-output (4.00 GB)")),
    );
    // A sensible scene against a tight limit.
    let s = scene(dir.path(), &|t| t);
    refused(&s, dir.path(), &["--max-output", "100kB"])
        .stderr(predicate::str::contains("--max-output (100 kB)"));
}

#[test]
fn a_stiffness_typo_is_refused_with_the_step_and_the_wall_time() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| {
        t.replace("young = 10000.0", "young = 1e300")
    });
    refused(&s, dir.path(), &[]).stderr(
        predicate::str::contains("e150 time steps of ")
            .and(predicate::str::contains("e-153 s"))
            .and(predicate::str::contains("years"))
            .and(predicate::str::contains("--max-steps is 100,000,000")),
    );
}

#[test]
fn check_prints_what_a_run_would_cost() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    let out = solve().arg(&s).arg("--check").assert().success();
    let text = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    for what in [
        "material points: 1,844",
        "time step: ",
        "steps to 20.00 ms",
        "outputs: 2 (0 probes), about ",
        "memory: about ",
        "wall time: about ",
        // Timed here: the steps of this case on the engine a run would build.
        "for the steps (measured here: ",
        " steps of this case at ",
    ] {
        assert!(
            text.contains(what),
            "--check does not print {what:?}:\n{text}"
        );
    }
    // The predicted volume is that of a real run, within 5 %.
    let predicted = text
        .lines()
        .find_map(|l| l.split("about ").nth(1)?.strip_suffix(" on disk"))
        .expect("a volume");
    let (v, unit) = predicted.split_once(' ').unwrap();
    let scale = match unit {
        "kB" => 1e3,
        "MB" => 1e6,
        other => panic!("unexpected unit {other}"),
    };
    let predicted = v.parse::<f64>().unwrap() * scale;
    let run = dir.path().join("run");
    solve()
        .arg(&s)
        .arg("--out")
        .arg(&run)
        .arg("-q")
        .assert()
        .success();
    let written: u64 = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    let ratio = predicted / written as f64;
    assert!(
        (0.95..1.05).contains(&ratio),
        "predicted {predicted} B, wrote {written} B"
    );
}

/// The calibrated wall time is the run's steps at the measured time per step: the printed
/// figures agree with each other, and a job that runs its workshop twin counts its steps twice.
#[test]
fn check_times_steps_of_the_case_and_counts_a_job_s_twin() {
    let text = |scene: &Path, extra: &[&str]| -> String {
        let out = solve()
            .arg(scene)
            .arg("--check")
            .args(extra)
            .assert()
            .success();
        String::from_utf8(out.get_output().stdout.clone()).unwrap()
    };
    // "about 12,780 steps", "at 269.1 µs each", "about 6.878 s on": numbers in words.
    let number_before = |text: &str, suffix: &str| -> f64 {
        let at = text
            .find(suffix)
            .unwrap_or_else(|| panic!("no {suffix:?} in\n{text}"));
        let word = text[..at].rsplit(' ').next().unwrap();
        word.replace(',', "").parse().unwrap()
    };
    // A duration in words before `suffix`, after `prefix`: "269.1 µs", "6.878 s", "1 min 18 s"
    // (floored to the second: `tolerance` covers it).
    let seconds = |text: &str, prefix: &str, suffix: &str| -> (f64, f64) {
        let at = text
            .find(suffix)
            .unwrap_or_else(|| panic!("no {suffix:?} in\n{text}"));
        let from = text[..at].rfind(prefix).expect("the prefix") + prefix.len();
        let words: Vec<&str> = text[from..at].split(' ').collect();
        let mut total = 0.0;
        for pair in words.chunks(2) {
            let v: f64 = pair[0].parse().unwrap();
            total += v * match pair[1] {
                "s" => 1.0,
                "ms" => 1e-3,
                "µs" => 1e-6,
                "min" => 60.0,
                "h" => 3600.0,
                other => panic!("unexpected unit {other}"),
            };
        }
        let floored = words.len() > 2;
        (total, if floored { 1.0 / total } else { 1e-3 })
    };
    for (scene, twice) in [
        (testdata("oedometer.toml"), true),
        (testdata("column_gravity.toml"), false),
    ] {
        let t = text(&scene, &["--threads", "1"]);
        assert_eq!(
            t.contains("twice: the job's run and its workshop twin"),
            twice,
            "{t}"
        );
        let steps = number_before(&t, " steps to ");
        let (per_step, _) = seconds(&t, " at ", " each, ");
        let (wall, floored) = seconds(&t, "wall time: about ", " on 1 thread(s)");
        let runs = if twice { 2.0 } else { 1.0 };
        let expected = runs * steps * per_step;
        // (Each figure printed to four significant digits, or to the second.)
        assert!(
            (wall / expected - 1.0).abs() < 2e-3 + floored,
            "{wall} s against {runs} × {steps} × {per_step} s:\n{t}"
        );
        assert!(number_before(&t, " steps of this case") >= 2.0, "{t}");
    }
}

/// A case whose first steps already fail is caught by `--check`: the plan is printed, the
/// failing step named, and the exit code is a diverged run's (3).
#[test]
fn check_catches_a_case_that_fails_in_its_first_steps() {
    let dir = tempfile::tempdir().unwrap();
    let s = common::golden_scene(dir.path(), "column_dry", "soft", &|t| {
        t.replace("young = 10000.0", "young = 1.0")
            .replace("end = 0.01", "end = 2.0")
            .replace("output_interval = 0.005", "output_interval = 0.1")
    });
    let out = solve().arg(&s).arg("--check").assert().code(3);
    let o = out.get_output();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(stdout.contains("material points: 461"), "{stdout}");
    assert!(
        stderr.contains("of its calibration failed") && stderr.contains("check volume tripped"),
        "{stderr}"
    );
    // No hint about outputs: a check writes none.
    assert!(!stderr.contains("run.pvd"), "{stderr}");
    assert!(!dir.path().join("o").exists());
}

#[test]
fn a_mesh_or_a_file_in_the_wrong_place_says_what_to_do() {
    let dir = tempfile::tempdir().unwrap();
    refused(&testdata("column_tet4.msh"), dir.path(), &[]).stderr(
        predicate::str::contains("is a Gmsh mesh")
            .and(predicate::str::contains("scene"))
            .and(predicate::str::contains("sfcb")),
    );
    let file = dir.path().join("taken");
    std::fs::write(&file, "not a folder").unwrap();
    let s = scene(dir.path(), &|t| t);
    solve()
        .arg(&s)
        .arg("--out")
        .arg(&file)
        .assert()
        .failure()
        .stderr(predicate::str::contains("is a file").and(predicate::str::contains("folder")));
    // A GOM without its CPS says which file it looked for and how to give another.
    let gom = dir.path().join("lonely.GOM");
    std::fs::copy(testdata("column_tet4.GOM"), &gom).unwrap();
    refused(&gom, dir.path(), &[])
        .stderr(predicate::str::contains("lonely.CPS_001").and(predicate::str::contains("--cps")));
}

#[test]
fn batch_jobs_see_progress_lines_and_quiet_silences_them() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    // assert_cmd captures stderr: not a terminal, as in a batch job's log.
    let a = solve()
        .arg(&s)
        .arg("--out")
        .arg(dir.path().join("a"))
        .args(["--progress-every", "1e-9"])
        .assert()
        .success()
        .stdout(predicate::str::contains("done: 20.00 ms simulated in "))
        .stdout(predicate::str::contains("1,844 material points"));
    let err = String::from_utf8(a.get_output().stderr.clone()).unwrap();
    let line = err
        .lines()
        .find(|l| l.starts_with("mpm-solve: step "))
        .unwrap_or_else(|| panic!("no progress line:\n{err}"));
    for part in [" of about ", "t = ", " steps/s", " point-steps/s", "ETA "] {
        assert!(line.contains(part), "{part:?} missing from {line:?}");
    }
    solve()
        .arg(&s)
        .arg("--out")
        .arg(dir.path().join("b"))
        .args(["--progress-every", "1e-9", "--quiet"])
        .assert()
        .success()
        .stderr(predicate::str::is_empty());
}

#[test]
fn run_json_is_strict_json_with_a_schema_version() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), &|t| t);
    let out = dir.path().join("out");
    solve()
        .arg(&s)
        .arg("--out")
        .arg(&out)
        .arg("-q")
        .assert()
        .success();
    let text = std::fs::read_to_string(out.join("run.json")).unwrap();
    for bad in ["NaN", "Infinity"] {
        assert!(!text.contains(bad), "run.json holds {bad}");
    }
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema_version"], 1);
}
