//! The edges (faces σ) of a mesh from its cells: numbering by vertex pair, the cells on either
//! side, the edge of every cell side, and the edge errors ([`MeshError::BadEdge`]).

use super::NO_CELL;
#[cfg(doc)]
use super::PolyMesh;
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::error::MeshError;

/// The edges of a mesh whose cells are stored flat (`cell_ptr`, `cell_verts`, as in
/// [`PolyMesh`] but `usize`; every cell has at least 3 vertices, all below `nv`, and there are
/// fewer than `u32::MAX` cell sides, so that the edge ids fit in the 32-bit `cell_edges`),
/// numbered in increasing order of their (smaller vertex, larger vertex) pair, or the first
/// [`MeshError::BadEdge`] in that order: an edge shared by more than two cells, or two cells
/// that traverse an edge in the same direction.
///
/// Algorithm, linear apart from sorting a handful of items per vertex:
/// 1. every cell side (half-edge, identified by its slot in `cell_verts`) is put into the bucket
///    of its smaller end point by a counting sort (CSR by smaller vertex); the sides are visited
///    in slot order, so every bucket lists its sides in (cell, local edge) order;
/// 2. each bucket is sorted by (larger vertex, slot): buckets are small (about six sides per
///    vertex on a triangle mesh), which `sort_unstable` handles by insertion sort;
/// 3. scanning the buckets in vertex order visits the sides sorted by their (smaller, larger)
///    vertex pair, ties in slot order; every run of equal pairs is one edge. The first side of a
///    run gives `edge_cells[e][0]`, so an interior edge lists its lower-numbered cell first, and
///    of three or more cells on one edge the two lowest-numbered ones are compared first (the
///    global sort of all sides this replaces left both to the tie order of `sort_unstable`).
///
/// The result is the same as sorting all sides by (smaller vertex, larger vertex, slot), without
/// the O(n log n) sort of scattered records. The scatter of step 1 is a random access per side,
/// so the bucket arrays use `u32` indices whenever the mesh allows it (fewer than 2³¹ cell
/// sides): half the memory traffic of `usize` records.
pub(super) fn build_edges(
    nv: usize,
    cell_ptr: &[usize],
    cell_verts: &[usize],
) -> Result<Edges, MeshError> {
    // the largest value stored is 2·slot + 1 < 2·cell_verts.len() (cells and vertices are fewer)
    let small = u32::try_from(cell_verts.len().saturating_mul(2))
        .ok()
        .zip(u32::try_from(nv).ok())
        .is_some();
    if small {
        build_edges_with::<u32>(nv, cell_ptr, cell_verts)
    } else {
        build_edges_with::<usize>(nv, cell_ptr, cell_verts)
    }
}

/// The edge arrays of a [`PolyMesh`], as [`build_edges`] makes them.
#[derive(Debug, PartialEq)]
pub(super) struct Edges {
    /// End points of each edge, smaller vertex first.
    pub(super) edges: Vec<[usize; 2]>,
    /// The cells on either side of each edge (`[K, NO_CELL]` on the boundary).
    pub(super) edge_cells: Vec<[usize; 2]>,
    /// The edge of each cell side (indexed like `cell_verts`), 32-bit as [`PolyMesh`] keeps it
    /// (there are no more edges than cell sides, fewer than `u32::MAX`).
    pub(super) cell_edges: Vec<u32>,
}

/// Unsigned index type of the scratch arrays of [`build_edges`] and of the sweep's events
/// (`u32` when the values fit: half the memory traffic and footprint of `usize`).
pub(crate) trait EdgeIndex: Copy + Ord + Default + 'static {
    /// `v` as `Self`; [`build_edges`] only calls it with values that fit.
    fn from_usize(v: usize) -> Self;
    fn to_usize(self) -> usize;
}

impl EdgeIndex for u32 {
    fn from_usize(v: usize) -> Self {
        debug_assert!(u32::try_from(v).is_ok());
        v as u32
    }
    fn to_usize(self) -> usize {
        self as usize
    }
}

impl EdgeIndex for usize {
    fn from_usize(v: usize) -> Self {
        v
    }
    fn to_usize(self) -> usize {
        self
    }
}

/// The buckets of [`bucket_sides`]: offsets by smaller vertex, the sides, the number of edges.
type Buckets<I> = (Vec<I>, Vec<HalfEdge<I>>, usize);

/// A cell side in the buckets of [`build_edges`]: (larger vertex, 2·slot + \[the side runs from
/// the larger to the smaller vertex\], cell). The direction rides along so that step 3 reads no
/// vertex ids; sorting by the second item sorts by slot.
type HalfEdge<I> = (I, I, I);

/// Steps 1 and 2 of [`build_edges`]: the cell sides in buckets by smaller vertex (bucket v is
/// `half[start[v]..start[v + 1]]`), each bucket sorted, and the number of edges; or
/// [`AllocFailure`] if the buckets cannot be allocated.
fn bucket_sides<I: EdgeIndex>(
    nv: usize,
    cell_ptr: &[usize],
    cell_verts: &[usize],
) -> Result<Buckets<I>, AllocFailure> {
    let n_half = cell_verts.len();
    let nc = cell_ptr.len().saturating_sub(1);
    // the side in `slot` of cell k (slots s..e) joins cell_verts[slot] to cell_verts[next(slot)]
    let next = |slot: usize, s: usize, e: usize| if slot + 1 < e { slot + 1 } else { s };

    // 1. counting sort by smaller vertex: bucket v is half[start[v]..start[v + 1]]
    let mut start = try_filled(nv + 1, I::default(), "the edge buckets of the vertices")?;
    for k in 0..nc {
        let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
        for slot in s..e {
            let (a, b) = (cell_verts[slot], cell_verts[next(slot, s, e)]);
            let c = &mut start[a.min(b) + 1];
            *c = I::from_usize(c.to_usize() + 1);
        }
    }
    for v in 0..nv {
        start[v + 1] = I::from_usize(start[v + 1].to_usize() + start[v].to_usize());
    }
    let mut cursor = try_vec(start.len(), "the edge bucket cursors")?;
    cursor.extend_from_slice(&start);
    let zero = (I::default(), I::default(), I::default());
    let mut half = try_filled(n_half, zero, "the cell sides sorted by vertex")?;
    for k in 0..nc {
        let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
        for slot in s..e {
            let (a, b) = (cell_verts[slot], cell_verts[next(slot, s, e)]);
            let c = &mut cursor[a.min(b)];
            half[c.to_usize()] = (
                I::from_usize(a.max(b)),
                I::from_usize(2 * slot + usize::from(a > b)),
                I::from_usize(k),
            );
            *c = I::from_usize(c.to_usize() + 1);
        }
    }
    drop(cursor);
    // 2. sort the buckets and count the edges, so that the edge arrays are allocated once
    let mut ne = 0;
    for v in 0..nv {
        let bucket = &mut half[start[v].to_usize()..start[v + 1].to_usize()];
        bucket.sort_unstable();
        ne += bucket
            .iter()
            .enumerate()
            .filter(|&(i, h)| i == 0 || bucket[i - 1].0 != h.0)
            .count();
    }
    Ok((start, half, ne))
}

/// [`build_edges`] with scratch indices of type `I`.
fn build_edges_with<I: EdgeIndex>(
    nv: usize,
    cell_ptr: &[usize],
    cell_verts: &[usize],
) -> Result<Edges, MeshError> {
    let n_half = cell_verts.len();
    debug_assert!(n_half < u32::MAX as usize, "checked by from_flat_cells");
    let (start, half, ne) = bucket_sides::<I>(nv, cell_ptr, cell_verts)?;
    // 3. runs of equal (smaller, larger) vertex pairs are the edges
    let mut edges = try_vec(ne, "the end points of the edges")?;
    let mut edge_cells = try_vec(ne, "the cells of the edges")?;
    // edge ids are below the number of sides (each edge has a side), so below u32::MAX
    let mut cell_edges = try_filled(n_half, 0u32, "the edges of the cell sides")?;
    for lo in 0..nv {
        let bucket = &half[start[lo].to_usize()..start[lo + 1].to_usize()];
        let mut i = 0;
        while i < bucket.len() {
            let (hi, code, k) = bucket[i];
            let (hi, code, k) = (hi.to_usize(), code.to_usize(), k.to_usize());
            let e = edges.len();
            edges.push([lo, hi]);
            cell_edges[code / 2] = e as u32;
            let mut cells_of_edge = [k, NO_CELL];
            let mut j = i + 1;
            while j < bucket.len() && bucket[j].0.to_usize() == hi {
                let (code2, k2) = (bucket[j].1.to_usize(), bucket[j].2.to_usize());
                if j > i + 1 {
                    return Err(MeshError::BadEdge {
                        a: lo,
                        b: hi,
                        msg: "shared by more than two cells".into(),
                    });
                }
                if code2 % 2 == code % 2 {
                    return Err(MeshError::BadEdge {
                        a: lo,
                        b: hi,
                        msg: format!(
                            "cells {k} and {k2} traverse it in the same direction (overlapping cells)"
                        ),
                    });
                }
                cells_of_edge[1] = k2;
                cell_edges[code2 / 2] = e as u32;
                j += 1;
            }
            edge_cells.push(cells_of_edge);
            i = j;
        }
    }
    Ok(Edges {
        edges,
        edge_cells,
        cell_edges,
    })
}

#[cfg(test)]
mod tests {
    use super::super::{NO_CELL, PolyMesh, test_meshes};
    use super::*;

    /// The edges as the original construction defined them: all cell sides sorted by
    /// (smaller vertex, larger vertex) with ties in slot order (a stable sort), runs of equal
    /// pairs being the edges. Returns `(edges, edge_cells, cell_edges)`; panics on invalid input.
    fn reference_edges(m: &PolyMesh) -> Edges {
        let mut sides = Vec::new();
        for k in 0..m.n_cells() {
            let c = m.cell_vertices(k);
            for i in 0..c.len() {
                let (a, b) = (c[i] as usize, c[(i + 1) % c.len()] as usize);
                sides.push(((a.min(b), a.max(b)), m.cell_range(k).start + i, k));
            }
        }
        sides.sort_by_key(|s| s.0);
        let (mut edges, mut edge_cells) = (Vec::<[usize; 2]>::new(), Vec::<[usize; 2]>::new());
        let mut cell_edges = vec![u32::MAX; sides.len()];
        for (key, slot, k) in sides {
            if edges.last() == Some(&[key.0, key.1]) {
                edge_cells.last_mut().unwrap()[1] = k;
            } else {
                edges.push([key.0, key.1]);
                edge_cells.push([k, NO_CELL]);
            }
            cell_edges[slot] = (edges.len() - 1) as u32;
        }
        Edges {
            edges,
            edge_cells,
            cell_edges,
        }
    }

    #[test]
    fn edges_are_numbered_by_vertex_pair_with_lower_cell_first() {
        let meshes = test_meshes();
        for m in &meshes {
            let reference = reference_edges(m);
            let edges: Vec<[usize; 2]> = (0..m.n_edges()).map(|e| m.edge_vertices(e)).collect();
            let edge_cells: Vec<[usize; 2]> = (0..m.n_edges()).map(|e| m.edge_cells(e)).collect();
            assert_eq!(edges, reference.edges);
            assert_eq!(edge_cells, reference.edge_cells);
            for (e, c) in edge_cells.iter().enumerate() {
                assert_eq!(m.is_boundary_edge(e), c[1] == NO_CELL);
            }
            assert_eq!(m.cell_edges, reference.cell_edges);
            assert!(m.edges.windows(2).all(|w| w[0] < w[1]) && m.edges.iter().all(|e| e[0] < e[1]));
            // both index widths of the bucket arrays give the same result, from the cells as
            // `from_flat_cells` receives them (usize)
            let widen = |v: &[u32]| v.iter().map(|&x| x as usize).collect::<Vec<usize>>();
            let (ptr, verts) = (widen(&m.cell_ptr), widen(&m.cell_verts));
            let wide = build_edges_with::<usize>(m.n_vertices(), &ptr, &verts);
            let narrow = build_edges_with::<u32>(m.n_vertices(), &ptr, &verts);
            assert_eq!(wide, narrow);
            assert_eq!(wide, Ok(reference));
            // the boundary edges are sorted by vertex pair, which set_boundary_tags relies on
            assert!(
                m.boundary_edges
                    .windows(2)
                    .all(|w| m.edges[w[0]] < m.edges[w[1]])
            );
        }
    }

    #[test]
    fn bad_edges_are_reported_in_vertex_pair_order() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, -1.0]];
        // edge (0, 1) is shared by three cells; the first two traverse it in opposite directions
        let cells = vec![vec![0, 1, 3], vec![1, 0, 4], vec![0, 1, 2], vec![2, 3, 1]];
        let e = PolyMesh::from_cells(v.clone(), cells).unwrap_err();
        assert_eq!(
            e,
            MeshError::BadEdge {
                a: 0,
                b: 1,
                msg: "shared by more than two cells".into()
            }
        );
        // the same triangle twice: the cells are named in increasing order
        let cells = vec![vec![2, 3, 1], vec![0, 1, 2], vec![0, 1, 2]];
        let e = PolyMesh::from_cells(v[..4].to_vec(), cells).unwrap_err();
        assert_eq!(
            e,
            MeshError::BadEdge {
                a: 0,
                b: 1,
                msg: "cells 1 and 2 traverse it in the same direction (overlapping cells)".into()
            }
        );
    }
}
