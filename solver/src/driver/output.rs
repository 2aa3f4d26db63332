//! Run outputs (docs/design.md §2.4): `mesh.vtu`, `particles_NNNNN.vtu`, `run.pvd`, `history.csv`,
//! `energy.csv`, `reaction.csv` (cases with prescribed velocities), `run.json`. Every file is written whole and atomically; the CSV and PVD files are
//! rewritten after each output time so that a run stopped by an error leaves what it completed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use mpm_shared::io::write_output_with;
use mpm_shared::text::real_to_string;
use mpm_shared::vtu::{self, Cells, DataArray, Encoding, Piece, Values};

use crate::driver::checkpoint::Series;
use crate::driver::engine::Engine;
use crate::element::Element;
use crate::input::case::Case;
use crate::real::Real;
use crate::state::particles::{Field, FieldReader, Value, Written};

/// Accumulates the time series and writes the files.
pub struct Output {
    dir: PathBuf,
    series: Series,
    probes: Vec<u32>,
}

fn csv_real(s: &mut String, v: f64) {
    s.push(',');
    s.push_str(&real_to_string(v));
}

/// A text field, quoted (inner quotes doubled) when it holds a comma, quote or line break.
fn csv_text(s: &mut String, t: &str) {
    if t.contains([',', '"', '\n', '\r']) {
        s.push('"');
        s.push_str(&t.replace('"', "\"\""));
        s.push('"');
    } else {
        s.push_str(t);
    }
}

impl Output {
    /// Prepares `dir` (created if missing) and writes `mesh.vtu`.
    pub fn new<R: Real, E: Element>(
        dir: &Path,
        case: &Case,
        engine: &Engine<R, E>,
    ) -> mpm_shared::Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| mpm_shared::Error::io(dir, e))?;
        write_output_with(&dir.join("mesh.vtu"), |w| {
            vtu::write_model(w, &case.model, None, Encoding::Appended)
        })?;
        let p = &engine.particles;
        // Points are re-sorted as they move: probes are kept by id and found at each output.
        let probes = case
            .run
            .probes
            .iter()
            .copied()
            .filter(|id| p.id.contains(id))
            .collect();
        Ok(Output {
            dir: dir.to_path_buf(),
            series: Series {
                pvd: Vec::new(),
                history: if p.liquid.is_some() {
                    "time,id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,syz,szx,pore_pressure\n".into()
                } else {
                    "time,id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,syz,szx\n".into()
                },
                energy: "time,kinetic,external_work,strain,dissipated,balance_error\n".into(),
                reaction: if engine.reactions.is_empty() {
                    String::new()
                } else {
                    "step,time,set,ux,uy,uz,fx,fy,fz\n".into()
                },
            },
            probes,
        })
    }

    /// What the series files hold so far (for a checkpoint).
    pub fn series(&self) -> &Series {
        &self.series
    }

    /// Continues from a checkpoint's series: rewrites `run.pvd`, `history.csv`, `energy.csv` and
    /// `reaction.csv` as they were then (none of them before the first output).
    pub fn resume(&mut self, series: Series) -> mpm_shared::Result<()> {
        self.series = series;
        if self.series.pvd.is_empty() {
            for f in ["run.pvd", "history.csv", "energy.csv", "reaction.csv"] {
                let p = self.dir.join(f);
                match std::fs::remove_file(&p) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(mpm_shared::Error::io(&p, e))
                    }
                    _ => {}
                }
            }
            return Ok(());
        }
        self.write_series()
    }

    fn write_series(&self) -> mpm_shared::Result<()> {
        let s = &self.series;
        write_output_with(&self.dir.join("run.pvd"), |w| vtu::write_pvd(w, &s.pvd))?;
        mpm_shared::io::write_output(&self.dir.join("history.csv"), s.history.as_bytes())?;
        mpm_shared::io::write_output(&self.dir.join("energy.csv"), s.energy.as_bytes())?;
        if !s.reaction.is_empty() {
            mpm_shared::io::write_output(&self.dir.join("reaction.csv"), s.reaction.as_bytes())?;
        }
        Ok(())
    }

    /// Writes the state at the current time: a particle file and the updated series.
    pub fn write<R: Real, E: Element>(&mut self, engine: &Engine<R, E>) -> mpm_shared::Result<()> {
        let p = &engine.particles;
        let active: Vec<usize> = (0..p.len()).filter(|&i| p.active[i]).collect();
        // The particle file holds what the field list marks as written, in its order.
        let mut arrays = Collect {
            origin: engine.mesh.origin,
            active: &active,
            points: Vec::new(),
            arrays: Vec::new(),
        };
        p.read_fields(&mut arrays);
        let cells = Cells::vertices(active.len());
        let piece = Piece {
            points: &arrays.points,
            cells: &cells,
            point_data: arrays
                .arrays
                .iter()
                .map(|(name, components, values)| DataArray {
                    name,
                    components: *components,
                    values: match values {
                        Column::F64(v) => Values::F64(v),
                        Column::I32(v) => Values::I32(v),
                    },
                })
                .collect(),
            cell_data: Vec::new(),
        };
        let name = format!("particles_{:05}.vtu", self.series.pvd.len());
        write_output_with(&self.dir.join(&name), |w| {
            vtu::write_vtu(w, &piece, Encoding::Appended)
        })?;
        let s = &mut self.series;
        s.pvd.push((engine.time, name));
        for &id in &self.probes {
            let Some(i) = p.id.iter().position(|&x| x == id) else {
                continue;
            };
            s.history.push_str(&real_to_string(engine.time));
            let _ = write!(s.history, ",{}", p.id[i]);
            for v in engine.mesh.global(&p.x[i]) {
                csv_real(&mut s.history, v);
            }
            for v in p.u[i].iter().chain(&p.stress[i]) {
                csv_real(&mut s.history, v.f64());
            }
            if let Some(l) = &p.liquid {
                csv_real(&mut s.history, l.p[i].f64());
            }
            s.history.push('\n');
        }
        s.energy.push_str(&real_to_string(engine.time));
        csv_real(&mut s.energy, engine.total_kinetic_energy());
        csv_real(&mut s.energy, engine.external_work);
        csv_real(&mut s.energy, engine.internal_energy());
        csv_real(&mut s.energy, engine.dissipated);
        csv_real(&mut s.energy, engine.balance_error());
        s.energy.push('\n');
        for r in &engine.reactions {
            let _ = write!(
                s.reaction,
                "{},{},",
                engine.steps,
                real_to_string(engine.time)
            );
            csv_text(&mut s.reaction, &r.name);
            for v in r.displacement().iter().chain(&r.reported()) {
                csv_real(&mut s.reaction, *v);
            }
            s.reaction.push('\n');
        }
        // The particle file first, then the series that name it: a reader of run.pvd mid-run
        // sees complete outputs only.
        self.write_series()
    }
}

/// One point-data array of a particle file.
enum Column {
    F64(Vec<f64>),
    I32(Vec<i32>),
}

/// Gathers the written fields of the active points.
struct Collect<'a> {
    /// Added to positions, so that files are in the input's coordinates.
    origin: [f64; 3],
    active: &'a [usize],
    points: Vec<f64>,
    arrays: Vec<(&'static str, usize, Column)>,
}

impl FieldReader for Collect<'_> {
    fn field<T: Value>(&mut self, field: Field, values: &[T]) {
        let (name, offset) = match field.written {
            Written::No => return,
            Written::Position => {
                for &i in self.active {
                    let start = self.points.len();
                    values[i].push_f64(&mut self.points);
                    for (a, x) in self.points[start..].iter_mut().enumerate() {
                        *x += self.origin[a];
                    }
                }
                return;
            }
            Written::As(name) => (name, 0),
            Written::OneBased(name) => (name, 1),
        };
        let column = if T::INTEGER || offset != 0 {
            let mut out = Vec::with_capacity(self.active.len() * T::COMPONENTS);
            for &i in self.active {
                values[i].push_i32(offset, &mut out);
            }
            Column::I32(out)
        } else {
            let mut out = Vec::with_capacity(self.active.len() * T::COMPONENTS);
            for &i in self.active {
                values[i].push_f64(&mut out);
            }
            Column::F64(out)
        };
        self.arrays.push((name, T::COMPONENTS, column));
    }
}

/// The instruction set this binary was compiled for: `x86-64` (the portable default),
/// `x86-64-v3` (AVX2, FMA and BMI2, e.g. `RUSTFLAGS="-C target-cpu=x86-64-v3"`), `x86-64-v4`
/// (AVX-512 as well), or the architecture's name elsewhere. Outputs do not depend on it
/// (docs/design.md §9); speed does, so benchmarks record it.
pub fn instruction_set() -> &'static str {
    if cfg!(target_arch = "x86_64") {
        let v3 = cfg!(all(
            target_feature = "avx2",
            target_feature = "fma",
            target_feature = "bmi2"
        ));
        match (v3, cfg!(target_feature = "avx512f")) {
            (true, true) => "x86-64-v4",
            (true, false) => "x86-64-v3",
            _ => "x86-64",
        }
    } else {
        std::env::consts::ARCH
    }
}

/// Peak resident memory of this process in bytes (Linux), 0 where unknown.
pub fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// Version of the layout of `run.json`: raised whenever a key is renamed or changes meaning.
pub const RUN_JSON_SCHEMA: u32 = 1;

/// How a run stopped, as `run.json` reports it.
#[derive(Debug, Clone, Copy)]
pub enum Stop<'a> {
    /// It reached its last output time.
    Completed,
    /// A guard rail tripped, or an unstable step flung a point out of the mesh.
    Diverged(&'a crate::driver::guard::Divergence),
    /// A signal stopped it after a step (the message says where).
    Interrupted(&'a str),
    /// An error stopped it (the message).
    Failed(&'a str),
}

impl Stop<'_> {
    /// `run.json`'s `status`.
    pub fn status(&self) -> &'static str {
        match self {
            Stop::Completed => "completed",
            Stop::Diverged(_) => "diverged",
            Stop::Interrupted(_) => "interrupted",
            Stop::Failed(_) => "failed",
        }
    }

    /// `run.json`'s `reason`: why it stopped, in words.
    pub fn reason(&self) -> String {
        match self {
            Stop::Completed => "reached the last output time".into(),
            Stop::Diverged(d) => d.to_string(),
            Stop::Interrupted(m) | Stop::Failed(m) => m.to_string(),
        }
    }
}

/// What `run.json` says of a run besides the engine's state.
pub struct Summary<'a> {
    /// The output folder.
    pub dir: &'a Path,
    /// The case.
    pub case: &'a Case,
    /// Wall seconds of the run so far (over resumed runs).
    pub wall: f64,
    /// Wall seconds spent stepping.
    pub stepping: f64,
    /// How it stopped.
    pub stop: Stop<'a>,
    /// Per rank, over MPI ranks (`Engine::rank_report`).
    pub ranks: Option<Vec<serde_json::Value>>,
}

/// Writes `run.json` (strict JSON: a non-finite number is written as null).
pub fn write_summary<R: Real, E: Element>(
    summary: Summary<'_>,
    engine: &Engine<R, E>,
) -> mpm_shared::Result<()> {
    let Summary {
        dir,
        case,
        wall,
        stepping,
        stop,
        ranks,
    } = summary;
    let n = engine.particles.len();
    let ps = if stepping > 0.0 {
        (n as f64) * engine.steps as f64 / stepping
    } else {
        0.0
    };
    let grid_bytes = engine.grid.bytes() as f64 / n.max(1) as f64;
    let phases = PhaseTables::of(engine);
    let diverged = match stop {
        Stop::Diverged(d) => Some(d),
        _ => None,
    };
    // serde_json writes a non-finite number as null, so the file stays strict JSON.
    let mut json = serde_json::json!({
        "schema_version": RUN_JSON_SCHEMA,
        "case": case.name,
        "inputs": case.inputs,
        "threads": engine.team.threads,
        "pinning": match case.run.engine.pin {
            crate::parallel::team::Pin::None => "none",
            crate::parallel::team::Pin::Cores => "cores",
            crate::parallel::team::Pin::Auto => "auto",
        },
        "pinned_cores": engine.team.pinned,
        "busy_cores": engine.team.busy,
        "first_touch": case.run.engine.first_touch,
        "huge_pages": crate::parallel::huge_pages::enabled(),
        "huge_page_bytes": crate::parallel::huge_pages::resident_huge_bytes(),
        "precision": R::NAME,
        "instruction_set": instruction_set(),
        "particles": n,
        "elements": engine.mesh.elements(),
        "nodes": engine.mesh.nodes(),
        "steps": engine.steps,
        "dt": engine.dt,
        "simulated_time": engine.time,
        "wall_seconds": wall,
        "particle_steps_per_second": ps,
        "phase_seconds": phases.seconds,
        "phase_ns_per_particle_step": phases.ns,
        "phase_threads_ns_per_particle_step": phases.threads_ns,
        "modelled_bytes_per_particle_step": phases.bytes,
        "bytes_per_particle": engine.particles.bytes_per_point() as f64 + grid_bytes,
        "peak_rss_bytes": peak_rss_bytes(),
        "lost_particles": engine.lost,
        "status": stop.status(),
        "reason": stop.reason(),
        "energy": energy_json(engine),
        "diagnosis": diverged.map(diagnosis_json),
    });
    // Whether the point passes ran their AVX2 copies (docs/design.md §9); outside the literal
    // above, which is at the macro's recursion limit (the keys are written sorted either way).
    json["avx2_copies"] = serde_json::json!(crate::parallel::avx2::detected());
    json["scheme"] = scheme_json(engine);
    if let Some(ranks) = ranks {
        add_ranks(&mut json, ranks, &engine.balance);
    }
    let mut text = serde_json::to_string_pretty(&json).expect("plain JSON");
    text.push('\n');
    mpm_shared::io::write_output(&dir.join("run.json"), text.as_bytes())
}

/// `run.json`'s tables by reported phase: seconds, nanoseconds per particle-step, where the
/// threads' time went, and the modelled bytes.
struct PhaseTables {
    seconds: serde_json::Map<String, serde_json::Value>,
    ns: serde_json::Map<String, serde_json::Value>,
    threads_ns: serde_json::Map<String, serde_json::Value>,
    bytes: serde_json::Map<String, serde_json::Value>,
}

impl PhaseTables {
    fn of<R: Real, E: Element>(engine: &Engine<R, E>) -> Self {
        use crate::driver::engine::PHASES;
        let particle_steps = (engine.particles.len() as f64) * engine.steps as f64;
        // Nanoseconds per particle-step (0 before any step).
        let per_ps = |v: f64| {
            if particle_steps > 0.0 {
                v * 1e9 / particle_steps
            } else {
                0.0
            }
        };
        let table = |values: &mut dyn Iterator<Item = serde_json::Value>| {
            PHASES
                .iter()
                .zip(values)
                .map(|(k, v)| (k.to_string(), v))
                .collect()
        };
        PhaseTables {
            seconds: table(&mut engine.phase_seconds.iter().map(|&v| serde_json::json!(v))),
            ns: table(
                &mut engine
                    .phase_seconds
                    .iter()
                    .map(|&v| serde_json::json!(per_ps(v))),
            ),
            // Where the threads' time went in each step phase, in ns per particle-step: the
            // mean thread's work, the wait for the busiest thread, the pool's start and join
            // (the output phase is the caller's).
            threads_ns: table(&mut engine.phase_load[..5].iter().map(|l| {
                serde_json::json!({
                    "work": per_ps(l.mean),
                    "imbalance": per_ps(l.busiest - l.mean),
                    "pool": per_ps(l.wall - l.busiest),
                })
            })),
            bytes: table(
                &mut engine
                    .modelled_bytes()
                    .into_iter()
                    .map(|b| serde_json::json!(b)),
            ),
        }
    }
}

/// `run.json`'s energy terms; under mass scaling by f, the kinetic energy of the scaled mass
/// (f times the physical one) beside it: what the run's inertia carries that the soil's would
/// not.
fn energy_json<R: Real, E: Element>(engine: &Engine<R, E>) -> serde_json::Value {
    let mut out = serde_json::json!({
        "kinetic": engine.total_kinetic_energy(),
        "strain": engine.internal_energy(),
        "liquid_compression": engine.internal_energy() - engine.strain_energy,
        "dissipated": engine.dissipated,
        "external_work": engine.external_work,
        "balance_work": engine.balance_work,
        "balance_error": engine.balance_error(),
        "energy_tolerance": engine.guards.energy_tolerance,
        "guards": engine.guards.enabled,
    });
    let f = engine.config.mass_scaling;
    if f != 1.0 {
        out["mass_scaling"] = serde_json::json!({
            "factor": f,
            "kinetic_of_scaled_mass": f * engine.total_kinetic_energy(),
        });
    }
    out
}

/// `run.json`'s scheme: `explicit`, or the semi-implicit scheme with what its pressure solves
/// took (steps solved, conjugate-gradient iterations in all, per step at most and on average,
/// the largest relative residual a step ended with, the tolerance).
fn scheme_json<R: Real, E: Element>(engine: &Engine<R, E>) -> serde_json::Value {
    let Some(s) = &engine.semi_implicit else {
        return serde_json::json!({ "name": "explicit" });
    };
    let c = &s.counts;
    serde_json::json!({
        "name": "semi-implicit",
        "pressure_solves": c.solves,
        "iterations": c.iterations,
        "most_iterations": c.most,
        "mean_iterations": c.iterations as f64 / (c.solves.max(1) as f64),
        "worst_residual": c.worst_residual,
        "tolerance": s.tolerance,
    })
}

/// `run.json`'s diagnosis of a diverged run.
fn diagnosis_json(d: &crate::driver::guard::Divergence) -> serde_json::Value {
    serde_json::json!({
        "check": d.check.name(),
        "step": d.step,
        "time": d.time,
        "point": d.point,
        "element": d.element,
        "node": d.node,
        "field": d.field,
        "value": d.value,
        "cause": d.cause,
        "message": d.to_string(),
    })
}

/// A run over MPI ranks: the mesh is the whole one, and each rank reports its share.
fn add_ranks(
    json: &mut serde_json::Value,
    ranks: Vec<serde_json::Value>,
    b: &crate::driver::engine::Balance,
) {
    let elements: u64 = ranks.iter().filter_map(|r| r["elements"].as_u64()).sum();
    json["elements"] = serde_json::json!(elements);
    json["nodes"] = serde_json::Value::Null;
    json["ranks"] = serde_json::json!(ranks);
    json["balance"] = serde_json::json!({
        "imbalance": b.imbalance,
        "worst_imbalance": b.worst,
        "repartitions": b.repartitions,
    });
}
