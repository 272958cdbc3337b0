//! Sparse symmetric positive definite solves with faer: the symbolic Cholesky factorisation
//! (fill-reducing AMD ordering, elimination tree, supernodes) is computed once per pattern; each
//! solve only refactorises numerically.

use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// A lower-triangular CSC sparsity pattern and its symbolic Cholesky factorisation.
#[derive(Debug, Clone)]
pub struct SpdPattern {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicLlt<usize>,
}

impl SpdPattern {
    /// Builds the pattern from column pointers and (sorted) row indices of the lower triangle,
    /// and analyses it once.
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> crate::Result<Self> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = SymbolicLlt::try_new(pattern.as_ref(), Side::Lower)
            .map_err(|e| crate::Error::Linear(format!("symbolic Cholesky failed: {e:?}")))?;
        Ok(SpdPattern { pattern, symbolic })
    }
    /// Matrix dimension.
    pub fn n(&self) -> usize {
        self.pattern.nrows()
    }
    /// Number of stored entries (lower triangle).
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }
    /// Column pointers.
    pub fn col_ptr(&self) -> &[usize] {
        self.pattern.col_ptr()
    }
    /// Row indices.
    pub fn row_idx(&self) -> &[usize] {
        self.pattern.row_idx()
    }
    /// Numeric factorisation of the matrix with these `values` (same order as `row_idx`),
    /// reusing the symbolic analysis.
    pub fn factor(&self, values: &[f64]) -> crate::Result<SpdFactor> {
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let llt = Llt::try_new_with_symbolic(self.symbolic.clone(), a, Side::Lower).map_err(|e| {
            crate::Error::Linear(format!(
                "numeric Cholesky failed ({e:?}): the matrix is not numerically positive definite"
            ))
        })?;
        Ok(SpdFactor { llt })
    }
}

/// A numeric Cholesky factor.
pub struct SpdFactor {
    llt: Llt<usize, f64>,
}

impl SpdFactor {
    /// Solves A x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let col = faer::ColMut::from_slice_mut(b);
        self.llt.solve_in_place(col);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_tridiagonal_system_and_refactorises() {
        // lower triangle of tridiag(−1, 2, −1), n = 5
        let n = 5;
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for j in 0..n {
            row_idx.push(j);
            if j + 1 < n {
                row_idx.push(j + 1);
            }
            col_ptr.push(row_idx.len());
        }
        let p = SpdPattern::new(n, col_ptr, row_idx).unwrap();
        for scale in [1.0, 3.0] {
            let vals: Vec<f64> = p
                .row_idx()
                .iter()
                .enumerate()
                .map(|(i, _)| i)
                .collect::<Vec<_>>()
                .iter()
                .map(|&i| {
                    let j = p.col_ptr().iter().rposition(|&c| c <= i).unwrap();
                    if p.row_idx()[i] == j {
                        2.0 * scale
                    } else {
                        -scale
                    }
                })
                .collect();
            let f = p.factor(&vals).unwrap();
            let mut x = vec![1.0; n];
            f.solve_in_place(&mut x);
            // residual of A x = 1
            for i in 0..n {
                let mut ax = 2.0 * scale * x[i];
                if i > 0 {
                    ax -= scale * x[i - 1];
                }
                if i + 1 < n {
                    ax -= scale * x[i + 1];
                }
                assert!((ax - 1.0).abs() < 1e-13);
            }
        }
        // an indefinite matrix is an error, not a panic
        let mut vals = vec![-1.0; p.nnz()];
        vals[0] = -2.0;
        assert!(p.factor(&vals).is_err());
    }
}
