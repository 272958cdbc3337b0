//! Global assembly with static condensation: a symbolic part built once per scheme, values
//! refilled per problem, and the state of consecutive solves held by the caller.
//!
//! - [`symbolic::SymbolicSystem`] (what depends only on the scheme): the unknowns of each cell,
//!   the pattern of the condensed (skeleton) matrix and its symbolic Cholesky factorisation,
//!   and the scatter maps. Share it (`Arc`) between problems posed on the same scheme, e.g.
//!   the four values of C of the paper's Test 3.
//! - [`values::ProblemValues`] (per problem): data evaluation, local matrices and loads,
//!   boundary conditions; for schemes without interior unknowns (P1, CR), the global matrix
//!   assembled once instead of the local matrices ([`assembled`]), each solve masking it.
//! - [`DiscreteSystem`] = both, immutable once built. [`DiscreteSystem::solve`] takes a set of
//!   *fixed* unknowns (Dirichlet unknowns are always fixed; the active-set solver adds active
//!   constrained unknowns) and
//!   1. condenses each cell ([`condense::condense`]): interior unknowns are eliminated, for HMM the cell
//!      value u_K (or nothing when the cell is active);
//!   2. assembles into the fixed pattern ([`gather`]); a fixed skeleton unknown keeps its row
//!      and column in the pattern with a unit diagonal and zeros elsewhere, its value moved to
//!      the right-hand side;
//!   3. refactorises numerically, or runs multigrid-preconditioned conjugate gradients
//!      ([`linear::LinearSolver`], [`iterative`]), and recovers the interior unknowns ([`solve`]).
//! - [`SolveState`] (per sequence of solves, owned by the caller and passed `&mut`): what one
//!   solve leaves for the next — the initial guess of the conjugate gradients, the multigrid
//!   hierarchy whose levels the next solve reuses, a screening solve to refine, the
//!   cell system, the direct solver built when the iterative one failed, and buffers. Two
//!   solves through fresh states give the same bits; reusing a state makes the next solve
//!   cheaper, never different beyond the solver tolerance. [`Solving`] pairs a system with a
//!   state as the [`crate::vi::QuadraticEnergy`] the algorithms minimise.
//!
//! Every type here is generic over the mesh `M` and the dimension `D` (defaults `PolyMesh`
//! and 2): the data evaluation reads the mesh through [`crate::mesh::SolveMesh<D>`] (cell
//! tags, boundary faces, their tags and centres), and nothing else depends on D. The scheme
//! stays a trait object; the solve paths are compiled once per mesh type used.
//!
//! When every local matrix couples each skeleton unknown with its cell's unknown only (HMM on
//! rectangles with a diagonal tensor, where it is the two-point flux scheme), the solves
//! (iterative and direct) eliminate the skeleton unknowns instead and solve on the cells
//! ([`two_point`]).
//!
//! The cell loops (local matrices, condensation, residual, recovery) run in parallel with
//! rayon; the global arrays are then *gathered* entry by entry (each entry of the condensed
//! matrix and each residual row knows its contributions, listed in cell order) instead of
//! scattered, so that the sums do not depend on the number of threads; the symbolic
//! factorisation runs beside the local matrices (after the pattern, when they are assembled
//! at once). Measurements: `replication/BENCHMARKS.md`.

pub mod assembled;
pub mod condense;
pub mod gather;
pub mod iterative;
pub mod linear;
pub use crate::offsets;
pub mod residual;
pub mod solve;
pub mod state;
pub mod symbolic;
pub mod two_point;
pub mod values;

#[cfg(test)]
mod tests_assembled;
#[cfg(test)]
mod tests_limits;

use crate::budget::MemoryBudget;
use crate::linalg::{FactorThreads, Ordering};
use crate::mesh::{PolyMesh, SolveMesh};
use crate::problem::Problem;
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::vi::FixedValues;
use condense::{CellSystem, SymMatrix};
pub use linear::{
    AUTO_ITERATIVE_MIN, AUTO_ITERATIVE_MIN_3D, ITERATIVE_MAX_ITER, ITERATIVE_RTOL, LinearSolver,
    PATCH_LAYERS, PATCH_LAYERS_3D, PATCH_MAX_FRACTION, REUSE_MAX_CHANGED, REUSE_MAX_CHANGED_3D,
    REUSE_MAX_CHANGED_UNPATCHED, REUSE_MAX_SLOWDOWN, SCREENING_REDUCTION, SCREENING_RTOL,
};
pub use state::{SolveState, Solving};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering as AtomicOrdering};
use std::time::Instant;
pub use symbolic::{DofMap, SymbolicSystem};
pub use values::ProblemValues;

/// Options of the symbolic system.
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemOptions {
    /// Fill-reducing ordering of the symbolic factorisation (default: AMD).
    pub ordering: Ordering,
    /// Threads of the numeric factorisations (default: one; see [`FactorThreads`]).
    pub factor_threads: FactorThreads,
    /// How the condensed systems are solved (default: chosen by size).
    pub linear: LinearSolver,
    /// The memory the assembly may take (default: the fixed [`MemoryBudget::DEFAULT`], so
    /// that the answer does not depend on the machine; the command line and Python pass
    /// [`MemoryBudget::available`]). The setup ([`DofMap::check_setup_memory`]) and the
    /// numeric factorisation are estimated against it before they allocate, and refused with
    /// [`Error::Linear`](crate::Error::Linear) giving the estimate if it does not fit.
    pub budget: MemoryBudget,
}

/// The identity of each [`DiscreteSystem`], so that a [`SolveState`] filled by one system is
/// never read by another (an identity, not solver state: it decides nothing a solve computes).
static NEXT_SYSTEM_ID: AtomicU64 = AtomicU64::new(1);

/// The assembled discrete problem (see the module docs): immutable once built; the solves
/// keep what they carry from one to the next in a [`SolveState`].
pub struct DiscreteSystem<'a, M = PolyMesh, const D: usize = 2>
where
    M: SolveMesh<D> + ?Sized,
{
    sym: Arc<SymbolicSystem<'a, M, D>>,
    values: ProblemValues<D>,
    n_skel: usize,
    n: usize,
    /// See [`NEXT_SYSTEM_ID`].
    id: u64,
    /// Time to build (data, local matrices, and the symbolic system when built here), seconds.
    pub setup_seconds: f64,
    /// The symbolic factorisation, seconds (0 when the symbolic system was given). With
    /// interior unknowns it runs beside the local matrices, so `setup_seconds −
    /// symbolic_seconds` is what it did not hide.
    pub symbolic_seconds: f64,
}

impl<'a, M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'a, M, D> {
    /// Builds the symbolic system of `scheme` and the values of `problem`, side by side (the
    /// values after the pattern when no cell has interior unknowns: they are assembled on it).
    pub fn new(
        scheme: &'a dyn GradientDiscretisation<M, D>,
        problem: &Problem<D>,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let dof_map = Arc::new(DofMap::new(scheme)?);
        dof_map.check_setup_memory(options.budget)?;
        // without interior unknowns the values are assembled on the pattern: after it
        if dof_map.n_int.iter().all(|&ni| ni == 0) {
            let mut sym = SymbolicSystem::with_dof_map(scheme, Arc::clone(&dof_map), options)?;
            let pattern = sym.kept_pattern("the assembly")?;
            let pattern = (pattern.col_ptr(), pattern.row_idx());
            let values = ProblemValues::evaluate_assembled(scheme, &dof_map, pattern, problem)?;
            drop(dof_map);
            // solved iteratively, the matrix is all the solves read
            sym.release_pattern();
            let mut s = Self::from_parts(Arc::new(sym), values);
            s.symbolic_seconds = s.sym.symbolic_seconds;
            s.setup_seconds = t0.elapsed().as_secs_f64();
            return Ok(s);
        }
        let (values, sym) = rayon::join(
            || ProblemValues::evaluate(scheme, &dof_map, problem),
            || SymbolicSystem::with_dof_map(scheme, Arc::clone(&dof_map), options),
        );
        drop(dof_map);
        let sym = Arc::new(sym?);
        let symbolic_seconds = sym.symbolic_seconds;
        let mut s = Self::from_parts(sym, values?);
        s.setup_seconds = t0.elapsed().as_secs_f64();
        s.symbolic_seconds = symbolic_seconds;
        Ok(s)
    }

    /// The values of `problem` on a symbolic system built before (and shared).
    pub fn with_symbolic(
        sym: Arc<SymbolicSystem<'a, M, D>>,
        problem: &Problem<D>,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let values = if sym.no_interior {
            // the symbolic system keeps no dof map for these schemes (see its docs)
            let dm = DofMap::new(sym.scheme())?;
            dm.check_setup_memory(sym.options.budget)?;
            let rebuilt;
            let pattern = match sym.pattern() {
                Some(p) => (p.col_ptr(), p.row_idx()),
                None => {
                    rebuilt = sym.rebuild_pattern(&dm)?;
                    (&rebuilt.0[..], &rebuilt.1[..])
                }
            };
            ProblemValues::evaluate_assembled(sym.scheme(), &dm, pattern, problem)?
        } else {
            ProblemValues::evaluate(sym.scheme(), &sym.dof_map, problem)?
        };
        let mut s = Self::from_parts(sym, values);
        s.setup_seconds = t0.elapsed().as_secs_f64();
        Ok(s)
    }

    fn from_parts(sym: Arc<SymbolicSystem<'a, M, D>>, values: ProblemValues<D>) -> Self {
        DiscreteSystem {
            n_skel: sym.n_condensed(),
            n: sym.n_unknowns(),
            sym,
            values,
            id: NEXT_SYSTEM_ID.fetch_add(1, AtomicOrdering::Relaxed),
            setup_seconds: 0.0,
            symbolic_seconds: 0.0,
        }
    }

    /// The symbolic system (shareable with other problems on the same scheme).
    pub fn symbolic(&self) -> &Arc<SymbolicSystem<'a, M, D>> {
        &self.sym
    }
    /// The scheme.
    pub fn scheme(&self) -> &'a dyn GradientDiscretisation<M, D> {
        self.sym.scheme()
    }
    /// Number of unknowns (skeleton and interior).
    pub fn n_unknowns(&self) -> usize {
        self.n
    }
    /// Size of the condensed system.
    pub fn n_condensed(&self) -> usize {
        self.n_skel
    }
    /// Stored entries of the condensed matrix (lower triangle).
    pub fn nnz(&self) -> usize {
        self.sym.nnz()
    }
    /// Stored values of the Cholesky factor of the condensed matrix (its fill).
    pub fn factor_len(&self) -> usize {
        self.sym.factor_len()
    }
    /// Dirichlet unknowns and their values (`None`: not Dirichlet).
    pub fn dirichlet(&self) -> &FixedValues {
        &self.values.dirichlet
    }
    /// The unknowns carrying the trace on Γ3, including those that are also Dirichlet unknowns
    /// (P1 vertices at Γ1 ∩ Γ3), which are never constrained but must satisfy the barrier.
    pub fn signorini_dofs(&self) -> &[PointDof<D>] {
        &self.values.signorini
    }
    /// The full load vector b.
    pub fn load(&self) -> &[f64] {
        &self.values.load
    }

    /// The local system of cell k: its unknowns, its number of interior unknowns, its local
    /// matrix and load (not kept for schemes without interior unknowns, whose global matrix
    /// is assembled instead: [`Self::assembled`]).
    #[inline]
    fn local(&self, k: usize) -> CellSystem<'_> {
        debug_assert!(self.values.assembled.is_none());
        let (d, ni) = self.sym.dof_map.cell(k);
        let r = self.sym.dof_map.dof_ptr.range(k);
        let v = &self.values;
        CellSystem {
            dofs: d,
            n_interior: ni,
            matrix: SymMatrix {
                n: d.len(),
                lower: &v.mats[v.mat_ptr.range(k)],
            },
            load: &v.loads[r],
        }
    }

    /// Empties `state` if it was filled by another system, and marks it as this one's.
    fn bind(&self, state: &mut SolveState) {
        if state.system != Some(self.id) {
            *state = SolveState {
                system: Some(self.id),
                ..Default::default()
            };
        }
    }

    /// This system paired with `state`: the [`crate::vi::QuadraticEnergy`] the algorithms
    /// minimise, its solves carrying what they learn in `state`.
    pub fn with_state<'s>(&'s self, state: &'s mut SolveState) -> Solving<'s, 'a, M, D> {
        self.bind(state);
        Solving {
            system: self,
            state,
        }
    }
}
