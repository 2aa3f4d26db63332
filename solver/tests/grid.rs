//! The background grid (`[grid]`): runs on it give the same bytes for any thread count in both
//! precisions, dry and saturated, in 3D and in plane strain; the quadratic B-splines settle a
//! self-weight column to the closed form; what the grid does not model is refused by name.

mod common;

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use common::testdata;
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
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = 0.1"
fixed = [true, false, false]
[[fixity]]
plane = "z = 0"
fixed = [false, false, true]
[[fixity]]
plane = "z = 0.1"
fixed = [false, false, true]
"#,
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
        saturated(d, true, "[grid]\ncell = 0.05", 0.01),
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
}
