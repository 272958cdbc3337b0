//! The mesh types the solve driver accepts, and the warm start each offers.
//!
//! The driver ([`super::solve_problem`]) is written once for every dimension: it needs from a
//! mesh what assembly needs ([`SolveMesh`]), and a way to predict the initial active set when
//! [`WarmStart::Nested`](super::WarmStart::Nested) is asked for. That prediction
//! ([`super::warm_start`]) is written once for every mesh that can be agglomerated
//! ([`CoarseMesh`](super::coarse_mesh::CoarseMesh)): [`PolyMesh`] and [`PolyMesh3`] both offer
//! it. A mesh type without one returns `None`, and asking it for the nested start is then an
//! error ([`nested_start_unavailable`]), not a silent fallback.

use super::constraints::Constraints;
use super::warm_start::{self, Prediction};
use crate::budget::MemoryBudget;
use crate::mesh::{PolyMesh, SolveMesh};
use crate::mesh3d::PolyMesh3;
use crate::problem::Problem;
use crate::scheme::GradientDiscretisation;
use crate::vi::Cancel;

/// A mesh the solve driver accepts (see the module docs).
pub trait SolverMesh<const D: usize>: SolveMesh<D> {
    /// The nested warm start's prediction of the active set of `cons` for `problem` on
    /// `scheme` (`Some(Err(reason))`: no prediction could be made, the iteration starts cold
    /// and the report says why), or `None` if this mesh type has no nested start.
    fn nested_start(
        scheme: &dyn GradientDiscretisation<Self, D>,
        problem: &Problem<D>,
        cons: &Constraints,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Prediction, String>>;
}

impl SolverMesh<2> for PolyMesh {
    fn nested_start(
        scheme: &dyn GradientDiscretisation,
        problem: &Problem,
        cons: &Constraints,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Prediction, String>> {
        Some(warm_start::predict(scheme, problem, cons, budget, cancel))
    }
}

impl SolverMesh<3> for PolyMesh3 {
    fn nested_start(
        scheme: &dyn GradientDiscretisation<PolyMesh3, 3>,
        problem: &Problem<3>,
        cons: &Constraints,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Prediction, String>> {
        Some(warm_start::predict(scheme, problem, cons, budget, cancel))
    }
}

/// The error of a nested warm start asked for on a mesh type of dimension `d` that has none.
pub fn nested_start_unavailable(d: usize) -> crate::Error {
    crate::Error::InvalidData(format!(
        "the nested warm start is not available on this {d}D mesh type: solve with the cold \
         start (WarmStart::Cold, --warm-start cold)"
    ))
}
