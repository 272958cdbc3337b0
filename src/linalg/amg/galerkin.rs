//! The Galerkin product A_{ℓ+1} = Pᵀ A_ℓ P (step 5 of the setup, see [`super`]).

use super::NONE;
use super::rows::build_rows;
use crate::budget::{AllocFailure, try_filled, try_grow};
use crate::linalg::csr::CsrMatrix;
use crate::linalg::rows::Rows;

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
    /// Clears the accumulator.
    fn clear(&mut self) {
        for &c in &self.cols {
            self.pos[c as usize] = NONE;
        }
        self.cols.clear();
        self.vals.clear();
    }
    /// Appends the row, sorted by column, and clears the accumulator.
    fn drain_into(&mut self, cols: &mut Vec<u32>, vals: &mut Vec<f64>) -> Result<(), AllocFailure> {
        let what = "the entries of a Galerkin product";
        try_grow(cols, self.cols.len(), what)?;
        try_grow(vals, self.cols.len(), what)?;
        self.cols.sort_unstable();
        for &c in &self.cols {
            let p = self.pos[c as usize] as usize;
            cols.push(c);
            vals.push(self.vals[p]);
            self.pos[c as usize] = NONE;
        }
        self.cols.clear();
        self.vals.clear();
        Ok(())
    }
}

/// A_c = Pᵀ A P row by row (see the module documentation): row J of R A (R = Pᵀ),
/// Σ_{i : r_Ji ≠ 0} r_Ji A_i, in one accumulator (its columns in the order they are met), then
/// row J of A_c = Σ_k (R A)_Jk P_k in another, sorted; R A is not stored. The same sums in the
/// same order as forming R A first. [`AllocFailure`] if A_c or the accumulators cannot be
/// allocated.
pub(super) fn galerkin<A: Rows + ?Sized>(
    a: &A,
    p: &CsrMatrix,
    r: &CsrMatrix,
) -> Result<CsrMatrix, AllocFailure> {
    let (nf, nc) = (a.n_cols(), p.n_cols());
    build_rows(
        r.n_rows(),
        nc,
        || Ok((Accumulator::new(nf)?, Accumulator::new(nc)?)),
        |(ra, ac), row, cols, vals| {
            let (rc, rv) = r.row(row);
            for (&i, &rji) in rc.iter().zip(rv) {
                let (mc, mv) = a.row(i as usize);
                for (&k, &aik) in mc.iter().zip(mv) {
                    if aik != 0.0 {
                        ra.add(k, rji * aik);
                    }
                }
            }
            for (&k, &rak) in ra.cols.iter().zip(&ra.vals) {
                let (pc, pv) = p.row(k as usize);
                for (&j, &pkj) in pc.iter().zip(pv) {
                    if pkj != 0.0 {
                        ac.add(j, rak * pkj);
                    }
                }
            }
            ra.clear();
            ac.drain_into(cols, vals)
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
            let ac = galerkin(&a, &p, &p.transpose().unwrap()).unwrap();
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
