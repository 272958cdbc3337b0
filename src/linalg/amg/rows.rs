//! Building a sparse matrix row by row, in parallel, with a result that does not depend on
//! the threads: the row lengths counted first, then the rows written in place
//! ([`build_counted_rows`]), so that the entries are held once.

use crate::budget::{AllocFailure, try_filled};
use crate::linalg::csr::{CsrMatrix, ROW_CHUNK};
use rayon::prelude::*;

/// Builds a matrix row by row in parallel in two passes, so that its entries are held once:
/// `count(scratch, i)` gives the number of entries of row i, the offsets follow, the arrays of
/// the matrix are allocated at their exact size, and `fill(scratch, i, cols, vals)` writes row
/// i into its slices (of that length). Building each chunk's rows in buffers and concatenating
/// them, as this did before, held about twice the matrix at that moment, which set the peak
/// memory of a multigrid setup (the product R A of the Galerkin operator, the prolongator);
/// this reads the inputs twice instead. The result does not depend on the threads. [`AllocFailure`] if the scratch or the
/// arrays cannot be allocated.
pub(super) fn build_counted_rows<S, I, C, F>(
    n_rows: usize,
    n_cols: usize,
    init: I,
    count: C,
    fill: F,
) -> Result<CsrMatrix, AllocFailure>
where
    S: Send,
    I: Fn() -> Result<S, AllocFailure> + Sync + Send,
    C: Fn(&mut S, usize) -> usize + Sync + Send,
    F: Fn(&mut S, usize, &mut [u32], &mut [f64]) + Sync + Send,
{
    let mut row_ptr = try_filled(n_rows + 1, 0usize, "the row offsets of a multigrid matrix")?;
    // the row lengths, then their prefix sums (row i + 1's slot holds row i's length first)
    row_ptr[1..]
        .par_chunks_mut(ROW_CHUNK)
        .enumerate()
        .try_for_each_init(&init, |s, (c, lens)| {
            let s = s.as_mut().map_err(|f| f.clone())?;
            for (k, l) in lens.iter_mut().enumerate() {
                *l = count(s, c * ROW_CHUNK + k);
            }
            Ok::<(), AllocFailure>(())
        })?;
    for i in 0..n_rows {
        row_ptr[i + 1] += row_ptr[i];
    }
    let nnz = row_ptr[n_rows];
    let mut col_idx = try_filled(nnz, 0u32, "the column indices of a multigrid matrix")?;
    let mut values = try_filled(nnz, 0.0f64, "the entries of a multigrid matrix")?;
    // each chunk's slices of the arrays, in order
    let n_chunks = n_rows.div_ceil(ROW_CHUNK);
    let mut pieces: Vec<(usize, &mut [u32], &mut [f64])> = Vec::with_capacity(n_chunks);
    let (mut ci, mut va) = (&mut col_idx[..], &mut values[..]);
    for c in 0..n_chunks {
        let (i0, i1) = (c * ROW_CHUNK, ((c + 1) * ROW_CHUNK).min(n_rows));
        let len = row_ptr[i1] - row_ptr[i0];
        let (c0, c1) = std::mem::take(&mut ci).split_at_mut(len);
        let (v0, v1) = std::mem::take(&mut va).split_at_mut(len);
        pieces.push((c, c0, v0));
        (ci, va) = (c1, v1);
    }
    let row_ptr_ref = &row_ptr;
    pieces
        .into_par_iter()
        .try_for_each_init(&init, |s, (c, cols, vals)| {
            let s = s.as_mut().map_err(|f| f.clone())?;
            let (i0, i1) = (c * ROW_CHUNK, ((c + 1) * ROW_CHUNK).min(n_rows));
            let base = row_ptr_ref[i0];
            for i in i0..i1 {
                let (a, b) = (row_ptr_ref[i] - base, row_ptr_ref[i + 1] - base);
                fill(s, i, &mut cols[a..b], &mut vals[a..b]);
            }
            Ok::<(), AllocFailure>(())
        })?;
    Ok(CsrMatrix::from_parts(
        n_rows, n_cols, row_ptr, col_idx, values,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::csr::PAR_MIN_NNZ;

    #[test]
    fn rows_counted_then_written_in_place_are_the_rows() {
        // row i: columns (i * 7 + k²) mod n for k ≤ i % 6, deduplicated, unsorted on purpose
        // (the order written is kept), value i − j / 3; below one chunk, and several chunks
        // (in parallel)
        for n in [9, 3 * ROW_CHUNK + 17, PAR_MIN_NNZ + 5] {
            let row = |i: usize| -> Vec<(u32, f64)> {
                let mut seen = std::collections::BTreeSet::new();
                (0..=i % 6)
                    .map(|k| ((i * 7 + k * k) % n) as u32)
                    .filter(|&j| seen.insert(j))
                    .map(|j| (j, i as f64 - j as f64 / 3.0))
                    .collect()
            };
            let two = build_counted_rows(
                n,
                n,
                || Ok(0usize),
                |counted, i| {
                    *counted += 1;
                    row(i).len()
                },
                |_, i, cols, vals| {
                    let r = row(i);
                    assert_eq!((cols.len(), vals.len()), (r.len(), r.len()), "row {i}");
                    for (k, (j, v)) in r.into_iter().enumerate() {
                        cols[k] = j;
                        vals[k] = v;
                    }
                },
            )
            .unwrap();
            let nnz: usize = (0..n).map(|i| row(i).len()).sum();
            assert_eq!((two.n_rows(), two.n_cols(), two.nnz()), (n, n, nnz));
            for i in 0..n {
                let (c, v) = two.row(i);
                let expected = row(i);
                assert_eq!(c.len(), expected.len(), "row {i}");
                for ((&cj, &vj), &(ej, ev)) in c.iter().zip(v).zip(&expected) {
                    assert_eq!((cj, vj.to_bits()), (ej, ev.to_bits()), "row {i}");
                }
            }
        }
    }
}
