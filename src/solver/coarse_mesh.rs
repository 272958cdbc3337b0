//! What the nested warm start ([`super::warm_start`]) asks of a mesh beyond assembly, written
//! once per mesh type so that the prediction itself is written once for every dimension:
//! coarse meshes of the same domain by agglomeration ([`crate::mesh::agglomerate`] on
//! [`PolyMesh`], [`crate::mesh3d::agglomerate`] on [`PolyMesh3`]), the length scale of a cell
//! of measure |K| (|K|^{1/D}), the distance from a point to a face, the vertices of cells
//! and faces (for vertex unknowns), and how coarse the first level is.
//!
//! The distance from p to a polygonal face σ of a 3D mesh is the least distance from p to the
//! triangles of σ's fan (the triangles the mesh integrates on, [`crate::mesh3d`]: σ itself if
//! it is a triangle, otherwise the triangles (c, v_i, v_{i+1}) with c the mean of σ's
//! vertices). That is the distance to σ when σ is planar and star-shaped from c, and to the
//! surface the mesh integrates on when σ is warped.

use super::warm_start::{FIRST_LEVEL_UNKNOWNS_PER_CELL, FIRST_LEVEL_UNKNOWNS_PER_CELL_3D};
use crate::budget::{AllocFailure, MemoryBudget, try_vec};
use crate::error::MeshError;
use crate::mesh::complex::{Vector, VertexAverage};
use crate::mesh::{PolyMesh, SolveMesh};
use crate::mesh3d::{Point3, PolyMesh3, agglomerate::NO_FACE};

/// Marker for "no coarse face" in the dense maps of the agglomerations and covers (interior
/// fine faces), from which [`BoundaryFaceMap::from_dense`] keeps the other entries.
pub const NO_COARSE_FACE: u32 = u32::MAX;

/// A coarse mesh made of unions of the cells of a fine one, and the maps between them.
#[derive(Debug, Clone)]
pub struct Level<M> {
    /// The coarse mesh.
    pub mesh: M,
    /// The coarse cell of each fine cell (32-bit, as the meshes' own indices: these maps are
    /// the size of the fine mesh and live beside the fine setup).
    pub cell_of: Vec<u32>,
    /// The coarse face of each fine boundary face (the same face).
    pub boundary_face_of: BoundaryFaceMap,
}

/// The coarse face of each fine boundary face, kept for the boundary faces only: a level
/// lives beside the fine setup (the coarse branch of the solver's join), and a map indexed by
/// every fine face would hold 4 bytes per face for the few on the boundary (48 MB for the 12M
/// faces of 6M tetrahedra, whose 120k boundary faces take 1 MB here).
#[derive(Debug, Clone)]
pub struct BoundaryFaceMap {
    /// The number of faces of the fine mesh.
    fine_faces: usize,
    /// The fine boundary faces, increasing.
    faces: Vec<u32>,
    /// The coarse face of each of them.
    coarse: Vec<u32>,
}

impl BoundaryFaceMap {
    /// The map of a dense one (indexed by fine face; [`NO_COARSE_FACE`] for interior faces).
    pub fn from_dense(dense: &[u32]) -> Result<Self, AllocFailure> {
        let n = dense.iter().filter(|&&c| c != NO_COARSE_FACE).count();
        let mut faces = try_vec(n, "the fine boundary faces of a coarse level")?;
        let mut coarse = try_vec(n, "the coarse boundary faces of a coarse level")?;
        for (e, &c) in dense.iter().enumerate() {
            if c != NO_COARSE_FACE {
                // exact: a dense map has an entry per fine face, and both mesh types number
                // their faces below u32::MAX (their builds refuse more)
                faces.push(e as u32);
                coarse.push(c);
            }
        }
        Ok(Self {
            fine_faces: dense.len(),
            faces,
            coarse,
        })
    }

    /// The coarse face of the fine face `e` (`None` for a face not on the boundary).
    pub fn get(&self, e: usize) -> Option<usize> {
        let e = u32::try_from(e).ok()?;
        let i = self.faces.binary_search(&e).ok()?;
        Some(self.coarse[i] as usize)
    }

    /// The number of faces of the fine mesh the map was made on.
    pub fn fine_faces(&self) -> usize {
        self.fine_faces
    }
}

/// A mesh on which the nested warm start can make coarse levels (see the module docs).
pub trait CoarseMesh<const D: usize>: SolveMesh<D> + VertexAverage + Sized {
    /// The first coarse level has about (fine unknowns) / this many cells
    /// ([`FIRST_LEVEL_UNKNOWNS_PER_CELL`], [`FIRST_LEVEL_UNKNOWNS_PER_CELL_3D`]).
    const UNKNOWNS_PER_COARSE_CELL: usize;
    /// The size H of the cells when a domain of measure `measure` is cut into `cells` cells:
    /// (measure / cells)^{1/D}.
    fn cell_size(measure: f64, cells: usize) -> f64;
    /// The length of a cell of measure `measure`: measure^{1/D}.
    fn cell_length(measure: f64) -> f64;
    /// Agglomerates the mesh into cells of size about `size`, within `budget`; where the mesh
    /// type can, the boundary faces of one coarse cell with the same key in `boundary_key`
    /// (indexed by face; [`KEEP`](crate::mesh3d::agglomerate::KEEP) keeps a face as it is) are merged by plane
    /// ([`crate::mesh3d::agglomerate::agglomerate3_merging`]).
    fn coarsen(
        &self,
        size: f64,
        boundary_key: Option<&[u32]>,
        budget: MemoryBudget,
    ) -> Result<Level<Self>, MeshError>;
    /// A coarse mesh of boxes of side `size` covering the mesh, for when agglomeration cannot
    /// coarsen it or the domain is a box ([`Self::box_tiling`]; in 3D
    /// [`crate::mesh3d::agglomerate::box_cover`]: its domain is a staircase around Ω's and no
    /// boundary face carries over, so it serves obstacle problems only; in 2D
    /// [`crate::mesh::box_cover`], for a rectangular domain only); `None` where the mesh type
    /// has none.
    fn cover(&self, size: f64, budget: MemoryBudget) -> Option<Result<Level<Self>, MeshError>>;
    /// The side h of boxes that tile the mesh's domain exactly, if that domain is a box (its
    /// measure `measure` is its bounding box's) cut by h ≈ `size` (h = L / round(L / `size`), L
    /// its longest side) into whole boxes along every side; `None` otherwise and where the mesh
    /// type has no [`Self::cover`].
    fn box_tiling(&self, measure: f64, size: f64) -> Option<f64>;
    /// The distance from `p` to face `f` (see the module docs).
    fn face_distance(&self, f: usize, p: Vector<D>) -> f64;
    /// The vertices of cell `k`, each once (in `scratch` if the mesh does not store them).
    fn cell_vertex_ids<'s>(&'s self, k: usize, scratch: &'s mut Vec<u32>) -> &'s [u32];
    /// The vertices of face `f` (written to `scratch`).
    fn face_vertex_ids<'s>(&self, f: usize, scratch: &'s mut Vec<u32>) -> &'s [u32];
}

/// [`CoarseMesh::box_tiling`] of a mesh whose bounding box has the sides `sides` and whose
/// cells measure `measure` in all: h = L / round(L / `size`) (L the longest side) if the
/// domain fills its bounding box and boxes of side h cut every side into whole boxes (up to a
/// relative 10⁻⁹).
fn tiling(sides: &[f64], measure: f64, size: f64) -> Option<f64> {
    let volume = sides.iter().product::<f64>();
    let longest = sides.iter().copied().fold(0.0, f64::max);
    if !((measure - volume).abs() <= 1e-9 * volume && size > 0.0) {
        return None;
    }
    let h = longest / (longest / size).round().max(1.0);
    let whole = |l: f64| {
        let k = (l / h).round();
        k >= 1.0 && (l - k * h).abs() <= 1e-9 * l
    };
    sides.iter().all(|&l| whole(l)).then_some(h)
}

impl CoarseMesh<2> for PolyMesh {
    const UNKNOWNS_PER_COARSE_CELL: usize = FIRST_LEVEL_UNKNOWNS_PER_CELL;
    fn cell_size(measure: f64, cells: usize) -> f64 {
        (measure / cells as f64).sqrt()
    }
    fn cell_length(measure: f64) -> f64 {
        measure.sqrt()
    }
    /// The planar agglomeration (it takes no budget: its memory is that of the coarse mesh).
    /// Its coarse boundary edges are the fine ones (`boundary_key` is not read): a 2D coarse
    /// cell along the boundary has about H/h of them, a 3D one (H/h)² boundary faces.
    fn coarsen(
        &self,
        size: f64,
        _boundary_key: Option<&[u32]>,
        _budget: MemoryBudget,
    ) -> Result<Level<Self>, MeshError> {
        let a = crate::mesh::agglomerate::agglomerate(self, size)?;
        Ok(Level {
            mesh: a.mesh,
            boundary_face_of: BoundaryFaceMap::from_dense(&a.boundary_edge_of)?,
            cell_of: a.cell_of,
        })
    }
    /// The boxes of [`crate::mesh::box_cover`], which tile a rectangular domain exactly and
    /// refuse any other (the planar agglomeration straightens the faces of its aggregates, so
    /// it coarsens any planar mesh: no staircase cover is needed in 2D).
    fn cover(&self, size: f64, _budget: MemoryBudget) -> Option<Result<Level<Self>, MeshError>> {
        Some(crate::mesh::box_cover::box_cover(self, size).and_then(|a| {
            Ok(Level {
                boundary_face_of: BoundaryFaceMap::from_dense(&a.boundary_edge_of)?,
                mesh: a.mesh,
                cell_of: a.cell_of,
            })
        }))
    }
    fn box_tiling(&self, measure: f64, size: f64) -> Option<f64> {
        let b = self.bounding_box();
        tiling(&[b.x[1] - b.x[0], b.y[1] - b.y[0]], measure, size)
    }
    fn face_distance(&self, f: usize, p: Vector<2>) -> f64 {
        let [v, w] = self.edge_vertices(f);
        segment_distance(p, self.vertex(v), self.vertex(w))
    }
    fn cell_vertex_ids<'s>(&'s self, k: usize, _scratch: &'s mut Vec<u32>) -> &'s [u32] {
        self.cell_vertices(k)
    }
    fn face_vertex_ids<'s>(&self, f: usize, scratch: &'s mut Vec<u32>) -> &'s [u32] {
        scratch.clear();
        scratch.extend(self.edge_vertices(f).map(|v| v as u32));
        scratch
    }
}

impl CoarseMesh<3> for PolyMesh3 {
    const UNKNOWNS_PER_COARSE_CELL: usize = FIRST_LEVEL_UNKNOWNS_PER_CELL_3D;
    fn cell_size(measure: f64, cells: usize) -> f64 {
        (measure / cells as f64).cbrt()
    }
    fn cell_length(measure: f64) -> f64 {
        measure.cbrt()
    }
    fn coarsen(
        &self,
        size: f64,
        boundary_key: Option<&[u32]>,
        budget: MemoryBudget,
    ) -> Result<Level<Self>, MeshError> {
        // more than half the cells in failed aggregates: this level would not be coarser
        let a = crate::mesh3d::agglomerate::agglomerate3_merging(
            self,
            size,
            boundary_key,
            0.5,
            budget,
        )?;
        level3(a)
    }
    fn cover(&self, size: f64, budget: MemoryBudget) -> Option<Result<Level<Self>, MeshError>> {
        Some(crate::mesh3d::agglomerate::box_cover(self, size, budget).and_then(level3))
    }
    fn box_tiling(&self, measure: f64, size: f64) -> Option<f64> {
        tiling(
            &self.bounding_box().ranges().map(|r| r[1] - r[0]),
            measure,
            size,
        )
    }
    fn face_distance(&self, f: usize, p: Vector<3>) -> f64 {
        let ids = self.face_vertices(f);
        let x = self.vertices();
        let corner = |i: usize| x[ids[i] as usize];
        let m = ids.len();
        if m == 3 {
            return triangle_distance(p, [corner(0), corner(1), corner(2)]);
        }
        let mut c = [0.0; 3];
        for i in 0..m {
            for (cr, xr) in c.iter_mut().zip(corner(i)) {
                *cr += xr;
            }
        }
        let c = c.map(|s| s / m as f64);
        (0..m)
            .map(|i| triangle_distance(p, [c, corner(i), corner((i + 1) % m)]))
            .fold(f64::INFINITY, f64::min)
    }
    fn cell_vertex_ids<'s>(&'s self, k: usize, scratch: &'s mut Vec<u32>) -> &'s [u32] {
        scratch.clear();
        for &f in self.cell_faces(k) {
            scratch.extend_from_slice(self.face_vertices(f as usize));
        }
        scratch.sort_unstable();
        scratch.dedup();
        scratch
    }
    fn face_vertex_ids<'s>(&self, f: usize, scratch: &'s mut Vec<u32>) -> &'s [u32] {
        scratch.clear();
        scratch.extend_from_slice(self.face_vertices(f));
        scratch
    }
}

/// The level of a 3D agglomeration or cover: its cell map moved, its boundary face map kept
/// for the boundary faces only ([`NO_FACE`] is [`NO_COARSE_FACE`]).
fn level3(a: crate::mesh3d::agglomerate::Agglomeration3) -> Result<Level<PolyMesh3>, MeshError> {
    const _: () = assert!(NO_FACE == NO_COARSE_FACE);
    Ok(Level {
        boundary_face_of: BoundaryFaceMap::from_dense(&a.boundary_face_of)?,
        cell_of: a.cell_of,
        mesh: a.mesh,
    })
}

/// Distance from p to the segment [a, b].
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (d, q) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        ((q[0] * d[0] + q[1] * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q[0] - t * d[0]).hypot(q[1] - t * d[1])
}

fn sub(a: Point3, b: Point3) -> Point3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Point3, b: Point3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Distance from p to the triangle t (closed), by the closest point: the region of p among
/// the vertex, edge and face regions of t (Ericson, Real-Time Collision Detection, § 5.1.5,
/// in barycentric form). A degenerate triangle falls back to its edges.
fn triangle_distance(p: Point3, t: [Point3; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return dot(ap, ap).sqrt(); // vertex a
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return dot(bp, bp).sqrt(); // vertex b
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return dot(cp, cp).sqrt(); // vertex c
    }
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    let edge = |o: Point3, e: Point3| {
        let l2 = dot(e, e);
        let t = if l2 > 0.0 {
            (dot(sub(p, o), e) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = sub(sub(p, o), e.map(|x| t * x));
        dot(q, q).sqrt()
    };
    let denom = va + vb + vc;
    if !(denom > 0.0) {
        // degenerate: the least distance to the three edges
        return edge(a, ab).min(edge(a, ac)).min(edge(b, sub(c, b)));
    }
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return edge(a, ab);
    }
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return edge(a, ac);
    }
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return edge(b, sub(c, b));
    }
    let (v, w) = (vb / denom, vc / denom);
    let q = sub(ap, ab.map(|x| v * x));
    let q = sub(q, ac.map(|x| w * x));
    dot(q, q).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sparse map answers as the dense one it was made from, on every face and beyond.
    #[test]
    fn boundary_face_map_answers_as_the_dense_map() {
        let x = NO_COARSE_FACE;
        let dense = [x, 3, x, x, 0, 7, x, 1];
        let map = BoundaryFaceMap::from_dense(&dense).unwrap();
        assert_eq!(map.fine_faces(), 8);
        for (e, &c) in dense.iter().enumerate() {
            let want = (c != x).then_some(c as usize);
            assert_eq!(map.get(e), want, "face {e}");
        }
        assert_eq!(map.get(8), None);
        assert_eq!(map.get(usize::MAX), None);
        let interior = BoundaryFaceMap::from_dense(&[x; 5]).unwrap();
        assert_eq!(interior.fine_faces(), 5);
        assert!((0..5).all(|e| interior.get(e).is_none()));
    }

    /// The triangle distance against brute force over a fine barycentric grid of the triangle.
    #[test]
    fn triangle_distance_is_the_least_distance_to_the_triangle() {
        let mut rng = crate::mesh::test_rng(7);
        let mut pt = || [0, 1, 2].map(|_| 4.0 * rng() - 2.0);
        for _ in 0..200 {
            let t = [pt(), pt(), pt()];
            let p = pt();
            let n = 200;
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let q: Point3 = [0, 1, 2]
                        .map(|r| t[0][r] + u * (t[1][r] - t[0][r]) + v * (t[2][r] - t[0][r]));
                    let d = sub(p, q);
                    best = best.min(dot(d, d).sqrt());
                }
            }
            let d = triangle_distance(p, t);
            // the grid's points are within its spacing of every point of the triangle
            let spacing = [0, 1, 2]
                .map(|i| dot(sub(t[(i + 1) % 3], t[i]), sub(t[(i + 1) % 3], t[i])).sqrt())
                .iter()
                .fold(0.0f64, |m, &l| m.max(l))
                / n as f64;
            assert!(d <= best + 1e-12, "{d} > {best}");
            assert!(d >= best - spacing, "{d} < {best} - {spacing}");
        }
    }

    /// Boxes tile a box domain when the longest side's count fits the others; never a domain
    /// that is not its bounding box.
    #[test]
    fn box_tiling_needs_a_box_that_whole_boxes_cut() {
        use crate::mesh::CellComplex;
        use crate::mesh3d::Cuboid;
        use crate::mesh3d::generate::kuhn;
        let budget = MemoryBudget::DEFAULT;
        let cuboid = Cuboid::new([0.0, 2.0], [0.0, 1.0], [0.0, 1.0]);
        let m = PolyMesh3::from_polyhedra(kuhn(4, cuboid, budget).unwrap(), budget).unwrap();
        let measure: f64 = (0..m.n_cells()).map(|k| m.cell_measure(k)).sum();
        // 2 / 0.26 rounds to 8 boxes of 0.25: 4 along the unit sides
        assert_eq!(m.box_tiling(measure, 0.26), Some(0.25));
        // 2 / 0.3 rounds to 7 boxes of 2/7: 3.5 along the unit sides
        assert_eq!(m.box_tiling(measure, 0.3), None);
        // the same mesh seen as a smaller domain (a cell missing) is not a box
        assert_eq!(m.box_tiling(0.99 * measure, 0.26), None);
        // in 2D the same rule: a 2 × 1 rectangle, and an L-shape's measure
        let planar = crate::mesh::generate::cartesian_rect(8, 4, [0.0, 2.0], [0.0, 1.0]).unwrap();
        assert_eq!(planar.box_tiling(2.0, 0.26), Some(0.25));
        assert_eq!(planar.box_tiling(2.0, 0.3), None);
        assert_eq!(planar.box_tiling(1.5, 0.26), None);
        let cover = planar.cover(0.25, budget).unwrap().unwrap();
        assert_eq!(cover.mesh.n_cells(), 32);
        assert!(planar.cover(0.3, budget).unwrap().is_err());
    }

    /// A point above the middle of the unit square face of a cube, and one beside it.
    #[test]
    fn face_distance_on_a_cube() {
        let m = PolyMesh3::from_polyhedra(
            crate::mesh3d::test_meshes::cubes(1, 1),
            MemoryBudget::DEFAULT,
        )
        .unwrap();
        // the face on x = 1
        let f = (0..m.n_faces())
            .find(|&f| {
                m.face_vertices(f)
                    .iter()
                    .all(|&v| m.vertices()[v as usize][0] == 1.0)
            })
            .unwrap();
        assert!((m.face_distance(f, [1.5, 0.5, 0.5]) - 0.5).abs() < 1e-14);
        assert!((m.face_distance(f, [1.0, 2.0, 0.5]) - 1.0).abs() < 1e-14);
        let d = m.face_distance(f, [2.0, 2.0, 2.0]);
        assert!((d - 3f64.sqrt()).abs() < 1e-14, "{d}");
    }
}
