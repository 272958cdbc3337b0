//! Returning the free pages of the heap to the system.
//!
//! glibc's allocator keeps the pages of a freed block that lies inside its heap (below the
//! top) resident: only the top of the heap is trimmed. A solve frees large arrays phase after
//! phase (the nested start's coarse solves, the masked matrices of the previous steps), and the
//! holes they leave are not always reused by the next phase's arrays, so the resident set grows
//! beyond the data that is alive. [`release_free_pages`] hands those pages back
//! (`malloc_trim(0)`, which since glibc 2.8 also releases whole free pages inside the heap); the
//! iterative solver calls it before building a new multigrid hierarchy, the largest transient
//! of a solve, so that its peak is the live data plus the setup rather than also the holes.
//! The price is a page fault for each released page touched again; the measurements are in
//! `replication/BENCHMARKS.md` ("Measurements behind the defaults").

/// Returns the free pages inside the heap to the system where the allocator is glibc's; does
/// nothing elsewhere. The allocations are unchanged: only pages holding no live block go.
pub fn release_free_pages() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free memory of glibc's arenas to the system; it takes
    // the arenas' locks and touches no live allocation.
    unsafe {
        libc::malloc_trim(0);
    }
}
