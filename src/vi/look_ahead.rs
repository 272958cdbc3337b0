//! Look-ahead of the active set on a patch: the changes that the next active-set steps would
//! make near the free boundary, found by small local solves instead of global ones.
//!
//! After a global iterate u^k of the active set A_k, the rule of [`super::active_set`] gives
//! A_{k+1}. Where it changes A_k, the next global solve changes u mostly nearby, and the step
//! after it changes the active set again, one layer of cells at a time while the contact zone
//! shrinks ([`crate::solver::warm_start`] describes why). The look-ahead runs those steps on a
//! patch only:
//!
//! 1. **Patch.** P = the unknowns within `layers` steps, in the graph of M, of the
//!    constrained unknowns where A_{k+1} differs from A_k (Dirichlet unknowns excluded).
//! 2. **Local problem.** Minimise the energy over the unknowns of P with every other unknown
//!    frozen at u^k: M_PP x = b_P − M_{P,P^c} u^k_{P^c}, the constrained unknowns of P under
//!    their barrier.
//! 3. **Local active-set iteration** on it, from A_{k+1} ∩ P, with the same rule and round-off
//!    thresholds as the global one (sparse Cholesky of M_PP with unit rows and columns for the
//!    fixed unknowns: one symbolic analysis, one numeric factorisation per local solve), until
//!    the local active set repeats itself.
//! 4. A_{k+1} on P is replaced by the local active set, if the local iteration converged.
//!
//! The look-ahead only proposes the next active set: the global iteration still solves with
//! it, applies its own rule to the result and stops only when that leaves the active set
//! unchanged, so the solution and its certificate are the ones without look-ahead; a poor
//! proposal costs global solves, never accuracy. The global iteration discards a proposal
//! equal to A_k or to an earlier active set (which would end the iteration or close a cycle
//! without a global decision).
//!
//! Cost: each row of the patch read once ([`QuadraticEnergy::row_entries`], layer by layer),
//! and per local solve a Cholesky factorisation of order |P| — small against a global solve
//! when the changes are confined to a band along the free boundary, as after a warm start. Patches
//! above [`LookAheadOptions::max_fraction`] of the unknowns are not tried.

use super::{Constraints, FixedValues, QuadraticEnergy};
use crate::linalg::{CholeskyWork, SpdPattern};
use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// The multiply–rotate hash of rustc's FxHasher, for the unknown indices of a patch: std's
/// default (SipHash) resists crafted keys, which these are not (the system's own indices),
/// and costs a look-ahead a large share of its time in its maps
/// (`replication/measurements/solver.md`).
#[derive(Default, Clone, Copy)]
struct IndexHasher(u64);

impl Hasher for IndexHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

/// Maps and sets keyed by unknown indices ([`IndexHasher`]).
type IndexMap<V> = HashMap<usize, V, BuildHasherDefault<IndexHasher>>;
type IndexSet = HashSet<usize, BuildHasherDefault<IndexHasher>>;

/// Options of the look-ahead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LookAheadOptions {
    /// Graph distance from the changed unknowns to the edge of the patch.
    pub layers: usize,
    /// Local solves at most; an iteration that has not converged by then proposes nothing.
    pub max_solves: usize,
    /// Largest patch, as a fraction of the unknowns.
    pub max_fraction: f64,
}

impl Default for LookAheadOptions {
    /// 6 layers, at most 50 local solves, patches of at most a fifth of the unknowns. Too few
    /// layers give small patches whose proposals the global iteration takes back; 6 keeps a
    /// margin over the smallest number that saved global solves on the benchmarks. The
    /// measurements behind it are in `replication/BENCHMARKS.md` ("Measurements behind the
    /// defaults").
    fn default() -> Self {
        LookAheadOptions {
            layers: 6,
            max_solves: 50,
            max_fraction: 0.2,
        }
    }
}

/// What a look-ahead did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LookAheadReport {
    /// Wall-clock time, in seconds.
    pub seconds: f64,
    /// Unknowns of the patch.
    pub patch: usize,
    /// Local solves.
    pub solves: usize,
    /// Whether the local iteration converged (its active set is then proposed).
    pub converged: bool,
}

/// The round-off thresholds of the active-set rule, from the scales of the evaluation of the
/// global iterate.
#[derive(Debug, Clone, Copy)]
pub struct Thresholds {
    /// Scale of the residual (max_i |b_i| + Σ_j |M_ij u_j|).
    pub scale_r: f64,
    /// Scale of u.
    pub scale_u: f64,
    /// The parameter c of the rule.
    pub c: f64,
}

impl Thresholds {
    /// Herbin's rule for one constrained unknown (step 2 of [`super::active_set`]): an active
    /// unknown stays if its multiplier λ exceeds round-off of the residual, an inactive one
    /// enters if its violation s(u − g) exceeds round-off of u.
    pub fn stays_active(
        &self,
        active: bool,
        multiplier: f64,
        violation: f64,
        measure: f64,
    ) -> bool {
        // one threshold per term: a single one mixing both would grow like 1/m_j on fine
        // meshes and let violations through
        let score = multiplier / measure + self.c * violation;
        let thr = if active {
            1e-13 * self.scale_r / measure
        } else {
            self.c * 1e-13 * self.scale_u
        };
        score > thr
    }
}

/// Looks ahead from the global iterate `u` of the active set `active` (see the module docs):
/// on success `next` (the rule's next active set) is replaced on the patch by the local
/// iteration's active set. `Ok(None)` when there is nothing to do or the energy cannot give
/// rows of M. `u = (values, partial)`: a partial iterate
/// ([`super::SolveTimings::partial`]) is read outside the patch through
/// [`QuadraticEnergy::partial_values`].
pub fn look_ahead<P>(
    q: &dyn QuadraticEnergy,
    cons: &Constraints<P>,
    u: (&[f64], bool),
    active: &[bool],
    next: &mut [bool],
    thr: Thresholds,
    opts: &LookAheadOptions,
) -> crate::Result<Option<LookAheadReport>> {
    let t0 = std::time::Instant::now();
    let n = q.n_unknowns();
    let dirichlet = q.dirichlet();
    let seeds: Vec<usize> = (0..cons.dofs.len())
        .filter(|&j| next[j] != active[j])
        .map(|j| cons.dofs[j].dof)
        .collect();
    if seeds.is_empty() {
        return Ok(None);
    }
    let Some((patch, entries)) = grow_patch(
        q,
        dirichlet,
        seeds,
        opts.layers,
        opts.max_fraction * n as f64,
    )?
    else {
        return Ok(None);
    };
    let mut local = LocalProblem::new(q, cons, u, &patch, entries)?;
    let mut report = LookAheadReport {
        patch: patch.len(),
        ..Default::default()
    };
    let s = cons.side.sign();
    let mut act: Vec<bool> = local.cons.iter().map(|&(_, j)| next[j]).collect();
    let mut history = vec![act.clone()];
    while report.solves < opts.max_solves {
        // a local problem need not be positive definite (a patch over a part of the domain
        // that only its barrier anchors, all of it free): then nothing is proposed
        let x = match local.solve(cons, &act) {
            Ok(x) if x.iter().all(|v| v.is_finite()) => x,
            _ => break,
        };
        report.solves += 1;
        let r = local.residual(&x);
        let new: Vec<bool> = local
            .cons
            .iter()
            .zip(&act)
            .map(|(&(l, j), &a)| {
                let (lambda, gap) = if a {
                    (s * r[l], 0.0)
                } else {
                    (0.0, s * (x[l] - cons.barrier[j]))
                };
                thr.stays_active(a, lambda, gap, cons.dofs[j].measure)
            })
            .collect();
        if new == act {
            for (&(_, j), &a) in local.cons.iter().zip(&act) {
                next[j] = a;
            }
            report.converged = true;
            break;
        }
        if history.contains(&new) {
            break; // a local cycle: propose nothing
        }
        history.push(new.clone());
        act = new;
    }
    report.seconds = t0.elapsed().as_secs_f64();
    Ok(Some(report))
}

/// Entries (i, j, M_ij) of rows of M.
type Entries = Vec<(usize, usize, f64)>;

/// The unknowns within `layers` graph steps of `seeds` (sorted), Dirichlet unknowns excluded,
/// and the entries of their rows of M (each row read once, as its layer is reached); `None`
/// when there are more than `max` or the energy cannot give rows.
fn grow_patch(
    q: &dyn QuadraticEnergy,
    dirichlet: &FixedValues,
    seeds: Vec<usize>,
    layers: usize,
    max: f64,
) -> crate::Result<Option<(Vec<usize>, Entries)>> {
    let mut inside: IndexSet = seeds.iter().copied().collect();
    let mut frontier = seeds;
    let mut entries = Vec::new();
    for layer in 0..=layers {
        let Some(rows) = q.row_entries(&frontier)? else {
            return Ok(None);
        };
        if layer < layers {
            frontier = rows
                .iter()
                .map(|&(_, j, _)| j)
                .filter(|&j| !dirichlet.is_fixed(j) && inside.insert(j))
                .collect();
        } else {
            frontier.clear();
        }
        entries.extend(rows);
        if inside.len() as f64 > max {
            return Ok(None);
        }
        if frontier.is_empty() {
            break;
        }
    }
    let mut patch: Vec<usize> = inside.into_iter().collect();
    patch.sort_unstable();
    Ok(Some((patch, entries)))
}

/// M_PP (lower triangle, by columns), the right-hand side b_P − M_{P,P^c} u_{P^c}, and the
/// constrained unknowns of the patch.
struct LocalProblem {
    pattern: SpdPattern,
    /// Values of the lower triangle of M_PP on `pattern`.
    values: Vec<f64>,
    /// b_P − M_{P,P^c} u_{P^c}.
    rhs: Vec<f64>,
    /// (local index, constraint index) of the constrained unknowns of the patch.
    cons: Vec<(usize, usize)>,
    /// The memory of the factorisations, reused from one local solve to the next.
    work: CholeskyWork,
}

impl LocalProblem {
    fn new<P>(
        q: &dyn QuadraticEnergy,
        cons: &Constraints<P>,
        (u, partial): (&[f64], bool),
        patch: &[usize],
        entries: Entries,
    ) -> crate::Result<Self> {
        let local: IndexMap<usize> = patch.iter().enumerate().map(|(l, &g)| (g, l)).collect();
        let p = patch.len();
        let b = q.load();
        // a partial iterate's frozen values outside the patch, recovered where it has none
        let frozen: Option<IndexMap<f64>> = if partial {
            let mut outside: Vec<usize> = entries
                .iter()
                .map(|&(_, j, _)| j)
                .filter(|j| !local.contains_key(j))
                .collect();
            outside.sort_unstable();
            outside.dedup();
            let values = q.partial_values(u, &outside)?;
            Some(outside.into_iter().zip(values).collect())
        } else {
            None
        };
        let mut rhs: Vec<f64> = patch.iter().map(|&g| b[g]).collect();
        // lower-triangle entries (row ≥ column), by column then row, duplicates summed
        let mut lower: Vec<(usize, usize, f64)> = Vec::with_capacity(entries.len() / 2 + p);
        for (i, j, v) in entries {
            let li = local[&i];
            match local.get(&j) {
                Some(&lj) if li >= lj => lower.push((lj, li, v)),
                Some(_) => {}
                None => rhs[li] -= v * frozen.as_ref().map_or(u[j], |f| f[&j]),
            }
        }
        lower.sort_unstable_by_key(|&(c, r, _)| (c, r));
        let mut merged: Vec<(usize, usize, f64)> = Vec::with_capacity(lower.len());
        for (c, r, v) in lower {
            match merged.last_mut() {
                Some(last) if (last.0, last.1) == (c, r) => last.2 += v,
                _ => merged.push((c, r, v)),
            }
        }
        let mut col_ptr = vec![0usize; p + 1];
        for &(c, _, _) in &merged {
            col_ptr[c + 1] += 1;
        }
        for c in 0..p {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = merged.iter().map(|e| e.1).collect();
        let values: Vec<f64> = merged.iter().map(|e| e.2).collect();
        let pattern = SpdPattern::new(p, col_ptr, row_idx)?;
        let cons: Vec<(usize, usize)> = cons
            .dofs
            .iter()
            .enumerate()
            .filter_map(|(j, pd)| local.get(&pd.dof).map(|&l| (l, j)))
            .collect();
        Ok(LocalProblem {
            pattern,
            values,
            rhs,
            cons,
            work: CholeskyWork::new(),
        })
    }

    /// The local solution with the constrained unknowns `act` (indexed like `self.cons`)
    /// fixed at their barrier: unit rows and columns for them, their columns moved to the
    /// right-hand side.
    fn solve<P>(&mut self, cons: &Constraints<P>, act: &[bool]) -> crate::Result<Vec<f64>> {
        let p = self.rhs.len();
        let mut fixed = vec![f64::NAN; p];
        for (&(l, j), &a) in self.cons.iter().zip(act) {
            if a {
                fixed[l] = cons.barrier[j];
            }
        }
        let mut x = self.rhs.clone();
        let mut values = self.values.clone();
        let (col_ptr, row_idx) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for c in 0..p {
            let range = col_ptr[c]..col_ptr[c + 1];
            for (&r, v) in row_idx[range.clone()].iter().zip(&mut values[range]) {
                let (free_r, free_c) = (fixed[r].is_nan(), fixed[c].is_nan());
                if free_r && free_c {
                    continue;
                }
                // entry (r, c) and its mirror (c, r): a fixed column moves to the right-hand
                // side of a free row
                if free_r {
                    x[r] -= *v * fixed[c];
                } else if free_c {
                    x[c] -= *v * fixed[r];
                }
                *v = if r == c { 1.0 } else { 0.0 };
            }
        }
        for (xl, f) in x.iter_mut().zip(&fixed) {
            if !f.is_nan() {
                *xl = *f;
            }
        }
        self.pattern
            .factor(&values, &mut self.work)?
            .solve_in_place(&mut x);
        Ok(x)
    }

    /// The local residual rhs − M_PP x (M_PP symmetric, stored as its lower triangle).
    fn residual(&self, x: &[f64]) -> Vec<f64> {
        let mut r = self.rhs.clone();
        let (col_ptr, row_idx) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for (c, &xc) in x.iter().enumerate() {
            let range = col_ptr[c]..col_ptr[c + 1];
            for (&rw, &v) in row_idx[range.clone()].iter().zip(&self.values[range]) {
                r[rw] -= v * xc;
                if rw != c {
                    r[c] -= v * x[rw];
                }
            }
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vi::Side;
    use crate::vi::active_set::{self, ActiveSetOptions};
    use crate::vi::certificate::evaluate;
    use crate::vi::dense::{Dense, all_constrained, laplacian_1d};

    /// −u'' = f on n points under the upper barrier g (a tent): contact in the middle (on 60
    /// points, 23 unknowns, which the plain iteration reaches from A₀ = ∅ in 10 solves,
    /// shrinking 54 by about 4 unknowns per solve).
    fn tent(n: usize) -> (Dense, Constraints) {
        let sys = Dense {
            m: laplacian_1d(n),
            b: vec![0.002; n],
            dir: FixedValues::free(n).unwrap(),
        };
        let g = (0..n)
            .map(|i| 0.6 - 0.015 * (i as f64 - n as f64 / 2.0).abs())
            .collect();
        (sys, all_constrained(n, g, Side::Upper))
    }

    fn thresholds(q: &Dense, cons: &Constraints, u: &[f64], active: &[bool]) -> Thresholds {
        let ev = evaluate(q, Some(cons), u, active).unwrap();
        Thresholds {
            scale_r: ev.scale_r,
            scale_u: ev.scale_u,
            c: 1.0,
        }
    }

    /// A patch covering every unknown makes the local problem the global one: the look-ahead
    /// from any iterate proposes the solution's active set. A one-layer patch changes the
    /// proposal only near the changes.
    #[test]
    fn a_patch_over_everything_proposes_the_solution() {
        let n = 60;
        let (mut q, cons) = tent(n);
        let exact = active_set::solve(
            &mut q,
            &cons,
            &ActiveSetOptions {
                screening: false,
                ..Default::default()
            },
        )
        .unwrap();
        let n_active = exact.active.iter().filter(|&&a| a).count();
        assert!(n_active > 5 && n_active < n - 10, "{n_active}");
        // an iterate: a few unknowns of the contact zone active
        let mut active = vec![false; n];
        for a in active.iter_mut().skip(n / 2 - 2).take(4) {
            *a = true;
        }
        let (u, _) = q
            .minimise_with_fixed(&cons.fixed(n, &active).unwrap())
            .unwrap();
        let thr = thresholds(&q, &cons, &u, &active);
        // the rule's next set: the violated unknowns enter
        let ev = evaluate(&q, Some(&cons), &u, &active).unwrap();
        let rule: Vec<bool> = (0..n)
            .map(|j| {
                let (l, gap) = if active[j] {
                    (ev.multiplier[j], 0.0)
                } else {
                    (0.0, u[j] - cons.barrier[j])
                };
                thr.stays_active(active[j], l, gap, 1.0)
            })
            .collect();
        assert_ne!(rule, exact.active);
        let mut next = rule.clone();
        let wide = LookAheadOptions {
            layers: n,
            max_fraction: 1.0,
            ..Default::default()
        };
        let rep = look_ahead(&q, &cons, (&u, false), &active, &mut next, thr, &wide)
            .unwrap()
            .unwrap();
        assert!(
            rep.converged && rep.patch == n && rep.solves >= 1,
            "{rep:?}"
        );
        assert_eq!(next, exact.active);

        let mut next = rule.clone();
        let narrow = LookAheadOptions { layers: 1, ..wide };
        let rep = look_ahead(&q, &cons, (&u, false), &active, &mut next, thr, &narrow)
            .unwrap()
            .unwrap();
        assert!(rep.patch < n, "{rep:?}");
        let changed: Vec<usize> = (0..n).filter(|&j| rule[j] != active[j]).collect();
        for j in 0..n {
            let near = changed.iter().any(|&c| c.abs_diff(j) <= 1);
            assert!(
                near || next[j] == rule[j],
                "unknown {j} outside the patch changed"
            );
        }
        // nothing changed: nothing to look ahead
        let mut same = exact.active.clone();
        let (u, _) = q
            .minimise_with_fixed(&cons.fixed(n, &same).unwrap())
            .unwrap();
        let thr = thresholds(&q, &cons, &u, &exact.active);
        let none =
            look_ahead(&q, &cons, (&u, false), &exact.active, &mut same, thr, &wide).unwrap();
        assert!(none.is_none());
        // too large a patch: nothing proposed
        let mut next = rule.clone();
        let capped = LookAheadOptions {
            max_fraction: 0.1,
            ..wide
        };
        let thr = thresholds(&q, &cons, &u, &active);
        assert!(
            look_ahead(&q, &cons, (&u, false), &active, &mut next, thr, &capped)
                .unwrap()
                .is_none()
        );
        assert_eq!(next, rule);
    }

    /// A singular local problem (a Neumann patch with its barrier freed) proposes nothing and
    /// is not an error.
    #[test]
    fn a_singular_local_problem_proposes_nothing() {
        let n = 6;
        let mut m = laplacian_1d(n);
        m[(0, 0)] = 1.0;
        m[(n - 1, n - 1)] = 1.0; // pure Neumann: singular, constants in the kernel
        let q = Dense {
            m,
            b: vec![0.1; n],
            dir: FixedValues::free(n).unwrap(),
        };
        let cons = all_constrained(n, vec![0.5; n], Side::Upper);
        let active = vec![true; n];
        let u = vec![0.5; n];
        let mut next = vec![false; n];
        let thr = Thresholds {
            scale_r: 1.0,
            scale_u: 1.0,
            c: 1.0,
        };
        let opts = LookAheadOptions {
            layers: n,
            max_fraction: 1.0,
            ..Default::default()
        };
        let rep = look_ahead(&q, &cons, (&u, false), &active, &mut next, thr, &opts)
            .unwrap()
            .unwrap();
        assert!(!rep.converged, "{rep:?}");
        assert_eq!(next, vec![false; n]);
    }

    /// The active-set method with look-ahead: the same solution and certificate as without,
    /// in fewer solves, from a cold start on a problem whose contact zone the plain iteration
    /// shrinks one unknown per solve.
    #[test]
    fn look_ahead_saves_solves_and_keeps_the_solution() {
        let n = 60;
        let (mut q, cons) = tent(n);
        let plain = ActiveSetOptions {
            screening: false,
            ..Default::default()
        };
        let a = active_set::solve(&mut q, &cons, &plain).unwrap();
        let b = active_set::solve(
            &mut q,
            &cons,
            &ActiveSetOptions {
                // the default fraction would refuse every patch of so small a problem
                look_ahead: Some(LookAheadOptions {
                    layers: 3,
                    max_fraction: 0.5,
                    ..Default::default()
                }),
                ..plain
            },
        )
        .unwrap();
        b.certificate.check(1e-10).unwrap();
        assert_eq!(a.active, b.active);
        for (x, y) in a.u.iter().zip(&b.u) {
            assert!((x - y).abs() < 1e-12);
        }
        assert_eq!(a.niter, 10);
        assert!(b.niter <= 5, "{} vs {}", b.niter, a.niter);
        assert!(
            b.log
                .iter()
                .any(|l| l.look_ahead.is_some_and(|r| r.converged))
        );
    }
}
