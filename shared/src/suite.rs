//! Where tests and tools find Anura3D's benchmark suite and the Anura3D binaries: the
//! environment variables `ANURA3D_BENCHMARKS` (a folder holding `Benchmarks/`),
//! `ANURA3D_ORACLE` (the 3D binary) and `ANURA3D_ORACLE_2D` (the 2D one, built by
//! `scripts/build-oracle-2d`). A relative value is taken from the workspace root, whatever folder the caller runs
//! in (cargo runs each package's tests in that package's folder). Unset or empty: `Ok(None)`,
//! and the caller says it skipped; set but wrong: an error, never a silent skip.

use std::path::{Path, PathBuf};

/// The variable naming the benchmark folder.
pub const BENCHMARKS_VAR: &str = "ANURA3D_BENCHMARKS";
/// The variable naming the Anura3D binary (3D models).
pub const ORACLE_VAR: &str = "ANURA3D_ORACLE";
/// The variable naming the 2D Anura3D binary (plane strain and axisymmetric models).
pub const ORACLE_2D_VAR: &str = "ANURA3D_ORACLE_2D";

/// Says on the terminal that a test skipped its check and why. Written to the process's
/// standard error directly, past the test harness's capture, so that a skip shows in a plain
/// `cargo test` run instead of passing silently.
pub fn skipped(what: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "skipped: {what}");
}

/// The value of `var` as a path, relative values joined to `workspace_root`.
fn resolve(var: &str, workspace_root: &Path) -> Option<PathBuf> {
    resolve_value(std::env::var_os(var).as_deref(), workspace_root)
}

/// `value` as a path, `None` when absent or empty, relative values joined to `workspace_root`.
fn resolve_value(value: Option<&std::ffi::OsStr>, workspace_root: &Path) -> Option<PathBuf> {
    let v = value.filter(|v| !v.is_empty())?;
    let p = PathBuf::from(v);
    Some(if p.is_relative() {
        workspace_root.join(p)
    } else {
        p
    })
}

/// The benchmark suite's root folder (the one holding `Benchmarks/`), `None` when
/// `ANURA3D_BENCHMARKS` is unset; an error naming the variable when it is set to a folder that
/// does not hold the suite.
pub fn anura3d_benchmarks(workspace_root: &Path) -> Result<Option<PathBuf>, String> {
    benchmarks_at(resolve(BENCHMARKS_VAR, workspace_root), workspace_root)
}

fn benchmarks_at(p: Option<PathBuf>, workspace_root: &Path) -> Result<Option<PathBuf>, String> {
    let Some(p) = p else {
        return Ok(None);
    };
    if p.join("Benchmarks").is_dir() {
        Ok(Some(p))
    } else {
        Err(format!(
            "{BENCHMARKS_VAR} is set, but {} holds no Benchmarks folder (a relative value is taken from the workspace root {})",
            p.display(),
            workspace_root.display()
        ))
    }
}

/// The Anura3D binary, `None` when `ANURA3D_ORACLE` is unset; an error when it is set to
/// something that is not a file.
pub fn anura3d_oracle(workspace_root: &Path) -> Result<Option<PathBuf>, String> {
    binary(
        ORACLE_VAR,
        workspace_root,
        "../shared/anura3d-oracle/build.sh DIR",
    )
}

/// The 2D Anura3D binary, `None` when `ANURA3D_ORACLE_2D` is unset; an error when it is set to
/// something that is not a file.
pub fn anura3d_oracle_2d(workspace_root: &Path) -> Result<Option<PathBuf>, String> {
    binary(ORACLE_2D_VAR, workspace_root, "scripts/build-oracle-2d DIR")
}

fn binary(var: &str, workspace_root: &Path, build: &str) -> Result<Option<PathBuf>, String> {
    let Some(p) = resolve(var, workspace_root) else {
        return Ok(None);
    };
    if p.is_file() {
        Ok(Some(p))
    } else {
        Err(format!(
            "{var} is set, but {} is not a file (build Anura3D with {build})",
            p.display()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn relative_values_are_taken_from_the_workspace_root_and_wrong_ones_fail() {
        let ws = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(ws.path().join("suite/Benchmarks")).unwrap();
        let at =
            |v: Option<&str>| benchmarks_at(resolve_value(v.map(OsStr::new), ws.path()), ws.path());
        assert_eq!(at(None), Ok(None));
        assert_eq!(at(Some("")), Ok(None));
        assert_eq!(at(Some("suite")), Ok(Some(ws.path().join("suite"))));
        let abs = ws.path().join("suite").display().to_string();
        assert_eq!(at(Some(&abs)), Ok(Some(ws.path().join("suite"))));
        let err = at(Some("elsewhere")).unwrap_err();
        assert!(
            err.contains("ANURA3D_BENCHMARKS") && err.contains("elsewhere"),
            "{err}"
        );
    }
}
