//! P1 and Crouzeix–Raviart on small tetrahedral meshes: an obstacle and a Signorini problem
//! solved by the active-set method (through `solve_problem`), against exhaustive enumeration
//! of the active sets where there are few constrained unknowns, and projected Gauss–Seidel
//! run to 1e-15 where there are more (the HMM counterparts are in `src/solver/tests_3d.rs`).

use gradvi::assembly::{DiscreteSystem, SolveState};
use gradvi::budget::MemoryBudget;
use gradvi::mesh3d::generate::kuhn;
use gradvi::mesh3d::{Cuboid, PolyMesh3};
use gradvi::problem::{BoundaryKind, ConstraintKind, Problem, Side};
use gradvi::scheme::{GradientDiscretisation, SchemeKind, build_with3};
use gradvi::solver::constraints::build as build_constraints;
use gradvi::solver::{SolveOptions, solve_problem};
use gradvi::vi::{exhaustive, pgs};

/// 6n³ Kuhn tetrahedra of the unit cube.
fn tets(n: usize) -> PolyMesh3 {
    let p = kuhn(n, Cuboid::UNIT, MemoryBudget::DEFAULT).unwrap();
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap()
}

/// −Δu ≥ −20, u ≥ ψ = −0.05 − 1.2 x, u = 0 on ∂Ω (ψ < 0 there): the solution touches the
/// obstacle where ψ is high (small x) and leaves it where ψ is low.
fn obstacle() -> Problem<3> {
    Problem::<3>::new("obstacle-3d", Box::new(|_| -20.0)).with_constraint(
        ConstraintKind::Obstacle,
        Side::Lower,
        Box::new(|x| -0.05 - 1.2 * x[0]),
    )
}

/// −Δu = 2π sin(2πx), u = 0 on z = 1, u ≥ 0, ∇u·n ≥ 0, u ∇u·n = 0 on z = 0, zero flux on
/// the other faces: contact where the source pushes down.
fn signorini() -> Problem<3> {
    let pi = std::f64::consts::PI;
    Problem::<3>::new(
        "signorini-3d",
        Box::new(move |x| 2.0 * pi * (2.0 * pi * x[0]).sin()),
    )
    .with_boundary(|x: [f64; 3], _| {
        if x[2] > 1.0 - 1e-12 {
            BoundaryKind::Dirichlet
        } else if x[2] < 1e-12 {
            BoundaryKind::Signorini
        } else {
            BoundaryKind::Neumann
        }
    })
    .with_constraint(ConstraintKind::Signorini, Side::Lower, Box::new(|_| 0.0))
}

/// Solves `p` with `kind` on `m` by the active-set method (cold start), checks its
/// certificate and that the active set is proper (some unknowns active, some free), and
/// compares with exhaustive enumeration (same active set) or with projected Gauss–Seidel.
fn check_against_reference(kind: SchemeKind, m: &PolyMesh3, p: &Problem<3>, exhaustive: bool) {
    let s = build_with3(kind, m, &Default::default()).unwrap();
    let s: &dyn GradientDiscretisation<PolyMesh3, 3> = s.as_ref();
    let sol = solve_problem(s, p, &SolveOptions::paper()).unwrap();
    sol.result.certificate.check(1e-10).unwrap();
    let n_active = sol.result.active.iter().filter(|&&a| a).count();
    let what = format!("{kind}, {}, {} cells", p.name, m.n_cells());
    assert!(
        n_active > 0 && n_active < sol.result.active.len(),
        "{what}: {n_active} of {} active",
        sol.result.active.len()
    );
    let sys = DiscreteSystem::new(s, p, Default::default()).unwrap();
    let cons = build_constraints(&sys, p).unwrap().unwrap();
    let mut state = SolveState::default();
    let reference = if exhaustive {
        let (u, active) = exhaustive::solve(&mut sys.with_state(&mut state), &cons).unwrap();
        assert_eq!(active, sol.result.active, "{what}");
        u
    } else {
        let o = pgs::PgsOptions {
            tol: 1e-15,
            ..Default::default()
        };
        pgs::solve(&sys.with_state(&mut state), &cons, &o)
            .unwrap()
            .u
    };
    let umax = reference.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (a, b) in sol.u().iter().zip(&reference) {
        assert!((a - b).abs() <= 1e-9 * umax, "{what}: {a} vs {b}");
    }
}

#[test]
fn p1_on_tetrahedra_agrees_with_enumeration_and_gauss_seidel_on_an_obstacle_problem() {
    // 3³ cubes: 8 interior vertices (2⁸ active sets); 4³: 27, by Gauss–Seidel
    check_against_reference(SchemeKind::P1, &tets(3), &obstacle(), true);
    check_against_reference(SchemeKind::P1, &tets(4), &obstacle(), false);
}

#[test]
fn cr_on_tetrahedra_agrees_with_enumeration_and_gauss_seidel_on_an_obstacle_problem() {
    // 1 cube: 6 interior faces; 2³ cubes: 72, by Gauss–Seidel
    check_against_reference(SchemeKind::Cr, &tets(1), &obstacle(), true);
    check_against_reference(SchemeKind::Cr, &tets(2), &obstacle(), false);
}

#[test]
fn p1_and_cr_on_tetrahedra_agree_with_enumeration_and_gauss_seidel_on_a_signorini_problem() {
    // 2³ cubes: 9 vertices (P1) and 8 faces (CR) on z = 0; 4³ cubes by Gauss–Seidel
    check_against_reference(SchemeKind::P1, &tets(2), &signorini(), true);
    check_against_reference(SchemeKind::Cr, &tets(2), &signorini(), true);
    check_against_reference(SchemeKind::P1, &tets(4), &signorini(), false);
    check_against_reference(SchemeKind::Cr, &tets(4), &signorini(), false);
}
