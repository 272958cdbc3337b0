//! The workspace of faer's dense matrix-product kernel, checked against the process's limits
//! before a computation that may need it, so that a limit too small for it is a typed
//! out-of-memory error instead of an abort.
//!
//! faer runs its dense products (on x86_64 with AVX2 and FMA, or AVX-512) in
//! `private-gemm-x86`, which maps a workspace of about twice the last-level cache size on each
//! thread, infallibly, the first time that thread runs a product, and keeps it
//! ([`dense_product_workspace`] says how much, and why it can be large). The supernodal sparse
//! Cholesky factorisation reaches that kernel through its Schur-complement updates, and the
//! dense Cholesky factorisation through its blocked updates (measurements of which calls and
//! sizes do: `replication/measurements/limits.md`).
//!
//! [`reserve`] is called before such a computation. It counts the threads that may run a
//! product and have not mapped the workspace yet (the calling thread; with parallel faer
//! (`Par::Rayon`), every thread of the rayon pool too), checks that many workspaces against
//! [`rlimit_headroom`](crate::budget::rlimit_headroom) (an address-space or data limit;
//! without one there is nothing to check), and then has each of those threads run a 1 × 1
//! product, so that every workspace the computation may use is mapped now, under the check,
//! and no thread maps one later unchecked. A thread that mapped its workspace through faer
//! outside [`reserve`] is counted again: the check is then stricter than needed, never
//! looser. The workspace changes no result: the kernel overwrites what it reads of it.

use crate::budget::{check_dense_product_workspace, dense_product_workspace};
use std::cell::Cell;

thread_local! {
    /// Whether [`reserve`] mapped the product workspace of this thread.
    static MAPPED: Cell<bool> = const { Cell::new(false) };
}

/// Checks that the threads that may run faer's dense products in a computation with `par`
/// can map their workspace within the process's limits, and maps it ([module docs](self));
/// [`Error::OutOfMemory`](crate::Error::OutOfMemory) naming the workspace otherwise. `avoid`
/// says what else would avoid it, for the message.
pub(crate) fn reserve(par: faer::Par, avoid: &str) -> crate::Result<()> {
    if dense_product_workspace() == 0 {
        return Ok(());
    }
    let parallel = matches!(par, faer::Par::Rayon(n) if n.get() > 1);
    let in_pool = rayon::current_thread_index().is_some();
    let workers = if parallel {
        rayon::broadcast(|_| !MAPPED.get())
            .into_iter()
            .filter(|&unmapped| unmapped)
            .count()
    } else {
        0
    };
    // a caller in the pool was counted by the broadcast
    let counted = parallel && in_pool;
    let caller = usize::from(!(MAPPED.get() || counted));
    let threads = (workers + caller) as u64;
    if threads == 0 {
        return Ok(());
    }
    check_dense_product_workspace(threads, avoid)?;
    map_here();
    if parallel {
        rayon::broadcast(|_| map_here());
    }
    Ok(())
}

/// Maps this thread's product workspace (a 1 × 1 product with a lower-triangular destination,
/// which faer hands to the kernel whatever its size), once.
fn map_here() {
    if MAPPED.get() {
        return;
    }
    let mut dst = faer::Mat::<f64>::zeros(1, 1);
    let one = faer::Mat::<f64>::identity(1, 1);
    use faer::linalg::matmul::triangular::{BlockStructure, matmul};
    matmul(
        dst.as_mut(),
        BlockStructure::TriangularLower,
        faer::Accum::Replace,
        one.as_ref(),
        BlockStructure::Rectangular,
        one.as_ref(),
        BlockStructure::Rectangular,
        1.0,
        faer::Par::Seq,
    );
    MAPPED.set(true);
}
