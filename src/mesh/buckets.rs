//! Sorting helpers: a counting sort into buckets (compressed sparse rows), shared by the
//! mesh sweep and the symbolic assembly, and the sorted lattice keys of points.

use crate::budget::{AllocFailure, try_filled, try_vec};

/// The buckets of a counting sort: item i goes to bucket `key(i)` (if any), buckets
/// ascending, items ascending within a bucket, each stored as `item(i)`.
/// Returns the bucket offsets (`n_buckets + 1` of them) and the items; aborts, as `vec!`
/// does, if they cannot be allocated ([`try_counting_sort`] returns the failure instead).
pub(crate) fn counting_sort<T: Copy + Default + 'static>(
    n_buckets: usize,
    keys: impl Iterator<Item = Option<usize>> + Clone,
    item: impl Fn(usize) -> T,
) -> (Vec<usize>, Vec<T>) {
    try_counting_sort(n_buckets, keys, item).unwrap_or_else(|f| f.abort())
}

/// [`counting_sort`], or [`AllocFailure`] if its arrays (offsets, fill cursors and items) cannot
/// be allocated: for the buckets whose size the input decides.
pub(crate) fn try_counting_sort<T: Copy + Default + 'static>(
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

/// Items per chunk of [`try_par_counting_sort`], at least.
const PAR_CHUNK: usize = 1 << 20;

/// [`try_counting_sort`] of the items `0..n_items` (item i stored as `item(i)`), in parallel:
/// the items are cut into consecutive chunks, each chunk counts its items per bucket, the
/// counts give each chunk its cursor in every bucket (chunks in order), and the chunks place
/// their items at once. Items keep their order within a bucket, so the result is that of the
/// sequential sort, whatever the number of threads. The counts take `n_buckets` words per
/// chunk; there are at most as many chunks as threads and as `n_items / n_buckets`, so they
/// never outweigh the items. A single chunk is the sequential sort.
pub(crate) fn try_par_counting_sort(
    n_buckets: usize,
    n_items: usize,
    key: impl Fn(usize) -> Option<usize> + Sync,
    item: impl Fn(usize) -> u32 + Sync,
) -> Result<(Vec<usize>, Vec<u32>), AllocFailure> {
    par_counting_sort_in(n_buckets, n_items, PAR_CHUNK, key, item)
}

/// [`try_par_counting_sort`] with chunks of at least `min_chunk` items.
fn par_counting_sort_in(
    n_buckets: usize,
    n_items: usize,
    min_chunk: usize,
    key: impl Fn(usize) -> Option<usize> + Sync,
    item: impl Fn(usize) -> u32 + Sync,
) -> Result<(Vec<usize>, Vec<u32>), AllocFailure> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU32, Ordering};
    let n_chunks = (n_items / min_chunk.max(1))
        .min(rayon::current_num_threads())
        .min(n_items / n_buckets.max(1));
    if n_chunks <= 1 {
        return try_counting_sort(n_buckets, (0..n_items).map(&key), &item);
    }
    let len = n_items.div_ceil(n_chunks);
    let range = |c: usize| c * len..((c + 1) * len).min(n_items);
    // per chunk, its count of each bucket, turned below into its cursor in each bucket
    let mut cursors = (0..n_chunks)
        .into_par_iter()
        .map(|c| {
            let mut count = try_filled(n_buckets, 0usize, "the bucket counts of a counting sort")?;
            for b in range(c).filter_map(&key) {
                count[b] += 1;
            }
            Ok(count)
        })
        .collect::<Result<Vec<_>, AllocFailure>>()?;
    let mut ptr = try_filled(
        n_buckets + 1,
        0usize,
        "the bucket offsets of a counting sort",
    )?;
    for b in 0..n_buckets {
        let mut at = ptr[b];
        for cursor in cursors.iter_mut() {
            (cursor[b], at) = (at, at + cursor[b]);
        }
        ptr[b + 1] = at;
    }
    // every slot is written exactly once, by the chunk whose cursor reaches it
    let mut items: Vec<AtomicU32> = try_vec(ptr[n_buckets], "the items of a counting sort")?;
    items.extend((0..ptr[n_buckets]).map(|_| AtomicU32::new(0)));
    cursors
        .into_par_iter()
        .enumerate()
        .for_each(|(c, mut cursor)| {
            for i in range(c) {
                if let Some(b) = key(i) {
                    items[cursor[b]].store(item(i), Ordering::Relaxed);
                    cursor[b] += 1;
                }
            }
        });
    Ok((ptr, items.into_iter().map(AtomicU32::into_inner).collect()))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parallel_counting_sort_is_the_sequential_one() {
        // keys with empty buckets, items without a bucket, and uneven chunks
        let n = 10_007;
        let key = |i: usize| (i % 13 != 5).then_some((i * 7919) % 101);
        let item = |i: usize| (3 * i + 1) as u32;
        let want = counting_sort(101, (0..n).map(key), item);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        for min_chunk in [1, 64, 2_500, 1 << 20] {
            let got = pool
                .install(|| par_counting_sort_in(101, n, min_chunk, key, item))
                .unwrap();
            assert_eq!(got, want, "chunks of at least {min_chunk}");
        }
        // more buckets than items: one chunk
        let got = par_counting_sort_in(50_000, n, 1, key, item).unwrap();
        assert_eq!(got, counting_sort(50_000, (0..n).map(key), item));
    }
}
