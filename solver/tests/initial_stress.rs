//! Initial stresses: the K0 procedure and uniform stresses from scenes and GOM/CPS input. A K0
//! column under gravity starts in equilibrium; a uniform stress held by equal tractions stays
//! at rest; a released one keeps the energy balance (the guard rails count the initial stress's
//! work); the scene keys and the GOM/CPS keys are read, or refused naming the item.

mod common;

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use common::testdata;
use mpm_solve::driver::engine::Engine;
use mpm_solve::driver::run::{run, RunOptions};
use mpm_solve::input::case::Case;

/// The coarse gravity column (`column_tet4.msh`, 0.1 x 1 x 0.1 m, laterally confined), 20 ms,
/// undamped, with `material` lines added to its material, as `dir/NAME.toml`.
fn column(dir: &Path, name: &str, material: &str) -> PathBuf {
    let text = common::scene(dir, &|t| {
        t.replace("local = 0.75", "local = 0.0").replace(
            "points_per_element = 4",
            &format!("points_per_element = 4\n{material}"),
        )
    });
    let p = dir.join(format!("{name}.toml"));
    std::fs::rename(text, &p).unwrap();
    p
}

/// The unit cube (`cube_tet4.msh`) with rollers on x = 0, y = 0 and z = 0, no gravity, 0.1 s in
/// one output, its material `soil` carrying `material` lines, and `rest` appended.
fn cube(dir: &Path, name: &str, material: &str, rest: &str) -> PathBuf {
    let text = format!(
        "mesh = {:?}\n[time]\nend = 0.1\ncourant = 0.5\noutput_interval = 0.1\n\
         [[material]]\nphysical = \"soil\"\ndensity = 2000.0\nyoung = 10000.0\npoisson = 0.3\n{material}\n\
         [[fixity]]\nplane = \"x = 0\"\nfixed = [true, false, false]\n\
         [[fixity]]\nplane = \"y = 0\"\nfixed = [false, true, false]\n\
         [[fixity]]\nplane = \"z = 0\"\nfixed = [false, false, true]\n{rest}",
        testdata("cube_tet4.msh").display().to_string()
    );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

fn load(scene: &Path) -> Case {
    mpm_solve::input::scene::load(scene).unwrap_or_else(|e| panic!("{e}"))
}

fn scene_error(scene: &Path) -> String {
    match mpm_solve::input::scene::load(scene) {
        Ok(_) => panic!("{} was accepted", scene.display()),
        Err(e) => e.to_string(),
    }
}

/// Runs `case` to its end (guard rails on, their defaults) into a temporary folder.
fn run_to_end(case: &Case) -> Engine<f64> {
    let out = tempfile::tempdir().unwrap();
    run::<f64, Tet4>(case, out.path(), &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn largest_displacement(e: &Engine<f64>) -> f64 {
    e.particles
        .u
        .iter()
        .flatten()
        .fold(0.0, |a: f64, v| a.max(v.abs()))
}

#[test]
fn a_k0_column_under_gravity_starts_in_equilibrium() {
    let dir = tempfile::tempdir().unwrap();
    // K0 = ν / (1 - ν): the laterally confined elastic column's own ratio.
    let k0 = 0.3 / 0.7;
    let stressed = load(&column(dir.path(), "k0", &format!("k0 = {k0}")));
    let free = load(&column(dir.path(), "free", ""));
    // The initial state: σ'yy = -ρ g d at the element's centroid, σ'xx = σ'zz = K0 σ'yy.
    let e0 = Engine::<f64, Tet4>::new(&stressed, false).unwrap();
    let (mut deepest, mut checked) = (0.0f64, 0);
    for s in &e0.particles.stress {
        assert!(s[1] < 0.0 && s[1] >= -2.0 * 9.81 * 1.0, "{s:?}");
        assert!((s[0] - k0 * s[1]).abs() <= 1e-12 * s[1].abs(), "{s:?}");
        assert_eq!(s[0], s[2]);
        assert_eq!(&s[3..], &[0.0; 3]);
        deepest = deepest.min(s[1]);
        checked += 1;
    }
    assert!(checked > 0 && deepest < -15.0, "deepest σ'yy {deepest}");
    let (a, b) = (run_to_end(&stressed), run_to_end(&free));
    assert!(a.steps > 100, "the energy checks start after step 100");
    let (ua, ub) = (largest_displacement(&a), largest_displacement(&b));
    eprintln!("largest |u| after 20 ms: {ua:.3e} m from K0 stresses, {ub:.3e} m stress-free");
    assert!(ub > 1e-4, "the stress-free column settles ({ub})");
    assert!(ua < 1e-3 * ub, "K0 column moved {ua} m, stress-free {ub} m");
    // The guard rails measure the balance against the energy the K0 stresses hold, not
    // against round-off work terms (which tripped the check at step 192 before).
    eprintln!("energy balance error: {:.3e}", a.balance_error());
    assert!(a.balance_error() < 1e-6, "{}", a.balance_error());
}

#[test]
fn a_uniform_stress_held_by_equal_tractions_stays_at_rest() {
    let dir = tempfile::tempdir().unwrap();
    let confine = "[[traction]]\nphysical = \"x1\"\ntraction = [-100.0, 0.0, 0.0]\n\
                   [[traction]]\nphysical = \"top\"\ntraction = [0.0, -100.0, 0.0]\n\
                   [[traction]]\nphysical = \"z1\"\ntraction = [0.0, 0.0, -100.0]\n";
    let stress = "initial_stress = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0]";
    let held = load(&cube(dir.path(), "held", stress, confine));
    let e = run_to_end(&held);
    assert!(e.steps > 100, "{} steps", e.steps);
    let u = largest_displacement(&e);
    // The same tractions on an unstressed cube move it by millimetres.
    let loaded = run_to_end(&load(&cube(dir.path(), "loaded", "", confine)));
    let u_loaded = largest_displacement(&loaded);
    eprintln!("largest |u|: {u:.3e} m held by its stress, {u_loaded:.3e} m unstressed");
    assert!(
        u_loaded > 1e-3 && u < 1e-9 * u_loaded,
        "{u} against {u_loaded}"
    );
    for s in &e.particles.stress {
        assert!(
            (s[0] + 100.0).abs() < 1e-6 && (s[1] + 100.0).abs() < 1e-6,
            "{s:?}"
        );
    }
}

#[test]
fn a_released_initial_stress_keeps_the_energy_balance() {
    // Compressed by 100 kPa and released on three faces: it springs out, the kinetic energy
    // coming from the initial stress (the strain energy goes negative). The guards must see
    // a balanced run, not a blow-up or an energy-balance failure.
    let dir = tempfile::tempdir().unwrap();
    let case = load(&cube(
        dir.path(),
        "released",
        "initial_stress = [-100.0, -100.0, -100.0, 0.0, 0.0, 0.0]",
        "",
    ));
    let e = run_to_end(&case);
    assert!(e.steps > 100, "{} steps", e.steps);
    assert!(e.step_kinetic > 0.0 && e.strain_energy < 0.0);
    eprintln!(
        "kinetic {:.3e} kJ, strain {:.3e} kJ, balance error {:.2e}",
        e.step_kinetic,
        e.strain_energy,
        e.balance_error()
    );
    assert!(
        e.balance_error() < 0.02,
        "balance error {}",
        e.balance_error()
    );
}

#[test]
fn scene_keys_are_read_and_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The ground defaults to the highest node; gravity.k0_surface moves it.
    let top = load(&column(d, "top", "k0 = 0.5"));
    let init = top.start.initial_stress.as_ref().unwrap();
    assert_eq!(init.k0.as_ref().unwrap().surface_point, [0.0, 1.0]);
    let lower = column(d, "lower", "k0 = 0.5");
    let text = std::fs::read_to_string(&lower)
        .unwrap()
        .replace("[gravity]\n", "[gravity]\nk0_surface = 0.5\n");
    std::fs::write(&lower, text).unwrap();
    let e = Engine::<f64, Tet4>::new(&load(&lower), false).unwrap();
    // Points above y = 0.5 start unstressed, those below carry the weight of depth - 0.5.
    for (x, s) in e.particles.x.iter().zip(&e.particles.stress) {
        let y = e.mesh.global(x)[1];
        if y > 0.55 {
            assert_eq!(s[1], 0.0);
        } else if y < 0.45 {
            assert!(s[1] < 0.0);
        }
    }
    let uniform = load(&column(d, "uniform", "initial_stress = [1, 2, 3, 4, 5, 6]"));
    let e = Engine::<f64, Tet4>::new(&uniform, false).unwrap();
    assert!(e
        .particles
        .stress
        .iter()
        .all(|s| *s == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
    for (material, gravity_edit, expected) in [
        (
            "k0 = 0.5\ninitial_stress = [0, 0, 0, 0, 0, 0]",
            None,
            "material \"soil\": give k0 or initial_stress, not both",
        ),
        (
            "k0 = -0.1",
            None,
            "material \"soil\".k0: must be finite and at least 0",
        ),
        (
            "k0 = 0.5",
            Some(("vector = [0.0, -9.81, 0.0]", "vector = [0.0, 0.0, -9.81]")),
            "material \"soil\".k0: the K0 procedure needs gravity along -y",
        ),
        (
            "k0 = 0.5",
            Some((
                "vector = [0.0, -9.81, 0.0]",
                "vector = [0.0, -9.81, 0.0]\nramp = 0.01",
            )),
            "gravity.ramp: the K0 stresses carry the full weight from the start",
        ),
        (
            "k0 = 0.5\n[material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.15e4\n\
             intrinsic_permeability = 1e-10\nviscosity = 1e-6\ninitial_pore_pressure = -5.0",
            None,
            "material \"soil\".k0: the K0 procedure sets the pore pressure",
        ),
        (
            "initial_stress = [0, 0, 0, 0, 0, nan]",
            None,
            "material \"soil\".initial_stress: must be finite",
        ),
    ] {
        let p = column(d, "bad", material);
        if let Some((a, b)) = gravity_edit {
            let t = std::fs::read_to_string(&p).unwrap().replace(a, b);
            std::fs::write(&p, t).unwrap();
        }
        let e = scene_error(&p);
        assert!(e.contains(expected), "{material}: {e}");
    }
    // A ground surface without k0 is a mistake.
    let p = column(d, "surface", "");
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace("[gravity]\n", "[gravity]\nk0_surface = 0.5\n");
    std::fs::write(&p, text).unwrap();
    let e = scene_error(&p);
    assert!(e.contains("gravity.k0_surface: no material has k0"), "{e}");
    // The undrained start of a consolidation run sets the stresses itself.
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace(
            "oedometer_tet4.msh",
            &testdata("oedometer_tet4.msh").display().to_string(),
        )
        .replace("poisson = 0.3", "poisson = 0.3\nk0 = 0.5");
    assert!(text.contains("k0 = 0.5") && text.contains("start = \"undrained\""));
    let p = d.join("undrained.toml");
    std::fs::write(&p, text).unwrap();
    let e = scene_error(&p);
    assert!(e.contains("consolidation.start = \"undrained\""), "{e}");
}

#[test]
fn the_exporter_writes_k0_and_refuses_what_anura3d_cannot_start_from() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files =
        mpm_solve::input::export_anura3d::export_scene(&testdata("layered_k0.toml"), &d.join("a"))
            .unwrap();
    let cps = std::fs::read_to_string(&files.cps).unwrap();
    assert!(
        cps.contains("$$K0_PROCEDURE\n1\n$$SURFACE_ELEVATION\n1.0\n"),
        "{cps}"
    );
    let gom = std::fs::read_to_string(&files.gom).unwrap();
    assert!(gom.contains("$$K0_VALUE_SOLID\n0.6\n") && gom.contains("$$K0_VALUE_SOLID\n0.4\n"));
    // Read back, the GOM/CPS starts from the scene's stresses exactly.
    let (back, _) = mpm_solve::input::anura3d::load(&files.gom, &files.cps).unwrap();
    let scene = load(&testdata("layered_k0.toml"));
    let a = Engine::<f64, Tet4>::new(&back, false).unwrap();
    let b = Engine::<f64, Tet4>::new(&scene, false).unwrap();
    assert_eq!(a.particles.id, b.particles.id);
    assert_eq!(a.particles.stress, b.particles.stress);
    let refused = |name: &str, material: &str, expected: &str| {
        let p = column(d, name, material);
        let e = mpm_solve::input::export_anura3d::export_scene(&p, &d.join(name))
            .expect_err(name)
            .to_string();
        assert!(e.contains(expected), "{e}");
    };
    refused(
        "uniform",
        "initial_stress = [-1, -1, -1, 0, 0, 0]",
        "material \"soil\".initial_stress: cannot be exported to Anura3D: Anura3D has no uniform initial stress",
    );
    refused(
        "big",
        "k0 = 1.5",
        "material \"soil\".k0: cannot be exported to Anura3D: Anura3D accepts K0 in [0, 1]",
    );
    // K0 on one layer only.
    let text = std::fs::read_to_string(testdata("layered_k0.toml"))
        .unwrap()
        .replace(
            "layered_column_tet4.msh",
            &testdata("layered_column_tet4.msh").display().to_string(),
        )
        .replace("k0 = 0.4\n", "");
    let p = d.join("one.toml");
    std::fs::write(&p, text).unwrap();
    let e = mpm_solve::input::export_anura3d::export_scene(&p, &d.join("one"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("material \"upper\": cannot be exported to Anura3D: Anura3D's K0 procedure stresses every material"),
        "{e}"
    );
}

/// The exported K0 column as GOM/CPS text, edited, loaded back.
fn gom_case(
    dir: &Path,
    name: &str,
    edit_gom: &dyn Fn(String) -> String,
    edit_cps: &dyn Fn(String) -> String,
) -> Result<Case, String> {
    let scene = column(dir, name, "k0 = 0.5");
    let a = dir.join(format!("{name}_a3d"));
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a).unwrap();
    let gom = edit_gom(std::fs::read_to_string(&files.gom).unwrap());
    let cps = edit_cps(std::fs::read_to_string(&files.cps).unwrap());
    std::fs::write(&files.gom, gom).unwrap();
    std::fs::write(&files.cps, cps).unwrap();
    mpm_solve::input::anura3d::load(&files.gom, &files.cps)
        .map(|c| c.0)
        .map_err(|e| e.to_string())
}

/// σ'yy of the first point (id 1).
fn first_vertical(case: &Case) -> f64 {
    let e = Engine::<f64, Tet4>::new(case, false).unwrap();
    let i = e.particles.id.iter().position(|&id| id == 1).unwrap();
    e.particles.stress[i][1]
}

#[test]
fn gom_k0_keys_are_modelled_or_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let same = |t: String| t;
    let base = first_vertical(&gom_case(d, "base", &same, &same).unwrap());
    assert!(base < -1.0, "{base}");
    let set = |key: &'static str, value: &'static str| {
        move |t: String| {
            let head = format!("$${key}\n");
            let at = t.find(&head).map(|i| i + head.len());
            match at {
                Some(i) => {
                    let end = i + t[i..].find('\n').unwrap();
                    format!("{}{value}{}", &t[..i], &t[end..])
                }
                None => t.replace("$$END", &format!("$${key}\n{value}\n$$END")),
            }
        }
    };
    // K0 off: unstressed.
    let off = gom_case(d, "off", &same, &set("K0_PROCEDURE", "0")).unwrap();
    assert!(off.start.initial_stress.is_none());
    // The gravity multiplier's first value scales the weight.
    let half = gom_case(d, "half", &same, &set("GRAVITY_LOAD", "step 0.5 1.0")).unwrap();
    assert!((first_vertical(&half) - 0.5 * base).abs() < 1e-12 * base.abs());
    // A vertical load times SOLID_TRACTION's first value adds everywhere.
    let loaded = gom_case(d, "load", &same, &|t| {
        set("SOLID_TRACTION", "step 2.0 2.0")(set("INITIAL_VERTICAL_LOAD_K0", "-5.0")(t))
    })
    .unwrap();
    assert!((first_vertical(&loaded) - (base - 10.0)).abs() < 1e-12);
    // The ground lowered by 0.1 m.
    let lowered = gom_case(d, "lowered", &same, &set("SURFACE_ELEVATION", "0.9")).unwrap();
    assert!((first_vertical(&lowered) - (base + 0.1 * 19.62)).abs() < 1e-9);
    for (name, gom, cps, expected) in [
        (
            "missing",
            &set("K0_VALUE_SOLID", "x") as &dyn Fn(String) -> String,
            &same as &dyn Fn(String) -> String,
            "material 1 \"soil\": missing or non-numeric $$K0_VALUE_SOLID",
        ),
        (
            "range",
            &set("K0_VALUE_SOLID", "1.5"),
            &same,
            "$$K0_VALUE_SOLID must be in [0, 1]",
        ),
        (
            "two",
            &same,
            &set("K0_PROCEDURE", "2"),
            "$$K0_PROCEDURE: must be 0 or 1",
        ),
        (
            "layers",
            &same,
            &set("NUMBER_SOIL_LAYERS", "2"),
            "$$NUMBER_SOIL_LAYERS: 2 soil layers",
        ),
        (
            "z",
            &same,
            &set("GRAVITY_VECTOR", "0.0 0.0 -1.0"),
            "$$GRAVITY_VECTOR: the K0 procedure measures depth along gravity's x-y direction",
        ),
        (
            "water",
            &|t: String| t.replace("$$FINISH", "$$INITIAL_WATER_SURFACE_FROM_FILE\n0\n$$FINISH"),
            &same,
            "$$INITIAL_WATER_SURFACE_FROM_FILE: the K0 procedure with a soil or phreatic surface",
        ),
    ] {
        let e = gom_case(d, name, gom, cps).expect_err(name);
        assert!(e.contains(expected), "{name}: {e}");
    }
}
