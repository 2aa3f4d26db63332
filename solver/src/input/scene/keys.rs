//! The key tables' types: each section's file declares the keys its reader accepts as a
//! [`Table`] of [`Key`]s, which the reference renders; and the scene's names of the
//! law parameters ([`scene_key`]).

/// One key of a scene table.
#[derive(Debug, Clone, Copy)]
pub struct Key {
    /// The key as the scene writes it.
    pub name: &'static str,
    /// Its TOML type, e.g. `float`, `string`, `[float, float, float]`.
    pub kind: &'static str,
    /// Its default: a value, `required`, or how it is found when left out.
    pub default: &'static str,
    /// Its unit (empty for none).
    pub unit: &'static str,
    /// What it means, in one line.
    pub meaning: &'static str,
}

/// A key of a table (a `const` shorthand for the tables' long lists).
pub(super) const fn key(
    name: &'static str,
    kind: &'static str,
    default: &'static str,
    unit: &'static str,
    meaning: &'static str,
) -> Key {
    Key {
        name,
        kind,
        default,
        unit,
        meaning,
    }
}

/// A table of the scene and the keys its reader accepts.
#[derive(Debug, Clone, Copy)]
pub struct Table {
    /// How the scene writes the table's header: `[time]`, `[[material]]`, `[material.liquid]`;
    /// empty for the top level.
    pub header: &'static str,
    /// What the table is for.
    pub about: &'static str,
    /// Its keys, in the order the reader declares them.
    pub keys: &'static [Key],
}

impl Table {
    /// The table's path in TOML (`time`, `material`, `material.liquid`; empty for the top
    /// level): its header without the brackets.
    pub fn path(&self) -> &'static str {
        self.header.trim_matches(|c| c == '[' || c == ']')
    }
}

/// The scene's name of the law parameter `key` (Anura3D's key): Anura3D's key in lower case,
/// `young` and `poisson` for the elastic constants.
pub fn scene_key(key: &str) -> String {
    match key {
        "YOUNG_MODULUS" => "young".into(),
        "POISSON_RATIO" => "poisson".into(),
        k => k.to_ascii_lowercase(),
    }
}
