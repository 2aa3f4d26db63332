//! Point-by-point comparisons with Anura3D itself: a scene is exported as a GOM/CPS pair
//! (`--export-anura3d`), run by the Anura3D binary that `ANURA3D_ORACLE` names (built by
//! `../shared/anura3d-oracle/build.sh`) and by `mpm-solve` on the same files, and every material
//! point is compared (by id) at the end of every load step. Skipped, visibly, when the variable
//! is unset; a failure when it names no file.

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_shared::anura3d_vtk::{read_step, MaterialPointState};
use mpm_solve::compare::tolerance::Tolerances;
use mpm_solve::input::case::Drag;
use mpm_solve::jobs::consolidation::{ConsolidationSpec, Layer, Start};
use mpm_solve::jobs::terzaghi;

mod common;
use common::{run_oracle, testdata};

/// The Anura3D binary, or `None` (skipped, visibly) when `ANURA3D_ORACLE` is unset.
fn oracle() -> Option<PathBuf> {
    common::oracle("comparison with Anura3D")
}

/// One load step's pore pressure and height of every material point, for the comparison with
/// Terzaghi (the point-by-point comparison with Anura3D goes through `mpm_solve::compare`).
#[derive(Debug, Clone, Default)]
struct Step {
    p: Vec<f64>,
    y: Vec<f64>,
}

fn from_anura3d(points: &[MaterialPointState]) -> Step {
    Step {
        p: points
            .iter()
            .map(|m| m.pressure_liquid.unwrap_or(0.0))
            .collect(),
        y: points.iter().map(|m| m.position[1]).collect(),
    }
}

/// Runs `mpm-solve` on the exported files with `drag`, writing its outputs into `out`; one
/// [`Step`] per load step.
fn run_ours(gom: &Path, cps: &Path, drag: Drag, out: &Path) -> Vec<Step> {
    let (mut case, _) = mpm_solve::input::anura3d::load(gom, cps).unwrap();
    case.numerics.drag = drag;
    let mut steps = Vec::new();
    mpm_solve::driver::run::run_observed::<f64, Tet4>(&case, out, &Default::default(), &mut |e| {
        let p = &e.particles;
        let l = p.liquid.as_ref();
        steps.push(Step {
            p: (0..p.len()).map(|i| l.map_or(0.0, |l| l.p[i])).collect(),
            y: (0..p.len()).map(|i| p.x[i][1]).collect(),
        });
    })
    .unwrap();
    steps
}

/// Per load step: (largest, RMS) difference of u, σ' and p over every point and component,
/// relative to the field's largest Anura3D value at that step, from `mpm-compare`'s library
/// with Anura3D's run folder as the golden side. `steps` load steps are expected.
fn compare(anura: &Path, ours: &Path, steps: usize) -> Vec<[(f64, f64); 3]> {
    compare_fields(anura, ours, steps, true)
}

/// [`compare`] of a dry case: u and σ' (p given as 0).
fn compare_dry(anura: &Path, ours: &Path, steps: usize) -> Vec<[(f64, f64); 3]> {
    compare_fields(anura, ours, steps, false)
}

/// [`compare`], the pore pressure compared only when `pore_pressure`.
fn compare_fields(
    anura: &Path,
    ours: &Path,
    steps: usize,
    pore_pressure: bool,
) -> Vec<[(f64, f64); 3]> {
    let report = mpm_solve::compare::compare(anura, ours, &Tolerances::default())
        .unwrap_or_else(|e| panic!("cannot compare with Anura3D: {e}"));
    assert_eq!(
        report.outputs.len(),
        steps,
        "different numbers of load steps"
    );
    report
        .outputs
        .iter()
        .map(|o| {
            ["displacement", "stress", "pore_pressure"].map(|name| {
                if name == "pore_pressure" && !pore_pressure {
                    return (0.0, 0.0);
                }
                let f = o
                    .fields
                    .iter()
                    .find(|f| f.field == name)
                    .unwrap_or_else(|| {
                        panic!("{name} not compared at {}: {:?}", o.golden, report.notes)
                    });
                (f.max_rel, f.rms_rel)
            })
        })
        .collect()
}

fn table(title: &str, rows: &[[(f64, f64); 3]]) -> String {
    let mut s = format!(
        "{title}\n| load step | u max | u RMS | σ' max | σ' RMS | p max | p RMS |\n|---:|---:|---:|---:|---:|---:|---:|\n"
    );
    for (k, r) in rows.iter().enumerate() {
        s.push_str(&format!(
            "| {} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} |\n",
            k + 1,
            r[0].0,
            r[0].1,
            r[1].0,
            r[1].1,
            r[2].0,
            r[2].1
        ));
    }
    s
}

/// RMS over points of (excess pore pressure - Terzaghi) / u0 at each load step.
fn terzaghi_rms(layer: &Layer, steps: &[Step], times: &[f64]) -> Vec<f64> {
    steps
        .iter()
        .zip(times)
        .map(|(st, &t)| {
            let tv = layer.tv(t);
            let sum: f64 =
                st.p.iter()
                    .zip(&st.y)
                    .map(|(&p, &y)| {
                        let zeta = ((layer.top - y) / layer.height).clamp(0.0, 1.0);
                        let e = (-p - layer.u0 * terzaghi::excess_pressure(zeta, tv)) / layer.u0;
                        e * e
                    })
                    .sum();
            (sum / st.p.len() as f64).sqrt()
        })
        .collect()
}

#[test]
fn consolidation_column_matches_anura3d_point_by_point() {
    let Some(bin) = oracle() else { return };
    let scene = testdata("oracle_column.toml");
    let dir = tempfile::tempdir().unwrap();
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, dir.path()).unwrap();
    let name = files.gom.file_stem().unwrap().to_string_lossy().to_string();
    run_oracle(&bin, dir.path(), &name);
    let case = mpm_solve::input::scene::load(&scene).unwrap();
    let anura: Vec<Step> = (1..=case.time.output_times.len() as u32)
        .map(|k| from_anura3d(&read_step(dir.path(), &name, k).unwrap()))
        .collect();
    let (ex, im) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run_ours(&files.gom, &files.cps, Drag::Explicit, ex.path());
    let ours = run_ours(&files.gom, &files.cps, Drag::Implicit, im.path());
    let steps = case.time.output_times.len();
    let explicit = compare(dir.path(), ex.path(), steps);
    let implicit = compare(dir.path(), im.path(), steps);
    eprintln!(
        "{}",
        table(
            "mpm-solve --drag explicit against Anura3D (relative to each field's largest Anura3D value)",
            &explicit
        )
    );
    eprintln!(
        "{}",
        table("mpm-solve --drag implicit against Anura3D", &implicit)
    );
    // Against Terzaghi, both codes on the same files.
    let spec = ConsolidationSpec {
        load: 10.0,
        start: Start::Rest,
        compare_rest: false,
    };
    let layer = Layer::of(&case, &spec).unwrap();
    let (ta, to) = (
        terzaghi_rms(&layer, &anura, &case.time.output_times),
        terzaghi_rms(&layer, &ours, &case.time.output_times),
    );
    eprintln!("| T_v | Anura3D RMS / u0 | mpm-solve (implicit drag) RMS / u0 |\n|---:|---:|---:|");
    for (k, t) in case.time.output_times.iter().enumerate() {
        eprintln!("| {:.3} | {:.4} | {:.4} |", layer.tv(*t), ta[k], to[k]);
    }
    for (k, r) in explicit.iter().enumerate() {
        for (f, name) in r.iter().zip(["u", "σ'", "p"]) {
            assert!(
                f.0 <= 1e-4,
                "explicit drag, load step {}: {name} differs by {:.2e} of its largest value",
                k + 1,
                f.0
            );
        }
    }
    for (k, r) in implicit.iter().enumerate() {
        for (f, name) in r.iter().zip(["u", "σ'", "p"]) {
            assert!(
                f.1 <= 1e-2,
                "implicit drag, load step {}: {name} RMS difference {:.2e}",
                k + 1,
                f.1
            );
        }
    }
}

/// Anura3D's 10-point rule on linear tetrahedra: the oracle column with 10 points per element,
/// both codes on the same exported files, explicit drag, to T_v = 0.1 (four outputs): every
/// point's u, σ' and p agree.
#[test]
fn ten_points_per_element_match_anura3d() {
    let Some(bin) = oracle() else { return };
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(testdata("oracle_column.toml"))
        .unwrap()
        .replace("points_per_element = 4", "points_per_element = 10")
        .replace("end_tv = 0.5", "end_tv = 0.1")
        .replace(
            "oracle_column_tet4.msh",
            &testdata("oracle_column_tet4.msh").display().to_string(),
        );
    assert!(text.contains("points_per_element = 10") && text.contains("end_tv = 0.1"));
    let scene = dir.path().join("ten.toml");
    std::fs::write(&scene, text).unwrap();
    let a3d = dir.path().join("a3d");
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
    run_oracle(&bin, &a3d, "ten");
    let steps = mpm_solve::input::scene::load(&scene)
        .unwrap()
        .time
        .output_times
        .len();
    let out = tempfile::tempdir().unwrap();
    run_ours(&files.gom, &files.cps, Drag::Explicit, out.path());
    let rows = compare(&a3d, out.path(), steps);
    eprintln!(
        "{}",
        table(
            "10 points per element, --drag explicit, against Anura3D",
            &rows
        )
    );
    for (k, r) in rows.iter().enumerate() {
        for (f, name) in r.iter().zip(["u", "σ'", "p"]) {
            assert!(
                f.0 <= 1e-4,
                "load step {}: {name} differs by {:.2e} of its largest value",
                k + 1,
                f.0
            );
        }
    }
}

/// Anura3D's workshop set-up (at rest, 10 kPa applied suddenly, damping 0.05) on the default
/// job's mesh, run by Anura3D and by the default job's own workshop twin (`compare_rest`):
/// against Terzaghi, our RMS pore-pressure error is no worse than Anura3D's at any output.
/// About 7 minutes of Anura3D on this machine: `cargo test --release -p mpm-solve --test oracle
/// -- --ignored` with `ANURA3D_ORACLE` set.
#[test]
#[ignore = "runs Anura3D for about 7 minutes"]
fn workshop_set_up_no_worse_than_anura3d_against_terzaghi() {
    let Some(bin) = oracle() else { return };
    let dir = tempfile::tempdir().unwrap();
    // The default job with the workshop's start, as a scene next to the default mesh.
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace("start = \"undrained\"", "start = \"rest\"")
        .replace("compare_rest = true", "compare_rest = false")
        .replace(
            "mesh = \"oedometer_tet4.msh\"",
            &format!(
                "mesh = {:?}",
                testdata("oedometer_tet4.msh").display().to_string()
            ),
        );
    let scene = dir.path().join("workshop.toml");
    std::fs::write(&scene, text).unwrap();
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, dir.path()).unwrap();
    run_oracle(&bin, dir.path(), "workshop");
    let case = mpm_solve::input::scene::load(&scene).unwrap();
    let anura: Vec<Step> = (1..=case.time.output_times.len() as u32)
        .map(|k| from_anura3d(&read_step(dir.path(), "workshop", k).unwrap()))
        .collect();
    let layer = Layer::of(&case, &case.start.consolidation.unwrap()).unwrap();
    let theirs = terzaghi_rms(&layer, &anura, &case.time.output_times);
    // Ours: the default job's workshop column (the scene route, its own damping rule).
    let job = mpm_solve::input::scene::load(&testdata("oedometer.toml")).unwrap();
    let out = tempfile::tempdir().unwrap();
    let (_, _, workshop) =
        mpm_solve::jobs::consolidation::run_job::<f64, Tet4>(&job, out.path(), &Default::default())
            .unwrap();
    let ours = workshop.expect("the default job runs the workshop set-up too");
    eprintln!("| T_v | Anura3D RMS / u0 | mpm-solve workshop column RMS / u0 |\n|---:|---:|---:|");
    assert_eq!(ours.records.len(), theirs.len());
    for (r, a) in ours.records.iter().zip(&theirs) {
        eprintln!("| {:.2} | {:.4} | {:.4} |", r.tv, a, r.rms);
    }
    let _ = files;
    for (r, a) in ours.records.iter().zip(&theirs) {
        assert!(
            r.rms <= *a,
            "T_v = {}: RMS {:.4} against Anura3D's {:.4}",
            r.tv,
            r.rms,
            a
        );
    }
}

/// Benchmark 4005 run for four load steps instead of its one quasi-static step: a load on the
/// liquid, MPM-MIXED, objective stress and strain smoothing together, against Anura3D, point by
/// point (needs `ANURA3D_BENCHMARKS` too).
#[test]
fn liquid_load_mixed_objective_smoothing_match_anura3d() {
    let Some(bin) = oracle() else { return };
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(root) = found else {
        mpm_shared::suite::skipped("benchmark 4005 against Anura3D (ANURA3D_BENCHMARKS not set)");
        return;
    };
    let case = root.join(
        "Benchmarks/Pre-Commit_Tests/4005_LinearLoad_DYN_MPMMIXED_pressure_2019.1/test-4005.A3D",
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(case.join("test-4005.GOM"), dir.path().join("c.GOM")).unwrap();
    // Four dynamic load steps with a sudden load and light damping.
    let cps = common::with_cps_values(
        &std::fs::read_to_string(case.join("test-4005.CPS_001")).unwrap(),
        &[
            ("$$NUMBER_OF_LOADSTEPS", "4"),
            ("$$TIME_PER_LOADSTEP", "0.0005"),
            ("$$QUASISTATIC_CONVERGENCE", "0"),
            ("$$HOMOGENEOUS_LOCAL_DAMPING", "1 0.05"),
            ("$$LIQUID_PRESSURE", "step 1.0 1.0"),
        ],
    );
    std::fs::write(dir.path().join("c.CPS_001"), cps).unwrap();
    run_oracle(&bin, dir.path(), "c");
    let out = tempfile::tempdir().unwrap();
    run_ours(
        &dir.path().join("c.GOM"),
        &dir.path().join("c.CPS_001"),
        Drag::Explicit,
        out.path(),
    );
    let rows = compare(dir.path(), out.path(), 4);
    eprintln!(
        "{}",
        table("4005 over four load steps, --drag explicit", &rows)
    );
    for (k, r) in rows.iter().enumerate() {
        for (f, name) in r.iter().zip(["u", "σ'", "p"]) {
            assert!(
                f.0 <= 1e-10,
                "load step {}: {name} differs by {:.2e}",
                k + 1,
                f.0
            );
        }
    }
}

/// A dry column compressed by a rough platen (`[[velocity]]` on its top surface, exported as
/// `$$PRESCRIBED_NODAL_VELOCITY_SURFACE`), sudden (`step`), ramped over the run (`linear`), and
/// following a table (`file`, the project's `.PVF`), also one that ends within the run (the
/// platen stops), against Anura3D point by point: u and σ' agree to round-off in every load
/// step.
#[test]
fn prescribed_nodal_velocity_matches_anura3d() {
    let Some(bin) = oracle() else { return };
    let table = "curve = [[0.0, 0.0], [0.05, 1.0], [0.1, 0.25], [0.15, 1.5], [0.3, 0.5]]";
    for (name, multiplier, pvf) in [
        ("sudden", "ramp = 0.0", None),
        ("ramped", "ramp = 0.2", None),
        ("table", table, None),
        (
            "stopping",
            table,
            Some("0.0 0.0\n0.04 1.0\n0.12 0.5\nend\n"),
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let text = format!(
            r#"mesh = "{}"
[time]
end = 0.2
courant = 0.5
output_interval = 0.05
[damping]
local = 0.1
[[material]]
physical = "soil"
density = 2000.0
young = 1000.0
poisson = 0.3
points_per_element = 4
[[fixity]]
physical = "bottom"
fixed = [true, true, true]
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = 0.1"
fixed = [true, false, false]
[[velocity]]
physical = "top"
velocity = [0.002, -0.01, 0.0]
{multiplier}
"#,
            testdata("oracle_column_tet4.msh").display()
        );
        let scene = dir.path().join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let a3d = dir.path().join("a3d");
        let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
        let gom = std::fs::read_to_string(&files.gom).unwrap();
        assert!(gom.contains("$$PRESCRIBED_NODAL_VELOCITY_SURFACE\n25\n"));
        if let Some(rows) = pvf {
            std::fs::write(a3d.join(format!("{name}.PVF")), rows).unwrap();
        }
        run_oracle(&bin, &a3d, name);
        let out = tempfile::tempdir().unwrap();
        run_ours(&files.gom, &files.cps, Drag::Explicit, out.path());
        // The GOM's nodal set records its reaction.
        assert!(out.path().join("reaction.csv").exists());
        let report = mpm_solve::compare::compare(&a3d, out.path(), &Tolerances::default())
            .unwrap_or_else(|e| panic!("cannot compare with Anura3D: {e}"));
        assert_eq!(report.outputs.len(), 4);
        for o in &report.outputs {
            for field in ["displacement", "stress"] {
                let f = o.fields.iter().find(|f| f.field == field).unwrap();
                eprintln!("{name} {}: {field} max rel {:.2e}", o.golden, f.max_rel);
                assert!(
                    f.max_rel <= 1e-10,
                    "{name}, {}: {field} differs by {:.2e} of its largest value",
                    o.golden,
                    f.max_rel
                );
            }
        }
    }
}
/// Largest difference of σ' and of p (each relative to its largest Anura3D value) between
/// Anura3D's first output of the run in `dir` (project `name`; written after its first step,
/// which lasts 1e-15 s, so it holds the initial state) and the initial state of `mpm-solve` set
/// up on the same files, point by point by id.
fn initial_state_difference(dir: &Path, name: &str) -> (f64, f64) {
    let anura = read_step(dir, name, 0).unwrap();
    let (case, _) = mpm_solve::input::anura3d::load(
        &dir.join(format!("{name}.GOM")),
        &dir.join(format!("{name}.CPS_001")),
    )
    .unwrap();
    let engine = mpm_solve::driver::engine::Engine::<f64, Tet4>::new(&case, false).unwrap();
    let p = &engine.particles;
    assert_eq!(p.len(), anura.len(), "different numbers of points");
    let mut index = vec![usize::MAX; p.len() + 1];
    for (i, &id) in p.id.iter().enumerate() {
        index[id as usize] = i;
    }
    let big = |f: &dyn Fn(&MaterialPointState) -> f64| {
        anura.iter().map(|m| f(m).abs()).fold(0.0, f64::max)
    };
    let s_max = anura
        .iter()
        .flat_map(|m| m.eff_stress_solid)
        .fold(0.0, |a: f64, v| a.max(v.abs()));
    let p_max = big(&|m| m.pressure_liquid.unwrap_or(0.0));
    assert!(s_max > 0.0, "Anura3D started unstressed");
    let (mut ds, mut dp) = (0.0f64, 0.0f64);
    for m in &anura {
        let i = index[m.id as usize];
        for (a, b) in m.eff_stress_solid.iter().zip(&p.stress[i]) {
            ds = ds.max((a - b).abs() / s_max);
        }
        if let Some(l) = &p.liquid {
            dp = dp.max((m.pressure_liquid.unwrap_or(0.0) - l.p[i]).abs() / p_max.max(1e-300));
        }
    }
    (ds, dp)
}

/// Anura3D's K0 procedure on two dry layers of different densities and K0 values under gravity
/// (`testdata/layered_k0.toml`, exported): the initial stresses agree point by point to
/// round-off, and so do u and σ' after each of the three load steps.
#[test]
fn layered_k0_column_matches_anura3d_point_by_point() {
    let Some(bin) = oracle() else { return };
    let dir = tempfile::tempdir().unwrap();
    let files =
        mpm_solve::input::export_anura3d::export_scene(&testdata("layered_k0.toml"), dir.path())
            .unwrap();
    run_oracle(&bin, dir.path(), "layered_k0");
    let (ds, _) = initial_state_difference(dir.path(), "layered_k0");
    eprintln!("initial σ': largest difference {ds:.1e} of the largest value");
    assert!(ds <= 1e-12, "initial σ' differs by {ds:.2e}");
    let out = tempfile::tempdir().unwrap();
    run_ours(&files.gom, &files.cps, Drag::Implicit, out.path());
    let rows = compare_dry(dir.path(), out.path(), 3);
    eprintln!("{}", table("two K0 layers against Anura3D", &rows));
    for (k, r) in rows.iter().enumerate() {
        for (f, name) in r.iter().zip(["u", "σ'"]) {
            assert!(
                f.0 <= 1e-10,
                "load step {}: {name} differs by {:.2e}",
                k + 1,
                f.0
            );
        }
    }
}

/// The K0 procedure on a saturated (coupled) column: effective stresses from the mixture's
/// weight less the hydrostatic pore pressure, which the points start with; both agree with
/// Anura3D's point by point to round-off, at the start and after three load steps.
#[test]
fn saturated_k0_column_matches_anura3d_point_by_point() {
    let Some(bin) = oracle() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sat_k0.toml");
    let mut text = format!(
        "mesh = {:?}\n[time]\nend = 0.006\ncourant = 0.5\noutput_interval = 0.002\n\
         [gravity]\nvector = [0.0, -9.81, 0.0]\n\
         [[material]]\nphysical = \"soil\"\ndensity = 2650.0\nyoung = 10000.0\npoisson = 0.3\nk0 = 0.5\n\
         [material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.15e4\n\
         intrinsic_permeability = 1.0e-10\nviscosity = 1.0e-6\n\
         [[fixity]]\nphysical = \"bottom\"\nfixed = [true, true, true]\n",
        testdata("oracle_column_tet4.msh").display().to_string()
    );
    for (plane, fixed) in [
        ("x = 0", "[true, false, false]"),
        ("x = 0.1", "[true, false, false]"),
        ("z = 0", "[false, false, true]"),
        ("z = 0.1", "[false, false, true]"),
    ] {
        text += &format!("[[fixity]]\nplane = \"{plane}\"\nfixed = {fixed}\n");
    }
    std::fs::write(&scene, text).unwrap();
    let a3d = dir.path().join("a3d");
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
    run_oracle(&bin, &a3d, "sat_k0");
    let (ds, dp) = initial_state_difference(&a3d, "sat_k0");
    eprintln!("initial σ' and p: largest differences {ds:.1e} and {dp:.1e} of the largest values");
    assert!(
        ds <= 1e-12 && dp <= 1e-12,
        "initial σ' {ds:.2e}, p {dp:.2e}"
    );
    let out = tempfile::tempdir().unwrap();
    run_ours(&files.gom, &files.cps, Drag::Explicit, out.path());
    let rows = compare(&a3d, out.path(), 3);
    eprintln!("{}", table("saturated K0 column against Anura3D", &rows));
    for (k, r) in rows.iter().enumerate() {
        // u is compared relative to a displacement that is itself round-off (the column is
        // at rest): only σ' and p are meaningful here.
        for (f, name) in r.iter().zip(["u", "σ'", "p"]).skip(1) {
            assert!(
                f.0 <= 1e-10,
                "load step {}: {name} differs by {:.2e}",
                k + 1,
                f.0
            );
        }
    }
}

/// Benchmark 0011 (saturated, MPM-MIXED, quasi-static) starts from the K0 procedure with a
/// surface load (`$$INITIAL_VERTICAL_LOAD_K0 -50`): its initial σ' and p agree with Anura3D's
/// point by point (needs `ANURA3D_BENCHMARKS` too).
#[test]
fn benchmark_0011_k0_start_matches_anura3d() {
    let Some(bin) = oracle() else { return };
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(root) = found else {
        mpm_shared::suite::skipped("benchmark 0011 against Anura3D (ANURA3D_BENCHMARKS not set)");
        return;
    };
    let case = root.join(
        "Benchmarks/Pre-Commit_Tests/0011_1D_Oedometer_Elasticity_2Phase_MPM_SuddenLoad_Consolidation_Ex2_1a",
    );
    let dir = tempfile::tempdir().unwrap();
    for ext in ["GOM", "CPS_001"] {
        std::fs::copy(
            case.join(format!("test-11_2021.{ext}")),
            dir.path().join(format!("c.{ext}")),
        )
        .unwrap();
    }
    run_oracle(&bin, dir.path(), "c");
    let (ds, dp) = initial_state_difference(dir.path(), "c");
    eprintln!("benchmark 0011, initial σ' and p: largest differences {ds:.1e} and {dp:.1e}");
    assert!(
        ds <= 1e-12 && dp <= 1e-12,
        "initial σ' {ds:.2e}, p {dp:.2e}"
    );
}
