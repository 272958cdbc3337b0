//! Tetrahedra of a [`PolyMesh3`]: the vertices of a cell that is one, in a fixed order, for
//! the schemes defined on simplices (P1 and Crouzeix–Raviart). A [`PolyMesh3`] stores cells as
//! lists of faces; a cell is a tetrahedron when it has four faces, each a triangle (a valid
//! mesh has closed cells, so these four triangles share four vertices).

use super::PolyMesh3;

impl PolyMesh3 {
    /// The four vertices of cell `k` if it is a tetrahedron, `None` otherwise: the three
    /// vertices of its local face 0 in the order of that face's loop, then the vertex not on
    /// it. Local face i of the cell need not be opposite vertex i; a vertex v is opposite the
    /// face whose loop does not hold v.
    pub fn tetrahedron(&self, k: usize) -> Option<[u32; 4]> {
        let faces = self.cell_faces(k);
        if faces.len() != 4
            || faces
                .iter()
                .any(|&f| self.face_vertices(f as usize).len() != 3)
        {
            return None;
        }
        let first = self.face_vertices(faces[0] as usize);
        let apex = self
            .face_vertices(faces[1] as usize)
            .iter()
            .copied()
            .find(|v| !first.contains(v))?;
        Some([first[0], first[1], first[2], apex])
    }

    /// The first cell that is not a tetrahedron, with its numbers of faces and of distinct
    /// vertices; `None` if every cell is one.
    pub fn first_non_tetrahedron(&self) -> Option<(usize, usize, usize)> {
        let k = (0..self.n_cells()).find(|&k| self.tetrahedron(k).is_none())?;
        let mut ids: Vec<u32> = self
            .cell_faces(k)
            .iter()
            .flat_map(|&f| self.face_vertices(f as usize).iter().copied())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        Some((k, self.cell_faces(k).len(), ids.len()))
    }
}

#[cfg(test)]
mod tests {
    use crate::budget::MemoryBudget;
    use crate::mesh3d::{PolyMesh3, test_meshes};

    #[test]
    fn tetrahedra_are_recognised_with_their_four_vertices() {
        let m = PolyMesh3::from_polyhedra(test_meshes::tetrahedra(2, 1), MemoryBudget::DEFAULT)
            .unwrap();
        assert_eq!(m.first_non_tetrahedron(), None);
        for k in 0..m.n_cells() {
            let mut t = m.tetrahedron(k).unwrap().to_vec();
            for &f in m.cell_faces(k) {
                // each face holds three of the four vertices
                let on = t.iter().filter(|v| m.face_vertices(f as usize).contains(v));
                assert_eq!(on.count(), 3);
            }
            t.sort_unstable();
            t.dedup();
            assert_eq!(t.len(), 4);
        }
        let c = PolyMesh3::from_polyhedra(test_meshes::cubes(2, 1), MemoryBudget::DEFAULT).unwrap();
        assert_eq!(c.tetrahedron(0), None);
        assert_eq!(c.first_non_tetrahedron(), Some((0, 6, 8)));
    }
}
