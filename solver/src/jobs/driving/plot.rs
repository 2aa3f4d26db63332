//! `driving.png`: the set and the resistances per blow against the tip's depth (top), the head
//! force and velocity of the first and the last blow against time (bottom).

use std::path::Path;

use super::{BlowRecord, TraceRow};
use crate::jobs::plot::{chart, font, legend, Panel, Words};

type Drawn = Result<(), Box<dyn std::error::Error>>;

/// Writes the figure into `path` (whole): `name` heads it; `axisymmetric` says the forces are
/// the whole ring's.
pub(super) fn write(
    path: &Path,
    name: &str,
    blows: &[BlowRecord],
    traces: (&[TraceRow], &[TraceRow]),
    axisymmetric: bool,
) -> mpm_shared::Result<()> {
    crate::jobs::plot::write_png(path, |tmp| {
        use plotters::prelude::*;
        let text = font().is_some();
        let root = BitMapBackend::new(tmp, (1400, 1000)).into_drawing_area();
        root.fill(&WHITE)?;
        let panels = root.split_evenly((2, 2));
        let whole = if axisymmetric { " (whole pile)" } else { "" };
        draw_set(&panels[0], name, blows, text)?;
        draw_resistance(&panels[1], name, blows, whole, text)?;
        let shown = (blows.len(), window(traces));
        draw_trace(&panels[2], traces, shown, text, Trace::Force(whole))?;
        draw_trace(&panels[3], traces, shown, text, Trace::Velocity)?;
        root.present()?;
        Ok(())
    })
}

/// The range from 0 (or the least value, when negative) to a little beyond the largest of
/// `values` (finite ones only; 0..1 when there are none).
fn span(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    let pad = 0.05 * (hi - lo).max(1e-12);
    if hi > lo {
        (lo - if lo < 0.0 { pad } else { 0.0 })..(hi + pad)
    } else {
        0.0..1.0
    }
}

/// The depth axis, downwards: the tips' depths with a margin of a twentieth of their spread
/// (at least 5 mm).
fn depths(blows: &[BlowRecord]) -> std::ops::Range<f64> {
    let (lo, hi) = blows
        .iter()
        .map(|b| b.tip_depth)
        .filter(|d| d.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
            (a.min(d), b.max(d))
        });
    if lo > hi {
        return 1.0..0.0;
    }
    let pad = (0.05 * (hi - lo)).max(5e-3);
    (hi + pad)..(lo - pad).max(0.0)
}

/// Forces in MN when they reach 10 MN, else in kN: (the factor from kN, the unit).
fn force_unit(values: impl Iterator<Item = f64>) -> (f64, &'static str) {
    let top = values
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if top >= 1e4 {
        (1e-3, "MN")
    } else {
        (1.0, "kN")
    }
}

/// The set per blow (mm) against the tip's depth.
fn draw_set(area: &Panel, name: &str, blows: &[BlowRecord], text: bool) -> Drawn {
    use plotters::prelude::*;
    let words = Words {
        caption: format!("{name}: set per blow against depth"),
        x: "permanent set of the blow (mm)",
        y: "tip depth below the initial ground (m)",
    };
    let x = span(blows.iter().map(|b| b.set * 1e3));
    let mut c = chart(area, x, depths(blows), words, text)?;
    let points: Vec<(f64, f64)> = blows.iter().map(|b| (b.set * 1e3, b.tip_depth)).collect();
    c.draw_series(LineSeries::new(points.clone(), RED.stroke_width(2)))?;
    c.draw_series(points.iter().map(|&p| Circle::new(p, 4, RED.filled())))?;
    Ok(())
}

/// A series of a per-blow panel: its label, its value and its colour.
type Series = (
    &'static str,
    fn(&BlowRecord) -> f64,
    plotters::style::RGBColor,
);

/// The peak base and shaft resistance of each blow against the tip's depth.
fn draw_resistance(
    area: &Panel,
    name: &str,
    blows: &[BlowRecord],
    whole: &str,
    text: bool,
) -> Drawn {
    use plotters::prelude::*;
    let (k, unit) = force_unit(blows.iter().flat_map(|b| [b.max_base, b.max_shaft]));
    let x_desc = format!("peak resistance in the blow ({unit}){whole}");
    let words = Words {
        caption: format!("{name}: soil resistance per blow"),
        x: &x_desc,
        y: "tip depth below the initial ground (m)",
    };
    let x = span(blows.iter().flat_map(|b| [k * b.max_base, k * b.max_shaft]));
    let mut c = chart(area, x, depths(blows), words, text)?;
    let series: [Series; 2] = [
        ("base", |b| b.max_base, BLUE),
        ("shaft (outside and inside)", |b| b.max_shaft, GREEN),
    ];
    for (label, f, colour) in series {
        let points: Vec<(f64, f64)> = blows.iter().map(|b| (k * f(b), b.tip_depth)).collect();
        let line = c.draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?;
        if text {
            line.label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
        c.draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
    }
    legend(&mut c, SeriesLabelPosition::LowerMiddle, text)
}

/// Which head trace a panel draws.
#[derive(Clone, Copy)]
enum Trace<'a> {
    /// The hammer's force, with the forces' note.
    Force(&'a str),
    /// The head's velocity.
    Velocity,
}

/// The traces' time window (s): five times as long as the hammer pushes in either blow (the
/// last row with a force above a hundredth of its peak), and at least 2 ms.
fn window((first, latest): (&[TraceRow], &[TraceRow])) -> f64 {
    let pushing = |rows: &[TraceRow]| {
        let peak = rows.iter().map(|r| r.head_force.abs()).fold(0.0, f64::max);
        rows.iter()
            .filter(|r| r.head_force.abs() > 0.01 * peak)
            .map(|r| r.time)
            .fold(0.0, f64::max)
    };
    (5.0 * pushing(first).max(pushing(latest))).max(2e-3)
}

/// A head trace of the first blow and of the last one (blow `last`) against the time since
/// each struck, up to `t_end` (s).
fn draw_trace(
    area: &Panel,
    (first, latest): (&[TraceRow], &[TraceRow]),
    (last, t_end): (usize, f64),
    text: bool,
    what: Trace,
) -> Drawn {
    use plotters::prelude::*;
    let (value, caption, desc, k): (fn(&TraceRow) -> f64, &str, String, f64) = match what {
        Trace::Force(whole) => {
            let rows = first.iter().chain(latest);
            let (k, unit) = force_unit(rows.map(|r| r.head_force));
            (
                |r| r.head_force,
                "pile head force",
                format!("head force ({unit}){whole}"),
                k,
            )
        }
        Trace::Velocity => (
            |r| r.head_velocity,
            "pile head velocity",
            "head velocity, down (m/s)".into(),
            1.0,
        ),
    };
    let within = |rows: &[TraceRow]| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.time <= t_end)
            .map(|r| (r.time * 1e3, k * value(r)))
            .collect()
    };
    let (a, b) = (within(first), within(latest));
    let y = span(a.iter().chain(&b).map(|p| p.1));
    let words = Words {
        caption: format!("{caption}: blow 1 and blow {last}"),
        x: "time since the blow struck (ms)",
        y: &desc,
    };
    let mut c = chart(area, 0.0..t_end * 1e3, y, words, text)?;
    for (rows, label, colour) in [
        (a, "blow 1".to_string(), BLACK),
        (b, format!("blow {last}"), RED),
    ] {
        let line = c.draw_series(LineSeries::new(rows, colour.stroke_width(2)))?;
        if text {
            line.label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
    }
    legend(&mut c, SeriesLabelPosition::UpperRight, text)
}
