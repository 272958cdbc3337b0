//! The certificate: evidence that u solves the discrete variational inequality.
//!
//! With r = b − Mu, the multiplier of constrained unknown j is λ_j = s r_j (s = +1 for an upper
//! barrier, −1 for a lower one), and u solves the inequality iff
//! s(u_j − g_j) ≤ 0 and λ_j ≥ 0 and λ_j (u_j − g_j) = 0 on constrained unknowns, and r_i = 0 on
//! the other non-Dirichlet unknowns. Each quantity is scaled to be dimensionless: violations by
//! scale_u = max(‖u‖∞, ‖g‖∞), residuals and multipliers by scale_r = max_i(|b_i| + Σ_j |M_ij u_j|).
//!
//! [`evaluate`] computes the residual once and returns everything derived from it (certificate,
//! multipliers, scales), so that the caller never recomputes it.

use super::{Constraints, QuadraticEnergy};
use crate::budget::{try_filled, try_vec};
use crate::error::SolverError;
use rayon::prelude::*;

/// Least number of unknowns of one parallel task.
const MIN_LEN: usize = 4096;

/// Evidence that u solves the discrete variational inequality (see the module docs).
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
    /// ‖u‖∞ against the size of the data (set by the solve driver, which knows the data; 0
    /// for a purely algebraic solve): see `crate::solver::magnitude`. Must not exceed
    /// [`MAGNITUDE_LIMIT`].
    pub data_magnitude: f64,
}

/// The largest accepted [`Certificate::data_magnitude`].
pub const MAGNITUDE_LIMIT: f64 = 1e6;

impl Certificate {
    /// The largest of the four scaled quantities (violation, −min multiplier,
    /// complementarity, balance residual): what [`Certificate::check`] compares with `tol`.
    pub fn worst(&self) -> f64 {
        self.max_violation
            .max(-self.min_multiplier)
            .max(self.complementarity)
            .max(self.balance_residual)
    }

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
        if !(self.data_magnitude <= MAGNITUDE_LIMIT) {
            return Err(SolverError::Certificate {
                quantity: "size of u against the size of the data (the system is singular or \
                           nearly so)"
                    .into(),
                value: self.data_magnitude,
                tol: MAGNITUDE_LIMIT,
            });
        }
        Ok(())
    }
}

/// An error unless `tol` is a usable certificate tolerance: finite and in (0, 1) (a tolerance
/// of 1 or more, infinite or NaN would switch the certificate off).
pub fn check_tolerance(tol: f64) -> crate::Result<()> {
    if tol > 0.0 && tol < 1.0 {
        Ok(())
    } else {
        Err(crate::Error::InvalidData(format!(
            "the certificate tolerance must be in (0, 1), got {tol}"
        )))
    }
}

/// What [`evaluate`] (or [`evaluate_screened`]) computed from one residual.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// The certificate; after [`evaluate_screened`] its balance residual is NaN (not
    /// computed), so that it can never pass [`Certificate::check`].
    pub certificate: Certificate,
    /// λ_j = s (b − Mu)_j for each constrained unknown (empty without constraints).
    pub multiplier: Vec<f64>,
    /// max_i(|b_i| + Σ_j |M_ij u_j|) (at least the smallest positive float); after
    /// [`evaluate_screened`], the maximum over the constrained unknowns only.
    pub scale_r: f64,
    /// max(‖u‖∞, ‖g‖∞) (at least the smallest positive float).
    pub scale_u: f64,
    /// Whether the residual was computed on the constrained unknowns only
    /// ([`evaluate_screened`]).
    pub screened: bool,
}

/// Computes the certificate of `u` with the active set `active` (indexed like `cons.dofs`),
/// from a single evaluation of the residual.
pub fn evaluate<P: Sync>(
    q: &dyn QuadraticEnergy,
    cons: Option<&Constraints<P>>,
    u: &[f64],
    active: &[bool],
) -> crate::Result<Evaluation> {
    let (r, scale) = q.residual(u)?;
    let scale_r = max_scale(&scale);
    let scale_u = scale_u(cons, u);
    // one bit per unknown: an active constrained unknown (excluded from the balance residual)
    let mut is_active = try_filled(u.len().div_ceil(64), 0u64, "the active unknowns")?;
    let mut c = Certificate::default();
    let mut lambda = Vec::new();
    if let Some(cons) = cons {
        c = constrained(cons, u, |j| r[cons.dofs[j].dof], scale_r, scale_u);
        let s = cons.side.sign();
        lambda = try_vec(cons.dofs.len(), "the multipliers")?;
        lambda.par_extend(
            cons.dofs
                .par_iter()
                .with_min_len(MIN_LEN)
                .map(|pd| s * r[pd.dof]),
        );
        for (pd, _) in cons.dofs.iter().zip(active).filter(|(_, a)| **a) {
            is_active[pd.dof / 64] |= 1 << (pd.dof % 64);
        }
    }
    let dir = q.dirichlet();
    let free = |i: usize| !dir.is_fixed(i) && is_active[i / 64] >> (i % 64) & 1 == 0;
    c.balance_residual = r
        .par_iter()
        .enumerate()
        .with_min_len(MIN_LEN)
        .filter(|&(i, _)| free(i))
        .map(|(_, v)| v.abs() / scale_r)
        .reduce(|| 0.0, f64::max);
    Ok(Evaluation {
        certificate: c,
        multiplier: lambda,
        scale_r,
        scale_u,
        screened: false,
    })
}

/// What the active-set rule reads of a screened iterate `u` (an iterative solve stopped early to
/// choose the next active set), from the residual on the constrained unknowns only
/// ([`QuadraticEnergy::residual_at`]): the multipliers, to the bit those of [`evaluate`];
/// the violation, the least multiplier and the complementarity, scaled by the residual scale
/// of the constrained unknowns (a lower bound of [`evaluate`]'s, which only sets the
/// round-off thresholds of the rule); no balance residual (NaN). On HMM the constrained
/// unknowns are the cells' of the obstacle or the faces of Γ₃, a fraction of the system,
/// whose other rows would cost a pass over every cell's local matrix.
///
/// A `partial` iterate ([`super::SolveTimings::partial`]; its values at the constrained
/// unknowns filled by [`QuadraticEnergy::partial_values`]) is read through
/// [`QuadraticEnergy::partial_residual_at`]: the multipliers then agree with
/// [`evaluate`]'s of the completed iterate up to rounding, not to the bit, and the scales are
/// those of the rows the energy computes them from and of the unknowns the iterate has (the
/// NaN of the others are skipped by the maxima); a screened iterate only chooses the next
/// active set, and the decisions that end the iteration are taken on exact, complete ones.
pub fn evaluate_screened<P: Sync>(
    q: &dyn QuadraticEnergy,
    cons: &Constraints<P>,
    u: &[f64],
    partial: bool,
) -> crate::Result<Evaluation> {
    let row = |j: usize| cons.dofs[j].dof;
    let (mut r, scale) = if partial {
        q.partial_residual_at(u, cons.dofs.len(), &row)?
    } else {
        q.residual_at(u, cons.dofs.len(), &row)?
    };
    let scale_r = scale.max(f64::MIN_POSITIVE);
    let scale_u = scale_u(Some(cons), u);
    let mut c = constrained(cons, u, |j| r[j], scale_r, scale_u);
    c.balance_residual = f64::NAN;
    // the multipliers λ_j = s r_j, in place
    let s = cons.side.sign();
    r.par_iter_mut().with_min_len(MIN_LEN).for_each(|v| *v *= s);
    let lambda = r;
    Ok(Evaluation {
        certificate: c,
        multiplier: lambda,
        scale_r,
        scale_u,
        screened: true,
    })
}

/// The largest residual scale (at least the smallest positive float).
fn max_scale(scale: &[f64]) -> f64 {
    max_abs(scale).max(f64::MIN_POSITIVE)
}

/// max_i |x_i| (0 for an empty slice), in parallel: a maximum does not depend on the order.
/// NaN entries are skipped (`f64::max` returns the other operand): those of a partial
/// iterate, which are not values.
fn max_abs(x: &[f64]) -> f64 {
    x.par_iter()
        .with_min_len(MIN_LEN)
        .map(|v| v.abs())
        .reduce(|| 0.0, f64::max)
}

/// max(‖u‖∞, ‖g‖∞) (at least the smallest positive float).
fn scale_u<P>(cons: Option<&Constraints<P>>, u: &[f64]) -> f64 {
    let mut scale_u = max_abs(u);
    if let Some(cons) = cons {
        scale_u = scale_u.max(max_abs(&cons.barrier));
    }
    scale_u.max(f64::MIN_POSITIVE)
}

/// The certificate's constrained quantities (violation, least multiplier,
/// complementarity; balance residual 0), with `r(j)` the residual of constrained unknown j
/// (its multiplier is λ_j = s r(j)).
fn constrained<P: Sync>(
    cons: &Constraints<P>,
    u: &[f64],
    r: impl Fn(usize) -> f64 + Sync,
    scale_r: f64,
    scale_u: f64,
) -> Certificate {
    let s = cons.side.sign();
    // (violation, least multiplier, complementarity): maxima and a minimum, which do not
    // depend on the order of the parallel reduction
    let (violation, min_l, complementarity) = cons
        .dofs
        .par_iter()
        .enumerate()
        .with_min_len(MIN_LEN)
        .map(|(j, pd)| {
            let l = s * r(j);
            let gap = u[pd.dof] - cons.barrier[j];
            (
                (s * gap).max(0.0) / scale_u,
                l / scale_r,
                (l * gap).abs() / (scale_r * scale_u),
            )
        })
        .reduce(
            || (0.0, f64::INFINITY, 0.0),
            |a, b| (a.0.max(b.0), a.1.min(b.1), a.2.max(b.2)),
        );
    Certificate {
        max_violation: violation,
        min_multiplier: if min_l.is_finite() { min_l } else { 0.0 },
        complementarity,
        ..Default::default()
    }
}
