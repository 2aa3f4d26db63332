//! The halo each MPI rank would exchange on a large mesh, without running it: a cube of
//! `--cells N` × N × N cells of six tetrahedra, ordered along the Morton curve by `sfcb`'s
//! ordering, cut into `--ranks` contiguous ranges as the solver cuts it (balanced by the
//! material points, `--points` per element, boundaries on blocks of 64 elements), and per rank
//! the elements it sends (owned elements whose nodes another rank's elements touch, counted
//! once per rank they go to), its halo (other ranks' elements touching its nodes) and its
//! neighbours, by the rules of `parallel::partition`. Prints one JSON line per rank count.
//! `docs/scaling.md` models the communication of 64 to 4,096 ranks from these figures
//! (`scripts/scaling-mpi`).
//!
//! `cargo run --release -p mpm-solve --example halo_model -- --cells 100 --ranks 64,128,256`

use std::collections::HashMap;
use std::time::Instant;

use mpm_shared::{generate, ElementType};
use mpm_solve::parallel::team::{aligned_to_blocks, balanced_ranges};

fn arg<'a>(a: &'a [String], key: &str) -> Option<&'a str> {
    a.iter()
        .position(|x| x == key)
        .and_then(|i| a.get(i + 1))
        .map(|s| s.as_str())
}

/// Mean and largest of per-rank counts.
fn spread(v: &[u64]) -> (f64, u64) {
    let mean = v.iter().sum::<u64>() as f64 / v.len() as f64;
    (mean, v.iter().copied().max().unwrap_or(0))
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = arg(&a, "--cells").map_or(20, |s| s.parse().expect("--cells N"));
    let points: u64 = arg(&a, "--points").map_or(4, |s| s.parse().expect("--points K"));
    let rank_counts: Vec<usize> = arg(&a, "--ranks")
        .unwrap_or("64,256,1024,4096")
        .split(',')
        .map(|s| s.parse().expect("--ranks P,Q,..."))
        .collect();
    let t0 = Instant::now();
    let model = generate::box_mesh([n, n, n], [1.0; 3], ElementType::Tet4);
    let order = sfcb::order::order(
        &model,
        sfcb::order::Options {
            curve: sfcb::order::Curve::Morton,
            levels: 21,
            cubic: true,
        },
    )
    .expect("a finite box");
    let elements = model.element_count();
    let nodes = model.node_count();
    // Corners of the element at each curve position.
    let corners = |i: usize| -> &[u32] {
        let e = order.order[i] as usize;
        &model.connectivity[4 * e..4 * e + 4]
    };
    let setup = t0.elapsed().as_secs_f64();
    for &ranks in &rank_counts {
        let t = Instant::now();
        let ranges = aligned_to_blocks(
            balanced_ranges(std::iter::repeat(points).take(elements), ranks),
            elements,
        );
        if ranges.len() != ranks || ranges.iter().any(|r| r.is_empty()) {
            println!(
                "{{\"ranks\": {ranks}, \"error\": \"more ranks than blocks of 64 elements\"}}"
            );
            continue;
        }
        // The lowest and highest rank touching each node: most nodes have one.
        let mut low = vec![u32::MAX; nodes];
        let mut high = vec![0u32; nodes];
        for (r, range) in ranges.iter().enumerate() {
            for i in range.clone() {
                for &c in corners(i) {
                    low[c as usize] = low[c as usize].min(r as u32);
                    high[c as usize] = high[c as usize].max(r as u32);
                }
            }
        }
        // Every rank touching a shared node, increasing (elements are visited in rank order).
        let mut touching: HashMap<u32, Vec<u32>> = HashMap::new();
        for (r, range) in ranges.iter().enumerate() {
            for i in range.clone() {
                for &c in corners(i) {
                    if low[c as usize] != high[c as usize] {
                        let t = touching.entry(c).or_default();
                        if t.last() != Some(&(r as u32)) {
                            t.push(r as u32);
                        }
                    }
                }
            }
        }
        let mut sends = vec![0u64; ranks];
        let mut halo = vec![0u64; ranks];
        let mut border = vec![0u64; ranks];
        let mut pairs: HashMap<(u32, u32), u64> = HashMap::new();
        let mut others: Vec<u32> = Vec::with_capacity(16);
        for (r, range) in ranges.iter().enumerate() {
            for i in range.clone() {
                others.clear();
                for &c in corners(i) {
                    if let Some(t) = touching.get(&c) {
                        others.extend(t.iter().copied().filter(|&q| q as usize != r));
                    }
                }
                if others.is_empty() {
                    continue;
                }
                others.sort_unstable();
                others.dedup();
                border[r] += 1;
                for &q in &others {
                    sends[r] += 1;
                    halo[q as usize] += 1;
                    *pairs.entry((r as u32, q)).or_default() += 1;
                }
            }
        }
        let mut neighbours = vec![0u64; ranks];
        for &(r, _) in pairs.keys() {
            neighbours[r as usize] += 1;
        }
        let owned: Vec<u64> = ranges.iter().map(|r| r.len() as u64).collect();
        let (owned_mean, owned_max) = spread(&owned);
        let (sends_mean, sends_max) = spread(&sends);
        let (halo_mean, halo_max) = spread(&halo);
        let (border_mean, border_max) = spread(&border);
        let (nb_mean, nb_max) = spread(&neighbours);
        println!(
            "{{\"cells\": {n}, \"elements\": {elements}, \"nodes\": {nodes}, \"ranks\": {ranks}, \"owned_mean\": {owned_mean:.1}, \"owned_max\": {owned_max}, \"sends_mean\": {sends_mean:.1}, \"sends_max\": {sends_max}, \"border_mean\": {border_mean:.1}, \"border_max\": {border_max}, \"halo_mean\": {halo_mean:.1}, \"halo_max\": {halo_max}, \"neighbours_mean\": {nb_mean:.2}, \"neighbours_max\": {nb_max}, \"shared_nodes\": {}, \"setup_seconds\": {setup:.1}, \"seconds\": {:.1}}}",
            touching.len(),
            t.elapsed().as_secs_f64()
        );
    }
}
