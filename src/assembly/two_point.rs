//! Condensation onto the cells, when every skeleton unknown couples with its cells only.
//!
//! The usual condensation ([`super::condense()`]) eliminates each cell's interior unknowns and
//! solves for the skeleton: for HMM, the face unknowns (about twice as many as the cells on
//! quadrilaterals, 7 entries per row). It is the only choice in general, because the faces of a
//! cell are coupled with each other. But when every local matrix M_K has a *diagonal* skeleton
//! block (M_K)_SS — each face unknown σ is coupled with its cells' unknowns u_K and with
//! nothing else — the global block M_SS is diagonal too, and the faces can be eliminated
//! instead, exactly and row by row. This is the case of HMM on rectangles with a diagonal
//! tensor and α = 1, where HMM *is* the two-point flux scheme (the classical equivalence of
//! the lumped mixed method with cell-centred finite differences on rectangles): with
//! d_{K,σ} = h/2 the consistent part and the stabilisation of a square sum to
//! Σ_σ (|σ| A n·n / d_{K,σ}) (u_σ − u_K)².
//!
//! With d_σ = Σ_{K ∋ σ} (M_K)_σσ, m_σK = (M_K)_σK and b the load, the row of a free face reads
//! d_σ u_σ + Σ_{K ∋ σ} m_σK u_K = b_σ, so
//!
//!   u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ,
//!
//! and substituting into the cell rows gives the cell system A u_T = r:
//!
//!   A_KK = (M_K)_KK − Σ_{σ ∈ K free} m_σK² / d_σ,
//!   A_KL = − Σ_{σ ∈ K ∩ L free} m_σK m_σL / d_σ,
//!   r_K  = b_K − Σ_{σ ∈ K free} m_σK b_σ / d_σ − Σ_{σ ∈ K Dirichlet} m_σK u_σ,
//!
//! symmetric positive definite (a Schur complement of M on the non-Dirichlet unknowns), one
//! row per cell with one entry per neighbour: 5 per row on quadrilaterals instead of 7 for
//! twice as many face unknowns. A and r are built once per problem; a solve with some cells
//! fixed (the active obstacle constraints) turns their rows and columns into unit ones and
//! moves A_KL u_L to the right-hand side. The faces are then recovered by the formula above,
//! and the certificate is computed, as always, from the full system.
//!
//! The structure is detected, not assumed: every cell has one interior unknown, every skeleton
//! unknown belongs to at most two cells, and every off-diagonal entry of every (M_K)_SS is at
//! most [`TWO_POINT_TOL`] times √((M_K)_σσ (M_K)_σ'σ') in magnitude (zero in exact arithmetic on
//! rectangles; what rounding leaves of it is dropped, a change of the system far below the
//! certificate's tolerance, which the final residual of the full system then shows). A solve
//! that fixes a skeleton unknown other than a Dirichlet one (a Signorini constraint) uses the
//! skeleton system.

use super::{DiscreteSystem, FixedValues, hierarchy};
use crate::linalg::CsrMatrix;
use crate::vi::SolveTimings;
use rayon::prelude::*;
use std::time::Instant;

/// Relative size below which an off-diagonal entry of a local skeleton block counts as zero
/// (see the module docs).
pub const TWO_POINT_TOL: f64 = 1e-12;

/// The cell system of the module docs, with no cell fixed.
pub(super) struct CellSystemAll {
    /// The interior unknown of each cell.
    cell_dof: Vec<u32>,
    /// The matrix A (both triangles, sorted columns).
    a: CsrMatrix,
    /// The right-hand side r.
    r: Vec<f64>,
    /// d_σ of each skeleton unknown (0 on Dirichlet ones).
    d: Vec<f64>,
}

impl CellSystemAll {
    /// Number of cells.
    pub(super) fn n(&self) -> usize {
        self.cell_dof.len()
    }

    /// The interior unknown of cell k.
    pub(super) fn cell_dof(&self, k: usize) -> usize {
        self.cell_dof[k] as usize
    }
}

impl DiscreteSystem<'_> {
    /// The cell system of this problem, if its local matrices have the two-point structure
    /// (built on first use).
    pub(super) fn cell_system(&self) -> Option<&CellSystemAll> {
        self.cell_system
            .get_or_init(|| self.build_cell_system())
            .as_ref()
    }

    /// Whether the iterative solves take the cell system: it exists, and `fixed` fixes no
    /// skeleton unknown (besides the Dirichlet ones).
    pub(super) fn cell_system_for(&self, fixed: &[Option<f64>]) -> Option<&CellSystemAll> {
        let skeleton_fixed = fixed[..self.n_skel]
            .par_iter()
            .with_min_len(4096)
            .any(|f| f.is_some());
        if skeleton_fixed {
            None
        } else {
            self.cell_system()
        }
    }

    /// Solves with `fixed` on the cell system `cs` by multigrid-preconditioned conjugate
    /// gradients to the relative residual `rtol` (the counterpart of the skeleton solve of
    /// [`DiscreteSystem::solve_to`], with the same reuse of hierarchies and the same screening).
    /// The assembly time counts from `t0` (so that it includes building the cell system).
    pub(super) fn solve_cells(
        &self,
        cs: &CellSystemAll,
        fixed: &[Option<f64>],
        rtol: f64,
        t0: Instant,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let reuse = self.next_hierarchy(fixed, true);
        let fx = self.fixed_values(fixed);
        let (a, rhs) = self.fixed_cell_system(cs, &fx)?;
        let t1 = Instant::now();
        let hier = hierarchy(a, reuse, true)?;
        let t2 = Instant::now();
        let mut x = self.take_cell_guess(cs);
        let out = self.run_pcg(hier, &rhs, &mut x, rtol, fixed)?;
        let u = self.complete_cells(cs, &fx, &x)?;
        self.keep_cells(x, &u);
        Ok((u, out.timings([t0, t1, t2, Instant::now()])))
    }

    /// The initial guess of a cell solve: the last cell solution; else the cells recovered
    /// from the last skeleton solution (or the warm start's guess), u_K = (b_K − Σ_σ m_σK
    /// u_σ) / (M_K)_KK; else zero.
    pub(super) fn take_cell_guess(&self, cs: &CellSystemAll) -> Vec<f64> {
        let nc = cs.n();
        let cells = self
            .last_cells
            .lock()
            .map(|mut c| std::mem::take(&mut *c))
            .unwrap_or_default();
        if cells.len() == nc {
            return cells;
        }
        // the skeleton guess holds every unknown the cells' rows read (their skeleton ones)
        let skel = self.take_initial_guess();
        (0..nc)
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| super::interior_value(&self.local(k), &|_| None, &skel))
            .collect()
    }

    /// Keeps the cell values `x` and the skeleton values of `u` as the initial guesses of the
    /// next solves (of either system).
    pub(super) fn keep_cells(&self, x: Vec<f64>, u: &[f64]) {
        if let Ok(mut b) = self.last_solution.lock() {
            *b = u[..self.n_skel].to_vec();
        }
        if let Ok(mut c) = self.last_cells.lock() {
            *c = x;
        }
    }

    /// The cell system, if the local matrices have the two-point structure (module docs).
    fn build_cell_system(&self) -> Option<CellSystemAll> {
        let sym = &self.sym;
        let (dm, inc) = (&sym.dof_map, &sym.maps.inc);
        if !sym.single_interior || self.n_skel == 0 {
            return None;
        }
        let nc = dm.n_cells();
        let dirichlet = &self.values.dirichlet;
        // the skeleton block of every cell is diagonal; every skeleton unknown in ≤ 2 cells
        let diagonal = (0..nc).into_par_iter().with_min_len(4096).all(|k| {
            let cell = self.local(k);
            let m = cell.matrix;
            (1..cell.dofs.len()).all(|a| {
                m.at(a, a) > 0.0
                    && (1..a).all(|b| {
                        m.at(a, b).abs() <= TWO_POINT_TOL * (m.at(a, a) * m.at(b, b)).sqrt()
                    })
            })
        });
        if !diagonal || (0..self.n_skel).any(|s| inc.list(s).len() > 2) {
            return None;
        }
        let cell_dof: Vec<u32> = (0..nc).map(|k| dm.cell(k).0[0]).collect();
        let d: Vec<f64> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|s| {
                if dirichlet[s].is_some() {
                    return 0.0;
                }
                inc.list(s)
                    .iter()
                    .map(|&k| {
                        let cell = self.local(k as usize);
                        let a = super::local_index(cell.dofs, s);
                        cell.matrix.at(a, a)
                    })
                    .sum()
            })
            .collect();
        let b = &self.values.load;
        // per chunk of cells: their rows' lengths, entries (sorted by column) and r_K
        type Rows = (Vec<usize>, Vec<u32>, Vec<f64>, Vec<f64>);
        let chunks: Vec<Rows> = super::chunks(nc, super::CHUNK)
            .into_par_iter()
            .map(|(k0, k1)| {
                let mut out: Rows = Default::default();
                let mut entries: Vec<(u32, f64)> = Vec::new();
                for k in k0..k1 {
                    let r = self.cell_row(k, &d, b, &mut entries);
                    out.0.push(entries.len());
                    out.1.extend(entries.iter().map(|e| e.0));
                    out.2.extend(entries.iter().map(|e| e.1));
                    out.3.push(r);
                }
                out
            })
            .collect();
        let nnz: usize = chunks.iter().map(|c| c.1.len()).sum();
        let mut row_ptr = Vec::with_capacity(nc + 1);
        row_ptr.push(0);
        let (mut cols, mut vals) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
        let mut r = Vec::with_capacity(nc);
        for (lens, c, v, rk) in chunks {
            for len in lens {
                row_ptr.push(row_ptr[row_ptr.len() - 1] + len);
            }
            cols.extend_from_slice(&c);
            vals.extend_from_slice(&v);
            r.extend_from_slice(&rk);
        }
        let a = CsrMatrix::new(nc, nc, row_ptr, cols, vals).ok()?;
        Some(CellSystemAll { cell_dof, a, r, d })
    }

    /// Row k of the cell system A with no cell fixed: its entries (column, value), sorted by
    /// column, in `entries`; returns r_K (module docs).
    fn cell_row(&self, k: usize, d: &[f64], b: &[f64], entries: &mut Vec<(u32, f64)>) -> f64 {
        let (inc, dirichlet) = (&self.sym.maps.inc, &self.values.dirichlet);
        let cell = self.local(k);
        let m = cell.matrix;
        let mut diag = m.at(0, 0);
        let mut r = b[cell.dofs[0] as usize];
        entries.clear();
        for (a, &s) in cell.dofs.iter().enumerate().skip(1) {
            let (s, msk) = (s as usize, m.at(a, 0));
            if let Some(v) = dirichlet[s] {
                r -= msk * v;
                continue;
            }
            diag -= msk * msk / d[s];
            r -= msk * b[s] / d[s];
            for &l in inc.list(s) {
                if l as usize != k {
                    let other = self.local(l as usize);
                    let msl = other.matrix.at(super::local_index(other.dofs, s), 0);
                    entries.push((l, -msk * msl / d[s]));
                }
            }
        }
        entries.push((k as u32, diag));
        entries.sort_by_key(|e| e.0);
        // cells sharing several faces: one entry, summed in face order
        entries.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                kept.1 += later.1;
            }
            same
        });
        r
    }

    /// The cell system with the cells whose unknowns `fixed` gives (or that are Dirichlet)
    /// fixed: their rows and columns unit ones (dropped off the diagonal), A_KL u_L moved to
    /// the right-hand side of the free rows, u_K the right-hand side of the fixed ones.
    pub(super) fn fixed_cell_system(
        &self,
        cs: &CellSystemAll,
        fixed: &FixedValues,
    ) -> crate::Result<(CsrMatrix, Vec<f64>)> {
        let nc = cs.n();
        let value: Vec<Option<f64>> = (0..nc)
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| fixed.get(cs.cell_dof(k)))
            .collect();
        let (rp, ci, va) = (cs.a.row_ptr(), cs.a.col_idx(), cs.a.values());
        // the entries each row keeps (a fixed row: its diagonal)
        let lens: Vec<usize> = (0..nc)
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| match value[k] {
                Some(_) => 1,
                None => ci[rp[k]..rp[k + 1]]
                    .iter()
                    .filter(|&&l| value[l as usize].is_none())
                    .count(),
            })
            .collect();
        let mut row_ptr = Vec::with_capacity(nc + 1);
        row_ptr.push(0);
        for len in lens {
            row_ptr.push(row_ptr[row_ptr.len() - 1] + len);
        }
        let nnz = row_ptr[nc];
        let (mut cols, mut vals, mut rhs) = (vec![0u32; nnz], vec![0.0; nnz], vec![0.0; nc]);
        let ranges = super::chunks(nc, 4 * super::CHUNK);
        let c_slices = super::split_by_ranges(&mut cols, &ranges, |k| row_ptr[k]);
        let v_slices = super::split_by_ranges(&mut vals, &ranges, |k| row_ptr[k]);
        let r_slices = super::split_by_ranges(&mut rhs, &ranges, |k| k);
        let tasks: Vec<_> = ranges
            .into_iter()
            .zip(c_slices)
            .zip(v_slices)
            .zip(r_slices)
            .collect();
        tasks
            .into_par_iter()
            .for_each(|((((k0, k1), cols), vals), rhs)| {
                let mut w = 0;
                for k in k0..k1 {
                    if let Some(v) = value[k] {
                        (cols[w], vals[w], rhs[k - k0]) = (k as u32, 1.0, v);
                        w += 1;
                        continue;
                    }
                    let mut r = cs.r[k];
                    for p in rp[k]..rp[k + 1] {
                        let l = ci[p];
                        match value[l as usize] {
                            Some(v) => r -= va[p] * v,
                            None => {
                                (cols[w], vals[w]) = (l, va[p]);
                                w += 1;
                            }
                        }
                    }
                    rhs[k - k0] = r;
                }
            });
        Ok((CsrMatrix::new(nc, nc, row_ptr, cols, vals)?, rhs))
    }

    /// The full unknown vector from the cell values `x`: the fixed cells take their values,
    /// the free skeleton unknowns u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ, the Dirichlet ones
    /// theirs; a non-finite value is an error.
    pub(super) fn complete_cells(
        &self,
        cs: &CellSystemAll,
        fixed: &FixedValues,
        x: &[f64],
    ) -> crate::Result<Vec<f64>> {
        let mut u = vec![0.0; self.n];
        for (k, &xk) in x.iter().enumerate() {
            let dof = cs.cell_dof(k);
            u[dof] = fixed.get(dof).unwrap_or(xk);
        }
        let (inc, b) = (&self.sym.maps.inc, &self.values.load);
        let skel: Vec<f64> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|s| {
                if let Some(v) = self.values.dirichlet[s] {
                    return v;
                }
                let mut acc = b[s];
                for &k in inc.list(s) {
                    let cell = self.local(k as usize);
                    let a = super::local_index(cell.dofs, s);
                    acc -= cell.matrix.at(a, 0) * u[cell.dofs[0] as usize];
                }
                acc / cs.d[s]
            })
            .collect();
        u[..self.n_skel].copy_from_slice(&skel);
        super::check_finite(u)
    }
}
