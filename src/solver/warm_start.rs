//! Warm starts of the monotony algorithm: an initial active set predicted by coarse solves.
//!
//! From A₀ = ∅ the monotony algorithm puts every violated unknown in the active set at once
//! and then frees one layer of cells along the free boundary per solve, so that NITER grows
//! like the number of cell layers between the first contact zone and the final one,
//! ∝ 1/h ∝ N^{1/D} (`replication/BENCHMARKS.md` measures it in 2D). Every solve costs a linear
//! solve of the whole system, so the total grows like N^{1+1/D}.
//!
//! [`WarmStart::Nested`] (the default) bounds NITER instead: it solves the *same problem*
//! (same A, f, boundary conditions and barrier) with HMM on a coarse polygonal (polyhedral)
//! mesh of the same domain with about (fine skeleton unknowns) /
//! [`FIRST_LEVEL_UNKNOWNS_PER_CELL`] cells in 2D (a 12th of the cells for HMM on
//! quadrilaterals, a 48th for P1 on triangles) and
//! (fine unknowns)/[`FIRST_LEVEL_UNKNOWNS_PER_CELL_3D`] in 3D (a 24th of the cells for HMM on
//! hexahedra), made by agglomerating the fine cells ([`crate::mesh::agglomerate`] in
//! 2D, [`crate::mesh3d::agglomerate`] in 3D: any domain, any mesh, material interfaces and
//! boundary faces kept; what the prediction needs of a mesh is
//! [`CoarseMesh`], and the code below is written once for
//! both dimensions), itself warm-started in the same way from a mesh [`RATIO`] times coarser while
//! that one has at least [`MIN_CELLS`] cells, and starts the fine iteration from the predicted
//! active set.
//!
//! **Meshes that do not agglomerate.** On unstructured tetrahedra and Voronoi cells the 3D
//! aggregates have jagged boundaries and fail their star-shape checks
//! ([`crate::mesh3d::agglomerate`]; the agglomeration gives up when more than half the cells
//! are in failing aggregates). For the obstacle the level is then a cover of the mesh by boxes
//! of the same size H ([`crate::mesh3d::agglomerate::box_cover`]): each fine cell belongs to
//! the box of its centroid, the coarse domain is the union of those boxes (Ω up to a staircase
//! of boxes along ∂Ω, where the coarse problem takes its boundary data), and the levels above
//! it agglomerate the boxes. Signorini needs Γ's faces, which boxes do not have: it starts
//! cold on such meshes.
//!
//! **Box domains.** When Ω is a box that boxes of one side h ≈ H tile exactly
//! ([`CoarseMesh::box_tiling`]), the first level of an obstacle problem is that cover from the
//! start: it is then Ω itself, with no staircase, and it is built by sorting the fine cells by
//! box instead of growing, checking and merging aggregates of them (on 6M Kuhn tetrahedra,
//! 1.1 s against 2.9 s, with the same NITER: `replication/measurements/solver3d.md`). In 2D
//! the boxes are those of [`crate::mesh::box_cover`], which carries the boundary tags over to
//! the boxes' sides and refuses a box holding two materials or a side holding two boundary
//! tags (that level is then agglomerated); the measurements are in
//! `replication/measurements/solver.md`.
//!
//! **Prediction.** A fine unknown of the obstacle barrier lies in one or more coarse cells (a
//! cell unknown in the aggregate of its cell; a vertex or face unknown in those of the fine
//! cells around it). It is predicted active if all of them are active *and* it is farther than
//! [`EROSION`] · |K|^{1/D} from every face of such a K whose neighbour is free (in 3D, a face
//! of K is a planar polygon, a fine face or the merge of coplanar fine faces, and the distance
//! is to its fan triangles). This erodes the
//! coarse contact zone a little, so that the fine iteration mostly *adds* unknowns, which it
//! does in one step, rather than freeing them, which it does one layer of cells per step. A
//! Signorini unknown sits on boundary faces (edges in 2D), which the coarse meshes keep: it is
//! predicted active if the coarse unknowns of all its boundary faces are.
//!
//! **First guess.** The prediction also carries the finest coarse solution to the fine
//! skeleton unknowns (each takes the mean of Π_D u over the coarse cells of the fine cells
//! around it; [`Prediction::guess`]); the first iterative fine solve starts from it instead
//! of zero. It is within the coarse discretisation error of the fine solution (a few per cent
//! in the tests), which saves the conjugate gradients some of their first iterations; the
//! direct solver ignores it.
//!
//! The coarse iterations look ahead ([`crate::vi::look_ahead`]) like the fine one, which
//! saves coarse solves and leaves the prediction unchanged. They also stop before a solve that
//! is likely their last ([`ActiveSetOptions::predict_only`]): that solve would mostly only
//! confirm the set, and the prediction needs the set, not the certificate (the fine
//! iteration certifies). When it would have confirmed, the predicted set is the one it would
//! have returned, and the first guess comes from the solve before it. The measurements behind these
//! choices and the constants below are in `replication/BENCHMARKS.md` ("Measurements behind
//! the defaults").
//!
//! The warm start changes the path, never the answer: the stopping rule (A_{k+1} = A_k) and
//! the [`Certificate`](super::Certificate) do not depend on the start, so the solution is the
//! one of the cold iteration (the same discrete variational inequality has one solution); only
//! NITER and the time differ. NITER then counts the fine solves only; the coarse ones are
//! reported in [`WarmStartReport`]. When no coarse mesh can be made (a mesh with fewer than
//! 64 · [`FIRST_LEVEL_UNKNOWNS_PER_CELL`] skeleton unknowns in 2D, 64 ·
//! [`FIRST_LEVEL_UNKNOWNS_PER_CELL_3D`] unknowns in 3D, or an agglomeration that fails validation)
//! or a coarse solve fails, the
//! iteration starts cold and [`WarmStartReport::skipped`] says why.

use super::coarse_mesh::{CoarseMesh, Level};
use super::start::SolverMesh;
use crate::assembly::{DiscreteSystem, LinearSolver, SystemOptions};
use crate::budget::MemoryBudget;
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::mesh::NO_CELL;
use crate::mesh::complex::Vector;
use crate::mesh3d::agglomerate::KEEP;
use crate::problem::{BoundaryKind, ConstraintKind, Problem};
use crate::scheme::{Entity, GradientDiscretisation, Hmm};
use crate::solver::constraints::Constraints;
use crate::vi::{ActiveSetOptions, Cancel};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, Ordering::Relaxed};
use std::time::Instant;

/// How the monotony algorithm starts (`--warm-start nested|cold` on the command line).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum WarmStart {
    /// From A₀ = ∅ (the paper's algorithm; NITER comparable with its tables; the
    /// replication uses it).
    Cold,
    /// From an active set predicted by nested coarse HMM solves on agglomerated meshes of
    /// the domain (see the module docs), the iteration looking ahead
    /// ([`crate::vi::look_ahead`]). The default.
    #[default]
    Nested,
}

impl std::str::FromStr for WarmStart {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "cold" => Ok(WarmStart::Cold),
            "nested" => Ok(WarmStart::Nested),
            _ => Err(crate::Error::InvalidData(format!(
                "unknown warm start '{s}' (expected cold or nested)"
            ))),
        }
    }
}

impl std::fmt::Display for WarmStart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            WarmStart::Cold => "cold",
            WarmStart::Nested => "nested",
        })
    }
}

/// What a warm start did.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct WarmStartReport {
    /// The number of cells of the coarse meshes solved, finest first.
    pub levels: Vec<usize>,
    /// Linear solves of all coarse levels.
    pub coarse_solves: usize,
    /// Size of the predicted active set on the fine unknowns.
    pub predicted_active: usize,
    /// Wall-clock time of the prediction (agglomeration and coarse solves, which run beside
    /// the fine setup, and the mapping to the fine unknowns), in seconds.
    pub seconds: f64,
    /// Why no prediction was made (the iteration then starts cold).
    pub skipped: Option<String>,
}

/// Each coarse level has about 1/RATIO of the cells of the level below (H ≈ 4h in 2D, H ≈ 2.5h
/// in 3D).
pub const RATIO: usize = 16;

/// On planar meshes, the first coarse level has about (fine skeleton unknowns) /
/// FIRST_LEVEL_UNKNOWNS_PER_CELL cells ([`SolverMesh::warm_start_unknowns`]). P1 on triangles
/// has about one unknown per two cells, so that is a 48th of its cells; HMM has one skeleton
/// unknown per face, about 2 per quadrilateral and 1.5 per triangle, so a 12th of the cells of
/// a quadrilateral mesh and a 16th of a triangular one. A finer first level makes the coarse
/// solves cost more, a coarser one predicts less well and costs fine solves. HMM's level was
/// sized by all its unknowns (cells and faces) before: a third finer, with the same NITER and
/// more time (`replication/measurements/solver.md`, "The first coarse level").
pub const FIRST_LEVEL_UNKNOWNS_PER_CELL: usize = 24;

/// On 3D meshes, the first coarse level has about (fine unknowns) /
/// FIRST_LEVEL_UNKNOWNS_PER_CELL_3D cells: N/96, a 24th of the cells for HMM on hexahedra
/// (about 4 unknowns per cell), H ≈ 2.9h. Coarser than in 2D because a 3D agglomerate keeps
/// the fine faces of its non-planar interfaces and of the domain's boundary
/// ([`crate::mesh3d::agglomerate`]; only coplanar interior interfaces are merged), so its HMM
/// system is larger than a 2D one's for the same aggregate size
/// (`replication/measurements/solver3d.md`; the value was chosen before the interfaces were
/// merged and has not been re-tuned since).
pub const FIRST_LEVEL_UNKNOWNS_PER_CELL_3D: usize = 96;

/// A coarser level is made while it would have at least this many cells.
pub const MIN_CELLS: usize = 256;

/// Erosion of the coarse contact zone, in units of |K|^{1/D} (see the module docs): 1/4 erodes it
/// by about a quarter of a coarse cell. Larger values cost the fine iteration more solves
/// (it frees cells one layer per solve but adds them all at once).
pub const EROSION: f64 = 0.25;

/// A planar coarse level on which HMM takes the cell system (axis-parallel boxes, as the box
/// cover of the first level of ex9 and of every rectangle: [`crate::assembly::two_point`]) is
/// solved by the multigrid-preconditioned conjugate gradients from this many cells on, far
/// below the size from which [`LinearSolver::Auto`] takes them (it counts the skeleton
/// unknowns, about twice the cells here, and is set for skeleton systems). On such a level the
/// sparse Cholesky factorisation of the cell system (its ordering, symbolic and numeric
/// phases) and the triangular solves cost more than the few multigrid cycles of a solve of its
/// 5-point rows, from about this size on: the measurements (ex9's first levels of HMM and P1,
/// above and below it) are in `replication/measurements/solver.md`, "Iterative solves on the
/// coarse levels of boxes". The coarse level only predicts: a failed iterative solve skips
/// the warm start (a cold start, with the reason), it cannot change the answer.
pub const COARSE_ITERATIVE_MIN_CELLS: usize = 65_536;

/// The linear solver of the coarse level `mesh` ([`COARSE_ITERATIVE_MIN_CELLS`]): iterative
/// for a planar mesh of that many cells on which HMM likely takes the cell system,
/// [`LinearSolver::Auto`] otherwise.
pub fn coarse_linear_solver<M: CoarseMesh<D>, const D: usize>(mesh: &M) -> LinearSolver {
    if D == 2
        && mesh.n_cells() >= COARSE_ITERATIVE_MIN_CELLS
        && crate::assembly::two_point::likely_cell_system(mesh)
    {
        LinearSolver::Iterative
    } else {
        LinearSolver::Auto
    }
}

/// The active states of a coarse solve.
struct CoarseState {
    /// Obstacle: active coarse cells.
    cell: Vec<bool>,
    /// Signorini: active coarse faces.
    face: Vec<bool>,
}

/// What the coarse solves of the nested warm start leave for the prediction on the fine
/// unknowns: the finest coarse level, its active states and Π_D u there ([`coarse_solves`],
/// then [`predict_from`]). The coarse solves read the fine mesh and the problem only, not the
/// fine system, so the solve driver runs them beside the fine setup (`rayon::join`: at one
/// thread one after the other, at more the coarse solves in a pool of their own,
/// [`super::coarse_threads`]).
pub struct CoarseSolves<M> {
    /// The finest coarse level (the levels above it are dropped once solved).
    level: Level<M>,
    /// The active states of its solve.
    state: CoarseState,
    /// Π_D u on its cells.
    values: Vec<f64>,
    /// The number of cells of every level, finest first.
    sizes: Vec<usize>,
    /// Linear solves of all levels.
    solves: usize,
    /// Wall-clock time of the levels and their solves, in seconds.
    seconds: f64,
}

/// The coarse levels of a fine mesh `fine` with `unknowns` unknowns and the solves of
/// `problem` on them, coarsest first, each warm-started by the one above ([`CoarseSolves`]);
/// the coarse systems assembled within `budget`, the coarse solves polling `cancel` before
/// the levels are made and between their linear solves. `Err(reason)` when no level can be
/// made or solved (or `cancel` stopped them).
pub fn coarse_solves<M: CoarseMesh<D> + SolverMesh<D>, const D: usize>(
    fine: &M,
    unknowns: usize,
    problem: &Problem<D>,
    budget: MemoryBudget,
    cancel: Option<&Cancel>,
) -> Result<CoarseSolves<M>, String> {
    let t0 = Instant::now();
    Cancel::check(cancel).map_err(|e| e.to_string())?;
    let kind = constraint_kind(problem)?;
    let levels = hierarchy(fine, problem, kind, unknowns, budget)?;
    // from the coarsest level to the finest coarse one, each warm-started by the one above
    let mut state: Option<CoarseState> = None;
    let mut values: Vec<f64> = Vec::new();
    let mut solves = 0;
    for l in (0..levels.len()).rev() {
        let initial = |hmm: &Hmm<'_, M, D>, c: &Constraints| {
            state
                .as_ref()
                .map(|s| map_down(s, &levels[l + 1], hmm, c, kind, None))
                .transpose()
                .map_err(oom)
        };
        let mesh = &levels[l].mesh;
        let linear = coarse_linear_solver(mesh);
        let (sol_values, s, n) = coarse_solve(mesh, problem, budget, linear, cancel, initial)?;
        solves += n;
        values = sol_values;
        state = Some(s);
    }
    let state = state.ok_or_else(|| "no coarse level".to_string())?;
    let sizes = levels.iter().map(|a| a.mesh.n_cells()).collect();
    // the finest level; the coarser ones are dropped here
    let level = levels
        .into_iter()
        .next()
        .ok_or_else(|| "no coarse level".to_string())?;
    Ok(CoarseSolves {
        level,
        state,
        values,
        sizes,
        solves,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The kind of the barrier of `problem` (`Err` if it has none).
fn constraint_kind<const D: usize>(problem: &Problem<D>) -> Result<ConstraintKind, String> {
    Ok(problem
        .constraint
        .as_ref()
        .ok_or_else(|| "the problem has no barrier".to_string())?
        .kind)
}

/// Predicts the active set of the constrained unknowns `cons` of `scheme` for `problem` from
/// the coarse solves `coarse` made on `scheme`'s mesh (see the module docs), and the first
/// guess of the fine solve. `Err(reason)` when an array cannot be allocated, or when `coarse`
/// was made on a mesh with another number of cells or faces.
pub fn predict_from<M: CoarseMesh<D>, const D: usize>(
    coarse: CoarseSolves<M>,
    scheme: &dyn GradientDiscretisation<M, D>,
    problem: &Problem<D>,
    cons: &Constraints,
) -> Result<Prediction, String> {
    let t0 = Instant::now();
    let kind = constraint_kind(problem)?;
    let fine = scheme.mesh();
    let made_on = (
        coarse.level.cell_of.len(),
        coarse.level.boundary_face_of.fine_faces(),
    );
    if made_on != (fine.n_cells(), fine.n_faces()) {
        return Err(format!(
            "coarse solves made on a mesh of {} cells and {} faces, not on this one ({} and {})",
            made_on.0,
            made_on.1,
            fine.n_cells(),
            fine.n_faces()
        ));
    }
    let needs_vertices =
        (0..scheme.n_unknowns()).any(|d| matches!(scheme.dof_entity(d), Entity::Vertex(_)));
    let incidence = needs_vertices.then(|| VertexIncidence::new(fine));
    let CoarseSolves {
        level,
        state,
        values,
        sizes,
        solves,
        seconds,
    } = coarse;
    let active = map_down(&state, &level, scheme, cons, kind, incidence.as_ref()).map_err(oom)?;
    let guess = prolong(&values, &level, scheme, incidence.is_some()).map_err(oom)?;
    let report = WarmStartReport {
        levels: sizes,
        coarse_solves: solves,
        predicted_active: active.iter().filter(|&&a| a).count(),
        seconds: seconds + t0.elapsed().as_secs_f64(),
        skipped: None,
    };
    Ok(Prediction {
        active,
        guess,
        report,
    })
}

/// Predicts the active set of the constrained unknowns `cons` of `scheme` for `problem`:
/// [`coarse_solves`] on `scheme`'s mesh, then [`predict_from`].
pub fn predict<M: CoarseMesh<D> + SolverMesh<D>, const D: usize>(
    scheme: &dyn GradientDiscretisation<M, D>,
    problem: &Problem<D>,
    cons: &Constraints,
    budget: MemoryBudget,
    cancel: Option<&Cancel>,
) -> Result<Prediction, String> {
    let unknowns = M::warm_start_unknowns(scheme);
    let coarse = coarse_solves(scheme.mesh(), unknowns, problem, budget, cancel)?;
    predict_from(coarse, scheme, problem, cons)
}

/// A failed allocation of the warm start as the reason it was skipped.
fn oom(f: AllocFailure) -> String {
    crate::Error::from(f).to_string()
}

/// The solve of `problem` with HMM on the coarse mesh `mesh` (its systems within `budget`,
/// solved by `linear`), started from the active set `initial` gives for its scheme and
/// constraints: Π_D u at the cells, the active states and the number of linear solves.
fn coarse_solve<M: CoarseMesh<D> + SolverMesh<D>, const D: usize>(
    mesh: &M,
    problem: &Problem<D>,
    budget: MemoryBudget,
    linear: LinearSolver,
    cancel: Option<&Cancel>,
    initial: impl Fn(&Hmm<'_, M, D>, &Constraints) -> Result<Option<Vec<bool>>, String>,
) -> Result<(Vec<f64>, CoarseState, usize), String> {
    let fail = |e: crate::Error| format!("coarse solve ({} cells): {e}", mesh.n_cells());
    let hmm = Hmm::<M, D>::with_alpha(mesh, 1.0).map_err(fail)?;
    Cancel::check(cancel).map_err(fail)?;
    let system_options = SystemOptions {
        budget,
        linear,
        ..Default::default()
    };
    let system = DiscreteSystem::new(&hmm, problem, system_options).map_err(fail)?;
    let prepared = super::prepare(system, problem).map_err(fail)?;
    let c = prepared
        .constraints
        .as_ref()
        .ok_or_else(|| "the problem has no barrier".to_string())?;
    let opts = super::SolveOptions {
        active_set: ActiveSetOptions {
            look_ahead: Some(super::look_ahead_options(D)),
            cancel: cancel.cloned(),
            // the level only predicts: its last solve, which would confirm the set, is not made
            predict_only: true,
            ..Default::default()
        },
        warm_start: WarmStart::Cold,
        ..Default::default()
    };
    let (active, u, niter) =
        super::predict_prepared(&prepared, &opts, initial(&hmm, c)?).map_err(fail)?;
    let mut s = CoarseState {
        cell: try_filled(mesh.n_cells(), false, "the coarse active cells").map_err(oom)?,
        face: try_filled(mesh.n_faces(), false, "the coarse active faces").map_err(oom)?,
    };
    for (d, &a) in c.dofs.iter().zip(&active) {
        match hmm.dof_entity(d.dof) {
            Entity::Cell(k) => s.cell[k] = a,
            Entity::Edge(e) => s.face[e] = a,
            Entity::Vertex(_) => {}
        }
    }
    Ok((hmm.cell_values(&u), s, niter))
}

/// What the coarse solves predict on the fine problem.
#[derive(Debug, Clone)]
pub struct Prediction {
    /// The predicted active set, on the constrained unknowns.
    pub active: Vec<bool>,
    /// A first guess of the skeleton unknowns (the first iterative solve starts from it): the
    /// finest coarse solution Π_D u, constant on each coarse cell, averaged over the coarse
    /// cells around each fine unknown.
    pub guess: Vec<f64>,
    /// What was done.
    pub report: WarmStartReport,
}

/// The coarse cell values `values` (on the coarse mesh of `agg`) carried to the skeleton
/// unknowns of `scheme` (on its fine mesh): each unknown takes the mean over the fine cells
/// around its entity (the cell, the one or two cells of a face, the cells of a vertex) of
/// the value of their coarse cell. `at_vertices`: the scheme has vertex unknowns.
fn prolong<M: CoarseMesh<D>, const D: usize>(
    values: &[f64],
    agg: &Level<M>,
    scheme: &dyn GradientDiscretisation<M, D>,
    at_vertices: bool,
) -> Result<Vec<f64>, AllocFailure> {
    let fine = scheme.mesh();
    let of = |k: usize| values.get(agg.cell_of[k] as usize).copied().unwrap_or(0.0);
    // the mean around each vertex, by one pass over the cells: each sum adds the values of
    // the cells in increasing order from the starting value of `Sum`, as summing a gathered
    // list of the vertex's cells would
    let vertex_mean: Vec<f64> = if at_vertices {
        let zero: f64 = std::iter::empty::<f64>().sum();
        let mut sum = try_filled(fine.n_vertices(), zero, "the vertex sums of the warm start")?;
        let mut count = try_filled(
            fine.n_vertices(),
            0u32,
            "the vertex counts of the warm start",
        )?;
        let mut scratch = Vec::new();
        for k in 0..fine.n_cells() {
            let x = of(k);
            for &v in fine.cell_vertex_ids(k, &mut scratch) {
                sum[v as usize] += x;
                count[v as usize] += 1;
            }
        }
        sum.iter_mut()
            .zip(&count)
            .for_each(|(s, &n)| *s = if n == 0 { 0.0 } else { *s / n as f64 });
        sum
    } else {
        Vec::new()
    };
    let mut guess = try_vec(scheme.n_skeleton(), "the first guess of the warm start")?;
    guess.par_extend(
        (0..scheme.n_skeleton())
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| match scheme.dof_entity(d) {
                Entity::Cell(k) => of(k),
                Entity::Edge(e) => match fine.face_cells(e) {
                    [a, NO_CELL] => of(a),
                    [a, b] => 0.5 * (of(a) + of(b)),
                },
                Entity::Vertex(v) => vertex_mean.get(v).copied().unwrap_or(0.0),
            }),
    );
    Ok(guess)
}

/// Whether a fine problem on a planar mesh with this many skeleton unknowns
/// ([`SolverMesh::warm_start_unknowns`]) is too small to have a coarse level (the first would
/// have fewer than 64 cells): the nested start is then skipped.
pub fn too_coarse(unknowns: usize) -> bool {
    unknowns / FIRST_LEVEL_UNKNOWNS_PER_CELL < 64
}

/// The coarse meshes, finest first: the first has about `unknowns` /
/// [`CoarseMesh::UNKNOWNS_PER_COARSE_CELL`] cells, each further one agglomerates the one below into
/// about 1/[`RATIO`] of its cells, while that leaves at least [`MIN_CELLS`] cells (and the
/// first at least 64).
fn hierarchy<M: CoarseMesh<D>, const D: usize>(
    fine: &M,
    problem: &Problem<D>,
    kind: ConstraintKind,
    unknowns: usize,
    budget: MemoryBudget,
) -> Result<Vec<Level<M>>, String> {
    let measure: f64 = (0..fine.n_cells()).map(|k| fine.cell_measure(k)).sum();
    let first = unknowns / M::UNKNOWNS_PER_COARSE_CELL;
    if first < 64 {
        return Err(format!(
            "the mesh ({} cells) is too coarse for a nested warm start",
            fine.n_cells()
        ));
    }
    let mut levels: Vec<Level<M>> = Vec::new();
    loop {
        let below = levels.last().map_or(fine, |a| &a.mesh);
        let target = if levels.is_empty() {
            first
        } else {
            below.n_cells() / RATIO
        };
        let size = M::cell_size(measure, target);
        // an obstacle on a box: the first level is the exact cover by boxes (module docs)
        let tiling = match kind {
            ConstraintKind::Obstacle if levels.is_empty() => below.box_tiling(measure, size),
            _ => None,
        };
        let agg = match tiling.and_then(|h| below.cover(h, budget)) {
            Some(Ok(cover)) => Ok(cover),
            _ => {
                let keys = boundary_keys(below, problem).map_err(oom)?;
                below.coarsen(size, Some(&keys), budget)
            }
        };
        let agg = match agg {
            Ok(a) if a.mesh.n_cells() * 2 <= below.n_cells() => a,
            // the aggregates failed their checks (jagged unions of unstructured cells): for
            // the obstacle, boxes
            first => {
                let cover = if kind == ConstraintKind::Obstacle {
                    below.cover(size, budget)
                } else {
                    None
                };
                let n = below.n_cells();
                match (cover, first) {
                    (Some(Ok(cover)), _) => cover,
                    (Some(Err(c)), Err(e)) => {
                        return Err(format!(
                            "agglomerating {n} cells into {target}: {e}; covering them with \
                             boxes: {c}"
                        ));
                    }
                    (_, first) => {
                        first.map_err(|e| format!("agglomerating {n} cells into {target}: {e}"))?
                    }
                }
            }
        };
        if agg.mesh.n_cells() * 2 > below.n_cells() {
            break; // no real coarsening (a mesh of slivers): stop here
        }
        let n = agg.mesh.n_cells();
        levels.push(agg);
        if n / RATIO < MIN_CELLS {
            break;
        }
    }
    if levels.is_empty() {
        return Err("the agglomerated mesh is not coarser than the mesh".into());
    }
    Ok(levels)
}

/// The boundary merge key of each face of `mesh` ([`CoarseMesh::coarsen`]): one key per
/// (boundary condition, tag) pair of `problem` at the face's centre, so that a merged coarse
/// face joins only fine faces of one boundary part with one tag; [`KEEP`] for interior faces
/// and for Signorini faces, which stay as they are so that the predicted contact zone on Γ3 is
/// resolved at the fine faces. The coarse problem evaluates its boundary data at the merged
/// faces' centres: it is a coarser discretisation of the same problem, like the cells.
fn boundary_keys<M: CoarseMesh<D>, const D: usize>(
    mesh: &M,
    problem: &Problem<D>,
) -> Result<Vec<u32>, AllocFailure> {
    let mut keys = try_filled(
        mesh.n_faces(),
        KEEP,
        "the boundary merge keys of the warm start",
    )?;
    let mut parts: std::collections::BTreeMap<(BoundaryKind, i32), u32> = Default::default();
    for f in mesh.boundary_faces_iter() {
        let tag = mesh.face_tag(f);
        let kind = (problem.boundary)(mesh.face_centre(f), tag);
        if kind != BoundaryKind::Signorini {
            let next = parts.len() as u32;
            keys[f] = *parts.entry((kind, tag)).or_insert(next);
        }
    }
    Ok(keys)
}

/// The prediction on the constrained unknowns `cons` of `scheme` (on the fine mesh of `agg`)
/// from the coarse active states `s` on `agg.mesh` (see the module docs).
fn map_down<M: CoarseMesh<D>, const D: usize>(
    s: &CoarseState,
    agg: &Level<M>,
    scheme: &dyn GradientDiscretisation<M, D>,
    cons: &Constraints,
    kind: ConstraintKind,
    incidence: Option<&VertexIncidence>,
) -> Result<Vec<bool>, AllocFailure> {
    let fine = scheme.mesh();
    let coarse = &agg.mesh;
    let class = match kind {
        ConstraintKind::Obstacle => classify(s, coarse)?,
        ConstraintKind::Signorini => Vec::new(),
    };
    let at_vertices = match (kind, incidence) {
        (ConstraintKind::Obstacle, Some(_)) => vertex_obstacle(s, agg, &class, scheme, cons)?,
        _ => Vec::new(),
    };
    let mut active = try_vec(cons.dofs.len(), "the predicted active set")?;
    let scratch = || (Vec::new(), Vec::new());
    let each = cons.dofs.par_iter().enumerate().with_min_len(4096);
    active.par_extend(each.map_init(scratch, |(cells, faces), (j, d)| {
        cells.clear();
        faces.clear();
        match scheme.dof_entity(d.dof) {
            Entity::Cell(k) => cells.push(k),
            Entity::Edge(e) => {
                let [a, b] = fine.face_cells(e);
                cells.push(a);
                if b != NO_CELL {
                    cells.push(b);
                }
                faces.push(e);
            }
            Entity::Vertex(v) => {
                if let Some(inc) = incidence {
                    faces.extend_from_slice(inc.boundary_faces(v));
                    if kind == ConstraintKind::Obstacle {
                        return at_vertices[j];
                    }
                }
            }
        }
        match kind {
            ConstraintKind::Obstacle => {
                let p = scheme.dof_point(d.dof);
                !cells.is_empty()
                    && cells
                        .iter()
                        .all(|&k| inside(&class, s, coarse, agg.cell_of[k] as usize, || p))
            }
            ConstraintKind::Signorini => {
                faces.retain(|&e| fine.face_cells(e)[1] == NO_CELL);
                !faces.is_empty()
                    && faces.iter().all(|&e| {
                        let ce = agg.boundary_face_of.get(e);
                        ce.is_some_and(|ce| s.face.get(ce).copied().unwrap_or(false))
                    })
            }
        }
    }));
    Ok(active)
}

/// For the obstacle, whether each constrained unknown at a vertex is predicted active: all the
/// fine cells around its vertex are [`active_inside`] (and there is one), found by one pass
/// over the fine cells rather than by gathering the cells of each vertex (`false` for the
/// unknowns not at a vertex).
fn vertex_obstacle<M: CoarseMesh<D>, const D: usize>(
    s: &CoarseState,
    agg: &Level<M>,
    class: &[u8],
    scheme: &dyn GradientDiscretisation<M, D>,
    cons: &Constraints,
) -> Result<Vec<bool>, AllocFailure> {
    let fine = scheme.mesh();
    let nv = fine.n_vertices();
    // the constrained unknowns at each vertex (CSR)
    let mut vertex: Vec<Option<usize>> = try_vec(cons.dofs.len(), "the vertices of the unknowns")?;
    vertex.extend(cons.dofs.iter().map(|d| match scheme.dof_entity(d.dof) {
        Entity::Vertex(v) => Some(v),
        _ => None,
    }));
    let (ptr, at) = crate::mesh::buckets::try_counting_sort(nv, vertex.iter().copied(), |j| j)?;
    // per unknown: no cell seen yet, all cells seen so far pass, or one fails; the cells are
    // visited in parallel, and the outcome does not depend on their order (a failure is
    // final, a pass only replaces "unseen")
    const UNSEEN: u8 = 0;
    const PASS: u8 = 1;
    const FAIL: u8 = 2;
    let mut state: Vec<AtomicU8> = try_vec(cons.dofs.len(), "the vertex passes of the warm start")?;
    state.extend((0..cons.dofs.len()).map(|_| AtomicU8::new(UNSEEN)));
    (0..fine.n_cells())
        .into_par_iter()
        .for_each_init(Vec::new, |scratch, k| {
            let c = agg.cell_of[k] as usize;
            for &v in fine.cell_vertex_ids(k, scratch) {
                let v = v as usize;
                for &j in &at[ptr[v]..ptr[v + 1]] {
                    let now = state[j].load(Relaxed);
                    if now == FAIL {
                        continue;
                    }
                    let pass = inside(class, s, &agg.mesh, c, || {
                        scheme.dof_point(cons.dofs[j].dof)
                    });
                    if !pass {
                        state[j].store(FAIL, Relaxed);
                    } else if now == UNSEEN {
                        let _ = state[j].compare_exchange(UNSEEN, PASS, Relaxed, Relaxed);
                    }
                }
            }
        });
    let mut active = try_vec(state.len(), "the predicted active vertices")?;
    active.extend(state.into_iter().map(|x| x.into_inner() == PASS));
    Ok(active)
}

/// [`classify`]: a free coarse cell.
const FREE: u8 = 0;
/// [`classify`]: an active coarse cell whose neighbours across its faces are all active (or
/// none: a boundary face), so that every point of it is [`active_inside`] it.
const INTERIOR: u8 = 1;
/// [`classify`]: an active coarse cell with a free neighbour, where [`active_inside`] depends
/// on the point's distance to the faces between them.
const RIM: u8 = 2;

/// The class of each coarse cell ([`FREE`], [`INTERIOR`], [`RIM`]) under the active states `s`:
/// the part of [`active_inside`] that does not depend on the point, found once per coarse cell
/// instead of once per fine unknown and cell around it.
fn classify<M: CoarseMesh<D>, const D: usize>(
    s: &CoarseState,
    coarse: &M,
) -> Result<Vec<u8>, AllocFailure> {
    let mut class = try_vec(coarse.n_cells(), "the classes of the coarse cells")?;
    class.par_extend(
        (0..coarse.n_cells())
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| {
                if !s.cell[k] {
                    return FREE;
                }
                let all_active = coarse.cell_faces(k).iter().all(|&e| {
                    let [a, b] = coarse.face_cells(e as usize);
                    let other = if a == k { b } else { a };
                    other == NO_CELL || s.cell[other]
                });
                if all_active { INTERIOR } else { RIM }
            }),
    );
    Ok(class)
}

/// [`active_inside`] for coarse cell `k` of class `class[k]` ([`classify`]) and the point
/// `p()`: the point is asked for, and the distances to its faces measured, on [`RIM`] cells
/// only.
fn inside<M: CoarseMesh<D>, const D: usize>(
    class: &[u8],
    s: &CoarseState,
    coarse: &M,
    k: usize,
    p: impl FnOnce() -> Vector<D>,
) -> bool {
    match class[k] {
        FREE => false,
        INTERIOR => true,
        _ => active_inside(s, coarse, k, p()),
    }
}

/// Whether coarse cell `k` is active and `p` is at least [`EROSION`] · |K|^{1/D} away from
/// each of its faces across which the neighbour is free.
fn active_inside<M: CoarseMesh<D>, const D: usize>(
    s: &CoarseState,
    coarse: &M,
    k: usize,
    p: Vector<D>,
) -> bool {
    if !s.cell[k] {
        return false;
    }
    let reach = EROSION * M::cell_length(coarse.cell_measure(k));
    coarse.cell_faces(k).iter().all(|&e| {
        let e = e as usize;
        let [a, b] = coarse.face_cells(e);
        let other = if a == k { b } else { a };
        other == NO_CELL || s.cell[other] || coarse.face_distance(e, p) >= reach
    })
}

/// The boundary faces around each vertex of a mesh (for vertex unknowns; the cells around
/// the vertices are visited by passes over the cells, [`vertex_obstacle`] and [`prolong`]).
struct VertexIncidence {
    /// Offsets of each vertex's faces in `faces` (CSR).
    ptr: Vec<usize>,
    /// The boundary faces of each vertex, ascending.
    faces: Vec<usize>,
}

impl VertexIncidence {
    fn new<M: CoarseMesh<D>, const D: usize>(mesh: &M) -> Self {
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        let mut scratch = Vec::new();
        for f in mesh.boundary_faces_iter() {
            for &v in mesh.face_vertex_ids(f, &mut scratch) {
                pairs.push((v as usize, f));
            }
        }
        let (ptr, faces) = crate::mesh::buckets::counting_sort(
            mesh.n_vertices(),
            pairs.iter().map(|&(v, _)| Some(v)),
            |i| pairs[i].1,
        );
        VertexIncidence { ptr, faces }
    }
    fn boundary_faces(&self, v: usize) -> &[usize] {
        &self.faces[self.ptr[v]..self.ptr[v + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::PolyMesh;
    use crate::mesh::generate::cartesian_triangles;
    use crate::scheme::P1;

    /// The coarse levels' solver: iterative on planar boxes from
    /// [`COARSE_ITERATIVE_MIN_CELLS`] cells on, `Auto` below, on triangles and in 3D.
    #[test]
    fn coarse_levels_of_boxes_are_solved_iteratively_from_their_size() {
        use crate::mesh::generate::cartesian_rect;
        use crate::mesh3d::{PolyMesh3, test_meshes::cubes};
        let side = (COARSE_ITERATIVE_MIN_CELLS as f64).sqrt().ceil() as usize;
        let boxes = |nx: usize| cartesian_rect(nx, side, [0.0, 2.0], [0.0, 1.0]).unwrap();
        let at = boxes(side);
        assert!(at.n_cells() >= COARSE_ITERATIVE_MIN_CELLS);
        assert_eq!(coarse_linear_solver(&at), LinearSolver::Iterative);
        let below = boxes(side - 1);
        assert!(below.n_cells() < COARSE_ITERATIVE_MIN_CELLS);
        assert_eq!(coarse_linear_solver(&below), LinearSolver::Auto);
        let n = side * 3 / 4;
        let triangles = cartesian_triangles(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert!(triangles.n_cells() >= COARSE_ITERATIVE_MIN_CELLS);
        assert_eq!(coarse_linear_solver(&triangles), LinearSolver::Auto);
        let m = PolyMesh3::from_polyhedra(cubes(41, 1), MemoryBudget::DEFAULT).unwrap();
        assert!(m.n_cells() >= COARSE_ITERATIVE_MIN_CELLS);
        assert_eq!(coarse_linear_solver(&m), LinearSolver::Auto);
    }

    /// A coarse solve predicts the same active cells with the iterative solver as with the
    /// direct one, and cell values within the solvers' tolerances; both from no initial set
    /// and from the set the first predicted.
    #[test]
    fn the_coarse_prediction_does_not_depend_on_the_linear_solver() {
        let mesh = crate::mesh::generate::cartesian(96, 96).unwrap();
        let problem = crate::problem::paper_test3(-5.0);
        let budget = MemoryBudget::DEFAULT;
        let run = |linear, start: Option<&CoarseState>| {
            let initial = |hmm: &Hmm<'_, PolyMesh, 2>, c: &Constraints| {
                Ok(start.map(|s| {
                    c.dofs
                        .iter()
                        .map(|d| match hmm.dof_entity(d.dof) {
                            Entity::Cell(k) => s.cell[k],
                            _ => false,
                        })
                        .collect()
                }))
            };
            coarse_solve(&mesh, &problem, budget, linear, None, initial).unwrap()
        };
        let (direct_u, direct, n_direct) = run(LinearSolver::Direct, None);
        let (iter_u, iter, n_iter) = run(LinearSolver::Iterative, None);
        let active = direct.cell.iter().filter(|&&a| a).count();
        assert!(active > 0 && active < mesh.n_cells(), "{active}");
        assert_eq!(direct.cell, iter.cell);
        assert_eq!(n_direct, n_iter);
        let scale = direct_u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for (a, b) in direct_u.iter().zip(&iter_u) {
            assert!((a - b).abs() <= 1e-6 * scale, "{a} against {b}");
        }
        let (_, again_direct, _) = run(LinearSolver::Direct, Some(&direct));
        let (_, again_iter, _) = run(LinearSolver::Iterative, Some(&direct));
        assert_eq!(again_direct.cell, again_iter.cell);
    }

    /// The boundary merge keys: one per boundary part and tag, [`KEEP`] on interior faces and
    /// on Signorini faces.
    #[test]
    fn boundary_keys_join_one_part_and_keep_signorini_faces() {
        use crate::mesh3d::{PolyMesh3, test_meshes::cubes};
        let m = PolyMesh3::from_polyhedra(cubes(3, 1), MemoryBudget::DEFAULT).unwrap();
        // Dirichlet on z = 1, Signorini on z = 0, Neumann on the sides
        let p = crate::solver::tests_3d::signorini();
        let keys = boundary_keys(&m, &p).unwrap();
        let (mut top, mut sides) = (Vec::new(), Vec::new());
        for (f, &k) in keys.iter().enumerate() {
            let z = m.face_centroid(f)[2];
            if !m.is_boundary_face(f) || z < 1e-12 {
                assert_eq!(k, KEEP, "face {f}");
            } else if z > 1.0 - 1e-12 {
                top.push(k);
            } else {
                sides.push(k);
            }
        }
        assert_eq!((top.len(), sides.len()), (9, 36));
        assert!(top.iter().all(|&k| k == top[0]) && sides.iter().all(|&k| k == sides[0]));
        assert!(top[0] != sides[0] && top[0] != KEEP && sides[0] != KEEP);
    }

    /// Coarse active states of a contact zone: the cells whose centroid is in the unit disc.
    fn disc_contact(coarse: &crate::mesh::PolyMesh) -> CoarseState {
        CoarseState {
            cell: (0..coarse.n_cells())
                .map(|k| {
                    let c = coarse.centroid(k);
                    c[0] * c[0] + c[1] * c[1] < 1.0
                })
                .collect(),
            face: vec![false; coarse.n_edges()],
        }
    }

    /// The passes over the cells of [`prolong`] and [`vertex_obstacle`] give exactly what
    /// gathering the cells of each vertex (their definition) gives.
    #[test]
    fn vertex_passes_are_the_gathered_definitions() {
        let fine = cartesian_triangles(64, 48, [-2.0, 2.0], [-1.5, 1.5]).unwrap();
        let scheme = P1::new(&fine).unwrap();
        let agg = fine.coarsen(0.3, None, MemoryBudget::DEFAULT).unwrap();
        let coarse = &agg.mesh;
        // a coarse contact zone (a disc) and coarse values
        let s = disc_contact(coarse);
        assert!(s.cell.iter().any(|&a| a) && !s.cell.iter().all(|&a| a));
        let values: Vec<f64> = (0..coarse.n_cells())
            .map(|k| (k as f64 * 0.731).sin())
            .collect();
        let incidence = VertexIncidence::new(&fine);
        let (ptr, ids) = fine.vertex_cells();
        let cells = |v: usize| &ids[ptr[v]..ptr[v + 1]];
        let guess = prolong(&values, &agg, &scheme, true).unwrap();
        assert_eq!(guess.len(), scheme.n_skeleton());
        let mut dofs = Vec::new();
        for (d, g) in guess.iter().enumerate() {
            if let Entity::Vertex(v) = scheme.dof_entity(d) {
                let c = cells(v);
                let want = c
                    .iter()
                    .map(|&k| values[agg.cell_of[k] as usize])
                    .sum::<f64>()
                    / c.len() as f64;
                assert_eq!(g.to_bits(), want.to_bits(), "vertex {v}");
                dofs.push(crate::vi::ConstrainedDof {
                    dof: d,
                    point: (),
                    measure: 1.0,
                });
            }
        }
        let cons = Constraints {
            barrier: vec![0.0; dofs.len()],
            dofs,
            side: crate::vi::Side::Upper,
        };
        let active = map_down(
            &s,
            &agg,
            &scheme,
            &cons,
            ConstraintKind::Obstacle,
            Some(&incidence),
        )
        .unwrap();
        let mut n = 0;
        for (j, d) in cons.dofs.iter().enumerate() {
            let Entity::Vertex(v) = scheme.dof_entity(d.dof) else {
                unreachable!()
            };
            let c = cells(v);
            let want = !c.is_empty()
                && c.iter().all(|&k| {
                    active_inside(&s, coarse, agg.cell_of[k] as usize, scheme.dof_point(d.dof))
                });
            assert_eq!(active[j], want, "vertex {v}");
            n += usize::from(want);
        }
        assert!(n > 0 && n < cons.dofs.len(), "{n} predicted active");
    }

    /// The classes of the coarse cells give `active_inside` at every point: free cells none,
    /// interior cells all, rim cells by distance (points at the cells' vertices, centroids and
    /// midpoints between them, on a disc contact zone that has cells of all three classes).
    #[test]
    fn classes_are_active_inside() {
        let fine = cartesian_triangles(40, 30, [-2.0, 2.0], [-1.5, 1.5]).unwrap();
        let agg = fine.coarsen(0.3, None, MemoryBudget::DEFAULT).unwrap();
        let coarse = &agg.mesh;
        let s = disc_contact(coarse);
        let class = classify(&s, coarse).unwrap();
        for c in [FREE, INTERIOR, RIM] {
            assert!(class.contains(&c), "no cell of class {c}");
        }
        for k in 0..coarse.n_cells() {
            let x = coarse.centroid(k);
            for &v in coarse.cell_vertices(k) {
                let p = coarse.vertex(v as usize);
                for q in [p, x, [0.5 * (p[0] + x[0]), 0.5 * (p[1] + x[1])]] {
                    assert_eq!(
                        inside(&class, &s, coarse, k, || q),
                        active_inside(&s, coarse, k, q),
                        "cell {k} (class {}) at {q:?}",
                        class[k]
                    );
                }
            }
        }
    }
}
