//! The Crouzeix–Raviart scheme with mass lumping: patch test (affine solutions reproduced),
//! fitted convergence slopes on triangle meshes, and obstacle and Signorini problems on tiny
//! meshes against exhaustive enumeration of the active sets.

use crate::common::*;
use gradvi::mesh::PolyMesh;
use gradvi::post::{fitted_slope, relative_errors};
use gradvi::problem::*;
use gradvi::scheme::*;
use gradvi::solver::{Solution, SolveOptions, solve_problem};
use std::path::PathBuf;

fn gmsh(name: &str) -> PolyMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name);
    gradvi::mesh::io::read_mesh(&path, gradvi::budget::MemoryBudget::DEFAULT).unwrap()
}

#[test]
fn cr_patch_test_reproduces_affine_solutions() {
    let exact = |x: [f64; 2]| 1.0 + 2.0 * x[0] - 3.0 * x[1];
    for (what, mesh) in [
        ("perturbed triangles", triangle_grid(6, 0.3)),
        ("gmsh test1_1", gmsh("test1_1.msh")),
    ] {
        let s = Cr::new(&mesh).unwrap();
        let sol = solve_problem(&s, &affine_problem(), &SolveOptions::default()).unwrap();
        // every edge unknown is the exact value at the midpoint
        for (e, ue) in sol.u().iter().enumerate() {
            let x = mesh.edge_midpoint(e);
            assert!((ue - exact(x)).abs() < 1e-10, "{what}: edge {e}");
        }
        let cv = s.cell_values(sol.u());
        let cg = s.cell_gradients(sol.u());
        for k in 0..mesh.n_cells() {
            let x = mesh.centroid(k);
            assert!((cv[k] - exact(x)).abs() < 1e-10, "{what}: cell {k}");
            assert!(
                (cg[k][0] - 2.0).abs() < 1e-10 && (cg[k][1] + 3.0).abs() < 1e-10,
                "{what}: gradient {:?}",
                cg[k]
            );
        }
        for (v, uv) in s.vertex_values(sol.u()).iter().enumerate() {
            assert!(
                (uv - exact(mesh.vertex(v))).abs() < 1e-10,
                "{what}: vertex {v}"
            );
        }
    }
}

/// (h, e_u, e_∇u) of FVCA5 test 1.1 (smooth, anisotropic, Dirichlet) on each mesh.
fn errors(meshes: &[PolyMesh]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let p = fvca5_test11();
    let ex = p.exact.as_ref().unwrap();
    let (mut h, mut eu, mut eg) = (vec![], vec![], vec![]);
    for m in meshes {
        let s = Cr::new(m).unwrap();
        let sol = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
        let e = relative_errors(&s, sol.u(), &ex.u, &ex.grad);
        h.push(m.h());
        eu.push(e.l2_u);
        eg.push(e.l2_grad);
    }
    (h, eu, eg)
}

/// Theory (non-conforming P1, mass lumping a perturbation of order h in the load): order 1 on
/// the broken gradient, order 2 on u at centroids (Aubin–Nitsche), each within ±0.15.
fn assert_orders(name: &str, (h, eu, eg): (Vec<f64>, Vec<f64>, Vec<f64>)) {
    let (su, sg) = (fitted_slope(&h, &eu), fitted_slope(&h, &eg));
    eprintln!("CR {name}: slope u {su:.3}, slope grad {sg:.3} (errors u {eu:?}, grad {eg:?})");
    assert!(
        (su - 2.0).abs() <= 0.15,
        "CR {name}: slope of u {su:.3}, expected 2 ± 0.15"
    );
    assert!(
        (sg - 1.0).abs() <= 0.15,
        "CR {name}: slope of ∇u {sg:.3}, expected 1 ± 0.15"
    );
}

#[test]
fn cr_converges_at_the_expected_orders() {
    let tri: Vec<PolyMesh> = [8, 16, 32, 64]
        .iter()
        .map(|&n| triangle_grid(n, 0.25))
        .collect();
    assert_orders("perturbed triangles", errors(&tri));
    let unstructured: Vec<PolyMesh> = (1..=4).map(|l| gmsh(&format!("test1_{l}.msh"))).collect();
    assert_orders("gmsh test1_1..4", errors(&unstructured));
}

/// Every active set whose equality-constrained solution satisfies the KKT conditions, with
/// its solution (exhaustive enumeration).
fn kkt_active_sets(sol: &Solution) -> Vec<(Vec<bool>, Vec<f64>)> {
    let cons = sol.constraints.as_ref().expect("a barrier");
    gradvi::vi::exhaustive::kkt_active_sets(
        &mut sol
            .system
            .with_state(&mut gradvi::assembly::SolveState::default()),
        cons,
        false,
    )
    .unwrap()
}

/// Solves `p` with CR on `mesh` and checks the solution against exhaustive enumeration: the
/// KKT active set is unique (non-degenerate data), equals the solver's, u agrees to 1e-10,
/// and the certificate passes.
fn check_against_enumeration(mesh: &PolyMesh, p: &Problem, n_constrained: usize) {
    let s = Cr::new(mesh).unwrap();
    let sol = solve_problem(&s, p, &SolveOptions::default()).unwrap();
    sol.result.certificate.check(1e-10).unwrap();
    let cons = sol.constraints.as_ref().unwrap();
    assert_eq!(cons.dofs.len(), n_constrained, "{}", p.name);
    let n_act = sol.result.active.iter().filter(|&&a| a).count();
    assert!(
        n_act > 0 && n_act < n_constrained,
        "{}: the contact set should be non-trivial ({n_act} of {n_constrained})",
        p.name
    );
    let found = kkt_active_sets(&sol);
    assert_eq!(
        found.len(),
        1,
        "{}: {} KKT active sets",
        p.name,
        found.len()
    );
    let (active, u) = &found[0];
    assert_eq!(&sol.result.active, active, "{}: active sets differ", p.name);
    let umax = u.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (a, b) in sol.u().iter().zip(u) {
        assert!((a - b).abs() <= 1e-10 * umax, "{}: {a} vs {b}", p.name);
    }
    eprintln!(
        "CR {}: {n_act} of {n_constrained} active, NITER {}",
        p.name,
        sol.niter()
    );
}

#[test]
fn cr_obstacle_and_signorini_match_enumeration() {
    // obstacle on the 8 interior edges of a 2×2 grid (Dirichlet boundary), lower barrier
    let grid2 = triangle_grid(2, 0.2);
    check_against_enumeration(&grid2, &paper_test3(-6.0), 8);
    // upper barrier, Neumann on x = 1: its 2 boundary edges are constrained too
    let upper = Problem::new("upper obstacle, Neumann on x = 1", Box::new(|_| 4.0))
        .with_boundary(|x, _| {
            if x[0] > 1.0 - 1e-12 {
                BoundaryKind::Neumann
            } else {
                BoundaryKind::Dirichlet
            }
        })
        .with_constraint(
            ConstraintKind::Obstacle,
            Side::Upper,
            Box::new(|x| 0.2 - 0.15 * x[0]),
        );
    check_against_enumeration(&grid2, &upper, 10);
    // Signorini: Test 1 (lower barrier on Γ3 = bottom, 8 edges) and Test 2 (upper barrier on
    // Γ3 = left, 8 edges; A and f jump across y = 1/2, f taken per cell)
    let grid8 = triangle_grid(8, 0.2);
    check_against_enumeration(&grid8, &paper_test1(), 8);
    check_against_enumeration(&triangle_grid(8, 0.0), &paper_test2(), 8);
}
