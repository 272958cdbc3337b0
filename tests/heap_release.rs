//! `gradvi::heap::release_free_pages` hands the free pages inside the heap back to the system:
//! blocks freed below a live one stay resident until it is called. Its own test binary, so
//! that no other test allocates while the resident set is read, and without the test harness,
//! so that it runs on the main thread and its blocks land in glibc's main heap (a thread's
//! arena returns whole free heaps by itself).

/// The resident set of this process, bytes.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn resident() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmRSS:")).unwrap();
    line.split_whitespace()
        .nth(1)
        .unwrap()
        .parse::<u64>()
        .unwrap()
        * 1024
}

fn main() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    freed_blocks_inside_the_heap_leave_the_resident_set();
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn freed_blocks_inside_the_heap_leave_the_resident_set() {
    // 4096 blocks of 64 KiB (below glibc's mmap threshold: they live in the heap), written,
    // then a small block above them, so that freeing them leaves a 256 MiB hole that glibc's
    // own trimming of the heap top cannot return
    const BLOCK: usize = 64 * 1024;
    const N: usize = 4096;
    let blocks: Vec<Vec<u8>> = (0..N).map(|i| vec![(i % 251) as u8 + 1; BLOCK]).collect();
    let guard = vec![7u8; 1024];
    let held = resident();
    drop(blocks);
    let freed = resident();
    gradvi::heap::release_free_pages();
    let released = resident();
    let total = (N * BLOCK) as u64;
    // the hole stays resident after the frees (most of it: the allocator may return a little)
    assert!(held.saturating_sub(freed) < total / 4, "{held} -> {freed}");
    // and leaves with the release (most of it: a few pages hold the allocator's bookkeeping)
    assert!(
        freed.saturating_sub(released) > total * 3 / 4,
        "{freed} -> {released} of {total}"
    );
    assert_eq!(guard.iter().map(|&b| b as u64).sum::<u64>(), 7 * 1024);
    println!(
        "released {} of {total} freed bytes",
        freed.saturating_sub(released)
    );
}
