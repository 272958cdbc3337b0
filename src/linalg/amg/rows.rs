//! Building a sparse matrix row by row, in parallel, with a result that does not depend on
//! the threads: in one pass (the rows computed in fixed chunks and concatenated in order,
//! [`build_rows`]: for rows that are expensive to compute and a matrix that is small beside
//! the inputs), or in two (the row lengths counted first, then the rows written in place,
//! [`build_counted_rows`]: the entries are held once).

use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::linalg::csr::{CsrMatrix, PAR_MIN_NNZ, ROW_CHUNK};
use rayon::prelude::*;

/// Builds a matrix row by row in parallel: `row(scratch, i, cols, vals)` appends the entries
/// of row i (sorted by column) to `cols` and `vals`, reserving their room first
/// ([`try_grow`](crate::budget::try_grow)); `init` makes the per-thread scratch.
/// [`AllocFailure`] if the scratch or the arrays of the matrix cannot be allocated (the
/// entries of one chunk of [`ROW_CHUNK`] rows grow as the rows are appended).
pub(super) fn build_rows<S, I, F>(
    n_rows: usize,
    n_cols: usize,
    init: I,
    row: F,
) -> Result<CsrMatrix, AllocFailure>
where
    S: Send,
    I: Fn() -> Result<S, AllocFailure> + Sync + Send,
    F: Fn(&mut S, usize, &mut Vec<u32>, &mut Vec<f64>) -> Result<(), AllocFailure> + Sync + Send,
{
    let n_chunks = n_rows.div_ceil(ROW_CHUNK);
    let parts: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..n_chunks)
        .into_par_iter()
        .map_init(&init, |s, c| {
            let s = s.as_mut().map_err(|f| f.clone())?;
            let (i0, i1) = (c * ROW_CHUNK, ((c + 1) * ROW_CHUNK).min(n_rows));
            let mut lens = try_vec(i1 - i0, "the row lengths of a multigrid matrix")?;
            let mut cols = Vec::new();
            let mut vals = Vec::new();
            for i in i0..i1 {
                let before = cols.len();
                row(s, i, &mut cols, &mut vals)?;
                lens.push(cols.len() - before);
            }
            Ok((lens, cols, vals))
        })
        .collect::<Result<_, AllocFailure>>()?;
    // concatenate the chunks in parallel: the offsets of each chunk's rows and entries first
    let mut starts = Vec::with_capacity(parts.len() + 1);
    starts.push(0usize);
    for p in &parts {
        starts.push(starts[starts.len() - 1] + p.1.len());
    }
    let nnz = starts[parts.len()];
    let mut row_ptr = try_filled(n_rows + 1, 0usize, "the row offsets of a multigrid matrix")?;
    let mut col_idx = try_filled(nnz, 0u32, "the column indices of a multigrid matrix")?;
    let mut values = try_filled(nnz, 0.0f64, "the entries of a multigrid matrix")?;
    row_ptr[n_rows] = nnz;
    // (the chunk's lengths, columns and values; its parts of row_ptr, col_idx, values; the
    // offset of its first entry)
    type Piece<'p> = (
        &'p (Vec<usize>, Vec<u32>, Vec<f64>),
        &'p mut [usize],
        &'p mut [u32],
        &'p mut [f64],
        usize,
    );
    let mut pieces: Vec<Piece> = Vec::with_capacity(parts.len());
    let (mut rp, mut ci, mut va) = (&mut row_ptr[..n_rows], &mut col_idx[..], &mut values[..]);
    for (p, &start) in parts.iter().zip(&starts) {
        let (r0, r1) = std::mem::take(&mut rp).split_at_mut(p.0.len());
        let (c0, c1) = std::mem::take(&mut ci).split_at_mut(p.1.len());
        let (v0, v1) = std::mem::take(&mut va).split_at_mut(p.2.len());
        pieces.push((p, r0, c0, v0, start));
        (rp, ci, va) = (r1, c1, v1);
    }
    let fill = |((lens, cols, vals), r, c, v, start): Piece| {
        let mut acc = start;
        for (rk, &l) in r.iter_mut().zip(lens) {
            *rk = acc;
            acc += l;
        }
        c.copy_from_slice(cols);
        v.copy_from_slice(vals);
    };
    if nnz < PAR_MIN_NNZ {
        pieces.into_iter().for_each(fill);
    } else {
        pieces.into_par_iter().for_each(fill);
    }
    Ok(CsrMatrix::from_parts(
        n_rows, n_cols, row_ptr, col_idx, values,
    ))
}

/// Builds a matrix row by row in parallel in two passes, so that its entries are held once:
/// `count(scratch, i)` gives the number of entries of row i, the offsets follow, the arrays of
/// the matrix are allocated at their exact size, and `fill(scratch, i, cols, vals)` writes row
/// i into its slices (of that length). [`build_rows`] holds about twice the matrix while it
/// concatenates the chunks, which set the peak memory of a multigrid setup when it built the
/// prolongator and the product R A; this computes every row twice instead. The result does
/// not depend on the threads. [`AllocFailure`] if the scratch or the arrays cannot be
/// allocated.
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

    #[test]
    fn rows_built_in_parallel_are_concatenated_in_order() {
        // row i holds the columns i, i + 1, …, i + i % 5 (mod n) sorted, value i + j / 8;
        // below and far above the parallel thresholds
        for n in [10, 3 * ROW_CHUNK + 11, PAR_MIN_NNZ + 5] {
            let row = |i: usize| -> Vec<(u32, f64)> {
                let mut r: Vec<u32> = (0..=i % 5).map(|k| ((i + k) % n) as u32).collect();
                r.sort_unstable();
                r.dedup();
                r.iter().map(|&j| (j, i as f64 + j as f64 / 8.0)).collect()
            };
            let m = build_rows(
                n,
                n,
                || Ok(0usize),
                |calls, i, cols, vals| {
                    *calls += 1;
                    for (j, v) in row(i) {
                        cols.push(j);
                        vals.push(v);
                    }
                    Ok(())
                },
            )
            .unwrap();
            assert_eq!((m.n_rows(), m.n_cols()), (n, n));
            for i in 0..n {
                let (c, v) = m.row(i);
                let expected = row(i);
                assert_eq!(c.len(), expected.len(), "row {i}");
                for ((&cj, &vj), &(ej, ev)) in c.iter().zip(v).zip(&expected) {
                    assert_eq!((cj, vj), (ej, ev), "row {i}");
                }
            }
        }
    }

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
                || Ok(()),
                |_, i| row(i).len(),
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
