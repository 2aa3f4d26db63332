//! Helpers shared by sfcb's test files.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

use assert_cmd::Command;

/// A file of the workspace's `testdata/`.
pub fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

/// The `sfcb` binary.
pub fn sfcb() -> Command {
    Command::cargo_bin("sfcb").unwrap()
}
