//! The Kershaw family of quadrangle meshes (FVCA5 `mesh4_1_k.typ2`, k = 1 … 6).
//!
//! Recovered from the published files: level k reproduces `mesh4_1_k` with the same vertices
//! in the same order (to 5.5e-11; the files round coordinates to 10 decimals) and the same cells
//! in the same order. Only the starting vertex of a cell's (counter-clockwise) list may differ
//! at levels ≥ 2: here every cell starts at its top-left vertex, as all cells of `mesh4_1_1` do,
//! while the finer files rotate their lists in a way that follows no rule we could identify.
//!
//! # Construction
//!
//! **Level 1** (17 × 17 cells, N = 17). Node (i, j), 0 ≤ i, j ≤ N, is
//!
//! ```text
//! x_ij = i/N,    y_ij = j/N + a_i · sin(π j/N)
//! ```
//!
//! with a_i = 0 for odd i and for i = 0, and for the even columns i = 2, 4, …, 16 the amplitudes
//! [`AMPLITUDES`] = 0.0194938, 0.0673057, 0.1441683, 0.2251026, 0.2657620, 0.2346703, 0.1434590,
//! 0.0404056. So every other vertical grid line is kept and the nodes of the lines in between are
//! pushed up by a sine profile (fixed on y = 0 and y = 1), whose amplitude peaks near x ≈ 0.6:
//! the zig-zag rows of acute (down to 12.5°) and obtuse (up to 167.5°) angles of the Kershaw mesh.
//! The fit y − j/N = a_i sin(πj/N) is exact to the 10 decimals of the files (residual 5e-11 on
//! every node); the amplitudes are least-squares values from all the column nodes of
//! `mesh4_1_1` … `mesh4_1_6` (uncertainty ~1e-11). No closed formula for a_i as a function of x
//! was found (sine and power-law profiles miss by more than 1e-3), so they are tabulated.
//!
//! **Level k** (17k × 17k cells) is the k × k subdivision of every level-1 cell by its bilinear
//! map: with P₀₀, P₁₀, P₀₁, P₁₁ the corners of a level-1 cell, its subnode (α, β),
//! 0 ≤ α, β ≤ k, is
//!
//! ```text
//! (1−s)(1−t) P₀₀ + s(1−t) P₁₀ + (1−s) t P₀₁ + s t P₁₁,    s = α/k, t = β/k.
//! ```
//!
//! (The finer files are *not* the sine formula on a finer grid: mesh4_1_2's node (2/17, 1/34)
//! is the midpoint 0.0312027538 of its edge, not 1/34 + a₂ sin(π/34) = 0.0312104.) Since the
//! level-1 vertical lines x = i/17 are straight, all fine vertical lines are straight too and the
//! mesh is piecewise bilinear. Levels beyond 6 continue the same subdivision.
//!
//! Counts: n = 17k, (n+1)² vertices, n² cells, 2n(n+1) edges, n edges on each side.
//! h = 0.3288, 0.1666, 0.1116, 0.0839, 0.0672, 0.0560 for k = 1 … 6.
//!
//! # Numbering (that of the files)
//!
//! Vertices: the (N+1)² level-1 nodes row by row; then, for every level-1 edge in the order
//! "rows j = 0 … N, in each row columns i = 0 … N, horizontal edge (i,j)–(i+1,j) if i < N then
//! vertical edge (i,j)–(i,j+1) if j < N", its k−1 inner subnodes from (i,j) onwards; then, for
//! every level-1 cell row by row, its (k−1)² inner subnodes with α outer, β inner.
//! Cells: the level-1 cells row by row, each replaced by its k² subcells with α outer, β inner;
//! subcell (α, β) lists the subnodes (α,β+1), (α,β), (α+1,β), (α+1,β+1) (top-left first,
//! counter-clockwise).

use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_vec};
use crate::error::Result;
use crate::mesh::{Point, PolyMesh};
use std::f64::consts::PI;

/// Cells per side of level 1 (N = 17).
pub const COARSE_N: usize = 17;

/// The sine amplitudes a_i of the level-1 columns i = 2, 4, …, 16 (a_i = 0 on the other columns).
pub const AMPLITUDES: [f64; 8] = [
    0.019493810362039,
    0.067305719933094,
    0.144168331198484,
    0.225102557651651,
    0.265761957393684,
    0.234670345285418,
    0.143459027005829,
    0.040405569420791,
];

/// a_i for column i of level 1.
fn amplitude(i: usize) -> f64 {
    if i.is_multiple_of(2) && (2..=16).contains(&i) {
        AMPLITUDES[i / 2 - 1]
    } else {
        0.0
    }
}

/// The mesh `mesh4_1_level`: (17·level)² quadrangles. Level 0 and levels above
/// [`Family::max_level`](super::Family::max_level) (481) give
/// [`Error::InvalidData`](crate::Error::InvalidData). Within the fixed budget
/// [`MemoryBudget::DEFAULT`]; [`kershaw_within`] takes the caller's.
pub fn kershaw(level: usize) -> Result<PolyMesh> {
    kershaw_within(level, MemoryBudget::DEFAULT)
}

/// As [`kershaw`], refusing ([`MeshError::TooLarge`](crate::MeshError::TooLarge)) a mesh that
/// would need more memory than `budget`, before allocating anything.
pub fn kershaw_within(level: usize, budget: MemoryBudget) -> Result<PolyMesh> {
    super::Family::Kershaw.check_level(level)?;
    super::check_memory(
        &format!("the Kershaw mesh of level {level}"),
        counts(level),
        budget,
    )?;
    let (vertices, cells) = kershaw_data(level)?;
    Ok(PolyMesh::from_cells(vertices, cells)?)
}

/// Cells, cell sides, vertices and edges of level k (n = 17k): n², 4n², (n+1)², 2n(n+1).
pub(crate) fn counts(k: usize) -> super::Counts {
    let n = (k as u64).checked_mul(COARSE_N as u64)?;
    let n1 = n.checked_add(1)?;
    let cells = n.checked_mul(n)?;
    Some([
        cells,
        cells.checked_mul(4)?,
        n1.checked_mul(n1)?,
        n.checked_mul(n1)?.checked_mul(2)?,
    ])
}

/// (1−s)·a + s·b, exactly a when a = b (keeps y = 1 exact on the top side).
fn lerp(a: f64, b: f64, s: f64) -> f64 {
    if a == b { a } else { (1.0 - s) * a + s * b }
}

/// Vertices and cells of level k ≥ 1, in the file numbering.
fn kershaw_data(k: usize) -> Result<(Vec<Point>, Vec<Vec<usize>>)> {
    let nc = COARSE_N;
    let n = nc * k;
    let sin_j: Vec<f64> = (0..=nc)
        .map(|j| {
            if j == 0 || j == nc {
                0.0
            } else {
                (PI * (j as f64 / nc as f64)).sin()
            }
        })
        .collect();
    let coarse = |i: usize, j: usize| -> Point {
        [
            i as f64 / nc as f64,
            j as f64 / nc as f64 + amplitude(i) * sin_j[j],
        ]
    };

    // --- file numbering of subnode (I, J), 0 ≤ I, J ≤ n
    let n_coarse_edges = 2 * nc * (nc + 1);
    let edge_base = (nc + 1) * (nc + 1);
    let cell_base = edge_base + n_coarse_edges * (k - 1);
    let row = 2 * nc + 1;
    let h_edge = |i: usize, j: usize| {
        if j < nc {
            j * row + 2 * i
        } else {
            nc * row + i
        }
    };
    let v_edge = |i: usize, j: usize| j * row + if i < nc { 2 * i + 1 } else { 2 * nc };
    let id = |ii: usize, jj: usize| -> usize {
        let (ci, a) = (ii / k, ii % k);
        let (cj, b) = (jj / k, jj % k);
        match (a, b) {
            (0, 0) => cj * (nc + 1) + ci,
            (_, 0) => edge_base + h_edge(ci, cj) * (k - 1) + a - 1,
            (0, _) => edge_base + v_edge(ci, cj) * (k - 1) + b - 1,
            _ => cell_base + (cj * nc + ci) * (k - 1) * (k - 1) + (a - 1) * (k - 1) + (b - 1),
        }
    };

    let kf = k as f64;
    let mut vertices = try_filled((n + 1) * (n + 1), [0.0; 2], "the vertices")?;
    for jj in 0..=n {
        let cj = (jj / k).min(nc - 1);
        let t = (jj - cj * k) as f64 / kf;
        for ii in 0..=n {
            let ci = (ii / k).min(nc - 1);
            let s = (ii - ci * k) as f64 / kf;
            let (p00, p10) = (coarse(ci, cj), coarse(ci + 1, cj));
            let (p01, p11) = (coarse(ci, cj + 1), coarse(ci + 1, cj + 1));
            let bottom = lerp(p00[1], p10[1], s);
            let top = lerp(p01[1], p11[1], s);
            vertices[id(ii, jj)] = [lerp(p00[0], p10[0], s), lerp(bottom, top, t)];
        }
    }

    let mut cells = try_vec(n * n, "the cells")?;
    for cj in 0..nc {
        for ci in 0..nc {
            for a in 0..k {
                for b in 0..k {
                    let (i0, j0) = (ci * k + a, cj * k + b);
                    cells.push(vec![
                        id(i0, j0 + 1),
                        id(i0, j0),
                        id(i0 + 1, j0),
                        id(i0 + 1, j0 + 1),
                    ]);
                }
            }
        }
    }
    Ok((vertices, cells))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    use crate::mesh::generate::total_area;

    #[test]
    fn counts_area_and_h() {
        let hs = [0.3288, 0.1666, 0.1116, 0.0839, 0.0672, 0.0560];
        for (k, h) in (1..=6).zip(hs) {
            let m = kershaw(k).unwrap();
            let n = 17 * k;
            assert_eq!(m.n_cells(), n * n);
            assert_eq!(m.n_vertices(), (n + 1) * (n + 1));
            assert_eq!(m.n_edges(), 2 * n * (n + 1));
            assert_eq!(m.boundary_edges_on(0, 0.0), n);
            assert!((total_area(&m) - 1.0).abs() < 1e-12);
            assert!((m.h() - h).abs() < 1e-4, "level {k}: h = {}", m.h());
            assert_eq!(m.bounding_box(), crate::mesh::Rect::UNIT);
        }
    }

    #[test]
    fn first_vertices_and_cells_of_mesh4_1_1_and_2() {
        let m = kershaw(1).unwrap();
        // mesh4_1_1.typ2, vertex 21 and cell 1 (1-based there)
        let v = m.vertex(20);
        assert!((v[0] - 0.1176470588).abs() < 1e-10 && (v[1] - 0.0624055077).abs() < 1e-10);
        assert_eq!(m.cell_vertices(0), &[18, 0, 1, 19]);
        let m = kershaw(2).unwrap();
        // mesh4_1_2.typ2: vertex 330 is the midpoint of a level-1 edge, 938 a level-1 cell centre
        let v = m.vertex(329);
        assert!((v[0] - 0.1176470588).abs() < 1e-10 && (v[1] - 0.0312027538).abs() < 1e-10);
        let v = m.vertex(937);
        assert!((v[0] - 0.0882352941).abs() < 1e-10 && (v[1] - 0.0303072593).abs() < 1e-10);
        let mut c = m.cell_vertices(0).to_vec();
        c.sort_unstable();
        assert_eq!(c, [0, 324, 325, 936]);
    }

    #[test]
    fn invalid_levels_are_errors() {
        for r in [kershaw(0), kershaw(482), kershaw(usize::MAX)] {
            assert!(matches!(r, Err(Error::InvalidData(_))), "{r:?}");
        }
    }
}
