//! The bundled Gmsh meshes convert to the bundled GOM files, keep Gmsh's geometry, and come out
//! positively oriented with every mid-edge node at its edge's midpoint.

use std::path::Path;

use mpm_shared::{gom, msh, ElementType};

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
        let mut vol = 0.0;
        for e in 0..model.element_count() {
            let el = model.element(e);
            let x = |k: usize| model.node(el[k] as usize);
            let det = msh::tet_det(x(0), x(2), x(3), x(1));
            assert!(det > 0.0, "{m}: element {} det {det}", e + 1);
            vol += det / 6.0;
            if model.element_type == ElementType::Tet10 {
                for (mid, (a, b)) in [
                    (4, (0, 1)),
                    (5, (1, 2)),
                    (6, (0, 2)),
                    (7, (0, 3)),
                    (8, (1, 3)),
                    (9, (2, 3)),
                ] {
                    for d in 0..3 {
                        assert!(
                            (x(mid)[d] - 0.5 * (x(a)[d] + x(b)[d])).abs() < 1e-12,
                            "{m}: element {} node {}",
                            e + 1,
                            mid + 1
                        );
                    }
                }
            }
        }
        let want = if m.starts_with("cube") { 1.0 } else { 0.01 };
        assert!((vol - want).abs() < 1e-9 * want, "{m}: volume {vol}");
    }
}

#[test]
fn triangles_are_counter_clockwise() {
    let model = gom::read(&std::fs::read(path("square_tri3.GOM")).unwrap(), "sq").unwrap();
    let mut area = 0.0;
    for e in 0..model.element_count() {
        let el = model.element(e);
        let (a, b, c) = (
            model.node(el[0] as usize),
            model.node(el[1] as usize),
            model.node(el[2] as usize),
        );
        let a2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(a2 > 0.0);
        area += a2 / 2.0;
    }
    assert!((area - 1.0).abs() < 1e-12);
}
