//! Numbering the faces of a mesh read from a file in space order, for the memory locality of
//! the face unknowns.
//!
//! [`PolyMesh3::from_polyhedra`] numbers the faces in the order of their first side, that is
//! in the order of the cells. A generated mesh lists its cells box after box, so neighbouring
//! faces get nearby numbers; a mesh file need not: gmsh lists the tetrahedra of its 3D
//! meshers in an order with no spatial coherence. The face unknowns (HMM's condensed system,
//! Crouzeix–Raviart) are numbered as the faces, and a row of their matrix then reaches
//! unknowns all over memory: every product with the matrix, every smoothing sweep and the
//! multigrid setup miss the caches once the system outgrows them. On the gmsh cube with a
//! spherical hole (288 242 tetrahedra, HMM, one thread), the whole run took 12.4 s in the
//! file's cell order, 11.9 s with the cells shuffled at random, and 6.9 s with the cells sorted
//! by the Morton code of their centroids (`replication/measurements/mesh3d.md`).
//!
//! [`PolyMesh3::with_local_face_order`] renumbers the faces by the Morton (Z-order) code of
//! their vertex average: the bounding box of the vertices is cut into 2²¹ steps per axis, the
//! three step indices are interleaved bit by bit, and faces are sorted by that code, ties by
//! their old number (so the order is a function of the mesh alone, whatever the threads).
//! Faces close in space are then close in number, and a cell's faces with them. Only the face
//! numbering changes: the cells, the vertices, each face's loop and orientation (still
//! outward from its first cell), its cells and its tag are the same, so every quantity of a
//! cell or a vertex (the solution at the cells and vertices, the errors) is the same up to the
//! order of floating-point sums. The cells keep the file's order, so that the user's cell
//! numbers stay valid in every output.
//!
//! The readers' path ([`PolyMesh3::from_file_polyhedra`]) applies it; generated meshes keep
//! their face numbering, already local, and their results bit for bit.

use super::{Point3, PolyMesh3, Polyhedra, WarpedFaces};
use crate::budget::{MemoryBudget, try_filled, try_vec};
use crate::error::MeshError;
use crate::offsets::Offsets;
use rayon::prelude::*;

/// Bits per axis of the Morton code (3 × 21 = 63 bits).
const BITS: u32 = 21;

/// The 21 low bits of `v` spread to every third bit.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The Morton code of `p` in the box with corner `lo` and sides `len` (each > 0).
fn morton(p: Point3, lo: Point3, len: Point3) -> u64 {
    let steps = ((1u64 << BITS) - 1) as f64;
    let q = |d: usize| {
        let t = ((p[d] - lo[d]) / len[d]).clamp(0.0, 1.0);
        (t * steps) as u64
    };
    spread(q(0)) | spread(q(1)) << 1 | spread(q(2)) << 2
}

impl PolyMesh3 {
    /// [`PolyMesh3::from_polyhedra_with`] followed by [`PolyMesh3::with_local_face_order`]:
    /// the build of a mesh read from a file (see the module docs of `face_order.rs`).
    pub fn from_file_polyhedra(
        p: Polyhedra,
        budget: MemoryBudget,
        warped: WarpedFaces,
    ) -> Result<PolyMesh3, MeshError> {
        PolyMesh3::from_polyhedra_with(p, budget, warped)?.with_local_face_order()
    }

    /// The same mesh with its faces numbered by the Morton code of their vertex average (see
    /// the module docs of `face_order.rs`): the cells, vertices, loops, incidences and tags
    /// are unchanged, only the face numbers. A failed allocation is a typed error.
    pub fn with_local_face_order(self) -> Result<PolyMesh3, MeshError> {
        let nf = self.n_faces();
        if nf < 2 {
            return Ok(self);
        }
        // the vertices' bounding box, each side at least the smallest positive normal number
        // (so that a flat box divides)
        let r = self.bounding_box().ranges();
        let lo = r.map(|[a, _]| a);
        let len = r.map(|[a, b]| (b - a).max(f64::MIN_POSITIVE));
        // (code, old number) of every face, sorted: the new order
        let mut keyed: Vec<(u64, u32)> = try_vec(nf, "the face order")?;
        keyed.par_extend((0..nf).into_par_iter().map(|f| {
            let vs = self.face_vertices(f);
            let mut c = [0.0; 3];
            for &v in vs {
                let x = self.vertices[v as usize];
                for d in 0..3 {
                    c[d] += x[d];
                }
            }
            let n = vs.len() as f64;
            (morton([c[0] / n, c[1] / n, c[2] / n], lo, len), f as u32)
        }));
        keyed.par_sort_unstable();
        if keyed.iter().enumerate().all(|(i, &(_, f))| f as usize == i) {
            return Ok(self);
        }
        let mut new_of: Vec<u32> = try_filled(nf, 0u32, "the new face numbers")?;
        for (i, &(_, f)) in keyed.iter().enumerate() {
            new_of[f as usize] = i as u32;
        }
        let order: Vec<u32> = keyed.into_iter().map(|(_, f)| f).collect();
        let mut m = self;
        // loops, in the new order
        let face_ptr =
            Offsets::from_lengths(order.iter().map(|&f| m.face_ptr.range(f as usize).len()))
                .map_err(|e| MeshError::NonConforming(format!("renumbering the faces: {e}")))?;
        let mut face_verts: Vec<u32> = try_vec(m.face_verts.len(), "the face loops")?;
        face_verts.par_extend(
            order
                .par_iter()
                .flat_map_iter(|&f| m.face_verts[m.face_ptr.range(f as usize)].iter().copied()),
        );
        let mut face_cells: Vec<[u32; 2]> = try_vec(nf, "the cells of the faces")?;
        face_cells.par_extend(order.par_iter().map(|&f| m.face_cells[f as usize]));
        m.cell_faces
            .par_iter_mut()
            .for_each(|f| *f = new_of[*f as usize]);
        // boundary faces in increasing new order, each with its tag
        let mut boundary: Vec<(u32, i32)> = try_vec(m.boundary_faces.len(), "the boundary faces")?;
        boundary.extend(m.boundary_faces.iter().enumerate().map(|(i, &f)| {
            (
                new_of[f as usize],
                m.boundary_tags.get(i).copied().unwrap_or(0),
            )
        }));
        boundary.par_sort_unstable();
        let tagged = !m.boundary_tags.is_empty();
        m.boundary_faces = boundary.iter().map(|&(f, _)| f).collect();
        if tagged {
            m.boundary_tags = boundary.iter().map(|&(_, t)| t).collect();
        }
        m.face_ptr = face_ptr;
        m.face_verts = face_verts;
        m.face_cells = face_cells;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh3d::Cuboid;
    use crate::mesh3d::generate::kuhn;

    /// Kuhn tetrahedra of (−2,2)³, n³ cubes, with the cells in a scrambled order (as a
    /// mesher may list them) and the boundary faces on x = −2 tagged 1, on y = −2 tagged 2.
    fn scrambled(n: usize) -> Polyhedra {
        let side = [-2.0, 2.0];
        let box_ = Cuboid {
            x: side,
            y: side,
            z: side,
        };
        let p = kuhn(n, box_, MemoryBudget::DEFAULT).unwrap();
        let nc = p.n_cells();
        // k -> 7919 k mod nc visits every cell once (7919 is prime and does not divide nc)
        assert_ne!(nc % 7919, 0);
        let mut q = Polyhedra {
            vertices: p.vertices.clone(),
            ..Default::default()
        };
        for i in 0..nc {
            let k = i * 7919 % nc;
            q.push_cell(p.cell_sides(k).map(|s| p.side_vertices(s)))
                .unwrap();
        }
        q.tagged_ptr.push(0);
        for s in 0..p.face_ptr.len() - 1 {
            let l = p.side_vertices(s);
            for (axis, tag) in [(0, 1), (1, 2)] {
                if l.iter().all(|&v| p.vertices[v as usize][axis] == -2.0) {
                    q.tagged_vertices.extend_from_slice(l);
                    q.tagged_ptr.push(q.tagged_vertices.len() as u32);
                    q.tagged_tags.push(tag);
                }
            }
        }
        q
    }

    /// Mean over the cells of the spread of their face numbers (largest minus smallest).
    fn spread_of_cells(m: &PolyMesh3) -> f64 {
        let total: usize = (0..m.n_cells())
            .map(|k| {
                let f = m.cell_faces(k);
                (*f.iter().max().unwrap() - *f.iter().min().unwrap()) as usize
            })
            .sum();
        total as f64 / m.n_cells() as f64
    }

    /// The renumbered mesh has the same cells with the same faces (loops, cells, tags) under
    /// new numbers, its boundary list is sorted and complete, and a cell's faces lie close
    /// together: the mean spread of a cell's face numbers falls from about a third of the
    /// faces to a few hundred.
    #[test]
    fn faces_are_renumbered_in_space_order_and_nothing_else_changes() {
        let m0 = PolyMesh3::from_polyhedra(scrambled(12), MemoryBudget::DEFAULT).unwrap();
        let m1 = m0.clone().with_local_face_order().unwrap();
        assert_eq!(m1.n_faces(), m0.n_faces());
        assert_eq!(m1.n_cells(), m0.n_cells());
        let mut seen = vec![false; m1.n_faces()];
        for k in 0..m0.n_cells() {
            assert_eq!(m1.cell_volume[k], m0.cell_volume[k]);
            assert_eq!(m1.centroid(k), m0.centroid(k));
            let (f0, f1) = (m0.cell_faces(k), m1.cell_faces(k));
            assert_eq!(f0.len(), f1.len());
            for (&a, &b) in f0.iter().zip(f1) {
                let (a, b) = (a as usize, b as usize);
                seen[b] = true;
                assert_eq!(m0.face_vertices(a), m1.face_vertices(b));
                assert_eq!(m0.face_cells(a), m1.face_cells(b));
                assert_eq!(m0.face_tag(a), m1.face_tag(b));
                assert!(m1.face_cells(b).contains(&k));
            }
        }
        assert!(seen.iter().all(|&s| s));
        let b = m1.boundary_faces();
        assert!(b.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(b.len(), m0.boundary_faces().len());
        assert!(b.iter().all(|&f| m1.is_boundary_face(f as usize)));
        let tagged =
            |m: &PolyMesh3, t: i32| (0..m.n_faces()).filter(|&f| m.face_tag(f) == t).count();
        assert_eq!(tagged(&m1, 1), 2 * 12 * 12);
        assert_eq!(tagged(&m1, 2), 2 * 12 * 12);
        // measured: 8703 (scrambled) against 599 (12³ cubes, 10 368 tetrahedra, 21 600 faces)
        let (s0, s1) = (spread_of_cells(&m0), spread_of_cells(&m1));
        assert!(s0 > 0.1 * m0.n_faces() as f64, "{s0}");
        assert!(s1 < s0 / 8.0, "{s0} -> {s1}");
        // a mesh already in order is returned as it is
        let again = m1.clone().with_local_face_order().unwrap();
        assert_eq!(again.cell_faces, m1.cell_faces);
    }

    /// HMM on the scrambled and the renumbered mesh: the same active set and the same cell
    /// values up to the order of floating-point sums.
    #[test]
    fn the_solution_does_not_depend_on_the_face_numbers() {
        use crate::scheme::{GradientDiscretisation, Hmm};
        use crate::solver::{SolveOptions, solve_problem};
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let problem = crate::problem::file::load(root.join("problems/ex9-3d.toml"), &[])
            .unwrap()
            .problem_in::<3>()
            .unwrap();
        let m0 = PolyMesh3::from_polyhedra(scrambled(8), MemoryBudget::DEFAULT).unwrap();
        let m1 = m0.clone().with_local_face_order().unwrap();
        let solve = |m: &PolyMesh3| {
            let s = Hmm::<PolyMesh3, 3>::with_alpha(m, 1.0).unwrap();
            let sol = solve_problem(&s, &problem, &SolveOptions::default()).unwrap();
            assert!(sol.result.certificate.worst() <= 1e-10);
            (
                s.cell_values(sol.u()),
                sol.niter(),
                sol.result.active.iter().filter(|&&a| a).count(),
            )
        };
        let (u0, n0, a0) = solve(&m0);
        let (u1, n1, a1) = solve(&m1);
        assert_eq!((n0, a0), (n1, a1));
        assert!(a0 > 0);
        let diff = u0
            .iter()
            .zip(&u1)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-12, "{diff}");
    }

    #[test]
    fn spread_interleaves_the_bits() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread(0x1f_ffff), 0x1249_2492_4924_9249);
        let lo = [0.0; 3];
        let len = [1.0; 3];
        // the corner is 0, the far corner all ones, and x is the lowest bit
        assert_eq!(morton([0.0; 3], lo, len), 0);
        assert_eq!(morton([1.0; 3], lo, len), (1u64 << 63) - 1);
        assert_eq!(morton([1.0, 0.0, 0.0], lo, len), spread(0x1f_ffff));
        assert_eq!(morton([0.0, 1.0, 0.0], lo, len), spread(0x1f_ffff) << 1);
    }
}
