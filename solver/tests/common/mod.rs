//! Helpers shared by the command-line test files.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

pub mod gom;
pub mod soil_column;

/// A file of the workspace's `testdata/`.
pub fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// The gravity column scene on the coarse mesh, 20 ms in two outputs, edited by `edit`,
/// written as `dir/scene.toml`.
pub fn scene(dir: &Path, edit: &dyn Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(testdata("column_gravity.toml"))
        .unwrap()
        .replace(
            "column_fine_tet4.msh",
            &testdata("column_tet4.msh").display().to_string(),
        )
        .replace("end = 0.6", "end = 0.02")
        .replace("output_interval = 0.1", "output_interval = 0.01");
    let p = dir.join("scene.toml");
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// A golden column scene (`column_dry` or `column_saturated`) with the mesh path made absolute
/// and `edit` applied, as `dir/NAME.toml`.
pub fn golden_scene(
    dir: &Path,
    golden: &str,
    name: &str,
    edit: &dyn Fn(String) -> String,
) -> PathBuf {
    let text = std::fs::read_to_string(testdata(&format!("golden/{golden}.toml")))
        .unwrap()
        .replace(
            "../column_tet4.msh",
            &testdata("column_tet4.msh").display().to_string(),
        );
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, edit(text)).unwrap();
    p
}

/// The default job's thresholds against Terzaghi, for any of its twins: from T_v = 0.05 on, the
/// default run's RMS pore-pressure error at most 0.05 of u0, and both runs' final settlement
/// within 0.5 % of Terzaghi's.
pub fn assert_terzaghi_thresholds(
    default: &mpm_solve::jobs::consolidation::Tracker,
    workshop: &mpm_solve::jobs::consolidation::Tracker,
) {
    for r in default.records.iter().filter(|r| r.tv >= 0.05 - 1e-9) {
        assert!(r.rms <= 0.05, "default at T_v {}: {}", r.tv, r.rms);
    }
    for t in [default, workshop] {
        let last = t.records.last().unwrap();
        let err = last.settlement / last.terzaghi - 1.0;
        eprintln!(
            "final settlement {:.4e} m, {:+.3}% off Terzaghi, RMS {:.4}",
            last.settlement,
            100.0 * err,
            last.rms
        );
        assert!(err.abs() <= 0.005, "settlement {err}");
    }
}

/// The Anura3D binary `ANURA3D_ORACLE` names, or `None` (the comparison `what` is reported as
/// skipped) when it is unset.
pub fn oracle(what: &str) -> Option<PathBuf> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_oracle(&workspace).unwrap_or_else(|e| panic!("{e}"));
    if found.is_none() {
        mpm_shared::suite::skipped(&format!("{what} (ANURA3D_ORACLE not set)"));
    }
    found
}

/// The 2D Anura3D binary `ANURA3D_ORACLE_2D` names, or `None` (the comparison `what` is
/// reported as skipped) when it is unset.
pub fn oracle_2d(what: &str) -> Option<PathBuf> {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let found = mpm_shared::suite::anura3d_oracle_2d(&workspace).unwrap_or_else(|e| panic!("{e}"));
    if found.is_none() {
        mpm_shared::suite::skipped(&format!("{what} (ANURA3D_ORACLE_2D not set)"));
    }
    found
}

/// The worst difference, relative to each field's largest Anura3D value, of each field of
/// `fields` over the outputs of `ours` paired with Anura3D's run in `anura`, and the number of
/// outputs paired.
pub fn worst_against_anura3d<const N: usize>(
    anura: &Path,
    ours: &Path,
    fields: [&str; N],
) -> ([f64; N], usize) {
    let report = mpm_solve::compare::compare(
        anura,
        ours,
        &mpm_solve::compare::tolerance::Tolerances::default(),
    )
    .unwrap_or_else(|e| panic!("cannot compare {} with Anura3D: {e}", ours.display()));
    let worst = |field: &str| {
        report
            .outputs
            .iter()
            .flat_map(|o| o.fields.iter().filter(|f| f.field == field))
            .map(|f| f.max_rel)
            .fold(0.0f64, f64::max)
    };
    (fields.map(worst), report.outputs.len())
}

/// Benchmark `name` of Anura3D's suite (its `.A3D` folder `src`) run with the CPS keys `set`
/// (`$$KEY`, value line) by Anura3D (`bin`) and by the solver in a temporary folder: every
/// point's position, displacement and stress agree within 1e-10 of each field's largest
/// Anura3D value at each of the `outputs` outputs; prints the worst differences under `label`.
pub fn benchmark_agrees_with_anura3d(
    bin: &Path,
    src: &Path,
    name: &str,
    set: &[(&str, &str)],
    outputs: usize,
    label: &str,
) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(src.join(format!("{name}.GOM")), dir.path().join("b.GOM")).unwrap();
    let cps = std::fs::read_to_string(src.join(format!("{name}.CPS_001"))).unwrap();
    let mut lines: Vec<String> = cps.lines().map(str::to_string).collect();
    for (key, value) in set {
        let k = lines.iter().position(|l| l.trim() == *key).unwrap();
        lines[k + 1] = value.to_string();
    }
    std::fs::write(dir.path().join("b.CPS_001"), lines.join("\n") + "\n").unwrap();
    agrees_with_anura3d(bin, dir.path(), "b", outputs, label);
}

/// `dir/NAME.GOM` + `dir/NAME.CPS_001` run by Anura3D (`bin`) and by the solver (into
/// `dir/ours`, returned): every point's position, displacement and stress agree within 1e-10
/// of each field's largest Anura3D value at each of the `outputs` outputs; prints the worst
/// differences under `label`.
pub fn agrees_with_anura3d(
    bin: &Path,
    dir: &Path,
    name: &str,
    outputs: usize,
    label: &str,
) -> PathBuf {
    let fields = ["position", "displacement", "stress"];
    agrees_in(bin, dir, name, (outputs, label), fields, &[])
}

/// [`agrees_with_anura3d`] for a saturated case: the pore pressures compared too, the drag
/// explicit as Anura3D's.
pub fn agrees_with_anura3d_saturated(
    bin: &Path,
    dir: &Path,
    name: &str,
    outputs: usize,
    label: &str,
) -> PathBuf {
    let fields = ["position", "displacement", "stress", "pore_pressure"];
    agrees_in(
        bin,
        dir,
        name,
        (outputs, label),
        fields,
        &["--drag", "explicit"],
    )
}

/// [`agrees_with_anura3d`] over `fields`, the solver run with `args`.
fn agrees_in<const N: usize>(
    bin: &Path,
    dir: &Path,
    name: &str,
    (outputs, label): (usize, &str),
    fields: [&str; N],
    args: &[&str],
) -> PathBuf {
    run_oracle(bin, dir, name);
    let out = dir.join("ours");
    let o = solve(&dir.join(format!("{name}.GOM")), &out, args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (worst, steps) = worst_against_anura3d(dir, &out, fields);
    let line: Vec<String> = fields
        .iter()
        .zip(&worst)
        .map(|(f, w)| format!("{f} {w:.1e}"))
        .collect();
    eprintln!("{label}: {}", line.join(", "));
    assert_eq!(steps, outputs);
    for (w, f) in worst.iter().zip(fields) {
        assert!(
            *w <= 1e-10,
            "{label}: {f} differs by {w:.2e} of its largest value"
        );
    }
    out
}

/// Runs the `mpm-solve` binary on `input` into `out`, quietly, with `args`.
pub fn solve(input: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
        .arg(input)
        .args(["-q", "--out", out.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap()
}

/// Runs `input` whole on one thread into `dir/full`, then for each `(step, every)` of `cuts`
/// aborts a run on two threads after that step (checkpointing every `every`) and resumes it
/// on `threads_after`: the resumed outputs are the whole run's, byte for byte.
pub fn killed_and_resumed_match(
    input: &Path,
    dir: &Path,
    cuts: &[(&str, &str)],
    threads_after: &str,
) {
    let full = dir.join("full");
    let o = solve(input, &full, &["--threads", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for &(at, every) in cuts {
        let cut = dir.join(format!("cut{at}"));
        let args = [
            "--threads",
            "2",
            "--abort-after-step",
            at,
            "--checkpoint-every",
            every,
        ];
        let first = solve(input, &cut, &args);
        assert!(
            !first.status.success(),
            "the run was to abort after step {at}"
        );
        let resumed = std::process::Command::new(env!("CARGO_BIN_EXE_mpm-solve"))
            .arg(input)
            .args([
                "-q",
                "--resume",
                cut.to_str().unwrap(),
                "--threads",
                threads_after,
            ])
            .output()
            .unwrap();
        assert!(
            resumed.status.success(),
            "{}",
            String::from_utf8_lossy(&resumed.stderr)
        );
        let (a, b) = (outputs(&full), outputs(&cut));
        assert_eq!(
            a.iter().map(|f| &f.0).collect::<Vec<_>>(),
            b.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        for (f, g) in a.iter().zip(&b) {
            assert!(f.1 == g.1, "killed after step {at}: {} differs", f.0);
        }
    }
}

/// Runs Anura3D on `dir/NAME.GOM` + `dir/NAME.CPS_001` in `dir`; fails unless it finishes.
pub fn run_oracle(bin: &Path, dir: &Path, name: &str) {
    let out = std::process::Command::new(bin)
        .arg(name)
        .current_dir(dir)
        .output()
        .expect("run Anura3D");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Calculation finished."),
        "Anura3D did not finish:\n{}",
        &text[text.len().saturating_sub(2000)..]
    );
}

/// The files of `dir` (recursively, but `run.json`, the checkpoint, which holds timings, and
/// the lock), with their bytes.
pub fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap();
            if name == "checkpoint" || name == ".lock" {
                continue;
            }
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().unwrap() != "run.json" {
                let name = path.strip_prefix(dir).unwrap().display().to_string();
                out.push((name, std::fs::read(&path).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// Writes a structured tetrahedral column w × h × w (`cells` cells up, one across) as the Gmsh
/// 2.2 file `dir/column.msh`, with the volume "soil" and the surface "top".
pub fn column_msh(dir: &Path, cells: usize, w: f64, h: f64) -> PathBuf {
    use std::fmt::Write as _;
    let model =
        mpm_shared::generate::box_mesh([1, cells, 1], [w, h, w], mpm_shared::ElementType::Tet4);
    let mut s = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 2 \"top\"\n3 1 \"soil\"\n$EndPhysicalNames\n",
    );
    writeln!(s, "$Nodes\n{}", model.node_count()).unwrap();
    for n in 0..model.node_count() {
        let p = model.node(n);
        writeln!(s, "{} {} {} {}", n + 1, p[0], p[1], p[2]).unwrap();
    }
    let mut top = Vec::new();
    for e in 0..model.element_count() {
        let c = model.element(e);
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let face = f.map(|k| c[k]);
            if face
                .iter()
                .all(|&v| (model.node(v as usize)[1] - h).abs() < 1e-9)
            {
                top.push(face);
            }
        }
    }
    writeln!(
        s,
        "$EndNodes\n$Elements\n{}",
        model.element_count() + top.len()
    )
    .unwrap();
    let mut id = 0;
    for f in &top {
        id += 1;
        writeln!(s, "{id} 2 2 2 4 {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1).unwrap();
    }
    for e in 0..model.element_count() {
        id += 1;
        let c = model.element(e);
        writeln!(
            s,
            "{id} 4 2 1 1 {} {} {} {}",
            c[0] + 1,
            c[1] + 1,
            c[2] + 1,
            c[3] + 1
        )
        .unwrap();
    }
    s.push_str("$EndElements\n");
    let path = dir.join("column.msh");
    std::fs::write(&path, s).unwrap();
    path
}

/// Writes a structured triangle section w × h (`cells` cells up, one across, each square cut
/// into two triangles) in the x-y plane as the Gmsh 2.2 file `dir/section.msh`, with the surface
/// "soil" and the curve "top".
pub fn section_msh(dir: &Path, cells: usize, w: f64, h: f64) -> PathBuf {
    use std::fmt::Write as _;
    let node = |i: usize, j: usize| 1 + i + 2 * j;
    let mut s = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 2 \"top\"\n2 1 \"soil\"\n$EndPhysicalNames\n",
    );
    writeln!(s, "$Nodes\n{}", 2 * (cells + 1)).unwrap();
    for j in 0..=cells {
        for i in 0..2 {
            let y = h * j as f64 / cells as f64;
            writeln!(s, "{} {} {y} 0", node(i, j), w * i as f64).unwrap();
        }
    }
    writeln!(s, "$EndNodes\n$Elements\n{}", 1 + 2 * cells).unwrap();
    writeln!(s, "1 1 2 2 2 {} {}", node(0, cells), node(1, cells)).unwrap();
    for j in 0..cells {
        let (a, b, c, d) = (node(0, j), node(1, j), node(1, j + 1), node(0, j + 1));
        writeln!(s, "{} 2 2 1 1 {a} {b} {c}", 2 + 2 * j).unwrap();
        writeln!(s, "{} 2 2 1 1 {a} {c} {d}", 3 + 2 * j).unwrap();
    }
    s.push_str("$EndElements\n");
    let path = dir.join("section.msh");
    std::fs::write(&path, s).unwrap();
    path
}

/// Runs the scene at `path` in the library (f64, elements `E`) to `end`, calling `each` after
/// every step.
pub fn run_scene<E: mpm_solve::element::Element>(
    path: &Path,
    end: f64,
    mut each: impl FnMut(&mpm_solve::driver::engine::Engine<f64, E>),
) -> mpm_solve::driver::engine::Engine<f64, E> {
    let case = mpm_solve::input::scene::load(path).unwrap();
    let mut engine = mpm_solve::driver::engine::Engine::<f64, E>::new(&case, false).unwrap();
    while engine.time < end * (1.0 - 1e-12) {
        engine.step(engine.dt.min(end - engine.time), None).unwrap();
        each(&engine);
    }
    engine
}

/// The `[[fixity]]` tables of a 0.1 × 0.1 m column's sides on rollers (x = 0, 0.1 and
/// z = 0, 0.1), for scenes on `oracle_column_tet4.msh` and `oedometer_tet4.msh`.
pub const COLUMN_SIDES: &str = r#"[[fixity]]
plane = "x = 0"
fixed = [true, false, false]
[[fixity]]
plane = "x = 0.1"
fixed = [true, false, false]
[[fixity]]
plane = "z = 0"
fixed = [false, false, true]
[[fixity]]
plane = "z = 0.1"
fixed = [false, false, true]
"#;

/// The scene of a laterally confined column on `oracle_column_tet4.msh` (0.1 × 1 × 0.1 m,
/// ρ = 2000 kg/m³, E = 1000 kPa, ν = 0.3, 4 points per element, sides on rollers) under a
/// sudden 10 kPa on its top, until `end` in `outputs` outputs at Courant 0.5: `extra` lines
/// after `[time]` (a `[damping]` table), `liquid` lines after the material (a
/// `[material.liquid]` table, or nothing), the base's fixed components `bottom`.
pub fn oracle_column_scene(
    end: f64,
    outputs: u32,
    extra: &str,
    liquid: &str,
    bottom: &str,
) -> String {
    format!(
        r#"mesh = "{}"
[time]
end = {end}
output_interval = {}
courant = 0.5
{extra}[[material]]
physical = "soil"
density = 2000.0
young = 1000.0
poisson = 0.3
points_per_element = 4
{liquid}[[fixity]]
physical = "bottom"
fixed = {bottom}
{COLUMN_SIDES}[[traction]]
physical = "top"
traction = [0.0, -10.0, 0.0]
"#,
        testdata("oracle_column_tet4.msh").display(),
        end / outputs as f64
    )
}

/// The CPS `text` with the value line of each key of `set` (`$$KEY`, value) replaced.
pub fn with_cps_values(text: &str, set: &[(&str, &str)]) -> String {
    let mut out = String::new();
    let mut next: Option<&str> = None;
    for line in text.lines() {
        match next.take() {
            Some(v) => out.push_str(v),
            None => {
                out.push_str(line);
                next = set.iter().find(|(k, _)| *k == line.trim()).map(|(_, v)| *v);
            }
        }
        out.push('\n');
    }
    out
}

/// Runs a loaded case, writing its files to `.1`, through [`mpm_solve::driver::dispatch`]
/// (its precision and element type chosen at run time).
pub struct Write<'a>(pub &'a mpm_solve::input::case::Case, pub &'a Path);

impl mpm_solve::driver::dispatch::Generic for Write<'_> {
    type Output = Result<(), mpm_solve::driver::run::RunError>;
    fn call<R: mpm_solve::real::Real, E: mpm_solve::element::Element>(self) -> Self::Output {
        mpm_solve::driver::run::run::<R, E>(self.0, self.1, &Default::default()).map(|_| ())
    }
}
