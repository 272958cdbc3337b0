//! The active-set solver: certificates, exhaustive enumeration on small problems, monotonicity
//! on M-matrices, a closed-form 1D obstacle problem, cycling, infeasibility and bad data.

use crate::common::*;
use gradvi::assembly::{DiscreteSystem, SolveState};
use gradvi::mesh::PolyMesh;
use gradvi::problem::*;
use gradvi::scheme::*;
use gradvi::solver::constraints::{Constraints, build as build_constraints};
use gradvi::solver::*;
use gradvi::vi::{QuadraticEnergy, active_set};
use gradvi::{Error, SolverError};
use nalgebra::{DMatrix, DVector};

/// The reference solution by exhaustive enumeration of the active sets.
fn enumerate(sys: &mut dyn QuadraticEnergy, cons: &Constraints) -> Vec<f64> {
    gradvi::vi::exhaustive::solve(sys, cons).unwrap().0
}

fn check_against_enumeration(scheme: &dyn GradientDiscretisation, p: &Problem, min_active: usize) {
    let sys = DiscreteSystem::new(scheme, p, Default::default()).unwrap();
    let cons = build_constraints(&sys, p).unwrap().unwrap();
    let sol = active_set::solve(
        &mut sys.with_state(&mut SolveState::default()),
        &cons,
        &ActiveSetOptions::default(),
    )
    .unwrap();
    let n_act = sol.active.iter().filter(|&&a| a).count();
    assert!(
        n_act >= min_active && n_act < cons.dofs.len(),
        "{}: the test should have a non-trivial contact set ({n_act} of {})",
        p.name,
        cons.dofs.len()
    );
    sol.certificate.check(1e-12).unwrap();
    let reference = enumerate(&mut sys.with_state(&mut SolveState::default()), &cons);
    let umax = reference.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (a, b) in sol.u.iter().zip(&reference) {
        assert!((a - b).abs() <= 1e-10 * umax, "{}: {a} vs {b}", p.name);
    }
    // and against projected Gauss–Seidel
    let pg = pgs_solution(&sys, &cons);
    for (a, b) in sol.u.iter().zip(&pg) {
        assert!((a - b).abs() <= 1e-9 * umax, "{} (PGS): {a} vs {b}", p.name);
    }
}

/// The projected Gauss–Seidel solution, run to 1e-15.
fn pgs_solution(sys: &DiscreteSystem, cons: &Constraints) -> Vec<f64> {
    gradvi::vi::pgs::solve(
        &sys.with_state(&mut SolveState::default()),
        cons,
        &gradvi::vi::pgs::PgsOptions {
            tol: 1e-15,
            ..Default::default()
        },
    )
    .unwrap()
    .u
}

fn upper_obstacle() -> Problem {
    Problem::new("upper obstacle", Box::new(|_| 4.0)).with_constraint(
        ConstraintKind::Obstacle,
        Side::Upper,
        Box::new(|x| 0.25 - 0.2 * x[0]),
    )
}

/// Test 1 data with an upper barrier on the other side (u ≤ −0.01 + 0.05 x on Γ3).
fn upper_signorini() -> Problem {
    let mut p = paper_test1();
    p.constraint = Some(Constraint {
        kind: ConstraintKind::Signorini,
        side: Side::Upper,
        barrier: Box::new(|x| -0.01 + 0.05 * x[0]),
    });
    p
}

#[test]
fn small_problems_match_enumeration_and_pgs() {
    let grid3 = square_grid(3);
    let tri = triangle_grid(4, 0.2);
    let grid4 = rect_grid(4, 3, 1.0, 1.0);
    // HMM obstacle on cells (9 cells), lower and upper
    check_against_enumeration(&Hmm::new(&grid3), &paper_test3(-9.0), 1);
    check_against_enumeration(&Hmm::new(&grid3), &upper_obstacle(), 1);
    // P1 obstacle on interior vertices (9 of them)
    check_against_enumeration(&P1::new(&tri).unwrap(), &paper_test3(-9.0), 1);
    check_against_enumeration(&P1::new(&tri).unwrap(), &upper_obstacle(), 1);
    // Signorini: HMM faces on Γ3 and P1 vertices on Γ3, lower (Test 1) and upper
    check_against_enumeration(&Hmm::new(&grid4), &paper_test1(), 1);
    check_against_enumeration(&Hmm::new(&tri), &upper_signorini(), 1);
    check_against_enumeration(&P1::new(&tri).unwrap(), &paper_test1(), 1);
    check_against_enumeration(&P1::new(&tri).unwrap(), &upper_signorini(), 1);
    // Test 2 (upper barrier, heterogeneous) on a 4×6 grid: 6 faces on Γ3
    check_against_enumeration(&Hmm::new(&rect_grid(4, 6, 1.0, 1.0)), &paper_test2(), 1);
}

/// For problems with too many constrained unknowns to enumerate: the active-set solution
/// against projected Gauss–Seidel run to 1e-15.
fn check_against_pgs(scheme: &dyn GradientDiscretisation, p: &Problem) {
    let sys = DiscreteSystem::new(scheme, p, Default::default()).unwrap();
    let cons = build_constraints(&sys, p).unwrap().unwrap();
    let sol = active_set::solve(
        &mut sys.with_state(&mut SolveState::default()),
        &cons,
        &ActiveSetOptions::default(),
    )
    .unwrap();
    let n_act = sol.active.iter().filter(|&&a| a).count();
    assert!(
        n_act > 0 && n_act < cons.dofs.len(),
        "{}: trivial contact set",
        p.name
    );
    sol.certificate.check(1e-12).unwrap();
    let pg = pgs_solution(&sys, &cons);
    let umax = pg.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (a, b) in sol.u.iter().zip(&pg) {
        assert!((a - b).abs() <= 1e-9 * umax, "{} (PGS): {a} vs {b}", p.name);
    }
}

#[test]
fn hexagonal_and_kershaw_problems_match_pgs() {
    use gradvi::mesh::generate::{hexagonal, kershaw};
    let hex = hexagonal(1).unwrap();
    let ker = kershaw(1).unwrap();
    // obstacle on cells, lower and upper; Signorini on faces, upper (Test 2) and lower (Test 1)
    check_against_pgs(&Hmm::new(&hex), &paper_test3(-10.0));
    check_against_pgs(&Hmm::new(&ker), &paper_test3(-10.0));
    check_against_pgs(&Hmm::new(&hex), &upper_obstacle());
    check_against_pgs(&Hmm::new(&ker), &upper_signorini());
    check_against_pgs(&Hmm::new(&hex), &paper_test1());
    check_against_pgs(&Hmm::new(&hex), &paper_test2());
}

#[test]
fn m_matrix_iterates_are_monotone_and_niter_is_bounded() {
    // HMM on a Cartesian mesh with A = I is the two-point scheme: an M-matrix
    let mesh = square_grid(16);
    let s = Hmm::new(&mesh);
    for c in [-5.0, -20.0] {
        let p = paper_test3(c);
        let sys = DiscreteSystem::new(&s, &p, Default::default()).unwrap();
        let cons = build_constraints(&sys, &p).unwrap().unwrap();
        let opts = ActiveSetOptions {
            keep_iterates: true,
            ..Default::default()
        };
        let sol = active_set::solve(
            &mut sys.with_state(&mut SolveState::default()),
            &cons,
            &opts,
        )
        .unwrap();
        assert!(sol.niter <= cons.dofs.len() + 2);
        // lower barrier: every violator enters at the second solve; from then on the iterates
        // are feasible, the active set only shrinks, and u^k increases to the solution
        for w in sol.iterates.windows(2) {
            for (a, b) in w[0].iter().zip(&w[1]) {
                assert!(b - a >= -1e-13, "C = {c}: not monotone ({a} -> {b})");
            }
        }
        for l in &sol.log[1..] {
            assert!(l.step.violation == 0.0, "{:?}", sol.log);
        }
        for l in &sol.log[2..] {
            assert!(l.step.entered == 0, "{:?}", sol.log);
        }
        assert!(
            sol.niter >= 3,
            "the test should exercise several iterations"
        );
    }
}

#[test]
fn one_dimensional_obstacle_converges_to_the_closed_form() {
    // −u'' = −8 on (0,1), u(0) = u(1) = 0, u ≥ −1/2: contact on [a, 1−a] with a = 1/√8,
    // u = 4x² − 8ax on [0, a]. Solved on a strip of n×1 cells with Neumann top and bottom.
    let a = (1.0f64 / 8.0).sqrt();
    let exact = move |x: f64| {
        let x = x.min(1.0 - x);
        if x < a {
            4.0 * x * x - 8.0 * a * x
        } else {
            -0.5
        }
    };
    let mut hs = vec![];
    let mut errs = vec![];
    for n in [16, 32, 64, 128] {
        let mesh = rect_grid(n, 1, 1.0, 1.0 / n as f64);
        let s = Hmm::new(&mesh);
        let p = Problem::new("1d", Box::new(|_| -8.0))
            .with_boundary(|x, _| {
                if x[0] < 1e-12 || x[0] > 1.0 - 1e-12 {
                    BoundaryKind::Dirichlet
                } else {
                    BoundaryKind::Neumann
                }
            })
            .with_constraint(ConstraintKind::Obstacle, Side::Lower, Box::new(|_| -0.5));
        let sol = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
        let cv = s.cell_values(sol.u());
        let e = (0..mesh.n_cells())
            .map(|k| (cv[k] - exact(mesh.centroid(k)[0])).abs())
            .fold(0.0, f64::max);
        hs.push(1.0 / n as f64);
        errs.push(e);
    }
    let slope = gradvi::post::fitted_slope(&hs, &errs);
    assert!(slope >= 1.0, "max-norm error slope {slope} ({errs:?})");
}

#[test]
fn no_contact_gives_the_linear_solution() {
    let mesh = triangle_grid(8, 0.1);
    for kind in [SchemeKind::Hmm, SchemeKind::P1] {
        let s = gradvi::scheme::build(kind, &mesh).unwrap();
        let p = Problem::new("free", Box::new(|_| -5.0)).with_constraint(
            ConstraintKind::Obstacle,
            Side::Lower,
            Box::new(|_| -10.0),
        );
        let vi = solve_problem(s.as_ref(), &p, &SolveOptions::default()).unwrap();
        let lin = solve_problem(
            s.as_ref(),
            &Problem::new("lin", Box::new(|_| -5.0)),
            &SolveOptions::default(),
        )
        .unwrap();
        assert_eq!(vi.niter(), 1);
        assert_eq!(vi.u(), lin.u(), "{kind}");
    }
}

#[test]
fn iteration_cap_is_a_typed_error() {
    let mesh = square_grid(8);
    let s = Hmm::new(&mesh);
    let opts = SolveOptions {
        active_set: ActiveSetOptions {
            max_solves: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    let err = solve_problem(&s, &paper_test3(-5.0), &opts).err().unwrap();
    assert!(
        matches!(
            err,
            Error::Solver(SolverError::MaxIterations { iterations: 1, .. })
        ),
        "{err}"
    );
}

#[test]
fn infeasible_and_invalid_data_are_rejected() {
    let tri = triangle_grid(4, 0.0);
    let p1 = P1::new(&tri).unwrap();
    // an upper obstacle below the Dirichlet data u = 0 on ∂Ω
    let p = Problem::new("infeasible", Box::new(|_| 1.0)).with_constraint(
        ConstraintKind::Obstacle,
        Side::Upper,
        Box::new(|_| -1.0),
    );
    let e = solve_problem(&p1, &p, &SolveOptions::default())
        .err()
        .expect("P1 obstacle below the Dirichlet data");
    assert!(matches!(e, Error::Infeasible(_)), "{e}");
    let hmm = Hmm::new(&tri);
    let e = solve_problem(&hmm, &p, &SolveOptions::default())
        .err()
        .expect("HMM obstacle below the Dirichlet data");
    assert!(matches!(e, Error::Infeasible(_)), "{e}");
    // Signorini (Test 2 geometry) with a barrier below the Dirichlet value at the Γ1 ∩ Γ3
    // corners, for P1 whose corner vertices carry both
    let mut p = paper_test2();
    p.constraint.as_mut().unwrap().barrier = Box::new(|_| -0.1);
    let e = solve_problem(&p1, &p, &SolveOptions::default())
        .err()
        .expect("P1 Signorini corner");
    assert!(matches!(e, Error::Infeasible(_)), "{e}");
    // NaN data
    let nan_f = Problem::new("nan", Box::new(|x| if x[0] > 0.5 { f64::NAN } else { 0.0 }));
    assert!(matches!(
        solve_problem(&hmm, &nan_f, &SolveOptions::default())
            .err()
            .unwrap(),
        Error::InvalidData(_)
    ));
    let nan_g = paper_test3(-5.0);
    let nan_g = Problem {
        constraint: Some(Constraint {
            barrier: Box::new(|_| f64::NAN),
            ..nan_g.constraint.unwrap()
        }),
        ..nan_g
    };
    assert!(matches!(
        solve_problem(&hmm, &nan_g, &SolveOptions::default())
            .err()
            .unwrap(),
        Error::InvalidData(_)
    ));
    let bad_a = Problem::new("bad A", Box::new(|_| 1.0))
        .with_diffusion(Box::new(|_| [[1.0, 2.0], [2.0, 1.0]]));
    assert!(matches!(
        solve_problem(&hmm, &bad_a, &SolveOptions::default())
            .err()
            .unwrap(),
        Error::InvalidData(_)
    ));
    let inf_dir =
        Problem::new("inf", Box::new(|_| 1.0)).with_dirichlet(Box::new(|_| f64::INFINITY));
    assert!(matches!(
        solve_problem(&hmm, &inf_dir, &SolveOptions::default())
            .err()
            .unwrap(),
        Error::InvalidData(_)
    ));
    // P1 on a polygonal mesh
    let quads = square_grid(2);
    assert!(matches!(
        P1::new(&quads).err().unwrap(),
        Error::InvalidData(_)
    ));
}

#[test]
fn hmm_on_cartesian_with_identity_is_the_two_point_scheme() {
    // TPFA: Σ_σ τ_σ (u_K − u_L) = |K| f(x_K), τ = |σ|/(d_K,σ + d_L,σ), boundary τ = |σ|/d_K,σ
    let n = 6;
    let mesh = square_grid(n);
    let f = |x: [f64; 2]| (3.0 * x[0]).sin() + x[1] * x[1];
    let p = Problem::new("tpfa", Box::new(f));
    let s = Hmm::new(&mesh);
    let sol = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
    let nc = mesh.n_cells();
    let mut a = DMatrix::<f64>::zeros(nc, nc);
    let mut b = DVector::<f64>::zeros(nc);
    for k in 0..nc {
        b[k] = mesh.measure(k) * f(mesh.centroid(k));
        for (i, &e) in mesh.cell_edges(k).iter().enumerate() {
            let e = e as usize;
            let [c0, c1] = mesh.edge_cells(e);
            let dk = mesh.cell_dist(k, i);
            if mesh.is_boundary_edge(e) {
                a[(k, k)] += mesh.edge_measure(e) / dk;
            } else {
                let l = if c0 == k { c1 } else { c0 };
                let tau = mesh.edge_measure(e) / (dk + dk);
                a[(k, k)] += tau;
                a[(k, l)] -= tau;
            }
        }
    }
    let tpfa = a.clone().cholesky().unwrap().solve(&b);
    let cv = s.cell_values(sol.u());
    for k in 0..nc {
        assert!(
            (cv[k] - tpfa[k]).abs() < 1e-12,
            "cell {k}: {} vs {}",
            cv[k],
            tpfa[k]
        );
    }
    // and the local HMM matrix on faces is diag(|σ|/d_K,σ): the condensed system is TPFA's
    for k in [0, 7] {
        let w = s.w_matrix(k, &[[1.0, 0.0], [0.0, 1.0]]);
        for i in 0..4 {
            for j in 0..4 {
                let e = mesh.cell_edges(k)[i] as usize;
                let expect = if i == j {
                    mesh.edge_measure(e) / mesh.cell_dist(k, i)
                } else {
                    0.0
                };
                assert!(
                    (w[(i, j)] - expect).abs() < 1e-12,
                    "W[{i},{j}] = {}",
                    w[(i, j)]
                );
            }
        }
    }
    let _: &PolyMesh = &mesh;
}

/// The rows of M that the look-ahead reads (`row_entries`, through the cells of each unknown)
/// are those of the whole matrix (`full_matrix_triplets`), on HMM (interior unknowns) and P1.
#[test]
fn row_entries_are_the_rows_of_the_full_matrix() {
    use std::collections::BTreeMap;
    let quads = gradvi::mesh::generate::cartesian(6, 5).unwrap();
    let tri = gradvi::mesh::generate::cartesian_triangles(5, 6, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let hmm = Hmm::new(&quads);
    let p1 = P1::new(&tri).unwrap();
    for scheme in [&hmm as &dyn GradientDiscretisation, &p1] {
        let sys = DiscreteSystem::new(scheme, &paper_test1(), Default::default()).unwrap();
        let n = sys.n_unknowns();
        let sum = |t: Vec<(usize, usize, f64)>| {
            let mut m = BTreeMap::new();
            for (i, j, v) in t {
                *m.entry((i, j)).or_insert(0.0) += v;
            }
            m
        };
        let rows: Vec<usize> = (0..n).filter(|i| i % 3 == 1).collect();
        let full: BTreeMap<_, _> = sum(sys.full_matrix_triplets())
            .into_iter()
            .filter(|((i, _), _)| i % 3 == 1)
            .collect();
        let got = sum(sys.row_entries(&rows).unwrap());
        assert_eq!(
            full.keys().collect::<Vec<_>>(),
            got.keys().collect::<Vec<_>>()
        );
        for (k, v) in &full {
            assert!((v - got[k]).abs() <= 1e-14 * v.abs().max(1.0), "{k:?}");
        }
        assert!(sys.row_entries(&[]).unwrap().is_empty());
    }
}
