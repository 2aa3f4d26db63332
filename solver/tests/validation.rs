//! Validation against analytical solutions (DESIGN §6). Run in release mode: each takes seconds.

use std::path::{Path, PathBuf};

use mpm_solve::engine::Engine;
use mpm_solve::scene;

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
    let engine = mpm_solve::run::run::<f64>(&case, dir.path(), false, false).unwrap();
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
fn loaded_column(ny: usize) -> mpm_solve::case::Case {
    use mpm_shared::{generate, ElementType};
    use mpm_solve::case::{Case, LoadCurve, MaterialSpec};
    let model = generate::box_mesh([ny / 10, ny, ny / 10], [0.1, 1.0, 0.1], ElementType::Tet4);
    let n = model.node_count();
    let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let mut fixed = vec![[false; 3]; n];
    for (i, f) in fixed.iter_mut().enumerate() {
        let p = model.node(i);
        if near(p[1], 0.0) {
            *f = [true; 3];
        }
        f[0] |= near(p[0], 0.0) || near(p[0], 0.1);
        f[2] |= near(p[2], 0.0) || near(p[2], 0.1);
    }
    let mut top = Vec::new();
    for e in 0..model.element_count() {
        let el = model.element(e);
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let face = f.map(|k| el[k]);
            if face.iter().all(|&v| near(model.node(v as usize)[1], 1.0)) {
                top.push(face);
            }
        }
    }
    let mut traction = vec![[0.0; 3]; n];
    scene::add_face_loads(&model, &top, [0.0, -10.0, 0.0], &mut traction);
    let total: f64 = traction.iter().map(|t| t[1]).sum();
    assert!((total + 10.0 * 0.01).abs() < 1e-9, "top load {total}");
    let n_el = model.element_count();
    Case {
        name: "wave".into(),
        inputs: vec![],
        model,
        materials: vec![
            None,
            Some(MaterialSpec::new("soil", 2000.0, 10000.0, 0.3).unwrap()),
        ],
        element_material: vec![1; n_el],
        points_per_element: vec![4; n_el],
        fixed,
        traction,
        traction_curve: LoadCurve::Step,
        gravity: [0.0; 3],
        gravity_curve: LoadCurve::Step,
        courant: 0.9,
        damping: 0.0,
        end_time: 0.02,
        output_times: vec![0.02],
        max_steps: None,
        probes: vec![],
    }
}

#[test]
fn compression_wave_arrives_at_mid_height_on_time() {
    let case = loaded_column(80);
    let mut engine = Engine::<f64>::new(&case, false).unwrap();
    let c = case.materials[1].as_ref().unwrap().wave_speed();
    let expected = 0.5 / c;
    // Points in a slab at mid-height; arrival = first time their mean sigma_yy reaches half the load.
    let slab: Vec<usize> = (0..engine.particles.len())
        .filter(|&i| (engine.particles.x[i][1] - 0.5).abs() < 0.00625)
        .collect();
    assert!(slab.len() > 20);
    let mut arrival = None;
    let mut prev = (0.0, 0.0);
    while engine.time < 2.0 * expected {
        engine.step(&case, engine.dt, None).unwrap();
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
