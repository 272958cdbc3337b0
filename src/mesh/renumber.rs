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

#[cfg(test)]
mod tests {
    use super::*;

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
