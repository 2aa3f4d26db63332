//! Mohr–Coulomb materials through the whole program: a TOML scene with `law = "mohr_coulomb"`
//! runs and ends on the yield surface in the expected active state; a Mohr–Coulomb scene that
//! stays elastic reproduces the linear elastic run bit for bit and carries no plastic state; GOM
//! files with `mohr_coulomb` and `strain_softening_mohr_coulomb` are read, and the export writes
//! Anura3D's keys.

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_solve::input::case::Case;
use mpm_solve::material::law::LawSpec;
use mpm_solve::material::mohr_coulomb::Surface;
use mpm_solve::material::principal::principal;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// `testdata/mc_column.toml` copied into `dir` as `stem.toml` with its mesh path made absolute
/// and `edit` applied.
fn scene(dir: &Path, stem: &str, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata("mc_column.toml")).unwrap();
    let text = text.replace(
        "\"column_tet4.msh\"",
        &format!("{:?}", testdata("column_tet4.msh")),
    );
    let p = dir.join(format!("{stem}.toml"));
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// Runs `case` to its end: the final stresses, and the particles' state values per point.
fn run(case: &Case, out: &Path) -> (Vec<[f64; 6]>, usize) {
    run_in::<f64>(case, out)
}

/// [`run`] at precision `R`, the stresses widened to f64.
fn run_in<R: mpm_solve::real::Real>(case: &Case, out: &Path) -> (Vec<[f64; 6]>, usize) {
    let engine = mpm_solve::driver::run::run_observed::<R, Tet4>(
        case,
        out,
        &Default::default(),
        &mut |_| {},
    )
    .unwrap();
    let stress = engine.particles.stress.iter();
    (
        stress.map(|s| s.map(|x| x.f64())).collect(),
        engine.particles.state_len,
    )
}

/// The column of `testdata/mc_column.toml` at precision `R`: it settles in the active state
/// on the yield surface, within `tol` of it relative to the largest principal stress.
fn settles_in_the_active_state<R: mpm_solve::real::Real>(tol: f64) {
    let dir = tempfile::tempdir().unwrap();
    let case = mpm_solve::input::scene::load(&scene(dir.path(), "mc", &|t| t)).unwrap();
    assert_eq!(
        case.body.materials[1].as_ref().unwrap().law.name(),
        "mohr_coulomb"
    );
    let (stress, state_len) = run_in::<R>(&case, &dir.path().join("out"));
    assert_eq!(state_len, 0);
    let surface = Surface::<f64>::new(30.0, 0.0, 0.0, 0.0);
    let (mut deep, mut active) = (0, 0);
    for s in &stress {
        let p = principal(s);
        let f = surface.yield_value(p.values[0], p.values[2]);
        assert!(f <= tol * p.values[0].abs().max(1.0), "F = {f} at {s:?}");
        // Below the top layer: no lateral stress below the active one σh = σv (1 - sin φ) /
        // (1 + sin φ) = σv / 3, most points at it (the others unloaded a little after the
        // dynamic overshoot of the sudden weight).
        if s[1] < -3.0 {
            deep += 1;
            let ratios = [s[0] / s[1], s[2] / s[1]];
            for r in ratios {
                assert!(r > 1.0 / 3.0 - 1e-3 && r < 0.4, "σh/σv = {r} at {s:?}");
            }
            if ratios.iter().all(|r| (r - 1.0 / 3.0).abs() < 0.01) {
                active += 1;
            }
        }
    }
    assert!(deep > stress.len() / 2, "{deep} of {} points", stress.len());
    assert!(active > deep / 2, "{active} of {deep} points active");
}

#[test]
fn a_mohr_coulomb_column_settles_in_the_active_state_on_the_surface() {
    settles_in_the_active_state::<f64>(1e-9);
}

/// In single precision too: the column starts from zero stress under a weight ramped up from
/// zero, so its first returns see stresses of order 1e-10 kPa, whose decomposition f32 once
/// turned into infinities (the run stopped at step 2 with a NaN stress).
#[test]
fn the_column_settles_in_single_precision_from_a_zero_stress() {
    settles_in_the_active_state::<f32>(1e-5);
}

#[test]
fn an_elastic_mohr_coulomb_run_is_the_linear_elastic_run() {
    let dir = tempfile::tempdir().unwrap();
    let short = |t: String| {
        t.replace("end = 0.6", "end = 0.1")
            .replace("output_interval = 0.3", "output_interval = 0.1")
    };
    let strong = scene(dir.path(), "strong", &|t| {
        short(t).replace(
            "cohesion = 0.0",
            "cohesion = 1000.0\ntensile_strength = 1000.0",
        )
    });
    let elastic = scene(dir.path(), "elastic", &|t| {
        short(t)
            .replace("law = \"mohr_coulomb\"", "")
            .replace("friction_angle = 30.0", "")
            .replace("cohesion = 0.0", "")
    });
    let a = mpm_solve::input::scene::load(&strong).unwrap();
    let b = mpm_solve::input::scene::load(&elastic).unwrap();
    assert_eq!(
        b.body.materials[1].as_ref().unwrap().law.name(),
        "linear_elasticity"
    );
    let (sa, la) = run(&a, &dir.path().join("a"));
    let (sb, lb) = run(&b, &dir.path().join("b"));
    assert_eq!((la, lb), (0, 0));
    assert_eq!(sa.len(), sb.len());
    if let Some(i) = (0..sa.len()).find(|&i| sa[i] != sb[i]) {
        panic!("point {i}: {:?} against {:?}", sa[i], sb[i]);
    }
    // run.json states the same memory per point.
    let bytes = |d: &str| {
        let j: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(d).join("run.json")).unwrap(),
        )
        .unwrap();
        j["bytes_per_particle"].as_f64().unwrap()
    };
    assert_eq!(bytes("a"), bytes("b"));
}

#[test]
fn scenes_refuse_keys_of_another_law_and_unknown_laws() {
    let dir = tempfile::tempdir().unwrap();
    type Edit<'a> = &'a dyn Fn(String) -> String;
    let cases: [(&str, Edit, &str); 5] = [
        (
            "foreign",
            &|t| t.replace("cohesion = 0.0", "cohesion = 0.0\nshape_factor = 3.0"),
            "material \"soil\": shape_factor does not belong to law mohr_coulomb",
        ),
        (
            "elastic",
            &|t| t.replace("law = \"mohr_coulomb\"", ""),
            "material \"soil\": friction_angle does not belong to law linear_elasticity",
        ),
        (
            "unknown",
            &|t| t.replace("law = \"mohr_coulomb\"", "law = \"cam_clay\""),
            "law \"cam_clay\" is not known",
        ),
        (
            "missing",
            &|t| t.replace("friction_angle = 30.0", ""),
            "law mohr_coulomb needs friction_angle",
        ),
        (
            "range",
            &|t| t.replace("cohesion = 0.0", "cohesion = 0.0\ntensile_strength = 1.0"),
            "tensile strength must be in [0, 0]",
        ),
    ];
    for (stem, edit, says) in cases {
        let e = mpm_solve::input::scene::load(&scene(dir.path(), stem, edit))
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{stem}: {e}");
    }
}

#[test]
fn the_export_refuses_the_strain_softening_law() {
    let dir = tempfile::tempdir().unwrap();
    let toml = scene(dir.path(), "soft", &|t| {
        t.replace(
            "law = \"mohr_coulomb\"",
            "law = \"strain_softening_mohr_coulomb\"",
        )
        .replace(
            "friction_angle = 30.0\ncohesion = 0.0",
            "peak_cohesion = 20.0\nresidual_cohesion = 2.0\npeak_friction_angle = 35.0\n\
                 residual_friction_angle = 25.0\npeak_dilatancy_angle = 5.0\n\
                 residual_dilatancy_angle = 0.0\nshape_factor = 50.0",
        )
    });
    assert_eq!(
        mpm_solve::input::scene::load(&toml).unwrap().body.materials[1]
            .as_ref()
            .unwrap()
            .law
            .state_len(),
        1
    );
    let e = mpm_solve::input::export_anura3d::export_scene(&toml, &dir.path().join("a3d"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("material \"soil\".law") && e.contains("no stress routine"),
        "{e}"
    );
}

#[test]
fn gom_files_with_mohr_coulomb_laws_are_read_and_exported_with_anura3d_keys() {
    let dir = tempfile::tempdir().unwrap();
    let toml = scene(dir.path(), "mc", &|t| {
        t.replace(
            "cohesion = 0.0",
            "cohesion = 5.0\ndilatancy_angle = 10.0\ntensile_strength = 2.0",
        )
    });
    let out = dir.path().join("a3d");
    mpm_solve::input::export_anura3d::export_scene(&toml, &out).unwrap();
    let gom = out.join("mc.GOM");
    let cps = out.join("mc.CPS_001");
    let text = std::fs::read_to_string(&gom).unwrap();
    assert!(
        text.contains(
            "$$MATERIAL_MODEL_SOLID\nmohr_coulomb\n$$YOUNG_MODULUS\n10000.0\n$$POISSON_RATIO\n0.2\n\
             $$FRICTION_ANGLE\n30.0\n$$COHESION\n5.0\n$$DILATANCY_ANGLE\n10.0\n$$TENSILE_STRENGTH\n2.0\n"
        ),
        "{}",
        &text[text.find("$$MATERIAL_INDEX").unwrap()..][..400]
    );
    let (case, _) = mpm_solve::input::anura3d::load(&gom, &cps).unwrap();
    let want = LawSpec::mohr_coulomb(1e4, 0.2, 30.0, 5.0, 10.0, 2.0).unwrap();
    assert_eq!(case.body.materials[1].as_ref().unwrap().law, want);
    // The same block with the strain-softening law's keys, in Anura3D's order.
    let at = text.find("$$MATERIAL_MODEL_SOLID").unwrap();
    let end = text[at..].find("$$STARTELMMAT").unwrap() + at;
    let softening = "$$MATERIAL_MODEL_SOLID\nstrain_softening_mohr_coulomb\n$$YOUNG_MODULUS\n10000\n\
         $$POISSON_RATIO\n0.2\n$$PEAK_COHESION\n20\n$$RESIDUAL_COHESION\n2\n$$PEAK_FRICTION_ANGLE\n35\n\
         $$RESIDUAL_FRICTION_ANGLE\n25\n$$PEAK_DILATANCY_ANGLE\n5\n$$RESIDUAL_DILATANCY_ANGLE\n0\n\
         $$SHAPE_FACTOR\n50\n";
    let soft_gom = out.join("soft.GOM");
    std::fs::write(
        &soft_gom,
        format!("{}{softening}{}", &text[..at], &text[end..]),
    )
    .unwrap();
    let (mut case, _) = mpm_solve::input::anura3d::load(&soft_gom, &cps).unwrap();
    let law = case.body.materials[1].as_ref().unwrap().law;
    assert_eq!(law.name(), "strain_softening_mohr_coulomb");
    assert_eq!(law.state_len(), 1);
    assert_eq!(
        law.parameters().iter().map(|p| p.1).collect::<Vec<_>>(),
        vec![1e4, 0.2, 20.0, 2.0, 35.0, 25.0, 5.0, 0.0, 50.0]
    );
    // It runs, with one state value per point.
    case.time.end_time = 2e-3;
    case.time.output_times = vec![2e-3];
    let (stress, state_len) = run(&case, &dir.path().join("soft"));
    assert_eq!(state_len, 1);
    assert!(stress.iter().flatten().all(|x| x.is_finite()));
    // A parameter out of range names the material.
    let bad = softening.replace("$$SHAPE_FACTOR\n50\n", "$$SHAPE_FACTOR\n-1\n");
    std::fs::write(&soft_gom, format!("{}{bad}{}", &text[..at], &text[end..])).unwrap();
    let e = mpm_solve::input::anura3d::load(&soft_gom, &cps)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("material 1 \"soil\"") && e.contains("shape factor must be non-negative"),
        "{e}"
    );
}

/// The block of `testdata/oracle_mc_block.toml` with `pic_blend` set (mesh path absolute).
fn block(dir: &Path, pic: &str) -> PathBuf {
    let text = std::fs::read_to_string(testdata("oracle_mc_block.toml"))
        .unwrap()
        .replace(
            "\"oracle_block_tet4.msh\"",
            &format!("{:?}", testdata("oracle_block_tet4.msh")),
        );
    let p = dir.join(format!("block_{pic}.toml"));
    std::fs::write(&p, format!("pic_blend = {pic}\n{text}")).unwrap();
    p
}

/// Pure FLIP (Anura3D's update, `pic_blend = 0`) lets the slumped block's loose front points
/// keep sliding on the rough base at about 1 m/s; a little PIC takes that velocity out. The
/// blend 0 is the default bit for bit.
#[test]
fn a_pic_blend_brings_the_slumped_block_to_rest() {
    let dir = tempfile::tempdir().unwrap();
    let run = |pic: &str| {
        let case = mpm_solve::input::scene::load(&block(dir.path(), pic)).unwrap();
        let out = dir.path().join(format!("out_{pic}"));
        let e = mpm_solve::driver::run::run_observed::<f64, Tet4>(
            &case,
            &out,
            &Default::default(),
            &mut |_| {},
        )
        .unwrap();
        let fastest = e
            .particles
            .v
            .iter()
            .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
            .fold(0.0, f64::max);
        (fastest, e.particles.x.clone())
    };
    let (flip, x_flip) = run("0.0");
    let (pic, _) = run("0.05");
    assert!(flip > 0.5, "FLIP's fastest point at the end: {flip} m/s");
    assert!(
        pic < 0.05,
        "with 5 % PIC the fastest point at the end: {pic} m/s"
    );
    let default = mpm_solve::input::scene::load(&testdata("oracle_mc_block.toml")).unwrap();
    let e = mpm_solve::driver::run::run_observed::<f64, Tet4>(
        &default,
        &dir.path().join("out_default"),
        &Default::default(),
        &mut |_| {},
    )
    .unwrap();
    assert!(
        e.particles.x == x_flip,
        "pic_blend = 0 is not the default run"
    );
}

#[test]
fn scenes_refuse_a_pic_blend_outside_0_1_or_with_prescribed_velocities() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["-0.1", "1.5", "nan"] {
        let err = mpm_solve::input::scene::load(&block(dir.path(), bad)).unwrap_err();
        assert!(err.to_string().contains("pic_blend"), "{bad}: {err}");
    }
    let p = block(dir.path(), "0.1");
    let text = std::fs::read_to_string(&p).unwrap()
        + "\n[[velocity]]\nname = \"push\"\nplane = \"y = 0.35\"\nvelocity = [0.0, -0.01, 0.0]\n";
    std::fs::write(&p, text).unwrap();
    let err = mpm_solve::input::scene::load(&p).unwrap_err();
    assert!(err.to_string().contains("[[velocity]]"), "{err}");
}

#[test]
fn the_export_refuses_a_pic_blend() {
    let dir = tempfile::tempdir().unwrap();
    let toml = block(dir.path(), "0.02");
    let e = mpm_solve::input::export_anura3d::export_scene(&toml, &dir.path().join("a3d"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("pic_blend") && e.contains("FLIP"), "{e}");
    let ok = block(dir.path(), "0.0");
    mpm_solve::input::export_anura3d::export_scene(&ok, &dir.path().join("a3d0")).unwrap();
}
