//! `--plot`: the worst material-point field (largest relative difference) as a PNG: on the left
//! its largest |difference| over components against the vertical coordinate y at its worst
//! output (binned, so a 10-million point output draws as fast as a small one), on the right its
//! largest difference per output against time.

use std::path::Path;

use super::read::{Field, Folder};
use super::{pair_outputs, CompareError, Report};

/// Depth bins of the profile.
const BINS: usize = 200;

/// Writes the plot to `path` (atomically: a temporary file beside it, then renamed).
pub fn write_png(
    path: &Path,
    golden: &Path,
    candidate: &Path,
    report: &Report,
) -> Result<(), CompareError> {
    let (o, f) = report
        .outputs
        .iter()
        .flat_map(|o| o.fields.iter().map(move |f| (o, f)))
        .max_by(|x, y| x.1.max_rel.total_cmp(&y.1.max_rel))
        .ok_or_else(|| CompareError::Plot("no material-point field was compared".into()))?;
    let field = Field::ALL
        .into_iter()
        .find(|x| x.name() == f.field)
        .expect("report fields are Field names");
    let (fa, fb) = (Folder::open(golden)?, Folder::open(candidate)?);
    let (pa, pb) = pair_outputs(&fa, &fb)?
        .into_iter()
        .find(|(pa, _)| pa.label == o.golden)
        .ok_or_else(|| CompareError::Plot(format!("{} is gone", o.golden)))?;
    let (a, b) = (fa.load(pa.index)?, fb.load(pb.index)?);
    let missing = || CompareError::Plot(format!("{} lost its field '{}'", o.golden, f.field));
    let (va, vb) = (
        a.field(field)?.ok_or_else(missing)?,
        b.field(field)?.ok_or_else(missing)?,
    );
    let pos = a
        .field(Field::Position)?
        .ok_or_else(|| CompareError::Plot("the golden output has no positions".into()))?;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..a.len() {
        let y = pos.get(k, 1);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut bins = vec![f64::NAN; BINS];
    for k in 0..a.len() {
        let y = pos.get(k, 1);
        let d = (0..field.components().len())
            .map(|c| (va.get(k, c) - vb.get(k, c)).abs())
            .fold(
                0.0f64,
                |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v) },
            );
        let i = (((y - lo) / span) * BINS as f64).clamp(0.0, (BINS - 1) as f64) as usize;
        bins[i] = if bins[i].is_nan() { d } else { bins[i].max(d) };
    }
    let profile: Vec<(f64, f64)> = bins
        .iter()
        .enumerate()
        .filter(|(_, d)| d.is_finite())
        .map(|(i, &d)| (d, lo + span * (i as f64 + 0.5) / BINS as f64))
        .collect();
    let series: Vec<(f64, f64)> = report
        .outputs
        .iter()
        .filter_map(|o| {
            let s = o.fields.iter().find(|s| s.field == f.field)?;
            Some((o.time?, s.max_abs))
        })
        .filter(|(_, d)| d.is_finite())
        .collect();
    let title = format!("{} at t = {} s", f.field, o.time.unwrap_or(0.0));
    let tmp = path.with_file_name(format!(
        ".{}.tmp.png",
        path.file_stem()
            .map_or("plot".into(), |s| s.to_string_lossy())
    ));
    draw(
        &tmp,
        &title,
        f.field.as_str(),
        &profile,
        &series,
        (lo, lo + span),
    )
    .map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        CompareError::Plot(format!("{}: {e}", path.display()))
    })?;
    std::fs::rename(&tmp, path).map_err(|e| CompareError::Plot(format!("{}: {e}", path.display())))
}

fn draw(
    path: &Path,
    title: &str,
    field: &str,
    profile: &[(f64, f64)],
    series: &[(f64, f64)],
    (lo, hi): (f64, f64),
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let text = crate::jobs::plot::font().is_some();
    let root = BitMapBackend::new(path, (1400, 650)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(700);
    let top = |v: &[(f64, f64)], x: bool| {
        let m = v
            .iter()
            .map(|p| if x { p.0 } else { p.1 })
            .fold(0.0f64, f64::max);
        if m > 0.0 {
            m * 1.05
        } else {
            1.0
        }
    };
    let mut chart = ChartBuilder::on(&left);
    chart.margin(20);
    if text {
        chart
            .caption(
                format!("{title}: |difference| against y"),
                ("sans-serif", 22),
            )
            .x_label_area_size(40)
            .y_label_area_size(60);
    }
    let mut c = chart.build_cartesian_2d(0.0..top(profile, true), lo..hi)?;
    if text {
        c.configure_mesh()
            .x_desc(format!(
                "largest |golden - candidate| of {field} over components, per y bin"
            ))
            .y_desc("y (m)")
            .draw()?;
    } else {
        c.configure_mesh().disable_mesh().draw()?;
    }
    c.draw_series(LineSeries::new(
        profile.iter().copied(),
        RED.stroke_width(2),
    ))?;
    c.draw_series(profile.iter().map(|&p| Circle::new(p, 2, RED.filled())))?;
    let t_end = series.iter().map(|p| p.0).fold(0.0f64, f64::max);
    let mut chart = ChartBuilder::on(&right);
    chart.margin(20);
    if text {
        chart
            .caption(
                format!("{field}: largest |difference| against time"),
                ("sans-serif", 22),
            )
            .x_label_area_size(40)
            .y_label_area_size(60);
    }
    let mut c = chart.build_cartesian_2d(
        0.0..t_end.max(f64::MIN_POSITIVE) * 1.05,
        0.0..top(series, false),
    )?;
    if text {
        c.configure_mesh()
            .x_desc("time t (s)")
            .y_desc(format!("largest |difference| of {field}"))
            .draw()?;
    } else {
        c.configure_mesh().disable_mesh().draw()?;
    }
    c.draw_series(LineSeries::new(
        series.iter().copied(),
        BLUE.stroke_width(2),
    ))?;
    c.draw_series(series.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))?;
    root.present()?;
    Ok(())
}
