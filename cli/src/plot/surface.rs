//! The 3D view of a discrete solution: the graph of a piecewise affine function on polygonal
//! cells as triangles ([`vertex_surface`]), drawn in plotters' 3D chart back to front (the
//! painter's algorithm in plotters' own projection), coloured by value and shaded by a light.

use std::path::Path;

use plotters::coord::cartesian::Cartesian3d;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    Canvas, Draw, boxed_text, check_finite, font, min_max, render, rgb, tick_label, titled,
    viridis, widen,
};
use gradvi::error::{Error, Result};
use gradvi::mesh::{PolyMesh, Rect};

/// Options of [`plot_surface`].
#[derive(Debug, Clone)]
pub struct SurfaceOptions {
    /// Title above the picture (empty: none).
    pub title: String,
    /// Labels of the x, y and vertical axes.
    pub labels: [String; 3],
    /// Output size in pixels (width, height).
    pub size: (u32, u32),
    /// Viewing azimuth in degrees, as MATLAB's `view(az, el)`: 0 looks from −y towards +y,
    /// positive values turn the viewer counter-clockwise around the vertical axis.
    pub azimuth: f64,
    /// Viewing elevation in degrees above the (x, y) plane, as MATLAB's `view`.
    pub elevation: f64,
    /// Height of the plot box relative to its longer horizontal side.
    pub z_aspect: f64,
    /// Labelled points `([x, y, z], label)` drawn on top of the surface (e.g. the point where
    /// the contact condition switches).
    pub markers: Vec<([f64; 3], String)>,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            labels: ["x".into(), "y".into(), "u".into()],
            size: (900, 700),
            azimuth: -37.5,
            elevation: 30.0,
            z_aspect: 0.75,
            markers: Vec::new(),
        }
    }
}

/// The graph of a piecewise affine function on a polygonal mesh, as triangles: a triangle is
/// itself; any other cell is a fan of triangles from its centroid, at the mean of its vertex
/// values, to its sides.
pub struct Surface {
    /// Points `[x, y, value]`: the vertices, then the centroids of the non-triangular cells.
    pub points: Vec<[f64; 3]>,
    /// Point ids of each triangle, and a bit mask of its sides that are mesh edges (bit i: side
    /// i → i + 1).
    pub triangles: Vec<([usize; 3], u8)>,
}

/// The [`Surface`] of the function with the given vertex values.
pub fn vertex_surface(mesh: &PolyMesh, values: &[f64]) -> Surface {
    let vertices = mesh.vertices().iter().zip(values);
    let mut points: Vec<[f64; 3]> = vertices.map(|(p, &u)| [p[0], p[1], u]).collect();
    let mut triangles = Vec::new();
    for k in 0..mesh.n_cells() {
        let cv = mesh.cell_vertices(k);
        if let [a, b, c] = *cv {
            triangles.push(([a as usize, b as usize, c as usize], 0b111));
            continue;
        }
        let x = mesh.centroid(k);
        let z = cv.iter().map(|&v| values[v as usize]).sum::<f64>() / cv.len() as f64;
        points.push([x[0], x[1], z]);
        for i in 0..cv.len() {
            let (a, b) = (cv[i] as usize, cv[(i + 1) % cv.len()] as usize);
            triangles.push(([a, b, points.len() - 1], 1));
        }
    }
    Surface { points, triangles }
}

/// Draws a 3D view of the piecewise affine function with the given vertex values on `mesh` into
/// the PNG file `path`, in the spirit of MATLAB's `trisurf`: faces coloured by height (viridis)
/// and shaded by a light from the viewer's upper left, thin cell edges on meshes of fewer than
/// 3000 cells, hidden faces resolved by the painter's algorithm, plotters' 3D axes with a title
/// per axis, a colour bar, and labelled markers on top.
///
/// Errors: [`Error::InvalidData`] if `values` does not have one finite value per vertex, a
/// marker or the view is not finite, or the path/size is unusable; [`Error::Io`] if the file
/// cannot be written.
pub fn plot_surface(
    path: &Path,
    mesh: &PolyMesh,
    values: &[f64],
    opts: &SurfaceOptions,
) -> Result<()> {
    if mesh.n_cells() == 0 || values.len() != mesh.n_vertices() {
        return Err(Error::InvalidData(format!(
            "surface field has {} values but the mesh has {} vertices (and {} cells)",
            values.len(),
            mesh.n_vertices(),
            mesh.n_cells()
        )));
    }
    check_finite("surface field", values)?;
    for (p, _) in &opts.markers {
        check_finite("marker", p)?;
    }
    check_finite("view", &[opts.azimuth, opts.elevation, opts.z_aspect])?;
    if opts.z_aspect <= 0.0 {
        return Err(Error::InvalidData("z_aspect must be positive".into()));
    }
    let surface = vertex_surface(mesh, values);
    let Rect {
        x: [x0, x1],
        y: [y0, y1],
    } = mesh.bounding_box();
    let (z0, z1) = min_max(values.iter().copied());
    // plotters' coordinates are (y, u, x): its second axis is the vertical one, and this order
    // keeps the data axes right-handed
    let r = [widen(y0, y1), widen(z0, z1), widen(x0, x1)];
    let bounds = Bounds {
        lo: r.map(|r| r.0),
        hi: r.map(|r| r.1),
    };
    let n = mesh.n_cells();
    let edges = (n < 3000).then_some(if n < 300 { 2 } else { 1 });
    render(path, opts.size, |root, s| {
        let (main, bar) = root.split_horizontally(root.dim_in_pixel().0 - (105.0 * s) as u32);
        let main = titled(&main, &opts.title, s)?;
        let mut chart = ChartBuilder::on(&main)
            .margin((8.0 * s) as u32)
            .build_cartesian_3d(
                bounds.lo[0]..bounds.hi[0],
                bounds.lo[1]..bounds.hi[1],
                bounds.lo[2]..bounds.hi[2],
            )?;
        let view = fit_view(&mut chart, &bounds, opts, s);
        draw_axes(&mut chart, &view, s, &opts.labels)?;
        paint(&chart, &view, &surface, edges)?;
        for (p, text) in &opts.markers {
            let at = chart.plotting_area().map_coordinate(&(p[1], p[2], p[0]));
            let r = 5.5 * s;
            root.draw(&Circle::new(at, r as i32, BLACK.filled()))?;
            let red = RGBColor(215, 25, 28).filled();
            root.draw(&Circle::new(at, (r - 1.5 * s) as i32, red))?;
            if !text.is_empty() {
                boxed_text(root, at, text, s, true)?;
            }
        }
        colorbar(&bar, s, (bounds.lo[1], bounds.hi[1]))
    })
}

type Chart3<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian3d<RangedCoordf64, RangedCoordf64, RangedCoordf64>,
>;

/// The plot box in plotters' coordinates (y, u, x).
#[derive(Clone, Copy)]
struct Bounds {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Bounds {
    /// Corner `i`: bit j set → the upper end of axis j.
    fn corner(&self, i: usize) -> [f64; 3] {
        std::array::from_fn(|j| {
            if i & (1 << j) == 0 {
                self.lo[j]
            } else {
                self.hi[j]
            }
        })
    }
}

/// plotters' 3D projection of the box: its size in pixels and its matrix.
struct View {
    b: Bounds,
    size: [f64; 3],
    m: [[f64; 4]; 4],
}

impl View {
    /// plotters' 3D pixel coordinates (before projection) of a point.
    fn px(&self, p: [f64; 3]) -> [f64; 3] {
        let b = &self.b;
        std::array::from_fn(|i| (p[i] - b.lo[i]) / (b.hi[i] - b.lo[i]) * self.size[i])
    }
    /// Distance from the screen, growing away from the viewer (plotters' convention).
    fn depth(&self, p: [f64; 3]) -> f64 {
        let q = self.px(p);
        (0..3).map(|i| self.m[2][i] * q[i]).sum()
    }
}

fn tuple(p: [f64; 3]) -> (f64, f64, f64) {
    (p[0], p[1], p[2])
}

/// Sets plotters' projection to MATLAB's `view(az, el)` and the box size to the data
/// proportions, as large as the plotting area allows with room for labels around it.
fn fit_view(chart: &mut Chart3, b: &Bounds, opts: &SurfaceOptions, s: f64) -> View {
    let l = (b.hi[0] - b.lo[0]).max(b.hi[2] - b.lo[2]);
    let unit = [
        (b.hi[0] - b.lo[0]) / l,
        opts.z_aspect,
        (b.hi[2] - b.lo[2]) / l,
    ];
    let (yaw, pitch) = (
        (opts.azimuth - 90.0).to_radians(),
        opts.elevation.to_radians(),
    );
    let set = |chart: &mut Chart3, k: f64| {
        let size = unit.map(|u| (u * k).round().max(1.0));
        chart.set_3d_pixel_range((size[0] as i32, size[1] as i32, size[2] as i32));
        chart.with_projection(|mut p| {
            p.yaw = yaw;
            p.pitch = pitch;
            p.into_matrix()
        });
        size
    };
    set(chart, 400.0);
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let mid = ((xr.start + xr.end) / 2, (yr.start + yr.end) / 2);
    let (ex, ey) = (0..8).fold((1, 1), |(ex, ey), i| {
        let p = chart.as_coord_spec().translate(&tuple(b.corner(i)));
        (ex.max((p.0 - mid.0).abs()), ey.max((p.1 - mid.1).abs()))
    });
    let kx = ((xr.end - xr.start) as f64 / 2.0 - 80.0 * s) / ex as f64;
    let ky = ((yr.end - yr.start) as f64 / 2.0 - 45.0 * s) / ey as f64;
    let size = set(chart, 400.0 * kx.min(ky).max(0.05));
    let m = *chart.as_coord_spec().projection().as_ref();
    View { b: *b, size, m }
}

/// plotters' 3D axes (back panels, grid, ticks, labels) and a title per axis, beyond the tick
/// labels of the box edge plotters draws the axis on: of the four edges parallel to the axis,
/// the nearest but the front one, its ticks pointing sideways or downwards away from the
/// centre. The one tick label of the y axis at the front corner, where it would overlap the x
/// axis's, is left out.
fn draw_axes(chart: &mut Chart3, view: &View, s: f64, labels: &[String; 3]) -> Draw {
    let corners: Vec<[f64; 3]> = (0..8).map(|i| view.b.corner(i)).collect();
    let depth: Vec<f64> = corners.iter().map(|&c| view.depth(c)).collect();
    let front = (0..8)
        .min_by(|&a, &b| depth[a].total_cmp(&depth[b]))
        .unwrap_or(0);
    let (y_front, dy) = (corners[front][0], view.b.hi[0] - view.b.lo[0]);
    let fmt = |v: &f64| tick_label(*v);
    let fmt_y = |v: &f64| {
        let at_front = (v - y_front).abs() < 1e-9 * dy;
        if at_front {
            String::new()
        } else {
            tick_label(*v)
        }
    };
    chart
        .configure_axes()
        .label_style(font(12.5, s))
        .tick_size((5.0 * s) as i32)
        .x_labels(6)
        .y_labels(6)
        .z_labels(6)
        .max_light_lines(1)
        .axis_panel_style(RGBColor(247, 247, 247).filled())
        .bold_grid_style(RGBColor(215, 215, 215).stroke_width(s as u32))
        .x_formatter(&fmt_y)
        .y_formatter(&fmt)
        .z_formatter(&fmt)
        .draw()?;
    let px: Vec<(f64, f64)> = (corners.iter())
        .map(|&c| chart.as_coord_spec().translate(&tuple(c)))
        .map(|(x, y)| (x as f64, y as f64))
        .collect();
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let mid = (
        (xr.start + xr.end) as f64 / 2.0,
        (yr.start + yr.end) as f64 / 2.0,
    );
    let style = font(15.0, s).pos(Pos::new(HPos::Center, VPos::Center));
    let area = chart.plotting_area().strip_coord_spec();
    // data x, y and u are plotters' axes 2, 0 and 1
    for (label, bit) in labels.iter().zip([4, 1, 2]) {
        let mut edges: Vec<usize> = (0..8).filter(|i| i & bit == 0).collect();
        let edge_depth = |i: &usize| depth[*i] + depth[*i | bit];
        edges.sort_by(|a, b| edge_depth(a).total_cmp(&edge_depth(b)));
        let (a, b) = (px[edges[1]], px[edges[1] | bit]);
        let (dx, dy) = if (b.0 - a.0).abs() < (b.1 - a.1).abs() {
            (if a.0 < mid.0 { -62.0 } else { 62.0 }, 0.0)
        } else {
            (0.0, if a.1 < mid.1 { -38.0 } else { 38.0 })
        };
        let at = ((a.0 + b.0) / 2.0 + dx * s, (a.1 + b.1) / 2.0 + dy * s);
        let at = (at.0 as i32 - xr.start, at.1 as i32 - yr.start);
        area.draw(&Text::new(label.clone(), at, style.clone()))?;
    }
    Ok(())
}

/// The painter's algorithm: the triangles from the farthest to the nearest, each coloured by
/// its mean value and shaded by a light from the viewer's upper left, with its mesh edges
/// (`edge_width` pixels of the supersampled canvas; `None`: no edges).
fn paint(chart: &Chart3, view: &View, surface: &Surface, edge_width: Option<u32>) -> Draw {
    let points: Vec<[f64; 3]> = surface.points.iter().map(|p| [p[1], p[2], p[0]]).collect();
    let px: Vec<[f64; 3]> = points.iter().map(|&p| view.px(p)).collect();
    let depth: Vec<f64> = points.iter().map(|&p| view.depth(p)).collect();
    let mut order: Vec<(f64, usize)> = (surface.triangles.iter().enumerate())
        .map(|(i, (t, _))| (t.iter().map(|&j| depth[j]).sum(), i))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let m = &view.m;
    let light: [f64; 3] = std::array::from_fn(|i| -m[2][i] - 0.6 * m[1][i] - 0.4 * m[0][i]);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (z0, z1) = (view.b.lo[1], view.b.hi[1]);
    let edge_style = RGBColor(35, 35, 35).stroke_width(edge_width.unwrap_or(1));
    let area = chart.plotting_area();
    for &(_, i) in &order {
        let (t, mask) = surface.triangles[i];
        let [a, b, c] = t.map(|j| px[j]);
        let (u, v) = (
            [0, 1, 2].map(|i| b[i] - a[i]),
            [0, 1, 2].map(|i| c[i] - a[i]),
        );
        let n: [f64; 3] = std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            u[j] * v[k] - u[k] * v[j]
        });
        let cos = dot(n, light) / (dot(n, n) * dot(light, light)).sqrt();
        let shade = if cos.is_finite() {
            0.65 + 0.35 * cos.abs()
        } else {
            1.0
        };
        let mean = t.iter().map(|&j| points[j][1]).sum::<f64>() / 3.0;
        let colour = viridis((mean - z0) / (z1 - z0)).map(|c| (c as f64 * shade).round() as u8);
        let tri: Vec<(f64, f64, f64)> = t.iter().map(|&j| tuple(points[j])).collect();
        area.draw(&Polygon::new(tri.clone(), rgb(colour).filled()))?;
        for side in (0..3).filter(|i| edge_width.is_some() && mask & (1 << i) != 0) {
            let ends = vec![tri[side], tri[(side + 1) % 3]];
            area.draw(&PathElement::new(ends, edge_style))?;
        }
    }
    Ok(())
}

/// A vertical colour bar of viridis over `range`, with plotters' ticks on its right.
fn colorbar(area: &Canvas, s: f64, (lo, hi): (f64, f64)) -> Draw {
    let h = area.dim_in_pixel().1 as f64;
    let mut chart = ChartBuilder::on(area)
        .margin_top((0.14 * h) as u32)
        .margin_bottom((0.12 * h) as u32)
        .margin_left((12.0 * s) as u32)
        .set_label_area_size(LabelAreaPosition::Right, (70.0 * s) as u32)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    let n = 256;
    chart.draw_series((0..n).map(|i| {
        let (a, b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
        let c = rgb(viridis((a + b) / 2.0)).filled();
        Rectangle::new([(0.0, lo + a * (hi - lo)), (1.0, lo + b * (hi - lo))], c)
    }))?;
    let fmt = |v: &f64| tick_label(*v);
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(7)
        .y_label_formatter(&fmt)
        .label_style(font(12.5, s))
        .axis_style(RGBColor(60, 60, 60).stroke_width(s as u32))
        .draw()?;
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::tests::{invalid, png_size, tmp};
    use super::*;

    /// A unit square of n × n quadrilaterals, or of 2n² triangles.
    pub(in crate::plot) fn grid(n: usize, triangles: bool) -> PolyMesh {
        let v = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| [i as f64 / n as f64, j as f64 / n as f64]))
            .collect();
        let mut c = Vec::new();
        for a in (0..n).flat_map(|j| (0..n).map(move |i| j * (n + 1) + i)) {
            let (b, cc, d) = (a + 1, a + n + 2, a + n + 1);
            if triangles {
                c.extend([vec![a, b, cc], vec![a, cc, d]]);
            } else {
                c.push(vec![a, b, cc, d]);
            }
        }
        PolyMesh::from_cells(v, c).expect("valid grid")
    }

    fn bump(p: [f64; 2]) -> f64 {
        (std::f64::consts::PI * p[0]).sin() * (std::f64::consts::PI * p[1]).sin() - 0.5
    }

    fn small() -> SurfaceOptions {
        SurfaceOptions {
            title: "test".into(),
            size: (200, 150),
            markers: vec![([0.5, 0.0, -0.5], "switch".into())],
            ..Default::default()
        }
    }

    #[test]
    fn a_polygon_is_a_fan_from_its_centroid_at_the_mean_value() {
        let s = vertex_surface(&grid(1, false), &[0.0, 1.0, 2.0, 3.0]);
        assert_eq!(s.points.len(), 5);
        assert_eq!(s.points[4], [0.5, 0.5, 1.5]);
        assert_eq!(s.triangles.len(), 4);
        assert!(s.triangles.iter().all(|(t, mask)| t[2] == 4 && *mask == 1));
        let t = vertex_surface(&grid(1, true), &[0.0; 4]);
        assert_eq!((t.points.len(), t.triangles[0].1), (4, 0b111));
    }

    #[test]
    fn surfaces_write_deterministic_pngs_of_the_requested_size() {
        for (name, m) in [("tri.png", grid(5, true)), ("quad.png", grid(4, false))] {
            let u: Vec<f64> = m.vertices().iter().map(|&p| bump(p)).collect();
            let (a, b) = (tmp(&format!("a_{name}")), tmp(&format!("b_{name}")));
            plot_surface(&a, &m, &u, &small()).expect("plot");
            plot_surface(&b, &m, &u, &small()).expect("plot");
            assert_eq!(png_size(&a), (200, 150));
            assert_eq!(std::fs::read(&a).ok(), std::fs::read(&b).ok());
        }
        // constant data, a view from below
        let m = grid(3, false);
        let opts = SurfaceOptions {
            azimuth: 120.0,
            elevation: -20.0,
            ..small()
        };
        let flat = vec![1.0; m.n_vertices()];
        plot_surface(&tmp("flat.png"), &m, &flat, &opts).expect("plot");
    }

    #[test]
    fn bad_surface_input_is_invalid_data() {
        let m = grid(3, false);
        let path = tmp("surface_bad.png");
        let u = vec![0.0; m.n_vertices()];
        invalid(plot_surface(&path, &m, &u[1..], &small()));
        let mut nan = u.clone();
        nan[4] = f64::NAN;
        invalid(plot_surface(&path, &m, &nan, &small()));
        let opts = SurfaceOptions {
            markers: vec![([0.0, f64::INFINITY, 0.0], "m".into())],
            ..small()
        };
        invalid(plot_surface(&path, &m, &u, &opts));
        assert!(!path.exists());
    }
}
