//! The absolute part of the certificate: the size of u against the size of the data.
//!
//! The certificate's residuals are scaled by the size of the computed u (max_i |b_i| +
//! Σ_j |M_ij u_j|), so a huge u from a (near-)singular system can pass them. The continuous
//! problem bounds u by its data: for −div(A∇u) = f in Ω (diameter D, A ≥ λ I), with Dirichlet
//! values u_D, Neumann flux q and a barrier g, a maximum-principle estimate gives
//!
//!   ‖u‖∞ ≤ U := max(‖u_D‖∞, ‖g‖∞) + D² ‖f‖∞ / λ + D ‖q‖∞ / λ
//!
//! up to a constant of order one that depends on the geometry and on how much of ∂Ω is
//! Dirichlet. The certificate's `data_magnitude` = ‖u‖∞ / U must stay below
//! [`MAGNITUDE_LIMIT`] = 10⁶: a margin no sensible problem comes near, which an answer of 10¹⁰
//! on data of size 1 cannot pass.

use crate::assembly::DiscreteSystem;
use crate::mesh::SolveMesh;
use crate::problem::{BoundaryKind, Problem};
use crate::scheme::Tensor;
use crate::solver::constraints::Constraints;
use rayon::prelude::*;

pub use crate::vi::certificate::MAGNITUDE_LIMIT;

/// U of the module docs, from the data evaluated where the scheme evaluates it.
pub fn data_scale<M: SolveMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    problem: &Problem<D>,
    cons: Option<&Constraints>,
) -> f64 {
    let mesh = system.scheme().mesh();
    let (f_max, lambda) = (0..mesh.n_cells())
        .into_par_iter()
        .map(|k| {
            let x = mesh.cell_centre(k);
            let tag = mesh.cell_tag(k);
            let f = problem.source_in(x, x, tag);
            let a = problem.diffusion_in(x, tag);
            (f.abs(), smallest_eigenvalue(&a))
        })
        .reduce(|| (0.0, f64::INFINITY), |a, b| (a.0.max(b.0), a.1.min(b.1)));
    let mut q_max = 0.0f64;
    for i in 0..mesh.n_boundary_faces() {
        let e = mesh.boundary_face(i);
        let x = mesh.face_centre(e);
        if (problem.boundary)(x, mesh.face_tag(e)) == BoundaryKind::Neumann {
            q_max = q_max.max((problem.neumann)(x).abs());
        }
    }
    let diam = mesh.domain_diameter();
    let dirichlet = system
        .dirichlet()
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let barrier = cons.map_or(0.0, |c| {
        c.barrier.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    });
    dirichlet.max(barrier) + (diam * diam * f_max + diam * q_max) / lambda
}

/// λ, the smallest eigenvalue of the symmetric tensor `a`: the smallest diagonal entry of a
/// diagonal tensor (the usual case, exact); otherwise in 2D m − √(d² + a₀₁a₁₀) with m and d the
/// half sum and half difference of the diagonal, in 3D nalgebra's symmetric eigenvalues of a
/// stack matrix. It is evaluated on every cell, so it allocates nothing: a heap matrix per cell
/// serialised the threads on the allocator (1.6 s of a 2-thread solve on 6M tetrahedra).
fn smallest_eigenvalue<const D: usize>(a: &Tensor<D>) -> f64 {
    let diagonal = (0..D).all(|i| (0..D).all(|j| i == j || a[i][j] == 0.0));
    if diagonal {
        return (0..D).map(|i| a[i][i]).fold(f64::INFINITY, f64::min);
    }
    if D == 2 {
        let (m, d) = (0.5 * (a[0][0] + a[1][1]), 0.5 * (a[0][0] - a[1][1]));
        return m - (d * d + a[0][1] * a[1][0]).max(0.0).sqrt();
    }
    if D == 3 {
        let m = nalgebra::Matrix3::from_fn(|i, j| a[i][j]);
        return m.symmetric_eigenvalues().min();
    }
    let m = nalgebra::DMatrix::from_fn(D, D, |i, j| a[i][j]);
    m.symmetric_eigenvalues().min()
}

/// ‖u‖∞ / U (0 when u = 0).
pub fn data_magnitude(u: &[f64], scale: f64) -> f64 {
    let umax = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if umax == 0.0 { 0.0 } else { umax / scale }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vi::Certificate;

    #[test]
    fn the_smallest_eigenvalue_of_diagonal_and_full_tensors() {
        assert_eq!(smallest_eigenvalue(&[[3.0, 0.0], [0.0, 0.5]]), 0.5);
        assert_eq!(
            smallest_eigenvalue(&[[2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 1.5]]),
            1.5
        );
        // [[2, 1], [1, 2]]: eigenvalues 1 and 3
        assert!((smallest_eigenvalue(&[[2.0, 1.0], [1.0, 2.0]]) - 1.0).abs() < 1e-14);
        // a rotation of diag(1, 2, 5) about z by 45°: [[1.5, 0.5, 0], [0.5, 1.5, 0], [0, 0, 5]]
        let a = [[1.5, 0.5, 0.0], [0.5, 1.5, 0.0], [0.0, 0.0, 5.0]];
        assert!((smallest_eigenvalue(&a) - 1.0).abs() < 1e-14);
        // the general path in 3D agrees with the dynamic one
        let b = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.25], [0.5, 0.25, 2.0]];
        let d = nalgebra::DMatrix::from_fn(3, 3, |i, j| b[i][j])
            .symmetric_eigenvalues()
            .min();
        assert!((smallest_eigenvalue(&b) - d).abs() < 1e-13);
    }

    #[test]
    fn the_certificate_refuses_an_answer_far_larger_than_the_data() {
        let mesh = crate::mesh::generate::cartesian(8, 8).unwrap();
        let scheme = crate::scheme::Hmm::new(&mesh);
        let p = crate::problem::paper_test3(-20.0);
        let sol = crate::solver::solve_problem(&scheme, &p, &Default::default()).unwrap();
        // ψ is of size 1 and f = −20 on the unit square: U ≈ 1 + 2·20
        let scale = data_scale(&sol.system, &p, sol.constraints.as_ref());
        assert!(scale > 20.0 && scale < 100.0, "{scale}");
        let m = sol.result.certificate.data_magnitude;
        assert!(m > 0.0 && m < 1.0, "{m}");
        // the garbage: |u| ≈ 4.6e10 on data of size 1
        let bad = Certificate {
            data_magnitude: data_magnitude(&[-4.6e10], 1.0),
            ..Default::default()
        };
        assert!(bad.check(1e-10).is_err());
        assert_eq!(data_magnitude(&[0.0, 0.0], 0.0), 0.0);
    }
}
