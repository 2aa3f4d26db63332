//! The semi-implicit two-phase scheme (`--scheme semi-implicit`, a scene's `time.scheme`): the
//! default job at the skeleton's step against Terzaghi, the explicit scheme reproduced where
//! both take the same step, the step kept down to a permeability of 1e-16 m², the same bits
//! for any thread count, and the refusals.

use std::path::{Path, PathBuf};

use mpm_solve::element::tet4::Tet4;
use mpm_solve::input::case::{Case, Scheme};
use mpm_solve::input::scene;
use mpm_solve::jobs::consolidation::{self, Tracker};

mod common;
use common::testdata;

/// The semi-implicit scheme at its default tolerance.
const SEMI: Scheme = Scheme::SemiImplicit {
    tolerance: mpm_solve::step::semi_implicit::DEFAULT_TOLERANCE,
};

/// The default job's scene with `edit` applied (the mesh path made absolute), written in `dir`.
fn oedometer(dir: &Path, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata("oedometer.toml"))
        .unwrap()
        .replace(
            "mesh = \"oedometer_tet4.msh\"",
            &format!("mesh = {:?}", testdata("oedometer_tet4.msh")),
        );
    let path = dir.join("oedometer.toml");
    std::fs::write(&path, edit(text)).unwrap();
    path
}

/// The default job's scene, one point per element, to T_v = 0.2, without the workshop twin, at
/// Courant number `courant`.
fn fast_case(courant: f64, scheme: Scheme) -> Case {
    let dir = tempfile::tempdir().unwrap();
    let path = oedometer(dir.path(), &|t| {
        t.replace("points_per_element = 4", "points_per_element = 1")
            .replace("end_tv = 1.0", "end_tv = 0.2")
            .replace("compare_rest = true", "compare_rest = false")
            .replace("courant = 0.5", &format!("courant = {courant}"))
    });
    let mut case = scene::load(&path).unwrap();
    case.numerics.scheme = scheme;
    case
}

fn run(case: &Case) -> (mpm_solve::driver::engine::Engine<f64, Tet4>, Tracker) {
    let dir = tempfile::tempdir().unwrap();
    consolidation::run_tracked::<f64, Tet4>(case, dir.path(), &Default::default()).unwrap()
}

/// The step `case` takes (one output after 0.1 ms).
fn step_of(case: &Case) -> f64 {
    let mut c = case.clone();
    c.time.end_time = 1e-4;
    c.time.output_times = vec![1e-4];
    run(&c).0.dt
}

/// The default job under the semi-implicit scheme: its step is the skeleton's, over 6× the
/// explicit one for the workshop's soil (E = 1 MPa, K_w = 21.5 MPa, n = 0.4), and both of its
/// runs stay within the default job's thresholds against Terzaghi, the default one's final
/// RMS pore-pressure error within 0.0035 of u0 (the explicit scheme's is 0.0024) and its
/// early ones below the explicit scheme's.
#[test]
fn the_default_job_takes_the_skeletons_step_and_matches_terzaghi() {
    let mut case = scene::load(&testdata("oedometer.toml")).unwrap();
    case.numerics.scheme = SEMI;
    let dir = tempfile::tempdir().unwrap();
    let (engine, default, workshop) =
        consolidation::run_job::<f64, Tet4>(&case, dir.path(), &Default::default()).unwrap();
    let workshop = workshop.expect("the job also runs the workshop set-up");
    common::assert_terzaghi_thresholds(&default, &workshop);
    let last = default.records.last().unwrap();
    eprintln!(
        "semi-implicit default job: {} steps of {:.3e} s, final RMS {:.4}",
        engine.steps, engine.dt, last.rms
    );
    assert!(last.rms <= 0.0035, "final RMS {}", last.rms);
    // The explicit scheme's RMS at T_v = 0.05 is 0.038 (its undrained wave still rings).
    assert!(default.records[0].rms <= 0.03, "{}", default.records[0].rms);
    let explicit = {
        let mut c = case.clone();
        c.numerics.scheme = Scheme::Explicit;
        step_of(&c)
    };
    assert!(
        engine.dt >= 6.0 * explicit,
        "step {} against the explicit {explicit}",
        engine.dt
    );
    let counts = engine.semi_implicit.as_ref().unwrap().counts;
    assert_eq!(counts.solves, engine.steps);
    assert!(counts.worst_residual <= 1e-8);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("run.json")).unwrap())
            .unwrap();
    assert_eq!(report["scheme"]["name"], "semi-implicit");
    assert_eq!(report["scheme"]["pressure_solves"], engine.steps);
}

/// How far the two schemes part when both take the explicit scheme's step at Courant number
/// `courant`: the largest settlement difference over the outputs (share of the settlement) and
/// the largest pore-pressure difference at the end (share of u0).
fn parting(courant: f64) -> (f64, f64) {
    let (explicit, te) = run(&fast_case(courant, Scheme::Explicit));
    // The Courant number that gives the semi-implicit scheme the same step.
    let probe = step_of(&fast_case(courant, SEMI));
    let (semi, ts) = run(&fast_case(courant * explicit.dt / probe, SEMI));
    assert!((semi.dt - explicit.dt).abs() <= 1e-9 * explicit.dt);
    assert_eq!(te.records.len(), ts.records.len());
    let settlement = te
        .records
        .iter()
        .zip(&ts.records)
        .map(|(a, b)| (a.settlement - b.settlement).abs() / a.settlement)
        .fold(0.0, f64::max);
    let u0 = te.layer.u0;
    let (pe, ps) = (
        &explicit.particles.liquid.as_ref().unwrap().p,
        &semi.particles.liquid.as_ref().unwrap().p,
    );
    let id = &semi.particles.id;
    let pressure = (0..pe.len())
        .map(|i| {
            let k = id
                .iter()
                .position(|&j| j == explicit.particles.id[i])
                .unwrap();
            (pe[i] - ps[k]).abs() / u0
        })
        .fold(0.0, f64::max);
    eprintln!(
        "Courant {courant}: settlement within {settlement:.2e}, pore pressure within \
         {pressure:.2e} u0"
    );
    (settlement, pressure)
}

/// Where both take the explicit scheme's own step the two schemes are the same equations but
/// for the pressure's time level (backward Euler, which damps the undrained wave the explicit
/// step carries): to T_v = 0.2 their settlements agree within 0.2 % and every point's pore
/// pressure within 4 % of u0 at Courant 0.5, and the differences shrink with the step (to
/// under half at a quarter of it): both converge to the same solution.
#[test]
fn at_the_explicit_step_it_converges_to_the_explicit_scheme() {
    let coarse = parting(0.5);
    let fine = parting(0.125);
    assert!(coarse.0 <= 2e-3 && coarse.1 <= 0.04, "{coarse:?}");
    assert!(
        fine.0 <= 0.5 * coarse.0 && fine.1 <= 0.5 * coarse.1,
        "{fine:?} against {coarse:?}"
    );
}

/// From the undrained state, at κ = 1e-9 and 1e-16 m² (the drag 10⁷ times stronger), the
/// semi-implicit scheme takes the same step, stays finite and, at 1e-16, undrained: the mean
/// excess pressure below the top row within 1 % of u0.
#[test]
fn a_permeability_of_1e_16_keeps_the_skeletons_step_and_stays_undrained() {
    let mut steps = Vec::new();
    for kappa in ["1.0214e-9", "1e-16"] {
        let dir = tempfile::tempdir().unwrap();
        let path = oedometer(dir.path(), &|t| {
            t.replace("1.0214e-9", kappa)
                .replace("compare_rest = true", "compare_rest = false")
                .replace("output_tv = 0.05", "")
                .replace("end_tv = 1.0", "")
                .replace(
                    "courant = 0.5",
                    "courant = 0.9\nscheme = \"semi-implicit\"\nend = 0.03\noutput_interval = 0.01",
                )
        });
        let case = scene::load(&path).unwrap();
        assert!(case.numerics.scheme.semi_implicit());
        let (engine, tracker) = run(&case);
        steps.push(engine.dt);
        let p = &engine.particles.liquid.as_ref().unwrap().p;
        assert!(p.iter().all(|x| x.is_finite()), "κ = {kappa}");
        if kappa == "1e-16" {
            let u0 = tracker.layer.u0;
            let deep: Vec<f64> = (0..engine.particles.len())
                .filter(|&i| engine.particles.x[i][1] < 0.9)
                .map(|i| -p[i] / u0)
                .collect();
            let mean = deep.iter().sum::<f64>() / deep.len() as f64;
            assert!((mean - 1.0).abs() < 0.01, "mean excess pressure {mean} u0");
        }
    }
    assert_eq!(steps[0].to_bits(), steps[1].to_bits(), "{steps:?}");
}

/// The command line's `--scheme semi-implicit` on the default job with one and with two
/// threads writes the same bytes.
#[test]
fn one_and_two_threads_write_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let input = oedometer(dir.path(), &|t| {
        t.replace("points_per_element = 4", "points_per_element = 1")
            .replace("end_tv = 1.0", "end_tv = 0.1")
    });
    let reports = same_bytes_on_one_and_two_threads(&input, &["--scheme", "semi-implicit"]);
    assert_eq!(reports[0]["scheme"]["name"], "semi-implicit");
}

/// Runs `input` with `args` on one and on two threads, asserts that they write the same files
/// (more than three), and returns both runs' `run.json`.
fn same_bytes_on_one_and_two_threads(input: &Path, args: &[&str]) -> Vec<serde_json::Value> {
    let dir = input.parent().unwrap();
    let (mut written, mut reports) = (Vec::new(), Vec::new());
    for threads in ["1", "2"] {
        let out = dir.join(format!("t{threads}"));
        let o = common::solve(input, &out, &[args, &["--threads", threads]].concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report = std::fs::read_to_string(out.join("run.json")).unwrap();
        reports.push(serde_json::from_str(&report).unwrap());
        written.push(common::outputs(&out));
    }
    assert!(written[0].len() > 3);
    assert!(
        written[0] == written[1],
        "the files differ between 1 and 2 threads"
    );
    reports
}

/// A column of 4,200 tetrahedra (past the count from which the solve's passes run on the
/// team): one and two threads write the same bytes.
#[test]
fn a_solve_shared_among_threads_writes_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = common::column_msh(dir.path(), 700, 0.1, 70.0);
    let text = std::fs::read_to_string(testdata("oedometer.toml")).unwrap();
    let text = text.split("[consolidation]").next().unwrap().to_string();
    let text = text
        .replace("mesh = \"oedometer_tet4.msh\"", &format!("mesh = {mesh:?}"))
        .replace("points_per_element = 4", "points_per_element = 1")
        .replace(
            "courant = 0.5",
            "courant = 0.9\nscheme = \"semi-implicit\"\nend = 0.05\noutput_interval = 0.025",
        )
        .replace("physical = \"bottom\"", "plane = \"y = 0\"");
    let input = dir.path().join("tall.toml");
    std::fs::write(&input, text).unwrap();
    for report in same_bytes_on_one_and_two_threads(&input, &[]) {
        assert!(report["elements"].as_u64().unwrap() >= 4096);
        assert!(report["scheme"]["iterations"].as_u64().unwrap() > 0);
    }
}

/// What the scheme does not model is refused by name before any output: a dry case, the
/// explicit drag; and a tolerance out of range.
#[test]
fn unmodelled_cases_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let dry = common::scene(dir.path(), &|t| t);
    let o = common::solve(
        &dry,
        &dir.path().join("dry"),
        &["--scheme", "semi-implicit"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("semi-implicit scheme") && err.contains("without saturated materials"),
        "{err}"
    );
    assert!(!dir.path().join("dry/run.json").exists());
    let wet = oedometer(dir.path(), &|t| t);
    let o = common::solve(
        &wet,
        &dir.path().join("drag"),
        &["--scheme", "semi-implicit", "--drag", "explicit"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("the explicit drag"), "{err}");
    let bad = oedometer(dir.path(), &|t| {
        t.replace("courant = 0.5", "courant = 0.5\npressure_tolerance = 0.1")
    });
    let o = common::solve(&bad, &dir.path().join("tol"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("time.pressure_tolerance"), "{err}");
}
