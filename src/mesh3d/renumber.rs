//! Dropping the vertices no face uses (gmsh files may carry geometry points, which
//! [`PolyMesh3::from_polyhedra`](super::PolyMesh3::from_polyhedra) refuses as
//! [`MeshError::UnusedVertex`](crate::MeshError::UnusedVertex)).

use super::Polyhedra;

impl Polyhedra {
    /// Removes the vertices that no face loop uses, keeping the others in order and renumbering
    /// the face loops and the tagged loops. Returns, for every old vertex, its new id
    /// (`u32::MAX` if dropped). A tagged loop through a dropped vertex keeps `u32::MAX` there,
    /// so that building the mesh reports it. Ids out of range are left for the build to report.
    pub fn drop_unused_vertices(&mut self) -> Vec<u32> {
        let n = self.vertices.len();
        let mut new_id = vec![u32::MAX; n];
        for &v in &self.face_vertices {
            if let Some(slot) = new_id.get_mut(v as usize) {
                *slot = 0;
            }
        }
        for (next, id) in new_id.iter_mut().filter(|id| **id == 0).enumerate() {
            *id = next as u32;
        }
        let mut i = 0;
        self.vertices.retain(|_| {
            i += 1;
            new_id[i - 1] != u32::MAX
        });
        let map = |v: &mut u32| {
            if let Some(&id) = new_id.get(*v as usize) {
                *v = id;
            }
        };
        self.face_vertices.iter_mut().for_each(map);
        self.tagged_vertices.iter_mut().for_each(map);
        new_id
    }
}

#[cfg(test)]
mod tests {
    use super::Polyhedra;

    #[test]
    fn unused_vertices_are_dropped_and_loops_renumbered() {
        let mut p = Polyhedra {
            vertices: (0..6).map(|i| [i as f64, 0.0, 0.0]).collect(),
            ..Polyhedra::default()
        };
        p.push_cell([&[1, 3, 4][..], &[1, 3, 5], &[1, 4, 5], &[3, 4, 5]])
            .unwrap();
        p.tagged_ptr = vec![0, 3];
        p.tagged_vertices = vec![5, 4, 3];
        p.tagged_tags = vec![2];
        let map = p.drop_unused_vertices();
        assert_eq!(map, vec![u32::MAX, 0, u32::MAX, 1, 2, 3]);
        assert_eq!(
            p.vertices,
            vec![
                [1.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [4.0, 0.0, 0.0],
                [5.0, 0.0, 0.0]
            ]
        );
        assert_eq!(p.side_vertices(1), &[0, 1, 3]);
        assert_eq!(p.tagged_vertices, vec![3, 2, 1]);
    }
}
