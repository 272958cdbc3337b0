//! The full (uncondensed) system M u = b seen from outside the solves: its residual (from which
//! the certificate is computed), its rows, its entries and the energy.

use super::DiscreteSystem;
use super::assembled::assembled_row;
use super::gather::{PAR_ROWS, local_index};
use crate::budget::try_filled;
use crate::mesh::SolveMesh;
use rayon::prelude::*;

/// Writes `r[k]` = the residual `at(row(k))` in parallel and returns the largest of the
/// scales `at` gives with them (the largest of each chunk, then of the chunks: a maximum, in
/// any order).
pub(super) fn fill_rows(
    r: &mut [f64],
    row: &(dyn Fn(usize) -> usize + Sync),
    at: impl Fn(usize) -> crate::Result<(f64, f64)> + Sync,
) -> crate::Result<f64> {
    let maxima: Vec<crate::Result<f64>> = r
        .par_chunks_mut(PAR_ROWS)
        .enumerate()
        .map(|(c, rc)| {
            let mut m = 0.0f64;
            for (o, ri) in rc.iter_mut().enumerate() {
                let (v, s) = at(row(c * PAR_ROWS + o))?;
                *ri = v;
                m = m.max(s);
            }
            Ok(m)
        })
        .collect();
    let mut scale = 0.0f64;
    for m in maxima {
        scale = scale.max(m?);
    }
    Ok(scale)
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// The residual r = b − M u of the full (uncondensed) system, and for each unknown the
    /// scale |b_i| + Σ_j |M_ij u_j| against which it is small. On Dirichlet unknowns r is the
    /// reaction, not a balance; on constrained unknowns it is the multiplier (up to sign).
    ///
    /// Without interior unknowns, M is assembled ([`super::assembled`]) and read row by row.
    /// Otherwise M u = Σ_K P_Kᵀ M_K P_K u is gathered row by row in parallel: row i visits the
    /// cells where unknown i appears (`inc`, ascending) and takes there the row of M_K u_K, so
    /// the sums run in the order of a sequential scatter (independent of the threads) and
    /// nothing per cell is stored; the scale then sums |(M_K)_ij u_j| cell by cell.
    pub fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        if let Some(a) = self.assembled() {
            return self.assembled_residual(a, u);
        }
        let mut r = try_filled(self.n, 0.0, "the residual of the system")?;
        let mut scale = try_filled(self.n, 0.0, "the residual scales of the system")?;
        // fallible per chunk of rows rather than per row (see `gather::par_try_fill`)
        r.par_chunks_mut(PAR_ROWS)
            .zip(scale.par_chunks_mut(PAR_ROWS))
            .enumerate()
            .try_for_each(|(c, (rc, sc))| -> crate::Result<()> {
                for (o, (ri, si)) in rc.iter_mut().zip(sc.iter_mut()).enumerate() {
                    (*ri, *si) = self.gathered_row(c * PAR_ROWS + o, u)?;
                }
                Ok(())
            })?;
        Ok((r, scale))
    }

    /// The entries `row(0)`, …, `row(len − 1)` of the residual of [`Self::residual`], to the
    /// bit (each row is computed as there), and the largest of their scales, without the
    /// other rows: what the active-set rule reads of a screened iterate (its multipliers, on
    /// the constrained unknowns). One vector of `len` entries is allocated.
    pub fn residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        let mut r = try_filled(len, 0.0, "the residual at the constrained unknowns")?;
        let assembled = self.assembled();
        let at = |i: usize| -> crate::Result<(f64, f64)> {
            if i >= self.n {
                return Err(crate::Error::Internal(format!(
                    "residual at row {i} of a system of {} unknowns",
                    self.n
                )));
            }
            match assembled {
                Some(a) => Ok(assembled_row(a, &self.values.load, u, i)),
                None => self.gathered_row(i, u),
            }
        };
        let scale = fill_rows(&mut r, row, at)?;
        Ok((r, scale))
    }

    /// Row `gi` of the residual and its scale, gathered from the cells of the unknown
    /// (ascending, the order of a sequential scatter).
    fn gathered_row(&self, gi: usize, u: &[f64]) -> crate::Result<(f64, f64)> {
        let inc = &self.sym.maps.inc;
        let mut a = self.values.load[gi];
        let mut b = a.abs();
        for &k in inc.list(gi) {
            let cell = self.local(k as usize);
            let (d, m) = (cell.dofs, cell.matrix);
            let i = local_index(d, gi)?;
            let (mut mu, mut abs) = (0.0, 0.0);
            for (j, &gj) in d.iter().enumerate() {
                let v = m.at(i, j) * u[gj as usize];
                mu += v;
                abs += v.abs();
            }
            a -= mu;
            b += abs;
        }
        Ok((a, b))
    }

    /// The entries (i, j, (M_K)_ij) of the rows i ∈ `rows` of the full matrix, cell by cell
    /// (repeated (i, j) sum), through the cells of each unknown.
    pub fn row_entries(&self, rows: &[usize]) -> crate::Result<Vec<(usize, usize, f64)>> {
        if let Some(a) = self.assembled() {
            return Self::assembled_rows(a, rows);
        }
        let inc = &self.sym.maps.inc;
        let mut t = Vec::new();
        for &gi in rows {
            for &k in inc.list(gi) {
                let cell = self.local(k as usize);
                let (d, m) = (cell.dofs, cell.matrix);
                let i = local_index(d, gi)?;
                t.extend(
                    d.iter()
                        .enumerate()
                        .map(|(j, &gj)| (gi, gj as usize, m.at(i, j))),
                );
            }
        }
        Ok(t)
    }

    /// The discrete energy ½ uᵀMu − bᵀu (the VI solution minimises it over the convex set).
    pub fn energy(&self, u: &[f64]) -> crate::Result<f64> {
        let (r, _) = self.residual(u)?;
        // ½uᵀMu − bᵀu = ½uᵀ(Mu − b) − ½bᵀu = −½uᵀr − ½bᵀu
        Ok(-0.5 * u.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>()
            - 0.5
                * u.iter()
                    .zip(&self.values.load)
                    .map(|(a, b)| a * b)
                    .sum::<f64>())
    }

    /// The entries of the full (uncondensed) matrix M = Σ_K P_Kᵀ M_K P_K, cell by cell: the
    /// triplets (i, j, (M_K)_ij) in global indices (repeated entries sum).
    pub fn full_matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        if let Some(a) = self.assembled() {
            for i in 0..a.n_rows() {
                let (cols, vals) = a.row(i);
                t.extend(cols.iter().zip(vals).map(|(&j, &v)| (i, j as usize, v)));
            }
            return t;
        }
        for k in 0..self.sym.scheme().mesh().n_cells() {
            let cell = self.local(k);
            let (d, m) = (cell.dofs, cell.matrix);
            for (j, &gj) in d.iter().enumerate() {
                for (i, &gi) in d.iter().enumerate() {
                    t.push((gi as usize, gj as usize, m.at(i, j)));
                }
            }
        }
        t
    }
}
