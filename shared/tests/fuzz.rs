//! Truncated and corrupted copies of real meshes must give an error, never a panic.

use std::path::{Path, PathBuf};

use mpm_shared::{gom, msh};
use proptest::prelude::*;

fn testdata(name: &str) -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn corpus() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = ["cube_tet4.GOM", "column_tet10.GOM", "square_tri3.GOM"]
        .iter()
        .map(|n| testdata(n))
        .collect();
    // Real Anura3D files when available: the small ones, to keep the test quick.
    if let Some(root) = std::env::var_os("ANURA3D_BENCHMARKS") {
        let mut stack = vec![PathBuf::from(root)];
        while let Some(d) = stack.pop() {
            let Ok(rd) = std::fs::read_dir(&d) else {
                continue;
            };
            for e in rd.flatten() {
                let p = e.path();
                let n = p.file_name().unwrap().to_string_lossy().to_string();
                if p.is_dir() {
                    stack.push(p);
                } else if (n.ends_with(".GOM") || n.contains(".GOM_stage"))
                    && p.metadata().map(|m| m.len() < 70_000).unwrap_or(false)
                {
                    v.push(std::fs::read(&p).unwrap());
                }
            }
        }
    }
    v
}

/// Byte range of the line that holds byte `i`, terminator included.
fn line_around(d: &[u8], i: usize) -> (usize, usize) {
    let s = d[..i]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let e = d[i..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(d.len(), |p| i + p + 1);
    (s, e)
}

/// Applies a corruption: truncate, overwrite a byte, delete a line, or duplicate a line.
fn corrupt(data: &[u8], op: u8, pos: f64, byte: u8) -> Vec<u8> {
    let i = ((data.len() as f64) * pos) as usize % data.len().max(1);
    let mut d = data.to_vec();
    match op % 5 {
        0 => d.truncate(i),
        1 => d[i] = byte,
        2 => {
            let (s, e) = line_around(&d, i);
            d.drain(s..e);
        }
        3 => {
            let (s, e) = line_around(&d, i);
            let line = d[s..e].to_vec();
            d.splice(s..s, line);
        }
        _ => d.insert(i, byte),
    }
    d
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, .. ProptestConfig::default() })]

    #[test]
    fn corrupted_gom_never_panics(which in any::<prop::sample::Index>(), op in 0u8..5, pos in 0.0f64..1.0, byte in any::<u8>()) {
        let corpus = corpus();
        let src = &corpus[which.index(corpus.len())];
        let bad = corrupt(src, op, pos, byte);
        // Either an error or a model that writes and reads back to itself.
        if let Ok(m) = gom::read(&bad, "fuzz.GOM") {
            let again = gom::read(&gom::write(&m), "rewritten").expect("a model we accepted must re-read");
            prop_assert_eq!(m, again);
        }
    }

    #[test]
    fn corrupted_msh_never_panics(op in 0u8..5, pos in 0.0f64..1.0, byte in any::<u8>(), v22 in any::<bool>()) {
        let src = testdata(if v22 { "cube_tet4_v22.msh" } else { "cube_tet10.msh" });
        let bad = corrupt(&src, op, pos, byte);
        if let Ok(m) = msh::read(&bad, "fuzz.msh") {
            let _ = msh::to_model(&m, "fuzz.msh");
        }
    }
}

#[test]
fn every_truncation_of_a_small_gom_is_an_error() {
    let src = testdata("square_tri3.GOM");
    for cut in 0..src.len() - "$$FINISH\n".len() {
        assert!(
            gom::read(&src[..cut], "cut.GOM").is_err(),
            "truncated at byte {cut} was accepted"
        );
    }
}
