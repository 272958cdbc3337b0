//! Conforming P1 finite elements on triangles (paper Section 3.1) and on tetrahedra.
//!
//! Unknowns: the values at the mesh vertices (all skeleton; nothing to condense).
//! Π_D u is the continuous piecewise-affine interpolant, ∇_D u its gradient, T_D u its trace.
//! Both dimensions are simplex schemes (see `scheme/simplex.rs`): what is written below for a
//! simplex K of dimension D holds for triangles (D = 2) and tetrahedra (D = 3), with the
//! barycentric coordinates λ_i of K as basis functions.
//!
//! Quadrature (stated because the cross-check against dolfinx depends on it):
//! - load: ∫_Ω (I_T f) φ_i, with I_T f the affine interpolant of f on each simplex T, from the
//!   values of f at the vertices of T, integrated exactly with the element mass matrix
//!   ∫_T λ_i λ_j = |T|(1 + δ_ij)/((D+1)(D+2)): |T|/12·(1 + δ_ij) on a triangle,
//!   |T|/20·(1 + δ_ij) on a tetrahedron. The assembler passes the source *of the cell*
//!   ([`crate::problem::Problem::source_in_cell`]), so a source discontinuous across a mesh line,
//!   as in the paper's Test 2, takes each triangle's own piece at the vertices on that line.
//!   For a continuous f this is dolfinx's `f_h * v * dx` with `f_h` interpolated in P1 (the
//!   reference scripts build the same one-sided interpolant for Test 2);
//! - diffusion: A is taken constant per simplex, A_K = A(x_K) at the centroid (dolfinx: DG0);
//! - boundary data: ∫_σ g φ_i ≈ |σ| g(x_σ)/D at each of the D vertices of the face σ (the
//!   centroid rule: φ_i(x_σ) = 1/D); Dirichlet values are imposed at the vertices;
//! - obstacle barriers are nodal: u(x_v) ≤ g(x_v) (or ≥); a vertex carries the lumped measure
//!   Σ_{T∋v} |T|/(D+1), a Signorini vertex the measure Σ_{σ∋v, σ⊂Γ3} |σ|/D.
//!
//! Basis gradients: on a triangle with vertices p_0, p_1, p_2 (counter-clockwise),
//! ∇λ_i = rot(p_{i+2} − p_{i+1})/(2|K|) with rot(x, y) = (y, −x). On a tetrahedron with
//! vertices p_0 … p_3 and edges e_j = p_j − p_0, the Jacobian J = [e_1 e_2 e_3] maps the
//! reference tetrahedron onto K and (λ_1, λ_2, λ_3) = J⁻¹(x − p_0), so ∇λ_j is row j of
//! J⁻¹: ∇λ_1 = (e_2 × e_3)/det J, ∇λ_2 = (e_3 × e_1)/det J, ∇λ_3 = (e_1 × e_2)/det J, and
//! ∇λ_0 = −(∇λ_1 + ∇λ_2 + ∇λ_3) (whatever the orientation: det J carries the sign).

use super::PointDof;
use super::simplex::{Local, SimplexMesh, SimplexUnknowns};
use crate::mesh::{Point, PolyMesh};
use crate::mesh3d::{Point3, PolyMesh3};
use nalgebra::DVector;

/// P1 finite elements on a mesh of simplices: by default a triangle mesh ([`PolyMesh`],
/// D = 2); `P1<PolyMesh3, 3>` on a tetrahedral [`PolyMesh3`]. A simplex scheme (see
/// `scheme/simplex.rs`) with an unknown on every vertex.
#[derive(Debug, Clone)]
pub struct P1<'a, M = PolyMesh, const D: usize = 2> {
    mesh: &'a M,
}

impl<'a, M: SimplexMesh<D>, const D: usize> P1<'a, M, D> {
    /// P1 on `mesh`; an error naming the first cell that is not a simplex (a triangle in 2-D,
    /// a tetrahedron in 3-D).
    pub fn new(mesh: &'a M) -> crate::Result<Self> {
        mesh.require_simplices("P1")?;
        Ok(P1 { mesh })
    }
}

impl super::simplex::SimplexScheme<PolyMesh, 2> for P1<'_> {
    const NAME: &'static str = "p1";
    const UNKNOWNS: SimplexUnknowns = SimplexUnknowns::Vertices;
    /// The gradients of the three barycentric functions λ_i of triangle `k`.
    fn basis_gradients(&self, k: usize) -> Local<Point> {
        let v = self.mesh.cell_vertices(k);
        let p: [Point; 3] = std::array::from_fn(|i| self.mesh.vertex(v[i] as usize));
        let twice_area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        let mut g = [[0.0; 2]; 4];
        for i in 0..3 {
            let a = p[(i + 1) % 3];
            let b = p[(i + 2) % 3];
            // ∇λ_i = rot(b − a)/(2|K|), with rot(x, y) = (y, −x) for counter-clockwise triangles
            g[i] = [(a[1] - b[1]) / twice_area, (b[0] - a[0]) / twice_area];
        }
        g
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point) -> f64, b: &mut DVector<f64>) {
        let v = self.mesh.cell_vertices(k);
        let fv: [f64; 3] = std::array::from_fn(|i| f(self.mesh.vertex(v[i] as usize)));
        let s = fv[0] + fv[1] + fv[2];
        let area = self.mesh.measure(k);
        super::zeroed_vector(b, 3);
        b.iter_mut()
            .zip(fv)
            .for_each(|(b, fi)| *b = area / 12.0 * (s + fi));
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof>) {
        out.clear();
        let half = 0.5 * self.mesh.edge_measure(e);
        for v in self.mesh.edge_vertices(e) {
            out.push(PointDof {
                dof: v,
                point: self.mesh.vertex(v),
                measure: half,
            });
        }
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        u[..self.mesh.n_vertices()].to_vec()
    }
    fn mesh(&self) -> &PolyMesh {
        self.mesh
    }
}

/// a × b.
fn cross(a: Point3, b: Point3) -> Point3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl super::simplex::SimplexScheme<PolyMesh3, 3> for P1<'_, PolyMesh3, 3> {
    const NAME: &'static str = "p1";
    const UNKNOWNS: SimplexUnknowns = SimplexUnknowns::Vertices;
    /// The gradients of the four barycentric functions λ_i of tetrahedron `k`: the rows of
    /// J⁻¹ (module docs), in the order of [`PolyMesh3::tetrahedron`].
    fn basis_gradients(&self, k: usize) -> Local<Point3> {
        let p = self
            .mesh
            .simplex_vertices(k)
            .map(|v| self.mesh.vertices()[v as usize]);
        let e: [Point3; 3] =
            std::array::from_fn(|j| std::array::from_fn(|c| p[j + 1][c] - p[0][c]));
        let rows = [cross(e[1], e[2]), cross(e[2], e[0]), cross(e[0], e[1])];
        let det = e[0][0] * rows[0][0] + e[0][1] * rows[0][1] + e[0][2] * rows[0][2];
        let mut g = [[0.0; 3]; 4];
        for j in 0..3 {
            g[j + 1] = rows[j].map(|c| c / det);
        }
        g[0] = std::array::from_fn(|c| -(g[1][c] + g[2][c] + g[3][c]));
        g
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point3) -> f64, b: &mut DVector<f64>) {
        let fv = self
            .mesh
            .simplex_vertices(k)
            .map(|v| f(self.mesh.vertices()[v as usize]));
        let s = fv[0] + fv[1] + fv[2] + fv[3];
        let vol = self.mesh.measure(k);
        super::zeroed_vector(b, 4);
        b.iter_mut()
            .zip(fv)
            .for_each(|(b, fi)| *b = vol / 20.0 * (s + fi));
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<3>>) {
        out.clear();
        let third = self.mesh.face_measure(e) / 3.0;
        for &v in self.mesh.face_vertices(e) {
            out.push(PointDof {
                dof: v as usize,
                point: self.mesh.vertices()[v as usize],
                measure: third,
            });
        }
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        u[..self.mesh.n_vertices()].to_vec()
    }
    fn mesh(&self) -> &PolyMesh3 {
        self.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scheme::GradientDiscretisation;
    use nalgebra::DMatrix;

    #[test]
    fn stiffness_of_reference_triangle() {
        let m = PolyMesh::from_cells(
            vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            vec![vec![0, 1, 2]],
        )
        .unwrap();
        let s = P1::new(&m).unwrap();
        let mut k = DMatrix::zeros(0, 0);
        s.local_matrix(0, &[[1.0, 0.0], [0.0, 1.0]], &mut k);
        let expect =
            DMatrix::from_row_slice(3, 3, &[1.0, -0.5, -0.5, -0.5, 0.5, 0.0, -0.5, 0.0, 0.5]);
        assert!((k - expect).amax() < 1e-15);
        let mut b = DVector::zeros(0);
        s.local_load(0, &|p| 1.0 + p[0], &mut b);
        // ∫ (1 + x) λ_i over the reference triangle: exact since I_h f = f
        let exact = [
            0.5 / 3.0 + 1.0 / 24.0,
            0.5 / 3.0 + 1.0 / 12.0,
            0.5 / 3.0 + 1.0 / 24.0,
        ];
        for i in 0..3 {
            assert!(
                (b[i] - exact[i]).abs() < 1e-15,
                "{i}: {} vs {}",
                b[i],
                exact[i]
            );
        }
    }
}
