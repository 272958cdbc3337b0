//! Square sparse matrices read row by row ([`Rows`]): the stored matrix ([`CsrMatrix`]) and a
//! masked view of one ([`MaskedRows`]), with the products the iterative solvers need.
//!
//! ## The masked view
//! A solve of the active-set iteration fixes some unknowns F and solves the system
//!
//!   S_ij = A_ij for i, j ∉ F (A_ij ≠ 0),   S_ii = 1 for i ∈ F,   S_ij = 0 else,
//!
//! (`assembly::assembled`). Copying S out of A costs as much memory as A itself. S differs
//! from A only in the rows of F and in the rows that couple to F (and in the rows where A
//! stores an exact zero, dropped from S), a small part of the rows once the active set is a
//! region and not scattered unknowns. [`MaskedRows`] keeps A (shared, [`Arc`]) and stores only
//! those rows of S: row i is read from A unless bit i of a mask is set, and then from the
//! patch, at the rank of i among the set bits (a popcount within its 64-bit word, plus the
//! count of the words before it). Every row reads the entries of S, in the order S stores
//! them, so a product with the view gives the bits of a product with S.

use super::csr::{CsrMatrix, PAR_MIN_NNZ, ROW_CHUNK};
use crate::budget::{AllocFailure, try_copy, try_filled, try_vec};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// Σ_j a_ij x_j over the entries (`cols`, `vals`) of a row.
#[inline(always)]
pub(crate) fn dot_row(cols: &[u32], vals: &[f64], x: &[f64]) -> f64 {
    let mut s = 0.0;
    for (&j, &v) in cols.iter().zip(vals) {
        s += v * x[j as usize];
    }
    s
}

/// A sparse matrix read row by row: row i is its column indices (strictly increasing) and
/// values. The products run on all cores for large matrices, in fixed chunks
/// of rows, and sums of chunk results are added in chunk order, so a result
/// depends only on the rows and never on the scheduling.
pub trait Rows: Sync {
    /// Rows.
    fn n_rows(&self) -> usize;
    /// Columns.
    fn n_cols(&self) -> usize;
    /// Stored entries (read by the choice between a sequential and a parallel product).
    fn nnz(&self) -> usize;
    /// The column indices and values of row `i`.
    fn row(&self, i: usize) -> (&[u32], &[f64]);

    /// `f(i, cols, vals)` for the rows i of `rows`, in increasing order (the loops of the
    /// products and sweeps: a view may read runs of rows faster than one by one).
    #[inline(always)]
    fn for_rows<F: FnMut(usize, &[u32], &[f64])>(&self, rows: Range<usize>, mut f: F) {
        for i in rows {
            let (cols, vals) = self.row(i);
            f(i, cols, vals);
        }
    }

    /// [`Self::for_rows`] in decreasing order.
    #[inline(always)]
    fn for_rows_rev<F: FnMut(usize, &[u32], &[f64])>(&self, rows: Range<usize>, mut f: F) {
        for i in rows.rev() {
            let (cols, vals) = self.row(i);
            f(i, cols, vals);
        }
    }

    /// Σ_j a_ij x_j for row i.
    #[inline(always)]
    fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (cols, vals) = self.row(i);
        dot_row(cols, vals, x)
    }

    /// Runs `f(i0, chunk)` on consecutive chunks of `y` (rows `i0..i0 + chunk.len()`), in
    /// parallel when the matrix is large enough.
    #[inline]
    fn for_row_chunks<F>(&self, y: &mut [f64], f: F)
    where
        F: Fn(usize, &mut [f64]) + Sync + Send,
    {
        if self.nnz() < PAR_MIN_NNZ {
            f(0, y);
        } else {
            y.par_chunks_mut(ROW_CHUNK)
                .enumerate()
                .for_each(|(c, chunk)| f(c * ROW_CHUNK, chunk));
        }
    }

    /// y = A x (lengths are the caller's invariant).
    fn mul_to(&self, x: &[f64], y: &mut [f64]) {
        debug_assert_eq!(y.len(), self.n_rows());
        self.for_row_chunks(y, |i0, chunk| {
            self.for_rows(i0..i0 + chunk.len(), |i, cols, vals| {
                chunk[i - i0] = dot_row(cols, vals, x);
            });
        });
    }

    /// r = b − A x (lengths are the caller's invariant).
    fn residual_to(&self, b: &[f64], x: &[f64], r: &mut [f64]) {
        debug_assert_eq!(b.len(), self.n_rows());
        debug_assert_eq!(r.len(), self.n_rows());
        self.for_row_chunks(r, |i0, chunk| {
            self.for_rows(i0..i0 + chunk.len(), |i, cols, vals| {
                chunk[i - i0] = b[i] - dot_row(cols, vals, x);
            });
        });
    }

    /// ‖b − A x‖₂ without storing the residual; partial sums over fixed chunks of rows, added
    /// in order (the result does not depend on the threads).
    fn residual_norm(&self, b: &[f64], x: &[f64]) -> f64 {
        let part = |i0: usize, i1: usize| -> f64 {
            let mut s = 0.0;
            self.for_rows(i0..i1, |i, cols, vals| {
                let d = b[i] - dot_row(cols, vals, x);
                s += d * d;
            });
            s
        };
        let n = self.n_rows();
        let parts: Vec<f64> = if self.nnz() < PAR_MIN_NNZ {
            vec![part(0, n)]
        } else {
            (0..n.div_ceil(ROW_CHUNK))
                .into_par_iter()
                .map(|c| part(c * ROW_CHUNK, ((c + 1) * ROW_CHUNK).min(n)))
                .collect()
        };
        parts.iter().sum::<f64>().sqrt()
    }

    /// The diagonal a_ii (0 where row i stores no diagonal entry), or [`AllocFailure`] if it
    /// cannot be allocated.
    fn try_diagonal(&self) -> Result<Vec<f64>, AllocFailure> {
        let n = self.n_rows().min(self.n_cols());
        let mut d = try_filled(n, 0.0, "the diagonal of the matrix")?;
        let fill = |i0: usize, chunk: &mut [f64]| {
            for (k, di) in chunk.iter_mut().enumerate() {
                let i = i0 + k;
                let (cols, vals) = self.row(i);
                if let Ok(p) = cols.binary_search(&(i as u32)) {
                    *di = vals[p];
                }
            }
        };
        self.for_row_chunks(&mut d, fill);
        Ok(d)
    }
}

impl Rows for CsrMatrix {
    #[inline]
    fn n_rows(&self) -> usize {
        CsrMatrix::n_rows(self)
    }
    #[inline]
    fn n_cols(&self) -> usize {
        CsrMatrix::n_cols(self)
    }
    #[inline]
    fn nnz(&self) -> usize {
        CsrMatrix::nnz(self)
    }
    #[inline(always)]
    fn row(&self, i: usize) -> (&[u32], &[f64]) {
        CsrMatrix::row(self, i)
    }
}

/// S of the module docs: a square matrix A (shared) with the rows and columns of the fixed
/// unknowns F masked, storing only the rows of S that differ from A's.
#[derive(Debug, Clone)]
pub struct MaskedRows {
    a: Arc<CsrMatrix>,
    /// Bit i: row i of S is not row i of A (read from the patch).
    patched: Vec<u64>,
    /// Set bits of `patched` before each word.
    rank: Vec<u32>,
    /// The patched rows, in order, stored by rows.
    ptr: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
    /// Stored entries of S.
    nnz: usize,
}

impl MaskedRows {
    /// S for the square matrix `a` and the fixed unknowns `fixed(i)` (i < order of `a`):
    /// row i ∈ F is the unit row; a row i ∉ F keeps its diagonal entry and its nonzero
    /// entries in free columns. Errors: `a` not square, or arrays that cannot be allocated.
    pub fn new<F>(a: Arc<CsrMatrix>, fixed: F) -> crate::Result<Self>
    where
        F: Fn(usize) -> bool + Sync,
    {
        let n = a.n_rows();
        if a.n_cols() != n {
            return Err(crate::Error::Linear(format!(
                "a masked view of a {}×{} matrix: it must be square",
                n,
                a.n_cols()
            )));
        }
        // which rows differ from A's: a fixed row (unless A's is the unit row already), or a
        // row that loses an entry
        let mut patched = try_filled(n.div_ceil(64), 0u64, "the masked rows")?;
        patched.par_iter_mut().enumerate().for_each(|(w, bits)| {
            for i in w * 64..((w + 1) * 64).min(n) {
                if differs(&a, &fixed, i) {
                    *bits |= 1 << (i % 64);
                }
            }
        });
        let (rank, count) = ranks(&patched)?;
        let len = |i: usize| {
            if fixed(i) {
                1
            } else {
                let (cols, vals) = a.row(i);
                cols.iter()
                    .zip(vals)
                    .filter(|&(&j, &v)| keep(&fixed, i, j, v))
                    .count()
            }
        };
        let mut ptr: Vec<usize> = try_vec(count + 1, "the masked rows")?;
        ptr.push(0);
        // entries of the patched rows in S and in A
        let (mut total, mut in_a) = (0, 0);
        for i in set_bits(&patched) {
            total += len(i);
            in_a += a.row(i).0.len();
            ptr.push(total);
        }
        let mut cols: Vec<u32> = try_vec(total, "the masked rows")?;
        let mut vals: Vec<f64> = try_vec(total, "the masked rows")?;
        for i in set_bits(&patched) {
            push_masked_row(&a, &fixed, i, &mut cols, &mut vals);
        }
        let nnz = a.nnz() - in_a + total;
        Ok(MaskedRows {
            a,
            patched,
            rank,
            ptr,
            cols,
            vals,
            nnz,
        })
    }

    /// The rows of S that a change of status (fixed or free) of the unknowns `changed` can
    /// alter: their own rows and every row with an entry in their columns, found as the
    /// columns of their rows of A, whose pattern is symmetric (the matrices of the solves are
    /// stored from their lower triangle); ascending, without repeats. An unknown out of range
    /// is an error.
    pub fn rows_touched_by(&self, changed: &[u32]) -> crate::Result<Vec<u32>> {
        let n = self.n_rows();
        if let Some(&c) = changed.iter().find(|&&c| c as usize >= n) {
            return Err(crate::Error::Linear(format!(
                "a masked view of order {n}: no unknown {c} to change"
            )));
        }
        let len = changed
            .iter()
            .map(|&c| 1 + self.a.row(c as usize).0.len())
            .sum();
        let mut rows = try_vec(len, "the rows touched by the changed unknowns")?;
        for &c in changed {
            rows.push(c);
            rows.extend_from_slice(self.a.row(c as usize).0);
        }
        rows.sort_unstable();
        rows.dedup();
        Ok(rows)
    }

    /// The view [`Self::new`] makes of the same A for the fixed unknowns `fixed`, made from
    /// this one: `rows` (ascending) must hold every row that differs between the two views,
    /// as [`Self::rows_touched_by`] the unknowns whose status differs gives them. Those rows
    /// are read from A again and the other patched rows copied, so that the cost is that of
    /// the patch and the touched rows, not a pass over A. Errors: `rows` not ascending or out
    /// of range, or arrays that cannot be allocated.
    pub fn remask<F>(&self, fixed: F, rows: &[u32]) -> crate::Result<Self>
    where
        F: Fn(usize) -> bool,
    {
        let (a, n) = (&self.a, self.n_rows());
        if rows.windows(2).any(|w| w[0] >= w[1]) || rows.last().is_some_and(|&r| r as usize >= n) {
            return Err(crate::Error::Linear(format!(
                "remasking a view of order {n}: the touched rows must be ascending and in range"
            )));
        }
        let mut touched = try_filled(n.div_ceil(64), 0u64, "the touched rows")?;
        let mut patched = try_copy(&self.patched, "the masked rows")?;
        for &i in rows {
            let (i, bit) = (i as usize, 1u64 << (i % 64));
            touched[i / 64] |= bit;
            if differs(a, &fixed, i) {
                patched[i / 64] |= bit;
            } else {
                patched[i / 64] &= !bit;
            }
        }
        let (rank, count) = ranks(&patched)?;
        // at most the old patch's entries and the touched rows' of A
        let bound = self.cols.len()
            + rows
                .iter()
                .map(|&i| a.row(i as usize).0.len())
                .sum::<usize>();
        let mut ptr: Vec<usize> = try_vec(count + 1, "the masked rows")?;
        let mut cols: Vec<u32> = try_vec(bound, "the masked rows")?;
        let mut vals: Vec<f64> = try_vec(bound, "the masked rows")?;
        ptr.push(0);
        let mut in_a = 0;
        for i in set_bits(&patched) {
            let bit = 1u64 << (i % 64);
            if touched[i / 64] & bit != 0 {
                push_masked_row(a, &fixed, i, &mut cols, &mut vals);
            } else {
                // untouched: patched before as now, the same row
                let (c, v) = self.patched_row(i, self.patched[i / 64] & (bit - 1));
                cols.extend_from_slice(c);
                vals.extend_from_slice(v);
            }
            in_a += a.row(i).0.len();
            ptr.push(cols.len());
        }
        let nnz = a.nnz() - in_a + cols.len();
        Ok(MaskedRows {
            a: a.clone(),
            patched,
            rank,
            ptr,
            cols,
            vals,
            nnz,
        })
    }

    /// Row i of the patch, `below` the bits of its word below bit i.
    #[inline]
    fn patched_row(&self, i: usize, below: u64) -> (&[u32], &[f64]) {
        let k = self.rank[i / 64] as usize + below.count_ones() as usize;
        let (s, e) = (self.ptr[k], self.ptr[k + 1]);
        (&self.cols[s..e], &self.vals[s..e])
    }

    /// The matrix A it masks.
    pub fn unmasked(&self) -> &Arc<CsrMatrix> {
        &self.a
    }

    /// Whether row i of S is in the patch (not A's row i: a fixed row, or a free row with an
    /// entry dropped, which an entry in a fixed column is).
    #[inline]
    pub fn is_patched(&self, i: usize) -> bool {
        self.patched[i / 64] & (1 << (i % 64)) != 0
    }

    /// Rows stored in the patch (the rows of S that are not A's).
    pub fn patched_rows(&self) -> usize {
        self.ptr.len() - 1
    }

    /// S stored by rows (a copy, to check the view against).
    #[cfg(test)]
    fn to_csr(&self) -> CsrMatrix {
        let n = self.n_rows();
        let mut row_ptr = vec![0usize; n + 1];
        let (mut col_idx, mut values) = (Vec::new(), Vec::new());
        for i in 0..n {
            let (c, v) = self.row(i);
            col_idx.extend_from_slice(c);
            values.extend_from_slice(v);
            row_ptr[i + 1] = col_idx.len();
        }
        CsrMatrix::from_parts(n, n, row_ptr, col_idx, values)
    }
}

/// Whether entry (i, j) of A, of value `v`, is an entry of S for the fixed unknowns `fixed`
/// (row i free): the diagonal, or a nonzero entry in a free column.
#[inline]
fn keep<F: Fn(usize) -> bool>(fixed: &F, i: usize, j: u32, v: f64) -> bool {
    j as usize == i || (v != 0.0 && !fixed(j as usize))
}

/// Whether row i of S differs from row i of A: a fixed row (unless A's is the unit row
/// already), or a free row that loses an entry.
#[inline]
fn differs<F: Fn(usize) -> bool>(a: &CsrMatrix, fixed: &F, i: usize) -> bool {
    let (cols, vals) = a.row(i);
    if fixed(i) {
        !(cols.len() == 1 && cols[0] as usize == i && vals[0] == 1.0)
    } else {
        cols.iter().zip(vals).any(|(&j, &v)| !keep(fixed, i, j, v))
    }
}

/// Appends row i of S to (`cols`, `vals`).
#[inline]
fn push_masked_row<F: Fn(usize) -> bool>(
    a: &CsrMatrix,
    fixed: &F,
    i: usize,
    cols: &mut Vec<u32>,
    vals: &mut Vec<f64>,
) {
    if fixed(i) {
        cols.push(i as u32);
        vals.push(1.0);
    } else {
        let (c, v) = a.row(i);
        for (&j, &x) in c.iter().zip(v).filter(|&(&j, &x)| keep(fixed, i, j, x)) {
            cols.push(j);
            vals.push(x);
        }
    }
}

/// The set bits of `patched` before each word, and in all.
fn ranks(patched: &[u64]) -> Result<(Vec<u32>, usize), AllocFailure> {
    let mut rank = try_filled(patched.len(), 0u32, "the masked rows")?;
    let mut count = 0usize;
    for (r, &bits) in rank.iter_mut().zip(patched) {
        *r = u32::try_from(count).unwrap_or(u32::MAX);
        count += bits.count_ones() as usize;
    }
    Ok((rank, count))
}

/// The rows whose bit is set in `patched`, ascending.
fn set_bits(patched: &[u64]) -> impl Iterator<Item = usize> + '_ {
    patched.iter().enumerate().flat_map(|(w, &bits)| {
        (0..64)
            .filter(move |b| bits & (1 << b) != 0)
            .map(move |b| w * 64 + b)
    })
}

impl Rows for MaskedRows {
    #[inline]
    fn n_rows(&self) -> usize {
        self.a.n_rows()
    }
    #[inline]
    fn n_cols(&self) -> usize {
        self.a.n_rows()
    }
    #[inline]
    fn nnz(&self) -> usize {
        self.nnz
    }
    #[inline(always)]
    fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let bits = self.patched[i / 64];
        let bit = 1u64 << (i % 64);
        if bits & bit == 0 {
            self.a.row(i)
        } else {
            self.patched_row(i, bits & (bit - 1))
        }
    }

    /// Word by word of the mask: the rows of a word with no patched row straight from A.
    #[inline(always)]
    fn for_rows<F: FnMut(usize, &[u32], &[f64])>(&self, rows: Range<usize>, mut f: F) {
        let (rp, ci, va) = (self.a.row_ptr(), self.a.col_idx(), self.a.values());
        let mut i = rows.start;
        while i < rows.end {
            let w = i / 64;
            let end = ((w + 1) * 64).min(rows.end);
            let bits = self.patched[w];
            // the patch rows of this word follow one another from the rank of row i; one call
            // of `f` in the loop, so that it is inlined
            let mut p =
                self.rank[w] as usize + (bits & ((1u64 << (i % 64)) - 1)).count_ones() as usize;
            for k in i..end {
                let (s, e, cols, vals) = if bits & (1 << (k % 64)) != 0 {
                    p += 1;
                    (self.ptr[p - 1], self.ptr[p], &self.cols[..], &self.vals[..])
                } else {
                    (rp[k], rp[k + 1], ci, va)
                };
                f(k, &cols[s..e], &vals[s..e]);
            }
            i = end;
        }
    }

    /// [`Rows::for_rows`] word by word, in decreasing order.
    #[inline(always)]
    fn for_rows_rev<F: FnMut(usize, &[u32], &[f64])>(&self, rows: Range<usize>, mut f: F) {
        let (rp, ci, va) = (self.a.row_ptr(), self.a.col_idx(), self.a.values());
        let mut end = rows.end;
        while end > rows.start {
            let w = (end - 1) / 64;
            let start = (w * 64).max(rows.start);
            let bits = self.patched[w];
            // the patch rows of this word, back from the count of those below row `end`
            let below_end = match end - w * 64 {
                64 => bits,
                r => bits & ((1u64 << r) - 1),
            };
            let mut p = self.rank[w] as usize + below_end.count_ones() as usize;
            for k in (start..end).rev() {
                let (s, e, cols, vals) = if bits & (1 << (k % 64)) != 0 {
                    p -= 1;
                    (self.ptr[p], self.ptr[p + 1], &self.cols[..], &self.vals[..])
                } else {
                    (rp[k], rp[k + 1], ci, va)
                };
                f(k, &cols[s..e], &vals[s..e]);
            }
            end = start;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::amg::testing::{fix, grid};

    /// The m × m grid matrix with an exact zero stored as the first entry of row `row`.
    fn grid_with_a_zero(m: usize, row: usize) -> CsrMatrix {
        let mut a = grid(m, 1.0, 1.0, &|_, _| 1.0);
        let p = a.row_ptr()[row];
        a.values_mut()[p] = 0.0;
        a
    }

    /// The unknowns of an m × m grid (row-major on the unit square) in the disc of centre
    /// (cx, cy) and squared radius r2.
    fn disc(m: usize, cx: f64, cy: f64, r2: f64) -> impl Fn(usize) -> bool + Copy + Sync {
        move |k: usize| {
            let (x, y) = (
                (k % m) as f64 / m as f64 - cx,
                (k / m) as f64 / m as f64 - cy,
            );
            x * x + y * y < r2
        }
    }

    #[test]
    fn the_masked_view_reads_the_rows_of_the_masked_copy() {
        // a grid with an exact zero stored off the diagonal, a disc of fixed unknowns, a fixed
        // unknown whose row is already the unit row, and scattered fixed ones
        let m = 120;
        let a = grid_with_a_zero(m, 500);
        let d = disc(m, 0.3, 0.6, 0.02);
        let fixed = |k: usize| d(k) || k.is_multiple_of(131);
        let mut unit = fix(&a, &|k| k == 7000);
        unit.drop_zeros();
        for a in [a, unit] {
            // S: the fixed rows and columns masked, the exact zeros dropped
            let mut copy = fix(&a, &fixed);
            copy.drop_zeros();
            let view = MaskedRows::new(Arc::new(a.clone()), fixed).unwrap();
            let stored = view.to_csr();
            assert_eq!(stored.row_ptr(), copy.row_ptr());
            assert_eq!(stored.col_idx(), copy.col_idx());
            assert_eq!(stored.values(), copy.values());
            assert_eq!(Rows::nnz(&view), copy.nnz());
            assert!(view.patched_rows() < m * m / 5, "{}", view.patched_rows());
            // the products give the bits of the copy's
            let x: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.37).sin()).collect();
            let (mut y0, mut y1) = (vec![0.0; m * m], vec![0.0; m * m]);
            copy.mul_to(&x, &mut y0);
            view.mul_to(&x, &mut y1);
            assert_eq!(y0, y1);
            assert_eq!(
                Rows::residual_norm(&copy, &x, &y0),
                view.residual_norm(&x, &y0)
            );
            assert_eq!(copy.try_diagonal().unwrap(), view.try_diagonal().unwrap());
        }
        // the runs of rows (forward and backward, across and within the words of the mask)
        // are the rows one by one
        let view = MaskedRows::new(Arc::new(grid(m, 1.0, 1.0, &|_, _| 1.0)), fixed).unwrap();
        for (r0, r1) in [
            (0, m * m),
            (5, 70),
            (64, 128),
            (130, 131),
            (1000, 7777),
            (9, 9),
        ] {
            let mut seen = Vec::new();
            view.for_rows(r0..r1, |i, c, v| seen.push((i, c.to_vec(), v.to_vec())));
            let rows: Vec<_> = (r0..r1)
                .map(|i| (i, view.row(i).0.to_vec(), view.row(i).1.to_vec()))
                .collect();
            assert_eq!(seen, rows);
            let mut back = Vec::new();
            view.for_rows_rev(r0..r1, |i, c, v| back.push((i, c.to_vec(), v.to_vec())));
            back.reverse();
            assert_eq!(back, rows);
        }
        // nothing fixed: A's rows, no patch; everything fixed: the identity
        let a = grid(30, 1.0, 1.0, &|_, _| 1.0);
        let none = MaskedRows::new(Arc::new(a.clone()), |_| false).unwrap();
        assert_eq!(none.patched_rows(), 0);
        assert_eq!(none.to_csr().values(), a.values());
        let all = MaskedRows::new(Arc::new(a), |_| true).unwrap();
        assert_eq!(Rows::nnz(&all), 900);
        assert_eq!(all.row(17), (&[17u32][..], &[1.0][..]));
        // not square: an error
        let rect = CsrMatrix::new(1, 2, vec![0, 1], vec![1], vec![1.0]).unwrap();
        let e = MaskedRows::new(Arc::new(rect), |_| false).unwrap_err();
        assert!(e.to_string().contains("square"), "{e}");
    }

    #[test]
    fn a_view_remasked_in_the_touched_rows_is_the_view_of_the_new_mask() {
        // a grid with an exact zero off the diagonal; the disc of fixed unknowns grows by a
        // ring on one side and shrinks on the other, scattered unknowns are fixed or freed
        let m = 90;
        let a = grid_with_a_zero(m, 700);
        let a = Arc::new(a);
        let (d0, d1) = (disc(m, 0.5, 0.5, 0.04), disc(m, 0.52, 0.5, 0.045));
        let f0 = move |k: usize| d0(k) || k.is_multiple_of(97);
        let f1 = move |k: usize| (d1(k) || k.is_multiple_of(89)) && k != 4095;
        let v0 = MaskedRows::new(a.clone(), f0).unwrap();
        let changed: Vec<u32> = (0..m * m)
            .filter(|&k| f0(k) != f1(k))
            .map(|k| k as u32)
            .collect();
        assert!(changed.len() > 50, "{}", changed.len());
        let rows = v0.rows_touched_by(&changed).unwrap();
        assert!(rows.windows(2).all(|w| w[0] < w[1]));
        assert!(rows.len() < m * m / 4, "{}", rows.len());
        let v1 = v0.remask(f1, &rows).unwrap();
        let fresh = MaskedRows::new(a.clone(), f1).unwrap();
        assert_eq!(v1.patched, fresh.patched);
        assert_eq!(v1.rank, fresh.rank);
        assert_eq!(v1.ptr, fresh.ptr);
        assert_eq!(v1.cols, fresh.cols);
        assert_eq!(v1.vals, fresh.vals);
        assert_eq!(Rows::nnz(&v1), Rows::nnz(&fresh));
        // and back again; with nothing changed, the same view
        let back = v1.remask(f0, &rows).unwrap();
        assert_eq!(back.to_csr().values(), v0.to_csr().values());
        assert_eq!((back.patched, back.nnz), (v0.patched.clone(), v0.nnz));
        let same = v0.remask(f0, &[]).unwrap();
        assert_eq!((same.ptr, same.cols), (v0.ptr.clone(), v0.cols.clone()));
        // rows that miss a changed unknown's neighbours give another view: the caller's
        // guarantee is needed
        let short = v0.remask(f1, &changed).unwrap();
        assert_ne!(short.to_csr().col_idx(), fresh.to_csr().col_idx());
        // rows out of order or of range, an unknown out of range: errors
        assert!(v0.remask(f1, &[5, 3]).is_err());
        assert!(v0.remask(f1, &[(m * m) as u32]).is_err());
        assert!(v0.rows_touched_by(&[(m * m) as u32]).is_err());
    }
}
