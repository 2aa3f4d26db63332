//! `--reorder` refuses a mesh whose coordinates cannot be ordered (sfcb's check), naming the
//! input files and the axis, instead of ordering every element onto one curve key.

use mpm_shared::{generate, ElementType};
use mpm_solve::input::case::Reorder;

#[test]
fn reorder_refuses_an_extent_that_is_not_finite() {
    let dir = tempfile::tempdir().unwrap();
    let mut model = generate::box_mesh([1, 1, 1], [1.0; 3], ElementType::Tet4);
    // Nodes 1 and 2 at z = -1e308 and +1e308: finite, but 2e308 apart.
    model.coords[2] = -1e308;
    model.coords[5] = 1e308;
    let gom = dir.path().join("far.GOM");
    mpm_shared::write_gom_file(&model, &gom).unwrap();
    let text = std::fs::read_to_string(&gom).unwrap().replacen(
        "$$STARTELMMAT",
        "$$MATERIAL_TYPE\ndry_material\n$$POROSITY_SOLID\n0.0\n$$DENSITY_SOLID\n1000\n$$MATERIAL_MODEL_SOLID\nlinear_elasticity\n$$YOUNG_MODULUS\n1000\n$$POISSON_RATIO\n0.0\n$$STARTELMMAT",
        1,
    );
    std::fs::write(&gom, text).unwrap();
    let cps = dir.path().join("far.CPS_001");
    std::fs::write(
        &cps,
        "### Anura3D_2021 ###\n$$TIME_PER_LOADSTEP\n1e-4\n$$COMPUTATION_METHOD\nMPM-MP\n$$END\n",
    )
    .unwrap();
    let (case, _) = mpm_solve::input::anura3d::load(&gom, &cps).unwrap();
    assert!(case.clone().reordered(Reorder::None).is_ok());
    for how in [Reorder::Morton, Reorder::Hilbert] {
        let e = case.clone().reordered(how).unwrap_err().to_string();
        assert!(e.contains("far.GOM") && e.contains("--reorder"), "{e}");
        assert!(e.contains("the z extent"), "{e}");
    }
}
