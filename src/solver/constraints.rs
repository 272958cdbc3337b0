//! The barrier of a problem on the unknowns of a discrete system: which unknowns carry it
//! (the scheme's obstacle unknowns, or the trace unknowns on Γ3), its values there (g(x_K),
//! a(x_σ), nodal values), and the check that the discrete convex set is not empty.

use crate::assembly::DiscreteSystem;
use crate::budget::{try_copy, try_filled, try_vec};
use crate::mesh::SolveMesh;
use crate::problem::{ConstraintKind, Problem, check_finite_at};
use crate::scheme::PointDof;
use crate::vi::ConstrainedDof;
use rayon::prelude::*;

/// The barrier of a problem on the unknowns of a discrete system: the algorithms' constraints
/// ([`crate::vi::Constraints`]): for each constrained unknown its index, its measure and the
/// barrier there, 24 bytes. The point where the barrier was evaluated is the scheme's
/// ([`GradientDiscretisation::dof_point`](crate::scheme::GradientDiscretisation::dof_point)),
/// computed where it is read (the warm start, the post-processing), not stored: 16 bytes per
/// constrained unknown less.
pub type Constraints = crate::vi::Constraints;

/// Builds the barrier of `problem` on the unknowns of the system, checking the data and the
/// non-emptiness of the discrete convex set.
pub fn build<M: SolveMesh<D> + ?Sized, const D: usize>(
    system: &DiscreteSystem<M, D>,
    problem: &Problem<D>,
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
                    "a Signorini barrier is given but no boundary face is of Signorini type".into(),
                ));
            }
            try_copy(system.signorini_dofs(), "the Signorini unknowns")?
        }
    };
    // barrier versus Dirichlet data: the convex set must not be empty. Obstacle: every
    // Dirichlet trace unknown (u_D must satisfy the barrier on ∂Ω); Signorini: the Dirichlet
    // unknowns that also carry the trace on Γ3.
    let mut tr = Vec::new();
    let mut checks: Vec<PointDof<D>> = Vec::new();
    match c.kind {
        ConstraintKind::Obstacle => {
            for i in 0..mesh.n_boundary_faces() {
                let e = mesh.boundary_face(i);
                scheme.face_trace_dofs(e, &mut tr);
                checks.extend(tr.iter().filter(|t| dir.is_fixed(t.dof)));
            }
        }
        ConstraintKind::Signorini => {
            checks.extend(candidates.iter().filter(|t| dir.is_fixed(t.dof)));
        }
    }
    for t in &checks {
        let v = dir.get(t.dof).unwrap_or(0.0);
        let g = check_finite_at((c.barrier)(t.point), || {
            format!("the barrier at {:?}", t.point)
        })?;
        if s * (v - g) > 1e-12 * (1.0 + g.abs()) {
            return Err(crate::Error::Infeasible(format!(
                "the Dirichlet value {v} at {:?} is {} the barrier {g}: the discrete convex set is empty",
                t.point,
                if s > 0.0 { "above" } else { "below" }
            )));
        }
    }
    // the barrier at the unknowns off the Dirichlet boundary, evaluated in parallel; the first
    // non-finite value in their order is reported
    // filtered in place: no second array of the candidates (32 bytes each in 2D)
    let mut dofs = candidates;
    dofs.retain(|pd| !dir.is_fixed(pd.dof));
    let mut barrier = try_filled(dofs.len(), 0.0, "the barrier at the constrained unknowns")?;
    barrier
        .par_iter_mut()
        .zip(&dofs)
        .with_min_len(4096)
        .for_each(|(g, pd)| *g = (c.barrier)(pd.point));
    for (pd, &g) in dofs.iter().zip(&barrier) {
        check_finite_at(g, || format!("the barrier at {:?}", pd.point))?;
    }
    let mut constrained = try_vec(dofs.len(), "the constrained unknowns")?;
    constrained.extend(dofs.into_iter().map(|pd| ConstrainedDof {
        dof: pd.dof,
        point: (),
        measure: pd.measure,
    }));
    let dofs = constrained;
    Ok(Some(Constraints {
        dofs,
        barrier,
        side: c.side,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Point;
    use crate::problem::Side;

    /// The barrier is evaluated at every constrained unknown; the first non-finite value (in
    /// the unknowns' order) is an error naming its point, a finite barrier gives one value per
    /// unknown off the Dirichlet boundary.
    #[test]
    fn barrier_values_and_the_first_non_finite_one() {
        let mesh = crate::mesh::generate::cartesian(8, 8).unwrap();
        let scheme = crate::scheme::Hmm::new(&mesh);
        let system = |p: &Problem| DiscreteSystem::new(&scheme, p, Default::default()).unwrap();
        let base = || crate::problem::paper_test3(-5.0);
        let p = base().with_constraint(
            ConstraintKind::Obstacle,
            Side::Upper,
            Box::new(|x: Point| x[0] + 2.0 * x[1]),
        );
        let c = build(&system(&p), &p).unwrap().unwrap();
        assert_eq!(c.dofs.len(), mesh.n_cells());
        for (pd, &g) in c.dofs.iter().zip(&c.barrier) {
            let k = pd.dof - mesh.n_edges();
            assert_eq!(g, mesh.centroid(k)[0] + 2.0 * mesh.centroid(k)[1]);
        }
        // NaN on the boundary: found by the check against the Dirichlet data
        let p = base().with_constraint(
            ConstraintKind::Obstacle,
            Side::Upper,
            Box::new(|x: Point| (0.5 - x[0]).sqrt()),
        );
        let e = build(&system(&p), &p).unwrap_err().to_string();
        assert!(e.contains("the barrier at [0.5625, 0.0] is NaN"), "{e}");
        // NaN inside (0.3, 0.7)² only: the first cell there, in cell order, is named
        let p = base().with_constraint(
            ConstraintKind::Obstacle,
            Side::Upper,
            Box::new(|x: Point| {
                if (x[0] - 0.5).abs() < 0.2 && (x[1] - 0.5).abs() < 0.2 {
                    f64::NAN
                } else {
                    1.0
                }
            }),
        );
        let e = build(&system(&p), &p).unwrap_err().to_string();
        assert!(e.contains("the barrier at [0.3125, 0.3125] is NaN"), "{e}");
    }
}
