//! The scaling benchmark behind `make bench` (`gradvi-dev bench`).
//!
//! Test 3 of the paper (obstacle problem, C = −5, [`gradvi::problem::paper_test3`]) is solved
//!
//! - with HMM and P1 on gmsh triangle meshes of the unit square from 10³ to 10⁶ cells (written
//!   at bench time from `meshes/test3_4.geo` with smaller characteristic lengths into
//!   `target/bench-meshes/`, which is not committed),
//! - with HMM on the hexagonal ([`gradvi::mesh::generate::hexagonal()`]) and Cartesian families,
//! - with the dolfinx P1 reference (`reference/solve.py`, PETSc SNES VI) on the same gmsh meshes
//!   up to [`DOLFINX_MAX_CELLS`] cells.
//!
//! Every case runs in a child process (`gradvi-dev` re-invokes itself with `bench --child`),
//! so that the peak resident memory (`VmHWM` of `/proc/self/status`) is that of the case alone.
//! A child prints one JSON [`BenchRow`]; the driver appends it to
//! `replication/results/bench.csv` as soon as it is known, and at the end writes
//! `replication/BENCHMARKS.md` and `replication/figures/bench.png` from that CSV only
//! ([`write_report`]).
//!
//! Four variants of gradvi's solver are timed:
//! - `cold`: the default options (the paper's monotony algorithm from A₀ = ∅, as in
//!   [`gradvi::solver::solve_problem`]);
//! - `nested`: the same algorithm with an initial active set predicted by a chain of coarse
//!   HMM solves on agglomerated meshes ([`gradvi::solver::warm_start`], the default of
//!   `gradvi solve`): the coarse solves cost a fraction of the fine one, and the fine
//!   iteration starts next to its solution. The certificate is the same;
//! - `nested-par`: `nested` with faer's parallel numeric factorisation instead of the
//!   sequential default ([`gradvi::linalg::FactorThreads`]), to measure that lever;
//! - `nested-nd`: `nested` with the nested-dissection ordering instead of AMD
//!   ([`gradvi::linalg::Ordering`]), to measure that one.
//!
//! Environment: `GRADVI_BENCH_MAX_CELLS` caps the mesh sizes (default [`DEFAULT_MAX_CELLS`]),
//! `GRADVI_BENCH_DOLFINX_MAX_CELLS` those of the dolfinx runs, `GRADVI_BENCH_VARIANTS`
//! (comma-separated, default `cold,nested,nested-par,nested-nd`) the gradvi variants. Progress goes to stderr;
//! `GRADVI_BENCH_LOG=1` adds each case's active-set log and factor size;
//! `GRADVI_BENCH_MERGE=1` keeps the rows of the existing CSV that the run does not redo (the
//! report then says that its rows come from several runs).
//! Arguments: `--report-only` rewrites the report from the existing CSV; `--child FAMILY
//! SCHEME VARIANT SIZE [FILE]` runs one case and prints its row as JSON; `--baseline EXE
//! [--baseline-rev REV]` compares every gradvi case with the earlier build EXE in the same run
//! ([`baseline`]); `--mesh3d` times reading and building tetrahedral meshes ([`mesh3d`]);
//! `--domains3d` runs the 3D any-domain benchmark (`domains3d`); `--hmm3d` runs HMM on n³
//! cubes of (−2,2)³ (`hmm3d`).

use gradvi::budget::MemoryBudget;
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{Family, cartesian_rect_within};
use gradvi::mesh::io::read_mesh;
use gradvi::problem::paper_test3;
use gradvi::scheme::SchemeKind;
use gradvi::solver::{Solution, SolveOptions, WarmStart, solve_problem};
use gradvi_cli::replication::records::{read_csv, write_csv};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

pub mod baseline;
mod data_replay;
mod domains3d;
mod domains3d_report;
mod hmm3d;
mod hmm3d_report;
pub mod mesh3d;
pub mod peers;
mod peers3d;
mod peers3d_report;
mod peers_cores;
mod peers_report;
mod peers_targets;
mod report;
pub use report::write_report;

/// The constant C of Test 3 used throughout.
pub const C: f64 = -5.0;
/// Default cap on the number of cells of a case.
pub const DEFAULT_MAX_CELLS: usize = 1_100_000;
/// Default cap on the number of cells of a dolfinx run.
pub const DOLFINX_MAX_CELLS: usize = 310_000;
/// Smallest mesh counted by the target "gradvi-P1 ≥ 10× faster than dolfinx-P1 at ≥ 100k
/// cells": the gmsh mesh generated for 10⁵ cells has a few less (99 968).
pub const P1_TARGET_MIN_CELLS: usize = 95_000;
/// Target cell counts of the gmsh triangle meshes.
pub const GMSH_TARGETS: [usize; 8] = [
    1_000, 3_000, 10_000, 30_000, 100_000, 150_000, 300_000, 1_000_000,
];
/// Levels of the hexagonal family (1681 to 410 881 cells; level 8, 1 640 961 cells, is
/// above the default cap).
pub const HEX_LEVELS: [usize; 6] = [3, 4, 5, 6, 7, 8];
/// n of the n × n Cartesian meshes.
pub const CARTESIAN_N: [usize; 6] = [32, 100, 178, 316, 562, 1000];
/// Range of cell counts over which growth exponents are fitted (10⁴ to 10⁶, with the slack
/// of the mesh families' sizes).
pub const FIT_RANGE: (usize, usize) = (8_000, 1_200_000);
/// gmsh characteristic length for `n` triangles on the unit square (calibrated on
/// `meshes/test3_4.geo`: lc = 0.01288 gives about 14 000 triangles).
pub fn gmsh_lc(n: usize) -> f64 {
    (2.32 / n as f64).sqrt()
}

/// Mesh families of the benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BenchFamily {
    /// gmsh Frontal-Delaunay triangles (`target/bench-meshes/test3_N.msh`).
    Gmsh,
    /// [`gradvi::mesh::generate::hexagonal()`] at a level.
    Hexagonal,
    /// [`gradvi::mesh::generate::cartesian()`] n × n.
    Cartesian,
}

impl BenchFamily {
    /// The lowercase name.
    pub fn name(self) -> &'static str {
        match self {
            BenchFamily::Gmsh => "gmsh",
            BenchFamily::Hexagonal => "hexagonal",
            BenchFamily::Cartesian => "cartesian",
        }
    }
    fn parse(s: &str) -> gradvi::Result<Self> {
        match s {
            "gmsh" => Ok(BenchFamily::Gmsh),
            "hexagonal" => Ok(BenchFamily::Hexagonal),
            "cartesian" => Ok(BenchFamily::Cartesian),
            _ => Err(bad(format!("unknown bench family '{s}'"))),
        }
    }
}

/// A variant of gradvi's solver (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// Default options: active-set iteration from A₀ = ∅, sparse Cholesky.
    Cold,
    /// Initial active set from coarse HMM solves on agglomerated meshes.
    Nested,
    /// As `Nested`, with faer's parallel numeric factorisation
    /// ([`gradvi::linalg::FactorThreads::Global`]) instead of the sequential default.
    NestedParallel,
    /// As `Nested`, with the nested-dissection ordering
    /// ([`gradvi::linalg::Ordering::NestedDissection`]) instead of AMD.
    NestedNd,
}

impl Variant {
    /// The lowercase name.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Cold => "cold",
            Variant::Nested => "nested",
            Variant::NestedParallel => "nested-par",
            Variant::NestedNd => "nested-nd",
        }
    }
    fn parse(s: &str) -> gradvi::Result<Self> {
        match s {
            "cold" => Ok(Variant::Cold),
            "nested" => Ok(Variant::Nested),
            "nested-par" => Ok(Variant::NestedParallel),
            "nested-nd" => Ok(Variant::NestedNd),
            _ => Err(bad(format!(
                "unknown variant '{s}' (cold, nested, nested-par, nested-nd)"
            ))),
        }
    }
}

/// One case: a mesh, a scheme and a solver variant.
#[derive(Debug, Clone)]
pub struct Case {
    /// Mesh family.
    pub family: BenchFamily,
    /// gmsh: target cells; hexagonal: level; Cartesian: n.
    pub size: usize,
    /// The mesh file (gmsh only).
    pub file: Option<PathBuf>,
    /// Scheme.
    pub scheme: SchemeKind,
    /// Solver variant.
    pub variant: Variant,
}

impl Case {
    /// Cell count expected before building the mesh (gmsh: the target).
    pub fn expected_cells(&self) -> usize {
        match self.family {
            BenchFamily::Gmsh => self.size,
            BenchFamily::Hexagonal => {
                gradvi::mesh::generate::Family::Hexagonal.cells_at_level(self.size)
            }
            BenchFamily::Cartesian => self.size * self.size,
        }
    }
    fn label(&self) -> String {
        format!(
            "{} {} {} {}",
            self.family.name(),
            self.size,
            self.scheme,
            self.variant.name()
        )
    }
    fn child_args(&self) -> Vec<String> {
        let mut a = vec![
            "bench".to_string(),
            "--child".to_string(),
            self.family.name().to_string(),
            self.scheme.to_string(),
            self.variant.name().to_string(),
            self.size.to_string(),
        ];
        if let Some(f) = &self.file {
            a.push(f.display().to_string());
        }
        a
    }
    fn from_child_args(a: &[String]) -> gradvi::Result<Self> {
        if a.len() < 4 {
            return Err(bad("--child FAMILY SCHEME VARIANT SIZE [FILE]".into()));
        }
        Ok(Case {
            family: BenchFamily::parse(&a[0])?,
            scheme: a[1].parse()?,
            variant: Variant::parse(&a[2])?,
            size: a[3]
                .parse()
                .map_err(|_| bad(format!("bad size '{}'", a[3])))?,
            file: a.get(4).map(PathBuf::from),
        })
    }
}

/// One row of `replication/results/bench.csv`. Times are wall-clock seconds; `NaN` where a
/// phase does not apply (dolfinx reports setup and solve only).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchRow {
    /// gmsh, hexagonal or cartesian.
    pub family: String,
    /// Mesh name (file stem, `level K`, `n×n`).
    pub mesh: String,
    /// gradvi or dolfinx.
    pub code: String,
    /// hmm or p1.
    pub scheme: String,
    /// cold or nested (gradvi), snes-vi (dolfinx).
    pub variant: String,
    /// Number of cells.
    pub cells: usize,
    /// Number of unknowns (dolfinx: vertices).
    pub unknowns: usize,
    /// Size of the factorised (condensed) system.
    pub condensed: usize,
    /// Stored entries of the condensed matrix (lower triangle).
    pub nnz: usize,
    /// Linear solves of the fine active-set iteration (dolfinx: SNES iterations).
    pub niter: usize,
    /// Linear solves of the coarse solves of the nested variant.
    pub coarse_niter: usize,
    /// Mesh generation or reading.
    pub mesh_s: f64,
    /// Coarse solves (nested variant).
    pub coarse_s: f64,
    /// Data, local matrices and pattern (dolfinx: everything before SNES, mesh reading
    /// included).
    pub setup_s: f64,
    /// Symbolic factorisation.
    pub symbolic_s: f64,
    /// Condensation and scatter, all iterations.
    pub assemble_s: f64,
    /// Numeric factorisations, all iterations.
    pub factor_s: f64,
    /// Triangular solves and interior recovery, all iterations (dolfinx: SNES solve).
    pub solve_s: f64,
    /// The rest: constraints, residuals and certificates of the active-set loop.
    pub other_s: f64,
    /// Everything, from the mesh to the certified solution.
    pub total_s: f64,
    /// Peak resident memory of the process (VmHWM / ru_maxrss), MiB.
    pub peak_mib: f64,
    /// Largest scaled quantity of the certificate (dolfinx: NaN).
    pub certificate: f64,
    /// Stored values of the Cholesky factor (its fill; 0 for dolfinx and rows of earlier
    /// versions of this file).
    #[serde(default)]
    pub factor_len: usize,
    /// The active-set changes of the fine iteration, one `+entered/-left` per solve
    /// (empty for dolfinx and rows of earlier versions).
    #[serde(default)]
    pub changes: String,
    /// Start of the `make bench` run that wrote the row (seconds since the Unix epoch; 0 for
    /// rows of earlier versions).
    #[serde(default)]
    pub run: u64,
}

/// The number of runs per case that the environment variable `var` asks for (1 to 20), or
/// `default` if it is unset; anything else is an error.
fn repeat_from_env(var: &str, default: usize) -> gradvi::Result<usize> {
    match std::env::var(var) {
        Ok(v) => v
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&r| (1..=20).contains(&r))
            .ok_or_else(|| bad(format!("{var} must be 1 to 20, got '{v}'"))),
        Err(_) => Ok(default),
    }
}

/// The non-negative integer in the environment variable `var` (surrounding blanks allowed), or
/// `default` when it is not set; a value that is not such an integer is an error naming the
/// variable, not a silent fallback to the default (a mistyped size bound would otherwise run,
/// or skip, the whole benchmark).
fn usize_from_env(var: &str, default: usize) -> gradvi::Result<usize> {
    parse_usize_var(var, std::env::var(var).ok().as_deref(), default)
}

/// [`usize_from_env`] on the value `value` of `var` (`None`: not set).
fn parse_usize_var(var: &str, value: Option<&str>, default: usize) -> gradvi::Result<usize> {
    match value {
        None => Ok(default),
        Some(v) => v
            .trim()
            .parse::<usize>()
            .map_err(|_| bad(format!("{var} must be a non-negative integer, got '{v}'"))),
    }
}

fn bad(msg: String) -> gradvi::Error {
    gradvi::Error::InvalidData(msg)
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> gradvi::Error {
    gradvi::Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    }
}

/// Peak resident memory of this process in MiB (`VmHWM` of `/proc/self/status`; NaN if not
/// available).
pub fn peak_memory_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Runs one case in this process and returns its row (the body of a `--child` process).
pub fn run_case(case: &Case) -> gradvi::Result<BenchRow> {
    let t0 = Instant::now();
    let (mesh, name) = case_mesh(case)?;
    let mesh_s = t0.elapsed().as_secs_f64();
    let scheme = gradvi::scheme::build(case.scheme, &mesh)?;
    let problem = paper_test3(C);
    let opts = case_options(case.variant);
    let sol = solve_problem(scheme.as_ref(), &problem, &opts)?;
    let total_s = t0.elapsed().as_secs_f64();
    // a nested case must have been predicted, except on meshes too coarse to have a coarser
    // level (the row then measures the cold start, with 0 coarse solves)
    if let Some(why) = sol.warm_start.as_ref().and_then(|w| w.skipped.as_ref())
        && !gradvi::solver::warm_start::too_coarse(
            <PolyMesh as gradvi::solver::SolverMesh<2>>::warm_start_unknowns(sol.system.scheme()),
        )
    {
        return Err(bad(format!(
            "{}: no nested prediction: {why}",
            case.label()
        )));
    }
    let system = &sol.system;
    if std::env::var_os("GRADVI_BENCH_LOG").is_some() {
        log_solve(&sol);
    }
    let t = sol.timings;
    let coarse_s = t.warm_start;
    let setup_s = t.setup - t.symbolic;
    let c = sol.result.certificate;
    Ok(BenchRow {
        family: case.family.name().into(),
        mesh: name,
        code: "gradvi".into(),
        scheme: case.scheme.to_string(),
        variant: case.variant.name().into(),
        cells: mesh.n_cells(),
        unknowns: system.n_unknowns(),
        condensed: system.n_condensed(),
        nnz: system.nnz(),
        niter: sol.niter(),
        coarse_niter: sol.warm_start.as_ref().map_or(0, |w| w.coarse_solves),
        mesh_s,
        coarse_s,
        setup_s,
        symbolic_s: t.symbolic,
        assemble_s: t.assemble,
        factor_s: t.factor,
        solve_s: t.solve,
        other_s: total_s
            - mesh_s
            - coarse_s
            - setup_s
            - t.symbolic
            - t.assemble
            - t.factor
            - t.solve,
        total_s,
        peak_mib: peak_memory_mib(),
        certificate: c.worst(),
        factor_len: sol.factor_len,
        changes: sol
            .result
            .log
            .iter()
            .map(|l| format!("+{}/-{}", l.step.entered, l.step.left))
            .collect::<Vec<_>>()
            .join(" "),
        run: 0,
    })
}

/// The mesh of `case` and its name (file stem, `hexa level K`, `n×n`).
fn case_mesh(case: &Case) -> gradvi::Result<(PolyMesh, String)> {
    Ok(match case.family {
        BenchFamily::Gmsh => {
            let f = case
                .file
                .as_ref()
                .ok_or_else(|| bad("a gmsh case needs its file".into()))?;
            let stem = f
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
            (read_mesh(f, MemoryBudget::available())?, stem)
        }
        BenchFamily::Hexagonal => (
            Family::Hexagonal.generate(case.size, MemoryBudget::available())?,
            format!("hexa level {}", case.size),
        ),
        BenchFamily::Cartesian => (
            cartesian_rect_within(
                case.size,
                case.size,
                [0.0, 1.0],
                [0.0, 1.0],
                MemoryBudget::available(),
            )?,
            format!("{0}x{0}", case.size),
        ),
    })
}

/// The solver options of a variant (module docs).
fn case_options(variant: Variant) -> SolveOptions {
    let system_options = gradvi::assembly::SystemOptions {
        ordering: match variant {
            Variant::NestedNd => gradvi::linalg::Ordering::NestedDissection,
            _ => gradvi::linalg::Ordering::Amd,
        },
        factor_threads: match variant {
            Variant::NestedParallel => gradvi::linalg::FactorThreads::Global,
            _ => gradvi::linalg::FactorThreads::Sequential,
        },
        // these variants measure the direct solver (the peer benchmark compares the two)
        linear: gradvi::assembly::LinearSolver::Direct,
        budget: MemoryBudget::available(),
    };
    SolveOptions {
        system: system_options,
        warm_start: match variant {
            Variant::Cold => WarmStart::Cold,
            Variant::Nested | Variant::NestedParallel | Variant::NestedNd => WarmStart::Nested,
        },
        ..Default::default()
    }
}

/// The factor size and the active-set log of a case's solve, on stderr (`GRADVI_BENCH_LOG`).
fn log_solve(sol: &Solution) {
    let system = &sol.system;
    eprintln!(
        "[bench]     condensed {} unknowns, {} entries, factor {} values",
        system.n_condensed(),
        system.nnz(),
        sol.factor_len
    );
    for l in &sol.result.log {
        eprintln!(
            "[bench]     solve {:>3}: active {:>8} (+{}, -{}), factor {:.3} s",
            l.step.solve, l.step.active, l.step.entered, l.step.left, l.timings.factor
        );
    }
}

/// Settings of a benchmark run.
#[derive(Debug, Clone)]
pub struct Config {
    /// The repository root (meshes/, reference/, replication/).
    pub root: PathBuf,
    /// Largest number of cells of a case.
    pub max_cells: usize,
    /// Largest number of cells of a dolfinx run.
    pub dolfinx_max_cells: usize,
    /// Variants of gradvi's solver to time.
    pub variants: Vec<Variant>,
    /// The Python interpreter that has dolfinx.
    pub python: PathBuf,
}

impl Config {
    /// Defaults, overridden by the environment variables of the module docs.
    pub fn from_env(root: &Path) -> gradvi::Result<Self> {
        let num = |key: &str, default: usize| -> gradvi::Result<usize> {
            match std::env::var(key) {
                Ok(v) => v
                    .trim()
                    .replace('_', "")
                    .parse::<f64>()
                    .map(|x| x as usize)
                    .map_err(|_| bad(format!("{key}={v} is not a number"))),
                Err(_) => Ok(default),
            }
        };
        let variants = match std::env::var("GRADVI_BENCH_VARIANTS") {
            Ok(v) => v
                .split(',')
                .map(|s| Variant::parse(s.trim()))
                .collect::<gradvi::Result<Vec<_>>>()?,
            Err(_) => vec![
                Variant::Cold,
                Variant::Nested,
                Variant::NestedParallel,
                Variant::NestedNd,
            ],
        };
        Ok(Config {
            root: root.to_path_buf(),
            max_cells: num("GRADVI_BENCH_MAX_CELLS", DEFAULT_MAX_CELLS)?,
            dolfinx_max_cells: num("GRADVI_BENCH_DOLFINX_MAX_CELLS", DOLFINX_MAX_CELLS)?,
            variants,
            python: PathBuf::from("/usr/bin/python3"),
        })
    }
    /// A file or directory of the benchmark: `rel` ([`CSV`], [`REPORT`], [`FIGURE`],
    /// [`MESH_DIR`]) below the repository root.
    pub fn path(&self, rel: &str) -> PathBuf {
        self.root.join(rel)
    }
}

/// The CSV of the benchmark, the single source of its report and figure.
pub const CSV: &str = "replication/results/bench.csv";
/// The report.
pub const REPORT: &str = "replication/BENCHMARKS.md";
/// The figure.
pub const FIGURE: &str = "replication/figures/bench.png";
/// Where the gmsh meshes are written (not committed).
pub const MESH_DIR: &str = "target/bench-meshes";

/// Writes (or reuses) the gmsh mesh with about `n` triangles; returns its path.
pub fn gmsh_mesh(cfg: &Config, n: usize) -> gradvi::Result<PathBuf> {
    let dir = cfg.path(MESH_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
    let src_path = cfg.root.join("meshes/test3_4.geo");
    let src = std::fs::read_to_string(&src_path).map_err(|e| io_err(&src_path, e))?;
    let lc = format!("lc = {:.6e};", gmsh_lc(n));
    let mut found = false;
    let geo: String = src
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("lc =") {
                found = true;
                lc.clone()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n";
    if !found {
        return Err(bad(format!("{}: no 'lc =' line", src_path.display())));
    }
    let geo_path = dir.join(format!("test3_{n}.geo"));
    let msh_path = dir.join(format!("test3_{n}.msh"));
    let same_geo = std::fs::read_to_string(&geo_path).is_ok_and(|g| g == geo);
    if same_geo && msh_path.exists() {
        return Ok(msh_path);
    }
    std::fs::write(&geo_path, &geo).map_err(|e| io_err(&geo_path, e))?;
    eprintln!(
        "[bench] gmsh: meshing {} (lc {})",
        geo_path.display(),
        gmsh_lc(n)
    );
    run_gmsh(&geo_path, &msh_path, 2, &[])?;
    Ok(msh_path)
}

/// The rows of the CSV `rel` below the root of `cfg` (empty if it does not exist yet).
pub fn read_rows_of<T: serde::de::DeserializeOwned>(
    cfg: &Config,
    rel: &str,
) -> gradvi::Result<Vec<T>> {
    let csv = cfg.path(rel);
    if csv.exists() {
        read_csv(&csv)
    } else {
        Ok(Vec::new())
    }
}

/// Meshes `geo` with gmsh (in dimension `dim`, 2 or 3; one thread, msh 4.1) into `msh`,
/// through a `.part` file renamed at the end, with `extra` arguments (e.g. `-setnumber lc
/// 0.01`).
pub fn run_gmsh(geo: &Path, msh: &Path, dim: u8, extra: &[String]) -> gradvi::Result<()> {
    let tmp = msh.with_extension("msh.part");
    let status = Command::new("gmsh")
        .arg(format!("-{dim}"))
        .args(["-nt", "1", "-format", "msh41", "-v", "2"])
        .args(extra)
        .arg(geo)
        .arg("-o")
        .arg(&tmp)
        .stdout(Stdio::null())
        .status()
        .map_err(|e| {
            io_err(
                Path::new("gmsh"),
                format!("{e} (install it with 'bash reference/install.sh')"),
            )
        })?;
    if !status.success() {
        return Err(io_err(geo, format!("gmsh failed: {status}")));
    }
    std::fs::rename(&tmp, msh).map_err(|e| io_err(msh, e))
}

/// The cases of a run, smallest first, within the caps of `cfg`. gmsh meshes are generated
/// (or reused) on the way.
pub fn plan(cfg: &Config) -> gradvi::Result<Vec<Case>> {
    let mut cases = Vec::new();
    for &n in &GMSH_TARGETS {
        if n > cfg.max_cells {
            continue;
        }
        let file = gmsh_mesh(cfg, n)?;
        for scheme in [SchemeKind::Hmm, SchemeKind::P1] {
            for &variant in &cfg.variants {
                cases.push(Case {
                    family: BenchFamily::Gmsh,
                    size: n,
                    file: Some(file.clone()),
                    scheme,
                    variant,
                });
            }
        }
    }
    for &variant in &cfg.variants {
        for &level in &HEX_LEVELS {
            cases.push(Case {
                family: BenchFamily::Hexagonal,
                size: level,
                file: None,
                scheme: SchemeKind::Hmm,
                variant,
            });
        }
        for &n in &CARTESIAN_N {
            cases.push(Case {
                family: BenchFamily::Cartesian,
                size: n,
                file: None,
                scheme: SchemeKind::Hmm,
                variant,
            });
        }
    }
    cases.retain(|c| c.expected_cells() <= cfg.max_cells);
    // stable: at equal size, the order above (gmsh first, cold before nested)
    cases.sort_by_key(|c| c.expected_cells());
    Ok(cases)
}

/// Runs `cmd` (the program `exe`) with stderr passed through, and returns its standard output;
/// an error naming `what` if it fails.
fn stdout_of(mut cmd: Command, exe: &Path, what: &str) -> gradvi::Result<String> {
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| io_err(exe, e))?;
    if !out.status.success() {
        return Err(bad(format!("{what} failed ({})", out.status)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Runs `case` in a child process (`EXE bench --child …`: `gradvi-dev`, or an earlier build's
/// `gradvi`) and parses its row.
pub fn run_child(exe: &Path, case: &Case) -> gradvi::Result<BenchRow> {
    let mut cmd = Command::new(exe);
    cmd.args(case.child_args());
    let what = format!("case {}", case.label());
    let text = stdout_of(cmd, exe, &what)?;
    json_row(&text, &format!("{what}: bad child output"))
}

/// The JSON object a process printed last on its standard output `text`, parsed; an error
/// starting with `what` otherwise.
fn json_row<T: serde::de::DeserializeOwned>(text: &str, what: &str) -> gradvi::Result<T> {
    let line = text
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or("");
    serde_json::from_str(line).map_err(|e| bad(format!("{what} ({e}): {text}")))
}

/// Whether `python` can import dolfinx and gmsh.
pub fn dolfinx_available(python: &Path) -> bool {
    Command::new(python)
        .args(["-c", "import dolfinx, gmsh"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs the dolfinx reference on a gmsh mesh (`reference/solve.py --case test3_1_C5 --mesh
/// FILE`) and reads its summary row. The peak memory is the interpreter's `ru_maxrss`.
pub fn run_dolfinx(cfg: &Config, mesh: &Path) -> gradvi::Result<BenchRow> {
    let stem = mesh
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let outdir = cfg.path(MESH_DIR).join(format!("dolfinx_{stem}"));
    let _ = std::fs::remove_dir_all(&outdir);
    let script = cfg.root.join("reference/solve.py");
    let case = format!("test3_1_C{}", C.abs());
    let wrapper = "import sys, runpy, resource\n\
        sys.argv = sys.argv[1:]\n\
        try:\n    runpy.run_path(sys.argv[0], run_name='__main__')\n\
        finally:\n    print('BENCH_MAXRSS_KB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n";
    let t0 = Instant::now();
    let mut cmd = Command::new(&cfg.python);
    cmd.arg("-c")
        .arg(wrapper)
        .arg(&script)
        .args(["--case", &case, "--mesh"])
        .arg(mesh)
        .arg("--outdir")
        .arg(&outdir);
    let text = stdout_of(cmd, &cfg.python, &format!("dolfinx on {}", mesh.display()))?;
    let wall = t0.elapsed().as_secs_f64();
    let peak_mib = text
        .lines()
        .find_map(|l| l.strip_prefix("BENCH_MAXRSS_KB "))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0);
    #[derive(Deserialize)]
    struct Summary {
        n_cells: usize,
        n_vertices: usize,
        snes_iterations: usize,
        time_setup_s: f64,
        time_solve_s: f64,
    }
    let rows: Vec<Summary> = read_csv(&outdir.join("reference_summary.csv"))?;
    let s = rows
        .first()
        .ok_or_else(|| bad(format!("dolfinx on {}: empty summary", mesh.display())))?;
    eprintln!(
        "[bench] dolfinx {stem}: setup {:.2} s, SNES {:.2} s ({} its), process wall {wall:.2} s",
        s.time_setup_s, s.time_solve_s, s.snes_iterations
    );
    Ok(BenchRow {
        family: BenchFamily::Gmsh.name().into(),
        mesh: stem,
        code: "dolfinx".into(),
        scheme: "p1".into(),
        variant: "snes-vi".into(),
        cells: s.n_cells,
        unknowns: s.n_vertices,
        condensed: s.n_vertices,
        nnz: 0,
        niter: s.snes_iterations,
        coarse_niter: 0,
        mesh_s: f64::NAN,
        coarse_s: 0.0,
        setup_s: s.time_setup_s,
        symbolic_s: f64::NAN,
        assemble_s: f64::NAN,
        factor_s: f64::NAN,
        solve_s: s.time_solve_s,
        other_s: f64::NAN,
        total_s: s.time_setup_s + s.time_solve_s,
        peak_mib,
        certificate: f64::NAN,
        factor_len: 0,
        changes: String::new(),
        run: 0,
    })
}

/// The benchmark program: `args` are those of the process (without the program name).
/// `--child …` runs one case and prints its JSON row; `--report-only` rewrites the report from
/// the CSV; otherwise every case of [`plan`] runs and the CSV, report and figure are written.
pub fn main_with_args(root: &Path, args: &[String]) -> gradvi::Result<()> {
    if let Some(i) = args.iter().position(|a| a == "--child") {
        let case = Case::from_child_args(&args[i + 1..])?;
        let row = run_case(&case)?;
        println!(
            "{}",
            serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
        );
        return Ok(());
    }
    if let Some(i) = args.iter().position(|a| a == "--peer-child") {
        return peers::child_main(&args[i + 1..], root);
    }
    if let Some(i) = args.iter().position(|a| a == "--peer3d-child") {
        return peers3d::child_main(&args[i + 1..], root);
    }
    if let Some(i) = args.iter().position(|a| a == "--hmm3d-child") {
        return hmm3d::child_main(&args[i + 1..], root);
    }
    if let Some(i) = args.iter().position(|a| a == "--domain3d-child") {
        return domains3d::child_main(&args[i + 1..], root);
    }
    if let Some(i) = args.iter().position(|a| a == "--mesh3d-child") {
        return mesh3d::child_main(&args[i + 1..]);
    }
    let mut cfg = Config::from_env(root)?;
    if args.iter().any(|a| a == "--mesh3d") {
        let exe = std::env::current_exe().map_err(|e| io_err(Path::new("current_exe"), e))?;
        return mesh3d::run(&exe, &cfg.path(MESH_DIR), cfg.max_cells);
    }
    if args.iter().any(|a| a == "--report-only") {
        if cfg.path(baseline::CSV).exists() {
            baseline::write_report(&cfg)?;
        }
        return write_report(&cfg);
    }
    let t0 = Instant::now();
    let exe = std::env::current_exe().map_err(|e| io_err(Path::new("current_exe"), e))?;
    if let Some(i) = args.iter().position(|a| a == "--baseline") {
        let base = args
            .get(i + 1)
            .ok_or_else(|| bad("--baseline needs the path of the earlier gradvi".into()))?;
        let rev = match args.iter().position(|a| a == "--baseline-rev") {
            Some(j) => args
                .get(j + 1)
                .ok_or_else(|| bad("--baseline-rev needs a revision".into()))?
                .clone(),
            None => base.clone(),
        };
        if std::env::var_os("GRADVI_BENCH_VARIANTS").is_none() {
            cfg.variants = vec![Variant::Nested];
        }
        return baseline::run(&cfg, &exe, Path::new(base), &rev);
    }
    if args.iter().any(|a| a == "--domains3d") {
        domains3d::run(&cfg, &exe)?;
        return write_report(&cfg);
    }
    if args.iter().any(|a| a == "--peers3d") {
        peers3d::run(&cfg, &exe)?;
        return write_report(&cfg);
    }
    if args.iter().any(|a| a == "--hmm3d") {
        hmm3d::run(&cfg, &exe)?;
        return write_report(&cfg);
    }
    if args.iter().any(|a| a == "--peers") {
        peers::run(&cfg, &exe)?;
        return write_report(&cfg);
    }
    run_scaling(&cfg, &exe, t0)
}

/// The scaling benchmark: every case of [`plan`] in a child process of `exe` (and dolfinx on
/// the gmsh meshes), the CSV written row by row, then the report and figure; `t0` is the start
/// of the run.
fn run_scaling(cfg: &Config, exe: &Path, t0: Instant) -> gradvi::Result<()> {
    eprintln!(
        "[bench] Test 3 (C = {C}), cells up to {} (GRADVI_BENCH_MAX_CELLS), dolfinx up to {} \
         (GRADVI_BENCH_DOLFINX_MAX_CELLS)",
        cfg.max_cells, cfg.dolfinx_max_cells
    );
    let cases = plan(cfg)?;
    let dolfinx = dolfinx_available(&cfg.python);
    if !dolfinx {
        eprintln!(
            "[bench] warning: {} cannot import dolfinx and gmsh: no dolfinx rows (run 'bash \
             reference/install.sh')",
            cfg.python.display()
        );
    }
    let csv = cfg.path(CSV);
    if let Some(d) = csv.parent() {
        std::fs::create_dir_all(d).map_err(|e| io_err(d, e))?;
    }
    let run = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    // GRADVI_BENCH_MERGE: keep the rows of earlier runs that this run does not redo
    let mut rows: Vec<BenchRow> = kept_rows(&csv, &cases)?;
    let mut done_dolfinx: Vec<PathBuf> = Vec::new();
    let n_cases = cases.len();
    for (i, case) in cases.iter().enumerate() {
        eprintln!("[bench] ({}/{n_cases}) {} ...", i + 1, case.label());
        let mut row = run_child(exe, case)?;
        row.run = run;
        eprintln!(
            "[bench]   {} cells, NITER {} (+{} coarse), total {:.3} s (factor {:.3}, assemble \
             {:.3}, solve {:.3}, other {:.3}), peak {:.0} MiB",
            row.cells,
            row.niter,
            row.coarse_niter,
            row.total_s,
            row.factor_s,
            row.assemble_s,
            row.solve_s,
            row.other_s,
            row.peak_mib
        );
        rows.push(row);
        if dolfinx
            && let Some(f) = &case.file
            && case.size <= cfg.dolfinx_max_cells
            && !done_dolfinx.contains(f)
        {
            eprintln!("[bench]   dolfinx P1 on {} ...", f.display());
            let mut d = run_dolfinx(cfg, f)?;
            d.run = run;
            rows.retain(|r| !(r.code == "dolfinx" && r.mesh == d.mesh));
            rows.push(d);
            done_dolfinx.push(f.clone());
        }
        write_csv(&csv, &rows)?;
    }
    write_report(cfg)?;
    eprintln!(
        "[bench] wrote {}, {} and {} in {:.1} s",
        csv.display(),
        cfg.path(REPORT).display(),
        cfg.path(FIGURE).display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The rows of the CSV `csv` that the run of `cases` does not redo, if `GRADVI_BENCH_MERGE` is
/// set; none otherwise.
fn kept_rows(csv: &Path, cases: &[Case]) -> gradvi::Result<Vec<BenchRow>> {
    if std::env::var_os("GRADVI_BENCH_MERGE").is_none() || !csv.exists() {
        return Ok(Vec::new());
    }
    let redo = |r: &BenchRow| {
        cases.iter().any(|c| {
            r.code == "gradvi"
                && r.family == c.family.name()
                && r.scheme == c.scheme.to_string()
                && r.variant == c.variant.name()
                && (r.cells as f64 - c.expected_cells() as f64).abs()
                    <= 0.2 * c.expected_cells() as f64
        })
    };
    let old: Vec<BenchRow> = read_csv(csv)?;
    let kept: Vec<BenchRow> = old.into_iter().filter(|r| !redo(r)).collect();
    eprintln!(
        "[bench] GRADVI_BENCH_MERGE: keeping {} rows of earlier runs",
        kept.len()
    );
    Ok(kept)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cold_and_nested_cases_give_certified_rows_and_a_report() {
        let mut rows = Vec::new();
        for (scheme, variant) in [
            (SchemeKind::Hmm, Variant::Cold),
            (SchemeKind::Hmm, Variant::Nested),
            (SchemeKind::P1, Variant::Nested),
            (SchemeKind::Hmm, Variant::NestedParallel),
            (SchemeKind::Hmm, Variant::NestedNd),
        ] {
            let family = if scheme == SchemeKind::P1 {
                BenchFamily::Hexagonal
            } else {
                BenchFamily::Cartesian
            };
            let case = Case {
                family,
                size: if scheme == SchemeKind::P1 { 2 } else { 40 },
                file: None,
                scheme,
                variant,
            };
            match run_case(&case) {
                Ok(r) => {
                    assert!(r.certificate <= 1e-10, "{r:?}");
                    assert!(r.niter >= 1);
                    assert_eq!(r.coarse_niter > 0, variant != Variant::Cold);
                    rows.push(r);
                }
                // P1 needs triangles: the hexagonal mesh is an error, not a panic
                Err(e) => assert_eq!(scheme, SchemeKind::P1, "{e}"),
            }
        }
        let dir = std::env::temp_dir().join(format!("gradvi-bench-test-{}", std::process::id()));
        let cfg = Config {
            root: dir.clone(),
            max_cells: 2000,
            dolfinx_max_cells: 0,
            variants: vec![Variant::Cold, Variant::Nested],
            python: PathBuf::from("/nonexistent"),
        };
        std::fs::create_dir_all(cfg.path(CSV).parent().unwrap()).unwrap();
        write_csv(&cfg.path(CSV), &rows).unwrap();
        write_report(&cfg).unwrap();
        let md = std::fs::read_to_string(cfg.path(REPORT)).unwrap();
        assert!(md.contains("## Targets") && md.contains("## All cases"));
        for section in [
            "## Lever: threads of the numeric factorisation",
            "## Lever: fill-reducing ordering",
            "## Size of the active-set changes",
        ] {
            assert!(md.contains(section), "no {section}");
        }
        // the changes of a row add up to its final active set, and the fill is recorded
        for r in &rows {
            assert!(
                r.factor_len > 0 && r.changes.split(' ').count() == r.niter,
                "{r:?}"
            );
        }
        // rows of an older CSV (without the new columns) still read
        let old = "family,mesh,code,scheme,variant,cells,unknowns,condensed,nnz,niter,coarse_niter,mesh_s,coarse_s,setup_s,symbolic_s,assemble_s,factor_s,solve_s,other_s,total_s,peak_mib,certificate\n\
                   gmsh,m,gradvi,hmm,cold,10,20,15,30,2,0,0.1,0,0.1,0.1,0.1,0.1,0.1,0.1,0.6,5,1e-16\n";
        std::fs::write(cfg.path(CSV), old).unwrap();
        let back: Vec<BenchRow> = read_csv(&cfg.path(CSV)).unwrap();
        assert_eq!((back[0].factor_len, back[0].run), (0, 0));
        assert!(
            std::fs::read(cfg.path(FIGURE))
                .unwrap()
                .starts_with(b"\x89PNG")
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
