//! A coarse mesh of boxes covering a fine 3D mesh, for the warm start's first coarse level
//! when agglomeration cannot coarsen the mesh.
//!
//! On unstructured tetrahedra (gmsh's, TetGen's) and on Voronoi cells, the union of the fine
//! cells in a box of size H has a jagged boundary: many of its fine faces lie in planes that
//! pass close to, or behind, its centroid, so the aggregate fails the star-shape checks of
//! [`agglomerate3`](super::agglomerate3) and is regrouped down to single cells. The cover
//! replaces those unions by the boxes themselves.
//!
//! ## Construction, for a box size H
//! With x₀ the lowest corner of the fine mesh's bounding box, fine cell K lies in the box
//! B_{ijk} = x₀ + H ([i, i+1] × [j, j+1] × [k, k+1]) that holds its centroid x_K. The coarse
//! cells are the boxes that hold at least one fine centroid, numbered in lexicographic
//! (i, j, k) order; a box is a hexahedron whose six faces are the squares of the grid, so two
//! coarse cells share a face exactly when their boxes do, and the mesh is conforming. The
//! coarse cell of K is its box; a box takes the tag of its fine cell of least index.
//!
//! Boxes that hold no centroid are added where the union would be pinched: around a grid
//! vertex, the boxes present, and those absent, must each be connected through the faces they
//! share (two boxes sharing only an edge or a corner are not: the union's boundary would pass
//! through that edge or vertex twice, which no mesh of a domain has). The absent boxes around
//! such a vertex are added, with the tag of a box present there, until no pinch remains or
//! after a few rounds (the build's validation then refuses the cover).
//!
//! The coarse domain is the union of the boxes: it covers every fine centroid and differs from
//! Ω by at most a box along ∂Ω (a staircase). Boundary data evaluated on it is evaluated up to
//! √3 H outside Ω, and no fine boundary face is a coarse one
//! ([`Agglomeration3::boundary_face_of`] is [`NO_FACE`] everywhere). So the cover serves a
//! prediction inside Ω (the obstacle's contact zone), not on Γ (Signorini's).
//!
//! Cost: O(n log n) in the fine cells (sorting the box keys); the coarse mesh has at most 8
//! vertices and 6 face sides per box.

use super::{Agglomeration3, NO_FACE};
use crate::budget::MemoryBudget;
use crate::error::MeshError;
use crate::mesh::agglomerate::floor_i64;
use crate::mesh3d::{PolyMesh3, Polyhedra};
use rayon::prelude::*;

/// The outward loops of the six faces of a box, as corner indices c = 4 dz + 2 dy + dx.
const BOX_FACES: [[usize; 4]; 6] = [
    [0, 4, 6, 2], // x = x0
    [1, 3, 7, 5], // x = x1
    [0, 1, 5, 4], // y = y0
    [2, 6, 7, 3], // y = y1
    [0, 2, 3, 1], // z = z0
    [4, 5, 7, 6], // z = z1
];

/// The box cover of `fine` with boxes of side `size` (see the module docs), within `budget`.
/// [`MeshError::NonConforming`] for a `size` that is not positive and finite or that makes
/// box indices overflow; the errors of [`PolyMesh3::from_polyhedra`].
pub fn box_cover(
    fine: &PolyMesh3,
    size: f64,
    budget: MemoryBudget,
) -> Result<Agglomeration3, MeshError> {
    let bb = fine.bounding_box().ranges();
    let origin = bb.map(|r| r[0]);
    let extent = bb.iter().map(|r| r[1] - r[0]).fold(0.0, f64::max);
    if !(size.is_finite() && size > 0.0 && extent / size < 1e6) {
        return Err(MeshError::NonConforming(format!(
            "box cover: box size {size} for a mesh of extent {extent}"
        )));
    }
    // the keys and their sorted copy (24 bytes each per cell), the coarse cell of each (4)
    let n = fine.n_cells() as u64;
    budget.check(
        format!("covering a 3D mesh of {n} cells with boxes"),
        n.saturating_mul(24 + 24 + 4),
    )?;
    let key = |k: usize| -> [i64; 3] {
        let c = fine.centroid(k);
        std::array::from_fn(|r| floor_i64((c[r] - origin[r]) / size))
    };
    let keys: Vec<[i64; 3]> = (0..fine.n_cells()).into_par_iter().map(key).collect();
    let mut boxes = distinct_boxes(&keys);
    let fills = fill_pinches(&mut boxes);
    let cell_of: Vec<u32> = keys
        .par_iter()
        .map(|k| boxes.binary_search(k).map_or(u32::MAX, |i| i as u32))
        .collect();
    drop(keys);
    // per box: 8 corners before and after deduplication (24 bytes each), the vertices (24
    // each), tag and first cell (12), 6 face sides of 4 vertices (4 + 16 bytes each)
    let nb = boxes.len() as u64;
    budget.check(
        format!("the {nb} boxes covering a 3D mesh"),
        nb.saturating_mul(8 * 24 * 2 + 8 * 24 + 12 + 6 * 20),
    )?;
    // the corners of the boxes, each once
    let corner = |b: &[i64; 3], c: usize| {
        [
            b[0] + (c & 1) as i64,
            b[1] + ((c >> 1) & 1) as i64,
            b[2] + (c >> 2) as i64,
        ]
    };
    let mut corners: Vec<[i64; 3]> = boxes
        .iter()
        .flat_map(|b| (0..8).map(move |c| corner(b, c)))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let mut tags = vec![i32::MAX; boxes.len()];
    let mut first = vec![usize::MAX; boxes.len()];
    for (k, &b) in cell_of.iter().enumerate() {
        if first[b as usize] == usize::MAX {
            first[b as usize] = k;
            tags[b as usize] = fine.cell_tag(k);
        }
    }
    // a filled box takes the tag of the box it was added beside, in the order of addition
    for (u, from) in &fills {
        let at = |g: &[i64; 3]| boxes.binary_search(g).unwrap_or(0);
        tags[at(u)] = tags[at(from)];
    }
    let mut p = Polyhedra {
        vertices: corners
            .iter()
            .map(|g| std::array::from_fn(|r| origin[r] + g[r] as f64 * size))
            .collect(),
        cell_tags: tags,
        ..Polyhedra::default()
    };
    let id = |g: [i64; 3]| corners.binary_search(&g).map_or(u32::MAX, |i| i as u32);
    for b in &boxes {
        let v: [u32; 8] = std::array::from_fn(|c| id(corner(b, c)));
        let loops: [[u32; 4]; 6] = BOX_FACES.map(|f| f.map(|c| v[c]));
        p.push_cell(loops.iter().map(|l| &l[..]))?;
    }
    let mesh = PolyMesh3::from_polyhedra(p, budget)?;
    Ok(Agglomeration3 {
        mesh,
        cell_of,
        boundary_face_of: vec![NO_FACE; fine.n_faces()],
        dissolved_cells: 0,
    })
}

/// The distinct `keys`, sorted (lexicographically: i, then j, then k). When the keys span a
/// grid of at most 4 boxes per key, they are marked on that grid and read back in order (O(n),
/// the case of a mesh of its bounding box); otherwise sorted (O(n log n), in parallel).
fn distinct_boxes(keys: &[[i64; 3]]) -> Vec<[i64; 3]> {
    let Some(&first) = keys.first() else {
        return Vec::new();
    };
    let (lo, hi) = keys
        .par_iter()
        .fold_with((first, first), |(mut lo, mut hi), k| {
            for r in 0..3 {
                (lo[r], hi[r]) = (lo[r].min(k[r]), hi[r].max(k[r]));
            }
            (lo, hi)
        })
        .reduce(
            || (first, first),
            |(a, b), (c, d)| {
                (
                    std::array::from_fn(|r| a[r].min(c[r])),
                    std::array::from_fn(|r| b[r].max(d[r])),
                )
            },
        );
    let dims: [u64; 3] = std::array::from_fn(|r| (hi[r] - lo[r]) as u64 + 1);
    let cells = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d));
    match cells {
        Some(g) if g <= 4 * keys.len() as u64 => {
            let at = |k: &[i64; 3]| {
                let o: [u64; 3] = std::array::from_fn(|r| (k[r] - lo[r]) as u64);
                ((o[0] * dims[1] + o[1]) * dims[2] + o[2]) as usize
            };
            let mut marked = vec![false; g as usize];
            for k in keys {
                marked[at(k)] = true;
            }
            let mut boxes = Vec::new();
            for (lin, _) in marked.iter().enumerate().filter(|(_, m)| **m) {
                let lin = lin as u64;
                let (i, jk) = (lin / (dims[1] * dims[2]), lin % (dims[1] * dims[2]));
                let (j, k) = (jk / dims[2], jk % dims[2]);
                boxes.push([lo[0] + i as i64, lo[1] + j as i64, lo[2] + k as i64]);
            }
            boxes
        }
        _ => {
            let mut boxes = keys.to_vec();
            boxes.par_sort_unstable();
            boxes.dedup();
            boxes
        }
    }
}

/// Rounds of [`fill_pinches`] at most (each adds boxes only next to existing ones).
const MAX_FILL_ROUNDS: usize = 8;

/// Whether the boxes of `mask` (bit c: the box at offset (c & 1, (c >> 1) & 1, c >> 2) of a
/// 2 × 2 × 2 block) are connected through the faces they share (true when empty).
fn connected(mask: u8) -> bool {
    if mask == 0 {
        return true;
    }
    let mut seen = 1u8 << mask.trailing_zeros();
    loop {
        let mut next = seen;
        for c in 0..8 {
            if seen & (1 << c) != 0 {
                for bit in [1, 2, 4] {
                    next |= (1 << (c ^ bit)) & mask;
                }
            }
        }
        if next == seen {
            return seen == mask;
        }
        seen = next;
    }
}

/// The 8 boxes around the grid vertex `v` (the boxes v − (0 or 1 on each axis)), as offsets
/// c of [`connected`].
fn around(v: [i64; 3], c: usize) -> [i64; 3] {
    [
        v[0] - 1 + (c & 1) as i64,
        v[1] - 1 + ((c >> 1) & 1) as i64,
        v[2] - 1 + (c >> 2) as i64,
    ]
}

/// Adds to the sorted boxes `boxes` those that remove the pinches (module docs): around every
/// grid vertex of a box, the boxes present and those absent must each be connected through
/// faces, or the union's boundary would pass more than once through the vertex; otherwise the
/// absent ones are added. Returns each added box with a box present beside it, in the order of
/// addition.
fn fill_pinches(boxes: &mut Vec<[i64; 3]>) -> Vec<([i64; 3], [i64; 3])> {
    let mut fills = Vec::new();
    for _ in 0..MAX_FILL_ROUNDS {
        let has = |g: &[i64; 3]| boxes.binary_search(g).is_ok();
        // the corners b + (0 or 1 on each axis) of every box
        let mut vertices: Vec<[i64; 3]> = (boxes.iter())
            .flat_map(|b| (0..8).map(move |c| around([b[0] + 1, b[1] + 1, b[2] + 1], c)))
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        let mut add: Vec<([i64; 3], [i64; 3])> = Vec::new();
        for v in vertices {
            let mask = (0..8).fold(0u8, |m, c| m | (u8::from(has(&around(v, c))) << c));
            if connected(mask) && connected(!mask) {
                continue;
            }
            let from = around(v, mask.trailing_zeros() as usize);
            add.extend(
                (0..8)
                    .filter(|c| mask & (1 << c) == 0)
                    .map(|c| (around(v, c), from)),
            );
        }
        if add.is_empty() {
            break;
        }
        add.sort_unstable();
        add.dedup_by_key(|a| a.0);
        boxes.extend(add.iter().map(|a| a.0));
        boxes.sort_unstable();
        fills.extend(add);
    }
    fills
}

#[cfg(test)]
mod tests {
    use super::{around, connected, distinct_boxes, fill_pinches};

    /// The grid marking (keys in a small grid, negative ones too) and the sort (keys spread
    /// far apart) both give the sorted distinct keys.
    #[test]
    fn distinct_boxes_are_the_sorted_distinct_keys() {
        let mut rng = crate::mesh::test_rng(3);
        for spread in [3.0, 1e6] {
            let keys: Vec<[i64; 3]> = (0..500)
                .map(|_| [0, 1, 2].map(|_| (spread * (2.0 * rng() - 1.0)).floor() as i64))
                .collect();
            let mut want = keys.clone();
            want.sort_unstable();
            want.dedup();
            assert_eq!(distinct_boxes(&keys), want, "spread {spread}");
        }
        assert!(distinct_boxes(&[]).is_empty());
    }

    /// Whether some grid vertex has its present or its absent boxes disconnected.
    fn pinched(b: &[[i64; 3]]) -> bool {
        b.iter().any(|x| {
            (0..8).any(|c| {
                let v = around([x[0] + 1, x[1] + 1, x[2] + 1], c);
                let m = (0..8).fold(0u8, |m, c| m | (u8::from(b.contains(&around(v, c))) << c));
                !(connected(m) && connected(!m))
            })
        })
    }

    /// Boxes that share only an edge or only a corner are joined by filled boxes; boxes that
    /// share a face are left as they are.
    #[test]
    fn pinches_are_filled() {
        assert!(connected(0b0000_0011) && !connected(0b1000_0001) && !connected(0b0000_1001));
        for pair in [[[0, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 1]]] {
            let mut b = pair.to_vec();
            assert!(pinched(&b));
            let fills = fill_pinches(&mut b);
            assert!(!fills.is_empty() && !pinched(&b), "{b:?}");
            assert!(pair.iter().all(|p| b.contains(p)));
            assert!(
                fills
                    .iter()
                    .all(|(u, from)| b.contains(u) && b.contains(from))
            );
        }
        let mut face = vec![[0, 0, 0], [1, 0, 0]];
        assert!(!pinched(&face) && fill_pinches(&mut face).is_empty());
    }
}
