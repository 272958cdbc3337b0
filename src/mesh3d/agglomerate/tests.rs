//! Tests of [`agglomerate3`](super::agglomerate3).

use super::{Agglomeration3, KEEP, MAX_SPLITS, NO_FACE, agglomerate3, agglomerate3_merging};
use crate::budget::MemoryBudget;
use crate::error::MeshError;
use crate::mesh3d::test_meshes::{cubes, perturbed_cubes, tetrahedra};
use crate::mesh3d::{Point3, PolyMesh3, Polyhedra};

fn mesh(p: Polyhedra) -> PolyMesh3 {
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap()
}

/// The boundary of the unit cube tagged 1..6 by side (x = 0, x = 1, y = 0, ...).
fn side_tags(m: &PolyMesh3) -> PolyMesh3 {
    m.with_boundary_tags(|x: Point3| {
        let (axis, d) = (0..3)
            .map(|r| (r, x[r].min(1.0 - x[r])))
            .fold((0, f64::INFINITY), |b, c| if c.1 < b.1 { c } else { b });
        assert!(d < 1e-12, "{x:?} is not on the boundary");
        1 + 2 * axis as i32 + i32::from(x[axis] > 0.5)
    })
}

fn total_volume(m: &PolyMesh3) -> f64 {
    (0..m.n_cells()).map(|k| m.measure(k)).sum()
}

/// The properties every agglomeration has: each coarse cell is the union of its fine cells
/// (volumes and centroids add up, one tag), the volumes sum to the domain's, and the boundary
/// faces carry over one to one with their area, centroid and tag.
fn check(fine: &PolyMesh3, agg: &Agglomeration3) {
    let coarse = &agg.mesh;
    assert_eq!(agg.cell_of.len(), fine.n_cells());
    let mut volume = vec![0.0; coarse.n_cells()];
    let mut moment = vec![[0.0; 3]; coarse.n_cells()];
    for (k, &c) in agg.cell_of.iter().enumerate() {
        let c = c as usize;
        assert_eq!(fine.cell_tag(k), coarse.cell_tag(c), "fine cell {k}");
        volume[c] += fine.measure(k);
        (0..3).for_each(|r| moment[c][r] += fine.measure(k) * fine.centroid(k)[r]);
    }
    for c in 0..coarse.n_cells() {
        assert!(
            (volume[c] - coarse.measure(c)).abs() < 1e-12,
            "coarse cell {c}"
        );
        let x = coarse.centroid(c);
        assert!((0..3).all(|r| (moment[c][r] / volume[c] - x[r]).abs() < 1e-12));
    }
    let v = total_volume(fine);
    // both sums round off by at most about n ε relative (n the number of fine cells)
    let tol = 4.0 * f64::EPSILON * fine.n_cells() as f64 * v;
    let defect = (total_volume(coarse) - v).abs();
    assert!(defect <= tol, "volumes differ by {defect:e}");
    let mut seen = vec![false; coarse.n_faces()];
    for f in 0..fine.n_faces() {
        let cf = agg.boundary_face_of[f];
        if !fine.is_boundary_face(f) {
            assert_eq!(cf, NO_FACE, "fine face {f}");
            continue;
        }
        let cf = cf as usize;
        assert!(coarse.is_boundary_face(cf) && !seen[cf], "fine face {f}");
        seen[cf] = true;
        assert_eq!(fine.face_tag(f), coarse.face_tag(cf));
        assert!((fine.face_measure(f) - coarse.face_measure(cf)).abs() < 1e-15);
        assert!(
            crate::mesh3d::geometry::dist(fine.face_centroid(f), coarse.face_centroid(cf)) < 1e-15
        );
    }
    assert_eq!(fine.boundary_faces().len(), coarse.boundary_faces().len());
    check_vector_areas(fine, agg);
}

/// Σ_σ |σ| n_{K,σ} over the faces of each coarse cell equals the same sum over the fine faces
/// on its boundary (merged faces are planar, so their |σ| n_σ is the sum of their pieces';
/// with warped fine faces neither sum is zero).
fn check_vector_areas(fine: &PolyMesh3, agg: &Agglomeration3) {
    let coarse = &agg.mesh;
    let mut want = vec![[0.0; 3]; coarse.n_cells()];
    let mut surface = vec![0.0; coarse.n_cells()];
    for f in 0..fine.n_faces() {
        let [k, l] = fine.face_cells(f);
        let (a, n) = (fine.face_measure(f), fine.face_normal(f));
        let ck = agg.cell_of[k] as usize;
        let cl = (l != crate::mesh::NO_CELL).then(|| agg.cell_of[l] as usize);
        if cl == Some(ck) {
            continue;
        }
        (0..3).for_each(|r| want[ck][r] += a * n[r]);
        surface[ck] += a;
        if let Some(cl) = cl {
            (0..3).for_each(|r| want[cl][r] -= a * n[r]);
            surface[cl] += a;
        }
    }
    for k in 0..coarse.n_cells() {
        let mut got = [0.0; 3];
        for (i, &f) in coarse.cell_faces(k).iter().enumerate() {
            let (n, _) = coarse.cell_normal_dist(k, i);
            (0..3).for_each(|r| got[r] += coarse.face_measure(f as usize) * n[r]);
        }
        let d = crate::mesh3d::geometry::dist(got, want[k]);
        assert!(
            d <= 1e-13 * surface[k],
            "coarse cell {k}: {got:?} vs {:?}",
            want[k]
        );
    }
}

/// Every coarse cell is closed and its faces are planar or merged exactly: the vector areas
/// add up to zero, Σ_σ |σ| n_{K,σ} = 0, and C_K = Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ = |K| I (the
/// divergence theorem on a cell bounded by planar faces, which HMM's consistency needs).
fn check_closed_cells(m: &PolyMesh3) {
    for k in 0..m.n_cells() {
        let (mut sum, mut c) = ([0.0; 3], [[0.0; 3]; 3]);
        let mut surface = 0.0;
        for (i, &f) in m.cell_faces(k).iter().enumerate() {
            let (n, _) = m.cell_normal_dist(k, i);
            let (a, x) = (m.face_measure(f as usize), m.face_centroid(f as usize));
            surface += a;
            for r in 0..3 {
                sum[r] += a * n[r];
                for q in 0..3 {
                    c[r][q] += a * n[r] * (x[q] - m.centroid(k)[q]);
                }
            }
        }
        let tol = 1e-13 * surface;
        assert!(sum.iter().all(|x| x.abs() <= tol), "cell {k}: {sum:?}");
        for (r, row) in c.iter().enumerate() {
            for (q, entry) in row.iter().enumerate() {
                let want = if r == q { m.measure(k) } else { 0.0 };
                let d = (entry - want).abs();
                assert!(
                    d <= 1e-12 * m.measure(k),
                    "cell {k}: C_K[{r}][{q}] off by {d:e}"
                );
            }
        }
    }
}

fn boundary_area(m: &PolyMesh3) -> f64 {
    (m.boundary_faces().iter())
        .map(|&f| m.face_measure(f as usize))
        .sum()
}

/// The number of fine cells in each coarse cell.
fn sizes(agg: &Agglomeration3) -> Vec<usize> {
    let mut n = vec![0; agg.mesh.n_cells()];
    agg.cell_of.iter().for_each(|&c| n[c as usize] += 1);
    n
}

#[test]
fn cubes_agglomerate_to_blocks_of_cubes() {
    let fine = side_tags(&mesh(cubes(8, 3)));
    for (per, want) in [(2, 64), (4, 8)] {
        let agg = agglomerate3(&fine, per as f64 / 8.0, MemoryBudget::DEFAULT).unwrap();
        check(&fine, &agg);
        check_closed_cells(&agg.mesh);
        assert_eq!(agg.mesh.n_cells(), want);
        assert_eq!(agg.dissolved_cells, 0);
        assert!(sizes(&agg).iter().all(|&n| n == per * per * per));
        let side = per as f64 / 8.0;
        let blocks = 8 / per;
        for c in 0..want {
            assert!((agg.mesh.measure(c) - side * side * side).abs() < 1e-15);
            // a block of per³ cubes has one face per neighbouring block and keeps the per²
            // fine faces of each side on the boundary
            let x = agg.mesh.centroid(c).map(|x| (x / side) as usize);
            let outer: usize = x
                .iter()
                .map(|&i| usize::from(i == 0) + usize::from(i == blocks - 1))
                .sum();
            let faces = (6 - outer) + outer * per * per;
            assert_eq!(agg.mesh.cell_faces(c).len(), faces, "block {x:?}");
        }
        // the faces between blocks, then the fine boundary faces
        let interior = 3 * blocks * blocks * (blocks - 1);
        assert_eq!(agg.mesh.n_faces(), interior + 6 * 64);
        assert!((boundary_area(&agg.mesh) - 6.0).abs() < 1e-13);
    }
}

#[test]
fn tetrahedra_and_perturbed_cubes_give_valid_coarser_meshes() {
    let kuhn = side_tags(&mesh(tetrahedra(6, 5)));
    // the six tetrahedra of a cube are placed by the cube: blocks of 2³ cubes
    let agg = agglomerate3(&kuhn, 2.0 / 6.0, MemoryBudget::DEFAULT).unwrap();
    check(&kuhn, &agg);
    check_closed_cells(&agg.mesh);
    assert_eq!(agg.mesh.n_cells(), 27);
    assert!(sizes(&agg).iter().all(|&n| n == 48));
    // the 8 triangles between two blocks merge into one square: 54 faces inside, and the 432
    // triangles of the boundary
    assert_eq!(agg.mesh.n_faces(), 54 + 432);
    assert!((boundary_area(&agg.mesh) - 6.0).abs() < 1e-13);
    for (fine, sizes, planar) in [
        (kuhn, [0.23, 0.5], true),
        (
            side_tags(&mesh(perturbed_cubes(8, 0.1, 7))),
            [0.25, 0.4],
            false,
        ),
    ] {
        for size in sizes {
            let agg = agglomerate3(&fine, size, MemoryBudget::DEFAULT).unwrap();
            check(&fine, &agg);
            // the fine faces between two aggregates or on the boundary: on Kuhn tetrahedra
            // those between two aggregates merge; between perturbed cubes no two are
            // coplanar, so none merge
            let kept = (0..fine.n_faces())
                .filter(|&f| match fine.face_cells(f) {
                    [_, crate::mesh::NO_CELL] => true,
                    [k, l] => agg.cell_of[k] != agg.cell_of[l],
                })
                .count();
            if planar {
                assert!(agg.mesh.n_faces() < kept, "size {size}");
            } else {
                assert_eq!(agg.mesh.n_faces(), kept, "size {size}");
            }
            assert!(
                agg.mesh.n_cells() * 4 < fine.n_cells(),
                "size {size}: {} of {} cells",
                agg.mesh.n_cells(),
                fine.n_cells()
            );
            // built from its own description, the coarse mesh is the same
            let again = mesh(agg.mesh.to_polyhedra());
            assert_eq!(again.n_faces(), agg.mesh.n_faces());
        }
    }
}

#[test]
fn aggregates_never_mix_cell_tags() {
    let fine = mesh(cubes(8, 11));
    let tags = (0..fine.n_cells())
        .map(|k| if fine.centroid(k)[0] < 0.4 { 1 } else { 2 })
        .collect();
    let fine = fine.with_cell_tags(tags).unwrap();
    let agg = agglomerate3(&fine, 0.5, MemoryBudget::DEFAULT).unwrap();
    check(&fine, &agg);
    // the four blocks at x < 1/2 are cut at x = 3/8 into a tag 1 and a tag 2 slab
    assert_eq!(agg.mesh.n_cells(), 12);
    let ones = (0..12).filter(|&c| agg.mesh.cell_tag(c) == 1).count();
    assert_eq!(ones, 4);
}

#[test]
fn small_aggregates_are_merged() {
    // H = 0.3 on 8³ cubes: blocks of 2, 3, 2 and 1 cubes along each axis; the single cube at
    // the far corner (volume 8⁻³ < H³/8) is merged into a neighbour, the 1 × 1 × 2 blocks
    // (2 · 8⁻³ > H³/8) are not
    let fine = mesh(cubes(8, 13));
    let agg = agglomerate3(&fine, 0.3, MemoryBudget::DEFAULT).unwrap();
    check(&fine, &agg);
    assert_eq!(agg.mesh.n_cells(), 63);
    let corner = fine.n_cells() - 1;
    assert!(sizes(&agg)[agg.cell_of[corner] as usize] > 1);
}

/// 4³ cubes tagged 1 on a U (i = 0, i = 3 or j = 0) and 2 on the 2 × 3 × 4 block inside it.
fn u_shape() -> PolyMesh3 {
    let fine = mesh(cubes(4, 17));
    let tags = (0..fine.n_cells())
        .map(|k| {
            let c = fine.centroid(k).map(|x| (x * 4.0) as usize);
            if c[0] == 0 || c[0] == 3 || c[1] == 0 {
                1
            } else {
                2
            }
        })
        .collect();
    fine.with_cell_tags(tags).unwrap()
}

#[test]
fn aggregates_not_star_shaped_are_regrouped() {
    // the U's centroid lies in its notch: not star-shaped; regrouped by boxes of side 1/2
    // into four pieces per layer of two cubes: straight bars of 4 cubes, kept, and L-shaped
    // pieces of 6 cubes holding a corner of the U. In units of the cube an L piece has
    // centroid (5/6, 5/6, 1) from its corner, so d = 1/6 on the faces of its notch, less
    // than MIN_DIST_RATIO · r = 0.1 · (49/36 + 25/36 + 1)^(1/2) ≈ 0.175: boxes of side 1/4
    // then leave its cubes alone. The block is kept.
    let fine = u_shape();
    let agg = agglomerate3(&fine, 1.0, MemoryBudget::DEFAULT).unwrap();
    check(&fine, &agg);
    check_closed_cells(&agg.mesh);
    assert_eq!(agg.dissolved_cells, 40);
    let mut s = sizes(&agg);
    s.sort_unstable();
    let mut want = vec![1; 24];
    want.extend([4, 4, 4, 4, 24]);
    assert_eq!(s, want);
}

#[test]
fn aggregates_failing_at_every_size_are_dissolved() {
    // boxes of side 300 / 2^8 > 1 still hold the whole U after the last halving: its 40 cubes
    // become coarse cells of their own
    let fine = u_shape();
    assert!(300.0 / (1 << MAX_SPLITS) as f64 > 1.0);
    let agg = agglomerate3(&fine, 300.0, MemoryBudget::DEFAULT).unwrap();
    check(&fine, &agg);
    assert_eq!(agg.dissolved_cells, 40);
    assert_eq!(agg.mesh.n_cells(), 41);
    let s = sizes(&agg);
    assert_eq!(s.iter().filter(|&&n| n == 24).count(), 1);
    assert_eq!(s.iter().filter(|&&n| n == 1).count(), 40);
}

#[test]
fn agglomeration_does_not_depend_on_threads() {
    let cases = [
        (mesh(tetrahedra(10, 19)), [0.17, 0.3]),
        (mesh(perturbed_cubes(16, 0.1, 23)), [0.11, 0.2]),
        (u_shape(), [1.0, 300.0]),
    ];
    let pools: Vec<_> = [1, 2, 3]
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        })
        .collect();
    for (c, (fine, sizes)) in cases.iter().enumerate() {
        for size in sizes {
            let one = pools[0].install(|| agglomerate3(fine, *size, MemoryBudget::DEFAULT));
            let one = one.unwrap();
            for (t, pool) in pools.iter().enumerate().skip(1) {
                let got = pool
                    .install(|| agglomerate3(fine, *size, MemoryBudget::DEFAULT))
                    .unwrap();
                let what = format!("case {c}, size {size}, {} threads", t + 1);
                assert_eq!(got.cell_of, one.cell_of, "{what}");
                assert_eq!(got.boundary_face_of, one.boundary_face_of, "{what}");
                assert_eq!(got.dissolved_cells, one.dissolved_cells, "{what}");
                assert_eq!(got.mesh.to_polyhedra(), one.mesh.to_polyhedra(), "{what}");
                assert_eq!(got.mesh.face_cells, one.mesh.face_cells, "{what}");
            }
        }
    }
}

#[test]
fn bad_size_and_small_budget_are_errors() {
    let fine = mesh(cubes(2, 29));
    for size in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = agglomerate3(&fine, size, MemoryBudget::DEFAULT).unwrap_err();
        assert!(matches!(err, MeshError::NonConforming(_)), "{size}: {err}");
    }
    let err = agglomerate3(&fine, 0.5, MemoryBudget::new(100)).unwrap_err();
    assert!(matches!(err, MeshError::TooLarge { .. }), "{err}");
}

/// The measurement of `replication/measurements/mesh3d.md` ("Agglomerating 10⁵ cells"): run
/// with `cargo test --release -p gradvi --lib measure_agglomeration -- --ignored --nocapture`.
#[test]
#[ignore]
fn measure_agglomeration_of_large_meshes() {
    let cases = [
        ("Kuhn tetrahedra, n = 26", tetrahedra(26, 31)),
        (
            "cubes, n = 46, nodes moved by 0.05 h",
            perturbed_cubes(46, 0.05, 37),
        ),
    ];
    for (name, p) in cases {
        let t = std::time::Instant::now();
        let fine = mesh(p);
        println!(
            "{name}: {} cells, built in {:.2?}",
            fine.n_cells(),
            t.elapsed()
        );
        for per_cell in [8, 16, 48, 384] {
            let size = (1.0 / (fine.n_cells() / per_cell) as f64).cbrt();
            let t = std::time::Instant::now();
            let agg = agglomerate3(&fine, size, MemoryBudget::DEFAULT).unwrap();
            let time = t.elapsed();
            check(&fine, &agg);
            assert!(agg.mesh.n_cells() < fine.n_cells());
            let faces = (0..agg.mesh.n_cells()).map(|c| agg.mesh.cell_faces(c).len());
            println!(
                "| {per_cell} | {size:.4} | {} | {} | {} | {} | {time:.2?} |",
                agg.mesh.n_cells(),
                agg.mesh.n_faces(),
                faces.max().unwrap_or(0),
                agg.dissolved_cells
            );
        }
    }
}

/// With boundary merge keys, the fine boundary faces of one coarse cell with one key and one
/// plane become one face: on Kuhn tetrahedra, the 8 triangles of a block's side become one
/// square. Faces keyed [`KEEP`] stay as they are. Every fine boundary face lies in a coarse
/// boundary face of its tag, whose area and centroid are those of its fine faces.
#[test]
fn boundary_faces_with_one_key_merge_by_plane() {
    let kuhn = side_tags(&mesh(tetrahedra(6, 5)));
    // one key per side, the side z = 1 (tag 6) kept
    let keys: Vec<u32> = (0..kuhn.n_faces())
        .map(|f| match kuhn.face_tag(f) {
            0 | 6 => KEEP,
            t => t as u32,
        })
        .collect();
    let agg =
        agglomerate3_merging(&kuhn, 2.0 / 6.0, Some(&keys), 1.0, MemoryBudget::DEFAULT).unwrap();
    let coarse = &agg.mesh;
    check_closed_cells(coarse);
    check_vector_areas(&kuhn, &agg);
    assert_eq!(coarse.n_cells(), 27);
    // 54 squares between blocks, 5 sides of 9 squares, and the 72 triangles of z = 1
    assert_eq!(coarse.n_faces(), 54 + 45 + 72);
    let mut area = vec![0.0; coarse.n_faces()];
    let mut moment = vec![[0.0; 3]; coarse.n_faces()];
    for &f in kuhn.boundary_faces() {
        let (f, cf) = (f as usize, agg.boundary_face_of[f as usize] as usize);
        assert!(coarse.is_boundary_face(cf), "fine face {f}");
        assert_eq!(kuhn.face_tag(f), coarse.face_tag(cf), "fine face {f}");
        assert_eq!(
            agg.cell_of[kuhn.face_cells(f)[0]] as usize,
            coarse.face_cells(cf)[0]
        );
        area[cf] += kuhn.face_measure(f);
        (0..3).for_each(|r| moment[cf][r] += kuhn.face_measure(f) * kuhn.face_centroid(f)[r]);
    }
    for &cf in coarse.boundary_faces() {
        let cf = cf as usize;
        let want = if coarse.face_tag(cf) == 6 {
            1.0 / 72.0
        } else {
            1.0 / 9.0
        };
        assert!(
            (area[cf] - want).abs() < 1e-15,
            "coarse face {cf}: {}",
            area[cf]
        );
        assert!(
            (coarse.face_measure(cf) - want).abs() < 1e-15,
            "coarse face {cf}"
        );
        let x = coarse.face_centroid(cf);
        assert!((0..3).all(|r| (moment[cf][r] / area[cf] - x[r]).abs() < 1e-14));
    }
    // the same with every key KEEP is the agglomeration without merging, face for face
    let none = agglomerate3_merging(
        &kuhn,
        2.0 / 6.0,
        Some(&vec![KEEP; kuhn.n_faces()]),
        1.0,
        MemoryBudget::DEFAULT,
    )
    .unwrap();
    let plain = agglomerate3(&kuhn, 2.0 / 6.0, MemoryBudget::DEFAULT).unwrap();
    assert_eq!(none.mesh.n_faces(), plain.mesh.n_faces());
    assert!(
        (0..plain.mesh.n_faces())
            .all(|f| none.mesh.face_vertices(f) == plain.mesh.face_vertices(f))
    );
    assert_eq!(none.boundary_face_of, plain.boundary_face_of);
    // keys for another mesh: a typed error
    let err =
        agglomerate3_merging(&kuhn, 0.5, Some(&keys[1..]), 1.0, MemoryBudget::DEFAULT).unwrap_err();
    assert!(
        matches!(err, MeshError::NonConforming(ref m) if m.contains("merge keys")),
        "{err}"
    );
}

/// The box cover: each fine centroid lies in its coarse cell, a box of side H; the boxes are
/// those that hold a fine centroid, and their volumes add up to H³ times their number.
#[test]
fn box_cover_puts_each_cell_in_the_box_of_its_centroid() {
    let fine = mesh(perturbed_cubes(8, 0.1, 7));
    let h = 0.3;
    let cover = super::box_cover(&fine, h, MemoryBudget::DEFAULT).unwrap();
    let coarse = &cover.mesh;
    // x₀ = 0: the boxes [0.3 i, 0.3 (i + 1)] for i = 0..3 along each axis hold centroids
    assert_eq!(coarse.n_cells(), 64);
    for k in 0..coarse.n_cells() {
        assert!((coarse.measure(k) - h * h * h).abs() < 1e-15, "box {k}");
    }
    for k in 0..fine.n_cells() {
        let (c, x) = (coarse.centroid(cover.cell_of[k] as usize), fine.centroid(k));
        assert!(
            (0..3).all(|r| (x[r] - c[r]).abs() <= 0.5 * h),
            "fine cell {k}"
        );
    }
    assert!(cover.boundary_face_of.iter().all(|&f| f == NO_FACE));
    check_closed_cells(coarse);
    assert!(super::box_cover(&fine, 0.0, MemoryBudget::DEFAULT).is_err());
    assert!(super::box_cover(&fine, 1e-9, MemoryBudget::DEFAULT).is_err());
}

/// With `max_failed` below the fraction of cells in failing aggregates, the agglomeration
/// stops after its first checks with an error, instead of regrouping.
#[test]
fn agglomeration_stops_early_when_most_aggregates_fail() {
    // the U of `aggregates_not_star_shaped_are_regrouped`: its 40 cells of 64 fail
    let fine = u_shape();
    let err = agglomerate3_merging(&fine, 1.0, None, 0.5, MemoryBudget::DEFAULT).unwrap_err();
    assert!(err.to_string().contains("does not agglomerate"), "{err}");
    assert!(agglomerate3_merging(&fine, 1.0, None, 0.7, MemoryBudget::DEFAULT).is_ok());
}
