//! Exact geometric predicates on points with `f64` coordinates.
//!
//! The mesh checks decide "do these two segments meet?" and "which side of this segment is that
//! point on?"; answered in plain floating point, near-degenerate inputs can get inconsistent
//! answers (a point found above a segment by one test and below it by another), which breaks
//! the invariants of the sweep in [`super::sweep`]. So the sign of the orientation determinant
//! is computed exactly: a floating-point evaluation with Shewchuk's error bound decides almost
//! every case, and the rare undecided ones are evaluated exactly with floating-point expansions
//! (J. R. Shewchuk, *Adaptive precision floating-point arithmetic and fast robust geometric
//! predicates*, 1997). Every other predicate here is built from [`orient`] and from comparisons
//! of coordinates, so all are exact.
//!
//! Exactness assumes finite coordinates (the mesh constructor checks this) whose magnitudes are
//! within a factor 2^900 of each other (otherwise the exact path may underflow).

use super::Point;
use std::cmp::Ordering;

/// Lexicographic order of points: by x, then by y (the order of the sweep).
/// `-0.0` and `0.0` compare equal; coordinates are finite.
pub(crate) fn lex(a: Point, b: Point) -> Ordering {
    let x = a[0].partial_cmp(&b[0]).unwrap_or(Ordering::Equal);
    x.then(a[1].partial_cmp(&b[1]).unwrap_or(Ordering::Equal))
}

/// Shewchuk's `ccwerrboundA` = (3 + 16ε)ε with ε = 2⁻⁵³.
const ORIENT_ERRBOUND: f64 = (3.0 + 16.0 * f64::EPSILON / 2.0) * (f64::EPSILON / 2.0);

/// The sign of det(b − a, c − a): `Greater` if c lies to the left of the directed line a → b
/// (a, b, c counter-clockwise), `Less` if to the right, `Equal` if the three points are
/// collinear. Exact.
pub(crate) fn orient(a: Point, b: Point, c: Point) -> Ordering {
    let (ux, uy) = (b[0] - a[0], b[1] - a[1]);
    let (vx, vy) = (c[0] - a[0], c[1] - a[1]);
    let left = ux * vy;
    let right = uy * vx;
    let det = left - right;
    let bound = ORIENT_ERRBOUND * (left.abs() + right.abs());
    if det > bound {
        Ordering::Greater
    } else if -det > bound {
        Ordering::Less
    } else if (ux == 0.0 || vy == 0.0) && (uy == 0.0 || vx == 0.0) {
        // both products have an exactly zero factor (x − y == 0 only if x == y): collinear,
        // the common case of axis-aligned points
        Ordering::Equal
    } else {
        orient_exact(a, b, c)
    }
}

/// (s, e) with s = fl(a + b) and s + e = a + b exactly (Knuth's two-sum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// (p, e) with p = fl(a·b) and p + e = a·b exactly (barring underflow), by a fused multiply-add.
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// Adds `b` to the non-overlapping expansion `e[..*n]` (increasing magnitude), dropping zero
/// components (Shewchuk's `grow_expansion_zeroelim`).
fn grow_expansion(e: &mut [f64; 12], n: &mut usize, b: f64) {
    let mut q = b;
    let mut k = 0;
    for i in 0..*n {
        let (s, h) = two_sum(q, e[i]);
        q = s;
        if h != 0.0 {
            e[k] = h;
            k += 1;
        }
    }
    if q != 0.0 {
        e[k] = q;
        k += 1;
    }
    *n = k;
}

/// [`orient`] evaluated exactly: the coordinates are scaled by a power of two (exact, and the
/// sign is unchanged since the determinant is homogeneous), the determinant is expanded into six
/// products a_x·b_y − a_x·c_y − a_y·b_x + a_y·c_x + b_x·c_y − b_y·c_x, each split exactly into
/// two doubles, and the twelve doubles are summed into an expansion whose largest component has
/// the sign of the sum.
fn orient_exact(a: Point, b: Point, c: Point) -> Ordering {
    let coords = [a[0], a[1], b[0], b[1], c[0], c[1]];
    let m = coords.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 {
        return Ordering::Equal;
    }
    let exponent = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let scale = 2f64.powi(-exponent.clamp(-1000, 1000));
    let [ax, ay, bx, by, cx, cy] = coords.map(|x| x * scale);
    let terms = [
        (ax, by),
        (-ax, cy),
        (-ay, bx),
        (ay, cx),
        (bx, cy),
        (-by, cx),
    ];
    let mut e = [0.0; 12];
    let mut n = 0;
    for (p, q) in terms {
        let (hi, lo) = two_product(p, q);
        grow_expansion(&mut e, &mut n, lo);
        grow_expansion(&mut e, &mut n, hi);
    }
    match n {
        0 => Ordering::Equal,
        _ => e[n - 1].partial_cmp(&0.0).unwrap_or(Ordering::Equal),
    }
}

/// Whether `c`, known to be collinear with `a` and `b`, lies on the closed segment \[a, b\].
fn on_segment(a: Point, b: Point, c: Point) -> bool {
    let (lo, hi) = if lex(a, b) == Ordering::Greater {
        (b, a)
    } else {
        (a, b)
    };
    lex(lo, c) != Ordering::Greater && lex(c, hi) != Ordering::Greater
}

/// Whether the closed segments \[p1, p2\] and \[q1, q2\] have a point in common (crossing,
/// touching or overlapping). Exact.
pub(crate) fn segments_meet(p1: Point, p2: Point, q1: Point, q2: Point) -> bool {
    let o1 = orient(p1, p2, q1);
    let o2 = orient(p1, p2, q2);
    if o1 == o2 && o1 != Ordering::Equal {
        return false;
    }
    let o3 = orient(q1, q2, p1);
    let o4 = orient(q1, q2, p2);
    if o3 == o4 && o3 != Ordering::Equal {
        return false;
    }
    if [o1, o2, o3, o4].iter().all(|&o| o != Ordering::Equal) {
        // strictly opposite sides both ways: a proper crossing
        return true;
    }
    (o1 == Ordering::Equal && on_segment(p1, p2, q1))
        || (o2 == Ordering::Equal && on_segment(p1, p2, q2))
        || (o3 == Ordering::Equal && on_segment(q1, q2, p1))
        || (o4 == Ordering::Equal && on_segment(q1, q2, p2))
}

/// Whether the segments \[v, a\] and \[v, b\], which share the end point `v`, have more than `v`
/// in common: they are collinear and leave `v` on the same side. Exact.
pub(crate) fn segments_overlap_from(v: Point, a: Point, b: Point) -> bool {
    orient(v, a, b) == Ordering::Equal && lex(v, a) == lex(v, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientation_signs() {
        assert_eq!(
            orient([0.0, 0.0], [1.0, 0.0], [0.5, 1.0]),
            Ordering::Greater
        );
        assert_eq!(orient([0.0, 0.0], [1.0, 0.0], [0.5, -1.0]), Ordering::Less);
        assert_eq!(orient([0.0, 0.0], [1.0, 1.0], [3.0, 3.0]), Ordering::Equal);
        assert_eq!(orient([-0.0, 0.0], [0.0, 1.0], [0.0, 7.0]), Ordering::Equal);
    }

    /// Points on a line whose coordinates are not representable: the floating-point determinant
    /// is noise, the exact one decides (and agrees with itself under permutation).
    #[test]
    fn exact_near_degenerate() {
        let a = [0.1, 0.1];
        let b = [0.3, 0.3];
        for k in 0..200 {
            let t = 0.5 + k as f64 * 1e-3;
            let c = [t, t];
            // c = (t, t) lies exactly on y = x, and so do a and b
            assert_eq!(orient(a, b, c), Ordering::Equal, "{t}");
            let up = [t, f64::from_bits(t.to_bits() + 1)];
            assert_eq!(orient(a, b, up), Ordering::Greater, "{t}");
            assert_eq!(orient(b, a, up), Ordering::Less, "{t}");
            assert_eq!(orient(up, a, b), Ordering::Greater, "{t}");
        }
        // an exact computation on huge and tiny coordinates
        let s = 1e200;
        assert_eq!(
            orient([0.1 * s, 0.1 * s], [0.3 * s, 0.3 * s], [0.7 * s, 0.7 * s]),
            orient_exact([0.1 * s, 0.1 * s], [0.3 * s, 0.3 * s], [0.7 * s, 0.7 * s])
        );
        let t = 1e-200;
        assert_eq!(
            orient(
                [0.0, 0.0],
                [t, t],
                [2.0 * t, f64::from_bits((2.0 * t).to_bits() - 1)]
            ),
            Ordering::Less
        );
    }

    #[test]
    fn segment_intersections() {
        let o = [0.0, 0.0];
        // proper crossing, touching at an end point, T-junction, collinear overlap, disjoint
        assert!(segments_meet(o, [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]));
        assert!(segments_meet(o, [1.0, 0.0], [1.0, 0.0], [2.0, 5.0]));
        assert!(segments_meet(o, [2.0, 0.0], [1.0, 0.0], [1.0, 5.0]));
        assert!(segments_meet(o, [2.0, 0.0], [1.0, 0.0], [3.0, 0.0]));
        assert!(!segments_meet(o, [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]));
        assert!(!segments_meet(o, [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]));
        assert!(!segments_meet(o, [2.0, 0.0], [1.0, 1e-300], [1.0, 5.0]));
        // shared end point
        assert!(segments_overlap_from(o, [1.0, 1.0], [2.0, 2.0]));
        assert!(!segments_overlap_from(o, [1.0, 1.0], [-2.0, -2.0]));
        assert!(!segments_overlap_from(o, [1.0, 1.0], [2.0, 2.1]));
    }
}
