//! Writes a structured tetrahedral box as GOM, for benchmarks:
//! `cargo run --release -p mpm-shared --example gen_box -- N OUT.GOM [tet4|tet10]`
//! (N³ cells × 6 tetrahedra; N = 56 gives 1.05M).

use mpm_shared::{generate, ElementType};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = a
        .first()
        .and_then(|s| s.parse().ok())
        .expect("usage: gen_box N OUT.GOM [tet4|tet10]");
    let out = a.get(1).expect("usage: gen_box N OUT.GOM [tet4|tet10]");
    let et = match a.get(2).map(String::as_str) {
        Some("tet4") => ElementType::Tet4,
        _ => ElementType::Tet10,
    };
    let m = generate::box_mesh([n; 3], [1.0; 3], et);
    mpm_shared::write_gom_file(&m, std::path::Path::new(out)).expect("writable output");
}
