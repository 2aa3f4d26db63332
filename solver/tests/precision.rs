//! Precision as a run-time choice: `--precision` on both input kinds and as a scene key, and the
//! model origin that keeps single precision usable on sites in UTM coordinates.

mod common;

use mpm_solve::element::tet4::Tet4;
use std::path::Path;

use assert_cmd::Command;
use mpm_solve::driver::engine::Engine;
use mpm_solve::driver::run::{run, RunOptions};
use mpm_solve::input::case::Case;
use mpm_solve::real::Real;

/// One field of point `i`, as f64 components.
type PointField<R> = dyn Fn(&Engine<R>, usize) -> Vec<f64>;

/// Largest |a - b| over the points, relative to the largest |a|, per field: position (in the
/// input's coordinates, less `shift`), displacement, velocity, stress.
fn differences<R: Real>(a: &Engine<R>, b: &Engine<R>, shift: [f64; 3]) -> [f64; 4] {
    let (pa, pb) = (&a.particles, &b.particles);
    assert_eq!(pa.id, pb.id, "same points in the same order");
    let mut out = [0.0; 4];
    let fields: [&PointField<R>; 4] = [
        &|e, i| e.mesh.global(&e.particles.x[i]).to_vec(),
        &|e, i| e.particles.u[i].iter().map(|v| v.f64()).collect(),
        &|e, i| e.particles.v[i].iter().map(|v| v.f64()).collect(),
        &|e, i| e.particles.stress[i].iter().map(|v| v.f64()).collect(),
    ];
    for (k, f) in fields.iter().enumerate() {
        let (mut diff, mut top) = (0.0f64, 0.0f64);
        for i in 0..pa.len() {
            let (va, vb) = (f(a, i), f(b, i));
            for c in 0..va.len() {
                let vb = if k == 0 { vb[c] - shift[c] } else { vb[c] };
                diff = diff.max((va[c] - vb).abs());
                top = top.max(va[c].abs());
            }
        }
        out[k] = diff / top.max(f64::MIN_POSITIVE);
    }
    out
}

/// The case moved by `shift`, and the case itself with its coordinates rounded as the moved
/// one holds them. At y = 5.8e6 m an f64 coordinate is only known to 1e-9 m: a mesh written in
/// UTM coordinates is a (slightly) different mesh, and that difference, not the solver, would
/// dominate the comparison. Rounding the reference the same way (`(x + s) - s` is exact, by
/// Sterbenz's lemma) compares the same geometry in both places.
fn translated(case: &Case, shift: [f64; 3]) -> (Case, Case) {
    let (mut here, mut there) = (case.clone(), case.clone());
    for (p, q) in here
        .model
        .coords
        .chunks_exact_mut(3)
        .zip(there.model.coords.chunks_exact_mut(3))
    {
        for a in 0..3 {
            q[a] = p[a] + shift[a];
            p[a] = q[a] - shift[a];
        }
    }
    (here, there)
}

fn both<R: Real>(case: &Case, shift: [f64; 3], dir: &Path) -> [f64; 4] {
    let opts = RunOptions::default();
    let (here, there) = translated(case, shift);
    let a = run::<R, Tet4>(&here, &dir.join(format!("{}-here", R::NAME)), &opts).unwrap();
    let b = run::<R, Tet4>(&there, &dir.join(format!("{}-utm", R::NAME)), &opts).unwrap();
    differences(&a, &b, shift)
}

#[test]
fn a_case_in_utm_coordinates_gives_the_results_of_the_same_case_at_the_origin() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = common::scene(tmp.path(), &|t| t);
    let case = mpm_solve::input::scene::load(&scene).unwrap();
    let shift = [450_000.0, 5_800_000.0, 0.0];
    for (name, d, tol) in [
        ("f64", both::<f64>(&case, shift, tmp.path()), 1e-9),
        ("f32", both::<f32>(&case, shift, tmp.path()), 1e-5),
    ] {
        for (field, v) in ["position", "displacement", "velocity", "stress"]
            .iter()
            .zip(d)
        {
            assert!(
                v <= tol,
                "{name}: {field} differs by {v:e} of its largest value after the translation"
            );
        }
    }
    // Without the origin, f32 positions at y = 5.8e6 m would have a resolution of 0.5 m; the
    // particle file still holds the input's coordinates.
    let out = tmp.path().join("f32-utm").join("particles_00001.vtu");
    let text = std::fs::read(&out).unwrap();
    assert!(text.len() > 1000);
}

#[test]
fn precision_is_chosen_on_the_command_line_for_both_input_kinds_and_in_scenes() {
    let tmp = tempfile::tempdir().unwrap();
    let precision_of = |dir: &Path| -> String {
        let j: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
        j["precision"].as_str().unwrap().to_string()
    };
    let scene = common::scene(tmp.path(), &|t| t);
    let gom = common::testdata("golden/column_anura3d.GOM");
    for (k, (input, extra, want)) in [
        (scene.clone(), vec![], "f64"),
        (scene.clone(), vec!["--precision", "f32"], "f32"),
        (gom.clone(), vec!["--precision", "f32"], "f32"),
        (gom, vec![], "f64"),
    ]
    .into_iter()
    .enumerate()
    {
        // One folder per run: a folder holding another case's run is refused.
        let out = tmp.path().join(format!("out-{want}-{k}"));
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&input)
            .arg("--out")
            .arg(&out)
            .args(["--quiet", "--threads", "2"])
            .args(&extra)
            .assert()
            .success();
        assert_eq!(precision_of(&out), want, "{}", input.display());
    }
    // The scene key, and the command line over it.
    let f32_scene = tmp.path().join("f32");
    std::fs::create_dir_all(&f32_scene).unwrap();
    let s = common::scene(&f32_scene, &|t| format!("precision = \"f32\"\n{t}"));
    for (extra, want) in [(vec![], "f32"), (vec!["--precision", "f64"], "f64")] {
        let out = tmp.path().join(format!("key-{want}"));
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&s)
            .arg("--out")
            .arg(&out)
            .args(["--quiet"])
            .args(&extra)
            .assert()
            .success();
        assert_eq!(precision_of(&out), want);
    }
    // A wrong value is named.
    let bad = tmp.path().join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    let s = common::scene(&bad, &|t| format!("precision = \"f16\"\n{t}"));
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&s)
        .arg("--check")
        .assert()
        .failure()
        .stderr(predicates::str::contains("\"f16\" is not a precision"));
}

#[test]
fn the_check_names_the_precision_and_the_cheaper_settings_of_the_accuracy_map() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = common::scene(tmp.path(), &|t| t);
    let out = |extra: &[&str]| -> String {
        let o = Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&scene)
            .arg("--check")
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success());
        String::from_utf8(o.stdout).unwrap()
    };
    let f64_plan = out(&[]);
    assert!(f64_plan.contains("in f64"), "{f64_plan}");
    assert!(f64_plan.contains("--precision f32:"), "{f64_plan}");
    assert!(f64_plan.contains("docs/accuracy.md"), "{f64_plan}");
    let f32_plan = out(&["--precision", "f32"]);
    assert!(f32_plan.contains("in f32"), "{f32_plan}");
    assert!(!f32_plan.contains("--precision f32:"), "{f32_plan}");
    // Half the bytes of state per point, so less memory predicted.
    let memory = |plan: &str| -> String {
        plan.lines()
            .find(|l| l.contains("memory:"))
            .unwrap()
            .to_string()
    };
    assert_ne!(memory(&f64_plan), memory(&f32_plan));
}

/// Single precision cuts a wave front's precursor from the nodal accelerations and re-mapped
/// velocities (`step::tail`): after each step of the saturated column (a sudden top load, whose
/// front runs down the column), no nonzero component of either phase lies below `f32::TAIL` of
/// the pair's largest, and the front has left such values behind in double precision, which
/// keeps them.
#[test]
fn single_precision_cuts_the_front_s_precursor_from_the_nodes_and_double_keeps_it() {
    use mpm_solve::state::grid::Grid;
    /// The fields' smallest nonzero magnitude over their largest.
    fn spread<R: Real>(g: &Grid<R>) -> [f64; 2] {
        let l = g.liquid.as_ref().expect("a two-phase grid");
        [[&g.acc, &l.acc], [&g.vel, &l.vel]].map(|pair| {
            let values = pair
                .iter()
                .flat_map(|f| f.iter().flatten())
                .map(|v| v.f64().abs());
            let largest = values.clone().fold(0.0, f64::max);
            let smallest = values.filter(|&v| v > 0.0).fold(f64::INFINITY, f64::min);
            smallest / largest
        })
    }
    fn run_steps<R: Real>(steps: usize) -> Vec<[f64; 2]> {
        let case = mpm_solve::input::scene::load(&common::testdata("golden/column_saturated.toml"))
            .unwrap();
        let mut engine = Engine::<R, Tet4>::new(&case, false).unwrap();
        (0..steps)
            .map(|_| {
                engine.step(engine.dt, None).unwrap();
                spread(&engine.grid)
            })
            .collect()
    }
    // The documented cut (2⁻⁴⁰ of the largest), written out so that a change of it is seen.
    let tail = 2f64.powi(-40);
    assert_eq!((f32::TAIL, f64::TAIL), (tail, 0.0));
    for (s, step) in run_steps::<f32>(20).iter().enumerate() {
        for (v, field) in step.iter().zip(["acceleration", "velocity"]) {
            assert!(*v >= tail, "f32 step {}: {field} spread {v:e}", s + 1);
        }
    }
    let kept = run_steps::<f64>(20);
    assert!(
        kept.iter().flatten().any(|&v| v < tail),
        "the f64 run shows no precursor to cut: {kept:?}"
    );
}
