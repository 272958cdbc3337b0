//! Two-dimensional polytopal meshes as flat, immutable, index-based data.
//!
//! A [`PolyMesh`] is built once from vertex coordinates and cell vertex lists
//! ([`PolyMesh::from_cells`]); the constructor fixes the orientation of every cell to
//! counter-clockwise, derives the edges (faces σ), the cell↔edge incidences and the boundary, caches
//! the geometry named in the crate's notation table, and validates everything HMM needs: a
//! partition of a polygonal domain into simple, star-shaped polygons meeting edge to edge, with
//! no overlap, checked in O(n log n) time whatever the input (see [`validate`] for the list of
//! checks and their costs, and [`MeshError`](crate::MeshError)). Nothing is mutated afterwards; transformations
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
//! | [`PolyMesh::bounding_box`] | the smallest [`Rect`] \[x0, x1\] × \[y0, y1\] holding Ω |
//!
//! ## Files
//! One job each: `build.rs` builds a mesh from cell lists (through the checks of [`validate`],
//! the edge numbering of `edges.rs` and the overlap sweep of `sweep.rs`); `poly_mesh.rs` holds
//! the accessors; `tags.rs` the boundary and cell tags; `geometry.rs` the geometry of points
//! and polygons and [`Rect`]; `renumber.rs` drops unused vertices for the readers;
//! the memory of a mesh is estimated ([`mesh_bytes`](crate::budget::mesh_bytes)) against the
//! caller's [`MemoryBudget`](crate::budget::MemoryBudget) before it is built;
//! [`generate`] and [`io`] make meshes, [`agglomerate`] coarsens them, [`complex`] is the
//! dimension-generic view a scheme reads.
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
//! boxes, `scheme/hmm.rs`). The problem data ([`crate::problem::Problem<D>`]), the assembly
//! and the solve driver are generic over the dimension too: what they read from a mesh beyond
//! its complex (cell tags, boundary faces and their tags, the domain's diameter) is the trait
//! [`SolveMesh<D>`](solve_mesh::SolveMesh), implemented by `PolyMesh` (edge midpoints and edge
//! tags, as always) and by [`crate::mesh3d::PolyMesh3`], on which HMM solves through the whole
//! pipeline. What is still 2-D: the problem-file compiler (expression variables x and y, 2×2
//! tensors), P1 and Crouzeix–Raviart (triangles) and the VTU writer of `PolyMesh` (polygons);
//! the nested warm start agglomerates both ([`crate::solver::coarse_mesh`]).

pub mod agglomerate;
pub mod box_cover;
pub(crate) mod buckets;
mod build;
pub mod complex;
mod edges;
pub mod generate;
mod geometry;
pub mod io;
mod poly_mesh;
mod predicates;
mod renumber;
pub mod solve_mesh;
mod sweep;
mod tags;
pub mod validate;

pub(crate) use build::Overlap;
pub use complex::CellComplex;
pub(crate) use edges::EdgeIndex;
pub use generate::Family;
pub(crate) use geometry::side_normal_dist;
pub use geometry::{Rect, polygon_area_centroid};
use geometry::{dist, sub};
pub use renumber::drop_unused_vertices;
pub(crate) use renumber::drop_unused_vertices_flat;
pub use solve_mesh::SolveMesh;
pub(crate) use tags::NonBoundaryTag;
pub use validate::MAX_CELL_VERTICES;

/// Marker for "no cell" in [`PolyMesh::edge_cells`] (the second cell of a boundary edge).
pub const NO_CELL: usize = usize::MAX;

/// A 2D point or vector.
pub type Point = [f64; 2];

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
    /// Boundary tag of each boundary edge, in the order of `boundary_edges` (0 when
    /// untagged); interior edges have tag 0. 4 bytes per boundary edge instead of per edge.
    boundary_tags: Vec<i32>,
    /// Tag of each cell (gmsh physical surface; 0 when untagged), or empty when every cell
    /// has tag 0 (generated meshes, meshes without physical surfaces): 4 bytes per cell less.
    cell_tags: Vec<i32>,
    /// The cells given clockwise, whose vertex lists were reversed: a bit per cell (empty when
    /// none was). |K| and x_K are computed from the vertices on demand, in the order the cell
    /// was given ([`PolyMesh::area_centroid`]): the same bits as the values stored before, 24
    /// bytes per cell less.
    reversed: Vec<u64>,
    // |σ| and x_σ are computed from the end points on demand (`edge_measure`,
    // `edge_midpoint`): 24 bytes per edge less, the same bits as stored values
    boundary_edges: Vec<usize>,
    h: f64,
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

/// Two rectangles tiling the unit square, the second given clockwise (for the tests).
#[cfg(test)]
pub(crate) fn unit_square_2x1() -> PolyMesh {
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

/// [`unit_square_2x1`] and level 2 of every generated family (for the tests).
#[cfg(test)]
pub(crate) fn test_meshes() -> Vec<PolyMesh> {
    let mut meshes = vec![unit_square_2x1()];
    for f in generate::Family::ALL {
        meshes.push(f.generate(2, crate::budget::MemoryBudget::DEFAULT).unwrap());
    }
    meshes
}
