//! Uniform Cartesian meshes of rectangles.
//!
//! On \[x₀,x₁\] × \[y₀,y₁\] with nx × ny cells, vertex (i, j) (0 ≤ i ≤ nx, 0 ≤ j ≤ ny) is
//!
//! ```text
//! v(i,j) = (x₀ + (x₁−x₀)·i/nx , y₀ + (y₁−y₀)·j/ny)      (x₁, y₁ exactly on the last line)
//! ```
//!
//! with id `j·(nx+1) + i` (row-major, lower-left first). Cell (i, j) (0 ≤ i < nx, 0 ≤ j < ny)
//! has id `j·nx + i` (row-major) and vertices `[v(i,j), v(i+1,j), v(i+1,j+1), v(i,j+1)]`:
//! counter-clockwise, starting at its lower-left vertex. This is the layout of the FVCA5
//! `mesh2_k` files (2^(k+1) × 2^(k+1) squares on \[0,1\]²).
//!
//! Counts: (nx+1)(ny+1) vertices, nx·ny cells, nx(ny+1) + ny(nx+1) edges, 2(nx+ny) boundary edges,
//! h = √((x₁−x₀)²/nx² + (y₁−y₀)²/ny²).

use super::{Counts, check_cell_count, check_memory};
use crate::budget::MemoryBudget;
use crate::budget::try_vec;
use crate::error::{Error, Result};
use crate::mesh::{Overlap, Point, PolyMesh};

/// The nx × ny uniform mesh of \[0,1\]² (see the module docs for the numbering), within the
/// fixed budget [`MemoryBudget::DEFAULT`].
pub fn cartesian(nx: usize, ny: usize) -> Result<PolyMesh> {
    cartesian_rect(nx, ny, [0.0, 1.0], [0.0, 1.0])
}

/// The nx × ny uniform mesh of the rectangle `[x[0], x[1]] × [y[0], y[1]]` (for instance a strip
/// `[0,1] × [0,0.1]`). Requires nx, ny ≥ 1, finite bounds with `x[0] < x[1]`, `y[0] < y[1]`,
/// and at most [`MAX_CELLS`](super::MAX_CELLS) cells; otherwise [`Error::InvalidData`]. Within
/// the fixed budget [`MemoryBudget::DEFAULT`]; [`cartesian_rect_within`] takes the caller's.
pub fn cartesian_rect(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Result<PolyMesh> {
    cartesian_rect_within(nx, ny, x, y, MemoryBudget::DEFAULT)
}

/// As [`cartesian_rect`], refusing ([`MeshError::TooLarge`](crate::MeshError::TooLarge)) a mesh
/// that would need more memory than `budget`, before allocating anything.
pub fn cartesian_rect_within(
    nx: usize,
    ny: usize,
    x: [f64; 2],
    y: [f64; 2],
    budget: MemoryBudget,
) -> Result<PolyMesh> {
    check_grid(nx, ny, x, y)?;
    let what = format!("a {nx} × {ny} Cartesian mesh");
    check_cell_count(&what, nx.checked_mul(ny))?;
    check_memory(&what, counts(nx, ny), budget)?;
    grid_mesh(nx, ny, x, y, [1, 4], |[a, b, c, d], cells| {
        cells.extend([a, b, c, d])
    })
}

/// The nx × ny grid of the rectangle `[x[0], x[1]] × [y[0], y[1]]` with every square cut into
/// two triangles by its diagonal from the lower-left to the upper-right vertex: square (i, j)
/// gives triangles `2(j·nx + i)` = [v(i,j), v(i+1,j), v(i+1,j+1)] and `2(j·nx + i) + 1` =
/// [v(i,j), v(i+1,j+1), v(i,j+1)], vertices numbered as in the module docs. On it, P1 with
/// f = 0 gives the five-point finite-difference Laplacian at the vertices (the diagonal
/// couplings cancel), the discretisation of PETSc's obstacle example `snes/tutorials/ex9.c`.
/// Same requirements as [`cartesian_rect`], with 2·nx·ny ≤ [`MAX_CELLS`](super::MAX_CELLS).
/// On \[0,1\]² with nx = ny = 2^(k+1), this is level k of the `triangles` family
/// ([`Family::Triangles`](super::Family::Triangles)). Within the fixed budget
/// [`MemoryBudget::DEFAULT`]; [`cartesian_triangles_within`] takes the caller's.
pub fn cartesian_triangles(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Result<PolyMesh> {
    cartesian_triangles_within(nx, ny, x, y, MemoryBudget::DEFAULT)
}

/// As [`cartesian_triangles`], refusing ([`MeshError::TooLarge`](crate::MeshError::TooLarge)) a
/// mesh that would need more memory than `budget`, before allocating anything.
pub fn cartesian_triangles_within(
    nx: usize,
    ny: usize,
    x: [f64; 2],
    y: [f64; 2],
    budget: MemoryBudget,
) -> Result<PolyMesh> {
    check_grid(nx, ny, x, y)?;
    let what = format!("a {nx} × {ny} triangulated Cartesian mesh");
    check_cell_count(&what, nx.checked_mul(ny).and_then(|c| c.checked_mul(2)))?;
    check_memory(&what, triangle_counts(nx, ny), budget)?;
    grid_mesh(nx, ny, x, y, [2, 3], |[a, b, c, d], cells| {
        cells.extend([a, b, c]);
        cells.extend([a, c, d]);
    })
}

/// The mesh of the nx × ny grid (arguments checked) whose square (i, j), with corners
/// [v(i,j), v(i+1,j), v(i+1,j+1), v(i,j+1)], gives the cells that `square` appends to the
/// flat cell list (`shape[0]` cells of `shape[1]` vertices), square after square in row-major
/// order.
fn grid_mesh(
    nx: usize,
    ny: usize,
    x: [f64; 2],
    y: [f64; 2],
    shape: [usize; 2],
    square: impl Fn([usize; 4], &mut Vec<usize>),
) -> Result<PolyMesh> {
    let vertices = grid_vertices(nx, ny, x, y)?;
    let v = |i: usize, j: usize| j * (nx + 1) + i;
    let n_cells = shape[0] * nx * ny;
    let mut cell_verts = try_vec(shape[1] * n_cells, "the vertices of the cells")?;
    for j in 0..ny {
        for i in 0..nx {
            square(
                [v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)],
                &mut cell_verts,
            );
        }
    }
    debug_assert_eq!(cell_verts.len(), shape[1] * n_cells);
    let mut cell_ptr = try_vec(n_cells + 1, "the cell offsets")?;
    cell_ptr.extend((0..=n_cells).map(|k| shape[1] * k));
    Ok(PolyMesh::from_flat_cells(
        vertices,
        cell_ptr,
        cell_verts,
        Overlap::ByConstruction,
    )?)
}

/// Cells, cell sides, vertices and edges of the nx × ny mesh.
pub(crate) fn counts(nx: usize, ny: usize) -> Counts {
    let (nx, ny) = (nx as u64, ny as u64);
    let (nx1, ny1) = (nx.checked_add(1)?, ny.checked_add(1)?);
    let cells = nx.checked_mul(ny)?;
    let edges = nx.checked_mul(ny1)?.checked_add(ny.checked_mul(nx1)?)?;
    Some([cells, cells.checked_mul(4)?, nx1.checked_mul(ny1)?, edges])
}

/// Cells, cell sides, vertices and edges of the triangulated nx × ny mesh
/// ([`cartesian_triangles`]): twice the squares, three sides each, the same vertices, and one
/// more edge (the diagonal) per square.
pub(crate) fn triangle_counts(nx: usize, ny: usize) -> Counts {
    let [squares, _, vertices, edges] = counts(nx, ny)?;
    Some([
        squares.checked_mul(2)?,
        squares.checked_mul(6)?,
        vertices,
        edges.checked_add(squares)?,
    ])
}

/// At least one cell per direction, finite bounds with lower < upper; else
/// [`Error::InvalidData`].
fn check_grid(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Result<()> {
    if nx == 0 || ny == 0 {
        return Err(Error::InvalidData(format!(
            "a Cartesian mesh needs at least one cell per direction (got {nx} × {ny})"
        )));
    }
    for (name, r) in [("x", x), ("y", y)] {
        if !(r[0].is_finite() && r[1].is_finite() && r[0] < r[1]) {
            return Err(Error::InvalidData(format!(
                "invalid {name} range [{}, {}] for a Cartesian mesh (need finite bounds, lower < upper)",
                r[0], r[1]
            )));
        }
    }
    Ok(())
}

/// The (nx+1)(ny+1) grid vertices, numbered as in the module docs. Their coordinates must
/// increase strictly along each direction (an error names the first pair that does not: the
/// range is too narrow for that many cells in floating point): the cells of such a tensor grid
/// tile the rectangle by construction, which is what [`Overlap::ByConstruction`] requires.
fn grid_vertices(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2]) -> Result<Vec<Point>> {
    let xs: Vec<f64> = (0..=nx).map(|i| grid_coord(x[0], x[1], i, nx)).collect();
    let ys: Vec<f64> = (0..=ny).map(|j| grid_coord(y[0], y[1], j, ny)).collect();
    for (name, c) in [("x", &xs), ("y", &ys)] {
        if let Some(i) = c.windows(2).position(|w| !(w[0] < w[1])) {
            return Err(Error::InvalidData(format!(
                "the {name} coordinates of a Cartesian mesh do not increase strictly: lines {i} \
                 and {} are both at {} ({} cells are too many for the range [{}, {}])",
                i + 1,
                c[i + 1],
                c.len() - 1,
                c[0],
                c[c.len() - 1]
            )));
        }
    }
    let mut vertices = try_vec((nx + 1) * (ny + 1), "the vertices")?;
    for &yj in &ys {
        vertices.extend(xs.iter().map(|&xi| [xi, yj]));
    }
    Ok(vertices)
}

/// Coordinate `i` of `n` equal steps on `[a, b]`, exactly `b` for `i = n`.
fn grid_coord(a: f64, b: f64, i: usize, n: usize) -> f64 {
    if i == n {
        b
    } else {
        a + (b - a) * (i as f64 / n as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::generate::total_area;

    /// Runs this test again in a child under `ulimit -v` of 1 GiB, where a 5000 × 5000 mesh
    /// passes the estimate against a budget of 1 TiB (the caller's choice) but its arrays
    /// cannot be mapped: the vertices (400 MB) fit, the cells' vertex list (800 MB) does not,
    /// and its allocation fails as a typed out-of-memory error naming it, not an abort.
    #[cfg(target_os = "linux")]
    #[test]
    fn an_allocation_the_address_space_refuses_is_a_typed_error() {
        const NAME: &str = "mesh::generate::cartesian::tests::an_allocation_the_address_space_refuses_is_a_typed_error";
        if std::env::var_os("GRADVI_ALLOC_CHILD").is_some() {
            let big = MemoryBudget::new(1 << 40);
            let e = cartesian_rect_within(5000, 5000, [0.0, 1.0], [0.0, 1.0], big).unwrap_err();
            assert!(e.is_out_of_memory(), "{e}");
            assert!(
                e.to_string()
                    .starts_with("the vertices of the cells would need about 762.9 MiB"),
                "{e}"
            );
            return;
        }
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 1048576 && exec \"$0\" \"$@\"")
            .arg(std::env::current_exe().unwrap())
            .args(["--exact", NAME, "--test-threads", "1"])
            .env("GRADVI_ALLOC_CHILD", "1")
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "the child under ulimit -v failed ({}): {said}",
            out.status
        );
        assert!(said.contains("1 passed"), "the child ran no test: {said}");
    }

    #[test]
    fn unit_square_counts_area_and_h() {
        for (nx, ny) in [(1, 1), (4, 4), (3, 5), (64, 64)] {
            let m = cartesian(nx, ny).unwrap();
            assert_eq!(m.n_cells(), nx * ny);
            assert_eq!(m.n_vertices(), (nx + 1) * (ny + 1));
            assert_eq!(m.n_edges(), nx * (ny + 1) + ny * (nx + 1));
            assert_eq!(m.boundary_edges().len(), 2 * (nx + ny));
            assert!((total_area(&m) - 1.0).abs() < 1e-12);
            let h = ((1.0 / (nx * nx) as f64) + 1.0 / (ny * ny) as f64).sqrt();
            assert!((m.h() - h).abs() < 1e-14, "{} vs {h}", m.h());
            assert_eq!(m.bounding_box(), crate::mesh::Rect::UNIT);
        }
    }

    #[test]
    fn row_major_counter_clockwise_from_lower_left() {
        let m = cartesian(4, 4).unwrap();
        assert_eq!(m.cell_vertices(0), &[0, 1, 6, 5]);
        assert_eq!(m.cell_vertices(5), &[6, 7, 12, 11]);
        assert_eq!(m.vertex(6), [0.25, 0.25]);
        assert_eq!(m.vertex(24), [1.0, 1.0]);
        assert_eq!(m.centroid(1), [0.375, 0.125]);
    }

    #[test]
    fn triangulated_grid() {
        let m = cartesian_triangles(4, 3, [-2.0, 2.0], [-2.0, 2.0]).unwrap();
        assert_eq!(m.n_cells(), 24);
        assert_eq!(m.n_vertices(), 20);
        assert_eq!(m.n_edges(), 4 * 4 + 3 * 5 + 12);
        assert!((total_area(&m) - 16.0).abs() < 1e-12);
        assert!(m.is_triangular());
        assert_eq!(m.cell_vertices(1), &[0, 6, 5]);
    }

    #[test]
    fn strip() {
        let m = cartesian_rect(20, 2, [0.0, 1.0], [0.0, 0.1]).unwrap();
        assert_eq!(m.n_cells(), 40);
        assert!((total_area(&m) - 0.1).abs() < 1e-14);
        assert_eq!(
            m.bounding_box(),
            crate::mesh::Rect::new([0.0, 1.0], [0.0, 0.1])
        );
        assert!((m.h() - (0.05f64.powi(2) * 2.0).sqrt()).abs() < 1e-14);
        let m = cartesian_rect(3, 1, [-1.0, 2.0], [5.0, 6.0]).unwrap();
        assert_eq!(m.vertex(7), [2.0, 6.0]);
    }

    #[test]
    fn invalid_arguments_are_errors() {
        for r in [
            cartesian(0, 3),
            cartesian(3, 0),
            cartesian_rect(2, 2, [1.0, 0.0], [0.0, 1.0]),
            cartesian_rect(2, 2, [0.0, 1.0], [0.0, f64::NAN]),
            cartesian_rect(2, 2, [0.0, 0.0], [0.0, 1.0]),
            cartesian(1 << 13, 1 << 14),
            cartesian(usize::MAX, 2),
            // 1000 steps of a range of 4 ulps: coordinates that do not increase strictly
            cartesian_rect(1000, 2, [1.0, 1.0 + 4.0 * f64::EPSILON], [0.0, 1.0]),
            cartesian_triangles(2, 1000, [0.0, 1.0], [1.0, 1.0 + 4.0 * f64::EPSILON]),
        ] {
            assert!(matches!(r, Err(Error::InvalidData(_))), "{r:?}");
        }
    }

    /// The generators skip the overlap sweep (`Overlap::ByConstruction`): the same
    /// cells pass the full validation, with the same mesh.
    #[test]
    fn tensor_grids_pass_the_full_validation() {
        for (nx, ny, x, y) in [
            (1, 1, [0.0, 1.0], [0.0, 1.0]),
            (7, 3, [-2.0, 2.0], [0.1, 0.3]),
            (30, 45, [0.0, 1.0], [0.0, 1.0]),
        ] {
            for m in [
                cartesian_rect(nx, ny, x, y).unwrap(),
                cartesian_triangles(nx, ny, x, y).unwrap(),
            ] {
                let v: Vec<Point> = (0..m.n_vertices()).map(|i| m.vertex(i)).collect();
                let cells: Vec<Vec<usize>> = (0..m.n_cells())
                    .map(|k| m.cell_vertices(k).iter().map(|&i| i as usize).collect())
                    .collect();
                let full = PolyMesh::from_cells(v, cells).unwrap();
                assert_eq!(full.n_edges(), m.n_edges());
                for e in 0..m.n_edges() {
                    assert_eq!(full.edge_cells(e), m.edge_cells(e));
                }
                for k in 0..m.n_cells() {
                    assert_eq!(full.cell_edges(k), m.cell_edges(k));
                    assert_eq!(full.centroid(k), m.centroid(k));
                }
            }
        }
    }
}
