//! The scene reference against the scene reader: each key table lists exactly the keys its
//! reader accepts (read back from the reader's own message about an unknown key), the
//! `[[material]]` table takes every law's parameters from the registry, and the Markdown
//! reference has a section per table and per law.

use std::collections::BTreeSet;
use std::path::Path;

use mpm_solve::input::scene::reference::{reference_markdown, scene_key, tables, Table};
use mpm_solve::material::law;

/// A key no reader knows.
const UNKNOWN: &str = "no_such_key";

/// The scene reader's message for `text` (which must be refused).
fn refusal(dir: &Path, stem: &str, text: &str) -> String {
    let path = dir.join(format!("{stem}.toml"));
    std::fs::write(&path, text).unwrap();
    match mpm_solve::input::scene::load(&path) {
        Ok(_) => panic!("{stem}: accepted\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A scene holding only `table` (inside its parent where it is a sub-table), with an unknown
/// key first in it: the reader stops there, before any check of what is missing.
fn scene_with_unknown_key(table: &Table) -> String {
    let mut text = String::new();
    if let Some((parent, _)) = table.path().rsplit_once('.') {
        let outer = tables()
            .into_iter()
            .find(|t| t.path() == parent)
            .unwrap_or_else(|| panic!("no table {parent}"));
        text.push_str(outer.header);
        text.push('\n');
    }
    if !table.header.is_empty() {
        text.push_str(table.header);
        text.push('\n');
    }
    text.push_str(&format!("{UNKNOWN} = 1\n"));
    text
}

/// The keys serde lists after "expected" in an unknown-key message.
fn listed(message: &str) -> BTreeSet<String> {
    let (_, tail) = message
        .split_once(&format!("unknown field `{UNKNOWN}`, expected "))
        .unwrap_or_else(|| panic!("not an unknown-key message: {message}"));
    let tail = tail.lines().next().unwrap_or("");
    tail.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// The parameters of every law of the registry, by their scene names.
fn law_parameters() -> BTreeSet<String> {
    law::KNOWN
        .iter()
        .flat_map(|l| law::keys(l).unwrap())
        .map(|k| scene_key(k))
        .collect()
}

#[test]
fn each_key_table_lists_exactly_the_keys_its_reader_accepts() {
    let dir = tempfile::tempdir().unwrap();
    for (i, table) in tables().into_iter().enumerate() {
        let message = refusal(dir.path(), &format!("t{i}"), &scene_with_unknown_key(table));
        let accepted = listed(&message);
        let mut documented: BTreeSet<String> =
            table.keys.iter().map(|k| k.name.to_string()).collect();
        assert_eq!(
            documented.len(),
            table.keys.len(),
            "{}: a key is listed twice",
            table.header
        );
        if table.path() == "material" {
            documented.extend(law_parameters());
        }
        let missing: Vec<_> = accepted.difference(&documented).collect();
        let extra: Vec<_> = documented.difference(&accepted).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "table {:?}: accepted but not in the table: {missing:?}; in the table but refused: \
             {extra:?}\n{message}",
            table.header
        );
    }
}

#[test]
fn every_table_documents_every_key() {
    for table in tables() {
        assert!(!table.about.is_empty(), "{}", table.header);
        for k in table.keys {
            for (what, v) in [
                ("type", k.kind),
                ("default", k.default),
                ("meaning", k.meaning),
            ] {
                assert!(
                    !v.trim().is_empty(),
                    "{} {}: no {what}",
                    table.header,
                    k.name
                );
            }
        }
    }
}

#[test]
fn the_reference_has_a_section_per_table_and_per_law() {
    let md = reference_markdown();
    for table in tables() {
        if !table.header.is_empty() {
            assert!(
                md.contains(&format!("## `{}`", table.header)),
                "{}",
                table.header
            );
        }
        for k in table.keys {
            assert!(md.contains(&format!("| `{}` |", k.name)), "{}", k.name);
        }
    }
    for name in law::KNOWN {
        assert!(md.contains(&format!("#### `law = \"{name}\"`")), "{name}");
        for k in law::keys(name).unwrap() {
            assert!(
                md.contains(&format!("| `{}` | `{k}` |", scene_key(k))),
                "{k}"
            );
        }
    }
}

#[test]
fn a_material_key_no_law_has_is_refused_with_its_line_and_the_keys_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let text = "mesh = \"m.msh\"\n[time]\nend = 1.0\n[[material]]\nphysical = \"soil\"\n\
                density = 2000.0\nyoung = 1e4\npoisson = 0.3\nfrction_angle = 30.0\n";
    let e = refusal(dir.path(), "typo", text);
    assert!(e.contains("line 9"), "{e}");
    assert!(
        e.contains("unknown field `frction_angle`, expected one of `physical`"),
        "{e}"
    );
    // Every law's parameters are among the keys allowed.
    for k in law_parameters() {
        assert!(e.contains(&format!("`{k}`")), "{k}: {e}");
    }
}
