//! The Galerkin product A_{ℓ+1} = Pᵀ A_ℓ P (step 5 of the setup, see [`super`]).

use super::NONE;
use super::rows::build_counted_rows;
use crate::budget::{AllocFailure, try_filled};
use crate::linalg::csr::CsrMatrix;

/// A dense accumulator of a sparse row: the values by column and the list of touched columns.
struct Accumulator {
    /// Position of each column in `cols`, or [`NONE`].
    pos: Vec<u32>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl Accumulator {
    fn new(n: usize) -> Result<Self, AllocFailure> {
        Ok(Accumulator {
            pos: try_filled(n, NONE, "the row accumulator of the Galerkin product")?,
            cols: Vec::new(),
            vals: Vec::new(),
        })
    }
    #[inline(always)]
    fn add(&mut self, j: u32, v: f64) {
        let p = self.pos[j as usize];
        if p == NONE {
            self.pos[j as usize] = self.cols.len() as u32;
            self.cols.push(j);
            self.vals.push(v);
        } else {
            self.vals[p as usize] += v;
        }
    }
    /// Marks column j as touched, without a value (the counting pass).
    #[inline(always)]
    fn touch(&mut self, j: u32) {
        if self.pos[j as usize] == NONE {
            self.pos[j as usize] = self.cols.len() as u32;
            self.cols.push(j);
        }
    }
    /// The number of touched columns, the accumulator cleared.
    fn take_count(&mut self) -> usize {
        for &c in &self.cols {
            self.pos[c as usize] = NONE;
        }
        let n = self.cols.len();
        self.cols.clear();
        self.vals.clear();
        n
    }
    /// Writes the row into `cols` and `vals` (of its length), sorted by column if `sorted`,
    /// else in the order of first touch, and clears the accumulator.
    fn drain_to(&mut self, cols: &mut [u32], vals: &mut [f64], sorted: bool) {
        debug_assert_eq!(cols.len(), self.cols.len());
        if sorted {
            self.cols.sort_unstable();
            for ((&c, oc), ov) in self.cols.iter().zip(cols.iter_mut()).zip(vals.iter_mut()) {
                *oc = c;
                *ov = self.vals[self.pos[c as usize] as usize];
                self.pos[c as usize] = NONE;
            }
        } else {
            for &c in &self.cols {
                self.pos[c as usize] = NONE;
            }
            cols.copy_from_slice(&self.cols);
            vals.copy_from_slice(&self.vals);
        }
        self.cols.clear();
        self.vals.clear();
    }
}

/// A_c = Pᵀ A P in two row-parallel products (see the module documentation): R A with
/// R = Pᵀ, row J = Σ_{i : r_Ji ≠ 0} r_Ji A_i (its columns left in the order they are met: only
/// read below), R freed, then row J of A_c = Σ_k (R A)_Jk P_k. [`AllocFailure`] if the
/// products cannot be allocated.
pub(super) fn galerkin(
    a: &CsrMatrix,
    p: &CsrMatrix,
    r: CsrMatrix,
) -> Result<CsrMatrix, AllocFailure> {
    let ra = product(&r, a, false)?;
    drop(r);
    product(&ra, p, true)
}

/// The sparse product L M, row J = Σ_k l_Jk M_k, zero entries of M skipped; each row's
/// columns sorted if `sorted`, else in the order they are met. Two passes (the row lengths,
/// then the rows in place, [`build_counted_rows`]), so that the product is held once.
fn product(l: &CsrMatrix, m: &CsrMatrix, sorted: bool) -> Result<CsrMatrix, AllocFailure> {
    let n = m.n_cols();
    build_counted_rows(
        l.n_rows(),
        n,
        || Accumulator::new(n),
        |acc, row| {
            for &k in l.row(row).0 {
                let (mc, mv) = m.row(k as usize);
                for (&j, &mkj) in mc.iter().zip(mv) {
                    if mkj != 0.0 {
                        acc.touch(j);
                    }
                }
            }
            acc.take_count()
        },
        |acc, row, cols, vals| {
            let (lc, lv) = l.row(row);
            for (&k, &lk) in lc.iter().zip(lv) {
                let (mc, mv) = m.row(k as usize);
                for (&j, &mkj) in mc.iter().zip(mv) {
                    if mkj != 0.0 {
                        acc.add(j, lk * mkj);
                    }
                }
            }
            acc.drain_to(cols, vals, sorted)
        },
    )
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::*;

    #[test]
    fn the_galerkin_product_is_pt_a_p() {
        // A large enough that the rows are built in parallel; P with two entries per row
        for m in [7, 120] {
            let a = grid(m, 1.0, 0.3, &|i, j| 1.0 + ((i * j) % 5) as f64);
            let (n, nc) = (m * m, m * m / 4 + 1);
            let (mut rp, mut cols, mut vals) = (vec![0], vec![], vec![]);
            for i in 0..n {
                let (c0, c1) = (i / 4, (i * 7 + 3) % nc);
                let mut row = vec![(c0 as u32, 1.0), (c1 as u32, 0.5 - (i % 3) as f64)];
                row.sort_by_key(|e| e.0);
                row.dedup_by_key(|e| e.0);
                for (c, v) in row {
                    cols.push(c);
                    vals.push(v);
                }
                rp.push(cols.len());
            }
            let p = CsrMatrix::new(n, nc, rp, cols, vals).unwrap();
            let ac = galerkin(&a, &p, p.transpose().unwrap()).unwrap();
            assert_eq!((ac.n_rows(), ac.n_cols()), (nc, nc));
            // column J of A_c against Pᵀ (A (P e_J)), for a few J
            for jc in [0, 1, nc / 2, nc - 1] {
                let mut e = vec![0.0; nc];
                e[jc] = 1.0;
                let (mut pe, mut ape, mut col) = (vec![0.0; n], vec![0.0; n], vec![0.0; nc]);
                p.spmv(&e, &mut pe).unwrap();
                a.spmv(&pe, &mut ape).unwrap();
                p.mul_transpose_to(&ape, &mut col);
                let mut got = vec![0.0; nc];
                ac.spmv(&e, &mut got).unwrap();
                for (g, c) in got.iter().zip(&col) {
                    assert!((g - c).abs() <= 1e-12 * c.abs().max(1.0), "{g} vs {c}");
                }
            }
            // sorted rows
            assert!((0..nc).all(|i| ac.row(i).0.windows(2).all(|w| w[0] < w[1])));
        }
    }
}
