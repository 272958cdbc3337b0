//! The coarse mesh of a rectangular domain cut into equal boxes: the first level of the
//! nested warm start of an obstacle problem when Ω is a rectangle
//! ([`crate::solver::warm_start`], `CoarseMesh::box_tiling`), in place of the
//! agglomeration of [`super::agglomerate`].
//!
//! ## Construction, for boxes of side h that tile the bounding box exactly
//! The bounding box [x₀, x₁] × [y₀, y₁] is cut into n_x × n_y boxes (n_x = (x₁ − x₀)/h,
//! n_y = (y₁ − y₀)/h, whole numbers up to a relative 10⁻⁹) by the lines x = x₀ + i h and
//! y = y₀ + j h, each moved to the nearest fine boundary vertex of the bottom (left) side when
//! that is within h/4, so that on a structured fine mesh every box is a union of whole fine
//! cells, as the agglomeration's aggregates are (boxes whose sides cut through fine cells cost
//! the later fine solves conjugate-gradient iterations: `replication/measurements/solver.md`).
//! Box (i, j) is the coarse cell i + n_x j, a rectangle whose four corners are the grid's, so
//! the coarse mesh is conforming and tiles the rectangle exactly. Fine cell K belongs to the
//! box of its key point ([`super::agglomerate`]: the centre of its bounding box on a
//! rectangle or a right triangle with axis-parallel legs, so that the two triangles of a
//! square stay together; its centroid otherwise).
//!
//! Refused (an error; the caller then agglomerates): a box that holds no fine cell (the domain
//! is not its bounding box, or the boxes are smaller than the cells), a box holding cells of
//! two materials (cell tags), a fine boundary edge off the bounding box, and a coarse boundary
//! side whose fine boundary edges carry two tags. So the coarse cells are unions of fine cells
//! of one material up to the fine cells cut by the box sides, and each coarse boundary side
//! carries the tag of the fine boundary edges whose midpoints lie on it (a fine edge across a
//! box corner counts for one side only, so near a change of tag the coarse data may differ
//! from the fine by one fine edge): boundary data given by tag carries over, and the coarse
//! problem evaluates it at the sides' midpoints. [`Agglomeration::boundary_edge_of`] maps each
//! fine boundary edge to the side that holds its midpoint.
//!
//! Cost: O(n) in the fine cells and edges (one key point per cell, one pass over the boundary
//! edges), against the agglomeration's unions, merges and tracing of aggregate boundaries.

use super::agglomerate::{Agglomeration, NO_EDGE, key_point};
use super::{Point, PolyMesh};
use crate::error::MeshError;
use rayon::prelude::*;

/// Relative tolerance of the tiling (the sides against whole numbers of boxes) and of a
/// boundary edge's distance to the bounding box.
const TILE_TOL: f64 = 1e-9;

/// Least number of fine cells of one parallel task.
const MIN_TASK: usize = 1 << 12;

/// The box cover of `fine` with boxes of side `size` (see the module docs).
/// [`MeshError::NonConforming`] when the boxes do not tile the bounding box, or for the
/// refusals of the module docs; the errors of [`PolyMesh::from_cells_tagged`].
pub fn box_cover(fine: &PolyMesh, size: f64) -> Result<Agglomeration, MeshError> {
    let fail = |m: String| Err(MeshError::NonConforming(format!("box cover: {m}")));
    let bb = fine.bounding_box();
    let (x0, y0) = (bb.x[0], bb.y[0]);
    let (lx, ly) = (bb.x[1] - bb.x[0], bb.y[1] - bb.y[0]);
    let boxes = |l: f64| -> Option<usize> {
        let k = (l / size).round();
        (size.is_finite()
            && size > 0.0
            && k >= 1.0
            && k <= fine.n_cells() as f64
            && (l - k * size).abs() <= TILE_TOL * l)
            .then_some(k as usize)
    };
    let (Some(nx), Some(ny)) = (boxes(lx), boxes(ly)) else {
        return fail(format!(
            "boxes of side {size} do not tile the bounding box {lx} × {ly}"
        ));
    };
    if nx.saturating_mul(ny) > fine.n_cells() {
        return fail(format!(
            "{nx} × {ny} boxes for {} fine cells",
            fine.n_cells()
        ));
    }
    // the grid lines: i h from the corner, each moved to the nearest fine vertex of the
    // bottom (left) side of the boundary within h/4, so that the boxes of a structured fine
    // mesh are unions of whole fine cells
    let tol = TILE_TOL * lx.max(ly);
    let mut bottom = Vec::new();
    let mut left = Vec::new();
    for &e in fine.boundary_edges() {
        for p in fine.edge_vertices(e).map(|v| fine.vertex(v)) {
            if (p[1] - y0).abs() <= tol {
                bottom.push(p[0]);
            }
            if (p[0] - x0).abs() <= tol {
                left.push(p[1]);
            }
        }
    }
    let xs = grid_lines(bb.x, nx, bottom);
    let ys = grid_lines(bb.y, ny, left);
    // exact: no more boxes than fine cells (checked above), fewer than u32::MAX (the mesh's
    // build refuses more)
    let cell_of: Vec<u32> = (0..fine.n_cells())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|k| {
            let p = key_point(fine, k);
            (line_index(p[0], &xs) + nx * line_index(p[1], &ys)) as u32
        })
        .collect();
    // one material per box, and no empty box
    let mut tags: Vec<Option<i32>> = vec![None; nx * ny];
    for (k, &b) in cell_of.iter().enumerate() {
        let (t, b) = (fine.cell_tag(k), b as usize);
        match tags[b] {
            None => tags[b] = Some(t),
            Some(s) if s != t => {
                return fail(format!(
                    "box {b} holds fine cells of the materials {s} and {t}"
                ));
            }
            Some(_) => {}
        }
    }
    if let Some(b) = tags.iter().position(Option::is_none) {
        return fail(format!(
            "box ({}, {}) holds no fine cell: the domain is not its bounding box",
            b % nx,
            b / nx
        ));
    }
    let cell_tags: Vec<i32> = tags.into_iter().flatten().collect();
    // the grid's corners: (i, j) is vertex i + (n_x + 1) j
    let vertex = |i: usize, j: usize| i + (nx + 1) * j;
    let mut vertices: Vec<Point> = Vec::with_capacity((nx + 1) * (ny + 1));
    for &y in &ys {
        vertices.extend(xs.iter().map(|&x| [x, y]));
    }
    let cells: Vec<Vec<usize>> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                vec![
                    vertex(i, j),
                    vertex(i + 1, j),
                    vertex(i + 1, j + 1),
                    vertex(i, j + 1),
                ]
            })
        })
        .collect();
    // the coarse boundary side of each fine boundary edge (its midpoint's), as its two grid
    // vertices, and the tag of each side
    let side_of = |e: usize| -> Option<[usize; 2]> {
        let [a, b] = fine.edge_vertices(e);
        let (p, q) = (fine.vertex(a), fine.vertex(b));
        let m = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
        let on = |c: f64, at: f64| (c - at).abs() <= tol;
        let (i, j) = (line_index(m[0], &xs), line_index(m[1], &ys));
        if on(p[1], bb.y[0]) && on(q[1], bb.y[0]) {
            Some([vertex(i, 0), vertex(i + 1, 0)])
        } else if on(p[1], bb.y[1]) && on(q[1], bb.y[1]) {
            Some([vertex(i, ny), vertex(i + 1, ny)])
        } else if on(p[0], bb.x[0]) && on(q[0], bb.x[0]) {
            Some([vertex(0, j), vertex(0, j + 1)])
        } else if on(p[0], bb.x[1]) && on(q[0], bb.x[1]) {
            Some([vertex(nx, j), vertex(nx, j + 1)])
        } else {
            None
        }
    };
    let mut side_tag: std::collections::BTreeMap<[usize; 2], i32> = Default::default();
    let mut sides = Vec::with_capacity(fine.boundary_edges().len());
    for &e in fine.boundary_edges() {
        let Some(s) = side_of(e) else {
            let [a, b] = fine.edge_vertices(e);
            return fail(format!(
                "the boundary edge {e} ({a}, {b}) is not on the bounding box"
            ));
        };
        let t = fine.edge_tag(e);
        match side_tag.insert(s, t) {
            Some(u) if u != t => {
                return fail(format!(
                    "the boundary side {s:?} holds fine edges tagged {u} and {t}"
                ));
            }
            _ => {}
        }
        sides.push((e, s));
    }
    let tagged: Vec<(usize, usize, i32)> = side_tag
        .iter()
        .filter(|(_, t)| **t != 0)
        .map(|(s, &t)| (s[0], s[1], t))
        .collect();
    let mesh = PolyMesh::from_cells_tagged(vertices, cells, &tagged)?.with_cell_tags(cell_tags)?;
    let mut boundary_edge_of = vec![NO_EDGE; fine.n_edges()];
    for (e, s) in sides {
        let pos = mesh.boundary_position(s[0], s[1]).ok_or_else(|| {
            MeshError::NonConforming(format!(
                "box cover: no coarse boundary side {s:?} for the fine edge {e}"
            ))
        })?;
        boundary_edge_of[e] = mesh.boundary_edges()[pos] as u32;
    }
    Ok(Agglomeration {
        mesh,
        cell_of,
        boundary_edge_of,
        dissolved_cells: 0,
    })
}

/// The box of coordinate `c` along the n + 1 increasing `lines` of [`grid_lines`]: the number
/// of interior lines at or below `c` (0 for `c` below the second line or NaN, n − 1 at or
/// above the last interior one). Found from the box of the unmoved line grid, i =
/// ⌊(c − l₀) n / (lₙ − l₀)⌋, then moved to the neighbour while a line is on the wrong side:
/// the lines are moved by at most h/4 (a step or none), where a search of the n − 1 lines
/// took about log₂ n unpredictable branches per call (per fine cell, twice).
fn line_index(c: f64, lines: &[f64]) -> usize {
    let n = lines.len() - 1;
    let (l0, ln) = (lines[0], lines[n]);
    // a saturating cast, which truncates: ⌊t⌋ for t ≥ 0, and 0 for NaN and for t < 0 (where
    // ⌊t⌋ would also give 0); no call to `floor` per fine cell
    let mut i = (((c - l0) / (ln - l0) * n as f64) as usize).min(n - 1);
    while i > 0 && lines[i] > c {
        i -= 1;
    }
    while i + 1 < n && lines[i + 1] <= c {
        i += 1;
    }
    i
}

/// The n + 1 lines cutting `range` into n cells: lᵢ = r₀ + i (r₁ − r₀)/n, moved to the
/// nearest of `snap` (fine boundary vertices) when that is within h/4 (h = (r₁ − r₀)/n); the
/// ends are r₀ and r₁ exactly. Consecutive lines stay at least h/2 apart.
fn grid_lines(range: [f64; 2], n: usize, mut snap: Vec<f64>) -> Vec<f64> {
    snap.sort_unstable_by(f64::total_cmp);
    let h = (range[1] - range[0]) / n as f64;
    let mut lines = Vec::with_capacity(n + 1);
    lines.push(range[0]);
    for i in 1..n {
        let t = range[0] + (range[1] - range[0]) * i as f64 / n as f64;
        let at = snap.partition_point(|&x| x < t);
        let nearest = [at.checked_sub(1), Some(at)]
            .into_iter()
            .flatten()
            .filter_map(|k| snap.get(k).copied())
            .min_by(|a, b| (a - t).abs().total_cmp(&(b - t).abs()));
        lines.push(match nearest {
            Some(x) if (x - t).abs() <= 0.25 * h => x,
            _ => t,
        });
    }
    lines.push(range[1]);
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{cartesian_rect, cartesian_triangles};

    #[test]
    fn line_index_counts_the_interior_lines_at_or_below() {
        // lines moved from the even grid, a coordinate on each line, between and outside
        let lines = grid_lines([0.0, 1.0], 8, vec![0.1, 0.26, 0.3, 0.52, 0.9, 0.99]);
        assert!(lines.windows(2).all(|w| w[0] < w[1]));
        assert_ne!(lines[1], 0.125);
        let search = |c: f64| lines[1..lines.len() - 1].partition_point(|&l| l <= c);
        let mut probes: Vec<f64> = (-20..=220).map(|i| i as f64 / 200.0).collect();
        probes.extend(lines.iter().copied());
        probes.extend(lines.iter().map(|l| l - 1e-12));
        probes.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1e300, 1e300]);
        for c in probes {
            assert_eq!(line_index(c, &lines), search(c), "c = {c}");
        }
        assert_eq!(line_index(0.5, &[0.0, 1.0]), 0);
    }

    fn inside(p: Point, m: &PolyMesh, c: usize) -> bool {
        let b = m.cell_vertices(c).iter().map(|&v| m.vertex(v as usize));
        let (lo, hi) = b.fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), q| {
            (
                [lo[0].min(q[0]), lo[1].min(q[1])],
                [hi[0].max(q[0]), hi[1].max(q[1])],
            )
        });
        (0..2).all(|r| lo[r] - 1e-12 <= p[r] && p[r] <= hi[r] + 1e-12)
    }

    #[test]
    fn triangulated_squares_go_to_their_box_in_pairs() {
        // 24 × 24 squares of (−2, 2)², each cut into two triangles, in 9 × 9 boxes of side
        // 4/9: the lines i h move to the nearest fine grid line (spacing 1/6, within h/4), so
        // each box is a union of whole squares
        let fine = cartesian_triangles(24, 24, [-2.0, 2.0], [-2.0, 2.0]).unwrap();
        let h = 4.0 / 9.0;
        let cover = box_cover(&fine, h).unwrap();
        let m = &cover.mesh;
        assert_eq!(m.n_cells(), 81);
        let area: f64 = (0..81).map(|c| m.measure(c)).sum();
        assert!((area - 16.0).abs() < 1e-12);
        for v in 0..m.n_vertices() {
            let p = m.vertex(v);
            for r in 0..2 {
                let sixths = (p[r] + 2.0) * 6.0;
                assert!((sixths - sixths.round()).abs() < 1e-9, "{p:?}");
                let boxes = (p[r] + 2.0) / h;
                assert!(
                    (boxes - boxes.round()).abs() * h <= 0.25 * h + 1e-12,
                    "{p:?}"
                );
            }
        }
        for k in 0..fine.n_cells() {
            let c = cover.cell_of[k] as usize;
            assert!(inside(key_point(&fine, k), m, c), "cell {k}");
            for &v in fine.cell_vertices(k) {
                assert!(inside(fine.vertex(v as usize), m, c), "cell {k}");
            }
        }
        // the two triangles of a square, on either side of its diagonal: one box
        for e in 0..fine.n_edges() {
            let [p, q] = fine.edge_vertices(e).map(|v| fine.vertex(v));
            if p[0] != q[0] && p[1] != q[1] {
                let [a, b] = fine.edge_cells(e);
                assert_eq!(cover.cell_of[a], cover.cell_of[b], "diagonal {e}");
            }
        }
        // every fine boundary edge lies on its coarse side
        let mut hit = vec![false; m.n_edges()];
        for &e in fine.boundary_edges() {
            let ce = cover.boundary_edge_of[e] as usize;
            assert!(m.is_boundary_edge(ce));
            hit[ce] = true;
            let [a, b] = m.edge_vertices(ce).map(|v| m.vertex(v));
            let p = fine.edge_midpoint(e);
            let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
            let len2 = (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2);
            let t = ((p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1])) / len2;
            assert!(cross.abs() < 1e-12 && (0.0..=1.0).contains(&t), "edge {e}");
        }
        assert_eq!(hit.iter().filter(|&&x| x).count(), m.boundary_edges().len());
        let interior = (0..fine.n_edges()).filter(|&e| !fine.is_boundary_edge(e));
        assert!(
            interior
                .into_iter()
                .all(|e| cover.boundary_edge_of[e] == NO_EDGE)
        );
    }

    #[test]
    fn grid_lines_snap_within_a_quarter_box() {
        // lines at 0.25, 0.5, 0.75; fine vertices near the first two only
        let lines = grid_lines([0.0, 1.0], 4, vec![0.9, 0.2, 0.52, 0.0, 1.0, 0.34]);
        assert_eq!(lines, vec![0.0, 0.2, 0.52, 0.75, 1.0]);
        // no vertex within h/4 = 1/16: the equal lines
        let lines = grid_lines([1.0, 3.0], 4, vec![1.2, 2.74]);
        assert_eq!(lines, vec![1.0, 1.5, 2.0, 2.5, 3.0]);
        // one box: the ends only
        assert_eq!(grid_lines([0.0, 2.0], 1, vec![1.0]), vec![0.0, 2.0]);
    }

    #[test]
    fn tags_carry_over_and_mixed_boxes_are_refused() {
        // boundary tags by side (bottom 1, right 2, else 0) and two materials split at x = 1/2
        let fine = cartesian_rect(16, 16, [0.0, 1.0], [0.0, 1.0])
            .unwrap()
            .with_boundary_tags(|p| {
                if p[1] < 1e-12 {
                    1
                } else if p[0] > 1.0 - 1e-12 {
                    2
                } else {
                    0
                }
            });
        let halves: Vec<i32> = (0..fine.n_cells())
            .map(|k| i32::from(fine.centroid(k)[0] > 0.5))
            .collect();
        let fine = fine.with_cell_tags(halves).unwrap();
        let cover = box_cover(&fine, 0.25).unwrap();
        let m = &cover.mesh;
        for &e in fine.boundary_edges() {
            assert_eq!(
                m.edge_tag(cover.boundary_edge_of[e] as usize),
                fine.edge_tag(e),
                "edge {e}"
            );
        }
        for k in 0..fine.n_cells() {
            assert_eq!(m.cell_tag(cover.cell_of[k] as usize), fine.cell_tag(k));
        }
        // boxes of 3/16... do not tile; boxes of 1/3 hold both materials (the middle column)
        let err = |s: f64| box_cover(&fine, s).unwrap_err().to_string();
        assert!(err(0.3).contains("do not tile"), "{}", err(0.3));
        assert!(err(1.0 / 3.0).contains("materials"), "{}", err(1.0 / 3.0));
        // a side whose fine edges carry two tags: the bottom split at x = 1/2
        let split = cartesian_rect(16, 16, [0.0, 1.0], [0.0, 1.0])
            .unwrap()
            .with_boundary_tags(|p| i32::from(p[1] < 1e-12 && p[0] < 0.5));
        assert!(box_cover(&split, 0.25).is_ok());
        let e = box_cover(&split, 1.0 / 3.0).unwrap_err().to_string();
        assert!(e.contains("tagged"), "{e}");
    }

    #[test]
    fn a_domain_that_is_not_its_bounding_box_is_refused() {
        // an L-shape: the unit square without its upper right quarter
        let square = cartesian_rect(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let keep: Vec<usize> = (0..square.n_cells())
            .filter(|&k| {
                let c = square.centroid(k);
                !(c[0] > 0.5 && c[1] > 0.5)
            })
            .collect();
        let cells: Vec<Vec<usize>> = keep
            .iter()
            .map(|&k| {
                square
                    .cell_vertices(k)
                    .iter()
                    .map(|&v| v as usize)
                    .collect()
            })
            .collect();
        let verts: Vec<Point> = (0..square.n_vertices()).map(|v| square.vertex(v)).collect();
        let (verts, cells, _) = crate::mesh::drop_unused_vertices(&verts, &cells);
        let l = PolyMesh::from_cells(verts, cells).unwrap();
        let e = box_cover(&l, 0.25).unwrap_err().to_string();
        assert!(e.contains("holds no fine cell"), "{e}");
        // not positive, not finite, or more boxes than cells
        for s in [0.0, -0.25, f64::NAN, f64::INFINITY, 1.0 / 64.0] {
            assert!(box_cover(&square, s).is_err(), "{s}");
        }
    }
}
