//! Figure helpers on plotters: PNG line/marker charts (with error bars), grouped bar panels and
//! box-plot panels, with DejaVu Sans loaded at run time.

use plotters::prelude::*;
pub use plotters::prelude::{RGBColor, SeriesLabelPosition};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;
use std::sync::OnceLock;

/// Where Debian's fonts-dejavu-core puts the font used for every label.
pub const FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

fn register_font() -> Result<(), String> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        let bytes = std::fs::read(FONT).map_err(|e| format!("cannot read {FONT} ({e}); install fonts-dejavu-core"))?;
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| format!("{FONT} is not a usable font"))
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

/// One data series: a line, or circles of radius `markers` (px) when set, with vertical error
/// bars of half-height `errors[k]` at point k when given. An empty label keeps the series out of
/// the legend.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub markers: Option<u32>,
    pub errors: Vec<f64>,
}

impl Series {
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.into(), points, color, markers: None, errors: vec![] }
    }
    pub fn markers(label: impl Into<String>, points: Vec<(f64, f64)>, color: RGBColor, radius: u32) -> Self {
        Self { label: label.into(), points, color, markers: Some(radius), errors: vec![] }
    }
    pub fn with_errors(self, errors: Vec<f64>) -> Self {
        Self { errors, ..self }
    }
}

/// The colour of the k-th of several categories (variants, concentrations).
pub fn palette(k: usize) -> RGBColor {
    const COLOURS: [RGBColor; 8] = [
        RGBColor(200, 30, 30),
        RGBColor(20, 90, 200),
        RGBColor(30, 150, 60),
        RGBColor(230, 140, 0),
        RGBColor(130, 60, 170),
        RGBColor(0, 160, 170),
        RGBColor(120, 120, 120),
        RGBColor(170, 110, 60),
    ];
    COLOURS[k % COLOURS.len()]
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
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), Box<dyn std::error::Error>> {
    line_chart_with_legend(path, title, x_label, y_label, series, SeriesLabelPosition::UpperLeft)
}

/// Where a chart's legend goes: a corner or edge, and how far the y axis extends above the data
/// (as a fraction of their range) to make room for it.
pub struct Legend {
    pub position: SeriesLabelPosition,
    pub headroom: f64,
}

impl Legend {
    /// Upper left, above the data: for a chart whose every corner holds points.
    pub fn above_data(headroom: f64) -> Self {
        Legend { position: SeriesLabelPosition::UpperLeft, headroom }
    }
}

impl From<SeriesLabelPosition> for Legend {
    fn from(position: SeriesLabelPosition) -> Self {
        Legend { position, headroom: 0.0 }
    }
}

/// A linear coordinate with its own tick positions (bold: labelled; light: grid only).
struct Axis {
    inner: plotters::coord::types::RangedCoordf64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Axis {
    fn new(range: std::ops::Range<f64>, bold: Vec<f64>, light: Vec<f64>) -> Self {
        Self { inner: range.into(), bold, light }
    }
}

impl plotters::coord::ranged1d::Ranged for Axis {
    type ValueType = f64;
    type FormatOption = plotters::coord::ranged1d::NoDefaultFormatting;
    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }
    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
}

impl plotters::coord::ranged1d::ValueFormatter<f64> for Axis {
    fn format(value: &f64) -> String {
        tick(value)
    }
}

/// How an axis maps values: linear, or logarithmic (base 10; values ≤ 0 are left out).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    Linear,
    Log,
}

impl Scale {
    fn to_axis(self, v: f64) -> f64 {
        match self {
            Scale::Linear => v,
            Scale::Log if v > 0.0 => v.log10(),
            Scale::Log => f64::NAN,
        }
    }
    /// Tick positions on the axis (axis units) between `lo` and `hi`: round numbers (1, 2, 5 ×
    /// 10^k steps) on a linear axis, 1, 2 and 5 of every decade on a log axis; and the light
    /// grid lines between them.
    fn ticks(self, lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
        match self {
            Scale::Linear => {
                let raw = (hi - lo) / 8.0;
                let decade = 10f64.powf(raw.log10().floor());
                let step =
                    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * decade).find(|&s| s >= raw).unwrap_or(10.0 * decade);
                let on = |step: f64| {
                    ((lo / step).ceil() as i64..=(hi / step).floor() as i64)
                        .map(|k| k as f64 * step)
                        .collect::<Vec<_>>()
                };
                (on(step), on(step / 5.0))
            }
            Scale::Log => {
                let (mut bold, mut light) = (vec![], vec![]);
                for k in lo.floor() as i64..=hi.ceil() as i64 {
                    for m in 1..10 {
                        let v = (m as f64).log10() + k as f64;
                        if v >= lo && v <= hi {
                            if [1, 2, 5].contains(&m) { &mut bold } else { &mut light }.push(v);
                        }
                    }
                }
                // A range within one decade gets every integer multiple labelled.
                if bold.len() < 3 {
                    bold.append(&mut light);
                    bold.sort_by(f64::total_cmp);
                }
                (bold, light)
            }
        }
    }

    fn label(self, v: &f64) -> String {
        match self {
            Scale::Linear => tick(v),
            Scale::Log => {
                // Ticks sit at integer multiples of 10^k: one significant digit names them.
                let x = 10f64.powf(*v);
                let digits = (-x.log10().floor()).max(0.0) as usize;
                if !(1e-3..1e5).contains(&x) {
                    format!("{x:.0e}")
                } else {
                    format!("{x:.digits$}")
                }
            }
        }
    }
}

/// [`line_chart`] with the legend where the data leave room.
pub fn line_chart_with_legend(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    legend: impl Into<Legend>,
) -> Result<(), Box<dyn std::error::Error>> {
    chart(path, title, (x_label, y_label), series, legend, (Scale::Linear, Scale::Linear))
}

/// An x–y chart with the given axis scales (log axes are labelled with the values themselves).
pub fn chart(
    path: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[Series],
    legend: impl Into<Legend>,
    (sx, sy): (Scale, Scale),
) -> Result<(), Box<dyn std::error::Error>> {
    register_font()?;
    let legend = legend.into();
    // Points and error-bar ends on the axes' own scales.
    type Points = Vec<(f64, f64)>;
    let mapped: Vec<(Points, Points)> = series
        .iter()
        .map(|s| {
            let pts: Vec<(f64, f64)> = s.points.iter().map(|&(x, y)| (sx.to_axis(x), sy.to_axis(y))).collect();
            let bars = s
                .points
                .iter()
                .zip(&s.errors)
                .filter(|(_, e)| e.is_finite())
                .map(|(&(_, y), &e)| (sy.to_axis(y - e), sy.to_axis(y + e)))
                .collect();
            (pts, bars)
        })
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (pts, bars) in &mapped {
        for &(x, y) in pts.iter().filter(|(x, y)| x.is_finite() && y.is_finite()) {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        for &(a, b) in bars {
            for v in [a, b].into_iter().filter(|v| v.is_finite()) {
                (y0, y1) = (y0.min(v), y1.max(v));
            }
        }
    }
    let pad = |lo: f64, hi: f64| {
        let d = (hi - lo).abs().max(hi.abs() * 1e-6).max(1e-300);
        (lo - 0.05 * d, hi + 0.05 * d)
    };
    let (x0, x1) = pad(x0, x1);
    let (y0, y1) = pad(y0, y1 + legend.headroom * (y1 - y0));
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let ((bx, lx), (by, ly)) = (sx.ticks(x0, x1), sy.ticks(y0, y1));
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(Axis::new(x0..x1, bx, lx), Axis::new(y0..y1, by, ly))?;
    let (fx, fy) = (|v: &f64| sx.label(v), |v: &f64| sy.label(v));
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .draw()?;
    for (s, (pts, _)) in series.iter().zip(&mapped) {
        let color = s.color;
        let bars = s.points.iter().zip(&s.errors).filter(|(_, e)| e.is_finite());
        chart.draw_series(bars.map(move |(&(x, y), &e)| {
            let x = sx.to_axis(x);
            let (lo, hi) = (sy.to_axis(y - e), sy.to_axis(y + e));
            // A log axis cannot show a bar reaching zero: it runs to the bottom of the chart.
            PathElement::new(vec![(x, if lo.is_finite() { lo } else { y0 }), (x, hi)], color.stroke_width(2))
        }))?;
        let pts: Vec<(f64, f64)> = pts.iter().copied().filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
        match s.markers {
            Some(r) => {
                let drawn = chart.draw_series(pts.iter().map(move |&p| Circle::new(p, r, color.stroke_width(2))))?;
                if !s.label.is_empty() {
                    drawn
                        .label(s.label.as_str())
                        .legend(move |(x, y)| Circle::new((x + 10, y), r, color.stroke_width(2)));
                }
            }
            None => {
                let drawn = chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))?;
                if !s.label.is_empty() {
                    drawn
                        .label(s.label.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                }
            }
        }
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend.position)
        .draw()?;
    root.present()?;
    Ok(())
}

/// One group of bars (one colour) over a panel's categories, with optional error half-heights.
pub struct BarGroup {
    pub label: String,
    pub color: RGBColor,
    pub values: Vec<f64>,
    pub errors: Vec<f64>,
}

/// A bar chart: one slot per category, the groups side by side within it.
pub struct BarPanel {
    pub title: String,
    pub y_label: String,
    pub categories: Vec<String>,
    pub groups: Vec<BarGroup>,
}

/// How [`category_panels`] draws a panel's groups.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// Bars from zero with thin grey spread lines clipped at zero: amounts.
    Bars,
    /// Circles with coloured ± bars on an axis that spans negative values, with a line at zero:
    /// differences, whose sign matters.
    Dots,
}

/// Category panels on a grid of `columns`, written to `path` (PNG): per category one bar or dot
/// per group, side by side, as `mark` says. Category labels are thinned to at most 20 per axis,
/// and set on two alternating rows where they would run into each other.
pub fn category_panels(
    path: &Path,
    title: &str,
    panels: &[BarPanel],
    columns: usize,
    panel_size: (u32, u32),
    mark: Mark,
) -> Result<(), Box<dyn std::error::Error>> {
    register_font()?;
    let rows = panels.len().div_ceil(columns.max(1));
    let root =
        BitMapBackend::new(path, (panel_size.0 * columns as u32, panel_size.1 * rows as u32 + 50)).into_drawing_area();
    root.fill(&WHITE)?;
    let (head, body) = root.split_vertically(50);
    head.titled(title, ("sans-serif", 24))?;
    for (panel, area) in panels.iter().zip(body.split_evenly((rows, columns))) {
        let n = panel.categories.len();
        // The values' range with their spreads, zero included.
        let ends = panel.groups.iter().flat_map(|g| {
            g.values.iter().enumerate().flat_map(move |(k, &v)| {
                let e = g.errors.get(k).copied().filter(|e| e.is_finite()).unwrap_or(0.0);
                [v - e, v + e]
            })
        });
        let (lo, hi) = ends.filter(|v| v.is_finite()).fold((0.0_f64, 0.0_f64), |(a, b), v| (a.min(v), b.max(v)));
        // Room above the data for the legend, when there is one.
        let labelled = panel.groups.iter().any(|g| !g.label.is_empty());
        let y_range = match mark {
            Mark::Bars => 0.0..hi * if labelled { 1.3 } else { 1.1 } + 1e-300,
            Mark::Dots => {
                let span = (hi - lo).max(1e-300);
                lo - 0.08 * span..hi + span * if labelled { 0.35 } else { 0.08 }
            }
        };
        let mut chart = ChartBuilder::on(&area)
            .caption(&panel.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(if panel.categories.iter().any(|c| c.len() > 6) { 70 } else { 40 })
            .y_label_area_size(80)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, y_range.clone())?;
        // Labels wider than the room between two shown ones are set on two alternating rows, so
        // that neighbours do not run into each other.
        let step = n.div_ceil(20).max(1);
        let label_style = TextStyle::from(("sans-serif", 14).into_font());
        let room = chart.plotting_area().dim_in_pixel().0 as usize * step / n.max(1);
        let staggered = panel
            .categories
            .iter()
            .step_by(step)
            .any(|c| area.estimate_text_size(c, &label_style).is_ok_and(|(width, _)| width as usize > room));
        let names = panel.categories.clone();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_desc(panel.y_label.as_str())
            .x_labels(n.min(40))
            .x_label_formatter(&|x| {
                let k = x.round();
                let own = (x - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < names.len();
                if own && !staggered && (k as usize).is_multiple_of(step) {
                    names[k as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()?;
        if staggered {
            let style = label_style.pos(Pos::new(HPos::Center, VPos::Top));
            for (k, name) in names.iter().enumerate().step_by(step) {
                let (x, y) = chart.backend_coord(&(k as f64, y_range.start));
                root.draw(&Text::new(name.as_str(), (x, y + 8 + 18 * (k / step % 2) as i32), style.clone()))?;
            }
        }
        if mark == Mark::Dots {
            chart.draw_series([PathElement::new(vec![(-0.5, 0.0), (n as f64 - 0.5, 0.0)], BLACK.stroke_width(1))])?;
        }
        // The share of a category's slot its groups fill, centred on the category.
        let slot = match mark {
            Mark::Bars => 0.8,
            Mark::Dots => 0.6,
        };
        let width = slot / panel.groups.len().max(1) as f64;
        for (g, group) in panel.groups.iter().enumerate() {
            let color = group.color;
            let left = move |k: usize| k as f64 - slot / 2.0 + g as f64 * width;
            let finite = || group.values.iter().enumerate().filter(|(_, v)| v.is_finite());
            let spreads =
                finite().filter_map(|(k, &v)| Some((k, v, group.errors.get(k).copied().filter(|e| e.is_finite())?)));
            let label = group.label.as_str();
            match mark {
                Mark::Bars => {
                    let drawn =
                        chart.draw_series(finite().map(|(k, &v)| {
                            Rectangle::new([(left(k), 0.0), (left(k) + width * 0.9, v)], color.filled())
                        }))?;
                    if !label.is_empty() {
                        drawn
                            .label(label)
                            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 14, y + 6)], color.filled()));
                    }
                    // Thin and grey, so that the bars stay readable where the spread is large;
                    // a spread below zero is clipped at the axis.
                    chart.draw_series(spreads.map(|(k, v, e)| {
                        let x = left(k) + width * 0.45;
                        PathElement::new(vec![(x, (v - e).max(0.0)), (x, v + e)], RGBColor(90, 90, 90).stroke_width(1))
                    }))?;
                }
                Mark::Dots => {
                    chart.draw_series(spreads.map(|(k, v, e)| {
                        let x = left(k) + width * 0.5;
                        PathElement::new(vec![(x, v - e), (x, v + e)], color.stroke_width(2))
                    }))?;
                    let drawn = chart.draw_series(
                        finite().map(|(k, &v)| Circle::new((left(k) + width * 0.5, v), 6, color.stroke_width(2))),
                    )?;
                    if !label.is_empty() {
                        drawn.label(label).legend(move |(x, y)| Circle::new((x + 8, y), 6, color.stroke_width(2)));
                    }
                }
            }
        }
        if labelled {
            chart
                .configure_series_labels()
                .label_font(("sans-serif", 14))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

/// Quartiles, Tukey fences (the most extreme data within 1.5 IQR of the box) and mean of a
/// sample, for a box plot.
#[derive(Debug, Clone)]
pub struct BoxStats {
    pub label: String,
    pub color: RGBColor,
    pub lower_fence: f64,
    pub q1: f64,
    pub median: f64,
    pub q3: f64,
    pub upper_fence: f64,
    pub mean: f64,
}

impl BoxStats {
    /// `None` for an empty sample. Quartiles by linear interpolation between order statistics.
    pub fn of(label: impl Into<String>, color: RGBColor, values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| {
            let h = p * (v.len() - 1) as f64;
            let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
            v[lo] + (h - lo as f64) * (v[hi] - v[lo])
        };
        let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
        let iqr = q3 - q1;
        let lower_fence = v.iter().copied().find(|&x| x >= q1 - 1.5 * iqr).unwrap_or(q1);
        let upper_fence = v.iter().rev().copied().find(|&x| x <= q3 + 1.5 * iqr).unwrap_or(q3);
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        Some(Self { label: label.into(), color, lower_fence, q1, median, q3, upper_fence, mean })
    }
}

/// A box-plot panel; `markers` are (label, mean, std) drawn as a dot with a ±std bar, for
/// sources that give only those; `limit`, when finite, a dashed grey line across the panel (a
/// cap the values cannot pass, such as the box edge).
pub struct BoxPanel {
    pub title: String,
    pub y_label: String,
    pub boxes: Vec<BoxStats>,
    pub markers: Vec<(String, f64, f64)>,
    pub limit: f64,
}

/// Box-plot panels on a grid of `columns` (box: quartiles, red median line, whiskers to the
/// fences, blue dot at the mean, as in the paper's figure), written to `path` (PNG).
pub fn box_panels(
    path: &Path,
    title: &str,
    panels: &[BoxPanel],
    columns: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    register_font()?;
    let rows = panels.len().div_ceil(columns.max(1));
    let root = BitMapBackend::new(path, (560 * columns as u32, 460 * rows as u32 + 50)).into_drawing_area();
    root.fill(&WHITE)?;
    let (head, body) = root.split_vertically(50);
    head.titled(title, ("sans-serif", 22))?;
    let blue = RGBColor(20, 90, 200);
    for (panel, area) in panels.iter().zip(body.split_evenly((rows, columns))) {
        let labels: Vec<String> =
            panel.boxes.iter().map(|b| b.label.clone()).chain(panel.markers.iter().map(|m| m.0.clone())).collect();
        let top = panel
            .boxes
            .iter()
            .map(|b| b.upper_fence.max(b.mean))
            .chain(panel.markers.iter().map(|m| m.1 + m.2))
            .chain([panel.limit].into_iter().filter(|l| l.is_finite()))
            .fold(0.0_f64, f64::max);
        let n = labels.len();
        let mut chart = ChartBuilder::on(&area)
            .caption(&panel.title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, 0.0..top * 1.08 + 1e-300)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .y_desc(panel.y_label.as_str())
            .x_labels(n)
            .x_label_formatter(&|x| {
                let k = x.round();
                if (x - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < labels.len() {
                    labels[k as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()?;
        if panel.limit.is_finite() {
            let grey = RGBColor(110, 110, 110);
            let dashes = (0..2 * n).map(|k| {
                let x = -0.5 + k as f64 * 0.5;
                PathElement::new(vec![(x, panel.limit), (x + 0.3, panel.limit)], grey.stroke_width(2))
            });
            chart.draw_series(dashes)?;
        }
        for (k, b) in panel.boxes.iter().enumerate() {
            let x = k as f64;
            let color = b.color;
            chart.draw_series([
                Rectangle::new([(x - 0.25, b.q1), (x + 0.25, b.q3)], color.stroke_width(2)),
                Rectangle::new([(x - 0.25, b.median), (x + 0.25, b.median)], RGBColor(220, 0, 0).stroke_width(3)),
            ])?;
            chart.draw_series([
                PathElement::new(vec![(x, b.q3), (x, b.upper_fence)], BLACK.stroke_width(1)),
                PathElement::new(vec![(x, b.q1), (x, b.lower_fence)], BLACK.stroke_width(1)),
                PathElement::new(vec![(x - 0.1, b.upper_fence), (x + 0.1, b.upper_fence)], BLACK.stroke_width(1)),
                PathElement::new(vec![(x - 0.1, b.lower_fence), (x + 0.1, b.lower_fence)], BLACK.stroke_width(1)),
            ])?;
            chart.draw_series([Circle::new((x, b.mean), 5, blue.filled())])?;
        }
        for (k, (_, mean, std)) in panel.markers.iter().enumerate() {
            let x = (panel.boxes.len() + k) as f64;
            chart.draw_series([PathElement::new(
                vec![(x, (mean - std).max(0.0)), (x, mean + std)],
                BLACK.stroke_width(2),
            )])?;
            chart.draw_series([Circle::new((x, *mean), 5, blue.filled())])?;
        }
    }
    root.present()?;
    Ok(())
}
