//! Velocities prescribed on material points: reading them from a GOM (and refusing what is not
//! modelled), and a column whose top elements are pushed down at constant speed.

use mpm_shared::{generate, ElementType, Model};
use mpm_solve::driver::engine::Engine;
use mpm_solve::element::tet4::Tet4;
use mpm_solve::input::case::{Case, LoadCurve, MaterialSpec, Reorder};
use mpm_solve::step::prescribed::{Prescribed, PrescribedElement, PrescribedVelocity};

/// A GOM of a 1 × 4 × 1 column of 24 dry linear elastic elements (4 points each) with the
/// sections `extra` inserted before the materials.
fn column_gom(extra: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.GOM");
    let model = generate::box_mesh([1, 4, 1], [1.0, 4.0, 1.0], ElementType::Tet4);
    mpm_shared::write_gom_file(&model, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let material = "$$MATERIAL_TYPE\ndry_material\n$$POROSITY_SOLID\n0.0\n$$DENSITY_SOLID\n1000\n$$MATERIAL_MODEL_SOLID\nlinear_elasticity\n$$YOUNG_MODULUS\n1000\n$$POISSON_RATIO\n0.0\n$$STARTELMMAT";
    assert!(text.contains("$$NUMBER_OF_MATERIALS") && text.contains("$$STARTELMMAT"));
    text.replacen(
        "$$NUMBER_OF_MATERIALS",
        &format!("{extra}$$NUMBER_OF_MATERIALS"),
        1,
    )
    .replacen("$$STARTELMMAT", material, 1)
}

const CPS: &str = "### Anura3D_2021 ###\n$$NUMBER_OF_LOADSTEPS\n1\n$$TIME_PER_LOADSTEP\n0.1\n$$COMPUTATION_METHOD\nMPM-MIXED\n$$GRAVITY_LOAD\noff 0.0 1.0\n$$PRESCRIBED_VELOCITY\nstep 1.0 1.0\n$$CONTACT_FORMULATION\n0\n$$END\n";

/// The top cell's six elements (ids 19-24) pushed down at 0.2 m/s.
fn rows(flags: &[&str]) -> String {
    let mut s = format!(
        "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME\n{}\n",
        flags.len()
    );
    for (k, f) in flags.iter().enumerate() {
        s += &format!("{} {f} 0.0 -0.2 0.0\n", 19 + k);
    }
    s
}

/// Loads `gom` with `cps`; the error's text on failure.
fn load(gom: &str, cps: &str) -> Result<Case, String> {
    let dir = tempfile::tempdir().unwrap();
    let (g, c) = (dir.path().join("c.GOM"), dir.path().join("c.CPS_001"));
    std::fs::write(&g, gom).unwrap();
    std::fs::write(&c, cps).unwrap();
    mpm_solve::input::anura3d::load(&g, &c)
        .map(|(case, _)| case)
        .map_err(|e| e.to_string())
}

fn centroid_y(model: &Model, e: usize) -> f64 {
    model.element(e)[..4]
        .iter()
        .map(|&n| model.node(n as usize)[1])
        .sum::<f64>()
        / 4.0
}

#[test]
fn gom_rows_are_read_and_what_is_not_modelled_is_refused() {
    let six = ["0 1 0"; 6];
    let case = load(&column_gom(&rows(&six)), CPS).unwrap();
    let pv = case
        .boundary
        .prescribed
        .as_ref()
        .expect("prescribed velocities");
    assert_eq!(pv.rows.len(), 6);
    assert_eq!(pv.multiplier(0.05), 1.0);
    for r in &pv.rows {
        assert_eq!(r.directions, [false, true, false]);
        assert_eq!(r.velocity, [0.0, -0.2, 0.0]);
        assert!(centroid_y(&case.model, r.element as usize) > 3.0);
    }
    // The rows follow a reordering of the elements.
    let moved = case.clone().reordered(Reorder::Hilbert).unwrap();
    let elements: Vec<u32> = moved
        .boundary
        .prescribed
        .as_ref()
        .unwrap()
        .rows
        .iter()
        .map(|r| r.element)
        .collect();
    assert_ne!(
        elements,
        pv.rows.iter().map(|r| r.element).collect::<Vec<_>>()
    );
    for &e in &elements {
        assert!(centroid_y(&moved.model, e as usize) > 3.0);
    }
    // An off multiplier switches the rows off, as in Anura3D.
    let off = CPS.replace("step 1.0 1.0", "off 0.0 1.0");
    assert!(load(&column_gom(&rows(&six)), &off)
        .unwrap()
        .boundary
        .prescribed
        .is_none());
    // Rows with other components (Anura3D would add the earlier rows' to later points).
    let err = load(
        &column_gom(&rows(&[
            "0 1 0", "1 1 0", "0 1 0", "0 1 0", "0 1 0", "0 1 0",
        ])),
        CPS,
    )
    .unwrap_err();
    assert!(
        err.contains("PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME") && err.contains("row 2"),
        "{err}"
    );
    // An element outside the mesh, a flag other than 0 or 1.
    let err = load(
        &column_gom(&rows(&six).replace("24 0 1 0", "25 0 1 0")),
        CPS,
    )
    .unwrap_err();
    assert!(err.contains("25"), "{err}");
    let err = load(&column_gom(&rows(&["0 2 0"])), CPS).unwrap_err();
    assert!(err.contains("0 or 1"), "{err}");
    // Volumes and surfaces at once (Anura3D refuses this too).
    let both = rows(&six)
        + &rows(&six).replace(
            "PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
            "PRESCRIBED_MATERIAL_POINT_VELOCITY_SURFACE",
        );
    let err = load(&column_gom(&both), CPS).unwrap_err();
    assert!(err.contains("more than once"), "{err}");
    // Contact without its structure, and a moving mesh without a box to compress or stretch:
    // refused, naming what is missing.
    let err = load(
        &column_gom(&rows(&six)),
        &CPS.replace("$$CONTACT_FORMULATION\n0", "$$CONTACT_FORMULATION\n1"),
    )
    .unwrap_err();
    assert!(err.contains("$$START_CONTACT_VOLUME: missing"), "{err}");
    let mesh = "$$MOVING_MESH_CORNER_NODES\n1\n2\n3\n4\n5\n6\n7\n8\n$$MOVING_MESH_DIRECTION\ny-direction\n$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n1\n";
    let err = load(&column_gom(&(rows(&six) + mesh)), CPS).unwrap_err();
    assert!(
        err.contains("$$EXTENDING_MESH_CORNER_NODES") && err.contains("compressing box"),
        "{err}"
    );
    // What switches nothing on is accepted: contact volumes with contact off, a direction and a
    // reference material without corner nodes.
    let inert = "$$START_CONTACT_VOLUME\n1\n19 1 \"soil\" 0 0 \"NAN\" 0.0 0.0 \"NAN\" 0.0 0.0 \"NAN\" 0.0 0.0\n$$MOVING_MESH_DIRECTION\ny-direction\n$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n1\n";
    assert!(load(&column_gom(&(rows(&six) + inert)), CPS).is_ok());
}

/// A laterally confined column 1 × 4 × 1 m (2 × 8 × 2 cells), fixed at the bottom, whose top
/// row of cells is pushed down at `speed`.
fn pushed_column(speed: f64) -> Case {
    let model = generate::box_mesh([2, 8, 2], [1.0, 4.0, 1.0], ElementType::Tet4);
    let fixed = mpm_solve::input::case::confined_box(&model);
    let material = MaterialSpec::new("soil", 1000.0, 1000.0, 0.0).unwrap();
    let mut case = Case::single_material("pushed", model, material, 4, fixed);
    let rows = (0..case.model.element_count())
        .filter(|&e| centroid_y(&case.model, e) > 3.5)
        .map(|e| PrescribedElement {
            element: e as u32,
            directions: [false, true, false],
            velocity: [0.0, -speed, 0.0],
        })
        .collect();
    case.boundary.prescribed = Some(PrescribedVelocity {
        name: "top".into(),
        rows,
        scale: 1.0,
        curve: LoadCurve::Step,
    });
    case.time.end_time = 0.4;
    case.time.output_times = vec![0.2, 0.4];
    case
}

/// Runs `case` and records, at each output, the time and every point's (id, x, u, v, stress).
#[allow(clippy::type_complexity)]
fn run(
    case: &Case,
) -> (
    Engine<f64>,
    Vec<(f64, Vec<(u32, [f64; 3], [f64; 3], [f64; 3], [f64; 6])>)>,
) {
    let dir = tempfile::tempdir().unwrap();
    let mut frames = Vec::new();
    let engine = mpm_solve::driver::run::run_observed::<f64, Tet4>(
        case,
        dir.path(),
        &Default::default(),
        &mut |e| {
            let p = &e.particles;
            let mut pts: Vec<_> = (0..p.len())
                .map(|i| (p.id[i], p.x[i], p.u[i], p.v[i], p.stress[i]))
                .collect();
            pts.sort_by_key(|q| q.0);
            frames.push((e.time, pts));
        },
    )
    .unwrap();
    (engine, frames)
}

#[test]
fn pushed_points_and_nodes_move_exactly_with_the_prescribed_velocity() {
    let speed = 0.1;
    let case = pushed_column(speed);
    // The marked points: those placed in the listed elements.
    let listed: Vec<u32> = case
        .boundary
        .prescribed
        .as_ref()
        .unwrap()
        .rows
        .iter()
        .map(|r| r.element)
        .collect();
    let start = Engine::<f64, Tet4>::new(&case, false).unwrap();
    let marked: Vec<u32> = (0..start.particles.len())
        .filter(|&i| listed.contains(&start.particles.element[i]))
        .map(|i| start.particles.id[i])
        .collect();
    assert_eq!(marked.len(), 4 * listed.len());
    assert_eq!(
        start
            .constraints
            .find::<Prescribed<f64>>()
            .unwrap()
            .marked_points(),
        marked.len()
    );
    let (engine, frames) = run(&case);
    assert!(engine.steps > 20, "{} steps", engine.steps);
    for (t, pts) in &frames {
        for &(id, _, u, v, _) in pts {
            if marked.contains(&id) {
                assert_eq!(v[1], -speed, "point {id} at t = {t}");
                let want = -speed * t;
                assert!(
                    (u[1] - want).abs() <= 1e-12 * want.abs(),
                    "point {id}: u_y {} vs {want}",
                    u[1]
                );
            }
        }
    }
    // The nodes of the listed elements moved at exactly the prescribed speed in the last step.
    let pr = engine.constraints.find::<Prescribed<f64>>().unwrap();
    assert_eq!(pr.masked_nodes().len(), 18);
    for &n in pr.masked_nodes() {
        assert_eq!(engine.grid.vel[n as usize][1], -speed, "node {n}");
    }
    // The column below is compressed by the push (its internal force on the pushed nodes is
    // what the zeroed accelerations discard).
    let (t, pts) = frames.last().unwrap();
    let below: Vec<f64> = pts
        .iter()
        .filter(|q| !marked.contains(&q.0) && q.1[1] > 3.0)
        .map(|q| q.4[1])
        .collect();
    assert!(!below.is_empty());
    assert!(
        below.iter().all(|&s| s < 0.0),
        "t = {t}: σyy below the pushed cells {below:?}"
    );

    // The same for any thread count, bit for bit.
    for threads in [1, 3] {
        let mut c = case.clone();
        c.run.engine.threads = threads;
        let (_, f) = run(&c);
        assert!(f == frames, "{threads} threads differ");
    }
    // And, but for round-off, in the elements' space-filling-curve order.
    let (_, f) = run(&case.clone().reordered(Reorder::Hilbert).unwrap());
    let (a, b) = (&frames.last().unwrap().1, &f.last().unwrap().1);
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        assert_eq!(p.0, q.0);
        for d in 0..3 {
            assert!(
                (p.2[d] - q.2[d]).abs() < 1e-9,
                "point {}: u {:?} vs {:?}",
                p.0,
                p.2,
                q.2
            );
        }
        if marked.contains(&p.0) {
            assert_eq!(q.3[1], -speed);
        }
    }
}

/// `$$PRESCRIBED_NODAL_VELOCITY_*` rows on the top nodes (y = 4) of the column GOM.
fn nodal_rows(section: &str, rows: &[&str]) -> String {
    let mut s = format!("$$PRESCRIBED_NODAL_VELOCITY_{section}\n{}\n", rows.len());
    for r in rows {
        s += r;
        s.push('\n');
    }
    s
}

#[test]
fn gom_nodal_rows_are_read_and_bad_ones_refused() {
    let gom = column_gom(&nodal_rows(
        "SURFACE",
        &["3 0 1 0 0.0 -0.2 0.0", "4 1 1 1 0.0 -0.2 0.0"],
    ));
    let case = load(&gom, CPS).unwrap();
    assert!(case.boundary.prescribed.is_none());
    let [set] = &case.boundary.nodal_velocity[..] else {
        panic!("one nodal set: {:?}", case.boundary.nodal_velocity)
    };
    assert_eq!(set.name, "$$PRESCRIBED_NODAL_VELOCITY_SURFACE");
    assert_eq!((set.rows[0].node, set.rows[1].node), (2, 3));
    assert_eq!(set.rows[0].directions, [false, true, false]);
    assert_eq!(set.rows[1].velocity, [0.0, -0.2, 0.0]);
    assert_eq!((set.scale, set.curve.clone()), (1.0, LoadCurve::Step));
    assert_eq!(case.reactions().len(), 1);
    // With points prescribed too: two sets, the points' first.
    let both = load(
        &column_gom(&(rows(&["0 1 0"; 6]) + &nodal_rows("POINT", &["3 0 1 0 0 -1 0"]))),
        CPS,
    )
    .unwrap();
    let names: Vec<String> = both.reactions().into_iter().map(|r| r.name).collect();
    assert_eq!(
        names,
        [
            "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME",
            "$$PRESCRIBED_NODAL_VELOCITY_POINT"
        ]
    );
    // An off multiplier switches them off, as in Anura3D; an empty section is none.
    let off = CPS.replace("step 1.0 1.0", "off 0.0 1.0");
    assert!(load(&gom, &off).unwrap().boundary.nodal_velocity.is_empty());
    assert!(load(&column_gom(&nodal_rows("LINE", &[])), CPS)
        .unwrap()
        .boundary
        .nodal_velocity
        .is_empty());
    // Two kinds of section at once (Anura3D refuses them), a node outside the mesh, a flag
    // other than 0 or 1, a missing value.
    let err = load(
        &column_gom(
            &(nodal_rows("SURFACE", &["3 0 1 0 0 -1 0"])
                + &nodal_rows("LINE", &["4 0 1 0 0 -1 0"])),
        ),
        CPS,
    )
    .unwrap_err();
    assert!(
        err.contains("more than one section") && err.contains("LINE"),
        "{err}"
    );
    let err = load(
        &column_gom(&nodal_rows("POINT", &["99999 0 1 0 0 -1 0"])),
        CPS,
    )
    .unwrap_err();
    assert!(
        err.contains("PRESCRIBED_NODAL_VELOCITY_POINT") && err.contains("99999"),
        "{err}"
    );
    let err = load(&column_gom(&nodal_rows("POINT", &["3 0 2 0 0 -1 0"])), CPS).unwrap_err();
    assert!(err.contains("0 or 1"), "{err}");
    let err = load(&column_gom(&nodal_rows("POINT", &["3 0 1 0 0 -1"])), CPS).unwrap_err();
    assert!(err.contains("row 1"), "{err}");
}
