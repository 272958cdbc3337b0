//! The 3D "any domain" benchmark (`gradvi-dev bench --domains3d`, `make bench-domains3d`): the
//! 3D radial obstacle problem (`problems/ex9-3d.toml`) on meshes that are not the Kuhn cubes of
//! the dolfinx comparison ([`super::peers3d`]).
//!
//! **The problem.** −Δu = 0, u ≥ ψ (ψ = √(1 − r²) on r ≤ 1, −1 beyond), u = ū on the whole
//! boundary, where ū = ψ on the contact ball r ≤ r₀ = 1/√2 and ū = 1/(2r) outside it. ū solves
//! the problem on any domain Ω that contains the contact ball (the derivation is in the problem
//! file): with the Dirichlet data ū on ∂Ω, ū is the solution, and the error |u − ū| measures
//! the scheme.
//!
//! **The domains** ([`DOMAINS`], `benches/domains3d/*.geo`, unstructured gmsh tetrahedra of
//! size `lc`): the ball of radius 2 centred at 0; the cube (−2,2)³ with a spherical hole of
//! centre (1.1, 1.1, 1.1) and radius 0.4 (its distance to 0 is 1.1√3 − 0.4 ≈ 1.51 > r₀); the
//! cube (−2,2)³ itself. Each is meshed for about [`TARGETS`] cells, up to
//! `GRADVI_BENCH_DOMAINS3D_MAX_CELLS` (default [`DEFAULT_MAX_CELLS`]), into
//! `target/bench-meshes/` (reused when present, not committed), the lc of a target from the
//! calibration [`lc_for`]. Beside them, HArDCore3D's Voronoi family ([`VORONOI`], RF format,
//! polyhedral cells of the unit cube, mapped affinely onto (−2,2)³), HMM only (P1 needs
//! tetrahedra), from `GRADVI_BENCH_HARDCORE3D` (default `../shared/meshes/hardcore3d` next to
//! the repository); where it is missing, its rows are absent and the report says so.
//!
//! **The solves.** HMM and P1 with the default options of `gradvi solve` (linear solver
//! `auto`: direct below `assembly::AUTO_ITERATIVE_MIN_3D` condensed unknowns, iterative above;
//! the nested warm start), on 1 and N cores ([`super::peers::core_counts`], rayon threads), each
//! in a child process (`gradvi-dev bench --domain3d-child DOMAIN SCHEME FILE`) so that the peak
//! memory is the case's own; `total_s` is the child's wall clock, measured by the driver. A
//! case that fails is a row with its error in `status` (the benchmark goes on). Rows go to
//! [`CSV`], written after each case; `GRADVI_BENCH_DOMAINS3D` (comma-separated, default
//! `ball,hole,cube,voronoi`) selects the domains, the rows of the others are kept from the
//! existing CSV. The report's section is [`super::domains3d_report`].

use super::peers3d::{BOX, problem};
use super::{Config, bad, io_err, json_row, peak_memory_mib};
use gradvi::budget::MemoryBudget;
use gradvi::mesh3d::PolyMesh3;
use gradvi::mesh3d::io::read_mesh3;
use gradvi::scheme::{SchemeKind, SchemeOptions, build_with3};
use gradvi::solver::{SolveOptions, solve_problem};
use gradvi_cli::replication::records::write_csv;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The CSV of this benchmark.
pub const CSV: &str = "replication/results/bench_domains3d.csv";
/// The gmsh domains (`benches/domains3d/NAME.geo`) with their volumes.
pub const DOMAINS: [(&str, f64); 3] = [
    ("ball", 4.0 / 3.0 * PI * 8.0),                    // (4/3)π 2³
    ("hole", 64.0 - 4.0 / 3.0 * PI * 0.4 * 0.4 * 0.4), // 4³ − (4/3)π 0.4³
    ("cube", 64.0),
];
/// Target numbers of tetrahedra of the gmsh meshes.
pub const TARGETS: [usize; 5] = [10_000, 30_000, 100_000, 300_000, 1_000_000];
/// Default cap on the cells of a gmsh mesh (`GRADVI_BENCH_DOMAINS3D_MAX_CELLS`).
pub const DEFAULT_MAX_CELLS: usize = 1_000_000;
/// gmsh's tetrahedra per unit volume at size lc are about this over lc³ (measured on these
/// `.geo` files, Delaunay with one size everywhere: 239 810 tetrahedra in the cube at
/// lc = 0.1086; the coarsest meshes have a little more).
pub const TETS_PER_LC3: f64 = 4.8;
/// The HArDCore3D family of polyhedral meshes, below `GRADVI_BENCH_HARDCORE3D`.
pub const VORONOI: &str = "Voro-small-0";
/// Its meshes, `voro-K` for K in this list (27 to 4 913 cells).
pub const VORONOI_LEVELS: [usize; 8] = [2, 4, 6, 8, 10, 12, 14, 16];
/// Where the HArDCore3D meshes are by default, relative to the repository root.
pub const HARDCORE3D_DIR: &str = "../shared/meshes/hardcore3d";

/// gmsh's size for about `n` tetrahedra in a domain of volume `volume` (see [`TETS_PER_LC3`]).
pub fn lc_for(volume: f64, n: usize) -> f64 {
    (TETS_PER_LC3 * volume / n as f64).cbrt()
}

/// One row of [`CSV`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Domain3Row {
    /// ball, hole, cube or voronoi.
    pub domain: String,
    /// The mesh file's stem.
    pub mesh: String,
    /// hmm or p1.
    pub scheme: String,
    /// The linear solver `auto` chose: direct, or iterative (conjugate gradients were run).
    pub linear: String,
    /// Rayon threads of the child.
    pub cores: usize,
    /// Cells (0 in a failed row).
    pub cells: usize,
    /// Unknowns (skeleton and interior).
    pub unknowns: usize,
    /// Linear solves of the fine active-set iteration.
    pub niter: usize,
    /// Linear solves of the nested warm start's coarse levels.
    pub coarse_niter: usize,
    /// Krylov iterations, all fine solves (0 with the direct solver).
    pub krylov: usize,
    /// gmsh's time to write the mesh (NaN for the Voronoi files).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub gmsh_s: f64,
    /// Reading and building the mesh.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub mesh_s: f64,
    /// The coarse solves of the warm start.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub coarse_s: f64,
    /// The solve, from the scheme to the certified solution (coarse solves included).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub solve_s: f64,
    /// The child's wall clock: mesh, solve, errors, freeing.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub total_s: f64,
    /// Peak resident memory of the child (`VmHWM`), MiB.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub peak_mib: f64,
    /// Largest |u − ū| (P1: at the vertices; HMM: cell values at the centroids).
    #[serde(deserialize_with = "super::peers::nullable")]
    pub err_max: f64,
    /// Mean |u − ū| over the same points.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub err_mean: f64,
    /// Largest scaled quantity of the certificate.
    #[serde(deserialize_with = "super::peers::nullable")]
    pub certificate: f64,
    /// Why the nested warm start did not run (empty when it ran: `coarse_niter` > 0).
    #[serde(default)]
    pub warm_skipped: String,
    /// `ok`, or `failed: ` and the child's error.
    pub status: String,
}

impl Domain3Row {
    /// Whether the case solved.
    pub fn ok(&self) -> bool {
        self.status == "ok"
    }
}

/// Max and mean of |v − ū(x)| over the pairs (x, v).
fn errors(points: &[[f64; 3]], values: &[f64], exact: &dyn Fn([f64; 3]) -> f64) -> (f64, f64) {
    let (max, sum) = points
        .iter()
        .zip(values)
        .map(|(&x, &v)| (v - exact(x)).abs())
        .fold((0.0f64, 0.0), |(m, s), e| (m.max(e), s + e));
    (max, sum / values.len().max(1) as f64)
}

/// The mesh of `file` (the Voronoi meshes mapped onto [`BOX`]).
fn read(domain: &str, file: &Path, budget: MemoryBudget) -> gradvi::Result<PolyMesh3> {
    let mut p = read_mesh3(file, budget)?;
    if domain == "voronoi" {
        for x in &mut p.vertices {
            *x = BOX.map_unit(*x);
        }
    }
    Ok(PolyMesh3::from_file_polyhedra(
        p,
        budget,
        gradvi::mesh3d::WarpedFaces::default(),
    )?)
}

/// Solves one case in this process (the body of a `--domain3d-child`); `total_s` and
/// `gmsh_s` are left to the driver.
fn run_gradvi(
    domain: &str,
    scheme: SchemeKind,
    file: &Path,
    root: &Path,
) -> gradvi::Result<Domain3Row> {
    let budget = MemoryBudget::available();
    let t0 = Instant::now();
    let mesh = read(domain, file, budget)?;
    let mesh_s = t0.elapsed().as_secs_f64();
    let problem = problem(root)?;
    let t1 = Instant::now();
    let disc = build_with3(scheme, &mesh, &SchemeOptions::default())?;
    let mut options = SolveOptions::default();
    options.system.budget = budget;
    let sol = solve_problem(disc.as_ref(), &problem, &options)?;
    let solve_s = t1.elapsed().as_secs_f64();
    let exact = problem
        .exact
        .as_ref()
        .ok_or_else(|| bad("ex9-3d.toml: no exact solution".into()))?;
    let (err_max, err_mean) = match scheme {
        SchemeKind::Hmm => {
            let centroids: Vec<[f64; 3]> = (0..mesh.n_cells()).map(|k| mesh.centroid(k)).collect();
            errors(&centroids, &disc.cell_values(sol.u()), &*exact.u)
        }
        _ => errors(mesh.vertices(), &disc.vertex_values(sol.u()), &*exact.u),
    };
    let krylov: usize = sol.result.log.iter().map(|l| l.timings.krylov).sum();
    let c = sol.result.certificate;
    Ok(Domain3Row {
        domain: domain.into(),
        mesh: stem(file),
        scheme: scheme.to_string(),
        linear: if krylov > 0 { "iterative" } else { "direct" }.into(),
        cores: rayon::current_num_threads(),
        cells: mesh.n_cells(),
        unknowns: sol.system.n_unknowns(),
        niter: sol.niter(),
        coarse_niter: sol.warm_start.as_ref().map_or(0, |w| w.coarse_solves),
        krylov,
        gmsh_s: f64::NAN,
        mesh_s,
        coarse_s: sol.timings.warm_start,
        solve_s,
        total_s: f64::NAN,
        peak_mib: peak_memory_mib(),
        err_max,
        err_mean,
        certificate: c.worst(),
        warm_skipped: sol
            .warm_start
            .as_ref()
            .and_then(|w| w.skipped.clone())
            .unwrap_or_default(),
        status: "ok".into(),
    })
}

/// The file name of `file` without its extension.
fn stem(file: &Path) -> String {
    file.file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
}

/// Arguments of a child process: `DOMAIN SCHEME FILE`.
pub fn child_main(args: &[String], root: &Path) -> gradvi::Result<()> {
    let [domain, scheme, file] = args else {
        return Err(bad("--domain3d-child DOMAIN SCHEME FILE".into()));
    };
    let row = run_gradvi(domain, scheme.parse()?, Path::new(file), root)?;
    println!(
        "{}",
        serde_json::to_string(&row).map_err(|e| bad(e.to_string()))?
    );
    Ok(())
}

/// One case: domain, scheme, mesh file, gmsh's time for it (NaN: not meshed by gmsh).
#[derive(Debug, Clone)]
pub struct Case3 {
    /// ball, hole, cube or voronoi.
    pub domain: &'static str,
    /// The scheme.
    pub scheme: SchemeKind,
    /// The mesh file (an RF stem for the Voronoi meshes).
    pub file: PathBuf,
    /// gmsh's time to write the mesh, seconds (NaN for the Voronoi files).
    pub gmsh_s: f64,
}

/// A row for a case whose child failed with `error` (its output, last line first).
fn failed_row(case: &Case3, cores: usize, error: String) -> Domain3Row {
    Domain3Row {
        domain: case.domain.into(),
        mesh: stem(&case.file),
        scheme: case.scheme.to_string(),
        linear: String::new(),
        cores,
        cells: 0,
        unknowns: 0,
        niter: 0,
        coarse_niter: 0,
        krylov: 0,
        gmsh_s: case.gmsh_s,
        mesh_s: f64::NAN,
        coarse_s: f64::NAN,
        solve_s: f64::NAN,
        total_s: f64::NAN,
        peak_mib: f64::NAN,
        err_max: f64::NAN,
        err_mean: f64::NAN,
        certificate: f64::NAN,
        warm_skipped: String::new(),
        status: format!("failed: {error}"),
    }
}

/// The row that records that the Voronoi family did not run because `dir` is missing.
fn not_run_row(dir: &Path) -> Domain3Row {
    let case = Case3 {
        domain: "voronoi",
        scheme: SchemeKind::Hmm,
        file: dir.to_path_buf(),
        gmsh_s: f64::NAN,
    };
    let mut row = failed_row(&case, 0, String::new());
    row.status = format!("not run: {} missing", dir.display());
    row
}

/// Runs `case` on `cores` threads in a child process of `exe`; a failure is a failed row with
/// the child's last line of stderr (which is passed through).
fn run_child(exe: &Path, case: &Case3, cores: usize) -> gradvi::Result<Domain3Row> {
    let mut cmd = Command::new(exe);
    cmd.args(["bench", "--domain3d-child", case.domain, case.scheme.name()])
        .arg(&case.file)
        .env("RAYON_NUM_THREADS", cores.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let t = Instant::now();
    let out = cmd.output().map_err(|e| io_err(exe, e))?;
    let secs = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    eprint!("{err}");
    if !out.status.success() {
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        return Ok(failed_row(
            case,
            cores,
            format!("{} ({})", last.trim(), out.status),
        ));
    }
    let what = format!("3D {} {} {}", case.domain, case.scheme, stem(&case.file));
    let text = String::from_utf8_lossy(&out.stdout);
    let mut row: Domain3Row = json_row(&text, &format!("{what}: bad child output"))?;
    row.total_s = secs;
    row.gmsh_s = case.gmsh_s;
    Ok(row)
}

/// Writes (or reuses) the gmsh mesh of `domain` for about `n` cells into `dir`; its path and
/// gmsh's time (kept in a `.seconds` file beside the mesh, so that a reused mesh keeps it).
fn gmsh_mesh(
    cfg: &Config,
    dir: &Path,
    domain: &str,
    volume: f64,
    n: usize,
) -> gradvi::Result<(PathBuf, f64)> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let geo = cfg.path(&format!("benches/domains3d/{domain}.geo"));
    let msh = dir.join(format!("{domain}3d_{n}.msh"));
    let seconds = msh.with_extension("seconds");
    if msh.exists() {
        let s = std::fs::read_to_string(&seconds)
            .ok()
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or(f64::NAN);
        return Ok((msh, s));
    }
    let lc = lc_for(volume, n);
    eprintln!(
        "[bench] gmsh: meshing {} (lc {lc:.5}, about {n} cells)",
        geo.display()
    );
    let t = Instant::now();
    let lc_arg = ["-setnumber".into(), "lc".into(), format!("{lc:.6e}")];
    super::run_gmsh(&geo, &msh, 3, &lc_arg)?;
    let s = t.elapsed().as_secs_f64();
    std::fs::write(&seconds, format!("{s}\n")).map_err(|e| io_err(&seconds, e))?;
    Ok((msh, s))
}

/// The Voronoi meshes' directory (`GRADVI_BENCH_HARDCORE3D` or [`HARDCORE3D_DIR`] below the
/// root), with [`VORONOI`] appended.
pub fn voronoi_dir(cfg: &Config) -> PathBuf {
    std::env::var_os("GRADVI_BENCH_HARDCORE3D")
        .map_or_else(|| cfg.path(HARDCORE3D_DIR), PathBuf::from)
        .join(VORONOI)
}

/// The cell cap of the gmsh meshes (`GRADVI_BENCH_DOMAINS3D_MAX_CELLS`).
fn max_cells() -> gradvi::Result<usize> {
    match std::env::var("GRADVI_BENCH_DOMAINS3D_MAX_CELLS") {
        Ok(v) => v
            .trim()
            .replace('_', "")
            .parse::<f64>()
            .map(|x| x as usize)
            .map_err(|_| {
                bad(format!(
                    "GRADVI_BENCH_DOMAINS3D_MAX_CELLS={v} is not a number"
                ))
            }),
        Err(_) => Ok(DEFAULT_MAX_CELLS),
    }
}

/// The cases of the selected `domains`, smallest meshes first (gmsh meshes written on the
/// way); the Voronoi family when its files are there.
fn cases(cfg: &Config, domains: &[String], max_cells: usize) -> gradvi::Result<Vec<Case3>> {
    let dir = cfg.path(super::MESH_DIR);
    let mut out = Vec::new();
    let wanted = |d: &str| domains.iter().any(|w| w == d);
    if wanted("voronoi") {
        let vdir = voronoi_dir(cfg);
        if vdir.is_dir() {
            for k in VORONOI_LEVELS {
                out.push(Case3 {
                    domain: "voronoi",
                    scheme: SchemeKind::Hmm,
                    file: vdir.join(format!("voro-{k}")),
                    gmsh_s: f64::NAN,
                });
            }
        }
    }
    for &n in TARGETS.iter().filter(|&&n| n <= max_cells) {
        for (domain, volume) in DOMAINS.into_iter().filter(|d| wanted(d.0)) {
            let (file, gmsh_s) = gmsh_mesh(cfg, &dir, domain, volume, n)?;
            for scheme in [SchemeKind::Hmm, SchemeKind::P1] {
                out.push(Case3 {
                    domain,
                    scheme,
                    file: file.clone(),
                    gmsh_s,
                });
            }
        }
    }
    Ok(out)
}

/// Runs the benchmark and writes [`CSV`] (after each row).
pub fn run(cfg: &Config, exe: &Path) -> gradvi::Result<()> {
    let domains: Vec<String> = std::env::var("GRADVI_BENCH_DOMAINS3D")
        .unwrap_or_else(|_| "ball,hole,cube,voronoi".into())
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let max_cells = max_cells()?;
    eprintln!(
        "[bench] 3D any domain ({}), gmsh meshes up to {max_cells} cells \
         (GRADVI_BENCH_DOMAINS3D_MAX_CELLS)",
        domains.join(", ")
    );
    let csv = cfg.path(CSV);
    // the rows of the domains not run this time are kept
    let mut rows: Vec<Domain3Row> = read_rows(cfg)?
        .into_iter()
        .filter(|r| !domains.contains(&r.domain))
        .collect();
    let vdir = voronoi_dir(cfg);
    if domains.iter().any(|d| d == "voronoi") && !vdir.is_dir() {
        eprintln!(
            "[bench] warning: no Voronoi rows: {} is missing",
            vdir.display()
        );
        rows.push(not_run_row(&vdir));
        write_csv(&csv, &rows)?;
    }
    for case in cases(cfg, &domains, max_cells)? {
        for cores in super::peers::core_counts() {
            eprintln!(
                "[bench] 3D {} {} {}, {cores} cores ...",
                case.domain,
                case.scheme,
                stem(&case.file)
            );
            let r = run_child(exe, &case, cores)?;
            eprintln!(
                "[bench]   {}: {} cells, {} unknowns, {}, NITER {} (+{}), {} Krylov, {:.2} s, {:.0} MiB, errors {:.3e} / {:.3e}",
                r.status,
                r.cells,
                r.unknowns,
                r.linear,
                r.niter,
                r.coarse_niter,
                r.krylov,
                r.total_s,
                r.peak_mib,
                r.err_max,
                r.err_mean
            );
            rows.push(r);
            write_csv(&csv, &rows)?;
        }
    }
    Ok(())
}

/// The rows of [`CSV`] (empty if it does not exist).
pub fn read_rows(cfg: &Config) -> gradvi::Result<Vec<Domain3Row>> {
    super::read_rows_of(cfg, CSV)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mesh_sizes_follow_the_calibration() {
        // the calibration point: the cube at lc = 0.1086 had 239 810 tetrahedra
        let lc = lc_for(64.0, 239_810);
        assert!((lc - 0.1086).abs() < 0.002, "{lc}");
        // eight times the cells, half the size
        let (a, b) = (lc_for(33.5, 10_000), lc_for(33.5, 80_000));
        assert!((a / b - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_voronoi_cell_mesh_is_mapped_onto_the_box_and_solved() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        // a mesh of the unit cube from the repository: six tetrahedra, read as "voronoi"
        let file = root.join("tests/data/mesh3d/cube6_41.msh");
        let mesh = read("voronoi", &file, MemoryBudget::available()).unwrap();
        assert_eq!(mesh.bounding_box(), BOX);
        let row = run_gradvi("voronoi", SchemeKind::Hmm, &file, &root).unwrap();
        assert_eq!((row.cells, row.status.as_str()), (6, "ok"));
        assert!(row.certificate <= 1e-8 && row.niter >= 1, "{row:?}");
        assert!(row.err_max.is_finite() && row.err_mean <= row.err_max);
    }

    #[test]
    fn errors_are_the_max_and_mean_distance_to_the_exact_values() {
        let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let (max, mean) = errors(&pts, &[1.0, 4.0], &|x| x[0] + 1.0);
        assert_eq!((max, mean), (2.0, 1.0));
    }
}
