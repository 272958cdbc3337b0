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
    let keys: Vec<[i64; 3]> = (0..fine.n_cells()).map(key).collect();
    let mut boxes = keys.clone();
    boxes.sort_unstable();
    boxes.dedup();
    let cell_of: Vec<u32> = keys
        .iter()
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
