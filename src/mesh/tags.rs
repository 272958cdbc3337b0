//! Tags on a [`PolyMesh`]: boundary tags of edges (gmsh physical lines, FVCA boundary
//! markers) and cell tags (gmsh physical surfaces).

use super::{Point, PolyMesh};
use crate::error::MeshError;

/// How [`PolyMesh::set_boundary_tags`] treats an entry that names no boundary edge of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NonBoundaryTag {
    /// Report it as [`MeshError::BadEdge`] (the contract of [`PolyMesh::from_cells_tagged`]).
    Reject,
    /// Skip it silently (gmsh line elements may be interior interfaces).
    Ignore,
}

impl PolyMesh {
    /// Tags boundary edges from `(vertex a, vertex b, tag)` entries (either vertex order), in
    /// order: a later entry for the same edge overrides an earlier one. An entry that names no
    /// boundary edge is an error ([`MeshError::BadEdge`]) or skipped, as `non_boundary` says.
    ///
    /// Each entry is found by binary search ([`PolyMesh::boundary_position`]).
    pub(crate) fn set_boundary_tags(
        &mut self,
        tagged_edges: &[(usize, usize, i32)],
        non_boundary: NonBoundaryTag,
    ) -> Result<(), MeshError> {
        for &(a, b, tag) in tagged_edges {
            match (self.boundary_position(a, b), non_boundary) {
                (Some(pos), _) => self.boundary_tags[pos] = tag,
                (None, NonBoundaryTag::Ignore) => {}
                (None, NonBoundaryTag::Reject) => {
                    return Err(MeshError::BadEdge {
                        a: a.min(b),
                        b: a.max(b),
                        msg: format!("tagged {tag} but it is not a boundary edge of the mesh"),
                    });
                }
            }
        }
        Ok(())
    }

    /// Returns the mesh with cell `k` tagged `tags[k]` (gmsh physical surfaces: heterogeneous
    /// media given as subdomains); an error if `tags` does not have one entry per cell.
    pub fn with_cell_tags(mut self, tags: Vec<i32>) -> Result<PolyMesh, MeshError> {
        if tags.len() != self.n_cells() {
            return Err(MeshError::NonConforming(format!(
                "{} cell tags for {} cells",
                tags.len(),
                self.n_cells()
            )));
        }
        // all zero: stored as no tags (see the field)
        self.cell_tags = if tags.iter().all(|&t| t == 0) {
            Vec::new()
        } else {
            tags
        };
        Ok(self)
    }

    /// The tag of cell `k` (its gmsh physical surface; 0 when untagged).
    pub fn cell_tag(&self, k: usize) -> i32 {
        if self.cell_tags.is_empty() {
            // bounds-checked as a stored tag would be
            assert!(k < self.n_cells(), "cell {k} of {}", self.n_cells());
            0
        } else {
            self.cell_tags[k]
        }
    }

    /// Returns a copy whose boundary edges are tagged by `tag(x_σ)` (interior edges keep tag 0).
    pub fn with_boundary_tags(&self, tag: impl Fn(Point) -> i32) -> PolyMesh {
        let mut m = self.clone();
        for (t, &e) in m.boundary_tags.iter_mut().zip(&self.boundary_edges) {
            *t = tag(self.edge_midpoint(e));
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_on_non_boundary_edges_are_rejected_or_ignored() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let cells = vec![vec![0, 1, 3], vec![0, 3, 2]];
        // (0, 3) is interior, (1, 2) no edge at all; (3, 1) is the boundary edge (1, 3)
        for bad in [(0, 3, 5), (1, 2, 5)] {
            let e = PolyMesh::from_cells_tagged(v.clone(), cells.clone(), &[(3, 1, 4), bad]);
            assert!(
                matches!(&e, Err(MeshError::BadEdge { msg, .. }) if msg.contains("tagged 5")),
                "{e:?}"
            );
        }
        let mut m = PolyMesh::from_cells(v, cells).unwrap();
        m.set_boundary_tags(
            &[(3, 1, 4), (0, 3, 5), (1, 2, 5), (1, 3, 6), (2, 0, 7)],
            NonBoundaryTag::Ignore,
        )
        .unwrap();
        let tags: Vec<(usize, usize, i32)> = (0..m.n_edges())
            .map(|e| (m.edge_vertices(e)[0], m.edge_vertices(e)[1], m.edge_tag(e)))
            .collect();
        // a later entry for the same edge wins; the interior edge keeps 0
        assert_eq!(
            tags,
            vec![(0, 1, 0), (0, 2, 7), (0, 3, 0), (1, 3, 6), (2, 3, 0)]
        );
    }
}
