//! What the assembly and the solver read from a mesh beyond its cell–face complex
//! ([`CellComplex`]): the tags that select data (A and f by cell tag, the boundary partition by
//! face tag), the boundary faces where boundary conditions are imposed, and the size of the
//! domain (the maximum-principle scale of the certificate).
//!
//! | quantity | maths | method |
//! |---|---|---|
//! | boundary faces | ℱ_ext, the faces of ∂Ω, ascending | [`SolveMesh::n_boundary_faces`], [`SolveMesh::boundary_face`] |
//! | cell tag | the subdomain of K (gmsh physical surface in 2D, volume in 3D) | [`SolveMesh::cell_tag`] |
//! | face tag | the boundary part of σ (gmsh physical curve in 2D, surface in 3D) | [`SolveMesh::face_tag`] |
//! | domain diameter | the diagonal of the bounding box of Ω | [`SolveMesh::domain_diameter`] |
//!
//! Boundary data is evaluated at the face centre x_σ ([`CellComplex::face_centre`]: the edge
//! midpoint in 2D, the face centroid in 3D). [`PolyMesh`] (D = 2) implements it here; the 3D
//! mesh type in `crate::mesh3d`.

use super::PolyMesh;
use super::complex::CellComplex;

/// A mesh the assembly and the solver accept (see the module docs).
pub trait SolveMesh<const D: usize>: CellComplex<D> {
    /// Number of boundary faces.
    fn n_boundary_faces(&self) -> usize;
    /// The `i`-th boundary face (ascending in `i`).
    fn boundary_face(&self, i: usize) -> usize;
    /// The tag of cell `k` (0 when untagged).
    fn cell_tag(&self, k: usize) -> i32;
    /// The boundary tag of face `f` (0 when untagged).
    fn face_tag(&self, f: usize) -> i32;
    /// The diameter of the bounding box of Ω.
    fn domain_diameter(&self) -> f64;
    /// The boundary faces, ascending.
    fn boundary_faces_iter(&self) -> impl Iterator<Item = usize> + '_
    where
        Self: Sized,
    {
        (0..self.n_boundary_faces()).map(|i| self.boundary_face(i))
    }
}

impl SolveMesh<2> for PolyMesh {
    fn n_boundary_faces(&self) -> usize {
        self.boundary_edges().len()
    }
    fn boundary_face(&self, i: usize) -> usize {
        self.boundary_edges()[i]
    }
    fn cell_tag(&self, k: usize) -> i32 {
        PolyMesh::cell_tag(self, k)
    }
    fn face_tag(&self, f: usize) -> i32 {
        self.edge_tag(f)
    }
    fn domain_diameter(&self) -> f64 {
        let bb = self.bounding_box();
        (bb.width().powi(2) + bb.height().powi(2)).sqrt()
    }
}
