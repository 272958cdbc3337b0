//! How the condensed systems S u = c are solved: the choice of solver and its tolerances.

/// How the condensed systems S u = c are solved.
///
/// - **Direct**: sparse Cholesky (faer), symbolic factorisation once, numeric factorisation
///   per solve ([`crate::linalg::cholesky`]). Exact to round-off; its fill grows like
///   N log N and its time like N^1.5 on 2D meshes.
/// - **Iterative**: conjugate gradients preconditioned by smoothed-aggregation algebraic
///   multigrid ([`crate::linalg::amg`], [`mod@crate::linalg::pcg`]), started from the previous
///   solution, to a relative residual of [`ITERATIVE_RTOL`]; memory O(N). The hierarchy of one
///   solve is kept in the caller's [`super::SolveState`] and its coarse levels precondition the
///   next solve while few unknowns changed status ([`REUSE_MAX_CHANGED`],
///   [`REUSE_MAX_SLOWDOWN`]). The active-set solver screens with solves to
///   [`SCREENING_RTOL`] and refines the last one ([`super::DiscreteSystem::screen`],
///   [`super::DiscreteSystem::refine`]). The certificate of the final solution is computed
///   the same way as for the direct solver, from the full system.
/// - **Auto** (the default): iterative from [`AUTO_ITERATIVE_MIN`] condensed unknowns on
///   ([`AUTO_ITERATIVE_MIN_3D`] on 3D meshes), direct below; if the conjugate gradients fail
///   (smoothed aggregation converges slowly on strongly distorted meshes with rotated
///   anisotropy), the direct solver takes over for that solve and the following ones of the
///   same [`super::SolveState`].
///
/// The measurements behind these choices are in `replication/BENCHMARKS.md` ("Measurements
/// behind the defaults").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolver {
    /// Direct below [`AUTO_ITERATIVE_MIN`] condensed unknowns ([`AUTO_ITERATIVE_MIN_3D`] on
    /// 3D meshes), iterative from there on.
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

/// [`LinearSolver::Auto`] solves iteratively from this many condensed unknowns on: about where
/// the iterative solver overtakes the direct one on the benchmarks (`make bench-peers`, the
/// peer benchmark in `replication/BENCHMARKS.md`).
pub const AUTO_ITERATIVE_MIN: usize = 250_000;

/// [`LinearSolver::Auto`] solves 3D systems iteratively from this many condensed unknowns on.
/// The fill of a sparse Cholesky factor grows faster on 3D meshes than on planar ones (like
/// N^{4/3} under nested dissection, its work like N²), while multigrid-preconditioned
/// conjugate gradients stay O(N); the two are level around 10⁴ condensed unknowns on the
/// generated 3D families, and the iterative solver is several times faster from a few 10⁴ on
/// (`replication/measurements/solver3d.md`).
pub const AUTO_ITERATIVE_MIN_3D: usize = 20_000;

/// The size from which [`LinearSolver::Auto`] solves iteratively on a mesh of dimension `d`:
/// [`AUTO_ITERATIVE_MIN_3D`] in 3D, [`AUTO_ITERATIVE_MIN`] otherwise.
pub const fn auto_iterative_min(d: usize) -> usize {
    if d == 3 {
        AUTO_ITERATIVE_MIN_3D
    } else {
        AUTO_ITERATIVE_MIN
    }
}

/// Relative residual ‖c − S u‖₂ ≤ ITERATIVE_RTOL ‖c‖₂ at which the conjugate gradients stop.
pub const ITERATIVE_RTOL: f64 = 1e-12;

/// Iteration cap of the conjugate gradients (multigrid keeps them in the tens).
pub const ITERATIVE_MAX_ITER: usize = 1000;

/// A screening solve ([`super::DiscreteSystem::screen`]) of the active-set iteration stops
/// once its residual is below SCREENING_RTOL ‖c‖ *and* below [`SCREENING_REDUCTION`] times the
/// residual it started from: accurate enough to decide the next active set; the last solve is
/// then refined to [`ITERATIVE_RTOL`] ([`super::DiscreteSystem::refine`]). On the nested
/// start's solves of the benchmarks the reduction is the bound that stops them (10⁻⁵ here
/// gave the same iterations in 2D); this one caps the solves that start far from their answer
/// (from zero). At 10⁻⁸ it stopped the first fine solve instead, two iterations later, with
/// the same NITER at every size measured (`replication/measurements/assembly.md`, "Screening
/// solves"); alone, without the reduction, a bound this loose misjudged unknowns near the
/// free boundary, which later solves had to take back.
pub const SCREENING_RTOL: f64 = 1e-6;

/// The reduction of its initial residual a screening solve must reach besides
/// [`SCREENING_RTOL`]. After a change of the active set, the previous solution may already
/// meet SCREENING_RTOL ‖c‖ (the change is local, ‖c‖ holds all the data), so that bound alone
/// would let a solve stop after no iteration, on the previous solution, and misjudge the
/// unknowns near the change.
pub const SCREENING_REDUCTION: f64 = 1e-4;

/// Consecutive iterative solves through one [`super::SolveState`] share their multigrid
/// hierarchy's coarse levels. The active-set iteration changes the condensed matrix only in
/// the rows and columns of the unknowns whose status changed, and after the first solves these
/// are few: the coarse levels built for an earlier matrix (the fine level and its smoother
/// always take the new matrix, [`crate::linalg::CoarseHierarchy`]) precondition the new one
/// about as well, and save a whole setup. A hierarchy is reused only if at most
/// [`REUSE_MAX_CHANGED`] of the unknowns changed status since the matrix it was built for, and
/// while conjugate gradients with it converge at most this factor slower (in mean residual
/// reduction per iteration) than with it fresh; otherwise the next solve builds a new one.
pub const REUSE_MAX_SLOWDOWN: f64 = 3.0;

/// The largest fraction of the unknowns that may have changed status (fixed or free) since
/// the matrix a hierarchy was built for, for it to be reused ([`REUSE_MAX_SLOWDOWN`]). The
/// unknowns freed since, in particular, were decoupled (unit rows) in the matrix the coarse
/// levels were built from, and have no coarse basis function; in 2D the reused hierarchy is
/// therefore corrected by exact solves on a patch around them ([`PATCH_LAYERS`]), which let
/// the bound rise from 10⁻³ (without the patch, a P1 hierarchy reused after 0.13% of the
/// unknowns changed took 9 CG iterations where a new one took 5) to 10⁻².
pub const REUSE_MAX_CHANGED: f64 = 1e-2;

/// Graph layers of the patch around the unknowns whose status changed since a reused
/// hierarchy was built, on which its preconditioner is corrected by exact solves
/// ([`crate::linalg::PatchCorrected`]: symmetric multiplicative, one sparse Cholesky
/// factorisation of the patch per solve) on planar meshes. Measured on ex9 with P1 at 1M
/// unknowns (`replication/measurements/assembly.md`): the second solve's hierarchy reused with
/// a patch of 6 layers took the CG iterations of a new hierarchy (5, then 7 in the third
/// solve) and saved its setup; without the patch it took 9 and 11.
pub const PATCH_LAYERS: usize = 6;

/// [`PATCH_LAYERS`] on 3D meshes: 0, no patch. Measured on the radial obstacle at 64³ cubes,
/// one thread: P1 (275k unknowns) took 35 Krylov iterations without a patch, 33 with 1 or 2
/// layers, 31 with 3, in the same time (1.56–1.65 s); HMM 46 without, 43 with 2, in the same
/// time (2.01–2.05 s). A 3D hierarchy reused without a patch already converges about as fast
/// as a new one there.
pub const PATCH_LAYERS_3D: usize = 0;

/// The patch layers on a mesh of dimension `d`.
pub(crate) fn patch_layers(d: usize) -> usize {
    if d == 3 {
        PATCH_LAYERS_3D
    } else {
        PATCH_LAYERS
    }
}

/// A patch with more than this fraction of the rows is not factorised: the reused hierarchy
/// then preconditions alone if at most [`REUSE_MAX_CHANGED_UNPATCHED`] of the unknowns changed,
/// else a new hierarchy is built.
pub const PATCH_MAX_FRACTION: f64 = 0.1;

/// The reuse bound of a hierarchy without the patch correction (the bound of 2D before it):
/// when the patch is declined ([`PATCH_MAX_FRACTION`]) and more than this fraction of the rows
/// changed, the solve builds a new hierarchy instead.
pub const REUSE_MAX_CHANGED_UNPATCHED: f64 = 1e-3;

/// [`REUSE_MAX_CHANGED`] on 3D meshes, without the patch correction. The active-set steps of
/// a 3D solve change a shell around the free boundary rather than a band, a larger fraction of
/// the unknowns at the same grid (3.3·10⁻³ at the second fine solve of the radial obstacle on
/// 64³ cubes), and a 3D multigrid setup costs as much as several CG iterations: the coarse
/// levels are reused up to this fraction (chosen before the 2D bound rose to the same value),
/// the slowdown bound [`REUSE_MAX_SLOWDOWN`] still discarding a hierarchy that preconditions
/// the new matrix poorly.
pub const REUSE_MAX_CHANGED_3D: f64 = 1e-2;

/// The reuse bound on a mesh of dimension `d`: [`REUSE_MAX_CHANGED_3D`] in 3D,
/// [`REUSE_MAX_CHANGED`] otherwise.
pub(crate) fn reuse_max_changed(d: usize) -> f64 {
    if d == 3 {
        REUSE_MAX_CHANGED_3D
    } else {
        REUSE_MAX_CHANGED
    }
}
