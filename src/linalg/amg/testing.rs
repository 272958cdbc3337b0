//! Test matrices and measures shared by the multigrid tests.

use super::{Amg, AmgOptions};
use crate::linalg::csr::CsrMatrix;
use crate::linalg::pcg::{PcgOptions, Preconditioner, dot, pcg};
use crate::linalg::rows::Rows;

/// −div(k∇u) on an m × m grid of unknowns with the 5-point stencil (homogeneous Dirichlet
/// conditions eliminated): couplings kx·h(k_p, k_q) in x and ky·h(k_p, k_q) in y, h the
/// harmonic mean; as the full CSR matrix.
pub(crate) fn grid(m: usize, kx: f64, ky: f64, coef: &dyn Fn(usize, usize) -> f64) -> CsrMatrix {
    let n = m * m;
    let harm = |a: f64, b: f64| 2.0 * a * b / (a + b);
    let mut col_ptr = vec![0];
    let (mut row_idx, mut values) = (Vec::new(), Vec::new());
    for j in 0..m {
        for i in 0..m {
            let c = coef(i, j);
            let k = |ii: usize, jj: usize, inside: bool| {
                if inside { harm(c, coef(ii, jj)) } else { c }
            };
            let west = k(i.wrapping_sub(1), j, i > 0);
            let east = k(i + 1, j, i + 1 < m);
            let south = k(i, j.wrapping_sub(1), j > 0);
            let north = k(i, j + 1, j + 1 < m);
            row_idx.push(j * m + i);
            values.push(kx * (west + east) + ky * (south + north));
            if i + 1 < m {
                row_idx.push(j * m + i + 1);
                values.push(-kx * east);
            }
            if j + 1 < m {
                row_idx.push((j + 1) * m + i);
                values.push(-ky * north);
            }
            col_ptr.push(row_idx.len());
        }
    }
    CsrMatrix::from_lower_csc(n, &col_ptr, &row_idx, &values).unwrap()
}

/// Fixes the unknowns for which `fixed` holds as the active-set solver does: their rows and
/// columns zeroed but for a unit diagonal.
pub(crate) fn fix(a: &CsrMatrix, fixed: &dyn Fn(usize) -> bool) -> CsrMatrix {
    let mut vals = a.values().to_vec();
    for i in 0..a.n_rows() {
        let r = a.row_ptr()[i]..a.row_ptr()[i + 1];
        for (v, &j) in vals[r.clone()].iter_mut().zip(&a.col_idx()[r]) {
            let j = j as usize;
            if fixed(i) || fixed(j) {
                *v = if i == j { 1.0 } else { 0.0 };
            }
        }
    }
    CsrMatrix::new(
        a.n_rows(),
        a.n_cols(),
        a.row_ptr().to_vec(),
        a.col_idx().to_vec(),
        vals,
    )
    .unwrap()
}

/// [`iterations_with`] a new hierarchy of `a`.
pub(crate) fn iterations(a: &CsrMatrix, opts: &AmgOptions) -> usize {
    iterations_with(a, &Amg::new(a, opts).unwrap())
}

/// The unknowns k of an m × m grid ([`grid`]) inside the disc of radius² `r2` about the
/// grid's centre (a contact zone).
pub(crate) fn disc(m: usize, r2: f64) -> impl Fn(usize) -> bool {
    move |k: usize| {
        let (x, y) = (
            (k % m) as f64 / m as f64 - 0.5,
            (k / m) as f64 / m as f64 - 0.5,
        );
        x * x + y * y < r2
    }
}

/// PCG iterations to ‖r‖ ≤ 1e-10 ‖b‖ with the preconditioner `p`, for b = A x* with x*
/// containing all frequencies; also checks the true residual.
pub(crate) fn iterations_with<P: Preconditioner + ?Sized>(a: &CsrMatrix, p: &P) -> usize {
    let n = a.n_rows();
    let xs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 1.0).collect();
    let mut b = vec![0.0; n];
    a.spmv(&xs, &mut b).unwrap();
    let mut x = vec![0.0; n];
    let opts = PcgOptions {
        rtol: 1e-10,
        atol: 0.0,
        max_iter: 200,
    };
    let rep = pcg(a, p, &mut p.work(), &b, &mut x, &opts).unwrap();
    assert!(rep.residual_norm <= 2e-10 * dot(&b, &b).sqrt(), "{rep:?}");
    let mut r = vec![0.0; n];
    a.residual_to(&b, &x, &mut r);
    assert!(
        dot(&r, &r).sqrt() <= 2e-10 * dot(&b, &b).sqrt(),
        "true residual"
    );
    rep.iterations
}
