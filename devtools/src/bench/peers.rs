//! The peer benchmark (`gradvi-dev bench --peers`, part of `make bench`):
//!
//! 1. **PETSc's obstacle example side by side.** Bueler's radial obstacle problem
//!    (`problems/ex9.toml`) as PETSc's `snes/tutorials/ex9.c` solves it, with grid sequencing
//!    and geometric multigrid (`-snes_grid_sequence K -pc_type mg`, built from Debian's
//!    packages by `benches/petsc/*.sh`), next to gradvi on the same problem at equal numbers of
//!    unknowns: P1 on the (G−1)² squares of the G × G grid cut into triangles (the same
//!    five-point discrete problem, G² unknowns with the boundary, as ex9 counts them) and HMM
//!    on the (G−1)² squares. Each row records time, peak memory, iterations and the errors
//!    against the exact solution (max and mean over the nodes for ex9 and P1, as ex9 computes
//!    them, boundary included; over the cell centres for HMM).
//! 2. **Any domain.** The paper's Test 3 data (C = −5) on gmsh meshes of an L-shaped domain, a
//!    disk and a square with a hole (`benches/domains/*.geo`) from 10⁴ to 10⁶ cells, HMM and
//!    P1 with the default (nested) start: NITER and the growth of the total time. Both linear
//!    solvers run on the meshes of [`DOMAIN_LC`] (gmsh's seed 1); the same domains are meshed
//!    again with another seed ([`RESEED`]) at sizes between those ([`RESEED_LC`]), where the
//!    default linear solver (`auto`) runs, so that its direct/iterative switch falls inside the
//!    range (rows with the `mesh` label [`RESEED_LABEL`]).
//!
//! **Equal cores.** Every ex9 case runs on 1 core and on N, the machine's cores
//! ([`core_counts`]): PETSc on 1 process and under `mpiexec -n N` (`benches/petsc/run_ex9.sh`;
//! its peak memory is then the sum of the ranks' peaks), gradvi with 1 and N rayon threads
//! (`RAYON_NUM_THREADS` of the child: the assembly, the multigrid and every other parallel loop
//! run on rayon's global pool). The report compares the codes at equal cores only. The domain
//! cases run on N cores.
//!
//! **The cost ratio R.** Every ex9 case is followed by its linear variant: the same mesh,
//! Dirichlet data, solver and cores without the barrier (gradvi: the problem with its
//! constraint dropped, `--peer-child --no-barrier`; PETSc: `ex9_linear`, ex9 without the bounds
//! and with Newton line search instead of the VI solver, built by `benches/petsc/build.sh`).
//! Its total time is the row's `linear_seconds`, and R = `total_s / linear_seconds`, both
//! measured the same way (PETSc: the whole process or MPI job; gradvi: the child from the mesh
//! to the freeing of everything). With several runs, R is the median of the runs' own ratios
//! and every run's pair is kept (`pairs`, [`median_row`]).
//!
//! **Data evaluation.** Each gradvi row carries two measures of the time spent evaluating the
//! problem's expressions: a bound (`data_seconds`: every datum at every centroid, edge midpoint
//! and vertex) and, for the ex9 obstacle cases, the solve's own evaluations (`data_used_s`):
//! the first run of the case (`--replay-data`) solves it a second time after its timed run, with
//! every datum recorded, and times the recorded evaluations replayed (`super::data_replay`).
//!
//! Every case runs in a child process, as in the scaling benchmark, so that peak memory is the
//! case's own. `GRADVI_BENCH_PEERS` (default `ex9,domains,reseeded`) selects the parts; the rows
//! of the other parts are kept from the existing CSV, and so are those of the ex9 grids not run:
//! below `GRADVI_BENCH_EX9_MIN_GRID` (default 0), above `GRADVI_BENCH_EX9_MAX_GRID`, or left out
//! for memory (4097², [`ex9_grids`]). `GRADVI_BENCH_PEER_REPEAT` (1 to 20, default 1) runs every
//! case that many times, interleaved with the other cases of its grid or mesh, and
//! records the run with the median time ([`run_group`]). `GRADVI_BENCH_LOG=1` prints each
//! solve's timings. Rows go to `replication/results/bench_peers.csv`; the report's first
//! sections are written from it ([`super::report`]).

use super::{Config, bad, io_err, json_row, peak_memory_mib, stdout_of};
use gradvi::budget::MemoryBudget;
use gradvi::budget::human_bytes;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{cartesian_rect_within, cartesian_triangles_within};
use gradvi::mesh::io::read_mesh;
use gradvi::problem::{Problem, paper_test3};
use gradvi::scheme::{Entity, SchemeKind};
use gradvi::solver::{SolveOptions, solve_problem};
use gradvi_cli::replication::records::write_csv;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The CSV of this benchmark.
pub const CSV: &str = "replication/results/bench_peers.csv";
/// Grids G (G × G nodes) of the ex9 comparison; `GRADVI_BENCH_EX9_MAX_GRID` caps them
/// (default [`DEFAULT_MAX_GRID`]).
pub const EX9_GRIDS: [usize; 5] = [257, 513, 1025, 2049, 4097];
/// Default cap on G: all grids. The largest, 4097² (16.8M unknowns), runs only where the
/// memory available is at least [`BIG_GRID_MEMORY`], and there only PETSc and gradvi P1 with
/// the iterative solver: the other variants would not fit in 24 GiB (their peaks at 2049²,
/// which grow about 4-fold per level, are in `replication/BENCHMARKS.md`, "Measurements behind
/// the defaults").
pub const DEFAULT_MAX_GRID: usize = 4097;
/// The grid from which only gradvi P1 iterative runs beside PETSc.
pub const BIG_GRID: usize = 4097;
/// The memory available needed to run [`BIG_GRID`]: 21 GiB, above the measured peaks of gradvi
/// P1 iterative and PETSc there (`replication/BENCHMARKS.md`, "Measurements behind the
/// defaults").
pub const BIG_GRID_MEMORY: u64 = 21 << 30;

/// The gradvi variants (scheme, linear solver) run on the ex9 grid G (see [`BIG_GRID`]).
pub fn ex9_variants(g: usize) -> Vec<(SchemeKind, &'static str)> {
    let all = [SchemeKind::P1, SchemeKind::Hmm]
        .into_iter()
        .flat_map(|s| linear_variants().into_iter().map(move |l| (s, l)));
    if g >= BIG_GRID {
        all.filter(|&(s, l)| s == SchemeKind::P1 && l == "iterative")
            .collect()
    } else {
        all.collect()
    }
}
/// The domains of the "any domain" family (`benches/domains/NAME.geo`).
pub const DOMAINS: [&str; 3] = ["lshape", "disk", "hole"];
/// gmsh characteristic lengths of the domain meshes (about 11k, 44k, 177k and 700k cells on
/// the L-shape; a little more on the others).
pub const DOMAIN_LC: [f64; 4] = [0.0125, 0.00625, 0.003125, 0.0015625];
/// The gmsh seed (`Mesh.RandomSeed`) of the re-seeded domain meshes; the `.geo` files use 1.
pub const RESEED: u32 = 7;
/// gmsh's random perturbation factor (`Mesh.RandomFactor`) of the re-seeded meshes (its
/// default is 10⁻⁹).
pub const RESEED_RANDOM_FACTOR: f64 = 1e-8;
/// Characteristic lengths of the re-seeded domain meshes: sizes the defaults were not tuned on
/// (about 16k, 64k, 126k, 255k and 504k cells on the L-shape; a little more on the others),
/// between those of [`DOMAIN_LC`].
pub const RESEED_LC: [f64; 5] = [0.0105, 0.0052, 0.0037, 0.0026, 0.00185];
/// The `mesh` label of the rows on the re-seeded meshes (empty for the others).
pub const RESEED_LABEL: &str = "seed 7";

/// One row of [`CSV`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PeerRow {
    /// ex9, lshape, disk or hole.
    pub family: String,
    /// gradvi or petsc.
    pub code: String,
    /// p1, hmm (gradvi); fd (PETSc's five-point finite differences).
    pub scheme: String,
    /// How the linear systems are solved: direct or iterative (gradvi), gs+mg (PETSc).
    pub linear: String,
    /// G of the G × G grid (ex9), 0 for the gmsh domains.
    pub grid: usize,
    /// Cells (0 for PETSc).
    pub cells: usize,
    /// Unknowns (ex9: G² for P1 and PETSc).
    pub unknowns: usize,
    /// Linear solves of the fine active-set iteration (PETSc: Newton steps on the finest grid).
    pub niter: usize,
    /// Linear solves of the coarse levels (PETSc: Newton steps on the coarser grids).
    pub coarse_niter: usize,
    /// Krylov iterations, all solves (0 with the direct solver).
    pub krylov: usize,
    /// Everything, from the mesh to the certified solution, the errors and the freeing of it all
    /// (PETSc: the process's wall clock).
    pub total_s: f64,
    /// From the mesh to the certified solution, without the errors and the freeing: the span
    /// the regression check compares with earlier builds (`super::baseline`, "Span"). NaN for
    /// PETSc and in rows written before this column.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub solved_s: f64,
    /// Mesh generation or reading.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub mesh_s: f64,
    /// Data, local matrices, pattern and symbolic factorisation.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub setup_s: f64,
    /// The coarse solves of the warm start.
    #[serde(deserialize_with = "nullable")]
    pub coarse_s: f64,
    /// Condensation and scatter, all iterations.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub assemble_s: f64,
    /// Numeric factorisations or multigrid setups, all iterations.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub factor_s: f64,
    /// Numeric factorisations (or multigrid setups) and solves, all iterations.
    #[serde(deserialize_with = "nullable")]
    pub linear_s: f64,
    /// Peak resident memory of the process, MiB.
    pub peak_mib: f64,
    /// Data evaluation (gradvi; see [`data_seconds`]): an upper bound of its share of the
    /// solve.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub data_s: f64,
    /// The solve's own data evaluations, recorded in a second, untimed solve and replayed on
    /// the solve's threads (`super::data_replay`; gradvi's ex9 obstacle rows, once per case).
    /// NaN where not measured, and in rows written before this column.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub data_used_s: f64,
    /// Largest error against the exact solution (ex9).
    #[serde(deserialize_with = "nullable")]
    pub err_max: f64,
    /// Mean error against the exact solution (ex9).
    #[serde(deserialize_with = "nullable")]
    pub err_mean: f64,
    /// Largest scaled quantity of the certificate (NaN for PETSc).
    #[serde(deserialize_with = "nullable")]
    pub certificate: f64,
    /// Runs of the case (`GRADVI_BENCH_PEER_REPEAT`): the row is that of the run with the
    /// median time, its peak memory the largest of all runs.
    #[serde(default = "one")]
    pub runs: usize,
    /// Cores of the run: gradvi's rayon threads, PETSc's MPI processes (0 in rows written
    /// before this column, when gradvi ran on every core and PETSc on one process).
    #[serde(default)]
    pub cores: usize,
    /// Total time of the linear variant of the case (the same mesh, data, solver and cores,
    /// without the barrier), measured like `total_s`; NaN where it was not run.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub linear_seconds: f64,
    /// The cost ratio R = `total_s / linear_seconds` (NaN without the linear variant). With
    /// several runs ([`median_row`]), the median of the runs' own ratios, and `total_s` and
    /// `linear_seconds` the medians of their times.
    #[serde(deserialize_with = "nullable", default = "nan")]
    pub r: f64,
    /// Which meshes of a domain: empty for the meshes of [`DOMAIN_LC`] (gmsh seed 1, and
    /// ex9's generated grids), [`RESEED_LABEL`] for those of [`RESEED_LC`].
    #[serde(default)]
    pub mesh: String,
    /// Every run's obstacle and linear-variant totals in seconds, in the order run,
    /// `obstacle/linear` separated by spaces (empty without the linear variant, and in rows
    /// written before this column).
    #[serde(default)]
    pub pairs: String,
}

fn one() -> usize {
    1
}

fn nan() -> f64 {
    f64::NAN
}

/// Seconds to evaluate every datum of `problem` at every point of the mesh where a scheme may
/// need it — A at the centroids, f, the barrier and the exact solution at the centroids, edge
/// midpoints and vertices: more evaluations than any scheme makes (P1 reads the barrier at the
/// vertices only, HMM at the centroids; no solve reads the exact solution). The points are
/// split over the threads of rayon's pool, those of the solve, as the assembly and the
/// constraints split their evaluations; so this is an upper bound of the time the solve spends
/// on data at its own core count (the "data evaluation under 10% of a 10⁶-cell solve"
/// is checked against it). Rows before 2026-12-06 timed it on one thread at every core count.
fn data_seconds(mesh: &PolyMesh, problem: &Problem) -> f64 {
    use rayon::prelude::*;
    let t = Instant::now();
    let cells: f64 = (0..mesh.n_cells())
        .into_par_iter()
        .with_min_len(4096)
        .map(|k| {
            let (x, tag) = (mesh.centroid(k), mesh.cell_tag(k));
            let a = problem.diffusion_in(x, tag);
            a[0][0] + problem.source_in(x, x, tag)
        })
        .sum();
    let (nc, ne, nv) = (mesh.n_cells(), mesh.n_edges(), mesh.n_vertices());
    let point = |i: usize| {
        if i < nc {
            mesh.centroid(i)
        } else if i < nc + ne {
            mesh.edge_midpoint(i - nc)
        } else {
            mesh.vertex(i - nc - ne)
        }
    };
    let points: f64 = (0..nc + ne + nv)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let p = point(i);
            let mut acc = problem.source_in(p, p, 0);
            if let Some(c) = &problem.constraint {
                acc += (c.barrier)(p);
            }
            if let Some(e) = &problem.exact {
                acc += (e.u)(p);
            }
            acc
        })
        .sum();
    std::hint::black_box(cells + points);
    t.elapsed().as_secs_f64()
}

/// An f64 that JSON writes as null when it is NaN.
pub(super) fn nullable<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// The ex9 problem of `problems/ex9.toml`.
fn ex9_problem(root: &Path) -> gradvi::Result<Problem> {
    Ok(gradvi::problem::file::load(root.join("problems/ex9.toml"), &[])?.problem())
}

/// Errors against the exact solution, as ex9 computes them: for P1 the nodal values at every
/// vertex (boundary included), max and mean; for HMM the cell values at the centroids.
fn errors(
    scheme: &dyn gradvi::scheme::GradientDiscretisation,
    problem: &Problem,
    u: &[f64],
) -> (f64, f64) {
    let Some(exact) = &problem.exact else {
        return (f64::NAN, f64::NAN);
    };
    let mesh = scheme.mesh();
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    let mut count = 0usize;
    let mut add = |value: f64, p| {
        let e = (value - (exact.u)(p)).abs();
        max = max.max(e);
        sum += e;
        count += 1;
    };
    match scheme.dof_entity(0) {
        Entity::Vertex(_) => {
            for (d, &ud) in u.iter().enumerate() {
                if let Entity::Vertex(v) = scheme.dof_entity(d) {
                    add(ud, mesh.vertex(v));
                }
            }
        }
        _ => {
            for (k, v) in scheme.cell_values(u).into_iter().enumerate() {
                add(v, mesh.centroid(k));
            }
        }
    }
    (max, sum / count.max(1) as f64)
}

/// The solve options of a linear-solver variant.
fn options(linear: &str) -> gradvi::Result<SolveOptions> {
    let mut o = SolveOptions::default();
    o.system.linear = linear.parse()?;
    o.system.budget = MemoryBudget::available();
    Ok(o)
}

/// The mesh, the problem and the grid size (0 for a domain case) of one gradvi case.
fn case_of(
    family: &str,
    scheme: SchemeKind,
    size: usize,
    file: Option<&Path>,
    root: &Path,
) -> gradvi::Result<(PolyMesh, Problem, usize)> {
    Ok(match family {
        "ex9" => {
            let n = size - 1;
            let mesh = match scheme {
                SchemeKind::P1 => cartesian_triangles_within(
                    n,
                    n,
                    [-2.0, 2.0],
                    [-2.0, 2.0],
                    MemoryBudget::available(),
                )?,
                _ => cartesian_rect_within(
                    n,
                    n,
                    [-2.0, 2.0],
                    [-2.0, 2.0],
                    MemoryBudget::available(),
                )?,
            };
            (mesh, ex9_problem(root)?, size)
        }
        _ => {
            let f = file.ok_or_else(|| bad(format!("{family}: a domain case needs its mesh")))?;
            (
                read_mesh(f, MemoryBudget::available())?,
                paper_test3(super::C),
                0,
            )
        }
    })
}

/// The timings of a solve and of each of its steps, on stderr (`GRADVI_BENCH_LOG`).
fn log_solve(sol: &gradvi::solver::Solution) {
    let t = sol.timings;
    eprintln!(
        "[bench]     setup {:.3} (symbolic {:.3}), warm start {:.3}, assembly {:.3}, factor/setup {:.3}, solve {:.3}, look-ahead {:.3}, total {:.3}",
        t.setup, t.symbolic, t.warm_start, t.assemble, t.factor, t.solve, t.look_ahead, t.total
    );
    for l in &sol.result.log {
        eprintln!(
            "[bench]     solve {:>3}: active {:>8} (+{}, -{}), assembly {:.3}, factor/setup {:.3}, solve {:.3}, {} CG",
            l.step.solve,
            l.step.active,
            l.step.entered,
            l.step.left,
            l.timings.assemble,
            l.timings.factor,
            l.timings.solve,
            l.timings.krylov
        );
    }
}

/// One gradvi case of a child process: its family, scheme, linear solver, grid size (0 for a
/// mesh file) and mesh file.
#[derive(Debug, Clone, Copy)]
struct ChildCase<'a> {
    family: &'a str,
    scheme: SchemeKind,
    linear: &'a str,
    size: usize,
    file: Option<&'a Path>,
}

/// Solves one gradvi case in this process (the body of a `--peer-child` process); without the
/// `barrier`, its linear variant (the problem's constraint dropped); with `replay`, its data
/// evaluations measured after the timed run ([`replayed_data_seconds`]).
fn run_gradvi(
    case: ChildCase,
    root: &Path,
    (barrier, replay): (bool, bool),
) -> gradvi::Result<PeerRow> {
    let ChildCase {
        family,
        scheme,
        linear,
        size,
        file,
    } = case;
    let t0 = Instant::now();
    let (mesh, mut problem, grid) = case_of(family, scheme, size, file, root)?;
    if !barrier {
        problem.constraint = None;
    }
    let mesh_s = t0.elapsed().as_secs_f64();
    let scheme_obj = gradvi::scheme::build(scheme, &mesh)?;
    let sol = solve_problem(scheme_obj.as_ref(), &problem, &options(linear)?)?;
    let solved_s = t0.elapsed().as_secs_f64();
    if let Some(why) = sol.warm_start.as_ref().and_then(|w| w.skipped.as_ref()) {
        return Err(bad(format!("{family} {size}: no nested prediction: {why}")));
    }
    if std::env::var_os("GRADVI_BENCH_LOG").is_some() {
        log_solve(&sol);
    }
    // errors as ex9 computes them, inside the timing as in ex9's
    let (err_max, err_mean) = errors(scheme_obj.as_ref(), &problem, sol.u());
    // a measurement of the benchmark only: taken out of the total below
    let data_s = data_seconds(&mesh, &problem);
    let c = sol.result.certificate;
    let t = sol.timings;
    let mut row = PeerRow {
        family: family.into(),
        code: "gradvi".into(),
        scheme: scheme.to_string(),
        linear: linear.into(),
        grid,
        cells: mesh.n_cells(),
        unknowns: sol.system.n_unknowns(),
        niter: sol.niter(),
        coarse_niter: sol.warm_start.as_ref().map_or(0, |w| w.coarse_solves),
        krylov: sol.result.log.iter().map(|l| l.timings.krylov).sum(),
        total_s: f64::NAN,
        solved_s,
        mesh_s,
        setup_s: t.setup,
        coarse_s: t.warm_start,
        assemble_s: t.assemble,
        factor_s: t.factor,
        linear_s: t.factor + t.solve,
        peak_mib: f64::NAN,
        data_s,
        data_used_s: f64::NAN,
        err_max,
        err_mean,
        certificate: c.worst(),
        runs: 1,
        cores: rayon_threads(),
        linear_seconds: f64::NAN,
        r: f64::NAN,
        mesh: String::new(),
        pairs: String::new(),
    };
    // PETSc's time is its whole process, finalisation (freeing) included: so is this one
    drop(sol);
    drop(scheme_obj);
    drop(mesh);
    drop(problem);
    row.total_s = t0.elapsed().as_secs_f64() - data_s;
    row.peak_mib = peak_memory_mib();
    if replay {
        row.data_used_s = replayed_data_seconds(case, root)?;
    }
    Ok(row)
}

/// The seconds the solve of a case spends evaluating its data, with its errors against the
/// exact solution: the case solved again with every datum recorded (`super::data_replay`),
/// after the timed run and its peak memory, and the recorded evaluations replayed.
fn replayed_data_seconds(case: ChildCase, root: &Path) -> gradvi::Result<f64> {
    let (mesh, problem, _) = case_of(case.family, case.scheme, case.size, case.file, root)?;
    let (problem, logs) = super::data_replay::record(problem);
    let scheme_obj = gradvi::scheme::build(case.scheme, &mesh)?;
    let sol = solve_problem(scheme_obj.as_ref(), &problem, &options(case.linear)?)?;
    std::hint::black_box(errors(scheme_obj.as_ref(), &problem, sol.u()));
    drop(sol);
    let r = logs.replay_seconds();
    let by: Vec<String> = r
        .by_datum
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(name, n)| format!("{name} {n}"))
        .collect();
    eprintln!(
        "[bench]     data: {} evaluations recorded ({}), replayed in {:.3} s",
        r.evaluations,
        by.join(", "),
        r.seconds
    );
    Ok(r.seconds)
}

/// The threads of rayon's global pool in this process (`RAYON_NUM_THREADS`, or every core).
fn rayon_threads() -> usize {
    rayon::current_num_threads()
}

/// Arguments of a child process: `[--no-barrier] [--replay-data] FAMILY SCHEME LINEAR SIZE
/// [FILE]` (`--no-barrier`: the linear variant; `--replay-data`: the data evaluations measured
/// after the timed run, [`replayed_data_seconds`]).
pub fn child_main(args: &[String], root: &Path) -> gradvi::Result<()> {
    let mut args = args;
    let (mut barrier, mut replay) = (true, false);
    while let Some(flag) = args.first().filter(|a| a.starts_with("--")) {
        match flag.as_str() {
            NO_BARRIER => barrier = false,
            REPLAY_DATA => replay = true,
            other => return Err(bad(format!("--peer-child: unknown flag '{other}'"))),
        }
        args = &args[1..];
    }
    if args.len() < 4 {
        return Err(bad(format!(
            "--peer-child [{NO_BARRIER}] [{REPLAY_DATA}] FAMILY SCHEME LINEAR SIZE [FILE]"
        )));
    }
    let size = args[3]
        .parse()
        .map_err(|_| bad(format!("bad size '{}'", args[3])))?;
    let case = ChildCase {
        family: &args[0],
        scheme: args[1].parse()?,
        linear: &args[2],
        size,
        file: args.get(4).map(Path::new),
    };
    let row = run_gradvi(case, root, (barrier, replay))?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
    );
    Ok(())
}

/// The flag of a child process that runs the linear variant of its case.
const NO_BARRIER: &str = "--no-barrier";
/// The flag of a child process that also measures the data evaluations of its solve
/// ([`replayed_data_seconds`]).
const REPLAY_DATA: &str = "--replay-data";

/// PETSc's ex9 at grid G on `nproc` MPI processes through `benches/petsc/run_ex9.sh` (built
/// once by `build.sh`); `bin` is `ex9` or `ex9_linear`.
fn run_petsc(cfg: &Config, bin: &Path, grid: usize, nproc: usize) -> gradvi::Result<PeerRow> {
    let mut cmd = Command::new("bash");
    cmd.arg(cfg.path("benches/petsc/run_ex9.sh"))
        .arg(bin)
        .arg(grid.to_string())
        .arg(nproc.to_string());
    let text = stdout_of(cmd, Path::new("benches/petsc/run_ex9.sh"), "PETSc ex9")?;
    #[derive(Deserialize)]
    struct Ex9 {
        processes: usize,
        unknowns: usize,
        seconds: f64,
        peak_mib: f64,
        snes_iterations: usize,
        snes_iterations_final: usize,
        ksp_iterations: usize,
        err_max: f64,
        err_mean: f64,
    }
    let r: Ex9 = json_row(&text, &format!("PETSc ex9 at {grid}: bad output"))?;
    Ok(PeerRow {
        family: "ex9".into(),
        code: "petsc".into(),
        scheme: "fd".into(),
        linear: "gs+mg".into(),
        grid,
        cells: 0,
        unknowns: r.unknowns,
        niter: r.snes_iterations_final,
        coarse_niter: r.snes_iterations - r.snes_iterations_final,
        krylov: r.ksp_iterations,
        total_s: r.seconds,
        solved_s: f64::NAN,
        mesh_s: f64::NAN,
        setup_s: f64::NAN,
        coarse_s: f64::NAN,
        assemble_s: f64::NAN,
        factor_s: f64::NAN,
        linear_s: f64::NAN,
        peak_mib: r.peak_mib,
        data_s: f64::NAN,
        data_used_s: f64::NAN,
        err_max: r.err_max,
        err_mean: r.err_mean,
        certificate: f64::NAN,
        runs: 1,
        cores: r.processes,
        linear_seconds: f64::NAN,
        r: f64::NAN,
        mesh: String::new(),
        pairs: String::new(),
    })
}

/// `obstacle` with the time of its linear variant `linear` and the cost ratio R.
fn with_linear(mut obstacle: PeerRow, linear: &PeerRow) -> PeerRow {
    obstacle.linear_seconds = linear.total_s;
    obstacle.r = obstacle.total_s / linear.total_s;
    obstacle.pairs = format!("{:.4}/{:.4}", obstacle.total_s, linear.total_s);
    obstacle
}

/// The (obstacle, linear) totals of a row's [`PeerRow::pairs`], in the order run; `None` if the
/// text is not such a list.
pub fn pairs_of(text: &str) -> Option<Vec<(f64, f64)>> {
    text.split_whitespace()
        .map(|p| {
            let (a, b) = p.split_once('/')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .collect()
}

/// The core counts of the ex9 comparison: 1 and N, the cores of this machine
/// (`std::thread::available_parallelism`).
pub fn core_counts() -> Vec<usize> {
    let n = std::thread::available_parallelism().map_or(1, |n| n.get());
    if n > 1 { vec![1, n] } else { vec![1] }
}

/// Installs (if missing) and builds PETSc's ex9; its path, or why not.
fn build_petsc(cfg: &Config) -> Result<PathBuf, String> {
    let run = |script: &str, arg: Option<&Path>| -> Result<String, String> {
        let mut cmd = Command::new("bash");
        cmd.arg(cfg.path(script));
        if let Some(a) = arg {
            cmd.arg(a);
        }
        let out = cmd
            .stderr(Stdio::inherit())
            .output()
            .map_err(|e| format!("{script}: {e}"))?;
        if !out.status.success() {
            return Err(format!("{script} failed ({})", out.status));
        }
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    };
    run("benches/petsc/install.sh", None)?;
    let out = run(
        "benches/petsc/build.sh",
        Some(&cfg.path("target/petsc-ex9")),
    )?;
    let bin = out.lines().last().unwrap_or("").trim().to_string();
    Ok(PathBuf::from(bin))
}

/// The gmsh mesh of `domain` at characteristic length `lc` (written once into
/// `target/bench-meshes/`), with the seed of its `.geo` file (1) or with `seed` (and
/// [`RESEED_RANDOM_FACTOR`]): then gmsh meshes a `.geo` written next to the mesh, which
/// includes the domain's and sets both options after it.
fn domain_mesh(cfg: &Config, domain: &str, lc: f64, seed: Option<u32>) -> gradvi::Result<PathBuf> {
    let dir = cfg.path(super::MESH_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
    let mut geo = cfg.path(&format!("benches/domains/{domain}.geo"));
    let msh = match seed {
        None => dir.join(format!("{domain}_{lc}.msh")),
        Some(s) => dir.join(format!("{domain}_seed{s}_{lc}.msh")),
    };
    if msh.exists() {
        return Ok(msh);
    }
    if let Some(s) = seed {
        let wrapper = dir.join(format!("{domain}_seed{s}.geo"));
        let text = format!(
            "Include \"{}\";\nMesh.RandomSeed = {s};\nMesh.RandomFactor = {RESEED_RANDOM_FACTOR:e};\n",
            geo.display()
        );
        std::fs::write(&wrapper, text).map_err(|e| io_err(&wrapper, e))?;
        geo = wrapper;
    }
    eprintln!("[bench] gmsh: meshing {} (lc {lc})", geo.display());
    super::run_gmsh(
        &geo,
        &msh,
        2,
        &["-setnumber".into(), "lc".into(), lc.to_string()],
    )?;
    Ok(msh)
}

/// How a gradvi child runs: its rayon threads (`None`: every core), whether the problem
/// keeps its barrier (`false`: the linear variant) and whether it measures its data
/// evaluations after the timed run ([`REPLAY_DATA`]).
#[derive(Debug, Clone, Copy)]
struct ChildRun {
    threads: Option<usize>,
    barrier: bool,
    replay: bool,
}

/// One gradvi case run in a child process.
fn gradvi_child(
    exe: &Path,
    (family, scheme, linear): (&str, SchemeKind, &str),
    size: usize,
    file: Option<&Path>,
    run: ChildRun,
) -> gradvi::Result<PeerRow> {
    let mut cmd = Command::new(exe);
    let mut args = child_args(family, scheme, linear, size, file);
    if run.replay {
        args.insert(2, REPLAY_DATA.into());
    }
    if !run.barrier {
        args.insert(2, NO_BARRIER.into());
    }
    cmd.args(args);
    if let Some(t) = run.threads {
        cmd.env("RAYON_NUM_THREADS", t.to_string());
    }
    let what = format!(
        "{family} {scheme} {linear} {size}{}",
        if run.barrier { "" } else { " (linear variant)" }
    );
    let text = stdout_of(cmd, exe, &what)?;
    json_row(&text, &format!("{what}: bad child output"))
}

/// The arguments of `gradvi` that run one gradvi case of this benchmark in a child process.
pub fn child_args(
    family: &str,
    scheme: SchemeKind,
    linear: &str,
    size: usize,
    file: Option<&Path>,
) -> Vec<String> {
    let mut args = vec!["bench".to_string(), "--peer-child".to_string()];
    args.extend([family.to_string(), scheme.to_string(), linear.to_string()]);
    args.push(size.to_string());
    args.extend(file.map(|f| f.display().to_string()));
    args
}

/// The linear-solver variants of gradvi that the peer benchmark runs.
pub fn linear_variants() -> Vec<&'static str> {
    vec!["direct", "iterative"]
}

/// Runs the peer benchmark and writes [`CSV`] (rows appended as they come).
pub fn run(cfg: &Config, exe: &Path) -> gradvi::Result<()> {
    let max_grid = super::usize_from_env("GRADVI_BENCH_EX9_MAX_GRID", DEFAULT_MAX_GRID)?;
    let min_grid = super::usize_from_env("GRADVI_BENCH_EX9_MIN_GRID", 0)?;
    let csv = cfg.path(CSV);
    let parts =
        std::env::var("GRADVI_BENCH_PEERS").unwrap_or_else(|_| "ex9,domains,reseeded".into());
    let part = |name: &str| parts.split(',').any(|p| p.trim() == name);
    let (do_ex9, do_domains, do_reseeded) = (part("ex9"), part("domains"), part("reseeded"));
    let ex9 = grids_from(ex9_grids(if do_ex9 { max_grid } else { 0 }), min_grid);
    let mut rows = kept_rows(read_rows(cfg)?, &ex9, do_domains, do_reseeded);
    let push = |row: PeerRow, rows: &mut Vec<PeerRow>| -> gradvi::Result<()> {
        eprintln!(
            "[bench]   {} {} {} {}, {} cores: {} unknowns, NITER {} (+{} coarse), {:.2} s, {:.0} MiB, errors {:.3e} / {:.3e}, linear variant {:.2} s (R {:.2})",
            row.family,
            row.code,
            row.scheme,
            row.linear,
            row.cores,
            row.unknowns,
            row.niter,
            row.coarse_niter,
            row.total_s,
            row.peak_mib,
            row.err_max,
            row.err_mean,
            row.linear_seconds,
            row.r
        );
        rows.push(row);
        // ex9 first, by grid (a kept grid may come after the grids run), each grid's rows in
        // the order they were run
        rows.sort_by_key(|r| {
            (
                r.family != "ex9",
                if r.family == "ex9" { r.grid } else { 0 },
            )
        });
        write_csv(&csv, rows)
    };
    let petsc = if do_ex9 {
        build_petsc(cfg)
    } else {
        Err("not asked for".into())
    };
    if let (true, Err(why)) = (do_ex9, &petsc) {
        eprintln!("[bench] warning: no PETSc rows: {why}");
    }
    let repeat = super::repeat_from_env("GRADVI_BENCH_PEER_REPEAT", 1)?;
    if repeat > 1 {
        eprintln!("[bench] {repeat} runs of every case, interleaved; rows: the median time");
    }
    for g in ex9 {
        let group = ex9_group(cfg, exe, petsc.as_deref().ok(), g);
        for row in run_group(&group, repeat)? {
            push(row, &mut rows)?;
        }
    }
    let mut domains: Vec<(DomainCase, &str)> = Vec::new();
    if do_domains {
        domains.extend(domain_cases(cfg, true)?.into_iter().map(|c| (c, "")));
    }
    if do_reseeded {
        domains.extend(reseeded_cases(cfg)?.into_iter().map(|c| (c, RESEED_LABEL)));
    }
    // the cases of one mesh form a group
    for mesh_cases in domains.chunk_by(|a, b| a.0.3 == b.0.3) {
        let group: Vec<Case> = mesh_cases
            .iter()
            .map(|((domain, scheme, linear, file), label)| -> Case {
                (
                    format!("{domain} ({}) gradvi {scheme} {linear}", file.display()),
                    Box::new(move |_| {
                        let what = (*domain, *scheme, *linear);
                        let run = ChildRun {
                            threads: None,
                            barrier: true,
                            replay: false,
                        };
                        let mut row = gradvi_child(exe, what, 0, Some(file.as_path()), run)?;
                        row.mesh = label.to_string();
                        Ok(row)
                    }),
                )
            })
            .collect();
        for row in run_group(&group, repeat)? {
            push(row, &mut rows)?;
        }
    }
    Ok(())
}

/// The ex9 cases of grid `g` (PETSc's when its binary `petsc` is there, then gradvi's), on each
/// of the [`core_counts`], each followed by its linear variant.
fn ex9_group<'a>(
    cfg: &'a Config,
    exe: &'a Path,
    petsc: Option<&'a Path>,
    g: usize,
) -> Vec<Case<'a>> {
    let mut group: Vec<Case> = Vec::new();
    for n in core_counts() {
        if let Some(bin) = petsc {
            let linear_bin = bin.with_file_name("ex9_linear");
            group.push((
                format!("ex9 PETSc gs+mg, {g}² grid, {n} processes (+ linear variant)"),
                Box::new(move |_| {
                    let obstacle = run_petsc(cfg, bin, g, n)?;
                    Ok(with_linear(obstacle, &run_petsc(cfg, &linear_bin, g, n)?))
                }),
            ));
        }
        for (scheme, linear) in ex9_variants(g) {
            let run = move |barrier, replay| {
                let threads = Some(n);
                let what = ("ex9", scheme, linear);
                let how = ChildRun {
                    threads,
                    barrier,
                    replay,
                };
                gradvi_child(exe, what, g, None, how)
            };
            // the first run of the case also measures its data evaluations
            group.push((
                format!("ex9 gradvi {scheme} {linear}, {g}² grid, {n} threads (+ linear variant)"),
                Box::new(move |r| {
                    let obstacle = run(true, r == 0)?;
                    Ok(with_linear(obstacle, &run(false, false)?))
                }),
            ));
        }
    }
    group
}

/// A case of this benchmark: what it is, and how to run it once (given the index of the run,
/// 0 for the first).
type Case<'a> = (String, Box<dyn Fn(usize) -> gradvi::Result<PeerRow> + 'a>);

/// Runs every case of `group` `repeat` times, the cases interleaved (so that a slow spell of
/// the machine falls on all of them), and returns one row per case: the run with the median
/// time (the upper median for an even count), with the largest peak memory of its runs.
fn run_group(group: &[Case], repeat: usize) -> gradvi::Result<Vec<PeerRow>> {
    let mut samples: Vec<Vec<PeerRow>> = vec![Vec::new(); group.len()];
    for r in 0..repeat {
        for ((what, run), out) in group.iter().zip(&mut samples) {
            if repeat > 1 {
                eprintln!("[bench] {what} (run {} of {repeat}) ...", r + 1);
            } else {
                eprintln!("[bench] {what} ...");
            }
            out.push(run(r)?);
        }
    }
    Ok(samples.into_iter().filter_map(median_row).collect())
}

/// The upper median of `x` (NaN if empty).
fn upper_median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x.get(x.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The row with the median time of `runs` (the upper median for an even count), with the
/// largest peak memory and the number of runs; `None` if there is none. With the linear
/// variant, R is the median of the runs' own ratios (each run's obstacle solve and linear
/// variant measured one after the other, in the same state of the machine), the linear
/// variant's time the median of its runs, and every run's pair is kept
/// ([`PeerRow::pairs`]).
fn median_row(mut runs: Vec<PeerRow>) -> Option<PeerRow> {
    let peak = runs.iter().map(|r| r.peak_mib).fold(f64::NAN, f64::max);
    // measured in one run only (the first)
    let data_used = runs.iter().map(|r| r.data_used_s).fold(f64::NAN, f64::max);
    let n = runs.len();
    let r = upper_median(runs.iter().map(|r| r.r).collect());
    let linear = upper_median(runs.iter().map(|r| r.linear_seconds).collect());
    let pairs: Vec<&str> = runs.iter().map(|r| r.pairs.as_str()).collect();
    let pairs = pairs.join(" ").trim().to_string();
    runs.sort_by(|a, b| a.total_s.total_cmp(&b.total_s));
    let mut row = runs.into_iter().nth(n / 2)?;
    row.peak_mib = peak;
    row.data_used_s = data_used;
    row.runs = n;
    row.r = r;
    row.linear_seconds = linear;
    row.pairs = pairs;
    Some(row)
}

/// The grids of `grids` (those [`ex9_grids`] admits) from `min_grid` up: the ex9 grids this run
/// solves.
fn grids_from(grids: Vec<usize>, min_grid: usize) -> Vec<usize> {
    grids.into_iter().filter(|&g| g >= min_grid).collect()
}

/// The rows of the existing CSV that a run keeps: the ex9 rows of every grid not in `ex9` (the
/// grids it solves), the any-domain rows unless it runs that part (`do_domains`), the
/// re-seeded rows unless it runs those (`do_reseeded`). The rows of the grids and parts it runs
/// are replaced by its own.
fn kept_rows(
    rows: Vec<PeerRow>,
    ex9: &[usize],
    do_domains: bool,
    do_reseeded: bool,
) -> Vec<PeerRow> {
    rows.into_iter()
        .filter(|r| {
            if r.family == "ex9" {
                !ex9.contains(&r.grid)
            } else if r.mesh == RESEED_LABEL {
                !do_reseeded
            } else {
                !do_domains
            }
        })
        .collect()
}

/// The ex9 grids up to `max_grid` that fit in the memory available ([`BIG_GRID`] needs
/// [`BIG_GRID_MEMORY`]; a grid left out is said on stderr).
fn ex9_grids(max_grid: usize) -> Vec<usize> {
    let available = MemoryBudget::available().bytes();
    EX9_GRIDS
        .into_iter()
        .filter(|&g| g <= max_grid)
        .filter(|&g| {
            let fits = g < BIG_GRID || available >= BIG_GRID_MEMORY;
            if !fits {
                eprintln!(
                    "[bench] warning: ex9 {g}² skipped: {} available, it needs {}",
                    human_bytes(available),
                    human_bytes(BIG_GRID_MEMORY)
                );
            }
            fits
        })
        .collect()
}

/// A gradvi case of the any-domain part: domain, scheme, linear solver and mesh file.
type DomainCase = (&'static str, SchemeKind, &'static str, PathBuf);

/// Whether a mesh of characteristic length `lc` of one of the [`DOMAINS`] is within the cell
/// cap of `cfg` (about 2.3/lc² triangles per unit area, areas 0.75 to 0.97).
fn within_cap(cfg: &Config, lc: f64) -> bool {
    0.75 * 2.3 / (lc * lc) <= cfg.max_cells as f64
}

/// The gradvi cases of the any-domain part, on the meshes of [`DOMAIN_LC`]: the meshes written
/// by gmsh when missing, those above the cell cap of `cfg` left out. Each mesh runs both
/// [`linear_variants`] and, with `auto`, the default linear solver too (the direct/iterative
/// switch falls inside the sizes, as on the re-seeded meshes).
fn domain_cases(cfg: &Config, auto: bool) -> gradvi::Result<Vec<DomainCase>> {
    let mut out = Vec::new();
    let mut linears = linear_variants();
    if auto {
        linears.push("auto");
    }
    for domain in DOMAINS {
        for &lc in DOMAIN_LC.iter().filter(|&&lc| within_cap(cfg, lc)) {
            let file = domain_mesh(cfg, domain, lc, None)?;
            for scheme in [SchemeKind::Hmm, SchemeKind::P1] {
                for &linear in &linears {
                    out.push((domain, scheme, linear, file.clone()));
                }
            }
        }
    }
    Ok(out)
}

/// The cases on the re-seeded meshes ([`RESEED`], [`RESEED_LC`]), HMM and P1 with the default
/// linear solver (`auto`: direct below `assembly::AUTO_ITERATIVE_MIN` condensed unknowns,
/// iterative above, so that the sizes cross the switch), within the cell cap of `cfg`.
fn reseeded_cases(cfg: &Config) -> gradvi::Result<Vec<DomainCase>> {
    let mut out = Vec::new();
    for domain in DOMAINS {
        for &lc in RESEED_LC.iter().filter(|&&lc| within_cap(cfg, lc)) {
            let file = domain_mesh(cfg, domain, lc, Some(RESEED))?;
            for scheme in [SchemeKind::Hmm, SchemeKind::P1] {
                out.push((domain, scheme, "auto", file.clone()));
            }
        }
    }
    Ok(out)
}

/// A gradvi case of this benchmark: family, scheme, linear solver, size (the ex9 grid; 0 for a
/// domain) and mesh file (domains).
pub type GradviCase = (String, SchemeKind, &'static str, usize, Option<PathBuf>);

/// Every gradvi case of this benchmark (ex9 up to the grid `max_grid`, then the domains), for
/// the regression check ([`super::baseline`]).
pub fn gradvi_cases(cfg: &Config, max_grid: usize) -> gradvi::Result<Vec<GradviCase>> {
    let mut out: Vec<GradviCase> = Vec::new();
    for g in ex9_grids(max_grid) {
        for (scheme, linear) in ex9_variants(g) {
            out.push(("ex9".into(), scheme, linear, g, None));
        }
    }
    // the forced solvers only: the regression check's earlier build may not know `auto`
    for (domain, scheme, linear, file) in domain_cases(cfg, false)? {
        out.push((domain.into(), scheme, linear, 0, Some(file)));
    }
    Ok(out)
}

/// The rows of [`CSV`] (empty if it does not exist).
pub fn read_rows(cfg: &Config) -> gradvi::Result<Vec<PeerRow>> {
    super::read_rows_of(cfg, CSV)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of `family` on grid `grid` (0 for a mesh file) from `mesh` (`""`, or
    /// [`RESEED_LABEL`] for the re-seeded meshes), by `code`.
    fn row(family: &str, code: &str, grid: usize, mesh: &str) -> PeerRow {
        PeerRow {
            family: family.into(),
            code: code.into(),
            scheme: "p1".into(),
            linear: "iterative".into(),
            grid,
            cells: 0,
            unknowns: grid * grid,
            niter: 3,
            coarse_niter: 0,
            krylov: 0,
            total_s: 1.0,
            solved_s: f64::NAN,
            mesh_s: f64::NAN,
            setup_s: f64::NAN,
            coarse_s: f64::NAN,
            assemble_s: f64::NAN,
            factor_s: f64::NAN,
            linear_s: f64::NAN,
            peak_mib: 1.0,
            data_s: f64::NAN,
            data_used_s: f64::NAN,
            err_max: 1e-6,
            err_mean: 1e-7,
            certificate: 1e-12,
            runs: 1,
            cores: 1,
            linear_seconds: f64::NAN,
            r: f64::NAN,
            mesh: mesh.into(),
            pairs: String::new(),
        }
    }

    /// What a CSV keeps: (family, code, grid, mesh) of each row.
    fn keys(rows: &[PeerRow]) -> Vec<(String, String, usize, String)> {
        rows.iter()
            .map(|r| (r.family.clone(), r.code.clone(), r.grid, r.mesh.clone()))
            .collect()
    }

    /// The rows of an earlier full run: PETSc and gradvi at every ex9 grid, one any-domain
    /// row, one re-seeded row.
    fn earlier() -> Vec<PeerRow> {
        let mut rows = Vec::new();
        for g in EX9_GRIDS {
            rows.push(row("ex9", "petsc", g, ""));
            rows.push(row("ex9", "gradvi", g, ""));
        }
        rows.push(row("lshape", "gradvi", 0, ""));
        rows.push(row("disk", "gradvi", 0, RESEED_LABEL));
        rows
    }

    #[test]
    fn a_run_of_one_grid_keeps_the_rows_of_every_other_grid_and_part() {
        // GRADVI_BENCH_PEERS=ex9, MIN_GRID = MAX_GRID = 1025: ex9_grids(1025) admits the three
        // smallest grids, the lower bound leaves 1025 alone
        let ex9 = grids_from(vec![257, 513, 1025], 1025);
        assert_eq!(ex9, vec![1025]);
        let kept = kept_rows(earlier(), &ex9, false, false);
        let mut want = keys(&earlier());
        want.retain(|k| k.2 != 1025);
        assert_eq!(keys(&kept), want);
        // 4097 left out for memory (not in the grids run): its rows are kept as well
        assert!(kept.iter().filter(|r| r.grid == 4097).count() == 2);
    }

    #[test]
    fn a_part_that_runs_replaces_its_own_rows_only() {
        let every_grid = grids_from(EX9_GRIDS.to_vec(), 0);
        assert_eq!(every_grid, EX9_GRIDS.to_vec());
        // the any-domain part alone: every ex9 row and the re-seeded row stay
        let kept = kept_rows(earlier(), &[], true, false);
        assert_eq!(kept.len(), earlier().len() - 1);
        assert!(kept.iter().all(|r| r.family != "lshape"));
        // everything runs: nothing is kept
        assert!(kept_rows(earlier(), &every_grid, true, true).is_empty());
        // a lower bound above every grid runs none of them and keeps every ex9 row
        assert!(grids_from(EX9_GRIDS.to_vec(), 5000).is_empty());
        assert_eq!(
            kept_rows(earlier(), &[], false, false).len(),
            earlier().len()
        );
    }

    #[test]
    fn a_child_rejects_an_unknown_flag_and_a_missing_size() {
        let root = Path::new(".");
        let args = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let err = child_main(&args(&["--replay", "ex9", "p1", "iterative", "5"]), root);
        assert!(
            err.unwrap_err()
                .to_string()
                .contains("unknown flag '--replay'")
        );
        let err = child_main(
            &args(&[NO_BARRIER, REPLAY_DATA, "ex9", "p1", "iterative"]),
            root,
        );
        assert!(
            err.unwrap_err()
                .to_string()
                .contains("FAMILY SCHEME LINEAR SIZE")
        );
    }

    #[test]
    fn each_run_of_a_group_gets_its_index_and_the_first_measures_the_data() {
        let case: Case = (
            "a case".into(),
            Box::new(|r| {
                let mut x = row("ex9", "gradvi", 1025, "");
                x.total_s = 1.0 + r as f64;
                x.data_used_s = if r == 0 { 0.25 } else { f64::NAN };
                Ok(x)
            }),
        );
        let rows = run_group(&[case], 3).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(
            (rows[0].total_s, rows[0].data_used_s, rows[0].runs),
            (2.0, 0.25, 3)
        );
    }

    #[test]
    fn the_median_row_keeps_the_data_measured_in_one_run() {
        let mut runs: Vec<PeerRow> = (0..3).map(|_| row("ex9", "gradvi", 1025, "")).collect();
        for (r, t) in runs.iter_mut().zip([3.0, 1.0, 2.0]) {
            r.total_s = t;
        }
        runs[0].data_used_s = 0.25;
        let m = median_row(runs).unwrap();
        assert_eq!((m.total_s, m.data_used_s, m.runs), (2.0, 0.25, 3));
    }

    /// R of several runs is the median of the runs' ratios, not the ratio within the run of the
    /// median obstacle time; the linear time is its runs' median; every pair is kept in order.
    #[test]
    fn the_median_row_takes_the_median_of_the_runs_ratios() {
        let linear = |t: f64| {
            let mut l = row("ex9", "gradvi", 1025, "");
            l.total_s = t;
            l
        };
        let runs: Vec<PeerRow> = [(2.0, 1.0), (3.0, 2.0), (2.5, 2.4)]
            .into_iter()
            .map(|(o, l)| {
                let mut x = row("ex9", "gradvi", 1025, "");
                x.total_s = o;
                with_linear(x, &linear(l))
            })
            .collect();
        // the run of the median obstacle time (2.5 s) has the ratio 1.04; the runs' ratios are
        // 2, 1.5 and 1.04
        let m = median_row(runs).unwrap();
        assert_eq!((m.total_s, m.linear_seconds, m.r), (2.5, 2.0, 1.5));
        assert_eq!(m.pairs, "2.0000/1.0000 3.0000/2.0000 2.5000/2.4000");
        assert_eq!(
            pairs_of(&m.pairs),
            Some(vec![(2.0, 1.0), (3.0, 2.0), (2.5, 2.4)])
        );
        assert_eq!(pairs_of("2.0/1.0 x"), None);
        // without the linear variant nothing changes
        let alone = median_row(vec![row("ex9", "petsc", 1025, "")]).unwrap();
        assert!(alone.r.is_nan() && alone.linear_seconds.is_nan() && alone.pairs.is_empty());
    }

    #[test]
    fn a_size_bound_that_is_not_an_integer_is_an_error_not_the_default() {
        use super::super::parse_usize_var;
        let var = "GRADVI_BENCH_EX9_MIN_GRID";
        assert_eq!(parse_usize_var(var, None, 7).unwrap(), 7);
        assert_eq!(parse_usize_var(var, Some(" 1025 "), 7).unwrap(), 1025);
        for bad in ["1e3", "-1", "", "1025²"] {
            let e = parse_usize_var(var, Some(bad), 7).unwrap_err().to_string();
            assert!(e.contains(var) && e.contains(bad), "{bad}: {e}");
        }
    }
}
