//! The cell–face complex of a mesh in any dimension D: what the schemes' local computations
//! read from a mesh, and nothing more.
//!
//! A polytopal mesh of a domain Ω ⊂ ℝᴰ is, for the gradient schemes, a set of cells K and
//! faces σ (edges when D = 2, polygons when D = 3) with
//!
//! | quantity | maths | method |
//! |---|---|---|
//! | cell measure | \|K\| (area, volume) | [`CellComplex::cell_measure`] |
//! | cell centre | x_K (the centroid, the authors' choice) | [`CellComplex::cell_centre`] |
//! | faces of K | σ ∈ ℱ_K, in a fixed local order | [`CellComplex::cell_faces`] |
//! | face measure | \|σ\| (length, area) | [`CellComplex::face_measure`] |
//! | face centre | x_σ (the centroid of σ) | [`CellComplex::face_centre`] |
//! | outward normal | n_{K,σ}, unit, on local face i of K | [`CellComplex::cell_face_normal_dist`] |
//! | orthogonal distance | d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 | [`CellComplex::cell_face_normal_dist`] |
//! | neighbours | the one or two cells of σ | [`CellComplex::face_cells`] |
//!
//! These are the only geometric quantities in the definition of HMM (consistent gradient,
//! stabilisation, fluxes: see [`crate::scheme::hmm`]) and in the identities that validate a
//! mesh (Σ_σ |σ| n_{K,σ} = 0 and Σ_σ |σ| d_{K,σ} = D |K|, the divergence theorem applied to
//! constants and to x − x_K). None of them depends on D, so a scheme written against this
//! trait is written once for 2-D and 3-D: [`crate::scheme::hmm::local_form`] is, and its
//! tests run it on a 3-D mesh of cubes.
//!
//! [`PolyMesh`] (D = 2, faces are edges) implements it; a 3-D mesh type implements it with
//! polygonal faces, and needs nothing else from this trait. What else is still 2-D in the
//! crate, and why, is listed in the module docs of [`crate::mesh`] ("Dimension").

use super::PolyMesh;

/// A point or vector of ℝᴰ.
pub type Vector<const D: usize> = [f64; D];

/// The cell–face complex of a mesh of dimension `D` (see the module docs).
pub trait CellComplex<const D: usize>: Sync {
    /// Number of cells.
    fn n_cells(&self) -> usize;
    /// Number of vertices.
    fn n_vertices(&self) -> usize;
    /// Number of faces (edges in 2-D).
    fn n_faces(&self) -> usize;
    /// The faces of cell `k`, in its local order (local face i is `cell_faces(k)[i]`), as 32-bit
    /// ids, the storage of [`PolyMesh`] (a mesh implementing this trait has fewer than
    /// `u32::MAX` faces); `f as usize` is the id the other methods take.
    fn cell_faces(&self, k: usize) -> &[u32];
    /// The cells on either side of face `f`; the second is [`super::NO_CELL`] on the boundary.
    fn face_cells(&self, f: usize) -> [usize; 2];
    /// |K|.
    fn cell_measure(&self, k: usize) -> f64;
    /// x_K, the centroid of cell `k`.
    fn cell_centre(&self, k: usize) -> Vector<D>;
    /// (|K|, x_K) together: the values of [`CellComplex::cell_measure`] and
    /// [`CellComplex::cell_centre`]. A mesh that computes both from the same sums (the planar
    /// mesh, on demand) overrides it to compute them once.
    fn cell_measure_centre(&self, k: usize) -> (f64, Vector<D>) {
        (self.cell_measure(k), self.cell_centre(k))
    }
    /// |σ|.
    fn face_measure(&self, f: usize) -> f64;
    /// x_σ, the centroid of face `f`.
    fn face_centre(&self, f: usize) -> Vector<D>;
    /// (n_{K,σ}, d_{K,σ}) on local face `i` of cell `k`: the outward unit normal and
    /// d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 (together: a mesh that computes them on demand
    /// computes both at once).
    fn cell_face_normal_dist(&self, k: usize, i: usize) -> (Vector<D>, f64);
    /// n_{K,σ}, the outward unit normal of cell `k` on its local face `i`.
    fn cell_face_normal(&self, k: usize, i: usize) -> Vector<D> {
        self.cell_face_normal_dist(k, i).0
    }
    /// d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 on local face `i` of cell `k`.
    fn cell_face_dist(&self, k: usize, i: usize) -> f64 {
        self.cell_face_normal_dist(k, i).1
    }
    /// Everything a local matrix needs of local face `i` of cell `k`: |σ|, x_σ and
    /// (n_{K,σ}, d_{K,σ}), the values of [`CellComplex::face_measure`],
    /// [`CellComplex::face_centre`] and [`CellComplex::cell_face_normal_dist`]; `xk` is x_K,
    /// the value of [`CellComplex::cell_centre`], which the caller has already. A mesh that
    /// computes its geometry on demand overrides it to compute each value once (the planar
    /// mesh computes x_K on demand, so it takes it from `xk` rather than once per face).
    fn cell_face_geometry(&self, k: usize, i: usize, xk: Vector<D>) -> FaceOfCell<D> {
        let _ = xk;
        let f = self.cell_faces(k)[i] as usize;
        let (normal, dist) = self.cell_face_normal_dist(k, i);
        FaceOfCell {
            measure: self.face_measure(f),
            centre: self.face_centre(f),
            normal,
            dist,
        }
    }
}

/// Local face σ of a cell K, as [`CellComplex::cell_face_geometry`] gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceOfCell<const D: usize> {
    /// |σ|.
    pub measure: f64,
    /// x_σ.
    pub centre: Vector<D>,
    /// n_{K,σ}, the outward unit normal.
    pub normal: Vector<D>,
    /// d_{K,σ} = (x_σ − x_K)·n_{K,σ}.
    pub dist: f64,
}

/// A mesh with vertices, for output: cell values averaged at the vertices (the vertex values
/// of a scheme whose unknowns live on cells and faces, for plots and VTU files).
pub trait VertexAverage {
    /// At each vertex, the average of the cell values `cv` of the cells around it, weighted by
    /// their measures.
    fn cell_average_at_vertices(&self, cv: &[f64]) -> Vec<f64>;
}

impl VertexAverage for PolyMesh {
    fn cell_average_at_vertices(&self, cv: &[f64]) -> Vec<f64> {
        let (ptr, ids) = self.vertex_cells();
        (0..self.n_vertices())
            .map(|v| {
                let cells = &ids[ptr[v]..ptr[v + 1]];
                let w: f64 = cells.iter().map(|&k| self.measure(k)).sum();
                cells.iter().map(|&k| self.measure(k) * cv[k]).sum::<f64>() / w
            })
            .collect()
    }
}

impl CellComplex<2> for PolyMesh {
    fn n_cells(&self) -> usize {
        PolyMesh::n_cells(self)
    }
    fn n_vertices(&self) -> usize {
        PolyMesh::n_vertices(self)
    }
    fn n_faces(&self) -> usize {
        self.n_edges()
    }
    fn cell_faces(&self, k: usize) -> &[u32] {
        self.cell_edges(k)
    }
    fn face_cells(&self, f: usize) -> [usize; 2] {
        self.edge_cells(f)
    }
    fn cell_measure(&self, k: usize) -> f64 {
        self.measure(k)
    }
    fn cell_centre(&self, k: usize) -> Vector<2> {
        self.centroid(k)
    }
    fn cell_measure_centre(&self, k: usize) -> (f64, Vector<2>) {
        self.area_centroid(k)
    }
    fn face_measure(&self, f: usize) -> f64 {
        self.edge_measure(f)
    }
    fn face_centre(&self, f: usize) -> Vector<2> {
        self.edge_midpoint(f)
    }
    fn cell_face_normal_dist(&self, k: usize, i: usize) -> (Vector<2>, f64) {
        self.cell_normal_dist(k, i)
    }
    /// The values of the accessors, x_K taken from `xk` (computed on demand otherwise).
    fn cell_face_geometry(&self, k: usize, i: usize, xk: Vector<2>) -> FaceOfCell<2> {
        let f = self.cell_edges(k)[i] as usize;
        let (normal, dist) = self.cell_normal_dist_from(k, i, xk);
        FaceOfCell {
            measure: self.edge_measure(f),
            centre: self.edge_midpoint(f),
            normal,
            dist,
        }
    }
}
