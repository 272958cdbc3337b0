//! Offsets of lists stored flat, one list per item: list k is `items[at(k)..at(k + 1)]`.
//!
//! The 3D mesh keeps one offset per cell (its faces) and per face (its vertex loop); the dof
//! map, the local matrices and the condensed blocks one per cell. On the meshes of large runs
//! every list usually has the same length (the four triangles of a tetrahedron, the unknowns
//! of P1 on triangles, the quadrilaterals of HMM on a Cartesian grid), and the offsets are
//! then the multiples of one stride: [`Offsets`] stores that stride alone, and otherwise the
//! offsets as 32-bit integers. At 2M P1 cells that is 0 bytes instead of 3 × 17 MB; on 6M
//! tetrahedra, 0 instead of 72 MB for the mesh's cell and face offsets.

use std::ops::Range;

/// The offsets of `n` lists stored flat (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Offsets {
    /// Every list has `stride` items: list k starts at `k × stride`.
    Uniform {
        /// Number of lists.
        n: usize,
        /// Items per list.
        stride: usize,
    },
    /// The `n + 1` offsets (0 first, non-decreasing, the number of items last).
    Explicit(Vec<u32>),
}

impl Offsets {
    /// The offsets of lists of the given lengths; an error if they hold 2^32 items or more.
    pub fn from_lengths(lengths: impl IntoIterator<Item = usize>) -> crate::Result<Self> {
        let mut ptr: Vec<u32> = vec![0];
        let mut total = 0usize;
        let mut stride = None;
        let mut uniform = true;
        for l in lengths {
            total += l;
            if total >= u32::MAX as usize {
                return Err(crate::Error::Linear(format!(
                    "more than 2^32 - 1 local entries (after {} cells): not supported",
                    ptr.len() - 1
                )));
            }
            uniform &= *stride.get_or_insert(l) == l;
            ptr.push(total as u32);
        }
        Ok(if uniform {
            Offsets::Uniform {
                n: ptr.len() - 1,
                stride: stride.unwrap_or(0),
            }
        } else {
            Offsets::Explicit(ptr)
        })
    }

    /// The offsets `ptr` (0 first, non-decreasing, the number of items last; checked by the
    /// caller), kept only if the lists differ in length.
    pub fn from_offsets(ptr: Vec<u32>) -> Self {
        let n = ptr.len().saturating_sub(1);
        let stride = if n == 0 { 0 } else { ptr[1] as usize };
        if ptr
            .iter()
            .enumerate()
            .all(|(k, &p)| p as usize == k * stride)
        {
            Offsets::Uniform { n, stride }
        } else {
            Offsets::Explicit(ptr)
        }
    }

    /// The `n + 1` offsets as 32-bit integers (what [`Self::from_offsets`] takes).
    pub fn to_offsets(&self) -> Vec<u32> {
        match self {
            Offsets::Uniform { n, stride } => (0..=*n).map(|k| (k * stride) as u32).collect(),
            Offsets::Explicit(p) => p.clone(),
        }
    }

    /// Number of lists.
    pub fn n_lists(&self) -> usize {
        match self {
            Offsets::Uniform { n, .. } => *n,
            Offsets::Explicit(p) => p.len() - 1,
        }
    }

    /// Offset `k` (`k ≤ n`): where list k starts, or the number of items for `k = n`.
    #[inline]
    pub fn at(&self, k: usize) -> usize {
        match self {
            Offsets::Uniform { stride, .. } => k * stride,
            Offsets::Explicit(p) => p[k] as usize,
        }
    }

    /// The positions of list `k`.
    #[inline]
    pub fn range(&self, k: usize) -> Range<usize> {
        self.at(k)..self.at(k + 1)
    }

    /// The number of items of all lists.
    pub fn total(&self) -> usize {
        self.at(self.n_lists())
    }

    /// Bytes of storage (0 when uniform).
    pub fn bytes(&self) -> usize {
        match self {
            Offsets::Uniform { .. } => 0,
            Offsets::Explicit(p) => 4 * p.len(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_lengths_store_the_stride() {
        let o = Offsets::from_lengths([3, 3, 3, 3]).unwrap();
        assert_eq!(o, Offsets::Uniform { n: 4, stride: 3 });
        assert_eq!((o.n_lists(), o.total(), o.range(2)), (4, 12, 6..9));
        assert_eq!(o.bytes(), 0);
    }

    #[test]
    fn mixed_lengths_store_every_offset() {
        let o = Offsets::from_lengths([3, 4, 0, 5]).unwrap();
        assert_eq!(o, Offsets::Explicit(vec![0, 3, 7, 7, 12]));
        assert_eq!(
            (o.n_lists(), o.total(), o.range(1), o.range(2)),
            (4, 12, 3..7, 7..7)
        );
        assert_eq!(o.bytes(), 20);
    }

    #[test]
    fn offsets_are_compressed_when_uniform_and_given_back() {
        for ptr in [
            vec![0, 3, 6, 9],
            vec![0, 3, 7, 7, 12],
            vec![0],
            vec![0, 0, 0],
        ] {
            let o = Offsets::from_offsets(ptr.clone());
            assert_eq!(o.to_offsets(), ptr);
            assert_eq!(o.n_lists(), ptr.len() - 1);
            assert_eq!(o.total(), *ptr.last().unwrap() as usize);
        }
        assert_eq!(
            Offsets::from_offsets(vec![0, 3, 6, 9]),
            Offsets::Uniform { n: 3, stride: 3 }
        );
        assert!(matches!(
            Offsets::from_offsets(vec![0, 3, 7]),
            Offsets::Explicit(_)
        ));
    }

    #[test]
    fn no_lists() {
        let o = Offsets::from_lengths(std::iter::empty()).unwrap();
        assert_eq!((o.n_lists(), o.total()), (0, 0));
    }

    #[test]
    fn too_many_items_is_an_error() {
        let half = u32::MAX as usize / 2 + 1;
        assert!(Offsets::from_lengths([half, half]).is_err());
    }
}
