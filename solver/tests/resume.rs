//! Checkpoints and `--resume` (docs/design.md §4.15, docs/guide/long-runs.md): a run killed at any
//! step (an abort of its own after step N, or a SIGKILL from here), or stopped by SIGINT or
//! SIGTERM, and then resumed, with other thread counts, ends with a folder byte-identical to an
//! uninterrupted run's (run.json but for its run-specific fields); the folder rules (lock,
//! refusals, --overwrite); a full disk and a read-only folder.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{golden_scene, testdata};

const BIN: &str = env!("CARGO_BIN_EXE_mpm-solve");

/// Keys of run.json that describe this process rather than the results: wall times, rates,
/// memory, and the threads (outputs do not depend on them), with the traffic model, whose
/// slots are those of the threads' borders, and the memory on huge pages (which a kernel that
/// gives them to every process changes from run to run).
const RUN_SPECIFIC: [&str; 12] = [
    "wall_seconds",
    "particle_steps_per_second",
    "phase_seconds",
    "phase_ns_per_particle_step",
    "phase_threads_ns_per_particle_step",
    "peak_rss_bytes",
    "threads",
    "pinning",
    "pinned_cores",
    "busy_cores",
    "modelled_bytes_per_particle_step",
    "huge_page_bytes",
];

/// A longer dry column: 0.2 s in 40 outputs (about 2,100 steps), for signals from outside.
fn long_scene(dir: &Path) -> PathBuf {
    golden_scene(dir, "column_dry", "long", &|t| {
        t.replace("end = 0.01", "end = 0.2")
    })
}

fn run(input: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .arg(input)
        .arg("-q")
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{:?}: {}", o.status, stderr(o));
}

/// Every file under `dir` but the checkpoint and the lock, by relative path.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if name == "checkpoint" || name == ".lock" {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// `b` holds the same files as `a`, byte for byte, run.json but for [`RUN_SPECIFIC`].
fn assert_same(a: &Path, b: &Path, what: &str) {
    assert_eq!(files(a), files(b), "{what}: the set of files differs");
    for f in files(a) {
        let (x, y) = (
            std::fs::read(a.join(&f)).unwrap(),
            std::fs::read(b.join(&f)).unwrap(),
        );
        if f.file_name().unwrap() == "run.json" {
            let strip = |bytes: &[u8]| {
                let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
                for k in RUN_SPECIFIC {
                    v.as_object_mut().unwrap().remove(k);
                }
                v
            };
            assert_eq!(strip(&x), strip(&y), "{what}: {} differs", f.display());
        } else {
            assert!(x == y, "{what}: {} differs", f.display());
        }
    }
}

/// Abort after so many steps, the checkpoint options, the threads before and after, and a
/// second abort during the resume.
type Plan<'a> = (u64, &'a [&'a str], &'a str, &'a str, Option<u64>);

/// Kills at several steps (with the checkpoints of the default policy or every 7 steps), then
/// resumes with another thread count, once or twice: the folder ends as the uninterrupted one.
fn killed_and_resumed(golden: &str, precision: &str) {
    killed_and_resumed_with(golden, precision, &|t| t)
}

/// [`killed_and_resumed`] with the scene edited by `edit`.
fn killed_and_resumed_with(golden: &str, precision: &str, edit: &dyn Fn(String) -> String) {
    let tmp = tempfile::tempdir().unwrap();
    let input = golden_scene(tmp.path(), golden, golden, edit);
    let full = tmp.path().join("full");
    let p = ["--precision", precision];
    ok(&run(
        &input,
        &[&["--out", full.to_str().unwrap(), "--threads", "1"], &p[..]].concat(),
    ));
    // (abort after steps, checkpoint policy, threads before, threads after; a second abort
    // during the resume).
    let plans: [Plan; 5] = [
        (1, &[], "2", "1", None),
        (30, &["--checkpoint-every", "7"], "1", "3", None),
        (53, &[], "3", "2", None),
        (54, &["--checkpoint-every", "7"], "2", "2", Some(30)),
        (105, &["--checkpoint-every", "1h"], "1", "2", None),
    ];
    for (k, (at, every, before, after, again)) in plans.into_iter().enumerate() {
        let out = tmp.path().join(format!("cut{k}"));
        let o = out.to_str().unwrap();
        let abort = at.to_string();
        let first = run(
            &input,
            &[
                &[
                    "--out",
                    o,
                    "--threads",
                    before,
                    "--abort-after-step",
                    &abort,
                ][..],
                every,
                &p,
            ]
            .concat(),
        );
        assert!(
            !first.status.success(),
            "the run was to abort after step {at}"
        );
        if let Some(n) = again {
            let n = n.to_string();
            let second = run(
                &input,
                &[
                    &["--resume", o, "--threads", after, "--abort-after-step", &n][..],
                    every,
                    &p,
                ]
                .concat(),
            );
            assert!(!second.status.success(), "the resume was to abort");
        }
        ok(&run(
            &input,
            &[&["--resume", o, "--threads", after][..], every, &p].concat(),
        ));
        assert_same(
            &full,
            &out,
            &format!(
                "{golden} {precision}, killed after step {at} ({before} then {after} threads)"
            ),
        );
    }
}

#[test]
fn killed_dry_runs_resume_byte_identical_in_f64_and_f32() {
    killed_and_resumed("column_dry", "f64");
    killed_and_resumed("column_dry", "f32");
}

/// A platen pushed into the dry column (a ramped nodal set) and the whole column's points
/// (a material-point set): `reaction.csv`, whose imposed displacement sums over the steps, ends
/// as the uninterrupted run's.
#[test]
fn killed_runs_with_prescribed_velocities_resume_byte_identical() {
    killed_and_resumed_with("column_dry", "f64", &|t| {
        t + "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -0.05, 0.0]\nramp = 0.004\nname = \"platen, rough\"\n"
    });
    killed_and_resumed_with("column_dry", "f32", &|t| {
        t + "[[velocity]]\nphysical = \"soil\"\nvelocity = [0.0, 0.0, 0.01]\ncomponents = [false, false, true]\n"
    });
}

/// Absorbing boundaries (dashpots and springs on the base, their displacements in the
/// checkpoint), dry and saturated.
#[test]
fn killed_runs_with_absorbing_boundaries_resume_byte_identical() {
    let absorbing = |t: String| {
        let base = "physical = \"bottom\"\nfixed = [true, true, true]";
        assert!(t.contains(base));
        t.replace(base, "physical = \"bottom\"\nfixed = [true, false, true]")
            + "[[absorbing]]\nphysical = \"bottom\"\nspring_length = 0.5\n"
    };
    killed_and_resumed_with("column_dry", "f64", &absorbing);
    killed_and_resumed_with("column_saturated", "f32", &absorbing);
}

/// Bulk viscosity (each point's viscous pressure and strain rate in the checkpoint), dry and
/// saturated.
#[test]
fn killed_runs_with_bulk_viscosity_resume_byte_identical() {
    let bulk = |t: String| {
        assert!(t.contains("[damping]\n"));
        t.replace("[damping]\n", "[damping]\nbulk_viscosity = [0.2, 1.5]\n")
    };
    killed_and_resumed_with("column_dry", "f64", &bulk);
    killed_and_resumed_with("column_saturated", "f32", &bulk);
}

#[test]
fn killed_saturated_runs_resume_byte_identical_in_f64_and_f32() {
    killed_and_resumed("column_saturated", "f64");
    killed_and_resumed("column_saturated", "f32");
}

/// The semi-implicit scheme (its solve starts from zero each step; its counts are in the
/// checkpoint).
#[test]
fn killed_semi_implicit_runs_resume_byte_identical() {
    let semi = |t: String| {
        // (Its step is about 6× longer: as many steps as the explicit run's need 6× the time.)
        let t = t
            .replace("courant = 0.5", "courant = 0.5\nscheme = \"semi-implicit\"")
            .replace("end = 0.01", "end = 0.08")
            .replace("output_interval = 0.005", "output_interval = 0.04");
        assert!(t.contains("semi-implicit") && t.contains("end = 0.08"));
        t
    };
    killed_and_resumed_with("column_saturated", "f64", &semi);
    killed_and_resumed_with("column_saturated", "f32", &semi);
}

/// A run from K0 stresses (the ground below the top, so the column moves): a resumed run takes
/// the checkpoint's stresses and does not set the initial ones again.
#[test]
fn killed_k0_runs_resume_byte_identical() {
    killed_and_resumed_with("column_dry", "f64", &|t| {
        let t = t
            .replace("points_per_element = 1", "points_per_element = 1\nk0 = 0.5")
            .replace("[gravity]\n", "[gravity]\nk0_surface = 0.8\n");
        assert!(t.contains("k0 = 0.5") && t.contains("k0_surface = 0.8"));
        t
    });
}

/// A Modified Cam Clay column from K0 stresses: the law's state (p_c and e, set at the first
/// step) goes through the checkpoint. (p_max = 200 kPa: a step no longer than the elastic
/// column's, whose step counts the plans abort at.)
#[test]
fn killed_cam_clay_runs_resume_byte_identical() {
    let clay = |t: String| {
        let t = t
            .replace(
                "young = 10000.0\npoisson = 0.3\npoints_per_element = 1",
                "law = \"modified_cam_clay\"\npoisson = 0.3\nlambda = 0.2\nkappa = 0.04\n\
                 critical_state_slope = 1.0\ninitial_void_ratio = 1.2\nocr = 1.5\n\
                 maximum_pressure = 200.0\npoints_per_element = 1\nk0 = 0.6",
            )
            .replace("[gravity]\n", "[gravity]\nk0_surface = 0.8\n");
        assert!(t.contains("modified_cam_clay") && t.contains("k0_surface = 0.8"));
        t
    };
    killed_and_resumed_with("column_dry", "f64", &clay);
    killed_and_resumed_with("column_dry", "f32", &clay);
}

/// The same with hypoplastic sand with the intergranular strain: its seven state values (e and
/// the intergranular strain tensor, co-rotated with the stress) go through the checkpoint.
#[test]
fn killed_hypoplastic_runs_resume_byte_identical() {
    let sand = |t: String| {
        let t = t
            .replace(
                "young = 10000.0\npoisson = 0.3\npoints_per_element = 1",
                "law = \"hypoplasticity\"\ncritical_friction_angle = 33.0\n\
                 granular_hardness = 1.0e6\nexponent_n = 0.25\nminimum_void_ratio = 0.55\n\
                 critical_void_ratio = 0.95\nmaximum_void_ratio = 1.05\nexponent_alpha = 0.25\n\
                 exponent_beta = 1.5\ninitial_void_ratio = 0.7\nigs_r = 1.0e-4\n\
                 igs_initial = 1.0\nmaximum_pressure = 200.0\npoints_per_element = 1\nk0 = 0.5",
            )
            .replace("[gravity]\n", "[gravity]\nk0_surface = 0.8\n");
        assert!(t.contains("hypoplasticity") && t.contains("k0_surface = 0.8"));
        t
    };
    killed_and_resumed_with("column_dry", "f64", &sand);
    killed_and_resumed_with("column_dry", "f32", &sand);
}

/// The consolidation job (two runs, the second into `workshop/`, and its records in
/// `consolidation.csv`), killed in either run.
#[test]
fn a_killed_consolidation_job_resumes_byte_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace(
            "oedometer_tet4.msh",
            &testdata("oedometer_tet4.msh").display().to_string(),
        )
        .replace("points_per_element = 4", "points_per_element = 1")
        // Faster consolidation: T_v = 1 in about 130 steps.
        .replace("1.0214e-9", "1.0214e-7");
    let input = tmp.path().join("oedometer.toml");
    std::fs::write(&input, text).unwrap();
    let full = tmp.path().join("full");
    ok(&run(
        &input,
        &["--out", full.to_str().unwrap(), "--threads", "1"],
    ));
    let steps =
        serde_json::from_slice::<serde_json::Value>(&std::fs::read(full.join("run.json")).unwrap())
            .unwrap()["steps"]
            .as_u64()
            .unwrap();
    for at in [steps / 3, steps + steps / 2] {
        let out = tmp.path().join(format!("cut{at}"));
        let o = out.to_str().unwrap();
        let a = at.to_string();
        let first = run(
            &input,
            &["--out", o, "--threads", "2", "--abort-after-step", &a],
        );
        assert!(!first.status.success());
        ok(&run(&input, &["--resume", o, "--threads", "1"]));
        assert_same(
            &full,
            &out,
            &format!("consolidation killed after {at} steps"),
        );
    }
}

/// Waits until `file` exists (the run got that far), at most 60 s.
fn wait_for(file: &Path) {
    let t = Instant::now();
    while !file.exists() {
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "{} never came",
            file.display()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn signal(pid: u32, sig: &str) {
    let s = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap();
    assert!(s.success());
}

#[test]
fn a_run_killed_by_sigkill_resumes_byte_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let input = long_scene(tmp.path());
    let full = tmp.path().join("full");
    ok(&run(
        &input,
        &["--out", full.to_str().unwrap(), "--threads", "2"],
    ));
    let out = tmp.path().join("cut");
    let mut child = Command::new(BIN)
        .arg(&input)
        .args(["-q", "--threads", "1", "--checkpoint-every", "13", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&out.join("particles_00007.vtu"));
    signal(child.id(), "-KILL");
    let status = child.wait().unwrap();
    assert!(!status.success());
    ok(&run(
        &input,
        &["--resume", out.to_str().unwrap(), "--threads", "2"],
    ));
    assert_same(&full, &out, "killed by SIGKILL");
}

/// Stops a long run with `sig` once it wrote its third particle file; returns the folder, the
/// process's output and the uninterrupted run's folder.
fn stopped_by(sig: &str, tmp: &Path) -> (PathBuf, Output, PathBuf) {
    let input = long_scene(tmp);
    let full = tmp.join("full");
    ok(&run(
        &input,
        &["--out", full.to_str().unwrap(), "--threads", "1"],
    ));
    let out = tmp.join("stopped");
    let child = Command::new(BIN)
        .arg(&input)
        .args(["-q", "--threads", "2", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&out.join("particles_00002.vtu"));
    signal(child.id(), sig);
    let o = child.wait_with_output().unwrap();
    (out, o, full)
}

/// The run stopped cleanly: a checkpoint, run.json says so, run.pvd names only whole files;
/// the printed command resumes it to the uninterrupted run's outputs.
fn stopped_cleanly(out: &Path, o: &Output, full: &Path) {
    let err = stderr(o);
    assert!(out.join("checkpoint/state.ckpt").is_file(), "{err}");
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(j["status"], "interrupted");
    let sets = mpm_shared::vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
    for s in &sets {
        mpm_shared::vtu_read::read_vtu_file(&out.join(&s.file)).unwrap();
    }
    let command = err
        .lines()
        .skip_while(|l| !l.contains("to continue the run"))
        .nth(1)
        .unwrap_or_else(|| panic!("no resume command in: {err}"))
        .trim()
        .to_string();
    assert!(command.contains("--resume"), "{command}");
    let r = Command::new("sh").arg("-c").arg(&command).output().unwrap();
    ok(&r);
    assert_same(
        full,
        out,
        "stopped by a signal, resumed by the printed command",
    );
}

#[test]
fn sigint_stops_after_a_step_with_a_checkpoint_and_exit_130() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, o, full) = stopped_by("-INT", tmp.path());
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    stopped_cleanly(&out, &o, &full);
}

#[test]
fn sigterm_stops_after_a_step_with_a_checkpoint_and_exit_143() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, o, full) = stopped_by("-TERM", tmp.path());
    assert_eq!(o.status.code(), Some(143), "{}", stderr(&o));
    stopped_cleanly(&out, &o, &full);
}

#[test]
fn a_folder_in_use_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let input = long_scene(tmp.path());
    let out = tmp.path().join("busy");
    let mut child = Command::new(BIN)
        .arg(&input)
        .args(["-q", "--threads", "1", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&out.join("particles_00001.vtu"));
    let o = run(&input, &["--out", out.to_str().unwrap(), "--overwrite"]);
    let r = run(&input, &["--resume", out.to_str().unwrap()]);
    let _ = child.kill();
    let _ = child.wait();
    for (what, o) in [("--overwrite", o), ("--resume", r)] {
        assert_eq!(o.status.code(), Some(1), "{what}");
        assert!(
            stderr(&o).contains("another run is writing into this folder"),
            "{what}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn a_resume_with_another_case_or_options_is_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let input = golden_scene(tmp.path(), "column_dry", "dry", &|t| t);
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let first = run(&input, &["--out", o, "--abort-after-step", "20"]);
    assert!(!first.status.success());
    let refused = |args: &[&str], input: &Path, name: &str| {
        let r = run(input, args);
        assert_eq!(r.status.code(), Some(1), "{args:?}");
        assert!(stderr(&r).contains(name), "{args:?}: {}", stderr(&r));
    };
    refused(&["--resume", o, "--precision", "f32"], &input, "precision");
    refused(&["--resume", o, "--probe", "7"], &input, "probes");
    refused(&["--resume", o, "--drag", "explicit"], &input, "drag");
    // The same file, edited.
    std::fs::write(
        &input,
        std::fs::read_to_string(&input)
            .unwrap()
            .replace("local = 0.75", "local = 0.7"),
    )
    .unwrap();
    refused(
        &["--resume", o],
        &input,
        "damping differs (checkpoint: 0.75, now: 0.7)",
    );
    // A new run into the interrupted one's folder is refused, naming --resume.
    let fresh = golden_scene(tmp.path(), "column_dry", "dry", &|t| t);
    refused(&["--out", o], &fresh, "--resume");
    // The thread count may change.
    ok(&run(&fresh, &["--resume", o, "--threads", "3"]));
}

#[test]
fn output_folder_rules() {
    let tmp = tempfile::tempdir().unwrap();
    let input = golden_scene(tmp.path(), "column_dry", "dry", &|t| t);
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    ok(&run(&input, &["--out", o]));
    // Re-running the same command replaces a completed run of the same case (the README's).
    let again = run(&input, &["--out", o]);
    ok(&again);
    assert!(stderr(&again).contains("replacing the completed run"));
    // Another case or other options: refused, then replaced under --overwrite.
    let r = run(&input, &["--out", o, "--precision", "f32"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(stderr(&r).contains("--overwrite") && stderr(&r).contains("precision"));
    ok(&run(
        &input,
        &["--out", o, "--precision", "f32", "--overwrite"],
    ));
    // A folder of other files: refused, never mixed; --overwrite empties it.
    let other = tmp.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let r = run(&input, &["--out", other.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(1));
    assert!(stderr(&r).contains("not empty"), "{}", stderr(&r));
    assert!(other.join("notes.txt").exists());
    ok(&run(
        &input,
        &["--out", other.to_str().unwrap(), "--overwrite"],
    ));
    assert!(!other.join("notes.txt").exists());
    // Nothing to resume.
    let r = run(
        &input,
        &["--resume", tmp.path().join("none").to_str().unwrap()],
    );
    assert_eq!(r.status.code(), Some(1));
    // A damaged checkpoint is named, not trusted.
    let cut = tmp.path().join("cut");
    assert!(!run(
        &input,
        &["--out", cut.to_str().unwrap(), "--abort-after-step", "9"]
    )
    .status
    .success());
    let ck = cut.join("checkpoint/state.ckpt");
    let mut bytes = std::fs::read(&ck).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 1;
    std::fs::write(&ck, bytes).unwrap();
    let r = run(&input, &["--resume", cut.to_str().unwrap()]);
    assert_eq!(r.status.code(), Some(1));
    assert!(stderr(&r).contains("checksum"), "{}", stderr(&r));
}

/// Mounts a tmpfs of `size` at `dir`; `None` (after saying why) where mounting is not allowed.
fn tmpfs(dir: &Path, size: &str) -> Option<()> {
    std::fs::create_dir_all(dir).unwrap();
    let o = Command::new("mount")
        .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
        .arg(dir)
        .output();
    match o {
        Ok(o) if o.status.success() => Some(()),
        Ok(o) => skipped(&format!("cannot mount a tmpfs ({})", stderr(&o).trim())),
        Err(e) => skipped(&format!("cannot run mount ({e})")),
    }
}

/// Says why a test is skipped on the real standard error (the test harness captures `println!`
/// and `eprintln!` of passing tests), and returns `None`.
fn skipped(why: &str) -> Option<()> {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "skipped: {why}");
    None
}

struct Unmount(PathBuf);

impl Drop for Unmount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// No `.tmp` file anywhere under `dir`.
fn no_partial_files(dir: &Path) {
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            assert!(
                !n.starts_with(".tmp-") && !n.ends_with(".tmp"),
                "partial file {}",
                p.display()
            );
            if p.is_dir() {
                stack.push(p);
            }
        }
    }
}

#[test]
fn a_full_disk_stops_with_the_file_named_and_the_checkpoint_intact() {
    let tmp = tempfile::tempdir().unwrap();
    let input = long_scene(tmp.path());
    let full = tmp.path().join("full");
    ok(&run(
        &input,
        &["--out", full.to_str().unwrap(), "--threads", "2"],
    ));
    let disk = tmp.path().join("disk");
    if tmpfs(&disk, "8m").is_none() {
        return;
    }
    let _guard = Unmount(disk.clone());
    let out = disk.join("out");
    // The run starts with room enough (the pre-flight checks the predicted volume); once it
    // wrote a few outputs, another file takes what is left.
    let child = Command::new(BIN)
        .arg(&input)
        .args(["-q", "--threads", "2", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&out.join("particles_00002.vtu"));
    let filler = disk.join("filler");
    {
        use std::io::Write;
        let mut f = std::fs::File::create(&filler).unwrap();
        let chunk = vec![0u8; 4096];
        while f.write_all(&chunk).is_ok() {}
        let _ = f.sync_all();
    }
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&out.display().to_string()) && err.contains("No space left"),
        "{err}"
    );
    no_partial_files(&disk);
    // Whatever run.pvd names reads back; the checkpoint resumes once there is room.
    if out.join("run.pvd").exists() {
        let sets = mpm_shared::vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
        for s in &sets {
            mpm_shared::vtu_read::read_vtu_file(&out.join(&s.file)).unwrap();
        }
    }
    std::fs::remove_file(&filler).unwrap();
    ok(&run(
        &input,
        &["--resume", out.to_str().unwrap(), "--threads", "1"],
    ));
    assert_same(&full, &out, "resumed after the disk filled");
}

#[test]
fn a_read_only_folder_is_an_error_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let input = golden_scene(tmp.path(), "column_dry", "dry", &|t| t);
    let disk = tmp.path().join("ro");
    if tmpfs(&disk, "1m").is_none() {
        return;
    }
    let _guard = Unmount(disk.clone());
    let ro = Command::new("mount")
        .args(["-o", "remount,ro"])
        .arg(&disk)
        .status()
        .unwrap();
    assert!(ro.success());
    let out = disk.join("out");
    let o = run(&input, &["--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains(&out.display().to_string()) && err.contains("Read-only"),
        "{err}"
    );
}
