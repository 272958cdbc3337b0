//! The geometry of polygonal faces and polyhedral cells, planar or warped.
//!
//! ## Faces
//! A face σ with vertex loop v_0 … v_{m−1} is cut into triangles: itself if m = 3, else the
//! fan T_i = (c_σ, v_i, v_{i+1}) around its vertex average c_σ = (1/m) Σ_i v_i (HArDCore3D's
//! `simplexify`). With N_T = ½ (b − a) × (c − a) the vector area of a triangle T = (a, b, c)
//! and x_T = (a + b + c)/3 its centroid,
//!
//! * |σ| = Σ_T |N_T| (the area of the fan),
//! * x_σ = Σ_T |N_T| x_T / |σ| (its centroid),
//! * n_σ = N_σ / |N_σ| with N_σ = Σ_T N_T = ½ Σ_i v_i × v_{i+1} (the vector area of the loop,
//!   independent of the fan centre), oriented by the loop.
//!
//! For a planar face the fan covers the polygon exactly (when the polygon is star-shaped with
//! respect to c_σ, which the checks of `validate.rs` make sure of), so these are its exact
//! area, centroid and unit normal, and |σ| n_σ = N_σ. For a warped face they are HArDCore's
//! area and centroid; HArDCore takes for n_σ the cross product of the most perpendicular pair
//! of directions from x_σ to the vertices, we take the direction of N_σ, which agrees with it
//! on planar faces and does not depend on a choice of vertices.
//!
//! ## Cells
//! A cell K is the union of the tetrahedra (p, T) over the fan triangles T of its faces, each
//! oriented outward, with apex p the average of the distinct vertices of K (HArDCore3D's
//! `point_in_cell`). With V_T = (1/3) N_T·(x_T − p) the signed volume of (p, T),
//!
//! * |K| = Σ_T V_T,
//! * x_K = p + Σ_T V_T · ¾ (x_T − p) / |K| (the tetrahedron (p, T) has centroid
//!   p + ¾ (x_T − p)).
//!
//! HArDCore sums unsigned volumes; we sum signed ones, which gives the same numbers when every
//! tetrahedron is positively oriented and is otherwise still the exact volume and centroid of
//! the polyhedron bounded by the fan triangles (the divergence theorem: the signed sum does
//! not depend on p). Two cells sharing a face use the same fan (the face's stored loop), so
//! their volumes add up exactly to the volume the boundary fans enclose.
//!
//! h_K is the largest distance between two vertices of K; d_{K,σ} = (x_σ − x_K)·n_{K,σ}.

use super::Point3;

pub(crate) fn sub(a: Point3, b: Point3) -> Point3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: Point3, b: Point3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: Point3, b: Point3) -> Point3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: Point3) -> f64 {
    dot(a, a).sqrt()
}

pub(crate) fn dist(a: Point3, b: Point3) -> f64 {
    norm(sub(a, b))
}

/// The vertex average of the points `loop_[i]` of `vertices`.
pub(crate) fn vertex_average(vertices: &[Point3], ids: &[u32]) -> Point3 {
    let mut c = [0.0; 3];
    for &v in ids {
        let p = vertices[v as usize];
        (0..3).for_each(|r| c[r] += p[r]);
    }
    let m = ids.len() as f64;
    c.map(|x| x / m)
}

/// Calls `f(a, b, c)` on the corners of each fan triangle of the face with vertex loop `ids`
/// (see the module docs), in loop order, or reversed (each triangle turned) if `reversed`.
pub(crate) fn for_each_fan_corners(
    vertices: &[Point3],
    ids: &[u32],
    reversed: bool,
    mut f: impl FnMut(Point3, Point3, Point3),
) {
    let m = ids.len();
    let p = |i: usize| vertices[ids[i] as usize];
    let mut tri = |a: Point3, b: Point3, c: Point3| {
        if reversed { f(a, c, b) } else { f(a, b, c) }
    };
    if m == 3 {
        tri(p(0), p(1), p(2));
        return;
    }
    let c = vertex_average(vertices, ids);
    for i in 0..m {
        tri(c, p(i), p((i + 1) % m));
    }
}

/// Calls `f(N_T, x_T)` on each fan triangle of the face with vertex loop `ids` (see the module
/// docs), in loop order, or reversed (N_T negated) if `reversed`.
pub(crate) fn for_each_fan_triangle(
    vertices: &[Point3],
    ids: &[u32],
    reversed: bool,
    mut f: impl FnMut(Point3, Point3),
) {
    for_each_fan_corners(vertices, ids, reversed, |a, b, c| {
        let n = cross(sub(b, a), sub(c, a)).map(|x| 0.5 * x);
        let x = [0, 1, 2].map(|r| (a[r] + b[r] + c[r]) / 3.0);
        f(n, x);
    });
}

/// The signed volume of the tetrahedron (p, a, b, c), positive if (a, b, c) turns
/// counter-clockwise seen from outside, that is, from the side away from p.
pub(crate) fn tet_volume(p: Point3, a: Point3, b: Point3, c: Point3) -> f64 {
    dot(sub(a, p), cross(sub(b, p), sub(c, p))) / 6.0
}

/// The geometry of a face: |σ|, x_σ, and its vector area N_σ (see the module docs).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FaceGeometry {
    pub area: f64,
    pub centroid: Point3,
    pub vector_area: Point3,
}

/// |σ|, x_σ and N_σ of the face with vertex loop `ids`.
pub(crate) fn face_geometry(vertices: &[Point3], ids: &[u32]) -> FaceGeometry {
    let (mut area, mut moment, mut vector_area) = (0.0, [0.0; 3], [0.0; 3]);
    for_each_fan_triangle(vertices, ids, false, |n, x| {
        let a = norm(n);
        area += a;
        (0..3).for_each(|r| {
            moment[r] += a * x[r];
            vector_area[r] += n[r];
        });
    });
    FaceGeometry {
        area,
        centroid: moment.map(|m| m / area),
        vector_area,
    }
}

/// max over the vertices v of the face of |(v − x_σ)·n_σ| / diam(σ): how far the face is
/// from its plane, relative to its size (0 for a planar face).
pub(crate) fn face_warp(vertices: &[Point3], ids: &[u32], centroid: Point3, normal: Point3) -> f64 {
    let p = |v: &u32| vertices[*v as usize];
    let off = ids
        .iter()
        .map(|v| dot(sub(p(v), centroid), normal).abs())
        .fold(0.0, f64::max);
    let diam = ids
        .iter()
        .flat_map(|a| ids.iter().map(move |b| (a, b)))
        .map(|(a, b)| dist(p(a), p(b)))
        .fold(0.0, f64::max);
    off / diam
}

/// (|K|, x_K) of a cell from its sides: `sides` yields, for every face of the cell, its vertex
/// loop and whether that loop is inward (to be reversed); `apex` is p of the module docs.
pub(crate) fn cell_volume_centroid<'a>(
    vertices: &[Point3],
    apex: Point3,
    sides: impl Iterator<Item = (&'a [u32], bool)>,
) -> (f64, Point3) {
    let (mut vol, mut moment) = (0.0, [0.0; 3]);
    for (ids, reversed) in sides {
        for_each_fan_triangle(vertices, ids, reversed, |n, x| {
            let d = sub(x, apex);
            let v = dot(n, d) / 3.0;
            vol += v;
            (0..3).for_each(|r| moment[r] += v * 0.75 * d[r]);
        });
    }
    (vol, [0, 1, 2].map(|r| apex[r] + moment[r] / vol))
}

/// The largest distance between two of the points `ids` of `vertices`.
pub(crate) fn diameter(vertices: &[Point3], ids: &[u32]) -> f64 {
    let mut d: f64 = 0.0;
    for (i, &a) in ids.iter().enumerate() {
        for &b in &ids[i + 1..] {
            d = d.max(dist(vertices[a as usize], vertices[b as usize]));
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_planar_pentagon_has_its_exact_area_and_centroid() {
        // the unit square with a roof point: area 1.25, centroid by decomposition
        let v = [
            [0.0, 0.0, 2.0],
            [1.0, 0.0, 2.0],
            [1.0, 1.0, 2.0],
            [0.5, 1.5, 2.0],
            [0.0, 1.0, 2.0],
        ];
        let g = face_geometry(&v, &[0, 1, 2, 3, 4]);
        assert!((g.area - 1.25).abs() < 1e-15);
        let cy = (1.0 * 0.5 + 0.25 * (1.0 + 0.5 / 3.0)) / 1.25;
        let want = [0.5, cy, 2.0];
        assert!((0..3).all(|r| (g.centroid[r] - want[r]).abs() < 1e-15));
        assert!(dist(g.vector_area, [0.0, 0.0, 1.25]) < 1e-15);
        assert_eq!(
            face_warp(&v, &[0, 1, 2, 3, 4], g.centroid, [0.0, 0.0, 1.0]),
            0.0
        );
    }

    #[test]
    fn a_warped_quadrilateral_is_measured_on_its_fan() {
        // the diagonal vertex lifted by t: four triangles around the vertex average
        let t = 0.2;
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, t],
            [0.0, 1.0, 0.0],
        ];
        let g = face_geometry(&v, &[0, 1, 2, 3]);
        let c = [0.5, 0.5, t / 4.0];
        let mut area = 0.0;
        for i in 0..4 {
            let (a, b) = (v[i], v[(i + 1) % 4]);
            area += 0.5 * norm(cross(sub(a, c), sub(b, c)));
        }
        assert!((g.area - area).abs() < 1e-15 && g.area > 1.0);
        let n = g.vector_area;
        assert!(n[2] > 0.0 && (n[0] + t / 2.0).abs() < 1e-15 && (n[1] + t / 2.0).abs() < 1e-15);
        let unit = n.map(|x| x / norm(n));
        assert!(face_warp(&v, &[0, 1, 2, 3], g.centroid, unit) > 0.01);
    }
}
