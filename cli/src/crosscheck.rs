//! Cross-check of gradvi against FEniCSx/dolfinx P1 (`gradvi crosscheck`, `make crosscheck`).
//!
//! `reference/solve.py` solves Tests 1–3 with dolfinx P1 and PETSc SNES `vinewtonrsls` on the
//! committed gmsh meshes and writes `nodal_<case>.csv` (`x,y,u` in gmsh node order) and
//! `reference_summary.csv`. [`run`] then
//! 1. reads those files ([`read_reference`]);
//! 2. solves every reference case with gradvi P1 and HMM on the same mesh and compares
//!    ([`solve_cases`]): the gradvi-P1 and dolfinx-P1 nodal values (matched by vertex
//!    coordinates) and active sets, the Test 2 errors of the three solutions (one formula,
//!    [`gradvi::post::relative_errors`]), contact metrics, NITER and timings; one row per case
//!    in `results/crosscheck.csv` ([`CrosscheckRow`]);
//! 3. writes `CROSSCHECK.md` from that CSV only ([`write_report`]), with computed verdicts, and
//!    fails (after writing the report) when a comparison with a tolerance fails.
//!
//! In 3D ([`three_d`]), the 3D radial obstacle on gmsh tetrahedra: gradvi P1 against dolfinx P1,
//! nodal values and active sets, in `results/crosscheck3d.csv` and a section of the report.
//!
//! gradvi-P1 and dolfinx-P1 solve the same discrete problem (same mesh, DG0 A at centroids,
//! load = exact integral of the one-sided affine interpolant of f, nodal barriers, Dirichlet
//! vertices excluded), so their solutions must agree to round-off: [`SAME_PROBLEM_TOL`].

use crate::replication::experiments::with_solution;
use crate::replication::records::{
    PaperTable1, PaperTable2, PaperTable3, TimingRow, read_csv, write_csv,
};
use anyhow::{Context, Result, bail};
use gradvi::budget::MemoryBudget;
use gradvi::mesh::io::read_mesh;
use gradvi::mesh::{Point, PolyMesh};
use gradvi::post::contact::{contact_measure, free_boundary, hausdorff, switch_point};
use gradvi::post::relative_errors;
use gradvi::problem::{Problem, paper_test1, paper_test2, paper_test3};
use gradvi::scheme::SchemeKind;
use gradvi::solver::constraints::Constraints;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod report;
mod report3d;
pub mod three_d;
pub use report::write_report;
use three_d::{Crosscheck3Row, NodalRow3, SUMMARY_3D, solve_cases3};

/// Same discrete problem: max |u_gradvi − u_dolfinx| / max |u_dolfinx| must not exceed this.
pub const SAME_PROBLEM_TOL: f64 = 1e-8;
/// Test 2: the errors of gradvi-P1 and dolfinx-P1 must agree to this relative tolerance.
pub const ERROR_AGREEMENT_TOL: f64 = 1e-6;
/// Test 2: minimal fitted order of the error on u (HMM and P1, aligned triangle meshes).
pub const MIN_ORDER_U: f64 = 1.5;
/// A dolfinx constrained vertex is active when |u − bound| ≤ this · max(1, |bound|).
pub const ACTIVE_TOL: f64 = 1e-12;
/// Tests 1 and 2: switch points must agree to within this many h.
pub const SWITCH_TOL_H: f64 = 2.0;
/// Test 3: the Hausdorff distance between the HMM and P1 free boundaries, in units of h.
pub const HAUSDORFF_TOL_H: f64 = 3.0;
/// Coordinates of gradvi and dolfinx vertices are matched exactly, or to this distance.
pub const MATCH_TOL: f64 = 1e-12;

/// Arguments of `gradvi crosscheck`.
#[derive(clap::Args, Debug, Clone)]
pub struct CrosscheckArgs {
    /// Directory of the dolfinx outputs (reference_summary.csv, nodal_CASE.csv).
    #[arg(long, default_value = "replication/results/reference")]
    pub reference: PathBuf,
    /// The replication directory: results/crosscheck.csv and CROSSCHECK.md go there.
    #[arg(long, default_value = "replication")]
    pub out: PathBuf,
    /// Directory of the paper's tables as data (table1.csv, table2.csv, table3.csv), for the
    /// paper's NITER.
    #[arg(long, default_value = "replication/paper")]
    pub paper: PathBuf,
    /// Directory of the gmsh meshes.
    #[arg(long, default_value = "meshes")]
    pub meshes: PathBuf,
    /// Directory of the problem files (the 3D cases solve `<test>.toml` from there).
    #[arg(long, default_value = "problems")]
    pub problems: PathBuf,
    /// Coarsest mesh of each test only.
    #[arg(long)]
    pub coarse: bool,
    /// Only rewrite CROSSCHECK.md from the existing results/crosscheck.csv and
    /// results/crosscheck_timings.csv (no reference needed).
    #[arg(long)]
    pub report_only: bool,
}

/// One row of `reference_summary.csv` (written by `reference/solve.py`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReferenceRow {
    /// Case name, e.g. `test1_2`, `test2tri_3`, `test3_2_C10`.
    pub case: String,
    /// `test1`, `test2` or `test3`.
    pub test: String,
    /// Mesh file name, e.g. `test3_2.msh`.
    pub mesh: String,
    /// The constant C of Test 3 (empty for Tests 1 and 2).
    #[serde(rename = "C")]
    pub c: Option<f64>,
    /// Triangles.
    pub n_cells: usize,
    /// Vertices.
    pub n_vertices: usize,
    /// Dofs with a finite bound, Dirichlet dofs excluded.
    pub n_constrained: usize,
    /// SNES iterations.
    pub snes_iterations: usize,
    /// PETSc converged reason (> 0: converged).
    pub snes_reason: i64,
    /// Mesh read, spaces, assembly, bounds (s).
    pub time_setup_s: f64,
    /// `snes.solve` (s).
    pub time_solve_s: f64,
    /// Min over constrained dofs of the distance to the bound.
    pub min_bound_gap: f64,
    /// Max |F_i| over dofs strictly inside their bounds.
    pub residual_inf: f64,
}

/// One row of `nodal_<case>.csv`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct NodalRow {
    /// Abscissa of the vertex.
    pub x: f64,
    /// Ordinate of the vertex.
    pub y: f64,
    /// dolfinx P1 value at the vertex.
    pub u: f64,
}

/// One row of `results/crosscheck.csv`: one reference case solved by the three codes.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CrosscheckRow {
    /// Reference case name.
    pub case: String,
    /// `test1`, `test2` or `test3`.
    pub test: String,
    /// Mesh name (file stem).
    pub mesh: String,
    /// Test 3 constant C (empty otherwise).
    pub c: Option<f64>,
    /// Number of triangles.
    pub n_cells: usize,
    /// Number of vertices (gradvi mesh).
    pub n_vertices: usize,
    /// h = max triangle diameter.
    pub h: f64,
    /// Constrained P1 unknowns in gradvi.
    pub n_constrained_gradvi: usize,
    /// Constrained dofs in dolfinx.
    pub n_constrained_dolfinx: usize,
    /// max_v |u_gradvi-P1(v) − u_dolfinx(v)| / max_v |u_dolfinx(v)|.
    pub p1_max_rel_diff: f64,
    /// Whether the gradvi-P1 and dolfinx-P1 active sets are identical.
    pub active_identical: bool,
    /// Number of constrained vertices active in one and not in the other.
    pub active_n_diff: usize,
    /// Active constrained unknowns, HMM.
    pub n_active_hmm: usize,
    /// Active constrained unknowns, gradvi-P1.
    pub n_active_p1: usize,
    /// Active constrained vertices, dolfinx-P1 (tolerance [`ACTIVE_TOL`]).
    pub n_active_dolfinx: usize,
    /// Linear solves of the monotony algorithm, HMM.
    pub niter_hmm: usize,
    /// Linear solves of the monotony algorithm, gradvi-P1.
    pub niter_p1: usize,
    /// SNES (vinewtonrsls) iterations.
    pub snes_iterations: usize,
    /// SNES converged reason.
    pub snes_reason: i64,
    /// The paper's NITER for this mesh (and C), if it has one.
    pub paper_niter: Option<usize>,
    /// Test 2: relative L² error of u at centroids, HMM.
    pub err_u_hmm: Option<f64>,
    /// Test 2: relative L² error of the gradient, HMM.
    pub err_grad_hmm: Option<f64>,
    /// Test 2: relative L² error of u, gradvi-P1.
    pub err_u_p1: Option<f64>,
    /// Test 2: relative L² error of the gradient, gradvi-P1.
    pub err_grad_p1: Option<f64>,
    /// Test 2: relative L² error of u, dolfinx-P1.
    pub err_u_dolfinx: Option<f64>,
    /// Test 2: relative L² error of the gradient, dolfinx-P1.
    pub err_grad_dolfinx: Option<f64>,
    /// Tests 1/2: switch coordinate on Γ3 (x for Test 1, y for Test 2), HMM.
    pub switch_hmm: Option<f64>,
    /// Tests 1/2: switch coordinate, gradvi-P1.
    pub switch_p1: Option<f64>,
    /// Tests 1/2: switch coordinate, dolfinx-P1.
    pub switch_dolfinx: Option<f64>,
    /// Tests 1/2: number of active/inactive switches along Γ3, HMM.
    pub switch_count_hmm: Option<usize>,
    /// Tests 1/2: number of switches along Γ3, gradvi-P1.
    pub switch_count_p1: Option<usize>,
    /// Tests 1/2: number of switches along Γ3, dolfinx-P1.
    pub switch_count_dolfinx: Option<usize>,
    /// Test 2: max |u| over the Γ3 unknowns in the exact contact zone (y > 1/2) divided by
    /// max |u| over all Γ3 unknowns, HMM (0 when the discrete solution touches the barrier
    /// there; small when it is close to it).
    pub trace_zone_hmm: Option<f64>,
    /// Test 2: the same for gradvi-P1.
    pub trace_zone_p1: Option<f64>,
    /// Test 2: the same for dolfinx-P1.
    pub trace_zone_dolfinx: Option<f64>,
    /// Test 3: contact area, HMM (Σ |K| over active cells).
    pub contact_hmm: Option<f64>,
    /// Test 3: contact area, gradvi-P1 (lumped vertex measures).
    pub contact_p1: Option<f64>,
    /// Test 3: contact area, dolfinx-P1 (lumped vertex measures).
    pub contact_dolfinx: Option<f64>,
    /// Test 3: Hausdorff distance between the HMM and gradvi-P1 free boundaries.
    pub hausdorff_hmm_p1: Option<f64>,
    /// Test 3: Hausdorff distance between the gradvi-P1 and dolfinx-P1 free boundaries.
    pub hausdorff_p1_dolfinx: Option<f64>,
    /// gradvi HMM solve time (assembly + all iterations), s.
    pub time_hmm_s: f64,
    /// gradvi P1 solve time (assembly + all iterations), s.
    pub time_p1_s: f64,
    /// dolfinx setup (mesh read, JIT, assembly, bounds), s.
    pub time_dolfinx_setup_s: f64,
    /// dolfinx SNES solve, s.
    pub time_dolfinx_solve_s: f64,
}

/// A reference case with its nodal values (rows [`NodalRow`] in 2D, [`NodalRow3`] in 3D).
pub struct ReferenceCase<N = NodalRow> {
    /// The summary row.
    pub summary: ReferenceRow,
    /// The nodal values, in gmsh node order.
    pub nodal: Vec<N>,
}

fn need(path: &Path) -> Result<()> {
    if !path.is_file() {
        bail!(
            "{} not found: run `make crosscheck` or reference/solve.py first \
             (/usr/bin/python3 reference/solve.py --all --outdir <reference dir>)",
            path.display()
        );
    }
    Ok(())
}

/// The mesh index k of `test1_k.msh`, `test2tri_k.msh`, `test3_k.msh`.
fn mesh_index(mesh: &str) -> Option<usize> {
    mesh.trim_end_matches(".msh")
        .rsplit('_')
        .next()?
        .parse()
        .ok()
}

/// Reads `reference_summary.csv` and the nodal files of its cases, ordered by test, mesh size
/// (coarse first) and |C|. With `coarse`, keeps the coarsest mesh of each test.
pub fn read_reference(dir: &Path, coarse: bool) -> Result<Vec<ReferenceCase>> {
    read_cases(dir, "reference_summary.csv", coarse)
}

/// As [`read_reference`], for the summary file `summary` and nodal rows of type `N`.
fn read_cases<N: DeserializeOwned>(
    dir: &Path,
    summary: &str,
    coarse: bool,
) -> Result<Vec<ReferenceCase<N>>> {
    let summary_path = dir.join(summary);
    need(&summary_path)?;
    let mut rows: Vec<ReferenceRow> =
        read_csv(&summary_path).with_context(|| format!("reading {}", summary_path.display()))?;
    if rows.is_empty() {
        bail!(
            "{} has no case: run `make crosscheck` or reference/solve.py first",
            summary_path.display()
        );
    }
    rows.sort_by(|a, b| {
        (a.test.as_str(), a.n_cells)
            .cmp(&(b.test.as_str(), b.n_cells))
            .then(b.c.unwrap_or(0.0).total_cmp(&a.c.unwrap_or(0.0)))
    });
    if coarse {
        let mut min_cells: BTreeMap<String, usize> = BTreeMap::new();
        for r in &rows {
            let e = min_cells.entry(r.test.clone()).or_insert(r.n_cells);
            *e = (*e).min(r.n_cells);
        }
        rows.retain(|r| min_cells[&r.test] == r.n_cells);
    }
    rows.into_iter()
        .map(|summary| {
            let p = dir.join(format!("nodal_{}.csv", summary.case));
            need(&p)?;
            let nodal: Vec<N> = read_csv(&p).with_context(|| format!("reading {}", p.display()))?;
            Ok(ReferenceCase { summary, nodal })
        })
        .collect()
}

/// For each gradvi vertex, the row of the dolfinx nodal file at the same coordinates (exactly,
/// or to [`MATCH_TOL`]). An error names the first vertex without a match.
pub fn match_vertices(mesh: &PolyMesh, nodal: &[NodalRow]) -> Result<Vec<usize>> {
    let points: Vec<Point> = (0..mesh.n_vertices()).map(|v| mesh.vertex(v)).collect();
    let rows: Vec<Point> = nodal.iter().map(|r| [r.x, r.y]).collect();
    match_points(&points, &rows)
}

/// For each of the gradvi vertices `points`, the index of the point of `nodal` at the same
/// coordinates: exactly (±0 alike), or else to [`MATCH_TOL`] in every coordinate (a search in
/// the rows sorted by their first coordinate). An error names the first vertex without a match.
pub(crate) fn match_points<const D: usize>(
    points: &[[f64; D]],
    nodal: &[[f64; D]],
) -> Result<Vec<usize>> {
    let key = |p: &[f64; D]| p.map(|c| (c + 0.0).to_bits());
    let exact: HashMap<[u64; D], usize> =
        nodal.iter().enumerate().map(|(i, r)| (key(r), i)).collect();
    let mut by_x: Vec<(f64, usize)> = nodal.iter().enumerate().map(|(i, r)| (r[0], i)).collect();
    by_x.sort_by(|a, b| a.0.total_cmp(&b.0));
    let close = |i: usize, p: &[f64; D]| (0..D).all(|c| (nodal[i][c] - p[c]).abs() <= MATCH_TOL);
    (points.iter().enumerate())
        .map(|(v, p)| {
            if let Some(&i) = exact.get(&key(p)) {
                return Ok(i);
            }
            let start = by_x.partition_point(|e| e.0 < p[0] - MATCH_TOL);
            by_x[start..]
                .iter()
                .take_while(|e| e.0 <= p[0] + MATCH_TOL)
                .map(|e| e.1)
                .find(|&i| close(i, p))
                .with_context(|| {
                    let at: Vec<String> = p.iter().map(f64::to_string).collect();
                    format!(
                        "gradvi vertex {v} at ({}) has no dolfinx vertex within {MATCH_TOL:e}",
                        at.join(", ")
                    )
                })
        })
        .collect()
}

fn problem_of(r: &ReferenceRow) -> Result<Problem> {
    Ok(match r.test.as_str() {
        "test1" => paper_test1(),
        "test2" => paper_test2(),
        "test3" => paper_test3(r.c.with_context(|| format!("case {}: test3 without C", r.case))?),
        t => bail!("case {}: unknown test '{t}'", r.case),
    })
}

/// Test 2: max |u| over the constrained (Γ3) unknowns with y > 1/2, the exact contact zone,
/// divided by max |u| over all of them.
fn trace_zone(
    scheme: &dyn gradvi::scheme::GradientDiscretisation,
    cons: &Constraints,
    u: &[f64],
) -> f64 {
    let (mut zone, mut all) = (0.0f64, 0.0f64);
    for d in &cons.dofs {
        let v = u[d.dof].abs();
        all = all.max(v);
        if scheme.dof_point(d.dof)[1] > 0.5 {
            zone = zone.max(v);
        }
    }
    zone / all.max(f64::MIN_POSITIVE)
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// What the cross-check keeps of the HMM solve.
struct HmmOutcome {
    niter: usize,
    time: f64,
    n_active: usize,
    err: Option<(f64, f64)>,
    switch: Option<f64>,
    switch_count: Option<usize>,
    trace_zone: Option<f64>,
    contact: Option<f64>,
    free: Vec<Point>,
}

/// The paper's NITER tables, for [`paper_niter`].
struct PaperTables {
    t1: Vec<PaperTable1>,
    t2: Vec<PaperTable2>,
    t3: Vec<PaperTable3>,
}

fn read_paper(dir: &Path) -> Result<PaperTables> {
    let rd = |f: &str| -> Result<PathBuf> {
        let p = dir.join(f);
        if !p.is_file() {
            bail!("{} not found (the paper's tables, as data)", p.display());
        }
        Ok(p)
    };
    Ok(PaperTables {
        t1: read_csv(&rd("table1.csv")?)?,
        t2: read_csv(&rd("table2.csv")?)?,
        t3: read_csv(&rd("table3.csv")?)?,
    })
}

/// The paper's NITER for a case: Test 1, the k-th row of Table 1 from coarse to fine; Test 2,
/// the hexagonal mesh of Table 2 with the same number of edges on Γ3 (the paper has no triangle
/// meshes for Test 2); Test 3, the k-th mesh of Table 3 by increasing cell count, same C.
fn paper_niter(p: &PaperTables, r: &ReferenceRow, n_gamma3: usize) -> Option<usize> {
    let k = mesh_index(&r.mesh)?.checked_sub(1)?;
    match r.test.as_str() {
        "test1" => {
            let mut t: Vec<&PaperTable1> = p.t1.iter().collect();
            t.sort_by(|a, b| b.h.total_cmp(&a.h));
            t.get(k).map(|x| x.niter)
        }
        "test2" => {
            p.t2.iter()
                .find(|x| x.family == "hexagonal" && x.n_gamma3 == n_gamma3)
                .map(|x| x.niter)
        }
        "test3" => {
            let mut cells: Vec<usize> = p.t3.iter().map(|x| x.n_cells).collect();
            cells.sort_unstable();
            cells.dedup();
            let nc = *cells.get(k)?;
            let c = r.c?;
            p.t3.iter()
                .find(|x| x.n_cells == nc && x.c == c)
                .map(|x| x.niter)
        }
        _ => None,
    }
}

/// Solves every reference case with gradvi HMM and P1 on the same mesh and compares.
/// `progress` receives one line per case.
pub fn solve_cases(
    args: &CrosscheckArgs,
    cases: &[ReferenceCase],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<CrosscheckRow>> {
    let paper = read_paper(&args.paper)?;
    let mut meshes: HashMap<String, PolyMesh> = HashMap::new();
    let mut rows = Vec::new();
    for case in cases {
        let r = &case.summary;
        if !meshes.contains_key(&r.mesh) {
            let path = args.meshes.join(&r.mesh);
            let m = read_mesh(&path, MemoryBudget::available())
                .with_context(|| format!("reading {}", path.display()))?;
            meshes.insert(r.mesh.clone(), m);
        }
        let mesh = &meshes[&r.mesh];
        if mesh.n_cells() != r.n_cells {
            bail!(
                "case {}: {} has {} triangles in gradvi but {} in dolfinx",
                r.case,
                r.mesh,
                mesh.n_cells(),
                r.n_cells
            );
        }
        let map = match_vertices(mesh, &case.nodal)
            .with_context(|| format!("case {}: matching the vertices", r.case))?;
        let ud: Vec<f64> = map.iter().map(|&i| case.nodal[i].u).collect();
        let problem = problem_of(r)?;
        let compared = Compared::of(&r.test);
        let hmm = hmm_outcome(mesh, &problem, compared)
            .with_context(|| format!("case {}: gradvi HMM", r.case))?;
        let paper_n = paper_niter(&paper, r, mesh.boundary_edges_on(0, 0.0));
        let row = p1_row(mesh, &problem, r, &ud, &hmm, paper_n, compared)
            .with_context(|| format!("case {}: gradvi P1", r.case))?;
        progress(&format!(
            "{:<14} {:>6} cells  P1 diff {:.1e}  active sets {}  NITER HMM {:>2} P1 {:>2} SNES {:>2}",
            row.case,
            row.n_cells,
            row.p1_max_rel_diff,
            if row.active_identical {
                "identical"
            } else {
                "DIFFER"
            },
            row.niter_hmm,
            row.niter_p1,
            row.snes_iterations
        ));
        rows.push(row);
    }
    Ok(rows)
}

/// What a test compares besides the solutions: the switch point along an axis (Tests 1 and 2),
/// the trace zone (Test 2), the contact measure and the free boundary (Test 3).
#[derive(Debug, Clone, Copy)]
struct Compared {
    axis: Option<usize>,
    trace_zone: bool,
    contact: bool,
}

impl Compared {
    fn of(test: &str) -> Self {
        let is2 = test == "test2";
        let is3 = test == "test3";
        let axis = if test == "test1" {
            Some(0)
        } else if is2 {
            Some(1)
        } else {
            None
        };
        Compared {
            axis,
            trace_zone: is2,
            contact: is3,
        }
    }
}

/// Solves `problem` with gradvi HMM on `mesh` and keeps what the cross-check compares.
fn hmm_outcome(mesh: &PolyMesh, problem: &Problem, compared: Compared) -> Result<HmmOutcome> {
    let (axis, is2, is3) = (compared.axis, compared.trace_zone, compared.contact);
    let exact = problem.exact.as_ref();
    with_solution(mesh, SchemeKind::Hmm, problem, |sol| {
        let cons = sol.constraints.as_ref().expect("every test has a barrier");
        let active = &sol.result.active;
        let scheme = sol.system.scheme();
        Ok(HmmOutcome {
            niter: sol.niter(),
            time: sol.timings.total,
            n_active: active.iter().filter(|&&a| a).count(),
            err: exact.map(|ex| {
                let e = relative_errors(scheme, sol.u(), &ex.u, &ex.grad);
                (e.l2_u, e.l2_grad)
            }),
            switch: axis.and_then(|a| switch_point(scheme, cons, active, a).map(|s| s.at)),
            switch_count: axis
                .map(|a| switch_point(scheme, cons, active, a).map_or(0, |s| s.count)),
            trace_zone: is2.then(|| trace_zone(scheme, cons, sol.u())),
            contact: is3.then(|| contact_measure(cons, active)),
            free: if is3 {
                free_boundary(
                    scheme,
                    cons,
                    active,
                    &gradvi::post::contact::neighbours(scheme, cons),
                )
            } else {
                Vec::new()
            },
        })
    })
    .map_err(anyhow::Error::from)
}

/// Solves `problem` with gradvi P1 on `mesh` and compares it with the dolfinx solution `ud`
/// (on gradvi's vertices) of the reference case `r`, beside the HMM outcome `hmm` and the
/// paper's NITER `paper_n`.
fn p1_row(
    mesh: &PolyMesh,
    problem: &Problem,
    r: &ReferenceRow,
    ud: &[f64],
    hmm: &HmmOutcome,
    paper_n: Option<usize>,
    compared: Compared,
) -> Result<CrosscheckRow> {
    let (axis, is2, is3) = (compared.axis, compared.trace_zone, compared.contact);
    let exact = problem.exact.as_ref();
    with_solution(mesh, SchemeKind::P1, problem, |sol| {
        let cons = sol.constraints.as_ref().expect("every test has a barrier");
        let active = &sol.result.active;
        let scheme = sol.system.scheme();
        let u = sol.u();
        // dolfinx active set on gradvi's constrained vertices
        let dact: Vec<bool> = cons
            .dofs
            .iter()
            .zip(&cons.barrier)
            .map(|(d, &g)| (ud[d.dof] - g).abs() <= ACTIVE_TOL * g.abs().max(1.0))
            .collect();
        let n_diff = active.iter().zip(&dact).filter(|(a, b)| a != b).count();
        let umax = ud.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let dmax = u[..mesh.n_vertices()]
            .iter()
            .zip(ud)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let errs = |v: &[f64]| {
            exact.map(|ex| {
                let e = relative_errors(scheme, v, &ex.u, &ex.grad);
                (e.l2_u, e.l2_grad)
            })
        };
        let (eg, ed) = (errs(u), errs(ud));
        let sw = |act: &[bool]| axis.and_then(|a| switch_point(scheme, cons, act, a).map(|s| s.at));
        let swc =
            |act: &[bool]| axis.map(|a| switch_point(scheme, cons, act, a).map_or(0, |s| s.count));
        let (fb_p1, fb_d) = if is3 {
            let nb = gradvi::post::contact::neighbours(scheme, cons);
            (
                free_boundary(scheme, cons, active, &nb),
                free_boundary(scheme, cons, &dact, &nb),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        Ok(CrosscheckRow {
            case: r.case.clone(),
            test: r.test.clone(),
            mesh: r.mesh.trim_end_matches(".msh").to_string(),
            c: r.c,
            n_cells: mesh.n_cells(),
            n_vertices: mesh.n_vertices(),
            h: mesh.h(),
            n_constrained_gradvi: cons.dofs.len(),
            n_constrained_dolfinx: r.n_constrained,
            p1_max_rel_diff: dmax / umax.max(f64::MIN_POSITIVE),
            active_identical: n_diff == 0 && cons.dofs.len() == r.n_constrained,
            active_n_diff: n_diff,
            n_active_hmm: hmm.n_active,
            n_active_p1: active.iter().filter(|&&a| a).count(),
            n_active_dolfinx: dact.iter().filter(|&&a| a).count(),
            niter_hmm: hmm.niter,
            niter_p1: sol.niter(),
            snes_iterations: r.snes_iterations,
            snes_reason: r.snes_reason,
            paper_niter: paper_n,
            err_u_hmm: hmm.err.map(|e| e.0),
            err_grad_hmm: hmm.err.map(|e| e.1),
            err_u_p1: eg.map(|e| e.0),
            err_grad_p1: eg.map(|e| e.1),
            err_u_dolfinx: ed.map(|e| e.0),
            err_grad_dolfinx: ed.map(|e| e.1),
            switch_hmm: hmm.switch,
            switch_p1: sw(active),
            switch_dolfinx: sw(&dact),
            switch_count_hmm: hmm.switch_count,
            switch_count_p1: swc(active),
            switch_count_dolfinx: swc(&dact),
            trace_zone_hmm: hmm.trace_zone,
            trace_zone_p1: is2.then(|| trace_zone(scheme, cons, u)),
            trace_zone_dolfinx: is2.then(|| trace_zone(scheme, cons, ud)),
            contact_hmm: hmm.contact,
            contact_p1: is3.then(|| contact_measure(cons, active)),
            contact_dolfinx: is3.then(|| contact_measure(cons, &dact)),
            hausdorff_hmm_p1: is3.then(|| finite(hausdorff(&hmm.free, &fb_p1))).flatten(),
            hausdorff_p1_dolfinx: is3.then(|| finite(hausdorff(&fb_p1, &fb_d))).flatten(),
            time_hmm_s: hmm.time,
            time_p1_s: sol.timings.total,
            time_dolfinx_setup_s: r.time_setup_s,
            time_dolfinx_solve_s: r.time_solve_s,
        })
    })
    .map_err(anyhow::Error::from)
}

/// Runs the cross-check: reads the reference, solves, writes `results/crosscheck.csv`,
/// `results/crosscheck_timings.csv` and `CROSSCHECK.md`; an error listing the failed
/// comparisons if a comparison with a tolerance fails (after writing the report).
pub fn run(args: &CrosscheckArgs) -> Result<()> {
    if args.report_only {
        return check(write_report(&args.out, args.coarse)?, args);
    }
    let t0 = Instant::now();
    eprintln!(
        "cross-check: reading the dolfinx reference from {}{}",
        args.reference.display(),
        if args.coarse {
            " (coarsest meshes)"
        } else {
            ""
        }
    );
    let cases = read_reference(&args.reference, args.coarse)?;
    let t_read = t0.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut progress = |s: &str| eprintln!("  {s}");
    let rows = solve_cases(args, &cases, &mut progress)?;
    let t_solve = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let cases3: Vec<ReferenceCase<NodalRow3>> =
        read_cases(&args.reference, SUMMARY_3D, args.coarse)?;
    let rows3: Vec<Crosscheck3Row> =
        solve_cases3(&args.meshes, &args.problems, &cases3, &mut progress)?;
    let t_solve3 = t.elapsed().as_secs_f64();
    let res = args.out.join("results");
    crate::replication::create_dir(&res)?;
    write_csv(&res.join("crosscheck.csv"), &rows)?;
    write_csv(&res.join("crosscheck3d.csv"), &rows3)?;
    let timings = vec![
        TimingRow {
            stage: "reading the reference".into(),
            seconds: t_read,
        },
        TimingRow {
            stage: "gradvi solves and comparisons".into(),
            seconds: t_solve,
        },
        TimingRow {
            stage: "3D: reading, gradvi solves and comparisons".into(),
            seconds: t_solve3,
        },
        TimingRow {
            stage: "total".into(),
            seconds: t0.elapsed().as_secs_f64(),
        },
    ];
    write_csv(&res.join("crosscheck_timings.csv"), &timings)?;
    let failed = write_report(&args.out, args.coarse)?;
    eprintln!(
        "wrote {} ({:.1} s)",
        args.out.join("CROSSCHECK.md").display(),
        t0.elapsed().as_secs_f64()
    );
    check(failed, args)
}

/// An error listing the failed comparisons, if any.
fn check(failed: Vec<String>, args: &CrosscheckArgs) -> Result<()> {
    if !failed.is_empty() {
        bail!(
            "cross-check failed ({} comparison(s)), see {}:\n  - {}",
            failed.len(),
            args.out.join("CROSSCHECK.md").display(),
            failed.join("\n  - ")
        );
    }
    Ok(())
}
