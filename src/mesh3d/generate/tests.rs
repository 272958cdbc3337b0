//! Tests of the 3D generators on the raw descriptions: counts, conformity, orientation,
//! volumes, planarity, mapping onto a box, determinism and the refusals.

use super::*;
use crate::MeshError;
use crate::mesh3d::Point3;
use std::collections::HashMap;

fn sub(a: Point3, b: Point3) -> Point3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: Point3, b: Point3) -> Point3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: Point3, b: Point3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn average(p: &Polyhedra, ids: impl Iterator<Item = u32>) -> Point3 {
    let (mut s, mut k) = ([0.0; 3], 0.0);
    for v in ids {
        let x = p.vertices[v as usize];
        s = [s[0] + x[0], s[1] + x[1], s[2] + x[2]];
        k += 1.0;
    }
    s.map(|c| c / k)
}

/// The fan triangles (c, v_i, v_{i+1}) of face side `s`, c the average of its vertices.
fn fan(p: &Polyhedra, s: usize) -> Vec<[Point3; 3]> {
    let f = p.side_vertices(s);
    let c = average(p, f.iter().copied());
    (0..f.len())
        .map(|i| {
            let a = p.vertices[f[i] as usize];
            let b = p.vertices[f[(i + 1) % f.len()] as usize];
            [c, a, b]
        })
        .collect()
}

/// Σ of the fan triangles' area vectors of face side `s` (the Newell vector: |σ| n_σ for a
/// planar face).
fn area_vector(p: &Polyhedra, s: usize) -> Point3 {
    fan(p, s).iter().fold([0.0; 3], |acc, [c, a, b]| {
        let n = cross(sub(*a, *c), sub(*b, *c));
        [0, 1, 2].map(|i| acc[i] + 0.5 * n[i])
    })
}

/// The largest distance of a vertex of face side `s` from the plane through its vertex
/// average normal to its area vector.
fn warp(p: &Polyhedra, s: usize) -> f64 {
    let n = area_vector(p, s);
    let len = dot(n, n).sqrt();
    let c = average(p, p.side_vertices(s).iter().copied());
    p.side_vertices(s)
        .iter()
        .map(|&v| (dot(sub(p.vertices[v as usize], c), n) / len).abs())
        .fold(0.0, f64::max)
}

/// Every consistency check of a generated description on `domain`: ids in range and every
/// vertex used; each cell closed with its faces oriented outward (every directed edge once,
/// with its reverse); every face listed by two cells in opposite orientations or, on the
/// boundary of the box only, by one; each cell star-shaped with respect to its vertex average
/// (every fan tetrahedron positive); volumes summing to the box's; the boundary faces' area
/// that of the box. Returns the largest face warp.
fn check(p: &Polyhedra, domain: Cuboid) -> f64 {
    let nv = p.vertices.len();
    let mut used = vec![false; nv];
    for &v in &p.face_vertices {
        assert!((v as usize) < nv, "vertex {v} out of range");
        used[v as usize] = true;
    }
    assert!(used.iter().all(|&u| u), "unused vertex");
    let mut faces: HashMap<Vec<u32>, Vec<usize>> = HashMap::new();
    let (mut volume, mut max_warp) = (0.0, 0.0f64);
    for k in 0..p.n_cells() {
        let mut edges = HashMap::new();
        let x_k = average(p, p.cell_sides(k).flat_map(|s| p.side_vertices(s).to_vec()));
        let mut vol_k = 0.0;
        for s in p.cell_sides(k) {
            let f = p.side_vertices(s);
            for i in 0..f.len() {
                *edges.entry((f[i], f[(i + 1) % f.len()])).or_insert(0) += 1;
            }
            let mut key = f.to_vec();
            key.sort_unstable();
            faces.entry(key).or_default().push(s);
            for [c, a, b] in fan(p, s) {
                let t = dot(sub(c, x_k), cross(sub(a, x_k), sub(b, x_k))) / 6.0;
                assert!(t > 0.0, "cell {k} side {s}: fan tetrahedron of volume {t}");
                vol_k += t;
            }
            max_warp = max_warp.max(warp(p, s));
        }
        for (&(a, b), &m) in &edges {
            assert_eq!(
                (m, edges.get(&(b, a))),
                (1, Some(&1)),
                "cell {k} edge {a}-{b}"
            );
        }
        volume += vol_k;
    }
    assert!(
        (volume - domain.volume()).abs() < 1e-12 * domain.volume(),
        "{volume}"
    );
    let r = domain.ranges();
    let on_side = |f: &[u32]| {
        (0..3).any(|a| (0..2).any(|e| f.iter().all(|&v| p.vertices[v as usize][a] == r[a][e])))
    };
    let mut boundary_area = 0.0;
    for (key, sides) in &faces {
        match sides[..] {
            [s] => {
                assert!(on_side(key), "face {key:?} listed once inside the box");
                let n = area_vector(p, s);
                boundary_area += dot(n, n).sqrt();
            }
            [s, t] => {
                assert!(!on_side(key), "boundary face {key:?} listed twice");
                let mut rev = p.side_vertices(t).to_vec();
                rev.reverse();
                let f = p.side_vertices(s);
                let at = rev.iter().position(|&v| v == f[0]).unwrap();
                rev.rotate_left(at);
                assert_eq!(f, &rev[..], "face {key:?} listed in the same orientation");
            }
            _ => panic!("face {key:?} listed {} times", sides.len()),
        }
    }
    let [a, b, c] = r.map(|r| r[1] - r[0]);
    let area = 2.0 * (a * b + b * c + c * a);
    assert!(
        (boundary_area - area).abs() < 1e-12 * area,
        "{boundary_area}"
    );
    max_warp
}

/// [cells, face sides, face vertices, vertices] of a description.
fn counted(p: &Polyhedra) -> [u64; 4] {
    [
        p.n_cells(),
        p.face_ptr.len() - 1,
        p.face_vertices.len(),
        p.vertices.len(),
    ]
    .map(|x| x as u64)
}

const BUDGET: MemoryBudget = MemoryBudget::DEFAULT;

#[test]
fn every_family_is_conforming_closed_and_fills_the_box() {
    let boxes = [
        Cuboid::UNIT,
        Cuboid::new([-1.0, 2.0], [0.5, 0.75], [10.0, 12.0]),
    ];
    for f in Family3::ALL {
        for level in 1..=2 {
            for domain in boxes {
                let p = f.polyhedra(level, domain, BUDGET).unwrap();
                assert_eq!(p.n_cells(), f.cells_at_level(level), "{f} {level}");
                assert_eq!(Some(counted(&p)), f.counts(level), "{f} {level}");
                let max_warp = check(&p, domain);
                let h = domain
                    .ranges()
                    .map(|r| r[1] - r[0])
                    .into_iter()
                    .fold(0.0, f64::max);
                if f == Family3::Warped {
                    assert!(max_warp > 1e-3 * h / 4.0, "{f}: faces are planar");
                } else {
                    assert!(max_warp < 1e-14 * h, "{f} {level}: warp {max_warp}");
                }
                assert!(p.cell_tags.is_empty() && p.tagged_ptr.is_empty());
            }
        }
    }
}

#[test]
fn level_3_counts_and_the_refined_formulas() {
    for f in Family3::ALL {
        let p = f.polyhedra(3, Cuboid::UNIT, BUDGET).unwrap();
        assert_eq!(Some(counted(&p)), f.counts(3), "{f}");
    }
    for n in [2, 6] {
        let p = refined(n, Cuboid::UNIT, BUDGET).unwrap();
        assert_eq!(Some(counted(&p)), refined::counts(n), "n = {n}");
        check(&p, Cuboid::UNIT);
    }
    assert_eq!(
        Family3::ALL.map(|f| f.cells_at_level(1)),
        [64, 384, 128, 288, 64]
    );
    assert_eq!(Family3::Cubes.cells_at_level(7), 1 << 24);
    assert_eq!(Family3::Refined.cells_at_level(6), 9 << 20);
}

#[test]
fn refined_cells_have_up_to_24_faces_and_boundary_faces_their_hanging_nodes() {
    let p = Family3::Refined.polyhedra(1, Cuboid::UNIT, BUDGET).unwrap();
    let faces: Vec<usize> = (0..p.n_cells()).map(|k| p.cell_sides(k).len()).collect();
    assert_eq!(faces.iter().max(), Some(&24));
    // coarse cube 1 = (1, 0, 0) is whole, after the 8 sub-cubes of cube 0: 4 squares on each
    // of its faces x−, x+, y+, z+, one polygon on y = 0 and on z = 0
    assert_eq!(faces[..9], [6, 6, 6, 6, 6, 6, 6, 6, 4 * 4 + 2]);
    // its face y = 0: corners (2,0,0), (4,0,0), (4,0,2), (2,0,2) in fine steps, with the
    // midpoints of the edges shared with the split cubes (0,0,0), (2,0,0) and (1,0,1), not of
    // its edge on the edge y = z = 0 of the box, which no split cube touches
    let side = p.cell_sides(8).nth(8).unwrap();
    let pts: Vec<Point3> = p
        .side_vertices(side)
        .iter()
        .map(|&v| p.vertices[v as usize])
        .collect();
    assert_eq!(
        pts,
        [
            [0.25, 0.0, 0.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.0, 0.125],
            [0.5, 0.0, 0.25],
            [0.375, 0.0, 0.25],
            [0.25, 0.0, 0.25],
            [0.25, 0.0, 0.125]
        ]
    );
    let e = refined(3, Cuboid::UNIT, BUDGET).unwrap_err().to_string();
    assert!(e.contains("even number"), "{e}");
}

#[test]
fn on_a_box_is_the_unit_cube_mesh_mapped() {
    let d = Cuboid::new([-2.0, 2.0], [-1.0, 0.5], [3.0, 3.125]);
    for f in Family3::ALL {
        let unit = f.polyhedra(2, Cuboid::UNIT, BUDGET).unwrap();
        let on = f.polyhedra(2, d, BUDGET).unwrap();
        assert_eq!(
            (&on.cell_ptr, &on.face_ptr, &on.face_vertices),
            (&unit.cell_ptr, &unit.face_ptr, &unit.face_vertices),
            "{f}"
        );
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (p, q) in on.vertices.iter().zip(&unit.vertices) {
            let m = d.map_unit(*q);
            for a in 0..3 {
                assert!((p[a] - m[a]).abs() <= 1e-15 * 4.0, "{f}: {p:?} vs {m:?}");
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        // the box exactly
        assert_eq!(
            Cuboid::new([lo[0], hi[0]], [lo[1], hi[1]], [lo[2], hi[2]]),
            d,
            "{f}"
        );
    }
    for bad in [
        Cuboid::new([1.0, 0.0], [0.0, 1.0], [0.0, 1.0]),
        Cuboid::new([0.0, 1.0], [0.0, f64::NAN], [0.0, 1.0]),
        Cuboid::new([0.0, 1.0], [0.0, 1.0], [2.0, 2.0]),
    ] {
        for f in Family3::ALL {
            let e = f.polyhedra(1, bad, BUDGET).unwrap_err().to_string();
            assert!(e.contains("is not a finite box"), "{f} {bad:?}: {e}");
        }
    }
}

#[test]
fn warped_meshes_depend_on_the_seed_only() {
    let build = |seed, threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| warped(6, Cuboid::UNIT, seed, BUDGET).unwrap())
    };
    let a = build(warped::SEED, 1);
    assert_eq!(a, build(warped::SEED, 3));
    // the family is this generator with its seed
    assert_eq!(
        Family3::Warped.polyhedra(1, Cuboid::UNIT, BUDGET).unwrap(),
        warped(4, Cuboid::UNIT, warped::SEED, BUDGET).unwrap()
    );
    let other = build(warped::SEED + 1, 2);
    assert_eq!(other.face_vertices, a.face_vertices);
    assert_ne!(other.vertices, a.vertices);
    // interior points move by at most AMPLITUDE · h per coordinate, boundary points not at all
    let grid = cubes(6, Cuboid::UNIT, BUDGET).unwrap();
    assert_eq!(grid.face_vertices, a.face_vertices);
    let h = 1.0 / 6.0;
    let mut moved = 0;
    for (p, q) in a.vertices.iter().zip(&grid.vertices) {
        let boundary = q.iter().any(|&c| c == 0.0 || c == 1.0);
        for c in 0..3 {
            let d = (p[c] - q[c]).abs();
            assert!(d <= warped::AMPLITUDE * h + 1e-15, "{d}");
            assert!(!boundary || d == 0.0);
        }
        moved += usize::from(p != q);
    }
    assert_eq!(moved, 5 * 5 * 5);
    check(&a, Cuboid::UNIT);
}

#[test]
fn levels_out_of_range_and_budgets_are_refused_before_allocating() {
    assert_eq!(Family3::ALL.map(|f| f.max_level()), [7, 6, 7, 6, 7]);
    for f in Family3::ALL {
        let max = f.max_level();
        assert!(f.cells_at_level(max) <= MAX_CELLS);
        assert!(f.cells_at_level(max + 1) > MAX_CELLS);
        assert_eq!(f.cells_at_level(0), 0);
        for level in [0, max + 1, 64, 1000, usize::MAX] {
            match f.polyhedra(level, Cuboid::UNIT, BUDGET) {
                Err(Error::InvalidData(msg)) => {
                    assert!(msg.contains(f.name()) && msg.contains("level"), "{msg}")
                }
                r => panic!("{f} level {level}: {r:?}"),
            }
        }
        assert_eq!(f.polyhedra_estimate(usize::MAX), u64::MAX);
        // the largest level, refused by a small budget at once, with the estimate
        let estimate = f.polyhedra_estimate(max);
        match f.polyhedra(max, Cuboid::UNIT, MemoryBudget::new(1 << 20)) {
            Err(Error::InvalidMesh(MeshError::TooLarge { bytes, budget, .. })) => {
                assert_eq!((bytes, budget), (estimate, 1 << 20))
            }
            r => panic!("{f}: {r:?}"),
        }
        // the estimate is a bound of what the description holds, and enough
        let p = f
            .polyhedra(1, Cuboid::UNIT, MemoryBudget::new(f.polyhedra_estimate(1)))
            .unwrap();
        let held = 24 * p.vertices.len()
            + 4 * (p.cell_ptr.len() + p.face_ptr.len() + p.face_vertices.len());
        assert!(held as u64 <= f.polyhedra_estimate(1), "{f}");
        assert!(
            f.polyhedra(
                1,
                Cuboid::UNIT,
                MemoryBudget::new(f.polyhedra_estimate(1) - 1)
            )
            .is_err()
        );
    }
    for r in [
        cubes(0, Cuboid::UNIT, BUDGET),
        kuhn(1 << 20, Cuboid::UNIT, BUDGET),
        prisms(usize::MAX, Cuboid::UNIT, BUDGET),
        refined(0, Cuboid::UNIT, BUDGET),
    ] {
        assert!(matches!(r, Err(Error::InvalidData(_))), "{r:?}");
    }
}

#[test]
fn family_names_round_trip() {
    for f in Family3::ALL {
        assert_eq!(f.name().parse::<Family3>().unwrap(), f);
        assert_eq!(f.to_string(), f.name());
    }
    assert_eq!(" Tetrahedra ".parse::<Family3>().unwrap(), Family3::Kuhn);
    assert_eq!("WARPED".parse::<Family3>().unwrap(), Family3::Warped);
    let e = "hexahedra".parse::<Family3>().unwrap_err().to_string();
    for f in Family3::ALL {
        assert!(e.contains(&format!("\"{f}\"")), "{e}");
    }
}
