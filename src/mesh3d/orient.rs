//! Orienting the faces of each polyhedron outward.
//!
//! The loops of a cell's faces come in either orientation. A closed polyhedron uses each edge
//! of its faces exactly twice, and once its faces are oriented consistently, in opposite
//! directions. So every edge shared by faces i and j says whether i and j must be turned the
//! same way (the edge runs in opposite directions in their loops) or opposite ways (the same
//! direction): a union–find with parity over the faces of the cell collects these relations,
//! and fails on a contradiction (a non-orientable surface). All faces must end up in one
//! component (a cell is one closed surface). The orientation found is outward if the signed
//! volume it gives is positive, else every face is turned. O(E log E) per cell of E edge uses.
//!
//! A tetrahedron (four triangles over four vertices) takes a short path with the same result:
//! one determinant and the parity of each loop's permutation (`orient_tetrahedron`; measured
//! in `replication/measurements/mesh3d.md`).

use super::Polyhedra;
use super::geometry::{cell_volume_centroid, cross, dot, sub, vertex_average};
use crate::error::MeshError;
use rayon::prelude::*;

/// Reused buffers of [`orient_cell`].
#[derive(Default)]
pub(crate) struct OrientScratch {
    /// (smaller vertex, larger vertex, local face, runs from smaller to larger).
    edges: Vec<(u32, u32, u32, bool)>,
    /// Union–find parent and parity with respect to the parent.
    parent: Vec<(u32, bool)>,
}

/// The root of local face `i` and the parity of `i` relative to it, compressing the path
/// (recursion depth at most the number of faces of a cell, [`MAX_CELL_FACES`](super::MAX_CELL_FACES)).
fn find(parent: &mut [(u32, bool)], i: u32) -> (u32, bool) {
    let (p, par) = parent[i as usize];
    if p == i {
        return (i, false);
    }
    let (root, rpar) = find(parent, p);
    parent[i as usize] = (root, par ^ rpar);
    (root, par ^ rpar)
}

/// Sets `inward[j]` for the local faces j of cell `k`: whether the loop of its side j must be
/// reversed to run counter-clockwise seen from outside the cell.
pub(crate) fn orient_cell(
    p: &Polyhedra,
    k: usize,
    scratch: &mut OrientScratch,
    inward: &mut [bool],
) -> Result<(), MeshError> {
    match orient_tetrahedron(p, p.cell_sides(k)) {
        Some(flags) => {
            inward.copy_from_slice(&flags);
            Ok(())
        }
        None => orient_by_edges(p, k, scratch, inward),
    }
}

/// [`orient_cell`] for any polyhedron: the union–find with parity of the module docs, then the
/// sign of the volume.
fn orient_by_edges(
    p: &Polyhedra,
    k: usize,
    scratch: &mut OrientScratch,
    inward: &mut [bool],
) -> Result<(), MeshError> {
    let sides = p.cell_sides(k);
    let first = sides.start;
    scratch.edges.clear();
    for (j, s) in sides.clone().enumerate() {
        let l = p.side_vertices(s);
        for i in 0..l.len() {
            let (a, b) = (l[i], l[(i + 1) % l.len()]);
            scratch.edges.push((a.min(b), a.max(b), j as u32, a < b));
        }
    }
    scratch.edges.sort_unstable();
    let n_faces = sides.len() as u32;
    scratch.parent.clear();
    scratch.parent.extend((0..n_faces).map(|i| (i, false)));
    let edges = &scratch.edges;
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        let (a, b) = (edges[i].0 as usize, edges[i].1 as usize);
        let open = |msg: String| MeshError::OpenCell { cell: k, a, b, msg };
        if j - i != 2 {
            return Err(open(format!(
                "is used by {} of its faces instead of 2",
                j - i
            )));
        }
        // the two faces must be turned oppositely iff they run the edge the same way
        let (f, g, want) = (edges[i].2, edges[i + 1].2, edges[i].3 == edges[i + 1].3);
        let (rf, pf) = find(&mut scratch.parent, f);
        let (rg, pg) = find(&mut scratch.parent, g);
        if rf == rg {
            if pf ^ pg != want {
                return Err(open(
                    "runs the same way in two faces however they are turned (the surface is not orientable)"
                        .into(),
                ));
            }
        } else {
            scratch.parent[rf as usize] = (rg, pf ^ pg ^ want);
        }
        i = j;
    }
    for j in 0..n_faces {
        let (root, parity) = find(&mut scratch.parent, j);
        if root != find(&mut scratch.parent, 0).0 {
            return Err(MeshError::BadCell {
                cell: k,
                msg: "its faces form more than one closed surface".into(),
            });
        }
        inward[j as usize] = parity;
    }
    let apex = vertex_average(&p.vertices, p.side_vertices(first));
    let loops = sides
        .clone()
        .map(|s| (p.side_vertices(s), inward[s - first]));
    let (vol, _) = cell_volume_centroid(&p.vertices, apex, loops);
    if !(vol.abs() > 0.0) {
        return Err(MeshError::DegenerateVolume {
            cell: k,
            volume: vol,
        });
    }
    if vol < 0.0 {
        inward.iter_mut().for_each(|b| *b = !*b);
    }
    Ok(())
}

/// The flags of [`orient_cell`] for a tetrahedron, without the edge sort and union–find:
/// `None` unless the cell is four triangles over four distinct vertices, each leaving out a
/// different one (then each edge is used by two faces and the faces form one closed
/// surface), or if its volume is zero (the general path then reports it).
///
/// With (a, b, c) the loop of the first side, d the fourth vertex and
/// D = det(b − a, c − a, d − a), a side whose loop is (x, y, z), leaving out w, has
/// det(y − x, z − x, w − x) = ε D, ε the sign of the permutation (x, y, z, w) of (a, b, c, d).
/// Its loop runs counter-clockwise seen from outside iff w lies behind its plane, that is iff
/// ε D < 0; so it is reversed iff ε D > 0. One determinant orients all four sides, so they are
/// consistent whatever its rounding; D has the sign of the volume the general path computes
/// for every cell whose volume passes the later size check (|K| > 10⁻¹⁴ h_K³).
fn orient_tetrahedron(p: &Polyhedra, sides: std::ops::Range<usize>) -> Option<[bool; 4]> {
    if sides.len() != 4 {
        return None;
    }
    let tri = |s: usize| -> Option<[u32; 3]> {
        let l = p.side_vertices(s);
        (l.len() == 3 && l[0] != l[1] && l[1] != l[2] && l[0] != l[2]).then(|| [l[0], l[1], l[2]])
    };
    let loops = [
        tri(sides.start)?,
        tri(sides.start + 1)?,
        tri(sides.start + 2)?,
        tri(sides.start + 3)?,
    ];
    let [a, b, c] = loops[0];
    let d = loops[1..]
        .iter()
        .flatten()
        .copied()
        .find(|v| ![a, b, c].contains(v))?;
    let order = [a, b, c, d];
    let position = |v: u32| order.iter().position(|&u| u == v);
    // per side, the positions of its loop and of the vertex it leaves out
    let mut left_out = [false; 4];
    let mut perms = [[0usize; 4]; 4];
    for (perm, l) in perms.iter_mut().zip(&loops) {
        let [x, y, z] = [position(l[0])?, position(l[1])?, position(l[2])?];
        let w = 6 - x - y - z;
        if left_out[w] {
            return None;
        }
        left_out[w] = true;
        *perm = [x, y, z, w];
    }
    let [pa, pb, pc, pd] = order.map(|v| p.vertices[v as usize]);
    let det = dot(cross(sub(pb, pa), sub(pc, pa)), sub(pd, pa));
    if !(det != 0.0 && det.is_finite()) {
        return None;
    }
    Some(perms.map(|q| {
        let inversions = (0..4)
            .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
            .filter(|&(i, j)| q[i] > q[j])
            .count();
        let even = inversions % 2 == 0;
        // ε D > 0
        even == (det > 0.0)
    }))
}

/// Cells per parallel task of [`orient_cells`].
const BLOCK: usize = 4096;

/// Per side of `p`, whether its loop must be reversed to be outward ([`orient_cell`] on every
/// cell, in parallel by blocks of [`BLOCK`] consecutive cells, whose sides are consecutive;
/// the error reported is that of the first bad cell).
pub(crate) fn orient_cells(p: &Polyhedra) -> Result<Vec<bool>, MeshError> {
    let mut inward = vec![false; p.face_ptr.len() - 1];
    let n = p.n_cells();
    let mut blocks = Vec::with_capacity(n.div_ceil(BLOCK));
    let mut rest = &mut inward[..];
    for start in (0..n).step_by(BLOCK) {
        let end = (start + BLOCK).min(n);
        let sides = (p.cell_ptr[end] - p.cell_ptr[start]) as usize;
        let (block, tail) = rest.split_at_mut(sides);
        blocks.push((start..end, block));
        rest = tail;
    }
    let err = blocks
        .into_par_iter()
        .map_init(OrientScratch::default, |scratch, (cells, block)| {
            let first = p.cell_ptr[cells.start] as usize;
            cells.into_iter().find_map(|k| {
                let r = p.cell_sides(k);
                orient_cell(p, k, scratch, &mut block[r.start - first..r.end - first]).err()
            })
        })
        .find_map_first(|e| e);
    match err {
        Some(e) => Err(e),
        None => Ok(inward),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tetrahedron of the unit cube's corner at the origin.
    const UNIT: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];

    /// One cell over the vertices `v` with the side loops `sides`.
    fn cell(v: [[f64; 3]; 4], sides: &[&[u32]]) -> Polyhedra {
        let mut p = Polyhedra {
            vertices: v.to_vec(),
            ..Polyhedra::default()
        };
        p.push_cell(sides.iter().copied()).unwrap();
        p
    }

    /// A tetrahedron over the vertices `v`, its four sides listed in the order `order` (each
    /// leaving out vertex `order[j]`), each loop rotated by `rot[j]` and reversed where `rev[j]`.
    fn tetrahedron(
        v: [[f64; 3]; 4],
        order: [usize; 4],
        rot: [usize; 4],
        rev: [bool; 4],
    ) -> Polyhedra {
        let loops: Vec<Vec<u32>> = (0..4)
            .map(|j| {
                let mut l: Vec<u32> = (0..4u32).filter(|&i| i as usize != order[j]).collect();
                l.rotate_left(rot[j]);
                if rev[j] {
                    l.reverse();
                }
                l
            })
            .collect();
        let sides: Vec<&[u32]> = loops.iter().map(|l| l.as_slice()).collect();
        cell(v, &sides)
    }

    /// The 24 orders of four sides.
    fn orders() -> Vec<[usize; 4]> {
        let mut out = Vec::new();
        for a in 0..4 {
            for b in (0..4).filter(|&b| b != a) {
                for c in (0..4).filter(|&c| c != a && c != b) {
                    out.push([a, b, c, 6 - a - b - c]);
                }
            }
        }
        out
    }

    /// Every order of the sides, every rotation and every direction of each loop (24 × 81 ×
    /// 16 listings), on a tetrahedron, its mirror image and a thin sliver far from the origin:
    /// the short path gives the general path's flags.
    #[test]
    fn tetrahedra_are_oriented_as_by_the_edges() {
        let mirror = [UNIT[0], UNIT[2], UNIT[1], UNIT[3]];
        let sliver = [
            [1e3, 1e3, 1e3],
            [1e3 + 1.0, 1e3, 1e3],
            [1e3, 1e3 + 1.0, 1e3],
            [1e3 + 0.5, 1e3 + 0.5, 1e3 + 1e-6],
        ];
        let mut checked = 0;
        for v in [UNIT, mirror, sliver] {
            for order in orders() {
                for code in 0..81 * 16 {
                    let rot = std::array::from_fn(|j| code / 3usize.pow(j as u32) % 3);
                    let rev = std::array::from_fn(|j| (code / 81) >> j & 1 == 1);
                    let p = tetrahedron(v, order, rot, rev);
                    let fast = orient_tetrahedron(&p, p.cell_sides(0)).expect("a tetrahedron");
                    let mut general = [false; 4];
                    orient_by_edges(&p, 0, &mut OrientScratch::default(), &mut general).unwrap();
                    assert_eq!(fast, general, "{v:?} {order:?} {rot:?} {rev:?}");
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 3 * 24 * 81 * 16);
    }

    #[test]
    fn only_tetrahedra_of_nonzero_volume_take_the_short_path() {
        let p = tetrahedron(UNIT, [0, 1, 2, 3], [0; 4], [false; 4]);
        assert!(orient_tetrahedron(&p, p.cell_sides(0)).is_some());
        // flat: the general path reports the zero volume
        let flat = [UNIT[0], UNIT[1], UNIT[2], [1.0, 1.0, 0.0]];
        let p = tetrahedron(flat, [0, 1, 2, 3], [0; 4], [false; 4]);
        assert!(orient_tetrahedron(&p, p.cell_sides(0)).is_none());
        let err = orient_cell(&p, 0, &mut OrientScratch::default(), &mut [false; 4]).unwrap_err();
        assert!(
            matches!(err, MeshError::DegenerateVolume { cell: 0, .. }),
            "{err:?}"
        );
        // a side listed twice (a vertex never left out): the general path refuses the cell
        let twice = tetrahedron(UNIT, [0, 0, 2, 3], [0; 4], [false; 4]);
        assert!(orient_tetrahedron(&twice, twice.cell_sides(0)).is_none());
        assert!(orient_cell(&twice, 0, &mut OrientScratch::default(), &mut [false; 4]).is_err());
        // a quadrilateral side, a repeated vertex
        let quad = cell(UNIT, &[&[0, 1, 2, 3], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]]);
        assert!(orient_tetrahedron(&quad, quad.cell_sides(0)).is_none());
        let repeated = cell(UNIT, &[&[0, 1, 1], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]]);
        assert!(orient_tetrahedron(&repeated, repeated.cell_sides(0)).is_none());
    }
}
