//! Matching the face sides of a [`Polyhedra`] into faces: two sides are the same face when
//! they have the same vertex set.
//!
//! The key of a side is its vertex loop sorted. The sides are first put in buckets by their
//! smallest vertex (a counting sort, O(S + V) for S sides and V vertices); within a bucket
//! (a few dozen sides in a tetrahedral mesh), in parallel over the buckets, the sides are
//! sorted by key, ties broken by side index, so that the sides of one face are consecutive.
//! Taking the buckets in vertex order, the keys come out in lexicographic order, the order of
//! a global sort. Keys are compared first by a `u128` packing their first four entries (each
//! plus one, padded with zeros, so that a shorter key sorts first as in a slice comparison),
//! which decides between faces of at most four vertices, then, on a tie, as slices. A key met
//! once is a boundary face, twice an interior face (its two sides must belong to different
//! cells), more often an error; the error reported is that of the smallest key. Faces are
//! numbered in the order of their first side, so that the faces of a cell are close in memory.
//! O(S + V) plus O(m log m) per bucket of m sides; scratch reused per thread, nothing
//! allocated per side.

use super::Polyhedra;
use crate::budget::{try_filled, try_vec};
use crate::error::MeshError;
use crate::mesh::buckets::counting_sort;
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
pub(crate) fn side_cells(p: &Polyhedra) -> Result<Vec<u32>, MeshError> {
    let mut out = try_vec(
        p.face_ptr.len().saturating_sub(1),
        "the cells of the face sides",
    )?;
    for k in 0..p.n_cells() {
        out.extend(p.cell_sides(k).map(|_| k as u32));
    }
    Ok(out)
}

/// Reused buffers of [`match_bucket`].
#[derive(Default)]
struct BucketScratch {
    /// The sorted loops of the bucket's sides, concatenated.
    keys: Vec<u32>,
    /// Per side of the bucket: packed key prefix, side, start of its key in `keys`, length.
    entries: Vec<(u128, u32, u32, u32)>,
}

/// The first four entries of the sorted key `key`, each plus one, packed big-end first and
/// padded with zeros: comparing packings compares the keys as slices, up to a tie between keys
/// longer than four that agree on their first four entries.
fn packed_prefix(key: &[u32]) -> u128 {
    (0..4).fold(0u128, |acc, i| {
        (acc << 32) | key.get(i).map_or(0, |&v| u128::from(v) + 1)
    })
}

/// Sorts the sides of one bucket by key and side, and flags the first side of every interior
/// face (`pair_start[i]`: sides `bucket[i]` and `bucket[i + 1]` form a face).
fn match_bucket(
    p: &Polyhedra,
    side_cell: &[u32],
    bucket: &mut [u32],
    pair_start: &mut [bool],
    scratch: &mut BucketScratch,
) -> Result<(), MeshError> {
    let BucketScratch { keys, entries } = scratch;
    keys.clear();
    entries.clear();
    for &s in bucket.iter() {
        let start = keys.len();
        keys.extend_from_slice(p.side_vertices(s as usize));
        keys[start..].sort_unstable();
        let len = keys.len() - start;
        entries.push((packed_prefix(&keys[start..]), s, start as u32, len as u32));
    }
    let key = |e: &(u128, u32, u32, u32)| &keys[e.2 as usize..(e.2 + e.3) as usize];
    entries.sort_unstable_by(|a, b| {
        (a.0.cmp(&b.0))
            .then_with(|| key(a).cmp(key(b)))
            .then(a.1.cmp(&b.1))
    });
    let mut i = 0;
    while i < entries.len() {
        let mut j = i + 1;
        while j < entries.len()
            && entries[j].0 == entries[i].0
            && key(&entries[j]) == key(&entries[i])
        {
            j += 1;
        }
        let cell = |g: usize| side_cell[entries[i + g].1 as usize] as usize;
        match j - i {
            1 => {}
            2 if cell(0) == cell(1) => {
                return Err(MeshError::BadCell {
                    cell: cell(0),
                    msg: format!(
                        "it lists the face with vertices {:?} twice",
                        key(&entries[i])
                    ),
                });
            }
            2 => pair_start[i] = true,
            _ => {
                return Err(MeshError::OvercrowdedFace {
                    vertices: key(&entries[i]).iter().map(|&v| v as usize).collect(),
                    cells: [cell(0), cell(1), cell(2)],
                });
            }
        }
        i = j;
    }
    for (b, e) in bucket.iter_mut().zip(entries.iter()) {
        *b = e.1;
    }
    Ok(())
}

/// `data` cut into consecutive mutable pieces at the offsets `ptr`.
fn split_at_offsets<'a, T>(mut data: &'a mut [T], ptr: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(ptr.len().saturating_sub(1));
    for w in ptr.windows(2) {
        let (head, tail) = data.split_at_mut(w[1] - w[0]);
        out.push(head);
        data = tail;
    }
    out
}

/// Per side, its partner side ([`NO_SIDE`] on the boundary), or the error of the smallest bad
/// key (see the module docs).
fn partners(p: &Polyhedra, side_cell: &[u32]) -> Result<Vec<u32>, MeshError> {
    let n_sides = side_cell.len();
    let smallest = |s: usize| p.side_vertices(s).iter().min().map(|&v| v as usize);
    let (ptr, mut order) =
        counting_sort(p.vertices.len(), (0..n_sides).map(smallest), |s| s as u32);
    let mut pair_start = try_filled(n_sides, false, "the pairs of face sides")?;
    let err = split_at_offsets(&mut order, &ptr)
        .into_par_iter()
        .zip(split_at_offsets(&mut pair_start, &ptr))
        .map_init(BucketScratch::default, |scratch, (bucket, pairs)| {
            match_bucket(p, side_cell, bucket, pairs, scratch)
        })
        .find_map_first(|r| r.err());
    if let Some(e) = err {
        return Err(e);
    }
    let mut partner = try_filled(n_sides, NO_SIDE, "the partners of the face sides")?;
    for i in (0..n_sides).filter(|&i| pair_start[i]) {
        let (a, b) = (order[i], order[i + 1]);
        partner[a as usize] = b;
        partner[b as usize] = a;
    }
    Ok(partner)
}

/// Matches the sides of `p` into faces (`side_cell`: [`side_cells`]).
pub(crate) fn match_faces(p: &Polyhedra, side_cell: &[u32]) -> Result<FaceMatch, MeshError> {
    let n_sides = side_cell.len();
    let partner = partners(p, side_cell)?;
    let mut face_of_side = try_filled(n_sides, 0u32, "the faces of the face sides")?;
    let mut face_sides = try_vec(n_sides / 2 + 1, "the sides of the faces")?;
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
