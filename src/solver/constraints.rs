//! The barrier of a problem on the unknowns of a discrete system: which unknowns carry it
//! (the scheme's obstacle unknowns, or the trace unknowns on Γ3), its values there (g(x_K),
//! a(x_σ), nodal values), and the check that the discrete convex set is not empty.

use crate::assembly::DiscreteSystem;
use crate::problem::{ConstraintKind, Problem, check_finite};
use crate::scheme::PointDof;
use crate::vi::Constraints;

/// Builds the barrier of `problem` on the unknowns of the system, checking the data and the
/// non-emptiness of the discrete convex set.
pub fn build(system: &DiscreteSystem, problem: &Problem) -> crate::Result<Option<Constraints>> {
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
