//! What the jobs' figures share: the font, panels with captions and described axes, legends,
//! and writing a PNG whole (a temporary file, then a rename).

use std::path::Path;

/// A TrueType font for the plot's text, from the usual system places (DejaVu Sans or
/// Liberation Sans); `None` when there is none, and the plot is then drawn without text.
pub fn font() -> Option<&'static [u8]> {
    use std::sync::OnceLock;
    static FONT: OnceLock<Option<&'static [u8]>> = OnceLock::new();
    *FONT.get_or_init(|| {
        [
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
            "/Library/Fonts/Arial.ttf",
        ]
        .iter()
        .find_map(|p| std::fs::read(p).ok())
        .map(|bytes| {
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            let _ = plotters::style::register_font(
                "sans-serif",
                plotters::style::FontStyle::Normal,
                bytes,
            );
            bytes
        })
    })
}

/// One panel of a figure.
pub type Panel<'a> =
    plotters::drawing::DrawingArea<plotters::backend::BitMapBackend<'a>, plotters::coord::Shift>;

/// A plot of one half: real numbers on both axes.
pub type Chart<'a, 'b> = plotters::chart::ChartContext<
    'a,
    plotters::backend::BitMapBackend<'b>,
    plotters::coord::cartesian::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// The captions and axis descriptions of a plot.
pub struct Words<'a> {
    /// The caption above the plot.
    pub caption: String,
    /// The x axis's description.
    pub x: &'a str,
    /// The y axis's description.
    pub y: &'a str,
}

/// A plot on `area` over `x` by `y` with a mesh, and with its `words` where `text` (a font
/// was found); without text, no labels and no mesh lines.
pub fn chart<'b>(
    area: &Panel<'b>,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    words: Words,
    text: bool,
) -> Result<Chart<'b, 'b>, Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let mut chart = ChartBuilder::on(area);
    chart.margin(20);
    if text {
        chart
            .caption(words.caption, ("sans-serif", 22))
            .x_label_area_size(40)
            .y_label_area_size(50);
    }
    let mut chart = chart.build_cartesian_2d(x, y)?;
    if text {
        chart
            .configure_mesh()
            .x_desc(words.x)
            .y_desc(words.y)
            .draw()?;
    } else {
        chart.configure_mesh().disable_mesh().draw()?;
    }
    Ok(chart)
}

/// The legend of `chart` at `position`, where `text` (a font was found).
pub fn legend<'a>(
    chart: &mut Chart<'a, 'a>,
    position: plotters::chart::SeriesLabelPosition,
    text: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    if text {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(position)
            .draw()?;
    }
    Ok(())
}

/// Draws a figure with `draw` into a temporary file beside `path`, then renames it into place:
/// a reader never sees half a PNG.
pub fn write_png(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<(), Box<dyn std::error::Error>>,
) -> mpm_shared::Result<()> {
    let name = path
        .file_name()
        .map_or_else(|| "figure.png".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.tmp.png"));
    draw(&tmp).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        mpm_shared::Error::io(path, std::io::Error::other(e.to_string()))
    })?;
    std::fs::rename(&tmp, path).map_err(|e| mpm_shared::Error::io(path, e))
}
