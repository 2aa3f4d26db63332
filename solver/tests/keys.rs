//! The key table (`mpm_solve::input::anura3d_keys::KEYS`) against the loader: every key refused (unless
//! inert) stops a generated case that is otherwise accepted, naming the key, its value and where
//! it is; and `docs/anura3d-keys.md` is the table's own rendering.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use mpm_shared::{generate, ElementType};
use mpm_solve::input::anura3d_keys::{self, KeyKind, KeyStatus, KEYS};

/// Elements of the generated box (1 × 2 × 1 cells of 6 tetrahedra).
const ELEMENTS: usize = 12;

/// A dry linear elastic box that the loader accepts.
fn base_gom() -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.GOM");
    let model = generate::box_mesh([1, 2, 1], [1.0, 2.0, 1.0], ElementType::Tet4);
    assert_eq!(model.element_count(), ELEMENTS);
    mpm_shared::write_gom_file(&model, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let material = "$$MATERIAL_TYPE\ndry_material\n$$POROSITY_SOLID\n0.0\n$$DENSITY_SOLID\n1000\n$$MATERIAL_MODEL_SOLID\nlinear_elasticity\n$$YOUNG_MODULUS\n1000\n$$POISSON_RATIO\n0.0\n$$STARTELMMAT";
    assert!(text.contains("$$STARTELMMAT"));
    text.replacen("$$STARTELMMAT", material, 1)
}

/// One short load step, no gravity.
const BASE_CPS: &str = "### Anura3D_2021 ###\n$$NUMBER_OF_LOADSTEPS\n1\n$$TIME_PER_LOADSTEP\n1e-4\n$$COMPUTATION_METHOD\nMPM-MP\n$$GRAVITY_LOAD\noff 0.0 1.0\n$$END\n";

/// `gom` with section `key` holding `body` (lines after the keyword): an existing section of
/// that name is replaced, otherwise it goes before `$$NUMBER_OF_MATERIALS`.
fn set_section(gom: &str, key: &str, body: &str) -> String {
    let head = format!("$${key}\n");
    let without = match gom.find(&head) {
        Some(at) => {
            let rest = &gom[at + head.len()..];
            let end = rest.find("$$").unwrap();
            format!("{}{}", &gom[..at], &rest[end..])
        }
        None => gom.to_string(),
    };
    without.replacen(
        "$$NUMBER_OF_MATERIALS",
        &format!("{head}{body}$$NUMBER_OF_MATERIALS"),
        1,
    )
}

/// A concrete key for the entry `pattern` (`*` filled in) and a value the loader must refuse:
/// for GOM sections the section's lines, for material keys and CPS keys the value line. `None`
/// for an entry no one has given a value yet (the test then fails, naming it).
fn refused_example(kind: KeyKind, pattern: &str) -> Option<(String, String)> {
    let (key, value) = match (kind, pattern) {
        (KeyKind::GomSection, "FORMULATION") => (pattern, "double-point\n".to_string()),
        (KeyKind::GomSection, "STARTDAMPING") => (pattern, "0.05\n".repeat(ELEMENTS)),
        (KeyKind::GomSection, "START_FIXITY_*_GAS") => {
            ("START_FIXITY_SURFACE_GAS", "1\n1 1 1 1\n".into())
        }
        (KeyKind::GomSection, "START_REMOVE_FIXITY_*") => {
            ("START_REMOVE_FIXITY_SURFACE_SOLID", "1\n1 1 1 1\n".into())
        }
        (KeyKind::GomSection, "START_LOAD_ON_*") => (
            "START_LOAD_ON_MATERIAL_POINTS_LIQUID",
            "1\n1 2 3 0 -1 0 0 -1 0 0 -1 0\n".into(),
        ),
        (KeyKind::GomSection, "PRESCRIBED_*") => (
            "PRESCRIBED_NODAL_VELOCITY_SURFACE_SOLID",
            "1\n1 0 1 0 0.0 -0.1 0.0\n".into(),
        ),
        (KeyKind::GomSection, "INITIAL_VELOCITY_MATERIAL_POINT") => {
            (pattern, "1\n1 0.0 -0.1 0.0\n".into())
        }
        (KeyKind::GomSection, "START_EXCAVATION_SOLID") => (pattern, "1 1\n".into()),
        (KeyKind::CpsKey, "TOTAL_TIME") => (pattern, "0.5".into()),
        (KeyKind::CpsKey, "HYDRAULIC_HEAD") => (pattern, "on".into()),
        (
            KeyKind::CpsKey,
            "APPLY_SMOOTHENING_LIQUID_PRESSURE_INCREMENT"
            | "FIX_SOLID_SKELETON"
            | "APPLY_POROSITY_UPDATE"
            | "APPLY_MATERIAL_UPDATE"
            | "APPLY_CONTACT_MESH_BOUNDARY"
            | "APPLY_CONTACT_VELOCITY_SCALING"
            | "APPLY_CONTACT_NORMAL_CORRECTION"
            | "SUBMERGED_CALCULATION"
            | "RESET_DISPLACEMENTS"
            | "K0_PROCEDURE"
            | "INITIAL_WATER_PRESSURE"
            | "INITIAL_VELOCITY"
            | "MP_STRESS_INITIALIZATION_FROMFILE"
            | "APPLY_SEEPAGE_FACE"
            | "APPLY_INFILTRATION",
        ) => (pattern, "1".into()),
        _ => return None,
    };
    Some((key.to_string(), value))
}

/// The case `gom` + `cps` written as `dir/box.GOM` and `dir/box.CPS_001`.
fn write_case(dir: &Path, gom: &str, cps: &str) -> PathBuf {
    let g = dir.join("box.GOM");
    std::fs::write(&g, gom).unwrap();
    std::fs::write(dir.join("box.CPS_001"), cps).unwrap();
    g
}

/// `mpm-solve GOM --out DIR`.
fn solve(gom: &Path, out: &Path) -> std::process::Output {
    Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(gom)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn base_case_is_accepted_and_runs() {
    let dir = tempfile::tempdir().unwrap();
    let g = write_case(dir.path(), &base_gom(), BASE_CPS);
    mpm_solve::input::anura3d::load(&g, &dir.path().join("box.CPS_001")).unwrap();
    let out = dir.path().join("out");
    let run = solve(&g, &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.join("run.json").exists());
}

#[test]
fn every_refused_key_stops_a_case_naming_key_value_and_place() {
    let base_gom = base_gom();
    let mut missing = Vec::new();
    let mut checked = 0;
    for &(kind, pattern, status) in KEYS {
        if !matches!(
            status,
            KeyStatus::Refused(_) | KeyStatus::RefusedUnlessInert(_)
        ) {
            continue;
        }
        let Some((key, value)) = refused_example(kind, pattern) else {
            missing.push(format!("{} $${pattern}", kind.label()));
            continue;
        };
        // The example must be the entry's own (a pattern filled in may not hit another entry).
        assert_eq!(
            anura3d_keys::lookup(kind, &key).map(|e| e.0),
            Some(pattern),
            "{key}"
        );
        let dir = tempfile::tempdir().unwrap();
        let (gom, cps, file, line) = match kind {
            KeyKind::GomSection => {
                let gom = set_section(&base_gom, &key, &value);
                let line = gom.lines().position(|l| l == format!("$${key}")).unwrap() + 1;
                (gom, BASE_CPS.to_string(), "box.GOM", Some(line))
            }
            KeyKind::MaterialKey => (
                base_gom.replacen(
                    "$$MATERIAL_TYPE",
                    &format!("$${key}\n{value}\n$$MATERIAL_TYPE"),
                    1,
                ),
                BASE_CPS.to_string(),
                "box.GOM",
                None,
            ),
            KeyKind::CpsKey => {
                let cps = BASE_CPS.replacen("$$END", &format!("$${key}\n{value}\n$$END"), 1);
                // The loader names the key's own line (1-based).
                let line = cps.lines().position(|l| l == format!("$${key}")).unwrap() + 1;
                (base_gom.clone(), cps, "box.CPS_001", Some(line))
            }
        };
        let g = write_case(dir.path(), &gom, &cps);
        let what = format!("{} $${key} = {value:?}", kind.label());
        // The library refuses it with the typed error...
        let err = mpm_solve::input::anura3d::load(&g, &dir.path().join("box.CPS_001"))
            .err()
            .unwrap_or_else(|| panic!("{what} was accepted"));
        assert!(
            matches!(err, mpm_solve::input::anura3d::CaseError::Key(_)),
            "{what}: {err}"
        );
        // ...and the command stops before the first step, writing nothing.
        let out = dir.path().join("out");
        let run = solve(&g, &out);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{what} ran");
        assert!(!out.exists(), "{what}: an output folder was written");
        assert!(stderr.starts_with("mpm-solve: error: "), "{what}: {stderr}");
        assert!(stderr.contains(file), "{what}: no file in {stderr}");
        assert!(stderr.contains(&format!("$${key} = ")), "{what}: {stderr}");
        let shown = match kind {
            // A section's value is summarised: its first text line, or how many rows it has.
            KeyKind::GomSection if key == "FORMULATION" => {
                value.lines().next().unwrap().to_string()
            }
            KeyKind::GomSection if key == "STARTDAMPING" => format!("{ELEMENTS} non-zero values"),
            KeyKind::GomSection => {
                let rows = if key.ends_with("CORNER_NODES") || key == "START_EXCAVATION_SOLID" {
                    value.lines().count()
                } else {
                    value.lines().next().unwrap().parse().unwrap()
                };
                format!("{rows} rows")
            }
            _ => value.clone(),
        };
        assert!(
            stderr.contains(&format!("{shown:?}")),
            "{what}: value {shown:?} not in {stderr}"
        );
        if let Some(line) = line {
            assert!(
                stderr.contains(&format!("(line {line})")),
                "{what}: line {line} not in {stderr}"
            );
        }
        assert!(stderr.contains("not modelled"), "{what}: {stderr}");
        checked += 1;
    }
    assert!(
        missing.is_empty(),
        "refused keys without an example value in refused_example (add one): {}",
        missing.join(", ")
    );
    // A floor against a vacuous pass: 23 kinds of key are refused unless inert (bulk viscosity,
    // absorbing boundaries and mass scaling became modelled).
    assert!(checked >= 23, "only {checked} refused keys checked");
}

#[test]
fn key_table_doc_is_generated_from_the_table() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(anura3d_keys::DOC_PATH);
    let want = anura3d_keys::markdown();
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "{} is not the rendering of anura3d_keys::KEYS; regenerate it with\n  UPDATE_DOCS=1 cargo test -p mpm-solve --test keys key_table_doc\nand commit it",
        anura3d_keys::DOC_PATH
    );
}
