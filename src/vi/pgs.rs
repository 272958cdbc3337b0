//! Projected Gauss–Seidel on the full (uncondensed) SPD system: a slow but robust fallback for
//! the active-set method, and an independent reference in the tests.
//!
//! Sweep i = 1..n over the non-Dirichlet unknowns: u_i ← (b_i − Σ_{j≠i} M_ij u_j)/M_ii, then,
//! on a constrained unknown, project onto {s(u_i − g_i) ≤ 0}. Converges for SPD M (it is
//! coordinate descent on the energy over a box). Stops when the largest update is below
//! `tol`·‖u‖∞. Between sweeps it polls the caller's cancellation hook
//! ([`PgsOptions::cancel`]), as the active-set method does between linear solves.

use super::FixedValues;
use super::certificate::evaluate;
use super::{
    Cancel, Constraints, IterationLog, IterationStep, Method, QuadraticEnergy, SolveTimings,
    VariationalSolution,
};
use crate::error::SolverError;

/// Options of projected Gauss–Seidel.
#[derive(Debug, Clone)]
pub struct PgsOptions {
    /// Maximum number of sweeps.
    pub max_sweeps: usize,
    /// Relative tolerance on the largest update of a sweep.
    pub tol: f64,
    /// Tolerance of the certificate.
    pub certificate_tol: f64,
    /// The caller's cancellation hook, polled between sweeps (at most every
    /// [`POLL_ENTRIES`] matrix entries of work, so that a hook that costs something, such as
    /// Python's signal check, stays negligible on small systems): when it asks, the solve stops
    /// with [`crate::Error::Interrupted`].
    pub cancel: Option<Cancel>,
}

/// The work, in matrix entries visited, between two polls of [`PgsOptions::cancel`]: a sweep
/// visits every entry of M once, so the hook is polled after every sweep when M has at least
/// this many entries, else every ⌈`POLL_ENTRIES` / nnz(M)⌉ sweeps.
pub const POLL_ENTRIES: usize = 1 << 16;

impl Default for PgsOptions {
    fn default() -> Self {
        PgsOptions {
            max_sweeps: 1_000_000,
            tol: 1e-14,
            certificate_tol: 1e-8,
            cancel: None,
        }
    }
}

/// The full matrix M in compressed sparse rows: the entries of row i are
/// `vals[row_ptr[i]..row_ptr[i + 1]]`, in the columns `cols[..]` of the same range, sorted.
struct Csr {
    row_ptr: Vec<usize>,
    cols: Vec<usize>,
    vals: Vec<f64>,
}

impl Csr {
    /// Sorts the triplets (i, j, v) by (i, j) and sums the repeated entries (in their sorted
    /// order, which `sort_unstable` makes deterministic for a given input).
    fn from_triplets(n: usize, mut t: Vec<(usize, usize, f64)>) -> Csr {
        t.sort_unstable_by_key(|&(i, j, _)| (i, j));
        let mut row_ptr = vec![0usize; n + 1];
        let mut cols = Vec::new();
        let mut vals: Vec<f64> = Vec::new();
        let mut last: Option<(usize, usize)> = None;
        for (i, j, v) in t {
            if last == Some((i, j)) {
                *vals.last_mut().expect("non-empty") += v;
            } else {
                cols.push(j);
                vals.push(v);
                row_ptr[i + 1] += 1;
                last = Some((i, j));
            }
        }
        for i in 0..n {
            row_ptr[i + 1] += row_ptr[i];
        }
        Csr {
            row_ptr,
            cols,
            vals,
        }
    }
}

/// The data of the sweeps: M, b, the Dirichlet values, the barrier g_i of each constrained
/// unknown and the side s (±1) of the constraint s(u_i − g_i) ≤ 0.
struct Sweeper<'a> {
    m: Csr,
    b: &'a [f64],
    dir: &'a FixedValues,
    bound: Vec<Option<f64>>,
    s: f64,
}

impl Sweeper<'_> {
    /// The projection onto {s(v − g_i) ≤ 0} of a value v of unknown i.
    fn project(&self, i: usize, v: f64) -> f64 {
        match self.bound[i] {
            Some(g) if self.s * (v - g) > 0.0 => g,
            _ => v,
        }
    }

    /// The first iterate: the Dirichlet values, zero elsewhere, projected onto the constraints.
    fn initial_guess(&self) -> Vec<f64> {
        (0..self.dir.len())
            .map(|i| self.project(i, self.dir.get(i).unwrap_or(0.0)))
            .collect()
    }

    /// One sweep over the non-Dirichlet unknowns, in place:
    /// u_i ← P_i((b_i − Σ_{j≠i} M_ij u_j) / M_ii), with the newest values of the u_j.
    /// Returns the largest change max_i |Δu_i|.
    fn sweep(&self, u: &mut [f64]) -> f64 {
        let Csr {
            row_ptr,
            cols,
            vals,
        } = &self.m;
        let mut change: f64 = 0.0;
        for i in 0..u.len() {
            if self.dir.is_fixed(i) {
                continue;
            }
            let mut r = self.b[i];
            let mut d = 0.0;
            for q in row_ptr[i]..row_ptr[i + 1] {
                let j = cols[q];
                if j == i {
                    d += vals[q];
                } else {
                    r -= vals[q] * u[j];
                }
            }
            let v = self.project(i, r / d);
            change = change.max((v - u[i]).abs());
            u[i] = v;
        }
        change
    }
}

/// Solves the discrete VI by projected Gauss–Seidel. `niter` of the result counts sweeps.
pub fn solve<P: Sync>(
    system: &dyn QuadraticEnergy,
    cons: &Constraints<P>,
    opts: &PgsOptions,
) -> crate::Result<VariationalSolution> {
    let n = system.n_unknowns();
    let mut bound: Vec<Option<f64>> = vec![None; n];
    for (j, pd) in cons.dofs.iter().enumerate() {
        bound[pd.dof] = Some(cons.barrier[j]);
    }
    let sweeper = Sweeper {
        m: Csr::from_triplets(n, system.matrix_triplets()),
        b: system.load(),
        dir: system.dirichlet(),
        bound,
        s: cons.side.sign(),
    };
    let mut u = sweeper.initial_guess();
    let poll_every = POLL_ENTRIES.div_ceil(sweeper.m.vals.len().max(1));
    let mut sweeps = 0;
    loop {
        sweeps += 1;
        let change = sweeper.sweep(&mut u);
        if sweeps % poll_every == 0 {
            Cancel::check(opts.cancel.as_ref())?;
        }
        // stop when max_i |Δu_i| ≤ tol · ‖u‖∞
        let norm = u
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        if change <= opts.tol * norm {
            break;
        }
        if sweeps >= opts.max_sweeps {
            return Err(SolverError::MaxIterations {
                iterations: sweeps,
                history: vec![],
            }
            .into());
        }
    }
    certified_solution(system, cons, opts, u, sweeps)
}

/// The solution u after `sweeps` sweeps, with its active set {i : u_i = g_i}, its multiplier
/// and its certificate (an error if the certificate fails).
fn certified_solution<P: Sync>(
    system: &dyn QuadraticEnergy,
    cons: &Constraints<P>,
    opts: &PgsOptions,
    u: Vec<f64>,
    sweeps: usize,
) -> crate::Result<VariationalSolution> {
    let active: Vec<bool> = cons
        .dofs
        .iter()
        .enumerate()
        .map(|(j, pd)| u[pd.dof] == cons.barrier[j])
        .collect();
    let ev = evaluate(system, Some(cons), &u, &active)?;
    let (cert, lambda) = (ev.certificate, ev.multiplier);
    cert.check(opts.certificate_tol)?;
    Ok(VariationalSolution {
        u,
        multiplier: lambda,
        active: active.clone(),
        niter: sweeps,
        log: vec![IterationLog {
            step: IterationStep {
                solve: sweeps,
                active: active.iter().filter(|&&a| a).count(),
                entered: 0,
                left: 0,
                violation: cert.max_violation,
                residual: Some(cert.balance_residual),
            },
            timings: SolveTimings::default(),
            look_ahead: None,
        }],
        certificate: cert,
        method: Method::ProjectedGaussSeidel,
        iterates: vec![],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vi::dense::cycling_system;
    use crate::vi::exhaustive;

    /// Projected Gauss–Seidel solves the system on which the active-set method cycles, to the
    /// enumerated solution, with a passing certificate.
    #[test]
    fn solves_the_cycling_system() {
        let (mut sys, cons) = cycling_system();
        let sol = solve(&sys, &cons, &PgsOptions::default()).unwrap();
        assert_eq!(sol.method, Method::ProjectedGaussSeidel);
        sol.certificate.check(1e-10).unwrap();
        let (reference, active) = exhaustive::solve(&mut sys, &cons).unwrap();
        assert_eq!(sol.active, active);
        for (a, b) in sol.u.iter().zip(&reference) {
            assert!((a - b).abs() < 1e-10, "{a} vs {b}");
        }
    }

    #[test]
    fn the_sweep_cap_is_a_typed_error() {
        let (sys, cons) = cycling_system();
        let o = PgsOptions {
            max_sweeps: 1,
            ..Default::default()
        };
        assert!(matches!(
            solve(&sys, &cons, &o),
            Err(crate::Error::Solver(SolverError::MaxIterations { .. }))
        ));
    }

    /// A hook that asks to stop on its third poll ends the sweeps with `Interrupted` after
    /// exactly three polls (the cycling system is small: one poll per `POLL_ENTRIES / nnz`
    /// sweeps), long before the sweeps would converge; a hook that never asks changes nothing.
    #[test]
    fn the_cancel_hook_is_polled_between_sweeps() {
        use std::sync::Arc;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let (sys, cons) = cycling_system();
        let polls = Arc::new(AtomicUsize::new(0));
        let counter = Arc::clone(&polls);
        // a negative tolerance: the sweeps never stop by themselves
        let o = PgsOptions {
            tol: -1.0,
            max_sweeps: usize::MAX,
            cancel: Some(Cancel::new(move || {
                counter.fetch_add(1, Ordering::SeqCst) + 1 >= 3
            })),
            ..Default::default()
        };
        assert!(matches!(
            solve(&sys, &cons, &o),
            Err(crate::Error::Interrupted)
        ));
        assert_eq!(polls.load(Ordering::SeqCst), 3);

        let never = PgsOptions {
            cancel: Some(Cancel::new(|| false)),
            ..Default::default()
        };
        let a = solve(&sys, &cons, &never).unwrap();
        let b = solve(&sys, &cons, &PgsOptions::default()).unwrap();
        assert_eq!(a.u, b.u);
        assert_eq!(a.niter, b.niter);
    }
}
