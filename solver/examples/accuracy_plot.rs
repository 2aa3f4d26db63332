//! Plots of the accuracy–cost map (`scripts/accuracy-study`, docs/accuracy.md): for each
//! problem in a results CSV, its error against wall time on log axes, one series per setting
//! family (integration × points per element × mesh kind × precision), each series drawn through
//! its mesh levels at every Courant number, and the Pareto front (no other run is both cheaper
//! and more accurate) marked.
//!
//! ```text
//! cargo run --release -p mpm-solve --example accuracy_plot -- RESULTS.csv OUT_PREFIX
//! ```
//!
//! writes `OUT_PREFIX-PROBLEM.png` per problem. The CSV needs the columns `problem`, `error`,
//! `wall_s`, `integration`, `ppe`, `mesh`, `precision`, `courant` and `cells`.

use std::collections::BTreeMap;
use std::error::Error;
use std::path::Path;

use plotters::prelude::*;

/// One run of the study.
#[derive(Debug, Clone)]
struct Run {
    problem: String,
    family: String,
    courant: f64,
    cells: u32,
    wall: f64,
    error: f64,
}

/// Series colours, in family order.
const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn read_runs(path: &Path) -> Result<Vec<Run>, Box<dyn Error>> {
    let mut rd = csv::Reader::from_path(path)?;
    let head = rd.headers()?.clone();
    let col = |name: &str| -> Result<usize, Box<dyn Error>> {
        head.iter()
            .position(|h| h == name)
            .ok_or_else(|| format!("{}: no column '{name}'", path.display()).into())
    };
    let [problem, error, wall, integration, ppe, mesh, precision, courant, cells] = [
        "problem",
        "error",
        "wall_s",
        "integration",
        "ppe",
        "mesh",
        "precision",
        "courant",
        "cells",
    ]
    .map(col);
    let (problem, error, wall, integration, ppe) = (problem?, error?, wall?, integration?, ppe?);
    let (mesh, precision, courant, cells) = (mesh?, precision?, courant?, cells?);
    let mut runs = Vec::new();
    for rec in rd.records() {
        let rec = rec?;
        let num = |i: usize| rec.get(i).and_then(|s| s.parse::<f64>().ok());
        let (Some(e), Some(w), Some(c), Some(n)) =
            (num(error), num(wall), num(courant), num(cells))
        else {
            continue;
        };
        if !(e > 0.0 && w > 0.0 && e.is_finite() && w.is_finite()) {
            continue;
        }
        runs.push(Run {
            problem: rec[problem].to_string(),
            family: format!(
                "{} {} pt/el {} {}",
                &rec[integration], &rec[ppe], &rec[mesh], &rec[precision]
            ),
            courant: c,
            cells: n as u32,
            wall: w,
            error: e,
        });
    }
    Ok(runs)
}

/// The runs no other run beats in both wall time and error, by increasing wall time.
fn pareto(runs: &[&Run]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<(f64, f64)> = runs.iter().map(|r| (r.wall, r.error)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in sorted {
        match front.last() {
            Some(q) if p.1 >= q.1 => {}
            _ => front.push(p),
        }
    }
    front
}

/// A decade range enclosing `values`.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if !lo.is_finite() {
        return (0.1, 1.0);
    }
    let lo = 10f64.powf(lo.log10().floor());
    let hi = 10f64.powf(hi.log10().ceil());
    (lo, if hi > lo { hi } else { lo * 10.0 })
}

fn draw(path: &Path, problem: &str, runs: &[&Run], text: bool) -> Result<(), Box<dyn Error>> {
    let root = BitMapBackend::new(path, (1100, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let (x0, x1) = decades(runs.iter().map(|r| r.wall));
    let (y0, y1) = decades(runs.iter().map(|r| r.error));
    let mut chart = ChartBuilder::on(&root);
    chart.margin(20);
    if text {
        chart
            .caption(
                format!("{problem}: error against wall time (1 thread)"),
                ("sans-serif", 24),
            )
            .x_label_area_size(45)
            .y_label_area_size(70);
    }
    let mut c = chart.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    if text {
        c.configure_mesh()
            .x_desc("wall time of the run (s)")
            .y_desc("error (see docs/accuracy.md)")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()?;
    } else {
        c.configure_mesh().draw()?;
    }
    let mut families: BTreeMap<&str, Vec<&Run>> = BTreeMap::new();
    for r in runs {
        families.entry(r.family.as_str()).or_default().push(r);
    }
    for (k, (family, members)) in families.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        // One line per Courant number through the mesh levels, so refinement reads as a path.
        let mut by_courant: BTreeMap<u64, Vec<&Run>> = BTreeMap::new();
        for r in members {
            by_courant.entry(r.courant.to_bits()).or_default().push(r);
        }
        for line in by_courant.values_mut() {
            line.sort_by_key(|r| r.cells);
            c.draw_series(LineSeries::new(
                line.iter().map(|r| (r.wall, r.error)),
                colour.mix(0.5).stroke_width(1),
            ))?;
        }
        let series = c.draw_series(
            members
                .iter()
                .map(|r| Circle::new((r.wall, r.error), 4, colour.filled())),
        )?;
        if text {
            series
                .label(family.to_string())
                .legend(move |(x, y)| Circle::new((x + 8, y), 4, colour.filled()));
        }
    }
    let front = pareto(runs);
    c.draw_series(LineSeries::new(
        front.iter().copied(),
        BLACK.stroke_width(2),
    ))?;
    let marks = c.draw_series(
        front
            .iter()
            .map(|&p| Cross::new(p, 7, BLACK.stroke_width(2))),
    )?;
    if text {
        marks
            .label("Pareto front")
            .legend(|(x, y)| Cross::new((x + 8, y), 6, BLACK.stroke_width(2)));
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [csv_path, prefix] = args.as_slice() else {
        return Err("usage: accuracy_plot RESULTS.csv OUT_PREFIX".into());
    };
    let runs = read_runs(Path::new(csv_path))?;
    let text = mpm_solve::jobs::plot::font().is_some();
    let mut problems: Vec<&str> = runs.iter().map(|r| r.problem.as_str()).collect();
    problems.sort_unstable();
    problems.dedup();
    for problem in problems {
        let mine: Vec<&Run> = runs.iter().filter(|r| r.problem == problem).collect();
        let path = format!("{prefix}-{problem}.png");
        draw(Path::new(&path), problem, &mine, text)?;
        println!("wrote {path} ({} runs)", mine.len());
    }
    Ok(())
}
