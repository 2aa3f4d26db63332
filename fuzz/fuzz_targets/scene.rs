//! Coverage-guided fuzzing of TOML scenes (see docs/design.md §7.5, "Fuzzing"): the input is the scene's text,
//! written beside a copy of the golden column mesh so that `mesh = "column_tet4.msh"` resolves.
#![no_main]

use std::sync::OnceLock;

fn dir() -> &'static std::path::Path {
    static D: OnceLock<tempfile::TempDir> = OnceLock::new();
    D.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let mesh = concat!(env!("CARGO_MANIFEST_DIR"), "/../testdata/column_tet4.msh");
        std::fs::copy(mesh, d.path().join("column_tet4.msh")).unwrap();
        d
    })
    .path()
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = dir().join("scene.toml");
    std::fs::write(&p, data).unwrap();
    let _ = mpm_solve::input::scene::resolve(&p);
});
