//! A laterally confined column of one soil law under a cap, loaded from a uniform start, and
//! the law's own element oedometer to compare it with (tests/cam_clay.rs, tests/hypoplastic.rs).

use std::path::Path;

use mpm_solve::element::tet4::Tet4;
use mpm_solve::material::element_test::{oedometer, Sample};
use mpm_solve::material::law::LawSpec;
use mpm_solve::real::Real;

use super::COLUMN_SIDES;

/// σ'v and σ'h at the start (kPa), and the load added on the top (kPa).
pub const START: (f64, f64) = (100.0, 60.0);
pub const LOAD: f64 = 50.0;

/// A tetrahedral column 0.1 × 1 × 0.1 m of ten cells up, the top one a "cap" of stiffer elastic
/// material that spreads the load evenly over the "soil" below (loaded on its own points,
/// the soil's top layer would be punched; ten times stiffer, not a hundred: a saturated cap
/// of E = 10⁵ kPa crossing into the clay's cells blows up in the explicit scheme), with the surfaces "top"
/// and "bottom", written as Gmsh 2.2 to `dir/capped.msh`.
pub fn capped_column(dir: &Path) -> std::path::PathBuf {
    use std::fmt::Write as _;
    let model =
        mpm_shared::generate::box_mesh([1, 10, 1], [0.1, 1.0, 0.1], mpm_shared::ElementType::Tet4);
    let mut s = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n4\n2 3 \"top\"\n2 4 \"bottom\"\n3 1 \"soil\"\n3 2 \"cap\"\n$EndPhysicalNames\n",
    );
    writeln!(s, "$Nodes\n{}", model.node_count()).unwrap();
    for n in 0..model.node_count() {
        let p = model.node(n);
        writeln!(s, "{} {} {} {}", n + 1, p[0], p[1], p[2]).unwrap();
    }
    let mut lines = Vec::new();
    let y = |v: u32| model.node(v as usize)[1];
    for e in 0..model.element_count() {
        let c = model.element(e);
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let face = f.map(|k| c[k]);
            for (height, tag) in [(1.0, 3), (0.0, 4)] {
                if face.iter().all(|&v| (y(v) - height).abs() < 1e-9) {
                    lines.push(format!(
                        "2 2 {tag} {tag} {} {} {}",
                        face[0] + 1,
                        face[1] + 1,
                        face[2] + 1
                    ));
                }
            }
        }
    }
    for e in 0..model.element_count() {
        let c = model.element(e);
        let centre = c.iter().map(|&v| y(v)).sum::<f64>() / 4.0;
        let tag = if centre > 0.9 { 2 } else { 1 };
        lines.push(format!(
            "4 2 {tag} {tag} {} {} {} {}",
            c[0] + 1,
            c[1] + 1,
            c[2] + 1,
            c[3] + 1
        ));
    }
    writeln!(s, "$EndNodes\n$Elements\n{}", lines.len()).unwrap();
    for (i, l) in lines.iter().enumerate() {
        writeln!(s, "{} {l}", i + 1).unwrap();
    }
    s.push_str("$EndElements\n");
    let path = dir.join("capped.msh");
    std::fs::write(&path, s).unwrap();
    path
}

/// The capped column ([`capped_column`], sides on rollers, base fixed) of soil (`law`'s lines) from a uniform
/// (σ'h, σ'v, σ'h), its top carrying σ'v at first and `LOAD` more ramped over 0.4 s,
/// weightless so that the stress is uniform; `liquid` lines make both materials saturated
/// (drained at the top).
pub fn scene(dir: &Path, liquid: &str, law: &str) -> std::path::PathBuf {
    let text = format!(
        r#"mesh = {mesh:?}
[time]
end = 1.5
courant = 0.5
output_interval = 1.5
[damping]
local = 0.7
[[material]]
physical = "soil"
density = 2650.0
{law}
points_per_element = 4
initial_stress = [-{h}, -{v}, -{h}, 0.0, 0.0, 0.0]
{liquid}
[[material]]
physical = "cap"
density = 2650.0
young = 1.0e4
poisson = 0.0
points_per_element = 4
initial_stress = [0.0, -{v}, 0.0, 0.0, 0.0, 0.0]
{liquid}
[[fixity]]
physical = "bottom"
fixed = [true, true, true]
{COLUMN_SIDES}
[[traction]]
physical = "top"
traction = [0.0, -{top}, 0.0]
curve = [[0.0, {first}], [0.4, 1.0]]
"#,
        mesh = capped_column(dir),
        h = START.1,
        v = START.0,
        top = START.0 + LOAD,
        first = START.0 / (START.0 + LOAD),
    );
    let p = dir.join("clay.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The logarithmic axial strain at which the element oedometer of `law` from `START` carries
/// σ'v = `target`, and its σ'h there.
pub fn element_answer(law: &LawSpec, target: f64) -> (f64, f64) {
    let mut sample = Sample::new(law, START.1, START.0);
    let path = oedometer(&mut sample, &[0.08], 1e-5);
    let i = path.partition_point(|r| r.axial_stress < target);
    let (a, b) = (path[i - 1], path[i]);
    let t = (target - a.axial_stress) / (b.axial_stress - a.axial_stress);
    let radial = |r: &mpm_solve::material::element_test::Record| r.p * 1.5 - r.axial_stress / 2.0;
    (
        a.axial + t * (b.axial - a.axial),
        radial(&a) + t * (radial(&b) - radial(&a)),
    )
}

/// Runs the scene to its end in precision `R`: the column's logarithmic shortening (from the
/// top points' mean displacement), the mean σ'v and σ'h, and the state length.
pub fn run<R: Real>(path: &Path, out: &Path) -> (f64, f64, f64, usize) {
    let case = mpm_solve::input::scene::load(path).unwrap();
    let engine = mpm_solve::driver::run::run_observed::<R, Tet4>(
        &case,
        out,
        &Default::default(),
        &mut |_| {},
    )
    .unwrap();
    let p = &engine.particles;
    // The soil's points (material 1; the cap is 2) in its lower part, below 0.4 m, which
    // move less than a tenth of a cell: higher up the points crossing cells make the stress
    // noisy (by ±7 % at 2 % strain on linear tetrahedra, the smooth-basis issue's subject).
    let soil: Vec<usize> = (0..p.stress.len())
        .filter(|&i| p.material[i] == 1 && p.x[i][1].f64() - p.u[i][1].f64() < 0.4)
        .collect();
    let n = soil.len() as f64;
    let sv = -soil.iter().map(|&i| p.stress[i][1].f64()).sum::<f64>() / n;
    let sh = -soil.iter().map(|&i| p.stress[i][0].f64()).sum::<f64>() / n;
    // The points' vertical displacement grows linearly with their height: its slope is the
    // engineering strain (least squares through the base).
    let (mut num, mut den) = (0.0, 0.0);
    for &i in &soil {
        let (x, u) = (&p.x[i], &p.u[i]);
        let y0 = x[1].f64() - u[1].f64();
        num += y0 * u[1].f64();
        den += y0 * y0;
    }
    let strain = -(1.0 + num / den).ln();

    (strain, sv, sh, p.state_len)
}

/// Checks that a column run (`what`) of `law` ended on the element oedometer's path: its σ'v within
/// `load` of the load (relative), its σ'h within 1 % and its strain within `strain` of the
/// element's at the σ'v it reached. The strain.
pub fn on_the_element_path(
    law: &LawSpec,
    what: &str,
    (strain, sv, sh): (f64, f64, f64),
    load: f64,
    strain_tol: f64,
) -> f64 {
    let (want_strain, want_h) = element_answer(law, sv);
    println!(
        "{what}: strain {strain:.5} (element {want_strain:.5}), σ'v {sv:.3}, σ'h {sh:.3} (element {want_h:.3})"
    );
    assert!(
        (sv / (START.0 + LOAD) - 1.0).abs() < load,
        "{what}: σ'v {sv}"
    );
    assert!(
        (sh / want_h - 1.0).abs() < 1e-2,
        "{what}: σ'h {sh} against {want_h}"
    );
    assert!(
        (strain / want_strain - 1.0).abs() < strain_tol,
        "{what}: {strain} against {want_strain}"
    );
    strain
}

/// The column scene at `path` written as Anura3D's files (without its load curve and uniform
/// initial stresses: Anura3D's loads ramp or step, and its initial stresses come from K0) and
/// read back: the GOM's text and the case.
pub fn exported_and_read_back(path: &Path) -> (String, mpm_solve::input::case::Case) {
    let text = std::fs::read_to_string(path).unwrap();
    let at = text.find("curve = ").unwrap();
    let text: String = text[..at]
        .lines()
        .filter(|l| !l.starts_with("initial_stress"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(path, text).unwrap();
    let out = path.with_extension("a3d");
    mpm_solve::input::export_anura3d::export_scene(path, &out).unwrap();
    let gom = out.join("clay.GOM");
    let (case, _) = mpm_solve::input::anura3d::load(&gom, &out.join("clay.CPS_001")).unwrap();
    (std::fs::read_to_string(&gom).unwrap(), case)
}
