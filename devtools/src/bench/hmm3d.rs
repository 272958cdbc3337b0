//! The HMM benchmark on n³ cubes (`gradvi-dev bench --hmm3d`, `make bench-hmm3d`): the 3D
//! radial obstacle problem (`problems/ex9-3d.toml`) on (−2,2)³ cut into n³ cubes, solved by
//! gradvi alone with the HMM scheme, up to the size of the performance issue's target 5: HMM on
//! 200³ cubes (8M cells) within 24 GiB.
//!
//! **The problem.** −Δu = 0, u ≥ ψ, u = ū on the boundary, ū the exact solution of the problem
//! file; the relative L² error of u at the centroids is the one `gradvi solve` prints
//! ([`gradvi::post::relative_errors`]).
//!
//! **The solve.** The cubes of [`gradvi::mesh3d::generate::cubes()`], HMM
//! ([`SchemeKind::Hmm`]), the default solve options with the iterative linear solver
//! (multigrid CG, the nested warm start), in a child process `gradvi-dev bench --hmm3d-child
//! [--no-barrier] N` so that the peak resident set (`VmHWM`) is the case's own. Every case runs
//! on 1 core and on N, the machine's cores ([`super::peers::core_counts`], rayon threads), and
//! is followed by its linear variant (`--no-barrier`: the same mesh, scheme, solver and cores
//! without the constraint); `total_s` is the wall clock of the child, measured by the driver,
//! and R = `total_s / linear_seconds`.
//!
//! **Sizes.** n in [`SIZES`] up to `GRADVI_BENCH_HMM3D_MAX_N` (default [`DEFAULT_MAX_N`]); a size
//! whose estimated peak ([`BYTES_PER_CELL`] per cell) does not fit in the memory available is
//! skipped, said on stderr ([`fits`]). Rows go to [`CSV`], rewritten after each case (a long run
//! keeps what it measured); as in [`super::peers3d`], the rows of the sizes run replace the
//! earlier run's, and those of the sizes not run (above the maximum, or skipped) are kept, so
//! that a quick rerun does not drop the 200³ row of target 5 ([`kept_rows`]); the report's
//! section is [`super::hmm3d_report`].

use super::peers3d::{BOX, phases, problem};
use super::{bad, json_row, peak_memory_mib, stdout_of};
use gradvi::budget::{MemoryBudget, human_bytes};
use gradvi::mesh3d::PolyMesh3;
use gradvi::mesh3d::generate::cubes;
use gradvi::scheme::{SchemeKind, SchemeOptions, build_with3};
use gradvi::solver::{SolveOptions, solve_problem};
use gradvi_cli::replication::records::write_csv;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// The CSV of this benchmark.
pub const CSV: &str = "replication/results/bench_hmm3d.csv";
/// Cubes per side: 32 768 to 8M cells (n³).
pub const SIZES: [usize; 5] = [32, 64, 100, 128, 200];
/// Default cap on n (`GRADVI_BENCH_HMM3D_MAX_N`).
pub const DEFAULT_MAX_N: usize = 64;
/// The size of target 5: 200³ cubes.
pub const TARGET_N: usize = 200;
/// The memory of target 5, MiB (24 GiB).
pub const TARGET_MIB: f64 = 24.0 * 1024.0;
/// Peak resident memory of an HMM child per cell, bytes, rounded up from a measurement:
/// `gradvi solve problems/ex9-3d.toml --scheme hmm --generate cubes --level 6` (128³ =
/// 2 097 152 cubes, iterative solver, 2 threads) peaked at 3 538 584 KiB, 1.69 KiB per cell.
/// Used only to skip the sizes that would not fit ([`fits`]).
pub const BYTES_PER_CELL: f64 = 1.8 * 1024.0;
/// The flag of a child that runs the linear variant.
const NO_BARRIER: &str = "--no-barrier";

/// One row of [`CSV`]: one case (n, cores) and its linear variant.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Hmm3Row {
    /// Cubes per side.
    pub n: usize,
    /// Cells (n³).
    pub cells: usize,
    /// Faces.
    pub faces: usize,
    /// Unknowns of the scheme (faces and cells).
    pub unknowns: usize,
    /// Rayon threads of the child.
    pub cores: usize,
    /// Linear solves of the fine active-set iteration.
    pub niter: usize,
    /// Linear solves of the nested warm start's coarse levels.
    pub coarse_niter: usize,
    /// Krylov iterations, all fine solves.
    pub krylov: usize,
    /// Mesh generation and the solver's setup.
    pub setup_s: f64,
    /// The solve (warm start and active-set iteration).
    pub solve_s: f64,
    /// Wall clock of the child, measured by the driver.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub total_s: f64,
    /// The solve by phase, seconds: warm start (coarse solves), assembly, multigrid setups,
    /// conjugate gradients, look-ahead (`warm|assemble|setup|cg|look-ahead`).
    pub phases: String,
    /// Peak resident memory of the child (`VmHWM`), MiB.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub peak_mib: f64,
    /// The certificate's largest scaled constraint violation.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub violation: f64,
    /// The certificate's scaled balance residual (non-Dirichlet, inactive unknowns).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub balance_residual: f64,
    /// The certificate's largest scaled quantity.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub certificate: f64,
    /// Whether the certificate passed at the solve's tolerance.
    pub certified: bool,
    /// Relative L² error of u at the centroids.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub l2_u: f64,
    /// Relative L² error of the gradient at the centroids.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub l2_grad: f64,
    /// `total_s` of the linear variant (no constraint).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub linear_seconds: f64,
    /// Krylov iterations of the linear variant.
    pub linear_krylov: usize,
    /// R = `total_s / linear_seconds`.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub r: f64,
    /// The solver's error when the solve failed (a typed error: certificate, iterations,
    /// memory…), empty when it succeeded; a failed row has `certified` false, its peak and
    /// times up to the failure, and no solve details (NaN or 0).
    #[serde(default)]
    pub error: String,
}

impl Hmm3Row {
    /// Peak resident memory per cell, bytes.
    pub fn bytes_per_cell(&self) -> f64 {
        self.peak_mib * 1024.0 * 1024.0 / self.cells as f64
    }

    /// Wall clock per cell, µs.
    pub fn us_per_cell(&self) -> f64 {
        1e6 * self.total_s / self.cells as f64
    }
}

/// Solves the case of `n` in this process (the body of a `--hmm3d-child`); without the
/// `barrier`, its linear variant. `total_s` and the linear fields are left to the driver.
fn run_gradvi(n: usize, barrier: bool, root: &Path) -> gradvi::Result<Hmm3Row> {
    let t0 = Instant::now();
    let budget = MemoryBudget::available();
    let mesh = PolyMesh3::from_polyhedra(cubes(n, BOX, budget)?, budget)?;
    let mut problem = problem(root)?;
    if !barrier {
        problem.constraint = None;
    }
    let scheme = build_with3(SchemeKind::Hmm, &mesh, &SchemeOptions::default())?;
    let mut options = SolveOptions::default();
    options.system.linear = "iterative".parse()?;
    options.system.budget = budget;
    let before_solve = t0.elapsed().as_secs_f64();
    let sol = match solve_problem(scheme.as_ref(), &problem, &options) {
        Ok(sol) => sol,
        Err(e) => {
            return Ok(failed_row(
                (n, mesh.n_cells(), mesh.n_faces(), scheme.n_unknowns()),
                before_solve,
                t0.elapsed().as_secs_f64() - before_solve,
                e.to_string(),
            ));
        }
    };
    let exact = problem
        .exact
        .as_ref()
        .ok_or_else(|| bad("ex9-3d.toml: no exact solution".into()))?;
    let errors = gradvi::post::relative_errors(scheme.as_ref(), sol.u(), &exact.u, &exact.grad);
    let t = sol.timings;
    let c = sol.result.certificate;
    Ok(Hmm3Row {
        n,
        cells: mesh.n_cells(),
        faces: mesh.n_faces(),
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
        violation: c.max_violation,
        balance_residual: c.balance_residual,
        certificate: c.worst(),
        certified: c.check(options.active_set.tol).is_ok(),
        l2_u: errors.l2_u,
        l2_grad: errors.l2_grad,
        linear_seconds: f64::NAN,
        linear_krylov: 0,
        r: f64::NAN,
        error: String::new(),
    })
}

/// The row of a solve that failed with `error`: (n, cells, faces, unknowns), the setup and
/// the time until the failure, the peak so far; no certificate, errors or iteration counts.
fn failed_row(
    (n, cells, faces, unknowns): (usize, usize, usize, usize),
    setup_s: f64,
    solve_s: f64,
    error: String,
) -> Hmm3Row {
    Hmm3Row {
        n,
        cells,
        faces,
        unknowns,
        cores: rayon::current_num_threads(),
        niter: 0,
        coarse_niter: 0,
        krylov: 0,
        setup_s,
        solve_s,
        total_s: f64::NAN,
        phases: String::new(),
        peak_mib: peak_memory_mib(),
        violation: f64::NAN,
        balance_residual: f64::NAN,
        certificate: f64::NAN,
        certified: false,
        l2_u: f64::NAN,
        l2_grad: f64::NAN,
        linear_seconds: f64::NAN,
        linear_krylov: 0,
        r: f64::NAN,
        error,
    }
}

/// Arguments of a child process: `[--no-barrier] N`.
pub fn child_main(args: &[String], root: &Path) -> gradvi::Result<()> {
    let barrier = args.first().is_none_or(|a| a != NO_BARRIER);
    let args = if barrier { args } else { &args[1..] };
    let n: usize = args
        .first()
        .and_then(|a| a.parse().ok())
        .ok_or_else(|| bad(format!("--hmm3d-child [{NO_BARRIER}] N")))?;
    let row = run_gradvi(n, barrier, root)?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
    );
    Ok(())
}

/// The estimated peak resident memory of the case of `n`, bytes ([`BYTES_PER_CELL`] × n³).
pub fn estimated_bytes(n: usize) -> f64 {
    BYTES_PER_CELL * (n as f64).powi(3)
}

/// Whether the case of `n` fits in `available` bytes by [`estimated_bytes`].
pub fn fits_in(n: usize, available: u64) -> bool {
    estimated_bytes(n) <= available as f64
}

/// Whether the size `n` fits in the memory available now ([`fits_in`]; said on stderr if not).
pub fn fits(n: usize) -> bool {
    let available = MemoryBudget::available().bytes();
    let ok = fits_in(n, available);
    if !ok {
        eprintln!(
            "[bench] warning: HMM 3D n = {n} ({} cells) skipped: it needs about {} ({:.0} bytes per cell), {} available",
            n.pow(3),
            human_bytes(estimated_bytes(n) as u64),
            BYTES_PER_CELL,
            human_bytes(available)
        );
    }
    ok
}

/// Runs the child of `n` on `cores` rayon threads (`barrier`: the obstacle problem, otherwise
/// its linear variant) and returns its row, `total_s` the child's wall clock measured here; one
/// line on stderr with its time and peak.
fn run_one(exe: &Path, n: usize, cores: usize, barrier: bool) -> gradvi::Result<Hmm3Row> {
    let what = format!(
        "HMM 3D n = {n}, {cores} core{}{}",
        if cores == 1 { "" } else { "s" },
        if barrier { "" } else { " (linear variant)" }
    );
    let mut cmd = Command::new(exe);
    cmd.args(["bench", "--hmm3d-child"]);
    if !barrier {
        cmd.arg(NO_BARRIER);
    }
    cmd.arg(n.to_string());
    cmd.env("RAYON_NUM_THREADS", cores.to_string());
    let t = Instant::now();
    let text = stdout_of(cmd, exe, &what)?;
    let total_s = t.elapsed().as_secs_f64();
    let mut row: Hmm3Row = json_row(&text, &format!("{what}: bad child output"))?;
    row.total_s = total_s;
    eprintln!(
        "[bench] {what}: {} cells, {} unknowns, NITER {} (+{}), {} Krylov, {:.2} s (setup {:.2}, solve {:.2}), peak {:.0} MiB ({:.0} bytes per cell), certificate {:.1e}{}, L2 error {:.3e}",
        row.cells,
        row.unknowns,
        row.niter,
        row.coarse_niter,
        row.krylov,
        row.total_s,
        row.setup_s,
        row.solve_s,
        row.peak_mib,
        row.bytes_per_cell(),
        row.certificate,
        if row.certified { "" } else { " (failed)" },
        row.l2_u
    );
    if !row.error.is_empty() {
        eprintln!("[bench]   the solve failed: {}", row.error);
    }
    Ok(row)
}

/// The case of `n` on `cores` cores, then its linear variant, and R.
fn run_case(exe: &Path, n: usize, cores: usize) -> gradvi::Result<Hmm3Row> {
    let mut row = run_one(exe, n, cores, true)?;
    if !row.error.is_empty() {
        // no R for a failed solve: its linear variant is not run
        return Ok(row);
    }
    let linear = run_one(exe, n, cores, false)?;
    row.linear_seconds = linear.total_s;
    row.linear_krylov = linear.krylov;
    row.r = row.total_s / linear.total_s;
    eprintln!("[bench]   R = {:.2}", row.r);
    Ok(row)
}

/// The cap on n: `GRADVI_BENCH_HMM3D_MAX_N`, [`DEFAULT_MAX_N`] when unset (an error when it is
/// not a non-negative integer).
fn max_n() -> gradvi::Result<usize> {
    super::usize_from_env("GRADVI_BENCH_HMM3D_MAX_N", DEFAULT_MAX_N)
}

/// Runs the benchmark and writes [`CSV`] (after each case).
pub fn run(cfg: &super::Config, exe: &Path) -> gradvi::Result<()> {
    let max_n = max_n()?;
    eprintln!(
        "[bench] HMM on n³ cubes of (-2,2)³, n in {SIZES:?} up to {max_n} (GRADVI_BENCH_HMM3D_MAX_N), cores {:?}",
        super::peers::core_counts()
    );
    let csv = cfg.path(CSV);
    let sizes: Vec<usize> = SIZES
        .into_iter()
        .filter(|&n| n <= max_n && fits(n))
        .collect();
    let mut rows = kept_rows(read_rows(cfg)?, &sizes);
    for n in sizes {
        for cores in super::peers::core_counts() {
            rows.push(run_case(exe, n, cores)?);
            // by size, each size's rows in the order they were run
            rows.sort_by_key(|r| r.n);
            write_csv(&csv, &rows)?;
        }
    }
    Ok(())
}

/// The rows of an earlier run that a run of the sizes `sizes` keeps: those of the other sizes.
fn kept_rows(earlier: Vec<Hmm3Row>, sizes: &[usize]) -> Vec<Hmm3Row> {
    earlier
        .into_iter()
        .filter(|r| !sizes.contains(&r.n))
        .collect()
}

/// The rows of [`CSV`] (empty if it does not exist).
pub fn read_rows(cfg: &super::Config) -> gradvi::Result<Vec<Hmm3Row>> {
    super::read_rows_of(cfg, CSV)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rerun of some sizes replaces their rows and keeps the others' (the 200³ row of a
    /// rerun up to 64, and a size skipped for memory).
    #[test]
    fn a_rerun_keeps_the_rows_of_the_sizes_it_does_not_run() {
        let row = |n: usize, cores: usize| Hmm3Row {
            n,
            cores,
            ..Default::default()
        };
        let earlier = vec![row(32, 1), row(32, 2), row(64, 1), row(200, 1), row(200, 2)];
        let kept = kept_rows(earlier.clone(), &[32, 64]);
        let sizes: Vec<(usize, usize)> = kept.iter().map(|r| (r.n, r.cores)).collect();
        assert_eq!(sizes, vec![(200, 1), (200, 2)]);
        assert_eq!(kept_rows(earlier.clone(), &[]).len(), earlier.len());
        assert!(kept_rows(earlier, &[32, 64, 200]).is_empty());
    }

    #[test]
    fn the_estimate_grows_with_the_cells_and_decides_the_skip() {
        // 200³ cells at 1.8 KiB: 8e6 × 1843.2 bytes, about 13.7 GiB
        assert_eq!(estimated_bytes(200), 8e6 * 1843.2);
        assert_eq!(estimated_bytes(100) * 8.0, estimated_bytes(200));
        let gib = 1u64 << 30;
        assert!(fits_in(200, 24 * gib));
        assert!(!fits_in(200, 13 * gib));
        assert!(fits_in(128, 4 * gib) && !fits_in(128, 3 * gib));
        assert!(fits_in(32, 64 << 20));
    }

    #[test]
    fn the_rows_per_cell_are_peak_and_time_over_cells() {
        let row = Hmm3Row {
            n: 2,
            cells: 8,
            faces: 36,
            unknowns: 44,
            cores: 1,
            niter: 1,
            coarse_niter: 0,
            krylov: 3,
            setup_s: 0.1,
            solve_s: 0.1,
            total_s: 0.4,
            phases: String::new(),
            peak_mib: 1.0,
            violation: 0.0,
            balance_residual: 1e-12,
            certificate: 1e-12,
            certified: true,
            l2_u: 1e-2,
            l2_grad: 1e-1,
            linear_seconds: 0.2,
            linear_krylov: 2,
            r: 2.0,
            error: String::new(),
        };
        assert_eq!(row.bytes_per_cell(), 131_072.0);
        assert_eq!(row.us_per_cell(), 50_000.0);
    }

    #[test]
    fn a_failed_row_goes_through_the_child_json_and_back() {
        let row = failed_row(
            (200, 8_000_000, 24_120_000, 32_120_000),
            50.0,
            90.0,
            "certificate failed".into(),
        );
        let text = serde_json::to_string(&row).unwrap();
        let back: Hmm3Row = json_row(&text, "test").unwrap();
        assert!(!back.certified && back.error == "certificate failed");
        assert!(back.certificate.is_nan() && back.l2_u.is_nan() && back.balance_residual.is_nan());
        assert_eq!(
            (back.n, back.cells, back.unknowns),
            (200, 8_000_000, 32_120_000)
        );
    }
}
