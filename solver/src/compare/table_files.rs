//! Which Anura3D benchmark tables a folder holds: its run's `PROJ.BMS` / `PROJ.BMR`, else the
//! `PROJ_expected` ones of a benchmark folder. Both the folder reader and the table comparison
//! ask this, so it stands apart from both.

use std::path::{Path, PathBuf};

use super::CompareError;

/// The benchmark tables of a folder.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TableFiles {
    /// The `.BMS` file: the run's `PROJ.BMS`, else `PROJ_expected.BMS`.
    pub bms: Option<PathBuf>,
    /// The `.BMR` file, chosen the same way.
    pub bmr: Option<PathBuf>,
}

impl TableFiles {
    /// Finds the tables of `dir`; more than one run table (or, without one, more than one
    /// expected table) of a kind is an error naming them.
    pub fn find(dir: &Path) -> Result<TableFiles, CompareError> {
        let entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| mpm_shared::Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file())
            .collect();
        let pick = |ext: &str| -> Result<Option<PathBuf>, CompareError> {
            let mut all: Vec<&PathBuf> = entries
                .iter()
                .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)))
                .collect();
            all.sort();
            let expected = |p: &&PathBuf| {
                p.file_stem()
                    .is_some_and(|s| s.to_string_lossy().ends_with("_expected"))
            };
            let (exp, run): (Vec<&PathBuf>, Vec<&PathBuf>) = all.into_iter().partition(expected);
            let chosen = if run.is_empty() { exp } else { run };
            match chosen.as_slice() {
                [] => Ok(None),
                [one] => Ok(Some((*one).clone())),
                many => Err(CompareError::NotARun {
                    dir: dir.to_path_buf(),
                    reason: format!(
                        "more than one .{ext} table ({}): which project?",
                        many.iter()
                            .map(|p| p.file_name().unwrap_or_default().to_string_lossy())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                }),
            }
        };
        Ok(TableFiles {
            bms: pick("BMS")?,
            bmr: pick("BMR")?,
        })
    }

    /// True when the folder has a table.
    pub fn any(&self) -> bool {
        self.bms.is_some() || self.bmr.is_some()
    }
}

/// The project name of a table file: its stem without `_expected`.
pub fn project_of(table: &Path) -> String {
    let stem = table
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    stem.strip_suffix("_expected").unwrap_or(&stem).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_tables_are_preferred_to_expected_ones() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path();
        assert_eq!(TableFiles::find(p).unwrap(), TableFiles::default());
        std::fs::write(p.join("case_expected.BMS"), "").unwrap();
        let t = TableFiles::find(p).unwrap();
        assert_eq!(t.bms.unwrap(), p.join("case_expected.BMS"));
        assert_eq!(project_of(&p.join("case_expected.BMS")), "case");
        std::fs::write(p.join("case.BMS"), "").unwrap();
        assert_eq!(
            TableFiles::find(p).unwrap().bms.unwrap(),
            p.join("case.BMS")
        );
        std::fs::write(p.join("other.BMS"), "").unwrap();
        let e = TableFiles::find(p).unwrap_err().to_string();
        assert!(
            e.contains("more than one .BMS table (case.BMS, other.BMS)"),
            "{e}"
        );
    }
}
