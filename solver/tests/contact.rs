//! Contact between a structure and the soil (`step::contact`, Anura3D's
//! `$$CONTACT_FORMULATION 1`): a pile pushed into the soil with friction and adhesion on its
//! shaft (the mesh moving with it, as Anura3D's contact expects), in 3D and in plane-strain and
//! axisymmetric sections, and benchmark 4006 run for five load steps, against Anura3D itself
//! (`ANURA3D_ORACLE`, `ANURA3D_ORACLE_2D`, `ANURA3D_BENCHMARKS`), point by point at every
//! load step; the same outputs for any thread
//! count; what contact does not model, refused by name. The comparisons say "skipped" when
//! their variables are unset.

mod common;

use std::path::{Path, PathBuf};

use common::gom;

/// The soil (material 1) and the pile (material 2, the structure) of the piles here.
const SOIL_AND_PILE: [gom::Material; 2] = [
    gom::Material {
        name: "soil",
        porosity: 0.3,
        density: 1800.0,
        young: 2000.0,
        saturated: false,
    },
    gom::Material {
        name: "pile",
        porosity: 0.0,
        density: 2400.0,
        young: 50000.0,
        saturated: false,
    },
];

/// The GOM's contact section `key` listing the pile's `elements` (1-based) with the soil's
/// (friction, adhesion), and the moving mesh around the pile (its box from y = 2 to 3, the
/// soil below compressed, the empty box above stretched; `corners(lo, hi)`: the node lines of
/// the box between those heights).
fn contact_sections<'a>(
    key: &str,
    elements: impl ExactSizeIterator<Item = &'a usize>,
    (mu, c): (f64, f64),
    corners: &dyn Fn(f64, f64) -> String,
) -> String {
    let mut s = format!("$${key}\n{}\n", elements.len());
    for e in elements {
        s.push_str(&format!(
            "{e} 1 \"soil\" {mu} {c} \"NAN\" 0.0 0.0 \"NAN\" 0.0 0.0 \"NAN\" 0.0 0.0\n"
        ));
    }
    s.push_str(&format!(
        "$$EXTENDING_MESH_CORNER_NODES\n{}$$COMPRESSING_MESH_CORNER_NODES\n{}$$MOVING_MESH_CORNER_NODES\n{}$$MOVING_MESH_DIRECTION\ny-direction\n$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n2\n",
        corners(3.0, 4.0),
        corners(0.0, 2.0),
        corners(2.0, 3.0)
    ));
    s
}

/// A pile (material 2, the structure) 0.5 m wide and 1 m long, its top at the surface of a
/// soil (material 1) 3 m deep and 1.5 m wide, on the symmetry plane x = 0, pushed down at
/// 0.1 m/s by a velocity prescribed on its points; friction `mu` and adhesion `c` (kPa) on its
/// shaft and tip. The mesh follows it (Anura3D's moving mesh, which keeps the structure in its
/// elements and so on its interface): the box around it moves, the soil's box below is
/// compressed, the empty one above stretched. Sides fixed normally, the base fixed; gravity.
/// `load_steps` of 0.5 s. `cps` adds or replaces CPS keys, `more` GOM text.
fn pile(
    dir: &Path,
    name: &str,
    load_steps: u32,
    mu: f64,
    c: f64,
    cps: &[(&str, &str)],
    more: &str,
) -> (PathBuf, PathBuf) {
    pile_in(dir, name, load_steps, (mu, c), (cps, more), false)
}

/// [`pile`]'s problem in a saturated soil (the liquid fixed where the solid is: an
/// impermeable box), the pile held sideways too (Anura3D's liquid at the wall reads the
/// structure's prescribed velocity in every component).
fn saturated_pile(dir: &Path, name: &str, load_steps: u32, mu: f64) -> (PathBuf, PathBuf) {
    pile_in(dir, name, load_steps, (mu, 0.0), (&[], ""), true)
}

/// [`pile`] and [`saturated_pile`].
fn pile_in(
    dir: &Path,
    name: &str,
    load_steps: u32,
    (mu, c): (f64, f64),
    (cps, more): (&[(&str, &str)], &str),
    saturated: bool,
) -> (PathBuf, PathBuf) {
    let [soil, pile] = SOIL_AND_PILE;
    let materials = [gom::Material { saturated, ..soil }, pile];
    let model = gom::box_model(
        [3, 8, 1],
        [1.5, 4.0, 0.5],
        &materials,
        |p| match (p[0], p[1]) {
            (_, y) if y >= 3.0 => 0,
            (x, y) if x < 0.5 && y >= 2.0 => 2,
            _ => 1,
        },
        |p| {
            let at = |v: f64, w: f64| (v - w).abs() < 1e-9;
            [
                at(p[0], 0.0) || at(p[0], 1.5),
                at(p[1], 0.0),
                at(p[2], 0.0) || at(p[2], 0.5),
            ]
        },
    );
    let pile = gom::elements_of(&model, 2);
    let corners = |lo: f64, hi: f64| -> String {
        gom::box_corners(&model, [0.0, lo, 0.0], [1.5, hi, 0.5])
            .iter()
            .map(|n| format!("{n}\n"))
            .collect()
    };
    let held = if saturated { [1, 1, 1] } else { [0, 1, 0] };
    let mut extra = gom::prescribed_section(&pile, &held, &[0.0, -0.1, 0.0]);
    extra.push_str(&contact_sections(
        "START_CONTACT_VOLUME",
        pile.iter(),
        (mu, c),
        &corners,
    ));
    extra.push_str(more);
    let steps = load_steps.to_string();
    // Undamped: local damping takes the sign of each nodal velocity, and the pile's sideways
    // velocities are round-off, whose sign need not be the same in two codes; damped, the codes
    // part by 1e-6 after a few steps (a damped run is compared as a whole in
    // `contact_outputs_do_not_depend_on_the_thread_count` and the 4006 run).
    let mut keys = vec![
        ("NUMBER_OF_LOADSTEPS", steps.as_str()),
        ("TIME_PER_LOADSTEP", "0.5"),
        ("CONTACT_FORMULATION", "1"),
        ("HOMOGENEOUS_LOCAL_DAMPING", "0 0.05"),
    ];
    keys.extend_from_slice(cps);
    gom::write(dir, name, &model, &extra, &keys)
}

/// Where [`pile_2d`]'s pile stands and how it is pushed.
#[derive(Clone, Copy)]
struct Push {
    /// An axisymmetric section (x the radius), else plane strain.
    axisymmetric: bool,
    /// The x of the pile's left side: 0 on the symmetry plane (the axis).
    left: f64,
    /// Its prescribed sideways velocity (m/s); 0: its x is free (held at 0 in a saturated
    /// soil, as [`saturated_pile`]).
    drift: f64,
    /// The soil saturated (the liquid fixed where the solid is).
    saturated: bool,
    /// Anura3D's strain smoothing (plane strain only).
    smoothing: bool,
}

/// [`pile`]'s problem as a section, plane strain or axisymmetric: the soil 1.5 m wide and 3 m
/// deep in cells of 0.25 m, the pile 0.5 m wide and 1 m long (on the axis: a solid pile of
/// radius 0.5 m), pushed down at 0.1 m/s (and sideways at `push.drift`), the mesh following
/// it; `load_steps` of 0.5 s, undamped.
fn pile_2d(
    dir: &Path,
    name: &str,
    push: Push,
    load_steps: u32,
    mu: f64,
    c: f64,
) -> (PathBuf, PathBuf) {
    let [soil, pile] = SOIL_AND_PILE;
    let saturated = push.saturated;
    let materials = [gom::Material { saturated, ..soil }, pile];
    let model = gom::rect_model(
        [6, 16],
        [1.5, 4.0],
        push.axisymmetric,
        &materials,
        |p| match (p[0], p[1]) {
            (_, y) if y >= 3.0 => 0,
            (x, y) if x > push.left && x < push.left + 0.5 && y >= 2.0 => 2,
            _ => 1,
        },
        |p| {
            let at = |v: f64, w: f64| (v - w).abs() < 1e-9;
            [at(p[0], 0.0) || at(p[0], 1.5), at(p[1], 0.0)]
        },
    );
    let pile = gom::elements_of(&model, 2);
    let corners = |lo: f64, hi: f64| -> String {
        gom::box_corners(&model, [0.0, lo, 0.0], [1.5, hi, 0.0])
            .iter()
            .map(|n| format!("{n}\n"))
            .collect()
    };
    let sideways = u8::from(push.drift != 0.0 || saturated);
    let mut extra = gom::prescribed_section(&pile, &[sideways, 1], &[push.drift, -0.1]);
    // Listed from the top down: the order decides a corner node's normal (Anura3D's rule).
    extra.push_str(&contact_sections(
        "START_BODY_CONTACT_2D",
        pile.iter().rev(),
        (mu, c),
        &corners,
    ));
    let steps = load_steps.to_string();
    gom::write(
        dir,
        name,
        &model,
        &extra,
        &[
            ("NUMBER_OF_LOADSTEPS", steps.as_str()),
            ("TIME_PER_LOADSTEP", "0.5"),
            ("CONTACT_FORMULATION", "1"),
            ("HOMOGENEOUS_LOCAL_DAMPING", "0 0.05"),
            ("GRAVITY_VECTOR", "0.0 -1.0"),
            ("STRAIN_SMOOTHING", if push.smoothing { "1" } else { "0" }),
            // Mixed integration is not modelled for axisymmetric sections.
            (
                "COMPUTATION_METHOD",
                if push.axisymmetric {
                    "MPM-MP"
                } else {
                    "MPM-MIXED"
                },
            ),
        ],
    )
}

/// Plane-strain and axisymmetric piles against Anura3D's 2D build. Adhesion is compared where
/// the pile pushes the soil (its tip, and the shaft of a pile pushed sideways): Anura3D's
/// adhesion acts at a node only while the bodies approach there, so on a shaft sliding straight
/// down the round-off sign of a zero normal velocity decides it, and two codes' round-off
/// need not agree (on a symmetric pile Anura3D's sideways velocities are 1e-30, ours 0).
#[test]
fn a_pile_pushed_into_a_section_matches_the_2d_oracle() {
    let Some(bin) = common::oracle_2d("2D contact against Anura3D") else {
        return;
    };
    let (plane, axi) = (
        Push {
            axisymmetric: false,
            left: 0.0,
            drift: 0.0,
            saturated: false,
            smoothing: false,
        },
        Push {
            axisymmetric: true,
            left: 0.0,
            drift: 0.0,
            saturated: false,
            smoothing: false,
        },
    );
    let sideways = Push {
        axisymmetric: false,
        left: 0.5,
        drift: 0.02,
        saturated: false,
        smoothing: false,
    };
    for (push, mu, c, label) in [
        (plane, 0.4, 0.0, "plane strain, on the symmetry plane"),
        (plane, 0.0, 0.0, "plane strain, on the symmetry plane"),
        (axi, 0.4, 0.0, "axisymmetric"),
        (axi, 0.0, 0.0, "axisymmetric"),
        (sideways, 0.4, 2.0, "plane strain, pushed sideways"),
        (
            Push {
                smoothing: true,
                ..plane
            },
            0.4,
            0.0,
            "plane strain, on the symmetry plane, strain smoothing",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        pile_2d(dir.path(), "pile", push, 3, mu, c);
        common::agrees_with_anura3d(
            &bin,
            dir.path(),
            "pile",
            3,
            &format!("{label}, μ = {mu}, c = {c}"),
        );
    }
    // In a saturated soil: the liquid held at the wall (the axisymmetric monopile's case).
    for axisymmetric in [true, false] {
        let push = Push {
            axisymmetric,
            left: 0.0,
            drift: 0.0,
            saturated: true,
            smoothing: false,
        };
        let dir = tempfile::tempdir().unwrap();
        pile_2d(dir.path(), "wet", push, 3, 0.4, 0.0);
        common::agrees_with_anura3d_saturated(
            &bin,
            dir.path(),
            "wet",
            3,
            &format!("saturated, axisymmetric {axisymmetric}, μ = 0.4"),
        );
    }
}

/// [`pile_2d`]'s axisymmetric pile as a scene: the same mesh (the empty box above the soil a
/// material group "air" without points), pushed down at 0.1 m/s by a velocity on its points
/// for two load steps of 0.5 s, with `[[contact]]` (`friction`, `adhesion`) and
/// `[moving_mesh]`; `extra` is appended to the scene.
fn pile_scene(dir: &Path, name: &str, friction: f64, adhesion: f64, extra: &str) -> PathBuf {
    use std::fmt::Write as _;
    let (nx, ny, w, h) = (6usize, 16usize, 1.5, 4.0);
    let node = |i: usize, j: usize| 1 + i + (nx + 1) * j;
    let mut msh = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n5\n2 1 \"soil\"\n2 2 \"pile\"\n2 3 \"air\"\n1 4 \"head\"\n1 5 \"shaft\"\n$EndPhysicalNames\n",
    );
    writeln!(msh, "$Nodes\n{}", (nx + 1) * (ny + 1)).unwrap();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (w * i as f64 / nx as f64, h * j as f64 / ny as f64);
            writeln!(msh, "{} {x} {y} 0", node(i, j)).unwrap();
        }
    }
    // The pile's head (y = 3) and shaft (r = 0.5) as lines: two cells each.
    writeln!(msh, "$EndNodes\n$Elements\n{}", 2 * nx * ny + 4).unwrap();
    let mut id = 0;
    for (group, a, b) in [
        (4, node(0, 12), node(1, 12)),
        (4, node(1, 12), node(2, 12)),
        (5, node(2, 8), node(2, 9)),
        (5, node(2, 9), node(2, 10)),
    ] {
        id += 1;
        writeln!(msh, "{id} 1 2 {group} {group} {a} {b}").unwrap();
    }
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (
                (i as f64 + 0.5) * w / nx as f64,
                (j as f64 + 0.5) * h / ny as f64,
            );
            let group = match (x, y) {
                (_, y) if y > 3.0 => 3,
                (x, y) if x < 0.5 && y > 2.0 => 2,
                _ => 1,
            };
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            for t in [[a, b, c], [a, c, d]] {
                id += 1;
                writeln!(msh, "{id} 2 2 {group} {group} {} {} {}", t[0], t[1], t[2]).unwrap();
            }
        }
    }
    msh.push_str("$EndElements\n");
    std::fs::write(dir.join(format!("{name}.msh")), msh).unwrap();
    let scene = format!(
        r#"mesh = "{name}.msh"
section = "axisymmetric"
[time]
end = 1.0
output_interval = 0.5
[gravity]
vector = [0.0, -9.81, 0.0]
[[material]]
physical = "soil"
density = 1800.0
young = 2000.0
poisson = 0.3
[[material]]
physical = "pile"
density = 2400.0
young = 50000.0
poisson = 0.3
[[material]]
physical = "air"
density = 1.0
young = 1.0
poisson = 0.0
points_per_element = 0
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = 1.5"
fixed = [true, false, false]
[[fixity]]
plane = "y = 0"
fixed = [false, true, false]
[[velocity]]
physical = "pile"
velocity = [0.0, -0.1, 0.0]
components = [false, true, false]
[[contact]]
structure = "pile"
friction = {friction}
adhesion = {adhesion}
[moving_mesh]
follows = "pile"
moving = [[0.0, 2.0], [1.5, 3.0]]
compressing = [[0.0, 0.0], [1.5, 2.0]]
extending = [[0.0, 3.0], [1.5, 4.0]]
{extra}"#
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, scene).unwrap();
    path
}

/// The last row of each set of `reaction.csv` in `out`: (set, [fx, fy, fz]).
fn last_reactions(out: &Path) -> Vec<(String, [f64; 3])> {
    let text = std::fs::read_to_string(out.join("reaction.csv")).unwrap();
    let mut last: Vec<(String, [f64; 3])> = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let force = [6, 7, 8].map(|k| f[k].parse::<f64>().unwrap());
        match last.iter_mut().find(|r| r.0 == f[2]) {
            Some(r) => r.1 = force,
            None => last.push((f[2].to_string(), force)),
        }
    }
    last
}

#[test]
fn a_scene_pushes_a_pile_with_contact_and_a_moving_mesh() {
    let dir = tempfile::tempdir().unwrap();
    // (friction, adhesion) → the soil's push on the pile and the jack's force, at the end;
    // the vertical push off the base (the shaft's and the top's, where the soil heaves onto
    // the pile's top corner).
    let (mut runs, mut shaft) = (Vec::new(), Vec::new());
    for (mu, c) in [(0.0, 0.0), (0.4, 0.0), (0.4, 5.0)] {
        let scene = pile_scene(dir.path(), "pile", mu, c, "");
        let out = dir.path().join(format!("out-{mu}-{c}"));
        let o = common::solve(&scene, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let sets = last_reactions(&out);
        assert_eq!(sets.len(), 3, "{sets:?}");
        assert_eq!(sets[1].0, "contact");
        assert_eq!(sets[2].0, "contact_base");
        shaft.push(sets[1].1[1] - sets[2].1[1]);
        runs.push((sets[1].1, sets[0].1));
    }
    eprintln!("| μ, c | soil's push on the pile (kN/rad) | jack (kN/rad) |\n|---|---:|---:|");
    for ((push, jack), label) in runs.iter().zip(["0, 0", "0.4, 0", "0.4, 5 kPa"]) {
        eprintln!("| {label} | {:.4} | {:.4} |", push[1], jack[1]);
    }
    // The soil holds the pile back (pushes it up), the more with friction and adhesion, and
    // the jack pushes down by the soil's push less the pile's weight (at a steady speed);
    // the soil's radial push on the shaft (per radian) points to the axis.
    let weight = 2.4 * 9.81 * 1.0 * 0.5 * 0.5 / 2.0; // per radian: ρ g L r² / 2
    for (push, jack) in &runs {
        assert!(push[1] > 0.0 && push[0] < 0.0, "{runs:?}");
        assert!(
            (jack[1] + push[1] - weight).abs() < 1e-3 * push[1],
            "{runs:?}"
        );
    }
    assert!(runs[1].0[1] > 1.05 * runs[0].0[1], "{runs:?}");
    // Friction on the shaft holds the pile back.
    assert!(shaft[1] > shaft[0] + 5.0, "{shaft:?}");
    // Adhesion acts where the soil presses on the pile (Anura3D's rule), so it takes part of
    // c L r (per radian) on the shaft, not all of it.
    let full = 5.0 * 1.0 * 0.5;
    assert!(runs[2].0[1] - runs[1].0[1] > 0.25 * full, "{runs:?}");
}

#[test]
fn what_a_scene_cannot_pair_with_contact_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, edit, expected) in [
        (
            "[[contact]]\nstructure = \"soil\"\n",
            None,
            "a second [[contact]]",
        ),
        (
            "",
            Some(("structure = \"pile\"", "structure = \"wall\"")),
            "no physical surface \"wall\"",
        ),
        (
            "",
            Some(("friction = 0", "friction = -1")),
            "friction = -1: expected a number",
        ),
        (
            "",
            Some((
                "physical = \"pile\"\nvelocity",
                "physical = \"soil\"\nvelocity",
            )),
            "only the structure's may be driven",
        ),
        (
            "",
            Some((
                "moving = [[0.0, 2.0], [1.5, 3.0]]",
                "moving = [[0.0, 2.1], [1.5, 3.0]]",
            )),
            "no mesh node at the box's corner",
        ),
        (
            "",
            Some(("follows = \"pile\"", "follows = \"rock\"")),
            "follows: no physical surface",
        ),
    ] {
        let scene = pile_scene(dir.path(), "bad", 0.0, 0.0, extra);
        if let Some((from, to)) = edit {
            let text = std::fs::read_to_string(&scene).unwrap();
            assert!(text.contains(from), "{from}");
            std::fs::write(&scene, text.replacen(from, to, 1)).unwrap();
        }
        let o = common::solve(&scene, &dir.path().join("out"), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{expected}: {err}");
        assert!(
            err.contains(expected) && err.contains("bad.toml"),
            "{expected}: {err}"
        );
        assert!(!dir.path().join("out").exists());
    }
}

#[test]
fn a_pile_pushed_into_soil_with_friction_matches_anura3d() {
    let Some(bin) = common::oracle("contact against Anura3D") else {
        return;
    };
    // With strain smoothing each material's volumetric strain takes its own body's nodes.
    let smoothing: &[(&str, &str)] = &[("STRAIN_SMOOTHING", "1")];
    for (mu, c, cps) in [(0.4, 2.0, &[][..]), (0.0, 0.0, &[]), (0.4, 0.0, smoothing)] {
        let dir = tempfile::tempdir().unwrap();
        pile(dir.path(), "pile", 3, mu, c, cps, "");
        common::agrees_with_anura3d(
            &bin,
            dir.path(),
            "pile",
            3,
            &format!("pile pushed, μ = {mu}, c = {c}, {cps:?}"),
        );
    }
}

/// The pile pushed into a saturated soil: the contact on the solid, the liquid held at the
/// impermeable wall, against Anura3D's two-phase contact.
#[test]
fn a_pile_pushed_into_saturated_soil_matches_anura3d() {
    let Some(bin) = common::oracle("contact with a saturated soil against Anura3D") else {
        return;
    };
    for mu in [0.4, 0.0] {
        let dir = tempfile::tempdir().unwrap();
        saturated_pile(dir.path(), "wet", 3, mu);
        common::agrees_with_anura3d_saturated(
            &bin,
            dir.path(),
            "wet",
            3,
            &format!("pile pushed into saturated soil, μ = {mu}"),
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let smoothing: &[(&str, &str)] = &[("STRAIN_SMOOTHING", "1")];
    pile_in(dir.path(), "wet", 3, (0.4, 0.0), (smoothing, ""), true);
    common::agrees_with_anura3d_saturated(
        &bin,
        dir.path(),
        "wet",
        3,
        "pile pushed into saturated soil, μ = 0.4, with strain smoothing",
    );
}

#[test]
fn benchmark_4006_over_five_load_steps_matches_anura3d() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let suite = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let Some(bin) = common::oracle("4006 with contact against Anura3D") else {
        return;
    };
    let Some(suite) = suite else {
        mpm_shared::suite::skipped("4006 against Anura3D (ANURA3D_BENCHMARKS not set)");
        return;
    };
    // 4006: a block pushed down into the soil at 0.2 m/s, with contact and a moving mesh; run
    // five dynamic load steps of 1 s instead of its single 1e-15 s time step.
    let src = suite
        .join("Benchmarks/Pre-Commit_Tests/4006_PrescribedVelocityMP/prescribedVelocityMP.A3D");
    common::benchmark_agrees_with_anura3d(
        &bin,
        &src,
        "prescribedVelocityMP",
        &[
            ("$$QUASISTATIC_CONVERGENCE", "0"),
            ("$$TIME_PER_LOADSTEP", "1.0"),
            ("$$NUMBER_OF_LOADSTEPS", "5"),
        ],
        5,
        "4006 over 5 load steps",
    );
}

#[test]
fn contact_outputs_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let (gom, _) = pile(dir.path(), "slide", 2, 0.4, 2.0, &[], "");
    let axi = Push {
        axisymmetric: true,
        left: 0.0,
        drift: 0.0,
        saturated: false,
        smoothing: false,
    };
    let (section, _) = pile_2d(dir.path(), "section", axi, 2, 0.4, 2.0);
    let scene = pile_scene(dir.path(), "scene", 0.4, 5.0, "");
    let (wet, _) = saturated_pile(dir.path(), "wet", 2, 0.4);
    let inputs = [
        (gom, "3D"),
        (section, "axisymmetric"),
        (scene, "scene"),
        (wet, "saturated"),
    ];
    for (input, label) in inputs {
        let (one, three) = (
            dir.path().join(format!("{label}-one")),
            dir.path().join(format!("{label}-three")),
        );
        for (out, threads) in [(&one, "1"), (&three, "3")] {
            let o = common::solve(&input, out, &["--threads", threads]);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        let (a, b) = (common::outputs(&one), common::outputs(&three));
        assert_eq!(a.len(), b.len());
        for (f, g) in a.iter().zip(&b) {
            assert_eq!(f.0, g.0);
            assert!(
                f.1 == g.1,
                "{label}: {} differs between 1 and 3 threads",
                f.0
            );
        }
    }
}

#[test]
fn friction_on_the_shaft_adds_to_the_settlement_of_the_soil_beside_the_pile() {
    let dir = tempfile::tempdir().unwrap();
    // How much more the soil beside the shaft settles than the soil away from it, per friction.
    let mut dragged = Vec::new();
    for mu in [0.0, 0.4] {
        let (gom, _) = pile(dir.path(), &format!("mu{mu}"), 2, mu, 0.0, &[], "");
        let out = dir.path().join(format!("out{mu}"));
        let o = common::solve(&gom, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
        assert_eq!(json["status"], "completed");
        let sets = mpm_shared::vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
        let last = sets.last().unwrap();
        let vtu = mpm_shared::vtu_read::read_vtu_file(&out.join(&last.file)).unwrap();
        let material = vtu.point_data("material").unwrap();
        let u = vtu.point_data("displacement").unwrap();
        let x = vtu.coordinates().unwrap();
        let settlement = |near: bool| {
            let set: Vec<usize> = (0..material.len())
                .filter(|&i| {
                    material.get(i, 0) == 1.0 && (x.get(i, 0) < 1.0) == near && x.get(i, 1) > 2.2
                })
                .collect();
            set.iter().map(|&i| -u.get(i, 1)).sum::<f64>() / set.len() as f64
        };
        dragged.push(settlement(true) - settlement(false));
    }
    eprintln!(
        "settlement of the soil beside the shaft less that away from it: frictionless {:.3e} m, μ = 0.4 {:.3e} m",
        dragged[0], dragged[1]
    );
    // Anura3D's friction acts while the soil approaches the shaft, so it adds a share, not all.
    assert!(
        dragged[0] > 0.0 && dragged[1] > 1.05 * dragged[0],
        "{dragged:?}"
    );
}

/// The scene's pile pushed by its jack with a pressure on its head too (`[[traction]]` with
/// `[[contact]]`: the head's faces load the structure alone): at a steady push the jack and the
/// soil carry the pile's weight and the load (jack + push = weight + load, as jack + push =
/// weight without it); without the jack the pile comes to rest on the soil, which then
/// carries both (before the contact's system velocity took the face loads, it carried 7.2 of
/// 9.19 kN/rad: the head's corner load went into the soil's correction). A load on a face
/// between the pile and the soil is refused by name.
#[test]
fn a_load_on_the_pile_head_acts_on_the_structure_alone() {
    let dir = tempfile::tempdir().unwrap();
    let p = 50.0;
    let extra = format!("[[traction]]\nphysical = \"head\"\npressure = {p}\n");
    let scene = pile_scene(dir.path(), "loaded", 0.4, 0.0, &extra);
    let out = dir.path().join("loaded-out");
    let o = common::solve(&scene, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sets = last_reactions(&out);
    // Per radian: the head's load p r² / 2 and the weight ρ g L r² / 2.
    let (load, weight) = (p * 0.25 / 2.0, 2.4 * 9.81 * 1.0 * 0.25 / 2.0);
    let (jack, push) = (sets[0].1[1], sets[1].1[1]);
    eprintln!(
        "jack {jack:.4}, soil's push {push:.4}, weight + load {:.4} kN/rad",
        weight + load
    );
    assert!(
        (jack + push - weight - load).abs() < 1e-3 * (weight + load),
        "{sets:?}"
    );
    // The same load with no jack: the pile rests on the soil, which carries the load and the
    // weight (damped, with a PIC blend against the ringing of a free structure's points).
    let scene = pile_scene(
        dir.path(),
        "free",
        0.4,
        0.0,
        &format!("{extra}[damping]\nlocal = 0.05\n"),
    );
    let mut text = std::fs::read_to_string(&scene).unwrap();
    let velocity = "[[velocity]]\nphysical = \"pile\"\nvelocity = [0.0, -0.1, 0.0]\n\
                    components = [false, true, false]\n";
    assert!(text.contains(velocity) && text.contains("end = 1.0"));
    text = text
        .replacen(velocity, "", 1)
        .replacen("end = 1.0", "end = 4.0", 1);
    std::fs::write(&scene, format!("pic_blend = 0.05\n{text}")).unwrap();
    let out = dir.path().join("free-out");
    let o = common::solve(&scene, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sets = last_reactions(&out);
    let push = sets[0].1[1];
    eprintln!("a free pile at rest: soil's push {push:.4} kN/rad");
    assert!(
        (push - weight - load).abs() < 2e-3 * (weight + load),
        "{sets:?}"
    );
    // On a face the pile shares with the soil.
    let extra = "[[traction]]\nphysical = \"shaft\"\npressure = 10.0\n";
    let scene = pile_scene(dir.path(), "shaft", 0.4, 0.0, extra);
    let o = common::solve(&scene, &dir.path().join("shaft-out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("between the structure and the soil"), "{err}");
}

/// The pile as a rigid body (`rigid = true`), free, loaded on its head, damped: its points
/// keep one velocity (they neither strain nor ring, in pure FLIP), and it comes to rest on the
/// soil, which then carries the load and the pile's weight.
#[test]
fn a_rigid_pile_moves_as_one_body_and_rests_on_the_soil() {
    let dir = tempfile::tempdir().unwrap();
    let p = 50.0;
    let extra =
        format!("[[traction]]\nphysical = \"head\"\npressure = {p}\n[damping]\nlocal = 0.05\n");
    let scene = pile_scene(dir.path(), "rigid", 0.4, 0.0, &extra);
    let mut text = std::fs::read_to_string(&scene).unwrap();
    let velocity = "[[velocity]]\nphysical = \"pile\"\nvelocity = [0.0, -0.1, 0.0]\n\
                    components = [false, true, false]\n";
    for from in [velocity, "end = 1.0", "adhesion = 0\n"] {
        assert!(text.contains(from), "{from}");
    }
    text = text
        .replacen(velocity, "", 1)
        .replacen("end = 1.0", "end = 4.0", 1)
        .replacen("adhesion = 0\n", "adhesion = 0\nrigid = true\n", 1);
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("rigid-out");
    let o = common::solve(&scene, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (load, weight) = (p * 0.25 / 2.0, 2.4 * 9.81 * 1.0 * 0.25 / 2.0);
    let sets = last_reactions(&out);
    let push = sets[0].1[1];
    eprintln!(
        "a rigid pile at rest: soil's push {push:.4} kN/rad (load + weight {:.4})",
        load + weight
    );
    assert!(
        (push - weight - load).abs() < 2e-3 * (weight + load),
        "{sets:?}"
    );
    let pvd = mpm_shared::vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
    for set in &pvd {
        let vtu = mpm_shared::vtu_read::read_vtu_file(&out.join(&set.file)).unwrap();
        let (material, v, stress) = (
            vtu.point_data("material").unwrap(),
            vtu.point_data("velocity").unwrap(),
            vtu.point_data("stress").unwrap(),
        );
        let pile: Vec<usize> = (0..material.len())
            .filter(|&i| material.get(i, 0) == 2.0)
            .collect();
        for c in 0..2 {
            let (lo, hi) = pile.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| {
                (lo.min(v.get(i, c)), hi.max(v.get(i, c)))
            });
            assert!(
                hi - lo < 1e-9,
                "t = {}: velocity {c} spans {lo} to {hi}",
                set.time
            );
        }
        let worst = pile
            .iter()
            .flat_map(|&i| (0..4).map(move |c| (i, c)))
            .map(|(i, c)| stress.get(i, c).abs())
            .fold(0.0f64, f64::max);
        assert!(
            worst < 1e-6,
            "t = {}: a rigid pile's stress {worst} kPa",
            set.time
        );
    }
}

/// The scene's pile pushed into a saturated soil (an impermeable pile: the liquid keeps the
/// wall's normal velocity), damped, against the same scene with the pile held still: the
/// pile's push raises the pore pressure under its tip at every output (measured: 4 to 30 kPa
/// of compression; with the liquid let through the wall, 7 to 23 kPa of suction instead), and
/// the jack still carries the soil's push less the pile's weight; a saturated structure is
/// refused by name.
#[test]
fn a_scene_pushes_a_pile_into_saturated_soil() {
    let dir = tempfile::tempdir().unwrap();
    let soil = "physical = \"soil\"\ndensity = 1800.0\nyoung = 2000.0\npoisson = 0.3\n";
    let pile = "physical = \"pile\"\ndensity = 2400.0\nyoung = 50000.0\npoisson = 0.3\n";
    let liquid = "[material.liquid]\ndensity = 1000.0\nbulk_modulus = 20000.0\n\
                  intrinsic_permeability = 1e-9\nviscosity = 1e-6\nporosity = 0.3\n";
    let edits = |name: &str, edits: &[(&str, String)]| {
        let extra = "[damping]\nlocal = 0.1\n";
        let scene = pile_scene(dir.path(), name, 0.4, 0.0, extra);
        let mut text = std::fs::read_to_string(&scene).unwrap();
        for (from, to) in edits {
            assert!(text.contains(from), "{from}");
            text = text.replacen(from, to, 1);
        }
        std::fs::write(&scene, text).unwrap();
        scene
    };
    let wet = (soil, format!("{soil}{liquid}"));
    let often = ("output_interval = 0.5", "output_interval = 0.1".to_string());
    let still = (
        "velocity = [0.0, -0.1, 0.0]",
        "velocity = [0.0, 0.0, 0.0]".to_string(),
    );
    let mut outputs = Vec::new();
    for (name, edit) in [
        ("pushed", vec![wet.clone(), often.clone()]),
        ("still", vec![wet.clone(), often, still]),
    ] {
        let out = dir.path().join(name);
        let o = common::solve(&edits(name, &edit), &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        outputs.push(out);
    }
    let sets = last_reactions(&outputs[0]);
    let (push, jack) = (sets[1].1[1], sets[0].1[1]);
    let weight = 2.4 * 9.81 * 1.0 * 0.5 * 0.5 / 2.0;
    assert!(
        push > 0.0 && (jack + push - weight).abs() < 1e-3 * push,
        "{sets:?}"
    );
    // Compression negative: the soil's points between 1.5 and 2 m high under the tip (r < 0.5;
    // the tip starts at 2 m), each run's mean pore pressure there per output.
    let under_tip = |out: &Path| -> Vec<f64> {
        let pvd = mpm_shared::vtu_read::read_pvd_file(&out.join("run.pvd")).unwrap();
        pvd.iter()
            .map(|set| {
                let vtu = mpm_shared::vtu_read::read_vtu_file(&out.join(&set.file)).unwrap();
                let (material, p) = (
                    vtu.point_data("material").unwrap(),
                    vtu.point_data("pore_pressure").unwrap(),
                );
                let x = vtu.coordinates().unwrap();
                let set: Vec<f64> = (0..material.len())
                    .filter(|&i| {
                        material.get(i, 0) == 1.0
                            && x.get(i, 0) < 0.5
                            && (1.5..2.0).contains(&x.get(i, 1))
                    })
                    .map(|i| p.get(i, 0))
                    .collect();
                set.iter().sum::<f64>() / set.len() as f64
            })
            .collect()
    };
    let (pushed, still) = (under_tip(&outputs[0]), under_tip(&outputs[1]));
    assert_eq!(pushed.len(), 10);
    let excess: Vec<f64> = pushed.iter().zip(&still).map(|(a, b)| a - b).collect();
    eprintln!("excess pore pressure under the tip (kPa) per 0.1 s: {excess:.1?}");
    assert!(excess.iter().all(|&e| e < -2.0), "{excess:?}");
    // A saturated structure.
    let scene = edits("wet_pile", &[(pile, format!("{pile}{liquid}"))]);
    let o = common::solve(&scene, &dir.path().join("wet_pile-out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("for a saturated structure"), "{err}");
}

/// A refusal's test: the CPS keys set and what the error must say.
type Refusal<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str);

/// A refusal's test: an edit of the GOM's text and what the error must say.
type Edit<'a> = (&'a str, &'a dyn Fn(String) -> String, &'a str);

#[test]
fn what_contact_does_not_model_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [Refusal; 2] = [
        (
            "scaling",
            &[("APPLY_CONTACT_VELOCITY_SCALING", "1")],
            "$$APPLY_CONTACT_VELOCITY_SCALING",
        ),
        ("value", &[("CONTACT_FORMULATION", "2")], "expected 0 or 1"),
    ];
    for (name, cps, want) in cases {
        let (gom, _) = pile(dir.path(), name, 1, 0.4, 0.0, cps, "");
        let o = common::solve(&gom, &dir.path().join(name), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{name}: {err}");
    }
    // The contact rows edited: `edit` of the GOM text, and what the error must say.
    let edits: [Edit; 2] = [
        (
            "rows",
            &|t| t.replacen("\"soil\" 0.4", "\"soil\" 0.5", 1),
            "differ from row 1",
        ),
        (
            "whole",
            // The last row dropped: one element of the structure's material is not listed.
            &|t| {
                let head = t.find("$$START_CONTACT_VOLUME\n").unwrap();
                let rows = head + "$$START_CONTACT_VOLUME\n".len();
                let count_end = rows + t[rows..].find('\n').unwrap();
                let n: usize = t[rows..count_end].parse().unwrap();
                let body = &t[count_end + 1..];
                let last_row = body.split_inclusive('\n').take(n).collect::<Vec<_>>();
                let kept: String = last_row[..n - 1].concat();
                format!(
                    "{}{}\n{kept}{}",
                    &t[..rows],
                    n - 1,
                    &body[last_row.concat().len()..]
                )
            },
            "not listed",
        ),
    ];
    for (name, edit, want) in edits {
        let (gom, _) = pile(dir.path(), name, 1, 0.4, 0.0, &[], "");
        let text = std::fs::read_to_string(&gom).unwrap();
        std::fs::write(&gom, edit(text)).unwrap();
        let o = common::solve(&gom, &dir.path().join(format!("{name}_out")), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains("START_CONTACT_VOLUME") && err.contains(want),
            "{name}: {err}"
        );
    }
    // Strain smoothing with the moving mesh following the soil: Anura3D would smooth the
    // structure with the soil's displacements.
    let (gom, _) = pile(
        dir.path(),
        "smooth_soil",
        1,
        0.4,
        0.0,
        &[("STRAIN_SMOOTHING", "1")],
        "",
    );
    let text = std::fs::read_to_string(&gom).unwrap();
    let follows = "$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n2\n";
    assert!(text.contains(follows));
    std::fs::write(
        &gom,
        text.replace(follows, "$$MOVING_MESH_REFERENCE_MATERIAL_INDEX\n1\n"),
    )
    .unwrap();
    let o = common::solve(&gom, &dir.path().join("smooth_soil_out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("$$STRAIN_SMOOTHING")
            && err.contains("needs the moving mesh to follow the structure's material 2"),
        "{err}"
    );
    // A velocity prescribed on a soil element: with contact it acts on the structure's nodes.
    let (gom, _) = pile(dir.path(), "soil_pushed", 1, 0.4, 0.0, &[], "");
    let text = std::fs::read_to_string(&gom).unwrap();
    let head = "$$PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME\n";
    let at = text.find(head).unwrap() + head.len();
    let first_row = at + text[at..].find('\n').unwrap() + 1;
    let element_end = first_row + text[first_row..].find(' ').unwrap();
    let edited = format!("{}1{}", &text[..first_row], &text[element_end..]);
    std::fs::write(&gom, edited).unwrap();
    let o = common::solve(&gom, &dir.path().join("soil_pushed_out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("PRESCRIBED_MATERIAL_POINT_VELOCITY_VOLUME")
            && err.contains("element 1 is not of the structure's material 2"),
        "{err}"
    );
}

#[test]
fn a_killed_scene_with_contact_resumes_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let scene = pile_scene(dir.path(), "pile", 0.4, 5.0, "");
    // Killed between outputs (the averaged reactions' windows half full), resumed on another
    // thread count.
    common::killed_and_resumed_match(&scene, dir.path(), &[("150", "7"), ("333", "1h")], "1");
}
