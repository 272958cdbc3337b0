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
use crate::budget::{try_filled, try_vec};
use crate::error::{Error, Result};
use crate::mesh::build::check_counts;
use crate::mesh::validate::diameter;
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
    grid_mesh(nx, ny, x, y, Squares::Whole)
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
    grid_mesh(nx, ny, x, y, Squares::Halved)
}

/// What each square of the grid becomes: one cell, or two triangles cut by the diagonal from
/// its lower-left to its upper-right vertex.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Squares {
    Whole,
    Halved,
}

impl Squares {
    /// Cells per square and vertices per cell.
    fn shape(self) -> [usize; 2] {
        match self {
            Squares::Whole => [1, 4],
            Squares::Halved => [2, 3],
        }
    }

    /// Appends to `out` the vertex lists of the cells of the square with corners
    /// [a, b, c, d] (counter-clockwise from the lower left).
    fn cells<T: Copy>(self, [a, b, c, d]: [T; 4], out: &mut Vec<T>) {
        match self {
            Squares::Whole => out.extend([a, b, c, d]),
            Squares::Halved => out.extend([a, b, c, a, c, d]),
        }
    }
}

/// The mesh of the nx × ny grid (arguments checked) whose square (i, j), with corners
/// [v(i,j), v(i+1,j), v(i+1,j+1), v(i,j+1)], gives the cells of `squares`, square after square
/// in row-major order.
///
/// On a grid whose steps are all within a factor 10³ of each other ([`well_shaped`]) the edges,
/// the cells on either side of each edge and the edge of every cell side are written down
/// directly ([`grid_topology`]), in the numbering [`PolyMesh::from_flat_cells`] gives them (by
/// (smaller vertex, larger vertex), the lower-numbered cell first): the same mesh, bit for bit
/// (tested), without sorting the cell sides or checking what the construction guarantees.
/// Other grids, whose thin cells checks 4 and 9 of the validation might refuse, go through
/// [`PolyMesh::from_flat_cells`] and its errors.
fn grid_mesh(nx: usize, ny: usize, x: [f64; 2], y: [f64; 2], squares: Squares) -> Result<PolyMesh> {
    let vertices = grid_vertices(nx, ny, x, y)?;
    let [per_square, per_cell] = squares.shape();
    let n_cells = per_square * nx * ny;
    if well_shaped(&vertices, nx, ny) {
        check_counts(vertices.len(), n_cells, per_cell * n_cells)?;
        return grid_topology(vertices, nx, ny, squares);
    }
    let v = |i: usize, j: usize| j * (nx + 1) + i;
    let mut cell_verts = try_vec(per_cell * n_cells, "the vertices of the cells")?;
    for j in 0..ny {
        for i in 0..nx {
            let corners = [v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)];
            squares.cells(corners, &mut cell_verts);
        }
    }
    debug_assert_eq!(cell_verts.len(), per_cell * n_cells);
    let mut cell_ptr = try_vec(n_cells + 1, "the cell offsets")?;
    cell_ptr.extend((0..=n_cells).map(|k| per_cell * k));
    Ok(PolyMesh::from_flat_cells(
        vertices,
        cell_ptr,
        cell_verts,
        Overlap::ByConstruction,
    )?)
}

/// Whether every step of the grid (whose coordinates increase strictly, checked by
/// [`grid_vertices`]) is finite and at least 10⁻³ times the largest step of either direction.
/// Its cells then pass every check of [`validate`](crate::mesh::validate) by a wide margin:
/// distinct vertices (strictly increasing coordinates), all used, counter-clockwise, simple,
/// convex; |K| ≥ 10⁻⁶ h_K²/4 against the 10⁻¹⁴ h_K² of check 4, and the centroid at least
/// 10⁻⁶ h_K/6 from every side against the 10⁻¹² h_K of check 9; a tensor grid tiles its
/// rectangle (checks 10–12).
fn well_shaped(vertices: &[Point], nx: usize, ny: usize) -> bool {
    let xs: Vec<f64> = vertices[..=nx].iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = (0..=ny).map(|j| vertices[j * (nx + 1)][1]).collect();
    let (lo, hi) = (xs.windows(2).chain(ys.windows(2)))
        .map(|w| w[1] - w[0])
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    xs.iter().chain(&ys).all(|c| c.is_finite()) && hi.is_finite() && lo >= 1e-3 * hi
}

/// The mesh of a [`well_shaped`] grid with its connectivity written down (see [`grid_mesh`]).
///
/// Edges are numbered as [`build_edges`](crate::mesh::edges) numbers them: by smaller vertex,
/// then larger. Vertex v = v(i,j) is the smaller end of its horizontal edge H(i,j) to v + 1
/// (i < nx), its vertical edge V(i,j) to v + nx + 1 (j < ny) and, halved, its diagonal D(i,j)
/// to v + nx + 2 (both), in that order; so row j < ny holds `per_row` = 2nx + 1 (3nx + 1
/// halved) edges, the top row nx, and
///
/// ```text
/// H(i,j) = j·per_row + k·i  (j < ny),   H(i,ny) = ny·per_row + i,
/// V(i,j) = j·per_row + k·i + [i < nx],  D(i,j) = j·per_row + 3i + 2,
/// ```
///
/// with k = 2 (3 halved) edges per vertex before the last column. The cells of square
/// s = j·nx + i: whole, cell s with sides H(i,j), V(i+1,j), H(i,j+1), V(i,j); halved, triangle
/// 2s = [v(i,j), v(i+1,j), v(i+1,j+1)] with sides H(i,j), V(i+1,j), D(i,j) and triangle
/// 2s + 1 = [v(i,j), v(i+1,j+1), v(i,j+1)] with sides D(i,j), H(i,j+1), V(i,j). An edge lists
/// its lower-numbered cell first: below H (the top side of the square below), left of V.
fn grid_topology(vertices: Vec<Point>, nx: usize, ny: usize, squares: Squares) -> Result<PolyMesh> {
    let halved = squares == Squares::Halved;
    let [per_square, per_cell] = squares.shape();
    let n_cells = per_square * nx * ny;
    let k = if halved { 3 } else { 2 };
    let per_row = k * nx + 1;
    let ne = per_row * ny + nx;
    let h_edge = |i: usize, j: usize| {
        if j < ny {
            j * per_row + k * i
        } else {
            ny * per_row + i
        }
    };
    let v_edge = |i: usize, j: usize| j * per_row + k * i + usize::from(i < nx);
    let d_edge = |i: usize, j: usize| j * per_row + 3 * i + 2;
    let vid = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let cell = |i: usize, j: usize| per_square * (j * nx + i);
    let none = u32::MAX;

    // the cells: vertices and sides, square after square
    let mut cell_verts: Vec<u32> = try_vec(per_cell * n_cells, "the vertices of the cells")?;
    let mut cell_edges: Vec<u32> = try_vec(per_cell * n_cells, "the edges of the cell sides")?;
    for j in 0..ny {
        for i in 0..nx {
            let corners = [vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)];
            squares.cells(corners, &mut cell_verts);
            let [bottom, right, top, left] = [
                h_edge(i, j),
                v_edge(i + 1, j),
                h_edge(i, j + 1),
                v_edge(i, j),
            ]
            .map(|e| e as u32);
            // the sides of the cells, in the order of their vertices (side m joins vertices m
            // and m + 1)
            if halved {
                let diagonal = d_edge(i, j) as u32;
                cell_edges.extend([bottom, right, diagonal, diagonal, top, left]);
            } else {
                cell_edges.extend([bottom, right, top, left]);
            }
        }
    }
    let mut cell_ptr: Vec<u32> = try_vec(n_cells + 1, "the 32-bit offsets of the cells")?;
    cell_ptr.extend((0..=n_cells).map(|c| (per_cell * c) as u32));

    // the edges in vertex order, with their cells (lower-numbered first)
    let mut edges: Vec<[u32; 2]> = try_vec(ne, "the end points of the edges")?;
    let mut edge_cells: Vec<[u32; 2]> = try_vec(ne, "the cells of the edges")?;
    let n_boundary = 2 * (nx + ny);
    let mut boundary_edges: Vec<usize> = try_vec(n_boundary, "the boundary edges")?;
    let mut push = |ends: [u32; 2], cells: [Option<usize>; 2]| {
        if cells[0].is_none() || cells[1].is_none() {
            boundary_edges.push(edges.len());
        }
        let mut on = cells.into_iter().flatten().map(|c| c as u32);
        edge_cells.push([on.next().unwrap_or(none), on.next().unwrap_or(none)]);
        edges.push(ends);
    };
    for j in 0..=ny {
        for i in 0..=nx {
            let v = vid(i, j);
            if i < nx {
                // H(i,j): the square below (its top side), then the square above
                let below = (j > 0).then(|| cell(i, j - 1) + usize::from(halved));
                let above = (j < ny).then(|| cell(i, j));
                push([v, vid(i + 1, j)], [below, above]);
            }
            if j < ny {
                // V(i,j): the square on the left (its right side), then the one on the right
                let left = (i > 0).then(|| cell(i - 1, j));
                let right = (i < nx).then(|| cell(i, j) + usize::from(halved));
                push([v, vid(i, j + 1)], [left, right]);
            }
            if halved && i < nx && j < ny {
                push(
                    [v, vid(i + 1, j + 1)],
                    [Some(cell(i, j)), Some(cell(i, j) + 1)],
                );
            }
        }
    }
    debug_assert_eq!((edges.len(), boundary_edges.len()), (ne, n_boundary));

    // h = max_K h_K, each h_K computed as the validation computes it (the same bits)
    let mut h: f64 = 0.0;
    let mut pts: Vec<Point> = Vec::with_capacity(per_cell);
    for c in cell_verts.chunks_exact(per_cell) {
        pts.clear();
        pts.extend(c.iter().map(|&v| vertices[v as usize]));
        h = h.max(diameter(&pts));
    }
    let boundary_tags = try_filled(n_boundary, 0i32, "the boundary tags")?;
    Ok(PolyMesh {
        vertices,
        cell_ptr,
        cell_verts,
        cell_edges,
        edges,
        edge_cells,
        boundary_tags,
        cell_tags: Vec::new(),
        reversed: Vec::new(),
        boundary_edges,
        h,
    })
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
    /// cannot be mapped: the vertices (400 MB) and the cells' 32-bit vertex list (400 MB) fit,
    /// the edges of the cell sides (400 MB more) do not, and their allocation fails as a typed
    /// out-of-memory error naming them, not an abort.
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
                    .starts_with("the edges of the cell sides would need about 381.5 MiB"),
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

    /// The generators write the connectivity of well-shaped grids down (`grid_topology`) and
    /// skip the overlap sweep of the others (`Overlap::ByConstruction`): either way, the same
    /// cells pass the full validation with the same mesh, every array and h bit for bit.
    #[test]
    fn tensor_grids_pass_the_full_validation() {
        for (nx, ny, x, y, written) in [
            (1, 1, [0.0, 1.0], [0.0, 1.0], true),
            (1, 4, [0.0, 1.0], [0.0, 1.0], true),
            (5, 1, [-1.0, 3.0], [2.0, 2.5], true),
            (7, 3, [-2.0, 2.0], [0.1, 0.3], true),
            (30, 45, [0.0, 1.0], [0.0, 1.0], true),
            (64, 64, [-2.0, 2.0], [-2.0, 2.0], true),
            // steps 10⁻⁴ apart: through `from_flat_cells`
            (3, 2, [0.0, 1.0], [0.0, 1e-4], false),
            (2, 1000, [0.0, 1.0], [0.0, 0.1], false),
        ] {
            assert_eq!(
                well_shaped(&grid_vertices(nx, ny, x, y).unwrap(), nx, ny),
                written,
                "{nx} × {ny} on {x:?} × {y:?}"
            );
            for m in [
                cartesian_rect(nx, ny, x, y).unwrap(),
                cartesian_triangles(nx, ny, x, y).unwrap(),
            ] {
                let v: Vec<Point> = (0..m.n_vertices()).map(|i| m.vertex(i)).collect();
                let cells: Vec<Vec<usize>> = (0..m.n_cells())
                    .map(|k| m.cell_vertices(k).iter().map(|&i| i as usize).collect())
                    .collect();
                let full = PolyMesh::from_cells(v, cells).unwrap();
                let bits = |p: &[Point]| p.iter().map(|q| q.map(f64::to_bits)).collect::<Vec<_>>();
                assert_eq!(bits(&full.vertices), bits(&m.vertices));
                assert_eq!(full.cell_ptr, m.cell_ptr);
                assert_eq!(full.cell_verts, m.cell_verts);
                assert_eq!(full.cell_edges, m.cell_edges);
                assert_eq!(full.edges, m.edges);
                assert_eq!(full.edge_cells, m.edge_cells);
                assert_eq!(full.boundary_edges, m.boundary_edges);
                assert_eq!(full.boundary_tags, m.boundary_tags);
                assert_eq!(full.cell_tags, m.cell_tags);
                assert_eq!(full.reversed, m.reversed);
                assert_eq!(full.h.to_bits(), m.h.to_bits(), "{nx} × {ny}");
            }
        }
    }

    /// Grids with a step far below the others, or non-finite, are not written down directly.
    #[test]
    fn thin_or_non_finite_grids_are_not_well_shaped() {
        let ok = grid_vertices(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert!(well_shaped(&ok, 4, 4));
        // 999 × 1 and 1001 × 1 cells of a unit square: steps on either side of 10⁻³
        let edge = grid_vertices(999, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert!(well_shaped(&edge, 999, 1));
        let thin = grid_vertices(1001, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert!(!well_shaped(&thin, 1001, 1));
        let mut bad = ok.clone();
        bad[4][0] = f64::INFINITY;
        assert!(!well_shaped(&bad, 4, 4));
        bad[4][0] = f64::NAN;
        assert!(!well_shaped(&bad, 4, 4));
    }
}
