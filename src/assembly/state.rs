//! What a sequence of solves of one [`DiscreteSystem`] carries from one solve to the next,
//! as a value the caller owns ([`SolveState`], passed `&mut`), and the pairing of a system with
//! a state as the energy the algorithms of [`crate::vi`] minimise ([`Solving`]).
//!
//! Nothing a solve returns depends on an earlier solve except through the state passed to it:
//! two solves through fresh states give bitwise the same result. Reusing a state gives the
//! iterative solver its previous solution as initial guess and the levels of its last
//! multigrid hierarchy (a cheaper solve, equal to the solver's tolerance), and keeps the
//! switch to the direct solver once the iterative one failed ([`super::LinearSolver::Auto`]).

use super::DiscreteSystem;
use super::iterative::KeptHierarchy;
use super::symbolic::Ragged;
use super::two_point::CellSystemAll;
use crate::linalg::{AmgWork, CholeskyWork, SpdPattern};
use crate::mesh::{PolyMesh, SolveMesh};
use crate::vi::FixedValues;
use crate::vi::{QuadraticEnergy, SolveTimings};
use std::sync::Arc;

/// The state carried between the solves of a [`DiscreteSystem`] (see the module docs). Start
/// with `SolveState::default()`; a state used with another system is emptied first, so it
/// never carries one system's data into another's solve.
#[derive(Default)]
pub struct SolveState {
    /// The system that filled it (`None`: fresh).
    pub(super) system: Option<u64>,
    /// Buffers of the condensation (blocks and loads), rewritten by every assembly.
    pub(super) scratch: (Vec<f64>, Vec<f64>),
    /// The gather sources of a system whose symbolic part has none (solved iteratively, see
    /// [`super::symbolic::ScatterMaps::src`]), built by the first solve that gathers the
    /// skeleton matrix.
    pub(super) sources: Option<Ragged<u32>>,
    /// The last skeleton solution, the initial guess of the next iterative solve.
    pub(super) last_solution: Vec<f64>,
    /// The cell values of the last solve, if it solved the cell system.
    pub(super) last_cells: Vec<f64>,
    /// The cell system (`Some(None)`: the local matrices do not allow it), built by the first
    /// solve.
    pub(super) cell_system: Option<Option<Arc<CellSystemAll>>>,
    /// The multigrid hierarchy of the last iterative solve.
    pub(super) kept: Option<KeptHierarchy>,
    /// The symbolic factorisation of the skeleton system built by the first direct solve
    /// that needs it (or why it could not be built): with [`super::LinearSolver::Auto`] when
    /// the iterative solver failed, or when the symbolic system deferred it
    /// ([`super::SymbolicSystem::is_direct`]).
    pub(super) direct_fallback: Option<Result<SpdPattern, String>>,
    /// The symbolic factorisation of the cell system, built by the first direct solve that
    /// takes it ([`super::two_point`]).
    pub(super) cell_direct: Option<SpdPattern>,
    /// The memory of the direct solver's numeric factorisations, reused from one to the next.
    pub(super) cholesky: CholeskyWork,
    /// The vectors of the multigrid cycles, reused from one iterative solve to the next.
    pub(super) amg: AmgWork,
}

impl SolveState {
    /// Frees what is kept from one solve to the next but the initial guess (the multigrid
    /// hierarchy and a screening solve), as the active-set iteration does when it ends.
    pub fn release(&mut self) {
        self.kept = None;
        self.amg = AmgWork::default();
    }

    /// The number of unknowns of the cell system ([`super::two_point`]: the cells, and the
    /// skeleton unknowns that could not be eliminated) if the solves through this state have
    /// taken it (`None` before any solve, and when too few skeleton unknowns can be
    /// eliminated).
    pub fn cell_system_size(&self) -> Option<usize> {
        self.cell_system.as_ref()?.as_ref().map(|c| c.n())
    }

    /// Of the [`Self::cell_system_size`] unknowns, the skeleton ones (not eliminated).
    pub fn cell_system_skeleton(&self) -> Option<usize> {
        self.cell_system.as_ref()?.as_ref().map(|c| c.n_kept())
    }

    /// Stored values of the Cholesky factors built here by the direct solves: the cell
    /// system's, and the skeleton system's when the symbolic system deferred it or the
    /// iterative solver failed (0 if none).
    pub fn factor_len(&self) -> usize {
        let skeleton = match &self.direct_fallback {
            Some(Ok(p)) => p.factor_len(),
            _ => 0,
        };
        skeleton + self.cell_direct.as_ref().map_or(0, SpdPattern::factor_len)
    }
}

/// A [`DiscreteSystem`] with the [`SolveState`] its solves go through: the
/// [`QuadraticEnergy`] of the algorithms ([`DiscreteSystem::with_state`]).
pub struct Solving<'s, 'a, M = PolyMesh, const D: usize = 2>
where
    M: SolveMesh<D> + ?Sized,
{
    /// The system.
    pub system: &'s DiscreteSystem<'a, M, D>,
    /// The state of its solves.
    pub state: &'s mut SolveState,
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> QuadraticEnergy for Solving<'_, '_, M, D> {
    fn n_unknowns(&self) -> usize {
        self.system.n_unknowns()
    }
    fn dirichlet(&self) -> &FixedValues {
        self.system.dirichlet()
    }
    fn load(&self) -> &[f64] {
        self.system.load()
    }
    fn minimise_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.system.solve(self.state, fixed)
    }
    fn screen_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.system.screen(self.state, fixed)
    }
    fn refine(&mut self, fixed: &FixedValues) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.system.refine(self.state, fixed)
    }
    fn polish(
        &mut self,
        fixed: &FixedValues,
        rtol: f64,
    ) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.system.polish(self.state, fixed, rtol)
    }
    fn release(&mut self) {
        self.state.release();
    }
    fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        self.system.residual(u)
    }
    fn residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        self.system.residual_at(u, len, row)
    }
    fn partial_values(&self, u: &[f64], at: &[usize]) -> crate::Result<Vec<f64>> {
        self.system.partial_values(self.state, u, at)
    }
    fn complete(&self, u: &mut [f64]) -> crate::Result<()> {
        self.system.complete_partial(self.state, u)
    }
    fn partial_residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        self.system.partial_residual_at(self.state, u, len, row)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.system.full_matrix_triplets()
    }
    fn row_entries(&self, rows: &[usize]) -> crate::Result<Option<Vec<(usize, usize, f64)>>> {
        self.system.row_entries(rows).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::{LinearSolver, SystemOptions};
    use crate::mesh::generate::{cartesian, cartesian_triangles};
    use crate::problem::paper_test3;
    use crate::scheme::{GradientDiscretisation, Hmm, P1};

    fn iterative() -> SystemOptions {
        SystemOptions {
            linear: LinearSolver::Iterative,
            ..Default::default()
        }
    }

    /// The unknowns below `k` fixed at 0.01.
    fn fixed(n: usize, k: usize) -> FixedValues {
        FixedValues::from_options((0..n).map(|i| (i < k).then_some(0.01))).unwrap()
    }

    fn bits(u: &[f64]) -> Vec<u64> {
        u.iter().map(|x| x.to_bits()).collect()
    }

    /// Whatever was solved before through other states, a solve through a fresh state gives
    /// the same bits; through a used state it reuses the hierarchy and agrees to the solver's
    /// tolerance. (With the state behind `&self`, the second fresh solve started from the
    /// first one's solution and hierarchy and differed in the last bits.)
    fn fresh_states_give_the_same_bits(scheme: &dyn GradientDiscretisation) {
        let p = paper_test3(-10.0);
        let sys = DiscreteSystem::new(scheme, &p, iterative()).unwrap();
        let n = sys.n_unknowns();
        // as many changes of status as a hierarchy may see and still be reused, patched or not
        // (with more, up to REUSE_MAX_CHANGED, only if its patch is small enough: not on
        // meshes this small)
        let changes = (crate::assembly::REUSE_MAX_CHANGED_UNPATCHED * n as f64).ceil() as usize;
        assert!(changes >= 1, "{n} unknowns");
        let (a, b) = (fixed(n, n / 2), fixed(n, n / 2 + changes));
        let (first, _) = sys.solve(&mut SolveState::default(), &b).unwrap();
        let mut used = SolveState::default();
        sys.solve(&mut used, &a).unwrap();
        let (again, t) = sys.solve(&mut used, &b).unwrap();
        assert!(
            t.reused,
            "{}: the used state's hierarchy is reused",
            scheme.name()
        );
        let (fresh, t) = sys.solve(&mut SolveState::default(), &b).unwrap();
        assert!(!t.reused);
        assert_eq!(bits(&first), bits(&fresh), "{}", scheme.name());
        let gap = again
            .iter()
            .zip(&fresh)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap < 1e-9, "{}: {gap:e}", scheme.name());
        assert_ne!(bits(&again), bits(&fresh), "the reuse is seen in the bits");
    }

    #[test]
    fn solves_through_fresh_states_are_bitwise_equal() {
        // HMM on squares solves on the cells, P1 on the skeleton
        let squares = cartesian(40, 40).unwrap();
        fresh_states_give_the_same_bits(&Hmm::new(&squares));
        let tri = cartesian_triangles(40, 40, [0.0, 1.0], [0.0, 1.0]).unwrap();
        fresh_states_give_the_same_bits(&P1::new(&tri).unwrap());
    }

    /// A state filled by one system is emptied before another system's solve: the result is
    /// that of a fresh state, bit for bit, and nothing of the first system is reused.
    #[test]
    fn a_state_never_carries_one_systems_data_into_another() {
        let tri = cartesian_triangles(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let p1 = P1::new(&tri).unwrap();
        let x = DiscreteSystem::new(&p1, &paper_test3(-10.0), iterative()).unwrap();
        let y = DiscreteSystem::new(&p1, &paper_test3(-20.0), iterative()).unwrap();
        let f = fixed(x.n_unknowns(), x.n_unknowns() / 2);
        let mut state = SolveState::default();
        x.solve(&mut state, &f).unwrap();
        assert!(state.kept.is_some());
        let (u, t) = y.solve(&mut state, &f).unwrap();
        assert!(!t.reused);
        let (fresh, _) = y.solve(&mut SolveState::default(), &f).unwrap();
        assert_eq!(bits(&u), bits(&fresh));
        // and `release` frees the hierarchy but keeps the guess
        state.release();
        assert!(state.kept.is_none() && !state.last_solution.is_empty());
    }

    /// A system solved iteratively has no gather sources until a solve gathers the skeleton
    /// matrix: HMM on squares solves on the cells and never builds them; on triangles (no
    /// cell system) the first assembly builds them into the state, and the condensed matrix
    /// and right-hand side are those of the system built for direct solves (sources built with
    /// the symbolic part), bit for bit.
    #[test]
    fn the_gather_sources_are_built_by_the_first_gather() {
        let p = paper_test3(-10.0);
        let squares = cartesian(16, 16).unwrap();
        let hmm = Hmm::new(&squares);
        let sys = DiscreteSystem::new(&hmm, &p, iterative()).unwrap();
        assert!(sys.sym.maps.src.is_none());
        let mut state = SolveState::default();
        sys.solve(&mut state, &FixedValues::free(sys.n_unknowns()).unwrap())
            .unwrap();
        assert!(state.cell_system_size().is_some() && state.sources.is_none());

        let tri = cartesian_triangles(12, 12, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let hmm = Hmm::new(&tri);
        let it = DiscreteSystem::new(&hmm, &p, iterative()).unwrap();
        let direct = SystemOptions {
            linear: LinearSolver::Direct,
            ..Default::default()
        };
        let di = DiscreteSystem::new(&hmm, &p, direct).unwrap();
        assert!(it.sym.maps.src.is_none() && di.sym.maps.src.is_some());
        let f = fixed(it.n_unknowns(), it.n_unknowns() / 3);
        let mut state = SolveState::default();
        let (a, b) = it.assemble_condensed(&mut state, &f).unwrap();
        assert!(state.sources.is_some());
        let mut other = SolveState::default();
        let (c, d) = di.assemble_condensed(&mut other, &f).unwrap();
        assert!(other.sources.is_none());
        assert_eq!((bits(&a), bits(&b)), (bits(&c), bits(&d)));
        // the solves through the state agree with the direct ones
        let (u, _) = it.solve(&mut state, &f).unwrap();
        let (v, _) = di.solve(&mut other, &f).unwrap();
        let gap = u
            .iter()
            .zip(&v)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(gap < 1e-8, "{gap:e}");
    }

    /// A direct solve on two-point local matrices (HMM on squares with a heterogeneous
    /// diagonal tensor) takes the cell system: it gives the skeleton system's direct solution
    /// to round-off, for two sets of fixed cells through one state (whose symbolic
    /// factorisation of the cell system is made once); a solve that fixes an eliminated face
    /// takes the skeleton system, bit for bit its direct solve.
    #[test]
    fn direct_solves_take_the_cell_system() {
        let squares = cartesian(24, 24).unwrap();
        let hmm = Hmm::new(&squares);
        let p =
            paper_test3(-10.0).with_diffusion(Box::new(|x| [[1.0 + x[0], 0.0], [0.0, 0.3 + x[1]]]));
        let direct = SystemOptions {
            linear: LinearSolver::Direct,
            ..Default::default()
        };
        let sys = DiscreteSystem::new(&hmm, &p, direct).unwrap();
        let (n, skel) = (sys.n_unknowns(), sys.n_skel);
        // the skeleton system, assembled and factorised as the direct solves did before
        let on_skeleton = |f: &FixedValues| {
            let mut other = SolveState::default();
            let (values, mut rhs) = sys.assemble_condensed(&mut other, f).unwrap();
            sys.solve_direct(&mut other, &values, &mut rhs).unwrap();
            sys.complete(f, rhs).unwrap()
        };
        let mut state = SolveState::default();
        for m in [3, 5] {
            let f = FixedValues::from_options(
                (0..n).map(|i| (i >= skel && (i - skel) % m == 0).then_some(0.01)),
            )
            .unwrap();
            let (u, t) = sys.solve(&mut state, &f).unwrap();
            assert_eq!((t.krylov, t.inexact), (0, false));
            let v = on_skeleton(&f);
            let scale = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let gap = u
                .iter()
                .zip(&v)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(scale > 1e-3 && gap <= 1e-12 * scale, "{gap:e} of {scale}");
            assert_ne!(bits(&u), bits(&v), "solved on another system");
        }
        assert_eq!(state.cell_system_size(), Some(squares.n_cells()));
        let pattern = state.cell_direct.as_ref().unwrap().col_ptr().as_ptr();
        sys.solve(&mut state, &FixedValues::free(n).unwrap())
            .unwrap();
        assert_eq!(
            state.cell_direct.as_ref().unwrap().col_ptr().as_ptr(),
            pattern
        );
        // an interior face fixed: not eliminated in this solve
        let face = (0..skel).find(|&s| !sys.dirichlet().is_fixed(s)).unwrap();
        let f = FixedValues::from_options((0..n).map(|i| (i == face).then_some(0.01))).unwrap();
        let (u, _) = sys.solve(&mut state, &f).unwrap();
        assert_eq!(bits(&u), bits(&on_skeleton(&f)));
    }

    /// The cell system is reported by the state that built it.
    #[test]
    fn the_cell_system_belongs_to_the_state() {
        let squares = cartesian(16, 16).unwrap();
        let hmm = Hmm::new(&squares);
        let sys = DiscreteSystem::new(&hmm, &paper_test3(-10.0), iterative()).unwrap();
        let mut state = SolveState::default();
        assert_eq!(state.cell_system_size(), None);
        sys.solve(&mut state, &FixedValues::free(sys.n_unknowns()).unwrap())
            .unwrap();
        assert_eq!(state.cell_system_size(), Some(squares.n_cells()));
        assert_eq!(state.cell_system_skeleton(), Some(0));
        assert_eq!(SolveState::default().cell_system_size(), None);
    }
}
