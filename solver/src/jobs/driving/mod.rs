//! The pile-driving report: for a run whose hammer blows (`[[traction]] hammer`) load a
//! structure in contact with the soil (`[[contact]]`), what a driving record holds, per blow
//! and along each blow.
//!
//! Per blow (`driving.csv`, one row at the end of each blow's interval): the tip's depth below
//! the initial ground, the blow's permanent set and the blow count per metre, the peaks of the
//! head force and velocity, the energy the hammer gave the pile, the peaks of the base and
//! shaft resistance, the excess pore pressure at the tip (peak, and left at the blow's end),
//! and the soil plug inside an open-ended pile (its length and the blow's incremental filling
//! ratio). Along each blow (`blows/blow_NNN.csv`): the head force and velocity, the pile's
//! penetration, the base and shaft resistance and the tip's excess pore pressure, as means over
//! [`TRACE_INTERVAL`]. `driving.png` draws the set and the resistances against depth and the
//! head traces of the first and the last blow.
//!
//! Forces are the whole pile's: an axisymmetric section's per-radian forces are multiplied by
//! 2π (a 3D model's are the model's own, e.g. a quarter of the pile's). Downward is −y.

mod plot;

use std::path::{Path, PathBuf};

use crate::driver::engine::Engine;
use crate::driver::run::{Observer, RunError};
use crate::element::Element;
use crate::input::case::Case;
use crate::parallel::exact::ExactSum;
use crate::real::Real;
use crate::step::contact::{CONTACT_BASE_SET, CONTACT_SET};
use crate::step::load_curve::LoadCurve;
use mpm_shared::text::real_to_string;

/// The length of a trace row (s): the traces are means over windows of this length (or of
/// one step, when the step is longer), about a pile-driving analyser's sampling rate.
pub const TRACE_INTERVAL: f64 = 1e-4;

/// The columns of a blow's trace file.
pub const TRACE_HEADER: &str =
    "time,head_force,head_velocity,penetration,base_resistance,shaft_resistance,tip_excess_pore_pressure";

/// The columns of `driving.csv`.
pub const BLOW_HEADER: &str = "blow,time,tip_depth,set,blows_per_metre,max_head_force,\
max_head_velocity,energy,max_base_resistance,max_shaft_resistance,\
max_tip_excess_pore_pressure,tip_excess_pore_pressure_at_end,plug_length,incremental_filling_ratio";

/// One row of a blow's trace: means over one [`TRACE_INTERVAL`] (forces, velocity) or the
/// state at its end (penetration, pore pressure).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Seconds since the blow struck, at the row's end.
    pub time: f64,
    /// The hammer's force on the pile head (kN, pushing down).
    pub head_force: f64,
    /// The pile head's velocity (m/s, down positive): the structure's mass-weighted nodal
    /// velocity over the loaded head's nodes.
    pub head_velocity: f64,
    /// The pile's downward displacement since the run's start (m; the mean of its points').
    pub penetration: f64,
    /// The soil's upward push on the pile's downward-facing interface (kN).
    pub base: f64,
    /// The rest of the soil's upward push on the pile: its shaft, outside and inside (kN).
    pub shaft: f64,
    /// The mean excess pore pressure (kPa, compression positive) of the soil's points around
    /// the tip; NaN in dry soil.
    pub tip_excess: f64,
}

impl TraceRow {
    fn values(&self) -> [f64; 7] {
        [
            self.time,
            self.head_force,
            self.head_velocity,
            self.penetration,
            self.base,
            self.shaft,
            self.tip_excess,
        ]
    }

    fn from_values(v: &[f64]) -> Self {
        TraceRow {
            time: v[0],
            head_force: v[1],
            head_velocity: v[2],
            penetration: v[3],
            base: v[4],
            shaft: v[5],
            tip_excess: v[6],
        }
    }
}

/// One blow of `driving.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowRecord {
    /// The blow's number (1-based).
    pub blow: u32,
    /// The time at its end (s).
    pub time: f64,
    /// The tip's depth below the initial ground at its end (m).
    pub tip_depth: f64,
    /// The blow's permanent set (m): the penetration it added.
    pub set: f64,
    /// The hammer's peak force on the head (kN).
    pub max_head_force: f64,
    /// The head's peak downward velocity (m/s).
    pub max_head_velocity: f64,
    /// The energy the hammer gave the pile, ∫ F v dt (kJ).
    pub energy: f64,
    /// Peak base resistance (kN).
    pub max_base: f64,
    /// Peak shaft resistance (kN).
    pub max_shaft: f64,
    /// Peak excess pore pressure at the tip (kPa; NaN in dry soil).
    pub max_tip_excess: f64,
    /// Excess pore pressure at the tip at the blow's end (kPa; NaN in dry soil).
    pub end_tip_excess: f64,
    /// The soil plug's length inside an open-ended pile at the blow's end: from the tip to the
    /// highest soil point inside its wall (m; NaN for a solid pile or outside axisymmetry).
    pub plug_length: f64,
    /// The plug's growth over the blow's set (1: the pile cores, 0: it is plugged).
    pub ifr: f64,
}

impl BlowRecord {
    fn values(&self) -> [f64; 13] {
        [
            f64::from(self.blow),
            self.time,
            self.tip_depth,
            self.set,
            self.max_head_force,
            self.max_head_velocity,
            self.energy,
            self.max_base,
            self.max_shaft,
            self.max_tip_excess,
            self.end_tip_excess,
            self.plug_length,
            self.ifr,
        ]
    }

    fn from_values(v: &[f64]) -> Self {
        BlowRecord {
            blow: v[0] as u32,
            time: v[1],
            tip_depth: v[2],
            set: v[3],
            max_head_force: v[4],
            max_head_velocity: v[5],
            energy: v[6],
            max_base: v[7],
            max_shaft: v[8],
            max_tip_excess: v[9],
            end_tip_excess: v[10],
            plug_length: v[11],
            ifr: v[12],
        }
    }

    /// Blows per metre of penetration at this blow's set (NaN when the pile did not go down).
    pub fn blows_per_metre(&self) -> f64 {
        if self.set > 0.0 {
            1.0 / self.set
        } else {
            f64::NAN
        }
    }
}

/// The pile and the ground as the case places them, before any step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// The structure's material index.
    pub material: u32,
    /// The highest node of the soil's filled elements (m): the initial ground.
    pub ground: f64,
    /// The lowest node of the structure's elements (m): the initial tip.
    pub tip: f64,
    /// The structure's horizontal extent, x then z: ([min, max], [min, max]).
    pub extent: ([f64; 2], [f64; 2]),
    /// The structure's cell size (m): the side of a square or cube of its elements' mean
    /// size; the band around the tip whose pore pressure is reported reaches this far.
    pub cell: f64,
    /// The inner radius of an open-ended pile in an axisymmetric section (its innermost node
    /// off the axis).
    pub inner: Option<f64>,
    /// What multiplies the run's forces into the whole pile's (2π in an axisymmetric section).
    pub ring: f64,
}

impl Geometry {
    /// The geometry of `case`'s structure of material `material`.
    pub fn of(case: &Case, material: u32) -> Self {
        let model = &case.model;
        let dim = model.dimension.coords();
        let corners = model.element_type.corners();
        let (mut ground, mut tip) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut x, mut z) = ([f64::INFINITY, f64::NEG_INFINITY], [0.0f64; 2]);
        let (mut size, mut count) = (0.0, 0usize);
        if dim == 3 {
            z = [f64::INFINITY, f64::NEG_INFINITY];
        }
        for e in 0..model.element_count() {
            let filled = case.body.points_per_element[e] > 0;
            let nodes = &model.element(e)[..corners];
            if case.body.element_material[e] != material {
                if filled {
                    for &n in nodes {
                        ground = ground.max(model.node(n as usize)[1]);
                    }
                }
                continue;
            }
            for &n in nodes {
                let c = model.node(n as usize);
                tip = tip.min(c[1]);
                x = [x[0].min(c[0]), x[1].max(c[0])];
                if dim == 3 {
                    z = [z[0].min(c[2]), z[1].max(c[2])];
                }
            }
            size += element_size(nodes.iter().map(|&n| model.node(n as usize)), dim);
            count += 1;
        }
        let axisymmetric = model.dimension == mpm_shared::Dimension::Axisymmetric;
        let cell = size / count.max(1) as f64;
        Geometry {
            material,
            ground,
            tip,
            extent: (x, z),
            cell,
            inner: (axisymmetric && x[0] > 1e-6 * cell).then_some(x[0]),
            ring: if axisymmetric {
                2.0 * std::f64::consts::PI
            } else {
                1.0
            },
        }
    }
}

/// An element's size: the side of the right triangle (2D) or the cube's sixth (3D) of its area
/// or volume, so that a square or cube split into simplices gives its side.
fn element_size<'a>(corners: impl Iterator<Item = &'a [f64]>, dim: usize) -> f64 {
    let c: Vec<[f64; 3]> = corners
        .map(|p| [p[0], p[1], if dim == 3 { p[2] } else { 0.0 }])
        .collect();
    let d = |i: usize| [0, 1, 2].map(|k| c[i][k] - c[0][k]);
    if dim == 2 || c.len() < 4 {
        let (a, b) = (d(1), d(2));
        (a[0] * b[1] - a[1] * b[0]).abs().sqrt()
    } else {
        let (a, b, e) = (d(1), d(2), d(3));
        let det = a[0] * (b[1] * e[2] - b[2] * e[1]) - a[1] * (b[0] * e[2] - b[2] * e[0])
            + a[2] * (b[0] * e[1] - b[1] * e[0]);
        det.abs().cbrt()
    }
}

/// The blows' schedule: one every `interval` seconds from t = `first`, `count` of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// The time of the first blow (s).
    pub first: f64,
    /// Seconds between blows.
    pub interval: f64,
    /// Number of blows.
    pub count: u32,
}

/// The sums of the trace row being formed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Window {
    /// Seconds summed.
    time: f64,
    /// ∫ dt of head force, head velocity, base and shaft.
    sums: [f64; 4],
}

/// What a blow keeps while it goes on.
#[derive(Debug, Clone, Default, PartialEq)]
struct Going {
    /// The blow (0-based).
    index: u32,
    /// The row being formed.
    window: Window,
    /// The blow's rows so far.
    rows: Vec<TraceRow>,
    /// ∫ F v dt so far (kJ).
    energy: f64,
    /// The penetration and plug length at the blow's start.
    start: [f64; 2],
}

/// The pile-driving report of a run, an [`Observer`] that writes its files into the run's
/// output folder as each blow ends.
pub struct Report {
    dir: PathBuf,
    name: String,
    geometry: Geometry,
    schedule: Schedule,
    /// The head's computational nodes (those the hammer loads).
    head: Vec<u32>,
    /// The hammer's force at multiplier 1 (kN, whole pile, down positive).
    head_load: f64,
    /// The multiplier of the face loads.
    curve: LoadCurve,
    /// Indices of the contact's reaction sets (the whole push, the base's part).
    sets: Option<(usize, usize)>,
    /// Each point's initial pore pressure, by id (empty in dry runs).
    pore0: Vec<f64>,
    going: Going,
    /// The first blow's rows, drawn beside the last one's.
    first: Vec<TraceRow>,
    /// The blows done.
    pub blows: Vec<BlowRecord>,
    /// The first file that could not be written.
    failed: Option<mpm_shared::Error>,
}

impl Report {
    /// The report of `case` writing into `dir`, when the case's face loads are hammer blows
    /// that load a structure in contact with the soil; `None` otherwise.
    pub fn of(case: &Case, dir: &Path) -> Option<Self> {
        let contact = case.boundary.contact.as_ref()?;
        let LoadCurve::Blows {
            first,
            interval,
            count,
            ..
        } = case.loads.traction_curve
        else {
            return None;
        };
        if case.loads.structure_traction.iter().all(|f| *f == [0.0; 3]) {
            return None;
        }
        Some(Report {
            dir: dir.to_path_buf(),
            name: case.name.clone(),
            geometry: Geometry::of(case, contact.material),
            schedule: Schedule {
                first,
                interval,
                count,
            },
            head: Vec::new(),
            head_load: 0.0,
            curve: case.loads.traction_curve.clone(),
            sets: None,
            pore0: Vec::new(),
            going: Going::default(),
            first: Vec::new(),
            blows: Vec::new(),
            failed: None,
        })
    }

    /// The first error met writing the report's files, if any (the run goes on without
    /// them).
    pub fn take_error(&mut self) -> Option<mpm_shared::Error> {
        self.failed.take()
    }

    /// The geometry the report measures against.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The pile's penetration (m down, the mean of its points' displacements) and the mean
    /// excess pore pressure of the soil's points around the tip (kPa, NaN in dry soil).
    fn penetration_and_tip<R: Real, E: Element>(&self, engine: &Engine<R, E>) -> (f64, f64) {
        let p = &engine.particles;
        let g = &self.geometry;
        let mut down = ExactSum::default();
        let mut n = 0u64;
        for i in 0..p.len() {
            if p.active[i] && p.material[i] == g.material {
                down.add(-p.u[i][1].f64());
                n += 1;
            }
        }
        let penetration = down.value() / n.max(1) as f64;
        let Some(liquid) = &p.liquid else {
            return (penetration, f64::NAN);
        };
        let tip = g.tip - penetration;
        let b = g.cell;
        let (x, z) = g.extent;
        let mut excess = ExactSum::default();
        let mut m = 0u64;
        for i in 0..p.len() {
            let c = p.x[i].map(|v| v.f64());
            let inside = (c[1] - tip).abs() <= b
                && c[0] >= x[0] - b
                && c[0] <= x[1] + b
                && c[2] >= z[0] - b
                && c[2] <= z[1] + b;
            if !inside || !p.active[i] || p.material[i] == g.material {
                continue;
            }
            let Some(&p0) = self.pore0.get(p.id[i] as usize) else {
                continue;
            };
            if p0.is_nan() {
                continue;
            }
            // Compression is negative in the points' pore pressure.
            excess.add(p0 - liquid.p[i].f64());
            m += 1;
        }
        let tip_excess = if m > 0 {
            excess.value() / m as f64
        } else {
            f64::NAN
        };
        (penetration, tip_excess)
    }

    /// The plug's length: from the tip (after `penetration`) to the highest soil point inside
    /// the pile's wall (NaN for a solid pile, or with no soil inside).
    fn plug_length<R: Real, E: Element>(&self, engine: &Engine<R, E>, penetration: f64) -> f64 {
        let Some(inner) = self.geometry.inner else {
            return f64::NAN;
        };
        let p = &engine.particles;
        let top = (0..p.len())
            .filter(|&i| p.active[i] && p.material[i] != self.geometry.material)
            .filter(|&i| p.x[i][0].f64() < inner)
            .map(|i| p.x[i][1].f64())
            .fold(f64::NEG_INFINITY, f64::max);
        if top.is_finite() {
            top - (self.geometry.tip - penetration)
        } else {
            f64::NAN
        }
    }

    /// The head's velocity (down positive): the structure's momentum over its mass at the head's
    /// nodes.
    fn head_velocity<R: Real, E: Element>(&self, engine: &Engine<R, E>) -> f64 {
        let Some(s) = &engine.structure else {
            return f64::NAN;
        };
        let (mut p, mut m) = (0.0, 0.0);
        for &n in &self.head {
            let n = n as usize;
            p += s.grid.mass[n].f64() * s.grid.vel[n][1].f64();
            m += s.grid.mass[n].f64();
        }
        if m > 0.0 {
            -p / m
        } else {
            f64::NAN
        }
    }

    /// Seconds since the blow going on struck, at `time`.
    fn since_struck(&self, time: f64) -> f64 {
        time - self.schedule.first - f64::from(self.going.index) * self.schedule.interval
    }

    /// Closes the trace row being formed, at `time` since the blow struck.
    fn close_row<R: Real, E: Element>(&mut self, engine: &Engine<R, E>, time: f64) {
        let w = self.going.window;
        if w.time <= 0.0 {
            return;
        }
        let (penetration, tip_excess) = self.penetration_and_tip(engine);
        let mean = w.sums.map(|s| s / w.time);
        self.going.rows.push(TraceRow {
            time,
            head_force: mean[0],
            head_velocity: mean[1],
            penetration,
            base: mean[2],
            shaft: mean[3],
            tip_excess,
        });
        self.going.window = Window::default();
    }

    /// Ends the blow going on: its record, its trace file, `driving.csv` and the figure.
    fn close_blow<R: Real, E: Element>(&mut self, engine: &Engine<R, E>) {
        let since = self.since_struck(engine.time);
        self.close_row(engine, since);
        let Some(last) = self.going.rows.last().copied() else {
            return;
        };
        let plug = self.plug_length(engine, last.penetration);
        let [pen0, plug0] = self.going.start;
        let set = last.penetration - pen0;
        let peak = |f: fn(&TraceRow) -> f64| {
            self.going
                .rows
                .iter()
                .map(f)
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let record = BlowRecord {
            blow: self.going.index + 1,
            time: engine.time,
            tip_depth: self.geometry.ground - (self.geometry.tip - last.penetration),
            set,
            max_head_force: peak(|r| r.head_force),
            max_head_velocity: peak(|r| r.head_velocity),
            energy: self.going.energy,
            max_base: peak(|r| r.base),
            max_shaft: peak(|r| r.shaft),
            max_tip_excess: if last.tip_excess.is_nan() {
                f64::NAN
            } else {
                peak(|r| r.tip_excess)
            },
            end_tip_excess: last.tip_excess,
            plug_length: plug,
            ifr: if set != 0.0 {
                (plug - plug0) / set
            } else {
                f64::NAN
            },
        };
        let rows = std::mem::take(&mut self.going.rows);
        if self.going.index == 0 {
            self.first = rows.clone();
        }
        self.blows.push(record);
        let written = self.write_blow(record.blow, &rows);
        if let (Err(e), None) = (written, &self.failed) {
            self.failed = Some(e);
        }
        self.going = Going {
            index: self.going.index + 1,
            start: [last.penetration, plug],
            ..Going::default()
        };
    }

    /// Writes blow `blow`'s trace file (`rows`), `driving.csv` and `driving.png` (the first
    /// blow's traces beside `rows`), each whole.
    fn write_blow(&self, blow: u32, rows: &[TraceRow]) -> mpm_shared::Result<()> {
        let folder = self.dir.join("blows");
        std::fs::create_dir_all(&folder).map_err(|e| mpm_shared::Error::io(&folder, e))?;
        let mut trace = format!("{TRACE_HEADER}\n");
        for r in rows {
            csv_row(&mut trace, &r.values());
        }
        mpm_shared::io::write_output(
            &folder.join(format!("blow_{blow:03}.csv")),
            trace.as_bytes(),
        )?;
        mpm_shared::io::write_output(&self.dir.join("driving.csv"), self.csv().as_bytes())?;
        plot::write(
            &self.dir.join("driving.png"),
            &self.name,
            &self.blows,
            (&self.first, rows),
            self.geometry.ring != 1.0,
        )
    }

    /// `driving.csv`: a row per blow done.
    pub fn csv(&self) -> String {
        let mut s = format!("{BLOW_HEADER}\n");
        for b in &self.blows {
            let v = b.values();
            let mut row = v[1..].to_vec();
            row.insert(3, b.blows_per_metre());
            s.push_str(&b.blow.to_string());
            s.push(',');
            csv_row(&mut s, &row);
        }
        s
    }
}

/// One CSV row of `values` and its line break, NaN written as an empty field.
fn csv_row(s: &mut String, values: &[f64]) {
    for (k, v) in values.iter().enumerate() {
        if k > 0 {
            s.push(',');
        }
        if !v.is_nan() {
            s.push_str(&real_to_string(*v));
        }
    }
    s.push('\n');
}

impl<R: Real, E: Element> Observer<R, E> for Report {
    fn on_start(&mut self, engine: &Engine<R, E>) -> Result<(), RunError> {
        if let Some(s) = &engine.structure {
            self.head = (0..s.traction.len() as u32)
                .filter(|&n| s.traction[n as usize] != [R::ZERO; 3])
                .collect();
            let mut load = ExactSum::default();
            for &n in &self.head {
                load.add(-s.traction[n as usize][1].f64());
            }
            self.head_load = load.value() * self.geometry.ring;
        }
        let set = |name: &str| engine.reactions.iter().position(|r| r.name == name);
        self.sets = set(CONTACT_SET).zip(set(CONTACT_BASE_SET));
        let p = &engine.particles;
        if let Some(liquid) = &p.liquid {
            let top = p.id.iter().copied().max().map_or(0, |m| m as usize + 1);
            self.pore0 = vec![f64::NAN; top];
            for i in 0..p.len() {
                self.pore0[p.id[i] as usize] = liquid.p[i].f64();
            }
        }
        let (penetration, _) = self.penetration_and_tip(engine);
        self.going.start = [penetration, self.plug_length(engine, penetration)];
        Ok(())
    }

    fn on_step(&mut self, engine: &Engine<R, E>) {
        // Before the first blow the pile settles; the first blow's set is counted from the
        // penetration at its start, taken in the last step before it (not in every step).
        if engine.time <= self.schedule.first {
            if engine.time + engine.dt > self.schedule.first {
                let (penetration, _) = self.penetration_and_tip(engine);
                self.going.start = [penetration, self.plug_length(engine, penetration)];
            }
            return;
        }
        if self.going.index >= self.schedule.count {
            return;
        }
        let dt = engine.dt;
        let force = self.curve.at(engine.time) * self.head_load;
        let velocity = self.head_velocity(engine);
        let (base, shaft) = self.sets.map_or((f64::NAN, f64::NAN), |(all, base)| {
            let ring = self.geometry.ring;
            let b = engine.reactions[base].force[1] * ring;
            (b, engine.reactions[all].force[1] * ring - b)
        });
        let w = &mut self.going.window;
        w.time += dt;
        for (s, v) in w.sums.iter_mut().zip([force, velocity, base, shaft]) {
            *s += v * dt;
        }
        self.going.energy += force * velocity * dt;
        let since = self.since_struck(engine.time);
        if since >= self.schedule.interval * (1.0 - 1e-9) {
            self.close_blow(engine);
        } else if self.going.window.time >= TRACE_INTERVAL * (1.0 - 1e-9) {
            self.close_row(engine, since);
        }
    }

    /// The report's state: the blows done, the first blow's rows and the one going on, as f64
    /// bits.
    fn save(&self) -> Vec<u8> {
        let g = &self.going;
        let mut v: Vec<f64> = vec![f64::from(g.index), g.window.time];
        v.extend(g.window.sums);
        v.extend([g.energy, g.start[0], g.start[1]]);
        v.push(self.blows.len() as f64);
        v.extend(self.blows.iter().flat_map(|b| b.values()));
        for rows in [&self.first, &g.rows] {
            v.push(rows.len() as f64);
            v.extend(rows.iter().flat_map(|r| r.values()));
        }
        crate::jobs::state_bytes(&v)
    }

    fn restore(&mut self, state: &[u8]) -> Result<(), String> {
        let v = crate::jobs::state_values(state, "a driving report")?;
        let short = || "a driving report cut short".to_string();
        let head = v.get(..9).ok_or_else(short)?;
        let mut at = 9;
        let mut take = |per: usize| -> Result<Vec<f64>, String> {
            let n = *v.get(at).ok_or_else(short)?;
            let end = at + 1 + n as usize * per;
            if n < 0.0 || n.fract() != 0.0 || end > v.len() {
                return Err(short());
            }
            let out = v[at + 1..end].to_vec();
            at = end;
            Ok(out)
        };
        let blows = take(13)?;
        let first = take(7)?;
        let rows = take(7)?;
        if at != v.len() {
            return Err("a driving report longer than announced".into());
        }
        self.going = Going {
            index: head[0] as u32,
            window: Window {
                time: head[1],
                sums: [head[2], head[3], head[4], head[5]],
            },
            rows: rows.chunks_exact(7).map(TraceRow::from_values).collect(),
            energy: head[6],
            start: [head[7], head[8]],
        };
        self.blows = blows
            .chunks_exact(13)
            .map(BlowRecord::from_values)
            .collect();
        self.first = first.chunks_exact(7).map(TraceRow::from_values).collect();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_or_a_cube_split_into_simplices_has_its_side_as_size() {
        let h = 0.25;
        let tri = [[0.0, 0.0], [h, 0.0], [h, h]];
        assert!((element_size(tri.iter().map(|c| &c[..]), 2) - h).abs() < 1e-15);
        let tet = [[0.0, 0.0, 0.0], [h, 0.0, 0.0], [h, h, 0.0], [h, h, h]];
        assert!((element_size(tet.iter().map(|c| &c[..]), 3) - h).abs() < 1e-15);
    }

    #[test]
    fn a_blow_that_does_not_drive_has_no_blow_count() {
        let b = BlowRecord::from_values(&[
            3.0, 0.3, 2.0, 0.004, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ]);
        assert_eq!(b.blows_per_metre(), 250.0);
        assert!(BlowRecord { set: -1e-4, ..b }.blows_per_metre().is_nan());
        assert_eq!(BlowRecord::from_values(&b.values()), b);
    }

    /// A report with some state of its own, as a run would leave it.
    fn report() -> Report {
        let row = |t: f64| TraceRow::from_values(&[t, 10.0 * t, 0.5, 0.01, 3.0, 1.0, f64::NAN]);
        Report {
            dir: PathBuf::from("out"),
            name: "pile".into(),
            geometry: Geometry {
                material: 2,
                ground: 10.0,
                tip: 8.0,
                extent: ([0.75, 1.0], [0.0, 0.0]),
                cell: 0.25,
                inner: Some(0.75),
                ring: 2.0 * std::f64::consts::PI,
            },
            schedule: Schedule {
                first: 0.1,
                interval: 0.1,
                count: 10,
            },
            head: vec![3, 4],
            head_load: 100.0,
            curve: LoadCurve::Step,
            sets: Some((1, 2)),
            pore0: Vec::new(),
            going: Going {
                index: 2,
                window: Window {
                    time: 2e-5,
                    sums: [1.0, 2.0, 3.0, 4.0],
                },
                rows: vec![row(1e-4), row(2e-4)],
                energy: 5.5,
                start: [0.02, 1.97],
            },
            first: vec![row(1e-4)],
            blows: vec![BlowRecord::from_values(&[1.0; 13]); 2],
            failed: None,
        }
    }

    #[test]
    fn the_report_goes_through_a_checkpoint_whole() {
        use crate::driver::run::Observer;
        type O = dyn Observer<f64, crate::element::tet4::Tet4>;
        let a = report();
        let state = <Report as Observer<f64>>::save(&a);
        let mut b = report();
        b.going = Going::default();
        b.first.clear();
        b.blows.clear();
        (&mut b as &mut O).restore(&state).unwrap();
        assert_eq!(b.going.rows.len(), 2);
        // NaN fields compare through their bits.
        assert_eq!(<Report as Observer<f64>>::save(&b), state);
        assert_eq!(
            (b.going.index, b.going.energy, b.going.start),
            (2, 5.5, [0.02, 1.97])
        );
        assert_eq!(b.blows, a.blows);
        assert!((&mut b as &mut O)
            .restore(&state[..state.len() - 8])
            .is_err());
        assert!((&mut b as &mut O)
            .restore(&state[..state.len() - 3])
            .is_err());
        assert!((&mut b as &mut O)
            .restore(&[state.clone(), vec![0; 8]].concat())
            .is_err());
    }
}
