//! Tests of the 3D generators through the validated mesh: every family builds, with the
//! geometry of the box and the identities of the HMM consistency.

use super::*;
use crate::mesh3d::{Point3, WARP_TOL};

/// Σ_K |K| = |box|, the boundary faces' area that of the box, Σ_σ |σ| n_{K,σ} = 0 for every
/// cell and Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ = |K| I, to 1e-12 (relative to h_K² and |K|) when
/// `planar`. On warped faces |σ| (the fan's area) exceeds |Σ_T |T| n_T| by O(warp²)|σ| and the
/// consistency defect below twice the warp (see [`validate`](crate::mesh3d::validate)): then
/// the flux is checked below [`WARP_TOL`]² Σ_σ |σ| and the defect below 2 [`WARP_TOL`] (components of C_K scaled by the box's aspect ratios, which
/// stretch them). Returns the largest number of faces of a cell.
fn check_geometry(m: &PolyMesh3, domain: Cuboid, planar: bool) -> usize {
    let volume: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    assert!(
        (volume - domain.volume()).abs() < 1e-12 * domain.volume(),
        "{volume}"
    );
    let len = domain.ranges().map(|r| r[1] - r[0]);
    let [a, b, c] = len;
    let box_area = 2.0 * (a * b + b * c + c * a);
    let area: f64 = m
        .boundary_faces()
        .iter()
        .map(|&f| m.face_measure(f as usize))
        .sum();
    assert!((area - box_area).abs() < 1e-12 * box_area, "{area}");
    let mut max_faces = 0;
    for k in 0..m.n_cells() {
        let (vol, x_k) = (m.measure(k), m.centroid(k));
        let h = m.diameter(k);
        let mut flux = [0.0; 3];
        let mut surface = 0.0;
        let mut c_k = [[0.0; 3]; 3];
        let faces = m.cell_faces(k);
        max_faces = max_faces.max(faces.len());
        for (i, &f) in faces.iter().enumerate() {
            let (n, d) = m.cell_normal_dist(k, i);
            assert!(d > 0.0, "cell {k} face {i}: d = {d}");
            let (area, x_f): (f64, Point3) =
                (m.face_measure(f as usize), m.face_centroid(f as usize));
            surface += area;
            for r in 0..3 {
                flux[r] += area * n[r];
                for s in 0..3 {
                    c_k[r][s] += area * n[r] * (x_f[s] - x_k[s]);
                }
            }
        }
        for r in 0..3 {
            let tol = if planar {
                1e-12 * h * h
            } else {
                WARP_TOL * WARP_TOL * surface
            };
            assert!(
                flux[r].abs() < tol,
                "cell {k}: flux {flux:?}, area {surface}"
            );
            for s in 0..3 {
                // C_K[r][s] scales as |K| L_s / L_r when the box is stretched
                let scale = len[r] / len[s] / vol;
                let defect = (c_k[r][s] - if r == s { vol } else { 0.0 }).abs() * scale;
                let tol = if planar { 1e-12 } else { 2.0 * WARP_TOL };
                assert!(
                    defect < tol,
                    "cell {k}: C_K[{r}][{s}] off |K| I by {defect:e} |K|"
                );
            }
        }
    }
    max_faces
}

#[test]
fn every_family_builds_at_levels_1_to_3_with_the_geometry_of_the_box() {
    let boxes = [
        Cuboid::UNIT,
        Cuboid::new([-1.0, 2.0], [0.5, 0.75], [10.0, 12.0]),
    ];
    for f in Family3::ALL {
        for level in 1..=3 {
            for domain in boxes {
                let m = match f.generate_on(level, domain, MemoryBudget::DEFAULT) {
                    Ok(m) => m,
                    Err(e) => panic!("{f} level {level} on {domain}: {e}"),
                };
                assert_eq!(m.n_cells(), f.cells_at_level(level), "{f} {level}");
                assert_eq!(m.bounding_box(), domain, "{f} {level}");
                let faces = check_geometry(&m, domain, f != Family3::Warped);
                match f {
                    Family3::Refined => assert_eq!(faces, 24, "{f} {level}"),
                    Family3::Kuhn => assert_eq!(faces, 4),
                    Family3::Prisms => assert_eq!(faces, 5),
                    Family3::Cubes | Family3::Warped => assert_eq!(faces, 6),
                }
            }
        }
    }
}

#[test]
fn generate_is_the_unit_cube_and_counts_the_build_in_its_budget() {
    for f in Family3::ALL {
        let m = f.generate(1, MemoryBudget::DEFAULT).unwrap();
        let p = f.polyhedra(1, Cuboid::UNIT, MemoryBudget::DEFAULT).unwrap();
        assert_eq!(m.n_vertices(), p.vertices.len(), "{f}");
        assert_eq!(m.bounding_box(), Cuboid::UNIT);
        let estimate = f.memory_estimate(1);
        assert!(estimate > f.polyhedra_estimate(1));
        assert!(f.generate(1, MemoryBudget::new(estimate)).is_ok(), "{f}");
        match f.generate(1, MemoryBudget::new(estimate - 1)) {
            Err(Error::InvalidMesh(crate::MeshError::TooLarge { bytes, .. })) => {
                assert_eq!(bytes, estimate)
            }
            r => panic!("{f}: {r:?}"),
        }
        let e = f
            .generate(f.max_level() + 1, MemoryBudget::DEFAULT)
            .unwrap_err();
        assert!(matches!(e, Error::InvalidData(_)), "{e}");
    }
}
