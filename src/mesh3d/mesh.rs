//! [`PolyMesh3`], the validated 3D polyhedral mesh, and its accessors.

use super::geometry::{diameter, dot, face_geometry, norm, sub};
use super::{Cuboid, Point3, Polyhedra};
use crate::mesh::NO_CELL;
use crate::mesh::complex::FaceOfCell;
use crate::offsets::Offsets;

/// A conforming mesh of polyhedra with the cells' volumes and centroids cached (face areas,
/// centroids and normals and cell diameters computed on demand: [`PolyMesh3::face_measure`],
/// [`PolyMesh3::face_frame`], [`PolyMesh3::diameter`]), flat and immutable: every array is
/// indexed by 32-bit ids, cells and faces are CSR lists (offsets, one stride when the lists
/// have one length, and data), nothing is allocated per cell. Built by [`PolyMesh3::from_polyhedra`]; see the module docs of
/// [`crate::mesh3d`] for the maths and the checks.
#[derive(Debug, Clone)]
pub struct PolyMesh3 {
    pub(crate) vertices: Vec<Point3>,
    /// Offsets of each cell's faces in `cell_faces` (one stride when every cell has as many).
    pub(crate) cell_ptr: Offsets,
    /// The faces of every cell, in the order the cell listed them.
    pub(crate) cell_faces: Vec<u32>,
    /// Offsets of each face's vertex loop in `face_verts` (one stride when every face has as
    /// many vertices).
    pub(crate) face_ptr: Offsets,
    /// The vertex loop of every face, counter-clockwise seen from outside its first cell.
    pub(crate) face_verts: Vec<u32>,
    /// The cells of every face; `u32::MAX` as second cell on the boundary.
    pub(crate) face_cells: Vec<[u32; 2]>,

    /// Tag of every cell (0 when untagged); empty when every cell has tag 0.
    pub(crate) cell_tags: Vec<i32>,
    pub(crate) cell_volume: Vec<f64>,
    pub(crate) cell_centroid: Vec<Point3>,
    /// The boundary faces, in increasing order.
    pub(crate) boundary_faces: Vec<u32>,
    /// The tag of each boundary face, in the order of `boundary_faces` (0 when untagged;
    /// interior faces have tag 0 and store none).
    pub(crate) boundary_tags: Vec<i32>,
    pub(crate) h: f64,
}

impl PolyMesh3 {
    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// The vertex coordinates.
    pub fn vertices(&self) -> &[Point3] {
        &self.vertices
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cell_ptr.n_lists()
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.face_ptr.n_lists()
    }

    /// The faces of cell `k`, in the order its description listed them (local face i is
    /// `cell_faces(k)[i]`).
    pub fn cell_faces(&self, k: usize) -> &[u32] {
        &self.cell_faces[self.cell_ptr.range(k)]
    }

    /// The vertex loop of face `f`, counter-clockwise seen from outside `face_cells(f)[0]`.
    pub fn face_vertices(&self, f: usize) -> &[u32] {
        &self.face_verts[self.face_ptr.range(f)]
    }

    /// The cells on either side of face `f`: the one its loop and normal are outward from,
    /// then the other, or [`NO_CELL`] on the boundary.
    pub fn face_cells(&self, f: usize) -> [usize; 2] {
        let [a, b] = self.face_cells[f];
        [a as usize, if b == u32::MAX { NO_CELL } else { b as usize }]
    }

    /// Whether face `f` is on the boundary.
    pub fn is_boundary_face(&self, f: usize) -> bool {
        self.face_cells[f][1] == u32::MAX
    }

    /// The boundary faces, in increasing order.
    pub fn boundary_faces(&self) -> &[u32] {
        &self.boundary_faces
    }

    /// |K|, the volume of cell `k`.
    pub fn measure(&self, k: usize) -> f64 {
        self.cell_volume[k]
    }

    /// x_K, the centroid (centre of mass) of cell `k`.
    pub fn centroid(&self, k: usize) -> Point3 {
        self.cell_centroid[k]
    }

    /// h_K, the largest distance between two vertices of cell `k` (computed when asked for).
    pub fn diameter(&self, k: usize) -> f64 {
        let mut ids: Vec<u32> = Vec::new();
        for &f in self.cell_faces(k) {
            ids.extend_from_slice(self.face_vertices(f as usize));
        }
        ids.sort_unstable();
        ids.dedup();
        diameter(&self.vertices, &ids)
    }

    /// h = max_K h_K.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// |σ|, the area of face `f` (computed from its loop when asked for, like
    /// [`PolyMesh3::face_frame`]: the same bits as the build's).
    pub fn face_measure(&self, f: usize) -> f64 {
        face_geometry(&self.vertices, self.face_vertices(f)).area
    }

    /// x_σ, the centroid of face `f` (computed from its loop: see [`PolyMesh3::face_frame`]).
    pub fn face_centroid(&self, f: usize) -> Point3 {
        self.face_frame(f).0
    }

    /// The unit normal of face `f`, outward from `face_cells(f)[0]` (computed from its loop:
    /// see [`PolyMesh3::face_frame`]).
    pub fn face_normal(&self, f: usize) -> Point3 {
        self.face_frame(f).1
    }

    /// (x_σ, n_σ) of face `f`: its centroid and its unit normal N_σ/|N_σ|, from the fan
    /// triangles of its loop (module docs of [`crate::mesh3d`]). They are not stored (48 bytes
    /// per face, more than the rest of a face's data); a pure function of the loop and the
    /// vertices, they have the same bits at every call.
    pub fn face_frame(&self, f: usize) -> (Point3, Point3) {
        let g = face_geometry(&self.vertices, self.face_vertices(f));
        let l = norm(g.vector_area);
        (g.centroid, g.vector_area.map(|x| x / l))
    }

    /// (n_{K,σ}, d_{K,σ}) on local face `i` of cell `k`: the outward unit normal and
    /// d_{K,σ} = (x_σ − x_K)·n_{K,σ}.
    pub fn cell_normal_dist(&self, k: usize, i: usize) -> (Point3, f64) {
        let g = self.face_of_cell(k, i);
        (g.normal, g.dist)
    }

    /// |σ|, x_σ, n_{K,σ} and d_{K,σ} of local face `i` of cell `k`, from one evaluation of the
    /// face's fan geometry: the values of [`PolyMesh3::face_measure`],
    /// [`PolyMesh3::face_centroid`] and [`PolyMesh3::cell_normal_dist`] (which takes its
    /// values from here), bit for bit.
    pub fn face_of_cell(&self, k: usize, i: usize) -> FaceOfCell<3> {
        let f = self.cell_faces(k)[i] as usize;
        let g = face_geometry(&self.vertices, self.face_vertices(f));
        let l = norm(g.vector_area);
        let n = g.vector_area.map(|x| x / l);
        let n = if self.face_cells[f][0] as usize == k {
            n
        } else {
            n.map(|x| -x)
        };
        FaceOfCell {
            measure: g.area,
            centre: g.centroid,
            normal: n,
            dist: dot(sub(g.centroid, self.cell_centroid[k]), n),
        }
    }

    /// The tag of cell `k` (gmsh physical volume; 0 when untagged).
    pub fn cell_tag(&self, k: usize) -> i32 {
        if self.cell_tags.is_empty() {
            0
        } else {
            self.cell_tags[k]
        }
    }

    /// The boundary tag of face `f` (gmsh physical surface; 0 for interior faces and untagged
    /// boundary faces), found among the boundary faces by binary search.
    pub fn face_tag(&self, f: usize) -> i32 {
        match self.boundary_index(f) {
            Some(i) => self.boundary_tags[i],
            None => 0,
        }
    }

    /// The position of face `f` in the list of boundary faces, if it is one.
    pub(crate) fn boundary_index(&self, f: usize) -> Option<usize> {
        if !self.is_boundary_face(f) {
            return None;
        }
        self.boundary_faces.binary_search(&(f as u32)).ok()
    }

    /// The smallest [`Cuboid`] holding the mesh.
    pub fn bounding_box(&self) -> Cuboid {
        let mut r = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
        for p in &self.vertices {
            for a in 0..3 {
                r[a] = [r[a][0].min(p[a]), r[a][1].max(p[a])];
            }
        }
        Cuboid::new(r[0], r[1], r[2])
    }

    /// The mesh as a [`Polyhedra`], what writers consume: every cell's faces as loops
    /// counter-clockwise seen from outside the cell, in the cell's local order; the cell tags
    /// (empty if all are 0); the boundary faces with a non-zero tag, as their outward loops.
    pub fn to_polyhedra(&self) -> Polyhedra {
        let sides = self.cell_faces.len();
        let mut p = Polyhedra {
            vertices: self.vertices.clone(),
            cell_ptr: self.cell_ptr.to_offsets(),
            face_ptr: Vec::with_capacity(sides + 1),
            face_vertices: Vec::with_capacity(self.face_verts.len() * 2),
            ..Polyhedra::default()
        };
        p.face_ptr.push(0);
        for k in 0..self.n_cells() {
            for &f in self.cell_faces(k) {
                let l = self.face_vertices(f as usize);
                if self.face_cells[f as usize][0] as usize == k {
                    p.face_vertices.extend_from_slice(l);
                } else {
                    p.face_vertices.extend(l.iter().rev());
                }
                p.face_ptr.push(p.face_vertices.len() as u32);
            }
        }
        if self.cell_tags.iter().any(|&t| t != 0) {
            p.cell_tags = self.cell_tags.clone();
        }
        for (&f, &tag) in self.boundary_faces.iter().zip(&self.boundary_tags) {
            if tag != 0 {
                if p.tagged_ptr.is_empty() {
                    p.tagged_ptr.push(0);
                }
                p.tagged_vertices
                    .extend_from_slice(self.face_vertices(f as usize));
                p.tagged_ptr.push(p.tagged_vertices.len() as u32);
                p.tagged_tags.push(tag);
            }
        }
        p
    }
}
