//! The monotony algorithm of Herbin (SIAM J. Numer. Anal. 40, 2003), i.e. the primal–dual
//! active set method of Hintermüller–Ito–Kunisch, for the discrete variational inequality
//!
//! find u with s(u_j − g_j) ≤ 0 on the constrained unknowns j, minimising ½uᵀMu − bᵀu,
//!
//! where s = +1 for an upper barrier (u ≤ g) and s = −1 for a lower one (u ≥ ψ). The
//! multiplier is the residual of the balance equation: λ_j = s (b − Mu)_j, and the KKT
//! conditions are λ_j ≥ 0, s(u_j − g_j) ≤ 0, λ_j (u_j − g_j) = 0, (b − Mu)_i = 0 elsewhere.
//! (For HMM obstacle problems λ_K = s(|K| f_K − Σ_σ |σ| F_{K,σ}); for Signorini faces
//! λ_σ = −s|σ|(F_{K,σ}) — the paper's Section 4 balances.)
//!
//! Iteration (NITER counts the linear solves, as in the paper's Tables 1–3):
//! 1. A₀ = ∅: solve the unconstrained problem (solve 1).
//! 2. Given the iterate (u^k, λ^k) of the active set A_k (u^k_j = g_j exactly on A_k,
//!    λ^k_j = 0 off A_k), set A_{k+1} = { j : λ^k_j / m_j + c·s(u^k_j − g_j) > 0 }, with m_j the
//!    measure of unknown j (|K|, |σ|, or a vertex's lumped measure) and c > 0 (default 1).
//!    Because complementarity holds exactly at every iterate, this is Herbin's rule — a
//!    violated unknown enters, an active unknown with a positive multiplier stays — whatever c;
//!    c matters only for a warm start given as an initial active set. Round-off is filtered by
//!    relative thresholds (violations below 10⁻¹³·‖u‖, multipliers below 10⁻¹³ times the
//!    residual scale are treated as zero).
//! 3. If A_{k+1} = A_k, stop: u^k is the solution (NITER = k + 1 solves). If A_{k+1} equals an
//!    older active set, the iteration cycles: a typed error with the history. Otherwise solve
//!    with A_{k+1} fixed and repeat.
//!
//! Every returned solution carries a [`Certificate`]; above tolerance the solve is an error.

use super::pgs;
use crate::assembly::SolveTimings;
use crate::error::SolverError;
use crate::problem::Side;
use crate::scheme::PointDof;

/// What the active-set and projected Gauss–Seidel solvers need from a discrete problem: the
/// quadratic energy ½uᵀMu − bᵀu with Dirichlet unknowns, a solve with extra fixed unknowns,
/// and the residual. Implemented by [`crate::assembly::DiscreteSystem`] for every scheme, and by
/// small dense systems in the tests.
pub trait LinearSystem {
    /// Number of unknowns.
    fn n_unknowns(&self) -> usize;
    /// Dirichlet unknowns and their values (`None`: free).
    fn dirichlet(&self) -> &[Option<f64>];
    /// The load vector b.
    fn load(&self) -> &[f64];
    /// Solves with the unknowns `fixed[d] = Some(v)` (and the Dirichlet ones) fixed.
    fn solve(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)>;
    /// r = b − Mu and the scale |b_i| + Σ_j |M_ij u_j| of each entry.
    fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>);
    /// The entries (i, j, M_ij) of M, possibly with repeated (i, j) to be summed.
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)>;
}

/// The barrier, on the unknowns it acts on.
#[derive(Debug, Clone)]
pub struct Constraints {
    /// Constrained unknowns (never Dirichlet unknowns), points and measures.
    pub dofs: Vec<PointDof>,
    /// Barrier value on each constrained unknown (g_K, a_σ, or nodal values).
    pub barrier: Vec<f64>,
    /// Upper or lower.
    pub side: Side,
}

/// Options of the active-set solver.
#[derive(Debug, Clone)]
pub struct ActiveSetOptions {
    /// The PDAS parameter c (> 0), multiplying the violation; multipliers are divided by the
    /// measure of their unknown.
    pub c: f64,
    /// Maximum number of linear solves.
    pub max_solves: usize,
    /// Tolerance of the certificate (each scaled quantity must be below it).
    pub tol: f64,
    /// On cycling or the iteration cap, fall back to projected Gauss–Seidel instead of failing.
    pub fallback: bool,
    /// Initial active set (warm start), indexed like [`Constraints::dofs`]. Takes precedence
    /// over [`ActiveSetOptions::warm_start`].
    pub initial_active: Option<Vec<bool>>,
    /// How [`crate::solver::solve_problem`] starts the iteration when no `initial_active` is
    /// given: cold (A₀ = ∅, the default) or from a nested coarse prediction (see
    /// [`crate::solver::warm_start`]). The algebraic [`solve`] has no mesh to predict on and
    /// rejects `Nested` without an `initial_active`.
    pub warm_start: super::warm_start::WarmStart,
    /// Keep every iterate u^k in [`VariationalSolution::iterates`] (for studies of the
    /// iteration; costs one vector per solve).
    pub keep_iterates: bool,
    /// Called with each line of the iteration log as soon as it is known (progress of long
    /// runs; `gradvi solve` prints it to stderr).
    pub progress: Option<fn(&IterationLog)>,
}

impl Default for ActiveSetOptions {
    fn default() -> Self {
        ActiveSetOptions {
            c: 1.0,
            max_solves: 500,
            tol: 1e-10,
            fallback: false,
            initial_active: None,
            warm_start: super::warm_start::WarmStart::Cold,
            keep_iterates: false,
            progress: None,
        }
    }
}

/// One line of the iteration log.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct IterationLog {
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
    /// Largest scaled balance residual on inactive unknowns of the iterate.
    pub residual: f64,
    /// Timings of the solve.
    pub timings: SolveTimings,
}

/// Evidence that u solves the discrete variational inequality. Every quantity is scaled to be
/// dimensionless: violations by ‖u‖∞ (or the barrier's sup if larger), residuals and multipliers
/// by max_i(|b_i| + Σ_j |M_ij u_j|).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Certificate {
    /// max_j max(0, s(u_j − g_j)) / scale_u.
    pub max_violation: f64,
    /// min_j λ_j / scale_r over constrained unknowns (≥ 0 up to round-off; reported as is).
    pub min_multiplier: f64,
    /// max_j |λ_j (u_j − g_j)| / (scale_r scale_u).
    pub complementarity: f64,
    /// max_i |(b − Mu)_i| / scale_r over unknowns that are neither Dirichlet nor active.
    pub balance_residual: f64,
}

impl Certificate {
    /// The first quantity above `tol`, as an error.
    pub fn check(&self, tol: f64) -> Result<(), SolverError> {
        for (name, v) in [
            ("constraint violation", self.max_violation),
            ("negative multiplier", -self.min_multiplier),
            ("complementarity", self.complementarity),
            ("balance residual", self.balance_residual),
        ] {
            if !(v <= tol) {
                return Err(SolverError::Certificate {
                    quantity: name.into(),
                    value: v,
                    tol,
                });
            }
        }
        Ok(())
    }
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
    /// Number of linear solves (NITER).
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

/// Computes the certificate of `u` (the multipliers are returned too).
pub fn certificate(
    system: &dyn LinearSystem,
    cons: Option<&Constraints>,
    u: &[f64],
    active: &[bool],
) -> (Certificate, Vec<f64>) {
    let (r, scale) = system.residual(u);
    let scale_r = scale
        .iter()
        .cloned()
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut scale_u = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut is_active = vec![false; u.len()];
    let mut c = Certificate::default();
    let mut lambda = Vec::new();
    if let Some(cons) = cons {
        scale_u = cons.barrier.iter().fold(scale_u, |m, x| m.max(x.abs()));
        let scale_u = scale_u.max(f64::MIN_POSITIVE);
        let s = cons.side.sign();
        let mut min_l = f64::INFINITY;
        for (j, pd) in cons.dofs.iter().enumerate() {
            let l = s * r[pd.dof];
            lambda.push(l);
            let gap = u[pd.dof] - cons.barrier[j];
            c.max_violation = c.max_violation.max((s * gap).max(0.0) / scale_u);
            min_l = min_l.min(l / scale_r);
            c.complementarity = c.complementarity.max((l * gap).abs() / (scale_r * scale_u));
            if active[j] {
                is_active[pd.dof] = true;
            }
        }
        c.min_multiplier = if min_l.is_finite() { min_l } else { 0.0 };
    }
    let dir = system.dirichlet();
    for i in 0..u.len() {
        if dir[i].is_none() && !is_active[i] {
            c.balance_residual = c.balance_residual.max(r[i].abs() / scale_r);
        }
    }
    (c, lambda)
}

fn fixed_from(system: &dyn LinearSystem, cons: &Constraints, active: &[bool]) -> Vec<Option<f64>> {
    let mut fixed = vec![None; system.n_unknowns()];
    for (j, pd) in cons.dofs.iter().enumerate() {
        if active[j] {
            fixed[pd.dof] = Some(cons.barrier[j]);
        }
    }
    fixed
}

/// Solves the discrete variational inequality by the active-set method (see module docs).
pub fn solve(
    system: &dyn LinearSystem,
    cons: &Constraints,
    opts: &ActiveSetOptions,
) -> crate::Result<VariationalSolution> {
    if !(opts.c > 0.0 && opts.c.is_finite()) {
        return Err(crate::Error::InvalidData(format!(
            "the active-set parameter c must be positive, got {}",
            opts.c
        )));
    }
    let m = cons.dofs.len();
    let s = cons.side.sign();
    let mut active = match &opts.initial_active {
        Some(a) if a.len() == m => a.clone(),
        Some(a) => {
            return Err(crate::Error::InvalidData(format!(
                "initial active set has {} entries for {m} constrained unknowns",
                a.len()
            )));
        }
        None if opts.warm_start == super::warm_start::WarmStart::Nested => {
            return Err(crate::Error::InvalidData(
                "the nested warm start needs the mesh: use solver::solve_problem, or give initial_active".into(),
            ));
        }
        None => vec![false; m],
    };
    let mut history: Vec<Vec<bool>> = vec![active.clone()];
    let mut iterates = Vec::new();
    let mut log = Vec::new();
    let mut entered = active.iter().filter(|&&a| a).count();
    let mut left = 0;
    let fail = |err: SolverError, log: &Vec<IterationLog>| -> crate::Result<VariationalSolution> {
        if opts.fallback {
            let mut sol = pgs::solve(system, cons, &pgs::PgsOptions::default())?;
            sol.niter += log.len();
            let mut full_log = log.clone();
            full_log.extend(sol.log);
            sol.log = full_log;
            Ok(sol)
        } else {
            Err(err.into())
        }
    };
    loop {
        let fixed = fixed_from(system, cons, &active);
        let (u, timings) = system.solve(&fixed)?;
        if opts.keep_iterates {
            iterates.push(u.clone());
        }
        let (cert, lambda) = certificate(system, Some(cons), &u, &active);
        let n_active = active.iter().filter(|&&a| a).count();
        log.push(IterationLog {
            solve: log.len() + 1,
            active: n_active,
            entered,
            left,
            violation: cert.max_violation,
            residual: cert.balance_residual,
            timings,
        });
        if let (Some(report), Some(line)) = (opts.progress, log.last()) {
            report(line);
        }
        // thresholds for round-off
        let (_, scale) = system.residual(&u);
        let scale_r = scale
            .iter()
            .cloned()
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let scale_u = cons
            .barrier
            .iter()
            .fold(u.iter().fold(0.0f64, |a, x| a.max(x.abs())), |a, x| {
                a.max(x.abs())
            })
            .max(f64::MIN_POSITIVE);
        let mut next = vec![false; m];
        for j in 0..m {
            let pd = &cons.dofs[j];
            let l = if active[j] { lambda[j] } else { 0.0 };
            let gap = if active[j] {
                0.0
            } else {
                s * (u[pd.dof] - cons.barrier[j])
            };
            let score = l / pd.measure + opts.c * gap;
            // round-off thresholds, one per term: an active unknown stays if its multiplier
            // exceeds round-off of the residual, an inactive one enters if its violation exceeds
            // round-off of u (a single threshold mixing both would grow like 1/m_j on fine
            // meshes and let violations through)
            let thr = if active[j] {
                1e-13 * scale_r / pd.measure
            } else {
                opts.c * 1e-13 * scale_u
            };
            next[j] = score > thr;
        }
        if next == active {
            cert.check(opts.tol)?;
            return Ok(VariationalSolution {
                u,
                multiplier: lambda,
                active,
                niter: log.len(),
                log,
                certificate: cert,
                method: Method::ActiveSet,
                iterates,
            });
        }
        if let Some(rep) = history.iter().position(|h| *h == next) {
            let hist = history
                .iter()
                .map(|h| h.iter().filter(|&&a| a).count())
                .collect();
            return fail(
                SolverError::Cycling {
                    iteration: log.len(),
                    repeats: rep,
                    history: hist,
                },
                &log,
            );
        }
        if log.len() >= opts.max_solves {
            let hist = history
                .iter()
                .map(|h| h.iter().filter(|&&a| a).count())
                .collect();
            return fail(
                SolverError::MaxIterations {
                    iterations: log.len(),
                    history: hist,
                },
                &log,
            );
        }
        entered = (0..m).filter(|&j| next[j] && !active[j]).count();
        left = (0..m).filter(|&j| !next[j] && active[j]).count();
        history.push(next.clone());
        active = next;
    }
}
