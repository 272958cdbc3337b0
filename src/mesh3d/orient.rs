//! Orienting the faces of each polyhedron outward.
//!
//! The loops of a cell's faces come in either orientation. A closed polyhedron uses each edge
//! of its faces exactly twice, and once its faces are oriented consistently, in opposite
//! directions. So every edge shared by faces i and j says whether i and j must be turned the
//! same way (the edge runs in opposite directions in their loops) or opposite ways (the same
//! direction): a union–find with parity over the faces of the cell collects these relations,
//! and fails on a contradiction (a non-orientable surface). All faces must end up in one
//! component (a cell is one closed surface). The orientation found is outward if the signed
//! volume it gives is positive, else every face is turned. O(E log E) per cell of E edge uses.

use super::Polyhedra;
use super::geometry::{cell_volume_centroid, vertex_average};
use crate::error::MeshError;
use rayon::prelude::*;

/// Reused buffers of [`orient_cell`].
#[derive(Default)]
pub(crate) struct OrientScratch {
    /// (smaller vertex, larger vertex, local face, runs from smaller to larger).
    edges: Vec<(u32, u32, u32, bool)>,
    /// Union–find parent and parity with respect to the parent.
    parent: Vec<(u32, bool)>,
}

/// The root of local face `i` and the parity of `i` relative to it, compressing the path
/// (recursion depth at most the number of faces of a cell, [`MAX_CELL_FACES`](super::MAX_CELL_FACES)).
fn find(parent: &mut [(u32, bool)], i: u32) -> (u32, bool) {
    let (p, par) = parent[i as usize];
    if p == i {
        return (i, false);
    }
    let (root, rpar) = find(parent, p);
    parent[i as usize] = (root, par ^ rpar);
    (root, par ^ rpar)
}

/// Sets `inward[j]` for the local faces j of cell `k`: whether the loop of its side j must be
/// reversed to run counter-clockwise seen from outside the cell.
pub(crate) fn orient_cell(
    p: &Polyhedra,
    k: usize,
    scratch: &mut OrientScratch,
    inward: &mut [bool],
) -> Result<(), MeshError> {
    let sides = p.cell_sides(k);
    let first = sides.start;
    scratch.edges.clear();
    for (j, s) in sides.clone().enumerate() {
        let l = p.side_vertices(s);
        for i in 0..l.len() {
            let (a, b) = (l[i], l[(i + 1) % l.len()]);
            scratch.edges.push((a.min(b), a.max(b), j as u32, a < b));
        }
    }
    scratch.edges.sort_unstable();
    let n_faces = sides.len() as u32;
    scratch.parent.clear();
    scratch.parent.extend((0..n_faces).map(|i| (i, false)));
    let edges = &scratch.edges;
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        let (a, b) = (edges[i].0 as usize, edges[i].1 as usize);
        let open = |msg: String| MeshError::OpenCell { cell: k, a, b, msg };
        if j - i != 2 {
            return Err(open(format!(
                "is used by {} of its faces instead of 2",
                j - i
            )));
        }
        // the two faces must be turned oppositely iff they run the edge the same way
        let (f, g, want) = (edges[i].2, edges[i + 1].2, edges[i].3 == edges[i + 1].3);
        let (rf, pf) = find(&mut scratch.parent, f);
        let (rg, pg) = find(&mut scratch.parent, g);
        if rf == rg {
            if pf ^ pg != want {
                return Err(open(
                    "runs the same way in two faces however they are turned (the surface is not orientable)"
                        .into(),
                ));
            }
        } else {
            scratch.parent[rf as usize] = (rg, pf ^ pg ^ want);
        }
        i = j;
    }
    for j in 0..n_faces {
        let (root, parity) = find(&mut scratch.parent, j);
        if root != find(&mut scratch.parent, 0).0 {
            return Err(MeshError::BadCell {
                cell: k,
                msg: "its faces form more than one closed surface".into(),
            });
        }
        inward[j as usize] = parity;
    }
    let apex = vertex_average(&p.vertices, p.side_vertices(first));
    let loops = sides
        .clone()
        .map(|s| (p.side_vertices(s), inward[s - first]));
    let (vol, _) = cell_volume_centroid(&p.vertices, apex, loops);
    if !(vol.abs() > 0.0) {
        return Err(MeshError::DegenerateVolume {
            cell: k,
            volume: vol,
        });
    }
    if vol < 0.0 {
        inward.iter_mut().for_each(|b| *b = !*b);
    }
    Ok(())
}

/// Cells per parallel task of [`orient_cells`].
const BLOCK: usize = 4096;

/// Per side of `p`, whether its loop must be reversed to be outward ([`orient_cell`] on every
/// cell, in parallel by blocks of [`BLOCK`] consecutive cells, whose sides are consecutive;
/// the error reported is that of the first bad cell).
pub(crate) fn orient_cells(p: &Polyhedra) -> Result<Vec<bool>, MeshError> {
    let mut inward = vec![false; p.face_ptr.len() - 1];
    let n = p.n_cells();
    let mut blocks = Vec::with_capacity(n.div_ceil(BLOCK));
    let mut rest = &mut inward[..];
    for start in (0..n).step_by(BLOCK) {
        let end = (start + BLOCK).min(n);
        let sides = (p.cell_ptr[end] - p.cell_ptr[start]) as usize;
        let (block, tail) = rest.split_at_mut(sides);
        blocks.push((start..end, block));
        rest = tail;
    }
    let err = blocks
        .into_par_iter()
        .map_init(OrientScratch::default, |scratch, (cells, block)| {
            let first = p.cell_ptr[cells.start] as usize;
            cells.into_iter().find_map(|k| {
                let r = p.cell_sides(k);
                orient_cell(p, k, scratch, &mut block[r.start - first..r.end - first]).err()
            })
        })
        .find_map_first(|e| e);
    match err {
        Some(e) => Err(e),
        None => Ok(inward),
    }
}
