//! Condensation onto the cells, when most skeleton unknowns couple with their cells only.
//!
//! The usual condensation ([`super::condense::condense`]) eliminates each cell's interior unknowns and
//! solves for the skeleton: for HMM, the face unknowns (about twice as many as the cells on
//! quadrilaterals, 7 entries per row). It is the only choice in general, because the faces of a
//! cell are coupled with each other. But a face unknown σ that, in each of its (at most two)
//! cells K, is coupled with the cell's interior unknown u_K and with no other skeleton unknown
//! — a zero row of (M_K)_SS off the diagonal — can be eliminated instead, exactly and row by
//! row. On rectangles with a diagonal tensor and α = 1 every face is such a face: there HMM
//! *is* the two-point flux scheme (the classical equivalence of the lumped mixed method with
//! cell-centred finite differences on rectangles; with d_{K,σ} = h/2 the consistent part and
//! the stabilisation of a square sum to Σ_σ (|σ| A n·n / d_{K,σ}) (u_σ − u_K)²). On the coarse
//! meshes of the warm start agglomerated from a Cartesian grid the inner cells are rectangles,
//! while the boundary cells keep their sides cut into the fine boundary edges, which couples
//! their faces: those are *kept* beside the cells.
//!
//! With E the eliminated faces, d_σ = Σ_{K ∋ σ} (M_K)_σσ, m_σK = (M_K)_σK and b the load, the
//! row of σ ∈ E reads d_σ u_σ + Σ_{K ∋ σ} m_σK u_K = b_σ, so
//!
//!   u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ,
//!
//! and substituting into the other rows gives the cell system A u = r on the cells and the
//! kept (free, not eliminated) skeleton unknowns:
//!
//!   A_KK = (M_K)_KK − Σ_{σ ∈ K ∩ E} m_σK² / d_σ,
//!   A_KL = − Σ_{σ ∈ K ∩ L ∩ E} m_σK m_σL / d_σ,
//!   A_Kσ' = (M_K)_Kσ',  A_σ'σ'' = Σ_{K ∋ σ', σ''} (M_K)_σ'σ''  (σ', σ'' kept),
//!   r_K  = b_K − Σ_{σ ∈ K ∩ E} m_σK b_σ / d_σ − Σ_{σ ∈ K Dirichlet} m_σK u_σ,
//!   r_σ' = b_σ' − Σ_{K ∋ σ'} Σ_{σ ∈ K Dirichlet} (M_K)_σ'σ u_σ,
//!
//! (an eliminated face has no entry with any skeleton unknown, so the kept rows do not see
//! E), symmetric positive definite (a Schur complement of M on the non-Dirichlet unknowns):
//! on quadrilaterals one row per cell with one entry per neighbour, 5 per row instead of 7
//! for twice as many face unknowns. A and r are built once per problem; a solve with some
//! unknowns fixed (the active obstacle constraints, and Signorini faces if they are kept)
//! turns their rows and columns into unit ones and moves their columns to the right-hand
//! side. The eliminated faces are then recovered by the formula above, and the certificate is
//! computed, as always, from the full system.
//!
//! The structure is detected, not assumed: every cell has one interior unknown; a face is
//! eliminated if it is free, in at most two cells, and each off-diagonal entry of its rows of
//! (M_K)_SS is at most [`TWO_POINT_TOL`] times √((M_K)_σσ (M_K)_σ'σ') in magnitude (zero in
//! exact arithmetic; what rounding leaves of it is dropped, a change of the system far below
//! the certificate's tolerance, which the final residual of the full system then shows). The
//! cell system is used only if it has at most 3/4 as many unknowns as the free skeleton (on
//! rectangles: 1/2; on triangles nothing is eliminated and it would be larger), and only for
//! solves that fix no eliminated face (otherwise the skeleton system is solved).
//!
//! Both solvers take it: the iterative one by multigrid-preconditioned conjugate gradients
//! (`DiscreteSystem::solve_cells`), the direct one by sparse Cholesky of its lower triangle,
//! whose pattern is A's whatever is fixed (a fixed row and column keep their entries as
//! zeros), so that one symbolic factorisation serves every active set
//! (`DiscreteSystem::solve_cells_direct`). On squares that is half the unknowns of the face
//! system, with 5 entries per row instead of 7: the warm start's coarse levels on box covers
//! and HMM's direct solves on Cartesian meshes factorise it (measurements in
//! `replication/measurements/solver.md`).

use super::gather::{CHUNK, Pinned, chunks, local_index, par_try_fill, split_by_ranges};
use super::iterative::hierarchy;
use super::solve::{check_finite, solve_directly};
use super::{DiscreteSystem, SolveState};
use crate::budget::{try_collect, try_copy, try_filled, try_grow, try_vec};
use crate::linalg::{CsrMatrix, SpdPattern};
use crate::mesh::SolveMesh;
use crate::vi::FixedValues;
use crate::vi::SolveTimings;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Whether the cell system is likely to take the direct solves on `mesh`, judged before any
/// value is known: every cell an axis-aligned box (2·D faces, each normal along an axis),
/// where HMM with a diagonal tensor is the two-point scheme and every face is eliminated.
/// The caller checks the other condition (one interior unknown per cell). With a direct
/// solver, [`super::SymbolicSystem`] then defers the symbolic factorisation of the skeleton
/// system to the first solve that needs it, which the solves through the cell system never
/// do; a wrong guess (a full tensor on boxes) only moves that factorisation from beside the
/// data evaluation to the first solve. O(faces), in parallel, ending at the first cell that
/// is not a box (at once on simplices).
pub(crate) fn likely_cell_system<M: SolveMesh<D> + ?Sized, const D: usize>(mesh: &M) -> bool {
    // a unit normal along an axis has a component of magnitude 1 (and the others 0)
    let along_an_axis = |n: crate::mesh::complex::Vector<D>| {
        n.iter().fold(0.0_f64, |m, c| m.max(c.abs())) >= 1.0 - 1e-9
    };
    let n_cells = mesh.n_cells();
    n_cells > 0
        && (0..n_cells).into_par_iter().with_min_len(4096).all(|k| {
            let nf = mesh.cell_faces(k).len();
            nf == 2 * D && (0..nf).all(|i| along_an_axis(mesh.cell_face_normal(k, i)))
        })
}

/// The rows of the cell system, whether each skeleton unknown is eliminated, and the row of
/// each kept one ([`NO_ROW`] else).
type EliminatedFaces = (Vec<u32>, Vec<bool>, Vec<u32>);

/// Relative size below which an off-diagonal entry of a local skeleton block counts as zero
/// (see the module docs).
pub const TWO_POINT_TOL: f64 = 1e-12;

/// No row: a skeleton unknown that is eliminated or Dirichlet.
const NO_ROW: u32 = u32::MAX;

/// The cell system of the module docs, with no unknown fixed.
pub(super) struct CellSystemAll {
    /// The unknown of each row: the interior unknown of each cell (rows 0..n_cells), then the
    /// kept skeleton unknowns.
    dofs: Vec<u32>,
    /// Number of cells.
    n_cells: usize,
    /// The matrix A (both triangles, sorted columns).
    a: CsrMatrix,
    /// The right-hand side r.
    r: Vec<f64>,
    /// d_σ of each eliminated skeleton unknown (0 on the others).
    d: Vec<f64>,
    /// The row of each kept skeleton unknown ([`NO_ROW`] on the others).
    kept_row: Vec<u32>,
}

impl CellSystemAll {
    /// Number of rows.
    pub(super) fn n(&self) -> usize {
        self.dofs.len()
    }

    /// The matrix A with no unknown fixed (the graph of the patches of
    /// [`crate::linalg::PatchCorrected`]).
    pub(super) fn matrix(&self) -> &CsrMatrix {
        &self.a
    }

    /// Number of kept skeleton unknowns.
    pub(super) fn n_kept(&self) -> usize {
        self.dofs.len() - self.n_cells
    }

    /// The unknown of row i.
    pub(super) fn dof(&self, i: usize) -> usize {
        self.dofs[i] as usize
    }
}

/// The value of each row of the cell system that `fixed` fixes (`None`: a free row).
fn fixed_rows(cs: &CellSystemAll, fixed: &Pinned) -> crate::Result<Vec<Option<f64>>> {
    let mut value = try_vec(cs.n(), "the fixed values of the cell system")?;
    value.par_extend(
        (0..cs.n())
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| fixed.get(cs.dof(i))),
    );
    Ok(value)
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// The cell system of this problem, if its local matrices have the two-point structure
    /// (built on first use and kept in `state`).
    pub(super) fn cell_system(
        &self,
        state: &mut SolveState,
    ) -> crate::Result<Option<Arc<CellSystemAll>>> {
        if state.cell_system.is_none() {
            state.cell_system = Some(self.build_cell_system()?.map(Arc::new));
        }
        Ok(state.cell_system.as_ref().and_then(|c| c.clone()))
    }

    /// The cell system if the iterative solves take it: it exists, and `fixed` fixes no
    /// eliminated skeleton unknown.
    pub(super) fn cell_system_for(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
    ) -> crate::Result<Option<Arc<CellSystemAll>>> {
        let Some(cs) = self.cell_system(state)? else {
            return Ok(None);
        };
        let eliminated_fixed = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .any(|s| fixed.is_fixed(s) && cs.kept_row[s] == NO_ROW);
        Ok((!eliminated_fixed).then_some(cs))
    }

    /// The values at `at` of a partial iterate `u` of a solve through `state`
    /// ([`Self::screen`]): its own, and its eliminated skeleton unknowns recovered from its
    /// cells, u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ. Without a cell system in `state`, `u`'s
    /// values (no iterate is then partial).
    pub fn partial_values(
        &self,
        state: &SolveState,
        u: &[f64],
        at: &[usize],
    ) -> crate::Result<Vec<f64>> {
        self.check_len(u)?;
        let cs = match &state.cell_system {
            Some(Some(cs)) => Some(&**cs),
            _ => None,
        };
        self.recovered_values(cs, u, at)
    }

    /// Fills the eliminated skeleton unknowns of a partial iterate `u` of a solve through
    /// `state` ([`Self::partial_values`] at each of them); a non-finite result is an error.
    /// Without a cell system in `state`, nothing to do.
    pub fn complete_partial(&self, state: &SolveState, u: &mut [f64]) -> crate::Result<()> {
        self.check_len(u)?;
        if let Some(Some(cs)) = &state.cell_system {
            self.complete_eliminated(cs, u)?;
        }
        match u.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(crate::Error::Linear(format!(
                "the solution is not finite at unknown {i}"
            ))),
            None => Ok(()),
        }
    }

    /// [`Self::residual_at`] of a partial iterate `u` of a solve through `state`, computed on
    /// the cell system (up to rounding the residual of the completed iterate, with the scales
    /// of the cell system's rows; see `cell_residual_at` in the source). Without a cell
    /// system in `state`, [`Self::residual_at`].
    pub fn partial_residual_at(
        &self,
        state: &SolveState,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        self.check_len(u)?;
        match &state.cell_system {
            Some(Some(cs)) => self.cell_residual_at(cs, u, len, row),
            _ => self.residual_at(u, len, row),
        }
    }

    /// An error unless `u` has one value per unknown.
    fn check_len(&self, u: &[f64]) -> crate::Result<()> {
        if u.len() == self.n {
            Ok(())
        } else {
            Err(crate::Error::InvalidData(format!(
                "an iterate of {} values for a system of {} unknowns",
                u.len(),
                self.n
            )))
        }
    }

    /// Solves with `fixed` on the cell system `cs` by multigrid-preconditioned conjugate
    /// gradients to the relative residual `rtol` (the counterpart of the skeleton solve of
    /// [`DiscreteSystem::solve`], with the same reuse of hierarchies and the same screening).
    /// The assembly time counts from `t0` (so that it includes building the cell system).
    /// With `partial`, an inexact (screened) solve returns its partial iterate
    /// ([`Self::partial_cells`]; [`SolveTimings::partial`]): the active-set rule reads the
    /// cells, and the faces are recovered only where they are needed, by the look-ahead on its
    /// patches and by the refinement of the last solve.
    pub(super) fn solve_cells(
        &self,
        state: &mut SolveState,
        cs: &CellSystemAll,
        fixed: &FixedValues,
        (rtol, partial): (f64, bool),
        t0: Instant,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let reuse = self.next_hierarchy(state, fixed, true)?;
        let fx = self.fixed_values(fixed);
        let (a, rhs) = self.fixed_cell_system(cs, &fx)?;
        let t1 = Instant::now();
        let hier = hierarchy(a.into(), reuse, true, &mut state.amg)?;
        let t2 = Instant::now();
        let mut x = self.take_cell_guess(state, cs)?;
        let out = self.run_pcg(state, hier, &rhs, &mut x, rtol, fixed, Some(cs))?;
        let partial = partial && out.inexact;
        let u = if partial {
            self.partial_cells(cs, Some(&fx), &x)?
        } else {
            self.complete_cells(cs, &fx, &x)?
        };
        self.keep_cells(state, x, &u)?;
        let timings = out.timings([t0, t1, t2, Instant::now()]);
        Ok((u, SolveTimings { partial, ..timings }))
    }

    /// The initial guess of a cell solve: the last cell solution; else the cells recovered
    /// from the last skeleton solution (or the warm start's guess), u_K = (b_K − Σ_σ m_σK
    /// u_σ) / (M_K)_KK, and the kept skeleton unknowns from it; else zero.
    pub(super) fn take_cell_guess(
        &self,
        state: &mut SolveState,
        cs: &CellSystemAll,
    ) -> crate::Result<Vec<f64>> {
        let cells = std::mem::take(&mut state.last_cells);
        if cells.len() == cs.n() {
            return Ok(cells);
        }
        // the skeleton guess holds every unknown the cells' rows read (their skeleton ones)
        let skel = self.take_initial_guess(state)?;
        let mut x = try_filled(cs.n(), 0.0, "the initial guess of the cell system")?;
        x.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, xi)| {
                *xi = if i < cs.n_cells {
                    super::condense::interior_value(&self.local(i), &|_| None, &skel)
                } else {
                    skel[cs.dof(i)]
                }
            });
        Ok(x)
    }

    /// Keeps the cell values `x` and the skeleton values of `u` in `state` as the initial
    /// guesses of the next solves (of either system). A partial `u` (NaN at the eliminated
    /// skeleton unknowns) leaves no skeleton guess: a skeleton solve after it completes one
    /// from the cells ([`Self::skeleton_guess_from_cells`]).
    pub(super) fn keep_cells(
        &self,
        state: &mut SolveState,
        x: Vec<f64>,
        u: &[f64],
    ) -> crate::Result<()> {
        let skel = &u[..self.n_skel];
        state.last_solution = if skel.iter().any(|v| v.is_nan()) {
            Vec::new()
        } else {
            try_copy(skel, "the initial guess of the next solve")?
        };
        state.last_cells = x;
        Ok(())
    }

    /// The skeleton values of the last cell solve kept in `state`, if it left its cell values
    /// but no skeleton guess (a partial iterate): the rows' values and the eliminated
    /// unknowns recovered from them; `None` otherwise.
    pub(super) fn skeleton_guess_from_cells(
        &self,
        state: &SolveState,
    ) -> crate::Result<Option<Vec<f64>>> {
        let Some(Some(cs)) = &state.cell_system else {
            return Ok(None);
        };
        if state.last_cells.len() != cs.n() {
            return Ok(None);
        }
        let mut u = self.partial_cells(cs, None, &state.last_cells)?;
        self.complete_eliminated(cs, &mut u)?;
        u.truncate(self.n_skel);
        Ok(Some(u))
    }

    /// The cell system, if enough of the skeleton unknowns can be eliminated (module docs).
    fn build_cell_system(&self) -> crate::Result<Option<CellSystemAll>> {
        if !self.sym.single_interior || self.n_skel == 0 {
            return Ok(None);
        }
        let Some((dofs, eliminated, kept_row)) = self.eliminated_faces()? else {
            return Ok(None);
        };
        let d = self.eliminated_diagonals(&eliminated)?;
        let mut cs = CellSystemAll {
            dofs,
            n_cells: self.sym.dof_map.n_cells(),
            a: CsrMatrix::new(0, 0, vec![0], Vec::new(), Vec::new())?,
            r: Vec::new(),
            d,
            kept_row,
        };
        let (a, r) = self.cell_rows(&cs)?;
        (cs.a, cs.r) = (a, r);
        Ok(Some(cs))
    }

    /// Which skeleton unknowns are eliminated (module docs): the unknown of each row of the
    /// cell system (the cells' interior unknowns, then the kept skeleton unknowns), the
    /// eliminated flags and the row of each kept skeleton unknown; `None` when too few can be
    /// eliminated for the cell system to pay.
    fn eliminated_faces(&self) -> crate::Result<Option<EliminatedFaces>> {
        let (dm, inc) = (&self.sym.dof_map, &self.sym.maps.inc);
        let nc = dm.n_cells();
        let dirichlet = &self.values.dirichlet;
        // the free skeleton unknowns coupled with another skeleton unknown in some cell
        let coupled_chunks: crate::Result<Vec<Vec<u32>>> = chunks(nc, CHUNK)
            .into_par_iter()
            .map(|(k0, k1)| {
                let mut out = Vec::new();
                for k in k0..k1 {
                    self.coupled_faces(k, &mut out)?;
                }
                Ok(out)
            })
            .collect();
        let coupled_chunks = coupled_chunks?;
        let n_coupled = coupled_chunks.iter().map(Vec::len).sum();
        let mut coupled_list = try_vec(n_coupled, "the coupled skeleton unknowns")?;
        for c in coupled_chunks {
            coupled_list.extend_from_slice(&c);
        }
        let mut kept_row = try_filled(self.n_skel, NO_ROW, "the rows of the cell system")?;
        let mut eliminated = try_filled(self.n_skel, false, "the eliminated skeleton unknowns")?;
        for (s, e) in eliminated.iter_mut().enumerate() {
            *e = !dirichlet.is_fixed(s) && inc.list(s).len() <= 2;
        }
        for &s in &coupled_list {
            eliminated[s as usize] = false;
        }
        let kept = (0..self.n_skel)
            .filter(|&s| !dirichlet.is_fixed(s) && !eliminated[s])
            .count();
        let mut dofs = try_vec(nc + kept, "the unknowns of the cell system")?;
        dofs.extend((0..nc).map(|k| dm.cell(k).0[0]));
        for s in 0..self.n_skel {
            if !dirichlet.is_fixed(s) && !eliminated[s] {
                kept_row[s] = dofs.len() as u32;
                dofs.push(s as u32);
            }
        }
        let free_skel = (0..self.n_skel).filter(|&s| !dirichlet.is_fixed(s)).count();
        Ok((4 * dofs.len() <= 3 * free_skel).then_some((dofs, eliminated, kept_row)))
    }

    /// Appends to `out` the free skeleton unknowns of cell `k` coupled with another skeleton
    /// unknown of the cell: (M_K)_σσ ≤ 0, or |(M_K)_σσ'| above [`TWO_POINT_TOL`] times
    /// √((M_K)_σσ (M_K)_σ'σ') for some other σ'.
    fn coupled_faces(&self, k: usize, out: &mut Vec<u32>) -> crate::Result<()> {
        let dirichlet = &self.values.dirichlet;
        let cell = self.local(k);
        let (m, dofs) = (cell.matrix, cell.dofs);
        try_grow(out, dofs.len(), "the coupled skeleton unknowns")?;
        let free = |a: usize| !dirichlet.is_fixed(dofs[a] as usize);
        for a in (1..dofs.len()).filter(|&a| free(a)) {
            let lone = m.at(a, a) > 0.0
                && (1..dofs.len())
                    .filter(|&b| b != a)
                    .all(|b| m.at(a, b).abs() <= TWO_POINT_TOL * (m.at(a, a) * m.at(b, b)).sqrt());
            if !lone {
                out.push(dofs[a]);
            }
        }
        Ok(())
    }

    /// d_σ = Σ_{K ∋ σ} (M_K)_σσ of the eliminated skeleton unknowns (0 on the others).
    fn eliminated_diagonals(&self, eliminated: &[bool]) -> crate::Result<Vec<f64>> {
        let inc = &self.sym.maps.inc;
        par_try_fill(self.n_skel, "the eliminated diagonals", |s| {
            if !eliminated[s] {
                return Ok(0.0);
            }
            let mut d = 0.0;
            for &k in inc.list(s) {
                let cell = self.local(k as usize);
                let a = local_index(cell.dofs, s)?;
                d += cell.matrix.at(a, a);
            }
            Ok(d)
        })
    }

    /// The matrix A (rows sorted by column, repeated couplings summed in order) and the
    /// right-hand side r of the cell system `cs` with nothing fixed, row chunks in parallel.
    fn cell_rows(&self, cs: &CellSystemAll) -> crate::Result<(CsrMatrix, Vec<f64>)> {
        let (n, nc) = (cs.n(), cs.n_cells);
        // per chunk of rows: their lengths, entries (sorted by column) and right-hand sides
        type Rows = (Vec<usize>, Vec<u32>, Vec<f64>, Vec<f64>);
        let chunks: Vec<crate::Result<Rows>> = chunks(n, CHUNK)
            .into_par_iter()
            .map(|(i0, i1)| {
                let mut out: Rows = Default::default();
                let mut entries: Vec<(u32, f64)> = Vec::new();
                for i in i0..i1 {
                    entries.clear();
                    let r = if i < nc {
                        self.cell_row(cs, i, &mut entries)?
                    } else {
                        self.kept_row(cs, cs.dof(i), &mut entries)?
                    };
                    entries.sort_by_key(|e| e.0);
                    // several couplings with one unknown: one entry, summed in order
                    entries.dedup_by(|later, kept| {
                        let same = later.0 == kept.0;
                        if same {
                            kept.1 += later.1;
                        }
                        same
                    });
                    try_grow(&mut out.0, 1, "the row lengths of the cell system")?;
                    try_grow(
                        &mut out.1,
                        entries.len(),
                        "the column indices of the cell system",
                    )?;
                    try_grow(&mut out.2, entries.len(), "the entries of the cell system")?;
                    try_grow(&mut out.3, 1, "the right-hand side of the cell system")?;
                    out.0.push(entries.len());
                    out.1.extend(entries.iter().map(|e| e.0));
                    out.2.extend(entries.iter().map(|e| e.1));
                    out.3.push(r);
                }
                Ok(out)
            })
            .collect();
        let chunks = chunks.into_iter().collect::<crate::Result<Vec<Rows>>>()?;
        let nnz: usize = chunks.iter().map(|c| c.1.len()).sum();
        let mut row_ptr = try_vec(n + 1, "the row offsets of the cell system")?;
        row_ptr.push(0);
        let mut cols = try_vec(nnz, "the column indices of the cell system")?;
        let mut vals = try_vec(nnz, "the entries of the cell system")?;
        let mut r = try_vec(n, "the right-hand side of the cell system")?;
        for (lens, c, v, rk) in chunks {
            for len in lens {
                row_ptr.push(row_ptr[row_ptr.len() - 1] + len);
            }
            cols.extend_from_slice(&c);
            vals.extend_from_slice(&v);
            r.extend_from_slice(&rk);
        }
        Ok((CsrMatrix::new(n, n, row_ptr, cols, vals)?, r))
    }

    /// Row k (a cell) of the cell system A with nothing fixed: its entries (column, value),
    /// unsorted, in `entries`; returns r_K (module docs).
    fn cell_row(
        &self,
        cs: &CellSystemAll,
        k: usize,
        entries: &mut Vec<(u32, f64)>,
    ) -> crate::Result<f64> {
        let (inc, dirichlet) = (&self.sym.maps.inc, &self.values.dirichlet);
        let cell = self.local(k);
        let m = cell.matrix;
        let mut diag = m.at(0, 0);
        let mut r = self.values.load[cell.dofs[0] as usize];
        for (a, &s) in cell.dofs.iter().enumerate().skip(1) {
            let (s, msk) = (s as usize, m.at(a, 0));
            if let Some(v) = dirichlet.get(s) {
                r -= msk * v;
            } else if cs.kept_row[s] != NO_ROW {
                entries.push((cs.kept_row[s], msk));
            } else {
                diag -= msk * msk / cs.d[s];
                r -= msk * self.values.load[s] / cs.d[s];
                for &l in inc.list(s) {
                    if l as usize != k {
                        let other = self.local(l as usize);
                        let msl = other.matrix.at(local_index(other.dofs, s)?, 0);
                        entries.push((l, -msk * msl / cs.d[s]));
                    }
                }
            }
        }
        entries.push((k as u32, diag));
        Ok(r)
    }

    /// The row of the kept skeleton unknown s with nothing fixed: its entries (column, value),
    /// unsorted, in `entries`; returns its right-hand side b_σ − Σ M_σσ' u_σ' over the
    /// Dirichlet σ' of its cells (module docs).
    fn kept_row(
        &self,
        cs: &CellSystemAll,
        s: usize,
        entries: &mut Vec<(u32, f64)>,
    ) -> crate::Result<f64> {
        let (inc, dirichlet) = (&self.sym.maps.inc, &self.values.dirichlet);
        let mut r = self.values.load[s];
        for &k in inc.list(s) {
            let cell = self.local(k as usize);
            let (m, a) = (cell.matrix, local_index(cell.dofs, s)?);
            entries.push((k, m.at(a, 0)));
            for (c, &t) in cell.dofs.iter().enumerate().skip(1) {
                let t = t as usize;
                if let Some(v) = dirichlet.get(t) {
                    r -= m.at(a, c) * v;
                } else if cs.kept_row[t] != NO_ROW {
                    entries.push((cs.kept_row[t], m.at(a, c)));
                }
                // an eliminated σ' is coupled with no skeleton unknown: nothing to add
            }
        }
        Ok(r)
    }

    /// The cell system with the rows (cells, kept skeleton unknowns) whose unknowns `fixed`
    /// gives fixed: their rows and columns unit ones (dropped off the diagonal), A_ij u_j moved
    /// to the right-hand side of the free rows, u_i the right-hand side of the fixed ones.
    pub(super) fn fixed_cell_system(
        &self,
        cs: &CellSystemAll,
        fixed: &Pinned,
    ) -> crate::Result<(CsrMatrix, Vec<f64>)> {
        let nc = cs.n();
        let value = fixed_rows(cs, fixed)?;
        let (rp, ci, va) = (cs.a.row_ptr(), cs.a.col_idx(), cs.a.values());
        // the entries each row keeps (a fixed row: its diagonal)
        let mut lens = try_vec(nc, "the row lengths of the cell system")?;
        lens.par_extend((0..nc).into_par_iter().with_min_len(4096).map(|k| {
            match value[k] {
                Some(_) => 1,
                None => ci[rp[k]..rp[k + 1]]
                    .iter()
                    .filter(|&&l| value[l as usize].is_none())
                    .count(),
            }
        }));
        let mut row_ptr = try_vec(nc + 1, "the row offsets of the cell system")?;
        row_ptr.push(0);
        for len in lens {
            row_ptr.push(row_ptr[row_ptr.len() - 1] + len);
        }
        let nnz = row_ptr[nc];
        let mut cols = try_filled(nnz, 0u32, "the column indices of the cell system")?;
        let mut vals = try_filled(nnz, 0.0, "the entries of the cell system")?;
        let mut rhs = try_filled(nc, 0.0, "the right-hand side of the cell system")?;
        let ranges = chunks(nc, 4 * CHUNK);
        let c_slices = split_by_ranges(&mut cols, &ranges, |k| row_ptr[k]);
        let v_slices = split_by_ranges(&mut vals, &ranges, |k| row_ptr[k]);
        let r_slices = split_by_ranges(&mut rhs, &ranges, |k| k);
        let tasks = try_collect(
            ranges.into_iter().zip(c_slices).zip(v_slices).zip(r_slices),
            "the tasks of the cell system",
        )?;
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

    /// The direct counterpart of [`Self::solve_cells`]: the cell system with `fixed` factorised
    /// by sparse Cholesky. Its lower triangle keeps the pattern of A whatever is fixed (the
    /// entries of a fixed row and column are zeros, its diagonal 1), so its symbolic analysis is
    /// made once, by the first direct cell solve, and kept in `state`; each solve refills the
    /// values and factorises. The assembly time counts from `t0`.
    pub(super) fn solve_cells_direct(
        &self,
        state: &mut SolveState,
        cs: &CellSystemAll,
        fixed: &FixedValues,
        t0: Instant,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        if state.cell_direct.is_none() {
            state.cell_direct = Some(self.cell_pattern(cs)?);
        }
        let SolveState {
            cell_direct,
            cholesky,
            ..
        } = state;
        let pattern = cell_direct
            .as_ref()
            .ok_or_else(|| crate::Error::Internal("no pattern of the cell system".into()))?;
        let fx = self.fixed_values(fixed);
        let (values, mut rhs) = fixed_cell_lower(cs, pattern, &fx)?;
        let t1 = Instant::now();
        let (t2, out) = solve_directly(pattern, &values, &mut rhs, cholesky)?;
        drop(values);
        // no initial guess is kept: a direct solve needs none, and once a system solves
        // directly every later solve of it does
        let u = self.complete_cells(cs, &fx, &rhs)?;
        Ok((u, out.timings([t0, t1, t2, Instant::now()])))
    }

    /// The lower triangle of the cell system's matrix A by columns (column j: the rows i ≥ j
    /// of row j of A, which is symmetric, sorted), analysed for the Cholesky factorisation with
    /// the system's ordering and threads, its numeric phase checked against the budget.
    fn cell_pattern(&self, cs: &CellSystemAll) -> crate::Result<SpdPattern> {
        let (rp, ci) = (cs.a.row_ptr(), cs.a.col_idx());
        let n = cs.n();
        let mut col_ptr = try_vec(n + 1, "the column offsets of the cell system's factor")?;
        col_ptr.push(0);
        for j in 0..n {
            let upper = ci[rp[j]..rp[j + 1]].iter().filter(|&&i| i as usize >= j);
            col_ptr.push(col_ptr[j] + upper.count());
        }
        let mut row_idx = try_vec(col_ptr[n], "the row indices of the cell system's factor")?;
        for j in 0..n {
            let upper = ci[rp[j]..rp[j + 1]].iter().filter(|&&i| i as usize >= j);
            row_idx.extend(upper.map(|&i| i as usize));
        }
        let nnz = row_idx.len() as u64;
        let opts = &self.sym.options;
        let p = SpdPattern::with_ordering(n, col_ptr, row_idx, opts.ordering)?
            .with_threads(opts.factor_threads);
        // the factor, the values of the lower triangle and a few vectors of rows
        let bytes = 8 * (p.factor_len() as u64) + 8 * nnz + 8 * 6 * (n as u64);
        opts.budget.check_computation(
            format!(
                "the numeric factorisation of the cell system (a Cholesky factor of {} entries)",
                p.factor_len()
            ),
            bytes,
        )?;
        Ok(p)
    }

    /// The full unknown vector from the values `x` of the rows: the fixed unknowns take their
    /// values, the eliminated skeleton unknowns u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ, the
    /// Dirichlet ones theirs; a non-finite value is an error.
    pub(super) fn complete_cells(
        &self,
        cs: &CellSystemAll,
        fixed: &Pinned,
        x: &[f64],
    ) -> crate::Result<Vec<f64>> {
        let mut u = self.partial_cells(cs, Some(fixed), x)?;
        self.complete_eliminated(cs, &mut u)?;
        check_finite(u)
    }

    /// [`Self::complete_cells`] without the eliminated skeleton unknowns, which are left NaN:
    /// the partial iterate of a screened solve ([`crate::vi::SolveTimings::partial`]). The
    /// rows' values must be finite (an error otherwise). `fixed`: the values of the fixed
    /// rows (`None`: `x`'s).
    pub(super) fn partial_cells(
        &self,
        cs: &CellSystemAll,
        fixed: Option<&Pinned>,
        x: &[f64],
    ) -> crate::Result<Vec<f64>> {
        let mut u = try_filled(self.n, f64::NAN, "the solution")?;
        for (i, &xi) in x.iter().enumerate() {
            let dof = cs.dof(i);
            let v = fixed.and_then(|f| f.get(dof)).unwrap_or(xi);
            if !v.is_finite() {
                return Err(crate::Error::Linear(format!(
                    "the solution is not finite at unknown {dof}"
                )));
            }
            u[dof] = v;
        }
        for (s, us) in u[..self.n_skel].iter_mut().enumerate() {
            if let Some(v) = self.values.dirichlet.get(s) {
                *us = v;
            }
        }
        Ok(u)
    }

    /// The value of the eliminated skeleton unknown `s` from the cell values of `u`:
    /// u_σ = (b_σ − Σ_{K ∋ σ} m_σK u_K) / d_σ, the cells in the order of `inc`.
    fn eliminated_value(&self, cs: &CellSystemAll, s: usize, u: &[f64]) -> crate::Result<f64> {
        let mut acc = self.values.load[s];
        for &k in self.sym.maps.inc.list(s) {
            let cell = self.local(k as usize);
            let a = local_index(cell.dofs, s)?;
            acc -= cell.matrix.at(a, 0) * u[cell.dofs[0] as usize];
        }
        Ok(acc / cs.d[s])
    }

    /// Whether skeleton unknown `s` is eliminated in `cs` (neither kept nor Dirichlet).
    fn is_eliminated(&self, cs: &CellSystemAll, s: usize) -> bool {
        s < self.n_skel && cs.kept_row[s] == NO_ROW && !self.values.dirichlet.is_fixed(s)
    }

    /// Fills the eliminated skeleton unknowns of `u` from its cell values
    /// ([`Self::eliminated_value`]), in parallel.
    pub(super) fn complete_eliminated(
        &self,
        cs: &CellSystemAll,
        u: &mut [f64],
    ) -> crate::Result<()> {
        let skel = par_try_fill(self.n_skel, "the skeleton values", |s| {
            if self.is_eliminated(cs, s) {
                self.eliminated_value(cs, s, u)
            } else {
                Ok(u[s])
            }
        })?;
        u[..self.n_skel].copy_from_slice(&skel);
        Ok(())
    }

    /// The values at `at` of a partial iterate `u` of the cell system `cs`, the eliminated
    /// skeleton unknowns recovered ([`crate::vi::QuadraticEnergy::partial_values`]; `None`:
    /// no cell system, `u`'s values).
    fn recovered_values(
        &self,
        cs: Option<&CellSystemAll>,
        u: &[f64],
        at: &[usize],
    ) -> crate::Result<Vec<f64>> {
        at.iter()
            .map(|&j| match (u.get(j), cs) {
                (Some(_), Some(cs)) if self.is_eliminated(cs, j) => self.eliminated_value(cs, j, u),
                (Some(&v), _) => Ok(v),
                (None, _) => Err(crate::Error::Internal(format!(
                    "unknown {j} of a system of {} unknowns",
                    self.n
                ))),
            })
            .collect()
    }

    /// The residual of the full system at the unknowns `row(0)`, …, `row(len − 1)` of a partial
    /// iterate `u` of the cell system `cs`, and the largest of their scales, computed on the
    /// cell system (module docs): at a cell or kept row i, r_i − Σ_j A_ij u_j with scale
    /// |r_i| + Σ_j |A_ij u_j|, equal to the full system's residual up to rounding because the
    /// eliminated skeleton unknowns satisfy their rows exactly; at an eliminated unknown, its
    /// row of the full system with its value recovered. One 5-point row per cell on squares,
    /// where the full rows would need the faces of every cell.
    fn cell_residual_at(
        &self,
        cs: &CellSystemAll,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        let at = |g: usize| -> crate::Result<(f64, f64)> {
            let i = if g >= self.n_skel {
                g - self.n_skel
            } else {
                cs.kept_row[g] as usize
            };
            if i < cs.n() && cs.dof(i) == g {
                let (cols, vals) = cs.a.row(i);
                let (mut a, mut b) = (cs.r[i], cs.r[i].abs());
                for (&j, &v) in cols.iter().zip(vals) {
                    let t = v * u[cs.dof(j as usize)];
                    a -= t;
                    b += t.abs();
                }
                Ok((a, b))
            } else if self.is_eliminated(cs, g) {
                // its row couples it with its cells only (the couplings with other skeleton
                // unknowns are below TWO_POINT_TOL, dropped as in the cell system)
                let v = self.eliminated_value(cs, g, u)?;
                let (mut a, mut b) = (self.values.load[g], self.values.load[g].abs());
                for &k in self.sym.maps.inc.list(g) {
                    let cell = self.local(k as usize);
                    let i = local_index(cell.dofs, g)?;
                    for (j, t) in [(i, v), (0, u[cell.dofs[0] as usize])] {
                        let t = cell.matrix.at(i, j) * t;
                        a -= t;
                        b += t.abs();
                    }
                }
                Ok((a, b))
            } else {
                Err(crate::Error::Internal(format!(
                    "residual at unknown {g}, neither a row of the cell system nor eliminated"
                )))
            }
        };
        let mut r = try_filled(len, 0.0, "the residual at the constrained unknowns")?;
        let scale = super::residual::fill_rows(&mut r, row, at)?;
        Ok((r, scale))
    }
}

/// The values of the lower triangle of the cell system (on `pattern`, built by
/// `DiscreteSystem::cell_pattern`) and the right-hand side, with the rows whose unknowns
/// `fixed` gives fixed: as `fixed_cell_system`, the entries of their rows and columns zero
/// (kept in the pattern) and their diagonal 1. Column j of the lower triangle is the tail of
/// row j of A from its diagonal on (A is symmetric, its columns sorted).
fn fixed_cell_lower(
    cs: &CellSystemAll,
    pattern: &SpdPattern,
    fixed: &Pinned,
) -> crate::Result<(Vec<f64>, Vec<f64>)> {
    let nc = cs.n();
    let value = fixed_rows(cs, fixed)?;
    let (rp, ci, va) = (cs.a.row_ptr(), cs.a.col_idx(), cs.a.values());
    let mut rhs = try_filled(nc, 0.0, "the right-hand side of the cell system")?;
    rhs.par_iter_mut()
        .enumerate()
        .with_min_len(4096)
        .for_each(|(k, r)| {
            *r = match value[k] {
                Some(v) => v,
                None => {
                    let mut r = cs.r[k];
                    for p in rp[k]..rp[k + 1] {
                        if let Some(v) = value[ci[p] as usize] {
                            r -= va[p] * v;
                        }
                    }
                    r
                }
            }
        });
    let cp = pattern.col_ptr();
    let mut values = try_filled(
        pattern.nnz(),
        0.0,
        "the entries of the cell system's lower triangle",
    )?;
    let ranges = chunks(nc, 4 * CHUNK);
    let slices = split_by_ranges(&mut values, &ranges, |j| cp[j]);
    let tasks = try_collect(
        ranges.into_iter().zip(slices),
        "the tasks of the cell system's lower triangle",
    )?;
    tasks.into_par_iter().for_each(|((j0, j1), out)| {
        let base = cp[j0];
        for j in j0..j1 {
            let tail = rp[j + 1] - (cp[j + 1] - cp[j]);
            for (w, p) in (cp[j] - base..).zip(tail..rp[j + 1]) {
                let i = ci[p] as usize;
                out[w] = match (value[j].is_some(), value[i].is_some(), i == j) {
                    (true, _, true) => 1.0,
                    (false, false, _) => va[p],
                    _ => 0.0,
                };
            }
        }
    });
    Ok((values, rhs))
}
