//! Small [`Polyhedra`] built by hand for the tests: the unit cube cut into k³ cubes, the same
//! cubes cut into 6 tetrahedra each, and two cells of which one is a non-convex polyhedron.
//! Face loops are listed in a scrambled orientation and rotation (from a seeded generator),
//! as readers may give them.

use super::{Point3, Polyhedra};
use crate::mesh::test_rng;

/// The index of grid node (i, j, l) of a k × k × k grid of cubes.
fn node(k: usize, i: usize, j: usize, l: usize) -> u32 {
    (i + (k + 1) * (j + (k + 1) * l)) as u32
}

/// The nodes of the (k + 1)³ grid of the unit cube.
fn grid_nodes(k: usize) -> Vec<Point3> {
    let mut v = Vec::new();
    for l in 0..=k {
        for j in 0..=k {
            for i in 0..=k {
                v.push([i, j, l].map(|c| c as f64 / k as f64));
            }
        }
    }
    v
}

/// Appends a cell whose faces are `faces`, each loop rotated and possibly reversed at random.
pub(crate) fn push_scrambled(p: &mut Polyhedra, faces: &[Vec<u32>], rng: &mut impl FnMut() -> f64) {
    let scrambled: Vec<Vec<u32>> = faces
        .iter()
        .map(|f| {
            let mut f = f.clone();
            let r = ((rng() * f.len() as f64) as usize).min(f.len() - 1);
            f.rotate_left(r);
            if rng() < 0.5 {
                f.reverse();
            }
            f
        })
        .collect();
    p.push_cell(scrambled.iter().map(|f| &f[..])).unwrap();
}

/// The 8 corners of cube (i, j, l) in the order of the bits of c: corner c is
/// (i + c&1, j + c>>1&1, l + c>>2&1).
fn corners(k: usize, i: usize, j: usize, l: usize) -> [u32; 8] {
    std::array::from_fn(|c| node(k, i + (c & 1), j + (c >> 1 & 1), l + (c >> 2 & 1)))
}

/// The six quadrilateral faces of a hexahedron with corners `c` (ordered as in [`corners`]).
pub(crate) fn hex_faces(c: [u32; 8]) -> Vec<Vec<u32>> {
    [
        [0, 2, 6, 4],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 5, 7, 6],
    ]
    .iter()
    .map(|q| q.iter().map(|&i| c[i]).collect())
    .collect()
}

/// The unit cube cut into k³ cubes.
pub(crate) fn cubes(k: usize, seed: u64) -> Polyhedra {
    let mut rng = test_rng(seed);
    let mut p = Polyhedra {
        vertices: grid_nodes(k),
        ..Polyhedra::default()
    };
    for l in 0..k {
        for j in 0..k {
            for i in 0..k {
                push_scrambled(&mut p, &hex_faces(corners(k, i, j, l)), &mut rng);
            }
        }
    }
    p
}

/// The unit cube cut into k³ cubes, each cut into 6 tetrahedra around its diagonal from corner
/// 0 to corner 7 (Kuhn's triangulation, conforming across cubes).
pub(crate) fn tetrahedra(k: usize, seed: u64) -> Polyhedra {
    let mut rng = test_rng(seed);
    let mut p = Polyhedra {
        vertices: grid_nodes(k),
        ..Polyhedra::default()
    };
    // the paths 0 → 7 adding one axis bit at a time, in the 6 orders of the axes
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for l in 0..k {
        for j in 0..k {
            for i in 0..k {
                let c = corners(k, i, j, l);
                for o in orders {
                    let a = 1 << o[0];
                    let b = a | 1 << o[1];
                    let t = [c[0], c[a], c[b], c[7]];
                    push_scrambled(&mut p, &tet_faces(t), &mut rng);
                }
            }
        }
    }
    p
}

/// The four triangular faces of tetrahedron `t`.
pub(crate) fn tet_faces(t: [u32; 4]) -> Vec<Vec<u32>> {
    vec![
        vec![t[0], t[1], t[2]],
        vec![t[0], t[1], t[3]],
        vec![t[0], t[2], t[3]],
        vec![t[1], t[2], t[3]],
    ]
}

/// The unit cube cut into two cells by a surface dented at its centre: the lower cell,
/// \[0, 1\]² × \[0, ½\] less the pyramid of apex (½, ½, `apex_z`) over its top, is a non-convex
/// polyhedron with 9 faces (star-shaped with respect to its centroid for `apex_z` ≥ 0.3); the
/// upper cell is convex.
pub(crate) fn dented_pair(apex_z: f64, seed: u64) -> Polyhedra {
    let mut rng = test_rng(seed);
    let mut v: Vec<Point3> = Vec::new();
    for z in [0.0, 0.5, 1.0] {
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            v.push([x, y, z]);
        }
    }
    v.push([0.5, 0.5, apex_z]);
    let mut p = Polyhedra {
        vertices: v,
        ..Polyhedra::default()
    };
    let dent: Vec<Vec<u32>> = (0..4).map(|i| vec![4 + i, 4 + (i + 1) % 4, 12]).collect();
    let sides = |lo: u32| -> Vec<Vec<u32>> {
        (0..4)
            .map(|i| vec![lo + i, lo + (i + 1) % 4, lo + 4 + (i + 1) % 4, lo + 4 + i])
            .collect()
    };
    let mut lower = sides(0);
    lower.push(vec![0, 1, 2, 3]);
    lower.extend(dent.iter().cloned());
    let mut upper = sides(4);
    upper.push(vec![8, 9, 10, 11]);
    upper.extend(dent);
    push_scrambled(&mut p, &lower, &mut rng);
    push_scrambled(&mut p, &upper, &mut rng);
    p
}

/// [`cubes`] with every interior grid node moved by up to `amp` times the grid step in each
/// coordinate (seeded): hexahedra with warped faces.
pub(crate) fn perturbed_cubes(k: usize, amp: f64, seed: u64) -> Polyhedra {
    let mut p = cubes(k, seed);
    let mut rng = test_rng(seed ^ 0x5eed);
    let h = 1.0 / k as f64;
    for v in &mut p.vertices {
        if v.iter().all(|&c| c > 0.0 && c < 1.0) {
            for c in v.iter_mut() {
                *c += amp * h * (2.0 * rng() - 1.0);
            }
        }
    }
    p
}
