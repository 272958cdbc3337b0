//! Step 2 of [`agglomerate3`](super::agglomerate3): whether an aggregate of fine cells is an
//! admissible coarse cell as it is (the conditions and their maths are in the module docs of
//! [`super`]).

use super::{MAX_CELL_FACES, MIN_DIST_RATIO};
use crate::mesh::NO_CELL;
use crate::mesh3d::PolyMesh3;
use crate::mesh3d::geometry::{cross, dist, dot, for_each_fan_corners, norm, sub};

/// Buffers reused from one aggregate to the next (one per rayon task).
#[derive(Default)]
pub(super) struct Scratch {
    /// The aggregate's boundary faces and whether each is reversed (its loop inward).
    sides: Vec<(u32, bool)>,
    /// The directed edges of the outward loops.
    edges: Vec<(u32, u32)>,
}

/// The faces of cell `k` on the boundary of aggregate `a`, each with whether its stored loop
/// must be reversed to be outward from `k`.
pub(super) fn boundary_sides<'a>(
    fine: &'a PolyMesh3,
    label: &'a [usize],
    a: usize,
    k: usize,
) -> impl Iterator<Item = (u32, bool)> + 'a {
    fine.cell_faces(k).iter().filter_map(move |&f| {
        let [c0, c1] = fine.face_cells(f as usize);
        let other = if c0 == k { c1 } else { c0 };
        (other == NO_CELL || label[other] != a).then_some((f, c0 != k))
    })
}

/// Whether the aggregate `a` of the fine cells `members` (labels `label`) passes the checks of
/// step 2.
pub(super) fn admissible(
    fine: &PolyMesh3,
    label: &[usize],
    a: usize,
    members: &[u32],
    s: &mut Scratch,
) -> bool {
    s.sides.clear();
    for &k in members {
        s.sides.extend(boundary_sides(fine, label, a, k as usize));
    }
    if s.sides.len() > MAX_CELL_FACES || !closed(fine, &s.sides, &mut s.edges) {
        return false;
    }
    let (mut volume, mut moment) = (0.0, [0.0; 3]);
    for &k in members {
        let (v, c) = (fine.measure(k as usize), fine.centroid(k as usize));
        volume += v;
        (0..3).for_each(|r| moment[r] += v * c[r]);
    }
    let x = moment.map(|m| m / volume);
    star_shaped(fine, &s.sides, x)
}

/// Whether every edge of the outward loops of `sides` is traversed exactly once in each
/// direction.
fn closed(fine: &PolyMesh3, sides: &[(u32, bool)], edges: &mut Vec<(u32, u32)>) -> bool {
    edges.clear();
    for &(f, reversed) in sides {
        let l = fine.face_vertices(f as usize);
        for i in 0..l.len() {
            let (u, v) = (l[i], l[(i + 1) % l.len()]);
            edges.push(if reversed { (v, u) } else { (u, v) });
        }
    }
    edges.sort_unstable();
    edges.windows(2).all(|w| w[0] != w[1])
        && edges
            .iter()
            .all(|&(u, v)| edges.binary_search(&(v, u)).is_ok())
}

/// Whether the closed surface of the outward `sides` is star-shaped with respect to `x` with
/// margin [`MIN_DIST_RATIO`], and its fan triangles add up to the full solid angle 4π.
fn star_shaped(fine: &PolyMesh3, sides: &[(u32, bool)], x: [f64; 3]) -> bool {
    let vertices = fine.vertices();
    let r = sides
        .iter()
        .flat_map(|&(f, _)| fine.face_vertices(f as usize))
        .map(|&v| dist(vertices[v as usize], x))
        .fold(0.0, f64::max);
    let margin = MIN_DIST_RATIO * r;
    let mut ok = true;
    let mut solid_angle = 0.0;
    for &(f, reversed) in sides {
        let n = fine.face_normal(f as usize);
        let d = dot(sub(fine.face_centroid(f as usize), x), n);
        if !((if reversed { -d } else { d }) >= margin) {
            return false;
        }
        for_each_fan_corners(
            vertices,
            fine.face_vertices(f as usize),
            reversed,
            |p, q, t| {
                let (a, b, c) = (sub(p, x), sub(q, x), sub(t, x));
                let det = dot(a, cross(b, c));
                // the distance from x to the plane of the triangle: 6 vol / (2 area)
                let twice_area = norm(cross(sub(q, p), sub(t, p)));
                ok &= det >= margin * twice_area;
                let (la, lb, lc) = (norm(a), norm(b), norm(c));
                let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
                solid_angle += 2.0 * det.atan2(den);
            },
        );
        if !ok {
            return false;
        }
    }
    (solid_angle - 4.0 * std::f64::consts::PI).abs() < 1e-6
}
