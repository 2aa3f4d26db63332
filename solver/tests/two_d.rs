//! 2D sections on 3-node triangles: plane strain and axisymmetric runs against closed forms
//! (Lamé's thick cylinder, Terzaghi, a column's self-weight), thread-count determinism, what
//! 2D scenes refuse, and point-by-point agreement with a 2D Anura3D (`ANURA3D_ORACLE_2D`, built
//! by `scripts/build-oracle-2d`) on Anura3D's own 2D benchmark cases (`ANURA3D_BENCHMARKS`).

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use mpm_solve::driver::dispatch::{dispatch, Generic};
use mpm_solve::driver::run::{run, RunError};
use mpm_solve::element::tri3::Tri3;
use mpm_solve::element::Element;
use mpm_solve::input::case::{Case, Drag};
use mpm_solve::input::scene;
use mpm_solve::jobs::consolidation;
use mpm_solve::real::Real;

mod common;
use common::{outputs, testdata};

/// A scene from testdata with its mesh path made absolute and `edit` applied, as `dir/NAME`.
fn scene_in(dir: &Path, name: &str, mesh: &str, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata(name)).unwrap().replace(
        &format!("mesh = \"{mesh}\""),
        &format!("mesh = {:?}", testdata(mesh)),
    );
    let p = dir.join(name);
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// Radial displacement, position and stress of every point at the end of a run.
struct Points {
    x: Vec<[f64; 3]>,
    u: Vec<[f64; 3]>,
    stress: Vec<[f64; 6]>,
}

struct RunPoints<'a>(&'a Case, &'a Path);

impl Generic for RunPoints<'_> {
    type Output = Result<Points, RunError>;
    fn call<R: Real, E: Element>(self) -> Self::Output {
        let e = run::<R, E>(self.0, self.1, &Default::default())?;
        let p = &e.particles;
        Ok(Points {
            x: p.x.iter().map(|x| e.mesh.global(x)).collect(),
            u: p.u.iter().map(|u| u.map(|v| v.f64())).collect(),
            stress: p.stress.iter().map(|s| s.map(|v| v.f64())).collect(),
        })
    }
}

fn run_points(case: &Case, dir: &Path) -> Points {
    dispatch(case, RunPoints(case, dir)).unwrap().unwrap()
}

#[test]
fn an_axisymmetric_thick_cylinder_expands_as_lame_says() {
    // Radii a = 1, b = 2 m, p = 100 kPa inside, E = 1e5 kPa, ν = 0.3, plane strain along the
    // axis: u_r(r) = p a² (1 + ν) ((1 - 2ν) r + b² / r) / (E (b² - a²)).
    let case = scene::load(&testdata("ring_axi.toml")).unwrap();
    assert_eq!(case.model.dimension, mpm_shared::Dimension::Axisymmetric);
    let dir = tempfile::tempdir().unwrap();
    let pts = run_points(&case, dir.path());
    let (e, nu, p, a, b) = (1e5, 0.3, 100.0, 1.0, 2.0);
    let lame = |r: f64| {
        p * a * a * (1.0 + nu) * ((1.0 - 2.0 * nu) * r + b * b / r) / (e * (b * b - a * a))
    };
    let top = lame(a);
    let (mut worst, mut sum) = (0.0f64, 0.0);
    for (x, u) in pts.x.iter().zip(&pts.u) {
        let r = x[0] - u[0];
        let err = (u[0] - lame(r)) / top;
        worst = worst.max(err.abs());
        sum += err * err;
        assert!(u[1].abs() < 1e-3 * top, "no axial motion: {u:?}");
    }
    let rms = (sum / pts.x.len() as f64).sqrt();
    eprintln!("Lamé, axisymmetric: worst {worst:.2e}, RMS {rms:.2e} of u_r(a)");
    assert!(worst <= 0.01, "worst {worst}");
    // The hoop stress (the out-of-plane component) carries the pressure: at the inner wall
    // σ_θθ = p (a² + b²) / (b² - a²) = 167 kPa, at the outer 67 kPa.
    let hoop = |r: f64| p * a * a * (1.0 + b * b / (r * r)) / (b * b - a * a);
    for (x, s) in pts.x.iter().zip(&pts.stress) {
        assert!(
            (s[2] - hoop(x[0])).abs() < 0.05 * hoop(a),
            "σ_θθ at r {}: {}",
            x[0],
            s[2]
        );
    }
}

#[test]
fn the_same_cylinder_in_plane_strain_is_a_different_problem() {
    // Read as plane strain, the section is a strip pushed against a wall (its outer edge held
    // in x): no hoop stress, and σ_zz follows the in-plane stresses.
    let dir = tempfile::tempdir().unwrap();
    let s = scene_in(dir.path(), "ring_axi.toml", "ring_axi_tri3.msh", &|t| {
        t.replace("section = \"axisymmetric\"", "section = \"plane_strain\"")
            .replace("end = 1.5", "end = 0.2")
            + "\n[[fixity]]\nplane = \"x = 2\"\nfixed = [true, false, false]\n"
    });
    let case = scene::load(&s).unwrap();
    assert_eq!(case.model.dimension, mpm_shared::Dimension::PlaneStrain);
    let pts = run_points(&case, dir.path());
    let worst_zz = pts
        .stress
        .iter()
        .map(|s| (s[2] - 0.3 * (s[0] + s[1])).abs())
        .fold(0.0, f64::max);
    assert!(
        worst_zz < 1e-9,
        "plane strain: σ_zz = ν (σ_xx + σ_yy), off by {worst_zz}"
    );
}

#[test]
fn terzaghi_in_plane_strain_meets_the_default_jobs_thresholds() {
    let case = scene::load(&testdata("oedometer_2d.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (_, default, workshop) =
        consolidation::run_job::<f64, Tri3>(&case, dir.path(), &Default::default()).unwrap();
    let workshop = workshop.expect("the job also runs the workshop set-up");
    common::assert_terzaghi_thresholds(&default, &workshop);
}

#[test]
fn a_plane_strain_column_carries_its_weight() {
    // A dry column under gravity, damped to rest, sides on rollers: σ_yy = -ρ g (H - y),
    // σ_xx = σ_zz = ν / (1 - ν) σ_yy.
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        r#"mesh = {:?}
[time]
end = 1.0
output_interval = 0.5
[gravity]
vector = [0.0, -9.81, 0.0]
[damping]
local = 0.75
[[material]]
physical = "soil"
density = 2000.0
young = 10000.0
poisson = 0.3
points_per_element = 1
[[fixity]]
physical = "bottom"
fixed = [true, true, true]
[[fixity]]
physical = "x0"
fixed = [true, false, false]
[[fixity]]
physical = "x1"
fixed = [true, false, false]
"#,
        testdata("oedometer_2d_tri3.msh")
    );
    let s = dir.path().join("column.toml");
    std::fs::write(&s, text).unwrap();
    let case = scene::load(&s).unwrap();
    let pts = run_points(&case, dir.path());
    let scale = 2.0 * 9.81;
    let mut worst = 0.0f64;
    for (x, s) in pts.x.iter().zip(&pts.stress) {
        let syy = -2.0 * 9.81 * (1.0 - x[1]);
        let sxx = 0.3 / 0.7 * syy;
        worst = worst
            .max((s[1] - syy).abs() / scale)
            .max((s[0] - sxx).abs() / scale)
            .max((s[2] - sxx).abs() / scale);
    }
    eprintln!("plane-strain self-weight: worst {worst:.2e} of ρ g H");
    assert!(worst < 0.03, "worst {worst}");
}

#[test]
fn outputs_do_not_depend_on_the_thread_count_in_2d() {
    let dir = tempfile::tempdir().unwrap();
    // A soft plane-strain column falling under gravity, undamped (points cross elements), and
    // the axisymmetric cylinder.
    let falling = scene_in(
        dir.path(),
        "oedometer_2d.toml",
        "oedometer_2d_tri3.msh",
        &|t| {
            let dry = t
                .split("[material.liquid]")
                .next()
                .unwrap()
                .replace("local = 0.05", "local = 0.0")
                .replace("young = 1000.0", "young = 100.0");
            format!(
            "{dry}\n[gravity]\nvector = [0.0, -9.81, 0.0]\n[[fixity]]\nphysical = \"bottom\"\nfixed = [true, true, true]\n"
        )
        .replace("[time]\ncourant = 0.5", "[time]\ncourant = 0.5\nend = 0.1\noutput_interval = 0.05")
        },
    );
    let ring = scene_in(dir.path(), "ring_axi.toml", "ring_axi_tri3.msh", &|t| {
        t.replace("end = 1.5", "end = 0.05")
            .replace("output_interval = 0.5", "output_interval = 0.025")
    });
    for scene in [falling, ring] {
        let mut reference: Option<Vec<(String, Vec<u8>)>> = None;
        for threads in ["1", "3"] {
            let out = tempfile::tempdir().unwrap();
            Command::cargo_bin("mpm-solve")
                .unwrap()
                .arg(&scene)
                .args(["--out", out.path().to_str().unwrap(), "--threads", threads])
                .assert()
                .success();
            let files = outputs(out.path());
            assert!(files.len() > 3, "{files:?}");
            match &reference {
                None => reference = Some(files),
                Some(r) => assert!(
                    r == &files,
                    "{}: outputs differ with {threads} threads",
                    scene.display()
                ),
            }
        }
    }
}

#[test]
fn two_dimensional_scenes_refuse_what_does_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let bad = |name: &str, edit: &dyn Fn(String) -> String, want: &str| {
        let s = scene_in(dir.path(), "ring_axi.toml", "ring_axi_tri3.msh", edit);
        let p = dir.path().join(name);
        std::fs::rename(&s, &p).unwrap();
        let e = scene::load(&p).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(want), "{name}: {e}");
    };
    bad(
        "section.toml",
        &|t| t.replace("\"axisymmetric\"", "\"cylindrical\""),
        "expected \"plane_strain\" or \"axisymmetric\"",
    );
    bad(
        "gravity.toml",
        &|t| format!("{t}\n[gravity]\nvector = [0.0, -9.81, 1.0]\n"),
        "its z component must be 0",
    );
    bad(
        "curve.toml",
        &|t| t.replace("physical = \"inner\"", "physical = \"wall\""),
        "no physical curve of that name",
    );
    // A 3D mesh is no section.
    let s = dir.path().join("three.toml");
    std::fs::write(
        &s,
        std::fs::read_to_string(testdata("oedometer.toml"))
            .unwrap()
            .replace(
                "mesh = \"oedometer_tet4.msh\"",
                &format!(
                    "mesh = {:?}\nsection = \"axisymmetric\"",
                    testdata("oedometer_tet4.msh")
                ),
            ),
    )
    .unwrap();
    let e = scene::load(&s).unwrap_err().to_string();
    assert!(e.contains("is for 2D (triangle) meshes"), "{e}");
    // Four points in a triangle and MPM-MIXED in an axisymmetric section are refused by the
    // engine, naming what.
    for (edit, want) in [
        (
            "points_per_element = 3\n\n[[material]]",
            "points_per_element = 4\n\n[[material]]",
        ),
        (
            "section = \"axisymmetric\"",
            "section = \"axisymmetric\"\nintegration = \"mixed\"",
        ),
    ] {
        let s = scene_in(dir.path(), "ring_axi.toml", "ring_axi_tri3.msh", &|t| {
            t.replacen(edit, want, 1)
        });
        let out = tempfile::tempdir().unwrap();
        let a = Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&s)
            .args(["--out", out.path().to_str().unwrap()])
            .assert()
            .failure()
            .code(1);
        let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        assert!(
            err.contains("1 or 3") || err.contains("not modelled for axisymmetric sections"),
            "{err}"
        );
    }
    // The generic dispatch computes both sections with their own elements.
    assert!(Tri3::computes(
        mpm_shared::Dimension::PlaneStrain,
        mpm_shared::ElementType::Tri3
    ));
}

/// Anura3D's 2D benchmark cases that the 2D oracle and we both run, compared point by point.
const ORACLE_CASES: [&str; 4] = [
    "Pre-Commit_Tests/3065_Gravitation_DYN_MPMMIXED_2Phase_Gravity_Dynamic_2D/test-3065.A3D",
    "Pre-Commit_Tests/Oedometer_PorePressureTraction_2phase_2D_1point/Oedometer_PorePressureTraction.A3D",
    "Pre-Commit_Tests/ColumnCollapse_PLANE_MC_2Phase_K0_MPM-MP/CC_Plane_MPM-MP.A3D",
    "Pre-Commit_Tests/ColumnCollapse_AXI_MC_2Phase_K0_MPM-MP/CC_AXI_MC_2Phase_K0_MPM-MP.A3D",
];

#[test]
fn anura3d_2d_cases_agree_with_the_2d_oracle_point_by_point() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let oracle = mpm_shared::suite::anura3d_oracle_2d(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let suite = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let (Some(bin), Some(suite)) = (oracle, suite) else {
        mpm_shared::suite::skipped(
            "2D comparison with Anura3D (ANURA3D_ORACLE_2D or ANURA3D_BENCHMARKS not set)",
        );
        return;
    };
    eprintln!("| case | position | displacement | σ' | p |\n|---|---:|---:|---:|---:|");
    for case_dir in ORACLE_CASES {
        let src = suite.join("Benchmarks").join(case_dir);
        let dir = tempfile::tempdir().unwrap();
        let mut name = String::new();
        for e in std::fs::read_dir(&src).unwrap() {
            let p = e.unwrap().path();
            let ext = p.extension().map(|e| e.to_string_lossy().to_string());
            if matches!(ext.as_deref(), Some("GOM") | Some("CPS_001")) {
                std::fs::copy(&p, dir.path().join(p.file_name().unwrap())).unwrap();
                name = p.file_stem().unwrap().to_string_lossy().to_string();
            }
        }
        common::run_oracle(&bin, dir.path(), &name);
        let (gom, cps) = (
            dir.path().join(format!("{name}.GOM")),
            dir.path().join(format!("{name}.CPS_001")),
        );
        let (mut case, _) = mpm_solve::input::anura3d::load(&gom, &cps).unwrap();
        // Anura3D's own drag discretisation: the two codes then compute the same numbers.
        case.numerics.drag = Drag::Explicit;
        let ours = tempfile::tempdir().unwrap();
        run_points(&case, ours.path());
        let (w, _) = common::worst_against_anura3d(
            dir.path(),
            ours.path(),
            ["position", "displacement", "stress", "pore_pressure"],
        );
        eprintln!(
            "| {} | {:.1e} | {:.1e} | {:.1e} | {:.1e} |",
            case_dir.rsplit('/').next().unwrap(),
            w[0],
            w[1],
            w[2],
            w[3]
        );
        for (v, f) in w
            .iter()
            .zip(["position", "displacement", "stress", "pore pressure"])
        {
            assert!(
                *v <= 1e-10,
                "{case_dir}: {f} differs by {v:.2e} of its largest value"
            );
        }
    }
}
