//! The Crouzeix–Raviart (non-conforming P1) scheme with mass lumping, on triangles and on
//! tetrahedra
//! (GDM book, Droniou–Eymard–Gallouët–Guichard–Herbin, Chapter 9: non-conforming P1, its
//! mass-lumped gradient discretisation).
//!
//! Unknowns: one value u_σ per edge σ, the value at the midpoint x_σ (all skeleton; nothing to
//! condense). On a triangle K with edges σ ∈ E_K, write v_σ for the vertex of K opposite σ and
//! λ_v for the barycentric coordinates. The Crouzeix–Raviart basis function of σ on K is
//! φ_σ = 1 − 2λ_{v_σ}: it is 1 at x_σ and 0 at the two other midpoints.
//!
//! - ∇_D u = the broken gradient of the Crouzeix–Raviart function Σ_σ u_σ φ_σ. Since
//!   ∇λ_{v_σ} = −|σ| n_{K,σ} / (2|K|), ∇φ_σ = |σ| n_{K,σ} / |K| and
//!   ∇_K u = (1/|K|) Σ_σ |σ| u_σ n_{K,σ}
//!   (HMM's consistent gradient without the cell unknown: Σ_σ |σ| n_{K,σ} = 0). With
//!   G = [|σ| n_{K,σ}/|K|]_σ (2×3), the local matrix is M_K = |K| Gᵀ A_K G, A_K = A(x_K).
//!   Its rows sum to zero, and it is exact for affine functions (∇_K u = ∇ū when u_σ = ū(x_σ)).
//! - Π_D u, mass-lumped: with D_{K,σ} = co(σ ∪ {x_K}) the triangle formed by σ and the centroid,
//!   Π_D u = u_σ on D_{K,σ}. As x_K is the barycentre, the height of D_{K,σ} over σ is a third of
//!   that of K, so |D_{K,σ}| = |K|/3, and the three D_{K,σ} tile K. An edge σ = K|L carries the
//!   diamond D_σ = D_{K,σ} ∪ D_{L,σ}, of measure Σ_{K∋σ} |K|/3.
//! - T_D u = u_σ on σ (the Crouzeix–Raviart trace integrated by the midpoint rule, which is
//!   exact for it: ∫_σ φ_σ = |σ|, ∫_σ φ_{σ'} = 0 for σ' ≠ σ).
//!
//! Quadrature (the choices, and why):
//! - load: ∫_K f Π_D v = Σ_σ v_σ ∫_{D_{K,σ}} f ≈ Σ_σ v_σ (|K|/3) f(x_{K,σ}), with
//!   x_{K,σ} = (x_K + s₁ + s₂)/3 the centroid of D_{K,σ} (s₁, s₂ the ends of σ). This
//!   one-point rule is exact for f affine on K (the book integrates ∫ f Π_D v exactly and
//!   prescribes no rule; we take the one exact on its degree). Its point lies strictly inside
//!   K, so the source of the cell is used: the assembler passes the closure of K
//!   ([`crate::problem::Problem::source_in_cell`] when the data are smooth by pieces), and
//!   even a plain source discontinuous across mesh lines is evaluated on K's own side. Summed
//!   over σ it gives |K| f(x_K) for affine f, HMM's cell load (f(x_K) at each of the three
//!   edges would be exact for constants only);
//! - diffusion: A is taken constant per triangle, A_K = A(x_K);
//! - boundary data: ∫_σ g T_D v ≈ |σ| g(x_σ) v_σ; Dirichlet values are imposed at x_σ,
//!   u_σ = u_D(x_σ);
//! - obstacle barriers act on every edge unknown, u_σ ≤ g(x_σ) (or ≥): Π_D u is u_σ on D_σ, so
//!   the barrier is piecewise constant on diamonds, and an edge carries the lumped measure
//!   |D_σ| = Σ_{K∋σ} |K|/3. Signorini barriers act on the boundary-edge unknowns of Γ3, with
//!   measure |σ| (from the trace, by the assembler).
//!
//! Output: [`super::GradientDiscretisation::cell_values`] gives the Crouzeix–Raviart function at
//! x_K, the mean of the three edge values (φ_σ(x_K) = 1/3); the vertex values are the
//! area-weighted mean, over the triangles around the vertex, of the Crouzeix–Raviart function
//! of each triangle at that vertex, u_{σ₁} + u_{σ₂} − u_{σ₀} (σ₁, σ₂ the edges through the
//! vertex, σ₀ the opposite one): exact for affine functions, unlike a mean of centroid values.

//!
//! ## Tetrahedra
//! The same scheme on a tetrahedron K (D = 3), one unknown u_σ per face σ, the value at its
//! centroid x_σ; everything above holds with 3 in place of 2 where it is the dimension:
//! - φ_σ = 1 − 3λ_{v_σ} (λ_{v_σ} is 0 on σ, so at x_σ, and 1/3 at the centroids of the three
//!   other faces), ∇φ_σ = −3∇λ_{v_σ} = |σ| n_{K,σ}/|K| (as ∇λ_{v_σ} = −|σ| n_{K,σ}/(3|K|)),
//!   so ∇_K u = (1/|K|) Σ_σ |σ| u_σ n_{K,σ} as in 2-D (G is 3×4);
//! - Π_D u = u_σ on the pyramid D_{K,σ} = co(σ ∪ {x_K}); x_K is the barycentre, so
//!   λ_{v_σ}(x_K) = 1/4 and the height of D_{K,σ} over σ is a quarter of that of K:
//!   |D_{K,σ}| = |K|/4 (each face unknown carries a quarter of the cell), and the four
//!   D_{K,σ} tile K. The obstacle measure of a face is |D_σ| = Σ_{K∋σ} |K|/4;
//! - load: Σ_σ v_σ (|K|/4) f(x_{K,σ}), x_{K,σ} = (s₁ + s₂ + s₃ + x_K)/4 the centroid of
//!   D_{K,σ} (s₁, s₂, s₃ the vertices of σ, in the order of its loop): exact for f affine on K,
//!   |K| f(x_K) in total;
//! - trace, Dirichlet and Signorini data: at x_σ with weight |σ|, as in 2-D;
//! - output: Π_D u at x_K is the mean of the four face values (φ_σ(x_K) = 1/4); at a vertex v
//!   of K the Crouzeix–Raviart function of K is Σ_{σ∋v} u_σ − 2u_{σ_v} (φ_σ(v) = 1 on the
//!   three faces through v, 1 − 3 = −2 on the face σ_v opposite v), averaged over the
//!   tetrahedra around v with their volumes as weights.

use super::PointDof;
use super::simplex::{Local, SimplexMesh, SimplexUnknowns};
use crate::mesh::complex::{CellComplex, Vector};
use crate::mesh::{Point, PolyMesh};
use crate::mesh3d::{Point3, PolyMesh3};
use nalgebra::DVector;

/// The mass-lumped Crouzeix–Raviart scheme on a mesh of simplices: by default a triangle mesh
/// ([`PolyMesh`], D = 2); `Cr<PolyMesh3, 3>` on a tetrahedral [`PolyMesh3`]. A simplex scheme
/// (see `scheme/simplex.rs`) with an unknown on every face (an edge in 2-D).
#[derive(Debug, Clone)]
pub struct Cr<'a, M = PolyMesh, const D: usize = 2> {
    mesh: &'a M,
}

impl<'a, M: SimplexMesh<D>, const D: usize> Cr<'a, M, D> {
    /// Crouzeix–Raviart on `mesh`; an error naming the first cell that is not a simplex (a
    /// triangle in 2-D, a tetrahedron in 3-D).
    pub fn new(mesh: &'a M) -> crate::Result<Self> {
        mesh.require_simplices("the Crouzeix–Raviart scheme")?;
        Ok(Cr { mesh })
    }
}

impl Cr<'_> {
    /// The centroid x_{K,σ} of the sub-triangle D_{K,σ} = co(σ ∪ {x_K}) of local edge `i` of
    /// triangle `k` (local edge i joins local vertices i and i+1).
    pub fn sub_centroid(&self, k: usize, i: usize) -> Point {
        let m = self.mesh;
        let v = m.cell_vertices(k);
        let (a, b) = (v[i] as usize, v[(i + 1) % 3] as usize);
        let (a, b, xk) = (m.vertex(a), m.vertex(b), m.centroid(k));
        [(a[0] + b[0] + xk[0]) / 3.0, (a[1] + b[1] + xk[1]) / 3.0]
    }
}

impl Cr<'_, PolyMesh3, 3> {
    /// The centroid x_{K,σ} = (s₁ + s₂ + s₃ + x_K)/4 of the pyramid D_{K,σ} = co(σ ∪ {x_K}) of
    /// local face `i` of tetrahedron `k`.
    pub fn sub_centroid(&self, k: usize, i: usize) -> Point3 {
        let m = self.mesh;
        let s = m.face_vertices(m.cell_faces(k)[i] as usize);
        let p = |j: usize| m.vertices()[s[j] as usize];
        let (a, b, c, xk) = (p(0), p(1), p(2), m.centroid(k));
        std::array::from_fn(|r| (a[r] + b[r] + c[r] + xk[r]) / 4.0)
    }
}

/// ∇φ_σ = |σ| n_{K,σ} / |K| for the D + 1 faces of simplex `k`, in the order of its local
/// faces (the columns of G).
fn face_basis_gradients<const D: usize>(m: &impl CellComplex<D>, k: usize) -> Local<Vector<D>> {
    let vol = m.cell_measure(k);
    let mut g = [[0.0; D]; 4];
    for (i, &e) in m.cell_faces(k).iter().enumerate() {
        let s = m.face_measure(e as usize) / vol;
        let nrm = m.cell_face_normal(k, i);
        g[i] = nrm.map(|c| s * c);
    }
    g
}

impl super::simplex::SimplexScheme<PolyMesh, 2> for Cr<'_> {
    const NAME: &'static str = "cr";
    const UNKNOWNS: SimplexUnknowns = SimplexUnknowns::Faces;
    fn basis_gradients(&self, k: usize) -> Local<Point> {
        face_basis_gradients(self.mesh, k)
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point) -> f64, b: &mut DVector<f64>) {
        let third = self.mesh.measure(k) / 3.0;
        super::zeroed_vector(b, 3);
        (0..3).for_each(|i| b[i] = third * f(self.sub_centroid(k, i)));
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof>) {
        super::face_unknown_trace(self.mesh, e, out);
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        let m = self.mesh;
        let mut sum = vec![0.0; m.n_vertices()];
        let mut weight = vec![0.0; m.n_vertices()];
        for k in 0..m.n_cells() {
            let (v, e, area) = (m.cell_vertices(k), m.cell_edges(k), m.measure(k));
            for j in 0..3 {
                // local vertex j lies on local edges j and j−1, opposite local edge j+1
                let value =
                    u[e[j] as usize] + u[e[(j + 2) % 3] as usize] - u[e[(j + 1) % 3] as usize];
                let vj = v[j] as usize;
                sum[vj] += area * value;
                weight[vj] += area;
            }
        }
        sum.iter().zip(&weight).map(|(s, w)| s / w).collect()
    }
    fn mesh(&self) -> &PolyMesh {
        self.mesh
    }
}

impl super::simplex::SimplexScheme<PolyMesh3, 3> for Cr<'_, PolyMesh3, 3> {
    const NAME: &'static str = "cr";
    const UNKNOWNS: SimplexUnknowns = SimplexUnknowns::Faces;
    fn basis_gradients(&self, k: usize) -> Local<Point3> {
        face_basis_gradients(self.mesh, k)
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point3) -> f64, b: &mut DVector<f64>) {
        let quarter = self.mesh.measure(k) / 4.0;
        super::zeroed_vector(b, 4);
        (0..4).for_each(|i| b[i] = quarter * f(self.sub_centroid(k, i)));
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<3>>) {
        super::face_unknown_trace(self.mesh, e, out);
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        let m = self.mesh;
        let mut sum = vec![0.0; m.n_vertices()];
        let mut weight = vec![0.0; m.n_vertices()];
        for k in 0..m.n_cells() {
            let (faces, vol) = (m.cell_faces(k), m.measure(k));
            for v in m.simplex_vertices(k) {
                // Σ_{σ∋v} u_σ − 2 u_{σ_v}: φ_σ(v) is 1 on the faces through v, −2 opposite it
                let value: f64 = faces
                    .iter()
                    .map(|&f| {
                        let uf = u[f as usize];
                        if m.face_vertices(f as usize).contains(&v) {
                            uf
                        } else {
                            -2.0 * uf
                        }
                    })
                    .sum();
                sum[v as usize] += vol * value;
                weight[v as usize] += vol;
            }
        }
        sum.iter().zip(&weight).map(|(s, w)| s / w).collect()
    }
    fn mesh(&self) -> &PolyMesh3 {
        self.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::{Entity, GradientDiscretisation, Tensor};
    use nalgebra::DMatrix;

    const A: Tensor = [[2.0, 0.3], [0.3, 1.0]];

    /// Four triangles of different shapes around an interior vertex.
    fn patch() -> PolyMesh {
        let v = vec![[0.0, 0.0], [1.0, 0.1], [1.2, 0.9], [0.1, 1.1], [0.45, 0.55]];
        PolyMesh::from_cells(
            v,
            vec![vec![0, 1, 4], vec![1, 2, 4], vec![2, 3, 4], vec![3, 0, 4]],
        )
        .unwrap()
    }

    fn affine(p: Point) -> f64 {
        0.4 + 0.7 * p[0] - 1.9 * p[1]
    }

    #[test]
    fn local_matrix_is_symmetric_semidefinite_with_constants_in_kernel() {
        let m = patch();
        let s = Cr::new(&m).unwrap();
        let mut mat = DMatrix::zeros(0, 0);
        for k in 0..m.n_cells() {
            s.local_matrix(k, &A, &mut mat);
            assert_eq!(mat.shape(), (3, 3));
            let scale = mat.amax();
            assert!((&mat - mat.transpose()).amax() < 1e-14 * scale);
            // rows sum to zero: constants are in the kernel
            assert!((&mat * DVector::from_element(3, 1.0)).amax() < 1e-13 * scale);
            // semidefinite, and the kernel is exactly the constants (G has rank 2)
            let mut e: Vec<f64> = mat.symmetric_eigenvalues().iter().cloned().collect();
            e.sort_by(f64::total_cmp);
            assert!(e[0].abs() < 1e-13 * scale && e[1] > 1e-3 * scale, "{e:?}");
        }
    }

    #[test]
    fn affine_functions_have_exact_gradient_energy_and_values() {
        let m = patch();
        let s = Cr::new(&m).unwrap();
        let grad = [0.7, -1.9];
        let u: Vec<f64> = (0..m.n_edges())
            .map(|e| affine(m.edge_midpoint(e)))
            .collect();
        let cg = s.cell_gradients(&u);
        let cv = s.cell_values(&u);
        let mut mat = DMatrix::zeros(0, 0);
        let mut dofs = Vec::new();
        for k in 0..m.n_cells() {
            assert!((cg[k][0] - grad[0]).abs() < 1e-13 && (cg[k][1] - grad[1]).abs() < 1e-13);
            assert!((cv[k] - affine(m.centroid(k))).abs() < 1e-13);
            // the energy is |K| A∇ū·∇ū
            s.local_dofs(k, &mut dofs);
            s.local_matrix(k, &A, &mut mat);
            let ul = DVector::from_iterator(3, dofs.iter().map(|&d| u[d]));
            let energy = ul.dot(&(&mat * &ul));
            let exact = m.measure(k)
                * (grad[0] * (A[0][0] * grad[0] + A[0][1] * grad[1])
                    + grad[1] * (A[1][0] * grad[0] + A[1][1] * grad[1]));
            assert!((energy - exact).abs() < 1e-12 * exact);
        }
        // the Crouzeix–Raviart function of each triangle is ū, so are its vertex values
        for (v, uv) in s.vertex_values(&u).iter().enumerate() {
            assert!((uv - affine(m.vertex(v))).abs() < 1e-13, "vertex {v}");
        }
    }

    #[test]
    fn lumped_load_and_measures() {
        let m = patch();
        let s = Cr::new(&m).unwrap();
        let mut b = DVector::zeros(0);
        for k in 0..m.n_cells() {
            s.local_load(k, &affine, &mut b);
            let v = m.cell_vertices(k);
            let xk = m.centroid(k);
            for i in 0..3 {
                // ∫_{D_{K,σ}} f for f affine: |D_{K,σ}| times the mean of f at its vertices
                let (a, c) = (m.vertex(v[i] as usize), m.vertex(v[(i + 1) % 3] as usize));
                let exact = m.measure(k) / 3.0 * (affine(a) + affine(c) + affine(xk)) / 3.0;
                assert!(
                    (b[i] - exact).abs() < 1e-14,
                    "{k}, {i}: {} vs {exact}",
                    b[i]
                );
            }
            // in total, ∫_K f = |K| f(x_K)
            assert!((b.sum() - m.measure(k) * affine(xk)).abs() < 1e-14);
        }
        // diamonds tile Ω; an interior edge gets a third of each neighbour, a boundary one of one
        let od = s.obstacle_dofs();
        assert_eq!(od.len(), m.n_edges());
        let total: f64 = od.iter().map(|d| d.measure).sum();
        let area: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
        assert!((total - area).abs() < 1e-14);
        for d in &od {
            let [k, l] = m.edge_cells(d.dof);
            let expect = if m.is_boundary_edge(d.dof) {
                m.measure(k) / 3.0
            } else {
                (m.measure(k) + m.measure(l)) / 3.0
            };
            assert!((d.measure - expect).abs() < 1e-15);
            assert_eq!(d.point, m.edge_midpoint(d.dof));
            assert_eq!(s.dof_entity(d.dof), Entity::Edge(d.dof));
        }
        let mut tr = Vec::new();
        let e = m.boundary_edges()[0];
        s.face_trace_dofs(e, &mut tr);
        assert_eq!(
            tr,
            vec![PointDof {
                dof: e,
                point: m.edge_midpoint(e),
                measure: m.edge_measure(e)
            }]
        );
        assert_eq!((s.n_skeleton(), s.n_interior()), (m.n_edges(), 0));
    }

    #[test]
    fn non_triangle_cells_are_rejected() {
        let m = PolyMesh::from_cells(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]],
            vec![vec![1, 4, 2], vec![0, 1, 2, 3]],
        )
        .unwrap();
        match Cr::new(&m) {
            Err(crate::Error::InvalidData(msg)) => {
                assert!(msg.contains("cell 1 has 4 vertices"), "{msg}")
            }
            other => panic!("expected InvalidData, got {:?}", other.map(|s| s.name())),
        }
    }
}
