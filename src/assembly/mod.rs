//! Global assembly with static condensation: a symbolic part built once per scheme, and
//! values refilled per problem and per active set.
//!
//! - [`symbolic::SymbolicSystem`] (what depends only on the scheme): the unknowns of each cell,
//!   the pattern of the condensed (skeleton) matrix and its symbolic Cholesky factorisation,
//!   and the scatter maps. Share it (`Arc`) between problems posed on the same scheme, e.g.
//!   the four values of C of the paper's Test 3.
//! - [`values::ProblemValues`] (per problem): data evaluation, local matrices and loads,
//!   boundary conditions.
//! - [`DiscreteSystem`] = both; [`DiscreteSystem::solve`] takes a set of *fixed* unknowns
//!   (Dirichlet unknowns are always fixed; the active-set solver adds active constrained
//!   unknowns) and
//!   1. condenses each cell ([`condense()`]): interior unknowns are eliminated, for HMM the cell
//!      value u_K (or nothing when the cell is active);
//!   2. assembles into the fixed pattern; a fixed skeleton unknown keeps its row and column in
//!      the pattern with a unit diagonal and zeros elsewhere, its value moved to the right-hand
//!      side;
//!   3. refactorises numerically, solves, and recovers the interior unknowns.
//!
//! When every local matrix couples each skeleton unknown with its cell's unknown only (HMM on
//! rectangles with a diagonal tensor, where it is the two-point flux scheme), the iterative
//! solves eliminate the skeleton unknowns instead and solve on the cells ([`two_point`]):
//! on ex9 at 1024² cells, 1M cell unknowns with 5 entries per row instead of 2.1M face
//! unknowns with 7.
//!
//! Performance (see `replication/BENCHMARKS.md`): the cell loops (local matrices,
//! condensation, residual, recovery) run in parallel with rayon; the global arrays are then
//! *gathered* entry by entry (each entry of the condensed matrix and each residual row knows
//! its contributions, listed in cell order) instead of scattered, so that the sums do not
//! depend on the number of threads; the symbolic factorisation runs beside the local
//! matrices; the buffers of the condensation, of the residual and of the Cholesky factor are
//! kept between solves.

pub mod condense;
pub mod offsets;
pub mod symbolic;
pub mod two_point;
pub mod values;

use crate::linalg::{FactorThreads, Ordering, SpdPattern};
use crate::problem::Problem;
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::vi::{QuadraticEnergy, SolveTimings};
use condense::{CellSystem, SymMatrix, condense, interior_value, recover_interior};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::Instant;
pub use symbolic::{DofMap, SymbolicSystem};
pub use values::ProblemValues;

/// Cells per parallel task in the cell loops (large enough to amortise the task, small enough
/// to balance two or more threads).
const CHUNK: usize = 4096;

/// The cell ranges `[c0, c1)` of the parallel tasks.
fn cell_chunks(nc: usize) -> Vec<(usize, usize)> {
    chunks(nc, CHUNK)
}

/// The ranges `[c0, c1)` of `size` consecutive indices (the last one shorter) covering `0..n`.
fn chunks(n: usize, size: usize) -> Vec<(usize, usize)> {
    (0..n.div_ceil(size))
        .map(|c| (c * size, ((c + 1) * size).min(n)))
        .collect()
}

/// Splits a buffer laid out by the offsets `ptr` (entity e owns `ptr(e)..ptr(e + 1)`, relative to
/// `ptr(ranges[0].0)`) into the consecutive slices of the entity `ranges`, so that each
/// parallel task writes its own slice.
fn split_by_ranges<'b, T>(
    mut buf: &'b mut [T],
    ranges: &[(usize, usize)],
    ptr: impl Fn(usize) -> usize,
) -> Vec<&'b mut [T]> {
    let mut slices = Vec::with_capacity(ranges.len());
    for &(c0, c1) in ranges {
        let (here, next) = std::mem::take(&mut buf).split_at_mut(ptr(c1) - ptr(c0));
        buf = next;
        slices.push(here);
    }
    slices
}

/// The position of unknown `g` among the unknowns `d` of a cell where it appears.
#[inline]
fn local_index(d: &[u32], g: usize) -> usize {
    d.iter().position(|&x| x as usize == g).unwrap_or(0)
}

/// The value of each fixed unknown (Dirichlet, or fixed by the caller), NaN for a free one
/// (the data and the barriers are finite).
struct FixedValues(Vec<f64>);

impl FixedValues {
    fn new(dirichlet: &[Option<f64>], fixed: &[Option<f64>]) -> Self {
        FixedValues(
            (0..dirichlet.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|d| dirichlet[d].or(fixed[d]).unwrap_or(f64::NAN))
                .collect(),
        )
    }
    /// The value of unknown `d` if it is fixed.
    fn get(&self, d: usize) -> Option<f64> {
        let v = self.0[d];
        if v.is_nan() { None } else { Some(v) }
    }
}

/// Options of the symbolic system.
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemOptions {
    /// Fill-reducing ordering of the symbolic factorisation (default: AMD).
    pub ordering: Ordering,
    /// Threads of the numeric factorisations (default: one; see [`FactorThreads`]).
    pub factor_threads: FactorThreads,
    /// How the condensed systems are solved (default: chosen by size).
    pub linear: LinearSolver,
}

/// How the condensed systems S u = c are solved.
///
/// - **Direct**: sparse Cholesky (faer), symbolic factorisation once, numeric factorisation
///   per solve ([`crate::linalg::cholesky`]). Exact to round-off; its fill grows like
///   N log N and its time like N^1.5 on 2D meshes.
/// - **Iterative**: conjugate gradients preconditioned by smoothed-aggregation algebraic
///   multigrid ([`crate::linalg::amg`], [`mod@crate::linalg::pcg`]), the hierarchy rebuilt for
///   each active set, started from the previous solution, to a relative residual of
///   [`ITERATIVE_RTOL`]; memory O(N). The active-set solver screens with solves to
///   [`SCREENING_RTOL`] and refines the last one ([`DiscreteSystem::screen`],
///   [`DiscreteSystem::refine`]): on ex9 at 1M unknowns the same active sets with 22 CG
///   iterations instead of 45, the conjugate gradients' time 1.85 s → 0.93 s. (Measured and
///   rejected: a looser screening tolerance, as inexact Newton methods use, took more
///   active-set steps, each with its multigrid setup — 11.2 s against 9.5 s on ex9 at 1M
///   unknowns in an earlier version; keeping the hierarchy of one active set as the
///   preconditioner of the next ones took 4–8 times more CG iterations.) The certificate of
///   the final solution is computed the same way as for the direct solver, from the full
///   system.
/// - **Auto** (the default): iterative from [`AUTO_ITERATIVE_MIN`] condensed unknowns on,
///   direct below (the crossover measured by `make bench`); if the conjugate gradients fail
///   (smoothed aggregation converges slowly on strongly distorted meshes with rotated
///   anisotropy), the direct solver takes over for that solve and the following ones.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolver {
    /// Direct below [`AUTO_ITERATIVE_MIN`] condensed unknowns, iterative from there on.
    #[default]
    Auto,
    /// Sparse Cholesky.
    Direct,
    /// Multigrid-preconditioned conjugate gradients.
    Iterative,
}

impl std::str::FromStr for LinearSolver {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "auto" => Ok(LinearSolver::Auto),
            "direct" => Ok(LinearSolver::Direct),
            "iterative" => Ok(LinearSolver::Iterative),
            _ => Err(crate::Error::InvalidData(format!(
                "unknown linear solver '{s}' (expected auto, direct or iterative)"
            ))),
        }
    }
}

impl std::fmt::Display for LinearSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinearSolver::Auto => "auto",
            LinearSolver::Direct => "direct",
            LinearSolver::Iterative => "iterative",
        })
    }
}

/// Cholesky factorisation of the condensed matrix (`values` on `pattern`) and solve of
/// S x = c in place (`rhs`); returns when the factorisation ended, 0 Krylov iterations, and
/// that the solve is exact.
fn solve_directly(
    pattern: &SpdPattern,
    values: &[f64],
    rhs: &mut [f64],
) -> crate::Result<(Instant, PcgOutcome)> {
    let factor = pattern.factor(values)?;
    let t2 = Instant::now();
    factor.solve_in_place(rhs);
    Ok((t2, PcgOutcome::default()))
}

/// [`LinearSolver::Auto`] solves iteratively from this many condensed unknowns on.
pub const AUTO_ITERATIVE_MIN: usize = 250_000;

/// Relative residual ‖c − S u‖₂ ≤ ITERATIVE_RTOL ‖c‖₂ at which the conjugate gradients stop.
pub const ITERATIVE_RTOL: f64 = 1e-12;

/// Iteration cap of the conjugate gradients (multigrid keeps them in the tens).
pub const ITERATIVE_MAX_ITER: usize = 1000;

/// A screening solve ([`DiscreteSystem::screen`]) of the active-set iteration stops once its
/// residual is below SCREENING_RTOL ‖c‖ *and* below [`SCREENING_REDUCTION`] times the residual
/// it started from: accurate enough to decide the next active set, the last solve then
/// refined to [`ITERATIVE_RTOL`] ([`DiscreteSystem::refine`]). Measured on ex9 with P1 at 1M
/// unknowns (the prediction's 96549 active unknowns, then 101624, 101055, 100787, 100757,
/// without look-ahead): 10⁻⁶ ‖c‖ alone misjudged 5 unknowns, freed in the fourth solve and
/// taken back in a sixth; 10⁻⁸ and 10⁻¹⁰ gave the active sets of full solves, with 7, 3, 3,
/// 3, 1 and 10, 6, 6, 5, 3 CG iterations against 13, 9, 9, 8, 6 to 10⁻¹².
pub const SCREENING_RTOL: f64 = 1e-8;

/// The reduction of its initial residual a screening solve must reach besides
/// [`SCREENING_RTOL`]. After a change of the active set, the previous solution already meets
/// 10⁻⁸ ‖c‖ (the change is local, ‖c‖ holds all the data), so that bound alone let solves stop
/// after 0 CG iterations, on the previous solution, and misjudge the unknowns near the
/// change: ex9 took 5 HMM solves at 2048² cells (+12/−6, +5/−27 after the third) and 6 P1
/// solves at 4097² nodes (+392/−4, +4/−390). With a reduction of 10⁻⁴ they take 3 and 4
/// (10⁻³ measured the same on HMM).
pub const SCREENING_REDUCTION: f64 = 1e-4;

/// Consecutive iterative solves of a [`DiscreteSystem`] share their multigrid hierarchy's
/// coarse levels. The active-set iteration changes the condensed matrix only in the rows and
/// columns of the unknowns whose status changed, and after the first solves these are few:
/// the coarse levels built for an earlier matrix (the fine level and its smoother always take
/// the new matrix, [`crate::linalg::CoarseHierarchy`]) precondition the new one about as well,
/// and save a whole setup. A hierarchy is reused only if at most [`REUSE_MAX_CHANGED`] of
/// the unknowns changed status since the matrix it was built for, and while conjugate
/// gradients with it converge at most this factor slower (in mean residual reduction per
/// iteration) than with it fresh; otherwise the next solve builds a new one.
pub const REUSE_MAX_SLOWDOWN: f64 = 3.0;

/// The largest fraction of the unknowns that may have changed status (fixed or free) since
/// the matrix a hierarchy was built for, for it to be reused ([`REUSE_MAX_SLOWDOWN`]).
/// Measured on ex9 at 1M unknowns (2 cores): a P1 hierarchy reused after 0.48% of the
/// unknowns changed needed 10 CG iterations where a new one needed 5, and 14 instead of 7 in
/// the next solve; an HMM hierarchy after 0.043% needed 8, as a new one did, and saved 1 s of
/// setup per solve. The unknowns freed since, in particular, were decoupled (unit rows) in
/// the matrix the coarse levels were built from, and have no coarse basis function.
pub const REUSE_MAX_CHANGED: f64 = 1e-3;

/// The multigrid hierarchy of the last iterative solve, kept until the next solve: to continue
/// that solve ([`DiscreteSystem::refine`]) when it was a screening solve that stopped early,
/// and to precondition the next solve's matrix.
struct KeptHierarchy {
    /// The hierarchy (it owns the condensed matrix of that solve).
    amg: crate::linalg::Amg<'static>,
    /// For a screening solve that stopped early: the right-hand side c of S x = c and the
    /// [`fingerprint`] of the fixed unknowns.
    screened: Option<(Vec<f64>, u64)>,
    /// ln of the mean residual reduction per CG iteration of the first solve with this
    /// hierarchy (negative; `None` if it took no iteration).
    fresh_rate: Option<f64>,
    /// The last solve with it converged more than [`REUSE_MAX_SLOWDOWN`] times slower than
    /// that: build a fresh hierarchy for the next solve.
    stale: bool,
    /// The fixed unknowns (Dirichlet or fixed by the caller) of the matrix it was built for,
    /// one bit per unknown.
    fixed_mask: Vec<u64>,
    /// Built for the cell system ([`two_point`]), not the skeleton one.
    cells: bool,
}

/// One bit per unknown: set where the unknown is fixed (Dirichlet, or by `fixed`).
fn fixed_mask(dirichlet: &[Option<f64>], fixed: &[Option<f64>]) -> Vec<u64> {
    let mut mask = vec![0u64; dirichlet.len().div_ceil(64)];
    for (i, (d, f)) in dirichlet.iter().zip(fixed).enumerate() {
        if d.is_some() || f.is_some() {
            mask[i / 64] |= 1 << (i % 64);
        }
    }
    mask
}

/// Where the hierarchy of the next iterative solve comes from.
enum NextHierarchy {
    /// The coarse levels of the last one, with its [`KeptHierarchy::fresh_rate`] and
    /// [`KeptHierarchy::fixed_mask`].
    Reuse {
        coarse: crate::linalg::CoarseHierarchy,
        fresh_rate: Option<f64>,
        built_for: Vec<u64>,
    },
    /// A new one, for the matrix with these fixed unknowns.
    New { fixed_mask: Vec<u64> },
}

/// A multigrid hierarchy in use: new, or the coarse levels of an earlier one.
struct Hierarchy {
    amg: crate::linalg::Amg<'static>,
    /// See [`KeptHierarchy::fresh_rate`].
    fresh_rate: Option<f64>,
    /// Built for an earlier matrix (its coarse levels).
    reused: bool,
    /// See [`KeptHierarchy::fixed_mask`].
    fixed_mask: Vec<u64>,
    /// See [`KeptHierarchy::cells`].
    cells: bool,
}

/// The multigrid hierarchy for the matrix `a` (of the cell system if `cells`), as `next` says.
fn hierarchy(
    a: crate::linalg::CsrMatrix,
    next: NextHierarchy,
    cells: bool,
) -> crate::Result<Hierarchy> {
    use crate::linalg::{Amg, AmgOptions};
    let opts = AmgOptions::default();
    Ok(match next {
        NextHierarchy::Reuse {
            coarse,
            fresh_rate,
            built_for,
        } => Hierarchy {
            amg: coarse.with_fine(a, &opts)?,
            fresh_rate,
            reused: true,
            fixed_mask: built_for,
            cells,
        },
        NextHierarchy::New { fixed_mask } => Hierarchy {
            amg: Amg::owning(a, &opts)?,
            fresh_rate: None,
            reused: false,
            fixed_mask,
            cells,
        },
    })
}

/// Number of unknowns whose bit differs.
fn changed(a: &[u64], b: &[u64]) -> usize {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x ^ y).count_ones() as usize)
        .sum()
}

/// What one run of conjugate gradients did (all zero or false: a direct solve).
#[derive(Default)]
struct PcgOutcome {
    iterations: usize,
    /// The residual is above [`ITERATIVE_RTOL`] ‖c‖ (a screening solve that stopped early).
    inexact: bool,
    /// ln of the mean residual reduction per iteration (`None` without iterations).
    rate: Option<f64>,
    /// Preconditioned with the coarse levels of an earlier hierarchy.
    reused: bool,
}

impl PcgOutcome {
    /// The timings of a solve that started at `t[0]`, assembled until `t[1]`, set up its
    /// factorisation or hierarchy until `t[2]` and solved until `t[3]`.
    fn timings(&self, t: [Instant; 4]) -> SolveTimings {
        SolveTimings {
            assemble: (t[1] - t[0]).as_secs_f64(),
            factor: (t[2] - t[1]).as_secs_f64(),
            solve: (t[3] - t[2]).as_secs_f64(),
            krylov: self.iterations,
            inexact: self.inexact,
            reused: self.reused,
        }
    }
}

/// `u`, or an error naming its first non-finite entry.
fn check_finite(u: Vec<f64>) -> crate::Result<Vec<f64>> {
    match u.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(crate::Error::Linear(format!(
            "the solution is not finite at unknown {i}"
        ))),
        None => Ok(u),
    }
}

/// A hash of the fixed unknowns and their values (to check that a refinement continues the
/// solve it belongs to).
fn fingerprint(fixed: &[Option<f64>]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for (i, v) in fixed.iter().enumerate() {
        if let Some(v) = v {
            (i, v.to_bits()).hash(&mut h);
        }
    }
    h.finish()
}

/// The assembled discrete problem (see the module docs).
pub struct DiscreteSystem<'a> {
    sym: Arc<SymbolicSystem<'a>>,
    values: ProblemValues,
    n_skel: usize,
    n: usize,
    /// Buffers of [`DiscreteSystem::assemble_condensed`], kept between calls.
    scratch: Mutex<(Vec<f64>, Vec<f64>)>,
    /// The last skeleton solution, the initial guess of the next iterative solve.
    last_solution: Mutex<Vec<f64>>,
    /// The cell values of the last solve, if it solved the cell system ([`two_point`]).
    last_cells: Mutex<Vec<f64>>,
    /// The cell system, when the local matrices allow it ([`two_point`]; built on the first
    /// iterative solve).
    cell_system: std::sync::OnceLock<Option<two_point::CellSystemAll>>,
    /// The multigrid hierarchy of the last iterative solve.
    kept: Mutex<Option<KeptHierarchy>>,
    /// With [`LinearSolver::Auto`], the direct solver built when the iterative one fails.
    direct_fallback: std::sync::OnceLock<crate::Result<SpdPattern>>,
    /// Time to build (data, local matrices, and the symbolic system when built here), seconds.
    pub setup_seconds: f64,
    /// The symbolic factorisation, seconds (0 when the symbolic system was given). It runs
    /// beside the local matrices, so `setup_seconds − symbolic_seconds` is what it did not hide.
    pub symbolic_seconds: f64,
}

impl<'a> DiscreteSystem<'a> {
    /// Builds the symbolic system of `scheme` and the values of `problem`, side by side.
    pub fn new(
        scheme: &'a dyn GradientDiscretisation,
        problem: &Problem,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let dof_map = Arc::new(DofMap::new(scheme)?);
        dof_map.check_setup_memory()?;
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
    pub fn with_symbolic(sym: Arc<SymbolicSystem<'a>>, problem: &Problem) -> crate::Result<Self> {
        let t0 = Instant::now();
        let values = ProblemValues::evaluate(sym.scheme(), &sym.dof_map, problem)?;
        let mut s = Self::from_parts(sym, values);
        s.setup_seconds = t0.elapsed().as_secs_f64();
        Ok(s)
    }

    fn from_parts(sym: Arc<SymbolicSystem<'a>>, values: ProblemValues) -> Self {
        DiscreteSystem {
            n_skel: sym.n_condensed(),
            n: sym.n_unknowns(),
            sym,
            values,
            scratch: Mutex::new((Vec::new(), Vec::new())),
            last_solution: Mutex::new(Vec::new()),
            last_cells: Mutex::new(Vec::new()),
            cell_system: std::sync::OnceLock::new(),
            kept: Mutex::new(None),
            direct_fallback: std::sync::OnceLock::new(),
            setup_seconds: 0.0,
            symbolic_seconds: 0.0,
        }
    }

    /// The symbolic system (shareable with other problems on the same scheme).
    pub fn symbolic(&self) -> &Arc<SymbolicSystem<'a>> {
        &self.sym
    }
    /// The scheme.
    pub fn scheme(&self) -> &'a dyn GradientDiscretisation {
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
    /// The number of unknowns of the cell system ([`two_point`]: the cells, and the skeleton
    /// unknowns that could not be eliminated) if the iterative solves have taken it (`None`
    /// before any iterative solve, with the direct solver, and when too few skeleton unknowns
    /// can be eliminated).
    pub fn cell_system_size(&self) -> Option<usize> {
        self.cell_system.get()?.as_ref().map(|c| c.n())
    }
    /// Of the [`Self::cell_system_size`] unknowns, the skeleton ones (not eliminated).
    pub fn cell_system_skeleton(&self) -> Option<usize> {
        self.cell_system.get()?.as_ref().map(|c| c.n_kept())
    }
    /// Stored entries of the condensed matrix (lower triangle).
    pub fn nnz(&self) -> usize {
        self.sym.pattern.nnz()
    }
    /// Stored values of the Cholesky factor of the condensed matrix (its fill).
    pub fn factor_len(&self) -> usize {
        self.sym.pattern.factor_len()
    }
    /// Dirichlet unknowns and their values (`None`: not Dirichlet).
    pub fn dirichlet(&self) -> &[Option<f64>] {
        &self.values.dirichlet
    }
    /// The unknowns carrying the trace on Γ3, including those that are also Dirichlet unknowns
    /// (P1 vertices at Γ1 ∩ Γ3), which are never constrained but must satisfy the barrier.
    pub fn signorini_dofs(&self) -> &[PointDof] {
        &self.values.signorini
    }
    /// The full load vector b.
    pub fn load(&self) -> &[f64] {
        &self.values.load
    }

    /// The local system of cell k: its unknowns, its number of interior unknowns, its local
    /// matrix and load.
    #[inline]
    fn local(&self, k: usize) -> CellSystem<'_> {
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

    /// Solves the linear system in which the unknowns with `fixed[d] = Some(v)` (and the
    /// Dirichlet unknowns) are fixed. Returns the full unknown vector.
    pub fn solve(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.solve_to(fixed, ITERATIVE_RTOL)
    }

    /// [`Self::solve`], but an iterative solve stops at [`SCREENING_RTOL`] and is kept (matrix,
    /// multigrid hierarchy, right-hand side) until the next solve, so that [`Self::refine`]
    /// can continue it ([`SolveTimings::inexact`] says whether it did stop early).
    pub fn screen(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.solve_to(fixed, SCREENING_RTOL)
    }

    /// Continues the last solve, an inexact [`Self::screen`] with the same `fixed`, to
    /// [`ITERATIVE_RTOL`] with its multigrid hierarchy; `None` if that solve was exact (or
    /// another solve came since). `fixed` differing from that solve's is an error.
    pub fn refine(&self, fixed: &[Option<f64>]) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        let kept = {
            let Ok(mut guard) = self.kept.lock() else {
                return Ok(None);
            };
            match guard.take() {
                Some(k) if k.screened.is_some() => k,
                other => {
                    *guard = other;
                    return Ok(None);
                }
            }
        };
        let KeptHierarchy {
            amg,
            screened,
            fresh_rate,
            fixed_mask,
            cells,
            ..
        } = kept;
        let (rhs, print) = screened.unwrap_or_default();
        if print != fingerprint(fixed) {
            return Err(crate::Error::InvalidData(
                "refine: the fixed unknowns differ from those of the screening solve".into(),
            ));
        }
        let t0 = Instant::now();
        let cs = if cells { self.cell_system() } else { None };
        let mut x = match cs {
            Some(cs) => self.take_cell_guess(cs),
            None => self.take_initial_guess(),
        };
        // the hierarchy's rate is known: a refinement is not judged against it
        let hier = Hierarchy {
            amg,
            fresh_rate,
            reused: false,
            fixed_mask,
            cells,
        };
        match self.run_pcg(hier, &rhs, &mut x, ITERATIVE_RTOL, fixed) {
            Ok(out) => {
                let u = match cs {
                    Some(cs) => {
                        let u = self.complete_cells(cs, &self.fixed_values(fixed), &x)?;
                        self.keep_cells(x, &u);
                        u
                    }
                    None => {
                        let u = self.complete(fixed, &x)?;
                        self.keep_solution(x);
                        u
                    }
                };
                Ok(Some((
                    u,
                    SolveTimings {
                        solve: t0.elapsed().as_secs_f64(),
                        krylov: out.iterations,
                        ..Default::default()
                    },
                )))
            }
            // as in a solve: with Auto, the direct solver takes over
            Err(_) if self.sym.options.linear == LinearSolver::Auto => {
                self.fallback_pattern()?;
                self.solve(fixed).map(Some)
            }
            Err(e) => Err(e),
        }
    }

    /// Assembles and solves with `fixed`, an iterative solve to the relative residual `rtol`.
    fn solve_to(
        &self,
        fixed: &[Option<f64>],
        rtol: f64,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let t0 = Instant::now();
        if self.direct_pattern().is_none()
            && let Some(cs) = self.cell_system_for(fixed)
        {
            match self.solve_cells(cs, fixed, rtol, t0) {
                Ok(r) => return Ok(r),
                // as below: with Auto, the direct solver takes over
                Err(_) if self.sym.options.linear == LinearSolver::Auto => {
                    self.fallback_pattern()?;
                    return self.solve_to(fixed, rtol);
                }
                Err(e) => return Err(e),
            }
        }
        let reuse = self.next_hierarchy(fixed, false);
        let (values, mut rhs) = self.assemble_condensed(fixed);
        let t1 = Instant::now();
        let (t2, out) = match self.direct_pattern() {
            Some(pattern) => solve_directly(pattern, &values, &mut rhs)?,
            None if self.sym.options.linear == LinearSolver::Auto => {
                let c = rhs.clone();
                let it = self
                    .csr(&values)
                    .and_then(|a| self.solve_csr(a, &mut rhs, rtol, fixed, reuse));
                match it {
                    Ok(r) => r,
                    // Auto chose the iterative solver by size: when the conjugate gradients
                    // fail (no convergence on a hard matrix), the direct solver takes over,
                    // for this solve and the following ones
                    Err(_) => {
                        rhs = c;
                        solve_directly(self.fallback_pattern()?, &values, &mut rhs)?
                    }
                }
            }
            None => {
                // the lower triangle is not needed once stored by rows: freed before the
                // multigrid hierarchy is built
                let a = self.csr(&values)?;
                drop(values);
                self.solve_csr(a, &mut rhs, rtol, fixed, reuse)?
            }
        };
        let u = self.complete(fixed, &rhs)?;
        Ok((u, out.timings([t0, t1, t2, Instant::now()])))
    }

    /// Where the hierarchy of the next iterative solve (of the cell system if `cells`) comes
    /// from: the last hierarchy's coarse levels are reused unless they went stale, were built
    /// for the other system, or too many unknowns changed status since; its matrix (and a
    /// screening solve not refined) are freed before the next system is built.
    fn next_hierarchy(&self, fixed: &[Option<f64>], cells: bool) -> NextHierarchy {
        let mask = fixed_mask(&self.values.dirichlet, fixed);
        let max_changed = (REUSE_MAX_CHANGED * self.n as f64) as usize;
        self.kept
            .lock()
            .ok()
            .and_then(|mut k| k.take())
            .filter(|k| {
                !k.stale && k.cells == cells && changed(&k.fixed_mask, &mask) <= max_changed
            })
            .and_then(|k| {
                let (fresh_rate, built_for) = (k.fresh_rate, k.fixed_mask);
                k.amg.into_coarse().map(|coarse| NextHierarchy::Reuse {
                    coarse,
                    fresh_rate,
                    built_for,
                })
            })
            .unwrap_or(NextHierarchy::New { fixed_mask: mask })
    }

    /// The values of the fixed unknowns: `fixed` and the Dirichlet ones.
    fn fixed_values(&self, fixed: &[Option<f64>]) -> FixedValues {
        FixedValues::new(&self.values.dirichlet, fixed)
    }

    /// The full unknown vector from the skeleton solution `skel`: interior unknowns recovered
    /// cell by cell; a non-finite value is an error.
    fn complete(&self, fixed: &[Option<f64>], skel: &[f64]) -> crate::Result<Vec<f64>> {
        let fx = |d: usize| -> Option<f64> { self.values.dirichlet[d].or(fixed[d]) };
        let mut u = vec![0.0; self.n];
        u[..self.n_skel].copy_from_slice(skel);
        self.recover_interiors(&fx, &mut u);
        check_finite(u)
    }

    /// The skeleton unknowns the next iterative solve starts from (ignored by the direct
    /// solver, and if its length is not the number of skeleton unknowns); afterwards each
    /// iterative solve starts from the previous solution.
    pub fn set_initial_guess(&self, guess: Vec<f64>) {
        if guess.len() == self.n_skel
            && let Ok(mut b) = self.last_solution.lock()
        {
            *b = guess;
        }
    }

    /// The symbolic factorisation to solve with: the symbolic system's, or the one built when
    /// the iterative solver failed ([`LinearSolver::Auto`]); `None`: solve iteratively.
    fn direct_pattern(&self) -> Option<&SpdPattern> {
        if self.sym.pattern.has_factorisation() {
            return Some(&self.sym.pattern);
        }
        self.direct_fallback.get().and_then(|p| p.as_ref().ok())
    }

    /// The symbolic factorisation of the condensed pattern, built on first use.
    fn fallback_pattern(&self) -> crate::Result<&SpdPattern> {
        let (col_ptr, row_idx) = self.condensed_pattern();
        self.direct_fallback
            .get_or_init(|| {
                SpdPattern::with_ordering(
                    self.n_skel,
                    col_ptr.to_vec(),
                    row_idx.to_vec(),
                    self.sym.options.ordering,
                )
            })
            .as_ref()
            .map_err(|e| crate::Error::Linear(e.to_string()))
    }

    /// The condensed matrix with lower-triangle `values`, both triangles stored by rows.
    fn csr(&self, values: &[f64]) -> crate::Result<crate::linalg::CsrMatrix> {
        let (col_ptr, row_idx) = self.condensed_pattern();
        let mut a =
            crate::linalg::CsrMatrix::from_lower_csc(self.n_skel, col_ptr, row_idx, values)?;
        a.drop_zeros();
        Ok(a)
    }

    /// Solves S x = c (S stored by rows in `a`, c in `rhs`, overwritten by x) by
    /// multigrid-preconditioned conjugate gradients from the previous solution, to the
    /// relative residual `rtol`, with the hierarchy `next` says; returns when the
    /// multigrid setup ended and what the conjugate gradients did (x short of
    /// [`ITERATIVE_RTOL`]: the system is kept for [`Self::refine`], with the fingerprint of
    /// `fixed`).
    fn solve_csr(
        &self,
        a: crate::linalg::CsrMatrix,
        rhs: &mut [f64],
        rtol: f64,
        fixed: &[Option<f64>],
        next: NextHierarchy,
    ) -> crate::Result<(Instant, PcgOutcome)> {
        let hier = hierarchy(a, next, false)?;
        let t2 = Instant::now();
        let mut x = self.take_initial_guess();
        let out = self.run_pcg(hier, rhs, &mut x, rtol, fixed)?;
        rhs.copy_from_slice(&x);
        self.keep_solution(x);
        Ok((t2, out))
    }

    /// [`Self::pcg`] with the hierarchy `hier`, which is then kept for
    /// the next solve (with c and the fingerprint of `fixed` if the solve stopped early). A
    /// reused hierarchy that fails is replaced by a new one, once; one that converged more
    /// than [`REUSE_MAX_SLOWDOWN`] times slower than when fresh is marked stale.
    fn run_pcg(
        &self,
        hier: Hierarchy,
        c: &[f64],
        x: &mut [f64],
        rtol: f64,
        fixed: &[Option<f64>],
    ) -> crate::Result<PcgOutcome> {
        let Hierarchy {
            mut amg,
            mut fresh_rate,
            mut reused,
            mut fixed_mask,
            cells,
        } = hier;
        let mut out = match self.pcg(&amg, c, x, rtol) {
            Ok(out) => out,
            Err(_) if reused => {
                let opts = crate::linalg::AmgOptions::default();
                amg = crate::linalg::Amg::owning(amg.into_matrix(), &opts)?;
                (fresh_rate, reused) = (None, false);
                fixed_mask = self::fixed_mask(&self.values.dirichlet, fixed);
                self.pcg(&amg, c, x, rtol)?
            }
            Err(e) => return Err(e),
        };
        out.reused = reused;
        let stale = match (reused, out.rate, fresh_rate) {
            (true, Some(r), Some(f)) => r > f / REUSE_MAX_SLOWDOWN,
            _ => false,
        };
        if let Ok(mut k) = self.kept.lock() {
            *k = Some(KeptHierarchy {
                amg,
                screened: out.inexact.then(|| (c.to_vec(), fingerprint(fixed))),
                fresh_rate: fresh_rate.or(out.rate),
                stale,
                fixed_mask,
                cells,
            });
        }
        Ok(out)
    }

    /// The initial guess of an iterative solve: the last solution, or zero.
    fn take_initial_guess(&self) -> Vec<f64> {
        let x = self
            .last_solution
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        if x.len() == self.n_skel {
            x
        } else {
            vec![0.0; self.n_skel]
        }
    }

    /// Conjugate gradients on S x = c (S the fine matrix of `amg`) from `x` to the relative
    /// residual `rtol`: the iterations, whether the true residual is above
    /// [`ITERATIVE_RTOL`] ‖c‖, and the mean reduction per iteration.
    fn pcg(
        &self,
        amg: &crate::linalg::Amg,
        c: &[f64],
        x: &mut [f64],
        rtol: f64,
    ) -> crate::Result<PcgOutcome> {
        use crate::linalg::{PcgOptions, pcg};
        let c_norm = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        let opts = if rtol > ITERATIVE_RTOL {
            // screening: the residual reduced by SCREENING_REDUCTION from where this solve
            // starts, and at most rtol ‖c‖ (never below the full target)
            let r0 = amg.matrix().residual_norm(c, x);
            PcgOptions {
                rtol: ITERATIVE_RTOL,
                atol: (SCREENING_REDUCTION * r0).min(rtol * c_norm),
                max_iter: ITERATIVE_MAX_ITER,
            }
        } else {
            PcgOptions {
                rtol,
                atol: 0.0,
                max_iter: ITERATIVE_MAX_ITER,
            }
        };
        let report = pcg(amg.matrix(), amg, c, x, &opts)?;
        let rate = (report.iterations > 0
            && report.residual_norm > 0.0
            && report.initial_residual_norm > 0.0)
            .then(|| {
                (report.residual_norm / report.initial_residual_norm).ln()
                    / report.iterations as f64
            });
        Ok(PcgOutcome {
            iterations: report.iterations,
            inexact: report.residual_norm > ITERATIVE_RTOL * c_norm,
            rate,
            reused: false,
        })
    }

    /// Keeps `x` as the initial guess of the next iterative solve.
    fn keep_solution(&self, x: Vec<f64>) {
        if let Ok(mut b) = self.last_solution.lock() {
            *b = x;
        }
        if let Ok(mut c) = self.last_cells.lock() {
            *c = Vec::new();
        }
    }

    /// Fills the interior unknowns of `u` from its skeleton values, cell by cell
    /// ([`recover_interior`]): u_R = M_RR⁻¹ (b_R − Σ_{j∉R} M_Rj u_j) on each cell.
    fn recover_interiors(&self, fx: &(dyn Fn(usize) -> Option<f64> + Sync), u: &mut [f64]) {
        let nc = self.sym.scheme().mesh().n_cells();
        if self.sym.single_interior {
            // one interior unknown per cell, computed in parallel from the skeleton values
            let interior: Vec<(usize, f64)> = (0..nc)
                .into_par_iter()
                .map(|k| {
                    let cell = self.local(k);
                    (cell.dofs[0] as usize, interior_value(&cell, fx, u))
                })
                .collect();
            for (dof, v) in interior {
                u[dof] = v;
            }
        } else {
            for k in 0..nc {
                let cell = self.local(k);
                if cell.n_interior > 0 {
                    recover_interior(&cell, fx, u);
                }
            }
        }
    }

    /// The lower-triangular CSC pattern (column pointers, row indices) of the condensed matrix.
    pub fn condensed_pattern(&self) -> (&[usize], &[usize]) {
        (self.sym.pattern.col_ptr(), self.sym.pattern.row_idx())
    }

    /// Condensed matrix values (in the order of [`Self::condensed_pattern`]) and right-hand
    /// side, with `fixed` and the Dirichlet unknowns fixed (unit rows).
    ///
    /// With P_K the map from the global skeleton unknowns to those of cell K, and F the fixed
    /// unknowns (value u_F),
    ///
    ///   S_ij = Σ_K (P_Kᵀ S_K P_K)_ij            for i, j ∉ F,   S_ii = 1 and S_ij = 0 else,
    ///   c_i  = b^N_i + Σ_K (P_Kᵀ (g_K − S_K P_K u_F))_i   for i ∉ F,   c_i = u_i for i ∈ F,
    ///
    /// where b^N is the Neumann load and (S_K, g_K) the condensed block and load of cell K
    /// ([`condense()`]). Then S u_S = c is the skeleton system with u_F moved to the right.
    pub fn assemble_condensed(&self, fixed: &[Option<f64>]) -> (Vec<f64>, Vec<f64>) {
        let fixed = FixedValues::new(&self.values.dirichlet, fixed);
        // buffers kept between calls (they are entirely rewritten where read)
        let (mut sbuf, mut gbuf) = self
            .scratch
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        // without interior unknowns S_K = M_K, laid out like the local matrices, and the
        // cells' right-hand sides are computed where they are gathered: no buffer at all
        let (values, rhs) = if self.sym.no_interior {
            let values = self.gather_matrix(&fixed, &self.values.mats);
            let rhs = self.gather_rhs(&fixed, |k, i| self.cell_rhs(k, i, &fixed));
            (values, rhs)
        } else {
            sbuf.resize(self.sym.maps.block_ptr.total(), 0.0);
            gbuf.resize(self.sym.dof_map.dofs.len(), 0.0);
            self.condense_cells(&fixed, &mut sbuf, &mut gbuf);
            let values = self.gather_matrix(&fixed, &sbuf);
            let dof_ptr = &self.sym.dof_map.dof_ptr;
            let rhs = self.gather_rhs(&fixed, |k, i| gbuf[dof_ptr.at(k) + i]);
            (values, rhs)
        };
        if let Ok(mut b) = self.scratch.lock() {
            *b = (sbuf, gbuf);
        }
        (values, rhs)
    }

    /// Condenses every cell (some with interior unknowns), in parallel: cell k's p×p block
    /// S_K at `block_ptr[k]` in `sbuf`, and its right-hand side g_K − S_K P_K u_F (its
    /// condensed load minus the columns of its fixed skeleton unknowns) at the positions of
    /// its skeleton unknowns in `gbuf` (laid out like `dofs`).
    fn condense_cells(&self, fixed: &FixedValues, sbuf: &mut [f64], gbuf: &mut [f64]) {
        let dof_ptr = &self.sym.dof_map.dof_ptr;
        let ranges = cell_chunks(self.sym.scheme().mesh().n_cells());
        let g_slices = split_by_ranges(gbuf, &ranges, |k| dof_ptr.at(k));
        let block_ptr = &self.sym.maps.block_ptr;
        let s_slices = split_by_ranges(sbuf, &ranges, |k| block_ptr.at(k));
        let tasks: Vec<_> = ranges.into_iter().zip(s_slices).zip(g_slices).collect();
        tasks.into_par_iter().for_each(|(((c0, c1), s), g)| {
            let mut full = Vec::new();
            for k in c0..c1 {
                let (so, go) = (
                    block_ptr.at(k) - block_ptr.at(c0),
                    dof_ptr.at(k) - dof_ptr.at(c0),
                );
                self.condense_cell(k, fixed, &mut full, &mut s[so..], &mut g[go..]);
            }
        });
    }

    /// Entry i of the right-hand side b_K − M_K P_K u_F of cell k without interior unknowns
    /// (what [`Self::condense_cell`] computes when S_K = M_K, in the same order of
    /// operations: the load, then the fixed columns one after the other).
    fn cell_rhs(&self, k: usize, i: usize, fixed: &FixedValues) -> f64 {
        let cell = self.local(k);
        let (d, m) = (cell.dofs, cell.matrix);
        let mut g = cell.load[i];
        for (bcol, &dj) in d.iter().enumerate() {
            if let Some(vj) = fixed.get(dj as usize) {
                g -= m.at(i, bcol) * vj;
            }
        }
        g
    }

    /// Condenses cell k: its block S_K, packed ([`condense::packed_index`]), into the first p(p + 1)/2
    /// entries of `s`, and its right-hand side g_K − S_K P_K u_F into `g` after its `ni`
    /// interior entries (the cell's stretch of a buffer laid out like `dofs` starts at `g`).
    /// `full` is scratch for the whole p × p block.
    fn condense_cell(
        &self,
        k: usize,
        fixed: &FixedValues,
        full: &mut Vec<f64>,
        s: &mut [f64],
        g: &mut [f64],
    ) {
        let fx = |d: usize| fixed.get(d);
        let cell = self.local(k);
        let (d, ni) = (cell.dofs, cell.n_interior);
        let p = d.len() - ni;
        full.resize(p * p, 0.0);
        let sk = &mut full[..];
        let gk = &mut g[ni..ni + p];
        condense(&cell, &fx, sk, gk);
        // g_K −= S_K P_K u_F, column by column
        for bcol in 0..p {
            if let Some(vj) = fx(d[ni + bcol] as usize) {
                for arow in 0..p {
                    gk[arow] -= sk[arow + bcol * p] * vj;
                }
            }
        }
        condense::pack_lower(p, sk, s);
    }

    /// The values of the condensed matrix, gathered entry by entry (column by column in
    /// parallel): entry q is the sum of its sources `src.list(q)` in
    /// `blocks` (the condensed blocks, or the local matrices when they coincide), listed in cell
    /// order (the order of a sequential scatter, whatever the number of
    /// threads); zero in the rows and columns of fixed unknowns, whose diagonal is 1.
    fn gather_matrix(&self, fixed: &FixedValues, blocks: &[f64]) -> Vec<f64> {
        let (col_ptr, row_idx) = (self.sym.pattern.col_ptr(), self.sym.pattern.row_idx());
        let src = &self.sym.maps.src;
        let is_fixed: Vec<bool> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| fixed.get(d).is_some())
            .collect();
        let mut values = vec![0.0; self.sym.pattern.nnz()];
        let ranges = chunks(self.n_skel, CHUNK * 4);
        let slices = split_by_ranges(&mut values, &ranges, |k| col_ptr[k]);
        let tasks: Vec<_> = ranges.into_iter().zip(slices).collect();
        tasks.into_par_iter().for_each(|((c0, c1), out)| {
            let base = col_ptr[c0];
            for c in c0..c1 {
                let col_fixed = is_fixed[c];
                for q in col_ptr[c]..col_ptr[c + 1] {
                    let r = row_idx[q];
                    out[q - base] = if col_fixed || is_fixed[r] {
                        if r == c { 1.0 } else { 0.0 }
                    } else {
                        let mut v = 0.0;
                        for &i in src.list(q) {
                            v += blocks[i as usize];
                        }
                        v
                    };
                }
            }
        });
        values
    }

    /// The right-hand side of the condensed system, gathered row by row: the Neumann load plus
    /// the contributions `cell_value(k, local index)` of the cells k of `inc.list(i)` (in cell
    /// order); the value on fixed rows.
    fn gather_rhs(
        &self,
        fixed: &FixedValues,
        cell_value: impl Fn(usize, usize) -> f64 + Sync,
    ) -> Vec<f64> {
        let inc = &self.sym.maps.inc;
        let mut rhs = vec![0.0; self.n_skel];
        rhs.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(gi, out)| {
                *out = match fixed.get(gi) {
                    Some(v) => v,
                    None => {
                        let mut acc = self.values.neumann_load[gi];
                        for &k in inc.list(gi) {
                            let k = k as usize;
                            let (d, _) = self.sym.dof_map.cell(k);
                            acc += cell_value(k, local_index(d, gi));
                        }
                        acc
                    }
                };
            });
        rhs
    }

    /// The residual r = b − M u of the full (uncondensed) system, and for each unknown the
    /// scale |b_i| + Σ_j |M_ij u_j| against which it is small. On Dirichlet unknowns r is the
    /// reaction, not a balance; on constrained unknowns it is the multiplier (up to sign).
    ///
    /// M u = Σ_K P_Kᵀ M_K P_K u, gathered row by row in parallel: row i visits the cells where
    /// unknown i appears (`inc`, ascending) and takes there the row of M_K u_K, so the sums
    /// run in the order of a sequential scatter (independent of the threads) and nothing per
    /// cell is stored.
    pub fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let inc = &self.sym.maps.inc;
        let mut r = vec![0.0; self.n];
        let mut scale = vec![0.0; self.n];
        r.par_iter_mut()
            .zip(scale.par_iter_mut())
            .enumerate()
            .with_min_len(4096)
            .for_each(|(gi, (ri, si))| {
                let mut a = self.values.load[gi];
                let mut b = a.abs();
                for &k in inc.list(gi) {
                    let cell = self.local(k as usize);
                    let (d, m) = (cell.dofs, cell.matrix);
                    let i = local_index(d, gi);
                    let (mut mu, mut abs) = (0.0, 0.0);
                    for (j, &gj) in d.iter().enumerate() {
                        let v = m.at(i, j) * u[gj as usize];
                        mu += v;
                        abs += v.abs();
                    }
                    a -= mu;
                    b += abs;
                }
                *ri = a;
                *si = b;
            });
        (r, scale)
    }

    /// The entries (i, j, (M_K)_ij) of the rows i ∈ `rows` of the full matrix, cell by cell
    /// (repeated (i, j) sum), through the cells of each unknown.
    pub fn row_entries(&self, rows: &[usize]) -> Vec<(usize, usize, f64)> {
        let inc = &self.sym.maps.inc;
        let mut t = Vec::new();
        for &gi in rows {
            for &k in inc.list(gi) {
                let cell = self.local(k as usize);
                let (d, m) = (cell.dofs, cell.matrix);
                let i = local_index(d, gi);
                t.extend(
                    d.iter()
                        .enumerate()
                        .map(|(j, &gj)| (gi, gj as usize, m.at(i, j))),
                );
            }
        }
        t
    }

    /// The discrete energy ½ uᵀMu − bᵀu (the VI solution minimises it over the convex set).
    pub fn energy(&self, u: &[f64]) -> f64 {
        let (r, _) = self.residual(u);
        // ½uᵀMu − bᵀu = ½uᵀ(Mu − b) − ½bᵀu = −½uᵀr − ½bᵀu
        -0.5 * u.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>()
            - 0.5
                * u.iter()
                    .zip(&self.values.load)
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
    }

    /// The entries of the full (uncondensed) matrix M = Σ_K P_Kᵀ M_K P_K, cell by cell: the
    /// triplets (i, j, (M_K)_ij) in global indices (repeated entries sum).
    pub fn full_matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for k in 0..self.sym.scheme().mesh().n_cells() {
            let cell = self.local(k);
            let (d, m) = (cell.dofs, cell.matrix);
            for (j, &gj) in d.iter().enumerate() {
                for (i, &gi) in d.iter().enumerate() {
                    t.push((gi as usize, gj as usize, m.at(i, j)));
                }
            }
        }
        t
    }
}

impl QuadraticEnergy for DiscreteSystem<'_> {
    fn n_unknowns(&self) -> usize {
        self.n
    }
    fn dirichlet(&self) -> &[Option<f64>] {
        &self.values.dirichlet
    }
    fn load(&self) -> &[f64] {
        &self.values.load
    }
    fn minimise_with_fixed(
        &self,
        fixed: &[Option<f64>],
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        DiscreteSystem::solve(self, fixed)
    }
    fn screen_with_fixed(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        DiscreteSystem::screen(self, fixed)
    }
    fn refine(&self, fixed: &[Option<f64>]) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        DiscreteSystem::refine(self, fixed)
    }

    fn release(&self) {
        if let Ok(mut k) = self.kept.lock() {
            drop(k.take());
        }
    }
    fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        DiscreteSystem::residual(self, u)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.full_matrix_triplets()
    }
    fn row_entries(&self, rows: &[usize]) -> Option<Vec<(usize, usize, f64)>> {
        Some(DiscreteSystem::row_entries(self, rows))
    }
}
