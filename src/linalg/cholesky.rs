//! The sparse Cholesky factorisation A = P⁻¹ L Lᵀ P⁻ᵀ of a symmetric positive definite matrix:
//! the symbolic analysis ([`SpdPattern`], once per pattern), the numeric factorisation
//! ([`SpdPattern::factor`], once per set of values) and the triangular solves
//! ([`SpdFactor::solve_in_place`]).

use super::ordering::{Ordering, nested_dissection};
use crate::budget::{AllocFailure, try_resize};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Side};
use std::sync::Arc;

/// Scratch memory of the numeric factorisation, with the size and alignment it was made for.
type Scratch = (MemBuffer, usize, usize);

/// The memory of the numeric factorisation, owned by the caller and kept between
/// factorisations: the values of L and faer's scratch memory. [`SpdPattern::factor`] writes
/// the factor into it (growing it when the pattern needs more), so a refactorisation reuses
/// the same memory instead of mapping (and page-faulting) hundreds of megabytes anew, and the
/// factor it returns borrows it. Its contents never change a result: every value of L is
/// written by the factorisation before it is read.
#[derive(Default)]
pub struct CholeskyWork {
    /// The values of L (the last factor's).
    values: Vec<f64>,
    /// faer's scratch memory of the numeric factorisation.
    scratch: Option<Scratch>,
}

impl std::fmt::Debug for CholeskyWork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskyWork")
            .field("bytes", &self.memory_bytes())
            .finish()
    }
}

impl CholeskyWork {
    /// Empty: the first factorisation allocates.
    pub fn new() -> Self {
        Self::default()
    }
    /// Bytes held (values of L and scratch memory).
    pub fn memory_bytes(&self) -> usize {
        self.values.capacity() * std::mem::size_of::<f64>()
            + self.scratch.as_ref().map_or(0, |s| s.1)
    }
}

/// Threads of the numeric factorisation and the triangular solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FactorThreads {
    /// One thread (the default; the assembly still runs on every core, with rayon). Chosen by
    /// measurement against [`FactorThreads::Global`]: `replication/BENCHMARKS.md`
    /// ("Measurements behind the defaults", and the lever table of variant `nested-par`).
    #[default]
    Sequential,
    /// faer's global parallelism (`faer::get_global_parallelism()`, rayon by default).
    Global,
}

impl FactorThreads {
    fn par(self) -> faer::Par {
        match self {
            FactorThreads::Sequential => faer::Par::Seq,
            FactorThreads::Global => faer::get_global_parallelism(),
        }
    }
}

/// A lower-triangular CSC sparsity pattern and its symbolic Cholesky factorisation (absent
/// for a pattern built by [`SpdPattern::without_factorisation`], whose matrices are solved
/// iteratively).
#[derive(Clone)]
pub struct SpdPattern {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: Option<Arc<SymbolicCholesky<usize>>>,
    threads: FactorThreads,
}

impl std::fmt::Debug for SpdPattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpdPattern")
            .field("n", &self.n())
            .field("nnz", &self.nnz())
            .field("factor_len", &self.factor_len())
            .finish()
    }
}

/// The symbolic analysis of the lower triangle `pattern` under `ordering`: the permutation P,
/// the elimination tree of P A Pᵀ, the pattern of L and its supernodes.
fn symbolic_factorisation(
    pattern: &SymbolicSparseColMat<usize>,
    ordering: Ordering,
) -> crate::Result<SymbolicCholesky<usize>> {
    // faer's allocations failing are the typed out-of-memory error; their size is not known,
    // so it gives the size of the pattern, a lower bound
    let err = |e: faer::sparse::FaerError| match e {
        faer::sparse::FaerError::OutOfMemory => crate::Error::from(AllocFailure {
            what: "the symbolic Cholesky factorisation".into(),
            bytes: 8 * (pattern.row_idx().len() + pattern.ncols() + 1) as u64,
        }),
        e => crate::Error::Linear(format!("symbolic Cholesky failed: {e:?}")),
    };
    match ordering {
        Ordering::Amd => factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(err),
        Ordering::NestedDissection => {
            let n = pattern.nrows();
            // fwd[new] = old, inv[old] = new
            let fwd = nested_dissection(n, pattern.col_ptr(), pattern.row_idx());
            let mut inv = vec![0usize; n];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old] = new;
            }
            let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
            factorize_symbolic_cholesky(
                pattern.as_ref(),
                Side::Lower,
                SymmetricOrdering::Custom(perm),
                Default::default(),
            )
            .map_err(err)
        }
    }
}

/// The kept scratch memory when it is large and aligned enough for `req`, new memory otherwise.
fn scratch_for(kept: Option<Scratch>, req: StackReq) -> crate::Result<Scratch> {
    match kept {
        Some((m, size, align)) if size >= req.size_bytes() && align >= req.align_bytes() => {
            Ok((m, size, align))
        }
        _ => Ok((
            MemBuffer::try_new(req).map_err(|_| AllocFailure {
                what: "the scratch memory of the numeric Cholesky factorisation".into(),
                bytes: req.size_bytes() as u64,
            })?,
            req.size_bytes(),
            req.align_bytes(),
        )),
    }
}

impl SpdPattern {
    /// Builds the pattern from column pointers and (sorted) row indices of the lower triangle,
    /// and analyses it once with the default ordering (AMD).
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> crate::Result<Self> {
        Self::with_ordering(n, col_ptr, row_idx, Ordering::default())
    }
    /// As [`SpdPattern::new`] with the given fill-reducing ordering.
    pub fn with_ordering(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        ordering: Ordering,
    ) -> crate::Result<Self> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = symbolic_factorisation(&pattern, ordering)?;
        Ok(SpdPattern {
            pattern,
            symbolic: Some(Arc::new(symbolic)),
            threads: FactorThreads::default(),
        })
    }
    /// The pattern alone, without the symbolic analysis (for iterative solves): [`Self::factor`]
    /// then fails and [`Self::factor_len`] is 0.
    pub fn without_factorisation(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> crate::Result<Self> {
        Ok(SpdPattern {
            pattern: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            symbolic: None,
            threads: FactorThreads::default(),
        })
    }
    /// Whether the symbolic factorisation was computed.
    pub fn has_factorisation(&self) -> bool {
        self.symbolic.is_some()
    }
    /// Sets the threads of the numeric factorisations and solves.
    pub fn with_threads(mut self, threads: FactorThreads) -> Self {
        self.threads = threads;
        self
    }
    /// Matrix dimension.
    pub fn n(&self) -> usize {
        self.pattern.nrows()
    }
    /// Number of stored entries (lower triangle).
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }
    /// Number of stored values of the Cholesky factor (its fill, supernodal blocks included).
    pub fn factor_len(&self) -> usize {
        self.symbolic.as_ref().map_or(0, |s| s.len_val())
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
    /// reusing the symbolic analysis: the values of L with P A Pᵀ = L Lᵀ, computed
    /// supernode by supernode in the order of the elimination tree, into `work` (whose memory
    /// is reused from the previous factorisation); the factor borrows it.
    pub fn factor<'w>(
        &'w self,
        values: &[f64],
        work: &'w mut CholeskyWork,
    ) -> crate::Result<SpdFactor<'w>> {
        let Some(symbolic) = &self.symbolic else {
            return Err(crate::Error::Linear(
                "no symbolic factorisation: this pattern was built for iterative solves".into(),
            ));
        };
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let par = self.threads.par();
        let len = symbolic.len_val();
        let l_values = &mut work.values;
        l_values.clear();
        try_resize(l_values, len, 0.0, "the Cholesky factor")?;
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let kept = work.scratch.take();
        let mem = work.scratch.insert(scratch_for(kept, req)?);
        // the supernodal updates run faer's dense product kernel, whose per-thread workspace
        // is checked against the process's limits first (the simplicial one runs none)
        if let SymbolicCholeskyRaw::Supernodal(_) = symbolic.raw() {
            super::product_workspace::reserve(
                par,
                "an iterative linear solver (`--linear iterative`)",
            )?;
        }
        symbolic
            .factorize_numeric_llt(
                l_values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem.0),
                Default::default(),
            )
            .map_err(|e| {
                crate::Error::Linear(format!(
                    "numeric Cholesky failed ({e:?}): the condensed matrix of order {} is \
                     singular or not numerically positive definite (a part of the mesh without \
                     Dirichlet unknowns or active barrier, or a degenerate cell)",
                    self.n()
                ))
            })?;
        Ok(SpdFactor {
            symbolic,
            values: &work.values,
            par,
        })
    }
}

impl SpdPattern {
    /// The factor that the last [`Self::factor`] of this pattern left in `work`, to solve
    /// with again without factorising: an error if `work` holds no factor of this pattern's
    /// size (none yet, or one of another pattern).
    pub fn factored<'w>(&'w self, work: &'w CholeskyWork) -> crate::Result<SpdFactor<'w>> {
        match &self.symbolic {
            Some(symbolic) if work.values.len() == symbolic.len_val() => Ok(SpdFactor {
                symbolic,
                values: &work.values,
                par: self.threads.par(),
            }),
            _ => Err(crate::Error::Internal(
                "no factor of this pattern in the Cholesky workspace".into(),
            )),
        }
    }
}

/// A numeric Cholesky factor: the symbolic analysis of its pattern and the values of L, held
/// in the caller's [`CholeskyWork`].
pub struct SpdFactor<'w> {
    symbolic: &'w SymbolicCholesky<usize>,
    values: &'w [f64],
    par: faer::Par,
}

impl SpdFactor<'_> {
    /// Solves A x = b in place: x = Pᵀ L⁻ᵀ L⁻¹ P b (a forward and a backward triangular solve
    /// between the two permutations).
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let par = self.par;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        let col = faer::ColMut::from_slice_mut(b);
        LltRef::new(self.symbolic, self.values).solve_in_place_with_conj(
            Conj::No,
            col.as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lower triangle of `scale` · tridiag(−1, 2, −1) of order n, by columns.
    fn tridiagonal(n: usize) -> SpdPattern {
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for j in 0..n {
            row_idx.push(j);
            if j + 1 < n {
                row_idx.push(j + 1);
            }
            col_ptr.push(row_idx.len());
        }
        SpdPattern::new(n, col_ptr, row_idx).unwrap()
    }

    /// The values of `scale` · tridiag(−1, 2, −1) on the pattern `p` (with a diagonal varying
    /// with the row, so that the factors of different scales differ everywhere).
    fn tridiagonal_values(p: &SpdPattern, scale: f64) -> Vec<f64> {
        let mut vals = Vec::with_capacity(p.nnz());
        for j in 0..p.n() {
            for &i in &p.row_idx()[p.col_ptr()[j]..p.col_ptr()[j + 1]] {
                vals.push(if i == j {
                    (2.0 + 0.01 * j as f64) * scale
                } else {
                    -scale
                });
            }
        }
        vals
    }

    #[test]
    fn solves_a_tridiagonal_system_and_refactorises() {
        let n = 5;
        let p = tridiagonal(n);
        let mut work = CholeskyWork::new();
        for scale in [1.0, 3.0] {
            let vals = tridiagonal_values(&p, scale);
            let f = p.factor(&vals, &mut work).unwrap();
            let mut x = vec![1.0; n];
            f.solve_in_place(&mut x);
            // residual of A x = 1
            for i in 0..n {
                let mut ax = (2.0 + 0.01 * i as f64) * scale * x[i];
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
        assert!(p.factor(&vals, &mut work).is_err());
        // a pattern without symbolic analysis cannot be factorised
        let bare = SpdPattern::without_factorisation(n, p.col_ptr().to_vec(), p.row_idx().to_vec())
            .unwrap();
        assert!(!bare.has_factorisation());
        assert!(
            bare.factor(&tridiagonal_values(&p, 1.0), &mut work)
                .is_err()
        );
    }

    /// The solution of A x = b for the tridiagonal matrix of `scale`, factorised in `work`.
    fn solve(p: &SpdPattern, scale: f64, work: &mut CholeskyWork) -> Vec<f64> {
        let mut x: Vec<f64> = (0..p.n()).map(|i| (i as f64 * 0.7).sin() + 1.5).collect();
        p.factor(&tridiagonal_values(p, scale), work)
            .unwrap()
            .solve_in_place(&mut x);
        x
    }

    #[test]
    fn a_reused_workspace_gives_the_bits_of_a_fresh_one() {
        let p = tridiagonal(3000);
        // two solves through fresh workspaces: the same bits
        let fresh = solve(&p, 2.0, &mut CholeskyWork::new());
        assert_eq!(fresh, solve(&p, 2.0, &mut CholeskyWork::new()));
        // a workspace that factorised other values (and failed once) gives them again, and
        // keeps its memory: no growth from one factorisation to the next
        let mut work = CholeskyWork::new();
        let other = solve(&p, 5.0, &mut work);
        assert_ne!(other, fresh);
        let bytes = work.memory_bytes();
        assert!(bytes >= p.factor_len() * 8, "{bytes}");
        let mut indefinite = tridiagonal_values(&p, 1.0);
        indefinite[0] = -1.0;
        assert!(p.factor(&indefinite, &mut work).is_err());
        assert_eq!(solve(&p, 2.0, &mut work), fresh);
        assert_eq!(solve(&p, 2.0, &mut work), fresh);
        assert_eq!(work.memory_bytes(), bytes);
        // a workspace grown by a larger pattern serves a smaller one
        let small = tridiagonal(40);
        assert_eq!(
            solve(&small, 2.0, &mut work),
            solve(&small, 2.0, &mut CholeskyWork::new())
        );
    }
}
