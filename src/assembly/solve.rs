//! One linear solve of the discrete system with some unknowns fixed: assemble the condensed
//! (or cell) system, solve it directly or iteratively ([`super::linear::LinearSolver`]), and
//! recover the eliminated unknowns.

use super::condense::{interior_value, recover_interior};
use super::gather::Pinned;
use super::iterative::{Hierarchy, KeptHierarchy, NextHierarchy, PcgOutcome, fingerprint};
use super::linear::{ITERATIVE_RTOL, LinearSolver, SCREENING_RTOL};
use super::symbolic::check_numeric_memory;
use super::{DiscreteSystem, SolveState};
use crate::budget::{try_copy, try_filled, try_vec};
use crate::linalg::{CholeskyWork, CsrMatrix, SpdPattern};
use crate::mesh::SolveMesh;
use crate::vi::FixedValues;
use crate::vi::SolveTimings;
use rayon::prelude::*;
use std::time::Instant;

/// Cholesky factorisation of the condensed matrix (`values` on `pattern`, in `work`) and solve
/// of S x = c in place (`rhs`); returns when the factorisation ended, 0 Krylov iterations, and
/// that the solve is exact.
pub(super) fn solve_directly(
    pattern: &SpdPattern,
    values: &[f64],
    rhs: &mut [f64],
    work: &mut CholeskyWork,
) -> crate::Result<(Instant, PcgOutcome)> {
    let factor = pattern.factor(values, work)?;
    let t2 = Instant::now();
    factor.solve_in_place(rhs);
    Ok((t2, PcgOutcome::default()))
}

/// `u`, or an error naming its first non-finite entry.
pub(super) fn check_finite(u: Vec<f64>) -> crate::Result<Vec<f64>> {
    match u.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(crate::Error::Linear(format!(
            "the solution is not finite at unknown {i}"
        ))),
        None => Ok(u),
    }
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// Solves the linear system in which the unknowns `fixed` fixes (and the
    /// Dirichlet unknowns) are fixed. Returns the full unknown vector. What carries to the next
    /// solve (initial guess, multigrid hierarchy, buffers) is kept in `state`; a fresh state
    /// gives the same bits whatever was solved before.
    pub fn solve(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.solve_to(state, fixed, (ITERATIVE_RTOL, false))
    }

    /// [`Self::solve`], but an iterative solve stops at [`SCREENING_RTOL`] and is kept in
    /// `state` (matrix, multigrid hierarchy, right-hand side) until the next solve, so that
    /// [`Self::refine`] can continue it ([`SolveTimings::inexact`] says whether it did stop
    /// early). An inexact solve of the cell system ([`super::two_point`]) returns a *partial*
    /// iterate ([`SolveTimings::partial`]): its eliminated skeleton unknowns are NaN, read
    /// through [`Self::partial_values`], [`Self::partial_residual_at`] and
    /// [`Self::complete_partial`] (the [`crate::vi::QuadraticEnergy`] methods `partial_values`,
    /// `partial_residual_at` and `complete`).
    pub fn screen(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.solve_to(state, fixed, (SCREENING_RTOL, true))
    }

    /// Continues the last solve through `state`, an inexact [`Self::screen`] with the same
    /// `fixed`, to [`ITERATIVE_RTOL`] with its multigrid hierarchy; `None` if that solve was
    /// exact (or another solve came since). `fixed` differing from that solve's is an error.
    pub fn refine(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
    ) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.bind(state);
        let kept = match state.kept.take() {
            Some(k) if k.screened.is_some() => k,
            other => {
                state.kept = other;
                return Ok(None);
            }
        };
        let KeptHierarchy {
            amg,
            screened,
            fresh_rate,
            fixed_mask,
            fine_mask,
            cells,
            ..
        } = kept;
        let (rhs, print) = screened.unwrap_or_default();
        if print != fingerprint(fixed) {
            return Err(crate::Error::InvalidData(
                "refine: the fixed unknowns differ from those of the screening solve".into(),
            ));
        }
        let t0 = Instant::now();
        // the hierarchy's rate is known: a refinement is not judged against it
        let hier = Hierarchy {
            amg,
            fresh_rate,
            fixed_mask,
            fine_mask,
            reused: None,
            cells,
        };
        match self.continue_pcg(state, hier, rhs, fixed) {
            Ok((u, iterations)) => Ok(Some((
                u,
                SolveTimings {
                    solve: t0.elapsed().as_secs_f64(),
                    krylov: iterations,
                    ..Default::default()
                },
            ))),
            // as in a solve: with Auto, the direct solver takes over
            Err(_) if self.sym.options.linear == LinearSolver::Auto => {
                self.fallback_pattern(state)?;
                self.solve(state, fixed).map(Some)
            }
            Err(e) => Err(e),
        }
    }

    /// Runs the conjugate gradients of a refinement with the kept hierarchy `hier`, on the
    /// system it was built for (right-hand side `rhs`, freed once they ended), from the last
    /// solution: the full unknown vector and the iterations.
    fn continue_pcg(
        &self,
        state: &mut SolveState,
        hier: Hierarchy,
        rhs: Vec<f64>,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, usize)> {
        let cs = if hier.cells {
            self.cell_system(state)?
        } else {
            None
        };
        let mut x = match &cs {
            Some(cs) => self.take_cell_guess(state, cs)?,
            None => self.take_initial_guess(state)?,
        };
        let out = self.run_pcg(
            state,
            hier,
            &rhs,
            &mut x,
            ITERATIVE_RTOL,
            fixed,
            cs.as_deref(),
        )?;
        drop(rhs);
        let u = match cs {
            Some(cs) => {
                let u = self.complete_cells(&cs, &self.fixed_values(fixed), &x)?;
                self.keep_cells(state, x, &u)?;
                u
            }
            None => {
                let u = self.complete(fixed, try_copy(&x, "the solution")?)?;
                self.keep_solution(state, x);
                u
            }
        };
        Ok((u, out.iterations))
    }

    /// [`Self::solve`] to the relative residual `rtol` (below [`ITERATIVE_RTOL`]), from the last
    /// solution kept in `state`: the active-set solver's polish of a settled iterate whose
    /// certificate residuals are above its tolerance (see `QuadraticEnergy::polish`). `None`
    /// for a direct solve, which is exact already.
    pub fn polish(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
        rtol: f64,
    ) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.bind(state);
        if self.is_direct(state) {
            return Ok(None);
        }
        self.solve_to(state, fixed, (rtol, false)).map(Some)
    }

    /// Assembles and solves with `fixed`, an iterative solve to the relative residual `rtol`;
    /// with `partial`, an inexact solve of the cell system returns its partial iterate
    /// ([`Self::screen`]).
    fn solve_to(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
        (rtol, partial): (f64, bool),
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.bind(state);
        let t0 = Instant::now();
        if let Some(cs) = self.cell_system_for(state, fixed)? {
            if self.is_direct(state) {
                return self.solve_cells_direct(state, &cs, fixed, t0);
            }
            match self.solve_cells(state, &cs, fixed, (rtol, partial), t0) {
                Ok(r) => return Ok(r),
                // as below: with Auto, the direct solver takes over
                Err(_) if self.sym.options.linear == LinearSolver::Auto => {
                    self.fallback_pattern(state)?;
                    return self.solve_to(state, fixed, (rtol, partial));
                }
                Err(e) => return Err(e),
            }
        }
        // the kept hierarchy is taken (or freed, for a direct solve) before the assembly
        let reuse = if self.is_direct(state) {
            state.kept = None;
            None
        } else {
            Some(self.next_hierarchy(state, fixed, false)?)
        };
        if let Some(a) = self.assembled() {
            let (x, t1, t2, out) = self.solve_assembled(state, a, fixed, rtol, reuse)?;
            let u = self.complete(fixed, x)?;
            return Ok((u, out.timings([t0, t1, t2, Instant::now()])));
        }
        let (values, mut rhs) = self.assemble_condensed(state, fixed)?;
        let t1 = Instant::now();
        let (t2, out) = match reuse {
            None => self.solve_direct(state, &values, &mut rhs)?,
            Some(reuse) if self.sym.options.linear == LinearSolver::Auto => {
                let c = try_copy(&rhs, "the right-hand side")?;
                let it = self
                    .csr(&values)
                    .and_then(|a| self.solve_csr(state, a.into(), &mut rhs, rtol, fixed, reuse));
                match it {
                    Ok(r) => r,
                    // Auto chose the iterative solver by size: when the conjugate gradients
                    // fail (no convergence on a hard matrix), the direct solver takes over,
                    // for this solve and the following ones
                    Err(_) => {
                        rhs = c;
                        self.fallback_pattern(state)?;
                        self.solve_direct(state, &values, &mut rhs)?
                    }
                }
            }
            Some(reuse) => {
                // the lower triangle is not needed once stored by rows: freed before the
                // multigrid hierarchy is built
                let a = self.csr(&values)?;
                drop(values);
                self.solve_csr(state, a.into(), &mut rhs, rtol, fixed, reuse)?
            }
        };
        let u = self.complete(fixed, rhs)?;
        Ok((u, out.timings([t0, t1, t2, Instant::now()])))
    }

    /// [`Self::solve_to`] for a scheme without interior unknowns: the system masked from the
    /// assembled matrix `a` ([`super::assembled`]), by rows for the conjugate gradients and on
    /// the lower pattern for the direct solver (with `Auto`, also when the conjugate gradients
    /// fail). Returns the solution, when the assembly and the multigrid setup ended, and what
    /// the solver did.
    fn solve_assembled(
        &self,
        state: &mut SolveState,
        a: &CsrMatrix,
        fixed: &FixedValues,
        rtol: f64,
        reuse: Option<NextHierarchy>,
    ) -> crate::Result<(Vec<f64>, Instant, Instant, PcgOutcome)> {
        let fx = self.fixed_values(fixed);
        let Some(reuse) = reuse else {
            let mut rhs = self.masked_rhs(a, &fx)?;
            let values = self.masked_lower(a, &fx, self.direct_pattern(&state.direct_fallback)?)?;
            let t1 = Instant::now();
            let (t2, out) = self.solve_direct(state, &values, &mut rhs)?;
            return Ok((rhs, t1, t2, out));
        };
        let (s, reuse) = self.masked_rows_reusing(&fx, reuse)?;
        let mut rhs = self.masked_rhs_of_view(&s, &fx)?;
        let t1 = Instant::now();
        match self.solve_csr(state, s.into(), &mut rhs, rtol, fixed, reuse) {
            Ok((t2, out)) => Ok((rhs, t1, t2, out)),
            // as for the gathered systems: with Auto, the direct solver takes over
            Err(_) if self.sym.options.linear == LinearSolver::Auto => {
                let fx = self.fixed_values(fixed);
                let mut c = self.masked_rhs(a, &fx)?;
                let pattern = self.fallback_pattern(state)?;
                let values = self.masked_lower(a, &fx, pattern)?;
                let (t2, out) = self.solve_direct(state, &values, &mut c)?;
                Ok((c, t1, t2, out))
            }
            Err(e) => Err(e),
        }
    }

    /// The values of the fixed unknowns: `fixed` and the Dirichlet ones.
    pub(super) fn fixed_values<'f>(&'f self, fixed: &'f FixedValues) -> Pinned<'f> {
        Pinned::new(&self.values.dirichlet, fixed)
    }

    /// The full unknown vector from the skeleton solution `skel`: interior unknowns recovered
    /// cell by cell; a non-finite value is an error. Without interior unknowns, `skel` itself
    /// (no second vector of the order of the system at the end of a solve).
    pub(super) fn complete(&self, fixed: &FixedValues, skel: Vec<f64>) -> crate::Result<Vec<f64>> {
        if self.n_skel == self.n {
            return check_finite(skel);
        }
        let pinned = self.fixed_values(fixed);
        let fx = |d: usize| -> Option<f64> { pinned.get(d) };
        let mut u = try_filled(self.n, 0.0, "the solution")?;
        u[..self.n_skel].copy_from_slice(&skel);
        drop(skel);
        self.recover_interiors(&fx, &mut u)?;
        check_finite(u)
    }

    /// Sets the skeleton unknowns the next iterative solve through `state` starts from
    /// (ignored by the direct solver, and if its length is not the number of skeleton
    /// unknowns); afterwards each iterative solve starts from the previous solution.
    pub fn set_initial_guess(&self, state: &mut SolveState, guess: Vec<f64>) {
        self.bind(state);
        if guess.len() == self.n_skel {
            state.last_solution = guess;
        }
    }

    /// Whether the solves are direct: the symbolic system has a factorisation or defers it
    /// ([`super::SymbolicSystem::is_direct`]), or the one built in `state` when the iterative
    /// solver failed ([`LinearSolver::Auto`]).
    fn is_direct(&self, state: &SolveState) -> bool {
        self.sym.is_direct() || matches!(state.direct_fallback, Some(Ok(_)))
    }

    /// The pattern of a direct solve ([`Self::is_direct`]): the symbolic system's, or
    /// `fallback`, the one built in the state when the iterative solver failed.
    fn direct_pattern<'s>(
        &'s self,
        fallback: &'s Option<Result<SpdPattern, String>>,
    ) -> crate::Result<&'s SpdPattern> {
        match (self.sym.pattern(), fallback) {
            (Some(p), _) if p.has_factorisation() => Ok(p),
            (_, Some(Ok(p))) => Ok(p),
            _ => Err(crate::Error::Internal(
                "a direct solve without a symbolic factorisation".into(),
            )),
        }
    }

    /// The direct solve of S x = c with the symbolic factorisation [`Self::is_direct`] finds
    /// (a deferred one built now, on first use).
    pub(super) fn solve_direct(
        &self,
        state: &mut SolveState,
        values: &[f64],
        rhs: &mut [f64],
    ) -> crate::Result<(Instant, PcgOutcome)> {
        if !self.sym.has_factorisation() {
            self.fallback_pattern(state)?;
        }
        let SolveState {
            direct_fallback,
            cholesky,
            ..
        } = state;
        solve_directly(self.direct_pattern(direct_fallback)?, values, rhs, cholesky)
    }

    /// The symbolic factorisation of the condensed pattern, built in `state` on first use (the
    /// direct solver taking over from a failed iterative one, or a deferred factorisation),
    /// and its numeric phase checked against the caller's budget
    /// ([`SystemOptions::budget`](super::SystemOptions::budget)) as for a direct system.
    pub(super) fn fallback_pattern<'s>(
        &self,
        state: &'s mut SolveState,
    ) -> crate::Result<&'s SpdPattern> {
        if state.direct_fallback.is_none() {
            let (col_ptr, row_idx) = match self.condensed_pattern() {
                Some((col_ptr, row_idx)) => {
                    let what = "the pattern copy of the direct solver";
                    (try_copy(col_ptr, what)?, try_copy(row_idx, what)?)
                }
                // released with the assembly (no interior unknowns): built again
                None => {
                    let dm = super::DofMap::new(self.scheme())?;
                    self.sym.rebuild_pattern(&dm)?
                }
            };
            let built =
                SpdPattern::with_ordering(self.n_skel, col_ptr, row_idx, self.sym.options.ordering)
                    // factorised with the threads a direct system uses
                    .map(|p| p.with_threads(self.sym.options.factor_threads))
                    .map_err(|e| e.to_string())
                    .and_then(|p| {
                        let budget = self.sym.options.budget;
                        match check_numeric_memory(&p, &self.sym.maps, self.n, budget) {
                            Ok(()) => Ok(p),
                            Err(crate::Error::Linear(m)) => Err(m),
                            Err(e) => Err(e.to_string()),
                        }
                    });
            state.direct_fallback = Some(built);
        }
        match &state.direct_fallback {
            Some(built) => built.as_ref().map_err(|e| crate::Error::Linear(e.clone())),
            None => Err(crate::Error::Internal("no direct fallback".into())),
        }
    }

    /// Fills the interior unknowns of `u` from its skeleton values, cell by cell
    /// ([`recover_interior`]): u_R = M_RR⁻¹ (b_R − Σ_{j∉R} M_Rj u_j) on each cell.
    fn recover_interiors(
        &self,
        fx: &(dyn Fn(usize) -> Option<f64> + Sync),
        u: &mut [f64],
    ) -> crate::Result<()> {
        let nc = self.sym.scheme().mesh().n_cells();
        if self.sym.no_interior {
            return Ok(());
        }
        if self.sym.single_interior {
            // one interior unknown per cell, computed in parallel from the skeleton values
            let mut interior: Vec<(usize, f64)> = try_vec(nc, "the interior values")?;
            interior.par_extend((0..nc).into_par_iter().map(|k| {
                let cell = self.local(k);
                (cell.dofs[0] as usize, interior_value(&cell, fx, u))
            }));
            for (dof, v) in interior {
                u[dof] = v;
            }
        } else {
            for k in 0..nc {
                let cell = self.local(k);
                if cell.n_interior > 0 {
                    recover_interior(&cell, fx, u).map_err(|e| e.in_cell(k))?;
                }
            }
        }
        Ok(())
    }
}
