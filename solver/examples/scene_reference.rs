//! Prints the scene reference (every key of a TOML scene, and every law's parameters) as
//! Markdown on standard output, generated from the scene reader's own key tables:
//!
//! `cargo run -p mpm-solve --example scene_reference > docs/guide/reference/scene.md`

fn main() {
    print!("{}", mpm_solve::input::scene::reference_markdown());
}
