//! The bases of their own: the background grid (`[grid]`) and the dual-domain gradients on the
//! mesh's elements (`gradient = "ddmp"`). Runs with either give the same bytes for any thread
//! count in both precisions, dry and saturated, in 3D and in plane strain; the quadratic
//! B-splines settle a self-weight column to the closed form; what neither models is refused by
//! name.

mod common;

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use common::{testdata, COLUMN_SIDES};
use mpm_solve::driver::run::{run, RunOptions};
use mpm_solve::element::tet4::Tet4;

/// A dry column (the oedometer mesh, 0.1 × 1 × 0.1 m) under gravity with damping, for `end`
/// seconds, on `grid` (the `[grid]` table's lines), as `dir/name.toml`.
fn dry_column(dir: &Path, name: &str, grid: &str, points: u32, end: f64) -> PathBuf {
    let text = format!(
        r#"mesh = "{mesh}"
{grid}
[time]
end = {end}
output_interval = {end}
courant = 0.5
[gravity]
vector = [0.0, -9.81, 0.0]
[damping]
local = 0.75
[[material]]
physical = "soil"
density = 2000.0
young = 10000.0
poisson = 0.3
points_per_element = {points}
[[fixity]]
physical = "bottom"
fixed = [true, true, true]
{COLUMN_SIDES}"#,
        mesh = testdata("oedometer_tet4.msh").display()
    );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// The default job (3D) or its plane-strain twin, saturated, cut to `end` seconds, on `grid`.
fn saturated(dir: &Path, two_d: bool, grid: &str, end: f64) -> PathBuf {
    let (scene, mesh) = if two_d {
        ("oedometer_2d.toml", "oedometer_2d_tri3.msh")
    } else {
        ("oedometer.toml", "oedometer_tet4.msh")
    };
    let text = std::fs::read_to_string(testdata(scene)).unwrap();
    // A plain timed run instead of the consolidation job.
    let text = text.split("[consolidation]").next().unwrap();
    let text = text
        .replace(
            &format!("mesh = \"{mesh}\""),
            &format!("mesh = \"{}\"", testdata(mesh).display()),
        )
        .replace(
            "[time]\ncourant = 0.5",
            &format!("{grid}\n[time]\ncourant = 0.5\nend = {end}\noutput_interval = {end}"),
        );
    let p = dir.join(if two_d { "sat2d.toml" } else { "sat3d.toml" });
    std::fs::write(&p, text).unwrap();
    p
}

fn solve(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// Every output file but run.json (which holds timings), name and bytes.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.file_name().unwrap() != "run.json")
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().to_string(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn grid_runs_are_the_same_bytes_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scenes = [
        dry_column(d, "dry", "[grid]\ncell = [0.1, 0.05, 0.1]", 1, 0.02),
        dry_column(
            d,
            "dry_gimp",
            "[grid]\ncell = [0.1, 0.05, 0.1]\nbasis = \"gimp\"",
            1,
            0.02,
        ),
        saturated(d, false, "[grid]\ncell = [0.1, 0.1, 0.1]", 0.01),
        dry_column(
            d,
            "dry_regular",
            "[grid]\ncell = 0.1\nbasis = \"gimp\"\npoints_per_axis = 2",
            1,
            0.02,
        ),
        saturated(d, true, "[grid]\ncell = 0.05", 0.01),
        dry_column(d, "dry_ddmp", "gradient = \"ddmp\"", 1, 0.02),
        saturated(d, false, "gradient = \"ddmp_blended\"", 0.01),
        saturated(d, true, "gradient = \"ddmp\"", 0.01),
    ];
    for scene in &scenes {
        for precision in ["f64", "f32"] {
            let runs: Vec<_> = ["1", "3"]
                .iter()
                .map(|threads| {
                    let out = d.join(format!(
                        "{}_{precision}_{threads}",
                        scene.file_stem().unwrap().to_string_lossy()
                    ));
                    let o = solve(
                        scene,
                        &out,
                        &["--threads", threads, "--precision", precision],
                    );
                    assert!(
                        o.status.success(),
                        "{}: {}",
                        scene.display(),
                        String::from_utf8_lossy(&o.stderr)
                    );
                    outputs(&out)
                })
                .collect();
            assert!(
                runs[0].len() >= 3,
                "{}: {:?}",
                scene.display(),
                runs[0].len()
            );
            assert_eq!(runs[0], runs[1], "{} in {precision}", scene.display());
        }
    }
}

/// RMS over the points of (σ_yy − (−γ (H − y0))) / (γH) after the run of `scene`.
#[test]
fn the_basis_flag_chooses_the_gradients_as_the_scene_key_does() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plain = dry_column(d, "plain", "", 1, 0.02);
    let keyed = dry_column(d, "keyed", "gradient = \"ddmp_blended\"", 1, 0.02);
    let run = |scene: &Path, name: &str, extra: &[&str]| {
        let out = d.join(name);
        let o = solve(scene, &out, extra);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        outputs(&out)
    };
    let by_key = run(&keyed, "by_key", &[]);
    let by_flag = run(&plain, "by_flag", &["--basis", "ddmp-blended"]);
    let element = run(&plain, "element", &[]);
    let back = run(&keyed, "back", &["--basis", "element"]);
    assert_eq!(by_key, by_flag);
    assert_eq!(element, back);
    assert_ne!(by_key, element, "the gradients change the answer");
    let grid = dry_column(d, "grid", "[grid]\ncell = 0.1", 1, 0.02);
    let o = solve(&grid, &d.join("grid_ddmp"), &["--basis", "ddmp"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("background grid"), "{err}");
}

fn vertical_stress_error(scene: &Path, out: &Path) -> f64 {
    let case = mpm_solve::input::scene::load(scene).unwrap();
    let e = run::<f64, Tet4>(&case, out, &RunOptions::default()).unwrap();
    let p = &e.particles;
    let gamma = 2.0 * 9.81;
    let mut e2 = 0.0;
    for i in 0..p.len() {
        let y0 = e.mesh.global(&p.x[i])[1] - p.u[i][1];
        let err = (p.stress[i][1] + gamma * (1.0 - y0)) / gamma;
        e2 += err * err;
    }
    (e2 / p.len() as f64).sqrt()
}

#[test]
fn quadratic_splines_settle_a_self_weight_column_to_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = dry_column(d, "sw", "[grid]\ncell = 0.1\nbasis = \"bspline2\"", 4, 2.0);
    let rms = vertical_stress_error(&scene, &d.join("out"));
    // Measured 0.0059 (docs/accuracy-grid.md: 10 cells, 24 points a cell); linear tetrahedra
    // give 0.025 with these points.
    assert!(rms < 0.0065, "RMS σ_v error {rms} of γH");
}

#[test]
fn what_the_grid_does_not_model_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            dry_column(
                d,
                "mixed",
                "integration = \"mixed\"\n[grid]\ncell = 0.1",
                1,
                0.01,
            ),
            "a background grid ([grid]) cannot model mixed integration",
        ),
        (
            dry_column(d, "uneven", "[grid]\ncell = 0.3", 1, 0.01),
            "grid.cell",
        ),
        (
            dry_column(d, "basis", "[grid]\ncell = 0.1\nbasis = \"cubic\"", 1, 0.01),
            "grid.basis",
        ),
        (
            dry_column(
                d,
                "smooth",
                "strain_smoothing = true\n[grid]\ncell = 0.1",
                1,
                0.01,
            ),
            "strain smoothing",
        ),
        (
            dry_column(
                d,
                "ddmp_mixed",
                "integration = \"mixed\"\ngradient = \"ddmp\"",
                1,
                0.01,
            ),
            "the dual-domain gradients (gradient = \"ddmp\", --basis ddmp) cannot model mixed integration",
        ),
        (
            dry_column(
                d,
                "ddmp_grid",
                "gradient = \"ddmp\"\n[grid]\ncell = 0.1",
                1,
                0.01,
            ),
            "a [grid] takes its basis's own",
        ),
        (
            dry_column(d, "ddmp_name", "gradient = \"smooth\"", 1, 0.01),
            "is not a gradient",
        ),
    ];
    for (scene, says) in &cases {
        let o = solve(scene, &d.join("never"), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{} ran", scene.display());
        assert!(err.contains(says), "{}: {err}", scene.display());
        assert!(!err.contains("panicked"), "{err}");
    }
    let o = Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(dry_column(d, "export", "[grid]\ncell = 0.1", 1, 0.01))
        .arg("--export-anura3d")
        .arg(d.join("a3d"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("remove [grid] to export"),
        "{err}"
    );
    let o = Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(dry_column(d, "export_ddmp", "gradient = \"ddmp\"", 1, 0.01))
        .arg("--export-anura3d")
        .arg(d.join("a3d_ddmp"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("remove gradient to export"),
        "{err}"
    );
}

#[test]
fn regular_points_fill_each_cell_once() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dry_column(
        dir.path(),
        "regular",
        "[grid]\ncell = 0.1\npoints_per_axis = 3",
        1,
        0.01,
    );
    let case = mpm_solve::input::scene::load(&scene).unwrap();
    let e = mpm_solve::driver::engine::Engine::<f64, Tet4>::new(&case, false).unwrap();
    let p = &e.particles;
    // 10 cells of 27 points, each a 27th of a cell, ids 1..=270 once each.
    assert_eq!(p.len(), 270);
    let volume: f64 = p.volume.iter().sum();
    assert!((volume - 0.01).abs() < 1e-15, "{volume}");
    let mut ids = p.id.clone();
    ids.sort_unstable();
    assert_eq!(ids, (1..=270).collect::<Vec<u32>>());
    for i in 0..p.len() {
        // Each in the element that holds it, at a sub-cell's centre.
        let n = e.mesh.shape(p.element[i] as usize, &p.x[i]);
        assert!(
            n.iter().all(|&v| v > -1e-12),
            "point {i} outside its element"
        );
        let x = e.mesh.global(&p.x[i]);
        for (a, h) in [(0, 0.1), (1, 0.1), (2, 0.1)] {
            let sub = x[a] / (h / 3.0) - 0.5;
            assert!((sub - sub.round()).abs() < 1e-9, "point {i} at {x:?}");
        }
    }
    assert!(
        p.element.windows(2).all(|w| w[0] <= w[1]),
        "points by element"
    );
}

#[test]
fn the_default_job_on_a_spline_grid_follows_terzaghi() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace(
            "mesh = \"oedometer_tet4.msh\"",
            &format!(
                "mesh = \"{}\"\n[grid]\ncell = [0.1, 0.05, 0.1]\nbasis = \"bspline2\"",
                testdata("oedometer_tet4.msh").display()
            ),
        )
        .replace("compare_rest = true", "compare_rest = false");
    let scene = dir.path().join("oedometer_grid.toml");
    std::fs::write(&scene, text).unwrap();
    let o = solve(&scene, &dir.path().join("out"), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    let line = said
        .lines()
        .find(|l| l.starts_with("default:"))
        .unwrap_or_else(|| panic!("no summary in {said}"));
    let rms: f64 = line
        .split("RMS pore-pressure error ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no error in {line}"));
    // Measured 0.0038 at T_v = 1 (linear tetrahedra: 0.0024). Before the grid's faces were
    // loaded with its own functions it was 0.052: a twisting mode from unequal corner loads.
    assert!(rms < 0.006, "{line}");
}
