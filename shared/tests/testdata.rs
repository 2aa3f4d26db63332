//! The bundled Gmsh meshes convert to the bundled GOM files, keep Gmsh's geometry, and come out
//! positively oriented with every mid-edge node at its edge's midpoint.

use std::path::Path;

use mpm_shared::{geometry, gom, msh};

fn path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

#[test]
fn gmsh_meshes_convert_to_the_golden_goms() {
    for m in [
        "cube_tet4",
        "cube_tet10",
        "column_tet4",
        "column_tet10",
        "square_tri3",
    ] {
        let mesh = msh::read(&std::fs::read(path(&format!("{m}.msh"))).unwrap(), m).unwrap();
        let model = msh::to_model(&mesh, m).unwrap();
        let golden = std::fs::read(path(&format!("{m}.GOM"))).unwrap();
        assert!(
            gom::write(&model) == golden,
            "{m}: conversion differs from testdata/{m}.GOM"
        );
        assert_eq!(gom::read(&golden, m).unwrap(), model);
    }
}

#[test]
fn msh_22_and_41_give_the_same_model() {
    let a = msh::read(&std::fs::read(path("cube_tet4.msh")).unwrap(), "a").unwrap();
    let b = msh::read(&std::fs::read(path("cube_tet4_v22.msh")).unwrap(), "b").unwrap();
    assert_eq!(
        msh::to_model(&a, "a").unwrap(),
        msh::to_model(&b, "b").unwrap()
    );
    // Boundary triangles carry their physical groups (named in $PhysicalNames).
    let tris = a.set(msh::kind::TRI3).unwrap();
    let top = a
        .physical_names
        .iter()
        .find(|p| p.name == "top")
        .unwrap()
        .tag;
    assert!(tris.physical.contains(&top));
}

#[test]
fn converted_tets_are_positive_with_midpoint_edges() {
    for m in ["cube_tet10", "column_tet10", "cube_tet4"] {
        let model = gom::read(&std::fs::read(path(&format!("{m}.GOM"))).unwrap(), m).unwrap();
        model
            .check_shapes(1e-12)
            .unwrap_or_else(|e| panic!("{m}: {e}"));
        let mut vol = 0.0;
        for e in 0..model.element_count() {
            let el = model.element(e);
            let x = |k: usize| model.node(el[k] as usize);
            vol += geometry::tet_det(x(0), x(2), x(3), x(1)) / 6.0;
        }
        let want = if m.starts_with("cube") { 1.0 } else { 0.01 };
        assert!((vol - want).abs() < 1e-9 * want, "{m}: volume {vol}");
    }
}

#[test]
fn triangles_are_counter_clockwise() {
    let model = gom::read(&std::fs::read(path("square_tri3.GOM")).unwrap(), "sq").unwrap();
    model.check_shapes(1e-12).unwrap();
}
