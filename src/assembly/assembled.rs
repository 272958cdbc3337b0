//! Schemes without interior unknowns (P1, mass-lumped Crouzeix–Raviart): the global matrix
//! assembled once, and each solve's system masked from it.
//!
//! When no cell has interior unknowns, the condensed matrix is the global matrix
//! M = Σ_K P_Kᵀ M_K P_K itself, and fixing unknowns only masks its rows and columns. The
//! system therefore assembles M once, when it is built, and stores it by rows (both
//! triangles, exact zeros dropped): the local matrices and loads are computed batch by batch
//! of cells and added into M and b at once ([`ProblemValues::evaluate_assembled`]), so that
//! they are never all held. A solve with the fixed unknowns F (values u_F) reads
//!
//!   S_ij = M_ij for i, j ∉ F,   S_ii = 1 for i ∈ F,   S_ij = 0 else,
//!   c_i  = b_i − Σ_{j ∈ F} M_ij u_j for i ∉ F,   c_i = u_i for i ∈ F,
//!
//! (b the full load, Neumann data included) from M and b alone, and so do the residual, the
//! energy and the rows the algorithms read. This is the system the cell-by-cell gather of
//! [`super::gather`] builds for schemes with interior unknowns, and the same bits for S: each
//! entry M_ij is the sum of its cells' contributions in cell order, as that gather sums them.
//! c, the residual and its scale are sums of the same terms in another order (per row of M
//! instead of per cell), equal up to round-off.
//!
//! The iterative solves never store S: the conjugate gradients and the multigrid read it
//! through a masked view of M ([`MaskedRows`]), which keeps only the rows of S that are not
//! M's (the rows of F and of their neighbours). The direct solver factorises S's values on
//! the lower pattern (`masked_lower`).
//!
//! Memory (measured in `replication/measurements/memory3d.md`): per tetrahedron, the 10 packed
//! local entries and 4 local loads (112 bytes) and the 10 gather sources (40 bytes) are never
//! all held; M takes 12 bytes per stored entry, about 15 entries per unknown on tetrahedra.

use super::DiscreteSystem;
#[cfg(doc)]
use super::ProblemValues;
use super::gather::{Pinned, chunks, split_by_ranges};
use super::iterative::{NextHierarchy, Reused};
use super::symbolic::DofMap;
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::linalg::amg::Fine;
use crate::linalg::{CsrMatrix, MaskedRows, SpdPattern};
use crate::mesh::SolveMesh;
use crate::offsets::Offsets;
use rayon::prelude::*;
use std::sync::Arc;

/// Unknowns (rows or columns) per parallel task.
const ROWS: usize = 1 << 14;

/// Adds the packed local matrices `mats` of the cells `b0..b1` (cell k's at
/// `mat_ptr.range(k)`, shifted by `mat_ptr.at(b0)`, in the order of its unknowns in `dm`) into
/// `lower`, the values of M's lower triangle on the lower CSC pattern (`col_ptr`, `row_idx`) of
/// the condensed matrix. The columns are split among the threads (at equal entries), each
/// thread visiting the cells in order and taking the entries (r, c), r ≥ c, of its columns: each
/// entry sums its contributions in cell order, whatever the number of threads, as the gather
/// of [`super::gather`] does.
pub(super) fn scatter(
    dm: &DofMap,
    (b0, b1): (usize, usize),
    (col_ptr, row_idx): (&[usize], &[usize]),
    mats: &[f64],
    mat_ptr: &Offsets,
    lower: &mut [f64],
) -> crate::Result<()> {
    let n = col_ptr.len() - 1;
    let parts = rayon::current_num_threads().clamp(1, n.max(1));
    let nnz = row_idx.len();
    let mut cuts: Vec<usize> = (0..=parts)
        .map(|t| col_ptr.partition_point(|&q| q < nnz * t / parts).min(n))
        .collect();
    (cuts[0], cuts[parts]) = (0, n);
    let ranges: Vec<(usize, usize)> = cuts.windows(2).map(|w| (w[0], w[1].max(w[0]))).collect();
    let slices = split_by_ranges(lower, &ranges, |c| col_ptr[c]);
    let m0 = mat_ptr.at(b0);
    ranges
        .into_par_iter()
        .zip(slices)
        .try_for_each(|((c0, c1), out)| -> crate::Result<()> {
            let base = col_ptr[c0];
            for k in b0..b1 {
                let (d, _) = dm.cell(k);
                let r = mat_ptr.range(k);
                let m = &mats[r.start - m0..r.end - m0];
                // the packed lower triangle, column b, rows a ≥ b
                let mut t = 0;
                for (b, &j) in d.iter().enumerate() {
                    for &i in &d[b..] {
                        let (row, col) = ((i.max(j)) as usize, (i.min(j)) as usize);
                        if (c0..c1).contains(&col) {
                            let rows = &row_idx[col_ptr[col]..col_ptr[col + 1]];
                            let q = rows.binary_search(&row).map_err(|_| {
                                crate::Error::Internal(format!(
                                    "entry ({row}, {col}) of cell {k} is not in the pattern"
                                ))
                            })?;
                            out[col_ptr[col] + q - base] += m[t];
                        }
                        t += 1;
                    }
                }
            }
            Ok(())
        })
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// The assembled matrix M of a scheme without interior unknowns, `None` for the others.
    pub fn assembled(&self) -> Option<&CsrMatrix> {
        self.values.assembled.as_deref()
    }

    /// S of the module docs as a masked view of M ([`MaskedRows`]: the rows of S that are
    /// not M's, M shared; a product with it gives the bits of a product with S stored by rows
    /// without its exact zeros, bitwise the stored rows of the gathered system): what the
    /// conjugate gradients and the multigrid read.
    pub(super) fn masked_rows(&self, fx: &Pinned) -> crate::Result<MaskedRows> {
        let a = self.values.assembled.clone().ok_or_else(|| {
            crate::Error::Internal("a masked view of a system without an assembled matrix".into())
        })?;
        MaskedRows::new(a, |i| fx.get(i).is_some())
    }

    /// [`Self::masked_rows`], and the hierarchy `next` for it: when `next` reuses a whole
    /// hierarchy whose fine matrix is a view of the same M ([`Reused::Whole`]), the view is
    /// made from that one in the rows the unknowns whose status changed touch
    /// ([`MaskedRows::remask`], the same view) and `next` carries those rows
    /// ([`Reused::Rows`]), so that neither the view nor the fine level takes a pass over M.
    pub(super) fn masked_rows_reusing(
        &self,
        fx: &Pinned,
        next: NextHierarchy,
    ) -> crate::Result<(MaskedRows, NextHierarchy)> {
        let NextHierarchy::Reuse {
            levels: Reused::Whole { amg, fine_mask },
            fresh_rate,
            built_for,
            current,
        } = next
        else {
            return Ok((self.masked_rows(fx)?, next));
        };
        let same = match (amg.fine(), &self.values.assembled) {
            (Fine::Masked(v), Some(a)) => Arc::ptr_eq(v.unmasked(), a),
            _ => false,
        };
        let (view, levels) = match amg.fine() {
            Fine::Masked(v) if same && fine_mask.len() == current.len() => {
                let changed = changed_bits(&fine_mask, &current)?;
                let rows = v.rows_touched_by(&changed)?;
                let view = v.remask(|i| fx.get(i).is_some(), &rows)?;
                (view, Reused::Rows { amg, rows })
            }
            _ => (self.masked_rows(fx)?, Reused::Whole { amg, fine_mask }),
        };
        Ok((
            view,
            NextHierarchy::Reuse {
                levels,
                fresh_rate,
                built_for,
                current,
            },
        ))
    }

    /// The values of S on `pattern`, the lower CSC pattern of the condensed matrix (what the
    /// direct solver factorises; bitwise the gathered values): column c of the pattern is
    /// read from row c of M, right of the diagonal (M is symmetric), entries M dropped as
    /// zero read 0.
    pub(super) fn masked_lower(
        &self,
        a: &CsrMatrix,
        fx: &Pinned,
        pattern: &SpdPattern,
    ) -> crate::Result<Vec<f64>> {
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let n = col_ptr.len() - 1;
        let mut lower = try_filled(row_idx.len(), 0.0, "the values of the condensed matrix")?;
        let ranges = chunks(n, ROWS);
        let slices = split_by_ranges(&mut lower, &ranges, |c| col_ptr[c]);
        ranges
            .into_par_iter()
            .zip(slices)
            .for_each(|((c0, c1), out)| {
                let base = col_ptr[c0];
                for c in c0..c1 {
                    let (cols, vals) = a.row(c);
                    let mut p = cols.partition_point(|&j| (j as usize) < c);
                    let col_fixed = fx.get(c).is_some();
                    for q in col_ptr[c]..col_ptr[c + 1] {
                        let r = row_idx[q];
                        while p < cols.len() && (cols[p] as usize) < r {
                            p += 1;
                        }
                        let m = if p < cols.len() && cols[p] as usize == r {
                            vals[p]
                        } else {
                            0.0
                        };
                        out[q - base] = if col_fixed || fx.get(r).is_some() {
                            if r == c { 1.0 } else { 0.0 }
                        } else {
                            m
                        };
                    }
                }
            });
        Ok(lower)
    }

    /// c of the module docs, rows in parallel.
    pub(super) fn masked_rhs(&self, a: &CsrMatrix, fx: &Pinned) -> crate::Result<Vec<f64>> {
        self.masked_rhs_rows(a, fx, |_| true)
    }

    /// [`Self::masked_rhs`] knowing the view `s` of M for the same fixed unknowns
    /// ([`Self::masked_rows`]): a free row that is not in its patch has no entry in a fixed
    /// column, so that c_i = b_i there without reading the row (bitwise the same c).
    pub(super) fn masked_rhs_of_view(
        &self,
        s: &MaskedRows,
        fx: &Pinned,
    ) -> crate::Result<Vec<f64>> {
        self.masked_rhs_rows(s.unmasked(), fx, |i| s.is_patched(i))
    }

    /// [`Self::masked_rhs`], reading row i of M only if `read(i)` (otherwise c_i = b_i for a
    /// free row).
    fn masked_rhs_rows(
        &self,
        a: &CsrMatrix,
        fx: &Pinned,
        read: impl Fn(usize) -> bool + Sync,
    ) -> crate::Result<Vec<f64>> {
        let load = &self.values.load;
        let mut c = try_filled(a.n_rows(), 0.0, "the right-hand side")?;
        c.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, ci)| {
                *ci = match fx.get(i) {
                    Some(v) => v,
                    None if !read(i) => load[i],
                    None => {
                        let (cols, vals) = a.row(i);
                        let mut acc = load[i];
                        for (&j, &m) in cols.iter().zip(vals) {
                            if let Some(vj) = fx.get(j as usize) {
                                acc -= m * vj;
                            }
                        }
                        acc
                    }
                }
            });
        Ok(c)
    }

    /// The residual b − M u and its scales |b_i| + Σ_j |M_ij u_j| (see
    /// [`DiscreteSystem::residual`]) from M, rows in parallel.
    pub(super) fn assembled_residual(
        &self,
        a: &CsrMatrix,
        u: &[f64],
    ) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        let load = &self.values.load;
        let mut r = try_filled(a.n_rows(), 0.0, "the residual of the system")?;
        let mut scale = try_filled(a.n_rows(), 0.0, "the residual scales of the system")?;
        r.par_iter_mut()
            .zip(scale.par_iter_mut())
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, (ri, si))| (*ri, *si) = assembled_row(a, load, u, i));
        Ok((r, scale))
    }

    /// The entries (i, j, M_ij) of the rows `rows` of M.
    pub(super) fn assembled_rows(
        a: &CsrMatrix,
        rows: &[usize],
    ) -> crate::Result<Vec<(usize, usize, f64)>> {
        let len = rows.iter().map(|&i| a.row(i).0.len()).sum();
        let mut t = try_vec(len, "the rows of the matrix")?;
        for &i in rows {
            let (cols, vals) = a.row(i);
            t.extend(cols.iter().zip(vals).map(|(&j, &v)| (i, j as usize, v)));
        }
        Ok(t)
    }
}

/// Row `i` of the residual b − M u of the assembled matrix `a` (b in `load`) and its scale
/// |b_i| + Σ_j |M_ij u_j|.
pub(super) fn assembled_row(a: &CsrMatrix, load: &[f64], u: &[f64], i: usize) -> (f64, f64) {
    let (cols, vals) = a.row(i);
    let (mut mu, mut abs) = (0.0, 0.0);
    for (&j, &m) in cols.iter().zip(vals) {
        let v = m * u[j as usize];
        mu += v;
        abs += v.abs();
    }
    (load[i] - mu, load[i].abs() + abs)
}

/// The positions of the bits that differ between the masks `a` and `b` (of equal length),
/// ascending.
fn changed_bits(a: &[u64], b: &[u64]) -> Result<Vec<u32>, AllocFailure> {
    let count = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x ^ y).count_ones() as usize)
        .sum();
    let mut out = try_vec(count, "the unknowns whose status changed")?;
    for (w, (x, y)) in a.iter().zip(b).enumerate() {
        let mut d = x ^ y;
        while d != 0 {
            out.push((w * 64) as u32 + d.trailing_zeros());
            d &= d - 1;
        }
    }
    Ok(out)
}
