//! Check 12a of [`validate`](super::validate): no cell covers a boundary vertex.
//!
//! Once every cell is a closed, outward-oriented surface and interior faces are shared by two
//! cells on opposite sides, Σ_K |K| equals the volume enclosed by the boundary surface,
//! (1/3) Σ_{boundary σ} Σ_{T ⊂ σ} N_T·x_T, exactly in exact arithmetic (the divergence theorem,
//! interior fans cancelling), whether or not cells overlap: the volume balance cannot see an
//! overlap in 3D. What does see it: cells covering a region twice have boundary faces inside
//! other cells (a cell floating inside another, two meshes interpenetrating, a mesh folded
//! over itself), so some boundary vertex lies strictly inside a cell. Each boundary vertex is
//! tested against the cells whose bounding box holds it, found in a uniform grid of about one
//! bucket per cell over the bounding box of the mesh (only the buckets holding a boundary
//! vertex are filled); a cell, star-shaped with respect to x_K
//! (check 10), is the union of the tetrahedra (x_K, T) over the fan triangles T of its faces,
//! and a point is strictly inside it if it lies in one of these tetrahedra and not on its
//! outer triangle (barycentric coordinates, to 10⁻⁹). Expected O(n) for meshes of cells of
//! comparable sizes. Overlaps in which no vertex enters a cell (two bars crossing, an edge
//! through a face) are check 12b's (`crossing.rs`), which shares the grid defined here.

use super::Point3;
use super::PolyMesh3;
use super::geometry::{for_each_fan_corners, tet_volume};
use crate::error::MeshError;
use crate::mesh::buckets::counting_sort;
use rayon::prelude::*;

/// A uniform grid of n × n × n buckets over a bounding box.
pub(super) struct Grid {
    lo: [f64; 3],
    width: [f64; 3],
    n: usize,
}

impl Grid {
    /// About one bucket per cell over the bounding box of `m` (at most 1024 per side).
    pub(super) fn over(m: &PolyMesh3) -> Grid {
        let bb = m.bounding_box().ranges();
        let n = ((m.n_cells() as f64).cbrt().ceil() as usize).clamp(1, 1024);
        Grid {
            lo: bb.map(|r| r[0]),
            width: std::array::from_fn(|a| (bb[a][1] - bb[a][0]) / n as f64),
            n,
        }
    }

    /// The slabs of every vertex of `m` ([`Grid::slabs`]).
    pub(super) fn vertex_slabs(&self, m: &PolyMesh3) -> Vec<[u16; 3]> {
        m.vertices.par_iter().map(|&p| self.slabs(p)).collect()
    }

    /// The buckets of the slab ranges `r` (as [`slab_range`] gives them), x fastest.
    pub(super) fn buckets(&self, r: [[usize; 2]; 3]) -> impl Iterator<Item = usize> + '_ {
        let n = self.n;
        (r[2][0]..=r[2][1]).flat_map(move |z| {
            (r[1][0]..=r[1][1])
                .flat_map(move |y| (r[0][0]..=r[0][1]).map(move |x| x + n * (y + n * z)))
        })
    }

    /// The index of the slab holding coordinate `x` along axis `a` (clamped to the grid).
    fn slab(&self, x: f64, a: usize) -> usize {
        (((x - self.lo[a]) / self.width[a]).floor().max(0.0) as usize).min(self.n - 1)
    }

    /// The slabs holding point `p` along each axis (below 1024: they fit 16 bits).
    fn slabs(&self, p: Point3) -> [u16; 3] {
        [0, 1, 2].map(|a| self.slab(p[a], a) as u16)
    }

    /// The bucket of slabs `s`.
    fn bucket(&self, s: [u16; 3]) -> usize {
        let n = self.n;
        s[0] as usize + n * (s[1] as usize + n * s[2] as usize)
    }
}

impl PolyMesh3 {
    /// [`MeshError::OverlappingPolyhedra`] naming a boundary vertex strictly inside a cell.
    ///
    /// Only the buckets holding a boundary vertex are filled (the others are never searched):
    /// the candidates of a vertex are the cells whose bucket range meets its bucket, in
    /// increasing order, and the error names the smallest boundary vertex inside a cell, and
    /// the smallest such cell.
    pub(crate) fn check_overlap(&self) -> Result<(), MeshError> {
        let grid = Grid::over(self);
        let n = grid.n;
        let mut boundary_vertices: Vec<u32> = self
            .boundary_faces
            .iter()
            .flat_map(|&f| self.face_vertices(f as usize).iter().copied())
            .collect();
        boundary_vertices.par_sort_unstable();
        boundary_vertices.dedup();
        let slabs = grid.vertex_slabs(self);
        // the searched buckets, numbered in increasing order
        let mut slot = vec![u32::MAX; n * n * n];
        for &v in &boundary_vertices {
            slot[grid.bucket(slabs[v as usize])] = 0;
        }
        let mut n_slots = 0u32;
        for s in slot.iter_mut().filter(|s| **s == 0) {
            *s = n_slots;
            n_slots += 1;
        }
        // (searched bucket, cell) pairs, one per searched bucket a cell's box meets, by cell
        let pairs: Vec<(u32, u32)> = (0..self.n_cells())
            .into_par_iter()
            .flat_map_iter(|k| {
                let ids = self
                    .cell_faces(k)
                    .iter()
                    .flat_map(|&f| self.face_vertices(f as usize));
                let slot = &slot;
                grid.buckets(slab_range(&slabs, ids)).filter_map(move |b| {
                    let b = slot[b];
                    (b != u32::MAX).then_some((b, k as u32))
                })
            })
            .collect();
        let (ptr, cells) = counting_sort(
            n_slots as usize,
            pairs.iter().map(|p| Some(p.0 as usize)),
            |i| pairs[i].1,
        );
        drop(pairs);
        let hit = boundary_vertices.par_iter().find_map_first(|&v| {
            let b = slot[grid.bucket(slabs[v as usize])] as usize;
            cells[ptr[b]..ptr[b + 1]]
                .iter()
                .find(|&&k| self.strictly_inside(k as usize, v))
                .map(|&k| (v, k))
        });
        match hit {
            Some((v, k)) => Err(MeshError::OverlappingPolyhedra {
                vertex: v as usize,
                cell: k as usize,
            }),
            None => Ok(()),
        }
    }

    /// Whether vertex `v` lies strictly inside cell `k` (see the module docs).
    fn strictly_inside(&self, k: usize, v: u32) -> bool {
        let xk = self.cell_centroid[k];
        let p = self.vertices[v as usize];
        let mut inside = false;
        for &f in self.cell_faces(k) {
            if inside {
                break;
            }
            let l = self.face_vertices(f as usize);
            if l.contains(&v) {
                return false;
            }
            let reversed = self.face_cells[f as usize][0] as usize != k;
            for_each_fan_corners(&self.vertices, l, reversed, |a, b, c| {
                inside |= in_tetrahedron(xk, [a, b, c], p);
            });
        }
        inside
    }
}

/// The ranges of slabs, along each axis, met by the bounding box of the points `ids`
/// (`slabs`: those of every vertex, [`Grid::vertex_slabs`]).
pub(super) fn slab_range<'a>(
    slabs: &[[u16; 3]],
    ids: impl IntoIterator<Item = &'a u32>,
) -> [[usize; 2]; 3] {
    let mut r = [[usize::MAX, 0]; 3];
    for &v in ids {
        let s = slabs[v as usize];
        for a in 0..3 {
            let i = s[a] as usize;
            r[a] = [r[a][0].min(i), r[a][1].max(i)];
        }
    }
    r
}

/// Whether `p` lies in the tetrahedron (xk, a, b, c) (positively oriented), strictly on the
/// inner side of (a, b, c): its barycentric coordinate of xk above 10⁻⁹, the others not below
/// −10⁻⁹.
fn in_tetrahedron(xk: Point3, [a, b, c]: [Point3; 3], p: Point3) -> bool {
    let vol = tet_volume(xk, a, b, c);
    if !(vol > 0.0) {
        return false;
    }
    let eps = 1e-9;
    tet_volume(p, a, b, c) / vol > eps
        && tet_volume(xk, p, b, c) / vol >= -eps
        && tet_volume(xk, a, p, c) / vol >= -eps
        && tet_volume(xk, a, b, p) / vol >= -eps
}
