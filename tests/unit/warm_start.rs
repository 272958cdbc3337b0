//! The nested warm start: same certified solution as the cold iteration, fewer fine solves,
//! and a cold start with the reason when the domain is not a rectangle.

use crate::common::*;
use gradvi::mesh::generate::{cartesian, hexagonal};
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

#[test]
fn nested_obstacle_gives_the_cold_solution_in_fewer_solves() {
    // HMM on a 128 × 128 grid: the coarse levels are 32 × 32 (n = √N/4), too small to recurse
    let mesh = cartesian(128, 128).unwrap();
    let hmm = Hmm::new(&mesh);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-5.0));
    assert!(r.skipped.is_none(), "{:?}", r.skipped);
    assert_eq!(r.levels, vec![(32, 32)]);
    assert!(r.predicted_active > 0 && r.coarse_solves >= 2);
    assert!(nested < cold, "nested {nested} solves, cold {cold}");
    // P1 on a gmsh triangle mesh of the replication, and HMM on hexagons
    let tri = read_mesh(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/test3_4.msh")).unwrap();
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
    // 40 × 160 cells on [0,1] × [0,4]: nx = 10, ny = 40 coarse cells; a 256 × 256 grid
    // recurses once (64 × 64, then 16 × 16)
    let mesh = rect_grid(40, 160, 1.0, 4.0);
    let hmm = Hmm::new(&mesh);
    let p = paper_test3(-5.0).with_constraint(
        ConstraintKind::Obstacle,
        Side::Lower,
        Box::new(|x| test3_obstacle([x[0], x[1] / 4.0])),
    );
    let (_, _, r) = compare(&hmm, &p);
    assert_eq!(r.levels, vec![(10, 40)]);
    // (a cold solve of this size is slow in a debug build: the nested one is checked alone)
    let mesh = cartesian(256, 256).unwrap();
    let hmm = Hmm::new(&mesh);
    let nested = solve_problem(&hmm, &paper_test3(-5.0), &opts(WarmStart::Nested)).unwrap();
    nested.result.certificate.check(1e-10).unwrap();
    let r = nested.warm_start.unwrap();
    assert_eq!(r.levels, vec![(64, 64), (16, 16)]);
    assert!(nested.result.niter <= 8, "{} solves", nested.result.niter);
}

#[test]
fn nested_signorini_gives_the_cold_solution() {
    let mesh = cartesian(64, 64).unwrap();
    let hmm = Hmm::new(&mesh);
    let (_, _, r) = compare(&hmm, &paper_test1());
    assert!(r.skipped.is_none() && r.predicted_active > 0, "{r:?}");
    let tri = read_mesh(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/test1_3.msh")).unwrap();
    let p1 = P1::new(&tri).unwrap();
    let (_, _, r) = compare(&p1, &paper_test1());
    assert!(r.skipped.is_none() && r.predicted_active > 0, "{r:?}");
}

#[test]
fn nested_on_a_non_rectangular_domain_starts_cold_and_says_why() {
    // an L-shaped domain: the 64 × 64 grid without its upper-right quarter
    let full = cartesian(64, 64).unwrap();
    let cells: Vec<Vec<usize>> = (0..full.n_cells())
        .filter(|&k| {
            let c = full.centroid(k);
            !(c[0] > 0.5 && c[1] > 0.5)
        })
        .map(|k| full.cell_vertices(k).to_vec())
        .collect();
    let (vertices, cells, _) = drop_unused_vertices(full.vertices(), &cells);
    let mesh = PolyMesh::from_cells(vertices, cells).unwrap();
    let hmm = Hmm::new(&mesh);
    let (cold, nested, r) = compare(&hmm, &paper_test3(-5.0));
    let why = r.skipped.expect("no prediction on an L-shaped domain");
    assert!(why.contains("rectangular"), "{why}");
    assert_eq!(cold, nested);
    // and on a mesh too coarse to have a coarser level
    let small = cartesian(12, 12).unwrap();
    let hmm = Hmm::new(&small);
    let (_, _, r) = compare(&hmm, &paper_test3(-5.0));
    assert!(r.skipped.expect("too coarse").contains("too coarse"));
}

#[test]
fn warm_start_names() {
    assert!("warm".parse::<WarmStart>().is_err());
    assert_eq!("nested".parse::<WarmStart>().unwrap(), WarmStart::Nested);
}
