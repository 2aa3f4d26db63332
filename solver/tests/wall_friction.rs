//! Frictional walls (`[[fixity]] friction = μ`): a block sliding on an inclined base against the
//! closed form of a block on a rough slope, and what the scene reader refuses.

mod common;

use mpm_shared::{generate, ElementType, Model};
use mpm_solve::element::tet4::Tet4;
use mpm_solve::input::case::{Case, MaterialSpec};
use mpm_solve::step::wall_friction::WallAxis;

fn centroid(model: &Model, e: usize) -> [f64; 3] {
    let el = &model.element(e)[..4];
    std::array::from_fn(|a| el.iter().map(|&n| model.node(n as usize)[a]).sum::<f64>() / 4.0)
}

/// A 0.2 × 0.1 × 0.1 m elastic block resting on a base (y = 0) of a 0.8 × 0.2 × 0.1 m mesh of
/// 0.05 m cells, the rest of the mesh empty, under gravity g tilted by `slope` degrees along
/// +x; the base a frictional wall of coefficient `mu`, the z faces smooth. The mean
/// displacement along x of the block's points after `time`.
fn slide(slope: f64, mu: f64, time: f64) -> f64 {
    let model = generate::box_mesh([16, 4, 2], [0.8, 0.2, 0.1], ElementType::Tet4);
    let n = model.node_count();
    let mut fixed = vec![[false; 3]; n];
    let mut walls = vec![[WallAxis::default(); 3]; n];
    for (i, f) in fixed.iter_mut().enumerate() {
        let p = model.node(i);
        if p[1].abs() < 1e-12 {
            // The body lies above the base: on its + side.
            walls[i][1] = WallAxis {
                side: 1.0,
                friction: mu,
            };
        }
        if p[2].abs() < 1e-12 || (p[2] - 0.1).abs() < 1e-12 {
            f[2] = true;
        }
    }
    let material = MaterialSpec::new("block", 2000.0, 1.0e5, 0.2).unwrap();
    let mut case = Case::single_material("slide", model, material, 4, fixed);
    case.boundary.walls = walls;
    case.body.element_material = (0..case.model.element_count())
        .map(|e| {
            let c = centroid(&case.model, e);
            u32::from(c[0] < 0.2 && c[1] < 0.1)
        })
        .collect();
    let g = 9.81;
    let s = slope.to_radians();
    case.loads.gravity = [g * s.sin(), -g * s.cos(), 0.0];
    case.time.end_time = time;
    case.time.output_times = vec![time];
    let dir = tempfile::tempdir().unwrap();
    let mut mean = f64::NAN;
    mpm_solve::driver::run::run_observed::<f64, Tet4>(
        &case,
        dir.path(),
        &Default::default(),
        &mut |e| {
            let p = &e.particles;
            mean = (0..p.len()).map(|i| p.u[i][0]).sum::<f64>() / p.len() as f64;
        },
    )
    .unwrap();
    mean
}

#[test]
fn a_block_slides_down_a_rough_slope_as_the_closed_form_says() {
    let (g, slope, t) = (9.81f64, 30f64, 0.1);
    let s = slope.to_radians();
    for mu in [0.0, 0.3] {
        // x = (g sin θ - μ g cos θ) t² / 2.
        let want = 0.5 * g * (s.sin() - mu * s.cos()) * t * t;
        let got = slide(slope, mu, t);
        let err = (got - want).abs() / want;
        assert!(
            err < 0.005,
            "mu {mu}: slid {got} m, want {want} m ({err:.4})"
        );
    }
    // Friction above tan θ holds the block: it moves only as much as its elastic shear allows
    // (the smooth block slides 24.5 mm in that time).
    let held = slide(slope, 0.7, t);
    assert!(held.abs() < 5e-4, "mu 0.7 let the block slide {held} m");
}

fn load(edit: &dyn Fn(String) -> String) -> Result<Case, String> {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene(dir.path(), edit);
    mpm_solve::input::scene::load(&scene).map_err(|e| e.to_string())
}

#[test]
fn scenes_give_walls_their_side_and_refuse_what_no_wall_can_be() {
    let base = |mu: &str| {
        let mu = mu.to_string();
        move |t: String| {
            t.replace(
                "physical = \"bottom\"\nfixed = [true, true, true]",
                &format!("physical = \"bottom\"\nfixed = [false, true, false]\nfriction = {mu}"),
            )
        }
    };
    let case = load(&base("0.4")).unwrap();
    let mut on_base = 0;
    let none = WallAxis::default();
    let wall = WallAxis {
        side: 1.0,
        friction: 0.4,
    };
    for (n, w) in case.boundary.walls.iter().enumerate() {
        if case.model.node(n)[1].abs() < 1e-12 {
            assert_eq!(*w, [none, wall, none], "node {n}");
            // The wall holds the normal, not a fixity.
            assert!(!case.boundary.fixed[n][1], "node {n}");
            on_base += 1;
        } else {
            assert_eq!(*w, [none; 3], "node {n}");
        }
    }
    assert!(on_base > 0);
    // A wall on the top of the column: the body below it.
    let top = load(&|t: String| {
        t + "\n[[fixity]]\nplane = \"y = 1\"\nfixed = [false, true, false]\nfriction = 0.2\n"
    })
    .unwrap();
    assert!(top
        .boundary
        .walls
        .iter()
        .enumerate()
        .any(|(n, w)| top.model.node(n)[1] > 0.999
            && w[1]
                == WallAxis {
                    side: -1.0,
                    friction: 0.2
                }));
    let refused = |edit: &dyn Fn(String) -> String, want: &[&str]| {
        let err = load(edit).unwrap_err();
        for w in want {
            assert!(err.contains(w), "{err}\nshould say {w}");
        }
    };
    refused(
        &|t: String| {
            t.replace(
                "physical = \"bottom\"\nfixed = [true, true, true]",
                "physical = \"bottom\"\nfixed = [true, true, true]\nfriction = 0.4",
            )
        },
        &["fixity \"bottom\".friction", "3 fixed components"],
    );
    refused(&base("-0.1"), &["bottom", ">= 0"]);
    refused(&base("nan"), &["bottom", "finite"]);
    refused(
        &|t: String| {
            t + "\n[[fixity]]\nplane = \"y = 0.5\"\nfixed = [false, true, false]\nfriction = 0.2\n"
        },
        &[
            "fixity plane \"y = 0.5\".friction",
            "both sides",
            "bound the mesh",
        ],
    );
}
