//! The accessors of a [`PolyMesh`]: counts, vertices, cell and edge incidences, and the geometry
//! named in the crate's notation table.

use super::geometry::{dist, polygon_area_centroid_of, side_normal_dist};
use super::{NO_CELL, Point, PolyMesh, Rect, validate};

impl PolyMesh {
    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }
    /// Number of cells K.
    pub fn n_cells(&self) -> usize {
        self.cell_ptr.len().saturating_sub(1)
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
    /// The range of cell `k` in `cell_verts` and `cell_edges`.
    #[inline]
    pub(super) fn cell_range(&self, k: usize) -> std::ops::Range<usize> {
        self.cell_ptr[k] as usize..self.cell_ptr[k + 1] as usize
    }
    /// Counter-clockwise vertex ids of cell `k`, 32-bit (the mesh stores them so; vertex ids are
    /// below `u32::MAX`): `v as usize` is the id of [`PolyMesh::vertex`].
    #[inline]
    pub fn cell_vertices(&self, k: usize) -> &[u32] {
        &self.cell_verts[self.cell_range(k)]
    }
    /// Edges of cell `k`, 32-bit like [`PolyMesh::cell_vertices`]; local edge i joins local
    /// vertices i and i+1.
    #[inline]
    pub fn cell_edges(&self, k: usize) -> &[u32] {
        &self.cell_edges[self.cell_range(k)]
    }
    /// The two end points of local edge `i` of cell `k` (local vertices i and i+1, cyclically),
    /// in counter-clockwise order.
    #[inline]
    fn cell_side_points(&self, k: usize, i: usize) -> (Point, Point) {
        let c = self.cell_vertices(k);
        let j = if i + 1 < c.len() { i + 1 } else { 0 };
        (self.vertices[c[i] as usize], self.vertices[c[j] as usize])
    }
    /// The outward unit normal n_{K,σ} and the distance d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 of
    /// local edge `i` of cell `k` (joining local vertices i and i+1), computed from the vertices
    /// and the centroid (not stored; no allocation).
    #[inline]
    pub fn cell_normal_dist(&self, k: usize, i: usize) -> (Point, f64) {
        self.cell_normal_dist_from(k, i, self.centroid(k))
    }
    /// [`PolyMesh::cell_normal_dist`] with x_K given (`xk`, the value of
    /// [`PolyMesh::centroid`]): for callers that have it, so that it is not computed per side.
    #[inline]
    pub(crate) fn cell_normal_dist_from(&self, k: usize, i: usize, xk: Point) -> (Point, f64) {
        let (p, q) = self.cell_side_points(k, i);
        side_normal_dist(p, q, xk)
    }
    /// The outward unit normal n_{K,σ} of cell `k` on its local edge `i` (joining local
    /// vertices i and i+1); see [`PolyMesh::cell_normal_dist`].
    #[inline]
    pub fn cell_normal(&self, k: usize, i: usize) -> Point {
        self.cell_normal_dist(k, i).0
    }
    /// The distance d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 from x_K to local edge `i` of cell `k`;
    /// see [`PolyMesh::cell_normal_dist`].
    #[inline]
    pub fn cell_dist(&self, k: usize, i: usize) -> f64 {
        self.cell_normal_dist(k, i).1
    }
    /// (n_{K,σ}, d_{K,σ}) of every local edge of cell `k`, in the order of
    /// [`PolyMesh::cell_edges`]: the values of [`PolyMesh::cell_normal_dist`], computed one at a
    /// time as the iterator advances (no allocation).
    pub fn cell_normals_dists(&self, k: usize) -> impl ExactSizeIterator<Item = (Point, f64)> + '_ {
        let c = self.cell_vertices(k);
        let xk = self.centroid(k);
        let n = c.len();
        // each corner is read once: the end of side i is the start of side i+1
        let mut p = self.vertices[c[0] as usize];
        (0..n).map(move |i| {
            let q = self.vertices[c[if i + 1 < n { i + 1 } else { 0 }] as usize];
            let side = side_normal_dist(p, q, xk);
            p = q;
            side
        })
    }
    /// The two vertex ids of edge `e` (smaller id first).
    #[inline]
    pub fn edge_vertices(&self, e: usize) -> [usize; 2] {
        self.edges[e].map(|v| v as usize)
    }
    /// The cells on either side of edge `e`: the lower-numbered cell first for an interior edge,
    /// `[K, NO_CELL]` on the boundary.
    #[inline]
    pub fn edge_cells(&self, e: usize) -> [usize; 2] {
        let [k, l] = self.edge_cells[e];
        [k as usize, if l == u32::MAX { NO_CELL } else { l as usize }]
    }
    /// Whether edge `e` lies on ∂Ω.
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_cells[e][1] == u32::MAX
    }
    /// The boundary edges, in increasing order.
    pub fn boundary_edges(&self) -> &[usize] {
        &self.boundary_edges
    }
    /// The position in [`Self::boundary_edges`] of the boundary edge between the vertices `a`
    /// and `b` (either order), if there is one. A binary search: edges are numbered in
    /// increasing (smaller vertex, larger vertex) order and the boundary edges are listed in
    /// increasing edge number, so that list is sorted by vertex pair already.
    pub(crate) fn boundary_position(&self, a: usize, b: usize) -> Option<usize> {
        let key = [a.min(b), a.max(b)];
        self.boundary_edges
            .binary_search_by(|&e| self.edge_vertices(e).cmp(&key))
            .ok()
    }
    /// Boundary tag of edge `e` (0 if none).
    pub fn edge_tag(&self, e: usize) -> i32 {
        if !self.is_boundary_edge(e) {
            return 0;
        }
        // boundary_edges is sorted: O(log n_boundary)
        match self.boundary_edges.binary_search(&e) {
            Ok(i) => self.boundary_tags[i],
            Err(_) => 0,
        }
    }
    /// |K|.
    #[inline]
    pub fn measure(&self, k: usize) -> f64 {
        self.area_centroid(k).0
    }
    /// x_K, the centre of mass of cell `k`.
    #[inline]
    pub fn centroid(&self, k: usize) -> Point {
        self.area_centroid(k).1
    }
    /// (|K|, x_K), computed from the vertices (not stored): the shoelace formula on the fan
    /// from the first corner ([`polygon_area_centroid`](super::geometry::polygon_area_centroid)),
    /// on the corners in the order the cell was given (a clockwise cell, whose list the mesh
    /// reversed, is read backwards), so that the values are those the validation computed.
    #[inline]
    pub fn area_centroid(&self, k: usize) -> (f64, Point) {
        let c = self.cell_vertices(k);
        let m = c.len();
        let v = &self.vertices;
        let reversed = !self.reversed.is_empty() && self.reversed[k / 64] >> (k % 64) & 1 == 1;
        let (a, x) = if reversed {
            polygon_area_centroid_of(m, |i| v[c[m - 1 - i] as usize])
        } else {
            polygon_area_centroid_of(m, |i| v[c[i] as usize])
        };
        (a.abs(), x)
    }
    /// h_K.
    pub fn diameter(&self, k: usize) -> f64 {
        // computed on demand (8 bytes per cell less; nothing reads it in a loop)
        let pts: Vec<Point> = self
            .cell_vertices(k)
            .iter()
            .map(|&v| self.vertices[v as usize])
            .collect();
        validate::diameter(&pts)
    }
    /// |σ|.
    pub fn edge_measure(&self, e: usize) -> f64 {
        let [a, b] = self.edge_vertices(e);
        dist(self.vertices[a], self.vertices[b])
    }
    /// x_σ = (a + b)/2 for the end points a, b (the same bits in either order).
    pub fn edge_midpoint(&self, e: usize) -> Point {
        let [a, b] = self.edge_vertices(e);
        let (p, q) = (self.vertices[a], self.vertices[b]);
        [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]
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
                let [a, b] = self.edge_vertices(e);
                self.vertices[a][axis] == value && self.vertices[b][axis] == value
            })
            .count()
    }
    /// The smallest axis-parallel rectangle that holds every vertex.
    pub fn bounding_box(&self) -> Rect {
        let mut b = Rect::new(
            [f64::INFINITY, f64::NEG_INFINITY],
            [f64::INFINITY, f64::NEG_INFINITY],
        );
        for p in &self.vertices {
            b.x[0] = b.x[0].min(p[0]);
            b.y[0] = b.y[0].min(p[1]);
            b.x[1] = b.x[1].max(p[0]);
            b.y[1] = b.y[1].max(p[1]);
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
            ptr[v as usize + 1] += 1;
        }
        for i in 0..nv {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut ids = vec![0usize; self.cell_verts.len()];
        for k in 0..self.n_cells() {
            for &v in self.cell_vertices(k) {
                let v = v as usize;
                ids[fill[v]] = k;
                fill[v] += 1;
            }
        }
        (ptr, ids)
    }
}

#[cfg(test)]
mod tests {
    use super::super::geometry::sub;
    use super::super::{test_meshes, unit_square_2x1};
    use super::*;

    #[test]
    fn cell_measures_and_centroids_are_those_of_the_cells_as_given() {
        // the unit square in two triangles and three quadrilaterals, two of them given
        // clockwise, with coordinates that do not round evenly: |K| and x_K (computed on
        // demand) have the bits of the shoelace formula on the corners in the order given,
        // although the mesh stores the clockwise cells reversed
        let v = vec![
            [0.0, 0.0],
            [0.3, 0.0],
            [1.0, 0.0],
            [0.0, 0.7],
            [0.37, 0.61],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.45, 1.0],
        ];
        let cells = vec![
            vec![0, 3, 4, 1], // clockwise
            vec![1, 2, 4],
            vec![2, 4, 7, 5], // clockwise
            vec![3, 4, 7, 6],
        ];
        let m = PolyMesh::from_cells(v.clone(), cells.clone()).unwrap();
        let mut any_reversed = false;
        for (k, c) in cells.iter().enumerate() {
            let pts: Vec<Point> = c.iter().map(|&i| v[i]).collect();
            let (a, x) = super::super::geometry::polygon_area_centroid(&pts);
            any_reversed |= a < 0.0;
            assert_eq!(m.measure(k).to_bits(), a.abs().to_bits(), "cell {k}");
            assert_eq!(
                m.centroid(k).map(f64::to_bits),
                x.map(f64::to_bits),
                "cell {k}"
            );
        }
        assert!(
            any_reversed,
            "no clockwise cell: the test would not exercise the reversal"
        );
    }

    #[test]
    fn the_face_geometry_of_a_cell_is_that_of_the_accessors() {
        use crate::mesh::complex::CellComplex;
        for m in test_meshes() {
            for k in 0..m.n_cells() {
                for (i, &e) in m.cell_edges(k).iter().enumerate() {
                    let got = CellComplex::cell_face_geometry(&m, k, i, m.centroid(k));
                    let (n, d) = m.cell_normal_dist(k, i);
                    let bits = |p: Point| p.map(f64::to_bits);
                    assert_eq!(got.measure.to_bits(), m.edge_measure(e as usize).to_bits());
                    assert_eq!(bits(got.centre), bits(m.edge_midpoint(e as usize)));
                    assert_eq!(
                        (bits(got.normal), got.dist.to_bits()),
                        (bits(n), d.to_bits())
                    );
                }
            }
        }
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
                let e = e as usize;
                let (n, d) = m.cell_normal_dist(k, i);
                assert_eq!(n, m.cell_normal(k, i));
                assert_eq!(d, m.cell_dist(k, i));
                s[0] += m.edge_measure(e) * n[0];
                s[1] += m.edge_measure(e) * n[1];
                vol += m.edge_measure(e) * d;
            }
            assert!(s[0].abs() < 1e-15 && s[1].abs() < 1e-15);
            assert!((vol - 2.0 * m.measure(k)).abs() < 1e-15);
        }
        assert!((m.h() - (0.25f64 + 1.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn side_geometry_is_computed_on_demand_consistently() {
        let meshes = test_meshes();
        for m in &meshes {
            for k in 0..m.n_cells() {
                let sides: Vec<(Point, f64)> = m.cell_normals_dists(k).collect();
                assert_eq!(sides.len(), m.cell_edges(k).len());
                let xk = m.centroid(k);
                for (i, &e) in m.cell_edges(k).iter().enumerate() {
                    let e = e as usize;
                    let (n, d) = sides[i];
                    assert_eq!((n, d), m.cell_normal_dist(k, i));
                    assert_eq!((n, d), (m.cell_normal(k, i), m.cell_dist(k, i)));
                    // a unit normal to σ pointing away from x_K
                    let [a, b] = m.edge_vertices(e);
                    let t = sub(m.vertex(b), m.vertex(a));
                    assert!((n[0] * n[0] + n[1] * n[1] - 1.0).abs() < 1e-15);
                    assert!((n[0] * t[0] + n[1] * t[1]).abs() < 1e-14 * m.edge_measure(e));
                    // d_{K,σ} from the stored x_σ: the same bits
                    let xs = m.edge_midpoint(e);
                    assert_eq!(d, (xs[0] - xk[0]) * n[0] + (xs[1] - xk[1]) * n[1]);
                    assert!(d > 0.0);
                }
            }
        }
    }
}
