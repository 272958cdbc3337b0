//! Checks 8 (warp) and 10 (star-shapedness) of [`validate`](super::validate), on the built
//! geometry.

use super::geometry::{dot, face_warp, for_each_fan_triangle, sub};
use super::validate::WARP_TOL;
use super::{Point3, PolyMesh3};
use crate::error::MeshError;
use rayon::prelude::*;

impl PolyMesh3 {
    /// The warp of face `f`: max over its vertices v of |(v − x_σ)·n_σ| / diam(σ), 0 for a
    /// planar face (see [`validate`](super::validate), "Warped faces").
    pub fn face_warp(&self, f: usize) -> f64 {
        let (centroid, normal) = self.face_frame(f);
        face_warp(&self.vertices, self.face_vertices(f), centroid, normal)
    }

    /// [`MeshError::WarpedFace`] for the first face warped beyond [`WARP_TOL`], then
    /// [`MeshError::NotStarShaped3`] for the first cell not strictly star-shaped with respect to
    /// x_K: d_{K,σ} ≤ 10⁻¹² h_K, or a fan triangle T of σ with (x_K, T) of volume ≤ 10⁻¹⁴ h_K³.
    /// `star[k]` says whether cell k passed [`PolyMesh3::star_defect`], evaluated with the cell
    /// geometry (the same pass over the cell's faces); the first failing cell's defect is
    /// computed again here for the error. Triangles are planar, so only faces of four or more
    /// vertices are checked for warp.
    pub(crate) fn check_shapes(&self, diameters: &[f64], star: &[bool]) -> Result<(), MeshError> {
        let warped = (0..self.n_faces())
            .into_par_iter()
            .find_first(|&f| self.face_vertices(f).len() > 3 && !(self.face_warp(f) <= WARP_TOL));
        if let Some(f) = warped {
            return Err(MeshError::WarpedFace {
                face: f,
                cell: self.face_cells[f][0] as usize,
                vertices: self.face_vertices(f).iter().map(|&v| v as usize).collect(),
                warp: self.face_warp(f),
                tol: WARP_TOL,
            });
        }
        let bad = star.par_iter().position_first(|&ok| !ok);
        match bad.and_then(|k| self.star_defect(k, self.cell_centroid[k], diameters[k])) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The first defect of star-shapedness of cell `k` with respect to the point `xk` (its
    /// centroid), `h` its diameter (see [`PolyMesh3::check_shapes`]).
    pub(crate) fn star_defect(&self, k: usize, xk: Point3, h: f64) -> Option<MeshError> {
        for (i, &f) in self.cell_faces(k).iter().enumerate() {
            let reversed = self.face_cells[f as usize][0] as usize != k;
            let (centroid, n) = self.face_frame(f as usize);
            let d = dot(sub(centroid, xk), n) * if reversed { -1.0 } else { 1.0 };
            let defect = |what, value| MeshError::NotStarShaped3 {
                cell: k,
                local_face: i,
                what,
                value,
            };
            if !(d > 1e-12 * h) {
                return Some(defect("d_(K,sigma)", d));
            }
            let mut worst = f64::INFINITY;
            for_each_fan_triangle(
                &self.vertices,
                self.face_vertices(f as usize),
                reversed,
                |n, x| {
                    worst = worst.min(dot(n, sub(x, xk)) / 3.0);
                },
            );
            if !(worst > 1e-14 * h * h * h) {
                return Some(defect("the volume of (x_K, T) for a fan triangle T", worst));
            }
        }
        None
    }
}
