//! Well-posedness before solving.
//!
//! The stiffness matrix M of every scheme annihilates the constants on each connected part of
//! the mesh (the consistent gradient of a constant is zero, and so is the stabilisation), so
//! on a part C of the mesh without Dirichlet unknowns, with 1_C the indicator of its unknowns,
//! E(u + t 1_C) = E(u) − t Σ_{i∈C} b_i for every t. Hence, with s = +1 for an upper barrier
//! (u + t 1_C stays admissible for t → −∞) and s = −1 for a lower one (t → +∞):
//! - no barrier on C: E is flat (Σ b = 0) or unbounded below along 1_C: no unique solution;
//! - a barrier on C: E is bounded below along 1_C iff s Σ_{i∈C} b_i > 0; if s Σ b < 0 it is
//!   unbounded, if Σ b = 0 (to round-off) the solution is not unique.
//!
//! **Marginal loads.** With a barrier, the sign of Σ_{i∈C} b_i decides between a solution and
//! none, and that sign belongs to the discretisation: two schemes (or two quadratures) give
//! discrete loads that differ by their consistency error, relative to Σ|b_i|. So where
//! ρ_C = |Σ_{i∈C} b_i| / Σ_{i∈C} |b_i| is below [`MARGINAL_LOAD_RATIO`], the conclusion
//! (solved, or refused as ill-posed) could change with the scheme or the mesh: [`analyse`]
//! reports C as a [`MarginalLoad`], which the driver keeps in the solution and the ill-posed
//! error names.
//!
//! In the well-posed case the monotony algorithm's first solve (A₀ = ∅) would still be singular
//! on C; [`analyse`] returns the constrained unknowns of such parts, which the driver puts in
//! the initial active set. Cost: one union–find pass over the local unknowns.

use crate::assembly::DiscreteSystem;
use crate::budget::{try_filled, try_vec};
use crate::mesh::SolveMesh;
use crate::solver::constraints::Constraints;
use std::fmt;

/// Below this ratio |Σ b| / Σ |b| of a part of the mesh without Dirichlet boundary, held by a
/// barrier, the sign of its total load (which decides whether the problem is well-posed) is
/// reported as depending on the discretisation ([`MarginalLoad`]). A perturbation of the load
/// of relative size ρ can flip that sign; 0.1 is larger than the consistency error of the
/// discrete loads of the coarse meshes users start from (a few per cent), so that a
/// conclusion that a finer mesh or another scheme could reverse is flagged.
pub const MARGINAL_LOAD_RATIO: f64 = 0.1;

/// A part of the mesh without Dirichlet boundary whose total discrete load nearly cancels, so
/// that whether the problem is well-posed there depends on the discretisation of the load.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MarginalLoad {
    /// A cell of the part (the first in the mesh's order).
    pub cell: usize,
    /// Σ b over the unknowns of the part.
    pub sum: f64,
    /// |Σ b| / Σ |b| over the unknowns of the part (below [`MARGINAL_LOAD_RATIO`]).
    pub ratio: f64,
}

impl fmt::Display for MarginalLoad {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "marginal load: on the part of the mesh containing cell {} (no Dirichlet \
             boundary), the discrete load sums to {:e}, only {:.3} of the sum of its absolute \
             values (below {MARGINAL_LOAD_RATIO}); whether the problem is well-posed there \
             depends on the sign of that sum, hence on the discretisation of the load (another \
             scheme or mesh may conclude otherwise)",
            self.cell, self.sum, self.ratio
        )
    }
}

/// What [`analyse`] found on a problem it accepts.
#[derive(Debug, Clone, Default)]
pub struct Analysis {
    /// The positions (in `cons.dofs`) of the constrained unknowns on parts of the mesh without
    /// Dirichlet unknowns (empty in the usual case).
    pub floating: Vec<usize>,
    /// The parts without Dirichlet unknowns whose load nearly cancels.
    pub marginal: Vec<MarginalLoad>,
}

/// Union–find with path halving.
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Checks the problem on `system` (see the module docs). Returns the floating constrained
/// unknowns and the marginal parts ([`Analysis`]), or a typed error saying why the problem is
/// ill-posed (naming the marginal load where there is one).
pub fn analyse<M: SolveMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    cons: Option<&Constraints>,
) -> crate::Result<Analysis> {
    let n = system.n_unknowns();
    let dm = &system.symbolic().dof_map;
    let what = "the connected parts of the mesh";
    let mut parent: Vec<usize> = try_vec(n, what)?;
    parent.extend(0..n);
    if let Some(m) = system.assembled() {
        // no dof map is kept: the unknowns are coupled by the nonzero entries of the assembled
        // matrix (the cells' couplings; a part the mesh joins to the rest by exactly zero
        // entries only is a part of the matrix, analysed as one)
        for r in 0..m.n_rows() {
            for &c in m.row(r).0.iter().take_while(|&&c| (c as usize) < r) {
                let (a, b) = (find(&mut parent, c as usize), find(&mut parent, r));
                if a != b {
                    parent[b] = a;
                }
            }
        }
    }
    for k in 0..dm.n_cells() {
        let (d, _) = dm.cell(k);
        if let Some((&first, rest)) = d.split_first() {
            let a = find(&mut parent, first as usize);
            for &x in rest {
                let b = find(&mut parent, x as usize);
                if a != b {
                    parent[b] = a;
                }
            }
        }
    }
    let mut root: Vec<usize> = try_vec(n, what)?;
    root.extend((0..n).map(|i| find(&mut parent, i)));
    drop(parent);
    let dir = system.dirichlet();
    let mut anchored = try_filled(n, false, what)?;
    let (mut sum_b, mut sum_abs) = (try_filled(n, 0.0f64, what)?, try_filled(n, 0.0f64, what)?);
    for i in 0..n {
        anchored[root[i]] |= dir.is_fixed(i);
        sum_b[root[i]] += system.load()[i];
        sum_abs[root[i]] += system.load()[i].abs();
    }
    let mut barred = try_filled(n, false, what)?;
    if let Some(c) = cons {
        for d in &c.dofs {
            barred[root[d.dof]] = true;
        }
    }
    let first_cell = |r: usize| {
        (0..dm.n_cells())
            .find(|&k| dm.cell(k).0.first().is_some_and(|&d| root[d as usize] == r))
            .unwrap_or(0)
    };
    let mut marginal = Vec::new();
    for r in (0..n).filter(|&i| root[i] == i && !anchored[i]) {
        let cell = first_cell(r);
        let part = format!("the part of the mesh containing cell {cell} has no Dirichlet boundary");
        let ratio = sum_b[r].abs() / sum_abs[r];
        let m = (sum_abs[r] > 0.0 && ratio < MARGINAL_LOAD_RATIO).then_some(MarginalLoad {
            cell,
            sum: sum_b[r],
            ratio,
        });
        let Some(c) = cons.filter(|_| barred[r]) else {
            return Err(crate::Error::IllPosed(format!(
                "{part} and no barrier: u is determined only up to an additive constant \
                 (give a Dirichlet part of the boundary)"
            )));
        };
        let s = c.side.sign();
        let (dir_t, bound) = if s > 0.0 {
            ("−∞", "upper")
        } else {
            ("+∞", "lower")
        };
        if !(s * sum_b[r] > 1e-12 * sum_abs[r]) {
            let why = if s * sum_b[r] < 0.0 {
                format!(
                    "the energy decreases without bound as t → {dir_t} along u + t·1 (Σ b = {:e} \
                     has the wrong sign for a {bound} barrier)",
                    sum_b[r]
                )
            } else {
                "the energy is constant along u + t·1 (Σ b = 0): the solution is not unique"
                    .to_string()
            };
            let note = m.map_or_else(String::new, |m| format!(" ({m})"));
            return Err(crate::Error::IllPosed(format!("{part}; {why}{note}")));
        }
        marginal.extend(m);
    }
    let floating = cons.map_or_else(Vec::new, |c| {
        (0..c.dofs.len())
            .filter(|&j| !anchored[root[c.dofs[j].dof]])
            .collect()
    });
    Ok(Analysis { floating, marginal })
}
