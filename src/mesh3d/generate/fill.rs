//! Filling the flat arrays of a [`Polyhedra`](crate::mesh3d::Polyhedra) layer by layer, in
//! parallel, without a per-cell allocation.
//!
//! A generator cuts its cells into layers (the cells of one z-slab of the grid) and describes
//! each layer through a [`Sink`]: `face` for every face of a cell, `end_cell` after its last
//! face. It is run twice: first into a [`Counter`] per layer (the numbers of cells, face sides
//! and face vertices), then, once the arrays are allocated to their exact sizes and cut into
//! one slice per layer at the prefix sums of those counts, into a [`Layer`] writing its slice.
//! Each layer writes absolute offsets (its own plus the sums of the layers before it), so the
//! layers are independent and the result does not depend on how rayon schedules them.

use crate::budget::{AllocFailure, try_filled};
use rayon::prelude::*;

/// Where a generator describes the cells of one layer.
pub(crate) trait Sink {
    /// Appends a face (a vertex loop) to the current cell.
    fn face(&mut self, vertices: &[u32]);
    /// Closes the current cell.
    fn end_cell(&mut self);
}

/// Counts what a layer describes: cells, face sides, face vertices.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Counter(pub [usize; 3]);

impl Sink for Counter {
    fn face(&mut self, vertices: &[u32]) {
        self.0[1] += 1;
        self.0[2] += vertices.len();
    }

    fn end_cell(&mut self) {
        self.0[0] += 1;
    }
}

/// Writes one layer into its slices of `cell_ptr[1..]`, `face_ptr[1..]` and `face_vertices`.
pub(crate) struct Layer<'a> {
    cell_end: &'a mut [u32],
    face_end: &'a mut [u32],
    vertices: &'a mut [u32],
    /// Entries written so far: cells, face sides, face vertices.
    written: [usize; 3],
    /// Face sides and face vertices of the layers before this one.
    base: [usize; 2],
}

impl Sink for Layer<'_> {
    fn face(&mut self, vertices: &[u32]) {
        let [_, s, v] = self.written;
        self.vertices[v..v + vertices.len()].copy_from_slice(vertices);
        self.written[2] += vertices.len();
        // below u32::MAX: the totals were checked before allocating
        self.face_end[s] = (self.base[1] + self.written[2]) as u32;
        self.written[1] += 1;
    }

    fn end_cell(&mut self) {
        self.cell_end[self.written[0]] = (self.base[0] + self.written[1]) as u32;
        self.written[0] += 1;
    }
}

/// The counts of layers `0..n_layers`, each described by `describe` into a [`Counter`].
pub(crate) fn count_layers(
    n_layers: usize,
    describe: impl Fn(usize, &mut Counter) + Sync,
) -> Vec<[usize; 3]> {
    (0..n_layers)
        .into_par_iter()
        .map(|l| {
            let mut c = Counter::default();
            describe(l, &mut c);
            c.0
        })
        .collect()
}

/// The flat arrays `cell_ptr`, `face_ptr`, `face_vertices` of the layers whose sizes are
/// `counts` (from [`count_layers`], whose sums must fit 32-bit offsets), each layer `l` written
/// by `describe(l, ..)`; [`AllocFailure`] if the arrays cannot be allocated. Panics if a layer describes other counts than it was counted with (a
/// broken generator, not bad input).
pub(crate) fn fill_layers(
    counts: &[[usize; 3]],
    describe: impl Fn(usize, &mut Layer) + Sync,
) -> Result<[Vec<u32>; 3], AllocFailure> {
    let total = counts
        .iter()
        .fold([0; 3], |t, c| [0, 1, 2].map(|i| t[i] + c[i]));
    let mut cell_ptr = try_filled(total[0] + 1, 0u32, "the cell offsets")?;
    let mut face_ptr = try_filled(total[1] + 1, 0u32, "the face offsets")?;
    let mut face_vertices = try_filled(total[2], 0u32, "the face loops")?;
    let cells = split_by(&mut cell_ptr[1..], counts.iter().map(|c| c[0]));
    let faces = split_by(&mut face_ptr[1..], counts.iter().map(|c| c[1]));
    let verts = split_by(&mut face_vertices, counts.iter().map(|c| c[2]));
    let mut base = [0, 0];
    let mut layers = Vec::with_capacity(counts.len());
    for (((cell_end, face_end), vertices), c) in cells.into_iter().zip(faces).zip(verts).zip(counts)
    {
        layers.push(Layer {
            cell_end,
            face_end,
            vertices,
            written: [0; 3],
            base,
        });
        base = [base[0] + c[1], base[1] + c[2]];
    }
    layers
        .into_par_iter()
        .enumerate()
        .for_each(|(l, mut layer)| {
            describe(l, &mut layer);
            assert_eq!(layer.written, counts[l], "layer {l} described other counts");
        });
    Ok([cell_ptr, face_ptr, face_vertices])
}

/// `slice` cut into consecutive pieces of the given lengths (which must sum to its length).
pub(crate) fn split_by<T>(
    mut slice: &mut [T],
    lengths: impl IntoIterator<Item = usize>,
) -> Vec<&mut [T]> {
    let mut pieces = Vec::new();
    for len in lengths {
        let (head, tail) = std::mem::take(&mut slice).split_at_mut(len);
        pieces.push(head);
        slice = tail;
    }
    debug_assert!(slice.is_empty());
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Layer l has l + 1 cells, cell c of it has c + 1 triangles (l, c, 0), ..
    fn describe(l: usize, s: &mut impl Sink) {
        for c in 0..=l {
            for f in 0..=c {
                s.face(&[l as u32, c as u32, f as u32]);
            }
            s.end_cell();
        }
    }

    #[test]
    fn layers_are_counted_then_written_at_their_offsets() {
        let counts = count_layers(4, describe);
        assert_eq!(counts[2], [3, 6, 18]);
        let [cell_ptr, face_ptr, fv] = fill_layers(&counts, |l, s| describe(l, s)).unwrap();
        assert_eq!(cell_ptr, [0, 1, 2, 4, 5, 7, 10, 11, 13, 16, 20]);
        assert_eq!(face_ptr.len(), 21);
        assert!(
            face_ptr
                .iter()
                .enumerate()
                .all(|(s, &o)| o as usize == 3 * s)
        );
        // the last face of the last cell of the last layer
        assert_eq!(&fv[fv.len() - 3..], &[3, 3, 3]);
        assert_eq!(&fv[3..9], &[1, 0, 0, 1, 1, 0]);
    }
}
