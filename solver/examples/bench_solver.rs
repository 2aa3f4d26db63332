//! One configuration of the solver benchmark (`scripts/bench-solver` runs the sweep): a column
//! of structured tetrahedra, 4 material points each, dry under gravity or saturated under a
//! sudden top load, a fixed number of steps; prints one JSON line with the median of the
//! repetitions (particle-steps/s overall and seconds per phase).
//!
//! `cargo run --release -p mpm-solve --example bench_solver -- --case dry|saturated
//!  --cells NXZ NY --steps S --reps R --threads T --pin none|cores|auto --first-touch on|off
//!  --order morton|random|none --precision f64|f32 --guards on|off
//!  --law linear|mc-elastic|mc-plastic|mc-flowing|mcc-flowing|hypo-flowing --surface on|off --dim 3|2
//!  --shear RATE
//!  --points N --basis tets|linear|gimp|bspline2`
//!
//! `--basis` other than `tets` runs the same column, points and loads on a background grid of
//! its cubes (squares in 2D) with that basis (the scene's `[grid]`, docs/design.md §4.20):
//! the column's tetrahedra are then the grid's cells cut up to locate the points.
//!
//! `--points N` places N material points per element instead of the usual 4 per tetrahedron
//! and 3 per triangle (any count the element supports: 1, 4 or 10 for tetrahedra, 1 or 3 for
//! triangles), to split a step's cost into what each element and each point takes.
//!
//! `--dim 2` runs the plane-strain twin: a rectangle of `--cells NX NY` square cells of 1 cm
//! (the 3D column's cell size at NY = 100, so the time step and the motion per step compare),
//! 2 triangles per cell and 3 material points per triangle, the same materials, loads and
//! fixities (sides fixed normally, bottom fixed), computed by the engine built for `Tri3`.
//!
//! The Mohr-Coulomb laws print, beside the timing, the share of point-steps that end on the
//! yield surface and the share that end there with a stress that moved (returned points), from
//! one more run of the same steps (`--surface off` leaves that run out, so that an instruction
//! count sees the timed run alone). `mcc-flowing` (Modified Cam Clay under the same uniform
//! compression as `mc-flowing`) prints no such shares: the count is Mohr-Coulomb's.
//!
//! `--mpi` (built with the cargo feature `mpi`, launched by `mpirun -np N`): the same case
//! over N ranks, each with `--threads` threads; rank 0 prints the line, with the total points
//! and, per rank, its share, halo and seconds per phase (`rank_reports`).
//!
//! `--shear RATE` starts every point with the horizontal velocity RATE·(y − y_bottom) (1/s):
//! points cross element faces at every step, out of the curve's order, so that the locate
//! phase re-sorts them each step, as in a run-out or a collapse (the quasi-static columns
//! never do).
//!
//! `--huge-pages on` asks for 2 MiB pages for the large arrays (`mpm_solve::parallel::huge_pages`,
//! off by default as in `mpm-solve`), to measure what they are worth.
//!
//! `--guards off` skips the per-step guard rails (docs/design.md §4.14), to measure their cost.
//!
//! `--order random` renumbers elements and nodes by a fixed pseudo-random permutation (the
//! locality a mesh generator's worst case gives); `morton` applies the solver's curve ordering.

use std::io::Write;
use std::time::Instant;

/// Large arrays on huge pages with `--huge-pages on`, as `mpm-solve`.
#[global_allocator]
static ALLOC: mpm_solve::parallel::huge_pages::HugePageAlloc =
    mpm_solve::parallel::huge_pages::HugePageAlloc;

use mpm_shared::{generate, ElementType, Model};
use mpm_solve::driver::dispatch::{dispatch, Generic};
use mpm_solve::driver::engine::{Engine, Options, PHASES};
use mpm_solve::element::tet4::Tet4;
use mpm_solve::element::tri3::Tri3;
use mpm_solve::element::Element;
use mpm_solve::input::case::{Case, MaterialSpec, Precision, Reorder};
use mpm_solve::material::liquid::LiquidSpec;
use mpm_solve::parallel::team::Pin;

fn arg<'a>(a: &'a [String], key: &str) -> Option<&'a str> {
    a.iter()
        .position(|x| x == key)
        .and_then(|i| a.get(i + 1))
        .map(|s| s.as_str())
}

/// A fixed permutation of 0..n (xorshift keys, sorted).
fn shuffle(n: usize, seed: u64) -> Vec<u32> {
    let mut s = seed;
    let mut keys: Vec<(u64, u32)> = (0..n as u32)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s, i)
        })
        .collect();
    keys.sort_unstable();
    keys.into_iter().map(|(_, i)| i).collect()
}

/// Fixities of a rectangle confined like the 3D column (`confined_box`, which reads a third
/// coordinate 2D models do not have): the bottom fixed, the sides fixed in x. The z component is
/// left free as a 2D GOM's two-column fixities leave it; nothing drives it in a plane section.
fn confined_rect(model: &Model) -> Vec<[bool; 3]> {
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for p in model.coords.chunks_exact(2) {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let tol = 1e-9 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let on = |v: f64, w: f64| (v - w).abs() <= tol;
    (0..model.node_count())
        .map(|i| {
            let p = model.node(i);
            let bottom = on(p[1], lo[1]);
            [bottom || on(p[0], lo[0]) || on(p[0], hi[0]), bottom, false]
        })
        .collect()
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let saturated = arg(&a, "--case") == Some("saturated");
    let cells: Vec<usize> = a
        .iter()
        .position(|x| x == "--cells")
        .map(|i| vec![a[i + 1].parse().unwrap(), a[i + 2].parse().unwrap()])
        .unwrap_or(vec![20, 200]);
    let steps: usize = arg(&a, "--steps").map_or(20, |s| s.parse().unwrap());
    let reps: usize = arg(&a, "--reps").map_or(3, |s| s.parse().unwrap());
    let threads: usize = arg(&a, "--threads").map_or(0, |s| s.parse().unwrap());
    // `auto` as mpm-solve's default (pinned only where every thread has a free core); an
    // unknown value is refused, not taken for `cores`.
    let pin = match arg(&a, "--pin") {
        Some("none") => Pin::None,
        Some("auto") => Pin::Auto,
        None | Some("cores") => Pin::Cores,
        Some(other) => {
            eprintln!("bench_solver: --pin {other}: expected none, cores or auto");
            std::process::exit(2);
        }
    };
    let first_touch = arg(&a, "--first-touch") != Some("off");
    let huge_pages = arg(&a, "--huge-pages") == Some("on");
    mpm_solve::parallel::huge_pages::set_enabled(huge_pages);
    let order = arg(&a, "--order").unwrap_or("morton").to_string();
    let plane = arg(&a, "--dim") == Some("2");

    let (nxz, ny) = (cells[0], cells[1]);
    let width = 0.1 * nxz as f64 / 10.0;
    let mut model = if plane {
        generate::rect_mesh([nxz, ny], [width, 0.01 * ny as f64])
    } else {
        generate::box_mesh([nxz, ny, nxz], [width, 1.0, width], ElementType::Tet4)
    };
    if order == "random" {
        let e_order = shuffle(model.element_count(), 0x9e37_79b9_7f4a_7c15);
        let n_perm = shuffle(model.node_count(), 0xd1b5_4a32_d192_ed03);
        model = model.reordered(&e_order, &n_perm).unwrap();
    }
    let fixed = if plane {
        confined_rect(&model)
    } else {
        mpm_solve::input::case::confined_box(&model)
    };
    let soil = if saturated {
        let liquid = LiquidSpec::new(0.4, 1000.0, 2.15e4, 1.0214e-9, 1e-6).unwrap();
        MaterialSpec::saturated(
            "soil",
            2650.0,
            mpm_solve::material::law::LawSpec::linear_elastic(1000.0, 0.3).unwrap(),
            liquid,
        )
        .unwrap()
    } else {
        // `--law mc-elastic`: Mohr-Coulomb whose points stay elastic (φ = 30°: the column's
        // K0 = ν/(1-ν) = 0.43 exceeds the active 0.33); `mc-plastic`: φ = 10° (active 0.70),
        // so every point returns at the first step and then sits on the yield surface, most of
        // the column moving as a rigid body under gravity (strain increments of round-off
        // size); `mc-flowing`: the same law under uniform oedometric compression (below), so
        // that every point returns at every step. `mcc-flowing`: Modified Cam Clay under the
        // same compression, normally consolidated at the start (OCR 1: p_c is set at the first
        // update to the initial stress's p_eq = p + q²/(M² p) = 208 kPa, on the yield surface),
        // so that every point but those near the free top (which unloads) is returned at every
        // step (p_c moved at about 96 % of the point-steps of 10 steps on the 1M-point column);
        // ν = 0.3 with G from K (G = 0), λ = 0.2, κ = 0.04, M = 1, e0 = 1.2. The time step
        // takes the law's stiffness at p_max = 1000 kPa (K = 55 MPa: a step 2.6 times shorter
        // than Mohr-Coulomb's, so about 3e-6 strain per step), far above the mean stress the
        // column reaches (at most about 135 kPa over the bench's steps), and it stays stable.
        // `hypo-flowing`: hypoplastic Hochstetten sand with intergranular strain (e0 0.70,
        // mobilised along the initial stress), the same compression, the time step from its
        // stiffest state at p_max = 1000 kPa (every point integrates its rate at every step).
        use mpm_solve::material::law::LawSpec;
        let law = match arg(&a, "--law") {
            Some("mc-elastic") => LawSpec::mohr_coulomb(10000.0, 0.3, 30.0, 0.0, 0.0, 0.0),
            Some("mc-plastic" | "mc-flowing") => {
                LawSpec::mohr_coulomb(10000.0, 0.3, 10.0, 0.0, 0.0, 0.0)
            }
            Some("mcc-flowing") => LawSpec::by_name("modified_cam_clay", &|k| match k {
                "POISSON_RATIO" => Some(0.3),
                "SHEAR_MODULUS" | "PRECONSOLIDATION_PRESSURE" | "NCL_INTERCEPT" => Some(0.0),
                "LAMBDA" => Some(0.2),
                "KAPPA" => Some(0.04),
                "CRITICAL_STATE_SLOPE" => Some(1.0),
                "INITIAL_VOID_RATIO" => Some(1.2),
                "OCR" => Some(1.0),
                "MINIMUM_PRESSURE" => Some(1.0),
                "MAXIMUM_PRESSURE" => Some(1000.0),
                // Any other parameter at its default, as a scene leaving it out gets.
                _ => {
                    mpm_solve::material::law::parameter_list("modified_cam_clay")?
                        .iter()
                        .find(|p| p.key == k)?
                        .default
                }
            }),
            Some("hypo-flowing") => LawSpec::by_name("hypoplasticity", &|k| match k {
                "CRITICAL_FRICTION_ANGLE" => Some(33.0),
                "GRANULAR_HARDNESS" => Some(1.0e6),
                "EXPONENT_N" => Some(0.25),
                "MINIMUM_VOID_RATIO" => Some(0.55),
                "CRITICAL_VOID_RATIO" => Some(0.95),
                "MAXIMUM_VOID_RATIO" => Some(1.05),
                "EXPONENT_ALPHA" => Some(0.25),
                "EXPONENT_BETA" => Some(1.5),
                "INITIAL_VOID_RATIO" => Some(0.7),
                "IGS_R" => Some(1e-4),
                "IGS_INITIAL" => Some(1.0),
                "MAXIMUM_PRESSURE" => Some(1000.0),
                _ => {
                    mpm_solve::material::law::parameter_list("hypoplasticity")?
                        .iter()
                        .find(|p| p.key == k)?
                        .default
                }
            }),
            _ => LawSpec::linear_elastic(10000.0, 0.3),
        }
        .unwrap();
        MaterialSpec::with_law("soil", 2000.0, law).unwrap()
    };
    let points = arg(&a, "--points").map_or(if plane { 3 } else { 4 }, |s| s.parse().unwrap());
    let mut case = Case::single_material("bench", model, soil, points, fixed);
    if !saturated {
        // Every law starts from the same stress, σv = 200, σh = 100 kPa (compression): inside
        // the φ = 30° surface (ratio 3), beyond the φ = 10° one (ratio 1.42), so under gravity
        // the `mc-plastic` points return at every step.
        use mpm_solve::input::initial_stress::{InitialStress, MaterialStart};
        let mut materials = vec![None; case.body.materials.len()];
        materials[1] = Some(MaterialStart::Uniform([
            -100.0, -200.0, -100.0, 0.0, 0.0, 0.0,
        ]));
        case.start.initial_stress = Some(InitialStress {
            k0: None,
            materials,
        });
    }
    case.time.courant = 0.5;
    case.numerics.damping = 0.05;
    if saturated {
        // Sudden 10 kPa on the top face (nodal loads of the top triangles of the box; of the
        // top edges of the rectangle, per unit thickness).
        let m = &case.model;
        let top = (0..m.node_count()).fold(f64::MIN, |t, n| t.max(m.node(n)[1]));
        let on_top: Vec<usize> = (0..m.node_count())
            .filter(|&n| (m.node(n)[1] - top).abs() < 1e-9)
            .collect();
        let face = if plane { width } else { width * width };
        let area = face / on_top.len() as f64;
        for n in on_top {
            case.loads.traction[n] = [0.0, -10.0 * area, 0.0];
        }
    } else {
        case.loads.gravity = [0.0, -9.81, 0.0];
    }
    if let Some(basis) = arg(&a, "--basis").filter(|&b| b != "tets") {
        use mpm_solve::basis::grid::GridSpec;
        use mpm_solve::basis::spline::Shape;
        let shape = match basis {
            "linear" => Shape::Linear,
            "gimp" => Shape::Gimp { a: 0.25 },
            "bspline2" => Shape::Bspline2,
            other => {
                eprintln!("bench_solver: --basis {other}: expected tets, linear, gimp or bspline2");
                std::process::exit(2);
            }
        };
        let h = width / nxz as f64;
        case.numerics.grid = Some(GridSpec {
            origin: [0.0; 3],
            cell: [h, if plane { 0.01 } else { 1.0 / ny as f64 }, h],
            cells: if plane { [nxz, ny, 1] } else { [nxz, ny, nxz] },
            dim: if plane { 2 } else { 3 },
            shape,
            points_per_axis: None,
        });
    }
    if order == "morton" {
        case = case.reordered(Reorder::Morton).unwrap();
    }
    case.run.guards.enabled = arg(&a, "--guards") != Some("off");
    case.run.engine = Options {
        threads,
        pin,
        first_touch,
    };
    let f32 = arg(&a, "--precision") == Some("f32");
    case.numerics.precision = if f32 { Precision::F32 } else { Precision::F64 };
    let law = arg(&a, "--law").unwrap_or("linear");
    // Vertical velocity -rate·(y - y_bottom): compression at a strain of about 1e-5 per step,
    // its elastic ratio of lateral to vertical increment (ν/(1-ν) = 0.43) below the active
    // ratio, so every trial lies beyond the surface.
    let flow = match arg(&a, "--shear") {
        Some(r) => Some(Flow::Shear(r.parse().unwrap())),
        None => matches!(law, "mc-flowing" | "mcc-flowing" | "hypo-flowing")
            .then_some(Flow::Compress(0.2)),
    };
    // The solver's own choice of precision and element (the case's model picks `Tri3` or
    // `Tet4`), so that the bench times the engine a run of this model would get.
    let comm = communicator(a.iter().any(|x| x == "--mpi"));
    let result = dispatch(
        &case,
        Measure {
            case: &case,
            steps,
            reps,
            flow,
            comm: comm.clone(),
        },
    )
    .unwrap();
    if comm.as_ref().is_some_and(|c| c.rank() != 0) {
        return;
    }
    let surface = if comm.is_some() {
        format!(
            ", \"ranks\": {}, \"traffic_per_step\": {}, \"rank_reports\": {}",
            comm.as_ref().map_or(1, |c| c.ranks()),
            serde_json::json!(result.traffic),
            serde_json::Value::from(result.reports.clone().unwrap_or_default())
        )
    } else if law.starts_with("mc-") && arg(&a, "--surface") != Some("off") {
        // Mohr-Coulomb's surface only (`mcc-flowing` does not start with "mc-").
        let friction = if law == "mc-elastic" { 30.0 } else { 10.0 };
        let (on, moved) = if plane {
            on_surface::<Tri3>(&case, steps, flow, friction)
        } else {
            on_surface::<Tet4>(&case, steps, flow, friction)
        };
        format!(", \"on_surface\": {on:.4}, \"returned\": {moved:.4}")
    } else {
        String::new()
    };
    let Measured {
        rates,
        phases,
        loads,
        thread_busy,
        info,
        bytes_per_point,
        huge_page_bytes,
        modelled,
        ..
    } = result;
    let mut sorted = rates.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let k = rates.iter().position(|&r| r == median).unwrap();
    let per_phase: Vec<String> = PHASES[..5]
        .iter()
        .zip(phases[k])
        .map(|(n, s)| format!("\"{n}\": {:.6e}", s / steps as f64))
        .collect();
    // Where the threads' time went, per step: the runs' wall time, the busiest thread's and
    // the mean thread's (their gaps: waiting for the slowest thread, and for the pool).
    let team: Vec<String> = PHASES[..5]
        .iter()
        .zip(loads[k])
        .map(|(n, l)| {
            let s = steps as f64;
            format!(
                "\"{n}\": [{:.6e}, {:.6e}, {:.6e}]",
                l.wall / s,
                l.busiest / s,
                l.mean / s
            )
        })
        .collect();
    let modelled_bytes: Vec<String> = PHASES[..5]
        .iter()
        .zip(modelled)
        .map(|(n, b)| format!("\"{n}\": {b:.1}"))
        .collect();
    let pinned: Vec<String> = info
        .2
        .iter()
        .map(|c| c.map_or("null".to_string(), |c| c.to_string()))
        .collect();
    // One line of JSON; a reader that closed the pipe early (`| head`) ends the run quietly,
    // any other failure to write is reported, neither as a panic.
    let line = format!(
        "{{\"case\": \"{}\", \"dim\": {}, \"law\": \"{}\", \"particles\": {}, \"elements\": {}, \"nodes\": {}, \"threads\": {}, \"pinned\": [{}], \"pin\": \"{}\", \"first_touch\": {}, \"huge_pages\": {}, \"huge_page_bytes\": {}, \"instruction_set\": \"{}\", \"avx2_copies\": {}, \"order\": \"{}\", \"steps\": {}, \"precision\": \"{}\", \"guards\": {}, \"bytes_per_point\": {}, \"modelled_bytes_per_particle_step\": {{{}}}, \"reps\": {:?}, \"median\": {:.6e}, \"phase_seconds_per_step\": {{{}}}, \"phase_team_per_step\": {{{}}}, \"thread_busy_per_step\": {:?}{}}}",
        if saturated { "saturated" } else { "dry" },
        if plane { 2 } else { 3 },
        arg(&a, "--law").unwrap_or("linear"),
        info.0,
        case.model.element_count(),
        case.model.node_count(),
        info.1,
        pinned.join(", "),
        match pin {
            Pin::Cores => "cores",
            Pin::Auto => "auto",
            Pin::None => "none",
        },
        first_touch,
        mpm_solve::parallel::huge_pages::enabled(),
        huge_page_bytes.map_or("null".to_string(), |b| b.to_string()),
        mpm_solve::driver::output::instruction_set(),
        mpm_solve::parallel::avx2::detected(),
        order,
        steps,
        if f32 { "f32" } else { "f64" },
        case.run.guards.enabled,
        bytes_per_point,
        modelled_bytes.join(", "),
        rates,
        median,
        per_phase.join(", "),
        team.join(", "),
        thread_busy[k],
        surface
    );
    if let Err(e) = writeln!(std::io::stdout().lock(), "{line}") {
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!("bench_solver: writing the result: {e}");
            std::process::exit(1);
        }
    }
}

/// What the repetitions measured.
struct Measured {
    rates: Vec<f64>,
    phases: Vec<[f64; 6]>,
    /// Per repetition and phase: the team's wall, busiest-thread and mean-thread seconds.
    loads: Vec<[mpm_solve::parallel::team::TeamLoad; 6]>,
    /// Per repetition: each thread's busy seconds per step.
    thread_busy: Vec<Vec<f64>>,
    info: (usize, usize, Vec<Option<usize>>),
    bytes_per_point: usize,
    /// Bytes on huge pages while the last repetition's engine was alive (Linux).
    huge_page_bytes: Option<u64>,
    /// Modelled bytes per particle-step of each phase.
    modelled: [f64; 5],
    /// Over MPI ranks: each rank's report of the last repetition (on rank 0).
    reports: Option<Vec<serde_json::Value>>,
    /// Per rank, per timed step of the last repetition: communicator calls, point-to-point
    /// messages and their bytes.
    traffic: Vec<Vec<f64>>,
}

/// The MPI ranks the bench was launched on (`--mpi`; the cargo feature `mpi`), or `None`.
fn communicator(mpi: bool) -> Option<std::sync::Arc<dyn mpm_solve::parallel::comm::Communicator>> {
    if !mpi {
        return None;
    }
    #[cfg(feature = "mpi")]
    {
        let world = mpm_solve::parallel::mpi_comm::MpiWorld::init().expect("MPI initialises");
        Some(std::sync::Arc::new(world))
    }
    #[cfg(not(feature = "mpi"))]
    panic!("--mpi needs the example built with --features mpi")
}

/// [`measure`] with the precision and element [`dispatch`] picks for the case.
struct Measure<'a> {
    case: &'a Case,
    steps: usize,
    reps: usize,
    flow: Option<Flow>,
    comm: Option<std::sync::Arc<dyn mpm_solve::parallel::comm::Communicator>>,
}

impl Generic for Measure<'_> {
    type Output = Measured;

    fn call<R: mpm_solve::real::Real, E: Element>(self) -> Measured {
        measure::<R, E>(self.case, self.steps, self.reps, self.flow, self.comm)
    }
}

/// Times `reps` runs of `steps` steps of `case` in precision `R` with elements `E`.
fn measure<R: mpm_solve::real::Real, E: Element>(
    case: &Case,
    steps: usize,
    reps: usize,
    flow: Option<Flow>,
    comm: Option<std::sync::Arc<dyn mpm_solve::parallel::comm::Communicator>>,
) -> Measured {
    let mut m = Measured {
        rates: Vec::new(),
        phases: Vec::new(),
        loads: Vec::new(),
        thread_busy: Vec::new(),
        info: (0, 0, Vec::new()),
        bytes_per_point: 0,
        huge_page_bytes: None,
        modelled: [0.0; 5],
        reports: None,
        traffic: Vec::new(),
    };
    // A sheared column loses a few points over its top corners: they are dropped.
    let drop_lost = matches!(flow, Some(Flow::Shear(_)));
    for _ in 0..reps {
        let mut engine = match &comm {
            Some(c) => {
                Engine::<R, E>::with_communicator(case, drop_lost, case.run.engine, c.clone())
                    .unwrap()
            }
            None => Engine::<R, E>::new(case, drop_lost).unwrap(),
        };
        if let Some(flow) = flow {
            set_flow(&mut engine, flow);
        }
        let np = engine
            .communicator()
            .sum_count(engine.particles.len() as u64) as usize;
        // Every rank starts the clock together (a collective), and the steps' own
        // collectives keep them together.
        engine.communicator().sum(0.0);
        let before = engine.communicator().traffic();
        engine.team.take_thread_busy();
        let t = Instant::now();
        for s in 0..steps {
            if let Err(e) = engine.step(engine.dt, None) {
                // A column too small for the step count (its free top springs up under the
                // uniform stress and points leave the mesh): say so, not a panic.
                eprintln!("bench_solver: step {} of {steps}: {e}", s + 1);
                std::process::exit(1);
            }
        }
        let secs = engine.communicator().max(t.elapsed().as_secs_f64());
        let after = engine.communicator().traffic();
        let per_step = [
            (after.calls - before.calls) as f64 / steps as f64,
            (after.messages - before.messages) as f64 / steps as f64,
            (after.bytes - before.bytes) as f64 / steps as f64,
        ];
        let mut all = Vec::new();
        engine.communicator().all_gather(&per_step, &mut all);
        m.traffic = all.chunks(3).map(|c| c.to_vec()).collect();
        m.reports = engine.rank_report().filter(|_| engine.is_distributed());
        m.rates.push(np as f64 * steps as f64 / secs);
        m.phases.push(engine.phase_seconds);
        m.loads.push(engine.phase_load);
        m.thread_busy.push(
            engine
                .team
                .take_thread_busy()
                .iter()
                .map(|b| b / steps as f64)
                .collect(),
        );
        m.info = (np, engine.team.threads, engine.team.pinned.clone());
        m.bytes_per_point = engine.particles.bytes_per_point();
        m.huge_page_bytes = mpm_solve::parallel::huge_pages::resident_huge_bytes();
        m.modelled = engine.modelled_bytes();
    }
    m
}

/// A velocity field the points start with.
#[derive(Debug, Clone, Copy)]
enum Flow {
    /// Uniform vertical compression at this rate (1/s).
    Compress(f64),
    /// Horizontal simple shear at this rate (1/s).
    Shear(f64),
}

/// Sets every point's velocity to `flow`, proportional to its height above the bottom.
fn set_flow<R: mpm_solve::real::Real, E: Element>(engine: &mut Engine<R, E>, flow: Flow) {
    let p = &mut engine.particles;
    let bottom = p.x.iter().fold(f64::MAX, |m, x| m.min(x[1].f64()));
    for (v, x) in p.v.iter_mut().zip(&p.x) {
        let h = x[1].f64() - bottom;
        *v = match flow {
            Flow::Compress(rate) => [R::ZERO, R::of(-rate * h), R::ZERO],
            Flow::Shear(rate) => [R::of(rate * h), R::ZERO, R::ZERO],
        };
    }
}

/// Shares of the point-steps of a run of `steps` steps that end on the Mohr-Coulomb surface
/// (φ = `friction`, c = 0: |F| within 1e-9 of the largest principal stress), and that end there
/// with a stress moved by more than 1e-9 of it (returned, not resting on the surface).
fn on_surface<E: Element>(
    case: &Case,
    steps: usize,
    flow: Option<Flow>,
    friction: f64,
) -> (f64, f64) {
    use mpm_solve::material::mohr_coulomb::Surface;
    use mpm_solve::material::principal::principal;
    let surface = Surface::<f64>::new(friction, 0.0, 0.0, 0.0);
    let mut engine = Engine::<f64, E>::new(case, false).unwrap();
    if let Some(flow) = flow {
        set_flow(&mut engine, flow);
    }
    let (mut on, mut moved, mut all) = (0usize, 0usize, 0usize);
    for _ in 0..steps {
        let before = engine.particles.stress.clone();
        engine.step(engine.dt, None).unwrap();
        let p = &engine.particles;
        for i in (0..p.len()).filter(|&i| p.active[i]) {
            let s = &p.stress[i];
            let v = principal(s).values;
            let scale = v[0].abs().max(v[2].abs());
            all += 1;
            if surface.yield_value(v[0], v[2]).abs() <= 1e-9 * scale {
                on += 1;
                let change = (0..6).fold(0.0f64, |m, k| m.max((s[k] - before[i][k]).abs()));
                if change > 1e-9 * scale {
                    moved += 1;
                }
            }
        }
    }
    (on as f64 / all as f64, moved as f64 / all as f64)
}
