//! Building a [`PolyMesh`]: from cell vertex lists (nested or flat), through the checks of
//! [`validate`](super::validate), the edge numbering ([`edges`](super::edges)) and the overlap
//! sweep, to the compact 32-bit arrays the mesh keeps.

use super::edges::{Edges, build_edges};
use super::tags::NonBoundaryTag;
use super::{NO_CELL, Point, PolyMesh, sweep, validate};
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::error::MeshError;

/// Whether [`PolyMesh::from_flat_cells`] sweeps for crossing edges and overlapping cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Overlap {
    /// Sweep (any input).
    Sweep,
    /// Not: the cells of a tensor-product grid with strictly increasing coordinates.
    ByConstruction,
}

/// [`MeshError::TooManyEntities`] unless the mesh's ids fit in its 32-bit arrays: vertex and cell
/// ids in the edge arrays (`u32::MAX` marking "no cell"), offsets into the cell arrays (up to the
/// number of cell sides) and edge ids in `cell_edges` (there are no more edges than cell sides).
pub(super) fn check_counts(vertices: usize, cells: usize, sides: usize) -> Result<(), MeshError> {
    for (what, count) in [
        ("vertices", vertices),
        ("cells", cells),
        ("cell sides", sides),
    ] {
        if count >= u32::MAX as usize {
            return Err(MeshError::TooManyEntities { what, count });
        }
    }
    Ok(())
}

/// `v` as 32-bit values (all below `u32::MAX`, which the caller has checked), in a new array of
/// exactly that length named `what`; `v` is freed.
fn to_u32(v: Vec<usize>, what: &str) -> Result<Vec<u32>, AllocFailure> {
    debug_assert!(v.iter().all(|&x| x < u32::MAX as usize));
    let mut out = try_vec(v.len(), what)?;
    out.extend(v.iter().map(|&x| x as u32));
    Ok(out)
}

impl PolyMesh {
    /// Builds and validates a mesh from vertex coordinates and cell vertex lists (0-based ids,
    /// either orientation: clockwise cells are reversed). No boundary tags.
    pub fn from_cells(vertices: Vec<Point>, cells: Vec<Vec<usize>>) -> Result<Self, MeshError> {
        Self::from_cells_tagged(vertices, cells, &[])
    }

    /// As [`PolyMesh::from_cells`], with boundary tags given as `(vertex a, vertex b, tag)` for
    /// boundary edges (either vertex order). Entries naming an edge that is not a boundary edge of
    /// the mesh are an error.
    pub fn from_cells_tagged(
        vertices: Vec<Point>,
        cells: Vec<Vec<usize>>,
        tagged_edges: &[(usize, usize, i32)],
    ) -> Result<Self, MeshError> {
        let mut cell_ptr = try_vec(cells.len() + 1, "the offsets of the cells")?;
        cell_ptr.push(0);
        let sides = cells.iter().map(Vec::len).sum();
        let mut cell_verts = try_vec(sides, "the vertices of the cells")?;
        for c in &cells {
            cell_verts.extend_from_slice(c);
            cell_ptr.push(cell_verts.len());
        }
        drop(cells);
        let mut mesh = Self::from_flat_cells(vertices, cell_ptr, cell_verts, Overlap::Sweep)?;
        mesh.set_boundary_tags(tagged_edges, NonBoundaryTag::Reject)?;
        Ok(mesh)
    }

    /// As [`PolyMesh::from_cells`] (no tags), with the cells stored flat: cell `k` lists the
    /// vertices `cell_verts[cell_ptr[k]..cell_ptr[k + 1]]`. `cell_ptr` must start at 0, be
    /// non-decreasing and end at `cell_verts.len()` (the caller builds it; the cell contents are
    /// validated exactly as by [`PolyMesh::from_cells`], in the same order, with the same errors;
    /// [`MeshError::TooManyEntities`] if there are `u32::MAX` vertices, cells or cell sides or
    /// more). Clockwise cells are reversed in place in `cell_verts`, which the checks and the
    /// edge numbering read as `usize`; the mesh then keeps 32-bit copies of `cell_ptr` and
    /// `cell_verts`, made (and the `usize` arrays freed) before the overlap check, the peak of
    /// the construction. Readers pass flat cells to avoid one small allocation per cell.
    ///
    /// `overlap` says whether the sweep for crossing edges and overlapping cells (checks 11
    /// and 12, O(N log N) and sequential) runs: [`Overlap::ByConstruction`] only for the cells
    /// of a tensor-product grid whose coordinates increase strictly along both directions (the
    /// Cartesian generators check them), which tile their rectangle by construction (the time
    /// this saves is recorded in `replication/BENCHMARKS.md`, "Measurements behind the
    /// defaults"); every other check runs.
    pub(crate) fn from_flat_cells(
        vertices: Vec<Point>,
        cell_ptr: Vec<usize>,
        mut cell_verts: Vec<usize>,
        overlap: Overlap,
    ) -> Result<Self, MeshError> {
        debug_assert!(
            cell_ptr.first() == Some(&0)
                && cell_ptr.last() == Some(&cell_verts.len())
                && cell_ptr.windows(2).all(|w| w[0] <= w[1]),
            "malformed cell_ptr"
        );
        let nv = vertices.len();
        if cell_ptr.len() < 2 {
            return Err(MeshError::Empty);
        }
        check_counts(nv, cell_ptr.len() - 1, cell_verts.len())?;
        // checks 1–5 of `validate` and the cell geometry, while the vertices are sorted for
        // checks 6 and 11 (the errors are reported in the order of the checks)
        let (cells, (duplicates, order)) = rayon::join(
            || validate::cell_geometry(&vertices, &cell_ptr, &mut cell_verts),
            || {
                rayon::join(
                    || validate::check_duplicate_vertices(&vertices),
                    || (overlap == Overlap::Sweep).then(|| sweep::SweepOrder::new(&vertices)),
                )
            },
        );
        let cells = cells?;
        duplicates?;
        let order = order.transpose()?;

        // --- edges, numbered in (min, max) vertex order (check 7), and check 8 meanwhile
        let (built, simple) = rayon::join(
            || build_edges(nv, &cell_ptr, &cell_verts),
            || validate::check_simple_cells(&vertices, &cell_ptr, &cell_verts),
        );
        let built = built?;
        simple?;
        let ne = built.edges.len();
        // not reached (every edge is a side of some cell), but the ids must fit in `cell_edges`
        if ne >= u32::MAX as usize {
            return Err(MeshError::TooManyEntities {
                what: "edges",
                count: ne,
            });
        }
        // star-shapedness with respect to the centroid (d_{K,σ} > 0, computed above)
        if let Some(err) = cells.not_star_shaped {
            return Err(err);
        }
        // compact storage of the cells (ids and offsets below u32::MAX, checked above), before
        // the overlap check, the peak of the construction; the usize arrays are freed
        let cell_ptr = to_u32(cell_ptr, "the 32-bit offsets of the cells")?;
        let cell_verts = to_u32(cell_verts, "the 32-bit vertices of the cells")?;

        let on_boundary = |e: &usize| built.edge_cells[*e][1] == NO_CELL;
        let n_boundary = (0..ne).filter(on_boundary).count();
        let mut boundary_edges = try_vec(n_boundary, "the boundary edges")?;
        boundary_edges.extend((0..ne).filter(on_boundary));
        check_boundary_and_overlap(
            &vertices,
            &cell_ptr,
            &cell_verts,
            &built,
            &boundary_edges,
            cells.total_area,
            order,
        )?;
        Ok(compact(
            vertices,
            cell_ptr,
            cell_verts,
            built,
            cells,
            boundary_edges,
        )?)
    }
}

/// Checks 10–12 of [`validate`] on cells stored in their final 32-bit arrays: the boundary is
/// a union of simple closed loops and, if `order` is given (the sweep runs), no two edges cross
/// and the cells do not overlap.
fn check_boundary_and_overlap(
    vertices: &[Point],
    cell_ptr: &[u32],
    cell_verts: &[u32],
    built: &Edges,
    boundary_edges: &[usize],
    cells_area: f64,
    order: Option<sweep::SweepOrder>,
) -> Result<(), MeshError> {
    let boundary = validate::boundary_loops(
        vertices,
        &built.edges,
        cell_verts,
        cell_ptr,
        &built.cell_edges,
        boundary_edges,
    )?;
    if let Some(order) = order {
        validate::check_no_overlap(
            &validate::Topology {
                vertices,
                cell_ptr,
                cell_verts,
                edges: &built.edges,
                edge_cells: &built.edge_cells,
                cells_area,
            },
            &boundary,
            order,
        )?;
    }
    Ok(())
}

/// The validated mesh, its edge arrays made 32-bit (ids below `u32::MAX`, checked before), no
/// tags, h = max_K h_K; or [`AllocFailure`] if those arrays cannot be allocated.
fn compact(
    vertices: Vec<Point>,
    cell_ptr: Vec<u32>,
    cell_verts: Vec<u32>,
    built: Edges,
    cells: validate::CellGeometry,
    boundary_edges: Vec<usize>,
) -> Result<PolyMesh, AllocFailure> {
    let Edges {
        edges,
        edge_cells,
        cell_edges,
    } = built;
    let ne = edges.len();
    let mut edges32: Vec<[u32; 2]> = try_vec(ne, "the end points of the edges")?;
    edges32.extend(edges.iter().map(|e| e.map(|v| v as u32)));
    drop(edges);
    let mut cells32: Vec<[u32; 2]> = try_vec(ne, "the cells of the edges")?;
    cells32.extend(
        edge_cells
            .iter()
            .map(|c| c.map(|k| if k == NO_CELL { u32::MAX } else { k as u32 })),
    );
    drop(edge_cells);
    let boundary_tags = try_filled(boundary_edges.len(), 0i32, "the boundary tags")?;
    let h = cells.h;
    Ok(PolyMesh {
        vertices,
        cell_ptr,
        cell_verts,
        cell_edges,
        edges: edges32,
        edge_cells: cells32,
        boundary_tags,
        cell_tags: Vec::new(),
        reversed: cells.reversed,
        boundary_edges,
        h,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_invalid_meshes() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 7]]),
            Err(MeshError::VertexOutOfRange { .. })
        ));
        assert!(PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 3, 2]]).is_ok());
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 2]]),
            Err(MeshError::UnusedVertex { vertex: 3 })
        ));
        // bow-tie: zero signed area
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 2, 3]]),
            Err(MeshError::DegenerateCell { .. })
        ));
        // overlapping: same triangle twice
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 3], vec![0, 1, 3], vec![0, 3, 2]]),
            Err(MeshError::BadEdge { .. })
        ));
        let d = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]];
        assert!(matches!(
            PolyMesh::from_cells(d, vec![vec![0, 1, 2], vec![3, 2, 1]]),
            Err(MeshError::DuplicateVertex { .. }) | Err(MeshError::BadEdge { .. })
        ));
    }

    #[test]
    fn counts_beyond_the_32_bit_arrays_are_rejected() {
        let max = u32::MAX as usize;
        assert_eq!(check_counts(max - 1, max - 1, max - 1), Ok(()));
        for (counts, what) in [
            ([max, 1, 3], "vertices"),
            ([3, max, 3], "cells"),
            ([3, 1, max], "cell sides"),
        ] {
            assert_eq!(
                check_counts(counts[0], counts[1], counts[2]),
                Err(MeshError::TooManyEntities { what, count: max })
            );
        }
        // the first in that order is reported
        let e = check_counts(max, max, max).unwrap_err();
        assert_eq!(
            e,
            MeshError::TooManyEntities {
                what: "vertices",
                count: max
            }
        );
        assert_eq!(
            MeshError::TooManyEntities {
                what: "cell sides",
                count: max
            }
            .to_string(),
            format!("the mesh has {max} cell sides: at most 2^32 - 2 are supported")
        );
    }

    /// Builds a 400 × 400 grid again and again in a child process whose data is limited to
    /// what it has plus 0, 1, 2, 4, … MiB: every build ends with the mesh or
    /// with a typed out-of-memory error (whichever of its arrays failed), never an abort; the
    /// smaller limits fail, the largest succeeds.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_build_the_data_limit_refuses_is_a_typed_error() {
        use crate::budget::child;
        const NAME: &str = "mesh::build::tests::a_build_the_data_limit_refuses_is_a_typed_error";
        if !child::is_child(NAME) {
            return child::run(NAME);
        }
        let n = 400;
        let grid = || {
            let vertices: Vec<Point> = (0..(n + 1) * (n + 1))
                .map(|v| [(v % (n + 1)) as f64, (v / (n + 1)) as f64])
                .collect();
            let cell_ptr: Vec<usize> = (0..=n * n).map(|k| 4 * k).collect();
            let cell_verts: Vec<usize> = (0..n * n)
                .flat_map(|k| {
                    let v = k / n * (n + 1) + k % n;
                    [v, v + 1, v + n + 2, v + n + 1]
                })
                .collect();
            (vertices, cell_ptr, cell_verts)
        };
        let mut refused = 0;
        for extra_mib in [0, 1, 2, 4, 8, 16, 32, 64, 1024] {
            let (vertices, cell_ptr, cell_verts) = grid();
            child::limit_data(extra_mib << 20);
            match PolyMesh::from_flat_cells(vertices, cell_ptr, cell_verts, Overlap::Sweep) {
                Ok(m) => assert_eq!(m.n_edges(), 2 * n * (n + 1)),
                Err(MeshError::TooLarge { what, bytes, .. }) => {
                    assert!(bytes > 0, "{what}");
                    refused += 1;
                }
                Err(e) => panic!("{extra_mib} MiB: {e}"),
            }
            child::limit_data(4 << 30);
        }
        assert!((1..9).contains(&refused), "{refused} builds refused");
    }

    #[test]
    fn rejects_non_star_shaped_cell() {
        // an arrow-shaped (non-convex) hexagon whose centroid sees one edge from behind
        let v = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.9, 0.1],
            [0.5, 0.05],
            [0.0, 1.0],
        ];
        let r = PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3, 4, 5]]);
        assert!(matches!(r, Err(MeshError::NotStarShaped { .. })), "{r:?}");
    }

    #[test]
    fn rejects_hanging_node() {
        // left cell is one square with 4 corners; the right side is split into two cells
        let v = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 2.0],
            [1.0, 2.0],
            [2.0, 2.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ];
        let cells = vec![vec![0, 1, 4, 3], vec![1, 2, 7, 6], vec![6, 7, 5, 4]];
        let r = PolyMesh::from_cells(v, cells);
        assert!(matches!(r, Err(MeshError::NonConforming(_))), "{r:?}");
    }
}
