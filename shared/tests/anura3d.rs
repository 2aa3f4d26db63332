//! Compatibility with Anura3D's own benchmark inputs. The folder comes from the environment
//! variable `ANURA3D_BENCHMARKS` (e.g. `../shared/anura3d`); without it these tests pass
//! without checking anything and say so.

use std::path::{Path, PathBuf};

use mpm_shared::cps::Cps;
use mpm_shared::gom;

fn benchmarks() -> Option<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&root).unwrap_or_else(|e| panic!("{e}"));
    if found.is_none() {
        mpm_shared::suite::skipped("Anura3D compatibility checks (ANURA3D_BENCHMARKS not set)");
    }
    found
}

fn files(root: &Path, pred: &dyn Fn(&str) -> bool) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if pred(&p.file_name().unwrap().to_string_lossy()) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

pub fn is_gom(name: &str) -> bool {
    name.ends_with(".GOM") || name.contains(".GOM_stage")
}

#[test]
fn every_gom_round_trips() {
    let Some(root) = benchmarks() else { return };
    let goms = files(&root, &is_gom);
    assert!(
        goms.len() >= 80,
        "expected the 87 GOM files, found {}",
        goms.len()
    );
    for p in &goms {
        let data = std::fs::read(p).unwrap();
        let name = p.display().to_string();
        let m = gom::read(&data, &name).unwrap_or_else(|e| panic!("{e}"));
        assert!(m.element_count() > 0 && m.node_count() > 0, "{name}");
        let w = gom::write(&m);
        let m2 = gom::read(&w, "written").unwrap_or_else(|e| panic!("{name}: rewritten: {e}"));
        assert_eq!(m, m2, "{name}: model changed in the round trip");
        assert_eq!(w, gom::write(&m2), "{name}: write is not deterministic");
        let text = String::from_utf8(w).unwrap();
        assert!(text.starts_with("### Anura3D_20"), "{name}");
        assert!(text.trim_end().ends_with("$$FINISH"), "{name}");
        // Coordinates and ids are kept exactly, whatever their spelling in the input.
        let original: Vec<f64> = m.coords.clone();
        assert_eq!(original, m2.coords);
    }
}

#[test]
fn tet10_mid_edge_nodes_sit_at_edge_midpoints_and_orientation_is_positive() {
    let Some(root) = benchmarks() else { return };
    let mut checked = 0;
    for p in files(&root, &is_gom) {
        let m = gom::read(&std::fs::read(&p).unwrap(), "x").unwrap();
        if m.element_type != mpm_shared::ElementType::Tet10 {
            continue;
        }
        m.check_shapes(1e-6)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        checked += m.element_count();
    }
    assert!(checked > 1000, "checked {checked} tetrahedra");
}

#[test]
fn every_cps_reads_and_types() {
    let Some(root) = benchmarks() else { return };
    let cpss = files(&root, &|n: &str| n.contains(".CPS"));
    assert!(cpss.len() >= 80);
    for p in cpss {
        let name = p.display().to_string();
        let (cps, _warnings) =
            Cps::read(&std::fs::read(&p).unwrap(), &name).unwrap_or_else(|e| panic!("{e}"));
        let s = cps.settings().unwrap_or_else(|e| panic!("{e}"));
        assert!(s.load_steps >= 1 && s.courant > 0.0, "{name}");
        assert_eq!(
            Cps::read(&cps.write(), "w").unwrap().0.entries,
            cps.entries,
            "{name}"
        );
    }
}
