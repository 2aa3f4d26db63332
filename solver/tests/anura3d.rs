//! Anura3D's 3D benchmarks with expected results, dry and saturated (`../shared/anura3d`,
//! found through `ANURA3D_BENCHMARKS`): the material-point positions, displacements, stresses
//! and pore pressures its expected `.BMS` files report, reproduced at the reported time.
//! Skipped, visibly, when the variable is unset; a failure when it names no benchmark folder.

use mpm_solve::element::tet4::Tet4;
use std::path::{Path, PathBuf};

use mpm_solve::jobs::anura3d_compare::compare;

/// The dry 3D cases with expected results: material-point (1005, 1006) and mixed (1007-1012)
/// integration, normal and objective stress, tolerances and damping factors.
const CASES: &[&str] = &[
    "1005_Oedometer_QS_MPMMP_1Phase_NormalStress_3D",
    "1006_Oedometer_QS_MPMMP_1Phase_ObjectiveStress_3D",
    "1007_Oedometer_QS_MPMMIXED_1Phase_NormalStress_3D",
    "1008_Oedometer_QS_MPMMIXED_1Phase_ObjectiveStress_3D",
    "1009_Oedometer_QS_MPMMIXED_1Phase_NormalStress_LowToleratedError_3D",
    "1010_Oedometer_QS_MPMMIXED_1Phase_NormalStress_HighToleratedError_3D",
    "1011_Oedometer_QS_MPMMIXED_1Phase_NormalStress_LowDampingFactor_3D",
    "1012_Oedometer_QS_MPMMIXED_1Phase_NormalStress_HighDampingFactor_3D",
    // Saturated (two-phase) columns under gravity, undamped and damped.
    "3065_Gravitation_DYN_MPMMIXED_2Phase_Gravity_Dynamic",
    "3066_Gravitation_QS_MPMMIXED_2Phase_Gravity_Damping",
    // A linear load on the liquid (its reported points are still at rest after the step).
    "4005_LinearLoad_DYN_MPMMIXED_pressure_2019.1",
    "4007_lineartraction",
    "4008_lineargravity",
    // Single-phase saturated types: drained (buoyant weight) and undrained total.
    "3072_Gravitation_QS_MPMMIXED_Drained_Gravity_Damping",
    "3074_Gravitation_QS_MPMMIXED_UndrainedTotal_Gravity_Damping",
    // Velocity prescribed on the points of a block, with contact and a moving mesh, one
    // 1e-15 s step (tests/contact.rs runs it for five load steps against Anura3D itself).
    "4006_PrescribedVelocityMP",
];

/// The benchmark folder: `ANURA3D_BENCHMARKS`, relative to the workspace root when relative.
/// Unset (or empty): `None`, and the test says it is skipped. Set to a folder that does not
/// hold the benchmarks: a failure, not a silent skip.
fn benchmarks() -> Option<PathBuf> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(root) = found else {
        mpm_shared::suite::skipped("Anura3D benchmark comparison (ANURA3D_BENCHMARKS not set)");
        return None;
    };
    let p = root.join("Benchmarks/Pre-Commit_Tests");
    assert!(p.is_dir(), "{} is not a folder", p.display());
    Some(p)
}

/// Reads a `.BMS` file with the shared reader.
fn read_bms(path: &Path) -> mpm_shared::bms::Bms {
    let data = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mpm_shared::bms::read_bms(&data, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"))
}

fn find(dir: &Path, suffix: &str) -> PathBuf {
    let a3d = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "A3D"))
        .unwrap();
    std::fs::read_dir(&a3d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(suffix))
        .unwrap()
}

#[test]
fn benchmarks_reproduce_the_expected_material_points() {
    let Some(root) = benchmarks() else {
        return;
    };
    let mut report = Vec::new();
    for name in CASES {
        let dir = root.join(name);
        let (gom, cps) = (find(&dir, ".GOM"), find(&dir, ".CPS_001"));
        let expected = read_bms(&find(&dir, "_expected.BMS"));
        assert!(!expected.material_points.is_empty(), "{name}: no rows read");
        let (case, _) = mpm_solve::input::anura3d::load(&gom, &cps).unwrap();
        let out = tempfile::tempdir().unwrap();
        let engine =
            mpm_solve::driver::run::run::<f64, Tet4>(&case, out.path(), &Default::default())
                .unwrap();
        let c = compare(&engine, &expected);
        assert!(
            c.time_matches(),
            "{name}: time {} vs {}",
            c.time,
            c.expected_time
        );
        assert!(
            c.missing.is_empty(),
            "{name}: points {:?} missing",
            c.missing
        );
        // 1% of the value, or of 1e-3 of the field's largest value for near-zeros; the report
        // prints 4 significant digits (0.05% rounding).
        if let Some(w) = c.worst_at {
            assert!(
                c.worst <= 0.01,
                "{name}: point {} column {}: {} vs expected {}",
                w.id,
                w.column,
                w.ours,
                w.expected
            );
        }
        report.push(format!(
            "{name}: {} points, t = {:.4e} s, worst relative difference {:.3}%",
            c.points,
            engine.time,
            100.0 * c.worst_plain
        ));
    }
    for line in report {
        eprintln!("{line}");
    }
}
