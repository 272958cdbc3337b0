//! The solve pipeline (assembly, constraints, checks, active-set method, certificate) on 3D
//! meshes ([`PolyMesh3`]) with HMM: the patch test on cubes, Kuhn tetrahedra and perturbed
//! cubes, an obstacle and a Signorini problem against exhaustive enumeration and projected
//! Gauss–Seidel, and the nested warm start (skipped on a mesh too coarse for it, otherwise
//! reaching the cold start's solution; its convergence tests: `tests/obstacle3d.rs`).

use super::{SolveOptions, constraints, solve_problem};
use crate::assembly::{DiscreteSystem, SolveState};
use crate::budget::MemoryBudget;
use crate::mesh::CellComplex;
use crate::mesh3d::{PolyMesh3, Polyhedra, test_meshes};
use crate::problem::{BoundaryKind, ConstraintKind, Problem, Side};
use crate::scheme::{Entity, GradientDiscretisation, Hmm, Tensor};
use crate::vi::{exhaustive, pgs};

/// An anisotropic constant tensor.
const A: Tensor<3> = [[2.0, 0.3, 0.1], [0.3, 1.0, 0.2], [0.1, 0.2, 1.5]];

fn affine(x: [f64; 3]) -> f64 {
    1.0 + 2.0 * x[0] - x[1] + 3.0 * x[2]
}

fn mesh(p: Polyhedra) -> PolyMesh3 {
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap()
}

fn hmm(m: &PolyMesh3) -> Hmm<'_, PolyMesh3, 3> {
    Hmm::<PolyMesh3, 3>::with_alpha(m, 1.0).unwrap()
}

/// The point of unknown `d` of HMM: x_σ or x_K.
fn dof_point(s: &Hmm<'_, PolyMesh3, 3>, d: usize) -> [f64; 3] {
    match s.dof_entity(d) {
        Entity::Edge(f) => s.mesh().face_centre(f),
        Entity::Cell(k) => s.mesh().cell_centre(k),
        Entity::Vertex(v) => panic!("HMM has no vertex unknown ({v})"),
    }
}

/// `p` with every vertex inside the unit cube moved by up to `amp` times `h` in each
/// coordinate (seeded), and then mapped by x ↦ L x with L lower triangular (a shear): on
/// tetrahedra the faces stay planar whatever the moves; on boxes the shear keeps them planar.
fn moved(mut p: Polyhedra, amp: f64, h: f64, shear: f64, seed: u64) -> Polyhedra {
    let mut rng = crate::mesh::test_rng(seed);
    for v in &mut p.vertices {
        if v.iter().all(|&c| c > 1e-12 && c < 1.0 - 1e-12) {
            for c in v.iter_mut() {
                *c += amp * h * (2.0 * rng() - 1.0);
            }
        }
        *v = [v[0], v[1] + shear * v[0], v[2] + shear * (v[0] - v[1])];
    }
    p
}

/// The patch test: −div(A∇u) = 0 with the Dirichlet data of an affine u and an anisotropic
/// constant A is solved exactly at every x_K and x_σ, through assembly and the solver. The
/// meshes have planar faces (HMM's consistency, Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ = |K| I, holds
/// for them; on warped faces it holds only to the order of the warp, see
/// `mesh3d::tests_build`, so no exactness is expected there).
#[test]
fn affine_solutions_are_reproduced_on_every_3d_family() {
    let meshes = [
        ("cubes 4³", mesh(test_meshes::cubes(4, 1))),
        ("Kuhn tetrahedra 3³", mesh(test_meshes::tetrahedra(3, 2))),
        (
            "perturbed Kuhn tetrahedra 3³",
            mesh(moved(
                test_meshes::tetrahedra(3, 3),
                0.15,
                1.0 / 3.0,
                0.0,
                3,
            )),
        ),
        (
            "sheared cubes 3³",
            mesh(moved(test_meshes::cubes(3, 4), 0.0, 1.0 / 3.0, 0.4, 4)),
        ),
    ];
    for (name, m) in &meshes {
        let s = hmm(m);
        let p = Problem::<3>::new("patch", Box::new(|_| 0.0))
            .with_diffusion(Box::new(|_| A))
            .with_dirichlet(Box::new(affine));
        let sol = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
        sol.result.certificate.check(1e-10).unwrap();
        for (d, ud) in sol.u().iter().enumerate() {
            let x = dof_point(&s, d);
            assert!(
                (ud - affine(x)).abs() < 1e-10,
                "{name}, unknown {d}: {ud} vs {}",
                affine(x)
            );
        }
    }
}

/// The 3D counterpart of the paper's Test 3 with a tilted obstacle: −Δu ≥ −20, u ≥ ψ,
/// ψ = −0.05 − 1.2 x, u = 0 on ∂Ω (ψ < 0 there). On 2³ cubes the cells at x = 1/4 are in
/// contact and those at x = 3/4 are not (two-point fluxes: u_K = −0.76 > ψ = −0.95 there).
fn obstacle() -> Problem<3> {
    Problem::<3>::new("obstacle-3d", Box::new(|_| -20.0)).with_constraint(
        ConstraintKind::Obstacle,
        Side::Lower,
        Box::new(|x| -0.05 - 1.2 * x[0]),
    )
}

/// A Signorini problem on the unit cube: −Δu = 2π sin(2πx), u = 0 on z = 1, u ≥ 0,
/// ∇u·n ≥ 0, u ∇u·n = 0 on z = 0, zero flux on the other faces.
pub(super) fn signorini() -> Problem<3> {
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

/// Solves `p` on `m` with the active-set method (cold start) and checks the certificate, the
/// active set (some unknowns active, some free) and the agreement with exhaustive enumeration
/// (`exhaustive`) or projected Gauss–Seidel run to 1e-15.
fn check_against_reference(m: &PolyMesh3, p: &Problem<3>, exhaustive: bool) {
    let s = hmm(m);
    let sol = solve_problem(&s, p, &SolveOptions::paper()).unwrap();
    sol.result.certificate.check(1e-10).unwrap();
    let n_active = sol.result.active.iter().filter(|&&a| a).count();
    assert!(
        n_active > 0 && n_active < sol.result.active.len(),
        "{}: {n_active} of {} active",
        p.name,
        sol.result.active.len()
    );
    let sys = DiscreteSystem::new(&s, p, Default::default()).unwrap();
    let cons = constraints::build(&sys, p).unwrap().unwrap();
    let mut state = SolveState::default();
    let reference = if exhaustive {
        let (u, active) = exhaustive::solve(&mut sys.with_state(&mut state), &cons).unwrap();
        assert_eq!(active, sol.result.active, "{}", p.name);
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
        assert!((a - b).abs() <= 1e-9 * umax, "{}: {a} vs {b}", p.name);
    }
}

#[test]
fn a_3d_obstacle_problem_agrees_with_exhaustive_enumeration_and_gauss_seidel() {
    check_against_reference(&mesh(test_meshes::cubes(2, 4)), &obstacle(), true);
    check_against_reference(&mesh(test_meshes::tetrahedra(1, 5)), &obstacle(), true);
    check_against_reference(&mesh(test_meshes::cubes(4, 6)), &obstacle(), false);
}

#[test]
fn a_3d_signorini_problem_agrees_with_exhaustive_enumeration_and_gauss_seidel() {
    check_against_reference(&mesh(test_meshes::cubes(2, 7)), &signorini(), true);
    check_against_reference(&mesh(test_meshes::tetrahedra(2, 8)), &signorini(), true);
    check_against_reference(
        &mesh(test_meshes::perturbed_cubes(4, 0.1, 9)),
        &signorini(),
        false,
    );
}

/// On a mesh too coarse for a coarse level the nested start is skipped, with the reason in
/// the report, and the iteration runs from A₀ = ∅ to the cold start's solution.
#[test]
fn the_nested_warm_start_is_skipped_on_a_coarse_3d_mesh() {
    let m = mesh(test_meshes::cubes(2, 10));
    let s = hmm(&m);
    let nested = solve_problem(&s, &obstacle(), &SolveOptions::default()).unwrap();
    let report = nested.warm_start.as_ref().unwrap();
    let why = report.skipped.as_deref().unwrap_or_default();
    assert!(why.contains("too coarse"), "{report:?}");
    let cold = solve_problem(&s, &obstacle(), &SolveOptions::paper()).unwrap();
    assert_eq!(nested.result.active, cold.result.active);
    for (a, b) in nested.u().iter().zip(cold.u()) {
        assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
    }
}

/// The nested start on the obstacle problem and on the Signorini problem (its unknowns on
/// boundary faces, which the coarse meshes keep one to one, while they merge the Dirichlet
/// and the Neumann faces by plane) makes a coarse level and reaches
/// the cold start's solution, in no more fine solves.
#[test]
fn the_nested_warm_start_reaches_the_cold_solution_in_3d() {
    let m = mesh(test_meshes::cubes(12, 11));
    let s = hmm(&m);
    for p in [obstacle(), signorini()] {
        let nested = solve_problem(&s, &p, &SolveOptions::default()).unwrap();
        let report = nested.warm_start.as_ref().unwrap();
        assert!(
            report.skipped.is_none() && !report.levels.is_empty() && report.predicted_active > 0,
            "{}: {report:?}",
            p.name
        );
        let cold = solve_problem(&s, &p, &SolveOptions::paper()).unwrap();
        assert_eq!(nested.result.active, cold.result.active, "{}", p.name);
        assert!(nested.niter() <= cold.niter(), "{}", p.name);
        let umax = cold.u().iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for (a, b) in nested.u().iter().zip(cold.u()) {
            assert!((a - b).abs() <= 1e-10 * umax, "{}: {a} vs {b}", p.name);
        }
    }
}

/// The polish of a settled iterate (`vi::active_set::POLISH_RTOLS`): with the iterative solver
/// and a certificate tolerance of 1e-13, the iteration settles with residuals (maxima over
/// the unknowns) of about 1e-13 after CG stopped at its 2-norm target; the polished solve
/// passes the certificate, where it failed before the polish existed. The solution is that
/// of the direct solver to the tolerance.
#[test]
fn a_settled_iterative_solve_is_polished_to_a_tight_certificate() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let problem = crate::problem::file::load(root.join("problems/ex9-3d.toml"), &[])
        .unwrap()
        .problem_in::<3>()
        .unwrap();
    let side = [-2.0, 2.0];
    let domain = crate::mesh3d::Cuboid {
        x: side,
        y: side,
        z: side,
    };
    let m = mesh(crate::mesh3d::generate::cubes(16, domain, MemoryBudget::DEFAULT).unwrap());
    let s = hmm(&m);
    let tol = 1e-13;
    let mut opts = SolveOptions::default();
    opts.active_set.tol = tol;
    opts.system.linear = "iterative".parse().unwrap();
    let it = solve_problem(&s, &problem, &opts).unwrap();
    let c = it.result.certificate;
    assert!(c.worst() <= tol, "{c:?}");
    opts.system.linear = "direct".parse().unwrap();
    let direct = solve_problem(&s, &problem, &opts).unwrap();
    let diff = (it.u().iter().zip(direct.u()))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-10,
        "largest difference to the direct solve {diff:e}"
    );
    assert_eq!(it.result.active, direct.result.active);
}
