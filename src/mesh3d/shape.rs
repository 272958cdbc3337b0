//! Checks 8 (warp) and 10 (star-shapedness) of [`validate`](super::validate), on the built
//! geometry.

use super::geometry::{cross, dot, face_warp, for_each_fan_triangle, norm, sub};
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
            let test = match self.triangle_star_defect(f as usize, reversed, xk, h) {
                Some(t) => t,
                None => self.face_star_defect(f as usize, reversed, xk, h),
            };
            if let Err((what, value)) = test {
                return Some(MeshError::NotStarShaped3 {
                    cell: k,
                    local_face: i,
                    what,
                    value,
                });
            }
        }
        None
    }

    /// The two tests of [`PolyMesh3::star_defect`] on face `f` (seen from a cell on its
    /// `reversed` side), any polygon: `Err((what, value))` for the first that fails.
    fn face_star_defect(
        &self,
        f: usize,
        reversed: bool,
        xk: Point3,
        h: f64,
    ) -> Result<(), (&'static str, f64)> {
        let (centroid, n) = self.face_frame(f);
        let d = dot(sub(centroid, xk), n) * if reversed { -1.0 } else { 1.0 };
        if !(d > 1e-12 * h) {
            return Err(("d_(K,sigma)", d));
        }
        let mut worst = f64::INFINITY;
        for_each_fan_triangle(&self.vertices, self.face_vertices(f), reversed, |n, x| {
            worst = worst.min(dot(n, sub(x, xk)) / 3.0);
        });
        if !(worst > 1e-14 * h * h * h) {
            return Err(("the volume of (x_K, T) for a fan triangle T", worst));
        }
        Ok(())
    }

    /// [`PolyMesh3::face_star_defect`] if face `f` is a triangle (`None` otherwise). A
    /// triangle is its own fan, so its frame and its one fan triangle share a cross product;
    /// the values are those of the general path, bit for bit (its frame's centroid (|N| x_T)/|N| and unit normal
    /// N/|N|, the reversed triangle's vector area −N and centroid (a + c + b)/3).
    fn triangle_star_defect(
        &self,
        f: usize,
        reversed: bool,
        xk: Point3,
        h: f64,
    ) -> Option<Result<(), (&'static str, f64)>> {
        let &[ia, ib, ic] = self.face_vertices(f) else {
            return None;
        };
        let [a, b, c] = [ia, ib, ic].map(|v| self.vertices[v as usize]);
        let nt = cross(sub(b, a), sub(c, a)).map(|x| 0.5 * x);
        let area = norm(nt);
        let x = [0, 1, 2].map(|r| (a[r] + b[r] + c[r]) / 3.0);
        let centroid = x.map(|v| (area * v) / area);
        let n = nt.map(|v| v / area);
        let d = dot(sub(centroid, xk), n) * if reversed { -1.0 } else { 1.0 };
        if !(d > 1e-12 * h) {
            return Some(Err(("d_(K,sigma)", d)));
        }
        let (nt, x) = if reversed {
            (
                nt.map(|v| -v),
                [0, 1, 2].map(|r| (a[r] + c[r] + b[r]) / 3.0),
            )
        } else {
            (nt, x)
        };
        let worst = dot(nt, sub(x, xk)) / 3.0;
        if !(worst > 1e-14 * h * h * h) {
            return Some(Err(("the volume of (x_K, T) for a fan triangle T", worst)));
        }
        Some(Ok(()))
    }
}

#[cfg(test)]
mod tests {
    use crate::budget::MemoryBudget;
    use crate::mesh3d::generate::kuhn;
    use crate::mesh3d::{Cuboid, PolyMesh3};

    #[test]
    fn the_triangle_star_test_is_the_general_one_bit_for_bit() {
        let b = Cuboid {
            x: [-0.5, 1.5],
            y: [0.0, 1.0],
            z: [0.25, 2.0],
        };
        let budget = MemoryBudget::DEFAULT;
        let m = PolyMesh3::from_polyhedra(kuhn(3, b, budget).unwrap(), budget).unwrap();
        let (mut passes, mut fails) = (0, 0);
        for k in 0..m.n_cells() {
            let xk = m.centroid(k);
            for &f in m.cell_faces(k) {
                let f = f as usize;
                let reversed = m.face_cells[f][0] as usize != k;
                // the centroid passes; points pushed out through the face fail either test
                let (c, n) = m.face_frame(f);
                let out = if reversed { -1.0 } else { 1.0 };
                for (x, h) in [
                    (xk, 1.0),
                    (c, 1.0),
                    ([0, 1, 2].map(|r| c[r] + 0.1 * out * n[r]), 1.0),
                    (xk, 1e6),
                ] {
                    let fast = m.triangle_star_defect(f, reversed, x, h).unwrap();
                    let general = m.face_star_defect(f, reversed, x, h);
                    match (fast, general) {
                        (Ok(()), Ok(())) => passes += 1,
                        (Err((w1, v1)), Err((w2, v2))) => {
                            assert_eq!(w1, w2);
                            assert_eq!(v1.to_bits(), v2.to_bits(), "{v1} {v2}");
                            fails += 1;
                        }
                        (a, b) => panic!("cell {k}, face {f}: {a:?} against {b:?}"),
                    }
                }
            }
        }
        assert!(passes > 0 && fails > 0, "{passes} {fails}");
    }
}
