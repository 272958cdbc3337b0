//! Tags on a [`PolyMesh3`]: boundary tags of faces (gmsh physical surfaces) and cell tags
//! (gmsh physical volumes), with the conventions of the 2D mesh: 0 for an interior or untagged
//! face and for an untagged cell.

use super::{Point3, PolyMesh3, Polyhedra};
use crate::error::MeshError;

impl PolyMesh3 {
    /// Tags the boundary faces listed in `p.tagged_*`, in order (a later entry for the same face
    /// overrides an earlier one). A tagged loop is found by its sorted vertex set among the
    /// boundary faces (sorted by the same key once, then binary search: O(n log n));
    /// [`MeshError::BadTaggedFace`] if it names no boundary face.
    pub(crate) fn set_face_tags(&mut self, p: &Polyhedra) -> Result<(), MeshError> {
        let n_tagged = p.tagged_tags.len();
        if n_tagged == 0 {
            return Ok(());
        }
        let mut keys: Vec<u32> = Vec::new();
        let mut key_ptr = vec![0usize];
        for &f in &self.boundary_faces {
            let start = keys.len();
            keys.extend_from_slice(self.face_vertices(f as usize));
            keys[start..].sort_unstable();
            key_ptr.push(keys.len());
        }
        let key = |b: usize| &keys[key_ptr[b]..key_ptr[b + 1]];
        let mut order: Vec<usize> = (0..self.boundary_faces.len()).collect();
        order.sort_unstable_by(|&a, &b| key(a).cmp(key(b)));
        let mut want = Vec::new();
        for t in 0..n_tagged {
            let l = &p.tagged_vertices[p.tagged_ptr[t] as usize..p.tagged_ptr[t + 1] as usize];
            want.clear();
            want.extend_from_slice(l);
            want.sort_unstable();
            match order.binary_search_by(|&b| key(b).cmp(&want)) {
                Ok(i) => self.boundary_tags[order[i]] = p.tagged_tags[t],
                Err(_) => {
                    return Err(MeshError::BadTaggedFace {
                        index: t,
                        vertices: l.iter().map(|&v| v as usize).collect(),
                        tag: p.tagged_tags[t],
                        msg: "is not a boundary face of the mesh".into(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Returns a copy whose boundary faces are tagged by `tag(x_σ)` (interior faces keep 0).
    pub fn with_boundary_tags(&self, tag: impl Fn(Point3) -> i32) -> PolyMesh3 {
        let mut m = self.clone();
        for (b, &f) in self.boundary_faces.iter().enumerate() {
            m.boundary_tags[b] = tag(self.face_centroid(f as usize));
        }
        m
    }

    /// Returns the mesh with cell `k` tagged `tags[k]`; [`MeshError::CellTagCount`] unless
    /// `tags` has one entry per cell.
    pub fn with_cell_tags(mut self, tags: Vec<i32>) -> Result<PolyMesh3, MeshError> {
        if tags.len() != self.n_cells() {
            return Err(MeshError::CellTagCount {
                tags: tags.len(),
                cells: self.n_cells(),
            });
        }
        self.cell_tags = tags;
        Ok(self)
    }
}
