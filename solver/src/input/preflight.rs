//! What a run will cost, predicted before any work: material points, time steps, output volume,
//! memory and a rough wall time (which a few of the case's own steps, timed by `--check`, make
//! this machine's: [`Plan::calibrated`]), checked against the user's limits. A mistyped output interval or
//! stiffness is refused here with the numbers that show the mistake, instead of filling the disk
//! or promising an ETA of centuries.

use std::fmt;
use std::path::Path;

use crate::driver::units;
use crate::input::case::{Case, Precision};

/// Bytes one material point takes in a `particles_NNNNN.vtu` file: position, displacement and
/// velocity (3 × f64 each), stress (6 × f64), material, element and id (i32), and the vertex
/// cell (connectivity and offset as i64, type as u8).
const VTU_POINT_BYTES: f64 = (3.0 + 3.0 + 3.0 + 6.0) * 8.0 + 3.0 * 4.0 + 8.0 + 8.0 + 1.0;
/// Extra bytes per point of a two-phase run: pore pressure and liquid velocity.
const VTU_LIQUID_BYTES: f64 = 4.0 * 8.0;
/// XML of one particle file, its `run.pvd` line and its `energy.csv` row.
const VTU_FILE_BYTES: f64 = 2600.0;
/// One `history.csv` row: 14 or 15 numbers of up to 24 characters.
const HISTORY_ROW_BYTES: f64 = 15.0 * 24.0;

/// Rough speed of the time step per thread, in point-steps per second, on the machines the
/// benchmarks ran on (docs/performance.md: 10–16 M/s on 2 cores for a 1M-point two-phase run).
/// Used only for the wall-time estimate.
const DRY_RATE_PER_THREAD: f64 = 6e6;
/// The same for two-phase runs.
const TWO_PHASE_RATE_PER_THREAD: f64 = 4e6;
/// How much faster single precision steps, from `scripts/bench-solver` (docs/performance.md:
/// the ratio of f32 to f64 particle-steps/s on the 1M-point cases, 2 threads).
const F32_SPEEDUP: f64 = 1.1;
/// Largest ratio between an f32 run's error and its f64 twin's on the accuracy map's dry
/// problems and uncrossed consolidation (docs/accuracy.md, "Single precision against double").
const F32_ERROR_FACTOR: f64 = 1.1;
/// Fixed cost of a step (thread barriers, bookkeeping), seconds.
const STEP_OVERHEAD: f64 = 20e-6;

/// Most output times a scene may ask for (each writes a particle file).
pub const MAX_OUTPUTS: f64 = 1e7;

/// Limits a run must stay within (`--max-output`, `--max-steps`, `--max-lost`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Largest predicted output volume, bytes.
    pub max_output_bytes: f64,
    /// Largest predicted number of time steps.
    pub max_steps: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_output_bytes: 4e9,
            max_steps: 1e8,
        }
    }
}

/// The predictions for one case.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Material points the run will place.
    pub points: u64,
    /// Elements and nodes of the model.
    pub elements: usize,
    /// Nodes of the model.
    pub nodes: usize,
    /// Whether the liquid phase is computed.
    pub two_phase: bool,
    /// Critical time step (s).
    pub dt: f64,
    /// Simulated time (s).
    pub end_time: f64,
    /// Time steps to the end (an upper bound for quasi-static load steps, which may converge
    /// earlier), of each run.
    pub steps: f64,
    /// Runs of the case: 2 for a consolidation job with its workshop twin
    /// ([`crate::input::case::ConsolidationSpec::runs`]), each with as many steps and outputs.
    pub runs: usize,
    /// Output times.
    pub outputs: usize,
    /// Probes written to `history.csv`.
    pub probes: usize,
    /// Bytes the outputs will take on disk.
    pub output_bytes: f64,
    /// Bytes of memory the run will hold (points, grid and mesh; excluding the model as read).
    pub memory_bytes: f64,
    /// Threads the estimate assumes.
    pub threads: usize,
    /// Precision the estimate assumes.
    pub precision: Precision,
    /// Wall time the time steps will take (s): from the benchmarks' rates, or from steps of
    /// the case timed here once [`Plan::calibrated`].
    pub wall_seconds: f64,
    /// The steps timed on this machine, where the plan was calibrated.
    pub calibration: Option<Calibration>,
    /// How far the mesh lets a structure travel (a moving mesh, or contact on a fixed one).
    pub mesh_limits: Option<MeshLimits>,
}

/// How far the mesh lets a structure travel before the run stops being sound.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshLimits {
    /// A moving mesh: the time step stays the initial mesh's, so a box ahead of the structure
    /// may shrink only to the Courant number of its length. Per storage box, its span along
    /// the axis (m) and that travel, (1 − Courant) × its length.
    Moving {
        /// The axis (0: x, 1: y, 2: z).
        axis: usize,
        /// The Courant number the step takes.
        courant: f64,
        /// Per storage box: [from, to] along the axis, and the travel towards it (m).
        boxes: Vec<([f64; 2], f64)>,
    },
    /// Contact on a fixed mesh: the interface is the initial one, so the structure may move a
    /// fraction of its smallest cell (m) only.
    Fixed {
        /// The structure's smallest element altitude (m).
        cell: f64,
    },
}

impl MeshLimits {
    /// The limits of `case`, whose elements' smallest altitudes are `altitude`; `None` without
    /// a moving mesh or contact.
    fn of(case: &Case, altitude: &[f64]) -> Option<Self> {
        let b = &case.boundary;
        if let Some(m) = &b.moving_mesh {
            let boxes = m
                .storage
                .iter()
                .map(|corners| {
                    let along = corners.iter().map(|&n| case.model.node(n as usize)[m.axis]);
                    let lo = along.clone().fold(f64::INFINITY, f64::min);
                    let hi = along.fold(f64::NEG_INFINITY, f64::max);
                    ([lo, hi], (1.0 - case.time.courant).max(0.0) * (hi - lo))
                })
                .collect();
            return Some(MeshLimits::Moving {
                axis: m.axis,
                courant: case.time.courant,
                boxes,
            });
        }
        let contact = b.contact.as_ref()?;
        // The case's elements are the model's, in its order.
        let cell = case
            .body
            .element_material
            .iter()
            .zip(altitude)
            .filter(|(&m, _)| m == contact.material)
            .map(|(_, &a)| a)
            .fold(f64::INFINITY, f64::min);
        Some(MeshLimits::Fixed { cell })
    }
}

impl fmt::Display for MeshLimits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshLimits::Moving {
                axis,
                courant,
                boxes,
            } => {
                let name = ["x", "y", "z"][(*axis).min(2)];
                write!(f, "  mesh limits: the time step stays the initial mesh's (Courant {courant}), so the structure may travel")?;
                for (k, ([lo, hi], travel)) in boxes.iter().enumerate() {
                    let sep = if k == 0 { "" } else { "; or" };
                    write!(
                        f,
                        "{sep} {travel:.3} m into the box from {name} = {} to {} m",
                        mpm_shared::text::real_to_string(*lo),
                        mpm_shared::text::real_to_string(*hi)
                    )?;
                }
                write!(f, " (its cells then shrink to {courant} of their length; beyond, the step is not stable)")
            }
            MeshLimits::Fixed { cell } => write!(
                f,
                "  mesh limits: contact on a fixed mesh: the interface is the initial one, so the \
                 structure may move a fraction of its smallest cell ({cell:.3} m) only; add \
                 [moving_mesh] for a longer travel"
            ),
        }
    }
}

/// Steps of the case timed on this machine (`mpm_solve::driver::calibrate`), with the threads,
/// pinning and precision the run would have.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Steps timed.
    pub steps: u64,
    /// Their wall time (s).
    pub seconds: f64,
}

impl Calibration {
    /// Seconds per step.
    pub fn per_step(&self) -> f64 {
        self.seconds / self.steps.max(1) as f64
    }
}

/// A limit the run would exceed, with the numbers that show why.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PreflightError {
    /// The outputs would not fit in `--max-output` or on the disk.
    #[error(
        "the run would write about {} ({} outputs, one every {} of simulated time, {} each), more than {what} ({}); write fewer outputs (a longer output interval) or raise --max-output",
        units::bytes(*.volume),
        units::count(*.outputs as f64),
        units::duration(*.interval),
        units::bytes(*.per_output),
        units::bytes(*.limit)
    )]
    OutputVolume {
        /// Predicted volume, bytes.
        volume: f64,
        /// Number of outputs.
        outputs: usize,
        /// Mean simulated time between outputs (s).
        interval: f64,
        /// Volume of one output, bytes.
        per_output: f64,
        /// Which limit: `--max-output` or the free space of the output folder.
        what: String,
        /// Its value, bytes.
        limit: f64,
    },
    /// The run would take too many steps.
    #[error(
        "the run would take about {} time steps of {} to reach {}, about {} at a rough {} on {threads} thread(s); --max-steps is {}. The critical step is set by the stiffest, lightest material and the smallest element: check Young's modulus, density and the mesh, or raise --max-steps",
        units::count(*.steps),
        units::duration(*.dt),
        units::duration(*.end),
        units::duration(*.wall),
        units::rate_of(*.rate, "point-steps"),
        units::count(*.limit)
    )]
    Steps {
        /// Predicted steps.
        steps: f64,
        /// Critical time step (s).
        dt: f64,
        /// Simulated time (s).
        end: f64,
        /// Estimated wall time (s).
        wall: f64,
        /// Assumed speed, point-steps per second.
        rate: f64,
        /// Threads assumed.
        threads: usize,
        /// The limit.
        limit: f64,
    },
}

/// Why a case cannot be planned: its mesh or its time step is unusable.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// An inverted or flat element, or a mesh that is not tetrahedral.
    #[error(transparent)]
    Mesh(#[from] crate::element::mesh::MeshError),
    /// The critical time step is not a positive number.
    #[error(transparent)]
    TimeStep(#[from] crate::input::time_step::TimeStepError),
}

/// Predicts what running `case` on `threads` threads will cost. Errors where the mesh or time
/// step is unusable (inverted elements, no stiffness).
pub fn plan(case: &Case, threads: usize) -> Result<Plan, PlanError> {
    use crate::element::{tet4::Tet4, tri3::Tri3, tri3::Tri3Axi, ElementKind};
    // What the plan needs of the mesh: its computational nodes and the elements' altitudes.
    fn sizes<E: crate::element::Element>(
        case: &Case,
    ) -> Result<(usize, Vec<f64>), crate::element::mesh::MeshError> {
        let mesh = case.mesh::<E, f64>()?;
        Ok((mesh.nodes(), mesh.min_altitude))
    }
    let (nodes, altitude) = match ElementKind::of(case.model.dimension, case.model.element_type) {
        Some(ElementKind::Tri3) => sizes::<Tri3>(case)?,
        Some(ElementKind::Tri3Axi) => sizes::<Tri3Axi>(case)?,
        _ => sizes::<Tet4>(case)?,
    };
    let dt = crate::input::time_step::critical(case, 0..altitude.len(), |e| altitude[e])?;
    let points: u64 = case
        .body
        .points_per_element
        .iter()
        .zip(&case.body.element_material)
        .filter(|(_, &m)| m != 0)
        .map(|(&n, _)| n as u64)
        .sum();
    let two_phase = case.has_liquid();
    // Steps: every output interval (load step) rounds up to whole steps; a quasi-static load
    // step ends after at most its step limit + 1.
    let mut steps = if case.time.initial_step.is_some() {
        1.0
    } else {
        0.0
    };
    let mut t0 = 0.0;
    for &t in &case.time.output_times {
        let n = ((t - t0) / dt).ceil().max(1.0);
        steps += match case.time.quasi_static.and_then(|q| q.max_steps) {
            Some(m) => n.min(m as f64 + 1.0),
            None => n,
        };
        t0 = t;
    }
    let per_point = VTU_POINT_BYTES + if two_phase { VTU_LIQUID_BYTES } else { 0.0 };
    let outputs = case.time.output_times.len();
    let per_output = points as f64 * per_point
        + VTU_FILE_BYTES
        + case.run.probes.len() as f64 * HISTORY_ROW_BYTES;
    let corners = case.model.element_type.nodes() as f64;
    let mesh_file = nodes as f64 * 24.0
        + case.model.element_count() as f64 * (corners * 8.0 + 9.0)
        + VTU_FILE_BYTES;
    let runs = case.start.consolidation.map_or(1, |s| s.runs());
    let output_bytes = runs as f64 * (outputs as f64 * per_output + mesh_file);
    let real = case.numerics.precision.bytes() as f64;
    let point_bytes = if two_phase { 24.0 } else { 17.0 } * real + 13.0;
    let node_bytes = if two_phase { 32.0 } else { 16.0 } * real + 24.0 + 6.0;
    let element_bytes = (3.0 * 3.0 + 4.0 * 3.0 + 2.0) * real + 4.0 * 4.0 * 2.0;
    let memory_bytes = points as f64 * point_bytes
        + nodes as f64 * node_bytes
        + altitude.len() as f64 * element_bytes;
    let threads = threads.max(1);
    let rate = rate(threads, two_phase, case.numerics.precision);
    let wall_seconds = runs as f64 * steps * (points as f64 / rate + STEP_OVERHEAD);
    Ok(Plan {
        points,
        elements: case.model.element_count(),
        nodes: case.model.node_count(),
        two_phase,
        dt,
        end_time: case.time.end_time,
        steps,
        runs,
        outputs,
        probes: case.run.probes.len(),
        output_bytes,
        memory_bytes,
        threads,
        precision: case.numerics.precision,
        wall_seconds,
        calibration: None,
        mesh_limits: MeshLimits::of(case, &altitude),
    })
}

/// The assumed speed, point-steps per second.
fn rate(threads: usize, two_phase: bool, precision: Precision) -> f64 {
    let per_thread = if two_phase {
        TWO_PHASE_RATE_PER_THREAD
    } else {
        DRY_RATE_PER_THREAD
    };
    let speedup = match precision {
        Precision::F64 => 1.0,
        Precision::F32 => F32_SPEEDUP,
    };
    threads as f64 * per_thread * speedup
}

impl Plan {
    /// The speed the wall time assumes, point-steps per second: measured, where calibrated.
    fn rate(&self) -> f64 {
        match self.calibration {
            Some(c) if c.seconds > 0.0 => self.points as f64 / c.per_step(),
            _ => rate(self.threads, self.two_phase, self.precision),
        }
    }

    /// The plan with its wall time from steps of the case timed here: the run's steps at the
    /// measured seconds per step (the time the outputs take to write not included).
    pub fn calibrated(mut self, c: Calibration) -> Self {
        self.wall_seconds = self.runs as f64 * self.steps * c.per_step();
        self.calibration = Some(c);
        self
    }

    /// Checks the plan against `limits` and, when `out` is given, the free space where the
    /// outputs go (its nearest existing ancestor).
    pub fn check(&self, limits: &Limits, out: Option<&Path>) -> Result<(), PreflightError> {
        let volume_error = |what: String, limit: f64| PreflightError::OutputVolume {
            volume: self.output_bytes,
            outputs: self.outputs,
            interval: self.end_time / self.outputs.max(1) as f64,
            per_output: self.output_bytes / self.outputs.max(1) as f64,
            what,
            limit,
        };
        if self.output_bytes > limits.max_output_bytes {
            return Err(volume_error("--max-output".into(), limits.max_output_bytes));
        }
        if let Some(dir) = out {
            if let Some((at, free)) = free_space(dir) {
                if self.output_bytes > free as f64 {
                    return Err(volume_error(
                        format!("the free space on {}", at.display()),
                        free as f64,
                    ));
                }
            }
        }
        if self.steps > limits.max_steps {
            return Err(PreflightError::Steps {
                steps: self.steps,
                dt: self.dt,
                end: self.end_time,
                wall: self.wall_seconds,
                rate: self.rate(),
                threads: self.threads,
                limit: limits.max_steps,
            });
        }
        Ok(())
    }
}

/// Settings that cost less than the case's at similar error on the problems of the accuracy map
/// (docs/accuracy.md: Terzaghi consolidation, a 1D elastic wave and a self-weight column, on
/// linear tetrahedra), one line each, with what the map measured. Rules of thumb: the map's
/// problems are one-dimensional and elastic, so the lines say so.
pub fn cheaper_settings(case: &Case) -> Vec<String> {
    let mut out = Vec::new();
    if case.numerics.precision == Precision::F64 {
        out.push(format!(
            "--precision f32: about half the bytes per point and {F32_SPEEDUP}× the speed; on the \
             map's dry problems and uncrossed consolidation its error was within \
             {F32_ERROR_FACTOR}× of f64's (not under cell crossing: see the map)"
        ));
    }
    let four = case
        .body
        .points_per_element
        .iter()
        .zip(&case.body.element_material)
        .any(|(&n, &m)| m != 0 && n == 4);
    if four && !case.has_liquid() {
        out.push(
            "1 material point per element instead of 4: a quarter of the points; on the map's \
             self-weight column its stress error was 1.6× smaller (the point sits at the \
             centroid), on the wave about the same"
                .into(),
        );
    }
    if case.time.courant < 0.9 && !case.has_liquid() {
        out.push(format!(
            "Courant number 0.9 instead of {}: {:.1}× fewer steps; on the map's dry problems the \
             error changed by at most 10 % between Courant 0.1 and 0.9 with 4 points per element",
            case.time.courant,
            0.9 / case.time.courant
        ));
    }
    out
}

/// Free bytes on the file system holding `dir` (or its nearest existing ancestor), with that
/// folder; `None` where it cannot be told.
fn free_space(dir: &Path) -> Option<(std::path::PathBuf, u64)> {
    let mut at = if dir.is_absolute() {
        dir.to_path_buf()
    } else {
        std::env::current_dir().ok()?.join(dir)
    };
    while !at.exists() {
        at = at.parent()?.to_path_buf();
    }
    fs4::available_space(&at).ok().map(|b| (at, b))
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "  material points: {}{}",
            units::count(self.points as f64),
            if self.two_phase { " (two-phase)" } else { "" }
        )?;
        writeln!(
            f,
            "  time step: {} (critical); about {} steps to {}{}",
            units::duration(self.dt),
            units::count(self.steps),
            units::duration(self.end_time),
            if self.runs == 2 {
                ", twice: the job's run and its workshop twin from rest"
            } else {
                ""
            }
        )?;
        writeln!(
            f,
            "  outputs: {} ({} probes), about {} on disk",
            units::count(self.outputs as f64),
            self.probes,
            units::bytes(self.output_bytes)
        )?;
        writeln!(
            f,
            "  memory: about {} in {}",
            units::bytes(self.memory_bytes),
            self.precision.name()
        )?;
        if let Some(m) = &self.mesh_limits {
            writeln!(f, "{m}")?;
        }
        match self.calibration {
            Some(c) => write!(
                f,
                "  wall time: about {} on {} thread(s) in {} for the steps (measured here: {} \
                 steps of this case at {} each, {}), plus writing the outputs",
                units::duration(self.wall_seconds),
                self.threads,
                self.precision.name(),
                c.steps,
                units::duration(c.per_step()),
                units::rate_of(self.rate(), "point-steps")
            ),
            None => write!(
                f,
                "  wall time: roughly {} on {} thread(s) in {} (at about {}, the benchmarks' \
                 rate)",
                units::duration(self.wall_seconds),
                self.threads,
                self.precision.name(),
                units::rate_of(self.rate(), "point-steps")
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::case::MaterialSpec;
    use crate::step::contact::{ContactSpec, InterfaceRule};
    use mpm_shared::generate::box_mesh;
    use mpm_shared::ElementType;

    /// A box of 2 × 2 × 2 cubes of 0.5 m, each split into six tetrahedra, all of material 1.
    fn case() -> Case {
        let model = box_mesh([2, 2, 2], [1.0, 1.0, 1.0], ElementType::Tet4);
        let material = MaterialSpec::new("pile", 2000.0, 1e4, 0.3).unwrap();
        let fixed = vec![[false; 3]; model.node_count()];
        Case::single_material("box", model, material, 1, fixed)
    }

    #[test]
    fn contact_on_a_fixed_mesh_reports_the_structures_smallest_cell() {
        let mut c = case();
        assert_eq!(
            plan(&c, 1).unwrap().mesh_limits,
            None,
            "no contact, no limit"
        );
        c.boundary.contact = Some(ContactSpec {
            material: 1,
            listed: vec![0],
            interfaces: vec![(0.0, 0.0); 2],
            rule: InterfaceRule::Tributary,
            rigid: false,
        });
        let p = plan(&c, 1).unwrap();
        let Some(MeshLimits::Fixed { cell }) = p.mesh_limits.clone() else {
            panic!("{:?}", p.mesh_limits);
        };
        // The smallest altitude of a cube's sixth tetrahedron is below its side and above a
        // third of it.
        assert!(cell > 0.5 / 3.0 && cell < 0.5, "{cell}");
        assert!(
            p.to_string()
                .contains("mesh limits: contact on a fixed mesh"),
            "{p}"
        );
    }

    #[test]
    fn a_moving_mesh_reports_the_travel_into_each_box() {
        let limits = MeshLimits::Moving {
            axis: 1,
            courant: 0.4,
            boxes: vec![([0.0, 7.0], 4.2), ([14.5, 15.0], 0.3)],
        };
        let text = limits.to_string();
        assert!(
            text.contains(
                "4.200 m into the box from y = 0.0 to 7.0 m; or 0.300 m into the box from y = 14.5 to 15.0 m"
            ),
            "{text}"
        );
        assert!(text.contains("shrink to 0.4 of their length"), "{text}");
    }
}
