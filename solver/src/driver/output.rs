//! Run outputs (docs/design.md §2.4): `mesh.vtu`, `particles_NNNNN.vtu`, `run.pvd`, `history.csv`,
//! `energy.csv`, `run.json`. Every file is written whole and atomically; the CSV and PVD files are
//! rewritten after each output time so that a run stopped by an error leaves what it completed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use mpm_shared::io::write_output_with;
use mpm_shared::text::real_to_string;
use mpm_shared::vtu::{self, Cells, DataArray, Encoding, Piece, Values};

use crate::driver::engine::Engine;
use crate::input::case::Case;
use crate::real::Real;

/// Accumulates the time series and writes the files.
pub struct Output {
    dir: PathBuf,
    pvd: Vec<(f64, String)>,
    history: String,
    energy: String,
    probes: Vec<u32>,
}

fn csv_real(s: &mut String, v: f64) {
    s.push(',');
    s.push_str(&real_to_string(v));
}

impl Output {
    /// Prepares `dir` (created if missing) and writes `mesh.vtu`.
    pub fn new<R: Real>(dir: &Path, case: &Case, engine: &Engine<R>) -> mpm_shared::Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| mpm_shared::Error::io(dir, e))?;
        write_output_with(&dir.join("mesh.vtu"), |w| {
            vtu::write_model(w, &case.model, None, Encoding::Appended)
        })?;
        let p = &engine.particles;
        // Points are re-sorted as they move: probes are kept by id and found at each output.
        let probes = case
            .probes
            .iter()
            .copied()
            .filter(|id| p.id.contains(id))
            .collect();
        Ok(Output {
            dir: dir.to_path_buf(),
            pvd: Vec::new(),
            history: if p.liquid.is_some() {
                "time,id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,syz,szx,pore_pressure\n".into()
            } else {
                "time,id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,syz,szx\n".into()
            },
            energy: "time,kinetic,external_work\n".into(),
            probes,
        })
    }

    /// Writes the state at the current time: a particle file and the updated series.
    pub fn write<R: Real>(&mut self, engine: &Engine<R>) -> mpm_shared::Result<()> {
        let p = &engine.particles;
        let active: Vec<usize> = (0..p.len()).filter(|&i| p.active[i]).collect();
        let flat = |f: &dyn Fn(usize) -> Vec<f64>| -> Vec<f64> {
            active.iter().flat_map(|&i| f(i)).collect()
        };
        let pts = flat(&|i| p.x[i].iter().map(|v| v.f64()).collect());
        let disp = flat(&|i| p.u[i].iter().map(|v| v.f64()).collect());
        let vel = flat(&|i| p.v[i].iter().map(|v| v.f64()).collect());
        let stress = flat(&|i| p.stress[i].iter().map(|v| v.f64()).collect());
        let material: Vec<i32> = active.iter().map(|&i| p.material[i] as i32).collect();
        let element: Vec<i32> = active.iter().map(|&i| p.element[i] as i32 + 1).collect();
        let id: Vec<i32> = active.iter().map(|&i| p.id[i] as i32).collect();
        let cells = Cells::vertices(active.len());
        let piece = Piece {
            points: &pts,
            cells: &cells,
            point_data: vec![
                DataArray {
                    name: "displacement",
                    components: 3,
                    values: Values::F64(&disp),
                },
                DataArray {
                    name: "velocity",
                    components: 3,
                    values: Values::F64(&vel),
                },
                DataArray {
                    name: "stress",
                    components: 6,
                    values: Values::F64(&stress),
                },
                DataArray {
                    name: "material",
                    components: 1,
                    values: Values::I32(&material),
                },
                DataArray {
                    name: "element",
                    components: 1,
                    values: Values::I32(&element),
                },
                DataArray {
                    name: "id",
                    components: 1,
                    values: Values::I32(&id),
                },
            ],
            cell_data: Vec::new(),
        };
        let (pore, liquid_vel);
        let mut piece = piece;
        if let Some(l) = &p.liquid {
            pore = active.iter().map(|&i| l.p[i].f64()).collect::<Vec<f64>>();
            liquid_vel = flat(&|i| l.w[i].iter().map(|v| v.f64()).collect());
            piece.point_data.push(DataArray {
                name: "pore_pressure",
                components: 1,
                values: Values::F64(&pore),
            });
            piece.point_data.push(DataArray {
                name: "liquid_velocity",
                components: 3,
                values: Values::F64(&liquid_vel),
            });
        }
        let name = format!("particles_{:05}.vtu", self.pvd.len());
        write_output_with(&self.dir.join(&name), |w| {
            vtu::write_vtu(w, &piece, Encoding::Appended)
        })?;
        self.pvd.push((engine.time, name));
        write_output_with(&self.dir.join("run.pvd"), |w| vtu::write_pvd(w, &self.pvd))?;
        for &id in &self.probes {
            let Some(i) = p.id.iter().position(|&x| x == id) else {
                continue;
            };
            self.history.push_str(&real_to_string(engine.time));
            let _ = write!(self.history, ",{}", p.id[i]);
            for v in p.x[i].iter().chain(&p.u[i]).chain(&p.stress[i]) {
                csv_real(&mut self.history, v.f64());
            }
            if let Some(l) = &p.liquid {
                csv_real(&mut self.history, l.p[i].f64());
            }
            self.history.push('\n');
        }
        self.energy.push_str(&real_to_string(engine.time));
        csv_real(&mut self.energy, engine.kinetic_energy());
        csv_real(&mut self.energy, engine.external_work);
        self.energy.push('\n');
        mpm_shared::io::write_output(&self.dir.join("history.csv"), self.history.as_bytes())?;
        mpm_shared::io::write_output(&self.dir.join("energy.csv"), self.energy.as_bytes())?;
        Ok(())
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

/// Writes `run.json` (strict JSON: a non-finite number is written as null).
pub fn write_summary<R: Real>(
    dir: &Path,
    case: &Case,
    engine: &Engine<R>,
    wall: f64,
    stepping: f64,
) -> mpm_shared::Result<()> {
    let phases: serde_json::Map<String, serde_json::Value> = crate::driver::engine::PHASES
        .iter()
        .zip(engine.phase_seconds)
        .map(|(k, v)| (k.to_string(), serde_json::json!(v)))
        .collect();
    let n = engine.particles.len();
    let ps = if stepping > 0.0 {
        (n as f64) * engine.steps as f64 / stepping
    } else {
        0.0
    };
    let grid_bytes = engine.grid.bytes() as f64 / n.max(1) as f64;
    // serde_json writes a non-finite number as null, so the file stays strict JSON.
    let json = serde_json::json!({
        "schema_version": RUN_JSON_SCHEMA,
        "case": case.name,
        "inputs": case.inputs,
        "threads": engine.team.threads,
        "pinning": match case.engine.pin {
            crate::parallel::team::Pin::None => "none",
            crate::parallel::team::Pin::Cores => "cores",
        },
        "pinned_cores": engine.team.pinned,
        "first_touch": case.engine.first_touch,
        "precision": R::NAME,
        "particles": n,
        "elements": engine.mesh.elements(),
        "nodes": engine.mesh.nodes(),
        "steps": engine.steps,
        "dt": engine.dt,
        "simulated_time": engine.time,
        "wall_seconds": wall,
        "particle_steps_per_second": ps,
        "phase_seconds": phases,
        "bytes_per_particle": engine.particles.bytes_per_point() as f64 + grid_bytes,
        "peak_rss_bytes": peak_rss_bytes(),
        "lost_particles": engine.lost,
    });
    let mut text = serde_json::to_string_pretty(&json).expect("plain JSON");
    text.push('\n');
    mpm_shared::io::write_output(&dir.join("run.json"), text.as_bytes())
}
