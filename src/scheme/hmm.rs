//! The Hybrid Mimetic Mixed scheme (paper Section 3.2), SUSHI stabilisation.
//!
//! Unknowns: u_K in every cell (interior, condensed) and u_σ on every edge (skeleton).
//! With x_K the centroid and, for each local edge σ of K, |σ|, x_σ, n_{K,σ}, d_{K,σ}:
//!
//! - consistent gradient ∇_K u = (1/|K|) Σ_σ |σ| (u_σ − u_K) n_{K,σ};
//! - residuals R_{K,σ}(u) = u_σ − u_K − ∇_K u · (x_σ − x_K);
//! - stabilisation B_K = α² diag(|σ| A_K n_{K,σ}·n_{K,σ} / d_{K,σ}) (α = 1 by default);
//! - local form |K| A_K ∇_K u·∇_K v + R_K(v)ᵀ B_K R_K(u).
//!
//! Writing δ = (u_σ − u_K)_σ, ∇_K u = G δ with G = [|σ| n_{K,σ}/|K|]_σ (2×n) and
//! R_K = (I − X G) δ with X the n×2 matrix of rows (x_σ − x_K)ᵀ, the form is δ(v)ᵀ W δ(u) with
//! W = |K| Gᵀ A_K G + (I − XG)ᵀ B_K (I − XG). The local matrix on [u_K, u_σ…] is
//! Cᵀ W C with C = [−1 | I]. The fluxes of the paper's Section 4 are
//! |σ| F_{K,σ}(u) = −(W δ(u))_σ, so that Σ_σ |σ| F_{K,σ}(u)(v_K − v_σ) is the local form.
//!
//! Load: |K| f(x_K) on the cell unknown (Π_D v = v_K on K). Trace: T_D v = v_σ on σ, so a
//! boundary datum g enters as |σ| g(x_σ), and Dirichlet values are imposed at x_σ.

use super::{GradientDiscretisation, PointDof, Tensor};
use crate::mesh::{Point, PolyMesh};
use nalgebra::{DMatrix, DVector};

/// HMM on a polygonal mesh.
#[derive(Debug, Clone)]
pub struct Hmm<'a> {
    mesh: &'a PolyMesh,
    alpha: f64,
}

impl<'a> Hmm<'a> {
    /// HMM with the default stabilisation parameter α = 1.
    pub fn new(mesh: &'a PolyMesh) -> Self {
        Hmm { mesh, alpha: 1.0 }
    }
    /// HMM with stabilisation parameter α (> 0).
    pub fn with_alpha(mesh: &'a PolyMesh, alpha: f64) -> crate::Result<Self> {
        if !(alpha > 0.0 && alpha.is_finite()) {
            return Err(crate::Error::InvalidData(format!(
                "HMM stabilisation parameter alpha must be positive and finite, got {alpha}"
            )));
        }
        Ok(Hmm { mesh, alpha })
    }
    /// The global index of the cell unknown u_K.
    pub fn cell_dof(&self, k: usize) -> usize {
        self.mesh.n_edges() + k
    }
    /// The matrix W of the module docs for cell `k` (size n_σ × n_σ).
    pub fn w_matrix(&self, k: usize, a: &Tensor) -> DMatrix<f64> {
        let m = self.mesh;
        let edges = m.cell_edges(k);
        let n = edges.len();
        let area = m.measure(k);
        let xk = m.centroid(k);
        let normals = m.cell_normals(k);
        let dists = m.cell_dists(k);
        let mut g = DMatrix::<f64>::zeros(2, n);
        let mut x = DMatrix::<f64>::zeros(n, 2);
        let mut bdiag = DVector::<f64>::zeros(n);
        for (i, &e) in edges.iter().enumerate() {
            let len = m.edge_measure(e);
            let nrm = normals[i];
            g[(0, i)] = len * nrm[0] / area;
            g[(1, i)] = len * nrm[1] / area;
            let xs = m.edge_midpoint(e);
            x[(i, 0)] = xs[0] - xk[0];
            x[(i, 1)] = xs[1] - xk[1];
            let ann = nrm[0] * (a[0][0] * nrm[0] + a[0][1] * nrm[1])
                + nrm[1] * (a[1][0] * nrm[0] + a[1][1] * nrm[1]);
            bdiag[i] = self.alpha * self.alpha * len * ann / dists[i];
        }
        let amat = nalgebra::Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1]);
        let ag = DMatrix::from_fn(2, n, |r, c| {
            amat[(r, 0)] * g[(0, c)] + amat[(r, 1)] * g[(1, c)]
        });
        let consistency = g.transpose() * ag * area;
        let r = DMatrix::<f64>::identity(n, n) - &x * &g;
        let mut br = r.clone();
        for i in 0..n {
            for j in 0..n {
                br[(i, j)] *= bdiag[i];
            }
        }
        consistency + r.transpose() * br
    }
    /// The fluxes F_{K,σ}(u) of cell `k` (one per local edge), for the full unknown vector `u`.
    pub fn fluxes(&self, k: usize, a: &Tensor, u: &[f64]) -> Vec<f64> {
        let w = self.w_matrix(k, a);
        let uk = u[self.cell_dof(k)];
        let edges = self.mesh.cell_edges(k);
        let delta = DVector::from_iterator(edges.len(), edges.iter().map(|&e| u[e] - uk));
        let wd = w * delta;
        edges
            .iter()
            .enumerate()
            .map(|(i, &e)| -wd[i] / self.mesh.edge_measure(e))
            .collect()
    }
}

impl GradientDiscretisation for Hmm<'_> {
    fn name(&self) -> &'static str {
        "hmm"
    }
    fn mesh(&self) -> &PolyMesh {
        self.mesh
    }
    fn n_skeleton(&self) -> usize {
        self.mesh.n_edges()
    }
    fn n_interior(&self) -> usize {
        self.mesh.n_cells()
    }
    fn dof_entity(&self, dof: usize) -> super::Entity {
        let ne = self.mesh.n_edges();
        if dof < ne {
            super::Entity::Edge(dof)
        } else {
            super::Entity::Cell(dof - ne)
        }
    }
    fn n_local_interior(&self, _k: usize) -> usize {
        1
    }
    fn local_dofs(&self, k: usize, dofs: &mut Vec<usize>) {
        dofs.clear();
        dofs.push(self.cell_dof(k));
        dofs.extend_from_slice(self.mesh.cell_edges(k));
    }
    fn local_matrix(&self, k: usize, a: &Tensor, m: &mut DMatrix<f64>) {
        let w = self.w_matrix(k, a);
        let n = w.nrows();
        *m = DMatrix::zeros(n + 1, n + 1);
        let mut total = 0.0;
        for i in 0..n {
            let mut row = 0.0;
            for j in 0..n {
                m[(i + 1, j + 1)] = w[(i, j)];
                row += w[(i, j)];
            }
            // C = [−1 | I]: (Cᵀ W C)_{K,σ} = −(W 1)_σ
            m[(i + 1, 0)] = -row;
            m[(0, i + 1)] = -row;
            total += row;
        }
        m[(0, 0)] = total;
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Point) -> f64, b: &mut DVector<f64>) {
        let n = self.mesh.cell_edges(k).len();
        *b = DVector::zeros(n + 1);
        b[0] = self.mesh.measure(k) * f(self.mesh.centroid(k));
    }
    fn edge_trace_dofs(&self, e: usize, out: &mut Vec<PointDof>) {
        super::edge_unknown_trace(self.mesh, e, out);
    }
    fn obstacle_dofs(&self) -> Vec<PointDof> {
        (0..self.mesh.n_cells())
            .map(|k| PointDof {
                dof: self.cell_dof(k),
                point: self.mesh.centroid(k),
                measure: self.mesh.measure(k),
            })
            .collect()
    }
    fn cell_values(&self, u: &[f64]) -> Vec<f64> {
        (0..self.mesh.n_cells())
            .map(|k| u[self.cell_dof(k)])
            .collect()
    }
    fn cell_gradients(&self, u: &[f64]) -> Vec<Point> {
        let m = self.mesh;
        (0..m.n_cells())
            .map(|k| {
                let uk = u[self.cell_dof(k)];
                let mut g = [0.0; 2];
                for (i, &e) in m.cell_edges(k).iter().enumerate() {
                    let w = m.edge_measure(e) * (u[e] - uk);
                    g[0] += w * m.cell_normals(k)[i][0];
                    g[1] += w * m.cell_normals(k)[i][1];
                }
                [g[0] / m.measure(k), g[1] / m.measure(k)]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pentagon() -> PolyMesh {
        let v = vec![[0.0, 0.0], [1.0, 0.1], [1.2, 0.9], [0.5, 1.3], [-0.2, 0.8]];
        PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3, 4]]).unwrap()
    }

    #[test]
    fn local_matrix_is_symmetric_with_constants_in_kernel() {
        let m = pentagon();
        let s = Hmm::new(&m);
        let a = [[2.0, 0.3], [0.3, 1.0]];
        let mut mat = DMatrix::zeros(0, 0);
        s.local_matrix(0, &a, &mut mat);
        assert!((&mat - mat.transpose()).amax() < 1e-14);
        let ones = DVector::from_element(6, 1.0);
        assert!((&mat * ones).amax() < 1e-13);
        // positive definite on the complement of constants
        let eig = mat.symmetric_eigenvalues();
        let mut e: Vec<f64> = eig.iter().cloned().collect();
        e.sort_by(f64::total_cmp);
        assert!(e[0].abs() < 1e-13 && e[1] > 1e-3, "{e:?}");
    }

    #[test]
    fn affine_functions_are_reproduced_exactly() {
        // for u affine, ∇_K u = ∇u, R_K(u) = 0, and the energy equals |K| A∇u·∇u
        let m = pentagon();
        let s = Hmm::new(&m);
        let a = [[2.0, 0.3], [0.3, 1.0]];
        let grad = [0.7, -1.9];
        let ua = |p: Point| 0.4 + grad[0] * p[0] + grad[1] * p[1];
        let mut u = vec![0.0; s.n_unknowns()];
        for (e, ue) in u.iter_mut().enumerate().take(m.n_edges()) {
            *ue = ua(m.edge_midpoint(e));
        }
        u[s.cell_dof(0)] = ua(m.centroid(0));
        let g = s.cell_gradients(&u)[0];
        assert!((g[0] - grad[0]).abs() < 1e-13 && (g[1] - grad[1]).abs() < 1e-13);
        let mut dofs = Vec::new();
        s.local_dofs(0, &mut dofs);
        let ul = DVector::from_iterator(dofs.len(), dofs.iter().map(|&d| u[d]));
        let mut mat = DMatrix::zeros(0, 0);
        s.local_matrix(0, &a, &mut mat);
        let energy = ul.dot(&(&mat * &ul));
        let exact = m.measure(0)
            * (grad[0] * (a[0][0] * grad[0] + a[0][1] * grad[1])
                + grad[1] * (a[1][0] * grad[0] + a[1][1] * grad[1]));
        assert!((energy - exact).abs() < 1e-12 * exact.abs());
        // fluxes: F_{K,σ} = −A∇u·n_{K,σ}
        let f = s.fluxes(0, &a, &u);
        for (i, fi) in f.iter().enumerate() {
            let n = m.cell_normals(0)[i];
            let an = (a[0][0] * grad[0] + a[0][1] * grad[1]) * n[0]
                + (a[1][0] * grad[0] + a[1][1] * grad[1]) * n[1];
            assert!((fi + an).abs() < 1e-12, "{fi} vs {}", -an);
        }
    }
}
