//! The solve on the coarsest level: a dense Cholesky factorisation A_L = L Lᵀ, once per
//! hierarchy, and two triangular solves per cycle.

use crate::linalg::rows::Rows;

/// The solver of the coarsest level.
#[derive(Debug, Clone)]
pub(super) enum CoarseSolve {
    /// The Cholesky factor L (A_L = L Lᵀ), its lower triangle packed row after row.
    Dense { n: usize, l: Vec<f64> },
    /// Coarsening stalled above [`DENSE_MAX`]: the level is only smoothed.
    Smooth,
}

impl CoarseSolve {
    /// Bytes of the factor.
    pub(super) fn memory_bytes(&self) -> usize {
        match self {
            CoarseSolve::Dense { l, .. } => std::mem::size_of_val(l.as_slice()),
            CoarseSolve::Smooth => 0,
        }
    }
}

/// The order up to which faer's dense Cholesky factorisation is unblocked (its default
/// `recursion_threshold`): no matrix product, and so no product workspace
/// ([`product_workspace`](crate::linalg::product_workspace)).
const FAER_LLT_RECURSION: usize = 64;

/// The dense Cholesky factor of the coarsest operator (faer), packed.
pub(super) fn dense_cholesky<A: Rows + ?Sized>(a: &A, level: usize) -> crate::Result<CoarseSolve> {
    let n = a.n_rows();
    if n == 0 {
        return Ok(CoarseSolve::Dense { n, l: Vec::new() });
    }
    // above faer's recursion threshold, the blocked factorisation's updates run its dense
    // product kernel, whose per-thread workspace is checked against the process's limits
    if n > FAER_LLT_RECURSION {
        crate::linalg::product_workspace::reserve(faer::get_global_parallelism(), "")?;
    }
    // the lower triangle only, factored in place (faer's `Llt::new` would copy it into a
    // second n × n matrix first: the same factorisation, twice the memory)
    let mut m = faer::Mat::<f64>::zeros(n, n);
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&j, &v) in cols.iter().zip(vals) {
            if j as usize <= i {
                m[(i, j as usize)] = v;
            }
        }
    }
    let par = faer::get_global_parallelism();
    use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
    // a column of n scalars, as in `Llt::new`
    let mut mem = faer::dyn_stack::MemBuffer::new(cholesky_in_place_scratch::<f64>(
        n,
        par,
        Default::default(),
    ));
    let stack = faer::dyn_stack::MemStack::new(&mut mem);
    cholesky_in_place(
        m.as_mut(),
        Default::default(),
        par,
        stack,
        Default::default(),
    )
    .map_err(|e| {
        crate::Error::Linear(format!(
            "multigrid setup: the coarsest operator (level {level}, order {n}) is not \
             numerically positive definite ({e:?}): neither is the matrix"
        ))
    })?;
    drop(mem);
    let mut l = Vec::with_capacity(n * (n + 1) / 2);
    for i in 0..n {
        for j in 0..=i {
            l.push(m[(i, j)]);
        }
    }
    Ok(CoarseSolve::Dense { n, l })
}

/// x = (L Lᵀ)⁻¹ b with L packed by rows: L y = b by rows, then Lᵀ x = y by columns of Lᵀ
/// (rows of L), both reading L contiguously.
pub(super) fn dense_solve(n: usize, l: &[f64], b: &[f64], x: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * (i + 1) / 2..(i + 1) * (i + 2) / 2];
        let mut s = b[i];
        for (lij, xj) in row[..i].iter().zip(&x[..i]) {
            s -= lij * xj;
        }
        x[i] = s / row[i];
    }
    for i in (0..n).rev() {
        let row = &l[i * (i + 1) / 2..(i + 1) * (i + 2) / 2];
        let xi = x[i] / row[i];
        x[i] = xi;
        for (lij, xj) in row[..i].iter().zip(&mut x[..i]) {
            *xj -= lij * xi;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::*;

    #[test]
    fn the_coarsest_solve_is_exact_and_rejects_an_indefinite_matrix() {
        let a = grid(12, 1.0, 0.5, &|i, j| 1.0 + ((i + j) % 3) as f64);
        let n = a.n_rows();
        let CoarseSolve::Dense { n: m, l } = dense_cholesky(&a, 2).unwrap() else {
            panic!("a dense factor was expected");
        };
        assert_eq!((m, l.len()), (n, n * (n + 1) / 2));
        let xs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        let mut b = vec![0.0; n];
        a.spmv(&xs, &mut b).unwrap();
        let mut x = vec![f64::NAN; n];
        dense_solve(n, &l, &b, &mut x);
        for (xi, si) in x.iter().zip(&xs) {
            assert!((xi - si).abs() < 1e-12, "{xi} vs {si}");
        }
        // off-diagonal entries larger than the diagonal: not positive definite
        let mut indef = a.clone();
        for v in indef.values_mut() {
            if *v < 0.0 {
                *v *= 10.0;
            }
        }
        let e = dense_cholesky(&indef, 3).unwrap_err().to_string();
        assert!(e.contains("level 3"), "{e}");
    }

    /// The in-place factorisation is faer's `Llt::new` on the same matrix, bit for bit, above
    /// faer's recursion threshold (order 144 > 64: the blocked path) and below it.
    #[test]
    fn the_in_place_factor_is_faers_llt_bit_for_bit() {
        for side in [12, 5] {
            let a = grid(side, 1.0, 0.3, &|i, j| 1.0 + ((i * 7 + j) % 5) as f64);
            let n = a.n_rows();
            let CoarseSolve::Dense { l, .. } = dense_cholesky(&a, 1).unwrap() else {
                panic!("a dense factor was expected");
            };
            let mut m = faer::Mat::<f64>::zeros(n, n);
            for i in 0..n {
                let (cols, vals) = a.row(i);
                for (&j, &v) in cols.iter().zip(vals) {
                    m[(i, j as usize)] = v;
                }
            }
            let llt = m.llt(faer::Side::Lower).unwrap();
            let mut k = 0;
            for i in 0..n {
                for j in 0..=i {
                    assert_eq!(
                        l[k].to_bits(),
                        llt.L()[(i, j)].to_bits(),
                        "({i}, {j}), n {n}"
                    );
                    k += 1;
                }
            }
        }
    }
}
