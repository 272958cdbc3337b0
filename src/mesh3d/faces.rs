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
use crate::mesh::buckets::try_par_counting_sort;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// No partner side: a boundary face.
pub(crate) const NO_SIDE: u32 = u32::MAX;

/// The sides of each face.
pub(crate) struct FaceMatch {
    /// Per side, the face it is a side of.
    pub face_of_side: Vec<u32>,
    /// Per face, its first side and its second side ([`NO_SIDE`] on the boundary).
    pub face_sides: Vec<[u32; 2]>,
}

/// Per side, the cell it belongs to (in parallel over chunks of sides; `p.cell_ptr` is well
/// formed, check 1).
pub(crate) fn side_cells(p: &Polyhedra) -> Result<Vec<u32>, MeshError> {
    let n_sides = p.face_ptr.len().saturating_sub(1);
    let mut out = try_filled(n_sides, 0u32, "the cells of the face sides")?;
    out.par_chunks_mut(SIDE_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let s0 = c * SIDE_CHUNK;
            // the cell of side s0: the last k with cell_ptr[k] ≤ s0 (empty cells skipped below)
            let mut k = p.cell_ptr.partition_point(|&x| x as usize <= s0) - 1;
            for (i, o) in chunk.iter_mut().enumerate() {
                while p.cell_ptr[k + 1] as usize <= s0 + i {
                    k += 1;
                }
                *o = k as u32;
            }
        });
    Ok(out)
}

/// Sides per chunk of the parallel passes over the sides.
const SIDE_CHUNK: usize = 1 << 16;

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

/// Sorts the sides of one bucket by key and side, and makes the two sides of every interior
/// face each other's `partner` (each side is in one bucket, so each slot is written once).
fn match_bucket(
    p: &Polyhedra,
    side_cell: &[u32],
    bucket: &[u32],
    partner: &[AtomicU32],
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
            2 => {
                let (a, b) = (entries[i].1, entries[i + 1].1);
                partner[a as usize].store(b, Ordering::Relaxed);
                partner[b as usize].store(a, Ordering::Relaxed);
            }
            _ => {
                return Err(MeshError::OvercrowdedFace {
                    vertices: key(&entries[i]).iter().map(|&v| v as usize).collect(),
                    cells: [cell(0), cell(1), cell(2)],
                });
            }
        }
        i = j;
    }
    Ok(())
}

/// Per side, its partner side ([`NO_SIDE`] on the boundary), or the error of the smallest bad
/// key (see the module docs).
fn partners(p: &Polyhedra, side_cell: &[u32]) -> Result<Vec<u32>, MeshError> {
    let n_sides = side_cell.len();
    let smallest = |s: usize| p.side_vertices(s).iter().min().map(|&v| v as usize);
    let (ptr, order) = try_par_counting_sort(p.vertices.len(), n_sides, smallest, |s| s as u32)?;
    let mut partner: Vec<AtomicU32> = try_vec(n_sides, "the partners of the face sides")?;
    partner.extend((0..n_sides).map(|_| AtomicU32::new(NO_SIDE)));
    let err = ptr
        .par_windows(2)
        .map_init(BucketScratch::default, |scratch, w| {
            match_bucket(p, side_cell, &order[w[0]..w[1]], &partner, scratch)
        })
        .find_map_first(|r| r.err());
    if let Some(e) = err {
        return Err(e);
    }
    Ok(partner.into_iter().map(AtomicU32::into_inner).collect())
}

/// Matches the sides of `p` into faces (`side_cell`: [`side_cells`]). Faces are numbered in
/// the order of their first side, in parallel over chunks of sides: each chunk counts its
/// first sides (boundary sides, and interior sides before their partner), the counts give
/// each chunk its first face number, and the second sides take the number of their partner.
pub(crate) fn match_faces(p: &Polyhedra, side_cell: &[u32]) -> Result<FaceMatch, MeshError> {
    let n_sides = side_cell.len();
    let partner = partners(p, side_cell)?;
    let first = |s: usize| partner[s] == NO_SIDE || partner[s] as usize > s;
    let n_chunks = n_sides.div_ceil(SIDE_CHUNK);
    let range = |c: usize| c * SIDE_CHUNK..((c + 1) * SIDE_CHUNK).min(n_sides);
    let counts: Vec<usize> = (0..n_chunks)
        .into_par_iter()
        .map(|c| range(c).filter(|&s| first(s)).count())
        .collect();
    let mut start = Vec::with_capacity(n_chunks + 1);
    start.push(0);
    for c in &counts {
        start.push(start.last().copied().unwrap_or(0) + c);
    }
    let n_faces = start[n_chunks];
    let mut face_sides: Vec<[u32; 2]> = try_filled(n_faces, [0, 0], "the sides of the faces")?;
    let mut face_of_side: Vec<AtomicU32> = try_vec(n_sides, "the faces of the face sides")?;
    face_of_side.extend((0..n_sides).map(|_| AtomicU32::new(0)));
    // the first sides, chunk by chunk into consecutive faces
    let mut pieces = Vec::with_capacity(n_chunks);
    let mut rest = face_sides.as_mut_slice();
    for (c, &len) in counts.iter().enumerate() {
        let (piece, tail) = rest.split_at_mut(len);
        pieces.push((c, piece));
        rest = tail;
    }
    pieces.into_par_iter().for_each(|(c, piece)| {
        let firsts = range(c).filter(|&s| first(s));
        for ((f, s), slot) in (start[c]..).zip(firsts).zip(piece.iter_mut()) {
            *slot = [s as u32, partner[s]];
            face_of_side[s].store(f as u32, Ordering::Relaxed);
        }
    });
    // the second sides, once every first side has its face
    (0..n_sides).into_par_iter().for_each(|s| {
        if !first(s) {
            let f = face_of_side[partner[s] as usize].load(Ordering::Relaxed);
            face_of_side[s].store(f, Ordering::Relaxed);
        }
    });
    Ok(FaceMatch {
        face_of_side: face_of_side
            .into_iter()
            .map(AtomicU32::into_inner)
            .collect(),
        face_sides,
    })
}

/// How loop `b` runs compared with loop `a` over the same vertex set: `Some(true)` in the same
/// cyclic order, `Some(false)` in the reverse order, `None` in neither (a different polygon).
pub(crate) fn same_direction(a: &[u32], b: &[u32]) -> Option<bool> {
    let m = a.len();
    if b.len() != m {
        return None;
    }
    let p = b.iter().position(|&v| v == a[0])?;
    // b read from position p on, cyclically (without a division per entry)
    let at = |i: usize| b[if p + i >= m { p + i - m } else { p + i }];
    if (1..m).all(|i| at(i) == a[i]) {
        Some(true)
    } else if (1..m).all(|i| at(m - i) == a[i]) {
        Some(false)
    } else {
        None
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
        assert_eq!(same_direction(&[1, 2, 3], &[3, 2, 1]), Some(false));
        assert_eq!(same_direction(&[1, 2, 3], &[2, 3, 1]), Some(true));
        assert_eq!(same_direction(&[1, 2, 3], &[1, 2, 3, 4]), None);
        assert_eq!(same_direction(&[1, 2, 3], &[4, 2, 3]), None);
        assert_eq!(
            same_direction(&[1, 2, 3, 4, 5], &[4, 3, 2, 1, 5]),
            Some(false)
        );
    }
}
