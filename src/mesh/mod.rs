//! Two-dimensional polytopal meshes as flat, immutable, index-based data.
//!
//! A [`PolyMesh`] is built once from vertex coordinates and cell vertex lists
//! ([`PolyMesh::from_cells`]); the constructor fixes the orientation of every cell to
//! counter-clockwise, derives the edges (faces σ), the cell↔edge incidences and the boundary, caches
//! the geometry named in the crate's notation table, and validates everything HMM needs (see
//! [`MeshError`]). Nothing is mutated afterwards; transformations return new meshes.
//!
//! | accessor | maths |
//! |---|---|
//! | [`PolyMesh::measure`] | \|K\| |
//! | [`PolyMesh::centroid`] | x_K (centre of mass, not the vertex average) |
//! | [`PolyMesh::diameter`] | h_K = max distance between two vertices of K |
//! | [`PolyMesh::edge_measure`] | \|σ\| |
//! | [`PolyMesh::edge_midpoint`] | x_σ |
//! | [`PolyMesh::cell_normals`] | n_{K,σ}, outward unit normals, one per local edge |
//! | [`PolyMesh::cell_dists`] | d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 |
//! | [`PolyMesh::h`] | h = max_K h_K |

pub mod generate;
pub mod io;

use crate::error::MeshError;

/// Marker for "no cell" in [`PolyMesh::edge_cells`] (the second cell of a boundary edge).
pub const NO_CELL: usize = usize::MAX;

/// A 2D point or vector.
pub type Point = [f64; 2];

/// A conforming polygonal mesh with cached geometry. See the module docs.
#[derive(Debug, Clone)]
pub struct PolyMesh {
    vertices: Vec<Point>,
    /// CSR offsets into `cell_verts`, `cell_edges`, `cell_normals`, `cell_dists`.
    cell_ptr: Vec<usize>,
    /// Counter-clockwise vertex ids of every cell.
    cell_verts: Vec<usize>,
    /// Local edge i of cell K joins local vertices i and i+1 (cyclically).
    cell_edges: Vec<usize>,
    cell_normals: Vec<Point>,
    cell_dists: Vec<f64>,
    /// Edge end points (smaller vertex id first).
    edges: Vec<[usize; 2]>,
    /// The cells on either side of an edge; `[K, NO_CELL]` on the boundary.
    edge_cells: Vec<[usize; 2]>,
    /// Boundary tag of each edge (0 for interior edges and untagged boundary edges).
    edge_tags: Vec<i32>,
    cell_area: Vec<f64>,
    cell_centroid: Vec<Point>,
    cell_diameter: Vec<f64>,
    edge_length: Vec<f64>,
    edge_midpoint: Vec<Point>,
    boundary_edges: Vec<usize>,
    h: f64,
}

fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}

fn dist(a: Point, b: Point) -> f64 {
    let d = sub(a, b);
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

/// Signed area and centroid of a polygon given by its vertices in order
/// (positive area for counter-clockwise order). Computed relative to the first vertex
/// for accuracy.
pub fn polygon_area_centroid(pts: &[Point]) -> (f64, Point) {
    let o = pts[0];
    let mut a2 = 0.0;
    let mut cx = 0.0;
    let mut cy = 0.0;
    for i in 1..pts.len().saturating_sub(1) {
        let p = sub(pts[i], o);
        let q = sub(pts[i + 1], o);
        let cr = p[0] * q[1] - p[1] * q[0];
        a2 += cr;
        cx += cr * (p[0] + q[0]);
        cy += cr * (p[1] + q[1]);
    }
    let area = 0.5 * a2;
    if a2 == 0.0 {
        return (0.0, o);
    }
    (area, [o[0] + cx / (3.0 * a2), o[1] + cy / (3.0 * a2)])
}

/// Removes the vertices that no cell uses and renumbers the cells accordingly.
/// Returns the new vertices, the new cells, and for each old vertex its new id (`None` if dropped).
/// Readers of formats that may list extra nodes (gmsh) call this before [`PolyMesh::from_cells`].
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

impl PolyMesh {
    /// Builds and validates a mesh from vertex coordinates and cell vertex lists (0-based ids,
    /// either orientation: clockwise cells are reversed). No boundary tags.
    pub fn from_cells(vertices: Vec<Point>, cells: Vec<Vec<usize>>) -> Result<Self, MeshError> {
        Self::from_cells_tagged(vertices, cells, &[])
    }

    /// As [`PolyMesh::from_cells`], with boundary tags given as `(vertex a, vertex b, tag)` for
    /// boundary edges (either vertex order). Entries naming an edge that is not a boundary edge of
    /// the mesh are an error.
    pub fn from_cells_tagged(
        vertices: Vec<Point>,
        cells: Vec<Vec<usize>>,
        tagged_edges: &[(usize, usize, i32)],
    ) -> Result<Self, MeshError> {
        let nv = vertices.len();
        let nc = cells.len();
        if nc == 0 {
            return Err(MeshError::Empty);
        }
        for (v, p) in vertices.iter().enumerate() {
            if !p[0].is_finite() || !p[1].is_finite() {
                return Err(MeshError::NonFiniteVertex { vertex: v });
            }
        }
        // --- cells: range, size, repeated vertices, orientation, area, centroid, diameter
        let mut cell_ptr = Vec::with_capacity(nc + 1);
        cell_ptr.push(0);
        let mut cell_verts = Vec::with_capacity(cells.iter().map(Vec::len).sum());
        let mut cell_area = Vec::with_capacity(nc);
        let mut cell_centroid = Vec::with_capacity(nc);
        let mut cell_diameter = Vec::with_capacity(nc);
        let mut used = vec![false; nv];
        let mut pts: Vec<Point> = Vec::new();
        for (k, c) in cells.iter().enumerate() {
            if c.len() < 3 {
                return Err(MeshError::BadCell {
                    cell: k,
                    msg: format!("has {} vertices, at least 3 are needed", c.len()),
                });
            }
            for &v in c {
                if v >= nv {
                    return Err(MeshError::VertexOutOfRange {
                        cell: k,
                        vertex: v,
                        n_vertices: nv,
                    });
                }
                used[v] = true;
            }
            for i in 0..c.len() {
                if c[i + 1..].contains(&c[i]) {
                    return Err(MeshError::BadCell {
                        cell: k,
                        msg: format!("lists vertex {} twice", c[i]),
                    });
                }
            }
            pts.clear();
            pts.extend(c.iter().map(|&v| vertices[v]));
            let (area, centroid) = polygon_area_centroid(&pts);
            let mut diam: f64 = 0.0;
            for i in 0..pts.len() {
                for j in i + 1..pts.len() {
                    diam = diam.max(dist(pts[i], pts[j]));
                }
            }
            if !(area.abs() > 1e-14 * diam * diam) {
                return Err(MeshError::DegenerateCell { cell: k, area });
            }
            if area > 0.0 {
                cell_verts.extend_from_slice(c);
            } else {
                cell_verts.extend(c.iter().rev());
            }
            cell_ptr.push(cell_verts.len());
            cell_area.push(area.abs());
            cell_centroid.push(centroid);
            cell_diameter.push(diam);
        }
        if let Some(v) = used.iter().position(|u| !u) {
            return Err(MeshError::UnusedVertex { vertex: v });
        }
        check_duplicate_vertices(&vertices)?;

        // --- edges: sort the (min, max, cell, local index, forward?) records
        let n_half = cell_verts.len();
        let mut half: Vec<(usize, usize, usize, usize)> = Vec::with_capacity(n_half); // (a, b, k, slot)
        for k in 0..nc {
            let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
            let n = e - s;
            for i in 0..n {
                let a = cell_verts[s + i];
                let b = cell_verts[s + (i + 1) % n];
                half.push((a, b, k, s + i));
            }
        }
        let mut order: Vec<usize> = (0..n_half).collect();
        order.sort_unstable_by_key(|&i| {
            let (a, b, _, _) = half[i];
            (a.min(b), a.max(b))
        });
        let mut edges = Vec::new();
        let mut edge_cells = Vec::new();
        let mut cell_edges = vec![0usize; n_half];
        let mut i = 0;
        while i < n_half {
            let (a, b, k, slot) = half[order[i]];
            let key = (a.min(b), a.max(b));
            let e = edges.len();
            edges.push([key.0, key.1]);
            cell_edges[slot] = e;
            let mut cells_of_edge = [k, NO_CELL];
            let mut j = i + 1;
            while j < n_half {
                let (a2, b2, k2, slot2) = half[order[j]];
                if (a2.min(b2), a2.max(b2)) != key {
                    break;
                }
                if j > i + 1 {
                    return Err(MeshError::BadEdge {
                        a: key.0,
                        b: key.1,
                        msg: "shared by more than two cells".into(),
                    });
                }
                if (a2, b2) == (a, b) {
                    return Err(MeshError::BadEdge {
                        a: key.0,
                        b: key.1,
                        msg: format!(
                            "cells {k} and {k2} traverse it in the same direction (overlapping cells)"
                        ),
                    });
                }
                cells_of_edge[1] = k2;
                cell_edges[slot2] = e;
                j += 1;
            }
            edge_cells.push(cells_of_edge);
            i = j;
        }
        let ne = edges.len();
        let edge_length: Vec<f64> = edges
            .iter()
            .map(|&[a, b]| dist(vertices[a], vertices[b]))
            .collect();
        let edge_midpoint: Vec<Point> = edges
            .iter()
            .map(|&[a, b]| {
                [
                    0.5 * (vertices[a][0] + vertices[b][0]),
                    0.5 * (vertices[a][1] + vertices[b][1]),
                ]
            })
            .collect();

        // --- normals and d_{K,σ}; star-shapedness with respect to the centroid
        let mut cell_normals = vec![[0.0; 2]; n_half];
        let mut cell_dists = vec![0.0; n_half];
        for k in 0..nc {
            let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
            let n = e - s;
            for i in 0..n {
                let p = vertices[cell_verts[s + i]];
                let q = vertices[cell_verts[s + (i + 1) % n]];
                let t = sub(q, p);
                let len = (t[0] * t[0] + t[1] * t[1]).sqrt();
                // counter-clockwise cell: outward normal is the tangent rotated by −90°
                let nrm = [t[1] / len, -t[0] / len];
                let xs = edge_midpoint[cell_edges[s + i]];
                let d =
                    (xs[0] - cell_centroid[k][0]) * nrm[0] + (xs[1] - cell_centroid[k][1]) * nrm[1];
                if !(d > 1e-12 * cell_diameter[k]) {
                    return Err(MeshError::NotStarShaped {
                        cell: k,
                        local_edge: i,
                        dist: d,
                    });
                }
                cell_normals[s + i] = nrm;
                cell_dists[s + i] = d;
            }
        }

        let boundary_edges: Vec<usize> = (0..ne).filter(|&e| edge_cells[e][1] == NO_CELL).collect();
        check_boundary_loops(
            &vertices,
            &edges,
            &edge_cells,
            &cell_ptr,
            &cell_verts,
            &cell_edges,
            &boundary_edges,
        )?;

        // --- tags
        let mut edge_tags = vec![0i32; ne];
        if !tagged_edges.is_empty() {
            let mut lookup: Vec<((usize, usize), usize)> = boundary_edges
                .iter()
                .map(|&e| ((edges[e][0], edges[e][1]), e))
                .collect();
            lookup.sort_unstable();
            for &(a, b, tag) in tagged_edges {
                let key = (a.min(b), a.max(b));
                match lookup.binary_search_by(|probe| probe.0.cmp(&key)) {
                    Ok(pos) => edge_tags[lookup[pos].1] = tag,
                    Err(_) => {
                        return Err(MeshError::BadEdge {
                            a: key.0,
                            b: key.1,
                            msg: format!("tagged {tag} but it is not a boundary edge of the mesh"),
                        });
                    }
                }
            }
        }
        let h = cell_diameter.iter().cloned().fold(0.0, f64::max);
        Ok(PolyMesh {
            vertices,
            cell_ptr,
            cell_verts,
            cell_edges,
            cell_normals,
            cell_dists,
            edges,
            edge_cells,
            edge_tags,
            cell_area,
            cell_centroid,
            cell_diameter,
            edge_length,
            edge_midpoint,
            boundary_edges,
            h,
        })
    }

    /// Returns a copy whose boundary edges are tagged by `tag(x_σ)` (interior edges keep tag 0).
    pub fn with_boundary_tags(&self, tag: impl Fn(Point) -> i32) -> PolyMesh {
        let mut m = self.clone();
        for &e in &self.boundary_edges {
            m.edge_tags[e] = tag(self.edge_midpoint[e]);
        }
        m
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }
    /// Number of cells K.
    pub fn n_cells(&self) -> usize {
        self.cell_area.len()
    }
    /// Number of edges σ (faces).
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }
    /// All vertex coordinates.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }
    /// Coordinates of vertex `v`.
    pub fn vertex(&self, v: usize) -> Point {
        self.vertices[v]
    }
    /// Counter-clockwise vertex ids of cell `k`.
    pub fn cell_vertices(&self, k: usize) -> &[usize] {
        &self.cell_verts[self.cell_ptr[k]..self.cell_ptr[k + 1]]
    }
    /// Edges of cell `k`; local edge i joins local vertices i and i+1.
    pub fn cell_edges(&self, k: usize) -> &[usize] {
        &self.cell_edges[self.cell_ptr[k]..self.cell_ptr[k + 1]]
    }
    /// Outward unit normals n_{K,σ} of cell `k`, one per local edge.
    pub fn cell_normals(&self, k: usize) -> &[Point] {
        &self.cell_normals[self.cell_ptr[k]..self.cell_ptr[k + 1]]
    }
    /// Distances d_{K,σ} from x_K to the edges of cell `k`, one per local edge.
    pub fn cell_dists(&self, k: usize) -> &[f64] {
        &self.cell_dists[self.cell_ptr[k]..self.cell_ptr[k + 1]]
    }
    /// The two vertex ids of edge `e` (smaller id first).
    pub fn edge_vertices(&self, e: usize) -> [usize; 2] {
        self.edges[e]
    }
    /// The cells on either side of edge `e`; the second is [`NO_CELL`] on the boundary.
    pub fn edge_cells(&self, e: usize) -> [usize; 2] {
        self.edge_cells[e]
    }
    /// Whether edge `e` lies on ∂Ω.
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_cells[e][1] == NO_CELL
    }
    /// The boundary edges, in increasing order.
    pub fn boundary_edges(&self) -> &[usize] {
        &self.boundary_edges
    }
    /// Boundary tag of edge `e` (0 if none).
    pub fn edge_tag(&self, e: usize) -> i32 {
        self.edge_tags[e]
    }
    /// |K|.
    pub fn measure(&self, k: usize) -> f64 {
        self.cell_area[k]
    }
    /// x_K, the centre of mass of cell `k`.
    pub fn centroid(&self, k: usize) -> Point {
        self.cell_centroid[k]
    }
    /// h_K.
    pub fn diameter(&self, k: usize) -> f64 {
        self.cell_diameter[k]
    }
    /// |σ|.
    pub fn edge_measure(&self, e: usize) -> f64 {
        self.edge_length[e]
    }
    /// x_σ.
    pub fn edge_midpoint(&self, e: usize) -> Point {
        self.edge_midpoint[e]
    }
    /// h = max_K h_K.
    pub fn h(&self) -> f64 {
        self.h
    }
    /// Number of boundary edges lying on the line {x_axis = value} (both end points exactly on
    /// it), e.g. `boundary_edges_on(0, 0.0)` counts the edges on x = 0.
    pub fn boundary_edges_on(&self, axis: usize, value: f64) -> usize {
        self.boundary_edges
            .iter()
            .filter(|&&e| {
                let [a, b] = self.edges[e];
                self.vertices[a][axis] == value && self.vertices[b][axis] == value
            })
            .count()
    }
    /// Bounding box `[xmin, ymin, xmax, ymax]`.
    pub fn bounding_box(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in &self.vertices {
            b[0] = b[0].min(p[0]);
            b[1] = b[1].min(p[1]);
            b[2] = b[2].max(p[0]);
            b[3] = b[3].max(p[1]);
        }
        b
    }
    /// Whether every cell is a triangle.
    pub fn is_triangular(&self) -> bool {
        (0..self.n_cells()).all(|k| self.cell_ptr[k + 1] - self.cell_ptr[k] == 3)
    }
    /// Cells incident to each vertex (CSR: offsets, cell ids).
    pub fn vertex_cells(&self) -> (Vec<usize>, Vec<usize>) {
        let nv = self.n_vertices();
        let mut ptr = vec![0usize; nv + 1];
        for &v in &self.cell_verts {
            ptr[v + 1] += 1;
        }
        for i in 0..nv {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut ids = vec![0usize; self.cell_verts.len()];
        for k in 0..self.n_cells() {
            for &v in self.cell_vertices(k) {
                ids[fill[v]] = k;
                fill[v] += 1;
            }
        }
        (ptr, ids)
    }
}

fn check_duplicate_vertices(vertices: &[Point]) -> Result<(), MeshError> {
    let mut idx: Vec<usize> = (0..vertices.len()).collect();
    idx.sort_unstable_by(|&a, &b| {
        vertices[a][0]
            .total_cmp(&vertices[b][0])
            .then(vertices[a][1].total_cmp(&vertices[b][1]))
    });
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in vertices {
        lo = lo.min(p[0]).min(p[1]);
        hi = hi.max(p[0]).max(p[1]);
    }
    let tol = 1e-13 * (hi - lo).max(1e-300);
    // end of the run of identical x values starting at each sorted position: inside a run the
    // y values are sorted, so the scan can jump past the run once y is out of reach (O(n log n))
    let n = idx.len();
    let mut run_end = vec![n; n];
    for i in (0..n.saturating_sub(1)).rev() {
        run_end[i] = if vertices[idx[i + 1]][0] == vertices[idx[i]][0] {
            run_end[i + 1]
        } else {
            i + 1
        };
    }
    for i in 0..n {
        let a = idx[i];
        let mut j = i + 1;
        while j < n {
            let b = idx[j];
            if vertices[b][0] - vertices[a][0] > tol {
                break;
            }
            if (vertices[b][1] - vertices[a][1]).abs() <= tol {
                return Err(MeshError::DuplicateVertex {
                    a: a.min(b),
                    b: a.max(b),
                    x: vertices[a][0],
                    y: vertices[a][1],
                });
            }
            if vertices[b][0] == vertices[a][0] && vertices[b][1] - vertices[a][1] > tol {
                j = run_end[j];
            } else {
                j += 1;
            }
        }
    }
    Ok(())
}

/// The boundary, oriented by its cells, must split into simple closed loops of non-zero area.
/// A hanging node (a cell side that is split in its neighbours but not in the cell itself) shows
/// up as a zero-area loop; a pinched vertex as a vertex with two outgoing boundary edges.
fn check_boundary_loops(
    vertices: &[Point],
    edges: &[[usize; 2]],
    edge_cells: &[[usize; 2]],
    cell_ptr: &[usize],
    cell_verts: &[usize],
    cell_edges: &[usize],
    boundary_edges: &[usize],
) -> Result<(), MeshError> {
    // oriented boundary edge: start -> end following its cell's counter-clockwise order
    let mut next: std::collections::BTreeMap<usize, usize> = std::collections::BTreeMap::new();
    for &e in boundary_edges {
        let k = edge_cells[e][0];
        let (s, t) = (cell_ptr[k], cell_ptr[k + 1]);
        let n = t - s;
        let i = (s..t)
            .find(|&i| cell_edges[i] == e)
            .expect("edge belongs to its cell")
            - s;
        let a = cell_verts[s + i];
        let b = cell_verts[s + (i + 1) % n];
        if next.insert(a, b).is_some() {
            return Err(MeshError::NonConforming(format!(
                "vertex {a} starts two boundary edges (pinched boundary or hanging node)"
            )));
        }
    }
    let mut total = 0.0;
    let mut loops = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for (&start, _) in next.iter() {
        if seen.contains(&start) {
            continue;
        }
        let mut pts = Vec::new();
        let mut v = start;
        loop {
            if !seen.insert(v) {
                return Err(MeshError::NonConforming(format!(
                    "boundary loop through vertex {v} does not close"
                )));
            }
            pts.push(vertices[v]);
            v = match next.get(&v) {
                Some(&w) => w,
                None => {
                    return Err(MeshError::NonConforming(format!(
                        "boundary edge ending at vertex {v} has no successor"
                    )));
                }
            };
            if v == start {
                break;
            }
        }
        let (area, _) = polygon_area_centroid(&pts);
        total += area.abs();
        loops.push((start, area));
    }
    let _ = edges;
    for (start, area) in loops {
        if area.abs() <= 1e-10 * total {
            return Err(MeshError::NonConforming(format!(
                "the boundary loop through vertex {start} encloses no area: a hanging node \
                 (a cell side split in the neighbouring cells but not in the cell itself)"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square_2x1() -> PolyMesh {
        let v = vec![
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [0.5, 1.0],
            [1.0, 1.0],
        ];
        // the second cell is clockwise on purpose
        PolyMesh::from_cells(v, vec![vec![0, 1, 4, 3], vec![1, 4, 5, 2]]).unwrap()
    }

    #[test]
    fn geometry_of_two_rectangles() {
        let m = unit_square_2x1();
        assert_eq!(m.n_cells(), 2);
        assert_eq!(m.n_edges(), 7);
        assert_eq!(m.boundary_edges().len(), 6);
        assert!((m.measure(0) - 0.5).abs() < 1e-15);
        assert!((m.centroid(1)[0] - 0.75).abs() < 1e-15);
        assert_eq!(m.cell_vertices(1), &[2, 5, 4, 1]);
        // Σ_σ |σ| n_{K,σ} = 0 and Σ_σ |σ| d_{K,σ} = 2|K|
        for k in 0..2 {
            let mut s = [0.0, 0.0];
            let mut vol = 0.0;
            for (i, &e) in m.cell_edges(k).iter().enumerate() {
                let n = m.cell_normals(k)[i];
                s[0] += m.edge_measure(e) * n[0];
                s[1] += m.edge_measure(e) * n[1];
                vol += m.edge_measure(e) * m.cell_dists(k)[i];
            }
            assert!(s[0].abs() < 1e-15 && s[1].abs() < 1e-15);
            assert!((vol - 2.0 * m.measure(k)).abs() < 1e-15);
        }
        assert!((m.h() - (0.25f64 + 1.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn rejects_invalid_meshes() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 7]]),
            Err(MeshError::VertexOutOfRange { .. })
        ));
        assert!(PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 3, 2]]).is_ok());
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 2]]),
            Err(MeshError::UnusedVertex { vertex: 3 })
        ));
        // bow-tie: zero signed area
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 2, 3]]),
            Err(MeshError::DegenerateCell { .. })
        ));
        // overlapping: same triangle twice
        assert!(matches!(
            PolyMesh::from_cells(v.clone(), vec![vec![0, 1, 3], vec![0, 1, 3], vec![0, 3, 2]]),
            Err(MeshError::BadEdge { .. })
        ));
        let d = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]];
        assert!(matches!(
            PolyMesh::from_cells(d, vec![vec![0, 1, 2], vec![3, 2, 1]]),
            Err(MeshError::DuplicateVertex { .. }) | Err(MeshError::BadEdge { .. })
        ));
    }

    #[test]
    fn rejects_non_star_shaped_cell() {
        // an arrow-shaped (non-convex) hexagon whose centroid sees one edge from behind
        let v = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.9, 0.1],
            [0.5, 0.05],
            [0.0, 1.0],
        ];
        let r = PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3, 4, 5]]);
        assert!(matches!(r, Err(MeshError::NotStarShaped { .. })), "{r:?}");
    }

    #[test]
    fn rejects_hanging_node() {
        // left cell is one square with 4 corners; the right side is split into two cells
        let v = vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 2.0],
            [1.0, 2.0],
            [2.0, 2.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ];
        let cells = vec![vec![0, 1, 4, 3], vec![1, 2, 7, 6], vec![6, 7, 5, 4]];
        let r = PolyMesh::from_cells(v, cells);
        assert!(matches!(r, Err(MeshError::NonConforming(_))), "{r:?}");
    }
}
