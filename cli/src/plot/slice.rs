//! A planar section of a 3D cell field: the polygons where the plane z = c cuts the cells,
//! filled by value ([`viridis`](super::viridis)), with marked cells outlined and, optionally, a
//! curve drawn over them.

use std::path::Path;

use plotters::prelude::*;

use super::{Canvas, Draw, check_finite, font, min_max, rgb, tick_label, titled, viridis, widen};
use gradvi::error::{Error, Result};

/// One cut cell of [`plot_slice`]: its polygon in the plane (x, y), its value, and whether it
/// is marked.
#[derive(Debug, Clone)]
pub struct SliceCell {
    /// The vertices of the section, in order around it.
    pub polygon: Vec<[f64; 2]>,
    /// The value the cell is coloured by.
    pub value: f64,
    /// Outlined (e.g. an active cell).
    pub marked: bool,
}

/// Options of [`plot_slice`].
#[derive(Debug, Clone)]
pub struct SliceOptions {
    /// Title above the picture.
    pub title: String,
    /// Output size in pixels.
    pub size: (u32, u32),
    /// What the value is (the label of the colour bar).
    pub value_label: String,
    /// The legend of the marked cells.
    pub marked_label: String,
    /// A curve drawn over the cells (e.g. the exact free boundary): its legend and its
    /// pieces, each a polyline.
    pub curve: Option<(String, Vec<Vec<[f64; 2]>>)>,
}

/// Draws the cut cells `cells` into the PNG file `path` with an equal aspect ratio, a colour
/// bar and a legend of the marked cells.
///
/// Errors: [`Error::InvalidData`] if there is no cell or a coordinate or value is not finite.
pub fn plot_slice(path: &Path, cells: &[SliceCell], opts: &SliceOptions) -> Result<()> {
    if cells.is_empty() {
        return Err(Error::InvalidData("a slice without cells".into()));
    }
    for p in opts.curve.iter().flat_map(|c| c.1.iter().flatten()) {
        check_finite("slice curve", p)?;
    }
    for c in cells {
        check_finite("slice value", &[c.value])?;
        for p in &c.polygon {
            check_finite("slice polygon", p)?;
        }
    }
    render(path, opts, cells)
}

fn render(path: &Path, opts: &SliceOptions, cells: &[SliceCell]) -> Result<()> {
    super::render(path, opts.size, |root, s| draw(root, s, cells, opts))
}

fn draw(root: &Canvas, s: f64, cells: &[SliceCell], opts: &SliceOptions) -> Draw {
    let area = titled(root, &opts.title, s)?;
    let (w, _) = area.dim_in_pixel();
    let (area, bar) = area.split_horizontally(w - (110.0 * s) as u32);
    let points = || cells.iter().flat_map(|c| c.polygon.iter());
    let (x0, x1) = widen_pair(min_max(points().map(|p| p[0])));
    let (y0, y1) = widen_pair(min_max(points().map(|p| p[1])));
    let (vmin, vmax) = min_max(cells.iter().map(|c| c.value));
    let (vmin, vmax) = widen(vmin, vmax);
    let (aw, ah) = area.dim_in_pixel();
    let (left, bottom, m) = (55.0 * s, 45.0 * s, 10.0 * s);
    let (pw, ph) = (aw as f64 - left - 2.0 * m, ah as f64 - bottom - 2.0 * m);
    let k = (pw / (x1 - x0)).min(ph / (y1 - y0)).max(1e-9);
    let (mx, my) = ((pw - k * (x1 - x0)) / 2.0, (ph - k * (y1 - y0)) / 2.0);
    let mut chart = ChartBuilder::on(&area)
        .margin_left((m + mx) as u32)
        .margin_right((m + mx) as u32)
        .margin_top((m + my) as u32)
        .margin_bottom((m + my) as u32)
        .x_label_area_size(bottom as u32)
        .y_label_area_size(left as u32)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let fmt = |v: &f64| tick_label(*v);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x")
        .y_desc("y")
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .label_style(font(12.5, s))
        .axis_desc_style(font(15.0, s))
        .draw()?;
    let colour = |v: f64| rgb(viridis((v - vmin) / (vmax - vmin)));
    let poly = |c: &SliceCell| c.polygon.iter().map(|p| (p[0], p[1])).collect::<Vec<_>>();
    chart.draw_series(
        cells
            .iter()
            .map(|c| Polygon::new(poly(c), colour(c.value).filled())),
    )?;
    let edge = RGBColor(60, 60, 60).stroke_width(1);
    let mark = RGBColor(230, 20, 20).stroke_width((2.0 * s) as u32);
    let closed = |c: &SliceCell| {
        let mut p = poly(c);
        p.push(p[0]);
        p
    };
    chart.draw_series(cells.iter().map(|c| PathElement::new(closed(c), edge)))?;
    chart
        .draw_series(
            (cells.iter().filter(|c| c.marked)).map(|c| PathElement::new(closed(c), mark)),
        )?
        .label(opts.marked_label.as_str())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], mark));
    if let Some((label, pieces)) = &opts.curve {
        // black on a white halo: visible on every colour of the map and on the red outlines
        let (halo, line) = (
            WHITE.stroke_width((4.5 * s) as u32),
            BLACK.stroke_width((2.0 * s) as u32),
        );
        let path = |p: &Vec<[f64; 2]>| p.iter().map(|q| (q[0], q[1])).collect::<Vec<_>>();
        chart.draw_series(pieces.iter().map(|p| PathElement::new(path(p), halo)))?;
        chart
            .draw_series(pieces.iter().map(|p| PathElement::new(path(p), line)))?
            .label(label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line));
    }
    chart
        .configure_series_labels()
        .position(super::LegendPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(font(13.0, s))
        .draw()?;
    colour_bar(&bar, s, (vmin, vmax), &opts.value_label)
}

fn widen_pair((lo, hi): (f64, f64)) -> (f64, f64) {
    let (lo, hi) = widen(lo, hi);
    let pad = 0.02 * (hi - lo);
    (lo - pad, hi + pad)
}

/// A vertical colour bar from `lo` (bottom) to `hi` (top) with five labels.
fn colour_bar(area: &Canvas, s: f64, (lo, hi): (f64, f64), label: &str) -> Draw {
    let (_, h) = area.dim_in_pixel();
    let (x0, x1) = ((10.0 * s) as i32, (30.0 * s) as i32);
    let (top, bottom) = ((40.0 * s) as i32, h as i32 - (60.0 * s) as i32);
    let steps = 100;
    for i in 0..steps {
        let t = i as f64 / steps as f64;
        let ya = bottom - ((bottom - top) as f64 * t) as i32;
        let yb = bottom - ((bottom - top) as f64 * (t + 1.0 / steps as f64)) as i32;
        area.draw(&Rectangle::new(
            [(x0, yb), (x1, ya)],
            rgb(viridis(t)).filled(),
        ))?;
    }
    area.draw(&Text::new(
        label.to_string(),
        (x0, top - (25.0 * s) as i32),
        font(14.0, s),
    ))?;
    for i in 0..=4 {
        let t = i as f64 / 4.0;
        let y = bottom - ((bottom - top) as f64 * t) as i32;
        let v = lo + t * (hi - lo);
        let text = tick_label((v * 1e4).round() / 1e4);
        area.draw(&Text::new(
            text,
            (x1 + (5.0 * s) as i32, y - (7.0 * s) as i32),
            font(12.0, s),
        ))?;
    }
    Ok(())
}
