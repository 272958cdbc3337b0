//! How much memory building a mesh may take, so that a request too large for the machine is
//! refused up front with an error giving the estimate, instead of aborting on allocation.
//!
//! * [`memory_budget`]: the memory the kernel reports as available (`MemAvailable` in
//!   `/proc/meminfo`), or less if the control group of the process limits it (a container:
//!   `/proc/meminfo` then shows the host's memory); [`DEFAULT_MEMORY_BUDGET`] (8 GiB) where
//!   neither is known. (It was capped at 8 GiB before; PETSc ex9's 4097² grid, 33.6M triangles,
//!   needed an estimated 9.5 GB for its mesh (8.5 GB since the cell arrays are 32-bit), and its
//!   whole P1 solve 19 GB, on a 24 GiB machine.)
//! * [`mesh_bytes`]: the peak memory of building and validating a [`PolyMesh`](super::PolyMesh)
//!   with given numbers of cells, cell sides, vertices and edges. The generators compare it with
//!   the budget before allocating anything ([`check_budget`]); a caller that needs memory for
//!   more than the mesh (a solve) can pass a smaller budget
//!   ([`Family::generate_within`](super::generate::Family::generate_within)).
//! * [`max_file_bytes`]: the largest mesh file the readers read, a quarter of the budget (the
//!   mesh built from a text file needs several times the size of the text). A larger file, or an
//!   endless stream, is refused after reading at most that much.

use crate::error::MeshError;

/// The memory budget where neither the available memory nor a control-group limit is known:
/// 8 GiB.
pub const DEFAULT_MEMORY_BUDGET: u64 = 8 << 30;

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

/// The memory a mesh may take: the available memory ([`available_memory`]), or what the
/// control group's limit leaves ([`cgroup_remaining`]) if smaller; [`DEFAULT_MEMORY_BUDGET`]
/// where neither is known.
pub fn memory_budget() -> u64 {
    match (available_memory(), cgroup_remaining()) {
        (Some(a), Some(c)) => a.min(c),
        (Some(a), None) => a,
        (None, Some(c)) => c,
        (None, None) => DEFAULT_MEMORY_BUDGET,
    }
}

/// The largest mesh file the readers accept: a quarter of [`memory_budget`].
pub fn max_file_bytes() -> u64 {
    memory_budget() / 4
}

/// Estimated peak memory, in bytes, of building a mesh with `cells` cells whose vertex lists
/// hold `sides` entries in all, `vertices` vertices and `edges` edges.
///
/// The peak is reached during the overlap check (the sweep of
/// [`validate`](super::validate)), when the arrays of [`PolyMesh`](super::PolyMesh) are all
/// built: 16 bytes per vertex (coordinates), 36 per cell (32-bit CSR offset, area, centroid,
/// and the diameter, present during the check, not kept by the mesh), 8 per cell side (32-bit
/// vertex and edge ids, compacted from `usize` before the check; n_{K,σ} and d_{K,σ} are
/// computed on demand) and 56 per edge (end points, cells, length, midpoint, tag); and the
/// sweep adds 72 bytes per vertex (sort keys, ranks, sorted points, event offsets, boundary
/// links) and 44 per edge (renumbered segments, event lists, treap handles). Measured peaks
/// (resident memory) were 85–95% of this estimate when it counted 40 bytes per side for the
/// stored normals and distances; without them the measured saving is exactly those 24 bytes
/// per side. Since then the mesh stores neither the edge lengths nor the midpoints (24 bytes
/// per edge, computed on demand), its edge end points and cells are 32-bit (16 bytes less per
/// edge) and the sweep's events are 32-bit where they fit; the estimate still counts the old
/// edge sizes, as margin. Its cell arrays (offsets, vertex and edge ids) are 32-bit too, and
/// counted so (4 bytes per cell and 8 per side less than with `usize`): measured peaks of
/// `gradvi mesh generate` (output file included) are 67–73% of the estimate (Cartesian level 9
/// 72%, triangles level 9 73%, hexagonal level 8 67%), and reading and validating a 1M-cell
/// typ2 file (Cartesian level 9, text and parsing included) 93%.
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

/// `Ok` if `bytes` fit in `budget`, else [`MeshError::TooLarge`] naming `what`.
pub fn check_budget(what: impl Into<String>, bytes: u64, budget: u64) -> Result<(), MeshError> {
    if bytes <= budget {
        Ok(())
    } else {
        Err(MeshError::TooLarge {
            what: what.into(),
            bytes,
            budget,
        })
    }
}

/// A byte count for people: `"512 B"`, `"3.2 MiB"`, `"6.1 GiB"`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_and_formatting() {
        let b = memory_budget();
        assert!(b > 0);
        if let Some(a) = available_memory() {
            assert!(b <= a);
        }
        if let Some(c) = cgroup_remaining() {
            assert!(b <= c);
        }
        assert_eq!(max_file_bytes(), b / 4);
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(3 << 20), "3.0 MiB");
        assert_eq!(human_bytes(DEFAULT_MEMORY_BUDGET), "8.0 GiB");
        assert_eq!(human_bytes(u64::MAX), "16384.0 PiB");
        assert!(check_budget("x", 10, 10).is_ok());
        let e = check_budget("a big mesh", 11 << 30, 8 << 30).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a big mesh would need about 11.0 GiB, more than the memory budget of 8.0 GiB"
        );
        assert_eq!(mesh_bytes(u64::MAX, 1, 1, 1), u64::MAX);
    }
}
