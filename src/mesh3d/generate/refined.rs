//! Locally refined Cartesian meshes: the n × n × n cubes of the grid (n even) in which the
//! cubes (i, j, k) with i + j + k even (a checkerboard) are each split into their 8 half-size
//! cubes, and the others are kept whole, as polyhedra with hanging nodes.
//!
//! The points are those of the grid with 2n steps per direction (the fine grid, point
//! (a, b, c), 0 ≤ a, b, c ≤ 2n) that some cell uses: the coarse points (a, b, c all even) and
//! the fine points in the closure of a split cube. A whole cube has split neighbours across
//! every interior face (the checkerboard), so each of its interior faces is listed as the 4
//! fine squares the neighbour sees, and each of its faces on the boundary of the box as one
//! polygon: its 4 corners with, between two corners, the midpoint of their edge when a split
//! cube uses it (every edge but one on an edge of the box). A whole cube in the interior is a
//! polyhedron with 24 square faces; the mesh is conforming face to face, and HMM sees the
//! hanging nodes as ordinary vertices of flat faces and cells.
//!
//! Numbering: points in the order of the fine grid (a fastest, then b, then c), skipping unused
//! ones; cells cube by cube in the order of the coarse cube ids, a split cube giving its 8
//! sub-cubes (x fastest, then y, then z), a whole cube one cell. Every face is listed
//! counter-clockwise seen from outside its cell, the faces of a cell in the order x−, x+, y−,
//! y+, z−, z+ (the 4 squares of a face normal to axis d with their lowest corners in the order
//! (0,0), (1,0), (0,1), (1,1) along axes d+1 and d+2, mod 3).
//!
//! Counts (n even): 9n³/2 cells (4n³ sub-cubes and n³/2 whole cubes); 36n³ − 9n² face sides
//! (24n³ for the sub-cubes; 12n³ − 12n² squares and 3n² boundary faces for the whole cubes);
//! 144n³ − 24n² − 12n face vertices (4 per square; 4 per boundary face plus 12n² − 12n edge
//! midpoints); (n+1)³ + n³/2 + 3n³ + 3n(n+1)² − 6n points (coarse points, centres of the split
//! cubes, centres of the faces that are interior or of a split cube, midpoints of the edges
//! but the 6n edges of the box that only a whole cube touches).

use super::fill::{Sink, count_layers, fill_layers};
use super::{Counts3, check_request, grid};
use crate::budget::MemoryBudget;
use crate::budget::try_filled;
use crate::error::{Error, Result};
use crate::mesh3d::{Cuboid, Point3, Polyhedra};
use rayon::prelude::*;

/// The id of a fine point no cell uses.
const UNUSED: u32 = u32::MAX;

/// The faces of a cube as (axis, side): x−, x+, y−, y+, z−, z+.
const FACES: [(usize, usize); 6] = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1)];

/// The locally refined mesh of `domain` with n × n × n coarse cubes (see the module docs).
/// [`Error::InvalidData`] for an odd n or n = 0, a domain that is not a finite box, or more
/// than [`MAX_CELLS`](crate::mesh::generate::MAX_CELLS) cells;
/// [`MeshError::TooLarge`](crate::MeshError::TooLarge) if the description and the table of
/// fine points would not fit in `budget` (checked before allocating).
pub fn refined(n: usize, domain: Cuboid, budget: MemoryBudget) -> Result<Polyhedra> {
    if !n.is_multiple_of(2) {
        return Err(Error::InvalidData(format!(
            "a locally refined mesh needs an even number of coarse cubes per side (got {n})"
        )));
    }
    let what = format!("a locally refined mesh of {n}³ coarse cubes");
    check_request(&what, n, domain, counts(n), table_bytes(n), budget)?;
    let axes = grid::axes(domain, 2 * n)?;
    let (ids, vertices) = fine_points(n, &axes)?;
    let fine = Fine { n, ids };
    let layer_counts = count_layers(n, |k, s| fine.layer(k, s));
    let [cell_ptr, face_ptr, face_vertices] = fill_layers(&layer_counts, |k, s| fine.layer(k, s))?;
    Ok(Polyhedra {
        vertices,
        cell_ptr,
        face_ptr,
        face_vertices,
        ..Polyhedra::default()
    })
}

/// Cells, face sides, face vertices and points of the mesh with n × n × n coarse cubes, n even
/// (the formulas of the module docs).
pub(crate) fn counts(n: usize) -> Counts3 {
    let n = n as u64;
    let n2 = n.checked_mul(n)?;
    let n3 = n2.checked_mul(n)?;
    let n1 = n.checked_add(1)?;
    let cells = n3.checked_mul(9)? / 2;
    let sides = n3.checked_mul(36)?.checked_sub(n2.checked_mul(9)?)?;
    let verts = n3
        .checked_mul(144)?
        .checked_sub(n2.checked_mul(24)?)?
        .checked_sub(n.checked_mul(12)?)?;
    let points = n1
        .checked_mul(n1)?
        .checked_mul(n1)?
        .checked_add(n3 / 2)?
        .checked_add(n3.checked_mul(3)?)?
        .checked_add(n.checked_mul(3)?.checked_mul(n1)?.checked_mul(n1)?)?
        .checked_sub(n.checked_mul(6)?)?;
    Some([cells, sides, verts, points])
}

/// The bytes of the table of fine-point ids, (2n+1)³ 32-bit entries.
pub(crate) fn table_bytes(n: usize) -> u64 {
    let m = (n as u64).saturating_mul(2).saturating_add(1);
    m.saturating_mul(m).saturating_mul(m).saturating_mul(4)
}

/// Whether a cell uses fine point `p` of the mesh with n coarse cubes per side: a coarse point,
/// or in the closure of a split cube. Along each axis the coarse cubes whose closure holds `p`
/// are one (odd coordinate, or on the boundary) or two consecutive ones (of both parities).
fn used(n: usize, p: [usize; 3]) -> bool {
    if p.iter().all(|c| c.is_multiple_of(2)) {
        return true;
    }
    let mut sum = 0;
    for &c in &p {
        match c {
            0 => {}
            c if !c.is_multiple_of(2) => sum += c / 2,
            c if c == 2 * n => sum += n - 1,
            _ => return true,
        }
    }
    sum.is_multiple_of(2)
}

/// The id of every fine point ([`UNUSED`] if no cell uses it), and the used points' coordinates
/// in the order of their ids; both filled plane by plane (fixed c) in parallel, at offsets from
/// a first counting pass.
fn fine_points(n: usize, axes: &[Vec<f64>; 3]) -> Result<(Vec<u32>, Vec<Point3>)> {
    let m = 2 * n + 1;
    let per_plane: Vec<usize> = (0..m)
        .into_par_iter()
        .map(|c| {
            (0..m * m)
                .filter(|&ab| used(n, [ab % m, ab / m, c]))
                .count()
        })
        .collect();
    let mut ids = try_filled(m * m * m, UNUSED, "the ids of the fine points")?;
    let mut points = try_filled(per_plane.iter().sum(), [0.0; 3], "the fine points")?;
    let first: Vec<usize> = per_plane
        .iter()
        .scan(0, |acc, &k| {
            let f = *acc;
            *acc += k;
            Some(f)
        })
        .collect();
    let pieces = super::fill::split_by(&mut points, per_plane.iter().copied());
    ids.par_chunks_mut(m * m)
        .zip(pieces)
        .enumerate()
        .for_each(|(c, (ids, points))| {
            let mut next = 0;
            for (ab, id) in ids.iter_mut().enumerate() {
                let (a, b) = (ab % m, ab / m);
                if used(n, [a, b, c]) {
                    *id = (first[c] + next) as u32;
                    points[next] = [axes[0][a], axes[1][b], axes[2][c]];
                    next += 1;
                }
            }
        });
    Ok((ids, points))
}

/// The fine-point ids of the mesh with n coarse cubes per side.
struct Fine {
    n: usize,
    ids: Vec<u32>,
}

impl Fine {
    /// The id of fine point `p` ([`UNUSED`] if no cell uses it).
    fn id(&self, [a, b, c]: [usize; 3]) -> u32 {
        let m = 2 * self.n + 1;
        self.ids[(c * m + b) * m + a]
    }

    /// The cells of the coarse cubes (·, ·, k).
    fn layer(&self, k: usize, s: &mut impl Sink) {
        for j in 0..self.n {
            for i in 0..self.n {
                if (i + j + k).is_multiple_of(2) {
                    self.split_cube([i, j, k], s);
                } else {
                    self.whole_cube([i, j, k], s);
                }
            }
        }
    }

    /// The 8 sub-cubes of coarse cube `c`.
    fn split_cube(&self, c: [usize; 3], s: &mut impl Sink) {
        for sub in 0..8 {
            let o: [usize; 3] = std::array::from_fn(|a| 2 * c[a] + ((sub >> a) & 1));
            for (d, e) in FACES {
                let mut corner = o;
                corner[d] += e;
                s.face(&square(corner, d, e == 1, 1).map(|p| self.id(p)));
            }
            s.end_cell();
        }
    }

    /// Coarse cube `c` as one cell: interior faces as 4 squares, boundary faces as polygons
    /// with the used edge midpoints.
    fn whole_cube(&self, c: [usize; 3], s: &mut impl Sink) {
        for (d, e) in FACES {
            let mut corner = c.map(|x| 2 * x);
            corner[d] += 2 * e;
            let on_boundary = if e == 0 {
                c[d] == 0
            } else {
                c[d] == self.n - 1
            };
            if on_boundary {
                let corners = square(corner, d, e == 1, 2);
                let mut face = [0u32; 8];
                let mut len = 0;
                for t in 0..4 {
                    let [p, q] = [corners[t], corners[(t + 1) % 4]];
                    face[len] = self.id(p);
                    len += 1;
                    let mid = self.id(std::array::from_fn(|a| (p[a] + q[a]) / 2));
                    if mid != UNUSED {
                        face[len] = mid;
                        len += 1;
                    }
                }
                s.face(&face[..len]);
            } else {
                for sub in 0..4 {
                    let mut low = corner;
                    low[(d + 1) % 3] += sub & 1;
                    low[(d + 2) % 3] += sub >> 1;
                    s.face(&square(low, d, e == 1, 1).map(|p| self.id(p)));
                }
            }
        }
        s.end_cell();
    }
}

/// The square of side `size` (in fine steps) normal to axis `d` with lowest corner `low`, as 4
/// fine points counter-clockwise seen from the side of +e_d (`positive`) or of −e_d. With
/// (u, w) = (d+1, d+2) mod 3, the loop (0,0), (s,0), (s,s), (0,s) in (u, w) turns
/// counter-clockwise about e_u × e_w = e_d.
fn square(low: [usize; 3], d: usize, positive: bool, size: usize) -> [[usize; 3]; 4] {
    let at = |du: usize, dw: usize| {
        let mut p = low;
        p[(d + 1) % 3] += du;
        p[(d + 2) % 3] += dw;
        p
    };
    let s = size;
    if positive {
        [at(0, 0), at(s, 0), at(s, s), at(0, s)]
    } else {
        [at(0, 0), at(0, s), at(s, s), at(s, 0)]
    }
}
