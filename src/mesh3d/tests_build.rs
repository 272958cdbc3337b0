//! Tests of [`PolyMesh3::from_polyhedra`] on valid meshes: the identities of the geometry
//! and HMM's consistency.

use super::geometry::{dot, sub};
use super::test_meshes::{cubes, dented_pair, tetrahedra};
use super::{Cuboid, PolyMesh3, Polyhedra};
use crate::budget::MemoryBudget;
use crate::mesh::NO_CELL;
use crate::mesh::complex::{CellComplex, VertexAverage};
use crate::scheme::hmm::local_form;
use nalgebra::DVector;

fn build(p: Polyhedra) -> PolyMesh3 {
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap()
}

/// max over cells of ‖Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ / |K| − I‖ (entrywise maximum).
pub(crate) fn consistency_defect(m: &PolyMesh3) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..m.n_cells() {
        let mut c = [[0.0; 3]; 3];
        let xk = m.centroid(k);
        for (i, &f) in m.cell_faces(k).iter().enumerate() {
            let f = f as usize;
            let (n, _) = m.cell_normal_dist(k, i);
            let xs = m.face_centroid(f);
            for r in 0..3 {
                for s in 0..3 {
                    c[r][s] += m.face_measure(f) * n[r] * (xs[s] - xk[s]);
                }
            }
        }
        for (r, row) in c.iter().enumerate() {
            for (s, v) in row.iter().enumerate() {
                let id = if r == s { 1.0 } else { 0.0 };
                worst = worst.max((v / m.measure(k) - id).abs());
            }
        }
    }
    worst
}

/// The identities every valid mesh satisfies: Σ|K| = `volume`, Σ_σ |σ| n_{K,σ} = 0 and
/// Σ_σ |σ| d_{K,σ} = 3|K| per cell, boundary area `area`, consistency to 1e-12.
fn check_identities(m: &PolyMesh3, volume: f64, area: f64) {
    let total: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    assert!((total - volume).abs() < 1e-12, "{total}");
    for k in 0..m.n_cells() {
        let (mut s, mut d3) = ([0.0; 3], 0.0);
        for (i, &f) in m.cell_faces(k).iter().enumerate() {
            let (n, d) = m.cell_normal_dist(k, i);
            let a = m.face_measure(f as usize);
            (0..3).for_each(|r| s[r] += a * n[r]);
            d3 += a * d;
            assert!(m.face_cells(f as usize).contains(&k));
        }
        assert!(s.iter().all(|x| x.abs() < 1e-12), "cell {k}: {s:?}");
        assert!((d3 - 3.0 * m.measure(k)).abs() < 1e-12, "cell {k}");
    }
    let b: f64 = m
        .boundary_faces()
        .iter()
        .map(|&f| m.face_measure(f as usize))
        .sum();
    assert!((b - area).abs() < 1e-12, "{b}");
    assert!(consistency_defect(m) < 1e-12, "{}", consistency_defect(m));
}

/// HMM's local form reproduces affine functions: W δ(u) = |σ| A∇u·n_{K,σ} on every face.
pub(crate) fn check_local_form(m: &PolyMesh3) {
    let a = [[3.0, 0.5, 0.2], [0.5, 2.0, 0.3], [0.2, 0.3, 1.0]];
    let grad = [2.0, -1.0, 0.5];
    let u = |p: [f64; 3]| 1.0 + (0..3).map(|r| grad[r] * p[r]).sum::<f64>();
    for k in 0..m.n_cells() {
        let w = local_form(m, k, &a, 1.0);
        let faces = m.cell_faces(k);
        let xk = m.centroid(k);
        let delta = DVector::from_iterator(
            faces.len(),
            faces
                .iter()
                .map(|&f| u(m.face_centroid(f as usize)) - u(xk)),
        );
        let wd = &w * delta;
        for (i, &f) in faces.iter().enumerate() {
            let n = m.cell_normal_dist(k, i).0;
            let flux: f64 = (0..3)
                .map(|r| n[r] * (0..3).map(|c| a[r][c] * grad[c]).sum::<f64>())
                .sum();
            let want = m.face_measure(f as usize) * flux;
            assert!((wd[i] - want).abs() < 1e-12, "cell {k} face {i}");
        }
    }
}

#[test]
fn cubes_have_exact_geometry() {
    for k in [1, 2, 3] {
        let m = build(cubes(k, 7 + k as u64));
        assert_eq!(m.n_cells(), k * k * k);
        assert_eq!(m.n_faces(), 3 * k * k * (k + 1));
        assert_eq!(m.boundary_faces().len(), 6 * k * k);
        check_identities(&m, 1.0, 6.0);
        check_local_form(&m);
        let h = 1.0 / k as f64;
        assert!((m.h() - 3f64.sqrt() * h).abs() < 1e-15);
        assert!((m.measure(0) - h * h * h).abs() < 1e-15);
        assert!((0..3).all(|r| (m.centroid(0)[r] - 0.5 * h).abs() < 1e-15));
        assert_eq!(m.bounding_box(), Cuboid::UNIT);
    }
}

#[test]
fn tetrahedra_have_exact_geometry() {
    let m = build(tetrahedra(2, 3));
    assert_eq!(m.n_cells(), 48);
    check_identities(&m, 1.0, 6.0);
    check_local_form(&m);
    // every tetrahedron of the Kuhn cut of a cube of side ½ has volume 1/48
    assert!((0..48).all(|k| (m.measure(k) - 1.0 / 48.0).abs() < 1e-15));
}

#[test]
fn a_non_convex_star_shaped_cell_is_accepted_and_consistent() {
    let m = build(dented_pair(0.3, 5));
    assert_eq!((m.n_cells(), m.n_faces()), (2, 14));
    let (lower, upper) = (0.5 - 0.2 / 3.0, 0.5 + 0.2 / 3.0);
    assert!((m.measure(0) - lower).abs() < 1e-15 && (m.measure(1) - upper).abs() < 1e-15);
    check_identities(&m, 1.0, 6.0);
    check_local_form(&m);
}

#[test]
fn faces_are_oriented_outward_from_their_first_cell() {
    let m = build(cubes(2, 11));
    for f in 0..m.n_faces() {
        let [a, b] = m.face_cells(f);
        let n = m.face_normal(f);
        let (xa, xs) = (m.centroid(a), m.face_centroid(f));
        assert!((0..3).map(|r| n[r] * (xs[r] - xa[r])).sum::<f64>() > 0.0);
        assert_eq!(b == NO_CELL, m.is_boundary_face(f));
        // the loop turns counter-clockwise around n: its vector area is |σ| n
        let l = m.face_vertices(f);
        let p = |i: usize| m.vertices()[l[i % l.len()] as usize];
        let mut va = [0.0; 3];
        for i in 0..l.len() {
            let c = super::geometry::cross(p(i), p(i + 1));
            (0..3).for_each(|r| va[r] += 0.5 * c[r]);
        }
        assert!((0..3).all(|r| (va[r] - m.face_measure(f) * n[r]).abs() < 1e-15));
    }
}

#[test]
fn to_polyhedra_gives_back_the_same_mesh_with_outward_loops_and_tags() {
    let mut p = cubes(2, 13);
    p.cell_tags = (0..8).collect();
    p.tagged_ptr = vec![0, 4];
    p.tagged_vertices = vec![0, 1, 4, 3];
    p.tagged_tags = vec![9];
    let m = build(p);
    let f0 = (0..m.n_faces()).find(|&f| m.face_tag(f) == 9).unwrap();
    assert!(m.is_boundary_face(f0) && m.face_centroid(f0)[2] == 0.0);
    assert_eq!((0..m.n_faces()).filter(|&f| m.face_tag(f) != 0).count(), 1);
    assert_eq!(m.cell_tag(5), 5);
    let q = m.to_polyhedra();
    assert_eq!(q.cell_tags, (0..8).collect::<Vec<_>>());
    assert_eq!(q.tagged_tags, vec![9]);
    let m2 = build(q.clone());
    assert_eq!(m2.to_polyhedra(), q);
    for k in 0..8 {
        assert_eq!(m2.measure(k), m.measure(k));
        assert_eq!(m2.centroid(k), m.centroid(k));
    }
    // every written loop is outward: the vector areas of a cell's loops give +|K| by the
    // divergence theorem with the centroid as apex
    for k in 0..8 {
        let mut vol = 0.0;
        for s in q.cell_sides(k) {
            let l = q.side_vertices(s);
            let p = |i: usize| q.vertices[l[i % l.len()] as usize];
            for i in 1..l.len() - 1 {
                let (a, b, c) = (p(0), p(i), p(i + 1));
                let x = m.centroid(k);
                let d = [0, 1, 2].map(|r| a[r] - x[r]);
                let e = super::geometry::cross(
                    [0, 1, 2].map(|r| b[r] - a[r]),
                    [0, 1, 2].map(|r| c[r] - a[r]),
                );
                vol += (0..3).map(|r| d[r] * e[r]).sum::<f64>() / 6.0;
            }
        }
        assert!((vol - m.measure(k)).abs() < 1e-15);
    }
}

#[test]
fn the_cell_complex_view_and_vertex_averages_match_the_accessors() {
    let m = build(tetrahedra(1, 17));
    let c: &dyn CellComplex<3> = &m;
    assert_eq!((c.n_cells(), c.n_faces()), (6, 18));
    for k in 0..6 {
        assert_eq!(c.cell_measure(k), m.measure(k));
        assert_eq!(c.cell_centre(k), m.centroid(k));
        for i in 0..4 {
            assert_eq!(c.cell_face_normal_dist(k, i), m.cell_normal_dist(k, i));
        }
    }
    // a constant is averaged to itself; cell index values give weighted means in range
    assert!(
        m.cell_average_at_vertices(&[2.5; 6])
            .iter()
            .all(|&v| (v - 2.5).abs() < 1e-15)
    );
    let avg = m.cell_average_at_vertices(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    assert_eq!(avg.len(), 8);
    // corner 0 and corner 7 belong to all six tetrahedra: the plain mean
    assert!((avg[0] - 2.5).abs() < 1e-15 && (avg[7] - 2.5).abs() < 1e-15);
}

#[test]
fn the_memory_estimate_is_checked_against_the_budget() {
    let p = cubes(2, 19);
    // the build before the boundary is known, then with the check of the boundary surface:
    // 24 boundary squares, 96 loop entries
    let need = super::mesh3_bytes(8, 48, 192, 27);
    let all = need + super::boundary_surface_bytes(96, 27);
    assert!(PolyMesh3::from_polyhedra(p.clone(), MemoryBudget::new(all)).is_ok());
    for (budget, asked) in [(need - 1, need), (need, all), (all - 1, all)] {
        let e = PolyMesh3::from_polyhedra(p.clone(), MemoryBudget::new(budget)).unwrap_err();
        assert!(
            matches!(e, crate::MeshError::TooLarge { bytes, .. } if bytes == asked),
            "{budget}: {e:?}"
        );
    }
}

#[test]
fn warped_faces_give_a_consistency_defect_of_the_order_of_their_warp() {
    // interior nodes of 4³ cubes moved by up to amp·h: planar faces no longer, the fan
    // geometry keeps Σ|K| = 1 and Σ_σ |σ| d_{K,σ} = 3|K| only approximately per cell
    for amp in [0.05, 0.1, 0.2] {
        let m = build(super::test_meshes::perturbed_cubes(4, amp, 23));
        let warp = (0..m.n_faces()).map(|f| m.face_warp(f)).fold(0.0, f64::max);
        let defect = consistency_defect(&m);
        let total: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
        eprintln!("amp {amp}: max warp {warp:.3e}, consistency defect {defect:.3e}");
        assert!((total - 1.0).abs() < 1e-12);
        assert!(
            warp > 0.1 * amp && defect > 1e-6 && defect < 2.0 * warp,
            "{warp} {defect}"
        );
    }
}

#[test]
fn the_face_geometry_of_a_cell_is_that_of_the_three_accessors_bit_for_bit() {
    // warped hexahedra, triangles and a dented (non-convex) pair: faces of 3 and 4 vertices
    let mut warped = cubes(2, 1);
    warped.vertices[13][2] += 0.05;
    for m in [
        build(warped),
        build(tetrahedra(2, 3)),
        build(dented_pair(0.3, 3)),
    ] {
        for k in 0..m.n_cells() {
            for i in 0..m.cell_faces(k).len() {
                let f = m.cell_faces(k)[i] as usize;
                let got = CellComplex::cell_face_geometry(&m, k, i, m.centroid(k));
                // n_{K,σ} and d_{K,σ} from the face's frame, as the accessors computed them
                let (centre, n) = m.face_frame(f);
                let normal = if m.face_cells(f)[0] == k {
                    n
                } else {
                    n.map(|x| -x)
                };
                let dist = dot(sub(centre, m.centroid(k)), normal);
                let bits = |x: [f64; 3]| x.map(f64::to_bits);
                assert_eq!(
                    (bits(got.normal), got.dist.to_bits()),
                    (bits(normal), dist.to_bits())
                );
                assert_eq!(got.measure.to_bits(), m.face_measure(f).to_bits());
                assert_eq!(bits(got.centre), bits(CellComplex::face_centre(&m, f)));
                assert_eq!(bits(got.centre), bits(centre));
                let (n2, d2) = CellComplex::cell_face_normal_dist(&m, k, i);
                assert_eq!(
                    (bits(n2), d2.to_bits()),
                    (bits(got.normal), got.dist.to_bits())
                );
                assert_eq!(bits(got.normal), bits(normal));
                assert_eq!(got.dist.to_bits(), dist.to_bits());
            }
        }
    }
}
