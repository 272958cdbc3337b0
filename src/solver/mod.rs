//! The solve driver: from a scheme and a problem to a certified [`Solution`].
//!
//! It sits above assembly and the algebraic algorithms ([`crate::vi`]) and decides what they
//! cannot: how the active-set iteration starts ([`WarmStart`]: cold, or from a nested coarse
//! prediction, [`warm_start`]), whether it looks ahead (with the nested start, the fast path:
//! each next active set is proposed after local solves on a patch around its changes,
//! [`crate::vi::look_ahead`], which saves global solves; the paper's cold start does not, so
//! its NITER stays the paper's algorithm), and what happens when it stalls (projected Gauss–Seidel if
//! [`SolveOptions::fallback`] is set, an error otherwise).
//!
//! ```text
//! solve_problem(scheme, problem, opts)
//!   = [ DiscreteSystem::new (symbolic ∥ values) → constraints::build → well_posed::analyse ]
//!       ∥ [ nested warm start: coarse levels and their solves (fine mesh and problem only) ]
//!     → warm start's prediction on the fine unknowns (map down, first guess)?
//!     → vi::active_set::run (→ vi::pgs::solve on a stall, if asked) → Solution
//! ```
//! The two branches of `∥` are a `rayon::join`: one after the other on one thread, side by
//! side on more, the coarse solves in a pool of their own ([`coarse_threads`]) so that
//! neither branch steals the other's work (measured in `replication/measurements/solver.md`).
//! The coarse solves read neither the fine system nor its barrier, so they compute the same
//! whatever the order; when the fine setup fails, its error is returned and the coarse solves
//! stop at their next check.
//! [`solve_with_symbolic`] reuses the symbolic system of an earlier solve on the same scheme.

pub mod coarse_mesh;
pub mod constraints;
pub mod magnitude;
pub mod start;
#[cfg(test)]
mod tests_3d;
pub mod warm_start;
pub mod well_posed;

use crate::assembly::{DiscreteSystem, SolveState, SymbolicSystem, SystemOptions};
use crate::budget::{try_copy, try_filled};
use crate::mesh::{PolyMesh, SolveMesh};
use crate::problem::Problem;
use crate::scheme::GradientDiscretisation;
use crate::vi::active_set::{self, Outcome, Predicted};
pub use crate::vi::{ActiveSetOptions, Cancel, Certificate, IterationLog, IterationStep, Method};
use crate::vi::{VariationalSolution, pgs};
use constraints::Constraints;
pub use start::SolverMesh;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
use std::time::Instant;
pub use warm_start::{WarmStart, WarmStartReport};
pub use well_posed::MarginalLoad;

/// Options of [`solve_problem`].
#[derive(Debug, Clone, Default)]
pub struct SolveOptions {
    /// The active-set algorithm (c, iteration cap, certificate tolerance, initial active set,
    /// progress).
    pub active_set: ActiveSetOptions,
    /// How the iteration starts when no `active_set.initial_active` is given (default: the
    /// nested coarse prediction; [`SolveOptions::paper`] for the paper's cold start).
    pub warm_start: WarmStart,
    /// On cycling or the iteration cap, fall back to projected Gauss–Seidel instead of failing.
    pub fallback: bool,
    /// The linear algebra (fill-reducing ordering, threads of the factorisation).
    pub system: SystemOptions,
}

impl SolveOptions {
    /// The paper's algorithm: the monotony iteration from A₀ = ∅ ([`WarmStart::Cold`]), whose
    /// NITER the paper's tables report. The replication uses it.
    pub fn paper() -> Self {
        SolveOptions {
            warm_start: WarmStart::Cold,
            ..Default::default()
        }
    }
}

/// Wall-clock timings of a solve, in seconds.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Timings {
    /// Data evaluation, local matrices, pattern and symbolic factorisation.
    pub setup: f64,
    /// Of which the symbolic factorisation.
    pub symbolic: f64,
    /// The warm start: its coarse solves and its prediction (0 for a cold start). The coarse
    /// solves run beside the setup, so with more than one thread `setup + warm_start` can
    /// exceed the wall-clock time they took together.
    pub warm_start: f64,
    /// Condensation and scatter, all iterations.
    pub assemble: f64,
    /// Numeric factorisations, all iterations.
    pub factor: f64,
    /// Triangular solves and interior recovery, all iterations.
    pub solve: f64,
    /// Look-aheads of the active set, all iterations.
    pub look_ahead: f64,
    /// Everything.
    pub total: f64,
}

/// A certified discrete solution and what it took.
pub struct Solution<'a, M = PolyMesh, const D: usize = 2>
where
    M: SolveMesh<D> + ?Sized,
{
    /// The assembled system (gives access to the scheme, the mesh and the symbolic system).
    pub system: DiscreteSystem<'a, M, D>,
    /// The barrier, if any.
    pub constraints: Option<Constraints>,
    /// The solver outcome (u, multipliers, active set, NITER, log, certificate).
    pub result: VariationalSolution,
    /// Timings.
    pub timings: Timings,
    /// What the warm start did (`None`: cold start, or no barrier).
    pub warm_start: Option<WarmStartReport>,
    /// The number of unknowns of the cell system the solves took, and how many of them are
    /// skeleton unknowns ([`crate::assembly::two_point`]; `None`: they solved the skeleton
    /// system).
    pub cell_system: Option<(usize, usize)>,
    /// Stored values of the Cholesky factors the direct solves used: the skeleton system's
    /// (built by the setup, or by the first solve that needed it when the setup deferred it)
    /// and the cell system's; 0 for iterative solves.
    pub factor_len: usize,
    /// The parts of the mesh without Dirichlet boundary whose well-posedness hangs on the
    /// sign of a small total load (see [`well_posed`]): a warning, empty in the usual case.
    pub marginal_load: Vec<well_posed::MarginalLoad>,
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> Solution<'_, M, D> {
    /// The full unknown vector.
    pub fn u(&self) -> &[f64] {
        &self.result.u
    }
    /// Number of linear solves.
    pub fn niter(&self) -> usize {
        self.result.niter
    }
    /// The multiplier on every unknown (zero off the constrained unknowns), or
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if its vector cannot be allocated.
    pub fn multiplier_field(&self) -> crate::Result<Vec<f64>> {
        self.constrained_field("the multiplier field", |j| self.result.multiplier[j])
    }
    /// 1 on active unknowns, 0 elsewhere, or
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if its vector cannot be allocated.
    pub fn active_field(&self) -> crate::Result<Vec<f64>> {
        self.constrained_field("the active-set field", |j| {
            if self.result.active[j] { 1.0 } else { 0.0 }
        })
    }
    /// A vector over every unknown, `value(j)` on the j-th constrained unknown and 0 elsewhere,
    /// allocated fallibly (its length is the number of unknowns).
    fn constrained_field(
        &self,
        what: &str,
        value: impl Fn(usize) -> f64,
    ) -> crate::Result<Vec<f64>> {
        let mut a = try_filled(self.result.u.len(), 0.0, what)?;
        if let Some(c) = &self.constraints {
            for (j, pd) in c.dofs.iter().enumerate() {
                a[pd.dof] = value(j);
            }
        }
        Ok(a)
    }
}

/// Assembles and solves `problem` with `scheme`: a linear solve if there is no barrier, the
/// active-set method otherwise, started as `opts.warm_start` says. The result is certified
/// (see [`Certificate`]).
pub fn solve_problem<'a, M: SolverMesh<D> + ?Sized, const D: usize>(
    scheme: &'a dyn GradientDiscretisation<M, D>,
    problem: &Problem<D>,
    opts: &SolveOptions,
) -> crate::Result<Solution<'a, M, D>> {
    let t0 = Instant::now();
    let build = || DiscreteSystem::new(scheme, problem, opts.system);
    solve_built(scheme, problem, opts, opts.system.budget, build, t0)
}

/// As [`solve_problem`], on a symbolic system built before for the same scheme (its
/// `opts.system` is then ignored): only the values are computed for `problem`.
pub fn solve_with_symbolic<'a, M: SolverMesh<D> + ?Sized, const D: usize>(
    symbolic: Arc<SymbolicSystem<'a, M, D>>,
    problem: &Problem<D>,
    opts: &SolveOptions,
) -> crate::Result<Solution<'a, M, D>> {
    let t0 = Instant::now();
    let (scheme, budget) = (symbolic.scheme(), symbolic.options.budget);
    let build = move || DiscreteSystem::with_symbolic(symbolic, problem);
    solve_built(scheme, problem, opts, budget, build, t0)
}

/// A discrete system with its barrier and the analysis of its well-posedness.
struct Prepared<'a, M: SolveMesh<D> + ?Sized, const D: usize> {
    system: DiscreteSystem<'a, M, D>,
    constraints: Option<Constraints>,
    analysis: well_posed::Analysis,
}

/// The barrier of `problem` on `system` and the analysis of its well-posedness.
fn prepare<'a, M: SolveMesh<D> + ?Sized, const D: usize>(
    system: DiscreteSystem<'a, M, D>,
    problem: &Problem<D>,
) -> crate::Result<Prepared<'a, M, D>> {
    let constraints = constraints::build(&system, problem)?;
    let analysis = well_posed::analyse(&system, constraints.as_ref())?;
    Ok(Prepared {
        system,
        constraints,
        analysis,
    })
}

/// The coarse solves of a nested warm start (`None`: the mesh type has none) and the seconds
/// they took.
type CoarseBranch<C> = (Option<Result<C, String>>, f64);

/// Solves `problem` on the system `build` makes for `scheme` (budget `budget`). With the
/// nested warm start, its coarse solves run beside the fine setup (the system, its barrier and
/// its well-posedness): they need the fine mesh and the problem only
/// ([`warm_start::CoarseSolves`]). When the fine setup fails, its error is returned and the
/// coarse solves are stopped at their next check.
fn solve_built<'a, M: SolverMesh<D> + ?Sized, const D: usize>(
    scheme: &'a dyn GradientDiscretisation<M, D>,
    problem: &Problem<D>,
    opts: &SolveOptions,
    budget: crate::budget::MemoryBudget,
    build: impl FnOnce() -> crate::Result<DiscreteSystem<'a, M, D>> + Send,
    t0: Instant,
) -> crate::Result<Solution<'a, M, D>> {
    let nested = opts.warm_start == WarmStart::Nested
        && opts.active_set.initial_active.is_none()
        && problem.constraint.is_some();
    if !nested {
        return solve_prepared(prepare(build()?, problem)?, problem, opts, t0, None);
    }
    // the coarse solves poll the caller's hook, and stop once the fine setup has failed
    let failed = Arc::new(AtomicBool::new(false));
    let cancel = {
        let (failed, hook) = (Arc::clone(&failed), opts.active_set.cancel.clone());
        Cancel::new(move || failed.load(Relaxed) || hook.as_ref().is_some_and(Cancel::requested))
    };
    let (fine, coarse) = rayon::join(
        || {
            let fine = build().and_then(|system| prepare(system, problem));
            if fine.is_err() {
                failed.store(true, Relaxed);
            }
            fine
        },
        || {
            let t = Instant::now();
            let unknowns = M::warm_start_unknowns(scheme);
            let run = || {
                scheme
                    .mesh()
                    .coarse_solves(unknowns, problem, budget, Some(&cancel))
            };
            let c = match coarse_pool() {
                // this worker waits blocked, not stealing the fine setup's work; if no thread
                // can be made, the branch runs here
                Some(pool) => std::thread::scope(|s| {
                    match std::thread::Builder::new().spawn_scoped(s, || pool.install(run)) {
                        Ok(h) => h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)),
                        Err(_) => run(),
                    }
                }),
                None => run(),
            };
            (c, t.elapsed().as_secs_f64())
        },
    );
    solve_prepared(fine?, problem, opts, t0, Some(coarse))
}

/// The threads of the coarse branch's own pool when the solve runs on `threads` threads
/// (see `coarse_pool`): a quarter of them, at least one. The fine setup keeps the others but
/// the one that waits for the pool. Only two threads (one each) were measured; the quarter
/// is a guess for larger machines, where the fine setup's parallel loops have more to gain.
pub fn coarse_threads(threads: usize) -> usize {
    (threads / 4).max(1)
}

/// The coarse branch's own pool ([`coarse_threads`]) when the solve has more than one thread
/// (`None`: one thread, or the pool could not be made, and the branch runs where the join put
/// it).
///
/// Why: in a `rayon::join` the coarse branch's parallel loops split into jobs that the fine
/// setup's thread steals, and the coarse branch, waiting for a stolen job, steals back a long
/// piece of the fine setup; on two threads HMM's coarse branch then ended with the fine setup
/// or after it instead of in half its time (`replication/measurements/solver.md`). In a pool of
/// its own, with the join's worker blocked on it (not stealing), the coarse solves keep their
/// threads and the fine setup the others until the coarse solves end; the computation is the
/// same (the solves are deterministic in the thread count, `tests/determinism.rs`).
fn coarse_pool() -> Option<rayon::ThreadPool> {
    let threads = rayon::current_num_threads();
    if threads < 2 {
        return None;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(coarse_threads(threads))
        .thread_name(|i| format!("gradvi-coarse-{i}"))
        .build()
        .ok()
}

/// Graph layers of the look-ahead's patches on 3D meshes (see [`look_ahead_options`]).
pub const LOOK_AHEAD_LAYERS_3D: usize = 3;

/// The look-ahead of the fast path ([`crate::vi::look_ahead`]) on a mesh of dimension `d`: the
/// default options in 2D; in 3D patches of [`LOOK_AHEAD_LAYERS_3D`] layers. A layer of a 3D
/// mesh graph holds many more unknowns than a planar one (a shell rather than a band around
/// the changed unknowns), so the default 6 layers give 3D patches whose local factorisations
/// cost a sizeable part of a global solve, or exceed the largest patch and propose nothing;
/// 3 layers proposed as well or better on the 3D benchmarks
/// (`replication/measurements/solver3d.md`).
pub fn look_ahead_options(d: usize) -> crate::vi::look_ahead::LookAheadOptions {
    let default = crate::vi::look_ahead::LookAheadOptions::default();
    if d == 3 {
        crate::vi::look_ahead::LookAheadOptions {
            layers: LOOK_AHEAD_LAYERS_3D,
            ..default
        }
    } else {
        default
    }
}

/// What [`warm_start`] returns: the predicted initial active set and the report.
type Start = (Option<Vec<bool>>, Option<WarmStartReport>);

/// The initial active set that the warm start predicts from the coarse solves `coarse`
/// (None: cold), and its report (None: no warm start was asked for, `coarse` is `None`); an
/// error if the mesh type has no nested start.
fn warm_start<M: SolverMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    state: &mut SolveState,
    problem: &Problem<D>,
    cons: &Constraints,
    coarse: Option<CoarseBranch<M::Coarse>>,
) -> crate::Result<Start> {
    let Some((coarse, seconds)) = coarse else {
        return Ok((None, None));
    };
    let t = Instant::now();
    let coarse = coarse.ok_or_else(|| start::nested_start_unavailable(D))?;
    let prediction = coarse.and_then(|c| M::nested_prediction(c, system.scheme(), problem, cons));
    Ok(match prediction {
        Ok(p) => {
            system.set_initial_guess(state, p.guess);
            (Some(p.active), Some(p.report))
        }
        Err(reason) => (
            None,
            Some(WarmStartReport {
                seconds: seconds + t.elapsed().as_secs_f64(),
                skipped: Some(reason),
                ..Default::default()
            }),
        ),
    })
}

/// What the active-set method on a system gives: a certified solution, or the prediction
/// that [`ActiveSetOptions::predict_only`] asks for.
enum Settled {
    Solved(VariationalSolution),
    Predicted(Predicted),
}

/// The active-set method on `system` (its solves through `state`), with the fallback of
/// `opts`.
fn solve_constrained<M: SolverMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    state: &mut SolveState,
    cons: &Constraints,
    opts: &SolveOptions,
    initial: Option<Vec<bool>>,
) -> crate::Result<Settled> {
    let mut o = match initial {
        Some(a) => ActiveSetOptions {
            initial_active: Some(a),
            ..opts.active_set.clone()
        },
        None => opts.active_set.clone(),
    };
    // the fast path looks ahead; the paper's cold start keeps the paper's algorithm
    if opts.warm_start == WarmStart::Nested && o.look_ahead.is_none() {
        o.look_ahead = Some(look_ahead_options(D));
    }
    match active_set::run(&mut system.with_state(state), cons, &o)? {
        Outcome::Solved(s) => Ok(Settled::Solved(s)),
        Outcome::Predicted(p) => Ok(Settled::Predicted(p)),
        Outcome::Stalled(stall) if opts.fallback => {
            let q = system.with_state(state);
            let po = pgs::PgsOptions {
                cancel: o.cancel.clone(),
                ..Default::default()
            };
            let mut sol = pgs::solve(&q, cons, &po)?;
            sol.niter += stall.log.len();
            let mut log = stall.log;
            log.extend(sol.log);
            sol.log = log;
            Ok(Settled::Solved(sol))
        }
        Outcome::Stalled(stall) => Err(stall.error.into()),
    }
}

/// The initial active set of the fine iteration: `initial` (the warm start's, else the one
/// `opts` gives, else none) with the barrier of the `floating` parts (those without Dirichlet
/// unknowns) active, or the first solve would be singular (see [`well_posed`]).
fn with_floating(
    initial: Option<Vec<bool>>,
    opts: &SolveOptions,
    cons: &Constraints,
    floating: &[usize],
) -> crate::Result<Option<Vec<bool>>> {
    if floating.is_empty() {
        return Ok(initial);
    }
    let what = "the initial active set";
    let mut a = match (initial, &opts.active_set.initial_active) {
        (Some(a), _) => a,
        (None, Some(given)) => try_copy(given, what)?,
        (None, None) => try_filled(cons.dofs.len(), false, what)?,
    };
    for &j in floating {
        a[j] = true;
    }
    Ok(Some(a))
}

/// The coarse solves' path ([`warm_start`]): the active-set method on the prepared system
/// `prepared` from `initial`, stopped before a solve that is likely the last when `opts` asks
/// for it ([`ActiveSetOptions::predict_only`]): the active set on the barrier's unknowns, the
/// iterate and the number of linear solves. Uncertified when it stopped early; a prediction
/// only.
fn predict_prepared<M: SolverMesh<D> + ?Sized, const D: usize>(
    prepared: &Prepared<'_, M, D>,
    opts: &SolveOptions,
    initial: Option<Vec<bool>>,
) -> crate::Result<(Vec<bool>, Vec<f64>, usize)> {
    let cons = prepared
        .constraints
        .as_ref()
        .ok_or_else(|| crate::Error::InvalidData("the problem has no barrier".into()))?;
    let initial = with_floating(initial, opts, cons, &prepared.analysis.floating)?;
    let mut state = SolveState::default();
    Ok(
        match solve_constrained(&prepared.system, &mut state, cons, opts, initial)? {
            Settled::Solved(s) => (s.active, s.u, s.niter),
            Settled::Predicted(p) => (p.active, p.u, p.log.len()),
        },
    )
}

/// Solves `problem` on the prepared system `prepared`, warm-started from the coarse solves
/// `coarse` if given.
fn solve_prepared<'a, M: SolverMesh<D> + ?Sized, const D: usize>(
    prepared: Prepared<'a, M, D>,
    problem: &Problem<D>,
    opts: &SolveOptions,
    t0: Instant,
    coarse: Option<CoarseBranch<M::Coarse>>,
) -> crate::Result<Solution<'a, M, D>> {
    let Prepared {
        system,
        constraints,
        analysis: well_posed::Analysis { floating, marginal },
    } = prepared;
    // what the solves of this system carry from one to the next: fresh for every problem
    let mut state = SolveState::default();
    let mut warm = None;
    let result = match &constraints {
        Some(c) => {
            let beside = coarse.is_some();
            let (initial, report) = warm_start(&system, &mut state, problem, c, coarse)?;
            warm = report;
            if beside {
                // the coarse solves ran beside the setup, mostly on other threads, whose
                // allocator arenas keep the pages of their freed arrays: hand them back before
                // the fine solves allocate theirs (`crate::heap`)
                crate::heap::release_free_pages();
            }
            // a warm start cut short by the hook is skipped: stop before the first fine solve
            Cancel::check(opts.active_set.cancel.as_ref())?;
            let initial = with_floating(initial, opts, c, &floating)?;
            match solve_constrained(&system, &mut state, c, opts, initial)? {
                Settled::Solved(s) => s,
                Settled::Predicted(_) => {
                    return Err(crate::Error::InvalidData(
                        "predict_only asks for a prediction, not a solution".into(),
                    ));
                }
            }
        }
        None => {
            crate::vi::solve_unconstrained(&mut system.with_state(&mut state), opts.active_set.tol)?
        }
    };
    let cell_system = state.cell_system_size().zip(state.cell_system_skeleton());
    let factor_len = system.factor_len() + state.factor_len();
    drop(state);
    let mut result = result;
    let scale = magnitude::data_scale(&system, problem, constraints.as_ref());
    result.certificate.data_magnitude = magnitude::data_magnitude(&result.u, scale);
    result.certificate.check(opts.active_set.tol)?;
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
        timings.look_ahead += l.look_ahead.map_or(0.0, |r| r.seconds);
    }
    timings.total = t0.elapsed().as_secs_f64();
    Ok(Solution {
        system,
        constraints,
        result,
        timings,
        warm_start: warm,
        cell_system,
        factor_len,
        marginal_load: marginal,
    })
}
