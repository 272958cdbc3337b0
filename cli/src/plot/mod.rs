//! PNG figures drawn with `plotters`: 3D views of discrete solutions ([`plot_surface`]), mesh
//! pictures ([`plot_mesh`]) and x–y line plots, alone ([`plot_lines`]) or as small multiples
//! ([`plot_panels`]).
//!
//! plotters draws the axes, ticks, log scales, grids, legends, lines, markers, polygons and text
//! and writes the PNG; the text uses the DejaVu Sans font embedded in the binary
//! (`assets/fonts`, Bitstream Vera licence), so nothing has to be installed. What is this
//! project's own is in [`surface`]: the graph of a piecewise affine function on polygonal cells
//! as triangles, drawn back to front (painter's algorithm) and coloured by value ([`viridis`]).
//!
//! Every function writes a PNG file (the path must end in `.png`, missing parent directories are
//! created), is deterministic, reports bad input as [`Error::InvalidData`] and write failures as
//! [`Error::Io`], and never panics on user input. Pictures are drawn at [`SUPERSAMPLE`]× the
//! requested size and box-filtered down, because plotters fills polygons without anti-aliasing.

mod lines;
mod mesh;
mod slice;
pub mod surface;

pub use lines::{LineOptions, LineSeries, Marker, data_range, plot_lines, plot_panels};
pub use mesh::{MeshPlotOptions, plot_mesh};
pub use plotters::chart::SeriesLabelPosition as LegendPosition;
pub use slice::{SliceCell, SliceOptions, plot_slice};
pub use surface::{SurfaceOptions, plot_surface};

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use gradvi::error::{Error, Result};

/// DejaVu Sans (Bitstream Vera licence, see `assets/fonts/LICENSE-DejaVu.txt`).
static FONT_BYTES: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../assets/fonts/DejaVuSans.ttf"
));

/// Family name under which the embedded font is registered.
const FONT: &str = "sans-serif";

/// Pictures are drawn this many times larger and box-filtered down (anti-aliasing).
pub const SUPERSAMPLE: u32 = 2;

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

/// matplotlib's viridis at 11 evenly spaced values, as 0xRRGGBB.
const VIRIDIS: [u32; 11] = [
    0x440154, 0x482475, 0x414487, 0x355f8d, 0x2a788e, 0x21918c, 0x22a884, 0x44bf70, 0x7ad151,
    0xbddf26, 0xfde725,
];

/// The red, green and blue of 0xRRGGBB.
fn channels(c: u32) -> [u8; 3] {
    [(c >> 16) as u8, (c >> 8) as u8, c as u8]
}

/// matplotlib's viridis colour map (dark blue → green → yellow) at `t` ∈ [0, 1] (clamped; NaN
/// maps to 0).
pub fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let (a, b, f) = (channels(VIRIDIS[i]), channels(VIRIDIS[i + 1]), x - i as f64);
    std::array::from_fn(|ch| (a[ch] as f64 + f * (b[ch] as f64 - a[ch] as f64)).round() as u8)
}

/// The `i`-th colour (cyclic) of matplotlib's qualitative palette "tab10", for series and
/// boundary tags.
pub fn palette(i: usize) -> [u8; 3] {
    const TAB10: [u32; 10] = [
        0x1f77b4, 0xd62728, 0x2ca02c, 0xff7f0e, 0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22,
        0x17becf,
    ];
    channels(TAB10[i % TAB10.len()])
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// The embedded font at `size` (pixels of the output picture) on a canvas scaled by `s`.
fn font(size: f64, s: f64) -> TextStyle<'static> {
    (FONT, size * s).into_font().into()
}

/// A tick label: plain decimals (at most 6 significant digits), 10ⁿ for large and small powers
/// of ten, a true minus sign.
fn tick_label(v: f64) -> String {
    let a = v.abs();
    let k = a.log10().round();
    let text = if a != 0.0 && !(1e-3..1e5).contains(&a) && (a / 10f64.powf(k) - 1.0).abs() < 1e-9 {
        const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
        let digits = (k as i64).to_string();
        let sup: String = (digits.chars())
            .map(|c| c.to_digit(10).map_or('⁻', |d| SUP[d as usize]))
            .collect();
        format!("{}10{sup}", if v < 0.0 { "-" } else { "" })
    } else {
        let t = format!("{v:.6}");
        let t = t.trim_end_matches('0').trim_end_matches('.');
        if t == "-0" { "0".into() } else { t.to_string() }
    };
    text.replace('-', "\u{2212}")
}

/// A tick label of a log axis: only mantissas 1, 2 and 5 are written (plotters puts a tick at
/// every mantissa on axes shorter than a decade or two).
fn log_tick_label(v: f64) -> String {
    let m = v / 10f64.powf(v.log10().floor());
    if [1.0, 2.0, 5.0, 10.0].iter().any(|x| (m - x).abs() < 1e-6) {
        tick_label(v)
    } else {
        String::new()
    }
}

fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Error::InvalidData(format!(
            "{what}: value {i} is not finite ({})",
            values[i]
        ))),
        None => Ok(()),
    }
}

fn min_max(values: impl IntoIterator<Item = f64>) -> (f64, f64) {
    (values.into_iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    })
}

/// Widens an empty or degenerate range so that it can be drawn.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if hi - lo > 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        (lo, hi)
    } else {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    }
}

type Canvas<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawError = Box<dyn std::error::Error>;
type Draw = std::result::Result<(), DrawError>;

/// Draws a picture of `size` pixels with `draw(root, scale)` on a canvas [`SUPERSAMPLE`] times
/// larger, filters it down and writes it to `path` as PNG.
fn render(path: &Path, size: (u32, u32), draw: impl FnOnce(&Canvas, f64) -> Draw) -> Result<()> {
    if path.extension().and_then(|e| e.to_str()) != Some("png") {
        let msg = format!("{}: a plot must be written to a .png file", path.display());
        return Err(Error::InvalidData(msg));
    }
    if !(16..=10_000).contains(&size.0) || !(16..=10_000).contains(&size.1) {
        let msg = format!(
            "plot size {}×{} is not within 16–10000 pixels",
            size.0, size.1
        );
        return Err(Error::InvalidData(msg));
    }
    ensure_font()?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    let (ss, w) = (SUPERSAMPLE as usize, size.0 as usize);
    let mut big = vec![255u8; w * size.1 as usize * 3 * ss * ss];
    {
        let big_size = (size.0 * SUPERSAMPLE, size.1 * SUPERSAMPLE);
        let root = BitMapBackend::with_buffer(&mut big, big_size).into_drawing_area();
        let bad = |e: &dyn std::fmt::Display| Error::InvalidData(format!("plot: {e}"));
        draw(&root, SUPERSAMPLE as f64).map_err(|e| bad(&e))?;
        root.present().map_err(|e| bad(&e))?;
    }
    let small: Vec<u8> = (0..w * size.1 as usize * 3)
        .map(|i| {
            let (x, y, ch) = (i / 3 % w, i / 3 / w, i % 3);
            let at = |dx: usize, dy: usize| big[3 * ((y * ss + dy) * w * ss + x * ss + dx) + ch];
            let sum: usize = (0..ss * ss).map(|j| at(j % ss, j / ss) as usize).sum();
            ((sum + ss * ss / 2) / (ss * ss)) as u8
        })
        .collect();
    let io = |e: &dyn std::fmt::Display| Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    };
    let mut out = BitMapBackend::new(path, size);
    out.blit_bitmap((0, 0), size, &small).map_err(|e| io(&e))?;
    out.present().map_err(|e| io(&e))
}

/// `area` under `title` (unchanged if the title is empty).
fn titled<'a>(
    area: &Canvas<'a>,
    title: &str,
    s: f64,
) -> std::result::Result<Canvas<'a>, DrawError> {
    if title.is_empty() {
        return Ok(area.clone());
    }
    let area = area.margin((8.0 * s) as u32, 0, 0, 0);
    Ok(area.titled(title, font(17.0, s))?)
}

/// `text` on a white box with a grey frame, centred at (or, with `beside`, above and right of)
/// the pixel `at` of the whole picture `root`.
fn boxed_text(root: &Canvas, at: (i32, i32), text: &str, s: f64, beside: bool) -> Draw {
    let style = font(13.0, s);
    let (tw, th) = root.estimate_text_size(text, &style)?;
    let (tw, th, p) = (tw as i32, th as i32, (4.0 * s) as i32);
    let x0 = at.0
        + if beside {
            (8.0 * s) as i32
        } else {
            -tw / 2 - p
        };
    let y0 = at.1
        + if beside {
            -th - (8.0 * s) as i32 - p
        } else {
            -th / 2 - p
        };
    let corners = [(x0, y0), (x0 + tw + 2 * p, y0 + th + 2 * p)];
    root.draw(&Rectangle::new(corners, WHITE.filled()))?;
    let frame = RGBColor(120, 120, 120).stroke_width(s as u32);
    root.draw(&Rectangle::new(corners, frame))?;
    let pos = Pos::new(HPos::Left, VPos::Top);
    root.draw(&Text::new(
        text.to_string(),
        (x0 + p, y0 + p),
        style.pos(pos),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path in a fresh temporary directory.
    pub(super) fn tmp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir()
            .join(format!("gradvi-plot-test-{}", std::process::id()))
            .join(name)
    }

    /// Width and height from the PNG signature and IHDR chunk.
    pub(super) fn png_size(path: &Path) -> (u32, u32) {
        let b = std::fs::read(path).expect("png written");
        assert_eq!(&b[..8], &[137, 80, 78, 71, 13, 10, 26, 10], "png signature");
        assert_eq!(&b[12..16], b"IHDR");
        let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        (be(16), be(20))
    }

    pub(super) fn invalid(r: Result<()>) {
        assert!(matches!(r, Err(Error::InvalidData(_))), "{r:?}");
    }

    #[test]
    fn render_checks_the_path_and_size_and_writes_a_png() {
        let white = |_: &Canvas, _: f64| -> Draw { Ok(()) };
        invalid(render(&tmp("x.jpg"), (100, 100), white));
        invalid(render(&tmp("x.png"), (0, 100), white));
        let path = tmp("nested/dir/white.png");
        render(&path, (40, 30), white).expect("render");
        assert_eq!(png_size(&path), (40, 30));
        // a path "below" a regular file cannot be created
        let e = render(&path.join("x.png"), (40, 30), white);
        assert!(matches!(e, Err(Error::Io { .. })), "{e:?}");
    }

    #[test]
    fn tick_labels_and_colours() {
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(-0.25), "\u{2212}0.25");
        assert_eq!(tick_label(1e-17 - 1e-17), "0");
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(1e6), "10\u{2076}");
        assert_eq!(tick_label(1e-5), "10\u{207B}\u{2075}");
        assert_eq!(log_tick_label(0.02), "0.02");
        assert_eq!(log_tick_label(3000.0), "");
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(f64::NAN), [68, 1, 84]);
        assert_eq!(palette(10), palette(0));
    }
}
