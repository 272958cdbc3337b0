//! The 3D peer benchmark (`gradvi-dev bench --peers3d`, `make bench-peers3d`): the 3D radial
//! obstacle problem (`problems/ex9-3d.toml`) solved by gradvi and by dolfinx 0.5 on the same
//! tetrahedra, at equal cores.
//!
//! **The identical discrete problem.** Both codes mesh (−2,2)³ with n³ cubes, each cut into the
//! six tetrahedra around its main diagonal: gradvi's Kuhn generator
//! ([`gradvi::mesh3d::generate::kuhn()`]) and dolfinx's `create_box` (checked: the same six
//! vertex sets per cube). P1 on them, f = 0, u = 1/(2r) at the boundary vertices, u ≥ ψ at every
//! vertex: the same matrix, right-hand side and bounds. Each obstacle run writes u at the
//! vertices (in the order i + (n+1)(j + (n+1)k) of the vertex (x_i, y_j, z_k)), and every row
//! records the largest difference to dolfinx's GAMG solution on one process (`diff_u`): the
//! difference of two solvers of one problem, at their tolerances.
//!
//! **The solvers.** gradvi: P1 with the iterative solver (algebraic multigrid CG, the nested
//! warm start), in a child process `gradvi-dev bench --peer3d-child [--no-barrier] N [FILE]`.
//! dolfinx: `benches/dolfinx/ex9_3d.py` under `/usr/bin/python3` (SNES `vinewtonrsls`, CG with
//! GAMG or with hypre BoomerAMG, `--ksp-rtol`/`--snes-rtol` 1e-10), one process alone or
//! `mpiexec -n N`. The "best" dolfinx configuration of a size and core count is the faster of
//! the two.
//!
//! **Equal cores.** Every case runs on 1 core and on N, the machine's cores
//! ([`super::peers::core_counts`]): gradvi with that many rayon threads (`RAYON_NUM_THREADS`),
//! dolfinx with that many MPI processes (`OMP_NUM_THREADS=1`); rows are compared at equal
//! cores only.
//!
//! **Time, memory and R.** `total_s` is the wall clock of the whole process (or MPI job, launch
//! included; dolfinx's Python imports and form compilation included, the compiled forms being
//! cached by a warm-up run at n = 4 before the first case), measured by this driver. Peak memory
//! is the child's peak resident set (gradvi: `VmHWM`; dolfinx: the sum over the ranks of
//! `getrusage` `ru_maxrss`). Every case is followed by its linear variant (the same mesh,
//! matrix, right-hand side, solver and cores without the bounds: gradvi with the constraint
//! dropped, dolfinx one KSP solve with the same CG and preconditioner), timed the same way,
//! and R = `total_s / linear_seconds`.
//!
//! Sizes: n in [`SIZES`] from `GRADVI_BENCH_3D_MIN_N` (default 0) up to `GRADVI_BENCH_3D_MAX_N`
//! (default [`DEFAULT_MAX_N`], a few minutes here); n = 100 and 200 (about 1M and 8M unknowns,
//! the sizes of the performance issue) only when asked. `GRADVI_BENCH_3D_DOLFINX` (default
//! `gamg,hypre`) names the dolfinx configurations run. A dolfinx case runs only when
//! [`MEMORY_MARGIN`] times its estimated peak ([`dolfinx_estimate`], extrapolated from its own
//! rows at smaller sizes) fits in the memory available; a case left out is said on stderr, and
//! the report names the comparisons it leaves open. Rows go to [`CSV`], rewritten after each
//! case; the rows of the sizes not run are kept from it. The report's 3D section is written
//! from it ([`super::peers3d_report`]).

use super::{bad, io_err, json_row, peak_memory_mib, stdout_of};
use gradvi::budget::MemoryBudget;
use gradvi::budget::human_bytes;
use gradvi::mesh3d::generate::kuhn;
use gradvi::mesh3d::{Cuboid, PolyMesh3};
use gradvi::scheme::{SchemeKind, SchemeOptions, build_with3};
use gradvi::solver::{SolveOptions, solve_problem};
use gradvi_cli::replication::records::write_csv;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The CSV of this benchmark.
pub const CSV: &str = "replication/results/bench_peers3d.csv";
/// Cubes per side: 4 913 to 8.1M unknowns ((n+1)³).
pub const SIZES: [usize; 5] = [16, 32, 64, 100, 200];
/// Default cap on n: up to 64³ cubes (274 625 unknowns).
pub const DEFAULT_MAX_N: usize = 64;
/// dolfinx's peak memory per unknown on one process, bytes (765 MiB at 274 625 unknowns,
/// measured): the estimate of [`dolfinx_estimate`] for a configuration without two smaller
/// rows to extrapolate from (a quarter more on more than one process).
pub const DOLFINX_BYTES_PER_UNKNOWN: f64 = 2_900.0;
/// A dolfinx case runs only if this many times its estimated peak ([`dolfinx_estimate`]) fits
/// in the memory available: an estimate that is a little low must not push the machine into
/// swap or its out-of-memory killer in the middle of a long run.
pub const MEMORY_MARGIN: f64 = 1.05;
/// The dolfinx script.
pub const SCRIPT: &str = "benches/dolfinx/ex9_3d.py";
/// Where the solutions at the vertices are written (not committed).
const U_DIR: &str = "target/bench-peers3d";

/// One row of [`CSV`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Peer3Row {
    /// gradvi or dolfinx.
    pub code: String,
    /// gradvi: `p1 iterative`; dolfinx: the preconditioner of CG, `gamg` or `hypre`.
    pub config: String,
    /// Cubes per side.
    pub n: usize,
    /// Tetrahedra (6n³).
    pub cells: usize,
    /// Unknowns ((n+1)³, Dirichlet vertices included, as dolfinx counts them).
    pub unknowns: usize,
    /// Cores: gradvi's rayon threads, dolfinx's MPI processes.
    pub cores: usize,
    /// gradvi: linear solves of the fine active-set iteration; dolfinx: Newton steps.
    pub niter: usize,
    /// gradvi: the coarse solves of the warm start; dolfinx: 0.
    pub coarse_niter: usize,
    /// Krylov iterations, all solves.
    pub krylov: usize,
    /// gradvi: mesh generation and setup; dolfinx: mesh, forms, assembly and bounds.
    pub setup_s: f64,
    /// The solve (gradvi: warm start and active-set iteration; dolfinx: SNES).
    pub solve_s: f64,
    /// Wall clock of the whole process or MPI job, measured by the driver.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub total_s: f64,
    /// gradvi's solve by phase, seconds: warm start (coarse solves), assembly, multigrid setups,
    /// conjugate gradients, look-ahead (`warm|assemble|setup|cg|look-ahead`; empty for dolfinx).
    #[serde(default)]
    pub phases: String,
    /// Peak resident memory, MiB (summed over the MPI ranks).
    pub peak_mib: f64,
    /// Largest |u − ū| at the vertices.
    pub err_max: f64,
    /// Mean |u − ū| at the vertices.
    pub err_mean: f64,
    /// `total_s` of the linear variant (no bounds).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub linear_seconds: f64,
    /// Krylov iterations of the linear variant.
    pub linear_krylov: usize,
    /// R = `total_s / linear_seconds`.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub r: f64,
    /// Largest |u − u_dolfinx| at the vertices, u_dolfinx from GAMG on one process (NaN for
    /// that row itself and for dolfinx on more than one process).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub diff_u: f64,
}

/// The domain of `problems/ex9-3d.toml`, (−2,2)³ (shared by the 3D benchmarks).
pub(super) const BOX: Cuboid = Cuboid {
    x: [-2.0, 2.0],
    y: [-2.0, 2.0],
    z: [-2.0, 2.0],
};

/// The ex9-3d problem of `problems/ex9-3d.toml` (shared by the 3D benchmarks).
pub(super) fn problem(root: &Path) -> gradvi::Result<gradvi::problem::Problem<3>> {
    gradvi::problem::file::load(root.join("problems/ex9-3d.toml"), &[])?.problem_in::<3>()
}

/// A solve's phases as the 3D benchmarks record them: `warm|assemble|setup|cg|look-ahead`,
/// seconds.
pub(super) fn phases(t: &gradvi::solver::Timings) -> String {
    format!(
        "{:.2}|{:.2}|{:.2}|{:.2}|{:.2}",
        t.warm_start, t.assemble, t.factor, t.solve, t.look_ahead
    )
}

/// Position of vertex `x` of the n³ grid of (−2,2)³ in the order i + (n+1)(j + (n+1)k).
fn grid_index(x: [f64; 3], n: usize) -> usize {
    let i = |c: f64| ((c + 2.0) * n as f64 / 4.0).round() as usize;
    i(x[0]) + (n + 1) * (i(x[1]) + (n + 1) * i(x[2]))
}

/// Writes `u` (values at the vertices of `mesh`) as little-endian f64 in grid order.
fn write_u(path: &Path, mesh: &PolyMesh3, n: usize, u: &[f64]) -> gradvi::Result<()> {
    let len = (n + 1).pow(3);
    let mut out = vec![f64::NAN; len];
    for (x, &v) in mesh.vertices().iter().zip(u) {
        out[grid_index(*x, n).min(len - 1)] = v;
    }
    let bytes: Vec<u8> = out.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).map_err(|e| io_err(path, e))
}

/// With `GRADVI_BENCH_MEM` set, prints to stderr the resident set (`VmRSS`) and its peak so
/// far (`VmHWM`) of this process after `phase`, in MiB (`make` never sets it: a measurement aid,
/// `replication/measurements/memory3d.md`).
fn memory_phase(phase: &str) {
    if std::env::var_os("GRADVI_BENCH_MEM").is_none() {
        return;
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kib = |key: &str| {
        status
            .lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .map_or(f64::NAN, |kb| kb / 1024.0)
    };
    eprintln!(
        "[memory] {phase}: VmRSS {:.0} MiB, VmHWM {:.0} MiB",
        kib("VmRSS:"),
        kib("VmHWM:")
    );
}

/// Solves the case of `n` in this process (the body of a `--peer3d-child`); without the
/// `barrier`, its linear variant. `total_s` is left to the driver.
fn run_gradvi(
    n: usize,
    barrier: bool,
    u_file: Option<&Path>,
    root: &Path,
) -> gradvi::Result<Peer3Row> {
    let t0 = Instant::now();
    let budget = MemoryBudget::available();
    let mesh = PolyMesh3::from_polyhedra(kuhn(n, BOX, budget)?, budget)?;
    memory_phase("mesh");
    let mut problem = problem(root)?;
    if !barrier {
        problem.constraint = None;
    }
    let scheme = build_with3(SchemeKind::P1, &mesh, &SchemeOptions::default())?;
    let mut options = SolveOptions::default();
    options.system.linear = "iterative".parse()?;
    options.system.budget = budget;
    let before_solve = t0.elapsed().as_secs_f64();
    memory_phase("scheme");
    let sol = solve_problem(scheme.as_ref(), &problem, &options)?;
    memory_phase("solve");
    let t = sol.timings;
    let u = scheme.vertex_values(sol.u());
    let exact = problem
        .exact
        .as_ref()
        .ok_or_else(|| bad("ex9-3d.toml: no exact solution".into()))?;
    let errors: Vec<f64> = mesh
        .vertices()
        .iter()
        .zip(&u)
        .map(|(x, v)| (v - (exact.u)(*x)).abs())
        .collect();
    if let Some(f) = u_file {
        write_u(f, &mesh, n, &u)?;
    }
    Ok(Peer3Row {
        code: "gradvi".into(),
        config: "p1 iterative".into(),
        n,
        cells: mesh.n_cells(),
        unknowns: sol.system.n_unknowns(),
        cores: rayon::current_num_threads(),
        niter: sol.niter(),
        coarse_niter: sol.warm_start.as_ref().map_or(0, |w| w.coarse_solves),
        krylov: sol.result.log.iter().map(|l| l.timings.krylov).sum(),
        setup_s: before_solve + t.setup,
        solve_s: t.total - t.setup,
        total_s: f64::NAN,
        phases: phases(&t),
        peak_mib: peak_memory_mib(),
        err_max: errors.iter().fold(0.0, |a: f64, &b| a.max(b)),
        err_mean: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
        linear_seconds: f64::NAN,
        linear_krylov: 0,
        r: f64::NAN,
        diff_u: f64::NAN,
    })
}

/// The flag of a child that runs the linear variant.
const NO_BARRIER: &str = "--no-barrier";

/// Arguments of a child process: `[--no-barrier] N [FILE]` (FILE: where to write u).
pub fn child_main(args: &[String], root: &Path) -> gradvi::Result<()> {
    let barrier = args.first().is_none_or(|a| a != NO_BARRIER);
    let args = if barrier { args } else { &args[1..] };
    let n: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .ok_or_else(|| bad(format!("--peer3d-child [{NO_BARRIER}] N [FILE]")))?;
    let row = run_gradvi(n, barrier, args.get(1).map(Path::new), root)?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
    );
    Ok(())
}

/// What a run of the dolfinx script prints.
#[derive(Deserialize)]
struct Dolfinx {
    processes: usize,
    unknowns: usize,
    cells: usize,
    setup_s: f64,
    solve_s: f64,
    newton: usize,
    ksp: usize,
    err_max: f64,
    err_mean: f64,
    peak_mib: f64,
}

/// One run of a case: the code, its configuration, n, cores, the linear variant or not, and
/// where to write u (`None`: nowhere).
struct Run<'a> {
    code: &'a str,
    config: &'a str,
    n: usize,
    cores: usize,
    barrier: bool,
    u_file: Option<PathBuf>,
}

/// `cmd`'s stdout and its wall clock, seconds.
fn timed(cmd: Command, exe: &Path, what: &str) -> gradvi::Result<(String, f64)> {
    let t = Instant::now();
    let text = stdout_of(cmd, exe, what)?;
    Ok((text, t.elapsed().as_secs_f64()))
}

/// The dolfinx command of `run` (one process alone, or `mpiexec -n N`).
fn dolfinx_command(python: &Path, script: &Path, run: &Run) -> Command {
    let mut cmd = if run.cores > 1 {
        let mut c = Command::new("mpiexec");
        c.args(["-n", &run.cores.to_string()]).arg(python);
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
            .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        c
    } else {
        Command::new(python)
    };
    cmd.arg(script)
        .args(["--n", &run.n.to_string(), "--pc", run.config]);
    if !run.barrier {
        cmd.arg("--linear");
    }
    if let Some(f) = &run.u_file {
        cmd.arg("--write-u").arg(f);
    }
    cmd.env("OMP_NUM_THREADS", "1");
    cmd
}

/// Runs `run` (gradvi through `exe`'s child mode, dolfinx through [`SCRIPT`]) and returns its
/// row, `total_s` measured here.
fn run_one(cfg: &super::Config, exe: &Path, run: &Run) -> gradvi::Result<Peer3Row> {
    let what = format!(
        "3D {} {} n = {}, {} cores{}",
        run.code,
        run.config,
        run.n,
        run.cores,
        if run.barrier { "" } else { " (linear variant)" }
    );
    eprintln!("[bench] {what} ...");
    if run.code == "gradvi" {
        let mut cmd = Command::new(exe);
        cmd.args(["bench", "--peer3d-child"]);
        if !run.barrier {
            cmd.arg(NO_BARRIER);
        }
        cmd.arg(run.n.to_string()).args(run.u_file.iter());
        cmd.env("RAYON_NUM_THREADS", run.cores.to_string());
        let (text, secs) = timed(cmd, exe, &what)?;
        let mut row: Peer3Row = json_row(&text, &format!("{what}: bad child output"))?;
        row.total_s = secs;
        return Ok(row);
    }
    let cmd = dolfinx_command(&cfg.python, &cfg.path(SCRIPT), run);
    let (text, secs) = timed(cmd, &cfg.python, &what)?;
    let d: Dolfinx = json_row(&text, &format!("{what}: bad output"))?;
    Ok(Peer3Row {
        code: "dolfinx".into(),
        config: run.config.into(),
        n: run.n,
        cells: d.cells,
        unknowns: d.unknowns,
        cores: d.processes,
        niter: d.newton,
        coarse_niter: 0,
        krylov: d.ksp,
        setup_s: d.setup_s,
        solve_s: d.solve_s,
        total_s: secs,
        phases: String::new(),
        peak_mib: d.peak_mib,
        err_max: d.err_max,
        err_mean: d.err_mean,
        linear_seconds: f64::NAN,
        linear_krylov: 0,
        r: f64::NAN,
        diff_u: f64::NAN,
    })
}

/// The values of a file written by `write_u` or `ex9_3d.py --write-u`.
fn read_u(path: &Path) -> gradvi::Result<Vec<f64>> {
    let bytes = std::fs::read(path).map_err(|e| io_err(path, e))?;
    if bytes.len() % 8 != 0 {
        return Err(bad(format!("{}: not a file of f64", path.display())));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect())
}

/// max |a − b| over the vertices (NaN values, vertices missing from a file, count as NaN).
fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, |m: f64, d| {
            if d.is_nan() || m.is_nan() {
                f64::NAN
            } else {
                m.max(d)
            }
        })
}

/// The estimated peak of a dolfinx case and what it rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Peak resident memory, MiB (summed over the ranks).
    pub mib: f64,
    /// What it was computed from: "its rows at n = 64 and 100" or the constant's text.
    pub basis: String,
}

/// (n + 1)³, the unknowns of n³ cubes.
fn unknowns_of(n: usize) -> f64 {
    ((n + 1) as f64).powi(3)
}

/// dolfinx's estimated peak memory for configuration `config` on `cores` processes at n³ cubes,
/// from `rows` (the CSV so far): the affine function of the unknowns through its rows (obstacle
/// runs, the same configuration and cores, peak measured) at the two largest sizes below n —
/// the mesh, the matrix, the multigrid hierarchy and the vectors all grow like the unknowns,
/// and the constant term holds the interpreter and libraries (measured: the affine function
/// through n = 64 and 100 on one process predicted 5406 MiB at n = 128 for the linear variant,
/// which read 5432 MiB; `replication/measurements/solver3d.md`); with only one such row,
/// proportional to it; with none, [`DOLFINX_BYTES_PER_UNKNOWN`] per unknown, a quarter more on
/// more than one process.
pub fn dolfinx_estimate(rows: &[Peer3Row], config: &str, cores: usize, n: usize) -> Estimate {
    let mut below: Vec<&Peer3Row> = rows
        .iter()
        .filter(|r| {
            r.code == "dolfinx"
                && r.config == config
                && r.cores == cores
                && r.n < n
                && r.peak_mib.is_finite()
                && r.peak_mib > 0.0
        })
        .collect();
    below.sort_by_key(|r| r.n);
    below.dedup_by_key(|r| r.n);
    let u = unknowns_of(n);
    match below.as_slice() {
        [.., a, b] => {
            let (ua, ub) = (unknowns_of(a.n), unknowns_of(b.n));
            let slope = (b.peak_mib - a.peak_mib) / (ub - ua);
            // a falling or flat footprint (noise at small sizes) is no basis: proportional then
            let mib = if slope > 0.0 {
                b.peak_mib + slope * (u - ub)
            } else {
                b.peak_mib * u / ub
            };
            Estimate {
                mib,
                basis: format!("its rows at n = {} and {}", a.n, b.n),
            }
        }
        [b] => Estimate {
            mib: b.peak_mib * u / unknowns_of(b.n),
            basis: format!("its row at n = {}", b.n),
        },
        [] => Estimate {
            mib: DOLFINX_BYTES_PER_UNKNOWN * u * if cores > 1 { 1.25 } else { 1.0 }
                / (1024.0 * 1024.0),
            basis: format!("{DOLFINX_BYTES_PER_UNKNOWN:.0} bytes per unknown"),
        },
    }
}

/// Whether a case of estimated peak `estimate` may run with `available` bytes free
/// ([`MEMORY_MARGIN`]).
pub fn fits_in(estimate: &Estimate, available: u64) -> bool {
    MEMORY_MARGIN * estimate.mib * 1024.0 * 1024.0 <= available as f64
}

/// The obstacle run `run` then its linear variant, R, and the difference of u to `reference`
/// (dolfinx GAMG on one process, when written already).
fn run_case(
    cfg: &super::Config,
    exe: &Path,
    mut run: Run,
    reference: &Path,
) -> gradvi::Result<Peer3Row> {
    let mut row = run_one(cfg, exe, &run)?;
    if let Some(f) = run
        .u_file
        .take()
        .filter(|f| f != reference && reference.exists())
    {
        row.diff_u = max_diff(&read_u(&f)?, &read_u(reference)?);
    }
    run.barrier = false;
    let linear = run_one(cfg, exe, &run)?;
    row.linear_seconds = linear.total_s;
    row.linear_krylov = linear.krylov;
    row.r = row.total_s / linear.total_s;
    eprintln!(
        "[bench]   {} {} n = {}, {} cores: {} unknowns, NITER {} (+{}), {} Krylov, {:.2} s (setup {:.2}, solve {:.2}), {:.0} MiB, error {:.3e}, |u - u_dolfinx| {:.1e}, linear {:.2} s, R {:.2}",
        row.code,
        row.config,
        row.n,
        row.cores,
        row.unknowns,
        row.niter,
        row.coarse_niter,
        row.krylov,
        row.total_s,
        row.setup_s,
        row.solve_s,
        row.peak_mib,
        row.err_max,
        row.diff_u,
        row.linear_seconds,
        row.r
    );
    Ok(row)
}

/// The cases of size `n` at every core count: dolfinx GAMG and hypre (when `dolfinx`; those
/// named in `GRADVI_BENCH_3D_DOLFINX`, comma-separated, default `gamg,hypre`; each
/// only if it fits ([`fits_in`]) by its estimate from the rows of the `smaller` sizes), then
/// gradvi, each followed by its linear variant, each row given to `push` as it comes; u is
/// compared with dolfinx GAMG on one process. A failed or left-out dolfinx run is said on
/// stderr and leaves its row out (the report shows it missing); a failed gradvi run is an
/// error.
fn run_size(
    cfg: &super::Config,
    exe: &Path,
    (n, dolfinx): (usize, bool),
    smaller: &[Peer3Row],
    push: &mut dyn FnMut(Peer3Row) -> gradvi::Result<()>,
) -> gradvi::Result<()> {
    let dir = cfg.path(U_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| io_err(&dir, e))?;
    let reference = dir.join(format!("u_dolfinx_gamg_{n}.f64"));
    let _ = std::fs::remove_file(&reference);
    let all: [(&str, &str); 3] = [
        ("dolfinx", "gamg"),
        ("dolfinx", "hypre"),
        ("gradvi", "p1 iterative"),
    ];
    let configs = std::env::var("GRADVI_BENCH_3D_DOLFINX").unwrap_or_else(|_| "gamg,hypre".into());
    let asked = |config: &str| configs.split(',').any(|c| c.trim() == config);
    for cores in super::peers::core_counts() {
        for &(code, config) in all
            .iter()
            .filter(|c| c.0 == "gradvi" || (dolfinx && asked(c.1)))
        {
            if code == "dolfinx" {
                let estimate = dolfinx_estimate(smaller, config, cores, n);
                let available = MemoryBudget::available().bytes();
                if !fits_in(&estimate, available) {
                    eprintln!(
                        "[bench] warning: no row for dolfinx {config}, n = {n}, {cores} cores: \
                         its estimated peak, {} (from {}), times {MEMORY_MARGIN} is above the \
                         {} available",
                        human_bytes((estimate.mib * 1024.0 * 1024.0) as u64),
                        estimate.basis,
                        human_bytes(available)
                    );
                    continue;
                }
            }
            let u_file = match (code, config) {
                ("dolfinx", "gamg") => (cores == 1).then(|| reference.clone()),
                ("dolfinx", _) => (cores == 1).then(|| dir.join(format!("u_{config}_{n}.f64"))),
                _ => Some(dir.join(format!("u_gradvi_{n}_{cores}.f64"))),
            };
            let run = Run {
                code,
                config,
                n,
                cores,
                barrier: true,
                u_file,
            };
            match run_case(cfg, exe, run, &reference) {
                Ok(row) => push(row)?,
                Err(e) if code == "dolfinx" => {
                    eprintln!(
                        "[bench] warning: no row for dolfinx {config}, n = {n}, {cores} cores: {e}"
                    )
                }
                Err(e) => return Err(e),
            }
        }
    }
    Ok(())
}

/// Runs the benchmark and writes [`CSV`] (after each row).
pub fn run(cfg: &super::Config, exe: &Path) -> gradvi::Result<()> {
    let max_n = super::usize_from_env("GRADVI_BENCH_3D_MAX_N", DEFAULT_MAX_N)?;
    let dolfinx = super::dolfinx_available(&cfg.python);
    if dolfinx {
        // compiles and caches dolfinx's forms, so that no timed run pays for it
        let warm = Run {
            code: "dolfinx",
            config: "gamg",
            n: 4,
            cores: 1,
            barrier: true,
            u_file: None,
        };
        run_one(cfg, exe, &warm)?;
    } else {
        eprintln!(
            "[bench] warning: no dolfinx rows: {} cannot import dolfinx",
            cfg.python.display()
        );
    }
    let min_n = super::usize_from_env("GRADVI_BENCH_3D_MIN_N", 0)?;
    let sizes: Vec<usize> = SIZES
        .into_iter()
        .filter(|&n| (min_n..=max_n).contains(&n))
        .collect();
    let earlier = read_rows(cfg)?;
    let csv = cfg.path(CSV);
    // the rows of the sizes not run now are kept; those of the sizes run are replaced
    let mut rows: Vec<Peer3Row> = earlier
        .iter()
        .filter(|r| !sizes.contains(&r.n))
        .cloned()
        .collect();
    for n in sizes {
        // the dolfinx estimates extrapolate from the rows of the smaller sizes, this run's
        let before = rows.clone();
        let mut push = |row: Peer3Row| -> gradvi::Result<()> {
            rows.push(row);
            // by size, each size's rows in the order they were run
            rows.sort_by_key(|r| r.n);
            write_csv(&csv, &rows)
        };
        run_size(cfg, exe, (n, dolfinx), &before, &mut push)?;
    }
    Ok(())
}

/// The rows of [`CSV`] (empty if it does not exist).
pub fn read_rows(cfg: &super::Config) -> gradvi::Result<Vec<Peer3Row>> {
    super::read_rows_of(cfg, CSV)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_index_numbers_x_fastest_then_y_then_z() {
        let n = 4;
        assert_eq!(grid_index([-2.0, -2.0, -2.0], n), 0);
        assert_eq!(grid_index([-1.0, -2.0, -2.0], n), 1);
        assert_eq!(grid_index([-2.0, -1.0, -2.0], n), 5);
        assert_eq!(grid_index([-2.0, -2.0, -1.0], n), 25);
        assert_eq!(grid_index([2.0, 2.0, 2.0], n), 124);
    }

    /// A dolfinx row of `config` on `cores` processes at n³ cubes with peak `mib`.
    fn dolfinx_row(config: &str, cores: usize, n: usize, mib: f64) -> Peer3Row {
        Peer3Row {
            code: "dolfinx".into(),
            config: config.into(),
            n,
            cells: 6 * n * n * n,
            unknowns: (n + 1).pow(3),
            cores,
            niter: 1,
            coarse_niter: 0,
            krylov: 1,
            setup_s: 1.0,
            solve_s: 1.0,
            total_s: 2.0,
            phases: String::new(),
            peak_mib: mib,
            err_max: 0.0,
            err_mean: 0.0,
            linear_seconds: 1.0,
            linear_krylov: 1,
            r: 2.0,
            diff_u: f64::NAN,
        }
    }

    #[test]
    fn the_dolfinx_estimate_extrapolates_its_own_two_largest_rows() {
        let u = |n: usize| ((n + 1) as f64).powi(3);
        let rows = vec![
            dolfinx_row("gamg", 1, 32, 179.0),
            dolfinx_row("gamg", 1, 64, 764.0),
            dolfinx_row("gamg", 1, 100, 2638.0),
            dolfinx_row("gamg", 2, 100, 2859.0),
            dolfinx_row("hypre", 1, 64, 790.0),
            dolfinx_row("hypre", 1, 200, 1.0),
        ];
        // affine through n = 64 and 100 (not 32, not the other configuration or cores)
        let e = dolfinx_estimate(&rows, "gamg", 1, 200);
        let want = 2638.0 + (2638.0 - 764.0) / (u(100) - u(64)) * (u(200) - u(100));
        assert!((e.mib - want).abs() < 1e-6 * want, "{e:?}");
        assert!(e.mib > 19_000.0 && e.mib < 21_000.0, "{e:?}");
        assert_eq!(e.basis, "its rows at n = 64 and 100");
        // its rows at n = 128 (predicted above) and below (the measured value 5432 MiB of the
        // linear variant is within 1%)
        let at128 = dolfinx_estimate(&rows, "gamg", 1, 128).mib;
        assert!((at128 / 5432.0 - 1.0).abs() < 0.01, "{at128}");
        // one row: proportional; rows at n or above are not used
        let e = dolfinx_estimate(&rows, "gamg", 2, 200);
        assert!((e.mib - 2859.0 * u(200) / u(100)).abs() < 1e-6, "{e:?}");
        assert_eq!(e.basis, "its row at n = 100");
        let e = dolfinx_estimate(&rows, "hypre", 1, 200);
        assert!((e.mib - 790.0 * u(200) / u(64)).abs() < 1e-6, "{e:?}");
        // none: the constant, a quarter more on two processes
        let e1 = dolfinx_estimate(&[], "gamg", 1, 64);
        let e2 = dolfinx_estimate(&[], "gamg", 2, 64);
        assert!((e1.mib - DOLFINX_BYTES_PER_UNKNOWN * u(64) / 1048576.0).abs() < 1e-6);
        assert!((e2.mib - 1.25 * e1.mib).abs() < 1e-6);
        // a footprint that fell (noise) is no slope: proportional to the larger row
        let falling = [
            dolfinx_row("gamg", 1, 16, 120.0),
            dolfinx_row("gamg", 1, 32, 110.0),
        ];
        let e = dolfinx_estimate(&falling, "gamg", 1, 64);
        assert!((e.mib - 110.0 * u(64) / u(32)).abs() < 1e-6, "{e:?}");
    }

    #[test]
    fn a_case_fits_with_the_margin_only() {
        let e = Estimate {
            mib: 1000.0,
            basis: String::new(),
        };
        let mib = 1024 * 1024;
        assert!(fits_in(&e, 1050 * mib));
        assert!(!fits_in(&e, 1049 * mib));
    }

    #[test]
    fn max_diff_is_nan_on_a_missing_value_or_length() {
        assert_eq!(max_diff(&[1.0, 2.0], &[1.5, 1.0]), 1.0);
        assert!(max_diff(&[1.0, f64::NAN], &[1.0, 1.0]).is_nan());
        assert!(max_diff(&[1.0], &[1.0, 1.0]).is_nan());
    }
}
