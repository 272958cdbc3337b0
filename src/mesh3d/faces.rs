//! Matching the face sides of a [`Polyhedra`] into faces: two sides are the same face when
//! they have the same vertex set.
//!
//! Every side's vertex loop is copied and sorted (its key); the sides are sorted by key (in
//! parallel, ties broken by side index), so that the sides of one face are consecutive. A key
//! met once is a boundary face, twice an interior face (its two sides must belong to different
//! cells), more often an error. Faces are numbered in the order of their first side, so that
//! the faces of a cell are close in memory. O(S log S) for S sides, plus O(m log m) per side
//! of m vertices.

use super::Polyhedra;
use crate::error::MeshError;
use rayon::prelude::*;

/// No partner side: a boundary face.
pub(crate) const NO_SIDE: u32 = u32::MAX;

/// The sides of each face.
pub(crate) struct FaceMatch {
    /// Per side, the face it is a side of.
    pub face_of_side: Vec<u32>,
    /// Per face, its first side and its second side ([`NO_SIDE`] on the boundary).
    pub face_sides: Vec<[u32; 2]>,
}

/// Per side, the cell it belongs to.
pub(crate) fn side_cells(p: &Polyhedra) -> Vec<u32> {
    let mut out = Vec::with_capacity(p.face_ptr.len().saturating_sub(1));
    for k in 0..p.n_cells() {
        out.extend(p.cell_sides(k).map(|_| k as u32));
    }
    out
}

/// Matches the sides of `p` into faces (`side_cell`: [`side_cells`]).
pub(crate) fn match_faces(p: &Polyhedra, side_cell: &[u32]) -> Result<FaceMatch, MeshError> {
    let n_sides = side_cell.len();
    let mut keys = p.face_vertices.clone();
    for s in 0..n_sides {
        keys[p.face_ptr[s] as usize..p.face_ptr[s + 1] as usize].sort_unstable();
    }
    let key = |s: u32| &keys[p.face_ptr[s as usize] as usize..p.face_ptr[s as usize + 1] as usize];
    let mut order: Vec<u32> = (0..n_sides as u32).collect();
    order.par_sort_unstable_by(|&a, &b| key(a).cmp(key(b)).then(a.cmp(&b)));
    let mut partner = vec![NO_SIDE; n_sides];
    let mut i = 0;
    while i < n_sides {
        let mut j = i + 1;
        while j < n_sides && key(order[j]) == key(order[i]) {
            j += 1;
        }
        let group = &order[i..j];
        let cell = |g: usize| side_cell[group[g] as usize] as usize;
        match group.len() {
            1 => {}
            2 if cell(0) == cell(1) => {
                return Err(MeshError::BadCell {
                    cell: cell(0),
                    msg: format!("it lists the face with vertices {:?} twice", key(group[0])),
                });
            }
            2 => {
                partner[group[0] as usize] = group[1];
                partner[group[1] as usize] = group[0];
            }
            _ => {
                return Err(MeshError::OvercrowdedFace {
                    vertices: key(group[0]).iter().map(|&v| v as usize).collect(),
                    cells: [cell(0), cell(1), cell(2)],
                });
            }
        }
        i = j;
    }
    drop(keys);
    let mut face_of_side = vec![0u32; n_sides];
    let mut face_sides = Vec::with_capacity(n_sides / 2 + 1);
    for s in 0..n_sides {
        let q = partner[s];
        if q == NO_SIDE || q as usize > s {
            face_of_side[s] = face_sides.len() as u32;
            face_sides.push([s as u32, q]);
        } else {
            face_of_side[s] = face_of_side[q as usize];
        }
    }
    Ok(FaceMatch {
        face_of_side,
        face_sides,
    })
}

/// How loop `b` runs compared with loop `a` over the same vertex set: `Some(true)` in the same
/// cyclic order, `Some(false)` in the reverse order, `None` in neither (a different polygon).
pub(crate) fn same_direction(a: &[u32], b: &[u32]) -> Option<bool> {
    let m = a.len();
    let p = b.iter().position(|&v| v == a[0])?;
    let fwd = (0..m).all(|i| b[(p + i) % m] == a[i]);
    let bwd = (0..m).all(|i| b[(p + m - i) % m] == a[i]);
    match (fwd, bwd) {
        (true, _) => Some(true),
        (false, true) => Some(false),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loops_are_compared_up_to_rotation() {
        assert_eq!(same_direction(&[1, 2, 3, 4], &[3, 4, 1, 2]), Some(true));
        assert_eq!(same_direction(&[1, 2, 3, 4], &[2, 1, 4, 3]), Some(false));
        assert_eq!(same_direction(&[1, 2, 3, 4], &[1, 3, 2, 4]), None);
        assert_eq!(same_direction(&[1, 2, 3], &[1, 3, 2]), Some(false));
    }
}
