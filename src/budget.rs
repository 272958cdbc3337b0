//! How much memory building a mesh or running a computation (assembly, factorisation,
//! multigrid) may take, so that a request too large is refused up front with an error giving
//! the estimate, instead of aborting on allocation. It uses only [`units`](crate::units) and
//! [`error`](crate::error), so every layer above, the linear algebra included, allocates
//! through it.
//!
//! The budget is the caller's: every generator and reader takes a [`MemoryBudget`], and the
//! library never looks at the machine's free memory unless the caller asks for it with
//! [`MemoryBudget::available`]. The same call therefore passes or fails whatever the load of
//! the machine. The convenience generators without a budget argument
//! ([`cartesian()`](crate::mesh::generate::cartesian()) and the like) use the fixed
//! [`MemoryBudget::DEFAULT`] (8 GiB).
//!
//! * [`MemoryBudget::available`]: the memory the kernel reports as available (`MemAvailable` in
//!   `/proc/meminfo`), or less if the control group of the process limits it (a container:
//!   `/proc/meminfo` then shows the host's memory) or if the process's own limits leave less
//!   ([`rlimit_headroom`]: `RLIMIT_AS`, as `ulimit -v` and batch systems set it, and
//!   `RLIMIT_DATA`); [`MemoryBudget::DEFAULT`] where none is known. The command line and the
//!   Python module start from it.
//! * [`mesh_bytes`]: the peak memory of building and validating a
//!   [`PolyMesh`](crate::mesh::PolyMesh) with given numbers of cells, cell sides, vertices and
//!   edges. The generators compare it with the budget before allocating anything
//!   ([`MemoryBudget::check`]); a caller that needs memory for more than the mesh (a solve)
//!   passes a smaller budget.
//! * [`try_vec`] and [`try_filled`]: the large buffers whose size the input decides (the
//!   arrays of a mesh, a matrix pattern, a factor) are allocated fallibly, so that a request
//!   the estimates let through but the process cannot map (an address-space limit reached by
//!   what is already allocated, an estimate that fell short) becomes a typed error instead of
//!   an abort: [`AllocFailure`], which converts into [`MeshError::TooLarge`] and
//!   [`Error::OutOfMemory`](crate::Error::OutOfMemory).
//! * [`dense_product_workspace`]: the address space faer's dense product kernel maps on each
//!   thread that runs a product (twice the last-level cache size as that kernel reads it,
//!   [`gemm_l3_bytes`]), and [`check_dense_product_workspace`], its check against
//!   [`rlimit_headroom`] before the computations that run it
//!   (`linalg::product_workspace`).
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

    /// The memory this process may still take now: the least of the available memory
    /// ([`available_memory`]), what the control group's limit leaves ([`cgroup_remaining`])
    /// and what the process's own limits leave ([`rlimit_headroom`]);
    /// [`MemoryBudget::DEFAULT`] where none is known.
    pub fn available() -> Self {
        let known = [available_memory(), cgroup_remaining(), rlimit_headroom()];
        MemoryBudget(known.into_iter().flatten().min().unwrap_or(Self::DEFAULT.0))
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

impl MemoryBudget {
    /// `Ok` if `bytes` fit in the budget, else [`Error::OutOfMemory`](crate::Error::OutOfMemory)
    /// naming `what`: the check of a computation that is not the building of a mesh (assembly,
    /// factorisation, multigrid).
    pub fn check_computation(self, what: impl Into<String>, bytes: u64) -> crate::Result<()> {
        if bytes <= self.0 {
            Ok(())
        } else {
            Err(crate::Error::OutOfMemory {
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

/// An allocation that failed: `bytes` bytes for `what`. Converts into the error of the
/// caller's layer, [`MeshError::TooLarge`] (building a mesh) or
/// [`Error::OutOfMemory`](crate::Error::OutOfMemory) (a computation), whose budget is then
/// what [`MemoryBudget::available`] says at the time of the failure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AllocFailure {
    /// What the buffer was for.
    pub what: String,
    /// The size asked for, in bytes.
    pub bytes: u64,
}

impl AllocFailure {
    /// Ends the process as an infallible allocation (`vec!`) does: `memory allocation of …
    /// failed` and an abort. Only for the callers that have no error to return it in.
    pub(crate) fn abort(self) -> ! {
        let bytes = usize::try_from(self.bytes).unwrap_or(usize::MAX);
        let layout = std::alloc::Layout::from_size_align(bytes.min(isize::MAX as usize), 1)
            .unwrap_or(std::alloc::Layout::new::<u8>());
        std::alloc::handle_alloc_error(layout)
    }
}

impl From<AllocFailure> for MeshError {
    fn from(f: AllocFailure) -> Self {
        MeshError::TooLarge {
            what: f.what,
            bytes: f.bytes,
            budget: MemoryBudget::available().bytes(),
        }
    }
}

impl From<AllocFailure> for crate::Error {
    fn from(f: AllocFailure) -> Self {
        crate::Error::OutOfMemory {
            what: f.what,
            bytes: f.bytes,
            budget: MemoryBudget::available().bytes(),
        }
    }
}

/// An empty vector with room for exactly `n` elements, or [`AllocFailure`] naming `what` if
/// the memory cannot be had (`Vec::try_reserve_exact`: a size beyond `isize::MAX` bytes, or
/// the allocator refusing, as under `ulimit -v`). For the buffers whose length the input
/// decides; filling it with `push` or `extend` then allocates nothing more.
pub fn try_vec<T>(n: usize, what: &str) -> Result<Vec<T>, AllocFailure> {
    let mut v = Vec::new();
    try_reserve(&mut v, n, what)?;
    Ok(v)
}

/// Room for `additional` more elements in `v` (`Vec::try_reserve_exact`), or [`AllocFailure`]
/// naming `what` with the size of the whole buffer.
pub fn try_reserve<T>(v: &mut Vec<T>, additional: usize, what: &str) -> Result<(), AllocFailure> {
    v.try_reserve_exact(additional).map_err(|_| AllocFailure {
        what: what.to_string(),
        bytes: (v.len() as u64)
            .saturating_add(additional as u64)
            .saturating_mul(std::mem::size_of::<T>() as u64),
    })
}

/// Room for `additional` more elements in `v`, growing it geometrically as `push` does
/// (`Vec::try_reserve`), or [`AllocFailure`] naming `what`: for buffers appended to piece
/// after piece (a check per piece, not per element, and amortised linear growth).
pub fn try_grow<T>(v: &mut Vec<T>, additional: usize, what: &str) -> Result<(), AllocFailure> {
    v.try_reserve(additional).map_err(|_| AllocFailure {
        what: what.to_string(),
        bytes: (v.len() as u64)
            .saturating_add(additional as u64)
            .saturating_mul(std::mem::size_of::<T>() as u64),
    })
}

/// `v` resized to `n` elements, new ones `value` (the fallible `Vec::resize`), or
/// [`AllocFailure`] as [`try_reserve`]: for buffers kept from one call to the next.
pub fn try_resize<T: Clone>(
    v: &mut Vec<T>,
    n: usize,
    value: T,
    what: &str,
) -> Result<(), AllocFailure> {
    try_reserve(v, n.saturating_sub(v.len()), what)?;
    v.resize(n, value);
    Ok(())
}

/// `n` copies of `value` (the fallible `vec![value; n]`), or [`AllocFailure`] as [`try_vec`].
///
/// A zero of a primitive number type (or `false`) is allocated zeroed, as `vec![0.0; n]` is
/// ([`std::alloc::alloc_zeroed`]): the allocator hands out fresh pages of a large block
/// without writing them, so the pages of a buffer that is only partly written before it is
/// freed never become resident.
pub fn try_filled<T: Clone + 'static>(
    n: usize,
    value: T,
    what: &str,
) -> Result<Vec<T>, AllocFailure> {
    if is_zero_bits(&value) {
        return try_zeroed(n, what);
    }
    let mut v = try_vec(n, what)?;
    v.resize(n, value);
    Ok(v)
}

/// Whether `value` is a value of one of the primitive types below whose bits are all zero:
/// the types for which a zeroed block is a valid vector of `value`s.
fn is_zero_bits<T: 'static>(value: &T) -> bool {
    use std::any::Any;
    let v = value as &dyn Any;
    v.downcast_ref::<f64>().is_some_and(|x| x.to_bits() == 0)
        || v.downcast_ref::<f32>().is_some_and(|x| x.to_bits() == 0)
        || v.downcast_ref::<usize>() == Some(&0)
        || v.downcast_ref::<u64>() == Some(&0)
        || v.downcast_ref::<u32>() == Some(&0)
        || v.downcast_ref::<u8>() == Some(&0)
        || v.downcast_ref::<i64>() == Some(&0)
        || v.downcast_ref::<i32>() == Some(&0)
        || v.downcast_ref::<bool>() == Some(&false)
}

/// `n` zero values of `T` from a zeroed allocation, or [`AllocFailure`] as [`try_vec`]. Only
/// for the types of [`is_zero_bits`], whose all-zero bit pattern is their zero (the caller
/// has checked it).
fn try_zeroed<T>(n: usize, what: &str) -> Result<Vec<T>, AllocFailure> {
    let fail = || AllocFailure {
        what: what.to_string(),
        bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
    };
    let layout = std::alloc::Layout::array::<T>(n).map_err(|_| fail())?;
    if layout.size() == 0 {
        // n = 0 (the types of `is_zero_bits` are not zero-sized)
        return Ok(Vec::new());
    }
    // SAFETY: `layout` has a non-zero size. The block is zeroed, and an all-zero bit pattern
    // is a valid value of each type `is_zero_bits` admits (the only callers' types), so its
    // `n` elements are initialised; it was allocated by the global allocator with the layout
    // of `n` elements of `T`, as `Vec::from_raw_parts` requires, with capacity `n`.
    unsafe {
        let ptr = std::alloc::alloc_zeroed(layout);
        if ptr.is_null() {
            return Err(fail());
        }
        Ok(Vec::from_raw_parts(ptr.cast::<T>(), n, n))
    }
}

/// A copy of `s` (the fallible `to_vec`), or [`AllocFailure`] as [`try_vec`].
pub fn try_copy<T: Clone>(s: &[T], what: &str) -> Result<Vec<T>, AllocFailure> {
    let mut v = try_vec(s.len(), what)?;
    v.extend_from_slice(s);
    Ok(v)
}

/// The items of `iter` in a vector (the fallible `collect` of an iterator whose length is
/// known), or [`AllocFailure`] as [`try_vec`].
pub fn try_collect<T>(
    iter: impl ExactSizeIterator<Item = T>,
    what: &str,
) -> Result<Vec<T>, AllocFailure> {
    let mut v = try_vec(iter.len(), what)?;
    v.extend(iter);
    Ok(v)
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

/// What the process's resource limits still allow it to map, in bytes: the least of
/// `RLIMIT_AS` less the current size of the address space (`VmSize` of `/proc/self/status`)
/// and `RLIMIT_DATA` less the current data segment (`VmData`). A limit is read with
/// `getrlimit` (Unix); where the current size cannot be read (no `/proc`, outside Linux) the
/// headroom is the whole limit. `None` when neither limit is set (`RLIM_INFINITY`) or on a
/// platform without `getrlimit`.
///
/// The address-space limit counts what is reserved, not only what is touched: the threads'
/// stacks and the allocator's arenas are in `VmSize`, which is why a process can be refused an
/// allocation well below its resident memory plus the limit.
pub fn rlimit_headroom() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let used = |key: &str| {
        status
            .as_deref()
            .and_then(|s| status_kib(s, key))
            .unwrap_or(0)
    };
    let as_room = rlimit(Limit::AddressSpace).map(|l| l.saturating_sub(used("VmSize:")));
    let data_room = rlimit(Limit::Data).map(|l| l.saturating_sub(used("VmData:")));
    as_room.into_iter().chain(data_room).min()
}

/// A line `key   N kB` of `/proc/self/status`, in bytes.
fn status_kib(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The resource limits [`rlimit_headroom`] reads.
#[derive(Clone, Copy)]
enum Limit {
    /// `RLIMIT_AS`: the size of the address space.
    AddressSpace,
    /// `RLIMIT_DATA`: the data segment (on Linux since 4.7, every private writable mapping).
    Data,
}

/// The soft limit `which` in bytes; `None` if unlimited or unknown.
#[cfg(unix)]
fn rlimit(which: Limit) -> Option<u64> {
    let resource = match which {
        Limit::AddressSpace => libc::RLIMIT_AS,
        Limit::Data => libc::RLIMIT_DATA,
    };
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one `rlimit` through a valid pointer and reads nothing else.
    let ok = unsafe { libc::getrlimit(resource, &mut lim) } == 0;
    // `rlim_t` is u64 on Linux, of other widths on other Unix systems
    #[allow(clippy::useless_conversion)]
    let cur = u64::try_from(lim.rlim_cur).ok();
    cur.filter(|_| ok && lim.rlim_cur != libc::RLIM_INFINITY)
}

/// No resource limits outside Unix.
#[cfg(not(unix))]
fn rlimit(_which: Limit) -> Option<u64> {
    None
}

/// The address space faer's dense matrix-product kernel maps, once and for good, on each
/// thread that runs it, in bytes; 0 where that kernel is not used or its size is not known.
///
/// On x86_64 with AVX-512F, or AVX2 and FMA, faer hands every dense product that is not tiny
/// (and every product with a triangular or row-indexed destination, whatever its size: the
/// Schur-complement updates of the supernodal sparse Cholesky factorisation and of the
/// blocked dense one) to `private-gemm-x86`. On the first such product a thread runs, that
/// kernel allocates its packing buffers in a thread-local vector, infallibly, and keeps them
/// until the thread ends: two buffers of L3 bytes each, rounded up to 4 KiB pages, where L3
/// is the kernel's own estimate of the last-level cache ([`gemm_l3_bytes`]). For `f64`
/// products it then needs ⌈8·⌈L3/8⌉₁₆ / 4096⌉ + ⌈8·⌈L3/8⌉ₙᵣ / 4096⌉ pages (⌈x⌉ₖ: x rounded
/// up to a multiple of k; nᵣ = 4 or 8, the width of its micro-kernel); when that exceeds the
/// 2·⌈L3/4096⌉ pages first allocated (an L3 that is not a multiple of 64 bytes), the vector is
/// grown by that many more pages, which the estimate adds, with the copy of the old ones.
///
/// The pages are touched only as far as the products use them, so the resident memory grows
/// little; but the address space (`RLIMIT_AS`, `ulimit -v`) and the data limit
/// (`RLIMIT_DATA`) count them whole, and an address-space limit smaller than this, times the
/// threads that run products, ends the process with `memory allocation of … failed`.
///
/// The cache sizes behind it are read from the system on each call ([`gemm_l3_bytes`]).
pub fn dense_product_workspace() -> u64 {
    if !dense_product_kernel_in_use() {
        return 0;
    }
    let Some(l3) = gemm_l3_bytes() else {
        return 0;
    };
    let pages = |bytes: u64| bytes.div_ceil(4096);
    let first = 2 * pages(l3);
    let elems = l3 / 8;
    let nr = if cfg!(target_arch = "x86_64") && avx512() {
        8
    } else {
        4
    };
    let needed = pages(elems.next_multiple_of(16) * 8) + pages(elems.next_multiple_of(nr) * 8);
    let total = if needed > first {
        first + first + needed
    } else {
        first
    };
    total * 4096
}

/// Whether faer's products run `private-gemm-x86`: x86_64 with AVX-512F, or AVX2 and FMA.
fn dense_product_kernel_in_use() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        avx512()
            || (std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma"))
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether the processor has AVX-512F (the kernel then uses its wider micro-kernels).
fn avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The last-level cache size, in bytes, as `private-gemm-x86` estimates it on Linux: for each
/// `cpuN/cache/indexM` of `/sys/devices/system/cpu` of type `Data` or `Unified`, its `size`
/// divided by the number of processors in its `shared_cpu_list` (the last one read of each
/// level is kept, unless its `coherency_line_size` is smaller than the kept one's); the level-3 value times the processors sharing a level-1 cache, times the
/// number of physical cores (`num_cpus::get_physical`). This is not the size of a cache: on
/// a virtual machine reporting one 480 MiB L3 shared by 2 processors on 2 cores it gives
/// 480 MiB, on a machine whose 32 MiB L3 is shared by 16 cores, 32 MiB. `None` where the
/// files cannot be read (not Linux): the kernel then falls back to `lscpu` or `cpuid`, whose
/// sizes this function does not reproduce, and [`dense_product_workspace`] is 0.
///
/// The files are read on every call (a few small files per supernodal factorisation, through
/// [`dense_product_workspace`]): nothing is kept between calls.
pub fn gemm_l3_bytes() -> Option<u64> {
    #[cfg(all(target_os = "linux", target_arch = "x86_64"))]
    {
        let (l3, l1_shared) = sysfs_caches(std::path::Path::new("/sys/devices/system/cpu"))?;
        Some(l3 * l1_shared * num_cpus::get_physical() as u64)
    }
    #[cfg(not(all(target_os = "linux", target_arch = "x86_64")))]
    {
        None
    }
}

/// The level-3 size per sharing processor and the number of processors sharing the level-1
/// cache, read from the cache directories under `cpu_dir` as [`gemm_l3_bytes`] says; `None`
/// if a file cannot be read (the kernel then ignores these files).
fn sysfs_caches(cpu_dir: &std::path::Path) -> Option<(u64, u64)> {
    let (mut l3, mut l3_line, mut l1_shared) = (0u64, 64u64, 1u64);
    for cpu in std::fs::read_dir(cpu_dir).ok()? {
        let cache = cpu.ok()?.path().join("cache");
        let is_cpu = cache
            .parent()
            .and_then(|p| p.file_name())
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.starts_with("cpu"));
        if !is_cpu || !cache.is_dir() {
            continue;
        }
        for index in std::fs::read_dir(cache).ok()? {
            let index = index.ok()?.path();
            let named = index.file_name().and_then(|n| n.to_str());
            if !index.is_dir() || !named.is_some_and(|n| n.starts_with("index")) {
                continue;
            }
            let Some(c) = cache_index(&index)? else {
                continue;
            };
            if c.level == 1 {
                l1_shared = c.shared;
            }
            if c.level == 3 && c.shared > 0 && c.line >= l3_line {
                (l3, l3_line) = (c.bytes / c.shared, c.line);
            }
        }
    }
    Some((l3, l1_shared))
}

/// One `indexM` directory, every file of it read as the kernel reads them: `Some(None)` if it
/// is not a data or unified cache or a value does not parse (the kernel skips it), else its
/// level, size, number of sharing processors and line size; `None` if a file cannot be read.
fn cache_index(index: &std::path::Path) -> Option<Option<CacheIndex>> {
    let mut c = CacheIndex {
        level: 0,
        bytes: 0,
        shared: 0,
        line: 64,
    };
    for entry in std::fs::read_dir(index).ok()? {
        let path = entry.ok()?.path();
        let Some(name) = path
            .file_name()
            .and_then(|n| n.to_str())
            .map(str::to_string)
        else {
            continue;
        };
        let text = std::fs::read_to_string(&path).ok()?;
        let t = text.trim();
        let parsed = match name.as_str() {
            "type" => matches!(t, "Data" | "Unified").then_some(()),
            "shared_cpu_list" => cpu_list_len(t).map(|n| c.shared = n),
            "level" => t.parse().ok().map(|l| c.level = l),
            "coherency_line_size" => t.parse().ok().map(|l| c.line = l),
            "size" => cache_size(t).map(|b| c.bytes = b),
            _ => Some(()),
        };
        if parsed.is_none() {
            return Some(None);
        }
    }
    Some(Some(c))
}

/// What [`cache_index`] reads of a cache.
struct CacheIndex {
    level: u64,
    bytes: u64,
    shared: u64,
    line: u64,
}

/// The number of processors in a list such as `0-3,8,10-11`; `None` if a range does not parse.
fn cpu_list_len(list: &str) -> Option<u64> {
    let mut n = 0;
    for item in list.split(',') {
        n += match item.split_once('-') {
            Some((a, b)) => b.parse::<u64>().ok()? + 1 - a.parse::<u64>().ok()?,
            None => 1,
        };
    }
    Some(n)
}

/// A cache size such as `491520K`, `2M` or `1G` (binary units), in bytes.
fn cache_size(t: &str) -> Option<u64> {
    let (num, unit) = match t.as_bytes().last()? {
        b'G' => (&t[..t.len() - 1], 1 << 30),
        b'M' => (&t[..t.len() - 1], 1 << 20),
        b'K' => (&t[..t.len() - 1], 1 << 10),
        _ => (t, 1),
    };
    num.parse::<u64>().ok().map(|n| n * unit)
}

/// `Ok` if `threads` more threads may each map faer's dense product workspace
/// ([`dense_product_workspace`]) within what the process's limits leave
/// ([`rlimit_headroom`]), else [`Error::OutOfMemory`](crate::Error::OutOfMemory) saying what
/// that workspace is; `avoid` names what else would avoid it (an iterative solver, for one;
/// empty if nothing), and fewer threads are suggested when `threads` > 1.
pub fn check_dense_product_workspace(threads: u64, avoid: &str) -> crate::Result<()> {
    let per_thread = dense_product_workspace();
    let bytes = per_thread.saturating_mul(threads);
    match rlimit_headroom() {
        Some(room) if bytes > room => {
            let fewer = (threads > 1).then_some("fewer threads (RAYON_NUM_THREADS=1)");
            let less: Vec<&str> = [avoid]
                .into_iter()
                .filter(|a| !a.is_empty())
                .chain(fewer)
                .collect();
            let less = if less.is_empty() {
                String::new()
            } else {
                format!("; {} would need less", less.join(", or "))
            };
            Err(crate::Error::OutOfMemory {
                what: format!(
                    "the dense matrix-product workspace of faer ({} of address space on each \
                     of {threads} thread(s): twice the {} last-level cache the system \
                     reports{less})",
                    human_bytes(per_thread),
                    human_bytes(gemm_l3_bytes().unwrap_or(0)),
                ),
                bytes,
                budget: room,
            })
        }
        _ => Ok(()),
    }
}

/// Estimated peak memory, in bytes, of building a mesh with `cells` cells whose vertex lists
/// hold `sides` entries in all, `vertices` vertices and `edges` edges.
///
/// The peak is reached during the overlap check (the sweep of
/// [`validate`](crate::mesh::validate)), when the arrays of [`PolyMesh`](crate::mesh::PolyMesh) are all
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

/// Test support for the fallible allocations: a test runs again in a child process, which
/// limits its own memory ([`limit_data`](child::limit_data)) after
/// building its input, so that the allocations of the code under test, and only those, meet
/// the limit.
#[cfg(all(test, target_os = "linux"))]
pub(crate) mod child {
    /// Whether this process is the child [`run`] started for the test `name`.
    pub(crate) fn is_child(name: &str) -> bool {
        std::env::var("GRADVI_ALLOC_TEST").is_ok_and(|v| v == name)
    }

    /// Runs the test `name` (its full path) of this test binary in a child process and
    /// checks that it passed there: an abort on a failed allocation fails it.
    ///
    /// The child's glibc maps every block of 64 KiB or more on its own and unmaps it when
    /// freed (a fixed `MALLOC_MMAP_THRESHOLD_`, which turns off glibc's dynamic threshold).
    /// With the dynamic threshold, the large blocks freed by a test's warm-up stay in the
    /// arenas, which the data limit counts as used; with many worker threads (16 here) those
    /// arenas held everything the limited run needed, no allocation met the limit and the
    /// test could not see a refusal.
    pub(crate) fn run(name: &str) {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", name, "--test-threads", "1"])
            .env("GRADVI_ALLOC_TEST", name)
            .env("MALLOC_MMAP_THRESHOLD_", "65536")
            .env("RUST_BACKTRACE", "0")
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "the child failed ({}): {said}{err}",
            out.status
        );
        assert!(said.contains("1 passed"), "the child ran no test: {said}");
    }

    /// Limits the data of this process (`RLIMIT_DATA`, as `ulimit -d` does: on Linux every
    /// private writable mapping, including the parts of the allocator's arenas put to use) to
    /// what it has now plus `extra` bytes, the worker threads started first (their stacks
    /// and arenas mapped before the limit). Unlike the address space, which counts the
    /// arenas' reserve whole, this meets every allocation of the code under test. The soft
    /// limit may be raised again, up to the hard one, by a later call.
    pub(crate) fn limit_data(extra: u64) {
        rayon::broadcast(|_| drop(std::hint::black_box(Box::new(0u64))));
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let used = super::status_kib(&status, "VmData:").unwrap();
        let mut lim = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit and setrlimit read or write one `rlimit` through a valid pointer.
        assert_eq!(unsafe { libc::getrlimit(libc::RLIMIT_DATA, &mut lim) }, 0);
        lim.rlim_cur = (used + extra).min(lim.rlim_max);
        assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_DATA, &lim) }, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zero of a primitive type comes from a zeroed block, anything else is written: the
    /// values are `n` copies of the value either way (−0.0, whose bits are not zero, included),
    /// with capacity n, and a block too large for the address space is a typed failure.
    #[test]
    fn filled_vectors_hold_their_value_zeroed_or_written() {
        let z: Vec<f64> = try_filled(1000, 0.0, "zeros").unwrap();
        assert!(z.len() == 1000 && z.capacity() == 1000);
        assert!(z.iter().all(|x| x.to_bits() == 0));
        let m: Vec<f64> = try_filled(7, -0.0, "negative zeros").unwrap();
        assert!(m.iter().all(|x| x.to_bits() == (-0.0f64).to_bits()));
        assert_eq!(try_filled(5, 0u32, "u32").unwrap(), [0; 5]);
        assert_eq!(try_filled(3, 0usize, "usize").unwrap(), [0; 3]);
        assert_eq!(try_filled(4, false, "flags").unwrap(), [false; 4]);
        assert_eq!(try_filled(2, true, "flags").unwrap(), [true; 2]);
        assert_eq!(try_filled(3, 1.5, "ones").unwrap(), [1.5; 3]);
        assert_eq!(try_filled(2, Some(0.0), "options").unwrap(), [Some(0.0); 2]);
        assert!(try_filled(0, 0.0f64, "empty").unwrap().is_empty());
        let e = try_filled(usize::MAX / 4, 0.0f64, "a huge block").unwrap_err();
        assert_eq!(e.what, "a huge block");
        let e = try_filled(usize::MAX / 16, 0u8, "a huge byte block").unwrap_err();
        assert_eq!(e.what, "a huge byte block");
    }

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
        if let Some(r) = rlimit_headroom() {
            assert!(b <= r);
        }
        let none = [available_memory(), cgroup_remaining(), rlimit_headroom()];
        if none.iter().all(Option::is_none) {
            assert_eq!(b, MemoryBudget::DEFAULT.bytes());
        }
    }

    #[test]
    fn status_lines_are_read_in_bytes() {
        let status = "Name:\tgradvi\nVmSize:\t  123456 kB\nVmData:\t 42 kB\n";
        assert_eq!(status_kib(status, "VmSize:"), Some(123456 * 1024));
        assert_eq!(status_kib(status, "VmData:"), Some(42 * 1024));
        assert_eq!(status_kib(status, "VmRSS:"), None);
    }

    /// Runs this test again in a child under `ulimit -v` (2 GiB of address space): there the
    /// budget is at most the limit less what the child has mapped, whatever the machine has.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_available_budget_sees_the_address_space_limit() {
        const LIMIT_KIB: u64 = 2 << 20;
        if std::env::var_os("GRADVI_BUDGET_CHILD").is_some() {
            let b = MemoryBudget::available().bytes();
            let r = rlimit_headroom().expect("the child runs under a limit");
            assert!(b <= r && r < LIMIT_KIB * 1024, "budget {b}, headroom {r}");
            assert_eq!(rlimit(Limit::AddressSpace), Some(LIMIT_KIB * 1024));
            return;
        }
        let exe = std::env::current_exe().unwrap();
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg(format!("ulimit -v {LIMIT_KIB} && exec \"$0\" \"$@\""))
            .arg(exe)
            .args([
                "--exact",
                "budget::tests::the_available_budget_sees_the_address_space_limit",
            ])
            .args(["--test-threads", "1"])
            .env("GRADVI_BUDGET_CHILD", "1")
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "the child under ulimit -v failed: {said}"
        );
        assert!(said.contains("1 passed"), "the child ran no test: {said}");
    }

    /// A request beyond what any address space holds is a typed error in both layers, with
    /// the size asked for; a request that fits gives the vector asked for.
    #[test]
    fn failed_allocations_are_typed_errors() {
        let v = try_filled(5, 1.5f64, "five values").unwrap();
        assert_eq!(v, vec![1.5; 5]);
        assert_eq!(try_vec::<u32>(7, "seven").unwrap().capacity(), 7);
        assert_eq!(
            try_collect((0..4).map(|i| i * 2), "four").unwrap(),
            [0, 2, 4, 6]
        );
        assert!(try_collect(0..usize::MAX, "too many").is_err());
        let mut w = vec![1u8, 2];
        try_resize(&mut w, 4, 9, "four").unwrap();
        assert_eq!(w, [1, 2, 9, 9]);
        assert!(try_resize(&mut w, usize::MAX, 0, "too many").is_err());
        assert_eq!(w, [1, 2, 9, 9]);
        let n = usize::MAX / 16;
        let f = try_vec::<[f64; 2]>(n, "the centroids of the cells").unwrap_err();
        assert_eq!(f.bytes, n as u64 * 16);
        let e = crate::Error::from(f.clone());
        assert!(e.is_out_of_memory(), "{e}");
        assert!(
            e.to_string()
                .starts_with("the centroids of the cells would need about"),
            "{e}"
        );
        assert!(matches!(
            MeshError::from(f),
            MeshError::TooLarge { bytes, .. } if bytes == n as u64 * 16
        ));
        assert!(try_filled(usize::MAX / 4, 0u64, "x").is_err());
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
        assert!(budget.check_computation("y", 10).is_ok());
        let e = MemoryBudget::new(1 << 30)
            .check_computation("assembling the system", 3 << 30)
            .unwrap_err();
        assert!(e.is_out_of_memory());
        assert!(
            e.to_string().starts_with(
                "assembling the system would need about 3.0 GiB, more than the 1.0 GiB of memory \
                 this process may take (use a coarser mesh"
            ),
            "{e}"
        );
    }

    /// A `/sys/devices/system/cpu` as this virtual machine's: two processors, each with a
    /// 48 KiB L1 data cache of its own and the one 480 MiB L3 shared by both; the instruction
    /// cache and the directories that are not processors are skipped.
    #[test]
    fn the_l3_size_is_read_as_the_product_kernel_reads_it() {
        let dir = std::env::temp_dir().join(format!("gradvi-l3-{}", std::process::id()));
        let caches = [
            ("index0", "1", "Data", "48K", "0"),
            ("index1", "1", "Instruction", "64K", "0"),
            ("index3", "3", "Unified", "491520K", "0-1"),
        ];
        for cpu in ["cpu0", "cpu1"] {
            for (index, level, kind, size, shared) in caches {
                let d = dir.join(cpu).join("cache").join(index);
                std::fs::create_dir_all(&d).unwrap();
                for (name, text) in [
                    ("level", level),
                    ("type", kind),
                    ("size", size),
                    ("shared_cpu_list", shared),
                    ("coherency_line_size", "64"),
                ] {
                    std::fs::write(d.join(name), format!("{text}\n")).unwrap();
                }
            }
        }
        std::fs::create_dir_all(dir.join("cpufreq")).unwrap();
        let read = sysfs_caches(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(read, Some((240 << 20, 1)));
        assert_eq!(cache_size("2M"), Some(2 << 20));
        assert_eq!(cache_size("1G"), Some(1 << 30));
        assert_eq!(cache_size("4096"), Some(4096));
        assert_eq!(cache_size("x"), None);
        assert_eq!(cpu_list_len("0-3,8,10-11"), Some(7));
        assert_eq!(cpu_list_len("0-a"), None);
        assert_eq!(
            sysfs_caches(std::path::Path::new("/nonexistent/gradvi")),
            None
        );
    }

    /// Under a data limit, the product workspace of more threads than fit is refused with the
    /// typed error naming it and suggesting fewer threads; none is always accepted.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_product_workspace_beyond_the_limit_is_a_typed_error() {
        const NAME: &str = "budget::tests::a_product_workspace_beyond_the_limit_is_a_typed_error";
        if !child::is_child(NAME) {
            return child::run(NAME);
        }
        let w = dense_product_workspace();
        child::limit_data(64 << 20);
        let refused = check_dense_product_workspace(2, "");
        let none = check_dense_product_workspace(0, "");
        child::limit_data(4 << 30);
        assert!(none.is_ok());
        if w > 32 << 20 {
            let e = refused.unwrap_err();
            assert!(e.is_out_of_memory(), "{e}");
            let m = e.to_string();
            assert!(
                m.contains("dense matrix-product workspace") && m.contains("RAYON_NUM_THREADS=1"),
                "{m}"
            );
        } else {
            assert!(refused.is_ok());
        }
    }
}
