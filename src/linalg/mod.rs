//! Sparse symmetric positive definite solves with faer: the symbolic Cholesky factorisation
//! (fill-reducing ordering, elimination tree, supernodes) is computed once per pattern; each
//! solve only refactorises numerically.
//!
//! Two fill-reducing orderings are available ([`Ordering`]): faer's approximate minimum degree
//! (the default) and a nested dissection by breadth-first level-set separators
//! ([`nested_dissection`]), which needs no coordinates.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Side};
use std::sync::{Arc, Mutex};

/// Buffers kept between factorisations: the values of a dropped factor and the scratch
/// memory, so that a refactorisation does not map (and page-fault) hundreds of megabytes anew.
type Pool = Arc<Mutex<(Vec<f64>, Option<(MemBuffer, usize, usize)>)>>;

/// The fill-reducing ordering of the symbolic factorisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Ordering {
    /// faer's approximate minimum degree (AMD).
    #[default]
    Amd,
    /// Nested dissection with breadth-first level-set separators ([`nested_dissection`]).
    NestedDissection,
}

/// Threads of the numeric factorisation and the triangular solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FactorThreads {
    /// One thread (the default). On the 2-core machine of the benchmark the sequential
    /// supernodal factorisation was faster than faer's parallel one on most cases, by up to
    /// about 2× around 10⁵ cells and by little at 10⁶ (`replication/BENCHMARKS.md`, lever
    /// table of variant `nested-par`); the assembly still runs on every core (rayon).
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

/// A lower-triangular CSC sparsity pattern and its symbolic Cholesky factorisation.
#[derive(Clone)]
pub struct SpdPattern {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: Arc<SymbolicCholesky<usize>>,
    pool: Pool,
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
        let err = |e: faer::sparse::FaerError| {
            crate::Error::Linear(format!("symbolic Cholesky failed: {e:?}"))
        };
        let symbolic = match ordering {
            Ordering::Amd => factorize_symbolic_cholesky(
                pattern.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                Default::default(),
            )
            .map_err(err)?,
            Ordering::NestedDissection => {
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
                .map_err(err)?
            }
        };
        Ok(SpdPattern {
            pattern,
            symbolic: Arc::new(symbolic),
            pool: Pool::default(),
            threads: FactorThreads::default(),
        })
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
        self.symbolic.len_val()
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
        let par = self.threads.par();
        let len = self.symbolic.len_val();
        let (mut l_values, mem) = match self.pool.lock() {
            Ok(mut p) => (std::mem::take(&mut p.0), p.1.take()),
            Err(_) => (Vec::new(), None),
        };
        l_values.clear();
        l_values.resize(len, 0.0);
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = match mem {
            Some((m, size, align)) if size >= req.size_bytes() && align >= req.align_bytes() => {
                (m, size, align)
            }
            _ => (
                MemBuffer::try_new(req)
                    .map_err(|e| crate::Error::Linear(format!("numeric Cholesky: {e:?}")))?,
                req.size_bytes(),
                req.align_bytes(),
            ),
        };
        let res = self
            .symbolic
            .factorize_numeric_llt(
                &mut l_values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem.0),
                Default::default(),
            )
            .map(|_| ());
        if let Ok(mut p) = self.pool.lock() {
            p.1 = Some(mem);
        }
        res.map_err(|e| {
            crate::Error::Linear(format!(
                "numeric Cholesky failed ({e:?}): the matrix is not numerically positive definite"
            ))
        })?;
        Ok(SpdFactor {
            symbolic: self.symbolic.clone(),
            values: l_values,
            pool: self.pool.clone(),
            par,
        })
    }
}

/// A numeric Cholesky factor.
pub struct SpdFactor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    pool: Pool,
    par: faer::Par,
}

impl Drop for SpdFactor {
    fn drop(&mut self) {
        if let Ok(mut p) = self.pool.lock() {
            p.0 = std::mem::take(&mut self.values);
        }
    }
}

impl SpdFactor {
    /// Solves A x = b in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let par = self.par;
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        let col = faer::ColMut::from_slice_mut(b);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            col.as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }
}

/// Leaves of the dissection at most this size are ordered as they are.
const ND_LEAF: usize = 64;

/// A nested-dissection ordering of the symmetric pattern given by its lower (or upper)
/// triangle in CSC form: `order[new] = old`.
///
/// A part is split by the breadth-first level structure rooted at a pseudo-peripheral vertex:
/// the level holding the median vertex is the separator (thinned: a separator vertex with no
/// neighbour beyond it joins the first half), the levels before and after it are the two
/// halves, ordered recursively before the separator. Disconnected parts are split into their
/// components; parts of at most 64 vertices, or whose level structure is too shallow to
/// split, are leaves ordered breadth-first. On the graphs of 2D meshes the level sets are
/// curves of O(√n) vertices, which gives the O(n log n) fill of nested dissection.
pub fn nested_dissection(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    // full adjacency, no diagonal
    let mut ptr = vec![0usize; n + 1];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r != c {
                ptr[r + 1] += 1;
                ptr[c + 1] += 1;
            }
        }
    }
    for i in 0..n {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut adj = vec![0usize; ptr[n]];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r != c {
                adj[fill[r]] = c;
                fill[r] += 1;
                adj[fill[c]] = r;
                fill[c] += 1;
            }
        }
    }
    drop(fill);

    enum Task {
        Split(Vec<usize>),
        Emit(Vec<usize>),
    }
    let mut order = Vec::with_capacity(n);
    let mut mark = vec![0u32; n]; // part id of each vertex
    let mut level = vec![u32::MAX; n];
    let mut next_id = 1u32;
    let mut stack = vec![Task::Split((0..n).collect())];
    // breadth-first search inside part `id` from `root`; returns the vertices in BFS order
    // and the start of each level in it (levels left in `level`, to be reset by the caller)
    let bfs = |root: usize,
               id: u32,
               mark: &[u32],
               level: &mut [u32],
               out: &mut Vec<usize>,
               starts: &mut Vec<usize>| {
        out.clear();
        starts.clear();
        out.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < out.len() {
            let v = out[head];
            let lv = level[v];
            if starts.len() == lv as usize {
                starts.push(head);
            }
            head += 1;
            for &w in &adj[ptr[v]..ptr[v + 1]] {
                if mark[w] == id && level[w] == u32::MAX {
                    level[w] = lv + 1;
                    out.push(w);
                }
            }
        }
    };
    let mut reached = Vec::new();
    let mut starts = Vec::new();
    while let Some(task) = stack.pop() {
        let part = match task {
            Task::Emit(v) => {
                order.extend_from_slice(&v);
                continue;
            }
            Task::Split(p) => p,
        };
        if part.len() <= ND_LEAF {
            order.extend_from_slice(&part);
            continue;
        }
        let id = next_id;
        next_id = next_id.wrapping_add(1).max(1);
        for &v in &part {
            mark[v] = id;
        }
        // pseudo-peripheral root: repeat BFS from a minimum-degree vertex of the last level
        let mut root = part[0];
        let mut depth = 0usize;
        for _ in 0..4 {
            bfs(root, id, &mark, &mut level, &mut reached, &mut starts);
            for &v in &reached {
                level[v] = u32::MAX;
            }
            let d = starts.len();
            let last = &reached[starts[d - 1]..];
            let cand = last
                .iter()
                .copied()
                .min_by_key(|&v| ptr[v + 1] - ptr[v])
                .unwrap_or(root);
            if d <= depth {
                break;
            }
            depth = d;
            root = cand;
        }
        bfs(root, id, &mark, &mut level, &mut reached, &mut starts);
        if reached.len() < part.len() {
            // disconnected: this component, then the rest
            let rest: Vec<usize> = part
                .iter()
                .copied()
                .filter(|&v| level[v] == u32::MAX)
                .collect();
            for &v in &reached {
                level[v] = u32::MAX;
            }
            stack.push(Task::Split(rest));
            stack.push(Task::Split(reached.clone()));
            continue;
        }
        let nlev = starts.len();
        // the level holding the median vertex
        let half = reached.len() / 2;
        let m = starts.iter().rposition(|&s| s <= half).unwrap_or(0);
        if m == 0 || m + 1 >= nlev {
            order.extend_from_slice(&reached);
            for &v in &reached {
                level[v] = u32::MAX;
            }
            continue;
        }
        let m32 = m as u32;
        let mut a: Vec<usize> = reached[..starts[m]].to_vec();
        let end_m = starts[m + 1];
        let b: Vec<usize> = reached[end_m..].to_vec();
        let mut sep = Vec::new();
        for &v in &reached[starts[m]..end_m] {
            let touches_b = adj[ptr[v]..ptr[v + 1]]
                .iter()
                .any(|&w| mark[w] == id && level[w] == m32 + 1);
            if touches_b {
                sep.push(v);
            } else {
                a.push(v);
            }
        }
        for &v in &reached {
            level[v] = u32::MAX;
        }
        stack.push(Task::Emit(sep));
        stack.push(Task::Split(b));
        stack.push(Task::Split(a));
    }
    order
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

    #[test]
    fn nested_dissection_is_a_permutation_and_factorises_a_grid_laplacian() {
        // 5-point Laplacian (+ identity) on a 30 × 20 grid, lower triangle
        let (nx, ny) = (30, 20);
        let n = nx * ny;
        let id = |i: usize, j: usize| j * nx + i;
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for c in 0..n {
            let (i, j) = (c % nx, c / nx);
            row_idx.push(c);
            if i + 1 < nx {
                row_idx.push(id(i + 1, j));
            }
            if j + 1 < ny {
                row_idx.push(id(i, j + 1));
            }
            col_ptr.push(row_idx.len());
        }
        let order = nested_dissection(n, &col_ptr, &row_idx);
        let mut seen = vec![false; n];
        for &v in &order {
            assert!(!seen[v]);
            seen[v] = true;
        }
        assert_eq!(order.len(), n);
        let mut values = vec![-1.0; row_idx.len()];
        for c in 0..n {
            values[col_ptr[c]] = 5.0;
        }
        let mut x = [vec![1.0; n], vec![1.0; n]];
        for (o, ordering) in [Ordering::Amd, Ordering::NestedDissection]
            .iter()
            .enumerate()
        {
            let p =
                SpdPattern::with_ordering(n, col_ptr.clone(), row_idx.clone(), *ordering).unwrap();
            p.factor(&values).unwrap().solve_in_place(&mut x[o]);
        }
        for (a, b) in x[0].iter().zip(&x[1]) {
            assert!((a - b).abs() < 1e-12);
        }
    }
}
