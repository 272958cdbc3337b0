//! Sorting helpers: a counting sort into buckets (compressed sparse rows), shared by the
//! mesh sweep and the symbolic assembly, and the sorted lattice keys of points.

/// The buckets of a counting sort: item i goes to bucket `key(i)` (if any), buckets
/// ascending, items ascending within a bucket, each stored as `item(i)`.
/// Returns the bucket offsets (`n_buckets + 1` of them) and the items.
pub(crate) fn counting_sort<T: Copy + Default>(
    n_buckets: usize,
    keys: impl Iterator<Item = Option<usize>> + Clone,
    item: impl Fn(usize) -> T,
) -> (Vec<usize>, Vec<T>) {
    let mut ptr = vec![0usize; n_buckets + 1];
    for b in keys.clone().flatten() {
        ptr[b + 1] += 1;
    }
    for i in 0..n_buckets {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut items = vec![T::default(); ptr[n_buckets]];
    for (i, key) in keys.enumerate() {
        if let Some(b) = key {
            items[fill[b]] = item(i);
            fill[b] += 1;
        }
    }
    (ptr, items)
}

/// From this many items on, [`sorted_point_keys`] sorts in parallel.
const PARALLEL_SORT: usize = 1 << 15;

/// The points keyed by `key` of each coordinate, `(key(x), key(y), index)`, sorted (in parallel
/// for many points: the items are distinct, so the order is that of a sequential sort).
pub(crate) fn sorted_point_keys<K: Ord + Send>(
    pts: &[super::Point],
    key: impl Fn(f64) -> K,
) -> Vec<(K, K, usize)> {
    let mut keyed: Vec<(K, K, usize)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p[0]), key(p[1]), i))
        .collect();
    if keyed.len() >= PARALLEL_SORT {
        use rayon::slice::ParallelSliceMut;
        keyed.par_sort_unstable();
    } else {
        keyed.sort_unstable();
    }
    keyed
}
