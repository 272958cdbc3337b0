//! Solvers: [`linear`] (sparse Cholesky with symbolic reuse), [`active_set`] (the monotony
//! algorithm with its certificate), [`pgs`] (projected Gauss–Seidel fallback), and
//! [`solve_problem`], the one entry point that turns a scheme and a problem into a certified
//! [`Solution`].

pub mod active_set;
pub mod linear;
pub mod pgs;
pub mod warm_start;

use crate::assembly::{DiscreteSystem, SystemOptions};
use crate::problem::{ConstraintKind, Problem, check_finite};
use crate::scheme::{GradientDiscretisation, PointDof};
pub use active_set::{
    ActiveSetOptions, Certificate, Constraints, IterationLog, Method, VariationalSolution,
};
use std::time::Instant;
pub use warm_start::{WarmStart, WarmStartReport};

/// Wall-clock timings of a solve, in seconds.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Timings {
    /// Data evaluation, local matrices, pattern and symbolic factorisation.
    pub setup: f64,
    /// Of which the symbolic factorisation.
    pub symbolic: f64,
    /// The coarse solves of a warm start (0 for a cold start).
    pub warm_start: f64,
    /// Condensation and scatter, all iterations.
    pub assemble: f64,
    /// Numeric factorisations, all iterations.
    pub factor: f64,
    /// Triangular solves and interior recovery, all iterations.
    pub solve: f64,
    /// Everything.
    pub total: f64,
}

/// A certified discrete solution and what it took.
pub struct Solution<'a> {
    /// The assembled system (gives access to the scheme and the mesh).
    pub system: DiscreteSystem<'a>,
    /// The barrier, if any.
    pub constraints: Option<Constraints>,
    /// The solver outcome (u, multipliers, active set, NITER, log, certificate).
    pub result: VariationalSolution,
    /// Timings.
    pub timings: Timings,
    /// What the warm start did (`None`: cold start, or no barrier).
    pub warm_start: Option<WarmStartReport>,
}

impl Solution<'_> {
    /// The full unknown vector.
    pub fn u(&self) -> &[f64] {
        &self.result.u
    }
    /// Number of linear solves.
    pub fn niter(&self) -> usize {
        self.result.niter
    }
    /// The multiplier on every unknown (zero off the constrained unknowns).
    pub fn multiplier_field(&self) -> Vec<f64> {
        let mut l = vec![0.0; self.result.u.len()];
        if let Some(c) = &self.constraints {
            for (j, pd) in c.dofs.iter().enumerate() {
                l[pd.dof] = self.result.multiplier[j];
            }
        }
        l
    }
    /// 1 on active unknowns, 0 elsewhere.
    pub fn active_field(&self) -> Vec<f64> {
        let mut a = vec![0.0; self.result.u.len()];
        if let Some(c) = &self.constraints {
            for (j, pd) in c.dofs.iter().enumerate() {
                if self.result.active[j] {
                    a[pd.dof] = 1.0;
                }
            }
        }
        a
    }
}

/// Builds the barrier of `problem` on the unknowns of the system, checking the data and the
/// non-emptiness of the discrete convex set.
pub fn build_constraints(
    system: &DiscreteSystem,
    problem: &Problem,
) -> crate::Result<Option<Constraints>> {
    let Some(c) = &problem.constraint else {
        return Ok(None);
    };
    let scheme = system.scheme();
    let mesh = scheme.mesh();
    let s = c.side.sign();
    let dir = system.dirichlet();
    let candidates = match c.kind {
        ConstraintKind::Obstacle => scheme.obstacle_dofs(),
        ConstraintKind::Signorini => {
            if system.signorini_dofs().is_empty() {
                return Err(crate::Error::InvalidData(
                    "a Signorini barrier is given but no boundary edge is of Signorini type".into(),
                ));
            }
            system.signorini_dofs().to_vec()
        }
    };
    // barrier versus Dirichlet data: the convex set must not be empty. Obstacle: every
    // Dirichlet trace unknown (u_D must satisfy the barrier on ∂Ω); Signorini: the Dirichlet
    // unknowns that also carry the trace on Γ3.
    let mut tr = Vec::new();
    let mut checks: Vec<PointDof> = Vec::new();
    match c.kind {
        ConstraintKind::Obstacle => {
            for &e in mesh.boundary_edges() {
                scheme.edge_trace_dofs(e, &mut tr);
                checks.extend(tr.iter().filter(|t| dir[t.dof].is_some()));
            }
        }
        ConstraintKind::Signorini => {
            checks.extend(candidates.iter().filter(|t| dir[t.dof].is_some()));
        }
    }
    for t in &checks {
        let v = dir[t.dof].unwrap_or(0.0);
        let g = check_finite(
            (c.barrier)(t.point),
            &format!("the barrier at {:?}", t.point),
        )?;
        if s * (v - g) > 1e-12 * (1.0 + g.abs()) {
            return Err(crate::Error::Infeasible(format!(
                "the Dirichlet value {v} at {:?} is {} the barrier {g}: the discrete convex set is empty",
                t.point,
                if s > 0.0 { "above" } else { "below" }
            )));
        }
    }
    let mut dofs = Vec::new();
    let mut barrier = Vec::new();
    for pd in candidates {
        if dir[pd.dof].is_some() {
            continue;
        }
        let g = check_finite(
            (c.barrier)(pd.point),
            &format!("the barrier at {:?}", pd.point),
        )?;
        dofs.push(pd);
        barrier.push(g);
    }
    Ok(Some(Constraints {
        dofs,
        barrier,
        side: c.side,
    }))
}

/// Assembles and solves `problem` with `scheme`: a linear solve if there is no barrier, the
/// active-set method otherwise, started as `opts.warm_start` says. The result is certified
/// (see [`Certificate`]).
pub fn solve_problem<'a>(
    scheme: &'a dyn GradientDiscretisation,
    problem: &Problem,
    opts: &ActiveSetOptions,
) -> crate::Result<Solution<'a>> {
    solve_problem_with(scheme, problem, SystemOptions::default(), opts)
}

/// As [`solve_problem`], with the options of the linear algebra (fill-reducing ordering,
/// threads of the factorisation).
pub fn solve_problem_with<'a>(
    scheme: &'a dyn GradientDiscretisation,
    problem: &Problem,
    system_options: SystemOptions,
    opts: &ActiveSetOptions,
) -> crate::Result<Solution<'a>> {
    let t0 = Instant::now();
    let system = DiscreteSystem::with_options(scheme, problem, system_options)?;
    let constraints = build_constraints(&system, problem)?;
    let mut warm = None;
    let result = match &constraints {
        Some(c) if opts.warm_start == WarmStart::Nested && opts.initial_active.is_none() => {
            let points: Vec<_> = c.dofs.iter().map(|d| d.point).collect();
            let t = Instant::now();
            let (initial, report) = match warm_start::predict(scheme.mesh(), problem, &points) {
                Ok((a, r)) => (Some(a), r),
                Err(reason) => (
                    None,
                    WarmStartReport {
                        seconds: t.elapsed().as_secs_f64(),
                        skipped: Some(reason),
                        ..Default::default()
                    },
                ),
            };
            warm = Some(report);
            let o = ActiveSetOptions {
                initial_active: Some(initial.unwrap_or_else(|| vec![false; points.len()])),
                ..opts.clone()
            };
            active_set::solve(&system, c, &o)?
        }
        Some(c) => active_set::solve(&system, c, opts)?,
        None => {
            let fixed = vec![None; system.n_unknowns()];
            let (u, t) = system.solve(&fixed)?;
            let (cert, _) = active_set::certificate(&system, None, &u, &[]);
            cert.check(opts.tol)?;
            VariationalSolution {
                u,
                multiplier: vec![],
                active: vec![],
                niter: 1,
                log: vec![IterationLog {
                    solve: 1,
                    active: 0,
                    entered: 0,
                    left: 0,
                    violation: 0.0,
                    residual: cert.balance_residual,
                    timings: t,
                }],
                certificate: cert,
                method: Method::Linear,
                iterates: vec![],
            }
        }
    };
    let mut timings = Timings {
        setup: system.setup_seconds,
        symbolic: system.symbolic_seconds,
        warm_start: warm.as_ref().map_or(0.0, |w| w.seconds),
        ..Default::default()
    };
    for l in &result.log {
        timings.assemble += l.timings.assemble;
        timings.factor += l.timings.factor;
        timings.solve += l.timings.solve;
    }
    timings.total = t0.elapsed().as_secs_f64();
    Ok(Solution {
        system,
        constraints,
        result,
        timings,
        warm_start: warm,
    })
}
