//! Benchmark harness behind `scripts/bench-sfcb`: for each mesh, the ordering core (keys, sort,
//! renumbering) with 1 and 2 threads against the C reference, a gather kernel on a shuffled
//! versus the reordered numbering, and partition quality of Morton and Hilbert cuts against
//! METIS. Prints one markdown table per measurement.
//!
//! `bench_sfcb [--c-ref BIN] [--mpmetis BIN] [--parts 16,64] [--reps R] [--work DIR] MESH...`

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use mpm_shared::{gom, Model};
use sfcb::{metrics, order};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn fnv(order: &[u32], node_new: &[u32]) -> u64 {
    let mut h: u64 = 1469598103934665603;
    for &x in order.iter().chain(node_new) {
        h ^= u64::from(x);
        h = h.wrapping_mul(1099511628211);
    }
    h
}

fn opts(curve: order::Curve) -> order::Options {
    order::Options {
        curve,
        levels: 21,
        cubic: true,
    }
}

/// Times the ordering core with `threads` workers: median seconds and the result's hash.
fn time_core(model: &Model, threads: usize, reps: usize) -> (f64, u64) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut times = Vec::new();
        let mut hash = 0;
        for _ in 0..reps {
            let t = Instant::now();
            let o = order::order(model, opts(order::Curve::Morton))
                .expect("benchmark meshes have finite coordinates");
            times.push(t.elapsed().as_secs_f64());
            hash = fnv(&o.order, &o.node_new);
        }
        (median(times), hash)
    })
}

/// Writes the binary dump the C reference reads.
fn dump(model: &Model, path: &Path) {
    let mut b: Vec<u8> = Vec::new();
    for v in [
        model.node_count(),
        model.element_count(),
        model.element_type.nodes(),
        model.element_type.corners(),
    ] {
        b.extend_from_slice(&(v as u64).to_le_bytes());
    }
    for &c in &model.coords {
        b.extend_from_slice(&c.to_le_bytes());
    }
    for &i in &model.connectivity {
        b.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(path, b).unwrap();
}

/// Deterministic pseudo-random permutation of 0..n (Fisher-Yates with SplitMix64).
fn shuffle(n: usize, mut seed: u64) -> Vec<u32> {
    let mut p: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        p.swap(i, (z % (i as u64 + 1)) as usize);
    }
    p
}

/// The gather kernel: for each element, read its corner coordinates and accumulate.
fn gather(model: &Model) -> f64 {
    let per = model.element_type.nodes();
    let corners = model.element_type.corners();
    let x = &model.coords;
    let mut acc = 0.0;
    for el in model.connectivity.chunks_exact(per) {
        let mut s = 0.0;
        for &v in &el[..corners] {
            let i = v as usize * 3;
            s += x[i] + 2.0 * x[i + 1] + 3.0 * x[i + 2];
        }
        acc += s * 0.25;
    }
    acc
}

fn time_gather(model: &Model, reps: usize) -> f64 {
    let mut times = Vec::new();
    let mut sink = 0.0;
    for _ in 0..reps {
        let t = Instant::now();
        sink += gather(model);
        times.push(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(sink);
    median(times)
}

/// Runs mpmetis on the corners of `model` and returns its element partition.
fn metis(
    model: &Model,
    mpmetis: &str,
    parts: u32,
    work: &Path,
    tag: &str,
) -> Option<(Vec<u32>, f64)> {
    let file = work.join(format!("{tag}.metis"));
    if !file.exists() {
        let mut s = String::with_capacity(model.element_count() * 40);
        s.push_str(&format!("{}\n", model.element_count()));
        for e in 0..model.element_count() {
            let el = &model.element(e)[..model.element_type.corners()];
            let ids: Vec<String> = el.iter().map(|v| (v + 1).to_string()).collect();
            s.push_str(&ids.join(" "));
            s.push('\n');
        }
        std::fs::write(&file, s).ok()?;
    }
    let t = Instant::now();
    let out = Command::new(mpmetis)
        .arg("-ncommon=3")
        .arg(&file)
        .arg(parts.to_string())
        .output()
        .ok()?;
    let secs = t.elapsed().as_secs_f64();
    if !out.status.success() {
        eprintln!("mpmetis failed: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    let epart = std::fs::read_to_string(format!("{}.epart.{parts}", file.display())).ok()?;
    Some((
        epart.lines().map(|l| l.trim().parse().unwrap()).collect(),
        secs,
    ))
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut c_ref = None;
    let mut mpmetis = None;
    let mut parts = vec![16u32, 64];
    let mut reps = 5;
    let mut work = std::env::temp_dir();
    let mut meshes = Vec::new();
    let mut sfcb_bin = None;
    let mut e2e_rows = Vec::new();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--sfcb" => sfcb_bin = args.next(),
            "--c-ref" => c_ref = args.next(),
            "--mpmetis" => mpmetis = args.next(),
            "--parts" => {
                parts = args
                    .next()
                    .unwrap()
                    .split(',')
                    .map(|p| p.parse().unwrap())
                    .collect()
            }
            "--reps" => reps = args.next().unwrap().parse().unwrap(),
            "--work" => work = PathBuf::from(args.next().unwrap()),
            _ => meshes.push(PathBuf::from(a)),
        }
    }
    let mut core_rows = Vec::new();
    let mut gather_rows = Vec::new();
    let mut part_rows = Vec::new();
    for path in &meshes {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let model = gom::read(&std::fs::read(path).unwrap(), &name).unwrap();
        let n = model.element_count();
        let (t1, h1) = time_core(&model, 1, reps);
        let (t2, h2) = time_core(&model, 2, reps);
        assert_eq!(h1, h2, "thread count changed the ordering");
        let (tc, same) = match &c_ref {
            Some(bin) => {
                let d = work.join(format!("{name}.dump"));
                dump(&model, &d);
                let out = Command::new(bin)
                    .arg(&d)
                    .arg(reps.to_string())
                    .output()
                    .unwrap();
                let text = String::from_utf8_lossy(&out.stdout).to_string();
                let mut it = text.split_whitespace();
                let t: f64 = it.next().unwrap().parse().unwrap();
                let h = u64::from_str_radix(it.next().unwrap(), 16).unwrap();
                let _ = std::fs::remove_file(&d);
                (Some(t), h == h1)
            }
            None => (None, true),
        };
        assert!(same, "{name}: the C reference ordered differently");
        let fmt_ratio = |t: f64| tc.map_or("-".to_string(), |c| format!("{:.2}", t / c));
        core_rows.push(format!(
            "| {name} | {n} | {} | {:.2} | {:.2} | {:.2} | {} | {} | {} |",
            tc.map_or("-".into(), |c| format!("{:.2}", c * 1e3)),
            t1 * 1e3,
            t2 * 1e3,
            t1 / t2,
            fmt_ratio(t1),
            fmt_ratio(t2),
            if c_ref.is_some() { "yes" } else { "-" }
        ));
        if let (Some(bin), true) = (&sfcb_bin, n >= 100_000) {
            let out = work.join(format!("{name}.sfcb.GOM"));
            let mb = std::fs::metadata(path).unwrap().len() as f64 / 1e6;
            let mut times = Vec::new();
            for _ in 0..3 {
                let _ = std::fs::remove_file(&out);
                let t = Instant::now();
                let st = Command::new(bin).arg(path).arg(&out).status().unwrap();
                times.push(t.elapsed().as_secs_f64());
                assert!(st.success());
            }
            let _ = std::fs::remove_file(&out);
            let t = median(times);
            e2e_rows.push(format!(
                "| {name} | {n} | {mb:.1} | {t:.3} | {:.0} |",
                mb / t
            ));
        }
        if n >= 100_000 {
            let shuffled = model
                .reordered(&shuffle(n, 1), &shuffle(model.node_count(), 2))
                .unwrap();
            let o = order::order(&shuffled, opts(order::Curve::Morton))
                .expect("benchmark meshes have finite coordinates");
            let ordered = shuffled.reordered(&o.order, &o.node_new).unwrap();
            let (ts, to, tg) = (
                time_gather(&shuffled, reps),
                time_gather(&ordered, reps),
                time_gather(&model, reps),
            );
            gather_rows.push(format!(
                "| {name} | {n} | {:.2} | {:.2} | {:.2} | {:.2} |",
                ts * 1e3,
                tg * 1e3,
                to * 1e3,
                ts / to
            ));
            let nb = metrics::face_neighbours(&ordered);
            let w = order::weights(&ordered);
            for &p in &parts {
                let mut row = |label: &str, part: &[u32], m: &Model, secs: Option<f64>| {
                    let nbm = if std::ptr::eq(m, &ordered) {
                        nb.clone()
                    } else {
                        metrics::face_neighbours(m)
                    };
                    let q = metrics::partition_quality(m, &nbm, part, &order::weights(m), p);
                    part_rows.push(format!(
                        "| {name} | {p} | {label} | {} | {} | {} | {:.3} | {} |",
                        q.edge_cut,
                        q.extra_pieces,
                        q.interface_nodes,
                        q.imbalance,
                        secs.map_or("-".into(), |s| format!("{:.2}", s))
                    ));
                    q.edge_cut
                };
                let mut morton = order::partitions(&w, p);
                let cut_m = row("morton", &morton, &ordered, None);
                let t = Instant::now();
                metrics::merge_pieces(n, &nb, &mut morton, &w, 20);
                let secs = t.elapsed().as_secs_f64();
                let cut_mm = row("morton + merge pieces", &morton, &ordered, Some(secs));
                let oh = order::order(&shuffled, opts(order::Curve::Hilbert))
                    .expect("benchmark meshes have finite coordinates");
                let hil = shuffled.reordered(&oh.order, &oh.node_new).unwrap();
                let wh = order::weights(&hil);
                let mut hp = order::partitions(&wh, p);
                row("hilbert", &hp, &hil, None);
                let nbh = metrics::face_neighbours(&hil);
                metrics::merge_pieces(n, &nbh, &mut hp, &wh, 20);
                row("hilbert + merge pieces", &hp, &hil, None);
                if let Some(bin) = &mpmetis {
                    if let Some((mp, secs)) = metis(&ordered, bin, p, &work, &name) {
                        let cut = row("metis", &mp, &ordered, Some(secs));
                        part_rows.push(format!(
                            "| {name} | {p} | cut / metis cut: morton {:.2}, merged {:.2} | | | | | |",
                            cut_m as f64 / cut as f64,
                            cut_mm as f64 / cut as f64
                        ));
                    }
                }
            }
        }
    }
    println!("### Ordering core (keys + sort + renumbering), median of {reps}, milliseconds\n");
    println!("| mesh | elements | C -O3 1 thread | sfcb 1 thread | sfcb 2 threads | speed-up 1→2 | sfcb/C 1 thread | sfcb/C 2 threads | same order as C |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---|");
    core_rows.iter().for_each(|r| println!("{r}"));
    if !e2e_rows.is_empty() {
        println!(
            "\n### End to end `sfcb IN.GOM OUT.GOM` (read, order, remap, write), median of 3\n"
        );
        println!("| mesh | elements | MB | seconds | MB/s |");
        println!("|---|---:|---:|---:|---:|");
        e2e_rows.iter().for_each(|r| println!("{r}"));
    }
    if !gather_rows.is_empty() {
        println!("\n### Gather kernel (read each element's corner coordinates), 1 thread, ms\n");
        println!("| mesh | elements | shuffled | as generated (Gmsh) | Morton-ordered | shuffled / ordered |");
        println!("|---|---:|---:|---:|---:|---:|");
        gather_rows.iter().for_each(|r| println!("{r}"));
        println!("\n### Partition quality (face-connected pieces beyond one per part)\n");
        println!("| mesh | parts | method | edge cut | extra pieces | interface nodes | imbalance | seconds |");
        println!("|---|---:|---|---:|---:|---:|---:|---:|");
        part_rows.iter().for_each(|r| println!("{r}"));
    }
}
