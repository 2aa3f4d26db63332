//! `--export-anura3d`: scenes written as Anura3D cases read back, run in both forms, refused
//! where Anura3D cannot reproduce them, and (with `ANURA3D_ORACLE` naming an Anura3D binary)
//! run by Anura3D itself.

use mpm_solve::element::tet4::Tet4;
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use mpm_shared::model::{Body, Token};
use mpm_shared::{ElementType, Model};
use mpm_solve::driver::engine::Engine;
use mpm_solve::input::case::Case;
use predicates::prelude::*;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// A copy of `testdata/NAME` in `dir` as `stem.toml`, its mesh path made absolute and `edit`
/// applied.
fn scene(dir: &Path, name: &str, stem: &str, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata(name)).unwrap();
    let text = text
        .replace(
            "\"column_fine_tet4.msh\"",
            &format!("{:?}", testdata("column_tet4.msh")),
        )
        .replace(
            "\"oedometer_tet4.msh\"",
            &format!("{:?}", testdata("oedometer_tet4.msh")),
        );
    let p = dir.join(format!("{stem}.toml"));
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// The oedometer scene as the workshop runs it: at rest, the load applied suddenly.
fn rest(t: String) -> String {
    t.replace(
        "start = \"undrained\"              # Terzaghi's t = 0+ state: no dynamic transient",
        "start = \"rest\"",
    )
}

/// The oedometer scene without its consolidation table, over `end` seconds without damping.
fn short_oedometer(t: String, end: f64) -> String {
    let t = t[..t.find("[consolidation]").unwrap()].to_string();
    t.replace(
        "[time]\ncourant = 0.5",
        &format!(
            "[time]\nend = {end}\ncourant = 0.5\noutput_interval = {}",
            end / 2.0
        ),
    )
    .replace("local = 0.05", "local = 0.0")
}

/// A short, undamped column under gravity on the coarse column mesh.
fn short_column(t: String) -> String {
    t.replace("end = 0.6", "end = 0.02")
        .replace("output_interval = 0.1", "output_interval = 0.01")
        .replace("local = 0.75", "local = 0.0")
}

/// `mpm-solve SCENE --export-anura3d DIR`, expected to succeed; returns (GOM, CPS).
fn export(scene: &Path, dir: &Path) -> (PathBuf, PathBuf) {
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(scene)
        .arg("--export-anura3d")
        .arg(dir)
        .assert()
        .success()
        .stdout(predicate::str::contains("wrote"));
    let stem = scene.file_stem().unwrap().to_string_lossy().to_string();
    let gom = dir.join(format!("{stem}.GOM"));
    let cps = dir.join(format!("{stem}.CPS_001"));
    assert!(gom.is_file() && cps.is_file());
    (gom, cps)
}

fn rows<'a>(model: &'a Model, keyword: &str) -> Vec<&'a [Token]> {
    model.table(keyword).unwrap().rows().collect()
}

fn int(t: &Token) -> i64 {
    t.as_int().unwrap()
}

/// The exported mesh is the scene's with mid-edge nodes: same elements in the same order, same
/// corners and corner nodes, every mid-edge node exactly at its edge's midpoint, shared between
/// neighbours and numbered after the original nodes in order of first appearance; fixities of
/// both phases as the scene's, a new mid-edge node fixed where both its corners are.
fn check_mesh(scene: &Case, gom: &Model) {
    let m = &scene.model;
    assert_eq!(m.element_type, ElementType::Tet4);
    assert_eq!(gom.element_type, ElementType::Tet10);
    assert_eq!(gom.element_count(), m.element_count());
    let n = m.node_count();
    assert_eq!(&gom.coords[..3 * n], &m.coords[..]);
    const EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)];
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut next = n as u32;
    for e in 0..m.element_count() {
        let (c, g) = (m.element(e), gom.element(e));
        assert_eq!(&g[..4], c, "element {e}: corners");
        for (k, (a, b)) in EDGES.iter().enumerate() {
            let mid = g[4 + k];
            let want = *edges
                .entry((c[*a].min(c[*b]), c[*a].max(c[*b])))
                .or_insert_with(|| {
                    next += 1;
                    next - 1
                });
            assert_eq!(mid, want, "element {e}: mid-edge node {}", k + 5);
            let (p, q, x) = (
                m.node(c[*a] as usize),
                m.node(c[*b] as usize),
                gom.node(mid as usize),
            );
            for d in 0..3 {
                assert_eq!(x[d], 0.5 * (p[d] + q[d]));
            }
        }
    }
    assert_eq!(gom.node_count(), next as usize);
    gom.check_shapes(0.0).unwrap();
    for (keyword, want) in [
        ("START_FIXITY_SURFACE_SOLID", &scene.boundary.fixed),
        ("START_FIXITY_SURFACE_LIQUID", &scene.boundary.liquid_fixed),
    ] {
        let mut got = vec![[false; 3]; gom.node_count()];
        for r in rows(gom, keyword) {
            got[int(&r[0]) as usize - 1] = [1, 2, 3].map(|i| int(&r[i]) == 1);
        }
        assert_eq!(&got[..n], &want[..], "{keyword}");
        for ((a, b), mid) in &edges {
            let (fa, fb) = (want[*a as usize], want[*b as usize]);
            assert_eq!(
                got[*mid as usize],
                [0, 1, 2].map(|d| fa[d] && fb[d]),
                "{keyword}: mid-edge node {}",
                mid + 1
            );
        }
        assert!(!got.iter().all(|f| *f == [false; 3]));
    }
    for k in ["LINE", "POINT"] {
        for p in ["SOLID", "LIQUID", "GAS"] {
            assert!(rows(gom, &format!("START_FIXITY_{k}_{p}")).is_empty());
        }
    }
    assert!(rows(gom, "START_REMOVE_FIXITY_SURFACE_SOLID").is_empty());
    let points: Vec<u32> = gom.material_points_per_element().unwrap();
    assert_eq!(points, scene.body.points_per_element);
}

/// The material points of both runs: same ids and initial positions (exactly), displacements
/// and stresses within `tol` of the largest.
fn check_runs(a: &Case, b: &Case, tol: f64) {
    let start = |c: &Case| {
        let e = Engine::<f64, Tet4>::new(c, false).unwrap();
        (e.particles.id.clone(), e.particles.x.clone())
    };
    let (ids, x0) = start(a);
    assert_eq!((ids.clone(), x0), start(b));
    let dir = tempfile::tempdir().unwrap();
    let ra =
        mpm_solve::driver::run::run::<f64, Tet4>(a, &dir.path().join("a"), &Default::default())
            .unwrap();
    let rb =
        mpm_solve::driver::run::run::<f64, Tet4>(b, &dir.path().join("b"), &Default::default())
            .unwrap();
    let (pa, pb) = (&ra.particles, &rb.particles);
    assert_eq!(pa.id, pb.id);
    let big_u = pa.u.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let big_s = pa
        .stress
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(big_u > 0.0 && big_s > 0.0);
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..pa.len() {
        for d in 0..3 {
            worst.0 = worst.0.max((pa.u[i][d] - pb.u[i][d]).abs() / big_u);
        }
        for d in 0..6 {
            worst.1 = worst
                .1
                .max((pa.stress[i][d] - pb.stress[i][d]).abs() / big_s);
        }
    }
    eprintln!(
        "{} points, {} and {} steps; largest differences: displacement {:.2e}, stress {:.2e} (of the largest)",
        pa.len(),
        ra.steps,
        rb.steps,
        worst.0,
        worst.1
    );
    assert!(worst.0 <= tol && worst.1 <= tol, "{worst:?}");
}

#[test]
fn dry_column_exports_and_runs_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "column_gravity.toml", "column", &short_column);
    let (gom_path, cps_path) = export(&s, &dir.path().join("a3d"));
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    let gom = mpm_shared::read_gom_file(&gom_path).unwrap();
    check_mesh(&sc, &gom);
    assert!(gom.table("START_LOAD_ON_NODES_SOLID").is_none());
    let mats = gom.materials();
    assert_eq!(mats.len(), 1);
    let props: Vec<(&str, &str)> = mats[0]
        .properties
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    assert_eq!(
        props,
        [
            ("MATERIAL_INDEX", "1"),
            ("MATERIAL_NAME", "soil"),
            ("MATERIAL_TYPE", "dry_material"),
            ("POROSITY_SOLID", "0.0"),
            ("DENSITY_SOLID", "2000.0"),
            ("K0_VALUE_SOLID", "0.0"),
            ("MATERIAL_MODEL_SOLID", "linear_elasticity"),
            ("YOUNG_MODULUS", "10000.0"),
            ("POISSON_RATIO", "0.3"),
        ]
    );
    let cps = std::fs::read(&cps_path).unwrap();
    let (cps, warnings) = mpm_shared::cps::Cps::read(&cps, "x").unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let line = |k: &str| cps.get(k).unwrap().lines.join("|");
    assert_eq!(line("NUMBER_OF_LOADSTEPS"), "2");
    assert_eq!(line("TIME_PER_LOADSTEP"), "0.01");
    assert_eq!(line("COMPUTATION_METHOD"), "MPM-MP");
    assert_eq!(line("GRAVITY_ACCELERATION"), "9.81");
    assert_eq!(line("GRAVITY_VECTOR"), "0.0 -1.0 0.0");
    assert_eq!(line("GRAVITY_LOAD"), "step  1.0  1.0");
    assert_eq!(line("SOLID_TRACTION"), "off  0.0  1.0");
    assert_eq!(line("HOMOGENEOUS_LOCAL_DAMPING"), "0 0.0");
    assert_eq!(line("STRAIN_SMOOTHING"), "0");
    assert_eq!(line("QUASISTATIC_CONVERGENCE"), "0");
    // No probes in the scene: the first, a middle and the last point.
    let n_points: u32 = sc.body.points_per_element.iter().sum();
    assert_eq!(
        cps.settings().unwrap().output_material_points,
        [1, n_points / 2, n_points]
    );
    // The GOM route builds the same case and computes the same.
    let (gc, _) = mpm_solve::input::anura3d::load(&gom_path, &cps_path).unwrap();
    assert_eq!(gc.body.materials, sc.body.materials);
    assert_eq!(gc.loads.gravity, sc.loads.gravity);
    assert_eq!(
        (gc.time.courant, gc.numerics.damping),
        (sc.time.courant, sc.numerics.damping)
    );
    assert_eq!(gc.time.output_times.len(), sc.time.output_times.len());
    for (a, b) in gc.time.output_times.iter().zip(&sc.time.output_times) {
        assert!((a - b).abs() <= 1e-12 * b);
    }
    check_runs(&sc, &gc, 1e-9);
}

#[test]
fn saturated_oedometer_exports_loads_and_runs_alike() {
    let dir = tempfile::tempdir().unwrap();
    // The consolidation job (at rest) exports as is.
    let s = scene(dir.path(), "oedometer.toml", "oedometer", &rest);
    let out = dir.path().join("a3d");
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&s)
        .arg("--export-anura3d")
        .arg(&out)
        .assert()
        .success()
        .stderr(predicate::str::contains("damps the liquid"));
    let gom = mpm_shared::read_gom_file(&out.join("oedometer.GOM")).unwrap();
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    check_mesh(&sc, &gom);
    let mats = gom.materials();
    let m = &mats[0];
    assert_eq!(m.kind, "saturated_material_coupled");
    for (k, v) in [
        ("POROSITY_SOLID", 0.4),
        ("DENSITY_SOLID", 2650.0),
        ("DENSITY_LIQUID", 1000.0),
        ("INTRINSIC_PERMEABILITY_LIQUID", 1.0214e-9),
        ("BULK_MODULUS_LIQUID", 2.15e4),
        ("DYNAMIC_VISCOSITY_LIQUID", 1.0e-6),
        ("K0_VALUE_SOLID", 0.0),
        ("YOUNG_MODULUS", 1000.0),
        ("POISSON_RATIO", 0.3),
    ] {
        assert_eq!(m.get_f64(k), Some(v), "{k}");
    }
    assert_eq!(m.get("MATERIAL_MODEL_SOLID"), Some("linear_elasticity"));
    // One load row per top face: corners on the top, (c2 - c1) x (c3 - c1) pointing into the
    // soil (down) as Anura3D's pre-processor writes boundary faces, the mid-edge nodes of edges
    // 12 23 31, and the traction at all six nodes.
    let loads = rows(&gom, "START_LOAD_ON_NODES_SOLID");
    let top = sc
        .model
        .coords
        .chunks_exact(3)
        .fold(f64::MIN, |m, p| m.max(p[1]));
    let mut area = 0.0;
    for r in &loads {
        assert_eq!(r.len(), 24);
        let ids: Vec<usize> = r[..6].iter().map(|t| int(t) as usize - 1).collect();
        let p: Vec<&[f64]> = ids.iter().map(|&i| gom.node(i)).collect();
        for x in &p {
            assert_eq!(x[1], top);
        }
        for (m, (a, b)) in [(3, (0, 1)), (4, (1, 2)), (5, (2, 0))] {
            let want: Vec<f64> = (0..3).map(|d| 0.5 * (p[a][d] + p[b][d])).collect();
            assert_eq!(p[m], want);
        }
        let (u, v) = (
            [0, 1, 2].map(|d| p[1][d] - p[0][d]),
            [0, 1, 2].map(|d| p[2][d] - p[0][d]),
        );
        let ny = u[2] * v[0] - u[0] * v[2];
        assert!(ny < 0.0, "face {ids:?} points out of the soil");
        area += -0.5 * ny;
        for node in 0..6 {
            let t: Vec<f64> = (0..3)
                .map(|d| r[6 + 3 * node + d].as_f64().unwrap())
                .collect();
            assert_eq!(t, [0.0, -10.0, 0.0]);
        }
    }
    assert!((area - 0.01).abs() < 1e-12, "loaded area {area}");
    let cps = std::fs::read(out.join("oedometer.CPS_001")).unwrap();
    let (cps, _) = mpm_shared::cps::Cps::read(&cps, "x").unwrap();
    let line = |k: &str| cps.get(k).unwrap().lines.join("|");
    assert_eq!(line("NUMBER_OF_LOADSTEPS"), "20");
    assert_eq!(line("SOLID_TRACTION"), "step  1.0  1.0");
    assert_eq!(line("GRAVITY_LOAD"), "off  0.0  1.0");
    // Anura3D needs g for the liquid's conductivity even when gravity is off.
    assert_eq!(line("GRAVITY_ACCELERATION"), "9.81");
    assert_eq!(line("HOMOGENEOUS_LOCAL_DAMPING"), "1 0.05");
    assert_eq!(line("STRAIN_SMOOTHING"), "1");
    let s = cps.settings().unwrap();
    assert!((s.time_per_load_step * 20.0 - sc.time.end_time).abs() < 1e-12 * sc.time.end_time);

    // A short undamped run: the GOM route computes the same problem.
    let s = scene(dir.path(), "oedometer.toml", "short", &|t| {
        short_oedometer(t, 0.01)
    });
    let (gom_path, cps_path) = export(&s, &dir.path().join("short"));
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    let (mut gc, _) = mpm_solve::input::anura3d::load(&gom_path, &cps_path).unwrap();
    assert_eq!(gc.body.materials, sc.body.materials);
    assert_eq!(
        gc.boundary.fixed[..sc.boundary.fixed.len()],
        sc.boundary.fixed[..]
    );
    assert_eq!(
        gc.boundary.liquid_fixed[..sc.boundary.fixed.len()],
        sc.boundary.liquid_fixed[..]
    );
    for (a, b) in gc.loads.traction.iter().zip(&sc.loads.traction) {
        for d in 0..3 {
            assert!((a[d] - b[d]).abs() <= 1e-15, "{a:?} {b:?}");
        }
    }
    assert!(gc.loads.traction[sc.loads.traction.len()..]
        .iter()
        .all(|t| *t == [0.0; 3]));
    // The GOM route follows Anura3D's rules (its step, strain smoothing, liquid mass, first
    // step; tests/oracle.rs compares it with Anura3D); with the scene's rules instead it
    // computes the scene's problem to rounding.
    assert!(gc.numerics.strain_smoothing && sc.numerics.smooth_pressure);
    gc.time.anura3d_time_step = false;
    gc.numerics.strain_smoothing = false;
    gc.numerics.smooth_pressure = true;
    gc.numerics.fixed_liquid_mass = false;
    gc.time.initial_step = None;
    gc.numerics.damping_rule = sc.numerics.damping_rule;
    gc.loads.liquid_load_on_mixture = sc.loads.liquid_load_on_mixture;
    check_runs(&sc, &gc, 1e-9);
}

/// A change to a scene's text.
type Edit = Box<dyn Fn(String) -> String>;

/// The short column scene edited by `edit`.
fn column(edit: impl Fn(String) -> String + 'static) -> Edit {
    Box::new(move |t| edit(short_column(t)))
}

/// A `[[traction]]` of 1 kPa down on the column's top, ramped over `ramp` seconds.
fn top_load(ramp: f64) -> String {
    format!("\n[[traction]]\nphysical = \"top\"\ntraction = [0.0, -1.0, 0.0]\nramp = {ramp}\n")
}

#[test]
fn what_anura3d_cannot_reproduce_is_refused_by_item() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "oedometer.toml",
            Box::new(|t| t),
            "consolidation.start: cannot be exported to Anura3D: \"undrained\"",
        ),
        (
            "column_gravity.toml",
            column(|t| t.replace("end = 0.02", "end = 0.025")),
            "time.output_interval",
        ),
        (
            "column_gravity.toml",
            column(|t| t.replace("[gravity]", "[gravity]\nramp = 0.01")),
            "gravity.ramp",
        ),
        (
            "column_gravity.toml",
            column(|t| format!("{t}{}", top_load(0.5))),
            "traction \"top\".ramp",
        ),
        (
            "column_gravity.toml",
            column(|t| t.replace("[time]", "[time]\nmax_steps = 10")),
            "time.max_steps",
        ),
        (
            "oedometer.toml",
            Box::new(|t| rest(t).replace("[time]", "[time]\nscheme = \"semi-implicit\"")),
            "time.scheme",
        ),
        (
            "column_gravity.toml",
            column(|t| t.replace("points_per_element = 4", "points_per_element = 2")),
            "material \"soil\".points_per_element",
        ),
        (
            "column_gravity.toml",
            column(|t| format!("probes = [1, 999999]\n{t}")),
            "probes",
        ),
        (
            "oedometer.toml",
            Box::new(|t| {
                rest(t).replace(
                    "viscosity = 1.0e-6               # kPa·s",
                    "viscosity = 1.0e-6\ninitial_pore_pressure = -5.0",
                )
            }),
            "material \"soil\".liquid.initial_pore_pressure",
        ),
    ];
    for (i, (name, edit, message)) in cases.iter().enumerate() {
        let s = scene(dir.path(), name, &format!("case{i}"), edit.as_ref());
        let out = dir.path().join(format!("out{i}"));
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&s)
            .arg("--export-anura3d")
            .arg(&out)
            .assert()
            .failure()
            .stderr(
                predicate::str::contains(*message).and(predicate::str::contains(
                    s.file_name().unwrap().to_string_lossy().as_ref(),
                )),
            );
        assert!(!out.exists(), "case {i} wrote something");
    }
    // A traction ramped over the whole run exports as Anura3D's linear multiplier.
    let s = scene(dir.path(), "column_gravity.toml", "ramped", &|t| {
        format!("{}{}", short_column(t), top_load(0.02))
    });
    let (gom, cps) = export(&s, &dir.path().join("ramped"));
    let cps = std::fs::read_to_string(cps).unwrap();
    assert!(
        cps.contains("$$SOLID_TRACTION\nlinear  0.0  1.0\n"),
        "{cps}"
    );
    let (gc, _) =
        mpm_solve::input::anura3d::load(&gom, &dir.path().join("ramped/ramped.CPS_001")).unwrap();
    assert_eq!(
        gc.loads.traction_curve,
        mpm_solve::input::scene::load(&s)
            .unwrap()
            .loads
            .traction_curve
    );
    // Only scenes export.
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&gom)
        .arg("--export-anura3d")
        .arg(dir.path().join("again"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("needs a TOML scene"));
}

/// Runs Anura3D on copies of `gom` and `cps` in `dir`; returns whether it finished (its last
/// line says so and the first load step's output exists) and what it printed.
fn run_anura3d(oracle: &Path, gom: &Path, cps: &Path, dir: &Path) -> (bool, String) {
    std::fs::create_dir_all(dir).unwrap();
    for f in [gom, cps] {
        std::fs::copy(f, dir.join(f.file_name().unwrap())).unwrap();
    }
    let stem = gom.file_stem().unwrap().to_string_lossy().to_string();
    let out = std::process::Command::new(oracle)
        .arg(&stem)
        .current_dir(dir)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let last = text
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("");
    let vtk = dir.join(format!("{stem}_MPScalar_001.vtk"));
    (
        last.trim() == "Calculation finished." && vtk.is_file(),
        text,
    )
}

/// The displacement at the end of the run of each output material point Anura3D followed
/// (`NAME.PAR_ID` files: a header naming the columns, then one row per time step).
fn anura3d_displacements(dir: &Path, stem: &str) -> Vec<(u32, [f64; 3])> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let Some(id) = name.strip_prefix(&format!("{stem}.PAR_")) else {
            continue;
        };
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header: Vec<&str> = lines.next().unwrap().split_whitespace().collect();
        let col = |k: &str| header.iter().position(|h| *h == k).unwrap();
        let last: Vec<&str> = lines.next_back().unwrap().split_whitespace().collect();
        // Fortran drops the E of three-digit exponents ("0.1234-100"): such values are 0 here.
        let num = |k: &str| last[col(k)].parse::<f64>().unwrap_or(0.0);
        assert_eq!(num("ID_MP") as u32, id.parse::<u32>().unwrap());
        out.push((id.parse().unwrap(), [num("Ux"), num("Uy"), num("Uz")]));
    }
    out.sort_by_key(|p| p.0);
    out
}

#[test]
fn anura3d_runs_the_exports() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_oracle(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(oracle) = found else {
        // Written past the test harness's capture, so that the skip shows in a plain run.
        let _ = writeln!(
            std::io::stderr(),
            "anura3d_runs_the_exports: skipped (set ANURA3D_ORACLE to an Anura3D binary to run the exports in Anura3D)"
        );
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let column = scene(dir.path(), "column_gravity.toml", "column", &short_column);
    let oedometer = scene(dir.path(), "oedometer.toml", "oedometer", &|t| {
        short_oedometer(t, 0.004)
    });
    // Tolerances on the end displacements, as a fraction of the largest: Anura3D prints four
    // digits; on the saturated case its STRAIN_SMOOTHING also smooths the solid's volumetric
    // strain, which mpm-solve does not.
    for (s, tol) in [(column, 1e-3), (oedometer, 0.03)] {
        let stem = s.file_stem().unwrap().to_string_lossy().to_string();
        let (gom, cps) = export(&s, &dir.path().join("a3d"));
        let work = dir.path().join(format!("run-{stem}"));
        let (ok, text) = run_anura3d(Path::new(&oracle), &gom, &cps, &work);
        let tail: String = text
            .chars()
            .skip(text.chars().count().saturating_sub(2000))
            .collect();
        assert!(ok, "Anura3D did not finish {}:\n{tail}", gom.display());
        let theirs = anura3d_displacements(&work, &stem);
        assert!(!theirs.is_empty());
        let (case, _) = mpm_solve::input::anura3d::load(&gom, &cps).unwrap();
        let ours = mpm_solve::driver::run::run::<f64, Tet4>(
            &case,
            &dir.path().join(&stem),
            &Default::default(),
        )
        .unwrap();
        let p = &ours.particles;
        let u = |id: u32| p.u[p.id.iter().position(|&i| i == id).unwrap()];
        let big = theirs
            .iter()
            .flat_map(|(id, _)| u(*id))
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = theirs
            .iter()
            .flat_map(|(id, a)| (0..3).map(move |d| (a[d] - u(*id)[d]).abs() / big))
            .fold(0.0f64, f64::max);
        eprintln!(
            "Anura3D finished {stem}: end displacements of points {:?} within {worst:.1e} of the largest ({big:.3e} m) from mpm-solve's",
            theirs.iter().map(|p| p.0).collect::<Vec<_>>()
        );
        assert!(big > 0.0 && worst <= tol, "{stem}: {worst}");
    }
}

#[test]
fn exported_gom_round_trips_through_the_writer() {
    // The files are written by the shared GOM writer: reading and writing again changes nothing.
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), "column_gravity.toml", "column", &short_column);
    let (gom, _) = export(&s, &dir.path().join("a3d"));
    let bytes = std::fs::read(&gom).unwrap();
    let model = mpm_shared::gom::read(&bytes, "x").unwrap();
    assert_eq!(mpm_shared::gom::write(&model), bytes);
    assert!(model
        .sections
        .iter()
        .all(|s| !matches!(s.body, Body::Opaque(_))));
}

#[test]
fn integration_and_objective_stress_of_a_scene_reach_the_case_and_the_export() {
    let dir = tempfile::tempdir().unwrap();
    let with = |t: String| {
        let t = short_column(t);
        t.replacen(
            "mesh = ",
            "integration = \"mixed\"\nobjective_stress = true\nstrain_smoothing = true\nmesh = ",
            1,
        )
    };
    let s = scene(dir.path(), "column_gravity.toml", "column", &with);
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    use mpm_solve::input::case::{Integration, MixedRule};
    assert_eq!(
        sc.numerics.integration,
        Integration::Mixed {
            filling: 0.9,
            rule: MixedRule::FullAtStart
        }
    );
    assert!(sc.numerics.objective_stress && sc.numerics.strain_smoothing);
    let (gom_path, cps_path) = export(&s, &dir.path().join("a3d"));
    let cps = std::fs::read(&cps_path).unwrap();
    let (cps, _) = mpm_shared::cps::Cps::read(&cps, "x").unwrap();
    let line = |k: &str| cps.get(k).unwrap().lines.join("|");
    assert_eq!(line("COMPUTATION_METHOD"), "MPM-MIXED");
    assert_eq!(line("APPLY_OBJECTIVE_STRESS"), "1");
    assert_eq!(line("DEGREE_OF_FILLING"), "0.9");
    assert_eq!(line("STRAIN_SMOOTHING"), "1");
    // The GOM route reads them back the same.
    let (gc, _) = mpm_solve::input::anura3d::load(&gom_path, &cps_path).unwrap();
    // Anura3D's reading of MPM-MIXED on GOM input (docs/design.md §4.9); in this full column,
    // whose points stay in their elements, both readings compute the same.
    assert_eq!(
        gc.numerics.integration,
        Integration::Mixed {
            filling: 0.9,
            rule: MixedRule::Anura3d
        }
    );
    assert_eq!(gc.numerics.objective_stress, sc.numerics.objective_stress);
    assert_eq!(gc.numerics.strain_smoothing, sc.numerics.strain_smoothing);
    check_runs(&sc, &gc, 1e-9);

    let bad = scene(dir.path(), "column_gravity.toml", "bad", &|t| {
        t.replacen("mesh = ", "integration = \"gauss\"\nmesh = ", 1)
    });
    let e = mpm_solve::input::scene::load(&bad).unwrap_err().to_string();
    assert!(
        e.contains("bad.toml") && e.contains("integration") && e.contains("\"gauss\""),
        "{e}"
    );
}

/// `[[velocity]]` entries export to Anura3D's prescribed-velocity sections under one
/// multiplier: a rough platen on the top nodes (with the new mid-edge nodes between them)
/// ramped over the run runs the same from the GOM; a volume's points go to the material-point
/// section; entries Anura3D's one multiplier cannot express are refused by name.
#[test]
fn prescribed_velocities_export_and_run_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let platen = "\n[[velocity]]\nphysical = \"top\"\nvelocity = [0.0, -0.05, 0.0]\nramp = 0.02\n";
    let s = scene(dir.path(), "column_gravity.toml", "platen", &|t| {
        format!("{}{platen}", short_column(t))
    });
    let (gom_path, cps_path) = export(&s, &dir.path().join("platen"));
    let cps = std::fs::read_to_string(&cps_path).unwrap();
    assert!(
        cps.contains("$$PRESCRIBED_VELOCITY\nlinear  0.0  1.0\n"),
        "{cps}"
    );
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    let (gc, _) = mpm_solve::input::anura3d::load(&gom_path, &cps_path).unwrap();
    let (a, b) = (
        &sc.boundary.nodal_velocity[0],
        &gc.boundary.nodal_velocity[0],
    );
    // The top's 4-node corners, then the mid-edge nodes the export adds between them.
    let gom = mpm_shared::read_gom_file(&gom_path).unwrap();
    let rows = rows(&gom, "PRESCRIBED_NODAL_VELOCITY_SURFACE");
    assert!(rows.len() > a.rows.len());
    assert_eq!(b.rows[..a.rows.len()], a.rows[..]);
    for r in &b.rows[a.rows.len()..] {
        assert!(r.node as usize >= sc.model.node_count());
        assert_eq!(gom.node(r.node as usize)[1], 1.0);
    }
    assert_eq!(gc.reactions()[0].curve, sc.reactions()[0].curve);
    // Anura3D's reaction output: the set's faces, each once (corners, then mid-edge nodes),
    // in an element that has them; their nodes are the set's nodes.
    let set: std::collections::BTreeSet<i64> = rows.iter().map(|r| int(&r[0])).collect();
    let faces: Vec<&[Token]> = gom
        .table("START_OUTPUT_REACTION_FORCES")
        .unwrap()
        .rows()
        .collect();
    let mut seen = std::collections::BTreeSet::new();
    let mut covered = std::collections::BTreeSet::new();
    for f in &faces {
        assert_eq!(f[0], Token::Text("\"top\"".into()));
        let nodes: Vec<i64> = f[2..8].iter().map(int).collect();
        let element = gom.element(int(&f[1]) as usize - 1);
        assert!(nodes[..3]
            .iter()
            .all(|&n| element[..4].contains(&(n as u32 - 1))));
        for (k, (a, b)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
            let (p, q, m) = (
                gom.node(nodes[a] as usize - 1),
                gom.node(nodes[b] as usize - 1),
                gom.node(nodes[3 + k] as usize - 1),
            );
            assert!((0..3).all(|d| (m[d] - 0.5 * (p[d] + q[d])).abs() < 1e-12));
        }
        let mut key = nodes[..3].to_vec();
        key.sort_unstable();
        assert!(seen.insert(key), "face {nodes:?} twice");
        covered.extend(nodes);
    }
    assert_eq!(covered, set);
    check_runs(&sc, &gc, 1e-9);

    // A physical volume: every element's row in the material-point section.
    let s = scene(dir.path(), "column_gravity.toml", "block", &|t| {
        format!(
            "{}\n[[velocity]]\nphysical = \"soil\"\nvelocity = [0.0, 0.0, 0.1]\ncomponents = [false, false, true]\n",
            short_column(t)
        )
    });
    let (gom_path, cps_path) = export(&s, &dir.path().join("block"));
    let (gc, _) = mpm_solve::input::anura3d::load(&gom_path, &cps_path).unwrap();
    let sc = mpm_solve::input::scene::load(&s).unwrap();
    let (a, b) = (
        sc.boundary.prescribed.unwrap(),
        gc.boundary.prescribed.unwrap(),
    );
    assert_eq!(a.rows, b.rows);
    assert_eq!(a.rows.len(), sc.model.element_count());
    assert!(std::fs::read_to_string(&cps_path)
        .unwrap()
        .contains("$$PRESCRIBED_VELOCITY\nstep  1.0  1.0\n"));

    // Two ramps, or a ramp shorter than the run: refused, naming the entry.
    for (k, (extra, item)) in [
        (
            format!("{platen}[[velocity]]\nplane = \"y = 0.5\"\nvelocity = [0.0, -0.05, 0.0]\nname = \"mid\"\n"),
            "velocity \"mid\".ramp",
        ),
        (platen.replace("ramp = 0.02", "ramp = 0.01"), "velocity \"top\".ramp"),
    ]
    .into_iter()
    .enumerate()
    {
        let s = scene(dir.path(), "column_gravity.toml", &format!("bad{k}"), &|t| {
            format!("{}{extra}", short_column(t))
        });
        Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&s)
            .arg("--export-anura3d")
            .arg(dir.path().join(format!("bad{k}")))
            .assert()
            .failure()
            .stderr(predicate::str::contains(item));
    }
}

/// `pressure = p` on a flat face is the traction -p n: the oedometer's top load given as a
/// pressure resolves to the same nodal forces and exports as the same Anura3D face loads (to
/// round-off); giving both (or neither) is refused by name.
#[test]
fn a_pressure_loads_as_the_traction_along_the_inward_normal() {
    let dir = tempfile::tempdir().unwrap();
    let load = "traction = [0.0, -10.0, 0.0]     # kPa, sudden";
    let short = |t: String| short_oedometer(rest(t), 0.01);
    let a = scene(dir.path(), "oedometer.toml", "vector", &short);
    let b = scene(dir.path(), "oedometer.toml", "pressure", &|t| {
        short(t).replace(load, "pressure = 10.0")
    });
    let (ca, cb) = (
        mpm_solve::input::scene::load(&a).unwrap(),
        mpm_solve::input::scene::load(&b).unwrap(),
    );
    assert!(ca.loads.traction.iter().any(|f| f[1] != 0.0));
    // The same to round-off (the unit normal is the cross product times 1 / its length).
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-14 * x.abs().max(y.abs()).max(1e-300);
    assert_eq!(ca.loads.traction.len(), cb.loads.traction.len());
    for (fa, fb) in ca.loads.traction.iter().zip(&cb.loads.traction) {
        assert!((0..3).all(|d| close(fa[d], fb[d])), "{fa:?} {fb:?}");
    }
    let (ga, _) = export(&a, &dir.path().join("a"));
    let (gb, _) = export(&b, &dir.path().join("b"));
    let table = |g: &Path| {
        mpm_shared::read_gom_file(g)
            .unwrap()
            .table("START_LOAD_ON_NODES_SOLID")
            .unwrap()
            .rows()
            .map(|r| r.to_vec())
            .collect::<Vec<_>>()
    };
    let (ta, tb) = (table(&ga), table(&gb));
    assert_eq!(ta.len(), tb.len());
    for (ra, rb) in ta.iter().zip(&tb) {
        assert_eq!(ra[..6], rb[..6]);
        for (x, y) in ra[6..].iter().zip(&rb[6..]) {
            assert!(
                close(x.as_f64().unwrap(), y.as_f64().unwrap()),
                "{ra:?} {rb:?}"
            );
        }
    }
    for (name, text) in [
        ("both", load.replace("# kPa, sudden", "\npressure = 10.0")),
        ("neither", String::new()),
    ] {
        let s = scene(dir.path(), "oedometer.toml", name, &|t| {
            short(t).replace(load, &text)
        });
        let err = mpm_solve::input::scene::load(&s).unwrap_err().to_string();
        assert!(
            err.contains("traction \"top\"") && err.contains("give one of traction"),
            "{name}: {err}"
        );
    }
}
