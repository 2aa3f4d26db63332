//! Fuzzing every reader of `mpm-shared` on stable Rust (issue 15, docs/design.md §7.5, "Fuzzing"): bad
//! input must give a typed error, never a panic, a hang or an allocation sized by a count the
//! input merely claims.
//!
//! For each reader: (a) every file of its corpus `testdata/fuzz/<reader>/` (minimised inputs that
//! once failed, and small seeds) is replayed; (b) a fixed number of structure-aware mutations of
//! the real test data and the corpus are run, drawn by proptest from a fixed seed so that CI runs
//! the same cases every time. Each case runs under `catch_unwind`, a watchdog and an allocation
//! cap (`fuzz_support::guard`); a failure names the reader, seed file and mutations and saves the
//! input under `target/tmp/fuzz-failures/<reader>/`.
//!
//! Budget: `CASES` per reader, about 10 s for the whole file with `cargo test --release` on 2
//! cores (the solver's scene harness has its own). Coverage-guided fuzzing of the same entry
//! points, for local runs on nightly: `fuzz/` (`cargo fuzz run gom`).

mod fuzz_support;

use fuzz_support::readers::{read_bms, read_cps, read_gom, read_msh, read_pvd, read_vtk, read_vtu};
use fuzz_support::{case, describe, files_under, guard, mutated, CappedAlloc};
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::path::{Path, PathBuf};

#[global_allocator]
static ALLOC: CappedAlloc = CappedAlloc;

/// Mutated cases per reader in CI; `FUZZ_CASES=N` runs N instead (a longer local search).
const CASES: u32 = 5000;

fn cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(CASES)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata")
}

/// The kept corpus of `reader`.
fn corpus(reader: &str) -> Vec<PathBuf> {
    files_under(&root().join("fuzz").join(reader))
}

/// Real test data that seeds `reader`'s mutations, besides its corpus.
fn real_seeds(reader: &str) -> Vec<PathBuf> {
    let t = root();
    let g = t.join("golden");
    let names: Vec<PathBuf> = match reader {
        "gom" => vec![
            t.join("square_tri3.GOM"),
            t.join("cube_tet4.GOM"),
            t.join("cube_tet10.hilbert.GOM"),
            t.join("column_tet4.GOM"),
            g.join("column_anura3d.GOM"),
        ],
        "msh" => vec![
            t.join("square_tri3.msh"),
            t.join("cube_tet4.msh"),
            t.join("cube_tet4_v22.msh"),
            t.join("column_tet4.msh"),
            t.join("cube_tet10.msh"),
        ],
        "cps" => vec![g.join("column_anura3d.CPS_001")],
        "vtu" => vec![
            g.join("column_dry/mesh.vtu"),
            g.join("column_dry/particles_00000.vtu"),
        ],
        "pvd" => vec![g.join("column_dry/run.pvd")],
        _ => vec![],
    };
    names
}

fn seeds(reader: &str) -> Vec<PathBuf> {
    let mut s = real_seeds(reader);
    s.extend(corpus(reader));
    assert!(!s.is_empty(), "no seeds for {reader}");
    s
}

/// What a case runs on its input.
type Exercise = fn(&[u8]);

/// Every reader: its corpus name and the function that exercises it.
const READERS: &[(&str, Exercise)] = &[
    ("gom", read_gom),
    ("msh", read_msh),
    ("cps", read_cps),
    ("vtu", read_vtu),
    ("pvd", read_pvd),
    ("bms", read_bms),
    ("vtk", read_vtk),
];

fn reader(name: &str) -> fn(&[u8]) {
    READERS.iter().find(|r| r.0 == name).expect("a reader").1
}

#[test]
fn the_kept_corpus_replays_without_failure() {
    let mut failures = Vec::new();
    let mut n = 0;
    for &(name, f) in READERS {
        for p in corpus(name) {
            let d = std::fs::read(&p).unwrap();
            n += 1;
            if let Err(e) = guard(name, &p.display().to_string(), &d, f) {
                failures.push(e);
            }
        }
    }
    assert!(n > 0, "the corpus is empty");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Runs `CASES` mutated cases of `name`'s seeds, the same ones every time.
fn fuzz(name: &str) {
    let f = reader(name);
    let paths = seeds(name);
    let data: Vec<Vec<u8>> = paths.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        max_shrink_iters: 512,
        ..Config::default()
    };
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&fuzz_support::fnv(name.as_bytes()).to_le_bytes());
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &key);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let r = runner.run(&case(paths.len()), |(k, muts)| {
        let input = mutated(&data[k], &muts);
        guard(name, &describe(&paths[k], &muts), &input, f).map_err(TestCaseError::fail)
    });
    if let Err(e) = r {
        panic!("{e}");
    }
}

#[test]
fn fuzz_gom() {
    fuzz("gom");
}

#[test]
fn fuzz_msh() {
    fuzz("msh");
}

#[test]
fn fuzz_cps() {
    fuzz("cps");
}

#[test]
fn fuzz_vtu() {
    fuzz("vtu");
}

#[test]
fn fuzz_pvd() {
    fuzz("pvd");
}

#[test]
fn fuzz_bms() {
    fuzz("bms");
}

#[test]
fn fuzz_vtk() {
    fuzz("vtk");
}
