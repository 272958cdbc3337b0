//! Compressed sparse row (CSR) matrices: the full symmetric matrix expanded from the lower
//! triangle the assembly produces, and the parallel products y = A x of the iterative solvers.
//!
//! Row i of A is stored in `col_idx[row_ptr[i]..row_ptr[i + 1]]` (column indices, strictly
//! increasing) and the same range of `values`. Column indices are `u32`: an index is read for
//! every stored entry of every product, and 4 bytes instead of 8 take a third off the memory
//! traffic of a product (12 instead of 16 bytes per entry), which is what bounds its speed.
//!
//! ## From the lower triangle (CSC) to the full matrix (CSR)
//! The assembly stores the lower triangle L of a symmetric A column by column (CSC):
//! column j holds the entries a_ij, i ≥ j. Row i of A is then
//!
//!   { a_ij : j < i }  =  row i of L, strictly left of the diagonal  (the entries (i, j) of the
//!                        columns j < i: a transposition),
//!   { a_ij : j ≥ i }  =  column i of L read as a row (a_ij = a_ji by symmetry).
//!
//! [`CsrMatrix::from_lower_csc`] does both in one sweep over the columns j = 0, 1, …: when
//! column j is reached, every entry left of the diagonal in row j has already been scattered
//! there by the columns before it, so row j is completed by copying column j, and the entries
//! of column j below the diagonal are scattered to their rows. Because the columns are visited
//! in increasing order, each row receives its left entries already sorted.
//!
//! Large matrices are expanded in parallel instead, by chunks of rows: the left part of rows
//! r0..r1 comes from the columns j < r1 whose last row reaches r0, scanned in increasing j
//! (so again sorted), once to count and once to fill the chunk's own part of the arrays.

use super::rows::Rows;
use crate::budget::{AllocFailure, try_filled, try_vec};
use rayon::prelude::*;

/// Rows per task of the parallel products: large enough that spreading the work costs nothing
/// measurable, small enough that two cores stay balanced on rows of unequal lengths.
pub(crate) const ROW_CHUNK: usize = 4096;

/// Below this many stored entries a product runs on the calling thread (spreading it costs
/// more than it saves).
pub(crate) const PAR_MIN_NNZ: usize = 60_000;

/// Rows per chunk of the parallel [`CsrMatrix::from_lower_csc`] (large against the band of
/// grid numberings, which each chunk scans again).
const CSC_CHUNK: usize = 16384;

/// For each chunk of [`CSC_CHUNK`] rows of the parallel [`CsrMatrix::from_lower_csc`], the
/// first column whose last row reaches the chunk (from the running maximum of the last
/// rows); `None` when the chunks would scan more than 4 n columns in all (a wide band);
/// [`AllocFailure`] if the running maximum cannot be allocated.
fn first_columns(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<Option<Vec<usize>>, AllocFailure> {
    // reach[j] = max_{j' ≤ j} (last row of column j'), running maximum
    let mut reach = try_filled(n, 0usize, "the column reach of the matrix")?;
    let mut m = 0;
    for (j, r) in reach.iter_mut().enumerate() {
        let (s, e) = (col_ptr[j], col_ptr[j + 1]);
        if e > s {
            m = m.max(row_idx[e - 1]);
        }
        *r = m.max(j);
    }
    let n_chunks = n.div_ceil(CSC_CHUNK);
    let first: Vec<usize> = (0..n_chunks)
        .map(|c| reach.partition_point(|&r| r < c * CSC_CHUNK))
        .collect();
    drop(reach);
    let scanned: usize = (0..n_chunks)
        .map(|c| ((c + 1) * CSC_CHUNK).min(n) - first[c])
        .sum();
    Ok((scanned <= 4 * n).then_some(first))
}

/// A sparse matrix in compressed sparse row form, with sorted column indices.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CsrMatrix {
    n_rows: usize,
    n_cols: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<u32>,
    values: Vec<f64>,
}

/// The error of a malformed sparse structure.
fn structure_error(msg: String) -> crate::Error {
    crate::Error::Linear(format!("invalid sparse matrix: {msg}"))
}

/// Checks a lower-triangular CSC matrix of order `n` (see [`CsrMatrix::from_lower_csc`]):
/// pointers, strictly increasing rows in each column, nothing above the diagonal or beyond
/// the order; the first bad column in order is the error. Returns whether the matrix is large
/// enough for the parallel sweep (the checks then also ran in parallel).
fn check_lower_csc(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
) -> crate::Result<bool> {
    if n > u32::MAX as usize {
        return Err(structure_error(format!(
            "order {n}: column indices are 32-bit"
        )));
    }
    if col_ptr.len() != n + 1
        || col_ptr[0] != 0
        || col_ptr[n] != row_idx.len()
        || row_idx.len() != values.len()
    {
        return Err(structure_error(format!(
            "lower CSC of order {n}: {} column pointers (from {:?} to {:?}), {} row indices, \
             {} values",
            col_ptr.len(),
            col_ptr.first(),
            col_ptr.last(),
            row_idx.len(),
            values.len()
        )));
    }
    // check the columns (in parallel for large matrices; the first bad column is reported)
    let check = |j: usize| -> Option<String> {
        let (s, e) = (col_ptr[j], col_ptr[j + 1]);
        if e < s || e > row_idx.len() {
            return Some(format!("column pointers decrease or overrun at column {j}"));
        }
        let rows = &row_idx[s..e];
        if rows.windows(2).any(|w| w[0] >= w[1]) {
            return Some(format!(
                "the row indices of column {j} are not strictly increasing"
            ));
        }
        if let Some(&r) = rows.first()
            && r < j
        {
            return Some(format!(
                "column {j} has the entry ({r}, {j}) above the diagonal: the lower triangle \
                 is expected"
            ));
        }
        if let Some(&r) = rows.last()
            && r >= n
        {
            return Some(format!("column {j} has row {r}, but the order is {n}"));
        }
        None
    };
    let parallel = row_idx.len() >= PAR_MIN_NNZ && n >= 2 * CSC_CHUNK;
    let bad = if parallel {
        (0..n)
            .into_par_iter()
            .with_min_len(ROW_CHUNK)
            .find_map_first(check)
    } else {
        (0..n).find_map(check)
    };
    if let Some(msg) = bad {
        return Err(structure_error(msg));
    }
    Ok(parallel)
}

impl CsrMatrix {
    /// A matrix from its CSR arrays, checked: `row_ptr` has `n_rows + 1` nondecreasing entries
    /// from 0 to `col_idx.len() == values.len()`, and the column indices of each row are
    /// strictly increasing and below `n_cols`.
    pub fn new(
        n_rows: usize,
        n_cols: usize,
        row_ptr: Vec<usize>,
        col_idx: Vec<u32>,
        values: Vec<f64>,
    ) -> crate::Result<Self> {
        if n_cols > u32::MAX as usize {
            return Err(structure_error(format!(
                "{n_cols} columns: column indices are 32-bit"
            )));
        }
        if row_ptr.len() != n_rows + 1 || row_ptr[0] != 0 {
            return Err(structure_error(format!(
                "row_ptr has {} entries starting at {:?}, expected {} starting at 0",
                row_ptr.len(),
                row_ptr.first(),
                n_rows + 1
            )));
        }
        if row_ptr[n_rows] != col_idx.len() || col_idx.len() != values.len() {
            return Err(structure_error(format!(
                "row_ptr ends at {}, with {} column indices and {} values",
                row_ptr[n_rows],
                col_idx.len(),
                values.len()
            )));
        }
        for i in 0..n_rows {
            let (s, e) = (row_ptr[i], row_ptr[i + 1]);
            if e < s || e > col_idx.len() {
                return Err(structure_error(format!(
                    "row_ptr decreases or overruns at row {i}"
                )));
            }
            let cols = &col_idx[s..e];
            if cols.windows(2).any(|w| w[0] >= w[1]) {
                return Err(structure_error(format!(
                    "the column indices of row {i} are not strictly increasing"
                )));
            }
            if let Some(&c) = cols.last()
                && c as usize >= n_cols
            {
                return Err(structure_error(format!(
                    "row {i} has column {c}, but there are {n_cols} columns"
                )));
            }
        }
        Ok(CsrMatrix {
            n_rows,
            n_cols,
            row_ptr,
            col_idx,
            values,
        })
    }

    /// The full symmetric n × n matrix whose lower triangle is given in CSC form (column
    /// pointers, row indices strictly increasing within a column and ≥ the column, values), as
    /// [`crate::assembly::DiscreteSystem::condensed_pattern`] and `assemble_condensed` produce
    /// it. See the module documentation for the sweep. Its arrays are allocated fallibly:
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if they cannot be.
    ///
    /// For large matrices (at least 32768 rows) the checks and the sweep run in parallel,
    /// by chunks of rows, each gathering the left parts of its rows from the columns that reach
    /// it (see `from_lower_csc_par`); the result is the same (the entries are only moved). When
    /// the band is so wide that the chunks would rescan more than 4 n columns, the sequential
    /// sweep is used. (Timings of both sweeps: `replication/BENCHMARKS.md`, "Measurements
    /// behind the defaults".)
    pub fn from_lower_csc(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> crate::Result<Self> {
        let parallel = check_lower_csc(n, col_ptr, row_idx, values)?;
        if parallel && let Some(a) = Self::from_lower_csc_par(n, col_ptr, row_idx, values)? {
            return Ok(a);
        }
        // left[i] = number of entries (i, j), j < i
        let mut left = try_filled(n, 0usize, "the row lengths of the matrix")?;
        for &r in row_idx {
            left[r] += 1;
        }
        // (the diagonal entries were counted: remove them)
        for j in 0..n {
            let (s, e) = (col_ptr[j], col_ptr[j + 1]);
            if s < e && row_idx[s] == j {
                left[j] -= 1;
            }
        }
        let mut row_ptr = try_vec(n + 1, "the row offsets of the matrix")?;
        row_ptr.push(0usize);
        let mut acc = 0;
        for j in 0..n {
            acc += left[j] + (col_ptr[j + 1] - col_ptr[j]);
            row_ptr.push(acc);
        }
        let nnz = acc;
        let mut col_idx = try_filled(nnz, 0u32, "the column indices of the matrix")?;
        let mut vals = try_filled(nnz, 0.0f64, "the entries of the matrix")?;
        // next[i]: where the next left entry of row i goes (reuses `left`)
        let mut next = left;
        next.copy_from_slice(&row_ptr[..n]);
        for j in 0..n {
            let (s, e) = (col_ptr[j], col_ptr[j + 1]);
            // row j: its left part is complete; append column j (the diagonal and the right)
            let start = next[j];
            debug_assert_eq!(start + (e - s), row_ptr[j + 1]);
            for (k, (&r, &v)) in row_idx[s..e].iter().zip(&values[s..e]).enumerate() {
                col_idx[start + k] = r as u32;
                vals[start + k] = v;
            }
            // scatter the entries below the diagonal to their rows
            for (&r, &v) in row_idx[s..e].iter().zip(&values[s..e]) {
                if r != j {
                    let p = next[r];
                    col_idx[p] = j as u32;
                    vals[p] = v;
                    next[r] = p + 1;
                }
            }
        }
        Ok(CsrMatrix {
            n_rows: n,
            n_cols: n,
            row_ptr,
            col_idx,
            values: vals,
        })
    }

    /// The parallel sweep of [`Self::from_lower_csc`] (a checked structure): the rows are cut
    /// into chunks of [`CSC_CHUNK`]; the left part of the rows r0..r1 of a chunk comes from the
    /// columns j < r1 whose last row reaches r0, i.e. from the first such column on (found
    /// from the running maximum of the last rows). Each chunk counts its rows, then (after a
    /// prefix sum) fills its own part of the arrays, scanning those columns twice. `None` when
    /// the columns to scan exceed 4 n in all (a wide band: the sequential sweep is cheaper);
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if the arrays cannot be allocated.
    fn from_lower_csc_par(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> crate::Result<Option<Self>> {
        let Some(first) = first_columns(n, col_ptr, row_idx)? else {
            return Ok(None);
        };
        let n_chunks = first.len();
        // the entries (r, j), r0 ≤ r < r1, of the columns j < r1 from `first` on, below the
        // diagonal, in increasing j: f(r, j, v)
        let scan = |c: usize, f: &mut dyn FnMut(usize, usize, f64)| {
            let (r0, r1) = (c * CSC_CHUNK, ((c + 1) * CSC_CHUNK).min(n));
            for j in first[c]..r1 {
                let (s, e) = (col_ptr[j], col_ptr[j + 1]);
                let rows = &row_idx[s..e];
                let lo = rows.partition_point(|&r| r < r0.max(j + 1));
                for (&r, &v) in rows[lo..].iter().zip(&values[s + lo..e]) {
                    if r >= r1 {
                        break;
                    }
                    f(r, j, v);
                }
            }
        };
        // row lengths, then pointers
        let mut row_ptr = try_filled(n + 1, 0usize, "the row offsets of the matrix")?;
        row_ptr[1..]
            .par_chunks_mut(CSC_CHUNK)
            .enumerate()
            .for_each(|(c, lens)| {
                let r0 = c * CSC_CHUNK;
                for (k, l) in lens.iter_mut().enumerate() {
                    *l = col_ptr[r0 + k + 1] - col_ptr[r0 + k];
                }
                scan(c, &mut |r, _, _| lens[r - r0] += 1);
            });
        for i in 0..n {
            row_ptr[i + 1] += row_ptr[i];
        }
        let nnz = row_ptr[n];
        let mut col_idx = try_filled(nnz, 0u32, "the column indices of the matrix")?;
        let mut vals = try_filled(nnz, 0.0f64, "the entries of the matrix")?;
        let mut pieces = Vec::with_capacity(n_chunks);
        let (mut ci, mut va) = (&mut col_idx[..], &mut vals[..]);
        for c in 0..n_chunks {
            let len = row_ptr[((c + 1) * CSC_CHUNK).min(n)] - row_ptr[c * CSC_CHUNK];
            let (c0, c1) = std::mem::take(&mut ci).split_at_mut(len);
            let (v0, v1) = std::mem::take(&mut va).split_at_mut(len);
            pieces.push((c, c0, v0));
            (ci, va) = (c1, v1);
        }
        let rp = &row_ptr;
        pieces
            .into_par_iter()
            .for_each_init(Vec::new, |next, (c, cols, vs)| {
                let (r0, r1) = (c * CSC_CHUNK, ((c + 1) * CSC_CHUNK).min(n));
                let base = rp[r0];
                next.clear();
                next.extend_from_slice(&rp[r0..r1]);
                next.iter_mut().for_each(|p| *p -= base);
                scan(c, &mut |r, j, v| {
                    let p = &mut next[r - r0];
                    cols[*p] = j as u32;
                    vs[*p] = v;
                    *p += 1;
                });
                // then each row's column (the diagonal and the right part)
                for (k, &p) in next.iter().enumerate() {
                    let j = r0 + k;
                    let (s, e) = (col_ptr[j], col_ptr[j + 1]);
                    debug_assert_eq!(p + (e - s), rp[j + 1] - base);
                    for (q, (&r, &v)) in row_idx[s..e].iter().zip(&values[s..e]).enumerate() {
                        cols[p + q] = r as u32;
                        vs[p + q] = v;
                    }
                }
            });
        Ok(Some(CsrMatrix {
            n_rows: n,
            n_cols: n,
            row_ptr,
            col_idx,
            values: vals,
        }))
    }

    /// A matrix from arrays already known to be well formed (built by this module or the
    /// multigrid setup).
    pub(crate) fn from_parts(
        n_rows: usize,
        n_cols: usize,
        row_ptr: Vec<usize>,
        col_idx: Vec<u32>,
        values: Vec<f64>,
    ) -> Self {
        debug_assert_eq!(row_ptr.len(), n_rows + 1);
        debug_assert_eq!(row_ptr[n_rows], col_idx.len());
        debug_assert_eq!(col_idx.len(), values.len());
        CsrMatrix {
            n_rows,
            n_cols,
            row_ptr,
            col_idx,
            values,
        }
    }

    /// Removes the stored off-diagonal entries whose value is exactly zero (diagonal entries
    /// are kept), in place; the arrays shrink to fit. The condensed matrices store many: the
    /// couplings of the fixed unknowns (unit rows and columns, zeroed by the active set) and
    /// structurally present couplings that cancel (P1 on right triangles couples the two
    /// acute vertices by cot 90° = 0, so the grids of `cartesian_triangles` store 7 entries
    /// per row for a 5-point operator). A dropped entry adds an exact `0 · x_j` to a sum, so
    /// every product, sweep and multigrid setup gives the same bits with or without it (for
    /// finite x); only the memory traffic, which bounds their speed, shrinks.
    pub fn drop_zeros(&mut self) {
        let mut w = 0;
        let mut start = 0;
        for i in 0..self.n_rows {
            let end = self.row_ptr[i + 1];
            for p in start..end {
                let (j, v) = (self.col_idx[p], self.values[p]);
                if v != 0.0 || j as usize == i {
                    self.col_idx[w] = j;
                    self.values[w] = v;
                    w += 1;
                }
            }
            start = end;
            self.row_ptr[i + 1] = w;
        }
        self.col_idx.truncate(w);
        self.col_idx.shrink_to_fit();
        self.values.truncate(w);
        self.values.shrink_to_fit();
    }

    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.n_rows
    }
    /// Number of columns.
    pub fn n_cols(&self) -> usize {
        self.n_cols
    }
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.col_idx.len()
    }
    /// Row pointers (`n_rows + 1` entries).
    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }
    /// Column indices, row after row.
    pub fn col_idx(&self) -> &[u32] {
        &self.col_idx
    }
    /// Values, in the order of [`Self::col_idx`].
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Values, to be refilled in place (the pattern does not change).
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }
    /// The column indices and values of row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let (s, e) = (self.row_ptr[i], self.row_ptr[i + 1]);
        (&self.col_idx[s..e], &self.values[s..e])
    }
    /// Bytes held by the arrays.
    pub fn memory_bytes(&self) -> usize {
        self.row_ptr.len() * std::mem::size_of::<usize>()
            + self.col_idx.len() * std::mem::size_of::<u32>()
            + self.values.len() * std::mem::size_of::<f64>()
    }

    /// The diagonal a_ii (0 where row i stores no diagonal entry), for a square matrix;
    /// aborts, as `vec!` does, if it cannot be allocated (the library's solve paths use a
    /// fallible variant that returns the failure instead).
    pub fn diagonal(&self) -> Vec<f64> {
        Rows::try_diagonal(self).unwrap_or_else(|f| f.abort())
    }

    /// y = A x, checked: `x` has `n_cols` entries and `y` has `n_rows`.
    pub fn spmv(&self, x: &[f64], y: &mut [f64]) -> crate::Result<()> {
        if x.len() != self.n_cols || y.len() != self.n_rows {
            return Err(crate::Error::Linear(format!(
                "product of a {}×{} matrix: x has {} entries and y {}",
                self.n_rows,
                self.n_cols,
                x.len(),
                y.len()
            )));
        }
        self.mul_to(x, y);
        Ok(())
    }

    /// y += A x (lengths are the caller's invariant).
    pub(crate) fn mul_add_to(&self, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n_cols);
        debug_assert_eq!(y.len(), self.n_rows);
        self.for_row_chunks(y, |i0, chunk| {
            for (k, yi) in chunk.iter_mut().enumerate() {
                *yi += self.row_dot(i0 + k, x);
            }
        });
    }

    /// y = Aᵀ x (lengths are the caller's invariant), by scattering the rows of A in order:
    /// y_j = Σ_i a_ij x_i added in increasing i, the order of the rows of [`Self::transpose`],
    /// so the result is bit-identical to `self.transpose().mul_to(x, y)` without storing the
    /// transpose. Sequential (scattered writes).
    pub(crate) fn mul_transpose_to(&self, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(x.len(), self.n_rows);
        debug_assert_eq!(y.len(), self.n_cols);
        y.fill(0.0);
        for (i, &xi) in x.iter().enumerate() {
            let (cols, vals) = self.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                y[j as usize] += v * xi;
            }
        }
    }

    /// The transpose Aᵀ (a counting sort of the entries by column; rows of the result come
    /// out sorted because the rows of A are visited in order), or
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if its arrays cannot be allocated.
    pub fn transpose(&self) -> crate::Result<CsrMatrix> {
        let (m, n) = (self.n_rows, self.n_cols);
        let mut row_ptr = try_filled(n + 1, 0usize, "the row offsets of the transpose")?;
        for &j in &self.col_idx {
            row_ptr[j as usize + 1] += 1;
        }
        for j in 0..n {
            row_ptr[j + 1] += row_ptr[j];
        }
        let mut next = try_vec(n, "the fill cursors of the transpose")?;
        next.extend_from_slice(&row_ptr[..n]);
        let mut col_idx = try_filled(self.nnz(), 0u32, "the column indices of the transpose")?;
        let mut values = try_filled(self.nnz(), 0.0, "the entries of the transpose")?;
        for i in 0..m {
            let (cols, vals) = self.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                let p = next[j as usize];
                col_idx[p] = i as u32;
                values[p] = v;
                next[j as usize] = p + 1;
            }
        }
        Ok(CsrMatrix {
            n_rows: n,
            n_cols: m,
            row_ptr,
            col_idx,
            values,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lower CSC of [[4, 1, 0], [1, 5, 2], [0, 2, 6]].
    fn lower() -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        (
            vec![0, 2, 4, 5],
            vec![0, 1, 1, 2, 2],
            vec![4.0, 1.0, 5.0, 2.0, 6.0],
        )
    }

    #[test]
    fn expands_the_lower_triangle_and_multiplies() {
        let (cp, ri, v) = lower();
        let a = CsrMatrix::from_lower_csc(3, &cp, &ri, &v).unwrap();
        assert_eq!(a.row_ptr(), &[0, 2, 5, 7]);
        assert_eq!(a.col_idx(), &[0, 1, 0, 1, 2, 1, 2]);
        assert_eq!(a.values(), &[4.0, 1.0, 1.0, 5.0, 2.0, 2.0, 6.0]);
        assert_eq!(a.diagonal(), vec![4.0, 5.0, 6.0]);
        let mut y = vec![0.0; 3];
        a.spmv(&[1.0, 2.0, 3.0], &mut y).unwrap();
        assert_eq!(y, vec![6.0, 17.0, 22.0]);
        assert_eq!(a.transpose().unwrap(), a);
        assert!(a.spmv(&[1.0], &mut y).is_err());
    }

    /// The residual norm without a residual vector is the norm of the residual.
    #[test]
    fn residual_norm_is_the_norm_of_the_residual() {
        let (cp, ri, v) = lower();
        let a = CsrMatrix::from_lower_csc(3, &cp, &ri, &v).unwrap();
        let (b, x) = ([1.0, -2.0, 0.5], [0.3, 0.1, -0.7]);
        let mut r = [0.0; 3];
        a.residual_to(&b, &x, &mut r);
        let expected = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((a.residual_norm(&b, &x) - expected).abs() <= 1e-15 * expected);
        assert!(expected > 0.1);
    }

    /// Aᵀx by scattering the rows equals the product with the stored transpose, bit for bit,
    /// on a rectangular matrix with several entries per column.
    #[test]
    fn transposed_product_is_the_product_with_the_transpose() {
        let (m, n) = (40, 9);
        let mut row_ptr = vec![0];
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for i in 0..m {
            for j in 0..n {
                if (i * 7 + j * 3) % 5 < 2 {
                    cols.push(j as u32);
                    vals.push(((i * n + j) as f64 * 0.37).sin());
                }
            }
            row_ptr.push(cols.len());
        }
        let a = CsrMatrix::new(m, n, row_ptr, cols, vals).unwrap();
        let x: Vec<f64> = (0..m).map(|i| (i as f64 * 1.3).cos()).collect();
        let (mut y, mut z) = (vec![f64::NAN; n], vec![0.0; n]);
        a.mul_transpose_to(&x, &mut y);
        a.transpose().unwrap().mul_to(&x, &mut z);
        assert_eq!(
            y.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            z.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert!(y.iter().all(|v| *v != 0.0));
    }

    #[test]
    fn dropping_zeros_keeps_the_products_and_the_diagonal() {
        // lower triangle of a 4 × 4 matrix with stored zeros: a zero diagonal entry (kept),
        // zero couplings (dropped)
        let cp = vec![0, 3, 5, 7, 8];
        let ri = vec![0, 1, 3, 1, 2, 2, 3, 3];
        let v = vec![4.0, 0.0, -1.0, 0.0, -0.0, 3.0, 0.0, 2.0];
        let a = CsrMatrix::from_lower_csc(4, &cp, &ri, &v).unwrap();
        let mut b = a.clone();
        b.drop_zeros();
        assert_eq!(b.row_ptr(), &[0, 2, 3, 4, 6]);
        assert_eq!(b.col_idx(), &[0, 3, 1, 2, 0, 3]);
        assert_eq!(b.values(), &[4.0, -1.0, 0.0, 3.0, -1.0, 2.0]);
        assert_eq!(b.diagonal(), a.diagonal());
        let x = [0.3, -1.7, 2.5, 1e-3];
        let (mut ya, mut yb) = ([0.0; 4], [0.0; 4]);
        a.spmv(&x, &mut ya).unwrap();
        b.spmv(&x, &mut yb).unwrap();
        assert_eq!(ya.map(f64::to_bits), yb.map(f64::to_bits));
        // nothing to drop: unchanged
        let mut c = b.clone();
        c.drop_zeros();
        assert_eq!(c, b);
    }

    /// The transpose of a 1 × (2³² − 1) matrix needs 32 GiB of row offsets: in a child
    /// process whose data is limited to what it has plus 64 MiB, a typed
    /// out-of-memory error naming them, not an abort; a small transpose still succeeds there.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_transpose_the_data_limit_refuses_is_a_typed_error() {
        use crate::budget::child;
        const NAME: &str =
            "linalg::csr::tests::a_transpose_the_data_limit_refuses_is_a_typed_error";
        if !child::is_child(NAME) {
            return child::run(NAME);
        }
        let wide = CsrMatrix::new(1, u32::MAX as usize, vec![0, 0], vec![], vec![]).unwrap();
        let (cp, ri, v) = lower();
        let small = CsrMatrix::from_lower_csc(3, &cp, &ri, &v).unwrap();
        child::limit_data(64 << 20);
        let e = wide.transpose().unwrap_err();
        assert!(e.is_out_of_memory(), "{e}");
        assert!(
            e.to_string()
                .starts_with("the row offsets of the transpose would need about 32.0 GiB"),
            "{e}"
        );
        assert_eq!(small.transpose().unwrap(), small);
    }

    #[test]
    fn rejects_malformed_structures() {
        let (cp, ri, v) = lower();
        // an entry above the diagonal
        assert!(CsrMatrix::from_lower_csc(3, &cp, &[0, 1, 0, 2, 2], &v).is_err());
        // unsorted rows
        assert!(CsrMatrix::from_lower_csc(3, &cp, &[1, 0, 1, 2, 2], &v).is_err());
        // a row out of range
        assert!(CsrMatrix::from_lower_csc(3, &cp, &[0, 1, 1, 3, 2], &v).is_err());
        // wrong lengths
        assert!(CsrMatrix::from_lower_csc(3, &cp, &ri, &v[..4]).is_err());
        assert!(CsrMatrix::new(2, 2, vec![0, 1, 2], vec![0, 2], vec![1.0, 1.0]).is_err());
        assert!(CsrMatrix::new(1, 2, vec![0, 2], vec![1, 0], vec![1.0, 1.0]).is_err());
        assert!(CsrMatrix::new(1, 2, vec![0, 2], vec![0, 1], vec![1.0, 1.0]).is_ok());
    }

    /// The lower CSC of an n × n symmetric matrix with the couplings (i, i + d) for d in
    /// `offsets` (where i + d < n), some of them missing, and a diagonal.
    fn banded(n: usize, offsets: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
        for j in 0..n {
            ri.push(j);
            v.push(10.0 + j as f64);
            for &d in offsets {
                if j + d < n && (j * 7 + d) % 5 != 0 {
                    ri.push(j + d);
                    v.push(-(j as f64) - d as f64 * 1e-6);
                }
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    /// The full matrix by sorting the triplets (i, j, v) of both triangles.
    fn expand_naively(n: usize, cp: &[usize], ri: &[usize], v: &[f64]) -> CsrMatrix {
        let mut t = Vec::new();
        for j in 0..n {
            for p in cp[j]..cp[j + 1] {
                t.push((ri[p], j, v[p]));
                if ri[p] != j {
                    t.push((j, ri[p], v[p]));
                }
            }
        }
        t.sort_by_key(|&(i, j, _)| (i, j));
        let mut row_ptr = vec![0; n + 1];
        for &(i, _, _) in &t {
            row_ptr[i + 1] += 1;
        }
        for i in 0..n {
            row_ptr[i + 1] += row_ptr[i];
        }
        let col_idx = t.iter().map(|&(_, j, _)| j as u32).collect();
        let values = t.iter().map(|&(_, _, v)| v).collect();
        CsrMatrix::new(n, n, row_ptr, col_idx, values).unwrap()
    }

    #[test]
    fn the_parallel_expansion_matches_the_sequential_one() {
        let n = 9 * CSC_CHUNK + 123;
        // a grid-like band (taken in parallel), then a wide one (the sequential fallback)
        for offsets in [vec![1, 2, 300, 301], vec![1, 40_000, n - 1]] {
            let (cp, ri, v) = banded(n, &offsets);
            let a = CsrMatrix::from_lower_csc(n, &cp, &ri, &v).unwrap();
            assert_eq!(a, expand_naively(n, &cp, &ri, &v), "{offsets:?}");
            assert_eq!(a.transpose().unwrap(), a);
        }
        // an error in a late column is found by the parallel check
        let (cp, mut ri, v) = banded(n, &[1, 2]);
        let p = cp[n - 10];
        ri.swap(p, p + 1);
        let e = CsrMatrix::from_lower_csc(n, &cp, &ri, &v)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("column {}", n - 10)), "{e}");
    }
}
