//! Writes sample VTU/PVD files in every encoding for `scripts/check-vtu.py`, which reads them back
//! with meshio (a real, independent VTU reader).
//!
//! `cargo run -p mpm-shared --example vtu_samples -- OUTDIR`

use std::path::PathBuf;

use mpm_shared::vtu::{self, Cells, DataArray, Encoding, Piece, Values};
use mpm_shared::{generate, ElementType};

fn main() {
    let dir = PathBuf::from(std::env::args().nth(1).expect("usage: vtu_samples OUTDIR"));
    std::fs::create_dir_all(&dir).unwrap();
    let model = generate::box_mesh([2, 3, 1], [1.0, 1.5, 0.5], ElementType::Tet10);
    let n = 50usize;
    let pts: Vec<f64> = (0..n * 3).map(|i| (i as f64 * 0.37).sin()).collect();
    let stress: Vec<f64> = (0..n * 6).map(|i| i as f64 - 0.5).collect();
    let id: Vec<i32> = (1..=n as i32).collect();
    let cells = Cells::vertices(n);
    let mut pvd = Vec::new();
    for (k, (enc, tag)) in [
        (Encoding::Ascii, "ascii"),
        (Encoding::Base64, "base64"),
        (Encoding::Appended, "appended"),
    ]
    .into_iter()
    .enumerate()
    {
        let mut f = std::fs::File::create(dir.join(format!("mesh_{tag}.vtu"))).unwrap();
        let part: Vec<i32> = (0..model.element_count() as i32).map(|e| e % 3).collect();
        vtu::write_model(&mut f, &model, Some(&part), enc).unwrap();
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![
                DataArray {
                    name: "stress",
                    components: 6,
                    values: Values::F64(&stress),
                },
                DataArray {
                    name: "id",
                    components: 1,
                    values: Values::I32(&id),
                },
            ],
            cell_data: vec![],
        };
        let name = format!("particles_{tag}.vtu");
        let mut f = std::fs::File::create(dir.join(&name)).unwrap();
        vtu::write_vtu(&mut f, &piece, enc).unwrap();
        pvd.push((k as f64 * 0.25, name));
    }
    let mut f = std::fs::File::create(dir.join("run.pvd")).unwrap();
    vtu::write_pvd(&mut f, &pvd).unwrap();
    println!("{} {} {}", model.node_count(), model.element_count(), n);
}
