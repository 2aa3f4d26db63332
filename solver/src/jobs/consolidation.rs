//! One-dimensional consolidation runs (an oedometer of saturated soil under a top load, drained
//! at the top) compared with Terzaghi: the undrained start, the per-output record (time factor,
//! settlement, pore-pressure errors) and the `consolidation.csv` / `consolidation.png` report.

use std::path::Path;

use crate::driver::engine::Engine;
use crate::driver::run::{run_with, Both, RunError, RunOptions, Unobserved};
use crate::element::Element;
use crate::input::case::Case;
use crate::jobs::plot::{chart, font, legend, Panel, Words};
use crate::jobs::terzaghi;
use crate::material::liquid::LiquidSpec;
use crate::real::Real;

pub use crate::input::case::{ConsolidationSpec, Start};

/// The layer and material constants the comparison needs.
#[derive(Debug, Clone, Copy)]
pub struct Layer {
    /// Drained top (y) and bottom of the layer.
    pub top: f64,
    /// Height H.
    pub height: f64,
    /// Plan area (m²).
    pub area: f64,
    /// Oedometric modulus.
    pub e_oed: f64,
    /// K_w / n.
    pub kw_over_n: f64,
    /// Consolidation coefficient c_v.
    pub cv: f64,
    /// Initial excess pore pressure u0 = q (K_w/n) / (E_oed + K_w/n).
    pub u0: f64,
    /// Load.
    pub load: f64,
}

/// Why a case is not a consolidation problem.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LayerError {
    /// No `[consolidation]` table.
    #[error("the case has no [consolidation] table")]
    NoTable,
    /// Not exactly one saturated material.
    #[error("a consolidation run needs exactly one saturated material; the case has {0}")]
    SaturatedMaterials(usize),
}

impl Layer {
    /// The layer of `case` (its one saturated material) under `spec`.
    pub fn of(case: &Case, spec: &ConsolidationSpec) -> Result<Self, LayerError> {
        let sat: Vec<_> = case
            .body
            .materials
            .iter()
            .flatten()
            .filter(|m| m.liquid.is_some())
            .collect();
        let [m] = sat.as_slice() else {
            return Err(LayerError::SaturatedMaterials(sat.len()));
        };
        let l: &LiquidSpec = m.liquid.as_ref().expect("saturated");
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        for p in case
            .model
            .coords
            .chunks_exact(case.model.dimension.coords())
        {
            lo = lo.min(p[1]);
            hi = hi.max(p[1]);
        }
        let height = hi - lo;
        let volume: f64 = (0..case.model.element_count())
            .filter(|&e| case.body.element_material[e] != 0)
            .map(|e| element_volume(&case.model, e))
            .sum();
        let e_oed = m.oedometric();
        let kw_over_n = l.bulk_modulus / l.porosity;
        Ok(Layer {
            top: hi,
            height,
            area: volume / height,
            e_oed,
            kw_over_n,
            cv: l.consolidation_coefficient(e_oed),
            u0: spec.load * kw_over_n / (e_oed + kw_over_n),
            load: spec.load,
        })
    }

    /// Time factor at time `t`.
    pub fn tv(&self, t: f64) -> f64 {
        self.cv * t / (self.height * self.height)
    }

    /// Time at time factor `tv`.
    pub fn time(&self, tv: f64) -> f64 {
        tv * self.height * self.height / self.cv
    }

    /// Vertical strain of the undrained 1D compression under the load.
    pub fn undrained_strain(&self) -> f64 {
        -self.load / (self.e_oed + self.kw_over_n)
    }

    /// Terzaghi's settlement: the undrained part at once, the rest by the degree of
    /// consolidation.
    pub fn settlement(&self, tv: f64) -> f64 {
        let immediate = self.load * self.height / (self.e_oed + self.kw_over_n);
        let last = self.load * self.height / self.e_oed;
        immediate + (last - immediate) * terzaghi::degree(tv)
    }
}

/// Volume of element `e` as the points measure theirs: a tetrahedron's, a triangle's area (per
/// unit thickness in plane strain), or its area times its centroid's radius (per radian in an
/// axisymmetric section).
fn element_volume(model: &mpm_shared::Model, e: usize) -> f64 {
    let c = model.element(e);
    if model.dimension.coords() == 2 {
        let p: Vec<&[f64]> = c[..3].iter().map(|&n| model.node(n as usize)).collect();
        let area = 0.5
            * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
                - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
                .abs();
        return match model.dimension {
            mpm_shared::Dimension::Axisymmetric => area * (p[0][0] + p[1][0] + p[2][0]) / 3.0,
            _ => area,
        };
    }
    let p: Vec<&[f64]> = c[..4].iter().map(|&n| model.node(n as usize)).collect();
    let d = |a: usize| [p[a][0] - p[0][0], p[a][1] - p[0][1], p[a][2] - p[0][2]];
    let (a, b, c) = (d(1), d(2), d(3));
    (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]))
        .abs()
        / 6.0
}

/// One output time of a consolidation run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// Time (s).
    pub time: f64,
    /// Time factor.
    pub tv: f64,
    /// Settlement of the top (m): the skeleton's volume loss over the plan area, plus the
    /// undrained start's strain when the run began there.
    pub settlement: f64,
    /// Terzaghi's settlement.
    pub terzaghi: f64,
    /// RMS over saturated points of (excess pore pressure - Terzaghi) / u0.
    pub rms: f64,
    /// Largest |excess pore pressure - Terzaghi| / u0.
    pub max: f64,
}

/// Collects a run's records.
#[derive(Debug, Clone)]
pub struct Tracker {
    /// The layer.
    pub layer: Layer,
    /// Settlement already present at the start (undrained start).
    pub offset: f64,
    /// Initial total volume of the saturated points.
    pub volume0: f64,
    /// Records, one per output.
    pub records: Vec<Record>,
    /// Pore-pressure profiles (relative depth, excess pressure / u0 per point) at the
    /// isochrone time factors [`ISOCHRONES`].
    pub profiles: Vec<(f64, Vec<(f64, f64)>)>,
}

/// Time factors of the plotted isochrones.
pub const ISOCHRONES: [f64; 5] = [0.05, 0.1, 0.2, 0.5, 1.0];

impl Tracker {
    /// Starts tracking `engine` (call after any initial state is applied).
    pub fn new<R: Real, E: Element>(engine: &Engine<R, E>, layer: Layer, start: Start) -> Self {
        let p = &engine.particles;
        let volume0 = (0..p.len())
            .filter(|&i| engine.fluids[p.material[i] as usize].is_some())
            .map(|i| p.volume[i].f64())
            .sum();
        let offset = match start {
            Start::Rest => 0.0,
            Start::Undrained => -layer.undrained_strain() * layer.height,
        };
        Tracker {
            layer,
            offset,
            volume0,
            records: Vec::new(),
            profiles: Vec::new(),
        }
    }

    /// Records the state at the engine's current time.
    pub fn record<R: Real, E: Element>(&mut self, engine: &Engine<R, E>) {
        let l = &self.layer;
        let p = &engine.particles;
        let tv = l.tv(engine.time);
        let (mut volume, mut sum2, mut max, mut count) = (0.0, 0.0, 0.0f64, 0usize);
        let keep = ISOCHRONES.iter().any(|&x| (x - tv).abs() < 1e-6);
        let mut profile = Vec::new();
        if let Some(lp) = &p.liquid {
            for i in 0..p.len() {
                if engine.fluids[p.material[i] as usize].is_none() || !p.active[i] {
                    continue;
                }
                volume += p.volume[i].f64();
                let y = engine.mesh.global(&p.x[i])[1];
                let zeta = ((l.top - y) / l.height).clamp(0.0, 1.0);
                let want = l.u0 * terzaghi::excess_pressure(zeta, tv);
                let err = (-lp.p[i].f64() - want) / l.u0;
                if keep {
                    profile.push((zeta, -lp.p[i].f64() / l.u0));
                }
                sum2 += err * err;
                max = max.max(err.abs());
                count += 1;
            }
        }
        if keep {
            self.profiles.push((tv, profile));
        }
        self.records.push(Record {
            time: engine.time,
            tv,
            settlement: self.offset + (self.volume0 - volume) / l.area,
            terzaghi: l.settlement(tv),
            rms: (sum2 / count.max(1) as f64).sqrt(),
            max,
        });
    }
}

/// The text of `consolidation.csv`: one row per output time of the default run, with the
/// workshop-style run's figures beside them when it was made.
pub fn csv(default: &Tracker, workshop: Option<&Tracker>) -> String {
    use mpm_shared::text::real_to_string as r;
    let mut s = String::from("tv,time,settlement,terzaghi_settlement,rms_error,max_error");
    if workshop.is_some() {
        s.push_str(",workshop_settlement,workshop_rms_error,workshop_max_error");
    }
    s.push('\n');
    for (k, d) in default.records.iter().enumerate() {
        let mut cols = vec![
            r(d.tv),
            r(d.time),
            r(d.settlement),
            r(d.terzaghi),
            r(d.rms),
            r(d.max),
        ];
        if let Some(w) = workshop {
            match w.records.get(k) {
                Some(x) => cols.extend([r(x.settlement), r(x.rms), r(x.max)]),
                None => cols.extend(["".into(), "".into(), "".into()]),
            }
        }
        s.push_str(&cols.join(","));
        s.push('\n');
    }
    s
}

/// Writes `consolidation.csv` into `dir` (atomically).
pub fn write_csv(
    dir: &Path,
    default: &Tracker,
    workshop: Option<&Tracker>,
) -> mpm_shared::Result<()> {
    mpm_shared::io::write_output(
        &dir.join("consolidation.csv"),
        csv(default, workshop).as_bytes(),
    )
}

/// The consolidation comparison as an observer of the run: it takes the start state and
/// records every output time against Terzaghi.
struct Observer {
    layer: Layer,
    start: Start,
    tracker: Option<Tracker>,
}

impl<R: Real, E: Element> crate::driver::run::Observer<R, E> for Observer {
    fn on_start(&mut self, engine: &Engine<R, E>) -> Result<(), RunError> {
        self.tracker = Some(Tracker::new(engine, self.layer, self.start));
        Ok(())
    }

    fn on_output(&mut self, engine: &Engine<R, E>) {
        if let Some(t) = &mut self.tracker {
            t.record(engine);
        }
    }

    /// The records and profiles so far (the rest follows from the start state), as f64 bits.
    fn save(&self) -> Vec<u8> {
        let Some(t) = &self.tracker else {
            return Vec::new();
        };
        let mut v: Vec<f64> = vec![t.records.len() as f64];
        for r in &t.records {
            v.extend([r.time, r.tv, r.settlement, r.terzaghi, r.rms, r.max]);
        }
        v.push(t.profiles.len() as f64);
        for (tv, points) in &t.profiles {
            v.extend([*tv, points.len() as f64]);
            v.extend(points.iter().flat_map(|&(a, b)| [a, b]));
        }
        crate::jobs::state_bytes(&v)
    }

    fn restore(&mut self, state: &[u8]) -> Result<(), String> {
        let Some(t) = &mut self.tracker else {
            return Ok(());
        };
        let v = crate::jobs::state_values(state, "consolidation records")?;
        let mut it = v.into_iter();
        let count = |it: &mut std::vec::IntoIter<f64>, per: usize| {
            let n = it.next().ok_or("consolidation records cut short")?;
            if n < 0.0 || n.fract() != 0.0 || n * per as f64 > it.len() as f64 {
                return Err("a consolidation record count beyond the state".to_string());
            }
            Ok(n as usize)
        };
        let next = |it: &mut std::vec::IntoIter<f64>| it.next().unwrap_or(f64::NAN);
        let n = count(&mut it, 6)?;
        t.records = (0..n)
            .map(|_| Record {
                time: next(&mut it),
                tv: next(&mut it),
                settlement: next(&mut it),
                terzaghi: next(&mut it),
                rms: next(&mut it),
                max: next(&mut it),
            })
            .collect();
        let n = count(&mut it, 2)?;
        t.profiles.clear();
        for _ in 0..n {
            let tv = next(&mut it);
            let m = count(&mut it, 2)?;
            let points = (0..m).map(|_| (next(&mut it), next(&mut it))).collect();
            t.profiles.push((tv, points));
        }
        if it.len() != 0 {
            return Err("consolidation records longer than announced".into());
        }
        Ok(())
    }
}

/// Runs the consolidation case `case` into `dir`: its final engine and the record of every
/// output time against Terzaghi.
pub fn run_tracked<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
) -> Result<(Engine<R, E>, Tracker), RunError> {
    run_tracked_with(case, dir, options, &mut Unobserved)
}

/// [`run_tracked`], telling `watch` too (e.g. a progress reporter).
pub fn run_tracked_with<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    watch: &mut dyn crate::driver::run::Observer<R, E>,
) -> Result<(Engine<R, E>, Tracker), RunError> {
    let spec = case
        .start
        .consolidation
        .ok_or_else(|| RunError::Job(Box::new(LayerError::NoTable)))?;
    let mut observer = Observer {
        layer: Layer::of(case, &spec).map_err(|e| RunError::Job(Box::new(e)))?,
        start: spec.start,
        tracker: None,
    };
    let engine = run_with(case, dir, options, &mut Both(&mut observer, watch))?;
    let tracker = observer.tracker.expect("on_start ran");
    Ok((engine, tracker))
}

/// What a consolidation job leaves: the engine at the end, the default run's tracker and the
/// workshop twin's, when it has one.
pub type JobOutcome<R, E> = (Engine<R, E>, Tracker, Option<Tracker>);

/// Runs a consolidation case into `dir` (and, with `compare_rest`, its workshop-style twin
/// into `dir/workshop`), then writes `consolidation.csv` and `consolidation.png` into `dir`.
/// Returns the default run's engine and both records.
pub fn run_job<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
) -> Result<JobOutcome<R, E>, RunError> {
    run_job_with(case, dir, options, &mut Unobserved)
}

/// [`run_job`], telling `watch` about both runs.
pub fn run_job_with<R: Real, E: Element>(
    case: &Case,
    dir: &Path,
    options: &RunOptions,
    watch: &mut dyn crate::driver::run::Observer<R, E>,
) -> Result<JobOutcome<R, E>, RunError> {
    let spec = case
        .start
        .consolidation
        .ok_or_else(|| RunError::Job(Box::new(LayerError::NoTable)))?;
    let (engine, tracker) = run_tracked_with::<R, E>(case, dir, options, watch)?;
    let workshop = if spec.runs() == 2 {
        let mut twin = case.clone();
        twin.start.consolidation = Some(ConsolidationSpec {
            start: Start::Rest,
            compare_rest: false,
            ..spec
        });
        twin.start.initial_state = None;
        let (_, t) = run_tracked_with::<R, E>(&twin, &dir.join("workshop"), options, watch)?;
        Some(t)
    } else {
        None
    };
    write_csv(dir, &tracker, workshop.as_ref())?;
    write_png(dir, &case.name, &tracker, workshop.as_ref())?;
    Ok((engine, tracker, workshop))
}

/// Writes `consolidation.png` into `dir` (atomically): pore-pressure isochrones against
/// Terzaghi on the left (points of the default run as dots, Terzaghi as lines), settlement
/// against time on the right; `name` (the case) heads both.
pub fn write_png(
    dir: &Path,
    name: &str,
    default: &Tracker,
    workshop: Option<&Tracker>,
) -> mpm_shared::Result<()> {
    crate::jobs::plot::write_png(&dir.join("consolidation.png"), |tmp| {
        draw(tmp, name, default, workshop)
    })
}

/// Draws the figure of [`write_png`] into `path`: the isochrones on the left half, the
/// settlement on the right.
fn draw(
    path: &Path,
    name: &str,
    default: &Tracker,
    workshop: Option<&Tracker>,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let text = font().is_some();
    let root = BitMapBackend::new(path, (1400, 650)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(700);
    draw_isochrones(&left, name, default, text)?;
    draw_settlement(&right, name, default, workshop, text)?;
    root.present()?;
    Ok(())
}

/// The isochrones: excess pressure / u0 (x) against depth / H (y, 0 at the drained top), of
/// Terzaghi as lines and of `default`'s points as dots, at each of [`ISOCHRONES`].
fn draw_isochrones(
    area: &Panel,
    name: &str,
    default: &Tracker,
    text: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let colours = [RED, BLUE, GREEN, MAGENTA, BLACK];
    let words = Words {
        caption: format!("{name}: excess pore pressure against depth"),
        x: "excess pore pressure u / u0 (u0: initial excess pressure)",
        y: "depth below the drained top z / H",
    };
    let mut chart = chart(area, 0.0..1.1f64, 1.0..0.0f64, words, text)?;
    for (k, &tv) in ISOCHRONES.iter().enumerate() {
        let colour = colours[k % colours.len()];
        if let Some((_, pts)) = default.profiles.iter().find(|(t, _)| (t - tv).abs() < 1e-6) {
            chart.draw_series(
                pts.iter()
                    .map(|&(z, u)| Circle::new((u, z), 1, colour.mix(0.5).filled())),
            )?;
        }
        let line = chart.draw_series(LineSeries::new(
            (0..=200).map(|i| {
                let z = i as f64 / 200.0;
                (terzaghi::excess_pressure(z, tv), z)
            }),
            colour.stroke_width(2),
        ))?;
        if text {
            line.label(format!(
                "T_v = {tv}: Terzaghi (line), material points (dots)"
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
    }
    legend(&mut chart, SeriesLabelPosition::LowerLeft, text)
}

/// The settlement of the top against time: Terzaghi's as a line, `default`'s records as dots
/// and `workshop`'s (where given) as triangles.
fn draw_settlement(
    area: &Panel,
    name: &str,
    default: &Tracker,
    workshop: Option<&Tracker>,
    text: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let l = &default.layer;
    let t_end = default.records.last().map_or(1.0, |r| r.time);
    let s_max = l.load * l.height / l.e_oed * 1.1;
    let words = Words {
        caption: format!("{name}: settlement of the top against time"),
        x: "time t (s)",
        y: "settlement of the top (mm)",
    };
    let mut chart = chart(area, 0.0..t_end, 0.0..s_max * 1e3, words, text)?;
    let terzaghi_line = chart.draw_series(LineSeries::new(
        (0..=200).map(|i| {
            let t = t_end * i as f64 / 200.0;
            (t, l.settlement(l.tv(t)) * 1e3)
        }),
        BLACK.stroke_width(2),
    ))?;
    if text {
        terzaghi_line
            .label("Terzaghi")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    }
    let ours = chart.draw_series(
        default
            .records
            .iter()
            .map(|r| Circle::new((r.time, r.settlement * 1e3), 4, RED.filled())),
    )?;
    if text {
        ours.label("default (undrained start)")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
    }
    if let Some(w) = workshop {
        let series = chart.draw_series(
            w.records
                .iter()
                .map(|r| TriangleMarker::new((r.time, r.settlement * 1e3), 5, BLUE)),
        )?;
        if text {
            series
                .label("workshop set-up (at rest, sudden load)")
                .legend(|(x, y)| TriangleMarker::new((x + 10, y), 5, BLUE));
        }
    }
    legend(&mut chart, SeriesLabelPosition::LowerRight, text)
}
