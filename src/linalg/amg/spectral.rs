//! Bounds and estimates of the largest eigenvalue of D⁻¹A: for ω of the prolongator smoothing
//! and the interval of the Chebyshev smoother (see [`super`]).

use crate::budget::{AllocFailure, try_filled, try_vec};
#[cfg(test)]
use crate::linalg::csr::CsrMatrix;
use crate::linalg::csr::ROW_CHUNK;
use crate::linalg::pcg::dot;
use crate::linalg::rows::Rows;
use rayon::prelude::*;

/// Gershgorin bound of ρ(D⁻¹A): max_i Σ_j |a_ij| / a_ii.
pub(super) fn gershgorin<A: Rows + ?Sized>(a: &A, diag: &[f64]) -> f64 {
    (0..a.n_rows())
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| a.row(i).1.iter().map(|v| v.abs()).sum::<f64>() / diag[i])
        .reduce(|| 0.0, f64::max)
}

/// The largest Ritz value of `steps` Lanczos steps on D^{-1/2} A D^{-1/2} (similar to D⁻¹A),
/// from a fixed pseudo-random start: a lower bound of λ_max(D⁻¹A), usually close.
/// [`AllocFailure`] if its vectors cannot be allocated.
pub(super) fn lanczos_lambda_max<A: Rows + ?Sized>(
    a: &A,
    diag: &[f64],
    steps: usize,
) -> Result<f64, AllocFailure> {
    let n = a.n_rows();
    if n == 0 {
        return Ok(0.0);
    }
    let what = "the Lanczos vectors";
    let mut s: Vec<f64> = try_vec(n, what)?;
    s.extend(diag.iter().map(|d| 1.0 / d.sqrt()));
    // a deterministic start with components along every eigenvector (almost surely)
    let mut v: Vec<f64> = try_vec(n, what)?;
    v.extend((0..n as u64).map(|i| {
        let h = (i.wrapping_add(1)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
        (h as f64 / (1u64 << 53) as f64) - 0.5
    }));
    let nv = dot(&v, &v).sqrt();
    v.iter_mut().for_each(|x| *x /= nv);
    let mut v_prev = try_filled(n, 0.0, what)?;
    let mut u = try_filled(n, 0.0, what)?;
    let mut w = try_filled(n, 0.0, what)?;
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let mut beta = 0.0;
    for _ in 0..steps.min(n) {
        u.iter_mut()
            .zip(&v)
            .zip(&s)
            .for_each(|((u, v), s)| *u = v * s);
        a.mul_to(&u, &mut w);
        w.iter_mut()
            .zip(&s)
            .zip(&v_prev)
            .for_each(|((w, s), vp)| *w = *w * s - beta * vp);
        let alpha = dot(&w, &v);
        w.iter_mut().zip(&v).for_each(|(w, v)| *w -= alpha * v);
        alphas.push(alpha);
        beta = dot(&w, &w).sqrt();
        if !(beta > 1e-12 * alpha.abs()) {
            break;
        }
        betas.push(beta);
        std::mem::swap(&mut v_prev, &mut v);
        v.iter_mut().zip(&w).for_each(|(v, w)| *v = w / beta);
    }
    let k = alphas.len();
    let t = nalgebra::DMatrix::from_fn(k, k, |i, j| {
        if i == j {
            alphas[i]
        } else if i == j + 1 {
            betas[j]
        } else if j == i + 1 {
            betas[i]
        } else {
            0.0
        }
    });
    Ok(t.symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(0.0, f64::max))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// tridiag(−1, 2, −1) of order n.
    fn laplacian_1d(n: usize) -> CsrMatrix {
        let (mut row_ptr, mut cols, mut vals) = (vec![0], vec![], vec![]);
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                cols.push(j as u32);
                vals.push(if i == j { 2.0 } else { -1.0 });
            }
            row_ptr.push(cols.len());
        }
        CsrMatrix::new(n, n, row_ptr, cols, vals).unwrap()
    }

    #[test]
    fn bounds_of_the_largest_eigenvalue() {
        // D⁻¹A = A / 2 has the eigenvalues 1 − cos(kπ/(n + 1)), k = 1..n
        let n = 30;
        let a = laplacian_1d(n);
        let d = a.diagonal();
        let exact = 1.0 + (std::f64::consts::PI / (n + 1) as f64).cos();
        assert_eq!(gershgorin(&a, &d), 2.0);
        // n steps: the whole Krylov space, the exact value
        let full = lanczos_lambda_max(&a, &d, n).unwrap();
        assert!((full - exact).abs() < 1e-10, "{full} vs {exact}");
        // fewer steps: a Ritz value, below λ_max and close to it
        let few = lanczos_lambda_max(&a, &d, 8).unwrap();
        assert!(
            few <= exact + 1e-12 && few > 0.95 * exact,
            "{few} vs {exact}"
        );
        assert_eq!(lanczos_lambda_max(&laplacian_1d(0), &[], 5), Ok(0.0));
    }
}
