//! Particle-steps per second on a large column under gravity (structured tetrahedra, 4 points
//! each): `cargo run --release -p mpm-solve --example throughput -- [CELLS_XZ] [CELLS_Y] [STEPS]`
//! (default 10 × 100 × 10 cells = 60,000 tetrahedra, 240,000 material points, 200 steps).

use std::time::Instant;

use mpm_shared::{generate, ElementType};
use mpm_solve::case::{Case, MaterialSpec};
use mpm_solve::engine::Engine;

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("integer"))
        .collect();
    let (nxz, ny, steps) = (
        *a.first().unwrap_or(&10),
        *a.get(1).unwrap_or(&100),
        *a.get(2).unwrap_or(&200),
    );
    let model = generate::box_mesh(
        [nxz, ny, nxz],
        [0.1 * nxz as f64 / 10.0, 1.0, 0.1 * nxz as f64 / 10.0],
        ElementType::Tet10,
    );
    let fixed = mpm_solve::case::confined_box(&model);
    let n_el = model.element_count();
    let soil = MaterialSpec::new("soil", 2000.0, 10000.0, 0.3).unwrap();
    let mut case = Case::single_material("throughput", model, soil, 4, fixed);
    case.gravity = [0.0, -9.81, 0.0];
    case.courant = 0.5;
    case.damping = 0.75;
    let mut engine = Engine::<f64>::new(&case, false).unwrap();
    let np = engine.particles.len();
    let t = Instant::now();
    for _ in 0..steps {
        engine.step(&case, engine.dt, None).unwrap();
    }
    let secs = t.elapsed().as_secs_f64();
    println!("{n_el} tetrahedra, {np} material points, {steps} steps in {secs:.2} s: {:.2}M particle-steps/s (1 thread, f64)", np as f64 * steps as f64 / secs / 1e6);
    for (name, s) in mpm_solve::engine::PHASES.iter().zip(engine.phase_seconds) {
        println!("  {name:18} {:6.1}%", 100.0 * s / secs);
    }
}
