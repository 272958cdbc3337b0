//! Convergence tier: patch tests (exactness) and fitted slopes on the four mesh families.

mod common;

use common::{ANISOTROPIC as A, affine_problem, fvca5_dir, triangle_grid};
use gradvi::mesh::PolyMesh;
use gradvi::mesh::generate::{cartesian, hexagonal, kershaw};
use gradvi::post::{fitted_slope, relative_errors};
use gradvi::problem::{BoundaryKind, Problem, fvca5_test11, paper_test2};
use gradvi::scheme::{GradientDiscretisation, Hmm, P1};
use gradvi::solver::{SolveOptions, solve_problem};

fn check_patch(scheme: &dyn GradientDiscretisation, what: &str) {
    let sol = solve_problem(scheme, &affine_problem(), &SolveOptions::default()).unwrap();
    let mesh = scheme.mesh();
    let cv = scheme.cell_values(sol.u());
    let cg = scheme.cell_gradients(sol.u());
    for k in 0..mesh.n_cells() {
        let x = mesh.centroid(k);
        let exact = 1.0 + 2.0 * x[0] - 3.0 * x[1];
        assert!(
            (cv[k] - exact).abs() < 1e-10,
            "{what}: cell {k}: {} vs {exact}",
            cv[k]
        );
        assert!(
            (cg[k][0] - 2.0).abs() < 1e-10 && (cg[k][1] + 3.0).abs() < 1e-10,
            "{what}: gradient {:?}",
            cg[k]
        );
    }
}

#[test]
fn patch_tests_reproduce_affine_solutions() {
    let tri = triangle_grid(6, 0.3);
    check_patch(&Hmm::new(&tri), "HMM triangles");
    check_patch(&P1::new(&tri).unwrap(), "P1 triangles");
    let cart = cartesian(5, 7).unwrap();
    check_patch(&Hmm::new(&cart), "HMM Cartesian");
    let hex = hexagonal(2).unwrap();
    check_patch(&Hmm::new(&hex), "HMM hexagonal");
    let ker = kershaw(1).unwrap();
    check_patch(&Hmm::new(&ker), "HMM Kershaw");
}

/// Relative errors of `problem` on each mesh; returns (h, e_u, e_grad).
fn errors(meshes: &[PolyMesh], p1: bool, problem: &Problem) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let ex = problem.exact.as_ref().unwrap();
    let (mut h, mut eu, mut eg) = (vec![], vec![], vec![]);
    for m in meshes {
        let s: Box<dyn GradientDiscretisation> = if p1 {
            Box::new(P1::new(m).unwrap())
        } else {
            Box::new(Hmm::new(m))
        };
        let sol = solve_problem(s.as_ref(), problem, &SolveOptions::default()).unwrap();
        let e = relative_errors(s.as_ref(), sol.u(), &ex.u, &ex.grad);
        h.push(m.h());
        eu.push(e.l2_u);
        eg.push(e.l2_grad);
    }
    (h, eu, eg)
}

/// Both fitted slopes within ±0.15 of the expected orders (two-sided: a slope far above the
/// expected one is as suspicious as one below it).
fn assert_slopes(name: &str, (h, eu, eg): (Vec<f64>, Vec<f64>, Vec<f64>), su: f64, sg: f64) {
    let (a, b) = (fitted_slope(&h, &eu), fitted_slope(&h, &eg));
    eprintln!("{name}: slope u {a:.3}, slope grad {b:.3} (errors u {eu:?}, grad {eg:?})");
    assert!(
        (a - su).abs() <= 0.15,
        "{name}: slope of u {a:.3}, expected {su} ± 0.15"
    );
    assert!(
        (b - sg).abs() <= 0.15,
        "{name}: slope of the gradient {b:.3}, expected {sg} ± 0.15"
    );
}

#[test]
fn fvca5_test11_converges_on_four_families() {
    let p = fvca5_test11();
    let cart: Vec<PolyMesh> = [8, 16, 32, 64]
        .iter()
        .map(|&n| cartesian(n, n).unwrap())
        .collect();
    let hex: Vec<PolyMesh> = (1..=4).map(|l| hexagonal(l).unwrap()).collect();
    let ker: Vec<PolyMesh> = (1..=3).map(|l| kershaw(l).unwrap()).collect();
    let tri: Vec<PolyMesh> = [8, 16, 32, 64]
        .iter()
        .map(|&n| triangle_grid(n, 0.25))
        .collect();
    // HMM: order 2 on u at centroids on every family. The theory guarantees order 1 for
    // ∇_K u; sampled at the centroids it superconverges (order 2) on the Cartesian and the
    // smoothly mapped Kershaw families, not on the perturbed triangles (order 1); on the
    // hexagonal family the measured slope is 1.46, its successive ratios rising (1.26, 1.42,
    // 1.49) — a partial superconvergence that the band pins at 1.5.
    assert_slopes("HMM Cartesian", errors(&cart, false, &p), 2.0, 2.0);
    assert_slopes("HMM hexagonal", errors(&hex, false, &p), 2.0, 1.5);
    assert_slopes("HMM Kershaw", errors(&ker, false, &p), 2.0, 2.0);
    assert_slopes("HMM triangles", errors(&tri, false, &p), 2.0, 1.0);
    // P1 on triangles: order 2 in L² (at centroids), order 1 for the gradient
    assert_slopes("P1 triangles", errors(&tri, true, &p), 2.0, 1.0);
}

#[test]
#[ignore = "needs ../shared/meshes/fvca5; run by `make test-external`"]
fn fvca5_triangles_from_the_shared_files() {
    let dir = fvca5_dir();
    let p = fvca5_test11();
    let meshes: Vec<PolyMesh> = (1..=4)
        .map(|l| {
            gradvi::mesh::io::read_mesh(
                dir.join(format!("mesh1_{l}.typ2")),
                gradvi::budget::MemoryBudget::DEFAULT,
            )
            .unwrap()
        })
        .collect();
    assert_slopes("HMM FVCA5 mesh1", errors(&meshes, false, &p), 2.0, 1.0);
    assert_slopes("P1 FVCA5 mesh1", errors(&meshes, true, &p), 2.0, 1.0);
}

#[test]
fn mixed_dirichlet_neumann_converges() {
    // FVCA5 1.1 with the flux A∇ū·n prescribed on x = 1 and y = 1
    let mut p = fvca5_test11();
    p.boundary = Box::new(|x, _| {
        if x[0] > 1.0 - 1e-12 || x[1] > 1.0 - 1e-12 {
            BoundaryKind::Neumann
        } else {
            BoundaryKind::Dirichlet
        }
    });
    p.neumann = Box::new(|x| {
        let (a, b) = (x[0], x[1]);
        let g = [
            16.0 * (1.0 - 2.0 * a) * b * (1.0 - b),
            16.0 * a * (1.0 - a) * (1.0 - 2.0 * b),
        ];
        let n = if a > 1.0 - 1e-12 {
            [1.0, 0.0]
        } else {
            [0.0, 1.0]
        };
        (A[0][0] * g[0] + A[0][1] * g[1]) * n[0] + (A[1][0] * g[0] + A[1][1] * g[1]) * n[1]
    });
    let hex: Vec<PolyMesh> = (1..=4).map(|l| hexagonal(l).unwrap()).collect();
    assert_slopes("HMM hexagonal mixed", errors(&hex, false, &p), 2.0, 1.5);
    let tri: Vec<PolyMesh> = [8, 16, 32, 64]
        .iter()
        .map(|&n| triangle_grid(n, 0.25))
        .collect();
    assert_slopes("P1 triangles mixed", errors(&tri, true, &p), 2.0, 1.0);
}

#[test]
fn test2_gradient_order_on_hexagonal_meshes() {
    // the paper's Test 2 (Signorini, heterogeneous, u ∈ H² only piecewise): order 1 on ∇u
    // between the last two hexagonal meshes (the paper's rate; measured 1.01), ± 0.15
    let p = paper_test2();
    let hex: Vec<PolyMesh> = (3..=4).map(|l| hexagonal(l).unwrap()).collect();
    let (h, _, eg) = errors(&hex, false, &p);
    let order = gradvi::post::order(eg[0], eg[1], h[0], h[1]);
    assert!((order - 1.0).abs() <= 0.15, "order on the gradient {order}");
}
