//! Mass scaling (`$$MASS_SCALING 1 f`, a scene's `time.mass_scaling`): a dry 3D column of ours
//! against the 3D Anura3D (`ANURA3D_ORACLE`) point by point; in a scene, the step √f times
//! longer, the same state at rest, the energy balance kept with the scaled inertia and the
//! scaled kinetic energy reported; and the refusals.

use std::path::Path;

use mpm_shared::vtu_read::read_vtu_file;
use mpm_solve::driver::dispatch::dispatch;
use mpm_solve::input::case::Drag;

mod common;
use common::{run_oracle, Write};

fn worst(anura: &Path, ours: &Path) -> [f64; 3] {
    let fields = ["position", "displacement", "stress"];
    let (w, outputs) = common::worst_against_anura3d(anura, ours, fields);
    assert!(outputs > 0);
    w
}

/// A laterally confined dry column of ours (0.1 × 1 × 0.1 m, E = 1000 kPa) under its weight
/// and a sudden 10 kPa on its top, undamped, with the mass scaled by 10, exported to Anura3D's
/// format and run by both codes: every point's position, displacement and stress agree within
/// 1e-10 of their largest values at each of three outputs. Without the scaling the two part by
/// far more.
#[test]
fn a_scaled_dry_column_matches_anura3d_point_by_point() {
    let Some(bin) = common::oracle("mass scaling against Anura3D") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let extra = "mass_scaling = 10.0\n[gravity]\nvector = [0.0, -9.81, 0.0]\n";
    let text = common::oracle_column_scene(0.09, 3, extra, "", "[true, true, true]");
    let scene = dir.path().join("scaled.toml");
    std::fs::write(&scene, text).unwrap();
    let a3d = dir.path().join("a3d");
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
    let cps = std::fs::read_to_string(&files.cps).unwrap();
    assert!(cps.contains("$$MASS_SCALING\n1 10"), "{cps}");
    run_oracle(&bin, &a3d, "scaled");
    let (mut case, _) = mpm_solve::input::anura3d::load(&files.gom, &files.cps).unwrap();
    assert_eq!(case.numerics.mass_scaling, 10.0);
    case.numerics.drag = Drag::Explicit;
    let ours = tempfile::tempdir().unwrap();
    dispatch(&case, Write(&case, ours.path())).unwrap().unwrap();
    let w = worst(&a3d, ours.path());
    eprintln!(
        "scaled column against Anura3D: position {:.1e}, displacement {:.1e}, σ {:.1e}",
        w[0], w[1], w[2]
    );
    for (v, f) in w.iter().zip(["position", "displacement", "stress"]) {
        assert!(*v <= 1e-10, "{f} differs by {v:.2e} of its largest value");
    }
    let mut unscaled = case.clone();
    unscaled.numerics.mass_scaling = 1.0;
    let out = tempfile::tempdir().unwrap();
    dispatch(&unscaled, Write(&unscaled, out.path()))
        .unwrap()
        .unwrap();
    let w = worst(&a3d, out.path());
    eprintln!("unscaled against the scaled Anura3D: σ {:.1e}", w[2]);
    assert!(
        w[2] > 1e-3,
        "the scaling changed nothing: σ within {:.1e}",
        w[2]
    );
}

/// A point's position and stress.
type PointStress = ([f64; 3], [f64; 6]);

/// `run.json` of the oracle column (dry, damped, under its weight and 10 kPa) run for `end`
/// seconds with the mass scaled by `f`, and its last output's points and stresses.
fn settle(dir: &Path, f: f64, end: f64) -> (serde_json::Value, Vec<PointStress>) {
    let extra = format!(
        "mass_scaling = {f:?}\n[damping]\nlocal = 0.7\n[gravity]\nvector = [0.0, -9.81, 0.0]\n"
    );
    let text = common::oracle_column_scene(end, 1, &extra, "", "[true, true, true]");
    let scene = dir.join(format!("f{f}.toml"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join(format!("out{f}"));
    let status = assert_cmd::Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .arg("-q")
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    // The last output of the points (the files of one kind sort in time order).
    let mut files: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "vtu"))
        .filter_map(|p| {
            read_vtu_file(&p)
                .ok()
                .filter(|v| v.point_data("stress").is_some())
                .map(|_| p)
        })
        .collect();
    files.sort();
    let last = read_vtu_file(files.last().expect("an output of the points")).unwrap();
    let (s, x) = (
        last.point_data("stress").unwrap(),
        last.coordinates().unwrap(),
    );
    let stress = (0..s.len())
        .map(|i| {
            let xi: [f64; 3] = std::array::from_fn(|c| x.get(i, c));
            let si: [f64; 6] = std::array::from_fn(|c| s.get(i, c));
            (xi, si)
        })
        .collect();
    (run, stress)
}

/// Scaling the mass by 100 makes the step 10 times longer; a damped column settles to the same
/// stresses (by tenth of the height), the energy guard holds with the scaled inertia, and
/// run.json reports the scaled mass's kinetic energy beside the physical one.
#[test]
fn the_step_grows_by_the_root_and_the_state_at_rest_is_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, at_rest) = settle(dir.path(), 1.0, 8.0);
    let (scaled, scaled_rest) = settle(dir.path(), 100.0, 8.0);
    let steps = |r: &serde_json::Value| r["steps"].as_f64().unwrap();
    let ratio = steps(&plain) / steps(&scaled);
    assert!(
        (ratio - 10.0).abs() < 0.2,
        "steps {} against {}",
        steps(&plain),
        steps(&scaled)
    );
    assert!(plain["energy"].get("mass_scaling").is_none());
    let m = &scaled["energy"]["mass_scaling"];
    assert_eq!(m["factor"].as_f64(), Some(100.0));
    let kinetic = scaled["energy"]["kinetic"].as_f64().unwrap();
    assert_eq!(m["kinetic_of_scaled_mass"].as_f64(), Some(100.0 * kinetic));
    // Settled (8 s is five of the scaled column's periods, 4H / c = 1.5 s) to the same
    // stresses: the mean σ_yy of each tenth of the height within 0.5 kPa (the base carries
    // about 30; single points ring more).
    let bins = |points: &[PointStress]| -> Vec<f64> {
        let mut sums = [(0.0, 0usize); 10];
        for (x, s) in points {
            let k = ((x[1] * 10.0) as usize).min(9);
            sums[k].0 += s[1];
            sums[k].1 += 1;
        }
        sums.iter().map(|(s, n)| s / *n as f64).collect()
    };
    let (a, b) = (bins(&at_rest), bins(&scaled_rest));
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    eprintln!("σ_yy by tenth of the height: {a:.2?} and scaled {b:.2?}");
    assert!(worst < 0.5, "mean σ_yy at rest differs by {worst} kPa");
}

/// What mass scaling is not modelled with, and factors out of range, are refused by name.
#[test]
fn mass_scaling_refusals_name_what_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let saturated = "[material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.15e4\nintrinsic_permeability = 1.0214e-9\nviscosity = 1.0e-6\n";
    for (name, extra, liquid, expect) in [
        ("low", "mass_scaling = 0.5\n", "", "time.mass_scaling"),
        ("nan", "mass_scaling = nan\n", "", "time.mass_scaling"),
        (
            "wet",
            "mass_scaling = 10.0\n",
            saturated,
            "with saturated materials",
        ),
    ] {
        let text = common::oracle_column_scene(0.01, 1, extra, liquid, "[true, true, true]");
        let scene = dir.path().join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = assert_cmd::Command::cargo_bin("mpm-solve")
            .unwrap()
            .arg(&scene)
            .arg("--out")
            .arg(dir.path().join(name))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{name} ran");
        assert!(stderr.contains(expect), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
    // Anura3D's key with a factor that does not divide.
    let scene = dir.path().join("gom.toml");
    let text =
        common::oracle_column_scene(0.01, 1, "mass_scaling = 2.0\n", "", "[true, true, true]");
    std::fs::write(&scene, text).unwrap();
    let files =
        mpm_solve::input::export_anura3d::export_scene(&scene, &dir.path().join("a3d")).unwrap();
    let cps = std::fs::read_to_string(&files.cps).unwrap();
    std::fs::write(
        &files.cps,
        cps.replace("$$MASS_SCALING\n1 2", "$$MASS_SCALING\n1 -2"),
    )
    .unwrap();
    let e = mpm_solve::input::anura3d::load(&files.gom, &files.cps).unwrap_err();
    assert!(e.to_string().contains("$$MASS_SCALING"), "{e}");
}
