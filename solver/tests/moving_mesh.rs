//! Anura3D's moving mesh (`step::moving_mesh`) on GOM input: a block pushed down a soil column
//! at a prescribed velocity, the mesh around it following, the soil ahead compressed and the
//! empty mesh behind stretched. Against Anura3D itself (`ANURA3D_ORACLE`), point by point at
//! every load step; the 2D foundation benchmark 4001 run for four load steps against the 2D
//! oracle (`ANURA3D_ORACLE_2D`, `ANURA3D_BENCHMARKS`); a run killed and resumed ends
//! byte-identical; a mesh moved past its room stops with the element named. The comparisons
//! say "skipped" when their variables are unset.

mod common;

use std::path::{Path, PathBuf};

use common::gom;

/// The block's speed (m/s, downwards).
const SPEED: f64 = 0.1;

/// Writes `dir/NAME.GOM` and `dir/NAME.CPS_001`: a 1 × 4 × 1 m column of 1 × 8 × 1 cells,
/// soil (material 1) up to y = 2.5 m, a stiffer block (material 2) from 2.5 to 3 m moved down
/// at [`SPEED`] by a prescribed velocity on its points, empty elements above. The moving box is
/// the block's, the compressing box the soil's, the extending box the empty part's (with `up`,
/// the block is pulled up instead, and the boxes swap: the soil's extends, the empty part's is
/// compressed). Sides fixed normally, the base fixed; gravity. `load_steps` of `duration` s.
fn block_in_column(
    dir: &Path,
    name: &str,
    load_steps: u32,
    duration: f64,
    up: bool,
) -> (PathBuf, PathBuf) {
    let model = gom::box_model(
        [1, 8, 1],
        [1.0, 4.0, 1.0],
        &[
            gom::Material {
                name: "soil",
                porosity: 0.3,
                density: 1800.0,
                young: 1000.0,
                saturated: false,
            },
            gom::Material {
                name: "block",
                porosity: 0.0,
                density: 2000.0,
                young: 20000.0,
                saturated: false,
            },
        ],
        |c| match c[1] {
            y if y < 2.5 => 1,
            y if y < 3.0 => 2,
            _ => 0,
        },
        |p| {
            let side = |v: f64| v.abs() < 1e-9 || (v - 1.0).abs() < 1e-9;
            [side(p[0]), p[1].abs() < 1e-9, side(p[2])]
        },
    );
    let corners = |lo: f64, hi: f64| -> String {
        gom::box_corners(&model, [0.0, lo, 0.0], [1.0, hi, 1.0])
            .iter()
            .map(|n| format!("{n}\n"))
            .collect()
    };
    let (extending, compressing) = if up {
        (corners(0.0, 2.5), corners(3.0, 4.0))
    } else {
        (corners(3.0, 4.0), corners(0.0, 2.5))
    };
    let extra = format!(
        "{}$$EXTENDING_MESH_CORNER_NODES\n{extending}$$COMPRESSING_MESH_CORNER_NODES\n{compressing}$$MOVING_MESH_CORNER_NODES\n{}$$MOVING_MESH_DIRECTION\ny-direction\n$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n2\n",
        gom::prescribed_section(
            &gom::elements_of(&model, 2),
            &[0, 1, 0],
            &[0.0, if up { SPEED } else { -SPEED }, 0.0]
        ),
        corners(2.5, 3.0),
    );
    gom::write(
        dir,
        name,
        &model,
        &extra,
        &[
            ("NUMBER_OF_LOADSTEPS", &load_steps.to_string()),
            ("TIME_PER_LOADSTEP", &duration.to_string()),
        ],
    )
}

#[test]
fn the_block_and_its_mesh_move_as_in_anura3d() {
    let Some(bin) = common::oracle("moving mesh against Anura3D") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    block_in_column(dir.path(), "block", 4, 0.5, false);
    let out = common::agrees_with_anura3d(
        &bin,
        dir.path(),
        "block",
        4,
        "block in column, 4 load steps",
    );
    // The run says it completed (no guard rail tripped on the moved mesh).
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(json["status"], "completed", "{json}");
}

#[test]
fn the_2d_footing_benchmark_moves_as_in_anura3d_over_four_load_steps() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let oracle = mpm_shared::suite::anura3d_oracle_2d(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let suite = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let (Some(bin), Some(suite)) = (oracle, suite) else {
        mpm_shared::suite::skipped(
            "2D moving mesh against Anura3D (ANURA3D_ORACLE_2D or ANURA3D_BENCHMARKS not set)",
        );
        return;
    };
    // 4001: a rough footing (its points' velocity prescribed, 0.5 m/s, in load-step stairs)
    // pushed into Mohr-Coulomb soil under K0 stresses, MPM-MIXED with strain smoothing; run
    // four load steps of 0.05 s instead of the benchmark's one time step.
    let name = "4001_foundation_k0_movingmesh_prescribedveloMP_step";
    let src = suite
        .join("Benchmarks/Pre-Commit_Tests")
        .join(name)
        .join(format!("{name}.A3D"));
    common::benchmark_agrees_with_anura3d(
        &bin,
        &src,
        name,
        &[
            ("$$QUASISTATIC_CONVERGENCE", "0"),
            ("$$TIME_PER_LOADSTEP", "0.05"),
            ("$$NUMBER_OF_LOADSTEPS", "4"),
        ],
        4,
        "4001 over 4 load steps",
    );
}

#[test]
fn a_moving_mesh_run_killed_and_resumed_ends_as_the_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let (gom, _) = block_in_column(dir.path(), "block", 4, 0.25, false);
    common::killed_and_resumed_match(&gom, dir.path(), &[("150", "7"), ("230", "50")], "3");
}

#[test]
fn a_mesh_moved_past_its_room_stops_naming_the_element() {
    let dir = tempfile::tempdir().unwrap();
    // Pulled up at 0.1 m/s for 15 s, the block would go 1.5 m up an empty box 1 m high.
    let (gom, _) = block_in_column(dir.path(), "block", 1, 15.0, true);
    let out = dir.path().join("out");
    let o = common::solve(&gom, &out, &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("the moving mesh turned element") && err.contains("inside out"),
        "{err}"
    );
}
