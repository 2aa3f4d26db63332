//! Bulk viscosity damping (`$$BULK_VISCOSITY_DAMPING`, a scene's `[damping] bulk_viscosity`):
//! Anura3D's `wave` benchmark against the energies its expected `.ENG` file reports and, point
//! by point, against a 2D Anura3D (`ANURA3D_ORACLE_2D`); a 3D column of ours under a sudden
//! load against the 3D Anura3D (`ANURA3D_ORACLE`); and what the damping does to a front in a
//! scene: the ringing behind it dies, the front still arrives on time, the load is carried.

use std::path::{Path, PathBuf};

use mpm_solve::driver::dispatch::dispatch;
use mpm_solve::driver::engine::Engine;
use mpm_solve::element::tri3::Tri3;
use mpm_solve::input::case::{Case, Drag};
use mpm_solve::step::bulk_viscosity::{BulkViscosity, Quadratic};

mod common;
use common::{run_oracle, Write};

/// The `wave` benchmark's folder, or `None` (reported as skipped) without `ANURA3D_BENCHMARKS`.
fn wave_benchmark(what: &str) -> Option<PathBuf> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    match found {
        Some(root) => Some(root.join("Benchmarks/wave")),
        None => {
            mpm_shared::suite::skipped(&format!("{what} (ANURA3D_BENCHMARKS not set)"));
            None
        }
    }
}

/// The `wave` case copied to `dir` (its CPS with `edit` applied), and its loaded case with
/// Anura3D's explicit drag.
fn wave_case(src: &Path, dir: &Path, edit: &dyn Fn(String) -> String) -> Case {
    std::fs::copy(src.join("wave_small.GOM"), dir.join("wave_small.GOM")).unwrap();
    let cps = std::fs::read_to_string(src.join("wave_small.CPS_001")).unwrap();
    std::fs::write(dir.join("wave_small.CPS_001"), edit(cps)).unwrap();
    let (mut case, _) = mpm_solve::input::anura3d::load(
        &dir.join("wave_small.GOM"),
        &dir.join("wave_small.CPS_001"),
    )
    .unwrap();
    case.numerics.drag = Drag::Explicit;
    case
}

/// Rows (kinetic energy, internal work, external work) of an Anura3D `.ENG` file.
fn energies(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let w: Vec<f64> = l.split_whitespace().map(|v| v.parse().unwrap()).collect();
            [w[2], w[3], w[4]]
        })
        .collect()
}

/// The wave benchmark (a saturated plane-strain column loaded suddenly, 20 steps of 0.1 ns,
/// bulk viscosity b1 = 0.42, b2 = 1.2): after every step Anura3D's nodal kinetic energy of
/// the solid agrees with the one its expected `.ENG` reports (seven digits) within 0.1 %, and
/// the internal and external work at the end too, while without the damping the kinetic
/// energy is more than 0.5 % off.
#[test]
fn the_wave_benchmark_reproduces_its_expected_energies() {
    let Some(src) = wave_benchmark("the wave benchmark's energies") else {
        return;
    };
    let expected = energies(&src.join("wave_small_001_expected.ENG"));
    assert_eq!(expected.len(), 21);
    let mut worst = [0.0f64; 2];
    for (k, switch) in ["1 0.42 1.2", "0 0.42 1.2"].into_iter().enumerate() {
        let dir = tempfile::tempdir().unwrap();
        let case = wave_case(&src, dir.path(), &|c| c.replace("1 0.42 1.2", switch));
        assert_eq!(case.numerics.bulk_viscosity.is_some(), k == 0);
        let mut engine = Engine::<f64, Tri3>::new(&case, false).unwrap();
        let first = case.time.initial_step.unwrap();
        let mut rows = Vec::new();
        while rows.len() < expected.len() {
            let dt = if rows.is_empty() { first } else { engine.dt };
            engine.step(dt, None).unwrap();
            rows.push([
                engine.nodal_kinetic,
                // Anura3D's internal work holds the liquid's compression energy.
                engine.strain_energy + engine.liquid_energy,
                engine.external_work,
            ]);
        }
        // The kinetic energy from the second step on (the first lasts 1e-15 s: its values
        // are round-off); the works, summed by other rules (Anura3D's from nodal forces by the
        // mid-point rule), at the end.
        for (got, want) in rows.iter().zip(&expected).skip(1) {
            worst[k] = worst[k].max((got[0] / want[0] - 1.0).abs());
        }
        let (got, want) = (rows.last().unwrap(), expected.last().unwrap());
        for c in 1..3 {
            let rel = (got[c] / want[c] - 1.0).abs();
            assert!(
                k == 1 || rel <= 1e-3,
                "work {c}: {} against {}",
                got[c],
                want[c]
            );
        }
    }
    eprintln!(
        "wave: kinetic energy within {:.2e} of the .ENG with bulk viscosity, {:.2e} without",
        worst[0], worst[1]
    );
    assert!(worst[0] <= 1e-3, "kinetic energy off by {:.2e}", worst[0]);
    // The damping takes 0.8 % of the kinetic energy over these 2 ns: a run without it is off
    // by far more than the tolerance.
    assert!(
        worst[1] > 5e-3,
        "the damping changes little: {:.2e}",
        worst[1]
    );
}

/// The worst difference of each of position, displacement, stress and pore pressure (relative
/// to its largest Anura3D value) between the Anura3D run in `anura` and ours in `ours`.
fn worst(anura: &Path, ours: &Path) -> [f64; 4] {
    let fields = ["position", "displacement", "stress", "pore_pressure"];
    let (w, outputs) = common::worst_against_anura3d(anura, ours, fields);
    assert!(outputs > 0);
    w
}

/// The wave benchmarks (`wave`: linear elastic; `wave_MC`: Mohr-Coulomb, whose steps are long
/// enough that the run takes three) run by a 2D Anura3D and by us, point by point: position,
/// displacement, effective stress and pore pressure agree within 1e-10 of their largest values.
/// Anura3D floors every step at 0.1 ns, the last of a load step too: `wave` ends after its first
/// 1e-15 s step and twenty of 0.1 ns, 1e-15 s past 2 ns, and our run of it ends there too.
#[test]
fn the_wave_benchmarks_match_the_2d_oracle_point_by_point() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let oracle = mpm_shared::suite::anura3d_oracle_2d(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(bin) = oracle else {
        mpm_shared::suite::skipped(
            "the wave benchmarks against Anura3D (ANURA3D_ORACLE_2D not set)",
        );
        return;
    };
    let Some(wave) = wave_benchmark("the wave benchmarks against Anura3D") else {
        return;
    };
    for (src, floored) in [
        (wave.clone(), true),
        (wave.with_file_name("wave_MC"), false),
    ] {
        let dir = tempfile::tempdir().unwrap();
        // Anura3D writes its material points as VTK files on request.
        let mut case = wave_case(&src, dir.path(), &|c| c.replace("GiD-Binary", "VTK"));
        run_oracle(&bin, dir.path(), "wave_small");
        if floored {
            let end = case.time.initial_step.unwrap() + 20.0 * 1e-10;
            case.time.end_time = end;
            case.time.output_times = vec![end];
        }
        let ours = tempfile::tempdir().unwrap();
        dispatch(&case, Write(&case, ours.path())).unwrap().unwrap();
        let w = worst(dir.path(), ours.path());
        let name = src.file_name().unwrap().to_string_lossy().to_string();
        eprintln!(
            "{name} against Anura3D: position {:.1e}, displacement {:.1e}, σ' {:.1e}, p {:.1e}",
            w[0], w[1], w[2], w[3]
        );
        for (v, f) in w.iter().zip(["position", "displacement", "σ'", "p"]) {
            assert!(
                *v <= 1e-10,
                "{name}: {f} differs by {v:.2e} of its largest value"
            );
        }
    }
}

/// A laterally confined column of ours (0.1 × 1 × 0.1 m, 2 × 20 × 2 cells) under a sudden load
/// of 10 kPa on its top, with a strong bulk viscosity (b1 = 0.4, b2 = 1.5), exported to
/// Anura3D's format and run by both codes: dry, and saturated (drained top), undamped
/// otherwise. Every point's position, displacement, effective stress and pore pressure agree
/// within 1e-10 of their largest values at each of three outputs, the quadratic term (Anura3D's
/// sign, as the exported GOM asks) included.
#[test]
fn a_suddenly_loaded_column_matches_anura3d_point_by_point() {
    let Some(bin) = common::oracle("bulk viscosity against Anura3D") else {
        return;
    };
    let saturated = "[material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.15e4\nintrinsic_permeability = 1.0214e-9\nviscosity = 1.0e-6\n";
    for (name, end, liquid) in [("dry", 0.03, ""), ("saturated", 0.006, saturated)] {
        let dir = tempfile::tempdir().unwrap();
        let damping = "[damping]\nbulk_viscosity = [0.4, 1.5]\n";
        let text = common::oracle_column_scene(end, 3, damping, liquid, "[true, true, true]");
        let scene = dir.path().join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let a3d = dir.path().join("a3d");
        let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
        let cps = std::fs::read_to_string(&files.cps).unwrap();
        assert!(
            cps.contains("$$BULK_VISCOSITY_DAMPING\n1 0.4 1.5\n"),
            "{cps}"
        );
        run_oracle(&bin, &a3d, name);
        let (mut case, _) = mpm_solve::input::anura3d::load(&files.gom, &files.cps).unwrap();
        case.numerics.drag = Drag::Explicit;
        let ours = tempfile::tempdir().unwrap();
        dispatch(&case, Write(&case, ours.path())).unwrap().unwrap();
        let w = worst(&a3d, ours.path());
        eprintln!(
            "{name} column against Anura3D: position {:.1e}, displacement {:.1e}, σ' {:.1e}, p {:.1e}",
            w[0], w[1], w[2], w[3]
        );
        for (v, f) in w.iter().zip(["position", "displacement", "σ'", "p"]) {
            assert!(
                *v <= 1e-10,
                "{name}: {f} differs by {v:.2e} of its largest value"
            );
        }
        // Both terms count: without the quadratic one's sign, or without the damping, the
        // stresses are far off.
        let b = case.numerics.bulk_viscosity.unwrap();
        for (what, bulk) in [
            (
                "the quadratic term resisting",
                Some(BulkViscosity {
                    sign: Quadratic::Resisting,
                    ..b
                }),
            ),
            ("no bulk viscosity", None),
        ] {
            let mut other = case.clone();
            other.numerics.bulk_viscosity = bulk;
            let out = tempfile::tempdir().unwrap();
            dispatch(&other, Write(&other, out.path()))
                .unwrap()
                .unwrap();
            let w = worst(&a3d, out.path());
            eprintln!("{name}, {what}: σ' {:.1e}", w[2]);
            assert!(w[2] > 1e-4, "{name}, {what}: σ' within {:.1e}", w[2]);
        }
    }
}

/// Behind a front: (RMS of σ_yy / p − 1 over the points between 0.6 H and 0.95 H, the mean of
/// σ_yy / p there, and the height where σ_yy first reaches p / 2 from below), when a sudden
/// load `LOAD` on the top of a plane-strain column (H = 1 m, 200 cells up, E = 10 MPa, ν = 0.3,
/// ρ = 2000 kg/m³) has travelled half its height, with `damping` the scene's `[damping]` lines.
fn front(damping: &str) -> (f64, f64, f64) {
    const LOAD: f64 = 10.0;
    let (young, nu, rho): (f64, f64, f64) = (10_000.0, 0.3, 2000.0);
    let c = (young * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) / (rho / 1000.0)).sqrt();
    let end = 0.5 / c;
    let dir = tempfile::tempdir().unwrap();
    let mesh = common::section_msh(dir.path(), 200, 0.05, 1.0);
    let text = format!(
        r#"mesh = "{}"
[time]
end = {end}
output_interval = {end}
courant = 0.5
{damping}
[[material]]
physical = "soil"
density = {rho}
young = {young}
poisson = {nu}
points_per_element = 3
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = 0.05"
fixed = [true, false, false]
[[fixity]]
plane = "y = 0"
fixed = [true, true, true]
[[traction]]
physical = "top"
traction = [0.0, -{LOAD}, 0.0]
"#,
        mesh.display()
    );
    let path = dir.path().join("front.toml");
    std::fs::write(&path, text).unwrap();
    let engine = common::run_scene::<Tri3>(&path, end, |_| {});
    let p = &engine.particles;
    let behind: Vec<f64> = (0..p.len())
        .filter(|&i| (0.6..0.95).contains(&p.x[i][1]))
        .map(|i| -p.stress[i][1] / LOAD)
        .collect();
    let n = behind.len() as f64;
    let rms = (behind.iter().map(|s| (s - 1.0).powi(2)).sum::<f64>() / n).sqrt();
    let mean = behind.iter().sum::<f64>() / n;
    let reached = (0..p.len())
        .filter(|&i| -p.stress[i][1] >= 0.5 * LOAD)
        .map(|i| p.x[i][1])
        .fold(f64::INFINITY, f64::min);
    (rms, mean, reached)
}

/// A sudden load on a column rings behind its front (the spurious oscillations of a
/// discontinuity on a mesh); bulk viscosity damps them, and the front still carries the load and
/// arrives on time: with b1 = 0.06, b2 = 1.2 (resisting) the ringing's RMS falls to under half,
/// the mean stress behind the front stays within 2 % of the load, and the front (σ_yy = p / 2)
/// stands within two cells of mid-height as without damping.
#[test]
fn bulk_viscosity_damps_the_ringing_behind_a_front() {
    let bare = front("");
    let damped = front("[damping]\nbulk_viscosity = [0.06, 1.2]");
    let strong = front("[damping]\nbulk_viscosity = [0.4, 1.2]");
    eprintln!("ringing RMS, mean, front height: undamped {bare:?}, b1 = 0.06 {damped:?}, b1 = 0.4 {strong:?}");
    assert!(bare.0 > 0.03, "no ringing to damp: {bare:?}");
    for (what, f) in [
        ("undamped", bare),
        ("b1 = 0.06", damped),
        ("b1 = 0.4", strong),
    ] {
        assert!((f.1 - 1.0).abs() < 0.02, "{what}: mean {}", f.1);
        assert!((f.2 - 0.5).abs() < 0.01, "{what}: front at {}", f.2);
    }
    assert!(
        damped.0 < 0.5 * bare.0,
        "b1 = 0.06: {damped:?} against {bare:?}"
    );
    assert!(
        strong.0 < 0.5 * bare.0,
        "b1 = 0.4: {strong:?} against {bare:?}"
    );
}

/// Anura3D damps the nodal force before it subtracts the bulk viscous one; here the viscous
/// pressure is part of the internal force. A GOM case with both is refused, naming both keys.
#[test]
fn bulk_viscosity_with_local_damping_is_refused_on_gom_input() {
    let Some(src) = wave_benchmark("bulk viscosity with local damping") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        src.join("wave_small.GOM"),
        dir.path().join("wave_small.GOM"),
    )
    .unwrap();
    let cps = std::fs::read_to_string(src.join("wave_small.CPS_001"))
        .unwrap()
        .replace(
            "$$HOMOGENEOUS_LOCAL_DAMPING\n0 0.75",
            "$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75",
        );
    assert!(cps.contains("\n1 0.75"));
    std::fs::write(dir.path().join("wave_small.CPS_001"), cps).unwrap();
    let e = mpm_solve::input::anura3d::load(
        &dir.path().join("wave_small.GOM"),
        &dir.path().join("wave_small.CPS_001"),
    )
    .expect_err("refused")
    .to_string();
    assert!(
        e.contains("$$BULK_VISCOSITY_DAMPING") && e.contains("HOMOGENEOUS_LOCAL_DAMPING"),
        "{e}"
    );
}
