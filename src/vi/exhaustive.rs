//! Exhaustive enumeration: the reference solver for small problems. For every subset A of the
//! constrained unknowns, minimise the energy with u_j = g_j on A; the discrete solution is the
//! candidate that is feasible (s(u_j − g_j) ≤ 0) with non-negative multipliers on A (λ_j =
//! s(b − Mu)_j ≥ 0). The inequality has a unique solution (strictly convex energy on a convex
//! set), so any candidate passing the test is it. Costs 2^m solves: m ≤ [`MAX_CONSTRAINED`].

use super::{Constraints, QuadraticEnergy};

/// Largest number of constrained unknowns accepted (2^20 solves).
pub const MAX_CONSTRAINED: usize = 20;

/// The solution and its active set, or a typed error when there are too many constrained
/// unknowns or no subset passes the test (which the theory excludes for SPD M and a non-empty
/// convex set: it would mean round-off larger than the tolerances, 1e-12 relative).
pub fn solve<P>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
) -> crate::Result<(Vec<f64>, Vec<bool>)> {
    let m = cons.dofs.len();
    let mut found = kkt_active_sets(q, cons, true)?;
    found
        .pop()
        .map(|(a, u)| (u, a))
        .ok_or(crate::Error::Solver(crate::SolverError::NoKktPoint {
            candidates: 1 << m,
        }))
}

/// Every active set whose equality-constrained minimiser satisfies the KKT conditions, with
/// that minimiser (the first one only if `first_only`). More than one means degenerate data
/// (an unknown exactly at the barrier with a zero multiplier).
pub fn kkt_active_sets<P>(
    q: &mut dyn QuadraticEnergy,
    cons: &Constraints<P>,
    first_only: bool,
) -> crate::Result<Vec<(Vec<bool>, Vec<f64>)>> {
    let m = cons.dofs.len();
    if m > MAX_CONSTRAINED {
        return Err(crate::Error::InvalidData(format!(
            "exhaustive enumeration is for at most {MAX_CONSTRAINED} constrained unknowns, got {m}"
        )));
    }
    let s = cons.side.sign();
    let mut found = Vec::new();
    for mask in 0u32..(1 << m) {
        let active: Vec<bool> = (0..m).map(|j| mask & (1 << j) != 0).collect();
        let (u, _) = q.minimise_with_fixed(&cons.fixed(q.n_unknowns(), &active)?)?;
        let (r, sc) = q.residual(&u)?;
        let scale = sc.iter().cloned().fold(0.0, f64::max);
        let umax = u.iter().fold(1e-300f64, |a, x| a.max(x.abs()));
        let ok = (0..m).all(|j| {
            let d = cons.dofs[j].dof;
            let feasible = s * (u[d] - cons.barrier[j]) <= 1e-12 * umax;
            let mult = !active[j] || s * r[d] >= -1e-12 * scale;
            feasible && mult
        });
        if ok {
            found.push((active, u));
            if first_only {
                break;
            }
        }
    }
    Ok(found)
}
