//! Absorbing boundaries (`[[absorbing]]`, docs/design.md §4.9): a laterally confined column under
//! a sudden load held on its top, against the closed forms of a plane wave meeting a dashpot:
//! the reflected stress is R = (a − 1)/(a + 1) times the incident one (0 for a = 1, −1/3 for
//! a = 0.5, +1 for a fixed base, which doubles the stress), and with a spring of length δ the
//! base settles by p δ / E_oed. Run in release mode.

mod common;

use std::path::{Path, PathBuf};

use mpm_solve::element::tet4::Tet4;
use mpm_solve::element::tri3::{Tri3, Tri3Axi};
use mpm_solve::element::Element;

/// Column width and height (m), cells along the height, top load (kPa), E (kPa), ν, ρ (kg/m³).
const W: f64 = 0.1;
const H: f64 = 1.0;
const CELLS: usize = 100;
const LOAD: f64 = 10.0;
const YOUNG: f64 = 10_000.0;
const POISSON: f64 = 0.3;
const DENSITY: f64 = 2000.0;

/// The P-wave speed sqrt(E_oed / ρ) (m/s).
fn wave_speed() -> f64 {
    let e_oed = YOUNG * (1.0 - POISSON) / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON));
    (e_oed / (DENSITY / 1000.0)).sqrt()
}

/// A scene of the 3D column (`section` `None`) or of the section (plane strain or
/// axisymmetric, x the radius), with `base` holding its bottom, the sides on rollers, the load
/// held on its top, undamped, until `end`.
fn column_scene(dir: &Path, name: &str, section: Option<&str>, base: &str, end: f64) -> PathBuf {
    let (mesh, head, points, z_rollers) = match section {
        None => (
            common::column_msh(dir, CELLS, W, H),
            String::new(),
            4,
            format!(
                "[[fixity]]\nplane = \"z = 0\"\nfixed = [false, false, true]\n\
             [[fixity]]\nplane = \"z = {W}\"\nfixed = [false, false, true]\n"
            ),
        ),
        Some(s) => (
            common::section_msh(dir, CELLS, W, H),
            format!("section = \"{s}\"\n"),
            3,
            String::new(),
        ),
    };
    let text = format!(
        r#"mesh = "{mesh}"
{head}[time]
end = {end}
output_interval = {end}
courant = 0.5
[[material]]
physical = "soil"
density = {DENSITY}
young = {YOUNG}
poisson = {POISSON}
points_per_element = {points}
[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = {W}"
fixed = [true, false, false]
{z_rollers}[[traction]]
physical = "top"
traction = [0.0, -{LOAD}, 0.0]
{base}
"#,
        mesh = mesh.display()
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// The mean σ_yy over the points between 0.1 H and 0.4 H, as a share of the load, when the
/// front reflected at the base has passed them (t = 1.9 H / c) and nothing else has come back;
/// on the 3D column, or on a section (`Some("plane_strain" | "axisymmetric")`) with element `E`.
fn lower_stress<E: Element>(section: Option<&str>, base: &str) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let end = 1.9 * H / wave_speed();
    let path = column_scene(dir.path(), "column", section, base, end);
    let engine = common::run_scene::<E>(&path, end, |_| {});
    let p = &engine.particles;
    let (sum, n) = (0..p.len())
        .filter(|&i| (0.1 * H..0.4 * H).contains(&p.x[i][1]))
        .fold((0.0, 0), |(s, n), i| (s + p.stress[i][1], n + 1));
    assert!(n > 50, "{n} points");
    -sum / n as f64 / LOAD
}

#[test]
fn a_dashpot_base_reflects_the_closed_forms_share_of_the_front() {
    let fixed = lower_stress::<Tet4>(
        None,
        "[[fixity]]\nplane = \"y = 0\"\nfixed = [true, true, true]",
    );
    let absorbed = lower_stress::<Tet4>(None, "[[absorbing]]\nplane = \"y = 0\"");
    let half = lower_stress::<Tet4>(None, "[[absorbing]]\nplane = \"y = 0\"\nnormal = 0.5");
    eprintln!(
        "σ_yy / p below mid-height after the reflection: fixed base {fixed:.4}, a = 1 {absorbed:.4}, a = 0.5 {half:.4}"
    );
    // A fixed base about doubles it; a = 1 leaves the load; R = (a − 1)/(a + 1) within 0.02.
    assert!((fixed - 2.0).abs() < 0.1, "fixed base: {fixed}");
    assert!((absorbed - 1.0).abs() < 0.05, "a = 1: {absorbed}");
    for (a, measured) in [(1.0, absorbed), (0.5, half)] {
        let r = measured - 1.0;
        let expected = (a - 1.0) / (a + 1.0);
        assert!(
            (r - expected).abs() < 0.02,
            "a = {a}: R = {r}, expected {expected}"
        );
    }
}

#[test]
fn sections_absorb_as_the_column_does() {
    // Plane strain per metre of thickness, axisymmetric per radian (the faces' ∫ r ds).
    for section in ["plane_strain", "axisymmetric"] {
        let run = |base: &str| match section {
            "plane_strain" => lower_stress::<Tri3>(Some(section), base),
            _ => lower_stress::<Tri3Axi>(Some(section), base),
        };
        let absorbed = run("[[absorbing]]\nplane = \"y = 0\"");
        let half = run("[[absorbing]]\nplane = \"y = 0\"\nnormal = 0.5");
        eprintln!("{section}: σ_yy / p below mid-height, a = 1 {absorbed:.4}, a = 0.5 {half:.4}");
        assert!(
            (absorbed - 1.0).abs() < 0.02,
            "{section}, a = 1: {absorbed}"
        );
        assert!(
            (half - 1.0 + 1.0 / 3.0).abs() < 0.02,
            "{section}, a = 0.5: {half}"
        );
    }
}

/// The saturated column (grains 2650 kg/m³, n = 0.4, water K_w = 2.2 GPa, κ = 1e-15 m²: the
/// drag holds both phases together over the wave's passage) on an absorbing base: the mean
/// total vertical stress between 0.1 H and 0.4 H over the load once the front reflected at
/// the base has passed them, and the undrained P-wave speed.
fn saturated_lower_stress(base: &str) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let (n, grains, k_w) = (0.4, 2.65, 2.2e6);
    let e_oed = YOUNG * (1.0 - POISSON) / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON));
    let rho_sat = (1.0 - n) * grains + n;
    let c_u = ((e_oed + k_w / n) / rho_sat).sqrt();
    let end = 1.9 * H / c_u;
    let scene = column_scene(dir.path(), "saturated", None, base, end);
    let text = std::fs::read_to_string(&scene).unwrap().replace(
        &format!("density = {DENSITY}\n"),
        "density = 2650.0\n",
    ).replace(
        "points_per_element = 4\n",
        "points_per_element = 4\n[material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.2e6\nintrinsic_permeability = 1e-15\nviscosity = 1e-6\n",
    );
    std::fs::write(&scene, text).unwrap();
    let engine = common::run_scene::<Tet4>(&scene, end, |_| {});
    let p = &engine.particles;
    let pore = &p.liquid.as_ref().expect("saturated").p;
    let (sum, count) = (0..p.len())
        .filter(|&i| (0.1 * H..0.4 * H).contains(&p.x[i][1]))
        .fold((0.0, 0), |(s, k), i| (s + p.stress[i][1] + pore[i], k + 1));
    (-sum / count as f64 / LOAD, c_u)
}

#[test]
fn a_saturated_column_takes_both_phases_dashpots() {
    // Undrained, the phases move together: the base's impedance is the sum of Anura3D's two
    // dashpots, the solid's (1 − n) ρ_s V_p with the skeleton's drained V_p and the liquid's
    // ρ_w V_w, while the column's is ρ_sat c_u; the front comes back with
    // R = (Z_base − Z_column) / (Z_base + Z_column).
    let fixed = saturated_lower_stress("[[fixity]]\nplane = \"y = 0\"\nfixed = [true, true, true]");
    let (absorbed, c_u) = saturated_lower_stress("[[absorbing]]\nplane = \"y = 0\"");
    let (n, grains, k_w) = (0.4, 2.65, 2.2e6);
    let e_oed = YOUNG * (1.0 - POISSON) / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON));
    let rho_dry = (1.0 - n) * grains;
    let z_base = rho_dry * (e_oed / rho_dry).sqrt() + (k_w * 1.0f64).sqrt();
    let z_column = ((1.0 - n) * grains + n) * c_u;
    let r = (z_base - z_column) / (z_base + z_column);
    eprintln!(
        "saturated: σ_total / p below mid-height, fixed base {:.4}, absorbing base {absorbed:.4} (R = {:.4}; closed form {r:.4})",
        fixed.0,
        absorbed - 1.0
    );
    assert!((fixed.0 - 2.0).abs() < 0.1, "fixed base: {}", fixed.0);
    assert!(
        (absorbed - 1.0 - r).abs() < 0.02,
        "R = {}, closed form {r}",
        absorbed - 1.0
    );
}

#[test]
fn a_spring_holds_the_base_at_p_delta_over_e_oed() {
    let dir = tempfile::tempdir().unwrap();
    let delta = 0.5;
    // Long enough for the dashpot to take the waves out (a = 1 leaves little to ring).
    let end = 40.0 * H / wave_speed();
    let base = format!("[[absorbing]]\nplane = \"y = 0\"\nspring_length = {delta}");
    let path = column_scene(dir.path(), "spring", None, &base, end);
    let engine = common::run_scene::<Tet4>(&path, end, |_| {});
    let p = &engine.particles;
    let (sum, n) = (0..p.len())
        .filter(|&i| p.x[i][1] < 0.5 * H / CELLS as f64)
        .fold((0.0, 0), |(s, n), i| (s + p.u[i][1], n + 1));
    let settled = -sum / n as f64;
    let e_oed = YOUNG * (1.0 - POISSON) / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON));
    let expected = LOAD * delta / e_oed;
    eprintln!("base settlement {settled:.6e} m, p δ / E_oed = {expected:.6e} m");
    assert!(
        (settled / expected - 1.0).abs() < 0.05,
        "{settled} against {expected}"
    );
}

#[test]
fn absorbing_runs_are_the_same_bytes_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let end = 0.5 * H / wave_speed();
    let scene = column_scene(
        d,
        "threads",
        None,
        "[[absorbing]]\nplane = \"y = 0\"\nspring_length = 1.0",
        end,
    );
    let runs: Vec<_> = ["1", "3"]
        .iter()
        .flat_map(|t| ["f64", "f32"].map(|p| (*t, p)))
        .map(|(threads, precision)| {
            let out = d.join(format!("out_{threads}_{precision}"));
            let o = common::solve(
                &scene,
                &out,
                &["--threads", threads, "--precision", precision],
            );
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            common::outputs(&out)
        })
        .collect();
    assert_eq!(runs[0], runs[2], "f64");
    assert_eq!(runs[1], runs[3], "f32");
}

#[test]
fn what_absorbing_boundaries_cannot_do_yet_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            "[[absorbing]]\nplane = \"y = 0.5\"",
            "lies between elements",
        ),
        ("[[absorbing]]\nplane = \"y = -1\"", "selects no face"),
        (
            "[[absorbing]]\nplane = \"y = 0\"\nnormal = -1",
            "absorbing plane \"y = 0\".normal",
        ),
        (
            "[[absorbing]]\nphysical = \"base\"",
            "no physical surface of that name",
        ),
        (
            "[[absorbing]]\nphysical = \"top\"\nplane = \"y = 0\"",
            "give exactly one of",
        ),
    ];
    for (i, (base, expected)) in cases.iter().enumerate() {
        let scene = column_scene(d, &format!("bad{i}"), None, base, 0.001);
        let o = common::solve(&scene, &d.join(format!("out{i}")), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(expected),
            "{base}: {err}"
        );
    }
    let grid = column_scene(
        d,
        "grid",
        None,
        "[[absorbing]]\nplane = \"y = 0\"\n[grid]\ncell = 0.05",
        0.001,
    );
    let o = common::solve(&grid, &d.join("grid_out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("background grid"), "{err}");
    let export = common::solve(
        &column_scene(d, "export", None, "[[absorbing]]\nplane = \"y = 0\"", 0.001),
        &d.join("never"),
        &["--export-anura3d", &d.join("a3d").display().to_string()],
    );
    let err = String::from_utf8_lossy(&export.stderr);
    assert!(
        !export.status.success() && err.contains("[[absorbing]]"),
        "{err}"
    );
}
