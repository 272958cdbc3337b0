//! Three-dimensional polyhedral meshes.
//!
//! Readers and generators describe a 3D mesh first as [`Polyhedra`]: flat arrays of vertex
//! coordinates and, for every cell, its faces as loops of vertex ids (a face shared by two
//! cells is listed by both, in either orientation, as in HArDCore's RF files and in gmsh's
//! element types once their faces are spelled out). The mesh type is built from that
//! description, which is where faces are matched, oriented and validated.
//!
//! [`PolyMesh3::from_polyhedra`] builds a [`PolyMesh3`]: flat CSR arrays with 32-bit ids (cells
//! as lists of faces, faces as vertex loops counter-clockwise seen from outside their first
//! cell, face–cell incidence, boundary faces, tags) and the geometry of the notation table
//! (stored, except x_σ and n_σ, which are computed from the face's loop when asked for:
//! [`PolyMesh3::face_frame`]), computed as `geometry.rs` states (exact for planar faces; for
//! warped faces the fan of triangles around the face's vertex average, HArDCore3D's
//! convention, or, with [`WarpedFaces::Split`] and [`PolyMesh3::from_polyhedra_with`], each of
//! those triangles a face of its own).
//!
//! | accessor | maths |
//! |---|---|
//! | [`PolyMesh3::measure`] | \|K\| |
//! | [`PolyMesh3::centroid`] | x_K (centre of mass, not the vertex average) |
//! | [`PolyMesh3::diameter`] | h_K = max distance between two vertices of K |
//! | [`PolyMesh3::face_measure`] | \|σ\| |
//! | [`PolyMesh3::face_centroid`] | x_σ |
//! | [`PolyMesh3::face_normal`] | n_σ, unit, outward from the face's first cell |
//! | [`PolyMesh3::cell_normal_dist`] | (n_{K,σ}, d_{K,σ} = (x_σ − x_K)·n_{K,σ}) on local face i |
//! | [`PolyMesh3::h`] | h = max_K h_K |
//! | [`PolyMesh3::bounding_box`] | the smallest [`Cuboid`] holding Ω |
//!
//! ## Files
//! One job each: `build.rs` runs the construction ([`mesh3_bytes`] is its memory estimate);
//! `faces.rs` matches face sides into faces; `orient.rs` orients each cell's faces outward;
//! `geometry.rs` computes the geometry (the maths is in its docs); [`validate`] lists every
//! check and runs those on the input; `shape.rs` checks warp and star-shapedness; `mesh.rs`
//! holds the type and its accessors; `tags.rs` the tags; `complex.rs` the
//! [`CellComplex<3>`](crate::mesh::CellComplex) view a scheme reads; `renumber.rs` drops
//! unused vertices ([`Polyhedra::drop_unused_vertices`], for readers); `surface.rs` and
//! `overlap.rs` check the boundary surface and overlaps; `simplex.rs` gives the vertices of a
//! tetrahedral cell ([`PolyMesh3::tetrahedron`]) to the schemes on simplices; `crossing.rs`
//! checks that no boundary edge crosses a boundary face; `split_faces.rs` splits warped faces
//! into their fan triangles when asked ([`WarpedFaces`], a build option whose default,
//! [`WarpedFaces::Fan`], keeps them whole).

pub mod agglomerate;
pub mod io;

pub mod generate;

use crate::error::MeshError;

mod build;
mod complex;
mod crossing;
mod face_order;
mod faces;
mod geometry;
mod mesh;
mod orient;
mod overlap;
mod renumber;
mod shape;
mod simplex;
mod solve_mesh;
mod split_faces;
mod surface;
mod tags;
#[cfg(test)]
pub(crate) mod test_meshes;
#[cfg(test)]
mod tests_build;
#[cfg(test)]
mod tests_errors;
#[cfg(test)]
mod tests_external;
#[cfg(test)]
mod tests_split;
pub mod validate;

pub use build::{boundary_surface_bytes, mesh3_bytes};
pub use mesh::PolyMesh3;
pub use split_faces::{PLANAR_TOL, WarpedFaces};
pub use validate::{MAX_CELL_FACES, MAX_FACE_VERTICES, WARP_TOL};

/// A point or vector of ℝ³.
pub type Point3 = [f64; 3];

/// An axis-parallel box \[x0, x1\] × \[y0, y1\] × \[z0, z1\]: the x range, the y range, then
/// the z range (the 3D counterpart of [`crate::mesh::Rect`]). Generators map the unit cube
/// onto one; the bounding box of a mesh is one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cuboid {
    /// \[x0, x1\].
    pub x: [f64; 2],
    /// \[y0, y1\].
    pub y: [f64; 2],
    /// \[z0, z1\].
    pub z: [f64; 2],
}

impl Cuboid {
    /// The unit cube \[0, 1\]³.
    pub const UNIT: Cuboid = Cuboid {
        x: [0.0, 1.0],
        y: [0.0, 1.0],
        z: [0.0, 1.0],
    };

    /// \[x\[0\], x\[1\]\] × \[y\[0\], y\[1\]\] × \[z\[0\], z\[1\]\].
    pub const fn new(x: [f64; 2], y: [f64; 2], z: [f64; 2]) -> Self {
        Cuboid { x, y, z }
    }

    /// The three ranges, in the order x, y, z.
    pub fn ranges(&self) -> [[f64; 2]; 3] {
        [self.x, self.y, self.z]
    }

    /// Whether every bound is finite and each range has positive length.
    pub fn is_proper(&self) -> bool {
        self.ranges()
            .iter()
            .all(|r| r[0].is_finite() && r[1].is_finite() && r[0] < r[1])
    }

    /// |x1 − x0| · |y1 − y0| · |z1 − z0|.
    pub fn volume(&self) -> f64 {
        self.ranges().iter().map(|r| r[1] - r[0]).product()
    }

    /// The image of `p` of the unit cube under the affine map onto this box.
    pub fn map_unit(&self, p: Point3) -> Point3 {
        let r = self.ranges();
        std::array::from_fn(|i| r[i][0] + (r[i][1] - r[i][0]) * p[i])
    }
}

impl std::fmt::Display for Cuboid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z] = self.ranges();
        write!(
            f,
            "[{}, {}]x[{}, {}]x[{}, {}]",
            x[0], x[1], y[0], y[1], z[0], z[1]
        )
    }
}

/// The flat description of a 3D polyhedral mesh, before validation.
///
/// Cell `k` has the faces `cell_ptr[k]..cell_ptr[k + 1]` (indices into `face_ptr`, one entry
/// per cell side, so a face shared by two cells appears twice); face side `s` has the vertex
/// loop `face_vertices[face_ptr[s]..face_ptr[s + 1]]` (0-based vertex ids, in order around the
/// face, either orientation). Both offset arrays start at 0, are non-decreasing and end at the
/// length of what they index; they are 32-bit, as every id of the mesh.
///
/// Tags: `cell_tags` is empty (no tags) or has one entry per cell (gmsh's physical volume);
/// boundary faces are tagged by `boundary_tags`, each a vertex loop of a boundary face (any
/// rotation or orientation: faces are matched by their vertex sets) with its tag (gmsh's
/// physical surface), in `tagged_ptr` / `tagged_vertices` / `tagged_tags` with the same flat
/// layout as the faces.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Polyhedra {
    /// Vertex coordinates.
    pub vertices: Vec<Point3>,
    /// Offsets of each cell's faces in `face_ptr` (length: cells + 1).
    pub cell_ptr: Vec<u32>,
    /// Offsets of each face side's vertex loop in `face_vertices` (length: cell sides + 1).
    pub face_ptr: Vec<u32>,
    /// The vertex loops of the cell sides, concatenated.
    pub face_vertices: Vec<u32>,
    /// One tag per cell, or empty.
    pub cell_tags: Vec<i32>,
    /// Offsets of the tagged boundary faces' vertex loops in `tagged_vertices`.
    pub tagged_ptr: Vec<u32>,
    /// The vertex loops of the tagged boundary faces, concatenated.
    pub tagged_vertices: Vec<u32>,
    /// The tag of each tagged boundary face.
    pub tagged_tags: Vec<i32>,
}

impl Polyhedra {
    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cell_ptr.len().saturating_sub(1)
    }

    /// The face sides of cell `k`, as ranges of `face_ptr` indices.
    pub fn cell_sides(&self, k: usize) -> std::ops::Range<usize> {
        self.cell_ptr[k] as usize..self.cell_ptr[k + 1] as usize
    }

    /// The vertex loop of face side `s`.
    pub fn side_vertices(&self, s: usize) -> &[u32] {
        &self.face_vertices[self.face_ptr[s] as usize..self.face_ptr[s + 1] as usize]
    }

    /// Appends a cell given as its faces' vertex loops (for readers and generators; the ids are
    /// not checked here, but when the mesh is built). [`MeshError::TooManyEntities`] if the
    /// face sides or face vertices outgrow the 32-bit offsets (then nothing is appended).
    pub fn push_cell<'a>(
        &mut self,
        faces: impl IntoIterator<Item = &'a [u32]> + Clone,
    ) -> Result<(), MeshError> {
        let (sides, verts) = faces
            .clone()
            .into_iter()
            .fold((0, 0), |(s, v), f| (s + 1, v + f.len()));
        check_count("face sides", self.face_ptr.len() + sides)?;
        check_count("face vertices", self.face_vertices.len() + verts)?;
        if self.cell_ptr.is_empty() {
            self.cell_ptr.push(0);
        }
        if self.face_ptr.is_empty() {
            self.face_ptr.push(0);
        }
        for f in faces {
            self.face_vertices.extend_from_slice(f);
            self.face_ptr.push(self.face_vertices.len() as u32);
        }
        self.cell_ptr.push((self.face_ptr.len() - 1) as u32);
        Ok(())
    }
}

/// [`MeshError::TooManyEntities`] unless `count` fits the 32-bit ids and offsets.
fn check_count(what: &'static str, count: usize) -> Result<(), MeshError> {
    if count >= u32::MAX as usize {
        return Err(MeshError::TooManyEntities { what, count });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{Cuboid, Polyhedra};

    #[test]
    fn cuboids_map_the_unit_cube_range_by_range() {
        let c = Cuboid::new([-1.0, 3.0], [0.0, 0.5], [2.0, 2.25]);
        assert_eq!(c.map_unit([0.0, 0.0, 0.0]), [-1.0, 0.0, 2.0]);
        assert_eq!(c.map_unit([1.0, 1.0, 1.0]), [3.0, 0.5, 2.25]);
        assert_eq!(c.volume(), 0.5);
        assert!(c.is_proper() && Cuboid::UNIT.is_proper());
        assert!(!Cuboid::new([0.0, 1.0], [1.0, 1.0], [0.0, 1.0]).is_proper());
        assert!(!Cuboid::new([0.0, f64::NAN], [0.0, 1.0], [0.0, 1.0]).is_proper());
        assert_eq!(c.to_string(), "[-1, 3]x[0, 0.5]x[2, 2.25]");
    }

    #[test]
    fn pushed_cells_are_read_back() {
        let mut p = Polyhedra::default();
        p.push_cell([&[0, 1, 2][..], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]])
            .unwrap();
        p.push_cell([&[1, 2, 3][..], &[1, 4, 2], &[2, 4, 3], &[3, 4, 1]])
            .unwrap();
        assert_eq!(p.n_cells(), 2);
        assert_eq!(p.cell_sides(1), 4..8);
        assert_eq!(p.side_vertices(5), &[1, 4, 2]);
        assert_eq!(p.face_ptr.len(), 9);
    }
}
