//! The key table's checks of a case ([`crate::input::anura3d_keys`]): every GOM section outside
//! the material blocks and every CPS key.

use std::path::Path;

use mpm_shared::model::Body;

use super::{CaseError, Input};

/// Checks every GOM section (outside material blocks) and every CPS key against the key table
/// ([`crate::input::anura3d_keys`]): keys that would change results and are not modelled stop the case
/// unless they hold their inert value. GOM sections the table does not know are named in a
/// warning (unknown CPS keys are, when the CPS is read).
pub(super) fn check_keys(input: &Input) -> Result<(), CaseError> {
    use crate::input::anura3d_keys::{check, status, KeyKind, KeyStatus};
    let (gfile, cfile) = (input.gfile.as_str(), input.cfile.as_str());
    for sec in &input.model.sections {
        let key = sec.keyword.as_str();
        if mpm_shared::model::is_material_key(key) {
            continue;
        }
        let Some(lines) = section_lines(&sec.body) else {
            continue;
        };
        if status(KeyKind::GomSection, key) == KeyStatus::Unknown {
            log::warn!("{gfile}: section $${key} is not known to this solver and is ignored");
        }
        // The model does not keep line numbers; a refusal looks its section up in the file.
        check(KeyKind::GomSection, key, &lines, gfile, 0)
            .map_err(|r| r.at_line(section_line(input.gom, key)))?;
    }
    for e in &input.cps.entries {
        check(KeyKind::CpsKey, &e.keyword, &e.lines, cfile, e.line)?;
    }
    Ok(())
}

/// A GOM section's content as the key table checks it: nothing for an empty list, a summary
/// line for tables, the text otherwise; `None` for the geometry sections.
pub(super) fn section_lines(body: &Body) -> Option<Vec<String>> {
    Some(match body {
        Body::Table { rows, .. } if rows.is_empty() => Vec::new(),
        Body::Table { rows, .. } => vec![format!("{} rows", rows.len())],
        Body::PerElement(t) => {
            let nonzero = t
                .rows()
                .flatten()
                .filter(|v| v.as_f64().is_some_and(|x| x != 0.0))
                .count();
            if nonzero == 0 {
                Vec::new()
            } else {
                vec![format!("{nonzero} non-zero values")]
            }
        }
        Body::Text(l) => l.clone(),
        Body::Opaque(l) if mpm_shared::model::opaque_is_empty(l) => Vec::new(),
        Body::Opaque(l) => l.clone(),
        _ => return None,
    })
}

/// The 1-based line of the section `$$key` in the GOM file `path` (0 when it cannot be read
/// again, as from standard input).
fn section_line(path: &Path, key: &str) -> usize {
    if mpm_shared::io::is_stdio(path) {
        return 0;
    }
    let Ok(data) = std::fs::read(path) else {
        return 0;
    };
    let head = format!("$${key}");
    data.split(|&b| b == b'\n')
        .position(|l| String::from_utf8_lossy(l).trim() == head)
        .map_or(0, |i| i + 1)
}
