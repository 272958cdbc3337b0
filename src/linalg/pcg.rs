//! Preconditioned conjugate gradients for A x = b, A symmetric positive definite, with a
//! symmetric positive definite preconditioner M ≈ A (e.g. the multigrid cycle of
//! [`super::amg`]).
//!
//! From x₀, r₀ = b − A x₀, z₀ = M⁻¹ r₀, p₀ = z₀, each iteration k = 0, 1, … computes
//!
//!   q = A p_k,   α_k = (r_k·z_k) / (p_k·q),
//!   x_{k+1} = x_k + α_k p_k,   r_{k+1} = r_k − α_k q,
//!   z_{k+1} = M⁻¹ r_{k+1},   β_k = (r_{k+1}·z_{k+1}) / (r_k·z_k),   p_{k+1} = z_{k+1} + β_k p_k,
//!
//! and stops when ‖r_{k+1}‖₂ ≤ max(rtol ‖b‖₂, atol). x_k minimises the A-norm of the error over
//! x₀ + span{z₀, (M⁻¹A) z₀, …}; for A and M SPD, p·q > 0 and r·z > 0 until convergence, so
//! either failing (*breakdown*: A or M is not positive definite, or rounding has taken over)
//! is an error, as are a non-finite residual and the iteration cap. The recursively updated
//! r_k drifts from b − A x_k by rounding; the report gives the true residual, recomputed at
//! the end.
//!
//! The vector operations run on all cores for long vectors, in fixed chunks; the partial sums
//! of the dot products are added in chunk order, so results do not depend on the scheduling.

#[cfg(test)]
use super::csr::CsrMatrix;
use super::csr::{PAR_MIN_NNZ, ROW_CHUNK};
use super::rows::{Rows, dot_row};
use crate::budget::{try_copy, try_filled, try_vec};
use rayon::prelude::*;

/// An approximate inverse z = M⁻¹ r of a symmetric positive definite M. M does not change
/// once built; what an application needs besides (vectors) is a workspace the caller owns and
/// keeps between applications ([`Self::Work`]).
pub trait Preconditioner {
    /// The workspace of an application (`()` when none is needed). Its contents never change
    /// a result.
    type Work;
    /// Order of M.
    fn n(&self) -> usize;
    /// A workspace for this preconditioner.
    fn work(&self) -> Self::Work;
    /// z = M⁻¹ r (`r` and `z` have [`Self::n`] entries, else an error), with `work`.
    fn apply(&self, r: &[f64], z: &mut [f64], work: &mut Self::Work) -> crate::Result<()>;
}

/// M = I: plain conjugate gradients.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Identity(pub usize);

impl Preconditioner for Identity {
    type Work = ();
    fn n(&self) -> usize {
        self.0
    }
    fn work(&self) {}
    fn apply(&self, r: &[f64], z: &mut [f64], _: &mut ()) -> crate::Result<()> {
        check_len("identity preconditioner", self.0, r.len(), z.len())?;
        z.copy_from_slice(r);
        Ok(())
    }
}

/// M = diag(A) (Jacobi).
#[derive(Debug, Clone, PartialEq)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    /// The inverse diagonal of `a`; a diagonal entry that is not positive and finite is an
    /// error naming its row.
    pub fn new<A: Rows + ?Sized>(a: &A) -> crate::Result<Self> {
        let d = a.try_diagonal()?;
        if let Some(i) = d.iter().position(|&v| !(v > 0.0 && v.is_finite())) {
            return Err(crate::Error::Linear(format!(
                "Jacobi preconditioner: diagonal entry {} at row {i} is not positive",
                d[i]
            )));
        }
        let mut inv_diag = try_vec(d.len(), "the Jacobi preconditioner")?;
        inv_diag.extend(d.iter().map(|v| 1.0 / v));
        Ok(Jacobi { inv_diag })
    }
}

impl Preconditioner for Jacobi {
    type Work = ();
    fn n(&self) -> usize {
        self.inv_diag.len()
    }
    fn work(&self) {}
    fn apply(&self, r: &[f64], z: &mut [f64], _: &mut ()) -> crate::Result<()> {
        check_len("Jacobi preconditioner", self.n(), r.len(), z.len())?;
        zip_chunks2(z, r, &self.inv_diag, |z, r, d| {
            for ((zi, ri), di) in z.iter_mut().zip(r).zip(d) {
                *zi = ri * di;
            }
        });
        Ok(())
    }
}

/// The error of vectors whose lengths do not match the operator.
pub(crate) fn check_len(what: &str, n: usize, r: usize, z: usize) -> crate::Result<()> {
    if r != n || z != n {
        return Err(crate::Error::Linear(format!(
            "{what} of order {n} applied to vectors of lengths {r} and {z}"
        )));
    }
    Ok(())
}

/// Stopping rule and iteration cap of [`pcg`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcgOptions {
    /// Relative tolerance: stop when ‖b − A x‖₂ ≤ rtol ‖b‖₂ (or ≤ atol).
    pub rtol: f64,
    /// Absolute tolerance on ‖b − A x‖₂.
    pub atol: f64,
    /// Iteration cap; reaching it is an error.
    pub max_iter: usize,
}

impl Default for PcgOptions {
    fn default() -> Self {
        PcgOptions {
            rtol: 1e-10,
            atol: 0.0,
            max_iter: 500,
        }
    }
}

/// What [`pcg`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcgReport {
    /// Iterations performed (products with A after the initial residual).
    pub iterations: usize,
    /// ‖b − A x‖₂ of the returned x, recomputed from scratch.
    pub residual_norm: f64,
    /// ‖b − A x₀‖₂ of the initial guess.
    pub initial_residual_norm: f64,
}

/// The sizes of A, M, b and x agree and the tolerances are non-negative.
fn check_inputs<A: Rows + ?Sized>(
    a: &A,
    m_order: usize,
    b: &[f64],
    x: &[f64],
    opts: &PcgOptions,
) -> crate::Result<()> {
    let n = a.n_rows();
    if a.n_cols() != n || b.len() != n || x.len() != n || m_order != n {
        return Err(crate::Error::Linear(format!(
            "conjugate gradients: matrix {}×{}, preconditioner of order {}, b of length {}, x \
             of length {}",
            n,
            a.n_cols(),
            m_order,
            b.len(),
            x.len()
        )));
    }
    if !(opts.rtol >= 0.0 && opts.atol >= 0.0) {
        return Err(crate::Error::Linear(format!(
            "conjugate gradients: tolerances must be non-negative (rtol = {}, atol = {})",
            opts.rtol, opts.atol
        )));
    }
    Ok(())
}

/// The error of an iteration that failed: `what` happened at iteration `k`, with the residual
/// norm `res` reached (order `n`).
fn failure(n: usize, what: String, k: usize, res: f64) -> crate::Error {
    crate::Error::Linear(format!(
        "conjugate gradients (order {n}): {what} at iteration {k}, residual norm {res:e}"
    ))
}

/// Solves A x = b by preconditioned conjugate gradients (see the module documentation),
/// starting from the `x` given and leaving the solution in it; `work` is the preconditioner's
/// workspace (e.g. [`Preconditioner::work`], or one kept from an earlier solve).
///
/// Errors: mismatched lengths, a non-finite residual (NaN or infinite data), a breakdown
/// (pᵀAp ≤ 0 or rᵀM⁻¹r ≤ 0: A or M not positive definite), or no convergence within
/// `max_iter` iterations; each names the iteration and the residual reached. On error `x` holds
/// the last iterate.
pub fn pcg<A: Rows + ?Sized, M: Preconditioner + ?Sized>(
    a: &A,
    m: &M,
    work: &mut M::Work,
    b: &[f64],
    x: &mut [f64],
    opts: &PcgOptions,
) -> crate::Result<PcgReport> {
    check_inputs(a, m.n(), b, x, opts)?;
    let n = a.n_rows();
    let b_norm = dot(b, b).sqrt();
    let tol = (opts.rtol * b_norm).max(opts.atol);
    let mut r = try_filled(n, 0.0, "the residual of the conjugate gradients")?;
    a.residual_to(b, x, &mut r);
    let r0 = dot(&r, &r).sqrt();
    if !r0.is_finite() {
        return Err(failure(
            n,
            "non-finite initial residual (NaN or infinite data)".into(),
            0,
            r0,
        ));
    }
    let report = PcgReport {
        iterations: 0,
        residual_norm: r0,
        initial_residual_norm: r0,
    };
    if r0 <= tol {
        return Ok(report);
    }
    iterate(a, m, work, b, x, r, tol, opts.max_iter, report)
}

/// The iterations of [`pcg`] from the initial residual `r` = b − A x (above `tol`, its norm in
/// `report`), with the preconditioner `m` and its workspace `work`, until ‖r‖₂ ≤ `tol` or
/// `max_iter` iterations.
#[allow(clippy::too_many_arguments)]
fn iterate<A: Rows + ?Sized, M: Preconditioner + ?Sized>(
    a: &A,
    m: &M,
    work: &mut M::Work,
    b: &[f64],
    x: &mut [f64],
    mut r: Vec<f64>,
    tol: f64,
    max_iter: usize,
    mut report: PcgReport,
) -> crate::Result<PcgReport> {
    let n = a.n_rows();
    let mut z = try_filled(
        n,
        0.0,
        "the preconditioned residual of the conjugate gradients",
    )?;
    m.apply(&r, &mut z, work)?;
    let mut rz = dot(&r, &z);
    let mut r_norm = report.initial_residual_norm;
    let not_pd = |rz: f64| {
        format!("breakdown, rᵀM⁻¹r = {rz:e} (the preconditioner is not positive definite)")
    };
    if !(rz > 0.0 && rz.is_finite()) {
        return Err(failure(n, not_pd(rz), 0, r_norm));
    }
    let mut p = try_copy(&z, "the search direction of the conjugate gradients")?;
    // q = A p lives in z's storage: q is dead once r is updated, before z = M⁻¹ r is written
    // (one vector fewer)
    for k in 1..=max_iter {
        let q = &mut z;
        let pq = mul_dot(a, &p, q);
        if !(pq > 0.0 && pq.is_finite()) {
            return Err(failure(
                n,
                format!("breakdown, pᵀAp = {pq:e} (the matrix is not positive definite)"),
                k,
                r_norm,
            ));
        }
        let alpha = rz / pq;
        let rr = update_x_r(alpha, &p, q, x, &mut r);
        r_norm = rr.sqrt();
        report.iterations = k;
        if !r_norm.is_finite() {
            return Err(failure(n, "non-finite residual".into(), k, r_norm));
        }
        if r_norm <= tol {
            a.residual_to(b, x, &mut r);
            report.residual_norm = dot(&r, &r).sqrt();
            return Ok(report);
        }
        m.apply(&r, &mut z, work)?;
        let rz_new = dot(&r, &z);
        if !(rz_new > 0.0 && rz_new.is_finite()) {
            return Err(failure(n, not_pd(rz_new), k, r_norm));
        }
        let beta = rz_new / rz;
        rz = rz_new;
        zip_chunks2(&mut p, &z, &z, |p, z, _| {
            for (pi, zi) in p.iter_mut().zip(z) {
                *pi = zi + beta * *pi;
            }
        });
    }
    a.residual_to(b, x, &mut r);
    Err(failure(
        n,
        format!(
            "no convergence within {max_iter} iterations (target {tol:e}, true residual {:e})",
            dot(&r, &r).sqrt()
        ),
        max_iter,
        r_norm,
    ))
}

/// Vectors shorter than this are handled on the calling thread.
const PAR_MIN_LEN: usize = PAR_MIN_NNZ / 4;

/// Runs `f` on matching chunks of `y`, `u` and `v` (all of the same length), in parallel for
/// long vectors.
pub(crate) fn zip_chunks2<F>(y: &mut [f64], u: &[f64], v: &[f64], f: F)
where
    F: Fn(&mut [f64], &[f64], &[f64]) + Sync + Send,
{
    debug_assert!(u.len() == y.len() && v.len() == y.len());
    if y.len() < PAR_MIN_LEN {
        f(y, u, v);
    } else {
        y.par_chunks_mut(ROW_CHUNK)
            .zip(u.par_chunks(ROW_CHUNK))
            .zip(v.par_chunks(ROW_CHUNK))
            .for_each(|((y, u), v)| f(y, u, v));
    }
}

/// Sums `f(c)` over the chunks c = 0, 1, … of `ROW_CHUNK` entries of a vector of length `n`,
/// in chunk order (the same sum whatever the scheduling).
fn chunk_sum<F>(n: usize, f: F) -> f64
where
    F: Fn(usize) -> f64 + Sync + Send,
{
    let chunks = n.div_ceil(ROW_CHUNK);
    if n < PAR_MIN_LEN {
        (0..chunks).map(f).sum()
    } else {
        let parts: Vec<f64> = (0..chunks).into_par_iter().map(f).collect();
        parts.iter().sum()
    }
}

/// u·v.
pub(crate) fn dot(u: &[f64], v: &[f64]) -> f64 {
    debug_assert_eq!(u.len(), v.len());
    chunk_sum(u.len(), |c| {
        let s = c * ROW_CHUNK;
        let e = (s + ROW_CHUNK).min(u.len());
        u[s..e].iter().zip(&v[s..e]).map(|(a, b)| a * b).sum()
    })
}

/// q = A p, returning p·q (one sweep).
fn mul_dot<A: Rows + ?Sized>(a: &A, p: &[f64], q: &mut [f64]) -> f64 {
    let n = q.len();
    let part = |c: usize, qc: &mut [f64]| -> f64 {
        let i0 = c * ROW_CHUNK;
        let mut s = 0.0;
        a.for_rows(i0..i0 + qc.len(), |i, cols, vals| {
            let qi = dot_row(cols, vals, p);
            qc[i - i0] = qi;
            s += qi * p[i];
        });
        s
    };
    if n < PAR_MIN_LEN {
        q.chunks_mut(ROW_CHUNK)
            .enumerate()
            .map(|(c, qc)| part(c, qc))
            .sum()
    } else {
        let parts: Vec<f64> = q
            .par_chunks_mut(ROW_CHUNK)
            .enumerate()
            .map(|(c, qc)| part(c, qc))
            .collect();
        parts.iter().sum()
    }
}

/// x += α p, r −= α q, returning r·r (one sweep).
fn update_x_r(alpha: f64, p: &[f64], q: &[f64], x: &mut [f64], r: &mut [f64]) -> f64 {
    let part = |(x, r, p, q): (&mut [f64], &mut [f64], &[f64], &[f64])| -> f64 {
        let mut s = 0.0;
        for (((xi, ri), pi), qi) in x.iter_mut().zip(r.iter_mut()).zip(p).zip(q) {
            *xi += alpha * pi;
            *ri -= alpha * qi;
            s += *ri * *ri;
        }
        s
    };
    if x.len() < PAR_MIN_LEN {
        x.chunks_mut(ROW_CHUNK)
            .zip(r.chunks_mut(ROW_CHUNK))
            .zip(p.chunks(ROW_CHUNK))
            .zip(q.chunks(ROW_CHUNK))
            .map(|(((x, r), p), q)| part((x, r, p, q)))
            .sum()
    } else {
        let parts: Vec<f64> = x
            .par_chunks_mut(ROW_CHUNK)
            .zip(r.par_chunks_mut(ROW_CHUNK))
            .zip(p.par_chunks(ROW_CHUNK))
            .zip(q.par_chunks(ROW_CHUNK))
            .map(|(((x, r), p), q)| part((x, r, p, q)))
            .collect();
        parts.iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// max_i |a_i − b_i|.
    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max)
    }

    /// A small SPD matrix (lower CSC → CSR): tridiag(−1, 4, −1) plus couplings i ↔ i + 5 of
    /// −0.5 and a varying diagonal, n = 30; and its dense form.
    fn small() -> (CsrMatrix, nalgebra::DMatrix<f64>) {
        let n = 30;
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
        let mut col_ptr = vec![0];
        let (mut row_idx, mut values) = (vec![], vec![]);
        for j in 0..n {
            let mut push = |i: usize, v: f64| {
                row_idx.push(i);
                values.push(v);
                dense[(i, j)] = v;
                dense[(j, i)] = v;
            };
            push(j, 4.0 + (j % 3) as f64);
            if j + 1 < n {
                push(j + 1, -1.0);
            }
            if j + 5 < n {
                push(j + 5, -0.5);
            }
            col_ptr.push(row_idx.len());
        }
        (
            CsrMatrix::from_lower_csc(n, &col_ptr, &row_idx, &values).unwrap(),
            dense,
        )
    }

    #[test]
    fn plain_and_jacobi_cg_match_a_dense_solve() {
        let (a, dense) = small();
        let n = a.n_rows();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let exact = dense
            .clone()
            .cholesky()
            .unwrap()
            .solve(&nalgebra::DVector::from_column_slice(&b));
        let opts = PcgOptions {
            rtol: 1e-12,
            atol: 0.0,
            max_iter: 100,
        };
        let mut x = vec![0.0; n];
        let rep = pcg(&a, &Identity(n), &mut (), &b, &mut x, &opts).unwrap();
        let bn = dot(&b, &b).sqrt();
        assert!(rep.residual_norm <= 1e-12 * bn * 1.5, "{rep:?}");
        assert!(rep.iterations > 1 && rep.iterations <= n);
        let err = max_diff(&x, exact.as_slice());
        assert!(err < 1e-11, "{err}");
        // Jacobi, from a nonzero initial guess
        let mut x = vec![1.0; n];
        let rep = pcg(&a, &Jacobi::new(&a).unwrap(), &mut (), &b, &mut x, &opts).unwrap();
        assert!((rep.initial_residual_norm - dot(&b, &b).sqrt()).abs() > 0.1);
        let err = max_diff(&x, exact.as_slice());
        assert!(err < 1e-11, "{err}");
        // an exact initial guess: no iteration
        let mut x: Vec<f64> = exact.iter().copied().collect();
        let rep = run(&a, &b, &mut x, &PcgOptions { rtol: 1e-8, ..opts }).unwrap();
        assert_eq!(rep.iterations, 0);
        // the absolute tolerance alone
        let mut x = vec![0.0; n];
        let rep = run(
            &a,
            &b,
            &mut x,
            &PcgOptions {
                rtol: 0.0,
                atol: 1e-3,
                max_iter: 100,
            },
        )
        .unwrap();
        assert!(
            rep.residual_norm <= 1e-3 * 1.01 && rep.iterations < 20,
            "{rep:?}"
        );
    }

    /// Unpreconditioned CG with `opts` on A x = b, from `x`.
    fn run(a: &CsrMatrix, b: &[f64], x: &mut [f64], o: &PcgOptions) -> crate::Result<PcgReport> {
        pcg(a, &Identity(a.n_rows()), &mut (), b, x, o)
    }

    /// Unpreconditioned CG with the default options on A x = b, from `x`, with M = I of
    /// order `m`.
    fn plain(a: &CsrMatrix, m: usize, b: &[f64], x: &mut [f64]) -> crate::Result<PcgReport> {
        pcg(a, &Identity(m), &mut (), b, x, &PcgOptions::default())
    }

    #[test]
    fn failures_are_errors() {
        let (a, _) = small();
        let n = a.n_rows();
        let b = vec![1.0; n];
        // too few iterations
        let mut x = vec![0.0; n];
        let e = run(
            &a,
            &b,
            &mut x,
            &PcgOptions {
                rtol: 1e-12,
                atol: 0.0,
                max_iter: 2,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("no convergence within 2 iterations"), "{e}");
        // NaN in b or in x₀
        let mut bad = b.clone();
        bad[3] = f64::NAN;
        assert!(plain(&a, n, &bad, &mut x).is_err());
        let mut x0 = vec![0.0; n];
        x0[5] = f64::INFINITY;
        assert!(plain(&a, n, &b, &mut x0).is_err());
        // an indefinite matrix: breakdown pᵀAp ≤ 0
        let neg = CsrMatrix::new(
            n,
            n,
            a.row_ptr().to_vec(),
            a.col_idx().to_vec(),
            a.values().iter().map(|v| -v).collect(),
        )
        .unwrap();
        let mut x = vec![0.0; n];
        let e = plain(&neg, n, &b, &mut x).unwrap_err().to_string();
        assert!(e.contains("breakdown") && e.contains("iteration 1"), "{e}");
        // a negative definite preconditioner: breakdown rᵀM⁻¹r ≤ 0
        struct Minus(usize);
        impl Preconditioner for Minus {
            type Work = ();
            fn n(&self) -> usize {
                self.0
            }
            fn work(&self) {}
            fn apply(&self, r: &[f64], z: &mut [f64], _: &mut ()) -> crate::Result<()> {
                z.iter_mut().zip(r).for_each(|(z, r)| *z = -r);
                Ok(())
            }
        }
        let e = pcg(&a, &Minus(n), &mut (), &b, &mut x, &PcgOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("preconditioner is not positive definite"), "{e}");
        // mismatched lengths, negative tolerances
        assert!(plain(&a, n, &b[1..], &mut x).is_err());
        assert!(plain(&a, n + 1, &b, &mut x).is_err());
        let neg_tol = PcgOptions {
            rtol: -1.0,
            ..PcgOptions::default()
        };
        assert!(pcg(&a, &Identity(n), &mut (), &b, &mut x, &neg_tol).is_err());
        // a non-positive diagonal for Jacobi
        assert!(Jacobi::new(&neg).is_err());
        assert!(
            Identity(3)
                .apply(&[1.0; 3], &mut [0.0; 2], &mut ())
                .is_err()
        );
    }

    #[test]
    fn long_vectors_take_the_parallel_path() {
        // n above the sequential threshold: the chunked kernels agree with plain loops
        let n = 3 * PAR_MIN_LEN + 17;
        let u: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
        let plain: f64 = u.iter().zip(&v).map(|(a, b)| a * b).sum();
        assert!((dot(&u, &v) - plain).abs() < 1e-9 * plain.abs().max(1.0));
        // a diagonal matrix diag(1..n): CG converges in few iterations with Jacobi, in one
        let a = CsrMatrix::new(
            n,
            n,
            (0..=n).collect(),
            (0..n as u32).collect(),
            (0..n).map(|i| 1.0 + i as f64).collect(),
        )
        .unwrap();
        let mut x = vec![0.0; n];
        let rep = pcg(
            &a,
            &Jacobi::new(&a).unwrap(),
            &mut (),
            &u,
            &mut x,
            &PcgOptions::default(),
        )
        .unwrap();
        assert_eq!(rep.iterations, 1);
        assert!(
            x.iter()
                .enumerate()
                .all(|(i, xi)| (xi * (1.0 + i as f64) - u[i]).abs() < 1e-12)
        );
    }
}
