//! [`PolyMesh3`] as a mesh the assembly and the solver accept ([`SolveMesh<3>`]): boundary
//! faces, cell tags (gmsh physical volumes), face tags (gmsh physical surfaces) and the
//! diagonal of the bounding box.

use super::PolyMesh3;
use crate::mesh::solve_mesh::SolveMesh;

impl SolveMesh<3> for PolyMesh3 {
    fn n_boundary_faces(&self) -> usize {
        self.boundary_faces().len()
    }
    fn boundary_face(&self, i: usize) -> usize {
        self.boundary_faces()[i] as usize
    }
    fn cell_tag(&self, k: usize) -> i32 {
        PolyMesh3::cell_tag(self, k)
    }
    fn face_tag(&self, f: usize) -> i32 {
        PolyMesh3::face_tag(self, f)
    }
    fn domain_diameter(&self) -> f64 {
        let b = self.bounding_box();
        let (dx, dy, dz) = (b.x[1] - b.x[0], b.y[1] - b.y[0], b.z[1] - b.z[0]);
        (dx * dx + dy * dy + dz * dz).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unit_cube_has_its_boundary_and_diameter() {
        let p = crate::mesh3d::test_meshes::cubes(2, 1);
        let m = PolyMesh3::from_polyhedra(p, crate::budget::MemoryBudget::DEFAULT).unwrap();
        // 6 sides of 2×2 squares
        assert_eq!(m.n_boundary_faces(), 24);
        let area: f64 = m.boundary_faces_iter().map(|f| m.face_measure(f)).sum();
        assert!((area - 6.0).abs() < 1e-12, "{area}");
        assert!((m.domain_diameter() - 3f64.sqrt()).abs() < 1e-15);
        assert!(
            m.boundary_faces_iter()
                .all(|f| m.face_cells(f)[1] == crate::mesh::NO_CELL)
        );
    }
}
