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
use crate::mesh::PolyMesh;
use crate::mesh::complex::{CellComplex, Vector, VertexAverage};
use nalgebra::{DMatrix, DVector};

/// The matrix W of the module docs for cell `k` of a cell–face complex of any dimension D, with
/// the constant tensor `a` = A_K and stabilisation parameter `alpha` (size n_σ × n_σ, local
/// faces in the order of [`CellComplex::cell_faces`]).
///
/// Nothing here depends on D: G is D × n_σ, X is n_σ × D, and the only geometry read is
/// |K|, x_K, |σ|, x_σ, n_{K,σ} and d_{K,σ}. The 2-D scheme ([`Hmm`]) calls it on a
/// [`PolyMesh`], the 3-D one (`Hmm<PolyMesh3, 3>`) on a
/// [`PolyMesh3`](crate::mesh3d::PolyMesh3); the tests also run it on a 3-D mesh of boxes.
pub fn local_form<const D: usize, M: CellComplex<D> + ?Sized>(
    mesh: &M,
    k: usize,
    a: &[[f64; D]; D],
    alpha: f64,
) -> DMatrix<f64> {
    let n = mesh.cell_faces(k).len();
    let (vol, xk) = mesh.cell_measure_centre(k);
    // Flat column-major work arrays in one allocation, and loops summing in the order of the
    // matrix products they replace (each entry summed over the inner index in increasing
    // order): the same bits as the nalgebra expression of the tests up to 5 faces, without
    // its dozen small allocations and generic products per cell (above 5 faces nalgebra's
    // blocked products round differently; see the test).
    // g: D × n (G), x: n × D (X), bd: n (B_K), ag: D × n (A_K G), r: n × n (I − X G)
    let mut work = vec![0.0; 3 * D * n + n + n * n];
    let (g, rest) = work.split_at_mut(D * n);
    let (x, rest) = rest.split_at_mut(n * D);
    let (bd, rest) = rest.split_at_mut(n);
    let (ag, r) = rest.split_at_mut(D * n);
    for i in 0..n {
        let face = mesh.cell_face_geometry(k, i, xk);
        let (len, nrm, dist, xs) = (face.measure, face.normal, face.dist, face.centre);
        for rr in 0..D {
            g[rr + D * i] = len * nrm[rr] / vol;
            x[i + n * rr] = xs[rr] - xk[rr];
        }
        // A_K n·n, summed in the order n_0 (A n)_0 + n_1 (A n)_1 + …
        let mut ann = 0.0;
        for rr in 0..D {
            let mut an = 0.0;
            for c in 0..D {
                an += a[rr][c] * nrm[c];
            }
            ann += nrm[rr] * an;
        }
        bd[i] = alpha * alpha * len * ann / dist;
    }
    for c in 0..n {
        for rr in 0..D {
            let mut v = 0.0;
            for j in 0..D {
                v += a[rr][j] * g[j + D * c];
            }
            ag[rr + D * c] = v;
        }
    }
    // R = I − X G
    for j in 0..n {
        for i in 0..n {
            let mut xg = x[i] * g[D * j];
            for rr in 1..D {
                xg += x[i + n * rr] * g[rr + D * j];
            }
            r[i + n * j] = if i == j { 1.0 } else { 0.0 } - xg;
        }
    }
    // W = |K| Gᵀ A_K G + Rᵀ B_K R
    let mut w = DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        for i in 0..n {
            let mut c = g[D * i] * ag[D * j];
            for rr in 1..D {
                c += g[rr + D * i] * ag[rr + D * j];
            }
            let mut s = r[n * i] * (r[n * j] * bd[0]);
            for l in 1..n {
                s += r[l + n * i] * (r[l + n * j] * bd[l]);
            }
            w[(i, j)] = c * vol + s;
        }
    }
    w
}

/// HMM on a mesh `M` of dimension `D`: by default the polygonal meshes of this crate
/// ([`PolyMesh`], D = 2); any [`CellComplex<D>`] with [`VertexAverage`] (for output) will do:
/// `Hmm::<PolyMesh3, 3>::with_alpha(&mesh, 1.0)` is HMM on general polyhedra (exact on
/// affine solutions where the faces are planar), and the tests run it on a 3-D mesh of boxes.
#[derive(Debug, Clone)]
pub struct Hmm<'a, M: ?Sized = PolyMesh, const D: usize = 2> {
    mesh: &'a M,
    alpha: f64,
}

impl<'a> Hmm<'a> {
    /// HMM on a polygonal mesh with the default stabilisation parameter α = 1.
    pub fn new(mesh: &'a PolyMesh) -> Self {
        Hmm { mesh, alpha: 1.0 }
    }
}

impl<'a, M: CellComplex<D> + ?Sized, const D: usize> Hmm<'a, M, D> {
    /// HMM with stabilisation parameter α (> 0).
    pub fn with_alpha(mesh: &'a M, alpha: f64) -> crate::Result<Self> {
        if !(alpha > 0.0 && alpha.is_finite()) {
            return Err(crate::Error::InvalidData(format!(
                "HMM stabilisation parameter alpha must be positive and finite, got {alpha}"
            )));
        }
        Ok(Hmm { mesh, alpha })
    }
    /// The global index of the cell unknown u_K.
    pub fn cell_dof(&self, k: usize) -> usize {
        self.mesh.n_faces() + k
    }
    /// The matrix W of the module docs for cell `k` (size n_σ × n_σ): [`local_form`] on this
    /// mesh.
    pub fn w_matrix(&self, k: usize, a: &Tensor<D>) -> DMatrix<f64> {
        local_form::<D, M>(self.mesh, k, a, self.alpha)
    }
    /// The fluxes F_{K,σ}(u) of cell `k` (one per local face), for the full unknown vector `u`.
    pub fn fluxes(&self, k: usize, a: &Tensor<D>, u: &[f64]) -> Vec<f64> {
        let w = self.w_matrix(k, a);
        let uk = u[self.cell_dof(k)];
        let faces = self.mesh.cell_faces(k);
        let delta = DVector::from_iterator(faces.len(), faces.iter().map(|&e| u[e as usize] - uk));
        let wd = w * delta;
        faces
            .iter()
            .enumerate()
            .map(|(i, &e)| -wd[i] / self.mesh.face_measure(e as usize))
            .collect()
    }
}

/// The local matrix Cᵀ W C of HMM on the unknowns [u_K, u_σ…] of a cell, from the matrix W
/// of [`local_form`] (on δ = (u_σ − u_K)_σ = C (u_K, u_σ…), C = [−1 | I]).
fn cell_face_matrix(w: &DMatrix<f64>, m: &mut DMatrix<f64>) {
    let n = w.nrows();
    super::zeroed_matrix(m, n + 1, n + 1);
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

impl<M: CellComplex<D> + VertexAverage + ?Sized, const D: usize> GradientDiscretisation<M, D>
    for Hmm<'_, M, D>
{
    fn name(&self) -> &'static str {
        "hmm"
    }
    fn mesh(&self) -> &M {
        self.mesh
    }
    fn n_skeleton(&self) -> usize {
        self.mesh.n_faces()
    }
    fn n_interior(&self) -> usize {
        self.mesh.n_cells()
    }
    fn dof_entity(&self, dof: usize) -> super::Entity {
        match dof.checked_sub(self.n_skeleton()) {
            Some(k) => super::Entity::Cell(k),
            None => super::Entity::Edge(dof),
        }
    }
    fn dof_point(&self, dof: usize) -> Vector<D> {
        match dof.checked_sub(self.n_skeleton()) {
            Some(k) => self.mesh.cell_centre(k),
            None => self.mesh.face_centre(dof),
        }
    }
    fn n_local_interior(&self, _k: usize) -> usize {
        1
    }
    fn local_dofs(&self, k: usize, dofs: &mut Vec<usize>) {
        dofs.clear();
        dofs.push(self.cell_dof(k));
        dofs.extend(self.mesh.cell_faces(k).iter().map(|&e| e as usize));
    }
    fn local_matrix(&self, k: usize, a: &Tensor<D>, m: &mut DMatrix<f64>) {
        cell_face_matrix(&self.w_matrix(k, a), m);
    }
    fn local_load(&self, k: usize, f: &dyn Fn(Vector<D>) -> f64, b: &mut DVector<f64>) {
        let n = self.mesh.cell_faces(k).len();
        super::zeroed_vector(b, n + 1);
        let (vol, xk) = self.mesh.cell_measure_centre(k);
        b[0] = vol * f(xk);
    }
    fn face_trace_dofs(&self, e: usize, out: &mut Vec<PointDof<D>>) {
        super::face_unknown_trace(self.mesh, e, out);
    }
    fn obstacle_dofs(&self) -> Vec<PointDof<D>> {
        (0..self.mesh.n_cells())
            .map(|k| PointDof {
                dof: self.cell_dof(k),
                point: self.mesh.cell_centre(k),
                measure: self.mesh.cell_measure(k),
            })
            .collect()
    }
    fn cell_values(&self, u: &[f64]) -> Vec<f64> {
        (0..self.mesh.n_cells())
            .map(|k| u[self.cell_dof(k)])
            .collect()
    }
    fn cell_gradients(&self, u: &[f64]) -> Vec<Vector<D>> {
        // ∇_K u = (1/|K|) Σ_σ |σ| (u_σ − u_K) n_{K,σ}
        let m = self.mesh;
        (0..m.n_cells())
            .map(|k| {
                let uk = u[self.cell_dof(k)];
                let mut g = [0.0; D];
                for (i, &e) in m.cell_faces(k).iter().enumerate() {
                    let e = e as usize;
                    let w = m.face_measure(e) * (u[e] - uk);
                    let nrm = m.cell_face_normal(k, i);
                    (0..D).for_each(|r| g[r] += w * nrm[r]);
                }
                g.map(|gr| gr / m.cell_measure(k))
            })
            .collect()
    }
    fn vertex_values(&self, u: &[f64]) -> Vec<f64> {
        self.mesh.cell_average_at_vertices(&self.cell_values(u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Point;

    fn pentagon() -> PolyMesh {
        let v = vec![[0.0, 0.0], [1.0, 0.1], [1.2, 0.9], [0.5, 1.3], [-0.2, 0.8]];
        PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3, 4]]).unwrap()
    }

    /// The nalgebra expression that [`local_form`] evaluates with plain loops.
    fn local_form_nalgebra(
        mesh: &PolyMesh,
        k: usize,
        a: &[[f64; 2]; 2],
        alpha: f64,
    ) -> DMatrix<f64> {
        let faces = mesh.cell_faces(k);
        let n = faces.len();
        let vol = mesh.cell_measure(k);
        let xk = mesh.cell_centre(k);
        let mut g = DMatrix::<f64>::zeros(2, n);
        let mut x = DMatrix::<f64>::zeros(n, 2);
        let mut bdiag = DVector::<f64>::zeros(n);
        for i in 0..n {
            let face = mesh.cell_face_geometry(k, i, xk);
            let (len, nrm, dist, xs) = (face.measure, face.normal, face.dist, face.centre);
            for r in 0..2 {
                g[(r, i)] = len * nrm[r] / vol;
                x[(i, r)] = xs[r] - xk[r];
            }
            let mut ann = 0.0;
            for r in 0..2 {
                let mut an = 0.0;
                for c in 0..2 {
                    an += a[r][c] * nrm[c];
                }
                ann += nrm[r] * an;
            }
            bdiag[i] = alpha * alpha * len * ann / dist;
        }
        let ag = DMatrix::from_fn(2, n, |r, c| {
            let mut v = 0.0;
            for j in 0..2 {
                v += a[r][j] * g[(j, c)];
            }
            v
        });
        let consistency = g.transpose() * ag * vol;
        let r = DMatrix::<f64>::identity(n, n) - &x * &g;
        let mut br = r.clone();
        for i in 0..n {
            for j in 0..n {
                br[(i, j)] *= bdiag[i];
            }
        }
        consistency + r.transpose() * br
    }

    /// The loops of `local_form` give the nalgebra expression's values on every cell of every
    /// generated family and the pentagon, with an anisotropic tensor and α ≠ 1: bit for bit
    /// up to 5 local faces (where nalgebra's products are loops in the same order), to
    /// round-off above.
    #[test]
    fn local_form_equals_the_matrix_expression_bit_for_bit() {
        let a = [[2.0, 0.3], [0.3, 1.0]];
        let mut meshes = crate::mesh::test_meshes();
        meshes.push(pentagon());
        let mut checked = [0, 0];
        for m in &meshes {
            for k in 0..m.n_cells() {
                for alpha in [1.0, 0.7] {
                    let w = local_form(m, k, &a, alpha);
                    let e = local_form_nalgebra(m, k, &a, alpha);
                    assert_eq!(w.shape(), e.shape());
                    let n = w.nrows();
                    for (p, q) in w.iter().zip(e.iter()) {
                        if n <= 5 {
                            assert_eq!(p.to_bits(), q.to_bits(), "cell {k}: {w} against {e}");
                        } else {
                            // above 5 × 5 nalgebra multiplies through matrixmultiply, whose
                            // blocked (and, where the CPU has it, fused) sums round otherwise
                            assert!(
                                (p - q).abs() <= 1e-15 * e.amax(),
                                "cell {k}: {w} against {e}"
                            );
                        }
                    }
                    checked[usize::from(n > 5)] += 1;
                }
            }
        }
        // both paths were met
        assert!(checked[0] > 0 && checked[1] > 0, "{checked:?}");
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
            let n = m.cell_normal(0, i);
            let an = (a[0][0] * grad[0] + a[0][1] * grad[1]) * n[0]
                + (a[1][0] * grad[0] + a[1][1] * grad[1]) * n[1];
            assert!((fi + an).abs() < 1e-12, "{fi} vs {}", -an);
        }
    }
}

/// HMM in three dimensions: [`local_form`] on a mesh of boxes (hexahedra with rectangular
/// faces), and a 3-D scheme implementing [`GradientDiscretisation`] on them, whose patch test
/// is solved through the trait alone.
#[cfg(test)]
mod tests_3d {
    use super::{Hmm, local_form};
    use crate::mesh::NO_CELL;
    use crate::mesh::complex::{CellComplex, Vector, VertexAverage};
    use crate::scheme::{Entity, GradientDiscretisation, Tensor};
    use nalgebra::{DMatrix, DVector};

    /// The boxes of the tensor grid with node coordinates `nodes[0..3]` (strictly increasing).
    /// Faces: those normal to x, then y, then z; local faces of a cell: −x, +x, −y, +y, −z, +z.
    struct Boxes {
        nodes: [Vec<f64>; 3],
        /// 32-bit face ids, as [`CellComplex::cell_faces`] returns them.
        cell_faces: Vec<[u32; 6]>,
        /// Per face: its normal axis, its lower corner index (i, j, k) and its cells.
        faces: Vec<(usize, [usize; 3], [usize; 2])>,
    }

    impl Boxes {
        fn new(nodes: [Vec<f64>; 3]) -> Self {
            let n = [nodes[0].len() - 1, nodes[1].len() - 1, nodes[2].len() - 1];
            let cell = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
            let mut faces = Vec::new();
            let mut face_id = std::collections::HashMap::new();
            for axis in 0..3 {
                let mut m = n;
                m[axis] += 1;
                for k in 0..m[2] {
                    for j in 0..m[1] {
                        for i in 0..m[0] {
                            let c = [i, j, k];
                            let mut lo = c;
                            let below = (c[axis] > 0).then(|| {
                                lo[axis] -= 1;
                                cell(lo[0], lo[1], lo[2])
                            });
                            let above = (c[axis] < n[axis]).then(|| cell(i, j, k));
                            let cells = match (below, above) {
                                (Some(b), Some(a)) => [b, a],
                                (Some(b), None) => [b, NO_CELL],
                                (None, Some(a)) => [a, NO_CELL],
                                (None, None) => unreachable!("a face has a cell"),
                            };
                            face_id.insert((axis, c), faces.len());
                            faces.push((axis, c, cells));
                        }
                    }
                }
            }
            let mut cell_faces = vec![[0; 6]; n[0] * n[1] * n[2]];
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let mut f = [0; 6];
                        for axis in 0..3 {
                            let mut c = [i, j, k];
                            f[2 * axis] = face_id[&(axis, c)] as u32;
                            c[axis] += 1;
                            f[2 * axis + 1] = face_id[&(axis, c)] as u32;
                        }
                        cell_faces[cell(i, j, k)] = f;
                    }
                }
            }
            Boxes {
                nodes,
                cell_faces,
                faces,
            }
        }
        fn n(&self) -> [usize; 3] {
            [0, 1, 2].map(|a| self.nodes[a].len() - 1)
        }
        fn cell_index(&self, k: usize) -> [usize; 3] {
            let n = self.n();
            [k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])]
        }
        fn width(&self, axis: usize, i: usize) -> f64 {
            self.nodes[axis][i + 1] - self.nodes[axis][i]
        }
        fn mid(&self, axis: usize, i: usize) -> f64 {
            0.5 * (self.nodes[axis][i] + self.nodes[axis][i + 1])
        }
    }

    impl CellComplex<3> for Boxes {
        fn n_cells(&self) -> usize {
            self.cell_faces.len()
        }
        fn n_vertices(&self) -> usize {
            self.nodes.iter().map(|x| x.len()).product()
        }
        fn n_faces(&self) -> usize {
            self.faces.len()
        }
        fn cell_faces(&self, k: usize) -> &[u32] {
            &self.cell_faces[k]
        }
        fn face_cells(&self, f: usize) -> [usize; 2] {
            self.faces[f].2
        }
        fn cell_measure(&self, k: usize) -> f64 {
            let c = self.cell_index(k);
            (0..3).map(|a| self.width(a, c[a])).product()
        }
        fn cell_centre(&self, k: usize) -> Vector<3> {
            let c = self.cell_index(k);
            [0, 1, 2].map(|a| self.mid(a, c[a]))
        }
        fn face_measure(&self, f: usize) -> f64 {
            let (axis, c, _) = self.faces[f];
            (0..3)
                .filter(|&a| a != axis)
                .map(|a| self.width(a, c[a]))
                .product()
        }
        fn face_centre(&self, f: usize) -> Vector<3> {
            let (axis, c, _) = self.faces[f];
            [0, 1, 2].map(|a| {
                if a == axis {
                    self.nodes[a][c[a]]
                } else {
                    self.mid(a, c[a])
                }
            })
        }
        fn cell_face_normal_dist(&self, k: usize, i: usize) -> (Vector<3>, f64) {
            let (axis, sign) = (i / 2, if i.is_multiple_of(2) { -1.0 } else { 1.0 });
            let mut nrm = [0.0; 3];
            nrm[axis] = sign;
            (nrm, 0.5 * self.width(axis, self.cell_index(k)[axis]))
        }
    }

    fn graded_boxes() -> Boxes {
        Boxes::new([
            vec![0.0, 0.1, 0.45, 1.0],
            vec![-1.0, -0.2, 0.3, 0.5],
            vec![0.0, 0.6, 0.7, 1.3],
        ])
    }

    const A: [[f64; 3]; 3] = [[3.0, 0.5, 0.2], [0.5, 2.0, 0.3], [0.2, 0.3, 1.0]];

    fn affine(p: Vector<3>) -> f64 {
        1.0 + 2.0 * p[0] - p[1] + 0.5 * p[2]
    }

    #[test]
    fn the_boxes_satisfy_the_identities_of_a_cell_complex() {
        // Σ_σ |σ| n_{K,σ} = 0 and Σ_σ |σ| d_{K,σ} = 3 |K|
        let m = graded_boxes();
        assert_eq!((m.n_cells(), m.n_faces()), (27, 108));
        for k in 0..m.n_cells() {
            let (mut s, mut vol) = ([0.0; 3], 0.0);
            for (i, &f) in m.cell_faces(k).iter().enumerate() {
                let f = f as usize;
                let (nrm, d) = m.cell_face_normal_dist(k, i);
                for r in 0..3 {
                    s[r] += m.face_measure(f) * nrm[r];
                }
                vol += m.face_measure(f) * d;
                assert!(m.face_cells(f).contains(&k));
            }
            assert!(s.iter().all(|v| v.abs() < 1e-15), "{s:?}");
            assert!((vol - 3.0 * m.cell_measure(k)).abs() < 1e-14);
        }
    }

    #[test]
    fn the_local_form_is_consistent_in_three_dimensions() {
        // W is symmetric, and for u affine W δ(u) = |K| Gᵀ A ∇u (the stabilisation vanishes):
        // the fluxes are −A∇u·n_{K,σ} exactly
        let m = graded_boxes();
        let grad = [2.0, -1.0, 0.5];
        for k in 0..m.n_cells() {
            let w = local_form(&m, k, &A, 1.0);
            assert!((&w - w.transpose()).amax() < 1e-13);
            let xk = m.cell_centre(k);
            let faces = m.cell_faces(k);
            let delta = DVector::from_iterator(
                6,
                faces
                    .iter()
                    .map(|&f| affine(m.face_centre(f as usize)) - affine(xk)),
            );
            let wd = &w * delta;
            for (i, &f) in faces.iter().enumerate() {
                let f = f as usize;
                let nrm = m.cell_face_normal(k, i);
                let flux: f64 = (0..3)
                    .map(|r| nrm[r] * (0..3).map(|c| A[r][c] * grad[c]).sum::<f64>())
                    .sum();
                // |σ| F_{K,σ} = −(W δ)_σ and F_{K,σ} = −A∇u·n
                assert!((wd[i] - m.face_measure(f) * flux).abs() < 1e-12, "{k} {i}");
            }
        }
    }

    impl VertexAverage for Boxes {
        fn cell_average_at_vertices(&self, cv: &[f64]) -> Vec<f64> {
            // the volume-weighted average of the boxes around each grid node
            let n = self.n();
            let mut sum = vec![(0.0, 0.0); (n[0] + 1) * (n[1] + 1) * (n[2] + 1)];
            for (k, &value) in cv.iter().enumerate() {
                let (c, vol) = (self.cell_index(k), self.cell_measure(k));
                for corner in 0..8 {
                    let v = [0, 1, 2].map(|a| c[a] + (corner >> a & 1));
                    let s = &mut sum[v[0] + (n[0] + 1) * (v[1] + (n[1] + 1) * v[2])];
                    *s = (s.0 + vol * value, s.1 + vol);
                }
            }
            sum.iter().map(|(s, w)| s / w).collect()
        }
    }

    /// Solves −div(A∇u) = f with u = g on the boundary faces for any scheme of any dimension,
    /// densely (a consumer written against the trait alone).
    fn dense_dirichlet_solve<M: CellComplex<D>, const D: usize>(
        s: &dyn GradientDiscretisation<M, D>,
        a: &Tensor<D>,
        f: &dyn Fn(Vector<D>) -> f64,
        g: &dyn Fn(Vector<D>) -> f64,
    ) -> Vec<f64> {
        let n = s.n_unknowns();
        let (mut mat, mut load) = (DMatrix::<f64>::zeros(n, n), vec![0.0; n]);
        let (mut dofs, mut m, mut b) = (Vec::new(), DMatrix::zeros(0, 0), DVector::zeros(0));
        for k in 0..s.mesh().n_cells() {
            s.local_dofs(k, &mut dofs);
            s.local_matrix(k, a, &mut m);
            s.local_load(k, f, &mut b);
            for (i, &gi) in dofs.iter().enumerate() {
                load[gi] += b[i];
                for (j, &gj) in dofs.iter().enumerate() {
                    mat[(gi, gj)] += m[(i, j)];
                }
            }
        }
        let mut fixed = crate::vi::FixedValues::free(n).unwrap();
        let mut trace = Vec::new();
        for e in (0..s.mesh().n_faces()).filter(|&e| s.mesh().face_cells(e)[1] == NO_CELL) {
            s.face_trace_dofs(e, &mut trace);
            trace.iter().for_each(|t| fixed.set(t.dof, g(t.point)));
        }
        let free: Vec<usize> = (0..n).filter(|&d| !fixed.is_fixed(d)).collect();
        let sys = DMatrix::from_fn(free.len(), free.len(), |i, j| mat[(free[i], free[j])]);
        let rhs = DVector::from_fn(free.len(), |i, _| {
            let lifted: f64 = (0..n)
                .map(|d| mat[(free[i], d)] * fixed.get(d).unwrap_or(0.0))
                .sum();
            load[free[i]] - lifted
        });
        let x = sys.cholesky().expect("SPD").solve(&rhs);
        let mut u: Vec<f64> = fixed.iter().map(|v| v.unwrap_or(0.0)).collect();
        free.iter().enumerate().for_each(|(i, &d)| u[d] = x[i]);
        u
    }

    #[test]
    fn affine_solutions_are_reproduced_exactly_in_three_dimensions() {
        // −div(A∇u) = 0 with u affine on the boundary faces: the discrete solution is the
        // affine function at every x_K and x_σ and its gradient is exact (the patch test),
        // with the scheme used through the trait only
        let m = graded_boxes();
        let s = Hmm::<Boxes, 3>::with_alpha(&m, 1.0).unwrap();
        let u = dense_dirichlet_solve(&s, &A, &|_| 0.0, &affine);
        for (d, ud) in u.iter().enumerate() {
            let x = match s.dof_entity(d) {
                Entity::Edge(f) => m.face_centre(f),
                Entity::Cell(k) => m.cell_centre(k),
                Entity::Vertex(_) => unreachable!("HMM has no vertex unknown"),
            };
            assert!((ud - affine(x)).abs() < 1e-10, "{d}: {ud} vs {}", affine(x));
        }
        for g in s.cell_gradients(&u) {
            assert!((g[0] - 2.0).abs() < 1e-10 && (g[1] + 1.0).abs() < 1e-10);
            assert!((g[2] - 0.5).abs() < 1e-10);
        }
        // a constant source: Σ_K |K| f = the total load, and the obstacle unknowns are the cells
        let obstacle = s.obstacle_dofs();
        assert_eq!(obstacle.len(), m.n_cells());
        let volume: f64 = obstacle.iter().map(|p| p.measure).sum();
        assert!((volume - 1.0 * 1.5 * 1.3).abs() < 1e-14);
        let ones = vec![1.0; s.n_unknowns()];
        assert!(
            s.vertex_values(&ones)
                .iter()
                .all(|v| (v - 1.0).abs() < 1e-14)
        );
        assert_eq!(s.vertex_values(&ones).len(), 4 * 4 * 4);
    }
}
