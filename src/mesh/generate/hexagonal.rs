//! The "hexa1" family of distorted hexagonal meshes (HArDCore2D / FVCA5 `hexa1_k.typ2`).
//!
//! This construction was recovered from the published files; it reproduces `hexa1_1` …
//! `hexa1_4` and `hexa1_5` (from `hexa1_5.mat`) *exactly*: same vertex coordinates (to 4e-16)
//! in the same order, same cells in the same order with the same starting vertices.
//!
//! # Construction
//!
//! Take the n × n lattice of \[0,1\]² (the files use n = 10·2^(level−1)), nodes
//! P_ij = (i/n, j/n), 0 ≤ i, j ≤ n, and the smooth map, equal to the identity on ∂Ω,
//!
//! ```text
//! T(x, y) = (x + φ, y + φ),   φ(x, y) = 0.1 · sin(2πx) · sin(2πy).
//! ```
//!
//! Cut every lattice square by its diagonal P_ij–P_(i+1,j+1) into a lower triangle
//! (P_ij, P_(i+1,j), P_(i+1,j+1)) and an upper triangle (P_ij, P_(i+1,j+1), P_(i,j+1)). The mesh
//! vertices are
//!
//! * ℓ_ij and u_ij (0 ≤ i, j < n): the centroids of the lower and upper triangles of square
//!   (i, j) *after* mapping their corners by T, e.g. ℓ_ij = (T P_ij + T P_(i+1,j) + T P_(i+1,j+1)) / 3;
//! * the 4n boundary nodes P_ij, and the 4n midpoints of the boundary lattice edges.
//!
//! There is one cell per lattice node, made of the centroids of the triangles around it
//! (a dual mesh). Around an interior node (i, j) the counter-clockwise hexagon is
//!
//! ```text
//! ℓ_(i−1,j−1), u_(i,j−1), ℓ_(i,j), u_(i,j), ℓ_(i−1,j), u_(i−1,j−1).
//! ```
//!
//! A boundary node keeps the triangle centroids that exist and closes its cell along ∂Ω with
//! "midpoint, node, midpoint": half-hexagons with a flat (180°) angle at the node, two
//! pentagons at (0,0) and (1,1) (two triangles) and two quadrangles at (1,0) and (0,1) (one
//! triangle). The diagonals all point along (1,1), so the hexagons are elongated in that
//! direction and φ (which moves points along (1,1)) stretches or squeezes them.
//!
//! Counts: 2n² + 8n vertices, (n+1)² cells, 3n² + 10n edges, 2n edges on each side of the square
//! (20·2^(level−1) on x = 0). h is 0.2414, 0.1297, 0.0657, 0.0330, 0.0165 for levels 1–5.
//!
//! # Numbering (that of the files)
//!
//! Vertices: first the triangle centroids, by shells m = 0 … n−1 (the squares with
//! max(i, j) = m): u_(m,0..m−1), ℓ_(0..m−1,m), ℓ_(m,0..m), u_(0..m,m); so shell m starts at id 2m².
//! Then the 4n boundary-edge midpoints, then the 4n boundary nodes, both in the order of the
//! boundary edges
//! bottom₀, left₀, bottom₁, left₁, …, bottom_(n−2), left_(n−2), bottom_(n−1), right₀ … right_(n−1),
//! top₀, left_(n−1), top₁ … top_(n−1) (bottom_k = [k/n, (k+1)/n] × {0}, left_k = {0} × [k/n, (k+1)/n],
//! and so on); the node listed with bottom_k is ((k+1)/n, 0), with left_k (0, k/n), with right_k
//! (1, (k+1)/n), with top_k (k/n, 1).
//!
//! Cells: by shells m = 0 … n of nodes, (m,0), (m,1), …, (m,m), (m−1,m), …, (0,m). An interior
//! hexagon starts at its smallest vertex id; a boundary cell starts at its first triangle
//! centroid after the boundary (counter-clockwise).
//!
//! Everything is index arithmetic: O(cells) time, no search.

use super::{Counts, check_cell_count, check_memory};
use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_vec};
use crate::error::{Error, Result};
use crate::mesh::{Point, PolyMesh};
use std::f64::consts::PI;

/// Amplitude of the distortion φ = A·sin(2πx)·sin(2πy) used by the `hexa1` files.
pub const DISTORTION: f64 = 0.1;

/// The lattice size n = 10·2^(level−1) of `hexa1_level` (`None` for level 0 or on overflow).
pub(crate) fn level_n(level: usize) -> Option<usize> {
    let shift = u32::try_from(level.checked_sub(1)?).ok()?;
    10usize.checked_mul(1usize.checked_shl(shift)?)
}

/// The mesh `hexa1_level`: n = 10·2^(level−1), (n+1)² cells (121, 441, 1681, 6561, 25921, …).
/// Level 0 and levels above [`Family::max_level`](super::Family::max_level) (10) give
/// [`Error::InvalidData`]. Within the fixed budget [`MemoryBudget::DEFAULT`];
/// [`Family::generate`](super::Family::generate) takes the caller's.
pub fn hexagonal(level: usize) -> Result<PolyMesh> {
    super::Family::Hexagonal.check_level(level)?;
    let n = level_n(level).expect("valid level");
    hexagonal_grid(n)
}

/// The same construction on an n × n lattice, for any n ≥ 1 ((n+1)² cells). Errors
/// ([`Error::InvalidData`]) for n = 0 or more than [`MAX_CELLS`](super::MAX_CELLS) cells; an
/// n for which the distortion folds a cell would give [`Error::InvalidMesh`] (none is known).
/// Within the fixed budget [`MemoryBudget::DEFAULT`]; [`hexagonal_grid_within`] takes the
/// caller's.
pub fn hexagonal_grid(n: usize) -> Result<PolyMesh> {
    hexagonal_grid_within(n, MemoryBudget::DEFAULT)
}

/// As [`hexagonal_grid`], refusing ([`MeshError::TooLarge`](crate::MeshError::TooLarge)) a mesh
/// that would need more memory than `budget`, before allocating anything.
pub fn hexagonal_grid_within(n: usize, budget: MemoryBudget) -> Result<PolyMesh> {
    if n == 0 {
        return Err(Error::InvalidData(
            "a hexagonal mesh needs a lattice of at least 1 × 1 squares (got n = 0)".into(),
        ));
    }
    let what = format!("a hexagonal mesh on a {n} × {n} lattice");
    check_cell_count(&what, n.checked_add(1).and_then(|m| m.checked_mul(m)))?;
    check_memory(&what, counts(n), budget)?;
    let (vertices, cells) = hexagonal_data(n)?;
    Ok(PolyMesh::from_cells(vertices, cells)?)
}

/// Cells, cell sides, vertices and edges of the construction on the n × n lattice:
/// (n+1)², 6n² + 12n (twice the 3n² + 10n edges, less the 8n boundary edges), 2n² + 8n and
/// 3n² + 10n.
pub(crate) fn counts(n: usize) -> Counts {
    let n = n as u64;
    let n2 = n.checked_mul(n)?;
    let n1 = n.checked_add(1)?;
    let cells = n1.checked_mul(n1)?;
    Some([
        cells,
        n2.checked_mul(6)?.checked_add(n.checked_mul(12)?)?,
        n2.checked_mul(2)?.checked_add(n.checked_mul(8)?)?,
        n2.checked_mul(3)?.checked_add(n.checked_mul(10)?)?,
    ])
}

/// A side of the unit square, for the boundary numbering.
#[derive(Clone, Copy)]
enum Side {
    Bottom,
    Left,
    Right,
    Top,
}

/// Vertex ids of the file numbering (see the module docs).
struct Numbering {
    n: usize,
}

impl Numbering {
    /// ℓ_ij, centroid of the lower triangle of square (i, j).
    fn lower(&self, i: usize, j: usize) -> usize {
        let m = i.max(j);
        if i == m {
            2 * m * m + 2 * m + j
        } else {
            2 * m * m + m + i
        }
    }
    /// u_ij, centroid of the upper triangle of square (i, j).
    fn upper(&self, i: usize, j: usize) -> usize {
        let m = i.max(j);
        if j == m {
            2 * m * m + 3 * m + 1 + i
        } else {
            2 * m * m + j
        }
    }
    /// Position of boundary edge k of `side` in the boundary sequence.
    fn pos(&self, side: Side, k: usize) -> usize {
        let n = self.n;
        match side {
            Side::Bottom => 2 * k,
            Side::Left if k + 1 < n => 2 * k + 1,
            Side::Left => 3 * n,
            Side::Right => 2 * n - 1 + k,
            Side::Top if k == 0 => 3 * n - 1,
            Side::Top => 3 * n + k,
        }
    }
    /// Midpoint of boundary edge k of `side`.
    fn mid(&self, side: Side, k: usize) -> usize {
        2 * self.n * self.n + self.pos(side, k)
    }
    /// The boundary lattice node (p, q).
    fn node(&self, p: usize, q: usize) -> usize {
        let n = self.n;
        let (side, k) = if q == 0 && p >= 1 {
            (Side::Bottom, p - 1)
        } else if p == 0 && q < n {
            (Side::Left, q)
        } else if p == n && q >= 1 {
            (Side::Right, q - 1)
        } else {
            (Side::Top, p)
        };
        2 * n * n + 4 * n + self.pos(side, k)
    }
}

/// sin(2π i/n), exactly 0 when 2i/n is an integer.
fn sin_2pi(i: usize, n: usize) -> f64 {
    if (2 * i).is_multiple_of(n) {
        0.0
    } else {
        (2.0 * PI * (i as f64 / n as f64)).sin()
    }
}

/// The vertices of the n × n construction, in the file numbering.
fn hexagonal_vertices(num: &Numbering) -> Result<Vec<Point>> {
    let n = num.n;
    let nf = n as f64;
    let coord = |i: usize| i as f64 / nf;
    let s: Vec<f64> = (0..=n).map(|i| sin_2pi(i, n)).collect();
    // T(P_ij)
    let t = |i: usize, j: usize| -> Point {
        let phi = DISTORTION * s[i] * s[j];
        [coord(i) + phi, coord(j) + phi]
    };
    let centroid = |a: Point, b: Point, c: Point| -> Point {
        [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
    };
    let nv = 2 * n * n + 8 * n;
    let mut vertices = try_filled(nv, [0.0; 2], "the vertices")?;
    for j in 0..n {
        for i in 0..n {
            let (p00, p10, p11, p01) = (t(i, j), t(i + 1, j), t(i + 1, j + 1), t(i, j + 1));
            vertices[num.lower(i, j)] = centroid(p00, p10, p11);
            vertices[num.upper(i, j)] = centroid(p00, p11, p01);
        }
    }
    let half = |k: usize| (2 * k + 1) as f64 / (2.0 * nf);
    for k in 0..n {
        vertices[num.mid(Side::Bottom, k)] = [half(k), 0.0];
        vertices[num.mid(Side::Left, k)] = [0.0, half(k)];
        vertices[num.mid(Side::Right, k)] = [1.0, half(k)];
        vertices[num.mid(Side::Top, k)] = [half(k), 1.0];
        vertices[num.node(k + 1, 0)] = [coord(k + 1), 0.0];
        vertices[num.node(0, k)] = [0.0, coord(k)];
        vertices[num.node(n, k + 1)] = [1.0, coord(k + 1)];
        vertices[num.node(k, n)] = [coord(k), 1.0];
    }
    Ok(vertices)
}

/// The vertices of the cell around node (i, j) of the n × n construction (0 ≤ i, j ≤ n),
/// counter-clockwise, in the file numbering.
fn hexagonal_cell(num: &Numbering, i: usize, j: usize) -> Vec<usize> {
    let n = num.n;
    let (l, u) = (|i, j| num.lower(i, j), |i, j| num.upper(i, j));

    use Side::*;
    let (bottom, top, left, right) = (j == 0, j == n, i == 0, i == n);
    match (bottom, top, left, right) {
        (false, false, false, false) => {
            let mut ring = vec![
                l(i - 1, j - 1),
                u(i, j - 1),
                l(i, j),
                u(i, j),
                l(i - 1, j),
                u(i - 1, j - 1),
            ];
            let first = (0..6).min_by_key(|&r| ring[r]).expect("six vertices");
            ring.rotate_left(first);
            ring
        }
        (true, _, true, _) => vec![
            l(0, 0),
            u(0, 0),
            num.mid(Left, 0),
            num.node(0, 0),
            num.mid(Bottom, 0),
        ],
        (true, _, _, true) => vec![
            l(n - 1, 0),
            num.mid(Bottom, n - 1),
            num.node(n, 0),
            num.mid(Right, 0),
        ],
        (_, true, _, true) => vec![
            u(n - 1, n - 1),
            l(n - 1, n - 1),
            num.mid(Right, n - 1),
            num.node(n, n),
            num.mid(Top, n - 1),
        ],
        (_, true, true, _) => vec![
            u(0, n - 1),
            num.mid(Top, 0),
            num.node(0, n),
            num.mid(Left, n - 1),
        ],
        (true, ..) => vec![
            l(i, 0),
            u(i, 0),
            l(i - 1, 0),
            num.mid(Bottom, i - 1),
            num.node(i, 0),
            num.mid(Bottom, i),
        ],
        (_, true, ..) => vec![
            u(i - 1, n - 1),
            l(i - 1, n - 1),
            u(i, n - 1),
            num.mid(Top, i),
            num.node(i, n),
            num.mid(Top, i - 1),
        ],
        (_, _, true, _) => vec![
            u(0, j - 1),
            l(0, j),
            u(0, j),
            num.mid(Left, j),
            num.node(0, j),
            num.mid(Left, j - 1),
        ],
        (_, _, _, true) => vec![
            l(n - 1, j),
            u(n - 1, j - 1),
            l(n - 1, j - 1),
            num.mid(Right, j - 1),
            num.node(n, j),
            num.mid(Right, j),
        ],
    }
}

/// Vertices and cells of the n × n construction, in the file numbering.
fn hexagonal_data(n: usize) -> Result<(Vec<Point>, Vec<Vec<usize>>)> {
    let num = Numbering { n };
    let vertices = hexagonal_vertices(&num)?;
    let cell = |i: usize, j: usize| hexagonal_cell(&num, i, j);
    let mut cells = try_vec((n + 1) * (n + 1), "the cells")?;
    for m in 0..=n {
        for j in 0..=m {
            cells.push(cell(m, j));
        }
        for i in (0..m).rev() {
            cells.push(cell(i, m));
        }
    }
    Ok((vertices, cells))
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::generate::total_area;

    #[test]
    fn level_1_is_hexa1_1() {
        let m = hexagonal(1).unwrap();
        assert_eq!((m.n_cells(), m.n_vertices(), m.n_edges()), (121, 280, 400));
        assert_eq!(m.boundary_edges_on(0, 0.0), 20);
        assert!((total_area(&m) - 1.0).abs() < 1e-13);
        assert!((m.h() - 0.2414).abs() < 1e-4, "h = {}", m.h());
        let mut sides = [0usize; 7];
        for k in 0..m.n_cells() {
            sides[m.cell_vertices(k).len()] += 1;
        }
        assert_eq!(sides, [0, 0, 0, 0, 2, 2, 117]);
        // first vertices and cells of hexa1_1.typ2 (1-based there)
        let v0 = m.vertex(0);
        assert!((v0[0] - 7.818_305_009_375_087E-2).abs() < 1e-15);
        assert!((v0[1] - 4.484_971_676_041_755E-2).abs() < 1e-15);
        assert_eq!(m.vertex(200), [0.05, 0.0]);
        assert_eq!(m.vertex(241), [0.0, 0.0]);
        assert_eq!(m.cell_vertices(0), &[0, 1, 201, 241, 200]);
        assert_eq!(m.cell_vertices(1), &[4, 2, 0, 200, 240, 202]);
        assert_eq!(m.cell_vertices(2), &[0, 2, 5, 7, 3, 1]);
        assert_eq!(m.cell_vertices(5), &[2, 4, 8, 13, 9, 5]);
    }

    #[test]
    fn levels_2_to_4_counts_and_h() {
        for (level, cells, h) in [(2, 441, 0.1297), (3, 1681, 0.0657), (4, 6561, 0.0330)] {
            let m = hexagonal(level).unwrap();
            let n = level_n(level).unwrap();
            assert_eq!(m.n_cells(), cells);
            assert_eq!(m.n_vertices(), 2 * n * n + 8 * n);
            assert_eq!(m.n_edges(), 3 * n * n + 10 * n);
            assert_eq!(m.boundary_edges_on(0, 0.0), 2 * n);
            assert!((total_area(&m) - 1.0).abs() < 1e-12);
            assert!((m.h() - h).abs() < 1e-4, "level {level}: h = {}", m.h());
        }
    }

    #[test]
    fn any_lattice_size_is_a_valid_mesh() {
        for n in 1..=12 {
            let m = hexagonal_grid(n).unwrap();
            assert_eq!(m.n_cells(), (n + 1) * (n + 1));
            assert!((total_area(&m) - 1.0).abs() < 1e-13, "n = {n}");
        }
    }

    #[test]
    fn invalid_sizes_are_errors() {
        assert_eq!(level_n(1), Some(10));
        assert_eq!(level_n(5), Some(160));
        assert_eq!(level_n(0), None);
        assert_eq!(level_n(64), None);
        for r in [
            hexagonal(0),
            hexagonal(11),
            hexagonal(usize::MAX),
            hexagonal_grid(0),
            hexagonal_grid(9000),
        ] {
            assert!(matches!(r, Err(Error::InvalidData(_))), "{r:?}");
        }
    }
}
