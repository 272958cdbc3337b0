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
use super::warm_start::{self, CoarseSolves, Prediction};
use crate::budget::MemoryBudget;
use crate::mesh::{PolyMesh, SolveMesh};
use crate::mesh3d::PolyMesh3;
use crate::problem::Problem;
use crate::scheme::GradientDiscretisation;
use crate::vi::Cancel;

/// A mesh the solve driver accepts (see the module docs).
pub trait SolverMesh<const D: usize>: SolveMesh<D> {
    /// What the coarse solves of the nested warm start hand to its prediction.
    type Coarse: Send;
    /// The coarse solves of the nested warm start of `problem` on this mesh, for a fine system
    /// of `unknowns` unknowns ([`warm_start::coarse_solves`]; `Some(Err(reason))`: they could
    /// not be made, the iteration starts cold and the report says why), or `None` if this mesh
    /// type has no nested start.
    fn coarse_solves(
        &self,
        unknowns: usize,
        problem: &Problem<D>,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Self::Coarse, String>>;
    /// The count of `scheme`'s unknowns by which the nested warm start sizes its first coarse
    /// level (the `unknowns` of [`Self::coarse_solves`];
    /// [`warm_start::FIRST_LEVEL_UNKNOWNS_PER_CELL`]): the skeleton unknowns on planar meshes,
    /// all of them on 3D ones.
    fn warm_start_unknowns(scheme: &dyn GradientDiscretisation<Self, D>) -> usize;
    /// The prediction of the active set of `cons` of `scheme` (on this mesh) from the coarse
    /// solves `coarse` ([`warm_start::predict_from`]).
    fn nested_prediction(
        coarse: Self::Coarse,
        scheme: &dyn GradientDiscretisation<Self, D>,
        problem: &Problem<D>,
        cons: &Constraints,
    ) -> Result<Prediction, String>;
}

impl SolverMesh<2> for PolyMesh {
    type Coarse = CoarseSolves<PolyMesh>;
    fn coarse_solves(
        &self,
        unknowns: usize,
        problem: &Problem,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Self::Coarse, String>> {
        Some(warm_start::coarse_solves(
            self, unknowns, problem, budget, cancel,
        ))
    }
    fn warm_start_unknowns(scheme: &dyn GradientDiscretisation) -> usize {
        scheme.n_skeleton()
    }
    fn nested_prediction(
        coarse: Self::Coarse,
        scheme: &dyn GradientDiscretisation,
        problem: &Problem,
        cons: &Constraints,
    ) -> Result<Prediction, String> {
        warm_start::predict_from(coarse, scheme, problem, cons)
    }
}

impl SolverMesh<3> for PolyMesh3 {
    type Coarse = CoarseSolves<PolyMesh3>;
    fn coarse_solves(
        &self,
        unknowns: usize,
        problem: &Problem<3>,
        budget: MemoryBudget,
        cancel: Option<&Cancel>,
    ) -> Option<Result<Self::Coarse, String>> {
        Some(warm_start::coarse_solves(
            self, unknowns, problem, budget, cancel,
        ))
    }
    fn warm_start_unknowns(scheme: &dyn GradientDiscretisation<PolyMesh3, 3>) -> usize {
        scheme.n_unknowns()
    }
    fn nested_prediction(
        coarse: Self::Coarse,
        scheme: &dyn GradientDiscretisation<PolyMesh3, 3>,
        problem: &Problem<3>,
        cons: &Constraints,
    ) -> Result<Prediction, String> {
        warm_start::predict_from(coarse, scheme, problem, cons)
    }
}

/// The error of a nested warm start asked for on a mesh type of dimension `d` that has none.
pub fn nested_start_unavailable(d: usize) -> crate::Error {
    crate::Error::InvalidData(format!(
        "the nested warm start is not available on this {d}D mesh type: solve with the cold \
         start (WarmStart::Cold, --warm-start cold)"
    ))
}
