//! Morton ordering: invariants on every bundled (and, when available, every Anura3D) mesh,
//! golden files, idempotence and thread independence.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use mpm_shared::model::{Body, IdKind, Token};
use mpm_shared::{gom, Model};
use sfcb::order;

fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

fn models() -> Vec<(String, Model)> {
    let mut v: Vec<(String, Model)> = [
        "cube_tet4.GOM",
        "cube_tet10.GOM",
        "column_tet10.GOM",
        "square_tri3.GOM",
    ]
    .iter()
    .map(|n| {
        (
            n.to_string(),
            gom::read(&std::fs::read(testdata(n)).unwrap(), n).unwrap(),
        )
    })
    .collect();
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    if found.is_none() {
        mpm_shared::suite::skipped("ordering the suite's meshes (ANURA3D_BENCHMARKS not set)");
    }
    if let Some(root) = found {
        let mut stack = vec![root];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                let n = p.file_name().unwrap().to_string_lossy().to_string();
                if p.is_dir() {
                    stack.push(p);
                } else if n.ends_with(".GOM") || n.contains(".GOM_stage") {
                    let m = gom::read(&std::fs::read(&p).unwrap(), &n).unwrap();
                    v.push((p.display().to_string(), m));
                }
            }
        }
    }
    v
}

fn opts(m: &Model, curve: order::Curve) -> order::Options {
    order::Options {
        curve,
        levels: if m.dimension.coords() == 3 { 21 } else { 31 },
        cubic: true,
    }
}

#[test]
fn ordering_is_a_bijection_and_everything_follows_its_element_and_nodes() {
    let mut refused = 0;
    for ((name, m), curve) in models().into_iter().flat_map(|x| {
        [
            (x.clone(), order::Curve::Morton),
            (x, order::Curve::Hilbert),
        ]
    }) {
        let ord = order::order(&m, opts(&m, curve)).unwrap();
        assert!(
            mpm_shared::model::inverse(&ord.order, m.element_count()).is_some(),
            "{name}"
        );
        assert!(
            mpm_shared::model::inverse(&ord.node_new, m.node_count()).is_some(),
            "{name}"
        );
        assert!(
            ord.keys.windows(2).all(|w| w[0] <= w[1]),
            "{name}: keys not sorted"
        );
        let r = match m.reordered(&ord.order, &ord.node_new) {
            Ok(r) => r,
            Err(e) => {
                assert!(m.first_unremappable().is_some(), "{name}: {e}");
                refused += 1;
                continue;
            }
        };
        // Each element keeps its vertex coordinates in the same local order.
        for (new, &old) in ord.order.iter().enumerate() {
            for (a, b) in r.element(new).iter().zip(m.element(old as usize)) {
                assert_eq!(r.node(*a as usize), m.node(*b as usize), "{name}");
            }
        }
        // Element-ordered sections follow; node and element ids in tables follow.
        for (s_old, s_new) in m.sections.iter().zip(&r.sections) {
            match (&s_old.body, &s_new.body) {
                (Body::PerElement(a), Body::PerElement(b)) => {
                    for (new, &old) in ord.order.iter().enumerate() {
                        assert_eq!(b.row(new), a.row(old as usize), "{name} {}", s_old.keyword);
                    }
                }
                (Body::Table { rows: a, refs, .. }, Body::Table { rows: b, .. }) => {
                    let cols = refs.columns();
                    for (ra, rb) in a.rows().zip(b.rows()) {
                        for j in 0..ra.len() {
                            let kind = cols.iter().find(|c| c.0 == j).map(|c| c.1);
                            match (kind, &ra[j], &rb[j]) {
                                (Some(IdKind::Node), Token::Int(x), Token::Int(y)) => assert_eq!(
                                    m.node(*x as usize - 1),
                                    r.node(*y as usize - 1),
                                    "{name} {}",
                                    s_old.keyword
                                ),
                                (Some(IdKind::Element), Token::Int(x), Token::Int(y)) => {
                                    assert_eq!(
                                        ord.order[*y as usize - 1] as i64,
                                        x - 1,
                                        "{name} {}",
                                        s_old.keyword
                                    )
                                }
                                _ => assert_eq!(ra[j], rb[j], "{name} {}", s_old.keyword),
                            }
                        }
                    }
                }
                (a, b) => assert_eq!(a, b, "{name} {}", s_old.keyword),
            }
        }
        // Ordering the ordered model changes nothing.
        let again = order::order(&r, opts(&r, curve)).unwrap();
        let rr = r.reordered(&again.order, &again.node_new).unwrap();
        assert!(gom::write(&rr) == gom::write(&r), "{name}: not idempotent");
    }
    // Every Anura3D file is understood well enough to be renumbered.
    assert_eq!(refused, 0, "{refused} refused");
}

#[test]
fn golden_files_and_thread_independence() {
    let dir = tempfile::tempdir().unwrap();
    for (m, curve) in [
        ("cube_tet10", "morton"),
        ("square_tri3", "morton"),
        ("cube_tet10", "hilbert"),
        ("square_tri3", "hilbert"),
    ] {
        let golden = std::fs::read(testdata(&format!("{m}.{curve}.GOM"))).unwrap();
        for threads in ["1", "2", "3"] {
            let out = dir.path().join(format!("{m}_{threads}.GOM"));
            Command::cargo_bin("sfcb")
                .unwrap()
                .arg(testdata(&format!("{m}.GOM")))
                .arg(&out)
                .args(["--threads", threads, "--curve", curve])
                .assert()
                .success();
            assert!(
                std::fs::read(&out).unwrap() == golden,
                "{m} with {threads} threads differs from the golden file"
            );
        }
        // From the Gmsh mesh directly, and through a pipe, the same bytes.
        let out = Command::cargo_bin("sfcb")
            .unwrap()
            .arg(testdata(&format!("{m}.msh")))
            .arg("-")
            .args(["--curve", curve])
            .output()
            .unwrap();
        assert!(out.stdout == golden, "{m}: msh input differs");
    }
}

#[test]
fn partitions_are_contiguous_and_balanced() {
    let m = gom::read(&std::fs::read(testdata("column_tet10.GOM")).unwrap(), "c").unwrap();
    let w = order::weights(&m);
    for p in [1u32, 2, 3, 7, 16] {
        let parts = order::partitions(&w, p);
        assert!(parts.windows(2).all(|x| x[0] <= x[1]));
        assert_eq!(*parts.last().unwrap(), p - 1);
        let mut count = vec![0usize; p as usize];
        parts.iter().for_each(|&q| count[q as usize] += 1);
        let (lo, hi) = (count.iter().min().unwrap(), count.iter().max().unwrap());
        assert!(hi - lo <= 1, "{p} parts: {count:?}");
    }
}

#[test]
fn report_has_timings_locality_and_partition_quality() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("sfcb")
        .unwrap()
        .arg(testdata("column_tet10.msh"))
        .arg(dir.path().join("c.vtu"))
        .args(["--partitions", "4", "--report", "-"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for phase in [
        "read", "keys", "sort", "renumber", "remap", "write", "total",
    ] {
        assert!(r["seconds"][phase].as_f64().unwrap() >= 0.0, "{phase}");
    }
    let (before, after) = (&r["locality"]["before"], &r["locality"]["after"]);
    // Gmsh numbers nodes by geometric entity, so the curve order must tighten elements.
    assert!(
        after["mean_id_spread"].as_f64().unwrap()
            < 0.5 * before["mean_id_spread"].as_f64().unwrap()
    );
    assert!(
        after["mean_cache_lines"].as_f64().unwrap() < before["mean_cache_lines"].as_f64().unwrap()
    );
    let p = &r["partitions"];
    assert_eq!(p["parts"], 4);
    assert_eq!(p["pieces"].as_array().unwrap().len(), 4);
    assert!(p["edge_cut"].as_u64().unwrap() > 0);
    assert!(p["imbalance"].as_f64().unwrap() < 1.05);
    // The VTU carries the partition field.
    let vtu = std::fs::read(dir.path().join("c.vtu")).unwrap();
    assert!(String::from_utf8_lossy(&vtu[..3000]).contains("Name=\"partition\""));
}

#[test]
fn merge_pieces_leaves_one_piece_per_part() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str]| -> serde_json::Value {
        let out = Command::cargo_bin("sfcb")
            .unwrap()
            .arg(testdata("column_tet10.msh"))
            .arg(dir.path().join("c.vtu"))
            .args(["--partitions", "8", "--report", "-"])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = run(&[]);
    let merged = run(&["--merge-pieces"]);
    assert!(plain["partitions"]["extra_pieces"].as_u64().unwrap() > 0);
    assert_eq!(merged["partitions"]["extra_pieces"], 0);
    assert!(merged["partitions"]["edge_cut"].as_u64() <= plain["partitions"]["edge_cut"].as_u64());
    // --merge-pieces needs --partitions.
    Command::cargo_bin("sfcb")
        .unwrap()
        .arg(testdata("column_tet10.msh"))
        .arg(dir.path().join("d.GOM"))
        .arg("--merge-pieces")
        .assert()
        .failure();
}

mod properties {
    use super::*;
    use mpm_shared::{generate, ElementType};
    use proptest::prelude::*;

    fn shuffle(n: usize, mut seed: u64) -> Vec<u32> {
        let mut p: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            p.swap(i, ((seed >> 33) % (i as u64 + 1)) as usize);
        }
        p
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

        /// Whatever the input numbering, ordering gives a bijection that keeps every element's
        /// vertices, is idempotent, and (without key ties) gives the same file.
        #[test]
        fn ordering_forgets_the_input_numbering(
            nx in 1usize..5, ny in 1usize..5, nz in 1usize..4,
            sx in 0.1f64..10.0, sy in 0.1f64..10.0,
            quadratic in any::<bool>(), hilbert in any::<bool>(),
            s1 in any::<u64>(), s2 in any::<u64>(),
        ) {
            let et = if quadratic { ElementType::Tet10 } else { ElementType::Tet4 };
            let base = generate::box_mesh([nx, ny, nz], [sx, sy, 1.0], et);
            let curve = if hilbert { order::Curve::Hilbert } else { order::Curve::Morton };
            let mut outputs = Vec::new();
            for seed in [s1, s2] {
                let m = base.reordered(&shuffle(base.element_count(), seed), &shuffle(base.node_count(), !seed)).unwrap();
                let o = order::order(&m, opts(&m, curve)).unwrap();
                prop_assert!(mpm_shared::model::inverse(&o.order, m.element_count()).is_some());
                prop_assert!(mpm_shared::model::inverse(&o.node_new, m.node_count()).is_some());
                let r = m.reordered(&o.order, &o.node_new).unwrap();
                for (new, &old) in o.order.iter().enumerate() {
                    for (a, b) in r.element(new).iter().zip(m.element(old as usize)) {
                        prop_assert_eq!(r.node(*a as usize), m.node(*b as usize));
                    }
                }
                let again = order::order(&r, opts(&r, curve)).unwrap();
                let rr = r.reordered(&again.order, &again.node_new).unwrap();
                let bytes = gom::write(&r);
                prop_assert!(gom::write(&rr) == bytes, "not idempotent");
                outputs.push((o.shared_keys, bytes));
            }
            if outputs[0].0 == 0 && outputs[1].0 == 0 {
                prop_assert!(outputs[0].1 == outputs[1].1, "output depends on the input numbering");
            }
        }
    }
}

#[test]
fn cps_material_points_follow_their_elements() {
    use mpm_shared::{generate, ElementType};
    let dir = tempfile::tempdir().unwrap();
    // A box with 4 material points per element, numbered shuffled so that ordering moves them.
    let base = generate::box_mesh([3, 2, 2], [1.0, 1.0, 1.0], ElementType::Tet10);
    let n = base.element_count();
    let perm: Vec<u32> = (0..n as u32).rev().collect();
    let mut m = base
        .reordered(&perm, &(0..base.node_count() as u32).collect::<Vec<_>>())
        .unwrap();
    // A GOM numbered this way from elsewhere: no record of another input order, so its own
    // order is the input's.
    m.sections
        .retain(|s| s.keyword != mpm_shared::points::INPUT_ELEMENTS);
    let gom_in = dir.path().join("in.GOM");
    mpm_shared::write_gom_file(&m, &gom_in).unwrap();
    let ids: Vec<u32> = vec![1, 2, 5, 40, 4 * n as u32];
    let mut cps = String::from("### Anura3D_2021 ###\n$$NUMBER_OF_LOADSTEPS\n1\n");
    cps.push_str(&format!(
        "$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n{}\n$$OUTPUT_MATERIAL_POINTS\n",
        ids.len()
    ));
    for i in &ids {
        cps.push_str(&format!("{i}\n"));
    }
    cps.push_str("$$END\n");
    let cps_in = dir.path().join("in.CPS_001");
    std::fs::write(&cps_in, cps).unwrap();
    let (gom_out, cps_out) = (dir.path().join("out.GOM"), dir.path().join("out.CPS_001"));
    Command::cargo_bin("sfcb")
        .unwrap()
        .arg(&gom_in)
        .arg(&gom_out)
        .arg("--cps")
        .arg(&cps_in)
        .arg(&cps_out)
        .assert()
        .success();
    let out = gom::read(&std::fs::read(&gom_out).unwrap(), "out").unwrap();
    let (c, _) = mpm_shared::cps::Cps::read(&std::fs::read(&cps_out).unwrap(), "out.CPS").unwrap();
    let new_ids = c.output_material_points().unwrap();
    assert_eq!(new_ids.len(), ids.len());
    let centroid = |model: &Model, e: usize| {
        let mut c = [0.0; 3];
        order::centroid(model, e, &mut c);
        c
    };
    for (old, new) in ids.iter().zip(&new_ids) {
        // 4 points per element: point k lies in element (k - 1) / 4, at the same slot.
        let (eo, en) = ((*old as usize - 1) / 4, (*new as usize - 1) / 4);
        assert_eq!(centroid(&m, eo), centroid(&out, en), "point {old} -> {new}");
        assert_eq!((*old - 1) % 4, (*new - 1) % 4);
    }
    // The written pair says which numbering its ids use, and mpm-solve's reading of them gives
    // back the input ids.
    let tag = c.get(mpm_shared::points::CPS_FILE_ORDER).expect("marked");
    let input_of = out
        .input_elements()
        .unwrap()
        .expect("input numbers recorded");
    assert_eq!(tag.lines, [mpm_shared::points::file_order_tag(&input_of)]);
    assert_eq!(mpm_shared::points::cps_input_ids(&c, &out).unwrap(), ids);
}

#[test]
fn cps_ids_of_an_ordered_gom_are_its_input_ids() {
    use mpm_shared::{generate, ElementType};
    let dir = tempfile::tempdir().unwrap();
    let base = generate::box_mesh([3, 2, 2], [1.0, 1.0, 1.0], ElementType::Tet4);
    let n = base.element_count();
    let perm: Vec<u32> = (0..n as u32).rev().collect();
    // An ordered GOM (it records base's order) and a CPS naming points of base.
    let m = base
        .reordered(&perm, &(0..base.node_count() as u32).collect::<Vec<_>>())
        .unwrap();
    let gom_in = dir.path().join("in.GOM");
    mpm_shared::write_gom_file(&m, &gom_in).unwrap();
    let ids: Vec<u32> = vec![1, 7, 4 * n as u32];
    let cps = format!(
        "### Anura3D_2021 ###\n$$OUTPUT_NUMBER_OF_MATERIAL_POINTS\n3\n$$OUTPUT_MATERIAL_POINTS\n{}\n$$END\n",
        ids.iter().map(|i| i.to_string()).collect::<Vec<_>>().join("\n")
    );
    let cps_in = dir.path().join("in.CPS_001");
    std::fs::write(&cps_in, cps).unwrap();
    let (gom_out, cps_out) = (dir.path().join("out.GOM"), dir.path().join("out.CPS_001"));
    Command::cargo_bin("sfcb")
        .unwrap()
        .args([&gom_in, &gom_out])
        .arg("--curve")
        .arg("hilbert")
        .arg("--cps")
        .args([&cps_in, &cps_out])
        .assert()
        .success();
    let out = gom::read(&std::fs::read(&gom_out).unwrap(), "out").unwrap();
    let (c, _) = mpm_shared::cps::Cps::read(&std::fs::read(&cps_out).unwrap(), "out.CPS").unwrap();
    let centroid = |model: &Model, e: usize| {
        let mut c = [0.0; 3];
        order::centroid(model, e, &mut c);
        c
    };
    for (old, new) in ids.iter().zip(c.output_material_points().unwrap()) {
        assert_eq!(
            centroid(&base, (*old as usize - 1) / 4),
            centroid(&out, (new as usize - 1) / 4),
            "point {old} -> {new}"
        );
    }
    assert_eq!(mpm_shared::points::cps_input_ids(&c, &out).unwrap(), ids);
    // The remapped CPS does not fit the GOM it came from: refused, naming the fix.
    let e = mpm_shared::points::cps_input_ids(&c, &m)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("another ordered GOM") && e.contains("sfcb --cps"),
        "{e}"
    );
    let e = mpm_shared::points::cps_input_ids(&c, &base)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("carries no $$START_INPUT_ELEMENT_NUMBERS"),
        "{e}"
    );
}
