//! Strength of connection: which couplings of A_ℓ are strong (step 1 of the setup, see
//! [`super`]).

use crate::budget::{AllocFailure, try_filled};
use crate::linalg::csr::{PAR_MIN_NNZ, ROW_CHUNK};
use crate::linalg::rows::Rows;
use rayon::prelude::*;

/// The strong off-diagonal entries of A, a_ij ≠ 0 with a_ij² ≥ θ² a_ii a_jj, whatever their
/// sign, as a flag per stored entry of A (in the order of its values; `rp` the offsets of
/// its rows, [`Rows::offsets`]).
/// (`replication/BENCHMARKS.md`, "Measurements behind the defaults", compares this rule with
/// counting only the negative couplings as strong.) [`AllocFailure`] if the flags cannot be
/// allocated.
pub(super) fn strength<A: Rows + ?Sized>(
    a: &A,
    rp: &[usize],
    diag: &[f64],
    theta: f64,
) -> Result<Vec<bool>, AllocFailure> {
    let t2 = theta * theta;
    let mut strong = try_filled(rp[a.n_rows()], false, "the strong couplings of the matrix")?;
    let fill = |i0: usize, flags: &mut [bool]| {
        let base = rp[i0];
        let mut i = i0;
        while base + flags.len() > rp[i] {
            let di = diag[i];
            let (cols, vals) = a.row(i);
            let f = &mut flags[rp[i] - base..rp[i + 1] - base];
            for ((f, &j), &v) in f.iter_mut().zip(cols).zip(vals) {
                let j = j as usize;
                *f = j != i && v != 0.0 && v * v >= t2 * di * diag[j];
            }
            i += 1;
        }
    };
    for_entry_chunks(a, rp, &mut strong, fill);
    Ok(strong)
}

/// Runs `f(i0, part)` on the parts of a per-entry array `x` of `a` that hold rows
/// `i0..i0 + ROW_CHUNK` (in parallel when `a` is large).
fn for_entry_chunks<A: Rows + ?Sized, T: Send, F>(a: &A, rp: &[usize], x: &mut [T], f: F)
where
    F: Fn(usize, &mut [T]) + Sync + Send,
{
    let n = a.n_rows();
    if a.nnz() < PAR_MIN_NNZ {
        if n > 0 {
            f(0, x);
        }
        return;
    }
    let mut parts = Vec::with_capacity(n.div_ceil(ROW_CHUNK));
    let mut rest = x;
    for i0 in (0..n).step_by(ROW_CHUNK) {
        let i1 = (i0 + ROW_CHUNK).min(n);
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(rp[i1] - rp[i0]);
        parts.push((i0, head));
        rest = tail;
    }
    parts.into_par_iter().for_each(|(i0, part)| f(i0, part));
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::*;

    #[test]
    fn only_the_strong_direction_of_an_anisotropic_diffusion_is_strong() {
        // couplings 0.01 in x (neighbours j = i ± 1), 1 in y (j = i ± m); a_ii ≈ 2
        for m in [12, 150] {
            let a = grid(m, 0.01, 1.0, &|_, _| 1.0);
            let d = a.diagonal();
            let flags = strength(&a, a.row_ptr(), &d, 0.08).unwrap();
            let mut n_strong = 0;
            for i in 0..a.n_rows() {
                let r = a.row_ptr()[i]..a.row_ptr()[i + 1];
                for (&j, &s) in a.col_idx()[r.clone()].iter().zip(&flags[r]) {
                    let vertical = (j as usize).abs_diff(i) == m;
                    assert_eq!(s, vertical, "m = {m}, entry ({i}, {j})");
                    n_strong += s as usize;
                }
            }
            assert_eq!(n_strong, 2 * m * (m - 1));
            // θ = 0: every off-diagonal nonzero
            let all = strength(&a, a.row_ptr(), &d, 0.0).unwrap();
            assert_eq!(all.iter().filter(|&&s| s).count(), a.nnz() - a.n_rows());
        }
    }
}
