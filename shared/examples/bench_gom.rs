//! GOM read and write throughput on a large mesh: median MB/s of several repetitions.
//!
//! `cargo run --release -p mpm-shared --example bench_gom -- [FILE.GOM | --cells N] [--reps R]`
//! Without a file it generates a 10-node tetrahedral box of N³ cells × 6 tets (N = 56 gives
//! 1.05M tetrahedra and about 130 MB of GOM).

use std::time::Instant;

use mpm_shared::{generate, gom, ElementType};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut cells = 56usize;
    let mut reps = 3usize;
    let mut file = None;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--cells" => {
                cells = args[i + 1].parse().expect("--cells N");
                i += 1;
            }
            "--reps" => {
                reps = args[i + 1].parse().expect("--reps R");
                i += 1;
            }
            f => file = Some(f.to_string()),
        }
        i += 1;
    }
    let (data, what) = match &file {
        Some(f) => (std::fs::read(f).expect("readable file"), f.clone()),
        None => {
            let m = generate::box_mesh([cells; 3], [1.0; 3], ElementType::Tet10);
            (gom::write(&m), format!("generated box {cells}^3 x 6 tet10"))
        }
    };
    let mb = data.len() as f64 / 1e6;
    let threads = rayon::current_num_threads();
    let mut read_s = Vec::new();
    let mut write_s = Vec::new();
    let mut model = None;
    for _ in 0..reps {
        let t = Instant::now();
        let m = gom::read(&data, &what).expect("valid GOM");
        read_s.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        let out = gom::write(&m);
        write_s.push(t.elapsed().as_secs_f64());
        if file.is_none() {
            // The generated text is what the writer produces, so it must come back identical.
            assert!(out == data, "write(read(x)) != x");
        }
        model = Some(m);
    }
    let m = model.expect("at least one repetition");
    let (r, w) = (median(read_s), median(write_s));
    println!("input      : {what}");
    println!(
        "mesh       : {} elements, {} nodes, {:.1} MB of GOM",
        m.element_count(),
        m.node_count(),
        mb
    );
    println!("threads    : {threads}");
    println!(
        "read       : {:.3} s  {:.0} MB/s (median of {reps})",
        r,
        mb / r
    );
    println!(
        "write      : {:.3} s  {:.0} MB/s (median of {reps})",
        w,
        mb / w
    );
}
