//! The nested warm start (coarse HMM solves on agglomerated meshes): same certified solution
//! as the cold iteration, fewer fine solves, on any domain; a cold start with the reason when
//! the mesh is too coarse.

use crate::common::*;
use gradvi::budget::MemoryBudget;
use gradvi::mesh::generate::{cartesian, cartesian_triangles, hexagonal};
use gradvi::mesh::io::read_mesh;
use gradvi::mesh::{PolyMesh, drop_unused_vertices};
use gradvi::problem::*;
use gradvi::scheme::*;
use gradvi::solver::*;
use std::path::Path;

fn opts(warm_start: WarmStart) -> SolveOptions {
    SolveOptions {
        warm_start,
        ..Default::default()
    }
}

/// Solves cold and nested, checks both certificates, the same active set and the same u, and
/// returns (cold NITER, nested NITER, the nested report).
fn compare(scheme: &dyn GradientDiscretisation, p: &Problem) -> (usize, usize, WarmStartReport) {
    let cold = solve_problem(scheme, p, &opts(WarmStart::Cold)).unwrap();
    let nested = solve_problem(scheme, p, &opts(WarmStart::Nested)).unwrap();
    assert!(cold.warm_start.is_none());
    cold.result.certificate.check(1e-10).unwrap();
    nested.result.certificate.check(1e-10).unwrap();
    assert_eq!(cold.result.active, nested.result.active);
    assert_close(cold.u(), nested.u(), 1e-12, "cold and nested");
    let report = nested.warm_start.clone().expect("a nested solve reports");
    (cold.niter(), nested.niter(), report)
}

/// The coarse levels have the sizes the hierarchy aims at, within a factor 1.6 (aggregates
/// follow the fine cells): (fine skeleton unknowns)/24 cells, then 16 times fewer per level.
fn assert_levels(r: &WarmStartReport, unknowns: usize, n_levels: usize) {
    assert_eq!(r.levels.len(), n_levels, "{r:?}");
    let mut target = (unknowns / warm_start::FIRST_LEVEL_UNKNOWNS_PER_CELL) as f64;
    for &n in &r.levels {
        assert!(
            n as f64 >= target / 1.6 && n as f64 <= target * 1.6,
            "{n} coarse cells, aimed at {target}: {r:?}"
        );
        target = n as f64 / warm_start::RATIO as f64;
    }
}

#[test]
fn nested_obstacle_gives_the_cold_solution_in_fewer_solves() {
    // HMM on a 128 × 128 grid: one coarse level of about a 12th of its cells (its skeleton
    // unknowns / 24), too small to recurse
    let mesh = cartesian(128, 128).unwrap();
    let hmm = Hmm::new(&mesh);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-5.0));
    assert!(r.skipped.is_none(), "{:?}", r.skipped);
    assert_levels(&r, hmm.n_skeleton(), 1);
    assert!(r.predicted_active > 0 && r.coarse_solves >= 2);
    assert!(nested < cold, "nested {nested} solves, cold {cold}");
    // P1 on a gmsh triangle mesh of the replication, and HMM on hexagons
    let tri = read_mesh(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/test3_4.msh"),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    let p1 = P1::new(&tri).unwrap();
    let (cold, nested, r) = compare(&p1, &paper_test3(-5.0));
    assert!(
        r.skipped.is_none() && nested < cold,
        "{cold} {nested} {r:?}"
    );
    let hex = hexagonal(4).unwrap();
    let hmm = Hmm::new(&hex);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-10.0));
    assert!(
        r.skipped.is_none() && nested < cold,
        "{cold} {nested} {r:?}"
    );
}

#[test]
fn nested_recurses_and_handles_rectangles() {
    // 40 × 160 cells on [0,1] × [0,4]: one level; a 256 × 256 grid recurses once
    let mesh = rect_grid(40, 160, 1.0, 4.0);
    let hmm = Hmm::new(&mesh);
    let p = paper_test3(-5.0).with_constraint(
        ConstraintKind::Obstacle,
        Side::Lower,
        Box::new(|x| test3_obstacle([x[0], x[1] / 4.0])),
    );
    let (_, _, r) = compare(&hmm, &p);
    assert_levels(&r, hmm.n_skeleton(), 1);
    // (a cold solve of this size is slow in a debug build: the nested one is checked alone)
    let mesh = cartesian(256, 256).unwrap();
    let hmm = Hmm::new(&mesh);
    let nested = solve_problem(&hmm, &paper_test3(-5.0), &opts(WarmStart::Nested)).unwrap();
    nested.result.certificate.check(1e-10).unwrap();
    let r = nested.warm_start.unwrap();
    assert_levels(&r, hmm.n_skeleton(), 2);
    assert!(nested.result.niter <= 8, "{} solves", nested.result.niter);
}

#[test]
fn nested_signorini_gives_the_cold_solution() {
    let mesh = cartesian(64, 64).unwrap();
    let hmm = Hmm::new(&mesh);
    let (_, _, r) = compare(&hmm, &paper_test1());
    assert!(r.skipped.is_none() && r.predicted_active > 0, "{r:?}");
    let tri = read_mesh(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/test1_3.msh"),
        gradvi::budget::MemoryBudget::DEFAULT,
    )
    .unwrap();
    let p1 = P1::new(&tri).unwrap();
    let (_, _, r) = compare(&p1, &paper_test1());
    assert!(r.skipped.is_none() && r.predicted_active > 0, "{r:?}");
}

/// The L-shaped domain: `full`, a mesh of the unit square, without its upper-right quarter.
fn l_shape(full: &PolyMesh) -> PolyMesh {
    let cells: Vec<Vec<usize>> = (0..full.n_cells())
        .filter(|&k| {
            let c = full.centroid(k);
            !(c[0] > 0.5 && c[1] > 0.5)
        })
        .map(|k| full.cell_vertices(k).iter().map(|&v| v as usize).collect())
        .collect();
    let (vertices, cells, _) = drop_unused_vertices(full.vertices(), &cells);
    PolyMesh::from_cells(vertices, cells).unwrap()
}

#[test]
fn nested_works_on_any_domain() {
    // an L-shaped domain: the 64 × 64 grid without its upper-right quarter
    let mesh = l_shape(&cartesian(64, 64).unwrap());
    let hmm = Hmm::new(&mesh);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-5.0));
    assert!(r.skipped.is_none(), "{r:?}");
    assert_levels(&r, hmm.n_skeleton(), 1);
    assert!(nested < cold, "nested {nested} solves, cold {cold}");
    // P1 on the same L-shape cut into triangles (finer: P1 has one unknown per two cells)
    let tri = l_shape(&cartesian_triangles(96, 96, [0.0, 1.0], [0.0, 1.0]).unwrap());
    let p1 = P1::new(&tri).unwrap();
    let (cold, nested, r) = compare(&p1, &paper_test3(-5.0));
    assert!(r.skipped.is_none() && r.predicted_active > 0, "{r:?}");
    assert_levels(&r, p1.n_skeleton(), 1);
    assert!(nested < cold, "P1: nested {nested} solves, cold {cold}");
    // gmsh triangles of an L-shape and of a domain with a hole (the example problems), HMM
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    for (file, msh) in [("lshape-obstacle", "lshape"), ("hole-obstacle", "hole")] {
        let pf = gradvi::problem::file::load(dir.join(format!("{file}.toml")), &[]).unwrap();
        let mesh = read_mesh(
            dir.join(format!("{msh}.msh")),
            gradvi::budget::MemoryBudget::DEFAULT,
        )
        .unwrap();
        let hmm = Hmm::new(&mesh);
        let (cold, nested, r) = compare(&hmm, &pf.problem());
        assert!(
            r.skipped.is_none() && r.predicted_active > 0,
            "{file}: {r:?}"
        );
        assert!(
            nested <= cold,
            "{file}: nested {nested} solves, cold {cold}"
        );
    }
}

/// The guess the prediction carries is the coarse solution on the fine unknowns: within a
/// coarse-mesh error of the fine solution, far closer than the zero start, for P1 (vertex
/// unknowns) and HMM (edge unknowns); its length is the number of skeleton unknowns.
#[test]
fn the_prediction_carries_a_first_guess() {
    use gradvi::assembly::DiscreteSystem;
    let p = paper_test3(-5.0);
    let tri = cartesian_triangles(96, 96, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let quads = cartesian(96, 96).unwrap();
    let p1 = P1::new(&tri).unwrap();
    let hmm = Hmm::new(&quads);
    for scheme in [&p1 as &dyn GradientDiscretisation, &hmm] {
        let system = DiscreteSystem::new(scheme, &p, Default::default()).unwrap();
        let cons = constraints::build(&system, &p).unwrap().unwrap();
        let pred = warm_start::predict(scheme, &p, &cons, MemoryBudget::DEFAULT, None).unwrap();
        assert_eq!(pred.guess.len(), scheme.n_skeleton());
        let fine = solve_problem(scheme, &p, &opts(WarmStart::Cold)).unwrap();
        let u = &fine.u()[..scheme.n_skeleton()];
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
        let err = norm(&mut u.iter().zip(&pred.guess).map(|(a, b)| a - b));
        let size = norm(&mut u.iter().copied());
        assert!(
            err < 0.1 * size,
            "{}: |guess - u| = {err:.3e}, |u| = {size:.3e}",
            scheme.name()
        );
    }
}

#[test]
fn nested_on_a_coarse_mesh_starts_cold_and_says_why() {
    let small = cartesian(12, 12).unwrap();
    let hmm = Hmm::new(&small);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-5.0));
    assert!(r.skipped.expect("too coarse").contains("too coarse"));
    assert_eq!(cold, nested);
}

#[test]
fn warm_start_names() {
    assert!("warm".parse::<WarmStart>().is_err());
    assert_eq!("nested".parse::<WarmStart>().unwrap(), WarmStart::Nested);
}

/// The driver runs the coarse solves beside the fine setup (`solver` module docs): its
/// prediction is the one [`warm_start::predict`] makes after the setup, with the same first
/// guess, in a pool of one thread (the branches one after the other) and of two (side by
/// side); and a fine setup that fails returns its own error, not the coarse solves'.
#[test]
fn coarse_solves_beside_the_setup_predict_as_in_sequence() {
    use gradvi::assembly::DiscreteSystem;
    let p = paper_test3(-5.0);
    let tri = cartesian_triangles(96, 96, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let p1 = P1::new(&tri).unwrap();
    let system = DiscreteSystem::new(&p1, &p, Default::default()).unwrap();
    let cons = constraints::build(&system, &p).unwrap().unwrap();
    let pred = warm_start::predict(&p1, &p, &cons, MemoryBudget::DEFAULT, None).unwrap();
    assert!(pred.report.coarse_solves > 0 && pred.report.predicted_active > 0);
    // coarse solves made on another mesh are refused, not indexed out of bounds
    let other = cartesian_triangles(80, 80, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let unknowns = P1::new(&other).unwrap().n_unknowns();
    let coarse = warm_start::coarse_solves(&other, unknowns, &p, MemoryBudget::DEFAULT, None);
    let e = warm_start::predict_from(coarse.unwrap(), &p1, &p, &cons).err();
    assert!(
        e.as_deref()
            .is_some_and(|e| e.contains("coarse solves made on a mesh")),
        "{e:?}"
    );
    let pool = |t: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    // Dirichlet data 0 above a barrier −1: the fine setup refuses the empty convex set
    let infeasible = paper_test3(-5.0).with_constraint(
        ConstraintKind::Obstacle,
        Side::Upper,
        Box::new(|_: gradvi::mesh::Point| -1.0),
    );
    for t in [1, 2] {
        let sol = pool(t)
            .install(|| solve_problem(&p1, &p, &opts(WarmStart::Nested)))
            .unwrap();
        sol.result.certificate.check(1e-10).unwrap();
        let r = sol.warm_start.clone().expect("a nested solve reports");
        assert_eq!(r.skipped, None, "{t} threads");
        assert_eq!(
            (&r.levels, r.coarse_solves, r.predicted_active),
            (
                &pred.report.levels,
                pred.report.coarse_solves,
                pred.report.predicted_active
            ),
            "{t} threads"
        );
        // the first solve started from the predicted active set
        let first = &sol.result.log[0].step;
        assert_eq!(first.active, pred.report.predicted_active, "{t} threads");
        let e = pool(t)
            .install(|| solve_problem(&p1, &infeasible, &opts(WarmStart::Nested)))
            .err()
            .expect("an empty convex set");
        assert!(
            matches!(e, gradvi::Error::Infeasible(_)),
            "{t} threads: {e}"
        );
    }
}
