//! Hypoplastic sand through the whole program: a scene with `law = "hypoplasticity"` loads a
//! laterally confined column, dry and saturated, in f64 and f32, on tetrahedra and on the
//! background grid, and ends where the law's own oedometer element test says
//! (tests/soil_elements.rs checks the element tests against published numbers); parameters
//! and starts outside the model's bounds are refused by name.

mod common;

use common::soil_column::{on_the_element_path, run, scene};
use mpm_solve::material::law::LawSpec;

/// Hochstetten sand (Herle & Gudehus 1999), e0 0.70, with or without the intergranular strain.
fn sand(igs: bool) -> String {
    let mut s = String::from(
        r#"law = "hypoplasticity"
critical_friction_angle = 33.0
granular_hardness = 1.0e6
exponent_n = 0.25
minimum_void_ratio = 0.55
critical_void_ratio = 0.95
maximum_void_ratio = 1.05
exponent_alpha = 0.25
exponent_beta = 1.5
initial_void_ratio = 0.7
maximum_pressure = 400.0"#,
    );
    if igs {
        s.push_str("\nigs_r = 1.0e-4\nigs_initial = 1.0");
    }
    s
}

/// The law of [`sand`], as the element test takes it.
fn law(igs: bool) -> LawSpec {
    let text = sand(igs);
    let values: Vec<(String, f64)> = text
        .lines()
        .filter_map(|l| {
            let (k, v) = l.split_once(" = ")?;
            Some((k.to_uppercase(), v.parse().ok()?))
        })
        .collect();
    let keys = mpm_solve::material::law::parameter_list("hypoplasticity").unwrap();
    LawSpec::by_name("hypoplasticity", &|k| {
        values
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| *v)
            .or_else(|| keys.iter().find(|p| p.key == k).and_then(|p| p.default))
    })
    .unwrap()
}

/// The column scene of [`sand`] with `liquid` lines, loaded over 2 s (a slower ramp than the
/// clay's: the sand's small vibrations in an explicit run would otherwise add up, see
/// [`without_the_intergranular_strain_small_cycles_ratchet`]), ended at 3 s.
fn sand_scene(dir: &std::path::Path, liquid: &str, igs: bool) -> std::path::PathBuf {
    let path = scene(dir, liquid, &sand(igs));
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("end = 1.5", "end = 3.0")
        .replace("[0.4, 1.0]", "[2.0, 1.0]");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_sand_column_settles_as_the_element_oedometer_says() {
    let dir = tempfile::tempdir().unwrap();
    let path = sand_scene(dir.path(), "", true);
    let (strain, sv, sh, state_len) = run::<f64>(&path, &dir.path().join("f64"));
    assert_eq!(state_len, 7);
    on_the_element_path(&law(true), "dry column", (strain, sv, sh), 2e-2, 1e-2);
    let (s32, sv32, sh32, _) = run::<f32>(&path, &dir.path().join("f32"));
    on_the_element_path(&law(true), "dry column, f32", (s32, sv32, sh32), 2e-2, 1e-2);
}

/// Hypoplasticity without the intergranular strain accumulates strain in every small cycle
/// (its known ratcheting, which the intergranular strain was made to cure): the column's
/// small vibrations about its load leave it more compressed than the monotonic element path.
#[test]
fn without_the_intergranular_strain_small_cycles_ratchet() {
    let dir = tempfile::tempdir().unwrap();
    let path = sand_scene(dir.path(), "", false);
    let (strain, sv, _, _) = run::<f64>(&path, &dir.path().join("f64"));
    let (want, _) = common::soil_column::element_answer(&law(false), sv);
    println!("without IGS: strain {strain:.5}, the element's {want:.5}");
    assert!(strain > 1.05 * want, "{strain} against {want}");
}

/// The same column on a background grid (quadratic B-splines, 0.1 m cells).
#[test]
fn on_the_background_grid_too() {
    let dir = tempfile::tempdir().unwrap();
    let path = sand_scene(dir.path(), "", true);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("[time]", "[grid]\ncell = 0.1\nbasis = \"bspline2\"\n[time]");
    std::fs::write(&path, text).unwrap();
    let (strain, sv, sh, _) = run::<f64>(&path, &dir.path().join("grid"));
    on_the_element_path(&law(true), "grid", (strain, sv, sh), 3e-2, 5e-2);
}

#[test]
fn a_saturated_sand_column_consolidates_to_the_same_state() {
    let dir = tempfile::tempdir().unwrap();
    let liquid = r#"[material.liquid]
porosity = 0.4117647058823529
density = 1000.0
bulk_modulus = 1.0e5
intrinsic_permeability = 1.0e-8
viscosity = 1.0e-6"#;
    // The semi-implicit scheme: the explicit one's pore pressures chatter from step to step,
    // each chatter a small reversal of the skeleton's strain that the intergranular strain
    // answers with its stiffest response (m_R), and the column ends 40 % stiffer (docs).
    let path = sand_scene(dir.path(), liquid, true);
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("[time]", "[time]\nscheme = \"semi-implicit\"");
    std::fs::write(&path, text).unwrap();
    let (strain, sv, sh, _) = run::<f64>(&path, &dir.path().join("saturated"));
    on_the_element_path(&law(true), "saturated column", (strain, sv, sh), 3e-2, 1e-2);
}

#[test]
fn parameters_and_starts_outside_the_bounds_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    for (text, says) in [
        (
            sand(true).replace("critical_void_ratio = 0.95", "critical_void_ratio = 1.1"),
            "the void ratios must grow from MINIMUM_VOID_RATIO",
        ),
        (
            sand(true).replace("maximum_pressure = 400.0", ""),
            "needs maximum_pressure",
        ),
        (
            format!("{}\npoisson = 0.3", sand(true)),
            "poisson does not belong to law hypoplasticity",
        ),
        (
            sand(true).replace("initial_void_ratio = 0.7", "initial_void_ratio = 1.2"),
            "INITIAL_VOID_RATIO (1.2) lies outside the model's bounds",
        ),
        (
            format!("{}\nigs_mt = 6.0", sand(true)),
            "IGS_MT (6) must not exceed IGS_MR (5)",
        ),
    ] {
        let path = scene(dir.path(), "", &text);
        let e = mpm_solve::input::scene::load(&path)
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{says}: {e}");
    }
    // e0 = 0.95 is admitted at zero pressure but looser than e_i = 0.9296 at the column's
    // p' = 73 kPa: the setup names the point.
    let path = scene(
        dir.path(),
        "",
        &sand(true).replace("initial_void_ratio = 0.7", "initial_void_ratio = 0.95"),
    );
    let case = mpm_solve::input::scene::load(&path).unwrap();
    let e = mpm_solve::driver::run::run_observed::<f64, mpm_solve::element::tet4::Tet4>(
        &case,
        &dir.path().join("loose"),
        &Default::default(),
        &mut |_| {},
    )
    .err()
    .expect("the loose start is refused")
    .to_string();
    assert!(
        e.contains("material point 1 of material \"soil\"")
            && e.contains(
                "void ratio 0.95 lies outside the hypoplastic bounds at p' = 73.3333 kPa"
            ),
        "{e}"
    );
}

#[test]
fn the_scene_exports_to_a_gom_that_reads_back_the_same_law() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene(dir.path(), "", &sand(true));
    let (text, case) = common::soil_column::exported_and_read_back(&path);
    assert!(
        text.contains(
            "$$MATERIAL_MODEL_SOLID\nhypoplasticity\n$$CRITICAL_FRICTION_ANGLE\n33.0\n\
             $$GRANULAR_HARDNESS\n1000000.0\n$$EXPONENT_N\n0.25\n$$MINIMUM_VOID_RATIO\n0.55\n\
             $$CRITICAL_VOID_RATIO\n0.95\n$$MAXIMUM_VOID_RATIO\n1.05\n$$EXPONENT_ALPHA\n0.25\n\
             $$EXPONENT_BETA\n1.5\n$$INITIAL_VOID_RATIO\n0.7\n$$IGS_R\n0.0001\n$$IGS_MR\n5.0\n\
             $$IGS_MT\n2.0\n$$IGS_BETA_R\n0.5\n$$IGS_CHI\n6.0\n$$IGS_INITIAL\n1.0\n\
             $$INTEGRATION_TOLERANCE\n0.0001\n$$MINIMUM_PRESSURE\n1.0\n$$MAXIMUM_PRESSURE\n400.0\n"
        ),
        "{}",
        &text[text.find("$$MATERIAL_INDEX").unwrap()..][..900]
    );
    assert_eq!(case.body.materials[1].as_ref().unwrap().law, law(true));
}
