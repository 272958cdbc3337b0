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
//! In the well-posed case the monotony algorithm's first solve (A₀ = ∅) would still be singular
//! on C; [`analyse`] returns the constrained unknowns of such parts, which the driver puts in
//! the initial active set. Cost: one union–find pass over the local unknowns.

use crate::assembly::DiscreteSystem;
use crate::mesh::SolveMesh;
use crate::solver::constraints::Constraints;

/// Union–find with path halving.
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Checks the problem on `system` (see the module docs). Returns the positions (in
/// `cons.dofs`) of the constrained unknowns lying on parts of the mesh without Dirichlet
/// unknowns (empty in the usual case), or a typed error saying why the problem is ill-posed.
pub fn analyse<M: SolveMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    cons: Option<&Constraints<D>>,
) -> crate::Result<Vec<usize>> {
    let n = system.n_unknowns();
    let dm = &system.symbolic().dof_map;
    let mut parent: Vec<usize> = (0..n).collect();
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
    let root: Vec<usize> = (0..n).map(|i| find(&mut parent, i)).collect();
    let dir = system.dirichlet();
    let mut anchored = vec![false; n];
    let (mut sum_b, mut sum_abs) = (vec![0.0f64; n], vec![0.0f64; n]);
    for i in 0..n {
        anchored[root[i]] |= dir[i].is_some();
        sum_b[root[i]] += system.load()[i];
        sum_abs[root[i]] += system.load()[i].abs();
    }
    let mut barred = vec![false; n];
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
    for r in (0..n).filter(|&i| root[i] == i && !anchored[i]) {
        let part = format!(
            "the part of the mesh containing cell {} has no Dirichlet boundary",
            first_cell(r)
        );
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
            return Err(crate::Error::IllPosed(format!("{part}; {why}")));
        }
    }
    Ok(cons.map_or_else(Vec::new, |c| {
        (0..c.dofs.len())
            .filter(|&j| !anchored[root[c.dofs[j].dof]])
            .collect()
    }))
}
