//! Deterministic in the thread count: the same input gives bitwise the same solution and the
//! same NITER with 1, 2 and 4 threads. Each run builds the mesh, the scheme and the solve
//! inside its own rayon pool (`ThreadPool::install`, as `RAYON_NUM_THREADS` would set the
//! global one), in 2D (HMM on rectangles, whose iterative solves take the cell system, and on
//! Kershaw's distorted quadrangles, whose iterative solves take the skeleton system; P1 on
//! triangles) and in 3D (HMM on Kuhn tetrahedra), with the direct and the iterative linear
//! solver.
//!
//! The meshes are large enough for every parallel path of the pipeline to split its work:
//! more than 2 × 4096 items for the loops split with `with_min_len(4096)` (assembly, gathers,
//! conjugate gradients), more than 32768 rows for the parallel transposition of the condensed
//! matrix (`linalg::csr`, chunks of 16384 rows) and more than 2^15 keys for the parallel sorts
//! of the mesh build.
//!
//! The four tests take about 25 s together in the test profile; they run in `make test` (and
//! alone in `make determinism`).

use gradvi::assembly::{LinearSolver, SystemOptions};
use gradvi::budget::MemoryBudget;
use gradvi::mesh::generate::{cartesian, cartesian_triangles, kershaw};
use gradvi::mesh3d::PolyMesh3;
use gradvi::mesh3d::generate::Family3;
use gradvi::problem::{ConstraintKind, Problem, Side, paper_test3};
use gradvi::scheme::{Hmm, P1};
use gradvi::solver::{SolveOptions, WarmStart, solve_problem};

/// The thread counts compared.
const THREADS: [usize; 3] = [1, 2, 4];

/// What a run gives: the bits of u and NITER.
type Run = (Vec<u64>, usize);

/// Runs `solve` in a pool of each of [`THREADS`] threads and checks that every run gives the
/// bits and the NITER of the first; returns NITER.
fn same_in_every_pool(what: &str, solve: impl Fn() -> Run + Sync) -> usize {
    let runs: Vec<Run> = THREADS
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(&solve)
        })
        .collect();
    let (u1, n1) = &runs[0];
    assert!(!u1.is_empty(), "{what}: no unknowns");
    for (t, (u, n)) in THREADS.iter().zip(&runs).skip(1) {
        assert_eq!(
            n, n1,
            "{what}: NITER with {t} threads differs from 1 thread"
        );
        assert_eq!(u.len(), u1.len(), "{what}: {t} threads");
        let first = u.iter().zip(u1).position(|(a, b)| a != b);
        assert_eq!(
            first, None,
            "{what}: with {t} threads u differs from 1 thread at unknown {first:?}"
        );
    }
    *n1
}

/// The options of a solve with the `linear` solver and the warm start `ws`.
fn opts(linear: LinearSolver, ws: WarmStart) -> SolveOptions {
    SolveOptions {
        warm_start: ws,
        system: SystemOptions {
            linear,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The bits of `u`.
fn bits(u: &[f64]) -> Vec<u64> {
    u.iter().map(|x| x.to_bits()).collect()
}

const LINEAR: [LinearSolver; 2] = [LinearSolver::Direct, LinearSolver::Iterative];

/// Test 3 (C = −20) on 128 × 128 squares (16384 cells, 33024 faces) with HMM: direct, and
/// iterative on the cell system (rectangles, isotropic tensor); the nested start and the cold
/// start.
#[test]
fn hmm_on_squares_is_deterministic_in_the_thread_count() {
    for linear in LINEAR {
        for ws in [WarmStart::Nested, WarmStart::Cold] {
            let what = format!("HMM, 128² squares, {linear}, {ws:?}");
            let niter = same_in_every_pool(&what, || {
                let m = cartesian(128, 128).unwrap();
                let s = Hmm::new(&m);
                let sol = solve_problem(&s, &paper_test3(-20.0), &opts(linear, ws)).unwrap();
                if linear == LinearSolver::Iterative {
                    assert!(sol.cell_system.is_some(), "{linear}: not the cell system");
                }
                (bits(sol.u()), sol.niter())
            });
            assert!(niter > 1, "{what}: {niter} solves");
        }
    }
}

/// Test 3 on the Kershaw mesh of level 8 (136² distorted quadrangles) with HMM: direct, and
/// iterative on the skeleton system.
#[test]
fn hmm_on_kershaw_quadrangles_is_deterministic_in_the_thread_count() {
    for linear in LINEAR {
        let what = format!("HMM, Kershaw level 8, {linear}");
        let niter = same_in_every_pool(&what, || {
            let m = kershaw(8).unwrap();
            let s = Hmm::new(&m);
            let o = opts(linear, WarmStart::Nested);
            let sol = solve_problem(&s, &paper_test3(-20.0), &o).unwrap();
            assert!(sol.cell_system.is_none(), "{what}: the cell system");
            (bits(sol.u()), sol.niter())
        });
        assert!(niter > 1, "{what}: {niter} solves");
    }
}

/// Test 3 on 200 × 200 squares cut into 80000 triangles (40401 vertices) with P1.
#[test]
fn p1_on_triangles_is_deterministic_in_the_thread_count() {
    for linear in LINEAR {
        let what = format!("P1, 200² × 2 triangles, {linear}");
        let niter = same_in_every_pool(&what, || {
            let m = cartesian_triangles(200, 200, [0.0, 1.0], [0.0, 1.0]).unwrap();
            let s = P1::new(&m).unwrap();
            let o = opts(linear, WarmStart::Nested);
            let sol = solve_problem(&s, &paper_test3(-20.0), &o).unwrap();
            (bits(sol.u()), sol.niter())
        });
        assert!(niter > 1, "{what}: {niter} solves");
    }
}

/// −Δu ≥ −20, u ≥ ψ = −0.05 − 1.2 x, u = 0 on ∂Ω on the unit cube (the obstacle problem of the
/// 3D solver tests) with HMM on the Kuhn tetrahedra of level 3 (6 · 16³ = 24576 cells, 50688
/// faces), cold start (the nested start is planar), direct and iterative.
#[test]
fn hmm_on_tetrahedra_is_deterministic_in_the_thread_count() {
    for linear in LINEAR {
        let what = format!("HMM, Kuhn tetrahedra level 3, {linear}");
        let niter = same_in_every_pool(&what, || {
            let m: PolyMesh3 = Family3::Kuhn.generate(3, MemoryBudget::DEFAULT).unwrap();
            let s = Hmm::<PolyMesh3, 3>::with_alpha(&m, 1.0).unwrap();
            let p = Problem::<3>::new("obstacle-3d", Box::new(|_| -20.0)).with_constraint(
                ConstraintKind::Obstacle,
                Side::Lower,
                Box::new(|x| -0.05 - 1.2 * x[0]),
            );
            let sol = solve_problem(&s, &p, &opts(linear, WarmStart::Cold)).unwrap();
            (bits(sol.u()), sol.niter())
        });
        assert!(niter > 1, "{what}: {niter} solves");
    }
}
