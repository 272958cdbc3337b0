//! The 3D cross-check: gradvi P1 on tetrahedra against dolfinx P1 on the same gmsh mesh.
//!
//! `reference/solve.py` solves the 3D radial obstacle (`problems/ex9-3d.toml`: Ω = (−2,2)³,
//! −Δu = 0, u ≥ ψ with ψ = √(1 − r²) for r ≤ 1 and −1 beyond, u = 1/(2r) on ∂Ω) on
//! `meshes/3d/ex9_3d_k.msh`, and the 3D Signorini problem (`problems/signorini-3d.toml`) on
//! `meshes/3d/signorini3d_k.msh`, and writes `reference_summary_3d.csv` and `nodal_<case>.csv`
//! (`x,y,z,u`). [`solve_cases3`] solves each case with gradvi P1 from the problem file on the
//! same mesh and compares the nodal values (vertices matched by coordinates) and the active
//! sets; one row per case in `results/crosscheck3d.csv` ([`Crosscheck3Row`]).
//!
//! Both codes solve the same discrete problem: P1 on the same tetrahedra, A constant per cell
//! (per tag for Signorini), the load = exact integral of the P1 interpolant of f (the cell's
//! piece), the flux by the centroid rule on boundary triangles (|σ| g(x_σ)/3 per vertex),
//! Dirichlet values at the vertices (dolfinx: interpolated boundary data, identity rows), nodal
//! barriers on the other constrained vertices. So the solutions and active sets agree to
//! round-off ([`super::SAME_PROBLEM_TOL`], [`super::ACTIVE_TOL`]).

use super::{ACTIVE_TOL, ReferenceCase, ReferenceRow, match_points};
use anyhow::{Context, Result, bail};
use gradvi::budget::MemoryBudget;
use gradvi::mesh3d::io::read_msh3;
use gradvi::mesh3d::{Point3, PolyMesh3};
use gradvi::post::relative_errors;
use gradvi::scheme::{SchemeKind, SchemeOptions, build_with3};
use gradvi::solver::{SolveOptions, solve_problem};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The summary file of the 3D reference cases (same columns as `reference_summary.csv`).
pub const SUMMARY_3D: &str = "reference_summary_3d.csv";

/// One row of a 3D `nodal_<case>.csv`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct NodalRow3 {
    /// First coordinate of the vertex.
    pub x: f64,
    /// Second coordinate.
    pub y: f64,
    /// Third coordinate.
    pub z: f64,
    /// dolfinx P1 value at the vertex.
    pub u: f64,
}

/// One row of `results/crosscheck3d.csv`: one 3D reference case, gradvi-P1 against dolfinx-P1.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Crosscheck3Row {
    /// Reference case name, e.g. `ex9_3d_1`.
    pub case: String,
    /// The problem (the name of its file in `problems/`), e.g. `ex9-3d`.
    pub test: String,
    /// Mesh name (file stem).
    pub mesh: String,
    /// Tetrahedra.
    pub n_cells: usize,
    /// Vertices (gradvi mesh).
    pub n_vertices: usize,
    /// h = max cell diameter.
    pub h: f64,
    /// Constrained P1 unknowns in gradvi.
    pub n_constrained_gradvi: usize,
    /// Constrained dofs in dolfinx.
    pub n_constrained_dolfinx: usize,
    /// max_v |u_gradvi-P1(v) − u_dolfinx(v)| / max_v |u_dolfinx(v)|.
    pub p1_max_rel_diff: f64,
    /// Whether the gradvi-P1 and dolfinx-P1 active sets are identical.
    pub active_identical: bool,
    /// Constrained vertices active in one and not in the other.
    pub active_n_diff: usize,
    /// Active constrained vertices, gradvi-P1.
    pub n_active_p1: usize,
    /// Active constrained vertices, dolfinx-P1 (tolerance [`ACTIVE_TOL`]).
    pub n_active_dolfinx: usize,
    /// Contact measure (volume for an obstacle, area for Signorini), gradvi-P1: Σ of the lumped
    /// vertex measures over active vertices.
    pub contact_p1: f64,
    /// Contact measure, dolfinx-P1, with the same measures.
    pub contact_dolfinx: f64,
    /// Relative L² error of u against the exact solution, gradvi-P1.
    pub err_u_p1: Option<f64>,
    /// Relative L² error of u, dolfinx-P1 (same formula, on its re-ordered nodal vector).
    pub err_u_dolfinx: Option<f64>,
    /// Linear solves of gradvi's active-set algorithm.
    pub niter_p1: usize,
    /// SNES (vinewtonrsls) iterations.
    pub snes_iterations: usize,
    /// SNES converged reason.
    pub snes_reason: i64,
    /// gradvi P1 solve time (assembly + all iterations), s.
    pub time_p1_s: f64,
    /// dolfinx setup (mesh read, JIT, assembly, bounds), s.
    pub time_dolfinx_setup_s: f64,
    /// dolfinx SNES solve, s.
    pub time_dolfinx_solve_s: f64,
}

/// For each gradvi vertex, the row of the dolfinx nodal file at the same coordinates (exactly,
/// or to [`super::MATCH_TOL`] in each coordinate). An error names the first vertex without a
/// match.
pub fn match_vertices3(vertices: &[Point3], nodal: &[NodalRow3]) -> Result<Vec<usize>> {
    let rows: Vec<Point3> = nodal.iter().map(|r| [r.x, r.y, r.z]).collect();
    match_points(vertices, &rows)
}

/// Solves every 3D reference case with gradvi P1 (problem file `problems/<test>.toml` on the
/// case's mesh, found in the `3d/` folder of `meshes`) and compares; `progress` receives one line per case.
pub fn solve_cases3(
    meshes: &Path,
    problems: &Path,
    cases: &[ReferenceCase<NodalRow3>],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Crosscheck3Row>> {
    let budget = MemoryBudget::available();
    let mut rows = Vec::new();
    for case in cases {
        let r = &case.summary;
        let path = meshes.join("3d").join(&r.mesh);
        let mesh = read_msh3(&path, budget)
            .and_then(|p| PolyMesh3::from_polyhedra(p, budget).map_err(Into::into))
            .with_context(|| format!("reading {}", path.display()))?;
        if mesh.n_cells() != r.n_cells {
            bail!(
                "case {}: {} has {} tetrahedra in gradvi but {} in dolfinx",
                r.case,
                r.mesh,
                mesh.n_cells(),
                r.n_cells
            );
        }
        let map = match_vertices3(mesh.vertices(), &case.nodal)
            .with_context(|| format!("case {}: matching the vertices", r.case))?;
        let ud: Vec<f64> = map.iter().map(|&i| case.nodal[i].u).collect();
        let row = p1_row3(&mesh, problems, r, &ud)
            .with_context(|| format!("case {}: gradvi P1 in 3D", r.case))?;
        progress(&format!(
            "{:<14} {:>6} cells  P1 diff {:.1e}  active sets {}  NITER P1 {:>2} SNES {:>2}",
            row.case,
            row.n_cells,
            row.p1_max_rel_diff,
            if row.active_identical {
                "identical"
            } else {
                "DIFFER"
            },
            row.niter_p1,
            row.snes_iterations
        ));
        rows.push(row);
    }
    Ok(rows)
}

/// Solves the problem of the reference case `r` with gradvi P1 on `mesh` and compares it with
/// the dolfinx solution `ud` (on gradvi's vertices).
fn p1_row3(
    mesh: &PolyMesh3,
    problems: &Path,
    r: &ReferenceRow,
    ud: &[f64],
) -> Result<Crosscheck3Row> {
    let pf_path = problems.join(format!("{}.toml", r.test));
    let pf = gradvi::problem::file::load(&pf_path, &[])?;
    pf.check_against_mesh3(mesh)?;
    let problem = pf.problem_in::<3>()?;
    let scheme = build_with3(SchemeKind::P1, mesh, &SchemeOptions::default())?;
    let sol = solve_problem(scheme.as_ref(), &problem, &SolveOptions::default())?;
    let cons = (sol.constraints.as_ref())
        .with_context(|| format!("{} has no barrier", pf_path.display()))?;
    let active = &sol.result.active;
    let u = sol.u();
    let dact: Vec<bool> = (cons.dofs.iter().zip(&cons.barrier))
        .map(|(d, &g)| (ud[d.dof] - g).abs() <= ACTIVE_TOL * g.abs().max(1.0))
        .collect();
    let n_diff = active.iter().zip(&dact).filter(|(a, b)| a != b).count();
    let volume = |act: &[bool]| -> f64 {
        (cons.dofs.iter().zip(act))
            .filter(|(_, a)| **a)
            .map(|(d, _)| d.measure)
            .sum()
    };
    let umax = ud.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let dmax =
        (u[..mesh.n_vertices()].iter().zip(ud)).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let err = |v: &[f64]| {
        (problem.exact.as_ref()).map(|ex| relative_errors(scheme.as_ref(), v, &ex.u, &ex.grad).l2_u)
    };
    Ok(Crosscheck3Row {
        case: r.case.clone(),
        test: r.test.clone(),
        mesh: r.mesh.trim_end_matches(".msh").to_string(),
        n_cells: mesh.n_cells(),
        n_vertices: mesh.n_vertices(),
        h: mesh.h(),
        n_constrained_gradvi: cons.dofs.len(),
        n_constrained_dolfinx: r.n_constrained,
        p1_max_rel_diff: dmax / umax.max(f64::MIN_POSITIVE),
        active_identical: n_diff == 0 && cons.dofs.len() == r.n_constrained,
        active_n_diff: n_diff,
        n_active_p1: active.iter().filter(|&&a| a).count(),
        n_active_dolfinx: dact.iter().filter(|&&a| a).count(),
        contact_p1: volume(active),
        contact_dolfinx: volume(&dact),
        err_u_p1: err(u),
        err_u_dolfinx: err(ud),
        niter_p1: sol.niter(),
        snes_iterations: r.snes_iterations,
        snes_reason: r.snes_reason,
        time_p1_s: sol.timings.total,
        time_dolfinx_setup_s: r.time_setup_s,
        time_dolfinx_solve_s: r.time_solve_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(p: [f64; 3]) -> NodalRow3 {
        NodalRow3 {
            x: p[0],
            y: p[1],
            z: p[2],
            u: 0.0,
        }
    }

    #[test]
    fn vertices_match_by_coordinates_exactly_or_within_the_tolerance() {
        let vertices = [[0.0, 0.0, 0.0], [1.0, -2.0, 0.5], [-2.0, 2.0, 2.0]];
        // permuted, one coordinate off by round-off, one -0.0
        let nodal = [
            row([-2.0000000000000004, 2.0, 2.0]),
            row([-0.0, 0.0, 0.0]),
            row([1.0, -2.0, 0.5]),
        ];
        assert_eq!(match_vertices3(&vertices, &nodal).unwrap(), vec![1, 2, 0]);
    }

    #[test]
    fn a_vertex_without_a_match_is_named() {
        let vertices = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
        let nodal = [row([0.0, 0.0, 0.0]), row([1.0, 1.0, 1.0 + 1e-9])];
        let e = match_vertices3(&vertices, &nodal).unwrap_err().to_string();
        assert!(e.starts_with("gradvi vertex 1 at (1, 1, 1)"), "{e}");
    }
}
