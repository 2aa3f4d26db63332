//! Load curves (`curve` on `[[traction]]`, `[gravity]`, `[[velocity]]`; a traction's `hammer`):
//! an elastic pile struck at its head against the closed form of a bar under a ram, and tables
//! against the loads they scale. Run in release mode.

mod common;

use std::path::{Path, PathBuf};

use mpm_solve::driver::engine::Engine;
use mpm_solve::element::tet4::Tet4;

/// The pile: 0.1 × 0.1 m, 1 m long, 100 cells, ν = 0 so that the lateral rollers leave the
/// bar's wave speed sqrt(E / ρ) and its impedance Z = A sqrt(E ρ).
const W: f64 = 0.1;
const L: f64 = 1.0;
const CELLS: usize = 100;
const YOUNG: f64 = 10_000.0;
const DENSITY: f64 = 2000.0;

fn bar_speed() -> f64 {
    (YOUNG / (DENSITY / 1000.0)).sqrt()
}

fn impedance() -> f64 {
    W * W * (YOUNG * DENSITY / 1000.0).sqrt()
}

/// The pile on a fixed toe, sides on rollers, undamped, loaded on its head by `load` (TOML
/// keys of a `[[traction]]` on "top"), with `extra` tables, until `end`.
fn pile_scene(dir: &Path, name: &str, load: &str, extra: &str, end: f64) -> PathBuf {
    let mesh = common::column_msh(dir, CELLS, W, L);
    let text = format!(
        r#"mesh = "{mesh}"
[time]
end = {end}
output_interval = {end}
courant = 0.5
[[material]]
physical = "soil"
density = {DENSITY}
young = {YOUNG}
poisson = 0.0
points_per_element = 4
[[fixity]]
plane = "y = 0"
fixed = [true, true, true]
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = {W}"
fixed = [true, false, false]
[[fixity]]
plane = "z = 0"
fixed = [false, false, true]
[[fixity]]
plane = "z = {W}"
fixed = [false, false, true]
[[traction]]
physical = "top"
{load}
{extra}
"#,
        mesh = mesh.display()
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `scene` in the library to `end`, calling `each` after every step.
fn run(scene_path: &Path, end: f64, each: impl FnMut(&Engine<f64, Tet4>)) -> Engine<f64, Tet4> {
    common::run_scene(scene_path, end, each)
}

#[test]
fn a_struck_pile_carries_z_v0_over_a_to_its_toe_in_l_over_c() {
    let dir = tempfile::tempdir().unwrap();
    let (c, z) = (bar_speed(), impedance());
    // A ram of 2.5 times the pile's mass: the blow decays over 2.5 transits, and the head
    // stress falls slowly enough to be read behind the front.
    let (ram, v0) = (0.05, 0.1);
    let decay = z / ram;
    let head = z * v0 / (W * W);
    let hammer = format!("hammer = {{ ram_mass = {ram}, velocity = {v0}, impedance = {z} }}");
    let end = 1.2 * L / c;
    // The toe's slab: the points of the third cell from the toe, which the front reaches before
    // its reflection doubles it; the arrival is the first time their mean stress reaches half
    // of what arrives, the head's stress decayed over the travel.
    let h = L / CELLS as f64;
    let mut arrival = None;
    let mut prev = (0.0, 0.0);
    let mut head_reading = None;
    let engine = run(
        &pile_scene(dir.path(), "pile", &hammer, "", end),
        end,
        |e| {
            let p = &e.particles;
            let slab = |lo: f64, hi: f64| {
                let (s, n) = (0..p.len())
                    .filter(|&i| (lo..hi).contains(&(p.x[i][1] - p.u[i][1])))
                    .fold((0.0, 0), |(s, n), i| (s + p.stress[i][1], n + 1));
                -s / n as f64
            };
            let toe = slab(2.0 * h, 3.0 * h);
            let arriving = head * (-decay * L / c).exp();
            if arrival.is_none() && toe >= 0.5 * arriving {
                let (t0, s0) = prev;
                arrival = Some(t0 + (e.time - t0) * (0.5 * arriving - s0) / (toe - s0));
            }
            prev = (e.time, toe);
            // The head's stress read at half a transit, over the points 0.1–0.4 L below the head,
            // each against the closed form at its depth: σ = (Z v0 / A) exp(−(Z/m)(t − d / c)).
            if head_reading.is_none() && e.time >= 0.5 * L / c {
                let (mut got, mut want) = (0.0, 0.0);
                for i in 0..p.len() {
                    let d = L - (p.x[i][1] - p.u[i][1]);
                    if (0.1 * L..0.4 * L).contains(&d) {
                        got -= p.stress[i][1];
                        want += head * (-decay * (e.time - d / c)).exp();
                    }
                }
                head_reading = Some(got / want);
            }
        },
    );
    let ratio = head_reading.unwrap();
    // The slab's centre is 2.5 cells above the toe.
    let expected = (L - 2.5 * h) / c;
    let arrival = arrival.expect("the blow never reached the toe");
    eprintln!(
        "pile: head stress / (Z v0 / A) = {ratio:.4}; arrival at the toe {arrival:.6} s, (L − 2.5 h) / c = {expected:.6} s ({:+.2} %)",
        100.0 * (arrival / expected - 1.0)
    );
    assert!((ratio - 1.0).abs() < 0.02, "head stress ratio {ratio}");
    assert!(
        (arrival / expected - 1.0).abs() < 0.02,
        "arrival {arrival} vs {expected}"
    );
    assert!(engine.time >= end * (1.0 - 1e-12));
}

#[test]
fn a_table_scales_the_load_as_a_ramp_does() {
    // Quasi-static: a load raised over 20 transits by a table equals the ramp's at each time.
    let dir = tempfile::tempdir().unwrap();
    let c = bar_speed();
    let end = 20.0 * L / c;
    let damp = "[damping]\nlocal = 0.75";
    let ramp = pile_scene(
        dir.path(),
        "ramp",
        &format!("traction = [0.0, -10.0, 0.0]\nramp = {end}"),
        damp,
        end,
    );
    std::fs::write(dir.path().join("ramp.csv"), format!("t,m\n0,0\n{end},1\n")).unwrap();
    let table = pile_scene(
        dir.path(),
        "table",
        "traction = [0.0, -10.0, 0.0]\ncurve = \"ramp.csv\"",
        damp,
        end,
    );
    let a = run(&ramp, end, |_| {});
    let b = run(&table, end, |_| {});
    assert_eq!(
        a.particles.stress, b.particles.stress,
        "the same multipliers, the same bits"
    );
    // Up then down: a triangle back to zero leaves the pile unloaded (to its ringing).
    let tri = pile_scene(
        dir.path(),
        "triangle",
        &format!(
            "traction = [0.0, -10.0, 0.0]\ncurve = [[0, 0], [{}, 1], [{end}, 0]]",
            end / 2.0
        ),
        damp,
        end,
    );
    let e = run(&tri, end, |_| {});
    let worst = e
        .particles
        .stress
        .iter()
        .map(|s| s[1].abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.5, "after the triangle: {worst} kPa");
}

#[test]
fn bad_curves_are_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            "traction = [0.0, -1.0, 0.0]\ncurve = [[1, 0], [0, 1]]",
            "traction \"top\".curve",
        ),
        (
            "traction = [0.0, -1.0, 0.0]\nramp = 1\ncurve = [[0, 1]]",
            "a ramp or a curve, not both",
        ),
        (
            "hammer = { ram_mass = 1, velocity = 1, impedance = 0 }",
            "hammer.impedance",
        ),
        (
            "hammer = { ram_mass = 1, velocity = 1, impedance = 1, blows = 3 }",
            "3 blows need",
        ),
        (
            "pressure = 1\nhammer = { ram_mass = 1, velocity = 1, impedance = 1 }",
            "give one of",
        ),
        (
            "traction = [0.0, -1.0, 0.0]\ncurve = \"none.csv\"",
            "none.csv",
        ),
    ];
    for (i, (load, expected)) in cases.iter().enumerate() {
        let scene = pile_scene(d, &format!("bad{i}"), load, "", 0.001);
        let o = common::solve(&scene, &d.join(format!("out{i}")), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(expected),
            "{load}: {err}"
        );
    }
    let gravity = pile_scene(
        d,
        "g",
        "traction = [0.0, -1.0, 0.0]",
        "[gravity]\nvector = [0.0, -9.81, 0.0]\ncurve = 7",
        0.001,
    );
    let o = common::solve(&gravity, &d.join("g_out"), &[]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("gravity.curve"));
    let export = common::solve(
        &pile_scene(
            d,
            "export",
            "traction = [0.0, -1.0, 0.0]\ncurve = [[0, 0], [1, 1]]",
            "",
            0.001,
        ),
        &d.join("never"),
        &["--export-anura3d", &d.join("a3d").display().to_string()],
    );
    let err = String::from_utf8_lossy(&export.stderr);
    assert!(!export.status.success() && err.contains("curve"), "{err}");
    // A velocity's table goes to Anura3D's `.PVF`, which reads 0 past its last time: it must
    // outlast the run.
    let short = pile_scene(
        d,
        "short",
        "traction = [0.0, 0.0, 0.0]",
        "[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -0.01, 0.0]\ncurve = [[0, 0], [0.0005, 1]]",
        0.001,
    );
    let o = common::solve(
        &short,
        &d.join("never2"),
        &["--export-anura3d", &d.join("a3d2").display().to_string()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("a last one after the end"),
        "{err}"
    );
}
