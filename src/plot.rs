//! Figure helpers on plotters: PNG line/marker charts with DejaVu Sans loaded at run time.

use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// Where Debian's fonts-dejavu-core puts the font used for every label.
pub const FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

fn register_font() -> Result<(), String> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        let bytes = std::fs::read(FONT).map_err(|e| format!("cannot read {FONT} ({e}); install fonts-dejavu-core"))?;
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).map_err(|_| format!("{FONT} is not a usable font"))
    })
    .clone()
}

/// The same colour for an engine in every figure: magdem red, LIGGGHTS blue, LAMMPS green.
pub fn engine_colour(engine: &str) -> RGBColor {
    match engine {
        "liggghts" => RGBColor(20, 90, 200),
        "lammps" => RGBColor(30, 150, 60),
        _ => RGBColor(200, 30, 30),
    }
}

/// One data series: a line, or circles of radius `markers` (px) when set. An empty label keeps
/// the series out of the legend.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub markers: Option<u32>,
}

/// Axis tick text with as many decimals as the magnitude needs.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.1}")
    } else if a >= 1e-3 {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

/// A labelled x–y chart written to `path` (PNG), legend in the upper left.
pub fn line_chart(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<(), Box<dyn std::error::Error>> {
    line_chart_with_legend(path, title, x_label, y_label, series, SeriesLabelPosition::UpperLeft)
}

/// [`line_chart`] with the legend where the data leave room.
pub fn line_chart_with_legend(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    legend: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>> {
    register_font()?;
    let all = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let pad = |lo: f64, hi: f64| {
        let d = (hi - lo).abs().max(hi.abs() * 1e-6).max(1e-300);
        (lo - 0.05 * d, hi + 0.05 * d)
    };
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1);
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .draw()?;
    for s in series {
        let color = s.color;
        match s.markers {
            Some(r) => {
                let drawn = chart.draw_series(s.points.iter().map(move |&p| Circle::new(p, r, color.stroke_width(2))))?;
                if !s.label.is_empty() {
                    drawn.label(s.label.as_str()).legend(move |(x, y)| Circle::new((x + 10, y), r, color.stroke_width(2)));
                }
            }
            None => {
                let drawn = chart.draw_series(LineSeries::new(s.points.iter().copied(), color.stroke_width(2)))?;
                if !s.label.is_empty() {
                    drawn.label(s.label.as_str()).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                }
            }
        }
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend)
        .draw()?;
    root.present()?;
    Ok(())
}
