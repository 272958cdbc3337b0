//! Algorithms for the discrete variational inequality, seen as an algebraic problem: minimise
//! the quadratic energy ½uᵀMu − bᵀu over {u : u_i = u_D,i on Dirichlet unknowns,
//! s(u_j − g_j) ≤ 0 on the constrained unknowns j}.
//!
//! The algorithms see only the trait [`QuadraticEnergy`] (what they need of M and b) and their
//! own types: [`Constraints`], [`Certificate`], [`IterationLog`] (an [`IterationStep`] and its
//! [`SolveTimings`]), [`VariationalSolution`], [`Side`]. They know nothing of meshes, schemes,
//! problems or assembly (this module imports none of them): the layers above implement the
//! trait (the assembled system paired with the state of its solves, `assembly::Solving`), and so
//! do small dense systems in the tests. A solve takes the energy `&mut`: what carries from one
//! solve to the next belongs to the value the caller passes.
//!
//! - [`active_set`]: the monotony (primal–dual active set) algorithm, with cycle detection;
//! - [`look_ahead`]: its next steps near the free boundary, by local solves on a patch;
//! - [`pgs`]: projected Gauss–Seidel, slow and robust (a fallback and an independent reference);
//! - [`exhaustive`]: enumeration of the active sets, the reference for small problems;
//! - [`certificate`]: the evidence that a vector solves the inequality.
//!
//! Which algorithm runs, from which start, and what happens when one fails, is decided by the
//! solve driver ([`crate::solver`]), not here.

pub mod active_set;
pub mod certificate;
#[cfg(test)]
pub(crate) mod dense;
pub mod exhaustive;
pub mod fixed;
pub mod look_ahead;
pub mod pgs;

pub use active_set::{ActiveSetOptions, Cancel};
pub use certificate::{Certificate, Evaluation};
pub use fixed::FixedValues;

/// Timings of one constrained minimisation (a linear solve), in seconds.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SolveTimings {
    /// Assembly of the reduced system (condensation and scatter).
    pub assemble: f64,
    /// Numeric factorisation (iterative solver: the multigrid setup).
    pub factor: f64,
    /// Triangular solves and recovery of eliminated unknowns (iterative solver: the
    /// conjugate gradients).
    pub solve: f64,
    /// Conjugate-gradient iterations (0 with the direct solver).
    pub krylov: usize,
    /// The solve stopped at the screening tolerance of
    /// [`QuadraticEnergy::screen_with_fixed`], not at full accuracy.
    pub inexact: bool,
    /// The iterative solver preconditioned with the coarse levels of an earlier solve's
    /// multigrid hierarchy instead of building one.
    pub reused: bool,
    /// The iterate is *partial*: a screened solve ([`SolveTimings::inexact`]) left the
    /// unknowns the energy derives from the others by their own rows unset (NaN), to be read
    /// through [`QuadraticEnergy::partial_values`] and [`QuadraticEnergy::complete`] (HMM's
    /// faces eliminated in the two-point form, `assembly::two_point`). Never set on an exact
    /// iterate.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub partial: bool,
}

impl SolveTimings {
    /// The timings of a solve followed by its continuation `more` (times and iterations
    /// added; exact if the continuation is).
    pub fn then(self, more: SolveTimings) -> SolveTimings {
        SolveTimings {
            assemble: self.assemble + more.assemble,
            factor: self.factor + more.factor,
            solve: self.solve + more.solve,
            krylov: self.krylov + more.krylov,
            inexact: more.inexact,
            reused: self.reused,
            partial: more.partial,
        }
    }
}

/// A strictly convex quadratic energy E(u) = ½uᵀMu − bᵀu (M symmetric positive definite on
/// the non-Dirichlet unknowns) with Dirichlet unknowns, as the algorithms of this module need
/// it.
pub trait QuadraticEnergy {
    /// Number of unknowns.
    fn n_unknowns(&self) -> usize;
    /// Dirichlet unknowns and their values (`None`: free).
    fn dirichlet(&self) -> &FixedValues;
    /// The load vector b.
    fn load(&self) -> &[f64];
    /// The minimiser of E with the unknowns `fixed` fixes (and the Dirichlet ones)
    /// fixed, i.e. the solution of the linear system with those rows replaced. `&mut self`:
    /// an implementation may carry what it learnt (an initial guess, a multigrid hierarchy)
    /// to the next solve; that state belongs to the value the caller passes, never to a lock
    /// behind `&self`.
    fn minimise_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)>;
    /// [`Self::minimise_with_fixed`] accurate enough to decide the next active set: an
    /// iterative solver may stop at a looser residual, and then sets
    /// [`SolveTimings::inexact`] (the active-set solver calls [`Self::refine`] before it
    /// stops or declares a cycle on such an iterate). Such an inexact iterate may also be
    /// partial ([`SolveTimings::partial`]): its derived unknowns are then NaN, and the
    /// algorithms read them through [`Self::partial_values`], evaluate it through
    /// [`Self::partial_residual_at`] and fill it through [`Self::complete`]. Default: the
    /// full solve.
    fn screen_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.minimise_with_fixed(fixed)
    }
    /// Continues the last solve, an inexact [`Self::screen_with_fixed`] with the same
    /// `fixed`, to full accuracy; `None` when there is nothing to continue (the caller keeps
    /// its iterate). Default: `None`.
    fn refine(&mut self, fixed: &FixedValues) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        let _ = fixed;
        Ok(None)
    }
    /// Solves again with `fixed`, from the last solution, to the relative residual `rtol`
    /// (below the iterative solver's usual target): what the active-set solver asks when its
    /// iteration has settled but the certificate's residuals, a maximum over the unknowns, are
    /// above its tolerance while the solve's residual, a 2-norm, met its own. `None` when the
    /// solves are exact (direct) and there is nothing to polish. Default: `None`.
    fn polish(
        &mut self,
        fixed: &FixedValues,
        rtol: f64,
    ) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        let _ = (fixed, rtol);
        Ok(None)
    }
    /// The iteration is over: free what is kept from one solve to the next (a multigrid
    /// hierarchy, for instance). Default: nothing.
    fn release(&mut self) {}
    /// r = b − Mu and, for each entry, the scale |b_i| + Σ_j |M_ij u_j| against which it is
    /// small (an error only if the energy's own data are inconsistent).
    fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)>;
    /// The entries `row(0)`, …, `row(len − 1)` of [`Self::residual`]'s r, to the bit, and
    /// the largest of their scales. Default: the whole residual, then those entries; an
    /// energy that can compute single rows overrides it.
    fn residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        let (r, scale) = self.residual(u)?;
        let mut out = Vec::with_capacity(len);
        let mut max = 0.0f64;
        for k in 0..len {
            let i = row(k);
            match (r.get(i), scale.get(i)) {
                (Some(&v), Some(&s)) => {
                    out.push(v);
                    max = max.max(s);
                }
                _ => {
                    return Err(crate::Error::Internal(format!(
                        "residual at row {i} of a system of {} unknowns",
                        r.len()
                    )));
                }
            }
        }
        Ok((out, max))
    }
    /// The values at the unknowns `at` of a partial iterate `u` ([`SolveTimings::partial`]):
    /// its own where it has them, and the derived unknowns it left unset recovered from the
    /// others by their rows (u_σ = (b_σ − Σ_{j≠σ} M_σj u_j) / M_σσ, which involves no other
    /// derived unknown). Only for partial iterates: on a complete one the recovered values
    /// could differ from u's in the last bits. Default (an energy whose iterates are never
    /// partial): u's values.
    fn partial_values(&self, u: &[f64], at: &[usize]) -> crate::Result<Vec<f64>> {
        at.iter()
            .map(|&j| {
                u.get(j).copied().ok_or_else(|| {
                    crate::Error::Internal(format!(
                        "unknown {j} of an iterate of {} unknowns",
                        u.len()
                    ))
                })
            })
            .collect()
    }
    /// Fills the derived unknowns of a partial iterate `u` ([`Self::partial_values`] at each
    /// of them), making it complete. Default: nothing (iterates are never partial).
    fn complete(&self, u: &mut [f64]) -> crate::Result<()> {
        let _ = u;
        Ok(())
    }
    /// [`Self::residual_at`] of a partial iterate `u`, computed from the unknowns it has: the
    /// residual of the iterate [`Self::complete`] would give, up to rounding (the derived
    /// unknowns satisfy their rows exactly), with the scale of the rows the energy computes
    /// them from. Only for partial iterates. Default: [`Self::residual_at`].
    fn partial_residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        self.residual_at(u, len, row)
    }
    /// The entries (i, j, M_ij) of M, possibly with repeated (i, j) to be summed.
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)>;
    /// The entries (i, j, M_ij) of the rows i ∈ `rows` of M (repeated (i, j) to be summed),
    /// for the [`look_ahead`]; `None` (the default) if the energy cannot give single rows.
    fn row_entries(&self, rows: &[usize]) -> crate::Result<Option<Vec<(usize, usize, f64)>>> {
        let _ = rows;
        Ok(None)
    }
}

/// Direction of a barrier, as the algorithms see it: the constraint is s·(u − g) ≤ 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Side {
    /// u ≤ g.
    Upper,
    /// u ≥ g.
    Lower,
}

impl Side {
    /// s = +1 for an upper barrier, −1 for a lower one.
    pub fn sign(self) -> f64 {
        match self {
            Side::Upper => 1.0,
            Side::Lower => -1.0,
        }
    }
}

/// A constrained unknown: its index, the measure that scales its multiplier, and a payload
/// `P` the algorithms carry without reading (the layers above put the point where the barrier
/// was evaluated there; the algorithms' own tests put `()`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstrainedDof<P = ()> {
    /// Global unknown index.
    pub dof: usize,
    /// Where the barrier was evaluated (or any payload of the caller's).
    pub point: P,
    /// Measure attached to the unknown (the multiplier is compared with it).
    pub measure: f64,
}

/// The barrier, on the unknowns it acts on.
#[derive(Debug, Clone)]
pub struct Constraints<P = ()> {
    /// Constrained unknowns (never Dirichlet unknowns), with the measure that scales the
    /// multiplier.
    pub dofs: Vec<ConstrainedDof<P>>,
    /// Barrier value on each constrained unknown (g_K, a_σ, or nodal values).
    pub barrier: Vec<f64>,
    /// Upper (u ≤ g) or lower (u ≥ ψ).
    pub side: Side,
}

impl<P> Constraints<P> {
    /// The fixed values of a solve with the active set `active`: u_j = g_j on active j, of
    /// the `n` unknowns of the system; a non-finite barrier on an active unknown is an error.
    pub fn fixed(&self, n: usize, active: &[bool]) -> crate::Result<FixedValues> {
        let mut fixed = FixedValues::free(n)?;
        for (j, pd) in self.dofs.iter().enumerate() {
            if active[j] {
                fixed.try_set(pd.dof, self.barrier[j])?;
            }
        }
        Ok(fixed)
    }
}

/// What one solve of an iteration did: one line of the iteration log without its timings
/// (the columns of the replication's `iterations.csv`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct IterationStep {
    /// Linear solve number (1-based).
    pub solve: usize,
    /// Size of the active set used for this solve.
    pub active: usize,
    /// Unknowns that entered the active set for this solve.
    pub entered: usize,
    /// Unknowns that left it.
    pub left: usize,
    /// Largest scaled constraint violation of the iterate.
    pub violation: f64,
    /// Largest scaled balance residual on inactive unknowns of the iterate; `None` for a
    /// screened iterate (an iterative solve stopped early to choose the next active set),
    /// whose residual is computed on the constrained unknowns only
    /// ([`certificate::evaluate_screened`]).
    pub residual: Option<f64>,
}

/// One line of the iteration log: the [`IterationStep`] (its fields read through the log,
/// `l.solve`, `l.active`, …) and the timings of the solve.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct IterationLog {
    /// What the solve did.
    #[serde(flatten)]
    pub step: IterationStep,
    /// Timings of the solve.
    pub timings: SolveTimings,
    /// The look-ahead made after the solve, if any ([`look_ahead`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub look_ahead: Option<look_ahead::LookAheadReport>,
}

/// How a solution was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Method {
    /// A single linear solve (no barrier).
    Linear,
    /// The active-set (monotony) algorithm.
    ActiveSet,
    /// Projected Gauss–Seidel (fallback).
    ProjectedGaussSeidel,
}

/// The outcome of a solve.
#[derive(Debug, Clone)]
pub struct VariationalSolution {
    /// All unknowns (skeleton first, then interior).
    pub u: Vec<f64>,
    /// Multiplier λ_j for each constrained unknown (indexed like [`Constraints::dofs`]).
    pub multiplier: Vec<f64>,
    /// Active flag for each constrained unknown.
    pub active: Vec<bool>,
    /// Number of linear solves (NITER), or of sweeps for projected Gauss–Seidel.
    pub niter: usize,
    /// Iteration log.
    pub log: Vec<IterationLog>,
    /// The certificate of the returned u.
    pub certificate: Certificate,
    /// How u was obtained.
    pub method: Method,
    /// The iterates u^1, u^2, … if [`ActiveSetOptions::keep_iterates`] was set.
    pub iterates: Vec<Vec<f64>>,
}

/// The solution of the problem without barrier: one solve, certified.
pub fn solve_unconstrained(
    q: &mut dyn QuadraticEnergy,
    tol: f64,
) -> crate::Result<VariationalSolution> {
    certificate::check_tolerance(tol)?;
    let fixed = FixedValues::free(q.n_unknowns())?;
    let (u, timings) = q.minimise_with_fixed(&fixed)?;
    let ev = certificate::evaluate::<()>(&*q, None, &u, &[])?;
    ev.certificate.check(tol)?;
    Ok(VariationalSolution {
        log: vec![IterationLog {
            step: IterationStep {
                solve: 1,
                active: 0,
                entered: 0,
                left: 0,
                violation: 0.0,
                residual: Some(ev.certificate.balance_residual),
            },
            timings,
            look_ahead: None,
        }],
        u,
        multiplier: vec![],
        active: vec![],
        niter: 1,
        certificate: ev.certificate,
        method: Method::Linear,
        iterates: vec![],
    })
}
