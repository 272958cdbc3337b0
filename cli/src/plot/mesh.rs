//! Pictures of meshes: edges, boundary parts by tag with a legend, annotations.

use std::path::Path;

use plotters::prelude::*;

use super::{
    Canvas, Draw, LegendPosition, boxed_text, check_finite, font, palette, render, rgb, tick_label,
    titled, widen,
};
use gradvi::error::{Error, Result};
use gradvi::mesh::{PolyMesh, Rect};

/// Options of [`plot_mesh`].
#[derive(Debug, Clone)]
pub struct MeshPlotOptions {
    /// Title above the picture (empty: none).
    pub title: String,
    /// Output size in pixels (width, height). The drawing keeps an equal aspect ratio.
    pub size: (u32, u32),
    /// Legend labels of boundary tags, `(tag, label)`, e.g. `(1, "Γ1")`. Boundary edges with a
    /// nonzero tag are drawn thick in a colour per tag; tags without a label here are shown as
    /// "tag N".
    pub boundary_labels: Vec<(i32, String)>,
    /// Text annotations `([x, y], text)` centred at points, e.g. "A = 100 I".
    pub annotations: Vec<([f64; 2], String)>,
    /// Horizontal dashed reference lines y = c.
    pub hlines: Vec<f64>,
}

impl Default for MeshPlotOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            size: (700, 600),
            boundary_labels: Vec::new(),
            annotations: Vec::new(),
            hlines: Vec::new(),
        }
    }
}

/// Draws the mesh `mesh` in 2D (equal aspect ratio) into the PNG file `path`: all edges,
/// boundary edges coloured by tag with a legend, text annotations, dashed reference lines, axes
/// with ticks, and a title.
///
/// Errors: [`Error::InvalidData`] if the mesh is empty, an annotation or reference line is not
/// finite, or the path/size is unusable; [`Error::Io`] if the file cannot be written.
pub fn plot_mesh(path: &Path, mesh: &PolyMesh, opts: &MeshPlotOptions) -> Result<()> {
    if mesh.n_cells() == 0 {
        return Err(Error::InvalidData("cannot plot an empty mesh".into()));
    }
    for (p, _) in &opts.annotations {
        check_finite("annotation position", p)?;
    }
    check_finite("hlines", &opts.hlines)?;
    render(path, opts.size, |root, s| draw_mesh(root, s, mesh, opts))
}

fn draw_mesh(root: &Canvas, s: f64, mesh: &PolyMesh, opts: &MeshPlotOptions) -> Draw {
    let mut tags: Vec<i32> = (mesh.boundary_edges().iter())
        .map(|&e| mesh.edge_tag(e))
        .filter(|&t| t != 0)
        .collect();
    tags.sort_unstable();
    tags.dedup();
    let tag_style = |i: usize| rgb(palette(i + 1)).stroke_width((3.0 * s) as u32);
    let mut legend: Vec<(String, ShapeStyle)> = Vec::new();
    let mut legend_w = 0;
    for (i, &t) in tags.iter().enumerate() {
        let label = opts.boundary_labels.iter().find(|(x, _)| *x == t);
        let label = label.map_or_else(|| format!("tag {t}"), |l| l.1.clone());
        legend_w =
            legend_w.max(root.estimate_text_size(&label, &font(13.5, s))?.0 + (70.0 * s) as u32);
        legend.push((label, tag_style(i)));
    }
    let area = titled(root, &opts.title, s)?;
    let (area, right) = area.split_horizontally(area.dim_in_pixel().0 - legend_w);
    // equal aspect ratio: the plotting area is centred in what the tick labels leave
    let Rect {
        x: [x0, x1],
        y: [y0, y1],
    } = mesh.bounding_box();
    let ((x0, x1), (y0, y1)) = (widen(x0, x1), widen(y0, y1));
    let pad = 0.03 * (x1 - x0).max(y1 - y0);
    let ((x0, x1), (y0, y1)) = ((x0 - pad, x1 + pad), (y0 - pad, y1 + pad));
    let (w, h) = area.dim_in_pixel();
    let (left, bottom, m) = (55.0 * s, 45.0 * s, 10.0 * s);
    let (aw, ah) = (w as f64 - left - 2.0 * m, h as f64 - bottom - 2.0 * m);
    let k = (aw / (x1 - x0)).min(ah / (y1 - y0)).max(1e-9);
    let (mx, my) = ((aw - k * (x1 - x0)) / 2.0, (ah - k * (y1 - y0)) / 2.0);
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
        .axis_style(RGBColor(60, 60, 60).stroke_width(s as u32))
        .draw()?;
    let point = |v: usize| (mesh.vertex(v)[0], mesh.vertex(v)[1]);
    let edge = |e: usize, style: ShapeStyle| {
        let [a, b] = mesh.edge_vertices(e);
        PathElement::new(vec![point(a), point(b)], style)
    };
    let thin = RGBColor(30, 30, 30).stroke_width(1);
    chart.draw_series((0..mesh.n_edges()).map(|e| edge(e, thin)))?;
    for (i, &t) in tags.iter().enumerate() {
        let on_tag = (mesh.boundary_edges().iter()).filter(|&&e| mesh.edge_tag(e) == t);
        chart.draw_series(on_tag.map(|&e| edge(e, tag_style(i))))?;
    }
    let dashed = RGBColor(80, 80, 80).stroke_width((1.5 * s) as u32);
    let (dash, gap) = ((7.0 * s) as i32, (4.0 * s) as i32);
    for &y in opts.hlines.iter().filter(|&&y| y >= y0 && y <= y1) {
        chart.draw_series(DashedLineSeries::new([(x0, y), (x1, y)], dash, gap, dashed))?;
    }
    for (p, text) in opts.annotations.iter().filter(|a| !a.1.is_empty()) {
        boxed_text(root, chart.backend_coord(&(p[0], p[1])), text, s, false)?;
    }
    if !legend.is_empty() {
        legend_only(&right.margin((m + my) as u32, 0, 0, 0), s, legend)?;
    }
    Ok(())
}

/// A legend of line samples alone, at the top left of `area` (a chart without data).
fn legend_only(area: &Canvas, s: f64, entries: Vec<(String, ShapeStyle)>) -> Draw {
    let mut chart = ChartBuilder::on(area).build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
    for (label, style) in entries {
        let sample =
            move |(x, y)| PathElement::new(vec![(x, y), (x + (26.0 * s) as i32, y)], style);
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
            .label(label)
            .legend(sample);
    }
    chart
        .configure_series_labels()
        .position(LegendPosition::UpperLeft)
        .legend_area_size((34.0 * s) as i32)
        .margin((6.0 * s) as i32)
        .label_font(font(13.5, s))
        .background_style(WHITE)
        .border_style(RGBColor(150, 150, 150))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::surface::tests::grid;
    use super::super::tests::{invalid, png_size, tmp};
    use super::*;

    #[test]
    fn mesh_plot_with_tags_and_annotations() {
        let m = grid(5, false).with_boundary_tags(|p| match p {
            [_, y] if y > 1.0 - 1e-12 => 1,
            [_, y] if y < 1e-12 => 3,
            _ => 2,
        });
        let path = tmp("mesh.png");
        let opts = MeshPlotOptions {
            title: "mesh".into(),
            size: (240, 180),
            boundary_labels: vec![(1, "Γ1".into()), (2, "Γ2".into())],
            annotations: vec![([0.5, 0.25], "A = 100 I".into())],
            hlines: vec![0.5],
        };
        plot_mesh(&path, &m, &opts).expect("plot");
        assert_eq!(png_size(&path), (240, 180));
        let nan = MeshPlotOptions {
            hlines: vec![f64::NAN],
            ..opts
        };
        invalid(plot_mesh(&tmp("mesh_bad.png"), &m, &nan));
    }
}
