//! The 3D section of `CROSSCHECK.md`, written from `results/crosscheck3d.csv` only: gradvi-P1
//! against dolfinx-P1 on gmsh tetrahedra, with the comparisons that fail their tolerance added
//! to the report's list.

use super::three_d::Crosscheck3Row;
use super::{ACTIVE_TOL, SAME_PROBLEM_TOL};
use crate::markdown::{Doc, NONE, Table, cells, fixed, pass, sci};

/// The measure of the exact contact set: for `ex9-3d` the volume of the ball of radius
/// r₀ = 1/√2, for `signorini-3d` the area of {x = 0, y > 1/2} (where ū = 0 on Γ3).
fn exact_contact(test: &str) -> Option<f64> {
    match test {
        "ex9-3d" => {
            Some(4.0 / 3.0 * std::f64::consts::PI * std::f64::consts::FRAC_1_SQRT_2.powi(3))
        }
        "signorini-3d" => Some(0.5),
        _ => None,
    }
}

/// Section 5: the same discrete problem in 3D, nodal values and active sets.
pub(super) fn same_problem_3d(md: &mut Doc, rows: &[Crosscheck3Row], failed: &mut Vec<String>) {
    md.section(2, "5. 3D: same discrete problem on tetrahedra (gradvi-P1 vs dolfinx-P1)", format!("Two problems on gmsh tetrahedra, each solved by gradvi from its problem file and by `reference/solve.py`: **ex9_3d_k**, the 3D radial obstacle `problems/ex9-3d.toml` (Ω = (−2,2)³, −Δu = 0, u ≥ ψ = √(1 − r²) for r ≤ 1 and −1 beyond, u = 1/(2r) on ∂Ω; contact set the ball of radius r₀ = 1/√2, volume {:.4}) on `meshes/3d/ex9_3d_k.msh`: Dirichlet values 1/(2|x_v|) at the boundary vertices, nodal barrier ψ(x_v) at every other vertex, f = 0; **signorini3d_k**, `problems/signorini-3d.toml` (the unit cube, two anisotropic materials by cell tag, u ≤ 0 on x = 0, exact contact zone {{x = 0, y > 1/2}}, area 0.5, where the contact is degenerate: ū = 0 with zero flux, so a discrete solution may stay just below the barrier on part of it) on `meshes/3d/signorini3d_k.msh` (`meshes/3d/signorini3d.geo` with h = 0.25, 0.125): A constant per tag, load = exact integral of the P1 interpolant of the cell's tag's f, flux by the centroid rule on each boundary triangle, u = 0 at the vertices of the Dirichlet faces, u ≤ 0 at the other vertices of x = 0. Tolerance as in section 1: max rel. nodal diff. ≤ {SAME_PROBLEM_TOL:.0e} and identical active sets (dolfinx: |u − g| ≤ {ACTIVE_TOL:.0e}·max(1, |g|), g the barrier). *contact*: Σ of the lumped measures of the active vertices (volume Σ_{{T∋v}} |T|/4 for the obstacle, area Σ_{{σ∋v, σ⊂Γ3}} |σ|/3 for Signorini), beside the exact measure. e_u: relative discrete L² error at the centroids against the exact solution, the same formula for both. NITER: gradvi's linear solves (default nested start); SNES: `vinewtonrsls` iterations.", exact_contact("ex9-3d").unwrap_or(f64::NAN)));
    if rows.is_empty() {
        md.para("No 3D case in the reference.");
        return;
    }
    let mut t = Table::new(
        "case | cells | vertices | h | constrained (gradvi / dolfinx) | max rel. nodal diff. | active gradvi / dolfinx | # diff. | contact gradvi / dolfinx (exact) | e_u gradvi / dolfinx | NITER / SNES | gradvi P1 [s] | dolfinx setup + solve [s] | same problem",
        "lrrrrrrrrrrrrl",
    );
    let mut bad = Vec::new();
    for x in rows {
        let ok = x.p1_max_rel_diff <= SAME_PROBLEM_TOL && x.active_identical;
        if !ok {
            bad.push(x.case.as_str());
        }
        t.row(cells![
            x.case,
            x.n_cells,
            x.n_vertices,
            fixed(x.h, 3),
            format!("{} / {}", x.n_constrained_gradvi, x.n_constrained_dolfinx),
            format!("{:.1e}", x.p1_max_rel_diff),
            format!("{} / {}", x.n_active_p1, x.n_active_dolfinx),
            x.active_n_diff,
            format!(
                "{} / {} ({})",
                fixed(x.contact_p1, 4),
                fixed(x.contact_dolfinx, 4),
                exact_contact(&x.test).map_or(NONE.to_string(), |c| fixed(c, 4))
            ),
            format!("{} / {}", sci(x.err_u_p1), sci(x.err_u_dolfinx)),
            format!("{} / {}", x.niter_p1, x.snes_iterations),
            format!("{:.3}", x.time_p1_s),
            format!("{:.3}", x.time_dolfinx_setup_s + x.time_dolfinx_solve_s),
            pass(ok)
        ]);
    }
    md.table(&t);
    let worst = rows
        .iter()
        .map(|x| x.p1_max_rel_diff)
        .fold(0.0f64, f64::max);
    md.para(format!(
        "Largest max rel. nodal diff. over the 3D cases: {worst:.1e}; active sets identical on {} of {} cases.",
        rows.iter().filter(|x| x.active_identical).count(),
        rows.len()
    ));
    if !bad.is_empty() {
        failed.push(format!(
            "3D same discrete problem: {} case(s) above {SAME_PROBLEM_TOL:.0e} or with different active sets: {}",
            bad.len(),
            bad.join(", ")
        ));
    }
}
