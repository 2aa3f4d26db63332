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

/// `gom` with the sections `(keyword, body)` put before `$$NUMBER_OF_MATERIALS`.
fn with_sections(gom: &str, sections: &[(&str, String)]) -> String {
    let mut text = String::new();
    for (k, body) in sections {
        text.push_str(&format!("$${k}\n{body}"));
    }
    gom.replacen(
        "$$NUMBER_OF_MATERIALS",
        &(text + "$$NUMBER_OF_MATERIALS"),
        1,
    )
}

/// Runs the GOM case `dir/NAME` with the explicit drag (Anura3D's), writing into `out`.
fn run_gom(dir: &Path, name: &str, out: &Path) {
    let (mut case, _) = mpm_solve::input::anura3d::load(
        &dir.join(format!("{name}.GOM")),
        &dir.join(format!("{name}.CPS_001")),
    )
    .unwrap();
    assert!(!case.boundary.absorbing.is_empty());
    case.numerics.drag = mpm_solve::input::case::Drag::Explicit;
    struct Run<'a>(&'a mpm_solve::input::case::Case, &'a Path);
    impl mpm_solve::driver::dispatch::Generic for Run<'_> {
        type Output = ();
        fn call<R: mpm_solve::real::Real, E: Element>(self) {
            mpm_solve::driver::run::run::<R, E>(self.0, self.1, &Default::default()).unwrap();
        }
    }
    mpm_solve::driver::dispatch::dispatch(&case, Run(&case, out)).unwrap();
}

/// The worst difference of displacement, stress and pore pressure (relative to each field's
/// largest Anura3D value) over the outputs of Anura3D's run in `anura` and ours of its files
/// (`name`), written to `ours`; and how many outputs paired.
fn ours_against_anura3d(anura: &Path, name: &str, ours: &Path) -> ([f64; 3], usize) {
    run_gom(anura, name, ours);
    common::worst_against_anura3d(anura, ours, ["displacement", "stress", "pore_pressure"])
}

/// A saturated material's liquid, as a scene gives it.
const SATURATED: &str = "[material.liquid]\nporosity = 0.4\ndensity = 1000.0\nbulk_modulus = 2.15e4\nintrinsic_permeability = 1.0214e-9\nviscosity = 1.0e-6\n";

/// The column of [`anura3ds_absorbing_base_matches_anura3d_point_by_point`] exported to
/// Anura3D's files in `dir/a3d` (its material's `liquid` lines, its end time): the GOM's text,
/// the absorbing sections to add to it, the CPS's text, and the exported files.
fn gom_column(
    dir: &Path,
    liquid: &str,
    end: f64,
) -> (
    String,
    Vec<(&'static str, String)>,
    String,
    mpm_solve::input::export_anura3d::Exported,
) {
    let text = common::oracle_column_scene(end, 4, "", liquid, "[true, false, true]");
    let scene = dir.join("c.toml");
    std::fs::write(&scene, text).unwrap();
    let a3d = dir.join("a3d");
    let files = mpm_solve::input::export_anura3d::export_scene(&scene, &a3d).unwrap();
    let gom = std::fs::read_to_string(&files.gom).unwrap();
    let model = mpm_shared::gom::read(gom.as_bytes(), "c.GOM").unwrap();
    let base: Vec<usize> = (0..model.node_count())
        .filter(|&n| model.node(n)[1] == 0.0)
        .collect();
    assert!(base.len() >= 9, "{} base nodes", base.len());
    let rows = |a: &str| {
        let mut s = format!("{}\n", base.len());
        for n in &base {
            s.push_str(&format!("{} 1 0.1 0.3 1 {a} 0.3 1 0.1 0.3\n", n + 1));
        }
        s
    };
    let mut sections = vec![("ABSORBING_BOUNDARY_SURFACE_SOLID", rows("0.5"))];
    if !liquid.is_empty() {
        sections.push(("ABSORBING_BOUNDARY_SURFACE_LIQUID", rows("0.5")));
    }
    sections.push(("ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX", "1\n".into()));
    let cps = std::fs::read_to_string(&files.cps).unwrap();
    (gom, sections, cps, files)
}

/// A column of ours (0.1 × 1 × 0.1 m, 2 × 20 × 2 cells, a sudden 10 kPa on its top, sides on
/// rollers), dry and saturated, whose base rests on Anura3D's absorbing boundary
/// (`$$ABSORBING_BOUNDARY_SURFACE_SOLID`, and `_LIQUID` when saturated: a = 0.5 normal to the
/// base, δ = 0.3 m), its increments from the points' sums (Anura3D's default) and
/// from the nodes (`$$APPLY_NODE_DATA_AB 1`), run by the 3D Anura3D and by us: every
/// point's displacement, effective stress and pore pressure agree within 1e-10 of their
/// largest values at each of four outputs; and the two rules' answers part. (The points'
/// sums are not normalised: a node takes several times its own motion, and with a = 1 the
/// lagged dashpot sinks the column in both codes.)
#[test]
fn anura3ds_absorbing_base_matches_anura3d_point_by_point() {
    let Some(bin) = common::oracle("Anura3D's absorbing boundary against Anura3D") else {
        return;
    };
    for (phases, liquid, end) in [("dry", "", 0.08), ("saturated", SATURATED, 0.02)] {
        let dir = tempfile::tempdir().unwrap();
        let (gom, sections, cps, files) = gom_column(dir.path(), liquid, end);
        for (mode, node_data) in [("point sums", false), ("node data", true)] {
            let run = dir.path().join(format!("{}", node_data as u8));
            std::fs::create_dir_all(&run).unwrap();
            std::fs::write(run.join("c.GOM"), with_sections(&gom, &sections)).unwrap();
            let cps = if node_data {
                cps.replace("$$END", "$$APPLY_NODE_DATA_AB\n1\n$$END")
            } else {
                cps.clone()
            };
            std::fs::write(run.join("c.CPS_001"), cps).unwrap();
            common::run_oracle(&bin, &run, "c");
            let (w, outputs) = ours_against_anura3d(&run, "c", &run.join("ours"));
            eprintln!(
                "{phases} column, {mode}: u {:.1e}, σ' {:.1e}, p {:.1e} over {outputs} outputs",
                w[0], w[1], w[2]
            );
            assert_eq!(outputs, 4);
            for (v, f) in w.iter().zip(["displacement", "σ'", "p"]) {
                assert!(*v <= 1e-10, "{phases}, {mode}: {f} differs by {v:.2e}");
            }
        }
        // The boundary acts, and the two rules differ: the nodes' rule's stresses part from
        // the points' sums' run.
        let (w, _) = common::worst_against_anura3d(
            &dir.path().join("0"),
            &dir.path().join("1").join("ours"),
            ["stress"],
        );
        eprintln!("{phases} column: the two rules part by σ' {:.1e}", w[0]);
        assert!(w[0] > 1e-3, "{phases}: the rules agree within {:.1e}", w[0]);
        if !liquid.is_empty() {
            // The liquid's boundary counts too: without its rows the pore pressures part.
            let solid_only = dir.path().join("solid_only");
            std::fs::create_dir_all(&solid_only).unwrap();
            let keep = [sections[0].clone(), sections[2].clone()];
            std::fs::write(solid_only.join("c.GOM"), with_sections(&gom, &keep)).unwrap();
            std::fs::copy(&files.cps, solid_only.join("c.CPS_001")).unwrap();
            let out = solid_only.join("ours");
            run_gom(&solid_only, "c", &out);
            let (w, _) =
                common::worst_against_anura3d(&dir.path().join("0"), &out, ["pore_pressure"]);
            eprintln!(
                "without the liquid's rows the pore pressures part by {:.1e}",
                w[0]
            );
            assert!(
                w[0] > 1e-3,
                "the liquid's boundary changes p by {:.1e}",
                w[0]
            );
        }
    }
}

/// Anura3D's own absorbing-boundary benchmark (`Oedometer_AbsorbingBoundary_GravityLoading_2D`,
/// a plane-strain column under its weight on an absorbing base), run as MPM (`MPM-MP`: the
/// benchmark is FEM) over four load steps of 0.25 s, its base freed in y so that the boundary
/// carries the column (the benchmark also fixes it, which leaves the boundary idle) with
/// δ = 0.01 m, by the 2D Anura3D and by us, with the points' sums and with the nodes' data:
/// displacement and stress within 1e-10 of their largest values at every output.
#[test]
fn anura3ds_2d_absorbing_benchmark_matches_the_2d_oracle() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let oracle = mpm_shared::suite::anura3d_oracle_2d(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let suite = mpm_shared::suite::anura3d_benchmarks(&workspace).unwrap_or_else(|e| panic!("{e}"));
    let (Some(bin), Some(suite)) = (oracle, suite) else {
        mpm_shared::suite::skipped(
            "the 2D absorbing boundary against Anura3D (ANURA3D_ORACLE_2D or ANURA3D_BENCHMARKS not set)",
        );
        return;
    };
    let name = "Oedometer_AbsorbingBoundary_GravityLoading_2D";
    let src = suite.join(format!(
        "Benchmarks/Pre-Commit_Tests/{name}/{name}.A3D/{name}"
    ));
    let gom = std::fs::read_to_string(src.with_extension("GOM")).unwrap();
    let at = gom.find("$$START_FIXITY_LINE_SOLID").unwrap();
    let mut fixities = gom[at..].to_string();
    for (fixed, free) in [
        ("\n1 1 1\n", "\n1 1 0\n"),
        ("\n3 0 1\n", "\n3 0 0\n"),
        ("\n6 1 1\n", "\n6 1 0\n"),
    ] {
        assert!(fixities.contains(fixed));
        fixities = fixities.replacen(fixed, free, 1);
    }
    let gom = format!("{}{fixities}", &gom[..at]).replace(" 1 1.5 15\n", " 1 1.5 0.01\n");
    let cps = common::with_cps_values(
        &std::fs::read_to_string(src.with_extension("CPS_001")).unwrap(),
        &[
            ("$$COMPUTATION_METHOD", "MPM-MP"),
            ("$$NUMBER_OF_LOADSTEPS", "4"),
            ("$$TIME_PER_LOADSTEP", "0.25"),
            ("$$QUASISTATIC_CONVERGENCE", "0"),
            ("$$VISUALIZATION_OPTION", "VTK"),
        ],
    );
    for (rule, node_data) in [("point sums", false), ("node data", true)] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("b.GOM"), &gom).unwrap();
        let cps = if node_data {
            cps.replace("$$END", "$$APPLY_NODE_DATA_AB\n1\n$$END")
        } else {
            cps.clone()
        };
        std::fs::write(dir.path().join("b.CPS_001"), cps).unwrap();
        common::run_oracle(&bin, dir.path(), "b");
        let (w, outputs) = ours_against_anura3d(dir.path(), "b", &dir.path().join("ours"));
        eprintln!(
            "2D benchmark, {rule}: u {:.1e}, σ' {:.1e} over {outputs} outputs",
            w[0], w[1]
        );
        assert_eq!(outputs, 4);
        for (v, f) in w.iter().zip(["displacement", "σ'"]) {
            assert!(*v <= 1e-10, "{rule}: {f} differs by {v:.2e}");
        }
    }
}

/// Anura3D's absorbing boundary (its accumulated forces, the last step's motion, and with the
/// points' sums each point's increment, which follow the points' re-sorting) goes through a
/// checkpoint: the saturated column of [`anura3ds_absorbing_base_matches_anura3d_point_by_point`]
/// killed after step 30 (checkpoints every 7 steps, two threads) and resumed on one thread ends
/// with the uninterrupted run's files, byte for byte, with either rule.
#[test]
fn anura3ds_absorbing_base_resumes_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let (gom, sections, cps, _) = gom_column(dir.path(), SATURATED, 0.02);
    for node_data in [false, true] {
        let run = dir.path().join(format!("{}", node_data as u8));
        std::fs::create_dir_all(&run).unwrap();
        let input = run.join("c.GOM");
        std::fs::write(&input, with_sections(&gom, &sections)).unwrap();
        let cps = if node_data {
            cps.replace("$$END", "$$APPLY_NODE_DATA_AB\n1\n$$END")
        } else {
            cps.clone()
        };
        std::fs::write(run.join("c.CPS_001"), cps).unwrap();
        let (full, cut) = (run.join("full"), run.join("cut"));
        let o = common::solve(&input, &full, &["--threads", "1"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let every = ["--checkpoint-every", "7", "--threads"];
        let killed = common::solve(
            &input,
            &cut,
            &[&every[..], &["2", "--abort-after-step", "30"]].concat(),
        );
        assert!(!killed.status.success(), "the run was to abort");
        let resumed = std::process::Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
            .arg(&input)
            .args(["-q", "--resume", cut.to_str().unwrap(), "--threads", "1"])
            .args(&every[..2])
            .output()
            .unwrap();
        assert!(
            resumed.status.success(),
            "{}",
            String::from_utf8_lossy(&resumed.stderr)
        );
        assert!(
            common::outputs(&full) == common::outputs(&cut),
            "node data {node_data}: the resumed run's files differ"
        );
    }
}

/// What Anura3D's absorbing boundary sections cannot hold is refused, naming the section: gas
/// rows, a flagged axis without a spring length (Anura3D divides by it), a missing reference
/// material, liquid rows on a dry reference material.
#[test]
fn bad_absorbing_sections_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let (gom, sections, cps, _) = gom_column(dir.path(), "", 0.02);
    let solid = sections[0].1.clone();
    let reference = (
        "ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX",
        "1\n".to_string(),
    );
    let zero_delta = solid.replacen(" 0.5 0.3 ", " 0.5 0.0 ", 1);
    assert_ne!(zero_delta, solid);
    for (what, sections, expect) in [
        (
            "gas rows",
            vec![
                ("ABSORBING_BOUNDARY_SURFACE_GAS", solid.clone()),
                reference.clone(),
            ],
            "gas phases are not modelled",
        ),
        (
            "δ = 0",
            vec![
                ("ABSORBING_BOUNDARY_SURFACE_SOLID", zero_delta),
                reference.clone(),
            ],
            "Anura3D divides the spring by it",
        ),
        (
            "no reference material",
            vec![("ABSORBING_BOUNDARY_SURFACE_SOLID", solid.clone())],
            "$$ABSORBING_BOUNDARY_REFERENCE_MATERIAL_INDEX: missing",
        ),
        (
            "liquid rows on a dry material",
            vec![
                ("ABSORBING_BOUNDARY_SURFACE_LIQUID", solid.clone()),
                reference.clone(),
            ],
            "the reference material is not saturated",
        ),
    ] {
        let run = dir.path().join(what.replace(' ', "_"));
        std::fs::create_dir_all(&run).unwrap();
        std::fs::write(run.join("c.GOM"), with_sections(&gom, &sections)).unwrap();
        std::fs::write(run.join("c.CPS_001"), &cps).unwrap();
        let e = mpm_solve::input::anura3d::load(&run.join("c.GOM"), &run.join("c.CPS_001"))
            .err()
            .unwrap_or_else(|| panic!("{what}: accepted"))
            .to_string();
        assert!(
            e.contains(expect) && e.contains("ABSORBING_BOUNDARY"),
            "{what}: {e}"
        );
    }
}
