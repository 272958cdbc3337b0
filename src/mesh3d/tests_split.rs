//! Tests of [`WarpedFaces`]: warped faces split into their fan triangles give an exactly
//! consistent mesh of the same cells; [`WarpedFaces::Fan`] leaves meshes as they were.

use super::generate::Family3;
use super::test_meshes::{cubes, perturbed_cubes};
use super::tests_build::{check_local_form, consistency_defect};
use super::{PLANAR_TOL, PolyMesh3, Polyhedra, WarpedFaces};
use crate::budget::MemoryBudget;
use crate::error::MeshError;

fn build(p: Polyhedra, w: WarpedFaces) -> PolyMesh3 {
    PolyMesh3::from_polyhedra_with(p, MemoryBudget::DEFAULT, w).unwrap()
}

/// Σ_K |K|.
fn total_volume(m: &PolyMesh3) -> f64 {
    (0..m.n_cells()).map(|k| m.measure(k)).sum()
}

/// The faces `fan` splits, and the faces and vertices splitting them adds: Σ (m_σ − 1), and
/// one per face.
fn expected_growth(fan: &PolyMesh3) -> (usize, usize, usize) {
    let warped = fan.faces_to_split();
    let faces = warped
        .iter()
        .map(|&f| fan.face_vertices(f as usize).len() - 1)
        .sum();
    (warped.len(), faces, warped.len())
}

/// `split` is `fan` with its warped faces split: same cells (volumes and centroids to
/// round-off, tags), the expected numbers of faces and vertices, every face planar, HMM's
/// consistency and local form exact.
fn check_split(fan: &PolyMesh3, split: &PolyMesh3) {
    let (n_warped, faces, vertices) = expected_growth(fan);
    assert!(n_warped > 0);
    assert_eq!(split.n_faces(), fan.n_faces() + faces);
    assert_eq!(split.n_vertices(), fan.n_vertices() + vertices);
    assert_eq!(split.n_cells(), fan.n_cells());
    assert!((total_volume(split) - total_volume(fan)).abs() < 1e-12);
    for k in 0..fan.n_cells() {
        assert!(
            (split.measure(k) - fan.measure(k)).abs() < 1e-14,
            "cell {k}"
        );
        let (a, b) = (split.centroid(k), fan.centroid(k));
        assert!((0..3).all(|r| (a[r] - b[r]).abs() < 1e-14), "cell {k}");
        assert_eq!(split.cell_tag(k), fan.cell_tag(k));
    }
    assert!(split.faces_to_split().is_empty());
    let defect = consistency_defect(split);
    assert!(defect < 1e-12, "consistency defect {defect:e}");
    check_local_form(split);
}

#[test]
fn the_warped_family_split_is_exactly_consistent_at_levels_1_to_3() {
    for level in 1..=3 {
        let p = Family3::Warped
            .polyhedra(level, super::Cuboid::UNIT, MemoryBudget::DEFAULT)
            .unwrap();
        let fan = build(p.clone(), WarpedFaces::Fan);
        assert!(consistency_defect(&fan) > 1e-5);
        let split = build(p, WarpedFaces::Split);
        check_split(&fan, &split);
        eprintln!(
            "level {level}: faces {} -> {}, consistency defect {:.3e} -> {:.3e}",
            fan.n_faces(),
            split.n_faces(),
            consistency_defect(&fan),
            consistency_defect(&split)
        );
        // every interior face of the warped family is warped, every boundary face planar
        let n = 1usize << (level + 1);
        assert_eq!(fan.faces_to_split().len(), 3 * n * n * (n - 1));
        assert_eq!(split.boundary_faces().len(), 6 * n * n);
    }
}

#[test]
fn split_boundary_faces_keep_their_tags_and_area() {
    // 2³ cubes with the centre of the bottom face (node 4 of the 3³ grid) lifted: the four
    // bottom faces around it are warped; they are tagged 5, a planar top face 7
    let mut p = cubes(2, 31);
    p.vertices[4][2] = 0.05;
    let bottom = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];
    p.tagged_ptr = (0..=5).map(|i| 4 * i).collect();
    p.tagged_vertices = bottom.iter().flatten().copied().collect();
    p.tagged_vertices.extend([18, 19, 22, 21]);
    p.tagged_tags = vec![5, 5, 5, 5, 7];
    let fan = build(p.clone(), WarpedFaces::Fan);
    let split = build(p, WarpedFaces::Split);
    check_split(&fan, &split);
    assert_eq!(fan.faces_to_split().len(), 4);
    let tagged = |m: &PolyMesh3, tag: i32| -> (usize, f64) {
        let faces: Vec<usize> = m
            .boundary_faces()
            .iter()
            .map(|&f| f as usize)
            .filter(|&f| m.face_tag(f) == tag)
            .collect();
        (faces.len(), faces.iter().map(|&f| m.face_measure(f)).sum())
    };
    let (n5, a5) = tagged(&split, 5);
    assert_eq!((n5, tagged(&fan, 5).0), (16, 4));
    assert!((a5 - tagged(&fan, 5).1).abs() < 1e-15);
    assert_eq!(tagged(&split, 7), tagged(&fan, 7));
    assert_eq!(tagged(&split, 0).0, tagged(&fan, 0).0);
}

#[test]
fn split_meshes_are_fan_meshes_of_the_perturbed_cubes_too() {
    for amp in [0.05, 0.2] {
        let p = perturbed_cubes(3, amp, 37);
        let fan = build(p.clone(), WarpedFaces::Fan);
        check_split(&fan, &build(p, WarpedFaces::Split));
    }
}

#[test]
fn the_fan_convention_and_planar_meshes_are_left_unchanged() {
    let p = perturbed_cubes(2, 0.1, 41);
    let plain = PolyMesh3::from_polyhedra(p.clone(), MemoryBudget::DEFAULT).unwrap();
    let fan = build(p, WarpedFaces::Fan);
    assert_eq!(WarpedFaces::default(), WarpedFaces::Fan);
    assert_eq!(plain.to_polyhedra(), fan.to_polyhedra());
    assert!((0..plain.n_faces()).all(|f| plain.face_centroid(f) == fan.face_centroid(f)));
    // planar cubes: nothing to split, the same mesh back
    let cubes = build(cubes(2, 43), WarpedFaces::Fan);
    assert!(cubes.faces_to_split().is_empty());
    let again = WarpedFaces::Split
        .apply(cubes.clone(), MemoryBudget::DEFAULT)
        .unwrap();
    assert_eq!(again.to_polyhedra(), cubes.to_polyhedra());
    assert!((0..cubes.n_faces()).all(|f| cubes.face_warp(f) <= PLANAR_TOL));
}

#[test]
fn splitting_is_refused_beyond_the_memory_budget() {
    let fan = build(perturbed_cubes(3, 0.1, 47), WarpedFaces::Fan);
    let e = fan.split_warped_faces(MemoryBudget::new(1000)).unwrap_err();
    assert!(matches!(e, MeshError::TooLarge { .. }), "{e:?}");
}

#[test]
fn conventions_are_parsed_by_name() {
    for w in WarpedFaces::ALL {
        assert_eq!(w.name().parse::<WarpedFaces>().unwrap(), w);
        assert_eq!(w.to_string(), w.name());
    }
    assert_eq!(
        " Split ".parse::<WarpedFaces>().unwrap(),
        WarpedFaces::Split
    );
    let e = "planar".parse::<WarpedFaces>().unwrap_err().to_string();
    assert!(e.contains("\"fan\" or \"split\""), "{e}");
}
