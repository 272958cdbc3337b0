//! Well-posedness before solving: problems whose energy is not bounded below on the convex set,
//! or flat along the constants, are typed errors; well-posed problems without a Dirichlet
//! boundary are solved (their barrier starts active) and certified.

use gradvi::Error;
use gradvi::mesh::generate::cartesian_rect;
use gradvi::problem::*;
use gradvi::scheme::*;
use gradvi::solver::*;

fn solve(kind: SchemeKind, p: &Problem) -> gradvi::Result<(usize, f64)> {
    let mesh = cartesian_rect(12, 8, [-1.0, 0.0], [0.2, 0.8])?;
    let tri;
    let mesh = if kind == SchemeKind::Hmm {
        mesh
    } else {
        tri = crate::common::triangle_grid(8, 0.0);
        tri
    };
    let s = build(kind, &mesh)?;
    let sol = solve_problem(s.as_ref(), p, &SolveOptions::default())?;
    sol.result.certificate.check(1e-10)?;
    let umax = sol.u().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    Ok((sol.niter(), umax))
}

#[test]
fn test2_with_every_boundary_edge_signorini_is_not_garbage() {
    // the reproducer: no Dirichlet edge; HMM used to return u ≈ −4.6e10 with exit 0
    let p = paper_test2().with_boundary(|_, _| BoundaryKind::Signorini);
    for kind in [SchemeKind::Hmm, SchemeKind::P1] {
        match solve(kind, &p) {
            Err(Error::IllPosed(msg)) => assert!(msg.contains("no Dirichlet"), "{msg}"),
            Ok((_, umax)) => assert!(umax < 1e3, "{kind}: |u| = {umax}"),
            Err(e) => panic!("{kind}: unexpected error {e}"),
        }
    }
}

#[test]
fn no_dirichlet_and_no_barrier_is_ill_posed() {
    let p = Problem::new("neumann", Box::new(|_| 1.0)).with_boundary(|_, _| BoundaryKind::Neumann);
    for kind in [SchemeKind::Hmm, SchemeKind::P1, SchemeKind::Cr] {
        let e = solve(kind, &p).unwrap_err();
        assert!(
            matches!(&e, Error::IllPosed(m) if m.contains("additive constant")),
            "{kind}: {e}"
        );
    }
}

#[test]
fn a_barrier_on_the_wrong_side_of_the_load_is_unbounded() {
    // lower barrier u ≥ −1 and f = +5 > 0: u + t pushes the energy to −∞ as t → +∞
    let p = Problem::new("up", Box::new(|_| 5.0))
        .with_boundary(|_, _| BoundaryKind::Neumann)
        .with_constraint(ConstraintKind::Obstacle, Side::Lower, Box::new(|_| -1.0));
    for kind in [SchemeKind::Hmm, SchemeKind::P1, SchemeKind::Cr] {
        let e = solve(kind, &p).unwrap_err();
        assert!(
            matches!(&e, Error::IllPosed(m) if m.contains("without bound")),
            "{kind}: {e}"
        );
    }
    // f = 0: flat along the constants
    let p = Problem::new("flat", Box::new(|_| 0.0))
        .with_boundary(|_, _| BoundaryKind::Neumann)
        .with_constraint(ConstraintKind::Obstacle, Side::Lower, Box::new(|_| -1.0));
    let e = solve(SchemeKind::Hmm, &p).unwrap_err();
    assert!(
        matches!(&e, Error::IllPosed(m) if m.contains("not unique")),
        "{e}"
    );
}

#[test]
fn a_barrier_that_holds_the_constants_is_solved_without_dirichlet_data() {
    // f = −5 pushes u down onto the lower barrier ψ = −1 everywhere: u = −1 exactly
    let p = Problem::new("down", Box::new(|_| -5.0))
        .with_boundary(|_, _| BoundaryKind::Neumann)
        .with_constraint(ConstraintKind::Obstacle, Side::Lower, Box::new(|_| -1.0));
    for kind in [SchemeKind::Hmm, SchemeKind::P1, SchemeKind::Cr] {
        let (niter, umax) = solve(kind, &p).unwrap();
        assert!((umax - 1.0).abs() < 1e-12, "{kind}: max |u| = {umax}");
        assert_eq!(niter, 1, "{kind}");
    }
}

#[test]
fn a_marginal_load_is_reported_by_both_schemes() {
    // the example: the paper's Test 2 data on (−1,0)×(0.2,0.8), every edge Signorini
    // with the upper barrier 0; ∫f = −0.015 is small against ∫|f|, so the sign of the discrete
    // load (which decides between a solution and none) is the discretisation's
    let p = paper_test2().with_boundary(|_, _| BoundaryKind::Signorini);
    let square = cartesian_rect(12, 8, [-1.0, 0.0], [0.2, 0.8]).unwrap();
    let triangles =
        gradvi::mesh::generate::cartesian_triangles(12, 8, [-1.0, 0.0], [0.2, 0.8]).unwrap();
    for (kind, mesh) in [(SchemeKind::Hmm, &square), (SchemeKind::P1, &triangles)] {
        let s = build(kind, mesh).unwrap();
        match solve_problem(s.as_ref(), &p, &SolveOptions::default()) {
            Ok(sol) => {
                let [m] = sol.marginal_load.as_slice() else {
                    panic!("{kind}: solved, {} marginal parts", sol.marginal_load.len());
                };
                assert!(
                    m.sum > 0.0 && m.ratio < well_posed::MARGINAL_LOAD_RATIO,
                    "{kind}: {m:?}"
                );
                assert!(m.to_string().starts_with("marginal load"), "{m}");
            }
            Err(Error::IllPosed(msg)) => {
                assert!(
                    msg.contains("without bound") && msg.contains("marginal load"),
                    "{kind}: {msg}"
                );
            }
            Err(e) => panic!("{kind}: {e}"),
        }
    }
}
