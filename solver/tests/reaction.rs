//! Prescribed velocities in scenes (`[[velocity]]`), on nodes and on material points, and the
//! reaction forces of `reaction.csv`: a confined elastic column compressed by a slow rigid
//! platen against the closed form, rough and smooth platens, thread-count determinism, a
//! material-point set, and what a scene entry may not say.

mod common;

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_solve::driver::run::{run, RunOptions};
use mpm_solve::input::case::{Case, LoadCurve, MaterialSpec};
use mpm_solve::input::scene;
use mpm_solve::step::prescribed::{PrescribedElement, PrescribedVelocity};

use common::{testdata, COLUMN_SIDES};

/// Young's modulus (kPa) and Poisson's ratio of the column.
const E: f64 = 1000.0;
const NU: f64 = 0.3;
/// Cross-section (m²) and height (m) of `oracle_column_tet4.msh` (0.1 × 1.0 × 0.1 m, y up).
const AREA: f64 = 0.01;
const HEIGHT: f64 = 1.0;

/// A dry column on `oracle_column_tet4.msh`, its sides on rollers and its bottom fixed, with
/// the `[[velocity]]` entries `velocity` (TOML text) and local damping 0.3, 0.7 s in outputs
/// of 0.1 s, written as `dir/NAME.toml`.
fn column(dir: &Path, name: &str, velocity: &str) -> PathBuf {
    let mesh = testdata("oracle_column_tet4.msh");
    let text = format!(
        r#"mesh = "{}"
[time]
end = 0.7
courant = 0.5
output_interval = 0.1
[damping]
local = 0.3
[[material]]
physical = "soil"
density = 2000.0
young = {E}
poisson = {NU}
points_per_element = 4
[[fixity]]
physical = "bottom"
fixed = [true, true, true]
{COLUMN_SIDES}{velocity}
"#,
        mesh.display()
    );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// One row of `reaction.csv`.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    step: u64,
    time: f64,
    set: String,
    u: [f64; 3],
    f: [f64; 3],
}

fn read_reaction(dir: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(dir.join("reaction.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("step,time,set,ux,uy,uz,fx,fy,fz"));
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            assert_eq!(c.len(), 9, "{l}");
            let v = |k: usize| c[k].parse::<f64>().unwrap();
            Row {
                step: c[0].parse().unwrap(),
                time: v(1),
                set: c[2].to_string(),
                u: [v(3), v(4), v(5)],
                f: [v(6), v(7), v(8)],
            }
        })
        .collect()
}

fn run_scene(path: &Path, out: &Path, threads: usize) -> Vec<Row> {
    let mut case = scene::load(path).unwrap();
    case.run.engine.threads = threads;
    run::<f64, Tet4>(&case, out, &RunOptions::default()).unwrap();
    read_reaction(out)
}

/// The constrained modulus: the column's sides are on rollers.
fn constrained_modulus() -> f64 {
    E * (1.0 - NU) / ((1.0 + NU) * (1.0 - 2.0 * NU))
}

const PUSH: &str = r#"[[velocity]]
physical = "top"
velocity = [0.0, -0.01, 0.0]
ramp = 0.1
name = "platen""#;

#[test]
fn a_slow_rough_platen_meets_the_closed_form_reaction() {
    let dir = tempfile::tempdir().unwrap();
    let rows = run_scene(
        &column(dir.path(), "rough", PUSH),
        &dir.path().join("out"),
        1,
    );
    assert_eq!(rows.len(), 7);
    let m = constrained_modulus();
    for r in &rows {
        assert_eq!(r.set, "platen");
        // The displacement: 0.01 m/s over the time, less half the ramp (0.5 ms).
        let want_u = -0.01 * (r.time - 0.05);
        assert!(
            (r.u[1] - want_u).abs() < 1e-5,
            "t = {}: u {:?}",
            r.time,
            r.u
        );
        assert_eq!((r.u[0], r.u[2]), (0.0, 0.0));
        if r.time < 0.25 {
            continue;
        }
        // The platen pushes the body down: F_y = A M ε with ε = u_y / H (negative).
        let want = AREA * m * r.u[1] / HEIGHT;
        let err = (r.f[1] - want).abs() / want.abs();
        assert!(
            err < 0.02,
            "t = {}: F_y {} vs A M ε = {want} ({err:.4})",
            r.time,
            r.f[1]
        );
        // A symmetric column: no net lateral reaction.
        assert!(
            r.f[0].abs() < 1e-3 * want.abs() && r.f[2].abs() < 1e-3 * want.abs(),
            "{r:?}"
        );
    }
}

#[test]
fn a_smooth_platen_takes_no_lateral_reaction_and_a_rough_one_does() {
    let dir = tempfile::tempdir().unwrap();
    let slant = "velocity = [0.002, -0.01, 0.0]";
    let rough = PUSH.replace("velocity = [0.0, -0.01, 0.0]", slant);
    let smooth = rough.replace(
        "ramp = 0.1",
        "ramp = 0.1\ncomponents = [false, true, false]",
    );
    let r = run_scene(
        &column(dir.path(), "rough", &rough),
        &dir.path().join("r"),
        1,
    );
    let s = run_scene(
        &column(dir.path(), "smooth", &smooth),
        &dir.path().join("s"),
        1,
    );
    let (r, s) = (r.last().unwrap(), s.last().unwrap());
    // The rough platen drags the top sideways: it pushes the body along +x.
    assert!(r.f[0] > 0.2 * r.f[1].abs(), "rough: {r:?}");
    assert!(r.u[0] > 0.0);
    // The smooth one prescribes y only: nothing sideways, and the closed form in y.
    assert_eq!((s.u[0], s.f[0], s.f[2]), (0.0, 0.0, 0.0), "smooth: {s:?}");
    let want = AREA * constrained_modulus() * s.u[1] / HEIGHT;
    assert!(
        (s.f[1] - want).abs() < 0.02 * want.abs(),
        "smooth: {s:?} vs {want}"
    );
}

#[test]
fn reaction_csv_is_the_same_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let p = column(dir.path(), "push", PUSH);
    let (a, b) = (dir.path().join("t1"), dir.path().join("t2"));
    run_scene(&p, &a, 1);
    run_scene(&p, &b, 2);
    let (x, y) = (
        std::fs::read(a.join("reaction.csv")).unwrap(),
        std::fs::read(b.join("reaction.csv")).unwrap(),
    );
    assert!(!x.is_empty());
    assert_eq!(x, y, "reaction.csv differs between 1 and 2 threads");
}

/// A confined column 1 × 4 × 1 m (2 × 8 × 2 cells), fixed at the bottom, whose top row of
/// cells (y > 3.5) is pushed down at 0.01 m/s as a material-point set.
fn pushed_points() -> Case {
    let model =
        mpm_shared::generate::box_mesh([2, 8, 2], [1.0, 4.0, 1.0], mpm_shared::ElementType::Tet4);
    let fixed = mpm_solve::input::case::confined_box(&model);
    let material = MaterialSpec::new("soil", 1000.0, 1000.0, 0.0).unwrap();
    let mut case = Case::single_material("pushed", model, material, 4, fixed);
    let rows = (0..case.model.element_count())
        .filter(|&e| {
            case.model.element(e)[..4]
                .iter()
                .all(|&n| case.model.node(n as usize)[1] >= 3.5)
        })
        .map(|e| PrescribedElement {
            element: e as u32,
            directions: [false, true, false],
            velocity: [0.0, -0.01, 0.0],
        })
        .collect();
    case.boundary.prescribed = Some(PrescribedVelocity {
        name: "block".into(),
        rows,
        scale: 1.0,
        curve: LoadCurve::ramp(0.2),
    });
    case.numerics.damping = 0.3;
    case.time.end_time = 2.0;
    case.time.output_times = vec![1.0, 2.0];
    case
}

#[test]
fn a_material_point_set_has_a_reaction_too() {
    let dir = tempfile::tempdir().unwrap();
    run::<f64, Tet4>(&pushed_points(), dir.path(), &RunOptions::default()).unwrap();
    let rows = read_reaction(dir.path());
    assert_eq!(rows.len(), 2);
    let r = &rows[1];
    assert_eq!(r.set, "block");
    // 0.01 m/s over 2 s less half the ramp, the ramp summed at the steps' ends (≈ 10 ms).
    assert!((r.u[1] + 0.01 * (2.0 - 0.1)).abs() < 1e-4, "{r:?}");
    // The 3.5 m below the pushed block take the displacement: F_y = A E u / 3.5 (ν = 0,
    // A = 1 m²), give or take the block's lowest nodes, which the points straddle.
    let want = 1000.0 * r.u[1] / 3.5;
    assert!((r.f[1] - want).abs() < 0.05 * want.abs(), "{r:?} vs {want}");
    assert_eq!((r.f[0], r.f[2]), (0.0, 0.0));
}

/// Loads a column scene with the `[[velocity]]` text `velocity`; the error's text on failure.
fn try_scene(velocity: &str) -> Result<Case, String> {
    let dir = tempfile::tempdir().unwrap();
    scene::load(&column(dir.path(), "s", velocity)).map_err(|e| e.to_string())
}

#[test]
fn velocity_entries_are_resolved_and_bad_ones_refused() {
    // A surface: its nodes, every component, named by the physical.
    let c = try_scene("[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -1.0, 0.0]").unwrap();
    assert_eq!(c.boundary.nodal_velocity.len(), 1);
    let s = &c.boundary.nodal_velocity[0];
    assert_eq!(s.name, "top");
    assert_eq!(s.rows.len(), 9);
    assert!(s
        .rows
        .iter()
        .all(|r| r.directions == [true; 3] && c.model.node(r.node as usize)[1] == 1.0));
    assert_eq!(s.curve, LoadCurve::Step);
    // A plane, with components and a ramp.
    let c = try_scene("[[velocity]]\nplane = \"y = 1.0\"\nvelocity = [0.0, -1.0, 0.0]\ncomponents = [false, true, false]\nramp = 0.5").unwrap();
    let s = &c.boundary.nodal_velocity[0];
    assert_eq!((s.name.as_str(), s.rows.len()), ("y = 1.0", 9));
    assert_eq!(s.rows[0].directions, [false, true, false]);
    assert_eq!(s.curve, LoadCurve::Ramp { over: 0.5 });
    // A volume: the points of its elements.
    let c =
        try_scene("[[velocity]]\nphysical = \"soil\"\nvelocity = [0.0, -1.0, 0.0]\nname = \"all\"")
            .unwrap();
    let p = c.boundary.prescribed.as_ref().unwrap();
    assert_eq!((p.name.as_str(), p.rows.len()), ("all", 480));
    assert!(c.boundary.nodal_velocity.is_empty());

    let refused = |text: &str, words: &[&str]| {
        let err = try_scene(text).unwrap_err();
        for w in words {
            assert!(err.contains(w), "{w:?} not in: {err}");
        }
    };
    refused(
        "[[velocity]]\nphysical = \"lid\"\nvelocity = [0.0, -1.0, 0.0]",
        &["velocity \"lid\"", "no physical surface or physical volume"],
    );
    refused(
        "[[velocity]]\nphysical = \"top\"\nplane = \"y = 1\"\nvelocity = [0.0, -1.0, 0.0]",
        &["velocity \"top\"", "exactly one of"],
    );
    refused(
        "[[velocity]]\nvelocity = [0.0, -1.0, 0.0]",
        &["exactly one of"],
    );
    refused(
        "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -1.0, 0.0]\ncomponents = [false, false, false]",
        &["velocity \"top\"", "prescribes nothing"],
    );
    refused(
        "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -1.0, 0.0]\ncomponents = [true, true]",
        &["components"],
    );
    refused(
        "[[velocity]]\nplane = \"y = 7\"\nvelocity = [0.0, -1.0, 0.0]",
        &["selects no node"],
    );
    refused(
        "[[velocity]]\nplane = \"w = 1\"\nvelocity = [0.0, -1.0, 0.0]",
        &["expected 'x = value'"],
    );
    refused(
        "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -1.0, 0.0]\nramp = -1.0",
        &["ramp"],
    );
    refused(
        "[[velocity]]\nphysical = \"soil\"\nvelocity = [0.0, -1.0, 0.0]\n[[velocity]]\nphysical = \"soil\"\nvelocity = [0.0, -2.0, 0.0]\nname = \"again\"",
        &["velocity \"again\"", "second material-point velocity"],
    );
    refused(
        "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -1.0, 0.0]\nspeed = 1.0",
        &["speed"],
    );
}
