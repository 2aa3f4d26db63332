//! Anura3D's 3D benchmarks with expected results, dry and saturated (`../shared/anura3d`,
//! found through `ANURA3D_BENCHMARKS`): the material-point positions, displacements, stresses
//! and pore pressures its expected `.BMS` files report, reproduced at the reported time.
//! Skipped when the variable is unset.

use std::path::{Path, PathBuf};

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
];

fn benchmarks() -> Option<PathBuf> {
    let dir = std::env::var_os("ANURA3D_BENCHMARKS")?;
    let p = PathBuf::from(dir).join("Benchmarks/Pre-Commit_Tests");
    p.is_dir().then_some(p)
}

/// One reported material point: time, id, then X Y Z, Ux Uy Uz, σxx σyy σzz σxy σyz σzx and
/// the pore pressure (WPressure).
struct Row {
    time: f64,
    id: u32,
    values: [f64; 13],
}

/// Reads the material-point table of a `.BMS` file.
fn read_bms(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows = Vec::new();
    let mut header: Option<Vec<String>> = None;
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.first() == Some(&"LoadStep") {
            header = Some(words.iter().map(|w| w.to_string()).collect());
            continue;
        }
        let Some(h) = &header else { continue };
        if words.len() != h.len() {
            continue;
        }
        let col = |name: &str| -> f64 {
            let i = h.iter().position(|x| x == name).unwrap();
            words[i].parse().unwrap()
        };
        let names = [
            "X",
            "Y",
            "Z",
            "Ux",
            "Uy",
            "Uz",
            "SigmaXX",
            "SigmaYY",
            "SigmaZZ",
            "SigmaXY",
            "SigmaYZ",
            "SigmaZX",
            "WPressure",
        ];
        rows.push(Row {
            time: col("Time"),
            id: col("ID_MP") as u32,
            values: names.map(col),
        });
    }
    rows
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
        eprintln!("ANURA3D_BENCHMARKS not set: skipped");
        return;
    };
    let mut report = Vec::new();
    for name in CASES {
        let dir = root.join(name);
        let gom = find(&dir, ".GOM");
        let cps = find(&dir, ".CPS_001");
        let expected = read_bms(&find(&dir, "_expected.BMS"));
        assert!(!expected.is_empty(), "{name}: no rows read");
        let (case, _) = mpm_solve::anura3d::load(&gom, &cps).unwrap();
        let out = tempfile::tempdir().unwrap();
        let engine = mpm_solve::run::run::<f64>(&case, out.path(), false, false).unwrap();
        let p = &engine.particles;
        // Each column's scale: values far below it are round-off in Anura3D's report (1e-27).
        let mut scale = [0.0f64; 13];
        for r in &expected {
            for (s, v) in scale.iter_mut().zip(r.values) {
                *s = s.max(v.abs());
            }
        }
        let mut worst: f64 = 0.0;
        for r in &expected {
            let rel_t = (engine.time - r.time).abs() / r.time;
            assert!(rel_t < 1e-3, "{name}: time {} vs {}", engine.time, r.time);
            let i = p.id.iter().position(|&id| id == r.id).unwrap();
            let pore = p.liquid.as_ref().map_or(0.0, |l| l.p[i]);
            let ours = [
                p.x[i][0],
                p.x[i][1],
                p.x[i][2],
                p.u[i][0],
                p.u[i][1],
                p.u[i][2],
                p.stress[i][0],
                p.stress[i][1],
                p.stress[i][2],
                p.stress[i][3],
                p.stress[i][4],
                p.stress[i][5],
                pore,
            ];
            for c in 0..13 {
                let want = r.values[c];
                // 1% of the value, or of 1e-3 of the column's largest value for near-zeros;
                // the report prints 4 significant digits (0.05% rounding).
                let tol = 0.01 * want.abs().max(1e-3 * scale[c]);
                let err = (ours[c] - want).abs();
                assert!(
                    err <= tol.max(1e-12),
                    "{name}: point {} column {c}: {} vs expected {want}",
                    r.id,
                    ours[c]
                );
                if want.abs() > (1e-3 * scale[c]).max(1e-12) {
                    worst = worst.max(err / want.abs());
                }
            }
        }
        report.push(format!(
            "{name}: {} points, t = {:.4e} s, worst relative difference {:.3}%",
            expected.len(),
            engine.time,
            100.0 * worst
        ));
    }
    for line in report {
        eprintln!("{line}");
    }
}
