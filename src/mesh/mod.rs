//! Two-dimensional polytopal meshes as flat, immutable, index-based data.
//!
//! A [`PolyMesh`] is built once from vertex coordinates and cell vertex lists
//! ([`PolyMesh::from_cells`]); the constructor fixes the orientation of every cell to
//! counter-clockwise, derives the edges (faces σ), the cell↔edge incidences and the boundary, caches
//! the geometry named in the crate's notation table, and validates everything HMM needs: a
//! partition of a polygonal domain into simple, star-shaped polygons meeting edge to edge, with
//! no overlap, checked in O(n log n) time whatever the input (see [`validate`] for the list of
//! checks and their costs, and [`MeshError`]). Nothing is mutated afterwards; transformations
//! return new meshes.
//!
//! The geometry of the cells and edges is stored; that of the cell sides (one entry per
//! (cell, local edge), n_{K,σ} and d_{K,σ}) is not: [`PolyMesh::cell_normal`] and
//! [`PolyMesh::cell_dist`] compute it on demand from the vertices and the centroid, without
//! allocating, by the same floating-point operations that validated them (one function serves
//! both), so every value is the same, to the last bit, at every call. This saves 24 bytes per
//! cell side (144 MB on a mesh of 2·10⁶ triangles).
//!
//! | accessor | maths |
//! |---|---|
//! | [`PolyMesh::measure`] | \|K\| |
//! | [`PolyMesh::centroid`] | x_K (centre of mass, not the vertex average) |
//! | [`PolyMesh::diameter`] | h_K = max distance between two vertices of K |
//! | [`PolyMesh::edge_measure`] | \|σ\| |
//! | [`PolyMesh::edge_midpoint`] | x_σ |
//! | [`PolyMesh::cell_normal`] | n_{K,σ}, the outward unit normal on local edge i |
//! | [`PolyMesh::cell_dist`] | d_{K,σ} = (x_σ − x_K)·n_{K,σ} > 0 on local edge i |
//! | [`PolyMesh::cell_normals_dists`] | (n_{K,σ}, d_{K,σ}) for all local edges, in order |
//! | [`PolyMesh::h`] | h = max_K h_K |
//!
//! ## Dimension
//! [`PolyMesh`] is two-dimensional by nature: its checks (orientation, star-shapedness, the
//! overlap sweep), its readers and the agglomeration of the warm start are planar. What a
//! scheme's local computation reads from a mesh is not, and is the trait
//! [`CellComplex<D>`](complex::CellComplex) (|K|, x_K, |σ|, x_σ, n_{K,σ}, d_{K,σ} and the
//! cell–face incidence, for any dimension D), which `PolyMesh` implements for D = 2. HMM's
//! local form ([`crate::scheme::hmm::local_form`]) is written against it and tested on a 3-D
//! mesh of boxes (the patch test). The assembler, the active-set and projected Gauss–Seidel
//! solvers and the linear algebra never read coordinates (they see unknowns, local matrices
//! and a quadratic energy). The scheme trait
//! [`GradientDiscretisation<M, D>`](crate::scheme::GradientDiscretisation) is generic over the
//! mesh type `M: CellComplex<D>` and the dimension (points and gradients `[f64; D]`, tensors
//! `[[f64; D]; D]`), with defaults `PolyMesh` and 2; its tests implement it in 3-D (HMM on
//! boxes, `scheme/hmm.rs`) and solve a 3-D patch test through it. What is still 2-D above the
//! scheme layer: the problem data (closures of `[f64; 2]`, 2×2 tensors, the expression
//! variables x and y), the assembler's boundary conditions and data evaluation (instantiated
//! at `PolyMesh`: cell tags, boundary edges and their tags, edge midpoints), P1 and
//! Crouzeix–Raviart (triangles), the warm start (planar agglomeration) and the VTU writer
//! (polygons). A 3-D mesh type implements `CellComplex<3>` plus those tags and boundary faces;
//! the problem and the assembler then gain the dimension as a const parameter, as the scheme
//! trait has.

pub mod agglomerate;
pub(crate) mod buckets;
pub mod budget;
pub mod complex;
pub mod generate;
pub mod io;
mod predicates;
mod sweep;
pub mod validate;

pub use complex::CellComplex;
pub use generate::Family;
pub use validate::MAX_CELL_VERTICES;

use crate::error::MeshError;

/// Marker for "no cell" in [`PolyMesh::edge_cells`] (the second cell of a boundary edge).
pub const NO_CELL: usize = usize::MAX;

/// A 2D point or vector.
pub type Point = [f64; 2];

/// Whether [`PolyMesh::from_flat_cells`] sweeps for crossing edges and overlapping cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Overlap {
    /// Sweep (any input).
    Sweep,
    /// Not: the cells of a tensor-product grid with strictly increasing coordinates.
    ByConstruction,
}

/// A conforming polygonal mesh with cached geometry. See the module docs.
#[derive(Debug, Clone)]
pub struct PolyMesh {
    vertices: Vec<Point>,
    /// CSR offsets into `cell_verts` and `cell_edges`, 32-bit: the number of cell sides (entries
    /// of the cell vertex lists) is below `u32::MAX` (checked when building).
    cell_ptr: Vec<u32>,
    /// Counter-clockwise vertex ids of every cell, 32-bit like [`PolyMesh::cell_vertices`]
    /// returns them (4 bytes less per cell side than `usize`).
    cell_verts: Vec<u32>,
    /// Local edge i of cell K joins local vertices i and i+1 (cyclically); 32-bit (there are no
    /// more edges than cell sides).
    cell_edges: Vec<u32>,
    /// Edge end points (smaller vertex id first), 32-bit: vertex ids are below `u32::MAX`
    /// (checked when building). 8 bytes less per edge: 25 MB per million edges.
    edges: Vec<[u32; 2]>,
    /// The cells on either side of an edge; `[K, u32::MAX]` on the boundary (`NO_CELL` in
    /// [`PolyMesh::edge_cells`]). Cell ids are below `u32::MAX` (checked when building).
    edge_cells: Vec<[u32; 2]>,
    /// Boundary tag of each edge (0 for interior edges and untagged boundary edges).
    edge_tags: Vec<i32>,
    /// Tag of each cell (gmsh physical surface; 0 when untagged).
    cell_tags: Vec<i32>,
    cell_area: Vec<f64>,
    cell_centroid: Vec<Point>,
    // |σ| and x_σ are computed from the end points on demand (`edge_measure`,
    // `edge_midpoint`): 24 bytes per edge less, the same bits as stored values
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

/// [`MeshError::TooManyEntities`] unless the mesh's ids fit in its 32-bit arrays: vertex and cell
/// ids in the edge arrays (`u32::MAX` marking "no cell"), offsets into the cell arrays (up to the
/// number of cell sides) and edge ids in `cell_edges` (there are no more edges than cell sides).
fn check_counts(vertices: usize, cells: usize, sides: usize) -> Result<(), MeshError> {
    for (what, count) in [
        ("vertices", vertices),
        ("cells", cells),
        ("cell sides", sides),
    ] {
        if count >= u32::MAX as usize {
            return Err(MeshError::TooManyEntities { what, count });
        }
    }
    Ok(())
}

/// `v` as 32-bit values (all below `u32::MAX`, which the caller has checked), in a new array of
/// exactly that length; `v` is freed.
fn to_u32(v: Vec<usize>) -> Vec<u32> {
    debug_assert!(v.iter().all(|&x| x < u32::MAX as usize));
    v.iter().map(|&x| x as u32).collect()
}

/// n_{K,σ} and d_{K,σ} of the side from corner `p` to corner `q` of a counter-clockwise cell
/// with centroid `xk`: the outward unit normal (the tangent rotated by −90°) and
/// d_{K,σ} = (x_σ − x_K)·n_{K,σ}. The one definition of both, used by the validation (check 9)
/// and by the accessors of [`PolyMesh`], so that they agree to the last bit.
#[inline]
pub(crate) fn side_normal_dist(p: Point, q: Point, xk: Point) -> (Point, f64) {
    let t = sub(q, p);
    let len = (t[0] * t[0] + t[1] * t[1]).sqrt();
    // counter-clockwise cell: outward normal is the tangent rotated by −90°
    let nrm = [t[1] / len, -t[0] / len];
    // x_σ, the same bits as `PolyMesh::edge_midpoint` (floating-point addition commutes)
    let xs = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
    let d = (xs[0] - xk[0]) * nrm[0] + (xs[1] - xk[1]) * nrm[1];
    (nrm, d)
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

/// How [`PolyMesh::set_boundary_tags`] treats an entry that names no boundary edge of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NonBoundaryTag {
    /// Report it as [`MeshError::BadEdge`] (the contract of [`PolyMesh::from_cells_tagged`]).
    Reject,
    /// Skip it silently (gmsh line elements may be interior interfaces).
    Ignore,
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
        let mut cell_ptr = Vec::with_capacity(cells.len() + 1);
        cell_ptr.push(0);
        let mut cell_verts = Vec::with_capacity(cells.iter().map(Vec::len).sum());
        for c in &cells {
            cell_verts.extend_from_slice(c);
            cell_ptr.push(cell_verts.len());
        }
        drop(cells);
        let mut mesh = Self::from_flat_cells(vertices, cell_ptr, cell_verts, Overlap::Sweep)?;
        mesh.set_boundary_tags(tagged_edges, NonBoundaryTag::Reject)?;
        Ok(mesh)
    }

    /// As [`PolyMesh::from_cells`] (no tags), with the cells stored flat: cell `k` lists the
    /// vertices `cell_verts[cell_ptr[k]..cell_ptr[k + 1]]`. `cell_ptr` must start at 0, be
    /// non-decreasing and end at `cell_verts.len()` (the caller builds it; the cell contents are
    /// validated exactly as by [`PolyMesh::from_cells`], in the same order, with the same errors;
    /// [`MeshError::TooManyEntities`] if there are `u32::MAX` vertices, cells or cell sides or
    /// more). Clockwise cells are reversed in place in `cell_verts`, which the checks and the
    /// edge numbering read as `usize`; the mesh then keeps 32-bit copies of `cell_ptr` and
    /// `cell_verts`, made (and the `usize` arrays freed) before the overlap check, the peak of
    /// the construction. Readers pass flat cells to avoid one small allocation per cell.
    ///
    /// `overlap` says whether the sweep for crossing edges and overlapping cells (checks 11
    /// and 12, O(N log N) and sequential) runs: [`Overlap::ByConstruction`] only for the cells
    /// of a tensor-product grid whose coordinates increase strictly along both directions (the
    /// Cartesian generators check them), which tile their rectangle by construction (the sweep
    /// was 1.5 s of the 3 s taken by a 2048² triangulated grid); every other check runs.
    pub(crate) fn from_flat_cells(
        vertices: Vec<Point>,
        cell_ptr: Vec<usize>,
        mut cell_verts: Vec<usize>,
        overlap: Overlap,
    ) -> Result<Self, MeshError> {
        debug_assert!(
            cell_ptr.first() == Some(&0)
                && cell_ptr.last() == Some(&cell_verts.len())
                && cell_ptr.windows(2).all(|w| w[0] <= w[1]),
            "malformed cell_ptr"
        );
        let nv = vertices.len();
        if cell_ptr.len() < 2 {
            return Err(MeshError::Empty);
        }
        check_counts(nv, cell_ptr.len() - 1, cell_verts.len())?;
        // checks 1–5 of `validate` and the cell geometry, while the vertices are sorted for
        // checks 6 and 11 (the errors are reported in the order of the checks)
        let (cells, (duplicates, order)) = rayon::join(
            || validate::cell_geometry(&vertices, &cell_ptr, &mut cell_verts),
            || {
                rayon::join(
                    || validate::check_duplicate_vertices(&vertices),
                    || (overlap == Overlap::Sweep).then(|| sweep::SweepOrder::new(&vertices)),
                )
            },
        );
        let cells = cells?;
        duplicates?;

        // --- edges, numbered in (min, max) vertex order (check 7), and check 8 meanwhile
        let (built, simple) = rayon::join(
            || build_edges(nv, &cell_ptr, &cell_verts),
            || validate::check_simple_cells(&vertices, &cell_ptr, &cell_verts),
        );
        let Edges {
            edges,
            edge_cells,
            cell_edges,
        } = built?;
        simple?;
        let ne = edges.len();
        // not reached (every edge is a side of some cell), but the ids must fit in `cell_edges`
        if ne >= u32::MAX as usize {
            return Err(MeshError::TooManyEntities {
                what: "edges",
                count: ne,
            });
        }
        // star-shapedness with respect to the centroid (d_{K,σ} > 0, computed above)
        if let Some(err) = cells.not_star_shaped {
            return Err(err);
        }
        // compact storage of the cells (ids and offsets below u32::MAX, checked above), before
        // the overlap check, the peak of the construction; the usize arrays are freed
        let cell_ptr = to_u32(cell_ptr);
        let cell_verts = to_u32(cell_verts);

        let boundary_edges: Vec<usize> = (0..ne).filter(|&e| edge_cells[e][1] == NO_CELL).collect();
        let boundary = validate::boundary_loops(
            &vertices,
            &edges,
            &cell_verts,
            &cell_ptr,
            &cell_edges,
            &boundary_edges,
        )?;
        if let Some(order) = order {
            validate::check_no_overlap(
                &validate::Topology {
                    vertices: &vertices,
                    cell_ptr: &cell_ptr,
                    cell_verts: &cell_verts,
                    edges: &edges,
                    edge_cells: &edge_cells,
                    cell_area: &cells.area,
                },
                &boundary,
                order,
            )?;
        }
        drop(boundary);

        // compact storage of the edges (ids below u32::MAX, checked above); the usize arrays
        // are freed
        let edges: Vec<[u32; 2]> = edges.iter().map(|e| e.map(|v| v as u32)).collect();
        let edge_cells: Vec<[u32; 2]> = edge_cells
            .iter()
            .map(|c| c.map(|k| if k == NO_CELL { u32::MAX } else { k as u32 }))
            .collect();
        let edge_tags = vec![0i32; ne];
        let cell_tags = vec![0i32; cells.area.len()];
        let h = cells.diameter.iter().cloned().fold(0.0, f64::max);
        Ok(PolyMesh {
            vertices,
            cell_ptr,
            cell_verts,
            cell_edges,
            edges,
            edge_cells,
            edge_tags,
            cell_tags,
            cell_area: cells.area,
            cell_centroid: cells.centroid,
            boundary_edges,
            h,
        })
    }

    /// Tags boundary edges from `(vertex a, vertex b, tag)` entries (either vertex order), in
    /// order: a later entry for the same edge overrides an earlier one. An entry that names no
    /// boundary edge is an error ([`MeshError::BadEdge`]) or skipped, as `non_boundary` says.
    ///
    /// Each entry is found by binary search in [`PolyMesh::boundary_edges`]: edges are numbered
    /// in increasing (smaller vertex, larger vertex) order and the boundary edges are listed in
    /// increasing edge number, so that list is sorted by vertex pair already.
    pub(crate) fn set_boundary_tags(
        &mut self,
        tagged_edges: &[(usize, usize, i32)],
        non_boundary: NonBoundaryTag,
    ) -> Result<(), MeshError> {
        for &(a, b, tag) in tagged_edges {
            let key = [a.min(b), a.max(b)];
            let found = self
                .boundary_edges
                .binary_search_by(|&e| self.edge_vertices(e).cmp(&key));
            match (found, non_boundary) {
                (Ok(pos), _) => self.edge_tags[self.boundary_edges[pos]] = tag,
                (Err(_), NonBoundaryTag::Ignore) => {}
                (Err(_), NonBoundaryTag::Reject) => {
                    return Err(MeshError::BadEdge {
                        a: key[0],
                        b: key[1],
                        msg: format!("tagged {tag} but it is not a boundary edge of the mesh"),
                    });
                }
            }
        }
        Ok(())
    }

    /// Returns the mesh with cell `k` tagged `tags[k]` (gmsh physical surfaces: heterogeneous
    /// media given as subdomains); an error if `tags` does not have one entry per cell.
    pub fn with_cell_tags(mut self, tags: Vec<i32>) -> Result<PolyMesh, MeshError> {
        if tags.len() != self.n_cells() {
            return Err(MeshError::NonConforming(format!(
                "{} cell tags for {} cells",
                tags.len(),
                self.n_cells()
            )));
        }
        self.cell_tags = tags;
        Ok(self)
    }

    /// The tag of cell `k` (its gmsh physical surface; 0 when untagged).
    pub fn cell_tag(&self, k: usize) -> i32 {
        self.cell_tags[k]
    }

    /// Returns a copy whose boundary edges are tagged by `tag(x_σ)` (interior edges keep tag 0).
    pub fn with_boundary_tags(&self, tag: impl Fn(Point) -> i32) -> PolyMesh {
        let mut m = self.clone();
        for &e in &self.boundary_edges {
            m.edge_tags[e] = tag(self.edge_midpoint(e));
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
    /// The range of cell `k` in `cell_verts` and `cell_edges`.
    #[inline]
    fn cell_range(&self, k: usize) -> std::ops::Range<usize> {
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
        let (p, q) = self.cell_side_points(k, i);
        side_normal_dist(p, q, self.cell_centroid[k])
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
        let xk = self.cell_centroid[k];
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

/// The edges of a mesh whose cells are stored flat (`cell_ptr`, `cell_verts`, as in
/// [`PolyMesh`] but `usize`; every cell has at least 3 vertices, all below `nv`, and there are
/// fewer than `u32::MAX` cell sides, so that the edge ids fit in the 32-bit `cell_edges`),
/// numbered in increasing order of their (smaller vertex, larger vertex) pair, or the first
/// [`MeshError::BadEdge`] in that order: an edge shared by more than two cells, or two cells
/// that traverse an edge in the same direction.
///
/// Algorithm, linear apart from sorting a handful of items per vertex:
/// 1. every cell side (half-edge, identified by its slot in `cell_verts`) is put into the bucket
///    of its smaller end point by a counting sort (CSR by smaller vertex); the sides are visited
///    in slot order, so every bucket lists its sides in (cell, local edge) order;
/// 2. each bucket is sorted by (larger vertex, slot): buckets are small (about six sides per
///    vertex on a triangle mesh), which `sort_unstable` handles by insertion sort;
/// 3. scanning the buckets in vertex order visits the sides sorted by their (smaller, larger)
///    vertex pair, ties in slot order; every run of equal pairs is one edge. The first side of a
///    run gives `edge_cells[e][0]`, so an interior edge lists its lower-numbered cell first, and
///    of three or more cells on one edge the two lowest-numbered ones are compared first (the
///    global sort of all sides this replaces left both to the tie order of `sort_unstable`).
///
/// The result is the same as sorting all sides by (smaller vertex, larger vertex, slot), without
/// the O(n log n) sort of scattered records. The scatter of step 1 is a random access per side,
/// so the bucket arrays use `u32` indices whenever the mesh allows it (fewer than 2³¹ cell
/// sides): half the memory traffic of `usize` records.
fn build_edges(nv: usize, cell_ptr: &[usize], cell_verts: &[usize]) -> Result<Edges, MeshError> {
    // the largest value stored is 2·slot + 1 < 2·cell_verts.len() (cells and vertices are fewer)
    let small = u32::try_from(cell_verts.len().saturating_mul(2))
        .ok()
        .zip(u32::try_from(nv).ok())
        .is_some();
    if small {
        build_edges_with::<u32>(nv, cell_ptr, cell_verts)
    } else {
        build_edges_with::<usize>(nv, cell_ptr, cell_verts)
    }
}

/// The edge arrays of a [`PolyMesh`], as [`build_edges`] makes them.
#[derive(Debug, PartialEq)]
struct Edges {
    /// End points of each edge, smaller vertex first.
    edges: Vec<[usize; 2]>,
    /// The cells on either side of each edge (`[K, NO_CELL]` on the boundary).
    edge_cells: Vec<[usize; 2]>,
    /// The edge of each cell side (indexed like `cell_verts`), 32-bit as [`PolyMesh`] keeps it
    /// (there are no more edges than cell sides, fewer than `u32::MAX`).
    cell_edges: Vec<u32>,
}

/// Unsigned index type of the scratch arrays of [`build_edges`] and of the sweep's events
/// (`u32` when the values fit: half the memory traffic and footprint of `usize`).
pub(crate) trait EdgeIndex: Copy + Ord + Default {
    /// `v` as `Self`; [`build_edges`] only calls it with values that fit.
    fn from_usize(v: usize) -> Self;
    fn to_usize(self) -> usize;
}

impl EdgeIndex for u32 {
    fn from_usize(v: usize) -> Self {
        debug_assert!(u32::try_from(v).is_ok());
        v as u32
    }
    fn to_usize(self) -> usize {
        self as usize
    }
}

impl EdgeIndex for usize {
    fn from_usize(v: usize) -> Self {
        v
    }
    fn to_usize(self) -> usize {
        self
    }
}

/// [`build_edges`] with scratch indices of type `I`.
fn build_edges_with<I: EdgeIndex>(
    nv: usize,
    cell_ptr: &[usize],
    cell_verts: &[usize],
) -> Result<Edges, MeshError> {
    let n_half = cell_verts.len();
    debug_assert!(n_half < u32::MAX as usize, "checked by from_flat_cells");
    let nc = cell_ptr.len().saturating_sub(1);
    // the side in `slot` of cell k (slots s..e) joins cell_verts[slot] to cell_verts[next(slot)]
    let next = |slot: usize, s: usize, e: usize| if slot + 1 < e { slot + 1 } else { s };

    // 1. counting sort by smaller vertex: bucket v is half[start[v]..start[v + 1]]
    let mut start = vec![I::default(); nv + 1];
    for k in 0..nc {
        let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
        for slot in s..e {
            let (a, b) = (cell_verts[slot], cell_verts[next(slot, s, e)]);
            let c = &mut start[a.min(b) + 1];
            *c = I::from_usize(c.to_usize() + 1);
        }
    }
    for v in 0..nv {
        start[v + 1] = I::from_usize(start[v + 1].to_usize() + start[v].to_usize());
    }
    let mut cursor = start.clone();
    // (larger vertex, 2·slot + [side runs from larger to smaller vertex], cell): the direction
    // rides along so that step 3 reads no vertex ids; sorting by the second item sorts by slot
    let mut half = vec![(I::default(), I::default(), I::default()); n_half];
    for k in 0..nc {
        let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
        for slot in s..e {
            let (a, b) = (cell_verts[slot], cell_verts[next(slot, s, e)]);
            let c = &mut cursor[a.min(b)];
            half[c.to_usize()] = (
                I::from_usize(a.max(b)),
                I::from_usize(2 * slot + usize::from(a > b)),
                I::from_usize(k),
            );
            *c = I::from_usize(c.to_usize() + 1);
        }
    }
    drop(cursor);
    // 2. sort the buckets and count the edges, so that the edge arrays are allocated once
    let mut ne = 0;
    for v in 0..nv {
        let bucket = &mut half[start[v].to_usize()..start[v + 1].to_usize()];
        bucket.sort_unstable();
        ne += bucket
            .iter()
            .enumerate()
            .filter(|&(i, h)| i == 0 || bucket[i - 1].0 != h.0)
            .count();
    }
    // 3. runs of equal (smaller, larger) vertex pairs are the edges
    let mut edges = Vec::with_capacity(ne);
    let mut edge_cells = Vec::with_capacity(ne);
    // edge ids are below the number of sides (each edge has a side), so below u32::MAX
    let mut cell_edges = vec![0u32; n_half];
    for lo in 0..nv {
        let bucket = &half[start[lo].to_usize()..start[lo + 1].to_usize()];
        let mut i = 0;
        while i < bucket.len() {
            let (hi, code, k) = bucket[i];
            let (hi, code, k) = (hi.to_usize(), code.to_usize(), k.to_usize());
            let e = edges.len();
            edges.push([lo, hi]);
            cell_edges[code / 2] = e as u32;
            let mut cells_of_edge = [k, NO_CELL];
            let mut j = i + 1;
            while j < bucket.len() && bucket[j].0.to_usize() == hi {
                let (code2, k2) = (bucket[j].1.to_usize(), bucket[j].2.to_usize());
                if j > i + 1 {
                    return Err(MeshError::BadEdge {
                        a: lo,
                        b: hi,
                        msg: "shared by more than two cells".into(),
                    });
                }
                if code2 % 2 == code % 2 {
                    return Err(MeshError::BadEdge {
                        a: lo,
                        b: hi,
                        msg: format!(
                            "cells {k} and {k2} traverse it in the same direction (overlapping cells)"
                        ),
                    });
                }
                cells_of_edge[1] = k2;
                cell_edges[code2 / 2] = e as u32;
                j += 1;
            }
            edge_cells.push(cells_of_edge);
            i = j;
        }
    }
    Ok(Edges {
        edges,
        edge_cells,
        cell_edges,
    })
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

/// A small xorshift generator (deterministic tests without a crate).
#[cfg(test)]
pub(crate) fn xorshift(mut s: u64) -> impl FnMut() -> u64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// [`xorshift`] as numbers in [0, 1).
#[cfg(test)]
pub(crate) fn test_rng(s: u64) -> impl FnMut() -> f64 {
    let mut next = xorshift(s);
    move || (next() >> 11) as f64 / (1u64 << 53) as f64
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
        let mut meshes = vec![unit_square_2x1()];
        for f in generate::Family::ALL {
            meshes.push(f.generate(2).unwrap());
        }
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

    /// The edges as the original construction defined them: all cell sides sorted by
    /// (smaller vertex, larger vertex) with ties in slot order (a stable sort), runs of equal
    /// pairs being the edges. Returns `(edges, edge_cells, cell_edges)`; panics on invalid input.
    fn reference_edges(m: &PolyMesh) -> Edges {
        let mut sides = Vec::new();
        for k in 0..m.n_cells() {
            let c = m.cell_vertices(k);
            for i in 0..c.len() {
                let (a, b) = (c[i] as usize, c[(i + 1) % c.len()] as usize);
                sides.push(((a.min(b), a.max(b)), m.cell_range(k).start + i, k));
            }
        }
        sides.sort_by_key(|s| s.0);
        let (mut edges, mut edge_cells) = (Vec::<[usize; 2]>::new(), Vec::<[usize; 2]>::new());
        let mut cell_edges = vec![u32::MAX; sides.len()];
        for (key, slot, k) in sides {
            if edges.last() == Some(&[key.0, key.1]) {
                edge_cells.last_mut().unwrap()[1] = k;
            } else {
                edges.push([key.0, key.1]);
                edge_cells.push([k, NO_CELL]);
            }
            cell_edges[slot] = (edges.len() - 1) as u32;
        }
        Edges {
            edges,
            edge_cells,
            cell_edges,
        }
    }

    #[test]
    fn edges_are_numbered_by_vertex_pair_with_lower_cell_first() {
        let mut meshes = vec![unit_square_2x1()];
        for f in generate::Family::ALL {
            meshes.push(f.generate(2).unwrap());
        }
        for m in &meshes {
            let reference = reference_edges(m);
            let edges: Vec<[usize; 2]> = (0..m.n_edges()).map(|e| m.edge_vertices(e)).collect();
            let edge_cells: Vec<[usize; 2]> = (0..m.n_edges()).map(|e| m.edge_cells(e)).collect();
            assert_eq!(edges, reference.edges);
            assert_eq!(edge_cells, reference.edge_cells);
            for (e, c) in edge_cells.iter().enumerate() {
                assert_eq!(m.is_boundary_edge(e), c[1] == NO_CELL);
            }
            assert_eq!(m.cell_edges, reference.cell_edges);
            assert!(m.edges.windows(2).all(|w| w[0] < w[1]) && m.edges.iter().all(|e| e[0] < e[1]));
            // both index widths of the bucket arrays give the same result, from the cells as
            // `from_flat_cells` receives them (usize)
            let widen = |v: &[u32]| v.iter().map(|&x| x as usize).collect::<Vec<usize>>();
            let (ptr, verts) = (widen(&m.cell_ptr), widen(&m.cell_verts));
            let wide = build_edges_with::<usize>(m.n_vertices(), &ptr, &verts);
            let narrow = build_edges_with::<u32>(m.n_vertices(), &ptr, &verts);
            assert_eq!(wide, narrow);
            assert_eq!(wide, Ok(reference));
            // the boundary edges are sorted by vertex pair, which set_boundary_tags relies on
            assert!(
                m.boundary_edges
                    .windows(2)
                    .all(|w| m.edges[w[0]] < m.edges[w[1]])
            );
        }
    }

    #[test]
    fn bad_edges_are_reported_in_vertex_pair_order() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, -1.0]];
        // edge (0, 1) is shared by three cells; the first two traverse it in opposite directions
        let cells = vec![vec![0, 1, 3], vec![1, 0, 4], vec![0, 1, 2], vec![2, 3, 1]];
        let e = PolyMesh::from_cells(v.clone(), cells).unwrap_err();
        assert_eq!(
            e,
            MeshError::BadEdge {
                a: 0,
                b: 1,
                msg: "shared by more than two cells".into()
            }
        );
        // the same triangle twice: the cells are named in increasing order
        let cells = vec![vec![2, 3, 1], vec![0, 1, 2], vec![0, 1, 2]];
        let e = PolyMesh::from_cells(v[..4].to_vec(), cells).unwrap_err();
        assert_eq!(
            e,
            MeshError::BadEdge {
                a: 0,
                b: 1,
                msg: "cells 1 and 2 traverse it in the same direction (overlapping cells)".into()
            }
        );
    }

    #[test]
    fn tags_on_non_boundary_edges_are_rejected_or_ignored() {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let cells = vec![vec![0, 1, 3], vec![0, 3, 2]];
        // (0, 3) is interior, (1, 2) no edge at all; (3, 1) is the boundary edge (1, 3)
        for bad in [(0, 3, 5), (1, 2, 5)] {
            let e = PolyMesh::from_cells_tagged(v.clone(), cells.clone(), &[(3, 1, 4), bad]);
            assert!(
                matches!(&e, Err(MeshError::BadEdge { msg, .. }) if msg.contains("tagged 5")),
                "{e:?}"
            );
        }
        let mut m = PolyMesh::from_cells(v, cells).unwrap();
        m.set_boundary_tags(
            &[(3, 1, 4), (0, 3, 5), (1, 2, 5), (1, 3, 6), (2, 0, 7)],
            NonBoundaryTag::Ignore,
        )
        .unwrap();
        let tags: Vec<(usize, usize, i32)> = (0..m.n_edges())
            .map(|e| (m.edge_vertices(e)[0], m.edge_vertices(e)[1], m.edge_tag(e)))
            .collect();
        // a later entry for the same edge wins; the interior edge keeps 0
        assert_eq!(
            tags,
            vec![(0, 1, 0), (0, 2, 7), (0, 3, 0), (1, 3, 6), (2, 3, 0)]
        );
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
    fn counts_beyond_the_32_bit_arrays_are_rejected() {
        let max = u32::MAX as usize;
        assert_eq!(check_counts(max - 1, max - 1, max - 1), Ok(()));
        for (counts, what) in [
            ([max, 1, 3], "vertices"),
            ([3, max, 3], "cells"),
            ([3, 1, max], "cell sides"),
        ] {
            assert_eq!(
                check_counts(counts[0], counts[1], counts[2]),
                Err(MeshError::TooManyEntities { what, count: max })
            );
        }
        // the first in that order is reported
        let e = check_counts(max, max, max).unwrap_err();
        assert_eq!(
            e,
            MeshError::TooManyEntities {
                what: "vertices",
                count: max
            }
        );
        assert_eq!(
            MeshError::TooManyEntities {
                what: "cell sides",
                count: max
            }
            .to_string(),
            format!("the mesh has {max} cell sides: at most 2^32 - 2 are supported")
        );
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
