//! PNG figures: 3D surface plots of discrete solutions ([`plot_surface`]), mesh pictures
//! ([`plot_mesh`]) and x–y line plots such as convergence curves ([`plot_lines`]).
//!
//! All three functions
//! * write a PNG file (the path must end in `.png`), creating missing parent directories;
//! * are deterministic: the same input gives the same bytes;
//! * validate their input and report problems as [`Error::InvalidData`] (wrong field length,
//!   NaN, empty series, non-positive data on a log axis, …) and I/O failures as [`Error::Io`];
//!   they never panic on user input;
//! * render at `supersample`× the requested resolution and box-filter down, which anti-aliases
//!   polygon edges and lines.
//!
//! Surfaces and meshes are rasterised by a small built-in scan-line rasteriser (exact
//! pixel-centre coverage, so adjacent polygons leave no seams and the painter's algorithm is
//! cheap); text is drawn by `plotters` with the DejaVu Sans font embedded in the binary
//! (`assets/fonts`, Bitstream Vera licence), so nothing has to be installed on the machine.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use gradvi::error::{Error, Result};
use gradvi::mesh::PolyMesh;

// ---------------------------------------------------------------------------------------------
// Font
// ---------------------------------------------------------------------------------------------

/// DejaVu Sans (Bitstream Vera licence, see `assets/fonts/LICENSE-DejaVu.txt`).
static FONT_BYTES: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/fonts/DejaVuSans.ttf"
));

/// Family name under which the embedded font is registered.
const FONT: &str = "sans-serif";

/// Registers the embedded font with plotters exactly once.
fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        let a = plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok();
        let b =
            plotters::style::register_font("DejaVu Sans", FontStyle::Normal, FONT_BYTES).is_ok();
        a && b
    });
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidData(
            "the embedded plotting font could not be loaded".into(),
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Colour maps
// ---------------------------------------------------------------------------------------------

/// A perceptual colour map used to colour values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Colormap {
    /// matplotlib's viridis (dark blue → green → yellow).
    #[default]
    Viridis,
    /// A close approximation of MATLAB's parula (blue → teal → yellow).
    Parula,
    /// Light to dark grey (for print).
    Gray,
}

const VIRIDIS: [[u8; 3]; 11] = [
    [68, 1, 84],
    [72, 36, 117],
    [65, 68, 135],
    [53, 95, 141],
    [42, 120, 142],
    [33, 145, 140],
    [34, 168, 132],
    [68, 191, 112],
    [122, 209, 81],
    [189, 223, 38],
    [253, 231, 37],
];

const PARULA: [[u8; 3]; 9] = [
    [62, 38, 168],
    [72, 82, 244],
    [39, 150, 235],
    [16, 177, 207],
    [22, 189, 175],
    [100, 205, 111],
    [203, 194, 44],
    [252, 198, 52],
    [249, 251, 21],
];

impl Colormap {
    /// Colour at `t` ∈ [0, 1] (clamped; NaN maps to 0).
    pub fn rgb(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let table: &[[u8; 3]] = match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Parula => &PARULA,
            Colormap::Gray => &[[235, 235, 235], [40, 40, 40]],
        };
        let x = t * (table.len() - 1) as f64;
        let i = (x.floor() as usize).min(table.len() - 2);
        let f = x - i as f64;
        let mut c = [0u8; 3];
        for (ch, out) in c.iter_mut().enumerate() {
            let a = table[i][ch] as f64;
            let b = table[i + 1][ch] as f64;
            *out = (a + f * (b - a)).round() as u8;
        }
        c
    }
}

/// Qualitative palette (matplotlib "tab10") for series and boundary tags.
const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

// ---------------------------------------------------------------------------------------------
// Public types
// ---------------------------------------------------------------------------------------------

/// A scalar field on a mesh.
#[derive(Debug, Clone, Copy)]
pub enum Field<'a> {
    /// One value per cell (piecewise constant, e.g. the HMM cell unknowns u_K).
    Cell(&'a [f64]),
    /// One value per vertex (nodal, e.g. P1 finite elements).
    Vertex(&'a [f64]),
    /// Cell values drawn as a fan from (x_K, u_K) to given vertex heights (e.g. HMM: cell
    /// unknowns, with vertex values that use the face unknowns on the boundary).
    CellWithVertex {
        /// One value per cell.
        cell: &'a [f64],
        /// One value per vertex.
        vertex: &'a [f64],
    },
}

/// How a [`Field::Cell`] is drawn by [`plot_surface`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CellRendering {
    /// Continuous surface: vertex heights are the area-weighted averages of the adjacent cell
    /// values, and each cell K is a fan of triangles from (x_K, u_K) to its vertices.
    #[default]
    Fan,
    /// Each cell is a flat polygon at height u_K (shows the piecewise constant function).
    Flat,
}

/// Options of [`plot_surface`].
#[derive(Debug, Clone)]
pub struct SurfaceOptions {
    /// Title above the picture (empty: none).
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Label of the vertical axis.
    pub z_label: String,
    /// Output size in pixels (width, height).
    pub size: (u32, u32),
    /// Viewing azimuth in degrees, as MATLAB's `view(az, el)`: 0 looks from −y towards +y,
    /// positive values turn the viewer counter-clockwise around the z axis. Default −37.5.
    pub azimuth: f64,
    /// Viewing elevation in degrees above the (x, y) plane, as MATLAB's `view`. Default 30.
    pub elevation: f64,
    /// Height of the plot box relative to its longer horizontal side. Default 0.75.
    pub z_aspect: f64,
    /// Vertical axis range; `None`: the data range rounded outwards to ticks.
    pub z_range: Option<(f64, f64)>,
    /// Colour range (values outside are clamped); `None`: the data range.
    pub color_range: Option<(f64, f64)>,
    /// Colour map for the fill colour by value.
    pub colormap: Colormap,
    /// Draw a colour bar on the right.
    pub colorbar: bool,
    /// Draw the cell edges; `None`: only when the mesh has fewer than 3000 cells.
    pub edges: Option<bool>,
    /// Shade faces by a light source (in addition to the colour map).
    pub lighting: bool,
    /// How cell fields are drawn.
    pub cell_rendering: CellRendering,
    /// Labelled 3D points `([x, y, z], label)` drawn on top of the surface (e.g. the point
    /// where the contact condition switches).
    pub markers: Vec<([f64; 3], String)>,
    /// 3D polylines drawn on top of the surface (e.g. a vertical line at the switch point).
    pub lines: Vec<Vec<[f64; 3]>>,
    /// Supersampling factor (1–4) used for anti-aliasing. Default 2.
    pub supersample: u32,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_label: "x".into(),
            y_label: "y".into(),
            z_label: "u".into(),
            size: (900, 700),
            azimuth: -37.5,
            elevation: 30.0,
            z_aspect: 0.75,
            z_range: None,
            color_range: None,
            colormap: Colormap::Viridis,
            colorbar: true,
            edges: None,
            lighting: true,
            cell_rendering: CellRendering::Fan,
            markers: Vec::new(),
            lines: Vec::new(),
            supersample: 2,
        }
    }
}

/// Options of [`plot_mesh`].
#[derive(Debug, Clone)]
pub struct MeshPlotOptions {
    /// Title above the picture (empty: none).
    pub title: String,
    /// Output size in pixels (width, height). The drawing keeps an equal aspect ratio.
    pub size: (u32, u32),
    /// Optional value per cell, shown as fill colour (with a colour bar).
    pub cell_values: Option<Vec<f64>>,
    /// Colour map for `cell_values`.
    pub colormap: Colormap,
    /// Legend labels of boundary tags, `(tag, label)`, e.g. `(1, "Γ1")`. Boundary edges with a
    /// nonzero tag are drawn thick in a colour per tag; tags without a label here are shown as
    /// "tag N".
    pub boundary_labels: Vec<(i32, String)>,
    /// Colour boundary edges by tag (and show the legend).
    pub show_boundary_tags: bool,
    /// Text annotations `([x, y], text)` centred at points, e.g. "A = 100 I".
    pub annotations: Vec<([f64; 2], String)>,
    /// Horizontal dashed reference lines y = c.
    pub hlines: Vec<f64>,
    /// Vertical dashed reference lines x = c.
    pub vlines: Vec<f64>,
    /// Draw a frame with ticks and x/y labels.
    pub axes: bool,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Supersampling factor (1–4) used for anti-aliasing. Default 2.
    pub supersample: u32,
}

impl Default for MeshPlotOptions {
    fn default() -> Self {
        Self {
            title: String::new(),
            size: (700, 600),
            cell_values: None,
            colormap: Colormap::Viridis,
            boundary_labels: Vec::new(),
            show_boundary_tags: true,
            annotations: Vec::new(),
            hlines: Vec::new(),
            vlines: Vec::new(),
            axes: true,
            x_label: "x".into(),
            y_label: "y".into(),
            supersample: 2,
        }
    }
}

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

/// One labelled series of [`plot_lines`].
#[derive(Debug, Clone)]
pub struct LineSeries {
    /// Legend label (empty: not in the legend).
    pub label: String,
    /// Points `[x, y]`, drawn joined in the given order.
    pub points: Vec<[f64; 2]>,
    /// Line colour; `None`: from a palette by series index.
    pub color: Option<[u8; 3]>,
    /// Marker at the data points.
    pub marker: Marker,
    /// Draw the line dashed (e.g. a reference slope).
    pub dashed: bool,
    /// Draw the connecting line (false: markers only).
    pub line: bool,
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
            line: true,
        }
    }
}

/// Where [`plot_lines`] puts its legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LegendPosition {
    /// The corner with the fewest data points.
    #[default]
    Best,
    /// Upper right corner.
    UpperRight,
    /// Upper left corner.
    UpperLeft,
    /// Lower right corner.
    LowerRight,
    /// Lower left corner.
    LowerLeft,
    /// No legend.
    Hidden,
}

/// Options of [`plot_lines`].
#[derive(Debug, Clone)]
pub struct LineOptions {
    /// Title above the plot (empty: none).
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Output size in pixels (width, height).
    pub size: (u32, u32),
    /// Logarithmic x axis (all x must be > 0).
    pub log_x: bool,
    /// Logarithmic y axis (all y must be > 0).
    pub log_y: bool,
    /// Legend placement.
    pub legend: LegendPosition,
    /// Draw light grid lines.
    pub grid: bool,
    /// Supersampling factor (1–4) used for anti-aliasing. Default 2.
    pub supersample: u32,
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
            legend: LegendPosition::Best,
            grid: true,
            supersample: 2,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Raster: scan-line rasteriser of convex polygons into an RGB buffer
// ---------------------------------------------------------------------------------------------

type P2 = [f64; 2];
type Rgb = [u8; 3];

struct Raster {
    w: usize,
    h: usize,
    buf: Vec<u8>,
}

impl Raster {
    fn new(w: usize, h: usize) -> Self {
        Self {
            w,
            h,
            buf: vec![255; w * h * 3],
        }
    }

    fn span(&mut self, j: usize, i0: usize, i1: usize, c: Rgb) {
        let row = &mut self.buf[3 * (j * self.w + i0)..3 * (j * self.w + i1)];
        for px in row.chunks_exact_mut(3) {
            px.copy_from_slice(&c);
        }
    }

    /// Fills a convex polygon: a pixel is covered when its centre is inside, with half-open
    /// rules in x and y, so polygons sharing an edge neither overlap nor leave a gap.
    fn fill_convex(&mut self, pts: &[P2], c: Rgb) {
        if pts.len() < 3 || pts.iter().any(|p| !p[0].is_finite() || !p[1].is_finite()) {
            return;
        }
        let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in pts {
            ymin = ymin.min(p[1]);
            ymax = ymax.max(p[1]);
        }
        let j0 = (ymin - 0.5).ceil().max(0.0);
        let j1 = (ymax - 0.5).ceil().min(self.h as f64);
        if j0 >= j1 {
            return;
        }
        let n = pts.len();
        for j in j0 as usize..j1 as usize {
            let yc = j as f64 + 0.5;
            let (mut xl, mut xr) = (f64::INFINITY, f64::NEG_INFINITY);
            for e in 0..n {
                let (a, b) = (pts[e], pts[(e + 1) % n]);
                // canonical orientation, so that a shared edge gives bit-identical crossings
                let (p, q) = if (a[1], a[0]) < (b[1], b[0]) {
                    (a, b)
                } else {
                    (b, a)
                };
                if p[1] <= yc && yc < q[1] {
                    let x = p[0] + (yc - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
                    xl = xl.min(x);
                    xr = xr.max(x);
                }
            }
            if xl < xr {
                let i0 = (xl - 0.5).ceil().max(0.0);
                let i1 = (xr - 0.5).ceil().min(self.w as f64);
                if i0 < i1 {
                    self.span(j, i0 as usize, i1 as usize, c);
                }
            }
        }
    }

    /// A straight segment of the given width (pixels) with square caps.
    fn line(&mut self, a: P2, b: P2, width: f64, c: Rgb) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        let hw = 0.5 * width.max(0.5);
        let (ux, uy) = if len > 1e-12 {
            (dx / len, dy / len)
        } else {
            (1.0, 0.0)
        };
        let (nx, ny) = (-uy * hw, ux * hw);
        let (ex, ey) = (ux * hw, uy * hw);
        self.fill_convex(
            &[
                [a[0] - ex + nx, a[1] - ey + ny],
                [b[0] + ex + nx, b[1] + ey + ny],
                [b[0] + ex - nx, b[1] + ey - ny],
                [a[0] - ex - nx, a[1] - ey - ny],
            ],
            c,
        );
    }

    fn polyline(&mut self, pts: &[P2], width: f64, c: Rgb) {
        for w in pts.windows(2) {
            self.line(w[0], w[1], width, c);
        }
    }

    fn dashed_line(&mut self, a: P2, b: P2, width: f64, dash: f64, gap: f64, c: Rgb) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        if len <= 0.0 || dash <= 0.0 {
            return;
        }
        let mut t = 0.0;
        while t < len {
            let t1 = (t + dash).min(len);
            let p = [a[0] + dx * t / len, a[1] + dy * t / len];
            let q = [a[0] + dx * t1 / len, a[1] + dy * t1 / len];
            self.line(p, q, width, c);
            t = t1 + gap;
        }
    }

    fn disc(&mut self, c0: P2, r: f64, c: Rgb) {
        let pts: Vec<P2> = (0..32)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 32.0;
                [c0[0] + r * a.cos(), c0[1] + r * a.sin()]
            })
            .collect();
        self.fill_convex(&pts, c);
    }

    fn rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, c: Rgb) {
        self.fill_convex(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]], c);
    }

    fn rect_outline(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, width: f64, c: Rgb) {
        self.polyline(
            &[[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]],
            width,
            c,
        );
    }

    /// Box-filters the buffer down by the factor `ss`.
    fn downsample(&self, ss: usize) -> Vec<u8> {
        let (w, h) = (self.w / ss, self.h / ss);
        let mut out = vec![0u8; w * h * 3];
        let n = (ss * ss) as u32;
        for j in 0..h {
            for i in 0..w {
                let mut acc = [0u32; 3];
                for dj in 0..ss {
                    let row = (j * ss + dj) * self.w;
                    for di in 0..ss {
                        let o = 3 * (row + i * ss + di);
                        acc[0] += self.buf[o] as u32;
                        acc[1] += self.buf[o + 1] as u32;
                        acc[2] += self.buf[o + 2] as u32;
                    }
                }
                let o = 3 * (j * w + i);
                for ch in 0..3 {
                    out[o + ch] = ((acc[ch] + n / 2) / n) as u8;
                }
            }
        }
        out
    }
}

// ---------------------------------------------------------------------------------------------
// Text, drawn by plotters over the raster
// ---------------------------------------------------------------------------------------------

struct Label {
    pos: P2,
    text: String,
    size: f64,
    h: HPos,
    v: VPos,
    color: Rgb,
    /// Rotated by 90° (reading bottom to top).
    rotate: bool,
}

impl Label {
    fn centered(pos: P2, text: impl Into<String>, size: f64) -> Self {
        Self {
            pos,
            text: text.into(),
            size,
            h: HPos::Center,
            v: VPos::Center,
            color: [0, 0, 0],
            rotate: false,
        }
    }
}

/// Width and height in pixels of `text` at font size `size`.
fn text_size(text: &str, size: f64) -> (f64, f64) {
    match (FONT, size).into_font().box_size(text) {
        Ok((w, h)) => (w as f64, h as f64),
        Err(_) => (0.6 * size * text.chars().count() as f64, size),
    }
}

/// Drawing errors of the bitmap backend.
type DrawErr = DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

fn draw_labels(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    labels: &[Label],
) -> std::result::Result<(), DrawErr> {
    for l in labels {
        if l.text.is_empty() || !l.pos[0].is_finite() || !l.pos[1].is_finite() {
            continue;
        }
        let color = RGBColor(l.color[0], l.color[1], l.color[2]);
        let font = (FONT, l.size).into_font();
        let font = if l.rotate {
            font.transform(FontTransform::Rotate270)
        } else {
            font
        };
        let style = TextStyle::from(font).color(&color).pos(Pos::new(l.h, l.v));
        area.draw(&Text::new(
            l.text.clone(),
            (l.pos[0].round() as i32, l.pos[1].round() as i32),
            style,
        ))?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Output plumbing
// ---------------------------------------------------------------------------------------------

fn io_err(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(msg.to_string()),
    }
}

/// Checks the path, image size and supersampling factor; registers the font; creates parent
/// directories.
fn prepare_output(path: &Path, size: (u32, u32), ss: u32) -> Result<()> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(Error::InvalidData(format!(
            "plot file {} must have the extension .png",
            path.display()
        )));
    }
    let (w, h) = size;
    if !(32..=16384).contains(&w) || !(32..=16384).contains(&h) {
        return Err(Error::InvalidData(format!(
            "image size {w}x{h} is outside 32..=16384 pixels"
        )));
    }
    if !(1..=4).contains(&ss) {
        return Err(Error::InvalidData(format!(
            "supersample factor {ss} is outside 1..=4"
        )));
    }
    if (w as u64) * (h as u64) * (ss as u64).pow(2) > 200_000_000 {
        return Err(Error::InvalidData(format!(
            "image {w}x{h} with supersampling {ss} is too large"
        )));
    }
    ensure_font()?;
    if let Some(parent) = path.parent()
        && !parent.as_os_str().is_empty()
    {
        std::fs::create_dir_all(parent).map_err(|source| Error::Io {
            path: parent.to_path_buf(),
            source,
        })?;
    }
    Ok(())
}

/// Draws `labels` over the raster, downsamples by `ss` and writes the PNG.
fn finish(path: &Path, mut raster: Raster, labels: &[Label], ss: u32) -> Result<()> {
    let (w, h) = (raster.w as u32, raster.h as u32);
    {
        let backend = BitMapBackend::with_buffer(&mut raster.buf, (w, h));
        let area = backend.into_drawing_area();
        draw_labels(&area, labels).map_err(|e| io_err(path, e))?;
        area.present().map_err(|e| io_err(path, e))?;
    }
    write_png(path, &raster, ss)
}

fn write_png(path: &Path, raster: &Raster, ss: u32) -> Result<()> {
    let small = raster.downsample(ss as usize);
    let (w, h) = (raster.w as u32 / ss, raster.h as u32 / ss);
    let mut backend = BitMapBackend::new(path, (w, h));
    backend
        .blit_bitmap((0, 0), (w, h), &small)
        .map_err(|e| io_err(path, e))?;
    backend.present().map_err(|e| io_err(path, e))?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Ticks
// ---------------------------------------------------------------------------------------------

/// A "nice" tick step (1, 2 or 5 × 10^k) for about `target` intervals on [lo, hi].
fn nice_step(lo: f64, hi: f64, target: f64) -> f64 {
    let range = (hi - lo).abs();
    if range <= 0.0 || !range.is_finite() {
        return 1.0;
    }
    let raw = range / target.max(1.0);
    let mag = 10f64.powf(raw.log10().floor());
    let norm = raw / mag;
    let nice = if norm < 1.5 {
        1.0
    } else if norm < 3.0 {
        2.0
    } else if norm < 7.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// The multiples of `step` in [lo, hi] (with a little tolerance).
fn ticks_in(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let eps = 1e-9 * step;
    let k0 = ((lo - eps) / step).ceil() as i64;
    let k1 = ((hi + eps) / step).floor() as i64;
    if k1 < k0 || k1 - k0 > 1000 {
        return Vec::new();
    }
    (k0..=k1).map(|k| k as f64 * step).collect()
}

/// Formats a tick value with as many decimals as `step` needs (Unicode minus sign).
fn fmt_tick(v: f64, step: f64) -> String {
    let v = if v.abs() < 1e-9 * step.abs() { 0.0 } else { v };
    let s = if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        let mut s = format!("{v:.1e}");
        if let Some(p) = s.find(".0e") {
            s.replace_range(p..p + 2, "");
        }
        s
    } else {
        let mut dec = 0usize;
        while dec < 10 {
            let scaled = step * 10f64.powi(dec as i32);
            if (scaled - scaled.round()).abs() < 1e-6 * scaled.abs().max(1.0) {
                break;
            }
            dec += 1;
        }
        format!("{v:.dec$}")
    };
    s.replace('-', "\u{2212}")
}

// ---------------------------------------------------------------------------------------------
// Validation helpers
// ---------------------------------------------------------------------------------------------

fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidData(format!(
            "{what}: entry {i} is not finite ({})",
            values[i]
        )));
    }
    Ok(())
}

fn check_range(what: &str, r: Option<(f64, f64)>) -> Result<()> {
    if let Some((a, b)) = r
        && !(a.is_finite() && b.is_finite() && a < b)
    {
        return Err(Error::InvalidData(format!(
            "{what} ({a}, {b}) must be finite with min < max"
        )));
    }
    Ok(())
}

fn min_max(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    values
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
}

/// Widens a degenerate range.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo {
        (lo, hi)
    } else {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    }
}

// ---------------------------------------------------------------------------------------------
// Surface plot
// ---------------------------------------------------------------------------------------------

type P3 = [f64; 3];

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Orthographic camera: MATLAB `view(az, el)` applied to the normalised plot box.
struct View {
    /// Rows: screen right, screen up, towards the viewer.
    r: [P3; 3],
    /// Data centre of the box.
    c: P3,
    /// Data → normalised box scaling per axis.
    sc: P3,
    /// Pixels per normalised unit.
    k: f64,
    /// Pixel position of the box centre.
    o: P2,
}

impl View {
    fn new(az_deg: f64, el_deg: f64, c: P3, sc: P3) -> Self {
        let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
        let r = [
            [az.cos(), az.sin(), 0.0],
            [-el.sin() * az.sin(), el.sin() * az.cos(), el.cos()],
            [el.cos() * az.sin(), -el.cos() * az.cos(), el.sin()],
        ];
        Self {
            r,
            c,
            sc,
            k: 1.0,
            o: [0.0, 0.0],
        }
    }
    fn norm(&self, p: P3) -> P3 {
        [
            (p[0] - self.c[0]) * self.sc[0],
            (p[1] - self.c[1]) * self.sc[1],
            (p[2] - self.c[2]) * self.sc[2],
        ]
    }
    /// Unscaled screen coordinates (y up) of a normalised point.
    fn plane(&self, q: P3) -> P2 {
        [dot(self.r[0], q), dot(self.r[1], q)]
    }
    fn px_of_norm(&self, q: P3) -> P2 {
        let p = self.plane(q);
        [self.o[0] + self.k * p[0], self.o[1] - self.k * p[1]]
    }
    fn px(&self, p: P3) -> P2 {
        self.px_of_norm(self.norm(p))
    }
    /// Screen direction (pixels, y down, unit length) of a data-space direction.
    fn dir(&self, d: P3) -> P2 {
        let q = [d[0] * self.sc[0], d[1] * self.sc[1], d[2] * self.sc[2]];
        let p = self.plane(q);
        let (x, y) = (p[0], -p[1]);
        let n = (x * x + y * y).sqrt();
        if n < 1e-9 { [0.0, 1.0] } else { [x / n, y / n] }
    }
}

/// Geometry of the triangulated surface.
struct Surface {
    /// Data-space points.
    pts: Vec<P3>,
    /// Triangles: point ids and a bit mask of the sides to stroke (bit i: side i → i+1).
    tris: Vec<([u32; 3], u8)>,
}

/// Every cell as a fan of triangles from its centroid (height `cell[k]`) to its sides
/// (vertex heights `vertex[v]`); points: the vertices, then the centroids.
fn fan_surface(
    mesh: &PolyMesh,
    cell: &[f64],
    vertex: &[f64],
    pts: &mut Vec<P3>,
    tris: &mut Vec<([u32; 3], u8)>,
) {
    let nv = mesh.n_vertices();
    pts.reserve(nv + cell.len());
    for (v, &z) in vertex.iter().enumerate() {
        let p = mesh.vertex(v);
        pts.push([p[0], p[1], z]);
    }
    for (k, &uk) in cell.iter().enumerate() {
        let c = mesh.centroid(k);
        pts.push([c[0], c[1], uk]);
        let cv = mesh.cell_vertices(k);
        for i in 0..cv.len() {
            let (a, b) = (cv[i], cv[(i + 1) % cv.len()]);
            tris.push(([a as u32, b as u32, (nv + k) as u32], 1));
        }
    }
}

fn build_surface(mesh: &PolyMesh, field: Field, rendering: CellRendering) -> Surface {
    let nv = mesh.n_vertices();
    let nc = mesh.n_cells();
    let mut pts: Vec<P3> = Vec::new();
    let mut tris: Vec<([u32; 3], u8)> = Vec::new();
    match (field, rendering) {
        (Field::Cell(u), CellRendering::Fan) => {
            // vertex heights: area-weighted averages of the adjacent cell values
            let mut num = vec![0.0; nv];
            let mut den = vec![0.0; nv];
            for (k, &uk) in u.iter().enumerate() {
                let a = mesh.measure(k);
                for &v in mesh.cell_vertices(k) {
                    num[v] += a * uk;
                    den[v] += a;
                }
            }
            let vertex: Vec<f64> = num
                .iter()
                .zip(&den)
                .map(|(&n, &d)| if d > 0.0 { n / d } else { 0.0 })
                .collect();
            fan_surface(mesh, u, &vertex, &mut pts, &mut tris);
        }
        (Field::CellWithVertex { cell, vertex }, _) => {
            fan_surface(mesh, cell, vertex, &mut pts, &mut tris);
        }
        (Field::Cell(u), CellRendering::Flat) => {
            for (k, &uk) in u.iter().enumerate() {
                let base = pts.len();
                let cv = mesh.cell_vertices(k);
                for &v in cv {
                    let p = mesh.vertex(v);
                    pts.push([p[0], p[1], uk]);
                }
                let c = mesh.centroid(k);
                pts.push([c[0], c[1], uk]);
                let m = cv.len();
                for i in 0..m {
                    let (a, b) = (base + i, base + (i + 1) % m);
                    tris.push(([a as u32, b as u32, (base + m) as u32], 1));
                }
            }
        }
        (Field::Vertex(u), _) => {
            for (p, &uv) in mesh.vertices().iter().zip(u) {
                pts.push([p[0], p[1], uv]);
            }
            for k in 0..nc {
                let cv = mesh.cell_vertices(k);
                if cv.len() == 3 {
                    tris.push(([cv[0] as u32, cv[1] as u32, cv[2] as u32], 0b111));
                    continue;
                }
                let c = mesh.centroid(k);
                let z = cv.iter().map(|&v| u[v]).sum::<f64>() / cv.len() as f64;
                let ci = pts.len() as u32;
                pts.push([c[0], c[1], z]);
                for i in 0..cv.len() {
                    let (a, b) = (cv[i], cv[(i + 1) % cv.len()]);
                    tris.push(([a as u32, b as u32, ci], 1));
                }
            }
        }
    }
    Surface { pts, tris }
}

/// Draws a 3D view of a discrete solution on `mesh` into the PNG file `path`, in the spirit of
/// MATLAB's `trisurf`/`patch`: faces coloured by height with a colour map, thin dark cell edges on
/// coarse meshes, hidden surfaces resolved by the painter's algorithm, a box with ticks and
/// labelled axes, an optional colour bar, and optional labelled markers and lines on top.
///
/// A [`Field::Cell`] is drawn as described by [`CellRendering`]; a [`Field::Vertex`] draws each
/// cell with its vertex heights (polygons other than triangles as a fan from the centroid at the
/// mean vertex height).
///
/// Errors: [`Error::InvalidData`] if the field length differs from the number of cells/vertices,
/// a value (or a marker/line coordinate, a range or the view) is not finite, a range is empty, or
/// the path/size is unusable; [`Error::Io`] if the file cannot be written.
pub fn plot_surface(
    path: &Path,
    mesh: &PolyMesh,
    field: Field,
    opts: &SurfaceOptions,
) -> Result<()> {
    // ---- validation
    let (values, expected, what) = match field {
        Field::Cell(u) => (u, mesh.n_cells(), "cells"),
        Field::Vertex(u) => (u, mesh.n_vertices(), "vertices"),
        Field::CellWithVertex { cell, vertex } => {
            if vertex.len() != mesh.n_vertices() {
                return Err(Error::InvalidData(format!(
                    "surface field has {} vertex values but the mesh has {} vertices",
                    vertex.len(),
                    mesh.n_vertices()
                )));
            }
            check_finite("surface field", vertex)?;
            (cell, mesh.n_cells(), "cells")
        }
    };
    if mesh.n_cells() == 0 {
        return Err(Error::InvalidData("cannot plot on an empty mesh".into()));
    }
    if values.len() != expected {
        return Err(Error::InvalidData(format!(
            "surface field has {} values but the mesh has {expected} {what}",
            values.len()
        )));
    }
    check_finite("surface field", values)?;
    check_range("z_range", opts.z_range)?;
    check_range("color_range", opts.color_range)?;
    if !(opts.azimuth.is_finite() && opts.elevation.is_finite()) {
        return Err(Error::InvalidData("view angles must be finite".into()));
    }
    if !(opts.z_aspect.is_finite() && opts.z_aspect > 0.0) {
        return Err(Error::InvalidData("z_aspect must be positive".into()));
    }
    for (p, _) in &opts.markers {
        check_finite("marker", p)?;
    }
    for l in &opts.lines {
        for p in l {
            check_finite("line point", p)?;
        }
    }
    let ss = opts.supersample;
    prepare_output(path, opts.size, ss)?;
    let s = ss as f64;
    let (w, h) = ((opts.size.0 * ss) as usize, (opts.size.1 * ss) as usize);

    // ---- geometry and ranges
    let surf = build_surface(mesh, field, opts.cell_rendering);
    let [x0, y0, x1, y1] = mesh.bounding_box();
    let (x0, x1) = widen(x0, x1);
    let (y0, y1) = widen(y0, y1);
    let (dmin, dmax) = min_max(surf.pts.iter().map(|p| p[2]));
    let (cmin, cmax) = opts.color_range.unwrap_or_else(|| widen(dmin, dmax));
    let (z0, z1, zstep) = match opts.z_range {
        Some((a, b)) => (a, b, nice_step(a, b, 5.0)),
        None => {
            let (a, b) = widen(dmin, dmax);
            let st = nice_step(a, b, 5.0);
            let lo = ((a + 1e-9 * st) / st).floor() * st;
            let hi = ((b - 1e-9 * st) / st).ceil() * st;
            (lo, hi, st)
        }
    };
    let l = (x1 - x0).max(y1 - y0);
    let mut view = View::new(
        opts.azimuth,
        opts.elevation,
        [0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)],
        [1.0 / l, 1.0 / l, opts.z_aspect / (z1 - z0)],
    );
    let rv = view.r[2];
    // back/front sides of the box
    let x_back = if rv[0] < 0.0 { x1 } else { x0 };
    let x_front = if rv[0] < 0.0 { x0 } else { x1 };
    let y_back = if rv[1] < 0.0 { y1 } else { y0 };
    let y_front = if rv[1] < 0.0 { y0 } else { y1 };
    let z_floor = if rv[2] >= 0.0 { z0 } else { z1 };
    let corners: Vec<P3> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { x0 } else { x1 },
                if i & 2 == 0 { y0 } else { y1 },
                if i & 4 == 0 { z0 } else { z1 },
            ]
        })
        .collect();
    // z axis: the vertical box edge that is leftmost on screen
    let z_corner = [[x0, y0], [x1, y0], [x0, y1], [x1, y1]]
        .into_iter()
        .min_by(|a, b| {
            // leftmost; among (nearly) equal, the farthest from the viewer
            let (qa, qb) = (view.norm([a[0], a[1], z0]), view.norm([b[0], b[1], z0]));
            let (pa, pb) = (view.plane(qa)[0], view.plane(qb)[0]);
            if (pa - pb).abs() > 1e-9 {
                pa.total_cmp(&pb)
            } else {
                dot(view.r[2], qa).total_cmp(&dot(view.r[2], qb))
            }
        })
        .unwrap_or([x0, y1]);

    // ---- fonts and ticks
    let fs_tick = 12.5 * s;
    let fs_axis = 15.0 * s;
    let fs_title = 17.0 * s;
    let tick_len = 5.0 * s;
    let gap = 4.0 * s;
    let xstep = nice_step(x0, x1, 5.0);
    let ystep = nice_step(y0, y1, 5.0);
    let xt = ticks_in(x0, x1, xstep);
    let yt = ticks_in(y0, y1, ystep);
    // seen from (almost) straight above or below, the z axis degenerates to a point
    let zt = if opts.elevation.abs() < 80.0 {
        ticks_in(z0, z1, zstep)
    } else {
        Vec::new()
    };
    let z_label = if opts.elevation.abs() < 80.0 {
        opts.z_label.clone()
    } else {
        String::new()
    };

    // ---- layout: the box and its labels must fit in the plot region
    let title_h = if opts.title.is_empty() {
        8.0 * s
    } else {
        2.4 * fs_title
    };
    let cb_w = if opts.colorbar { 105.0 * s } else { 0.0 };
    let region = [
        8.0 * s,
        title_h,
        w as f64 - cb_w - 8.0 * s,
        h as f64 - 8.0 * s,
    ];
    let axis_defs = |view: &View| -> Vec<AxisDef> {
        vec![
            AxisDef {
                a: [z_corner[0], z_corner[1], z0],
                b: [z_corner[0], z_corner[1], z1],
                ticks: zt
                    .iter()
                    .map(|&t| ([z_corner[0], z_corner[1], t], fmt_tick(t, zstep)))
                    .collect(),
                out: [-1.0, 0.0],
                label: z_label.clone(),
            },
            AxisDef {
                a: [x0, y_front, z_floor],
                b: [x1, y_front, z_floor],
                ticks: xt
                    .iter()
                    .map(|&t| ([t, y_front, z_floor], fmt_tick(t, xstep)))
                    .collect(),
                out: view.dir([0.0, y_front - y_back, 0.0]),
                label: opts.x_label.clone(),
            },
            AxisDef {
                a: [x_front, y0, z_floor],
                b: [x_front, y1, z_floor],
                ticks: yt
                    .iter()
                    .map(|&t| ([x_front, t, z_floor], fmt_tick(t, ystep)))
                    .collect(),
                out: view.dir([x_front - x_back, 0.0, 0.0]),
                label: opts.y_label.clone(),
            },
        ]
    };
    // pass 1: fit the bare box, pass 2: fit box + labels
    let (mut bx0, mut bx1, mut by0, mut by1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &c in &corners {
        let p = view.plane(view.norm(c));
        bx0 = bx0.min(p[0]);
        bx1 = bx1.max(p[0]);
        by0 = by0.min(p[1]);
        by1 = by1.max(p[1]);
    }
    let (rw, rh) = (region[2] - region[0], region[3] - region[1]);
    let fit = |view: &mut View, pad: [f64; 4]| {
        // pad: left, right, top, bottom protrusions in pixels
        let aw = (rw - pad[0] - pad[1]).max(10.0);
        let ah = (rh - pad[2] - pad[3]).max(10.0);
        view.k = (aw / (bx1 - bx0)).min(ah / (by1 - by0));
        let cx = region[0] + pad[0] + 0.5 * aw;
        let cy = region[1] + pad[2] + 0.5 * ah;
        // box centre in screen plane → pixel centre of the available area
        view.o = [
            cx - view.k * 0.5 * (bx0 + bx1),
            cy + view.k * 0.5 * (by0 + by1),
        ];
    };
    fit(&mut view, [60.0 * s, 20.0 * s, 10.0 * s, 50.0 * s]);
    for _ in 0..2 {
        let (_, labels) = axis_geometry(&view, &axis_defs(&view), fs_tick, fs_axis, tick_len, gap);
        let (px0, px1) = (view.o[0] + view.k * bx0, view.o[0] + view.k * bx1);
        let (py0, py1) = (view.o[1] - view.k * by1, view.o[1] - view.k * by0);
        let mut pad = [0.0f64; 4];
        for lb in &labels {
            let (tw, th) = text_size(&lb.text, lb.size);
            pad[0] = pad[0].max(px0 - (lb.pos[0] - 0.5 * tw));
            pad[1] = pad[1].max((lb.pos[0] + 0.5 * tw) - px1);
            pad[2] = pad[2].max(py0 - (lb.pos[1] - 0.5 * th));
            pad[3] = pad[3].max((lb.pos[1] + 0.5 * th) - py1);
        }
        for p in &mut pad {
            *p += 4.0 * s;
        }
        fit(&mut view, pad);
    }

    // ---- drawing
    let mut r = Raster::new(w, h);
    let mut labels: Vec<Label> = Vec::new();
    let pane_fill = [247, 247, 247];
    let grid = [218, 218, 218];
    let frame = [120, 120, 120];
    let gw = 1.0 * s;
    // back panes: floor, x wall, y wall
    let xy = |a: f64, b: f64, z: f64| view.px([a, b, z]);
    let floor = [
        xy(x0, y0, z_floor),
        xy(x1, y0, z_floor),
        xy(x1, y1, z_floor),
        xy(x0, y1, z_floor),
    ];
    let xwall = [
        xy(x_back, y0, z0),
        xy(x_back, y1, z0),
        xy(x_back, y1, z1),
        xy(x_back, y0, z1),
    ];
    let ywall = [
        xy(x0, y_back, z0),
        xy(x1, y_back, z0),
        xy(x1, y_back, z1),
        xy(x0, y_back, z1),
    ];
    for pane in [&floor, &xwall, &ywall] {
        r.fill_convex(pane, pane_fill);
    }
    for &t in &xt {
        r.line(xy(t, y0, z_floor), xy(t, y1, z_floor), gw, grid);
        r.line(xy(t, y_back, z0), xy(t, y_back, z1), gw, grid);
    }
    for &t in &yt {
        r.line(xy(x0, t, z_floor), xy(x1, t, z_floor), gw, grid);
        r.line(xy(x_back, t, z0), xy(x_back, t, z1), gw, grid);
    }
    for &t in &zt {
        r.line(xy(x0, y_back, t), xy(x1, y_back, t), gw, grid);
        r.line(xy(x_back, y0, t), xy(x_back, y1, t), gw, grid);
    }
    for pane in [&floor, &xwall, &ywall] {
        let mut p = pane.to_vec();
        p.push(pane[0]);
        r.polyline(&p, gw, frame);
    }

    // surface
    let npts = surf.pts.len();
    let mut scr: Vec<P2> = Vec::with_capacity(npts);
    let mut nrm: Vec<P3> = Vec::with_capacity(npts);
    for &p in &surf.pts {
        let q = view.norm(p);
        nrm.push(q);
        scr.push(view.px_of_norm(q));
    }
    let mut order: Vec<(f64, u32)> = surf
        .tris
        .iter()
        .enumerate()
        .map(|(i, (t, _))| {
            let d = (0..3).map(|j| dot(rv, nrm[t[j] as usize])).sum::<f64>();
            (d, i as u32)
        })
        .collect();
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let draw_edges = opts.edges.unwrap_or(mesh.n_cells() < 3000);
    let n = mesh.n_cells();
    let edge_w = if n < 300 {
        1.0 * s
    } else if n < 1500 {
        0.75 * s
    } else {
        0.5 * s
    };
    let edge_c = [35, 35, 35];
    // light: from the viewer's upper left
    let light = {
        let l = [
            rv[0] + 0.6 * view.r[1][0] - 0.4 * view.r[0][0],
            rv[1] + 0.6 * view.r[1][1] - 0.4 * view.r[0][1],
            rv[2] + 0.6 * view.r[1][2] - 0.4 * view.r[0][2],
        ];
        let n = dot(l, l).sqrt();
        [l[0] / n, l[1] / n, l[2] / n]
    };
    for &(_, ti) in &order {
        let (t, mask) = surf.tris[ti as usize];
        let ids = [t[0] as usize, t[1] as usize, t[2] as usize];
        let zmean = (surf.pts[ids[0]][2] + surf.pts[ids[1]][2] + surf.pts[ids[2]][2]) / 3.0;
        let mut c = opts.colormap.rgb((zmean - cmin) / (cmax - cmin));
        if opts.lighting {
            let (a, b, cc) = (nrm[ids[0]], nrm[ids[1]], nrm[ids[2]]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]];
            let nn = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = dot(nn, nn).sqrt();
            if len > 0.0 {
                let f = 0.65 + 0.35 * (dot(nn, light) / len).abs();
                for ch in &mut c {
                    *ch = (*ch as f64 * f).round().min(255.0) as u8;
                }
            }
        }
        let tri = [scr[ids[0]], scr[ids[1]], scr[ids[2]]];
        r.fill_convex(&tri, c);
        if draw_edges {
            for side in 0..3 {
                if mask & (1 << side) != 0 {
                    r.line(tri[side], tri[(side + 1) % 3], edge_w, edge_c);
                }
            }
        }
    }

    // axes: lines, ticks, labels
    let axes = axis_defs(&view);
    let (segs, mut axis_labels) = axis_geometry(&view, &axes, fs_tick, fs_axis, tick_len, gap);
    for (a, b) in segs {
        r.line(a, b, 1.0 * s, [60, 60, 60]);
    }
    labels.append(&mut axis_labels);

    // overlays
    for line in &opts.lines {
        let p: Vec<P2> = line.iter().map(|&q| view.px(q)).collect();
        r.polyline(&p, 2.5 * s, [215, 25, 28]);
    }
    for (p, text) in &opts.markers {
        let q = view.px(*p);
        r.disc(q, 5.5 * s, [0, 0, 0]);
        r.disc(q, 4.0 * s, [215, 25, 28]);
        if !text.is_empty() {
            let (tw, th) = text_size(text, fs_tick);
            let pos = [q[0] + 8.0 * s, q[1] - 8.0 * s];
            r.rect(
                pos[0] - 2.0 * s,
                pos[1] - th - 1.0 * s,
                pos[0] + tw + 2.0 * s,
                pos[1] + 2.0 * s,
                [255, 255, 255],
            );
            r.rect_outline(
                pos[0] - 2.0 * s,
                pos[1] - th - 1.0 * s,
                pos[0] + tw + 2.0 * s,
                pos[1] + 2.0 * s,
                0.75 * s,
                [120, 120, 120],
            );
            labels.push(Label {
                pos: [pos[0], pos[1] - 0.5 * th],
                text: text.clone(),
                size: fs_tick,
                h: HPos::Left,
                v: VPos::Center,
                color: [0, 0, 0],
                rotate: false,
            });
        }
    }

    // title
    if !opts.title.is_empty() {
        labels.push(Label::centered(
            [0.5 * w as f64, 0.5 * title_h + 2.0 * s],
            opts.title.clone(),
            fs_title,
        ));
    }

    // colour bar
    if opts.colorbar {
        let bx0 = w as f64 - cb_w + 14.0 * s;
        let bx1 = bx0 + 16.0 * s;
        let by0 = region[1] + 0.12 * rh;
        let by1 = region[3] - 0.12 * rh;
        colorbar(
            &mut r,
            &mut labels,
            [bx0, by0, bx1, by1],
            (cmin, cmax),
            opts.colormap,
            s,
        );
    }

    finish(path, r, &labels, ss)
}

/// One axis of the 3D box: the edge it is drawn on, its ticks, the outward screen direction.
struct AxisDef {
    a: P3,
    b: P3,
    ticks: Vec<(P3, String)>,
    out: P2,
    label: String,
}

/// Axis segments (edge + tick marks) and labels (tick values + axis title) in pixels.
fn axis_geometry(
    view: &View,
    axes: &[AxisDef],
    fs_tick: f64,
    fs_axis: f64,
    tick_len: f64,
    gap: f64,
) -> (Vec<(P2, P2)>, Vec<Label>) {
    let mut segs = Vec::new();
    let mut labels = Vec::new();
    // tick labels already placed, as [x0, y0, x1, y1]; a label that would overlap one is dropped
    // (e.g. the two "0" labels meeting at the front corner of the box)
    let mut placed: Vec<[f64; 4]> = Vec::new();
    for ax in axes {
        let d = ax.out;
        segs.push((view.px(ax.a), view.px(ax.b)));
        let mut reach: f64 = 0.0;
        for (p, text) in &ax.ticks {
            let q = view.px(*p);
            segs.push((q, [q[0] + d[0] * tick_len, q[1] + d[1] * tick_len]));
            let (tw, th) = text_size(text, fs_tick);
            let sup = d[0].abs() * 0.5 * tw + d[1].abs() * 0.5 * th;
            let t = tick_len + gap + sup;
            reach = reach.max(tick_len + gap + 2.0 * sup);
            let c = [q[0] + d[0] * t, q[1] + d[1] * t];
            let rect = [
                c[0] - 0.5 * tw - gap,
                c[1] - 0.5 * th - 0.5 * gap,
                c[0] + 0.5 * tw + gap,
                c[1] + 0.5 * th + 0.5 * gap,
            ];
            let overlaps = placed
                .iter()
                .any(|o| rect[0] < o[2] && o[0] < rect[2] && rect[1] < o[3] && o[1] < rect[3]);
            if overlaps {
                continue;
            }
            placed.push(rect);
            labels.push(Label::centered(c, text.clone(), fs_tick));
        }
        if !ax.label.is_empty() {
            let m = view.px([
                0.5 * (ax.a[0] + ax.b[0]),
                0.5 * (ax.a[1] + ax.b[1]),
                0.5 * (ax.a[2] + ax.b[2]),
            ]);
            let (tw, th) = text_size(&ax.label, fs_axis);
            let sup = d[0].abs() * 0.5 * tw + d[1].abs() * 0.5 * th;
            let t = reach.max(tick_len) + 2.0 * gap + sup;
            labels.push(Label::centered(
                [m[0] + d[0] * t, m[1] + d[1] * t],
                ax.label.clone(),
                fs_axis,
            ));
        }
    }
    (segs, labels)
}

/// A vertical colour bar in the rectangle `[x0, y0, x1, y1]` (pixels) with ticks on the right.
fn colorbar(
    r: &mut Raster,
    labels: &mut Vec<Label>,
    rect: [f64; 4],
    (lo, hi): (f64, f64),
    cmap: Colormap,
    s: f64,
) {
    let [x0, y0, x1, y1] = rect;
    let rows = (y1 - y0).max(1.0).ceil() as usize;
    for i in 0..rows {
        let ya = y0 + i as f64;
        let yb = (ya + 1.0).min(y1);
        let t = 1.0 - (ya + 0.5 - y0) / (y1 - y0);
        r.rect(x0, ya, x1, yb, cmap.rgb(t));
    }
    r.rect_outline(x0, y0, x1, y1, 1.0 * s, [60, 60, 60]);
    let step = nice_step(lo, hi, 6.0);
    for t in ticks_in(lo, hi, step) {
        let y = y1 - (t - lo) / (hi - lo) * (y1 - y0);
        r.line([x1, y], [x1 + 4.0 * s, y], 1.0 * s, [60, 60, 60]);
        labels.push(Label {
            pos: [x1 + 7.0 * s, y],
            text: fmt_tick(t, step),
            size: 12.5 * s,
            h: HPos::Left,
            v: VPos::Center,
            color: [0, 0, 0],
            rotate: false,
        });
    }
}

// ---------------------------------------------------------------------------------------------
// Mesh plot
// ---------------------------------------------------------------------------------------------

/// Draws the mesh `mesh` in 2D (equal aspect ratio) into the PNG file `path`: all edges, cells
/// optionally filled by `cell_values` (with a colour bar), boundary edges coloured by tag with a
/// legend, optional text annotations, dashed reference lines, a frame with ticks, and a title.
///
/// Errors: [`Error::InvalidData`] if `cell_values` does not have one finite value per cell, an
/// annotation or reference line is not finite, or the path/size is unusable; [`Error::Io`] if the
/// file cannot be written.
pub fn plot_mesh(path: &Path, mesh: &PolyMesh, opts: &MeshPlotOptions) -> Result<()> {
    if mesh.n_cells() == 0 {
        return Err(Error::InvalidData("cannot plot an empty mesh".into()));
    }
    if let Some(v) = &opts.cell_values {
        if v.len() != mesh.n_cells() {
            return Err(Error::InvalidData(format!(
                "cell_values has {} values but the mesh has {} cells",
                v.len(),
                mesh.n_cells()
            )));
        }
        check_finite("cell_values", v)?;
    }
    for (p, _) in &opts.annotations {
        check_finite("annotation position", p)?;
    }
    check_finite("hlines", &opts.hlines)?;
    check_finite("vlines", &opts.vlines)?;
    let ss = opts.supersample;
    prepare_output(path, opts.size, ss)?;
    let s = ss as f64;
    let (w, h) = ((opts.size.0 * ss) as usize, (opts.size.1 * ss) as usize);
    let fs_tick = 12.5 * s;
    let fs_axis = 15.0 * s;
    let fs_title = 17.0 * s;
    let fs_legend = 13.5 * s;

    // boundary tags present, in increasing order, with colours and labels
    let mut tags: Vec<i32> = if opts.show_boundary_tags {
        mesh.boundary_edges()
            .iter()
            .map(|&e| mesh.edge_tag(e))
            .filter(|&t| t != 0)
            .collect()
    } else {
        Vec::new()
    };
    tags.sort_unstable();
    tags.dedup();
    let tag_color = |t: i32| -> Rgb {
        let i = tags.iter().position(|&x| x == t).unwrap_or(0);
        PALETTE[(i + 1) % PALETTE.len()]
    };
    let tag_label = |t: i32| -> String {
        opts.boundary_labels
            .iter()
            .find(|(x, _)| *x == t)
            .map(|(_, l)| l.clone())
            .unwrap_or_else(|| format!("tag {t}"))
    };

    // layout
    let title_h = if opts.title.is_empty() {
        10.0 * s
    } else {
        2.4 * fs_title
    };
    let legend_w = if tags.is_empty() {
        0.0
    } else {
        let lw = tags
            .iter()
            .map(|&t| text_size(&tag_label(t), fs_legend).0)
            .fold(0.0, f64::max);
        lw + 60.0 * s
    };
    let cb_w = if opts.cell_values.is_some() {
        95.0 * s
    } else {
        0.0
    };
    let right_w = legend_w.max(cb_w) + 10.0 * s;
    let (left_m, bottom_m) = if opts.axes {
        (62.0 * s, 52.0 * s)
    } else {
        (12.0 * s, 12.0 * s)
    };
    let region = [left_m, title_h, w as f64 - right_w, h as f64 - bottom_m];
    let [bx0, by0, bx1, by1] = mesh.bounding_box();
    let (bx0, bx1) = widen(bx0, bx1);
    let (by0, by1) = widen(by0, by1);
    let pad = 0.03 * (bx1 - bx0).max(by1 - by0);
    let (dx0, dx1, dy0, dy1) = (bx0 - pad, bx1 + pad, by0 - pad, by1 + pad);
    let k = ((region[2] - region[0]) / (dx1 - dx0)).min((region[3] - region[1]) / (dy1 - dy0));
    let fw = k * (dx1 - dx0);
    let fh = k * (dy1 - dy0);
    let fx0 = region[0] + 0.5 * (region[2] - region[0] - fw);
    let fy0 = region[1] + 0.5 * (region[3] - region[1] - fh);
    let map = |p: [f64; 2]| -> P2 { [fx0 + k * (p[0] - dx0), fy0 + fh - k * (p[1] - dy0)] };

    let mut r = Raster::new(w, h);
    let mut labels = Vec::new();

    // cells
    if let Some(vals) = &opts.cell_values {
        let (lo, hi) = widen(
            min_max(vals.iter().copied()).0,
            min_max(vals.iter().copied()).1,
        );
        for (kc, &v) in vals.iter().enumerate() {
            let c = opts.colormap.rgb((v - lo) / (hi - lo));
            let xc = map(mesh.centroid(kc));
            let cv = mesh.cell_vertices(kc);
            for i in 0..cv.len() {
                let a = map(mesh.vertex(cv[i]));
                let b = map(mesh.vertex(cv[(i + 1) % cv.len()]));
                r.fill_convex(&[a, b, xc], c);
            }
        }
        let cbx0 = w as f64 - right_w + 14.0 * s;
        let top = if tags.is_empty() {
            region[1] + 0.1 * (region[3] - region[1])
        } else {
            region[1] + (tags.len() as f64 * 1.6 + 2.0) * fs_legend
        };
        colorbar(
            &mut r,
            &mut labels,
            [
                cbx0,
                top,
                cbx0 + 16.0 * s,
                region[3] - 0.1 * (region[3] - region[1]),
            ],
            (lo, hi),
            opts.colormap,
            s,
        );
    }

    // edges
    let n = mesh.n_cells();
    let ew = if n < 500 {
        1.0 * s
    } else if n < 5000 {
        0.7 * s
    } else {
        0.5 * s
    };
    let edge_c = if opts.cell_values.is_some() {
        [40, 40, 40]
    } else {
        [30, 30, 30]
    };
    for e in 0..mesh.n_edges() {
        let [a, b] = mesh.edge_vertices(e);
        r.line(map(mesh.vertex(a)), map(mesh.vertex(b)), ew, edge_c);
    }
    let bw = 3.0 * s;
    for &t in &tags {
        let c = tag_color(t);
        for &e in mesh.boundary_edges() {
            if mesh.edge_tag(e) == t {
                let [a, b] = mesh.edge_vertices(e);
                r.line(map(mesh.vertex(a)), map(mesh.vertex(b)), bw, c);
            }
        }
    }

    // reference lines
    for &yv in &opts.hlines {
        if yv >= dy0 && yv <= dy1 {
            r.dashed_line(
                map([dx0, yv]),
                map([dx1, yv]),
                1.5 * s,
                7.0 * s,
                4.0 * s,
                [80, 80, 80],
            );
        }
    }
    for &xv in &opts.vlines {
        if xv >= dx0 && xv <= dx1 {
            r.dashed_line(
                map([xv, dy0]),
                map([xv, dy1]),
                1.5 * s,
                7.0 * s,
                4.0 * s,
                [80, 80, 80],
            );
        }
    }

    // annotations: text on a white box
    for (p, text) in &opts.annotations {
        if text.is_empty() {
            continue;
        }
        let q = map(*p);
        let (tw, th) = text_size(text, fs_legend);
        let (hx, hy) = (0.5 * tw + 5.0 * s, 0.5 * th + 4.0 * s);
        r.rect(q[0] - hx, q[1] - hy, q[0] + hx, q[1] + hy, [255, 255, 255]);
        r.rect_outline(
            q[0] - hx,
            q[1] - hy,
            q[0] + hx,
            q[1] + hy,
            0.8 * s,
            [90, 90, 90],
        );
        labels.push(Label::centered(q, text.clone(), fs_legend));
    }

    // frame and ticks
    if opts.axes {
        let fc = [60, 60, 60];
        r.rect_outline(fx0, fy0, fx0 + fw, fy0 + fh, 1.0 * s, fc);
        let xstep = nice_step(dx0, dx1, (fw / (90.0 * s)).clamp(2.0, 8.0));
        let ystep = nice_step(dy0, dy1, (fh / (70.0 * s)).clamp(2.0, 8.0));
        for t in ticks_in(dx0, dx1, xstep) {
            let q = map([t, dy0]);
            r.line(q, [q[0], q[1] + 5.0 * s], 1.0 * s, fc);
            labels.push(Label {
                pos: [q[0], q[1] + 8.0 * s],
                text: fmt_tick(t, xstep),
                size: fs_tick,
                h: HPos::Center,
                v: VPos::Top,
                color: [0, 0, 0],
                rotate: false,
            });
        }
        for t in ticks_in(dy0, dy1, ystep) {
            let q = map([dx0, t]);
            r.line(q, [q[0] - 5.0 * s, q[1]], 1.0 * s, fc);
            labels.push(Label {
                pos: [q[0] - 8.0 * s, q[1]],
                text: fmt_tick(t, ystep),
                size: fs_tick,
                h: HPos::Right,
                v: VPos::Center,
                color: [0, 0, 0],
                rotate: false,
            });
        }
        labels.push(Label::centered(
            [fx0 + 0.5 * fw, fy0 + fh + 36.0 * s],
            opts.x_label.clone(),
            fs_axis,
        ));
        labels.push(Label::centered(
            [fx0 - 50.0 * s, fy0 + 0.5 * fh],
            opts.y_label.clone(),
            fs_axis,
        ));
    }

    // legend of boundary tags
    if !tags.is_empty() {
        let lx = w as f64 - right_w + 8.0 * s;
        let mut y = region[1] + 1.0 * fs_legend;
        let lh = 1.6 * fs_legend;
        let lw = legend_w - 10.0 * s;
        r.rect(
            lx,
            y - 0.8 * fs_legend,
            lx + lw,
            y + (tags.len() as f64 - 0.2) * lh,
            [255, 255, 255],
        );
        r.rect_outline(
            lx,
            y - 0.8 * fs_legend,
            lx + lw,
            y + (tags.len() as f64 - 0.2) * lh,
            0.8 * s,
            [150, 150, 150],
        );
        y += 0.15 * fs_legend;
        for &t in &tags {
            r.line([lx + 8.0 * s, y], [lx + 34.0 * s, y], bw, tag_color(t));
            labels.push(Label {
                pos: [lx + 42.0 * s, y],
                text: tag_label(t),
                size: fs_legend,
                h: HPos::Left,
                v: VPos::Center,
                color: [0, 0, 0],
                rotate: false,
            });
            y += lh;
        }
    }

    if !opts.title.is_empty() {
        labels.push(Label::centered(
            [0.5 * w as f64, 0.5 * title_h + 2.0 * s],
            opts.title.clone(),
            fs_title,
        ));
    }
    finish(path, r, &labels, ss)
}

// ---------------------------------------------------------------------------------------------
// Line plot
// ---------------------------------------------------------------------------------------------

/// Draws the x–y plot of `series` (linear or logarithmic axes) into the PNG file `path`: one
/// coloured line per series with markers, a legend of the labelled series, axis labels, light
/// grid and a title. Used for convergence and benchmark plots.
///
/// Errors: [`Error::InvalidData`] if there is no series, a series has no point, a coordinate is
/// not finite, a coordinate on a log axis is not positive, or the path/size is unusable;
/// [`Error::Io`] if the file cannot be written.
pub fn plot_lines(path: &Path, series: &[LineSeries], opts: &LineOptions) -> Result<()> {
    if series.is_empty() {
        return Err(Error::InvalidData("plot_lines: no series".into()));
    }
    for (i, sr) in series.iter().enumerate() {
        if sr.points.is_empty() {
            return Err(Error::InvalidData(format!(
                "plot_lines: series {i} (\"{}\") has no point",
                sr.label
            )));
        }
        for p in &sr.points {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(Error::InvalidData(format!(
                    "plot_lines: series {i} (\"{}\") has a non-finite point ({}, {})",
                    sr.label, p[0], p[1]
                )));
            }
            if (opts.log_x && p[0] <= 0.0) || (opts.log_y && p[1] <= 0.0) {
                return Err(Error::InvalidData(format!(
                    "plot_lines: series {i} (\"{}\") has the point ({}, {}) which cannot be shown on a log axis",
                    sr.label, p[0], p[1]
                )));
            }
        }
    }
    let ss = opts.supersample;
    prepare_output(path, opts.size, ss)?;
    let s = ss as f64;
    let (w, h) = ((opts.size.0 * ss) as usize, (opts.size.1 * ss) as usize);
    let fs_tick = 13.0 * s;
    let fs_axis = 15.0 * s;
    let fs_title = 17.0 * s;
    let fs_legend = 13.5 * s;

    // axes in transformed coordinates (log10 on log axes)
    let xaxis = LineAxis::new(
        series.iter().flat_map(|s| s.points.iter().map(|p| p[0])),
        opts.log_x,
    );
    let yaxis = LineAxis::new(
        series.iter().flat_map(|s| s.points.iter().map(|p| p[1])),
        opts.log_y,
    );

    // layout
    let title_h = if opts.title.is_empty() {
        14.0 * s
    } else {
        2.4 * fs_title
    };
    let target_y = ((h as f64 - title_h) / (60.0 * s)).clamp(3.0, 10.0);
    let target_x = (w as f64 / (110.0 * s)).clamp(3.0, 10.0);
    let yticks = yaxis.ticks(target_y);
    let ytw = yticks
        .iter()
        .filter(|t| t.2)
        .map(|t| text_size(&t.1, fs_tick).0)
        .fold(0.0, f64::max);
    let has_ylabel = !opts.y_label.is_empty();
    let left = 12.0 * s + ytw + 10.0 * s + if has_ylabel { 1.6 * fs_axis } else { 0.0 };
    let bottom = 14.0 * s
        + fs_tick
        + if opts.x_label.is_empty() {
            6.0 * s
        } else {
            2.2 * fs_axis
        };
    let (fx0, fy0) = (left, title_h);
    let (fx1, fy1) = (w as f64 - 24.0 * s, h as f64 - bottom);
    let (fw, fh) = (fx1 - fx0, fy1 - fy0);
    let xticks = xaxis.ticks(target_x);
    let map = |p: [f64; 2]| -> P2 { [fx0 + xaxis.frac(p[0]) * fw, fy1 - yaxis.frac(p[1]) * fh] };

    let mut r = Raster::new(w, h);
    let mut labels = Vec::new();
    let fc = [60, 60, 60];

    // grid
    if opts.grid {
        for (v, _, major) in &xticks {
            let x = fx0 + xaxis.frac_t(*v) * fw;
            let c = if *major {
                [222, 222, 222]
            } else {
                [240, 240, 240]
            };
            r.line([x, fy0], [x, fy1], 1.0 * s, c);
        }
        for (v, _, major) in &yticks {
            let y = fy1 - yaxis.frac_t(*v) * fh;
            let c = if *major {
                [222, 222, 222]
            } else {
                [240, 240, 240]
            };
            r.line([fx0, y], [fx1, y], 1.0 * s, c);
        }
    }

    // series
    let lw = 2.0 * s;
    let ms = 4.5 * s;
    let mut entries = Vec::new();
    for (i, sr) in series.iter().enumerate() {
        let c = sr.color.unwrap_or(PALETTE[i % PALETTE.len()]);
        let marker = match sr.marker {
            Marker::Auto => [
                Marker::Circle,
                Marker::Square,
                Marker::Triangle,
                Marker::Diamond,
                Marker::Cross,
            ][i % 5],
            m => m,
        };
        let px: Vec<P2> = sr.points.iter().map(|&p| map(p)).collect();
        let draw_line = sr.line && px.len() > 1;
        if draw_line {
            if sr.dashed {
                for wnd in px.windows(2) {
                    r.dashed_line(wnd[0], wnd[1], lw, 8.0 * s, 5.0 * s, c);
                }
            } else {
                r.polyline(&px, lw, c);
            }
        }
        for &q in &px {
            draw_marker(&mut r, q, marker, ms, c, s);
        }
        if !sr.label.is_empty() {
            entries.push((sr.label.clone(), c, marker, draw_line, sr.dashed));
        }
    }

    // frame, ticks, tick labels
    r.rect_outline(fx0, fy0, fx1, fy1, 1.0 * s, fc);
    let mut last_right = f64::NEG_INFINITY;
    for (v, text, major) in &xticks {
        let x = fx0 + xaxis.frac_t(*v) * fw;
        let tl = if *major { 5.0 * s } else { 3.0 * s };
        r.line([x, fy1], [x, fy1 + tl], 1.0 * s, fc);
        let half = 0.5 * text_size(text, fs_tick).0;
        if !text.is_empty() && x - half > last_right + 6.0 * s {
            last_right = x + half;
            labels.push(Label {
                pos: [x, fy1 + 8.0 * s],
                text: text.clone(),
                size: fs_tick,
                h: HPos::Center,
                v: VPos::Top,
                color: [0, 0, 0],
                rotate: false,
            });
        }
    }
    let mut last_top = f64::INFINITY;
    for (v, text, major) in &yticks {
        let y = fy1 - yaxis.frac_t(*v) * fh;
        let tl = if *major { 5.0 * s } else { 3.0 * s };
        r.line([fx0, y], [fx0 - tl, y], 1.0 * s, fc);
        let half = 0.5 * text_size(text, fs_tick).1;
        if !text.is_empty() && y + half < last_top - 2.0 * s {
            last_top = y - half;
            labels.push(Label {
                pos: [fx0 - 8.0 * s, y],
                text: text.clone(),
                size: fs_tick,
                h: HPos::Right,
                v: VPos::Center,
                color: [0, 0, 0],
                rotate: false,
            });
        }
    }
    labels.push(Label::centered(
        [0.5 * (fx0 + fx1), fy1 + 14.0 * s + fs_tick + 0.9 * fs_axis],
        opts.x_label.clone(),
        fs_axis,
    ));
    if has_ylabel {
        let mut l = Label::centered(
            [12.0 * s + 0.5 * fs_axis, 0.5 * (fy0 + fy1)],
            opts.y_label.clone(),
            fs_axis,
        );
        l.rotate = true;
        labels.push(l);
    }
    if !opts.title.is_empty() {
        labels.push(Label::centered(
            [0.5 * (fx0 + fx1), 0.5 * title_h + 2.0 * s],
            opts.title.clone(),
            fs_title,
        ));
    }

    // legend
    if opts.legend != LegendPosition::Hidden && !entries.is_empty() {
        let lh = 1.55 * fs_legend;
        let tw = entries
            .iter()
            .map(|e| text_size(&e.0, fs_legend).0)
            .fold(0.0, f64::max);
        let (bw, bh) = (tw + 62.0 * s, entries.len() as f64 * lh + 10.0 * s);
        let pos = match opts.legend {
            LegendPosition::Best => best_corner(series, &xaxis, &yaxis, bw / fw, bh / fh),
            p => p,
        };
        let m = 10.0 * s;
        let bx = match pos {
            LegendPosition::UpperLeft | LegendPosition::LowerLeft => fx0 + m,
            _ => fx1 - m - bw,
        };
        let by = match pos {
            LegendPosition::LowerLeft | LegendPosition::LowerRight => fy1 - m - bh,
            _ => fy0 + m,
        };
        r.rect(bx, by, bx + bw, by + bh, [255, 255, 255]);
        r.rect_outline(bx, by, bx + bw, by + bh, 1.0 * s, [170, 170, 170]);
        for (i, (text, c, marker, line, dashed)) in entries.iter().enumerate() {
            let y = by + 5.0 * s + (i as f64 + 0.5) * lh;
            let (a, b) = ([bx + 8.0 * s, y], [bx + 44.0 * s, y]);
            if *line {
                if *dashed {
                    r.dashed_line(a, b, lw, 8.0 * s, 5.0 * s, *c);
                } else {
                    r.line(a, b, lw, *c);
                }
            }
            draw_marker(&mut r, [bx + 26.0 * s, y], *marker, ms, *c, s);
            labels.push(Label {
                pos: [bx + 52.0 * s, y],
                text: text.clone(),
                size: fs_legend,
                h: HPos::Left,
                v: VPos::Center,
                color: [0, 0, 0],
                rotate: false,
            });
        }
    }
    finish(path, r, &labels, ss)
}

/// A linear or logarithmic axis of [`plot_lines`], in transformed units (log10 on log axes).
struct LineAxis {
    log: bool,
    a: f64,
    b: f64,
}

impl LineAxis {
    /// The data range (already checked finite, and positive on log axes) plus 5 % margins.
    fn new(values: impl IntoIterator<Item = f64>, log: bool) -> Self {
        let (lo, hi) = min_max(values);
        let (lo, hi) = if log {
            (lo.log10(), hi.log10())
        } else {
            (lo, hi)
        };
        let (lo, hi) = if hi - lo < 1e-12 * lo.abs().max(1.0) {
            if log {
                (lo - 0.5, hi + 0.5)
            } else {
                widen(lo, hi)
            }
        } else {
            (lo, hi)
        };
        let m = 0.05 * (hi - lo);
        Self {
            log,
            a: lo - m,
            b: hi + m,
        }
    }
    /// Position in [0, 1] of a data value.
    fn frac(&self, v: f64) -> f64 {
        self.frac_t(if self.log { v.log10() } else { v })
    }
    /// Position in [0, 1] of a transformed value.
    fn frac_t(&self, t: f64) -> f64 {
        (t - self.a) / (self.b - self.a)
    }
    /// Ticks as (transformed value, label, major); minor ticks have empty labels.
    fn ticks(&self, target: f64) -> Vec<(f64, String, bool)> {
        if !self.log {
            let step = nice_step(self.a, self.b, target);
            return ticks_in(self.a, self.b, step)
                .into_iter()
                .map(|t| (t, fmt_tick(t, step), true))
                .collect();
        }
        let decades = self.b - self.a;
        let (k0, k1) = (self.a.floor() as i64, self.b.ceil() as i64);
        // which mantissas get a label
        let labelled: &[u32] = if decades > 2.5 {
            &[1]
        } else if decades > 1.2 {
            &[1, 2, 5]
        } else if decades > 0.5 {
            &[1, 2, 3, 5]
        } else {
            &[1, 2, 3, 4, 5, 6, 7, 8, 9]
        };
        let every = ((decades / target).ceil() as i64).max(1);
        let mut out = Vec::new();
        for k in k0..=k1 {
            for m in 1..=9u32 {
                if decades > 8.0 && m > 1 {
                    continue;
                }
                let t = k as f64 + (m as f64).log10();
                if t < self.a - 1e-12 || t > self.b + 1e-12 {
                    continue;
                }
                let major = m == 1 && k.rem_euclid(every) == 0;
                let text = if (major || (m > 1 && labelled.contains(&m))) && (m == 1 || every == 1)
                {
                    fmt_log_value(m, k)
                } else {
                    String::new()
                };
                out.push((t, text, m == 1));
            }
        }
        // with less than two labelled ticks, label everything that is ticked
        if out.iter().filter(|t| !t.1.is_empty()).count() < 2 {
            for t in &mut out {
                let k = t.0.floor() as i64;
                let m = 10f64.powf(t.0 - k as f64).round() as u32;
                t.1 = fmt_log_value(m, k);
            }
        }
        out
    }
}

/// Formats m·10^k compactly: plain decimals for moderate magnitudes, 10ⁿ or m×10ⁿ otherwise.
fn fmt_log_value(m: u32, k: i64) -> String {
    if (-3..=4).contains(&k) {
        let v = m as f64 * 10f64.powi(k as i32);
        let dec = (-k).max(0) as usize;
        return format!("{v:.dec$}");
    }
    let sup: String = k
        .to_string()
        .chars()
        .map(|c| match c {
            '-' => '\u{207B}',
            '1' => '\u{00B9}',
            '2' => '\u{00B2}',
            '3' => '\u{00B3}',
            d => char::from_u32(0x2070 + d.to_digit(10).unwrap_or(0)).unwrap_or(d),
        })
        .collect();
    if m == 1 {
        format!("10{sup}")
    } else {
        format!("{m}\u{00D7}10{sup}")
    }
}

/// The legend corner (legend of relative size `lw` × `lh`) that covers the fewest data points
/// and line samples.
fn best_corner(
    series: &[LineSeries],
    xa: &LineAxis,
    ya: &LineAxis,
    lw: f64,
    lh: f64,
) -> LegendPosition {
    let (lw, lh) = (lw + 0.03, lh + 0.03);
    let cands = [
        (LegendPosition::UpperRight, 1.0 - lw, 1.0, 1.0 - lh, 1.0),
        (LegendPosition::UpperLeft, 0.0, lw, 1.0 - lh, 1.0),
        (LegendPosition::LowerRight, 1.0 - lw, 1.0, 0.0, lh),
        (LegendPosition::LowerLeft, 0.0, lw, 0.0, lh),
    ];
    let mut best = (usize::MAX, LegendPosition::UpperRight);
    for (pos, u0, u1, v0, v1) in cands {
        let mut count = 0;
        for sr in series {
            let uv: Vec<(f64, f64)> = sr
                .points
                .iter()
                .map(|p| (xa.frac(p[0]), ya.frac(p[1])))
                .collect();
            let mut samples = uv.clone();
            if sr.line {
                for wnd in uv.windows(2) {
                    for i in 1..16 {
                        let t = i as f64 / 16.0;
                        samples.push((
                            wnd[0].0 + t * (wnd[1].0 - wnd[0].0),
                            wnd[0].1 + t * (wnd[1].1 - wnd[0].1),
                        ));
                    }
                }
            }
            count += samples
                .iter()
                .filter(|(u, v)| *u >= u0 && *u <= u1 && *v >= v0 && *v <= v1)
                .count();
        }
        if count < best.0 {
            best = (count, pos);
        }
    }
    best.1
}

/// Draws a marker of radius `r` (pixels) at `q`.
fn draw_marker(raster: &mut Raster, q: P2, marker: Marker, r: f64, c: Rgb, s: f64) {
    match marker {
        Marker::None | Marker::Auto => {}
        Marker::Circle => raster.disc(q, r, c),
        Marker::Cross => {
            let a = 0.95 * r;
            raster.line([q[0] - a, q[1] - a], [q[0] + a, q[1] + a], 1.8 * s, c);
            raster.line([q[0] - a, q[1] + a], [q[0] + a, q[1] - a], 1.8 * s, c);
        }
        m => {
            let shape: &[(f64, f64)] = match m {
                Marker::Square => &[(-0.85, -0.85), (0.85, -0.85), (0.85, 0.85), (-0.85, 0.85)],
                Marker::Triangle => &[(0.0, -1.2), (1.05, 0.65), (-1.05, 0.65)],
                _ => &[(0.0, -1.25), (1.0, 0.0), (0.0, 1.25), (-1.0, 0.0)],
            };
            let pts: Vec<P2> = shape
                .iter()
                .map(|&(x, y)| [q[0] + r * x, q[1] + r * y])
                .collect();
            raster.fill_convex(&pts, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn grid(n: usize) -> PolyMesh {
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                v.push([i as f64 / n as f64, j as f64 / n as f64]);
            }
        }
        let mut c = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i;
                c.push(vec![a, a + 1, a + n + 2, a + n + 1]);
            }
        }
        PolyMesh::from_cells(v, c).expect("valid grid")
    }

    fn tri_grid(n: usize) -> PolyMesh {
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                v.push([i as f64 / n as f64, j as f64 / n as f64]);
            }
        }
        let mut c = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i;
                c.push(vec![a, a + 1, a + n + 2]);
                c.push(vec![a, a + n + 2, a + n + 1]);
            }
        }
        PolyMesh::from_cells(v, c).expect("valid grid")
    }

    fn tmp(name: &str) -> PathBuf {
        std::env::temp_dir()
            .join(format!("gradvi-plot-test-{}", std::process::id()))
            .join(name)
    }

    /// Width and height from the PNG signature and IHDR chunk.
    fn png_size(path: &Path) -> (u32, u32) {
        let b = std::fs::read(path).expect("png written");
        assert!(b.len() > 24, "png too short");
        assert_eq!(&b[..8], &[137, 80, 78, 71, 13, 10, 26, 10], "png signature");
        assert_eq!(&b[12..16], b"IHDR");
        let w = u32::from_be_bytes([b[16], b[17], b[18], b[19]]);
        let h = u32::from_be_bytes([b[20], b[21], b[22], b[23]]);
        (w, h)
    }

    fn bump(p: [f64; 2]) -> f64 {
        (std::f64::consts::PI * p[0]).sin() * (std::f64::consts::PI * p[1]).sin() - 0.5
    }

    fn small_surface() -> SurfaceOptions {
        SurfaceOptions {
            title: "test".into(),
            size: (160, 120),
            ..Default::default()
        }
    }

    #[test]
    fn surface_cell_field_writes_png_of_requested_size() {
        let m = grid(6);
        let u: Vec<f64> = (0..m.n_cells()).map(|k| bump(m.centroid(k))).collect();
        let path = tmp("nested/dir/surface_cell.png");
        let opts = SurfaceOptions {
            markers: vec![([0.5, 0.0, -0.5], "switch".into())],
            lines: vec![vec![[0.5, 0.0, -0.5], [0.5, 0.0, 0.5]]],
            ..small_surface()
        };
        plot_surface(&path, &m, Field::Cell(&u), &opts).expect("plot");
        assert_eq!(png_size(&path), (160, 120));
        let flat = tmp("surface_flat.png");
        let opts = SurfaceOptions {
            cell_rendering: CellRendering::Flat,
            colorbar: false,
            supersample: 1,
            ..small_surface()
        };
        plot_surface(&flat, &m, Field::Cell(&u), &opts).expect("plot");
        assert_eq!(png_size(&flat), (160, 120));
    }

    #[test]
    fn surface_vertex_field_and_polygons() {
        let m = tri_grid(5);
        let u: Vec<f64> = m.vertices().iter().map(|&p| bump(p)).collect();
        let path = tmp("surface_vertex.png");
        plot_surface(&path, &m, Field::Vertex(&u), &small_surface()).expect("plot");
        assert_eq!(png_size(&path), (160, 120));
        // quadrilaterals with a vertex field, constant data, unusual view
        let q = grid(3);
        let c = vec![1.0; q.n_vertices()];
        let opts = SurfaceOptions {
            azimuth: 120.0,
            elevation: -20.0,
            edges: Some(true),
            colormap: Colormap::Parula,
            ..small_surface()
        };
        plot_surface(&path, &q, Field::Vertex(&c), &opts).expect("plot");
        assert_eq!(png_size(&path), (160, 120));
    }

    #[test]
    fn surface_rejects_bad_input() {
        let m = grid(3);
        let path = tmp("surface_bad.png");
        let short = vec![0.0; m.n_cells() - 1];
        let e = plot_surface(&path, &m, Field::Cell(&short), &small_surface());
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let e = plot_surface(&path, &m, Field::Vertex(&short), &small_surface());
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let mut u = vec![0.0; m.n_cells()];
        u[4] = f64::NAN;
        let e = plot_surface(&path, &m, Field::Cell(&u), &small_surface());
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let u = vec![0.0; m.n_cells()];
        let opts = SurfaceOptions {
            markers: vec![([0.0, f64::INFINITY, 0.0], "m".into())],
            ..small_surface()
        };
        let e = plot_surface(&path, &m, Field::Cell(&u), &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let opts = SurfaceOptions {
            z_range: Some((1.0, 0.0)),
            ..small_surface()
        };
        let e = plot_surface(&path, &m, Field::Cell(&u), &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let e = plot_surface(&tmp("surface.jpg"), &m, Field::Cell(&u), &small_surface());
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let opts = SurfaceOptions {
            size: (0, 10),
            ..small_surface()
        };
        let e = plot_surface(&path, &m, Field::Cell(&u), &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        assert!(!path.exists());
    }

    #[test]
    fn unwritable_path_is_an_io_error() {
        let m = grid(2);
        let u = vec![0.0; m.n_cells()];
        let file = tmp("not_a_dir.png");
        plot_surface(&file, &m, Field::Cell(&u), &small_surface()).expect("plot");
        // a path "below" a regular file cannot be created
        let e = plot_surface(&file.join("x.png"), &m, Field::Cell(&u), &small_surface());
        assert!(matches!(e, Err(Error::Io { .. })), "{e:?}");
    }

    #[test]
    fn output_is_deterministic() {
        let m = grid(4);
        let u: Vec<f64> = (0..m.n_cells()).map(|k| bump(m.centroid(k))).collect();
        let (a, b) = (tmp("det_a.png"), tmp("det_b.png"));
        plot_surface(&a, &m, Field::Cell(&u), &small_surface()).expect("plot");
        plot_surface(&b, &m, Field::Cell(&u), &small_surface()).expect("plot");
        assert_eq!(std::fs::read(&a).ok(), std::fs::read(&b).ok());
    }

    #[test]
    fn mesh_plot_with_tags_values_and_annotations() {
        let m = grid(5).with_boundary_tags(|p| {
            if p[1] > 1.0 - 1e-12 {
                1
            } else if p[1] < 1e-12 {
                3
            } else {
                2
            }
        });
        let path = tmp("mesh.png");
        let opts = MeshPlotOptions {
            title: "mesh".into(),
            size: (200, 150),
            boundary_labels: vec![(1, "Γ1".into()), (2, "Γ2".into()), (3, "Γ3".into())],
            annotations: vec![
                ([0.5, 0.25], "A = 100 I".into()),
                ([0.5, 0.75], "A = I".into()),
            ],
            hlines: vec![0.5],
            vlines: vec![0.25],
            cell_values: Some((0..m.n_cells()).map(|k| m.centroid(k)[0]).collect()),
            ..Default::default()
        };
        plot_mesh(&path, &m, &opts).expect("plot");
        assert_eq!(png_size(&path), (200, 150));
        let bare = MeshPlotOptions {
            size: (120, 100),
            axes: false,
            supersample: 1,
            ..Default::default()
        };
        plot_mesh(&path, &tri_grid(3), &bare).expect("plot");
        assert_eq!(png_size(&path), (120, 100));
    }

    #[test]
    fn mesh_plot_rejects_bad_input() {
        let m = grid(3);
        let path = tmp("mesh_bad.png");
        let opts = MeshPlotOptions {
            cell_values: Some(vec![1.0; m.n_cells() + 1]),
            ..Default::default()
        };
        let e = plot_mesh(&path, &m, &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let mut v = vec![1.0; m.n_cells()];
        v[0] = f64::NAN;
        let opts = MeshPlotOptions {
            cell_values: Some(v),
            ..Default::default()
        };
        let e = plot_mesh(&path, &m, &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let opts = MeshPlotOptions {
            hlines: vec![f64::NAN],
            ..Default::default()
        };
        let e = plot_mesh(&path, &m, &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
    }

    #[test]
    fn line_plots_linear_and_loglog() {
        let h = [0.24, 0.13, 0.07, 0.03];
        let e1: Vec<[f64; 2]> = h.iter().map(|&h| [h, 2.0 * h * h]).collect();
        let e2: Vec<[f64; 2]> = h.iter().map(|&h| [h, 0.8 * h]).collect();
        let mut slope = LineSeries::new("O(h)", h.iter().map(|&h| [h, h]).collect());
        slope.dashed = true;
        slope.marker = Marker::None;
        let series = [LineSeries::new("L2", e1), LineSeries::new("H1", e2), slope];
        let path = tmp("lines_log.png");
        let opts = LineOptions {
            title: "convergence".into(),
            x_label: "h".into(),
            y_label: "error".into(),
            size: (220, 160),
            log_x: true,
            log_y: true,
            ..Default::default()
        };
        plot_lines(&path, &series, &opts).expect("plot");
        assert_eq!(png_size(&path), (220, 160));
        let lin = LineOptions {
            size: (200, 150),
            legend: LegendPosition::LowerLeft,
            ..Default::default()
        };
        let one = [LineSeries::new("single point", vec![[1.0, 1.0]])];
        plot_lines(&path, &one, &lin).expect("plot");
        assert_eq!(png_size(&path), (200, 150));
    }

    #[test]
    fn line_plot_rejects_bad_input() {
        let path = tmp("lines_bad.png");
        let opts = LineOptions::default();
        let e = plot_lines(&path, &[], &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let e = plot_lines(&path, &[LineSeries::new("empty", vec![])], &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let nan = [LineSeries::new("nan", vec![[0.0, 1.0], [1.0, f64::NAN]])];
        let e = plot_lines(&path, &nan, &opts);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
        let neg = [LineSeries::new("neg", vec![[1.0, 1.0], [2.0, -1.0]])];
        let log = LineOptions {
            log_y: true,
            ..Default::default()
        };
        let e = plot_lines(&path, &neg, &log);
        assert!(matches!(e, Err(Error::InvalidData(_))), "{e:?}");
    }

    #[test]
    fn raster_shared_edges_leave_no_gap_and_no_overlap() {
        let mut r = Raster::new(40, 40);
        // a square split along a sloped diagonal, vertices off the pixel grid
        let (a, b, c, d) = ([3.3, 4.1], [35.7, 5.2], [33.9, 36.6], [2.2, 34.8]);
        r.fill_convex(&[a, b, c], [255, 0, 0]);
        r.fill_convex(&[a, c, d], [0, 0, 255]);
        let mut r2 = Raster::new(40, 40);
        r2.fill_convex(&[a, b, c, d], [0, 0, 0]);
        for i in 0..40 * 40 {
            let covered_by_quad = r2.buf[3 * i] == 0;
            let px = &r.buf[3 * i..3 * i + 3];
            let covered = px != [255, 255, 255];
            assert_eq!(covered, covered_by_quad, "pixel {i}");
        }
        // overlap would need a third colour; there are only red, blue and white pixels
        assert!(
            r.buf
                .chunks(3)
                .all(|p| p == [255, 0, 0] || p == [0, 0, 255] || p == [255, 255, 255])
        );
    }

    #[test]
    fn tick_helpers() {
        assert_eq!(nice_step(0.0, 1.0, 5.0), 0.2);
        assert_eq!(ticks_in(0.0, 1.0, 0.25).len(), 5);
        assert_eq!(fmt_tick(0.5, 0.1), "0.5");
        assert_eq!(fmt_tick(-0.25, 0.25), "\u{2212}0.25");
        assert_eq!(fmt_tick(1e-17, 0.2), "0.0");
        assert_eq!(fmt_log_value(1, -5), "10\u{207B}\u{2075}");
        assert_eq!(fmt_log_value(2, -2), "0.02");
        assert_eq!(Colormap::Viridis.rgb(0.0), [68, 1, 84]);
        assert_eq!(Colormap::Viridis.rgb(1.0), [253, 231, 37]);
        assert_eq!(Colormap::Viridis.rgb(f64::NAN), [68, 1, 84]);
    }
}
