//! Sorting helpers: a counting sort into buckets (compressed sparse rows), shared by the
//! mesh sweep and the symbolic assembly, and the sorted lattice keys of points.

use crate::budget::{AllocFailure, try_filled, try_vec};

/// The buckets of a counting sort: item i goes to bucket `key(i)` (if any), buckets
/// ascending, items ascending within a bucket, each stored as `item(i)`.
/// Returns the bucket offsets (`n_buckets + 1` of them) and the items; aborts, as `vec!`
/// does, if they cannot be allocated ([`try_counting_sort`] returns the failure instead).
pub(crate) fn counting_sort<T: Copy + Default>(
    n_buckets: usize,
    keys: impl Iterator<Item = Option<usize>> + Clone,
    item: impl Fn(usize) -> T,
) -> (Vec<usize>, Vec<T>) {
    try_counting_sort(n_buckets, keys, item).unwrap_or_else(|f| f.abort())
}

/// [`counting_sort`], or [`AllocFailure`] if its arrays (offsets, fill cursors and items) cannot
/// be allocated: for the buckets whose size the input decides.
pub(crate) fn try_counting_sort<T: Copy + Default>(
    n_buckets: usize,
    keys: impl Iterator<Item = Option<usize>> + Clone,
    item: impl Fn(usize) -> T,
) -> Result<(Vec<usize>, Vec<T>), AllocFailure> {
    let mut ptr = try_filled(
        n_buckets + 1,
        0usize,
        "the bucket offsets of a counting sort",
    )?;
    for b in keys.clone().flatten() {
        ptr[b + 1] += 1;
    }
    for i in 0..n_buckets {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = try_vec(ptr.len(), "the bucket cursors of a counting sort")?;
    fill.extend_from_slice(&ptr);
    let mut items = try_filled(ptr[n_buckets], T::default(), "the items of a counting sort")?;
    for (i, key) in keys.enumerate() {
        if let Some(b) = key {
            items[fill[b]] = item(i);
            fill[b] += 1;
        }
    }
    Ok((ptr, items))
}

/// From this many items on, [`sorted_point_keys`] sorts in parallel.
const PARALLEL_SORT: usize = 1 << 15;

/// The points keyed by `key` of each coordinate, `(key(x), key(y), index)`, sorted (in parallel
/// for many points: the items are distinct, so the order is that of a sequential sort), or
/// [`AllocFailure`] if the keys cannot be allocated.
pub(crate) fn sorted_point_keys<K: Ord + Send>(
    pts: &[super::Point],
    key: impl Fn(f64) -> K,
) -> Result<Vec<(K, K, usize)>, AllocFailure> {
    let mut keyed: Vec<(K, K, usize)> = try_vec(pts.len(), "the sort keys of the vertices")?;
    keyed.extend(
        pts.iter()
            .enumerate()
            .map(|(i, p)| (key(p[0]), key(p[1]), i)),
    );
    if keyed.len() >= PARALLEL_SORT {
        use rayon::slice::ParallelSliceMut;
        keyed.par_sort_unstable();
    } else {
        keyed.sort_unstable();
    }
    Ok(keyed)
}
