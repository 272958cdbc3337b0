//! How much memory building a mesh may take, so that a request too large is refused up front
//! with an error giving the estimate, instead of aborting on allocation.
//!
//! The budget is the caller's: every generator and reader takes a [`MemoryBudget`], and the
//! library never looks at the machine's free memory unless the caller asks for it with
//! [`MemoryBudget::available`]. The same call therefore passes or fails whatever the load of
//! the machine. The convenience generators without a budget argument
//! ([`cartesian()`](super::generate::cartesian()) and the like) use the fixed
//! [`MemoryBudget::DEFAULT`] (8 GiB).
//!
//! * [`MemoryBudget::available`]: the memory the kernel reports as available (`MemAvailable` in
//!   `/proc/meminfo`), or less if the control group of the process limits it (a container:
//!   `/proc/meminfo` then shows the host's memory); [`MemoryBudget::DEFAULT`] where neither is
//!   known. The command line and the Python module start from it.
//! * [`mesh_bytes`]: the peak memory of building and validating a [`PolyMesh`](super::PolyMesh)
//!   with given numbers of cells, cell sides, vertices and edges. The generators compare it with
//!   the budget before allocating anything ([`MemoryBudget::check`]); a caller that needs memory
//!   for more than the mesh (a solve) passes a smaller budget.
//! * [`MemoryBudget::max_file_bytes`]: the largest mesh file the readers read, a quarter of the
//!   budget (the mesh built from a text file needs several times the size of the text). A
//!   larger file, or an endless stream, is refused after reading at most that much.
//!
//! Measurements of the estimate against peak resident memory are in `replication/BENCHMARKS.md`
//! ("Measurements behind the defaults").

use crate::error::MeshError;
pub use crate::units::human_bytes;
use std::fmt;

/// A number of bytes that building a mesh may take. Chosen by the caller: a fixed value
/// ([`MemoryBudget::new`], [`MemoryBudget::DEFAULT`]) gives the same answer on every machine,
/// [`MemoryBudget::available`] follows the machine's free memory at the time of the call.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MemoryBudget(u64);

impl MemoryBudget {
    /// 8 GiB: the budget of the generators that take none, and of
    /// [`MemoryBudget::available`] where the machine's memory is not known.
    pub const DEFAULT: MemoryBudget = MemoryBudget(8 << 30);

    /// A budget of `bytes` bytes.
    pub const fn new(bytes: u64) -> Self {
        MemoryBudget(bytes)
    }

    /// The budget in bytes.
    pub const fn bytes(self) -> u64 {
        self.0
    }

    /// The memory the machine has free now: the available memory ([`available_memory`]), or
    /// what the control group's limit leaves ([`cgroup_remaining`]) if smaller;
    /// [`MemoryBudget::DEFAULT`] where neither is known.
    pub fn available() -> Self {
        MemoryBudget(match (available_memory(), cgroup_remaining()) {
            (Some(a), Some(c)) => a.min(c),
            (Some(a), None) => a,
            (None, Some(c)) => c,
            (None, None) => Self::DEFAULT.0,
        })
    }

    /// The largest mesh file the readers accept with this budget: a quarter of it.
    pub const fn max_file_bytes(self) -> u64 {
        self.0 / 4
    }

    /// `Ok` if `bytes` fit in the budget, else [`MeshError::TooLarge`] naming `what`.
    pub fn check(self, what: impl Into<String>, bytes: u64) -> Result<(), MeshError> {
        if bytes <= self.0 {
            Ok(())
        } else {
            Err(MeshError::TooLarge {
                what: what.into(),
                bytes,
                budget: self.0,
            })
        }
    }
}

impl Default for MemoryBudget {
    /// [`MemoryBudget::DEFAULT`].
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl fmt::Display for MemoryBudget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&human_bytes(self.0))
    }
}

/// The memory the kernel reports as available (`MemAvailable` of `/proc/meminfo`), in bytes;
/// `None` where that file does not exist or cannot be read.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// What the memory limit of the process's control group still allows (limit less usage):
/// cgroup v2 (`/sys/fs/cgroup/memory.max` and `memory.current`) or v1
/// (`/sys/fs/cgroup/memory/memory.limit_in_bytes` and `memory.usage_in_bytes`). `None` when
/// there is no limit (v2 `max`, or a v1 limit beyond 2^60 bytes) or the files cannot be read.
pub fn cgroup_remaining() -> Option<u64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let num = |t: String| t.trim().parse::<u64>().ok();
    let (limit, usage) = match read("/sys/fs/cgroup/memory.max") {
        Some(t) => (
            num(t)?,
            read("/sys/fs/cgroup/memory.current").and_then(num)?,
        ),
        None => (
            read("/sys/fs/cgroup/memory/memory.limit_in_bytes").and_then(num)?,
            read("/sys/fs/cgroup/memory/memory.usage_in_bytes").and_then(num)?,
        ),
    };
    (limit < 1 << 60).then(|| limit.saturating_sub(usage))
}

/// Estimated peak memory, in bytes, of building a mesh with `cells` cells whose vertex lists
/// hold `sides` entries in all, `vertices` vertices and `edges` edges.
///
/// The peak is reached during the overlap check (the sweep of
/// [`validate`](super::validate)), when the arrays of [`PolyMesh`](super::PolyMesh) are all
/// built: 16 bytes per vertex (coordinates), 36 per cell (32-bit CSR offset, area, centroid,
/// and the diameter, present during the check, not kept by the mesh), 8 per cell side (32-bit
/// vertex and edge ids; n_{K,σ} and d_{K,σ} are computed on demand) and 56 per edge (end
/// points, cells, length, midpoint, tag: more than the mesh keeps, which stores 32-bit end
/// points and cells and computes lengths and midpoints on demand, as margin); and the sweep
/// adds 72 bytes per vertex (sort keys, ranks, sorted points, event offsets, boundary links)
/// and 44 per edge (renumbered segments, event lists, treap handles). How the estimate
/// compares with measured peaks is recorded in `replication/BENCHMARKS.md` ("Measurements
/// behind the defaults").
pub fn mesh_bytes(cells: u64, sides: u64, vertices: u64, edges: u64) -> u64 {
    let per_vertex = 16 + 72;
    let per_cell = 36;
    let per_side = 8;
    let per_edge = 56 + 44;
    cells
        .saturating_mul(per_cell)
        .saturating_add(sides.saturating_mul(per_side))
        .saturating_add(vertices.saturating_mul(per_vertex))
        .saturating_add(edges.saturating_mul(per_edge))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_available_budget_is_the_smaller_of_the_machine_limits() {
        let b = MemoryBudget::available().bytes();
        assert!(b > 0);
        if let Some(a) = available_memory() {
            assert!(b <= a);
        }
        if let Some(c) = cgroup_remaining() {
            assert!(b <= c);
        }
        if available_memory().is_none() && cgroup_remaining().is_none() {
            assert_eq!(b, MemoryBudget::DEFAULT.bytes());
        }
    }

    #[test]
    fn a_fixed_budget_checks_the_same_everywhere() {
        let budget = MemoryBudget::new(10);
        assert_eq!(budget.bytes(), 10);
        assert_eq!(MemoryBudget::new(4 << 30).max_file_bytes(), 1 << 30);
        assert_eq!(MemoryBudget::default(), MemoryBudget::DEFAULT);
        assert_eq!(MemoryBudget::DEFAULT.to_string(), "8.0 GiB");
        assert!(budget.check("x", 10).is_ok());
        let e = MemoryBudget::new(8 << 30)
            .check("a big mesh", 11 << 30)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "a big mesh would need about 11.0 GiB, more than the memory budget of 8.0 GiB"
        );
        assert_eq!(mesh_bytes(u64::MAX, 1, 1, 1), u64::MAX);
    }
}
