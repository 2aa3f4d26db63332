//! Pictures for docs/validation-mc.md (`scripts/validate-mc`).
//!
//! ```text
//! cargo run --release -p mpm-solve --example validation_plot -- curves OUT.png TITLE XLABEL YLABEL \
//!     [--ref VALUE:LABEL] LABEL=FILE.csv ...
//! cargo run --release -p mpm-solve --example validation_plot -- deposits OUT.png \
//!     A=FILE.csv:RUNOUT ...
//! ```
//!
//! `curves` draws each two-column CSV (header, then x,y rows) as a line, with optional
//! horizontal reference lines. `deposits` draws one panel per aspect ratio `A`: the final
//! material points of a column collapse as (r / r0, y / r0) from a CSV of `r,y` rows in units
//! of r0, the initial column's outline and the run-out `RUNOUT` (in r0) of Lube et al.'s
//! scaling as a vertical line.

use std::error::Error;

use plotters::prelude::*;

const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn read_xy(path: &str) -> Result<Vec<(f64, f64)>, Box<dyn Error>> {
    let mut rd = csv::Reader::from_path(path)?;
    let mut out = Vec::new();
    for (i, rec) in rd.records().enumerate() {
        let rec = rec?;
        let num = |k: usize| -> Result<f64, Box<dyn Error>> {
            rec.get(k)
                .ok_or_else(|| format!("{path}: row {}: too few columns", i + 2))?
                .trim()
                .parse::<f64>()
                .map_err(|e| format!("{path}: row {}: {e}", i + 2).into())
        };
        out.push((num(0)?, num(1)?));
    }
    Ok(out)
}

fn bounds(points: impl Iterator<Item = (f64, f64)>) -> (f64, f64, f64, f64) {
    points.fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), (x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    )
}

fn curves(out: &str, args: &[String]) -> Result<(), Box<dyn Error>> {
    let [title, xl, yl, rest @ ..] = args else {
        return Err("curves OUT.png TITLE XLABEL YLABEL [--ref V:LABEL] LABEL=FILE ...".into());
    };
    let mut refs = Vec::new();
    let mut series = Vec::new();
    let mut it = rest.iter();
    while let Some(a) = it.next() {
        if a == "--ref" {
            let r = it.next().ok_or("--ref needs VALUE:LABEL")?;
            let (v, l) = r.split_once(':').ok_or("--ref needs VALUE:LABEL")?;
            refs.push((v.parse::<f64>()?, l.to_string()));
        } else {
            let (label, file) = a.split_once('=').ok_or("series are LABEL=FILE")?;
            series.push((label.to_string(), read_xy(file)?));
        }
    }
    let all = series
        .iter()
        .flat_map(|(_, s)| s.iter().copied())
        .chain(refs.iter().map(|(v, _)| (0.0, *v)));
    let (x0, x1, y0, y1) = bounds(all);
    let (y0, y1) = (y0.min(0.0), y1 * 1.1);
    let root = BitMapBackend::new(out, (900, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title.as_str(), ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x0.min(0.0)..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(xl.as_str())
        .y_desc(yl.as_str())
        .draw()?;
    for (k, (label, s)) in series.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))?
            .label(label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    for (v, label) in &refs {
        chart
            .draw_series(LineSeries::new(
                vec![(x0.min(0.0), *v), (x1, *v)],
                BLACK.stroke_width(1),
            ))?
            .label(label.as_str())
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()?;
    root.present()?;
    Ok(())
}

fn deposits(out: &str, args: &[String]) -> Result<(), Box<dyn Error>> {
    let mut panels = Vec::new();
    for a in args {
        let (ratio, rest) = a.split_once('=').ok_or("panels are A=FILE.csv:RUNOUT")?;
        let (file, runout) = rest
            .rsplit_once(':')
            .ok_or("panels are A=FILE.csv:RUNOUT")?;
        panels.push((
            ratio.parse::<f64>()?,
            read_xy(file)?,
            runout.parse::<f64>()?,
        ));
    }
    if panels.is_empty() {
        return Err("no panels".into());
    }
    let x_max = panels
        .iter()
        .map(|(_, p, r)| p.iter().map(|q| q.0).fold(*r + 1.0, f64::max))
        .fold(0.0, f64::max)
        * 1.05;
    let root = BitMapBackend::new(out, (1000, 260 * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE)?;
    for ((a, pts, runout), area) in panels.iter().zip(root.split_evenly((panels.len(), 1))) {
        let y_max = a.max(1.0) * 1.1;
        let mut chart = ChartBuilder::on(&area)
            .caption(
                format!("a = {a}: final deposit (points), initial column (grey), Lube et al. run-out (red)"),
                ("sans-serif", 16),
            )
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..x_max, 0.0..y_max)?;
        chart
            .configure_mesh()
            .x_desc("r / r0")
            .y_desc("y / r0")
            .draw()?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.0, *a), (1.0, *a), (1.0, 0.0)],
            RGBColor(150, 150, 150).stroke_width(2),
        )))?;
        chart.draw_series(
            pts.iter()
                .map(|&(r, y)| Circle::new((r, y), 1, COLOURS[0].filled())),
        )?;
        let front = 1.0 + runout;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(front, 0.0), (front, y_max)],
            RGBColor(214, 39, 40).stroke_width(2),
        )))?;
    }
    root.present()?;
    Ok(())
}

/// Registers a system TrueType font for the text (plotters has none of its own here).
fn font() -> Result<(), Box<dyn Error>> {
    let path = [
        "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
        "/usr/share/fonts/TTF/DejaVuSans.ttf",
        "/usr/share/fonts/dejavu/DejaVuSans.ttf",
        "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    ]
    .iter()
    .find(|p| std::path::Path::new(p).exists())
    .ok_or("no TrueType font found (install fonts-dejavu-core)")?;
    let bytes: &'static [u8] = Box::leak(std::fs::read(path)?.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
        .map_err(|_| format!("{path}: not a usable font"))?;
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    font()?;
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.as_slice() {
        [kind, out, rest @ ..] if kind == "curves" => curves(out, rest),
        [kind, out, rest @ ..] if kind == "deposits" => deposits(out, rest),
        _ => Err("usage: validation_plot curves|deposits OUT.png ...".into()),
    }
}
