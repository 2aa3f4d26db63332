//! The parallel engine's promise: every output file but `run.json` (which holds timings) is
//! byte-identical for any thread count and both pin modes.

use mpm_solve::element::tet4::Tet4;
use std::path::Path;

use assert_cmd::Command;

mod common;
use common::{outputs, testdata};

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

/// A team started again mid-run with another thread count (as when another process takes a
/// core the run's threads were pinned to) gives the same bytes as a run that kept its team.
#[test]
fn outputs_do_not_change_when_the_team_changes_mid_run() {
    let scene = testdata("oracle_mc_block.toml");
    let run = |extra: &[&str]| {
        let dir = tempfile::tempdir().unwrap();
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&scene)
            .args(["--out", dir.path().to_str().unwrap(), "--quiet"])
            .args(extra)
            .assert()
            .success();
        let threads = std::fs::read_to_string(dir.path().join("run.json")).unwrap();
        let json: serde_json::Value = serde_json::from_str(&threads).unwrap();
        (outputs(dir.path()), json["threads"].as_u64().unwrap())
    };
    let (reference, _) = run(&["--threads", "2"]);
    for (threads, change, want) in [("2", "40:1", 1), ("1", "7:3", 3), ("3", "500:2", 2)] {
        let (files, now) = run(&["--threads", threads, "--rethread-after-step", change]);
        assert_eq!(now, want, "{threads} threads, then {change}");
        assert_eq!(files.len(), reference.len());
        for (a, b) in reference.iter().zip(&files) {
            assert!(
                a == b,
                "{} differs after {threads} threads, then {change}",
                a.0
            );
        }
    }
}

/// The default team watches the cores it pinned: a process that starts spinning on one of them
/// mid-run makes the run carry on without that core, and say so. Skipped, visibly, where there
/// are fewer than two cores, `taskset` is missing, or a core is already busy at the start (the
/// team then pins nothing and has nothing to watch).
#[test]
fn a_core_taken_mid_run_is_given_up() {
    let cores = core_affinity::get_core_ids().unwrap_or_default();
    if cores.len() < 2
        || std::process::Command::new("taskset")
            .arg("-V")
            .output()
            .is_err()
    {
        println!("skipped: needs two cores and taskset");
        return;
    }
    // The fine column for 0.3 s: several seconds, for the look at the start, the spinner, and
    // two looks a second apart.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("column_gravity.toml"))
        .unwrap()
        .replace(
            "column_fine_tet4.msh",
            &testdata("column_fine_tet4.msh").display().to_string(),
        )
        .replace("end = 0.6", "end = 0.3");
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("out");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
        .arg(&scene)
        .args(["--out", out.to_str().unwrap(), "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    let last = cores.last().unwrap().id;
    let mut hog = std::process::Command::new("taskset")
        .args(["-c", &last.to_string(), "sh", "-c", "while :; do :; done"])
        .spawn()
        .unwrap();
    let done = child.wait_with_output().unwrap();
    hog.kill().unwrap();
    hog.wait().unwrap();
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(done.status.success(), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let ids = |key: &str| -> Vec<Option<u64>> {
        json[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64())
            .collect()
    };
    let warned = stderr.contains("took cores");
    if !warned && !ids("busy_cores").is_empty() {
        println!(
            "skipped: cores {:?} busy when the run started",
            ids("busy_cores")
        );
        return;
    }
    assert!(warned, "the spinning core was not noticed: {stderr}");
    assert!(ids("busy_cores").contains(&Some(last as u64)), "{json}");
    assert!(
        !ids("pinned_cores").contains(&Some(last as u64)),
        "a thread still pinned to the taken core: {json}"
    );
}

/// After every step each element's range of points holds exactly the points located in it,
/// also when a point changes element without leaving the points' order (the last point of an
/// element moving on to the next: no re-sort, yet the ranges must follow). The block slumps
/// far enough for points to cross elements both ways.
#[test]
fn element_point_ranges_follow_every_point_at_every_step() {
    use mpm_solve::driver::engine::Engine;
    use mpm_solve::driver::run::{Observer, RunOptions};
    struct Check {
        steps: u64,
        crossings: u64,
        last: Vec<u32>,
    }
    impl Observer<f64> for Check {
        fn on_step(&mut self, e: &Engine<f64>) {
            let p = &e.particles;
            for el in 0..e.mesh.elements() {
                for i in e.layout.particles_of(el) {
                    assert_eq!(
                        p.element[i] as usize, el,
                        "step {}: point {i} (id {}) listed under element {el}, located in {}",
                        e.steps, p.id[i], p.element[i]
                    );
                }
            }
            // Count crossings by id (the points are re-sorted as they move).
            let ids = p.id.iter().max().map_or(0, |&m| m as usize + 1);
            let mut by_id = vec![0u32; ids];
            for i in 0..p.len() {
                by_id[p.id[i] as usize] = p.element[i];
            }
            if !self.last.is_empty() {
                self.crossings +=
                    by_id.iter().zip(&self.last).filter(|(a, b)| a != b).count() as u64;
            }
            self.last = by_id;
            self.steps += 1;
        }
    }
    let case = mpm_solve::input::scene::load(&testdata("oracle_mc_block.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut check = Check {
        steps: 0,
        crossings: 0,
        last: Vec::new(),
    };
    let options = RunOptions::default();
    mpm_solve::driver::run::run_with::<f64, Tet4>(&case, dir.path(), &options, &mut check).unwrap();
    assert!(
        check.steps > 1000 && check.crossings > 100,
        "{} steps, {} crossings",
        check.steps,
        check.crossings
    );
}

/// The points are located in the stress pass as they move (every run without moving mesh,
/// contact or dropped points) or in a pass of their own (the others, here through
/// `drop_lost`, with no point lost): the same elements, positions and stresses at every step,
/// on a block whose points cross elements both ways.
#[test]
fn locating_in_the_stress_pass_finds_what_the_locate_pass_finds() {
    use mpm_solve::driver::engine::Engine;
    let case = mpm_solve::input::scene::load(&testdata("oracle_mc_block.toml")).unwrap();
    for threads in [1, 3] {
        let mut case = case.clone();
        case.run.engine.threads = threads;
        let mut fused = Engine::<f64, Tet4>::new(&case, false).unwrap();
        let mut apart = Engine::<f64, Tet4>::new(&case, true).unwrap();
        let by_id = |p: &mpm_solve::state::particles::Particles<f64>| {
            let ids = p.id.iter().max().map_or(0, |&m| m as usize + 1);
            let mut e = vec![u32::MAX; ids];
            for (&id, &el) in p.id.iter().zip(&p.element) {
                e[id as usize] = el;
            }
            e
        };
        let mut crossings = 0;
        for step in 0..1500 {
            let before = by_id(&fused.particles);
            fused.step(fused.dt, None).unwrap();
            apart.step(apart.dt, None).unwrap();
            let (a, b) = (&fused.particles, &apart.particles);
            assert_eq!(a.id, b.id, "step {step}: the points' order");
            assert_eq!(a.element, b.element, "step {step}: the elements");
            let bits = |p: &mpm_solve::state::particles::Particles<f64>| {
                p.x.iter()
                    .chain(&p.u)
                    .flatten()
                    .chain(p.stress.iter().flatten())
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            };
            assert!(bits(a) == bits(b), "step {step}: positions or stresses");
            crossings += by_id(a).iter().zip(&before).filter(|(x, y)| x != y).count();
        }
        assert!(crossings > 100, "{threads} threads: {crossings} crossings");
    }
}
