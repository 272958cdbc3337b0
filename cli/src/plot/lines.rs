//! x–y line plots on linear or logarithmic axes, alone or as small multiples.

use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::series::LineSeries as Polyline;

use super::{
    Canvas, Draw, LegendPosition, font, log_tick_label, min_max, palette, render, rgb, tick_label,
    titled, widen,
};
use gradvi::error::{Error, Result};

/// Marker drawn at the data points of a [`LineSeries`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Marker {
    /// Chosen from the series index (circle, square, triangle, diamond, cross, …).
    #[default]
    Auto,
    /// No markers.
    None,
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Cross (×).
    Cross,
}

impl Marker {
    /// The outline of the marker of series `i` with radius `r` around (0, 0), in pixels (y
    /// down); a cross is the 12-gon of a plus sign turned by 45°.
    fn shape(self, i: usize, r: i32) -> Vec<(i32, i32)> {
        use Marker::*;
        let m = if self == Auto {
            [Circle, Square, Triangle, Diamond, Cross][i % 5]
        } else {
            self
        };
        let t = 0.28;
        let plus = [(t, -1.0), (t, -t), (1.0, -t), (1.0, t), (t, t), (t, 1.0)];
        let unit: Vec<(f64, f64)> = match m {
            Auto | None => Vec::new(),
            Circle => (0..24)
                .map(|i| (i as f64 * std::f64::consts::PI / 12.0).sin_cos())
                .collect(),
            Square => vec![(-0.85, -0.85), (0.85, -0.85), (0.85, 0.85), (-0.85, 0.85)],
            Triangle => vec![(0.0, -1.2), (1.05, 0.65), (-1.05, 0.65)],
            Diamond => vec![(0.0, -1.25), (1.0, 0.0), (0.0, 1.25), (-1.0, 0.0)],
            Cross => (plus.iter().chain(&plus.map(|(x, y)| (-x, -y))))
                .map(|&(x, y)| ((x - y) * 0.75, (x + y) * 0.75))
                .collect(),
        };
        let r = r as f64;
        let px = |(x, y): (f64, f64)| ((x * r).round() as i32, (y * r).round() as i32);
        unit.into_iter().map(px).collect()
    }
}

/// One labelled series of [`plot_lines`].
#[derive(Debug, Clone)]
pub struct LineSeries {
    /// Legend label (empty: not in the legend).
    pub label: String,
    /// Points `[x, y]`, drawn joined in the given order.
    pub points: Vec<[f64; 2]>,
    /// Line colour; `None`: from [`palette`](super::palette) by series index.
    pub color: Option<[u8; 3]>,
    /// Marker at the data points.
    pub marker: Marker,
    /// Draw the line dashed (e.g. a reference slope).
    pub dashed: bool,
}

impl LineSeries {
    /// A solid series with automatic colour and marker.
    pub fn new(label: impl Into<String>, points: Vec<[f64; 2]>) -> Self {
        Self {
            label: label.into(),
            points,
            color: None,
            marker: Marker::Auto,
            dashed: false,
        }
    }
}

/// Options of [`plot_lines`] and of each panel of [`plot_panels`].
#[derive(Debug, Clone)]
pub struct LineOptions {
    /// Title above the chart (empty: none).
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Output size in pixels (width, height); [`plot_panels`] ignores it.
    pub size: (u32, u32),
    /// Logarithmic x axis (all x must be > 0).
    pub log_x: bool,
    /// Logarithmic y axis (all y must be > 0).
    pub log_y: bool,
    /// Legend placement; `None`: no legend.
    pub legend: Option<LegendPosition>,
    /// The x range shown; `None`: the data range with a margin.
    pub x_range: Option<(f64, f64)>,
    /// The y range shown; `None`: the data range with a margin.
    pub y_range: Option<(f64, f64)>,
}

impl LineOptions {
    /// Log–log axes with a legend in the upper left (time against size).
    pub fn log_log(title: impl Into<String>, x_label: &str, y_label: &str) -> Self {
        LineOptions {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: true,
            legend: Some(LegendPosition::UpperLeft),
            ..Default::default()
        }
    }
}

impl Default for LineOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_label: "x".into(),
            y_label: "y".into(),
            size: (800, 600),
            log_x: false,
            log_y: false,
            legend: Some(LegendPosition::UpperLeft),
            x_range: None,
            y_range: None,
        }
    }
}

/// The range of the series' coordinate `i` with a 5 % margin (of decades on a log axis).
pub fn data_range(series: &[LineSeries], i: usize, log: bool) -> (f64, f64) {
    let (lo, hi) = min_max(series.iter().flat_map(|s| s.points.iter().map(|p| p[i])));
    let (a, b) = if log {
        widen(lo.log10(), hi.log10())
    } else {
        widen(lo, hi)
    };
    let m = 0.05 * (b - a);
    let inv = |x: f64| if log { 10f64.powf(x) } else { x };
    (inv(a - m), inv(b + m))
}

fn check_series(series: &[LineSeries], opts: &LineOptions) -> Result<()> {
    let bad = |why: String| Err(Error::InvalidData(format!("plot_lines: {why}")));
    if series.is_empty() {
        return bad("no series".into());
    }
    for (i, sr) in series.iter().enumerate() {
        let off_axis = |p: &[f64; 2]| (opts.log_x && p[0] <= 0.0) || (opts.log_y && p[1] <= 0.0);
        let wrong = sr
            .points
            .iter()
            .find(|p| !(p[0].is_finite() && p[1].is_finite()) || off_axis(p));
        if let Some(p) = wrong {
            return bad(format!(
                "series {i} (\"{}\") has the point {p:?}, which cannot be drawn",
                sr.label
            ));
        }
        if sr.points.is_empty() {
            return bad(format!("series {i} (\"{}\") has no point", sr.label));
        }
    }
    for (r, log) in [(opts.x_range, opts.log_x), (opts.y_range, opts.log_y)] {
        if let Some((a, b)) =
            r.filter(|&(a, b)| !(a.is_finite() && b.is_finite() && a < b && (!log || a > 0.0)))
        {
            return bad(format!("the axis range ({a}, {b}) cannot be drawn"));
        }
    }
    Ok(())
}

/// Draws the x–y plot of `series` (linear or logarithmic axes) into the PNG file `path`: one
/// coloured line per series with markers, a legend of the labelled series, axis labels, a grid
/// and a title.
///
/// Errors: [`Error::InvalidData`] if there is no series, a series has no point, a coordinate is
/// not finite, a coordinate on a log axis is not positive, a given range is empty, or the
/// path/size is unusable; [`Error::Io`] if the file cannot be written.
pub fn plot_lines(path: &Path, series: &[LineSeries], opts: &LineOptions) -> Result<()> {
    check_series(series, opts)?;
    render(path, opts.size, |root, s| draw_lines(root, s, series, opts))
}

/// Small multiples: the charts `panels` (series and options, as for [`plot_lines`]) on a grid of
/// `cols` columns under a common `title`, in one PNG file of `size` pixels.
pub fn plot_panels(
    path: &Path,
    title: &str,
    size: (u32, u32),
    cols: usize,
    panels: &[(Vec<LineSeries>, LineOptions)],
) -> Result<()> {
    if panels.is_empty() || cols == 0 {
        return Err(Error::InvalidData("plot_panels: no panel".into()));
    }
    for (series, opts) in panels {
        check_series(series, opts)?;
    }
    render(path, size, |root, s| {
        let root = titled(root, title, s)?;
        let rows = panels.len().div_ceil(cols);
        for (area, (series, opts)) in root.split_evenly((rows, cols)).iter().zip(panels) {
            draw_lines(area, s, series, opts)?;
        }
        Ok(())
    })
}

fn draw_lines(area: &Canvas, s: f64, series: &[LineSeries], opts: &LineOptions) -> Draw {
    let x = opts
        .x_range
        .unwrap_or_else(|| data_range(series, 0, opts.log_x));
    let y = opts
        .y_range
        .unwrap_or_else(|| data_range(series, 1, opts.log_y));
    let (x, y) = (x.0..x.1, y.0..y.1);
    match (opts.log_x, opts.log_y) {
        (false, false) => chart_lines(area, s, series, opts, x, y),
        (true, false) => chart_lines(area, s, series, opts, x.log_scale(), y),
        (false, true) => chart_lines(area, s, series, opts, x, y.log_scale()),
        (true, true) => chart_lines(area, s, series, opts, x.log_scale(), y.log_scale()),
    }
}

/// One chart of lines on the axes `x` and `y` (linear or logarithmic ranges).
fn chart_lines<X, Y>(
    area: &Canvas,
    s: f64,
    series: &[LineSeries],
    opts: &LineOptions,
    x: X,
    y: Y,
) -> Draw
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut builder = ChartBuilder::on(area);
    if !opts.title.is_empty() {
        builder.caption(&opts.title, font(16.0, s));
    }
    let mut chart = builder
        .margin((12.0 * s) as u32)
        .x_label_area_size((42.0 * s) as u32)
        .y_label_area_size((58.0 * s) as u32)
        .build_cartesian_2d(x, y)?;
    // on log axes plotters ticks every mantissa; the labels keep 1, 2 and 5
    let label = |log: bool| if log { log_tick_label } else { tick_label };
    let (fx, fy) = (label(opts.log_x), label(opts.log_y));
    let (fx, fy) = (|v: &f64| fx(*v), |v: &f64| fy(*v));
    chart
        .configure_mesh()
        .x_labels(if opts.log_x { 20 } else { 8 })
        .y_labels(if opts.log_y { 20 } else { 8 })
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_desc(opts.x_label.as_str())
        .y_desc(opts.y_label.as_str())
        .label_style(font(13.0, s))
        .axis_desc_style(font(15.0, s))
        .bold_line_style(RGBColor(222, 222, 222).stroke_width(s as u32))
        .light_line_style(TRANSPARENT)
        .axis_style(RGBColor(60, 60, 60).stroke_width(s as u32))
        .draw()?;
    let (dash, gap) = ((8.0 * s) as i32, (5.0 * s) as i32);
    for (i, sr) in series.iter().enumerate() {
        let color = rgb(sr.color.unwrap_or(palette(i)));
        let style = color.stroke_width((2.0 * s) as u32);
        let pts: Vec<(f64, f64)> = sr.points.iter().map(|p| (p[0], p[1])).collect();
        if sr.dashed {
            chart.draw_series(DashedLineSeries::new(pts.clone(), dash, gap, style))?;
        } else {
            chart.draw_series(Polyline::new(pts.clone(), style))?;
        }
        let shape = sr.marker.shape(i, (4.5 * s) as i32);
        let mark = |at| EmptyElement::at(at) + Polygon::new(shape.clone(), color.filled());
        let anno = chart.draw_series(pts.into_iter().map(mark))?;
        if sr.label.is_empty() {
            continue;
        }
        // the legend sample: the line, dashed or not, in three pieces, and the marker
        let pieces = if sr.dashed {
            [(0.0, 8.0), (13.0, 21.0), (26.0, 34.0)]
        } else {
            [(0.0, 12.0), (11.0, 23.0), (22.0, 34.0)]
        };
        let shape: Vec<(i32, i32)> = (shape.iter())
            .map(|&(x, y)| (x + (17.0 * s) as i32, y))
            .collect();
        anno.label(sr.label.as_str()).legend(move |(x, y)| {
            let seg = |(a, b): (f64, f64)| {
                PathElement::new(vec![((a * s) as i32, 0), ((b * s) as i32, 0)], style)
            };
            let [p, q, r] = pieces.map(seg);
            EmptyElement::at((x, y)) + p + q + r + Polygon::new(shape.clone(), color.filled())
        });
    }
    if let Some(position) = opts.legend.clone() {
        chart
            .configure_series_labels()
            .position(position)
            .legend_area_size((40.0 * s) as i32)
            .margin((8.0 * s) as i32)
            .label_font(font(13.0, s))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(170, 170, 170))
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::tests::{invalid, png_size, tmp};
    use super::*;

    #[test]
    fn line_plots_and_panels() {
        let h = [0.24, 0.13, 0.07, 0.03];
        let e1: Vec<[f64; 2]> = h.iter().map(|&h| [h, 2.0 * h * h]).collect();
        let e2: Vec<[f64; 2]> = h.iter().map(|&h| [h, 0.8 * h]).collect();
        let slope = LineSeries {
            dashed: true,
            marker: Marker::None,
            ..LineSeries::new("O(h)", h.iter().map(|&h| [h, h]).collect())
        };
        let series = vec![LineSeries::new("L2", e1), LineSeries::new("H1", e2), slope];
        let log = LineOptions {
            title: "convergence".into(),
            size: (260, 200),
            log_x: true,
            log_y: true,
            ..Default::default()
        };
        let path = tmp("lines.png");
        plot_lines(&path, &series, &log).expect("plot");
        assert_eq!(png_size(&path), (260, 200));
        let one = vec![LineSeries::new("single point", vec![[1.0, 1.0]])];
        let lin = LineOptions {
            legend: None,
            ..LineOptions::default()
        };
        plot_lines(&path, &one, &lin).expect("plot");
        let panels = [(series, log), (one, lin)];
        plot_panels(&path, "two panels", (400, 200), 2, &panels).expect("plot");
        assert_eq!(png_size(&path), (400, 200));
        assert_eq!(Marker::Auto.shape(0, 4), Marker::Circle.shape(0, 4));
        assert_eq!(Marker::Cross.shape(0, 4).len(), 12);
    }

    #[test]
    fn line_plot_rejects_bad_input() {
        let path = tmp("lines_bad.png");
        let opts = LineOptions::default();
        invalid(plot_lines(&path, &[], &opts));
        invalid(plot_lines(
            &path,
            &[LineSeries::new("empty", vec![])],
            &opts,
        ));
        let nan = [LineSeries::new("nan", vec![[0.0, 1.0], [1.0, f64::NAN]])];
        invalid(plot_lines(&path, &nan, &opts));
        let neg = [LineSeries::new("neg", vec![[1.0, 1.0], [2.0, -1.0]])];
        let log = LineOptions {
            log_y: true,
            ..Default::default()
        };
        invalid(plot_lines(&path, &neg, &log));
        let empty_range = LineOptions {
            x_range: Some((1.0, 1.0)),
            ..Default::default()
        };
        let ok = [LineSeries::new("ok", vec![[1.0, 1.0]])];
        invalid(plot_lines(&path, &ok, &empty_range));
        invalid(plot_panels(&path, "none", (100, 100), 1, &[]));
    }
}
