//! Validation against analytical solutions (docs/design.md §6). Run in release mode: each takes seconds.

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_solve::driver::engine::Engine;
use mpm_solve::input::scene;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

#[test]
fn column_under_self_weight_matches_rho_g_depth() {
    let dir = tempfile::tempdir().unwrap();
    let case = scene::load(&testdata("column_gravity.toml")).unwrap();
    assert!(case.model.element_count() >= 1000);
    let engine =
        mpm_solve::driver::run::run::<f64, Tet4>(&case, dir.path(), &Default::default()).unwrap();
    let p = &engine.particles;
    let rho_g = 2.0 * 9.81;
    let (mut num, mut den, mut count) = (0.0, 0.0, 0);
    for i in 0..p.len() {
        let y = p.x[i][1];
        if (y - 0.5).abs() < 0.05 {
            num += p.stress[i][1];
            den += -rho_g * (1.0 - (y - p.u[i][1]));
            count += 1;
        }
    }
    let ratio = num / den;
    eprintln!("self weight: {count} points at mid-depth, sigma_yy / rho g (H - y) = {ratio:.5}");
    assert!(count > 100);
    assert!((ratio - 1.0).abs() < 0.02, "ratio {ratio}");
    // At rest: kinetic energy negligible against the work done.
    assert!(engine.kinetic_energy() < 1e-6 * engine.external_work);
}

/// A laterally confined column 0.1 x 1.0 x 0.1 m of structured tetrahedra with `ny` cells over
/// the height, bottom fixed, and a sudden 10 kPa load on the top.
fn loaded_column(ny: usize) -> mpm_solve::input::case::Case {
    use mpm_shared::{generate, ElementType};
    use mpm_solve::input::case::{Case, MaterialSpec};
    let model = generate::box_mesh([ny / 10, ny, ny / 10], [0.1, 1.0, 0.1], ElementType::Tet4);
    let n = model.node_count();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let fixed = mpm_solve::input::case::confined_box(&model);
    let mut top = Vec::new();
    for e in 0..model.element_count() {
        let el = model.element(e);
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let face = f.map(|k| el[k]);
            if face.iter().all(|&v| near(model.node(v as usize)[1], 1.0)) {
                top.push(face.to_vec());
            }
        }
    }
    let mut traction = vec![[0.0; 3]; n];
    scene::add_face_loads(
        &model,
        &top,
        &vec![[0.0, -10.0, 0.0]; top.len()],
        &mut traction,
    );
    let total: f64 = traction.iter().map(|t| t[1]).sum();
    assert!((total + 10.0 * 0.01).abs() < 1e-9, "top load {total}");
    let soil = MaterialSpec::new("soil", 2000.0, 10000.0, 0.3).unwrap();
    let mut case = Case::single_material("wave", model, soil, 4, fixed);
    case.loads.traction = traction;
    case.time.end_time = 0.02;
    case.time.output_times = vec![0.02];
    case
}

#[test]
fn compression_wave_arrives_at_mid_height_on_time() {
    let case = loaded_column(80);
    let mut engine = Engine::<f64, Tet4>::new(&case, false).unwrap();
    let c = case.body.materials[1].as_ref().unwrap().wave_speed();
    let expected = 0.5 / c;
    // Points in a slab at mid-height; arrival = first time their mean sigma_yy reaches half the load.
    let slab: Vec<usize> = (0..engine.particles.len())
        .filter(|&i| (engine.particles.x[i][1] - 0.5).abs() < 0.00625)
        .collect();
    assert!(slab.len() > 20);
    let mut arrival = None;
    let mut prev = (0.0, 0.0);
    while engine.time < 2.0 * expected {
        engine.step(engine.dt, None).unwrap();
        let s: f64 = slab
            .iter()
            .map(|&i| engine.particles.stress[i][1])
            .sum::<f64>()
            / slab.len() as f64;
        if s <= -5.0 {
            // Interpolate the crossing within the step.
            let (t0, s0) = prev;
            arrival = Some(t0 + (engine.time - t0) * (-5.0 - s0) / (s - s0));
            break;
        }
        prev = (engine.time, s);
    }
    let arrival = arrival.expect("the wave never arrived");
    let err = (arrival - expected) / expected;
    eprintln!(
        "wave: arrival {arrival:.6} s, (H/2)/c = {expected:.6} s, error {:.2}%",
        100.0 * err
    );
    assert!(err.abs() < 0.03, "arrival error {:.2}%", 100.0 * err);
}

/// Writes a GOM + CPS oedometer (structured column, lateral rollers, fixed base, a nodal face
/// load q on the top) and returns the GOM path.
fn write_oedometer_case(dir: &Path, q: f64, method: &str) -> PathBuf {
    use mpm_shared::model::{Body, Refs, Section, Table, Token};
    use mpm_shared::{generate, ElementType};
    let mut model = generate::box_mesh([2, 20, 2], [0.1, 1.0, 0.1], ElementType::Tet4);
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let mut fix = Table::new();
    for (i, f) in mpm_solve::input::case::confined_box(&model)
        .into_iter()
        .enumerate()
    {
        if f.iter().any(|&b| b) {
            fix.push_row(
                [Token::Int(i as i64 + 1)]
                    .into_iter()
                    .chain(f.map(|b| Token::Int(b as i64))),
            );
        }
    }
    let mut load = Table::new();
    for e in 0..model.element_count() {
        let el = model.element(e).to_vec();
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            if f.iter().all(|&k| near(model.node(el[k] as usize)[1], 1.0)) {
                let ids = f.map(|k| Token::Int(el[k] as i64 + 1));
                let t = (0..3).flat_map(|_| [Token::Real(0.0), Token::Real(-q), Token::Real(0.0)]);
                load.push_row(ids.into_iter().chain(t));
            }
        }
    }
    for s in model.sections.iter_mut() {
        if s.keyword == "START_FIXITY_SURFACE_SOLID" {
            s.body = Body::Table {
                counted: true,
                refs: Refs::Nodes(1),
                rows: fix.clone(),
            };
        }
    }
    let at = model
        .sections
        .iter()
        .position(|s| s.keyword == "NUMBER_OF_MATERIALS")
        .unwrap();
    model.sections.insert(
        at,
        Section {
            keyword: "START_LOAD_ON_NODES_SOLID".into(),
            body: Body::Table {
                counted: true,
                refs: Refs::Nodes(3),
                rows: load,
            },
        },
    );
    let at = model
        .sections
        .iter()
        .position(|s| s.keyword == "MATERIAL_NAME")
        .unwrap()
        + 1;
    for (k, v) in [
        ("MATERIAL_TYPE", "dry_material"),
        ("POROSITY_SOLID", "0.0"),
        ("DENSITY_SOLID", "2000"),
        ("K0_VALUE_SOLID", "0.5"),
        ("MATERIAL_MODEL_SOLID", "linear_elasticity"),
        ("YOUNG_MODULUS", "1000"),
        ("POISSON_RATIO", "0.3"),
    ]
    .iter()
    .rev()
    {
        model.sections.insert(
            at,
            Section {
                keyword: k.to_string(),
                body: Body::Text(vec![v.to_string()]),
            },
        );
    }
    let gom = dir.join("oedo.GOM");
    mpm_shared::write_gom_file(&model, &gom).unwrap();
    let cps = format!(
        "### Anura3D_2021 ###\n$$NUMBER_OF_LOADSTEPS\n4\n$$TIME_PER_LOADSTEP\n0.5\n$$COURANT_NUMBER\n0.9\n$$COMPUTATION_METHOD\n{method}\n$$GRAVITY_LOAD\noff 0.0 1.0\n$$SOLID_TRACTION\nstep 0.0 1.0\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n1\n$$OUTPUT_MATERIAL_POINTS\n1\n$$END\n"
    );
    std::fs::write(dir.join("oedo.CPS_001"), cps).unwrap();
    gom
}

#[test]
fn anura3d_oedometer_settles_by_q_h_over_e_oed() {
    let dir = tempfile::tempdir().unwrap();
    // A load small enough that no material point crosses into another element: crossings make
    // MPM-MP stresses uneven near the top (that is what MPM-MIXED integration is for).
    let q = 5.0;
    let gom = write_oedometer_case(dir.path(), q, "MPM-MP");
    let (case, _) =
        mpm_solve::input::anura3d::load(&gom, &dir.path().join("oedo.CPS_001")).unwrap();
    let engine = mpm_solve::driver::run::run::<f64, Tet4>(
        &case,
        &dir.path().join("out"),
        &Default::default(),
    )
    .unwrap();
    let eoed = mpm_solve::material::linear_elastic::LinearElastic::<f64>::oedometric(1000.0, 0.3);
    let p = &engine.particles;
    // Uniform strain -q/E_oed: every point's vertical displacement is -q y0 / E_oed.
    let mut worst: f64 = 0.0;
    let (mut worst_s, mut mean_s) = (0.0f64, 0.0);
    for i in 0..p.len() {
        let y0 = p.x[i][1] - p.u[i][1];
        let want = -q * y0 / eoed;
        worst = worst.max((p.u[i][1] - want).abs() / (q / eoed));
        worst_s = worst_s.max((p.stress[i][1] + q).abs() / q);
        mean_s += p.stress[i][1] / p.len() as f64;
    }
    eprintln!(
        "oedometer: mean sigma_yy {mean_s:.5}, worst {:.3}% off q; kinetic {:e}",
        100.0 * worst_s,
        engine.kinetic_energy()
    );
    eprintln!(
        "oedometer: worst displacement error {:.3}% of q H / E_oed",
        100.0 * worst
    );
    assert!(worst < 0.01, "displacement error {worst}");
    // The particle volume shrinks by the strain while the grid stays, so the stress that
    // balances the load grows by about the strain (0.37 %).
    assert!(worst_s < 0.01, "stress error {worst_s}");
    // Four load steps, four particle files.
    assert!(dir.path().join("out/particles_00003.vtu").exists());
}

#[test]
fn unsupported_anura3d_features_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let gom = write_oedometer_case(dir.path(), 10.0, "UL-FEM");
    let err = mpm_solve::input::anura3d::load(&gom, &dir.path().join("oedo.CPS_001"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("$$COMPUTATION_METHOD") && err.contains("UL-FEM"),
        "{err}"
    );
}

#[test]
fn single_precision_runs_the_same_code_and_agrees() {
    let case = loaded_column(20);
    let mut a = Engine::<f64, Tet4>::new(&case, false).unwrap();
    let mut b = Engine::<f32, Tet4>::new(&case, false).unwrap();
    for _ in 0..200 {
        a.step(a.dt, None).unwrap();
        b.step(a.dt, None).unwrap();
    }
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..a.particles.len() {
        for c in 0..6 {
            num = num.max((a.particles.stress[i][c] - b.particles.stress[i][c] as f64).abs());
            den = den.max(a.particles.stress[i][c].abs());
        }
    }
    eprintln!("f32 vs f64: largest stress difference {num:e} of {den:e}");
    assert!(num < 1e-3 * den);
}

#[test]
fn mixed_integration_settles_like_material_points_with_one_stress_per_element() {
    let dir = tempfile::tempdir().unwrap();
    let q = 5.0;
    let gom = write_oedometer_case(dir.path(), q, "MPM-MIXED");
    let (case, _) =
        mpm_solve::input::anura3d::load(&gom, &dir.path().join("oedo.CPS_001")).unwrap();
    let engine = mpm_solve::driver::run::run::<f64, Tet4>(
        &case,
        &dir.path().join("out"),
        &Default::default(),
    )
    .unwrap();
    let p = &engine.particles;
    let mut by_element: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for i in 0..p.len() {
        by_element.entry(p.element[i]).or_default().push(i);
        assert!((p.stress[i][1] + q).abs() / q < 0.01, "point {i}");
    }
    // Points that stayed in a full element carry its Gauss-point stress.
    let mut shared = 0;
    for pts in by_element.values().filter(|v| v.len() == 4) {
        for &i in pts {
            for c in 0..6 {
                assert!((p.stress[i][c] - p.stress[pts[0]][c]).abs() <= 1e-12 * q);
            }
        }
        shared += 1;
    }
    assert!(shared > 0);
}
