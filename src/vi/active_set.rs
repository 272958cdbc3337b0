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
//! **Screening** ([`ActiveSetOptions::screening`], the default). Step 2 needs u^k only to the
//! accuracy that decides the signs of the scores, not to round-off; an iterative linear solver
//! may then stop early ([`QuadraticEnergy::screen_with_fixed`]). Before step 3 stops or
//! declares a cycle on such an inexact iterate, the solve is continued to full accuracy
//! ([`QuadraticEnergy::refine`], which reuses its preconditioner) and step 2 is redone on the
//! exact iterate; so the stopping rule, the cycle test and the certificate always see exact
//! solves, and the answer is the one without screening. A repeated active set after inexact
//! solves need not be a cycle (the older set may have come from an inexact iterate, whose
//! successor an exact one need not repeat): the iteration then goes on without screening and
//! the cycle test restarts from the current set. The continuation belongs to the same
//! active set and is not counted as another solve. Step 2 reads an inexact iterate through
//! [`super::certificate::evaluate_screened`]: its residual on the constrained unknowns only
//! (the multipliers, to the bit those of the whole residual; on HMM the other rows are most of
//! the system), with the round-off threshold of the multipliers scaled by those rows; its log
//! line has no balance residual ([`super::IterationStep::residual`] is `None`). An inexact
//! iterate may also be *partial* ([`SolveTimings::partial`]: HMM's faces eliminated in the
//! two-point form are not recovered after a screened solve of the cell system): its
//! constrained unknowns are filled if it lacks them, its multipliers are computed from the
//! unknowns it has ([`QuadraticEnergy::partial_residual_at`], equal to the whole residual's up
//! to rounding), the look-ahead recovers the values it freezes around its patch
//! ([`QuadraticEnergy::partial_values`]), and a kept iterate or a prediction is completed
//! ([`QuadraticEnergy::complete`]). The exact iterate of the stopping rule and the cycle test
//! is complete and evaluated whole, and so is every certificate. If screening misjudges an unknown, a later iterate corrects it, at worst at
//! the cost of more solves; the iterative solver's screening tolerances are chosen so that
//! on the benchmarks this costs no solve (the few unknowns misjudged on some of them are
//! taken back within the same number of solves: [`crate::assembly::SCREENING_RTOL`]).
//! A solve that is likely the last (the change of the active set before it at most
//! [`LAST_CHANGE_RATIO`] of the change before that) is not screened: it would
//! be refined anyway, and screening it would only add an evaluation of the inexact iterate and
//! a restart of the conjugate gradients (on ex9 at 1M unknowns, one Krylov iteration and
//! 0.1–0.2 s of the third fine solve; `replication/measurements/solver.md`).
//!
//! Every returned solution carries a [`super::Certificate`]; above tolerance the solve is an
//! error. Cycling and the iteration cap end the iteration with [`Outcome::Stalled`]; the solve
//! driver decides whether to fall back to projected Gauss–Seidel.

use super::certificate::{Evaluation, evaluate, evaluate_screened};
use super::look_ahead::{LookAheadOptions, LookAheadReport, Thresholds, look_ahead};
use super::{
    Constraints, IterationLog, IterationStep, Method, QuadraticEnergy, SolveTimings,
    VariationalSolution,
};
use crate::budget::try_vec;
use crate::error::SolverError;
use rayon::prelude::*;
use std::sync::Arc;

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
    /// Initial active set, indexed like [`Constraints::dofs`] (`None`: A₀ = ∅, the paper's
    /// algorithm).
    pub initial_active: Option<Vec<bool>>,
    /// Keep every iterate u^k in [`VariationalSolution::iterates`] (for studies of the
    /// iteration; costs one vector per solve).
    pub keep_iterates: bool,
    /// Called with each line of the iteration log as soon as it is known (progress of long
    /// runs; `gradvi solve` prints it to stderr).
    pub progress: Option<fn(&IterationLog)>,
    /// Screen the active sets with inexact solves (see the module docs): each solve only
    /// accurate enough to decide the next active set
    /// ([`QuadraticEnergy::screen_with_fixed`]), the last one refined. Changes nothing with a
    /// direct solver, which is always exact.
    pub screening: bool,
    /// Propose each next active set after a look-ahead on a patch around its changes
    /// ([`super::look_ahead`]; `None`, the default: the paper's algorithm).
    pub look_ahead: Option<LookAheadOptions>,
    /// The caller's cancellation hook, polled after every linear solve that is not the last
    /// (`None`, the default: never cancelled).
    pub cancel: Option<Cancel>,
    /// Stop before a solve that is likely the last ([`LAST_CHANGE_RATIO`]) and return the active
    /// set it would be made with and the last iterate, uncertified ([`Outcome::Predicted`]).
    /// For solves whose answer only predicts another's (the coarse levels of a warm start):
    /// when that solve would only have confirmed the set, the set is the one it would have
    /// returned. `false`, the default: every answer is certified.
    pub predict_only: bool,
}

/// A cancellation hook owned by the caller: a function polled between linear solves; when it
/// returns true the solve stops with [`crate::Error::Interrupted`]. The command line's hook
/// reads the flag its SIGINT and SIGTERM handlers set; the Python bindings' checks Python's
/// pending signals (so that Ctrl-C raises `KeyboardInterrupt`).
#[derive(Clone)]
pub struct Cancel(Arc<dyn Fn() -> bool + Send + Sync>);

impl Cancel {
    /// The hook `f`.
    pub fn new(f: impl Fn() -> bool + Send + Sync + 'static) -> Self {
        Cancel(Arc::new(f))
    }
    /// Whether the caller asks the solve to stop.
    pub fn requested(&self) -> bool {
        (self.0)()
    }
    /// `Err(Interrupted)` if the optional hook `cancel` asks the solve to stop.
    pub fn check(cancel: Option<&Cancel>) -> crate::Result<()> {
        match cancel {
            Some(c) if c.requested() => Err(crate::Error::Interrupted),
            _ => Ok(()),
        }
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Cancel(..)")
    }
}

impl Default for ActiveSetOptions {
    fn default() -> Self {
        ActiveSetOptions {
            c: 1.0,
            max_solves: 500,
            tol: 1e-10,
            initial_active: None,
            keep_iterates: false,
            progress: None,
            screening: true,
            look_ahead: None,
            cancel: None,
            predict_only: false,
        }
    }
}

/// An iteration that stopped without converging: why, and the log up to there.
#[derive(Debug, Clone)]
pub struct Stalled {
    /// Cycling or the iteration cap.
    pub error: SolverError,
    /// The solves made.
    pub log: Vec<IterationLog>,
}

/// An iteration stopped before a solve that was likely its last
/// ([`ActiveSetOptions::predict_only`]): a prediction, not a solution.
#[derive(Debug, Clone)]
pub struct Predicted {
    /// The active set the next solve would have been made with.
    pub active: Vec<bool>,
    /// The iterate of the last solve made (of the active set before `active`).
    pub u: Vec<f64>,
    /// The solves made.
    pub log: Vec<IterationLog>,
}

/// The result of [`run`].
#[derive(Debug, Clone)]
pub enum Outcome {
    /// Converged, certified.
    Solved(VariationalSolution),
    /// Cycled or reached the iteration cap (the caller may fall back to another method).
    Stalled(Stalled),
    /// Stopped before a likely last solve, as [`ActiveSetOptions::predict_only`] asks.
    Predicted(Predicted),
}

/// Solves the discrete variational inequality by the active-set method (see module docs);
/// cycling and the iteration cap are errors.
pub fn solve<P: Sync>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
    opts: &ActiveSetOptions,
) -> crate::Result<VariationalSolution> {
    match run(q, cons, opts)? {
        Outcome::Solved(s) => Ok(s),
        Outcome::Stalled(s) => Err(s.error.into()),
        Outcome::Predicted(_) => Err(crate::Error::InvalidData(
            "predict_only returns a prediction, not a solution: call active_set::run".into(),
        )),
    }
}

/// The initial active set of `opts`, checked against the constraints.
fn initial_active<P>(cons: &Constraints<P>, opts: &ActiveSetOptions) -> crate::Result<Vec<bool>> {
    if !(opts.c > 0.0 && opts.c.is_finite()) {
        return Err(crate::Error::InvalidData(format!(
            "the active-set parameter c must be positive and finite, got {}",
            opts.c
        )));
    }
    super::certificate::check_tolerance(opts.tol)?;
    if opts.max_solves == 0 {
        return Err(crate::Error::InvalidData(
            "the active-set method needs at least one solve (max_solves = 0)".into(),
        ));
    }
    let m = cons.dofs.len();
    match &opts.initial_active {
        Some(a) if a.len() == m => Ok(a.clone()),
        Some(a) => Err(crate::Error::InvalidData(format!(
            "initial active set has {} entries for {m} constrained unknowns",
            a.len()
        ))),
        None => Ok(vec![false; m]),
    }
}

/// The round-off thresholds of the rule, from the scales of the evaluation `ev`.
fn thresholds(ev: &Evaluation, c: f64) -> Thresholds {
    Thresholds {
        scale_r: ev.scale_r,
        scale_u: ev.scale_u,
        c,
    }
}

/// The next active set (Herbin's rule, step 2 of the module docs), with round-off thresholds
/// taken from the scales of the evaluation of the current iterate.
fn next_active<P: Sync>(
    cons: &Constraints<P>,
    u: &[f64],
    active: &[bool],
    ev: &Evaluation,
    c: f64,
) -> crate::Result<Vec<bool>> {
    let s = cons.side.sign();
    let thr = thresholds(ev, c);
    let mut next = try_vec(cons.dofs.len(), "the next active set")?;
    next.par_extend(
        cons.dofs
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .map(|(j, pd)| {
                let (l, gap) = if active[j] {
                    (ev.multiplier[j], 0.0)
                } else {
                    (0.0, s * (u[pd.dof] - cons.barrier[j]))
                };
                thr.stays_active(active[j], l, gap, pd.measure)
            }),
    );
    Ok(next)
}

/// The sizes of the active sets met so far.
fn sizes(history: &[Vec<bool>]) -> Vec<usize> {
    history
        .iter()
        .map(|h| h.iter().filter(|&&a| a).count())
        .collect()
}

/// One global solve with the unknowns `active` fixed at their barriers: the iterate, its
/// timings, its evaluation and the active set the rule proposes next. An inexact (screened)
/// iterate that would end the iteration or close a cycle (`next` equal to `active` or in
/// `history`) is first refined to full accuracy, so that those decisions are taken on an
/// exact one.
fn solve_step<P: Sync>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
    active: &[bool],
    history: &[Vec<bool>],
    screening: bool,
    (c, tol): (f64, f64),
) -> crate::Result<(Vec<f64>, SolveTimings, Evaluation, Vec<bool>)> {
    let fixed = cons.fixed(q.n_unknowns(), active)?;
    let (mut u, mut timings) = if screening {
        q.screen_with_fixed(&fixed)?
    } else {
        q.minimise_with_fixed(&fixed)?
    };
    if timings.partial {
        if timings.inexact {
            // the rule reads the iterate at the constrained unknowns
            fill_constrained(&*q, cons, &mut u)?;
        } else {
            // an exact iterate is evaluated whole (energies do not return these)
            q.complete(&mut u)?;
            timings.partial = false;
        }
    }
    // a screened iterate only chooses the next active set: its residual is computed on the
    // constrained unknowns only, unless it ends the iteration or closes a cycle
    let mut ev = if timings.inexact {
        evaluate_screened(&*q, cons, &u, timings.partial)?
    } else {
        evaluate(&*q, Some(cons), &u, active)?
    };
    let mut next = next_active(cons, &u, active, &ev, c)?;
    if ev.screened && (next == active || history.contains(&next)) {
        if let Some((v, more)) = q.refine(&fixed)? {
            u = v;
            timings = timings.then(more);
        }
        ev = evaluate(&*q, Some(cons), &u, active)?;
        next = next_active(cons, &u, active, &ev, c)?;
    }
    // settled, but the certificate's residuals (maxima over the unknowns) are above `tol`
    // while the iterative solve met its own 2-norm target: polish the solve
    for rtol in POLISH_RTOLS {
        if next != active || ev.certificate.check(tol).is_ok() {
            break;
        }
        // a polish that cannot reach `rtol` leaves the iterate and its certificate as they are
        let (v, more) = match q.polish(&fixed, rtol) {
            Ok(Some(polished)) => polished,
            Ok(None) | Err(crate::Error::Linear(_)) => break,
            Err(e) => return Err(e),
        };
        u = v;
        timings = timings.then(more);
        ev = evaluate(&*q, Some(cons), &u, active)?;
        next = next_active(cons, &u, active, &ev, c)?;
    }
    Ok((u, timings, ev, next))
}

/// Fills the constrained unknowns that the partial iterate `u` left unset
/// ([`QuadraticEnergy::partial_values`]; on HMM's obstacle none are, its cells are solved for,
/// while Signorini's faces may be derived ones).
fn fill_constrained<P>(
    q: &dyn QuadraticEnergy,
    cons: &Constraints<P>,
    u: &mut [f64],
) -> crate::Result<()> {
    let unset: Vec<usize> = cons
        .dofs
        .iter()
        .map(|pd| pd.dof)
        .filter(|&d| u.get(d).is_some_and(|v| v.is_nan()))
        .collect();
    if unset.is_empty() {
        return Ok(());
    }
    let values = q.partial_values(u, &unset)?;
    for (&d, v) in unset.iter().zip(values) {
        u[d] = v;
    }
    Ok(())
}

/// A complete copy of the iterate `u` (filled by [`QuadraticEnergy::complete`] if it is
/// partial).
fn completed(q: &dyn QuadraticEnergy, u: &[f64], partial: bool) -> crate::Result<Vec<f64>> {
    let mut v = u.to_vec();
    if partial {
        q.complete(&mut v)?;
    }
    Ok(v)
}

/// The relative residuals (‖c − Su‖₂ / ‖c‖₂) asked of an iterative solver, in turn, when the
/// iteration has settled (the next active set is the current one) but the certificate fails:
/// its residuals are maxima over the unknowns, scaled by the largest row, while the solver
/// stops on a 2-norm relative to the right-hand side, and on millions of unknowns the first
/// can exceed the certificate's tolerance while the second meets the solver's target
/// (`assembly::ITERATIVE_RTOL`). Direct solves are exact and are not polished.
pub const POLISH_RTOLS: [f64; 2] = [1e-13, 1e-14];

/// The look-ahead after a solve that proposes `next` ≠ `active` (see [`look_ahead`]) from the
/// iterate `u = (values, partial)`: its report, and its refined proposal if the local
/// iterations converged and it differs from `active` (the caller still rejects one that would
/// close a cycle).
fn refine_proposal<P>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
    u: (&[f64], bool),
    active: &[bool],
    next: &[bool],
    ev: &Evaluation,
    opts: &ActiveSetOptions,
) -> crate::Result<(Option<LookAheadReport>, Option<Vec<bool>>)> {
    let Some(la) = &opts.look_ahead else {
        return Ok((None, None));
    };
    if next == active {
        return Ok((None, None));
    }
    let mut proposal = next.to_vec();
    let thr = thresholds(ev, opts.c);
    let look = look_ahead(q, cons, u, active, &mut proposal, thr, la)?;
    let taken = look.is_some_and(|r| r.converged) && proposal != active;
    Ok((look, taken.then_some(proposal)))
}

/// Why the iteration stops without a solution after `solves` solves: a cycle (`next` repeats
/// an earlier active set) or the solve budget; `None` to go on.
fn stall(
    history: &[Vec<bool>],
    repeat: Option<usize>,
    solves: usize,
    max_solves: usize,
) -> Option<SolverError> {
    if let Some(rep) = repeat {
        Some(SolverError::Cycling {
            iteration: solves,
            repeats: rep,
            history: sizes(history),
        })
    } else if solves >= max_solves {
        Some(SolverError::MaxIterations {
            iterations: solves,
            history: sizes(history),
        })
    } else {
        None
    }
}

/// A change of the active set (the unknowns that entered or left it) at most this fraction of
/// the change before it marks the solve after it as likely the last. The first change from
/// A₀ = ∅ (every violated unknown at once) does not count.
pub const LAST_CHANGE_RATIO: f64 = 0.25;

/// Whether the solve after the changes `(older, newer)` of the active set (the numbers of
/// unknowns that entered or left it) is likely the last: `newer` is at most
/// [`LAST_CHANGE_RATIO`] of `older`, the iteration closing in on its set. Such a solve is not
/// screened: a screened one that ends the iteration is refined to full accuracy anyway
/// ([`solve_step`]), so screening it would only add an evaluation of the inexact iterate and a
/// restart of the conjugate gradients. If it is not the last after all, its exact iterate
/// chooses the next set as a screened one would (the iteration's path is the exact one, which
/// screening only approximates), at the cost of the extra accuracy.
fn likely_last(changes: (Option<usize>, Option<usize>)) -> bool {
    match changes {
        (Some(older), Some(newer)) => (newer as f64) <= LAST_CHANGE_RATIO * older as f64,
        _ => false,
    }
}

/// Runs the active-set method (see module docs) and says whether it converged.
pub fn run<P: Sync>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
    opts: &ActiveSetOptions,
) -> crate::Result<Outcome> {
    let mut active = initial_active(cons, opts)?;
    let m = active.len();
    let mut history: Vec<Vec<bool>> = vec![active.clone()];
    let mut iterates = Vec::new();
    let mut log: Vec<IterationLog> = Vec::new();
    let mut entered = active.iter().filter(|&&a| a).count();
    let mut left = 0;
    let mut screening = opts.screening;
    // whether an iterate since the last restart of the cycle test was inexact
    let mut inexact_seen = false;
    // the number of unknowns the last two changes of the active set moved (older, newer)
    let mut changes: (Option<usize>, Option<usize>) = (None, None);
    // the iterate of the last solve, kept for a prediction only (otherwise it would stay alive
    // through the next solve, one vector of the system's order at its peak), and whether it
    // is partial
    let mut last_u: Option<(Vec<f64>, bool)> = None;
    // from A₀ = ∅ the first change puts every violated unknown in at once, whatever the
    // distance to the solution: it does not count in `changes`
    let cold = !active.iter().any(|&a| a);
    loop {
        let last = likely_last(changes);
        if last && let Some((mut u, partial)) = last_u.take() {
            if partial {
                q.complete(&mut u)?;
            }
            q.release();
            return Ok(Outcome::Predicted(Predicted { active, u, log }));
        }
        let (u, timings, ev, mut next) = solve_step(
            q,
            cons,
            &active,
            &history,
            screening && !last,
            (opts.c, opts.tol),
        )?;
        inexact_seen |= timings.inexact;
        if opts.keep_iterates {
            iterates.push(completed(&*q, &u, timings.partial)?);
        }
        let (look, proposal) =
            refine_proposal(q, cons, (&u, timings.partial), &active, &next, &ev, opts)?;
        // a proposal that would close a cycle is not taken
        if let Some(p) = proposal
            && !history.contains(&p)
        {
            next = p;
        }
        log.push(IterationLog {
            step: IterationStep {
                solve: log.len() + 1,
                active: active.iter().filter(|&&a| a).count(),
                entered,
                left,
                violation: ev.certificate.max_violation,
                residual: (!ev.screened).then_some(ev.certificate.balance_residual),
            },
            timings,
            look_ahead: look,
        });
        if let (Some(report), Some(line)) = (opts.progress, log.last()) {
            report(line);
        }
        if next == active {
            q.release();
            ev.certificate.check(opts.tol)?;
            return Ok(Outcome::Solved(VariationalSolution {
                u,
                multiplier: ev.multiplier,
                active,
                niter: log.len(),
                log,
                certificate: ev.certificate,
                method: Method::ActiveSet,
                iterates,
            }));
        }
        let mut repeat = history.iter().position(|h| *h == next);
        if repeat.is_some() && inexact_seen {
            // the older set may have come from an inexact iterate, whose successor an exact
            // one need not repeat: go on with exact solves, the cycle test restarted from here
            screening = false;
            inexact_seen = false;
            history = vec![active.clone()];
            repeat = None;
        }
        if let Some(error) = stall(&history, repeat, log.len(), opts.max_solves) {
            q.release();
            return Ok(Outcome::Stalled(Stalled { error, log }));
        }
        if let Err(e) = Cancel::check(opts.cancel.as_ref()) {
            q.release();
            return Err(e);
        }
        entered = (0..m).filter(|&j| next[j] && !active[j]).count();
        left = (0..m).filter(|&j| !next[j] && active[j]).count();
        if !(cold && log.len() == 1) {
            changes = (changes.1, Some(entered + left));
        }
        if opts.predict_only {
            last_u = Some((u, timings.partial));
        }
        history.push(next.clone());
        active = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vi::dense::{Dense, Screening, all_constrained, cycling_system, laplacian_1d, spd};
    use crate::vi::exhaustive;
    use crate::vi::{FixedValues, Side};

    /// Random dense SPD problems with upper and lower barriers: the active-set solution equals
    /// exhaustive enumeration and its certificate passes, or the iteration stalls (it is not
    /// guaranteed to converge without the M-matrix property) and says so.
    #[test]
    fn dense_problems_against_enumeration() {
        let mut solved = 0;
        for seed in 0..40u64 {
            let n = 6;
            let m = spd(n, seed + 1);
            let b: Vec<f64> = (0..n)
                .map(|i| ((i as f64 + seed as f64) * 0.7).sin())
                .collect();
            let side = if seed % 2 == 0 {
                Side::Upper
            } else {
                Side::Lower
            };
            let g = (0..n).map(|i| 0.1 * (i as f64 - 2.5)).collect();
            let mut sys = Dense {
                m,
                b,
                dir: FixedValues::free(n).unwrap(),
            };
            let cons = all_constrained(n, g, side);
            let (reference, ref_active) = exhaustive::solve(&mut sys, &cons).unwrap();
            match run(&mut sys, &cons, &ActiveSetOptions::default()).unwrap() {
                Outcome::Solved(sol) => {
                    sol.certificate.check(1e-10).unwrap();
                    assert_eq!(sol.active, ref_active, "seed {seed}");
                    for (a, r) in sol.u.iter().zip(&reference) {
                        assert!((a - r).abs() < 1e-10, "seed {seed}: {a} vs {r}");
                    }
                    solved += 1;
                }
                Outcome::Stalled(s) => assert!(!s.log.is_empty()),
                Outcome::Predicted(_) => panic!("seed {seed}: a prediction without predict_only"),
            }
        }
        assert!(solved >= 30, "only {solved} of 40 converged");
    }

    /// An M-matrix (1D Laplacian): the monotony algorithm converges, from A₀ = ∅, to the
    /// enumerated solution.
    #[test]
    fn m_matrix_converges_to_the_enumerated_solution() {
        let n = 8;
        let m = laplacian_1d(n);
        let mut sys = Dense {
            m,
            b: vec![1.0; n],
            dir: FixedValues::free(n).unwrap(),
        };
        let cons = all_constrained(n, vec![3.0; n], Side::Upper);
        let sol = solve(&mut sys, &cons, &ActiveSetOptions::default()).unwrap();
        let (reference, active) = exhaustive::solve(&mut sys, &cons).unwrap();
        assert_eq!(sol.active, active);
        assert!(sol.active.iter().any(|&a| a) && !sol.active.iter().all(|&a| a));
        for (a, r) in sol.u.iter().zip(&reference) {
            assert!((a - r).abs() < 1e-12);
        }
    }

    /// Screening with inexact solves: small errors give the active sets and the solution of
    /// exact solves, with one refinement (of the last solve); errors that misjudge unknowns
    /// cost solves but still end at the exact solution, every stop decided on a refined
    /// iterate.
    #[test]
    fn screening_ends_at_the_exact_solution() {
        let n = 40;
        let m = laplacian_1d(n);
        let b = vec![0.01; n];
        let barrier: Vec<f64> = (0..n)
            .map(|i| 0.5 - 0.02 * (i as f64 - 20.0).abs())
            .collect();
        let cons = all_constrained(n, barrier, Side::Upper);
        let exact = |m: &nalgebra::DMatrix<f64>| Dense {
            m: m.clone(),
            b: b.clone(),
            dir: FixedValues::free(n).unwrap(),
        };
        let no_screening = ActiveSetOptions {
            screening: false,
            ..Default::default()
        };
        let reference = solve(&mut exact(&m), &cons, &no_screening).unwrap();
        assert!(reference.niter >= 3, "{}", reference.niter);
        let n_active = reference.active.iter().filter(|&&a| a).count();
        assert!(n_active > 2 && n_active < n, "{n_active}");
        for (error, same_path) in [(1e-9, true), (0.05, false)] {
            let mut q = Screening {
                exact: exact(&m),
                error,
                refinements: 0,
            };
            let sol = solve(&mut q, &cons, &ActiveSetOptions::default()).unwrap();
            assert_eq!(sol.active, reference.active, "error {error}");
            for (a, r) in sol.u.iter().zip(&reference.u) {
                assert!((a - r).abs() < 1e-12, "error {error}: {a} vs {r}");
            }
            sol.certificate.check(1e-10).unwrap();
            assert!(!sol.log.last().unwrap().timings.inexact);
            if same_path {
                assert_eq!(sol.niter, reference.niter);
                assert_eq!(q.refinements, 1);
            } else {
                // misjudged: the active sets differ from the exact path's
                let sizes: Vec<usize> = sol.log.iter().map(|l| l.step.active).collect();
                let exact: Vec<usize> = reference.log.iter().map(|l| l.step.active).collect();
                assert_ne!(sizes, exact);
                assert!(q.refinements >= 1);
            }
        }
    }

    /// Partial screened iterates (the odd unknowns derived, the even ones under the barrier):
    /// the same active sets, solution and single refinement as complete screened iterates,
    /// with the look-ahead reading the frozen values around its patches through
    /// `partial_values`; the iterates kept and a prediction are complete (finite).
    #[test]
    fn partial_iterates_end_at_the_solution_of_complete_ones() {
        use crate::vi::ConstrainedDof;
        use crate::vi::dense::Partial;
        let n = 201;
        let m = laplacian_1d(n);
        let b = vec![0.001; n];
        let even: Vec<usize> = (0..n).step_by(2).collect();
        let cons = Constraints {
            dofs: even
                .iter()
                .map(|&i| ConstrainedDof {
                    dof: i,
                    point: (),
                    measure: 1.0,
                })
                .collect(),
            barrier: even
                .iter()
                .map(|&i| 0.5 - 0.004 * (i as f64 - 100.0).abs())
                .collect(),
            side: Side::Upper,
        };
        let screening = || Screening {
            exact: Dense {
                m: m.clone(),
                b: b.clone(),
                dir: FixedValues::free(n).unwrap(),
            },
            error: 1e-9,
            refinements: 0,
        };
        let exact = solve(&mut screening(), &cons, &ActiveSetOptions::default()).unwrap();
        // a warm start off the solution by the constrained unknowns next to its contact zone
        let first = exact.active.iter().position(|&a| a).unwrap();
        let last = exact.active.iter().rposition(|&a| a).unwrap();
        assert!(first >= 3 && last + 3 < even.len(), "{first}..{last}");
        let mut initial = exact.active.clone();
        for j in [first - 2, first - 1, last + 1, last + 2] {
            initial[j] = true;
        }
        let opts = ActiveSetOptions {
            initial_active: Some(initial),
            keep_iterates: true,
            // patches of a few unknowns around the changes
            look_ahead: Some(LookAheadOptions {
                layers: 2,
                max_fraction: 0.5,
                ..Default::default()
            }),
            ..Default::default()
        };
        let mut complete = screening();
        let reference = solve(&mut complete, &cons, &opts).unwrap();
        let mut q = Partial {
            inner: screening(),
            derived: (0..n).map(|i| i % 2 == 1).collect(),
            partial_iterates: 0,
        };
        let sol = solve(&mut q, &cons, &opts).unwrap();
        assert!(q.partial_iterates >= 1);
        assert_eq!(sol.active, reference.active);
        assert_eq!(sol.active, exact.active);
        assert_eq!(sol.niter, reference.niter);
        assert_eq!(q.inner.refinements, complete.refinements);
        for (a, r) in sol.u.iter().zip(&reference.u) {
            assert!((a - r).abs() < 1e-12, "{a} vs {r}");
        }
        sol.certificate.check(1e-10).unwrap();
        assert!(sol.log.iter().any(|l| l.timings.partial));
        assert!(!sol.log.last().unwrap().timings.partial);
        // the look-aheads, on patches smaller than the system, read the frozen derived
        // unknowns recovered (NaN would stop their local iterations)
        let converged = |log: &[IterationLog]| {
            log.iter()
                .filter(|l| l.look_ahead.is_some_and(|r| r.converged && r.patch < n))
                .count()
        };
        assert!(converged(&sol.log) >= 1);
        assert_eq!(converged(&sol.log), converged(&reference.log));
        assert!(sol.iterates.iter().flatten().all(|v| v.is_finite()));
        // a prediction of the same iteration is complete
        let predict = ActiveSetOptions {
            predict_only: true,
            keep_iterates: false,
            ..opts
        };
        let mut q = Partial {
            inner: screening(),
            derived: (0..n).map(|i| i % 2 == 1).collect(),
            partial_iterates: 0,
        };
        match run(&mut q, &cons, &predict).unwrap() {
            Outcome::Predicted(p) => assert!(p.u.iter().all(|v| v.is_finite())),
            Outcome::Solved(s) => assert!(s.u.iter().all(|v| v.is_finite())),
            Outcome::Stalled(s) => panic!("stalled: {:?}", s.error),
        }
    }

    /// A 1D Laplacian with a flat barrier, its exact (unscreened) solution, and a warm start
    /// from that solution's active set with the unknowns `lo..hi` freed and the `extra` ones
    /// before it set active: the first solve puts the middle back in at once, the later ones
    /// free the extra unknowns one at a time.
    fn warm_flat_barrier(
        lo: usize,
        hi: usize,
        extra: usize,
    ) -> (
        Dense,
        Constraints<()>,
        VariationalSolution,
        ActiveSetOptions,
    ) {
        let n = 100;
        let mut q = Dense {
            m: laplacian_1d(n),
            b: vec![0.01; n],
            dir: FixedValues::free(n).unwrap(),
        };
        let cons = all_constrained(n, vec![0.3; n], Side::Upper);
        let no_screening = ActiveSetOptions {
            screening: false,
            ..Default::default()
        };
        let exact = solve(&mut q, &cons, &no_screening).unwrap();
        let mut a = exact.active.clone();
        a[lo..hi].iter_mut().for_each(|x| *x = false);
        let first = a.iter().position(|&x| x).unwrap();
        a[first - extra..first].iter_mut().for_each(|x| *x = true);
        let warm = ActiveSetOptions {
            initial_active: Some(a),
            ..Default::default()
        };
        (q, cons, exact, warm)
    }

    /// The changes of the active set between the solves of `log`.
    fn changes(log: &[IterationLog]) -> Vec<usize> {
        log[1..]
            .iter()
            .map(|l| l.step.entered + l.step.left)
            .collect()
    }

    /// A solve after a change of the active set at most [`LAST_CHANGE_RATIO`] of the one
    /// before it is not screened, whether or not it is the last; the others are. Warm-started
    /// so that the changes are 21, 1, 1, 1: the third solve (after 21 then 1) is exact and
    /// evaluated whole though the iteration goes on, the fourth (1 then 1) is screened again,
    /// and the path, the answer and the single refinement (of the last solve) are those of
    /// screening everywhere. From A₀ = ∅ the first change (every violated unknown) does not
    /// count: on the same problem the cold changes 100, 2, 2, … screen every solve but the
    /// last.
    #[test]
    fn a_solve_after_a_small_change_is_not_screened() {
        let (q, cons, _, warm) = warm_flat_barrier(40, 60, 4);
        let reference = solve(
            &mut q.clone(),
            &cons,
            &ActiveSetOptions {
                screening: false,
                ..warm.clone()
            },
        )
        .unwrap();
        assert_eq!(changes(&reference.log), [21, 1, 1, 1]);
        assert!(likely_last((Some(21), Some(1))));
        assert!(!likely_last((Some(1), Some(1))));
        assert!(!likely_last((None, Some(1))));
        let screened = |opts: &ActiveSetOptions| {
            let mut s = Screening {
                exact: q.clone(),
                error: 1e-9,
                refinements: 0,
            };
            let sol = solve(&mut s, &cons, opts).unwrap();
            let whole: Vec<bool> = sol.log.iter().map(|l| l.step.residual.is_some()).collect();
            (sol, whole, s.refinements)
        };
        let (sol, whole, refinements) = screened(&warm);
        assert_eq!(whole, [false, false, true, false, true]);
        assert_eq!(sol.niter, reference.niter);
        assert_eq!(sol.active, reference.active);
        assert_eq!(refinements, 1);
        for (a, r) in sol.u.iter().zip(&reference.u) {
            assert!((a - r).abs() < 1e-12, "{a} vs {r}");
        }
        sol.certificate.check(1e-10).unwrap();
        let cold = ActiveSetOptions::default();
        let (sol, whole, refinements) = screened(&cold);
        assert_eq!(changes(&sol.log)[..3], [100, 2, 2]);
        assert!(whole[..sol.niter - 1].iter().all(|&w| !w), "{whole:?}");
        assert_eq!((whole[sol.niter - 1], refinements), (true, 1));
    }

    /// `predict_only` stops before a solve that is likely the last: where that solve would
    /// only have confirmed its set (changes 21, 1, then none), the prediction is the
    /// solution's active set after two solves instead of three; where the iteration would
    /// have gone on (21, 1, 1, 1), it is the set of the third solve. `solve` refuses the
    /// option; without it, `run` certifies as before.
    #[test]
    fn predict_only_stops_before_the_likely_last_solve() {
        for (extra, niter) in [(2, 3), (4, 5)] {
            let (q, cons, exact, warm) = warm_flat_barrier(40, 60, extra);
            let full = solve(&mut q.clone(), &cons, &warm).unwrap();
            assert_eq!(full.niter, niter);
            assert_eq!(full.active, exact.active);
            let predict = ActiveSetOptions {
                predict_only: true,
                ..warm
            };
            let Outcome::Predicted(p) = run(&mut q.clone(), &cons, &predict).unwrap() else {
                panic!("extra {extra}: not a prediction");
            };
            assert_eq!(p.log.len(), 2);
            let count = p.active.iter().filter(|&&a| a).count();
            assert_eq!(count, full.log[2].step.active, "extra {extra}");
            if niter == 3 {
                assert_eq!(p.active, exact.active);
            } else {
                assert_ne!(p.active, exact.active);
            }
            assert_eq!(p.u.len(), exact.u.len());
            let e = solve(&mut q.clone(), &cons, &predict).unwrap_err();
            assert!(e.to_string().contains("predict_only"), "{e}");
        }
    }

    /// The hook is polled after each linear solve that is not the last: true stops the
    /// iteration after the first one; false changes nothing, bit for bit.
    #[test]
    fn the_cancellation_hook_stops_between_solves() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        let n = 40;
        let m = laplacian_1d(n);
        let barrier: Vec<f64> = (0..n)
            .map(|i| 0.5 - 0.02 * (i as f64 - 20.0).abs())
            .collect();
        let cons = all_constrained(n, barrier, Side::Upper);
        let mut q = Dense {
            m,
            b: vec![0.01; n],
            dir: FixedValues::free(n).unwrap(),
        };
        let plain = solve(&mut q, &cons, &ActiveSetOptions::default()).unwrap();
        assert!(plain.niter >= 3, "{}", plain.niter);
        for stop in [false, true] {
            let polls = Arc::new(AtomicUsize::new(0));
            let counter = Arc::clone(&polls);
            let o = ActiveSetOptions {
                cancel: Some(Cancel::new(move || {
                    counter.fetch_add(1, Ordering::SeqCst);
                    stop
                })),
                ..Default::default()
            };
            let r = solve(&mut q, &cons, &o);
            if stop {
                assert!(matches!(r, Err(crate::Error::Interrupted)), "{r:?}");
                assert_eq!(polls.load(Ordering::SeqCst), 1);
            } else {
                let r = r.unwrap();
                assert_eq!(polls.load(Ordering::SeqCst), plain.niter - 1);
                assert_eq!(r.niter, plain.niter);
                assert_eq!(r.active, plain.active);
                let bits = |u: &[f64]| u.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&r.u), bits(&plain.u));
            }
        }
    }

    #[test]
    fn cycling_is_reported_with_its_log() {
        let (mut sys, cons) = cycling_system();
        let Outcome::Stalled(s) = run(&mut sys, &cons, &ActiveSetOptions::default()).unwrap()
        else {
            panic!("the crafted system should cycle");
        };
        assert!(
            matches!(s.error, SolverError::Cycling { .. }),
            "{}",
            s.error
        );
        assert_eq!(s.log.len(), s.log.last().unwrap().step.solve);
        assert!(solve(&mut sys, &cons, &ActiveSetOptions::default()).is_err());
    }

    #[test]
    fn bad_options_are_typed_errors() {
        let (mut sys, cons) = cycling_system();
        for c in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let o = ActiveSetOptions {
                c,
                ..Default::default()
            };
            assert!(matches!(
                solve(&mut sys, &cons, &o),
                Err(crate::Error::InvalidData(_))
            ));
        }
        let o = ActiveSetOptions {
            initial_active: Some(vec![true]),
            ..Default::default()
        };
        assert!(matches!(
            solve(&mut sys, &cons, &o),
            Err(crate::Error::InvalidData(_))
        ));
        for tol in [0.0, 1.0, f64::INFINITY, f64::NAN, -1e-10] {
            let o = ActiveSetOptions {
                tol,
                ..Default::default()
            };
            assert!(
                matches!(
                    solve(&mut sys, &cons, &o),
                    Err(crate::Error::InvalidData(_))
                ),
                "{tol}"
            );
        }
        let o = ActiveSetOptions {
            max_solves: 0,
            ..Default::default()
        };
        assert!(matches!(
            solve(&mut sys, &cons, &o),
            Err(crate::Error::InvalidData(_))
        ));
    }
}
