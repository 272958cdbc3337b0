//! Warped faces kept whole or split into their fan triangles ([`WarpedFaces`]).
//!
//! ## Why split
//! For a cell K bounded by planar faces, the divergence theorem applied to the affine fields
//! x ↦ (x − x_K)_s gives HMM's consistency identity
//!
//! ```text
//! C_K = Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ = |K| I,
//! ```
//!
//! because ∫_σ n (x − x_K)ᵀ = |σ| n_σ (x_σ − x_K)ᵀ when n is constant on σ. On a warped face
//! kept whole ([`WarpedFaces::Fan`], HArDCore3D's convention: one face, one unknown, the
//! geometry of its fan of triangles T_i = (c_σ, v_i, v_{i+1}) around the vertex average c_σ,
//! see `geometry.rs`), the fan is still a closed part of the cell's boundary, so
//! Σ_T N_T (x_T − x_K)ᵀ = |K| I holds triangle by triangle, but the face contributes
//! |σ| n_σ (x_σ − x_K)ᵀ = (Σ_T N_T)(Σ_T |N_T| x_T / Σ_T |N_T|)ᵀ − (Σ_T N_T) x_Kᵀ, which equals
//! Σ_T N_T (x_T − x_K)ᵀ only when the N_T are parallel: C_K differs from |K| I by about the
//! warp (see [`validate`](super::validate), "Warped faces"), and HMM is not exact on affine
//! functions.
//!
//! [`WarpedFaces::Split`] makes every fan triangle of a face warped beyond [`PLANAR_TOL`] a
//! face of its own: c_σ becomes a new vertex, shared by the two cells of σ (so the mesh stays
//! conforming), σ with m vertices becomes the m triangles (c_σ, v_i, v_{i+1}), each planar,
//! and the identity above holds on every cell to round-off. The cells are the same
//! polyhedra (bounded by the same triangles), so |K| and x_K are unchanged up to round-off
//! (the apex of the volume sum, the cell's vertex average, now counts the new vertices; the
//! sum does not depend on it); the mesh gains one vertex and m − 1 faces per split face
//! (one unknown per triangle for HMM). Boundary tags go to every triangle of a tagged face;
//! cell tags and the order of cells are kept, faces are renumbered by the build.
//!
//! The default is [`WarpedFaces::Fan`], as in HArDCore3D and the FVCA6 benchmark.

use super::geometry::vertex_average;
use super::{PolyMesh3, Polyhedra, mesh3_bytes};
use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_vec};
use crate::error::{Error, MeshError};
use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;

/// The warp (see [`PolyMesh3::face_warp`]) above which [`WarpedFaces::Split`] splits a face:
/// faces planar to round-off are kept whole.
pub const PLANAR_TOL: f64 = 1e-12;

/// How a 3D mesh represents a face whose vertices do not lie in one plane (see the module
/// docs of `split_faces.rs`, summarised in [`PolyMesh3::split_warped_faces`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum WarpedFaces {
    /// One face with the geometry of its fan of triangles (HArDCore3D's convention; HMM's
    /// consistency then holds up to the warp).
    #[default]
    Fan,
    /// Every face warped beyond [`PLANAR_TOL`] split into its fan triangles around a new
    /// vertex (HMM's consistency exact).
    Split,
}

impl WarpedFaces {
    /// The two conventions, the default first.
    pub const ALL: [WarpedFaces; 2] = [WarpedFaces::Fan, WarpedFaces::Split];

    /// The lowercase name accepted by [`WarpedFaces::from_str`]: `fan` or `split`.
    pub fn name(self) -> &'static str {
        match self {
            WarpedFaces::Fan => "fan",
            WarpedFaces::Split => "split",
        }
    }

    /// `m` itself under [`WarpedFaces::Fan`]; [`PolyMesh3::split_warped_faces`] under
    /// [`WarpedFaces::Split`].
    pub fn apply(self, m: PolyMesh3, budget: MemoryBudget) -> Result<PolyMesh3, MeshError> {
        match self {
            WarpedFaces::Fan => Ok(m),
            WarpedFaces::Split => m.split_warped_faces(budget),
        }
    }
}

impl fmt::Display for WarpedFaces {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for WarpedFaces {
    type Err = Error;

    /// Parses `"fan"` or `"split"` (case-insensitive, surrounding blanks ignored).
    fn from_str(s: &str) -> Result<Self, Error> {
        WarpedFaces::ALL
            .into_iter()
            .find(|w| w.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                Error::InvalidData(format!(
                    "unknown convention for warped faces {s:?}: expected \"fan\" or \"split\""
                ))
            })
    }
}

impl PolyMesh3 {
    /// [`PolyMesh3::from_polyhedra`], then warped faces as `warped` says
    /// ([`WarpedFaces::apply`]). The mesh is validated with its faces whole first, so a face
    /// warped beyond [`WARP_TOL`](super::WARP_TOL) is refused under either convention.
    pub fn from_polyhedra_with(
        p: Polyhedra,
        budget: MemoryBudget,
        warped: WarpedFaces,
    ) -> Result<PolyMesh3, MeshError> {
        warped.apply(PolyMesh3::from_polyhedra(p, budget)?, budget)
    }

    /// The faces of at least four vertices whose warp exceeds [`PLANAR_TOL`], in increasing
    /// order: those [`PolyMesh3::split_warped_faces`] splits.
    pub fn faces_to_split(&self) -> Vec<u32> {
        (0..self.n_faces() as u32)
            .into_par_iter()
            .filter(|&f| {
                let f = f as usize;
                self.face_vertices(f).len() > 3 && self.face_warp(f) > PLANAR_TOL
            })
            .collect()
    }

    /// The mesh with every face of [`PolyMesh3::faces_to_split`] split into its fan triangles
    /// around its vertex average, which becomes a new vertex (numbered after the existing
    /// ones, in the order of the faces), built and validated again by
    /// [`PolyMesh3::from_polyhedra`]; `self` unchanged when no face is warped. The maths is in
    /// the module docs of `split_faces.rs`: HMM's consistency identity then holds exactly,
    /// volumes and centroids are unchanged up to round-off. The description of the new mesh
    /// and its build ([`mesh3_bytes`]) are checked against `budget` before they are allocated.
    pub fn split_warped_faces(self, budget: MemoryBudget) -> Result<PolyMesh3, MeshError> {
        let warped = self.faces_to_split();
        if warped.is_empty() {
            return Ok(self);
        }
        let p = self.split_description(&warped, budget)?;
        drop(self);
        PolyMesh3::from_polyhedra(p, budget)
    }

    /// The [`Polyhedra`] of the mesh with the faces `warped` (increasing) split (see
    /// [`PolyMesh3::split_warped_faces`]): every cell's faces as outward loops in its local
    /// order, a split face as its outward fan triangles; the tagged boundary faces likewise.
    fn split_description(
        &self,
        warped: &[u32],
        budget: MemoryBudget,
    ) -> Result<Polyhedra, MeshError> {
        let n_vertices = self.n_vertices() + warped.len();
        let mut centre = try_filled(self.n_faces(), u32::MAX, "the split faces")?;
        let (mut sides, mut entries) = (self.cell_faces.len() as u64, 0u64);
        for (j, &f) in warped.iter().enumerate() {
            centre[f as usize] = (self.n_vertices() + j) as u32;
        }
        for k in 0..self.n_cells() {
            for &f in self.cell_faces(k) {
                let m = self.face_vertices(f as usize).len() as u64;
                let split = centre[f as usize] != u32::MAX;
                sides += if split { m - 1 } else { 0 };
                entries += if split { 3 * m } else { m };
            }
        }
        for (what, count) in [
            ("vertices", n_vertices as u64),
            ("face sides", sides),
            ("face vertices", entries),
        ] {
            if count >= u64::from(u32::MAX) {
                let count = usize::try_from(count).unwrap_or(usize::MAX);
                return Err(MeshError::TooManyEntities { what, count });
            }
        }
        let cells = self.n_cells() as u64;
        let description = 24 * n_vertices as u64 + 4 * (cells + sides + 2 + entries);
        let bytes = description + mesh3_bytes(cells, sides, entries, n_vertices as u64);
        budget.check(
            format!("splitting the {} warped faces of a 3D mesh", warped.len()),
            bytes,
        )?;
        let mut p = Polyhedra {
            vertices: try_vec(n_vertices, "the vertices")?,
            cell_ptr: try_vec(self.n_cells() + 1, "the cell offsets")?,
            face_ptr: try_vec(sides as usize + 1, "the face offsets")?,
            face_vertices: try_vec(entries as usize, "the face loops")?,
            cell_tags: if self.cell_tags.iter().any(|&t| t != 0) {
                self.cell_tags.clone()
            } else {
                Vec::new()
            },
            ..Polyhedra::default()
        };
        p.vertices.extend_from_slice(&self.vertices);
        p.vertices.par_extend(
            warped
                .par_iter()
                .map(|&f| vertex_average(&self.vertices, self.face_vertices(f as usize))),
        );
        p.cell_ptr.push(0);
        p.face_ptr.push(0);
        let mut l = Vec::new();
        for k in 0..self.n_cells() {
            for &f in self.cell_faces(k) {
                self.outward_loop(f as usize, k, &mut l);
                push_split(
                    &mut p.face_vertices,
                    &mut p.face_ptr,
                    &l,
                    centre[f as usize],
                );
            }
            p.cell_ptr.push((p.face_ptr.len() - 1) as u32);
        }
        self.split_tagged_faces(&centre, &mut p);
        Ok(p)
    }

    /// The loop of face `f` counter-clockwise seen from outside its cell `k`, into `l`.
    fn outward_loop(&self, f: usize, k: usize, l: &mut Vec<u32>) {
        l.clear();
        l.extend_from_slice(self.face_vertices(f));
        if self.face_cells[f][0] as usize != k {
            l.reverse();
        }
    }

    /// The boundary faces with a non-zero tag as tagged faces of `p`, those with a new
    /// vertex in `centre` as their fan triangles, each with the face's tag.
    fn split_tagged_faces(&self, centre: &[u32], p: &mut Polyhedra) {
        for (&f, &tag) in self.boundary_faces.iter().zip(&self.boundary_tags) {
            let f = f as usize;
            if tag == 0 {
                continue;
            }
            if p.tagged_ptr.is_empty() {
                p.tagged_ptr.push(0);
            }
            let before = p.tagged_ptr.len();
            push_split(
                &mut p.tagged_vertices,
                &mut p.tagged_ptr,
                self.face_vertices(f),
                centre[f],
            );
            let added = p.tagged_ptr.len() - before;
            p.tagged_tags.extend(std::iter::repeat_n(tag, added));
        }
    }
}

/// Appends the loop `l` to the flat loops (`verts`, `ptr`) as it is if `centre` is
/// `u32::MAX`, else as its fan triangles (centre, l\[i\], l\[i + 1\]), which turn the same way.
fn push_split(verts: &mut Vec<u32>, ptr: &mut Vec<u32>, l: &[u32], centre: u32) {
    if centre == u32::MAX {
        verts.extend_from_slice(l);
        ptr.push(verts.len() as u32);
        return;
    }
    for i in 0..l.len() {
        verts.extend_from_slice(&[centre, l[i], l[(i + 1) % l.len()]]);
        ptr.push(verts.len() as u32);
    }
}
