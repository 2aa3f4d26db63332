//! Helpers shared by the command-line test files.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

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
