//! What P1 and Crouzeix–Raviart share: both are schemes on simplices of dimension D
//! (triangles, D = 2; tetrahedra, D = 3) with D + 1 skeleton unknowns per simplex and a
//! gradient constant on each ([`SimplexScheme`]); each states what is its own, and its
//! [`GradientDiscretisation`] follows from it. The meshes of simplices are [`SimplexMesh`]es:
//! the triangle meshes of [`PolyMesh`] and the tetrahedral meshes of [`PolyMesh3`].
//!
//! Local arrays have room for the D + 1 ≤ 4 unknowns of a tetrahedron ([`Local`]); a triangle
//! uses the first three entries.

use super::{Entity, GradientDiscretisation, PointDof, Tensor};
use crate::mesh::PolyMesh;
use crate::mesh::complex::{CellComplex, Vector};
use crate::mesh3d::PolyMesh3;
use nalgebra::{DMatrix, DVector};

/// The D + 1 entries of a simplex (vertices, faces, basis gradients) in its local order; only
/// the first D + 1 are meaningful.
pub type Local<T> = [T; 4];

/// A mesh whose cells may all be simplices: the vertices of each, in a fixed local order.
/// Implemented by [`PolyMesh`] (triangles, D = 2) and [`PolyMesh3`] (tetrahedra, D = 3).
pub trait SimplexMesh<const D: usize>: CellComplex<D> {
    /// The coordinates of vertex `v`.
    fn vertex_point(&self, v: usize) -> Vector<D>;
    /// The D + 1 vertices of simplex `k` (first D + 1 entries; the rest are 0): a triangle's
    /// vertices counter-clockwise as [`PolyMesh::cell_vertices`] stores them, a
    /// tetrahedron's as [`PolyMesh3::tetrahedron`] gives them. Only called on a mesh that
    /// [`SimplexMesh::require_simplices`] accepted.
    fn simplex_vertices(&self, k: usize) -> Local<u32>;
    /// An error naming the first cell that is not a simplex (`scheme` names the scheme that
    /// needs simplices).
    fn require_simplices(&self, scheme: &str) -> crate::Result<()>;
}

impl SimplexMesh<2> for PolyMesh {
    fn vertex_point(&self, v: usize) -> Vector<2> {
        self.vertex(v)
    }
    fn simplex_vertices(&self, k: usize) -> Local<u32> {
        let v = self.cell_vertices(k);
        [v[0], v[1], v[2], 0]
    }
    fn require_simplices(&self, scheme: &str) -> crate::Result<()> {
        match (0..self.n_cells()).find(|&k| self.cell_vertices(k).len() != 3) {
            Some(k) => Err(crate::Error::InvalidData(format!(
                "{scheme} needs a triangle mesh, but cell {k} has {} vertices",
                self.cell_vertices(k).len()
            ))),
            None => Ok(()),
        }
    }
}

impl SimplexMesh<3> for PolyMesh3 {
    fn vertex_point(&self, v: usize) -> Vector<3> {
        self.vertices()[v]
    }
    fn simplex_vertices(&self, k: usize) -> Local<u32> {
        // require_simplices checked every cell
        self.tetrahedron(k)
            .expect("a cell of a mesh accepted as tetrahedral is a tetrahedron")
    }
    fn require_simplices(&self, scheme: &str) -> crate::Result<()> {
        match self.first_non_tetrahedron() {
            Some((k, faces, vertices)) => Err(crate::Error::InvalidData(format!(
                "{scheme} needs a tetrahedral mesh, but cell {k} is not a tetrahedron \
                 ({faces} faces, {vertices} vertices)"
            ))),
            None => Ok(()),
        }
    }
}

/// Where the unknowns of a [`SimplexScheme`] live: one on every vertex or on every face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SimplexUnknowns {
    /// One unknown per mesh vertex, the value there (P1).
    Vertices,
    /// One unknown per mesh face (an edge in 2-D), the value at its centroid x_σ
    /// (Crouzeix–Raviart).
    Faces,
}

impl SimplexUnknowns {
    /// Number of unknowns on `mesh`.
    fn count<const D: usize>(self, mesh: &impl SimplexMesh<D>) -> usize {
        match self {
            SimplexUnknowns::Vertices => mesh.n_vertices(),
            SimplexUnknowns::Faces => mesh.n_faces(),
        }
    }
    /// The D + 1 unknowns of simplex `k`, in local order (32-bit, as the meshes store them).
    fn of_cell<const D: usize>(self, mesh: &impl SimplexMesh<D>, k: usize) -> Local<u32> {
        match self {
            SimplexUnknowns::Vertices => mesh.simplex_vertices(k),
            SimplexUnknowns::Faces => {
                let f = mesh.cell_faces(k);
                std::array::from_fn(|i| if i <= D { f[i] } else { 0 })
            }
        }
    }
    /// The mesh entity of unknown `i`.
    fn entity(self, i: usize) -> Entity {
        match self {
            SimplexUnknowns::Vertices => Entity::Vertex(i),
            SimplexUnknowns::Faces => Entity::Edge(i),
        }
    }
    /// Where unknown `i` is a value: the vertex, or the face centroid x_σ.
    fn point<const D: usize>(self, mesh: &impl SimplexMesh<D>, i: usize) -> Vector<D> {
        match self {
            SimplexUnknowns::Vertices => mesh.vertex_point(i),
            SimplexUnknowns::Faces => mesh.face_centre(i),
        }
    }
}

/// a·b summed from the first term on (a[0]b[0] + a[1]b[1] + …).
fn dot<const D: usize>(a: &Vector<D>, b: &Vector<D>) -> f64 {
    let mut s = a[0] * b[0];
    for c in 1..D {
        s += a[c] * b[c];
    }
    s
}

/// A scheme on simplices of dimension D with D + 1 unknowns per simplex, one per vertex or one
/// per face, all skeleton, and ∇_D u constant on each simplex (P1, Crouzeix–Raviart). It
/// states what is its own (the basis gradients, the load and trace quadratures, the vertex
/// values); the rest of [`GradientDiscretisation`] follows, the same for both and for D = 2, 3:
/// - local matrix M_K = |K| Gᵀ A_K G, with G = [∇φ_i]_i the D×(D+1) matrix of basis gradients;
/// - ∇_D u = Σ_i u_i ∇φ_i on K, and Π_D u at x_K the mean of the D + 1 unknowns (the affine
///   basis functions are 1/(D+1) at the centroid: λ_i(x_K) = 1/(D+1), and for
///   Crouzeix–Raviart φ_σ = 1 − D λ_{v_σ} gives 1 − D/(D+1) = 1/(D+1));
/// - obstacle barriers act on every unknown, at its point ([`SimplexUnknowns`]), with the
///   lumped measure Σ_{K∋i} |K|/(D+1).
///
/// The methods of the same names in [`GradientDiscretisation`] call these.
pub(super) trait SimplexScheme<M: SimplexMesh<D>, const D: usize>: Sync {
    /// Short name ("p1", "cr").
    const NAME: &'static str;
    /// Where the unknowns live.
    const UNKNOWNS: SimplexUnknowns;
    /// The gradients ∇φ_i of the D + 1 basis functions of simplex `k` (constant on it), in
    /// the order of its unknowns.
    fn basis_gradients(&self, k: usize) -> Local<Vector<D>>;
    /// [`GradientDiscretisation::local_load`].
    fn local_load(&self, k: usize, f: &dyn Fn(Vector<D>) -> f64, b: &mut DVector<f64>);
    /// [`GradientDiscretisation::face_trace_dofs`].
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<D>>);
    /// [`GradientDiscretisation::vertex_values`].
    fn vertex_values(&self, u: &[f64]) -> Vec<f64>;
    /// The mesh (simplices only).
    fn mesh(&self) -> &M;
}

/// The [`GradientDiscretisation`] of the simplex schemes on the mesh type `$m` of dimension
/// `$d` (one blanket implementation per mesh type: [`PolyMesh`] and [`PolyMesh3`]).
macro_rules! simplex_discretisation {
    ($m:ty, $d:literal) => {
        impl<T: SimplexScheme<$m, $d>> GradientDiscretisation<$m, $d> for T {
            fn name(&self) -> &'static str {
                T::NAME
            }
            fn mesh(&self) -> &$m {
                SimplexScheme::mesh(self)
            }
            fn n_skeleton(&self) -> usize {
                T::UNKNOWNS.count(SimplexScheme::mesh(self))
            }
            fn n_interior(&self) -> usize {
                0
            }
            fn dof_entity(&self, dof: usize) -> Entity {
                T::UNKNOWNS.entity(dof)
            }
            fn dof_point(&self, dof: usize) -> Vector<$d> {
                T::UNKNOWNS.point(SimplexScheme::mesh(self), dof)
            }
            fn n_local_interior(&self, _k: usize) -> usize {
                0
            }
            fn local_dofs(&self, k: usize, dofs: &mut Vec<usize>) {
                dofs.clear();
                let unknowns = T::UNKNOWNS.of_cell(SimplexScheme::mesh(self), k);
                dofs.extend(unknowns[..=$d].iter().map(|&i| i as usize));
            }
            fn local_matrix(&self, k: usize, a: &Tensor<$d>, m: &mut DMatrix<f64>) {
                let g = self.basis_gradients(k);
                let vol = SimplexScheme::mesh(self).cell_measure(k);
                super::zeroed_matrix(m, $d + 1, $d + 1);
                for i in 0..=$d {
                    let ag: Vector<$d> = std::array::from_fn(|r| dot(&a[r], &g[i]));
                    for j in 0..=$d {
                        m[(j, i)] = vol * dot(&ag, &g[j]);
                    }
                }
            }
            fn local_load(&self, k: usize, f: &dyn Fn(Vector<$d>) -> f64, b: &mut DVector<f64>) {
                SimplexScheme::local_load(self, k, f, b)
            }
            fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<$d>>) {
                SimplexScheme::face_trace_dofs(self, e, out)
            }
            fn obstacle_dofs(&self) -> Vec<PointDof<$d>> {
                use rayon::prelude::*;
                let (m, on) = (SimplexScheme::mesh(self), T::UNKNOWNS);
                // each cell's share |K|/(d+1), computed once per cell and in parallel, then
                // added to its unknowns in cell order: the sums of the one-pass loop, bit for bit
                let share: Vec<f64> = (0..m.n_cells())
                    .into_par_iter()
                    .with_min_len(4096)
                    .map(|k| m.cell_measure(k) / ($d + 1) as f64)
                    .collect();
                let mut meas = vec![0.0; on.count(m)];
                for (k, &w) in share.iter().enumerate() {
                    for &i in &on.of_cell(m, k)[..=$d] {
                        meas[i as usize] += w;
                    }
                }
                drop(share);
                meas.par_iter()
                    .enumerate()
                    .with_min_len(4096)
                    .map(|(i, &w)| PointDof {
                        dof: i,
                        point: on.point(m, i),
                        measure: w,
                    })
                    .collect()
            }
            fn cell_values(&self, u: &[f64]) -> Vec<f64> {
                let (m, on) = (SimplexScheme::mesh(self), T::UNKNOWNS);
                (0..m.n_cells())
                    .map(|k| {
                        on.of_cell(m, k)[..=$d]
                            .iter()
                            .map(|&i| u[i as usize])
                            .sum::<f64>()
                            / ($d + 1) as f64
                    })
                    .collect()
            }
            fn cell_gradients(&self, u: &[f64]) -> Vec<Vector<$d>> {
                let (m, on) = (SimplexScheme::mesh(self), T::UNKNOWNS);
                (0..m.n_cells())
                    .map(|k| {
                        let g = self.basis_gradients(k);
                        let mut r = [0.0; $d];
                        for (i, &d) in on.of_cell(m, k)[..=$d].iter().enumerate() {
                            let d = d as usize;
                            for c in 0..$d {
                                r[c] += u[d] * g[i][c];
                            }
                        }
                        r
                    })
                    .collect()
            }
            fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
                SimplexScheme::vertex_values(self, u)
            }
        }
    };
}

simplex_discretisation!(PolyMesh, 2);
simplex_discretisation!(PolyMesh3, 3);
