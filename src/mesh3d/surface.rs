//! Check 11 of [`validate`](super::validate): the boundary surface (the boundary faces, with
//! their loops outward) is closed and manifold.
//!
//! * Edges: the directed edges of the boundary loops, sorted by their vertex pair, must come
//!   in pairs. Every cell being closed (check 6) and every interior face listed oppositely by
//!   its two cells (check 7), each edge runs as often one way as the other over the boundary
//!   loops, so a count other than 2 is 4 or more: cells meeting along an edge only, or the two
//!   sheets of a non-conforming interface meeting at a common edge.
//! * Vertices: pairing the edges gives, at each corner (face, vertex) of the surface, the next
//!   corner around the vertex (across the outgoing edge, then one step along the neighbour's
//!   loop), a permutation of the corners. The corners at a vertex must form one cycle (one fan
//!   of faces): two fans mean a pinched surface (cells touching at a vertex, or the two sheets
//!   of a non-conforming interface, whose rims meet at vertices).
//!
//! O(n log n) for n boundary loop entries.

use super::PolyMesh3;
use crate::error::MeshError;
use rayon::prelude::*;

impl PolyMesh3 {
    /// [`MeshError::NonConformingEdge`] or [`MeshError::NonConformingVertex`] unless the
    /// boundary surface is closed and manifold (see the module docs).
    pub(crate) fn check_boundary_surface(&self) -> Result<(), MeshError> {
        // the corners of the surface: vertex, and the corner after it in its loop
        let mut corner_vertex: Vec<u32> = Vec::new();
        let mut succ: Vec<u32> = Vec::new();
        for &f in &self.boundary_faces {
            let l = self.face_vertices(f as usize);
            let base = corner_vertex.len() as u32;
            corner_vertex.extend_from_slice(l);
            succ.extend((0..l.len() as u32).map(|i| base + (i + 1) % l.len() as u32));
        }
        // directed edges: (smaller vertex, larger vertex, corner at the start of the edge)
        let mut edges: Vec<(u32, u32, u32)> = (0..corner_vertex.len())
            .map(|c| {
                let (a, b) = (corner_vertex[c], corner_vertex[succ[c] as usize]);
                (a.min(b), a.max(b), c as u32)
            })
            .collect();
        edges.par_sort_unstable();
        let mut next = vec![u32::MAX; corner_vertex.len()];
        let mut i = 0;
        while i < edges.len() {
            let (a, b, c) = edges[i];
            let mut j = i + 1;
            while j < edges.len() && (edges[j].0, edges[j].1) == (a, b) {
                j += 1;
            }
            let bad = |msg: String| {
                Err(MeshError::NonConformingEdge {
                    a: a as usize,
                    b: b as usize,
                    msg,
                })
            };
            if j - i != 2 {
                return bad(format!("is used by {} boundary faces instead of 2", j - i));
            }
            // the two uses run opposite ways (see the module docs)
            let d = edges[i + 1].2;
            next[c as usize] = succ[d as usize];
            next[d as usize] = succ[c as usize];
            i = j;
        }
        drop(edges);
        self.check_fans(&corner_vertex, &next)
    }

    /// The corners at each vertex form one cycle of `next`.
    fn check_fans(&self, corner_vertex: &[u32], next: &[u32]) -> Result<(), MeshError> {
        let mut fans = vec![0u32; self.n_vertices()];
        let mut seen = vec![false; corner_vertex.len()];
        for c in 0..corner_vertex.len() {
            if seen[c] {
                continue;
            }
            fans[corner_vertex[c] as usize] += 1;
            let mut d = c;
            while !seen[d] {
                seen[d] = true;
                d = next[d] as usize;
            }
        }
        match fans.iter().position(|&n| n > 1) {
            Some(v) => Err(MeshError::NonConformingVertex {
                vertex: v,
                fans: fans[v] as usize,
            }),
            None => Ok(()),
        }
    }
}
