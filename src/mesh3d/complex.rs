//! [`PolyMesh3`] as the cell–face complex a scheme reads ([`CellComplex<3>`]), and its cell
//! values averaged at the vertices ([`VertexAverage`]).

use super::PolyMesh3;
use crate::mesh::complex::{CellComplex, FaceOfCell, Vector, VertexAverage};

impl CellComplex<3> for PolyMesh3 {
    fn n_cells(&self) -> usize {
        PolyMesh3::n_cells(self)
    }
    fn n_vertices(&self) -> usize {
        PolyMesh3::n_vertices(self)
    }
    fn n_faces(&self) -> usize {
        PolyMesh3::n_faces(self)
    }
    fn cell_faces(&self, k: usize) -> &[u32] {
        PolyMesh3::cell_faces(self, k)
    }
    fn face_cells(&self, f: usize) -> [usize; 2] {
        PolyMesh3::face_cells(self, f)
    }
    fn cell_measure(&self, k: usize) -> f64 {
        self.measure(k)
    }
    fn cell_centre(&self, k: usize) -> Vector<3> {
        self.centroid(k)
    }
    fn face_measure(&self, f: usize) -> f64 {
        PolyMesh3::face_measure(self, f)
    }
    fn face_centre(&self, f: usize) -> Vector<3> {
        self.face_centroid(f)
    }
    fn cell_face_normal_dist(&self, k: usize, i: usize) -> (Vector<3>, f64) {
        self.cell_normal_dist(k, i)
    }
    /// The face's fan geometry computed once (the default computes it three times), with the
    /// same values as the three accessors (x_K is stored: `xk` is not needed).
    fn cell_face_geometry(&self, k: usize, i: usize, _xk: Vector<3>) -> FaceOfCell<3> {
        self.face_of_cell(k, i)
    }
}

impl VertexAverage for PolyMesh3 {
    /// At each vertex, the average of `cv` over the cells having it, weighted by their
    /// volumes (each cell counted once per vertex, whatever the number of its faces there).
    fn cell_average_at_vertices(&self, cv: &[f64]) -> Vec<f64> {
        let mut sum = vec![(0.0, 0.0); self.n_vertices()];
        let mut ids = Vec::new();
        for (k, &value) in cv.iter().enumerate().take(self.n_cells()) {
            ids.clear();
            for &f in self.cell_faces(k) {
                ids.extend_from_slice(self.face_vertices(f as usize));
            }
            ids.sort_unstable();
            ids.dedup();
            let vol = self.measure(k);
            for &v in &ids {
                let s = &mut sum[v as usize];
                *s = (s.0 + vol * value, s.1 + vol);
            }
        }
        sum.iter().map(|(s, w)| s / w).collect()
    }
}
