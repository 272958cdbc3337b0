//! The faces between two aggregates merged into polygons (step 3 of
//! [`agglomerate3`](super::agglomerate3)), so that a coarse cell has about one face per
//! neighbour and plane rather than one per fine face.
//!
//! ## Maths
//! A face of a [`PolyMesh3`] is one vertex loop, measured on the fan of triangles
//! (c_σ, v_i, v_{i+1}) around its vertex average c_σ ([`crate::mesh3d`]). The fine faces
//! σ_1 … σ_p between aggregates A and B (oriented outward from A, the one of lower index) are
//! grouped by plane: σ_j joins the group of σ_i when n_{σ_j}·n_{σ_i} > 0 and every vertex of
//! σ_j lies within [`PLANE_TOL`] · |σ_j|^{1/2} of the plane of σ_i (through x_{σ_i}, normal
//! n_{σ_i}). In a group, the faces sharing an edge are joined into connected pieces. A piece
//! P of several faces becomes one face when
//! * its boundary is one simple loop: the edges of P's outward loops used once within P
//!   (those used twice are inside P), each vertex starting at most one of them (no pinch), and
//!   following them from any one returns to it after all of them (one boundary component: a
//!   planar connected union bounded by one loop has no hole);
//! * the loop (kept with all its vertices, so that the neighbouring faces, which share its
//!   edges, still match it edge by edge) has at most [`MAX_FACE_VERTICES`] vertices;
//! * every fan triangle T_i = (c, v_i, v_{i+1}), c the mean of the loop's vertices, turns
//!   positively about n: (v_i − c) × (v_{i+1} − c)·n > [`FAN_TOL`] · 2 |P|. The angles of
//!   the T_i about c then add up to 2π times the winding number of the simple loop, which is
//!   1, so the fan covers P exactly once.
//!
//! The merged face σ then has the exact area |σ| = Σ_j |σ_j|, its centroid, and the vector
//! area |σ| n_σ = Σ_j |σ_j| n_{σ_j}; the cell's closed surface, volume and centroid are
//! those of the fine faces (the divergence theorem: the same surface, triangulated
//! differently), so Σ_σ |σ| n_{K,σ} = 0 still holds. d_{A,σ} = (x_σ − x_A)·n is the distance
//! from x_A to the common plane, the one the checks of step 2 bounded below for each σ_j and
//! each of their fan triangles, so the merged cell stays star-shaped with the same margin. A
//! piece that fails is kept as its fine faces.
//!
//! Faces on the boundary of the domain are merged in the same way when the caller gives each
//! a merge key ([`boundary`]): the fine boundary faces of one aggregate with the same key are
//! grouped by plane and connected piece as above. The caller chooses the key (the warm start
//! uses the boundary condition and the tag, so that a merged face joins only faces of one
//! boundary part, and keeps the Signorini faces as they are); [`KEEP`] keeps a face as it is.

use crate::mesh::NO_CELL;
use crate::mesh3d::MAX_FACE_VERTICES;
use crate::mesh3d::PolyMesh3;
use crate::mesh3d::geometry::{cross, dot, sub, vertex_average};

/// Largest distance of a vertex from the plane of a group, relative to |σ|^{1/2} of its face.
pub const PLANE_TOL: f64 = 1e-12;

/// Least (v_i − c) × (v_{i+1} − c)·n of a fan triangle of a merged face, relative to 2 |P|.
pub const FAN_TOL: f64 = 1e-9;

/// The boundary merge key of a fine boundary face kept as it is ([`super::agglomerate3_merging`]).
pub const KEEP: u32 = u32::MAX;

/// The faces of one aggregate A toward the aggregates of higher index: each with its
/// neighbour and the end of its loop (outward from A) in `loops`.
#[derive(Debug, Default)]
pub(super) struct Interfaces {
    pub faces: Vec<(u32, u32)>,
    pub loops: Vec<u32>,
}

impl Interfaces {
    /// The loop of face `j`, outward from the aggregate.
    pub fn face_loop(&self, j: usize) -> &[u32] {
        let start = if j == 0 { 0 } else { self.faces[j - 1].1 };
        &self.loops[start as usize..self.faces[j].1 as usize]
    }

    /// Appends the loop `l` (reversed if `reversed`) as a face toward `b`.
    fn push(&mut self, b: u32, l: &[u32], reversed: bool) {
        if reversed {
            self.loops.extend(l.iter().rev());
        } else {
            self.loops.extend_from_slice(l);
        }
        self.faces.push((b, self.loops.len() as u32));
    }
}

/// The boundary faces of one aggregate ([`boundary`]): the faces, and the index among them of
/// the face of each fine boundary face (fine face, index).
pub(super) type BoundaryFaces = (Interfaces, Vec<(u32, u32)>);

/// Buffers reused from one aggregate to the next.
#[derive(Default)]
pub(super) struct Scratch {
    /// (neighbour, fine face, reversed) of the faces toward aggregates of higher index.
    items: Vec<(u32, u32, bool)>,
    /// The faces (fine face, reversed) toward one neighbour.
    faces: Vec<(u32, bool)>,
    /// The plane group of each face of one neighbour, then sorted (group, index).
    group: Vec<(u32, u32)>,
    /// The faces of one plane group.
    members: Vec<(u32, bool)>,
    /// Directed edges (from, to, face index) of one plane group.
    edges: Vec<(u32, u32, u32)>,
    /// Union-find parents of the faces of one plane group, then the piece of each.
    parent: Vec<u32>,
    /// Per piece (indexed by its root): number of faces, area, its face in the output if
    /// merged ([`KEEP`] if not).
    pieces: Vec<(u32, f64, u32)>,
    /// The face in the output of each face of one plane group (set by `merge_group`).
    out_of: Vec<u32>,
    /// Boundary edges (piece, from, to) of one plane group.
    bnd: Vec<(u32, u32, u32)>,
    /// Boundary edges (from, to) of one piece.
    piece_edges: Vec<(u32, u32)>,
    /// The merged loop of one piece.
    lp: Vec<u32>,
}

/// The faces of aggregate `a` (fine faces on its boundary: `sides`, each with whether its
/// loop is inward) toward the aggregates b > a, merged by plane and piece (module docs).
pub(super) fn interfaces(
    fine: &PolyMesh3,
    label: &[usize],
    a: usize,
    sides: &[(u32, bool)],
    s: &mut Scratch,
) -> Interfaces {
    s.items.clear();
    for &(f, reversed) in sides {
        let [c0, c1] = fine.face_cells(f as usize);
        let other = if reversed { c0 } else { c1 };
        if other != NO_CELL && label[other] > a {
            s.items.push((label[other] as u32, f, reversed));
        }
    }
    s.items.sort_unstable();
    let mut out = Interfaces::default();
    let items = std::mem::take(&mut s.items);
    for run in items.chunk_by(|x, y| x.0 == y.0) {
        merge_run(fine, run, s, &mut out, |_, _| {});
    }
    s.items = items;
    out
}

/// Appends to `out` the faces `run` (fine face, reversed) toward one neighbour or of one
/// boundary key (`run[i].0`), merged by plane and piece ([`merge_group`] on each plane
/// group), calling `each` with every fine face and the index of its face in `out`.
fn merge_run(
    fine: &PolyMesh3,
    run: &[(u32, u32, bool)],
    s: &mut Scratch,
    out: &mut Interfaces,
    mut each: impl FnMut(u32, u32),
) {
    s.faces.clear();
    s.faces.extend(run.iter().map(|&(_, f, r)| (f, r)));
    plane_groups(fine, s);
    let groups = std::mem::take(&mut s.group);
    for g in groups.chunk_by(|x, y| x.0 == y.0) {
        s.members.clear();
        s.members
            .extend(g.iter().map(|&(_, i)| s.faces[i as usize]));
        merge_group(fine, run[0].0, s, out);
        (s.members.iter().zip(&s.out_of)).for_each(|(&(f, _), &j)| each(f, j));
    }
    s.group = groups;
}

/// The faces of aggregate `a` on the boundary of the domain (the fine faces of `sides` without
/// a neighbour), merged by key (`key`, indexed by fine face: [`KEEP`] keeps a face as it is,
/// and so does `None` every face),
/// plane and piece (module docs), and for each fine boundary face the index of its face in
/// the output. The faces kept as they are come in the order of `sides`.
pub(super) fn boundary(
    fine: &PolyMesh3,
    key: Option<&[u32]>,
    sides: &[(u32, bool)],
    s: &mut Scratch,
) -> BoundaryFaces {
    s.items.clear();
    s.items.extend(
        (sides.iter())
            .filter(|&&(f, _)| fine.is_boundary_face(f as usize))
            .map(|&(f, reversed)| (key.map_or(KEEP, |k| k[f as usize]), f, reversed)),
    );
    // stable: the faces of one key stay in the order of `sides`
    s.items.sort_by_key(|x| x.0);
    let mut out = Interfaces::default();
    let mut face_of = Vec::with_capacity(s.items.len());
    let items = std::mem::take(&mut s.items);
    for run in items.chunk_by(|x, y| x.0 == y.0) {
        if run[0].0 == KEEP {
            for &(k, f, reversed) in run {
                face_of.push((f, out.faces.len() as u32));
                out.push(k, fine.face_vertices(f as usize), reversed);
            }
            continue;
        }
        merge_run(fine, run, s, &mut out, |f, j| face_of.push((f, j)));
    }
    s.items = items;
    (out, face_of)
}

/// The outward unit normal of fine face `f` (turned if `reversed`).
fn normal(fine: &PolyMesh3, f: u32, reversed: bool) -> [f64; 3] {
    let n = fine.face_normal(f as usize);
    if reversed { n.map(|x| -x) } else { n }
}

/// Sets `s.group` to (plane group, index) of each of `s.faces`, sorted.
fn plane_groups(fine: &PolyMesh3, s: &mut Scratch) {
    s.group.clear();
    let faces = &s.faces;
    // the first face of each group (its index in `faces`)
    let mut planes: Vec<u32> = Vec::new();
    for (i, &(f, reversed)) in faces.iter().enumerate() {
        let n = normal(fine, f, reversed);
        let tol = PLANE_TOL * fine.face_measure(f as usize).sqrt();
        let on = |&j: &u32| {
            let (g, rg) = faces[j as usize];
            let (n0, x0) = (normal(fine, g, rg), fine.face_centroid(g as usize));
            dot(n, n0) > 0.0
                && (fine.face_vertices(f as usize).iter())
                    .all(|&v| dot(sub(fine.vertices()[v as usize], x0), n0).abs() <= tol)
        };
        let g = planes.iter().position(on).unwrap_or_else(|| {
            planes.push(i as u32);
            planes.len() - 1
        });
        s.group.push((g as u32, i as u32));
    }
    s.group.sort_unstable();
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

/// The edge (u, v) without its direction.
fn undirected(e: &(u32, u32, u32)) -> (u32, u32) {
    (e.0.min(e.1), e.0.max(e.1))
}

/// Sets `s.parent` to the piece (the least index of its faces) of each face of the plane
/// group `s.members` (faces joined through shared edges), and `s.edges` to their outward
/// edges sorted by undirected edge.
fn pieces(fine: &PolyMesh3, s: &mut Scratch) {
    s.edges.clear();
    for (i, &(f, reversed)) in s.members.iter().enumerate() {
        let l = fine.face_vertices(f as usize);
        for j in 0..l.len() {
            let (u, v) = (l[j], l[(j + 1) % l.len()]);
            let (u, v) = if reversed { (v, u) } else { (u, v) };
            s.edges.push((u, v, i as u32));
        }
    }
    s.edges.sort_unstable_by_key(|e| (undirected(e), e.2));
    s.parent.clear();
    s.parent.extend(0..s.members.len() as u32);
    for w in s.edges.windows(2) {
        if undirected(&w[0]) == undirected(&w[1]) {
            let (x, y) = (find(&mut s.parent, w[0].2), find(&mut s.parent, w[1].2));
            s.parent[x.max(y) as usize] = x.min(y);
        }
    }
    for i in 0..s.members.len() as u32 {
        let r = find(&mut s.parent, i);
        s.parent[i as usize] = r;
    }
}

/// Appends to `out` the faces toward `b` of the coplanar fine faces `s.members`: one merged
/// face per connected piece that passes the conditions of the module docs, then the fine
/// faces of the other pieces as they are; sets `s.out_of` to the output face of each member.
fn merge_group(fine: &PolyMesh3, b: u32, s: &mut Scratch, out: &mut Interfaces) {
    s.out_of.clear();
    if let [(f, reversed)] = s.members[..] {
        s.out_of.push(out.faces.len() as u32);
        out.push(b, fine.face_vertices(f as usize), reversed);
        return;
    }
    pieces(fine, s);
    // the boundary edges of the group (used once), each with its piece
    s.bnd.clear();
    let e = &s.edges;
    for j in 0..e.len() {
        let once = (j == 0 || undirected(&e[j - 1]) != undirected(&e[j]))
            && (j + 1 == e.len() || undirected(&e[j + 1]) != undirected(&e[j]));
        if once {
            s.bnd.push((s.parent[e[j].2 as usize], e[j].0, e[j].1));
        }
    }
    s.bnd.sort_unstable();
    s.pieces.clear();
    s.pieces.resize(s.members.len(), (0, 0.0, KEEP));
    for (i, &(f, _)) in s.members.iter().enumerate() {
        let p = &mut s.pieces[s.parent[i] as usize];
        p.0 += 1;
        p.1 += fine.face_measure(f as usize);
    }
    let n = normal(fine, s.members[0].0, s.members[0].1);
    for piece in s.bnd.chunk_by(|x, y| x.0 == y.0) {
        let r = piece[0].0 as usize;
        s.piece_edges.clear();
        s.piece_edges.extend(piece.iter().map(|&(_, u, v)| (u, v)));
        let merged = s.pieces[r].0 > 1
            && boundary_loop(&s.piece_edges, &mut s.lp)
            && fan_covers(fine, &s.lp, n, s.pieces[r].1);
        if merged {
            s.pieces[r].2 = out.faces.len() as u32;
            out.push(b, &s.lp, false);
        }
    }
    for (i, &(f, reversed)) in s.members.iter().enumerate() {
        let merged = s.pieces[s.parent[i] as usize].2;
        if merged == KEEP {
            s.out_of.push(out.faces.len() as u32);
            out.push(b, fine.face_vertices(f as usize), reversed);
        } else {
            s.out_of.push(merged);
        }
    }
}

/// Whether the directed edges `edges` (sorted) form one simple loop, written to `lp`.
fn boundary_loop(edges: &[(u32, u32)], lp: &mut Vec<u32>) -> bool {
    lp.clear();
    if edges.windows(2).any(|w| w[0].0 == w[1].0) || edges.len() > MAX_FACE_VERTICES {
        return false; // a vertex starts two boundary edges: a pinch
    }
    let start = edges[0].0;
    let mut v = start;
    loop {
        lp.push(v);
        match edges.binary_search_by_key(&v, |e| e.0) {
            Ok(j) => v = edges[j].1,
            Err(_) => return false,
        }
        if v == start || lp.len() > edges.len() {
            break;
        }
    }
    v == start && lp.len() == edges.len()
}

/// Whether every fan triangle of the loop `lp` around its vertex average turns positively
/// about `n` by more than [`FAN_TOL`] · 2 `area`.
fn fan_covers(fine: &PolyMesh3, lp: &[u32], n: [f64; 3], area: f64) -> bool {
    let x = fine.vertices();
    let c = vertex_average(x, lp);
    (0..lp.len()).all(|i| {
        let (p, q) = (x[lp[i] as usize], x[lp[(i + 1) % lp.len()] as usize]);
        dot(cross(sub(p, c), sub(q, c)), n) > FAN_TOL * 2.0 * area
    })
}

#[cfg(test)]
mod tests {
    use super::boundary_loop;

    fn sorted(mut e: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
        e.sort_unstable();
        e
    }

    #[test]
    fn one_loop_is_followed_from_its_first_vertex() {
        // the outline of two squares side by side: 0 1 2 / 5 4 3, with 1 and 4 on the loop
        let e = sorted(vec![(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0)]);
        let mut lp = Vec::new();
        assert!(boundary_loop(&e, &mut lp));
        assert_eq!(lp, [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn holes_and_pinches_are_not_one_loop() {
        let mut lp = Vec::new();
        // an outer square 0 1 2 3 and a hole 4 5 6 7 turning the other way
        let hole = sorted(vec![
            (0, 1),
            (1, 2),
            (2, 3),
            (3, 0),
            (4, 7),
            (7, 6),
            (6, 5),
            (5, 4),
        ]);
        assert!(!boundary_loop(&hole, &mut lp));
        // two triangles touching at vertex 0: 0 starts two edges
        let pinch = sorted(vec![(0, 1), (1, 2), (2, 0), (0, 3), (3, 4), (4, 0)]);
        assert!(!boundary_loop(&pinch, &mut lp));
        // an open chain
        assert!(!boundary_loop(&sorted(vec![(0, 1), (1, 2)]), &mut lp));
    }
}
