//! STREAM-style triad a = b + s c on the solver's thread team (pinned, first touch), for the
//! roofline of `scripts/bench-solver`: prints the best bandwidth over repetitions in GB/s,
//! counting 24 bytes per element as STREAM does.
//!
//! `cargo run --release -p mpm-solve --example triad -- [THREADS] [MIB_PER_ARRAY] [REPS]`
//! (`TRIAD_HUGE_PAGES=on` in the environment: its arrays on huge pages)

use std::time::Instant;

use mpm_solve::parallel::team::{balanced_ranges, Pin, Shared, Team};

/// The solver's allocator (`mpm_solve::parallel::huge_pages`; `TRIAD_HUGE_PAGES=on` turns
/// its advice on), so that the roofline compares like with like.
#[global_allocator]
static ALLOC: mpm_solve::parallel::huge_pages::HugePageAlloc =
    mpm_solve::parallel::huge_pages::HugePageAlloc;

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("integer"))
        .collect();
    let threads = *a.first().unwrap_or(&0);
    let mib = *a.get(1).unwrap_or(&256);
    let reps = *a.get(2).unwrap_or(&10);
    let n = mib * 1024 * 1024 / 8;
    mpm_solve::parallel::huge_pages::set_enabled(
        std::env::var("TRIAD_HUGE_PAGES").is_ok_and(|v| v == "on"),
    );
    let team = Team::new(threads, Pin::Cores).expect("team");
    let ranges = balanced_ranges(std::iter::repeat(1u64).take(n), team.threads);
    // Zeroed allocations: each thread first touches its own range below.
    let (mut x, mut y, mut z) = (vec![0.0f64; n], vec![0.0f64; n], vec![0.0f64; n]);
    {
        let (xs, ys, zs) = (
            Shared::new(&mut x),
            Shared::new(&mut y),
            Shared::new(&mut z),
        );
        team.run(|k| {
            // SAFETY: the ranges are disjoint.
            let (xr, yr, zr) = unsafe {
                (
                    xs.range(ranges[k].clone()),
                    ys.range(ranges[k].clone()),
                    zs.range(ranges[k].clone()),
                )
            };
            for i in 0..xr.len() {
                xr[i] = 0.0;
                yr[i] = 1.0;
                zr[i] = 2.0;
            }
        });
    }
    let mut best = f64::MAX;
    for _ in 0..reps {
        let xs = Shared::new(&mut x);
        let (yv, zv) = (&y, &z);
        let t = Instant::now();
        team.run(|k| {
            let r = ranges[k].clone();
            // SAFETY: the ranges are disjoint.
            let xr = unsafe { xs.range(r.clone()) };
            for (j, i) in r.enumerate() {
                xr[j] = yv[i] + 3.0 * zv[i];
            }
        });
        best = best.min(t.elapsed().as_secs_f64());
    }
    assert!(x.iter().all(|&v| v == 7.0));
    println!(
        "{{\"threads\": {}, \"mib_per_array\": {mib}, \"gb_per_s\": {:.3}}}",
        team.threads,
        24.0 * n as f64 / best / 1e9
    );
}
