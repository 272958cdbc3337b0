//! Dropping the vertices no cell uses, for the readers of formats that may list extra nodes.

use super::Point;

/// Removes the vertices that no cell uses and renumbers the cells accordingly.
/// Returns the new vertices, the new cells, and for each old vertex its new id (`None` if dropped).
/// Readers of formats that may list extra nodes (gmsh) call this before
/// [`PolyMesh::from_cells`](super::PolyMesh::from_cells).
pub fn drop_unused_vertices(
    vertices: &[Point],
    cells: &[Vec<usize>],
) -> (Vec<Point>, Vec<Vec<usize>>, Vec<Option<usize>>) {
    let mut new_id = vec![None; vertices.len()];
    let mut new_vertices = Vec::new();
    let mut new_cells = Vec::with_capacity(cells.len());
    for c in cells {
        let mut nc = Vec::with_capacity(c.len());
        for &v in c {
            let id = match new_id.get(v).copied().flatten() {
                Some(id) => id,
                None if v < vertices.len() => {
                    let id = new_vertices.len();
                    new_vertices.push(vertices[v]);
                    new_id[v] = Some(id);
                    id
                }
                // out of range: keep an out-of-range id so that from_cells reports it
                None => usize::MAX,
            };
            nc.push(id);
        }
        new_cells.push(nc);
    }
    (new_vertices, new_cells, new_id)
}

/// As [`drop_unused_vertices`] for cells stored flat: renumbers the vertex ids of `cell_verts` in
/// place (vertices are kept in order of first use, an out-of-range id becomes `usize::MAX` so
/// that [`PolyMesh::from_flat_cells`] reports it) and returns the kept vertices and, for each old
/// vertex, its new id (`usize::MAX` if dropped).
pub(crate) fn drop_unused_vertices_flat(
    vertices: &[Point],
    cell_verts: &mut [usize],
) -> (Vec<Point>, Vec<usize>) {
    const DROPPED: usize = usize::MAX;
    let mut new_id = vec![DROPPED; vertices.len()];
    let mut new_vertices = Vec::new();
    for v in cell_verts.iter_mut() {
        *v = match new_id.get(*v) {
            Some(&id) if id != DROPPED => id,
            Some(_) => {
                let id = new_vertices.len();
                new_vertices.push(vertices[*v]);
                new_id[*v] = id;
                id
            }
            None => DROPPED,
        };
    }
    (new_vertices, new_id)
}

/// Renumbers the vertices of a mesh read from a file in space order: by the Morton (Z-order)
/// code of their coordinates in their bounding box (32 bits per axis, interleaved; ties by the
/// current number), the ids in `cell_verts` and `new_id` (old file index → vertex id, as
/// [`drop_unused_vertices_flat`] returns it; `usize::MAX` entries, dropped or out of range,
/// stay as they are) rewritten to match. Returns the vertices in their new order.
///
/// Why: the readers number the vertices in the order the cells first use them, and the edges
/// are numbered by their end points, so both follow the file's cell order, which for gmsh's
/// 2D meshes has no spatial coherence. The rows of HMM's edge system (and P1's vertex system)
/// then reach all over memory. On the re-seeded L-shape of 258 272 triangles (HMM, one
/// thread) the whole run took 4.10 s in the file's order and 2.63 s with the triangles in
/// Morton order (`replication/measurements/mesh.md`). The cells keep the file's order; the
/// vertex numbers were already the reader's own.
pub(crate) fn space_order(
    vertices: Vec<Point>,
    cell_verts: &mut [usize],
    new_id: &mut [usize],
) -> Vec<Point> {
    let n = vertices.len();
    if n < 2 {
        return vertices;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &vertices {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let len = [0, 1].map(|d| (hi[d] - lo[d]).max(f64::MIN_POSITIVE));
    let code = |p: &Point| {
        let q = |d: usize| (((p[d] - lo[d]) / len[d]).clamp(0.0, 1.0) * u32::MAX as f64) as u64;
        spread2(q(0)) | spread2(q(1)) << 1
    };
    let mut keyed: Vec<(u64, usize)> = vertices
        .iter()
        .enumerate()
        .map(|(i, p)| (code(p), i))
        .collect();
    keyed.sort_unstable();
    let mut id_of = vec![0usize; n];
    for (new, &(_, old)) in keyed.iter().enumerate() {
        id_of[old] = new;
    }
    for v in cell_verts.iter_mut().chain(new_id.iter_mut()) {
        if *v < n {
            *v = id_of[*v];
        }
    }
    keyed.iter().map(|&(_, old)| vertices[old]).collect()
}

/// The 32 low bits of `v` spread to every other bit.
fn spread2(v: u64) -> u64 {
    let mut x = v & 0xffff_ffff;
    x = (x | x << 16) & 0x0000_ffff_0000_ffff;
    x = (x | x << 8) & 0x00ff_00ff_00ff_00ff;
    x = (x | x << 4) & 0x0f0f_0f0f_0f0f_0f0f;
    x = (x | x << 2) & 0x3333_3333_3333_3333;
    x = (x | x << 1) & 0x5555_5555_5555_5555;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertices of a scrambled grid come out in Z order; the cells and the file-index map
    /// point at the same coordinates as before, dropped entries stay dropped.
    #[test]
    fn vertices_are_renumbered_in_space_order() {
        assert_eq!(spread2(0b11), 0b101);
        assert_eq!(spread2(0xffff_ffff), 0x5555_5555_5555_5555);
        // a 4 × 4 grid of points listed in a scrambled order (7 is prime to 16)
        let v: Vec<Point> = (0..16)
            .map(|i| {
                let k = i * 7 % 16;
                [(k % 4) as f64, (k / 4) as f64]
            })
            .collect();
        let mut cells: Vec<usize> = vec![0, 5, 9, 3, 12, 15, usize::MAX];
        let mut ids: Vec<usize> = (0..16).collect();
        ids[4] = usize::MAX;
        let before: Vec<Option<Point>> = cells.iter().map(|&c| v.get(c).copied()).collect();
        let ids_before: Vec<Option<Point>> = ids.iter().map(|&c| v.get(c).copied()).collect();
        let w = space_order(v.clone(), &mut cells, &mut ids);
        let after: Vec<Option<Point>> = cells.iter().map(|&c| w.get(c).copied()).collect();
        let ids_after: Vec<Option<Point>> = ids.iter().map(|&c| w.get(c).copied()).collect();
        assert_eq!(before, after);
        assert_eq!(ids_before, ids_after);
        // Z order on the grid: (0,0), (1,0), (0,1), (1,1), (2,0), (3,0), (2,1), (3,1), (0,2)…
        let z: Vec<Point> = [
            [0, 0],
            [1, 0],
            [0, 1],
            [1, 1],
            [2, 0],
            [3, 0],
            [2, 1],
            [3, 1],
            [0, 2],
            [1, 2],
            [0, 3],
            [1, 3],
            [2, 2],
            [3, 2],
            [2, 3],
            [3, 3],
        ]
        .iter()
        .map(|&[x, y]| [x as f64, y as f64])
        .collect();
        assert_eq!(w, z);
    }

    #[test]
    fn flat_drop_unused_vertices_matches_the_nested_one() {
        let v: Vec<Point> = (0..8).map(|i| [i as f64, (i * i) as f64]).collect();
        let cells = vec![vec![5, 2, 7], vec![7, 2, 3, 9], vec![0, 5, 3]];
        let (nv, nc, ids) = drop_unused_vertices(&v, &cells);
        let mut flat: Vec<usize> = cells.concat();
        let (fv, fids) = drop_unused_vertices_flat(&v, &mut flat);
        assert_eq!(fv, nv);
        assert_eq!(flat, nc.concat());
        let ids: Vec<usize> = ids.iter().map(|i| i.unwrap_or(usize::MAX)).collect();
        assert_eq!(fids, ids);
    }
}
