//! The tensor grid the generators start from.
//!
//! On the box \[x₀,x₁\] × \[y₀,y₁\] × \[z₀,z₁\] with n steps per direction, grid point
//! (i, j, k), 0 ≤ i, j, k ≤ n, is
//!
//! ```text
//! (x₀ + (x₁−x₀)·i/n , y₀ + (y₁−y₀)·j/n , z₀ + (z₁−z₀)·k/n)      (x₁, y₁, z₁ exactly at n)
//! ```
//!
//! with id `(k·(n+1) + j)·(n+1) + i` (x fastest, then y, then z: the numbering of the 2D
//! Cartesian meshes, stacked). Cube (i, j, k), 0 ≤ i, j, k < n, has id `(k·n + j)·n + i` and
//! the local corners 0 … 7, corner `dx + 2·dy + 4·dz` being grid point (i+dx, j+dy, k+dz).

use crate::budget::try_filled;
use crate::error::{Error, Result};
use crate::mesh3d::{Cuboid, Point3};
use rayon::prelude::*;

/// The grid coordinates along each axis of `domain` with `n` steps, which must increase
/// strictly (else [`Error::InvalidData`] naming the axis: the range is too narrow for that many
/// steps in floating point).
pub(crate) fn axes(domain: Cuboid, n: usize) -> Result<[Vec<f64>; 3]> {
    let mut out: [Vec<f64>; 3] = Default::default();
    for (axis, (r, name)) in domain.ranges().into_iter().zip(["x", "y", "z"]).enumerate() {
        let c: Vec<f64> = (0..=n).map(|i| coord(r, i, n)).collect();
        if let Some(i) = c.windows(2).position(|w| !(w[0] < w[1])) {
            return Err(Error::InvalidData(format!(
                "the {name} coordinates of a 3D grid do not increase strictly: planes {i} and {} \
                 are both at {} ({n} steps are too many for the range [{}, {}])",
                i + 1,
                c[i + 1],
                r[0],
                r[1]
            )));
        }
        out[axis] = c;
    }
    Ok(out)
}

/// Coordinate `i` of `n` equal steps on `r`, exactly `r[1]` for `i = n`.
fn coord(r: [f64; 2], i: usize, n: usize) -> f64 {
    if i == n {
        r[1]
    } else {
        r[0] + (r[1] - r[0]) * (i as f64 / n as f64)
    }
}

/// Id of grid point (i, j, k) of the grid with n steps per direction.
pub(crate) fn point_id(n: usize, [i, j, k]: [usize; 3]) -> u32 {
    ((k * (n + 1) + j) * (n + 1) + i) as u32
}

/// The grid points of `axes` in the order of their ids, each moved by `shift(id, [i, j, k])`
/// (filled plane by plane in parallel; `shift` must depend on its arguments only);
/// [`Error::OutOfMemory`] if they cannot be allocated.
pub(crate) fn points(
    axes: &[Vec<f64>; 3],
    shift: impl Fn(usize, [usize; 3]) -> Point3 + Sync,
) -> Result<Vec<Point3>> {
    let [xs, ys, zs] = axes;
    let plane = xs.len() * ys.len();
    let mut out = try_filled(plane * zs.len(), [0.0; 3], "the grid points")?;
    out.par_chunks_mut(plane).enumerate().for_each(|(k, p)| {
        for (j, row) in p.chunks_mut(xs.len()).enumerate() {
            for (i, v) in row.iter_mut().enumerate() {
                let d = shift((k * ys.len() + j) * xs.len() + i, [i, j, k]);
                *v = [xs[i] + d[0], ys[j] + d[1], zs[k] + d[2]];
            }
        }
    });
    Ok(out)
}

/// The ids of the eight corners of cube (i, j, k), corner `dx + 2·dy + 4·dz` first to last.
pub(crate) fn cube_corners(n: usize, [i, j, k]: [usize; 3]) -> [u32; 8] {
    std::array::from_fn(|c| point_id(n, [i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_plane_is_the_box_face_and_ids_run_x_fastest() {
        let d = Cuboid::new([0.1, 0.7], [-1.0, 2.0], [0.0, 1.0]);
        let a = axes(d, 3).unwrap();
        assert_eq!(a[0][3], 0.7);
        assert_eq!(a[1], [-1.0, 0.0, 1.0, 2.0]);
        let p = points(&a, |_, _| [0.0; 3]).unwrap();
        assert_eq!(p.len(), 64);
        assert_eq!(p[point_id(3, [1, 2, 3]) as usize], [a[0][1], 1.0, 1.0]);
        assert_eq!(cube_corners(3, [0, 0, 0]), [0, 1, 4, 5, 16, 17, 20, 21]);
        let narrow = Cuboid::new([0.0, 1.0], [1.0, 1.0 + 4.0 * f64::EPSILON], [0.0, 1.0]);
        let e = axes(narrow, 64).unwrap_err().to_string();
        assert!(e.contains("the y coordinates"), "{e}");
    }
}
