//! What each fuzz case does with its input: read it with one reader and, when it reads, use what
//! came back (write it and read it again, call the accessors). Shared by the stable harness
//! (`shared/tests/fuzz_readers.rs`) and the coverage-guided targets in `fuzz/`; it depends on
//! `mpm-shared` alone.

use std::sync::OnceLock;

use mpm_shared::{anura3d_vtk, bms, cps, gom, msh, points, vtu_read};

/// Exercises the reader on `d`.
pub fn read_gom(d: &[u8]) {
    if let Ok(m) = gom::read(d, "fuzz.GOM") {
        // What we accept must write and read back to itself, and its accessors must not panic.
        let again = gom::read(&gom::write(&m), "rewritten").expect("a model we accepted re-reads");
        assert_eq!(m, again, "GOM round trip");
        let _ = m.element_materials();
        let _ = m.materials();
        let _ = m.input_elements();
        let _ = m.check_shapes(1e-9);
        if let Some(p) = m.material_points_per_element() {
            let ids = points::PointIds::new(&p, m.input_elements().ok().flatten().as_deref());
            for id in [0, 1, 2, u32::MAX] {
                let _ = ids.to_input(id).map(|i| ids.to_file(i));
            }
        }
    }
}

/// Exercises the reader on `d`.
pub fn read_msh(d: &[u8]) {
    if let Ok(m) = msh::read(d, "fuzz.msh") {
        if let Ok((model, _)) = msh::to_model_with_map(&m, "fuzz.msh") {
            let again =
                gom::read(&gom::write(&model), "rewritten").expect("converted model re-reads");
            assert_eq!(model, again, "msh -> GOM round trip");
        }
    }
}

/// The golden Anura3D geometry, for the CPS checks that need one.
fn golden_model() -> &'static mpm_shared::Model {
    static M: OnceLock<mpm_shared::Model> = OnceLock::new();
    M.get_or_init(|| {
        let p = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../testdata/golden/column_anura3d.GOM"
        );
        gom::read(&std::fs::read(p).unwrap(), "golden").unwrap()
    })
}

/// Exercises the reader on `d`.
pub fn read_cps(d: &[u8]) {
    if let Ok((c, _warnings)) = cps::Cps::read(d, "fuzz.CPS") {
        let _ = c.settings();
        let _ = c.output_material_points();
        let _ = points::cps_input_ids(&c, golden_model());
        let again = cps::Cps::read(&c.write(), "rewritten");
        assert!(
            again.is_ok(),
            "a CPS we accepted re-reads: {:?}",
            again.err()
        );
    }
}

/// Exercises the reader on `d`.
pub fn read_vtu(d: &[u8]) {
    if let Ok(v) = vtu_read::parse(mpm_shared::io::Input::Buffer(d.to_vec()), "fuzz.vtu") {
        for a in v.arrays.clone() {
            let view = v.array(a.section, &a.name).expect("a listed array");
            for i in 0..view.len() {
                for c in 0..view.components {
                    std::hint::black_box(view.get(i, c));
                }
            }
        }
        let _ = v.coordinates();
    }
}

/// Exercises the reader on `d`.
pub fn read_pvd(d: &[u8]) {
    let _ = vtu_read::read_pvd(d, "fuzz.pvd");
}

/// Exercises the reader on `d`.
pub fn read_bms(d: &[u8]) {
    if let Ok(b) = bms::read_bms(d, "fuzz.BMS") {
        let _ = b.records();
    }
    if let Ok(b) = bms::read_bmr(d, "fuzz.BMR") {
        let _ = b.node_records();
        let _ = b.material_point_records();
    }
    if let Ok(t) = bms::read_tables(d, "fuzz.BMS") {
        let _ = t.project_value("Number of material points");
        let _ = t.merged("material point data", "fuzz.BMS");
    }
}

/// Exercises the reader on `d`.
pub fn read_vtk(d: &[u8]) {
    if let Ok(v) = anura3d_vtk::read(d, "fuzz.vtk") {
        let _ = anura3d_vtk::material_points(&v, &v, &v, "fuzz.vtk");
    }
}
