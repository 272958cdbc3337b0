//! Check 12b of [`validate`](super::validate): no edge of the boundary surface crosses a
//! boundary face of another cell.
//!
//! ## Why the boundary surface
//! Once the checks before it pass, every cell is an embedded polyhedron positively oriented
//! (star-shaped with respect to x_K with positive fan tetrahedra, check 10), so its indicator
//! is the winding number of its outward boundary; summed over the cells, the interior faces
//! cancel (their two cells list them oppositely, check 7) and the number of cells covering a
//! point x is the winding number of the boundary surface (the boundary faces, outward) around
//! x. The winding number of an embedded closed surface is 0 or 1: cells overlap (a region
//! covered twice) only if the boundary surface intersects itself. Two boundary faces that
//! cross meet along a segment whose ends lie where an edge of one crosses the other; when no
//! end is a boundary vertex inside a cell (check 12a, `overlap.rs`), some boundary edge
//! crosses a boundary face in its interior: two tetrahedra interlocked as a star of David,
//! two bars crossing edge through face. The degenerate cases left, an edge meeting another
//! exactly (a crossing on the rim of a face) or a vertex lying exactly on a face, become one
//! of the cases above under a perturbation of the vertices.
//!
//! ## The test
//! The boundary edges (each shared by two boundary faces, check 11) are tested against the
//! boundary faces whose bounding box meets theirs, found in a uniform grid of about one
//! bucket per cell over the bounding box of the mesh (the (bucket, face) pairs of the face
//! boxes, sorted, searched by bucket). A face is skipped when it has a vertex of the edge (a
//! segment from a point of a planar face crosses its interior only lying in its plane) or
//! belongs to the cell of one of the edge's two boundary faces (the edges of an embedded cell
//! do not cross its faces). Edge (a, b) crosses the face when it crosses one of its fan triangles T (the
//! face itself if it is a triangle): with n = N_T the normal of T and L = |b − a|,
//!
//! * a and b lie strictly on either side of the plane of T, each more than 10⁻⁹ L off it
//!   ((a − p)·n and (b − p)·n of opposite signs, each of size above 10⁻⁹ L |n|);
//! * the crossing point x has barycentric coordinates in T at least −10⁻⁹, and strictly
//!   above 10⁻⁹ on the fan centre (off the rim of the face; on every corner if the face is a
//!   triangle).
//!
//! Touching configurations (an edge ending on a face, lying in its plane, or meeting it on
//! its rim) therefore never count; valid meshes have none but shared vertices and edges,
//! which are skipped. Expected O(n log n) in the size of the boundary surface for meshes of
//! cells of comparable sizes (the work per edge grows with the number of buckets its box
//! meets).

use super::geometry::{cross, dot, for_each_fan_corners, norm, sub};
use super::overlap::{Grid, slab_range};
use super::{Point3, PolyMesh3};
use crate::error::MeshError;
use rayon::prelude::*;

/// The relative tolerance of the tests (see the module docs).
const EPS: f64 = 1e-9;

/// A boundary edge: its vertices (a < b) and the cells of its two boundary faces.
#[derive(Clone, Copy)]
struct Edge {
    ends: [u32; 2],
    cells: [u32; 2],
}

impl PolyMesh3 {
    /// [`MeshError::EdgeThroughFace`] naming the first boundary edge (by its vertices) that
    /// crosses a boundary face of another cell in its interior, and the smallest such face
    /// (see the module docs of `crossing.rs`).
    pub(crate) fn check_crossings(&self) -> Result<(), MeshError> {
        let grid = Grid::over(self);
        let slabs = grid.vertex_slabs(self);
        // (bucket, face) for every bucket the box of a boundary face meets, sorted
        let mut pairs: Vec<(u32, u32)> = self
            .boundary_faces
            .par_iter()
            .flat_map_iter(|&f| {
                let r = slab_range(&slabs, self.face_vertices(f as usize));
                grid.buckets(r).map(move |b| (b as u32, f))
            })
            .collect();
        pairs.par_sort_unstable();
        let edges = self.boundary_edges();
        // the candidate list is a buffer per task: allocating one per edge cost more than the
        // search itself once two threads allocated and freed them
        let hit = edges
            .par_iter()
            .map_init(Vec::new, |candidates: &mut Vec<u32>, e| {
                candidates.clear();
                for b in grid.buckets(slab_range(&slabs, &e.ends)) {
                    let b = b as u32;
                    let start = pairs.partition_point(|p| p.0 < b);
                    let end = start + pairs[start..].partition_point(|p| p.0 == b);
                    candidates.extend(pairs[start..end].iter().map(|p| p.1));
                }
                candidates.sort_unstable();
                candidates.dedup();
                candidates
                    .iter()
                    .find(|&&f| self.edge_crosses_face(e, f as usize))
                    .map(|&f| (*e, f))
            })
            .find_map_first(|hit| hit);
        match hit {
            Some((e, f)) => Err(MeshError::EdgeThroughFace {
                a: e.ends[0] as usize,
                b: e.ends[1] as usize,
                edge_cell: e.cells[0] as usize,
                face: f as usize,
                face_cell: self.face_cells[f as usize][0] as usize,
            }),
            None => Ok(()),
        }
    }

    /// The edges of the boundary loops, each once, in increasing order of their vertex
    /// pairs, with the cells of their two boundary faces (check 11 has made sure there are
    /// two).
    fn boundary_edges(&self) -> Vec<Edge> {
        let mut half: Vec<(u32, u32, u32)> = self
            .boundary_faces
            .par_iter()
            .flat_map_iter(|&f| {
                let l = self.face_vertices(f as usize);
                let cell = self.face_cells[f as usize][0];
                (0..l.len()).map(move |i| {
                    let (a, b) = (l[i], l[(i + 1) % l.len()]);
                    (a.min(b), a.max(b), cell)
                })
            })
            .collect();
        half.par_sort_unstable();
        half.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
            .map(|g| Edge {
                ends: [g[0].0, g[0].1],
                cells: [g[0].2, g[g.len() - 1].2],
            })
            .collect()
    }

    /// Whether edge `e` crosses face `f` in its interior (see the module docs); `false` if
    /// `f` has a vertex of `e` or belongs to a cell of `e`.
    fn edge_crosses_face(&self, e: &Edge, f: usize) -> bool {
        let l = self.face_vertices(f);
        if e.cells.contains(&self.face_cells[f][0]) || l.iter().any(|v| e.ends.contains(v)) {
            return false;
        }
        let [a, b] = e.ends.map(|v| self.vertices[v as usize]);
        let mut crosses = false;
        for_each_fan_corners(&self.vertices, l, false, |p, q, r| {
            crosses = crosses || segment_crosses_triangle(a, b, [p, q, r], l.len() == 3);
        });
        crosses
    }
}

/// Whether the segment (a, b) crosses the triangle (p, q, r) (see the module docs): its ends
/// strictly on either side of the plane, the crossing point's barycentric coordinates at least
/// −[`EPS`], and above [`EPS`] on p (on every corner if `all_corners`).
fn segment_crosses_triangle(
    a: Point3,
    b: Point3,
    [p, q, r]: [Point3; 3],
    all_corners: bool,
) -> bool {
    let n = cross(sub(q, p), sub(r, p));
    let nn = dot(n, n);
    let (da, db) = (dot(sub(a, p), n), dot(sub(b, p), n));
    let off = EPS * norm(sub(b, a)) * nn.sqrt();
    if !(da * db < 0.0 && da.abs() > off && db.abs() > off) {
        return false;
    }
    let t = da / (da - db);
    let x: Point3 = std::array::from_fn(|i| a[i] + t * (b[i] - a[i]));
    let lp = dot(cross(sub(q, x), sub(r, x)), n) / nn;
    let lq = dot(cross(sub(r, x), sub(p, x)), n) / nn;
    let lr = 1.0 - lp - lq;
    let floor = if all_corners { EPS } else { -EPS };
    lp > EPS && lq > floor && lr > floor
}

#[cfg(test)]
mod tests {
    use super::segment_crosses_triangle;

    const T: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn segments_cross_triangles_only_through_their_interior() {
        let through = ([0.2, 0.2, -1.0], [0.2, 0.2, 1.0]);
        assert!(segment_crosses_triangle(through.0, through.1, T, true));
        // ending on the plane, lying in it, or passing beside the triangle: no crossing
        assert!(!segment_crosses_triangle(
            [0.2, 0.2, 0.0],
            [0.2, 0.2, 1.0],
            T,
            true
        ));
        assert!(!segment_crosses_triangle(
            [0.1, 0.1, 0.0],
            [0.3, 0.2, 0.0],
            T,
            true
        ));
        assert!(!segment_crosses_triangle(
            [0.8, 0.8, -1.0],
            [0.8, 0.8, 1.0],
            T,
            true
        ));
        // through the rim: an edge of a triangular face, or the outer edge of a fan triangle
        let rim = ([0.5, 0.0, -1.0], [0.5, 0.0, 1.0]);
        assert!(!segment_crosses_triangle(rim.0, rim.1, T, true));
        assert!(!segment_crosses_triangle(
            [0.5, 0.5, -1.0],
            [0.5, 0.5, 1.0],
            T,
            false
        ));
        // through a spoke of a fan (p is the fan centre): inside the face
        assert!(segment_crosses_triangle(rim.0, rim.1, T, false));
        // oblique, and either direction
        assert!(segment_crosses_triangle(
            [0.4, 0.1, 1.0],
            [0.0, 0.3, -1.0],
            T,
            true
        ));
        assert!(segment_crosses_triangle(through.1, through.0, T, true));
    }
}

#[cfg(test)]
mod timing {
    use crate::budget::MemoryBudget;
    use crate::mesh3d::PolyMesh3;
    use crate::mesh3d::generate::Family3;
    use std::time::Instant;

    /// The cost of checks 12a and 12b against the whole build on the Kuhn tetrahedra of level
    /// 5 (1.57 M cells); the numbers go to replication/measurements/mesh3d_io.md.
    #[test]
    #[ignore = "timing: cargo test --release -p gradvi --lib measure_crossing -- --ignored --nocapture"]
    fn measure_crossing_check_on_a_million_tetrahedra() {
        let p = Family3::Kuhn
            .polyhedra(5, crate::mesh3d::Cuboid::UNIT, MemoryBudget::DEFAULT)
            .unwrap();
        let t = Instant::now();
        let m = PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT).unwrap();
        let build = t.elapsed().as_secs_f64();
        let t = Instant::now();
        m.check_overlap().unwrap();
        let vertices = t.elapsed().as_secs_f64();
        let t = Instant::now();
        m.check_crossings().unwrap();
        let edges = t.elapsed().as_secs_f64();
        eprintln!(
            "{} cells, {} boundary faces: build {build:.3} s (checks included), check 12a \
             {vertices:.3} s, check 12b {edges:.3} s",
            m.n_cells(),
            m.boundary_faces().len()
        );
        assert_eq!(m.n_cells(), 6 * 64 * 64 * 64);
    }
}
