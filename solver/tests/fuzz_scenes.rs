//! Fuzzing TOML scenes (issue 15, docs/design.md §7.5, "Fuzzing"): "any input that reads must either run or
//! stop with a named error".
//!
//! - `fuzz_scene_reading`: the kept corpus `testdata/fuzz/scene/` replayed, then `CASES`
//!   structure-aware mutations of the real scenes (fixed proptest seed, so CI runs the same
//!   cases), each resolved into a case under `catch_unwind`, a watchdog and an allocation cap
//!   (the harness of `shared/tests/fuzz_readers.rs`).
//! - `readable_but_odd_inputs_run_or_stop_by_name`: scenes and meshes that read but hold
//!   negative, zero, huge or non-finite values, degenerate elements or unknown groups, run by the
//!   `mpm-solve` binary with `--check` and for a few steps; the exit code must be 0 (ran), 1
//!   (input error) or 3 (diverged), never a panic (101) or a signal.
//!
//! Budget: about 5 s for the file with `cargo test --release` on 2 cores (each binary run takes
//! a few tens of milliseconds).

#[path = "../../shared/tests/fuzz_support/mod.rs"]
mod fuzz_support;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;
use std::time::Duration;

use assert_cmd::Command;
use fuzz_support::{case, describe, files_under, guard_with_cap, mutated, CappedAlloc};
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};

#[global_allocator]
static ALLOC: CappedAlloc = CappedAlloc;

/// Mutated scenes resolved in CI; `FUZZ_CASES=N` runs N instead.
const CASES: u32 = 2000;

/// A scene may size one allocation by its own values up to the documented limits (10^7 output
/// times); nothing beyond.
const SCENE_CAP: usize = 256 << 20;

fn testdata() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata")
}

/// `text` with its `mesh = "..."` made absolute (relative to `dir`), so it resolves from anywhere.
fn absolute_mesh(text: &str, dir: &Path) -> String {
    text.lines()
        .map(|l| match l.trim_start().strip_prefix("mesh = \"") {
            Some(rest) => {
                let rel = rest.split('"').next().unwrap_or("");
                format!("mesh = {:?}", dir.join(rel).display().to_string())
            }
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// The real scenes and the kept corpus, meshes made absolute: `(name, text)`.
fn seeds() -> Vec<(PathBuf, Vec<u8>)> {
    let t = testdata();
    let mut paths = vec![
        t.join("golden/column_dry.toml"),
        t.join("golden/column_saturated.toml"),
        t.join("column_gravity.toml"),
        t.join("oedometer.toml"),
    ];
    // The corpus: scenes, and the meshes some of them name.
    paths.extend(
        files_under(&t.join("fuzz/scene"))
            .into_iter()
            .filter(|p| p.extension().is_some_and(|e| e == "toml")),
    );
    paths
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let fixed = absolute_mesh(&text, p.parent().unwrap());
            (p, fixed.into_bytes())
        })
        .collect()
}

/// Resolves the scene `d` (written to a scratch file) into a case; errors are fine.
fn resolve_scene(d: &[u8]) {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let dir = DIR.get_or_init(|| tempfile::tempdir().unwrap());
    let p = dir
        .path()
        .join(format!("s{}.toml", NEXT.fetch_add(1, Ordering::Relaxed)));
    std::fs::write(&p, d).unwrap();
    let r = mpm_solve::input::scene::resolve(&p);
    let _ = std::fs::remove_file(&p);
    if let Ok(r) = r {
        std::hint::black_box(r.case.time.output_times.len());
    }
}

fn cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(CASES)
}

#[test]
fn fuzz_scene_reading() {
    let seeds = seeds();
    // (a) The kept corpus, as is.
    for (p, d) in &seeds {
        if let Err(e) = guard_with_cap(
            "scene",
            &p.display().to_string(),
            d,
            resolve_scene,
            SCENE_CAP,
        ) {
            panic!("{e}");
        }
    }
    // (b) Mutations.
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        max_shrink_iters: 256,
        ..Config::default()
    };
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &[15; 32]);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let r = runner.run(&case(seeds.len()), |(k, muts)| {
        let input = mutated(&seeds[k].1, &muts);
        let label = describe(&seeds[k].0, &muts);
        guard_with_cap("scene", &label, &input, resolve_scene, SCENE_CAP)
            .map_err(TestCaseError::fail)
    });
    if let Err(e) = r {
        panic!("{e}");
    }
}

/// The golden dry column with its mesh absolute, run for about 5 steps.
fn base_scene(mesh: &Path) -> String {
    let text = std::fs::read_to_string(testdata().join("golden/column_dry.toml")).unwrap();
    absolute_mesh(&text, &testdata().join("golden"))
        .replace(
            &format!(
                "{:?}",
                testdata()
                    .join("golden/../column_tet4.msh")
                    .display()
                    .to_string()
            ),
            &format!("{:?}", mesh.display().to_string()),
        )
        .replace("end = 0.01", "end = 0.0005")
        .replace("output_interval = 0.005", "output_interval = 0.00025")
}

/// The golden column mesh with node `tag`'s coordinates replaced by `xyz`.
fn moved_node(tag: usize, xyz: &str) -> String {
    let text = std::fs::read_to_string(testdata().join("column_tet4.msh")).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // 4.1 node blocks: the tags, then the coordinates in the same order.
    let start = lines.iter().position(|l| l == "$Nodes").unwrap();
    let mut i = start + 2;
    loop {
        let head: Vec<usize> = lines[i].split(' ').map(|v| v.parse().unwrap()).collect();
        let n = head[3];
        if let Some(k) = (0..n).find(|&k| lines[i + 1 + k] == tag.to_string()) {
            lines[i + 1 + n + k] = xyz.to_string();
            break;
        }
        i += 1 + 2 * n;
    }
    lines.join("\n") + "\n"
}

/// Runs `mpm-solve` on `scene`; returns the exit code and the last line of its messages, failing
/// on a panic, a signal or a hang.
fn run_solver(name: &str, scene: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::cargo_bin("mpm-solve")
        .unwrap()
        .arg(scene)
        .args(["--quiet", "--threads", "2"])
        .args(args)
        .timeout(Duration::from_secs(60))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    assert!(
        matches!(code, Some(0 | 1 | 3)) && !stderr.contains("panicked"),
        "{name} ({args:?}): exit {code:?} (0, 1 or 3 expected; 101 is a panic, none a signal or the \
         60 s timeout)\n{stderr}"
    );
    if code == Some(1) {
        assert!(
            !stderr.trim().is_empty(),
            "{name}: exit 1 without a message"
        );
    }
    let last = stderr.lines().last().unwrap_or("").to_string();
    (code.unwrap(), last)
}

#[test]
fn readable_but_odd_inputs_run_or_stop_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let golden_mesh = testdata().join("column_tet4.msh");
    // Meshes that read: a node moved onto another (degenerate elements), a node far away, a
    // 2D mesh where a 3D one is needed.
    let meshes = [
        ("collapsed", moved_node(1, "0 0 0.1")),
        ("far", moved_node(5, "1e300 1e300 1e300")),
    ];
    let mut mesh_paths = vec![("golden".to_string(), golden_mesh.clone())];
    for (n, text) in meshes {
        let p = dir.path().join(format!("{n}.msh"));
        std::fs::write(&p, text).unwrap();
        mesh_paths.push((n.to_string(), p));
    }
    mesh_paths.push(("2d".into(), testdata().join("square_tri3.msh")));
    let base = base_scene(&golden_mesh);
    type Edit = (&'static str, &'static str, &'static str);
    // (name, text to replace, replacement) on the golden dry column.
    let edits: &[Edit] = &[
        ("unchanged", "", ""),
        ("zero density", "density = 2000.0", "density = 0.0"),
        ("negative density", "density = 2000.0", "density = -2000.0"),
        ("huge density", "density = 2000.0", "density = 1e300"),
        ("nan density", "density = 2000.0", "density = nan"),
        ("zero young", "young = 10000.0", "young = 0.0"),
        ("negative young", "young = 10000.0", "young = -1.0"),
        ("infinite young", "young = 10000.0", "young = inf"),
        ("huge young", "young = 10000.0", "young = 1e300"),
        ("tiny young", "young = 10000.0", "young = 1e-300"),
        ("poisson 0.5", "poisson = 0.3", "poisson = 0.5"),
        ("poisson -1", "poisson = 0.3", "poisson = -1.0"),
        ("poisson nan", "poisson = 0.3", "poisson = nan"),
        ("no points", "points_per_element = 1", "points_per_element = 0"),
        ("many points", "points_per_element = 1", "points_per_element = 4294967295"),
        ("odd points", "points_per_element = 1", "points_per_element = 7"),
        ("nan gravity", "[0.0, -9.81, 0.0]", "[nan, -9.81, 0.0]"),
        ("huge gravity", "[0.0, -9.81, 0.0]", "[0.0, -1e300, 0.0]"),
        ("full damping", "local = 0.75", "local = 1.0"),
        ("negative damping", "local = 0.75", "local = -0.5"),
        ("nan damping", "local = 0.75", "local = nan"),
        ("zero courant", "courant = 0.5", "courant = 0.0"),
        ("tiny courant", "courant = 0.5", "courant = 1e-12"),
        ("courant 2", "courant = 0.5", "courant = 2.0"),
        ("nan courant", "courant = 0.5", "courant = nan"),
        ("zero end", "end = 0.0005", "end = 0.0"),
        ("huge end", "end = 0.0005", "end = 1e300\nmax_steps = 5"),
        ("infinite end", "end = 0.0005", "end = inf"),
        ("nan end", "end = 0.0005", "end = nan"),
        ("tiny interval", "output_interval = 0.00025", "output_interval = 1e-300"),
        ("infinite interval", "output_interval = 0.00025", "output_interval = inf"),
        ("zero steps", "end = 0.0005", "end = 0.0005\nmax_steps = 0"),
        ("probe 0", "probes = [1, 200, 461]", "probes = [0]"),
        ("probe past the end", "probes = [1, 200, 461]", "probes = [4294967295]"),
        ("duplicate probes", "probes = [1, 200, 461]", "probes = [1, 1, 1]"),
        ("unknown physical", "physical = \"soil\"", "physical = \"rock\""),
        ("unknown fixity", "physical = \"bottom\"", "physical = \"nowhere\""),
        ("fixity on a volume", "physical = \"bottom\"", "physical = \"soil\""),
        ("plane far away", "plane = \"x = 0\"", "plane = \"x = 1e300\""),
        ("plane nan", "plane = \"x = 0\"", "plane = \"x = nan\""),
        ("plane bad axis", "plane = \"x = 0\"", "plane = \"q = 0\""),
        ("precision f16", "probes = [", "precision = \"f16\"\nprobes = ["),
        ("precision f32", "probes = [", "precision = \"f32\"\nprobes = ["),
        (
            "traction on an unknown group",
            "[[fixity]]\nphysical = \"bottom\"",
            "[[traction]]\nphysical = \"nowhere\"\ntraction = [0.0, -10.0, 0.0]\n\n[[fixity]]\nphysical = \"bottom\"",
        ),
        (
            "huge traction",
            "[[fixity]]\nphysical = \"bottom\"",
            "[[traction]]\nphysical = \"top\"\ntraction = [0.0, -1e300, 0.0]\n\n[[fixity]]\nphysical = \"bottom\"",
        ),
        (
            "nan traction",
            "[[fixity]]\nphysical = \"bottom\"",
            "[[traction]]\nphysical = \"top\"\ntraction = [nan, 0.0, 0.0]\nramp = -1.0\n\n[[fixity]]\nphysical = \"bottom\"",
        ),
        (
            "traction on a volume",
            "[[fixity]]\nphysical = \"bottom\"",
            "[[traction]]\nphysical = \"soil\"\ntraction = [0.0, -10.0, 0.0]\n\n[[fixity]]\nphysical = \"bottom\"",
        ),
        (
            "consolidation without liquid",
            "[gravity]",
            "[consolidation]\nload = 10.0\n\n[gravity]",
        ),
        (
            "saturated with zero porosity",
            "points_per_element = 1",
            "points_per_element = 1\nliquid = { porosity = 0.0, density = 1000.0, bulk_modulus = 1e5, intrinsic_permeability = 1e-12, viscosity = 1e-6 }",
        ),
        (
            "saturated with negative permeability",
            "points_per_element = 1",
            "points_per_element = 1\nliquid = { porosity = 0.4, density = 1000.0, bulk_modulus = 1e5, intrinsic_permeability = -1.0, viscosity = 0.0 }",
        ),
        (
            "saturated with infinite bulk modulus",
            "points_per_element = 1",
            "points_per_element = 1\nliquid = { porosity = 0.4, density = 1000.0, bulk_modulus = inf, intrinsic_permeability = 1e-12, viscosity = 1e-6 }",
        ),
    ];
    let mut n = 0;
    let mut codes = std::collections::BTreeMap::new();
    let mut run = |name: String, text: String| {
        let p = dir.path().join(format!("case{n}.toml"));
        n += 1;
        std::fs::write(&p, &text).unwrap();
        let out = dir.path().join(format!("out{n}"));
        let (a, _) = run_solver(&name, &p, &["--check"]);
        let (b, why) = run_solver(&name, &p, &["--out", out.to_str().unwrap()]);
        eprintln!("{name}: --check {a}, run {b}: {why}");
        *codes.entry((a, b)).or_insert(0) += 1;
    };
    for &(name, from, to) in edits {
        assert!(
            base.contains(from),
            "{name}: '{from}' not in the base scene"
        );
        run(name.to_string(), base.replacen(from, to, 1));
    }
    for (name, mesh) in &mesh_paths[1..] {
        run(
            format!("mesh {name}"),
            base.replace(
                &format!("{:?}", golden_mesh.display().to_string()),
                &format!("{:?}", mesh.display().to_string()),
            ),
        );
    }
    // The kept scene corpus through the binary too.
    for (p, text) in seeds().into_iter().skip(4) {
        run(
            format!("corpus {}", p.display()),
            String::from_utf8(text).unwrap(),
        );
    }
    // Exit codes (--check, run) -> how many inputs gave them, for the log.
    eprintln!("exit codes (--check, run): {codes:?}");
}
