//! What P1 and Crouzeix–Raviart share: both are schemes on triangles with three skeleton
//! unknowns per triangle and a gradient constant on each ([`TriangleScheme`]); each states what
//! is its own, and its [`GradientDiscretisation`] follows from it.

use super::{Entity, GradientDiscretisation, PointDof, Tensor};
use crate::mesh::{Point, PolyMesh};
use nalgebra::{DMatrix, DVector};

/// Where the unknowns of a [`TriangleScheme`] live: one on every vertex or on every edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum TriangleUnknowns {
    /// One unknown per mesh vertex, the value there (P1).
    Vertices,
    /// One unknown per mesh edge, the value at its midpoint x_σ (Crouzeix–Raviart).
    Edges,
}

impl TriangleUnknowns {
    /// Number of unknowns on `mesh`.
    fn count(self, mesh: &PolyMesh) -> usize {
        match self {
            TriangleUnknowns::Vertices => mesh.n_vertices(),
            TriangleUnknowns::Edges => mesh.n_edges(),
        }
    }
    /// The three unknowns of triangle `k`, in local order (32-bit, as the mesh stores them).
    fn of_cell(self, mesh: &PolyMesh, k: usize) -> &[u32] {
        match self {
            TriangleUnknowns::Vertices => mesh.cell_vertices(k),
            TriangleUnknowns::Edges => mesh.cell_edges(k),
        }
    }
    /// The mesh entity of unknown `i`.
    fn entity(self, i: usize) -> Entity {
        match self {
            TriangleUnknowns::Vertices => Entity::Vertex(i),
            TriangleUnknowns::Edges => Entity::Edge(i),
        }
    }
    /// Where unknown `i` is a value: the vertex, or the edge midpoint x_σ.
    fn point(self, mesh: &PolyMesh, i: usize) -> Point {
        match self {
            TriangleUnknowns::Vertices => mesh.vertex(i),
            TriangleUnknowns::Edges => mesh.edge_midpoint(i),
        }
    }
}

/// A scheme on triangles with three unknowns per triangle, one per vertex or one per edge, all
/// skeleton, and ∇_D u constant on each triangle (P1, Crouzeix–Raviart). It states what is its
/// own (the basis gradients, the load and trace quadratures, the vertex values); the rest of
/// [`GradientDiscretisation`] follows, the same for both:
/// - local matrix M_K = |K| Gᵀ A_K G, with G = [∇φ_i]_i the 2×3 matrix of basis gradients;
/// - ∇_D u = Σ_i u_i ∇φ_i on K, and Π_D u at x_K the mean of the three unknowns (the affine
///   basis functions are 1/3 at the centroid);
/// - obstacle barriers act on every unknown, at its point ([`TriangleUnknowns`]), with the
///   lumped measure Σ_{K∋i} |K|/3.
///
/// The methods of the same names in [`GradientDiscretisation`] call these.
pub(super) trait TriangleScheme: Sync {
    /// Short name ("p1", "cr").
    const NAME: &'static str;
    /// Where the unknowns live.
    const UNKNOWNS: TriangleUnknowns;
    /// The gradients ∇φ_i of the three basis functions of triangle `k` (constant on it), in
    /// the order of its unknowns.
    fn basis_gradients(&self, k: usize) -> [Point; 3];
    /// [`GradientDiscretisation::local_load`].
    fn local_load(&self, k: usize, f: &dyn Fn(Point) -> f64, b: &mut DVector<f64>);
    /// [`GradientDiscretisation::face_trace_dofs`].
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof>);
    /// [`GradientDiscretisation::vertex_values`].
    fn vertex_values(&self, u: &[f64]) -> Vec<f64>;
    /// The mesh (triangles only).
    fn mesh(&self) -> &PolyMesh;
}

impl<T: TriangleScheme> GradientDiscretisation for T {
    fn name(&self) -> &'static str {
        T::NAME
    }
    fn mesh(&self) -> &PolyMesh {
        TriangleScheme::mesh(self)
    }
    fn n_skeleton(&self) -> usize {
        T::UNKNOWNS.count(TriangleScheme::mesh(self))
    }
    fn n_interior(&self) -> usize {
        0
    }
    fn dof_entity(&self, dof: usize) -> Entity {
        T::UNKNOWNS.entity(dof)
    }
    fn n_local_interior(&self, _k: usize) -> usize {
        0
    }
    fn local_dofs(&self, k: usize, dofs: &mut Vec<usize>) {
        dofs.clear();
        let unknowns = T::UNKNOWNS.of_cell(TriangleScheme::mesh(self), k);
        dofs.extend(unknowns.iter().map(|&i| i as usize));
    }
    fn local_matrix(&self, k: usize, a: &Tensor, m: &mut DMatrix<f64>) {
        let g = self.basis_gradients(k);
        let area = TriangleScheme::mesh(self).measure(k);
        *m = DMatrix::zeros(3, 3);
        for i in 0..3 {
            let ag = [
                a[0][0] * g[i][0] + a[0][1] * g[i][1],
                a[1][0] * g[i][0] + a[1][1] * g[i][1],
            ];
            for j in 0..3 {
                m[(j, i)] = area * (ag[0] * g[j][0] + ag[1] * g[j][1]);
            }
        }
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point) -> f64, b: &mut DVector<f64>) {
        TriangleScheme::local_load(self, k, f, b)
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof>) {
        TriangleScheme::face_trace_dofs(self, e, out)
    }
    fn obstacle_dofs(&self) -> Vec<PointDof> {
        let (m, on) = (TriangleScheme::mesh(self), T::UNKNOWNS);
        let mut meas = vec![0.0; on.count(m)];
        for k in 0..m.n_cells() {
            for &i in on.of_cell(m, k) {
                meas[i as usize] += m.measure(k) / 3.0;
            }
        }
        meas.iter()
            .enumerate()
            .map(|(i, &w)| PointDof {
                dof: i,
                point: on.point(m, i),
                measure: w,
            })
            .collect()
    }
    fn cell_values(&self, u: &[f64]) -> Vec<f64> {
        let (m, on) = (TriangleScheme::mesh(self), T::UNKNOWNS);
        (0..m.n_cells())
            .map(|k| on.of_cell(m, k).iter().map(|&i| u[i as usize]).sum::<f64>() / 3.0)
            .collect()
    }
    fn cell_gradients(&self, u: &[f64]) -> Vec<Point> {
        let (m, on) = (TriangleScheme::mesh(self), T::UNKNOWNS);
        (0..m.n_cells())
            .map(|k| {
                let g = self.basis_gradients(k);
                let mut r = [0.0; 2];
                for (i, &d) in on.of_cell(m, k).iter().enumerate() {
                    let d = d as usize;
                    r[0] += u[d] * g[i][0];
                    r[1] += u[d] * g[i][1];
                }
                r
            })
            .collect()
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        TriangleScheme::vertex_values(self, u)
    }
}

/// An error unless every cell of `mesh` is a triangle (`scheme` names the scheme that needs it).
pub(super) fn require_triangles(mesh: &PolyMesh, scheme: &str) -> crate::Result<()> {
    match (0..mesh.n_cells()).find(|&k| mesh.cell_vertices(k).len() != 3) {
        Some(k) => Err(crate::Error::InvalidData(format!(
            "{scheme} needs a triangle mesh, but cell {k} has {} vertices",
            mesh.cell_vertices(k).len()
        ))),
        None => Ok(()),
    }
}
