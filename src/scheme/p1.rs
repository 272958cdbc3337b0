//! Conforming P1 finite elements on triangles (paper Section 3.1).
//!
//! Unknowns: the values at the mesh vertices (all skeleton; nothing to condense).
//! Π_D u is the continuous piecewise-affine interpolant, ∇_D u its gradient, T_D u its trace.
//!
//! Quadrature (stated because the cross-check against dolfinx depends on it):
//! - load: ∫_Ω (I_T f) φ_i, with I_T f the affine interpolant of f on each triangle T, from the
//!   values of f at the vertices of T, integrated exactly with the element mass matrix
//!   |T|/12·(1 + δ_ij). The assembler passes the source *of the cell*
//!   ([`crate::problem::Problem::source_in_cell`]), so a source discontinuous across a mesh line,
//!   as in the paper's Test 2, takes each triangle's own piece at the vertices on that line.
//!   For a continuous f this is dolfinx's `f_h * v * dx` with `f_h` interpolated in P1 (the
//!   reference scripts build the same one-sided interpolant for Test 2);
//! - diffusion: A is taken constant per triangle, A_K = A(x_K) at the centroid (dolfinx: DG0);
//! - boundary data: ∫_σ g φ_i ≈ |σ| g(x_σ)/2 at each end of σ (midpoint rule);
//! - obstacle barriers are nodal: u(x_v) ≤ g(x_v) (or ≥); a vertex carries the lumped measure
//!   Σ_{T∋v} |T|/3, a Signorini vertex the measure Σ_{σ∋v, σ⊂Γ3} |σ|/2.

use super::PointDof;
use super::triangle::TriangleUnknowns;
use crate::mesh::{Point, PolyMesh};
use nalgebra::DVector;

/// P1 finite elements on a triangle mesh: a triangle scheme (see `scheme/triangle.rs`) with an
/// unknown on every vertex.
#[derive(Debug, Clone)]
pub struct P1<'a> {
    mesh: &'a PolyMesh,
}

impl<'a> P1<'a> {
    /// P1 on `mesh`; an error if some cell is not a triangle.
    pub fn new(mesh: &'a PolyMesh) -> crate::Result<Self> {
        super::triangle::require_triangles(mesh, "P1")?;
        Ok(P1 { mesh })
    }
}

impl super::triangle::TriangleScheme for P1<'_> {
    const NAME: &'static str = "p1";
    const UNKNOWNS: TriangleUnknowns = TriangleUnknowns::Vertices;
    /// The gradients of the three barycentric functions λ_i of triangle `k`.
    fn basis_gradients(&self, k: usize) -> [Point; 3] {
        let v = self.mesh.cell_vertices(k);
        let p: Vec<Point> = v.iter().map(|&i| self.mesh.vertex(i as usize)).collect();
        let twice_area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        let mut g = [[0.0; 2]; 3];
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
        let fv: Vec<f64> = v.iter().map(|&i| f(self.mesh.vertex(i as usize))).collect();
        let s = fv[0] + fv[1] + fv[2];
        let area = self.mesh.measure(k);
        *b = DVector::from_fn(3, |i, _| area / 12.0 * (s + fv[i]));
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
