//! Geometry of points and polygons: differences and distances of points, the signed area and
//! centroid of a polygon, the normal and distance of a cell side.

use super::Point;

pub(crate) fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}

pub(crate) fn dist(a: Point, b: Point) -> f64 {
    let d = sub(a, b);
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

/// n_{K,σ} and d_{K,σ} of the side from corner `p` to corner `q` of a counter-clockwise cell
/// with centroid `xk`: the outward unit normal (the tangent rotated by −90°) and
/// d_{K,σ} = (x_σ − x_K)·n_{K,σ}. The one definition of both, used by the validation (check 9)
/// and by the accessors of [`PolyMesh`], so that they agree to the last bit.
#[inline]
pub(crate) fn side_normal_dist(p: Point, q: Point, xk: Point) -> (Point, f64) {
    let t = sub(q, p);
    let len = (t[0] * t[0] + t[1] * t[1]).sqrt();
    // counter-clockwise cell: outward normal is the tangent rotated by −90°
    let nrm = [t[1] / len, -t[0] / len];
    // x_σ, the same bits as `PolyMesh::edge_midpoint` (floating-point addition commutes)
    let xs = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
    let d = (xs[0] - xk[0]) * nrm[0] + (xs[1] - xk[1]) * nrm[1];
    (nrm, d)
}

/// Signed area and centroid of a polygon given by its vertices in order
/// (positive area for counter-clockwise order). Computed relative to the first vertex
/// for accuracy.
pub fn polygon_area_centroid(pts: &[Point]) -> (f64, Point) {
    polygon_area_centroid_of(pts.len(), |i| pts[i])
}

/// [`polygon_area_centroid`] of the polygon whose `m` corners are `pt(0)`, …, `pt(m − 1)`, with
/// the same operations in the same order (the same bits), without a slice of them.
#[inline]
pub(crate) fn polygon_area_centroid_of(m: usize, pt: impl Fn(usize) -> Point) -> (f64, Point) {
    let o = pt(0);
    let mut a2 = 0.0;
    let mut cx = 0.0;
    let mut cy = 0.0;
    for i in 1..m.saturating_sub(1) {
        let p = sub(pt(i), o);
        let q = sub(pt(i + 1), o);
        let cr = p[0] * q[1] - p[1] * q[0];
        a2 += cr;
        cx += cr * (p[0] + q[0]);
        cy += cr * (p[1] + q[1]);
    }
    let area = 0.5 * a2;
    if a2 == 0.0 {
        return (0.0, o);
    }
    (area, [o[0] + cx / (3.0 * a2), o[1] + cy / (3.0 * a2)])
}

/// An axis-parallel rectangle \[x0, x1\] × \[y0, y1\]: the x range, then the y range. The one
/// meaning of a rectangle in the crate: [`PolyMesh::bounding_box`](super::PolyMesh::bounding_box)
/// returns one, [`Family::generate_on`](super::generate::Family::generate_on) takes one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// \[x0, x1\], the range in x.
    pub x: [f64; 2],
    /// \[y0, y1\], the range in y.
    pub y: [f64; 2],
}

impl Rect {
    /// The unit square \[0, 1\]².
    pub const UNIT: Rect = Rect {
        x: [0.0, 1.0],
        y: [0.0, 1.0],
    };

    /// \[x\[0\], x\[1\]\] × \[y\[0\], y\[1\]\].
    pub const fn new(x: [f64; 2], y: [f64; 2]) -> Self {
        Rect { x, y }
    }

    /// x1 − x0.
    pub fn width(&self) -> f64 {
        self.x[1] - self.x[0]
    }

    /// y1 − y0.
    pub fn height(&self) -> f64 {
        self.y[1] - self.y[0]
    }

    /// The lower-left corner (x0, y0).
    pub fn min(&self) -> Point {
        [self.x[0], self.y[0]]
    }

    /// The upper-right corner (x1, y1).
    pub fn max(&self) -> Point {
        [self.x[1], self.y[1]]
    }

    /// Whether `p` lies in the closed rectangle.
    pub fn contains(&self, p: Point) -> bool {
        (self.x[0]..=self.x[1]).contains(&p[0]) && (self.y[0]..=self.y[1]).contains(&p[1])
    }

    /// Whether the bounds are finite with x0 < x1 and y0 < y1 (a rectangle with an interior).
    pub fn is_proper(&self) -> bool {
        self.x[1] > self.x[0]
            && self.y[1] > self.y[0]
            && [self.x, self.y].iter().flatten().all(|v| v.is_finite())
    }
}

impl std::fmt::Display for Rect {
    /// `[x0, x1]x[y0, y1]`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ([x0, x1], [y0, y1]) = (self.x, self.y);
        write!(f, "[{x0}, {x1}]x[{y0}, {y1}]")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rect_is_the_x_range_then_the_y_range() {
        let r = Rect::new([-2.0, 2.0], [-1.0, 0.5]);
        assert_eq!((r.width(), r.height()), (4.0, 1.5));
        assert_eq!((r.min(), r.max()), ([-2.0, -1.0], [2.0, 0.5]));
        assert!(r.contains([2.0, 0.5]) && r.contains([0.0, 0.0]));
        assert!(!r.contains([0.0, 1.0]) && !r.contains([-3.0, 0.0]));
        assert!(r.is_proper() && Rect::UNIT.is_proper());
        assert_eq!(r.to_string(), "[-2, 2]x[-1, 0.5]");
        for bad in [
            Rect::new([1.0, 0.0], [0.0, 1.0]),
            Rect::new([0.0, f64::NAN], [0.0, 1.0]),
            Rect::new([0.0, 1.0], [2.0, 2.0]),
            Rect::new([0.0, f64::INFINITY], [0.0, 1.0]),
        ] {
            assert!(!bad.is_proper(), "{bad}");
        }
    }

    #[test]
    fn polygon_area_and_centroid() {
        // a counter-clockwise unit square shifted to (2, 3), and the same clockwise
        let sq = [[2.0, 3.0], [3.0, 3.0], [3.0, 4.0], [2.0, 4.0]];
        assert_eq!(polygon_area_centroid(&sq), (1.0, [2.5, 3.5]));
        let mut cw = sq;
        cw.reverse();
        assert_eq!(polygon_area_centroid(&cw).0, -1.0);
        // degenerate: three points on a line
        assert_eq!(
            polygon_area_centroid(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
            (0.0, [0.0, 0.0])
        );
    }
}
