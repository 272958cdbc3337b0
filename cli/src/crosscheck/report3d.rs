//! The 3D section of `CROSSCHECK.md`, written from `results/crosscheck3d.csv` only: gradvi-P1
//! against dolfinx-P1 on gmsh tetrahedra, with the comparisons that fail their tolerance added
//! to the report's list.

use super::three_d::Crosscheck3Row;
use super::{ACTIVE_TOL, SAME_PROBLEM_TOL};
use crate::markdown::{Doc, Table, cells, fixed, pass, sci};

/// The contact volume of the exact solution of `ex9-3d`: the ball of radius r₀ = 1/√2.
fn exact_contact_volume() -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * std::f64::consts::FRAC_1_SQRT_2.powi(3)
}

/// Section 5: the same discrete problem in 3D, nodal values and active sets.
pub(super) fn same_problem_3d(md: &mut Doc, rows: &[Crosscheck3Row], failed: &mut Vec<String>) {
    md.section(2, "5. 3D: same discrete problem on tetrahedra (gradvi-P1 vs dolfinx-P1)", format!("The 3D radial obstacle `problems/ex9-3d.toml` (Ω = (−2,2)³, −Δu = 0, u ≥ ψ = √(1 − r²) for r ≤ 1 and −1 beyond, u = 1/(2r) on ∂Ω; contact set the ball of radius r₀ = 1/√2, volume {:.4}) on the gmsh tetrahedral meshes `meshes/ex9_3d_k.msh`. Both codes: P1 on the same tetrahedra, Dirichlet values 1/(2|x_v|) at the boundary vertices, nodal barrier ψ(x_v) at every other vertex, f = 0 (so no load quadrature enters). Tolerance as in section 1: max rel. nodal diff. ≤ {SAME_PROBLEM_TOL:.0e} and identical active sets (dolfinx: |u − ψ| ≤ {ACTIVE_TOL:.0e}·max(1, |ψ|)). *contact volume*: Σ of the lumped vertex measures Σ_{{T∋v}} |T|/4 over active vertices. e_u: relative discrete L² error at the centroids against the exact solution, the same formula for both. NITER: gradvi's linear solves (default nested start); SNES: `vinewtonrsls` iterations.", exact_contact_volume()));
    if rows.is_empty() {
        md.para("No 3D case in the reference.");
        return;
    }
    let mut t = Table::new(
        "case | cells | vertices | h | constrained (gradvi / dolfinx) | max rel. nodal diff. | active gradvi / dolfinx | # diff. | contact volume gradvi / dolfinx | e_u gradvi / dolfinx | NITER / SNES | gradvi P1 [s] | dolfinx setup + solve [s] | same problem",
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
                "{} / {}",
                fixed(x.contact_p1, 4),
                fixed(x.contact_dolfinx, 4)
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
