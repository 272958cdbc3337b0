//! The symbolic part of assembly: everything that depends only on the scheme (its unknowns and
//! how cells couple them), built once and shared by every problem posed on the same scheme.
//!
//! - the dof map: the unknowns of each cell, interior first ([`DofMap`]);
//! - the pattern of the condensed (skeleton) matrix, lower triangle, with a diagonal entry for
//!   every skeleton unknown, and its symbolic Cholesky factorisation ([`SpdPattern`]; a
//!   system without interior unknowns solved iteratively releases it once its matrix is
//!   assembled, [`SymbolicSystem::release_pattern`]). For direct solves of HMM on
//!   axis-aligned boxes the factorisation is deferred to the first solve that needs it: those
//!   solves take the cell system of [`super::two_point`] (a Cholesky factorisation of its own,
//!   half the unknowns), so on the warm start's box levels and on Cartesian meshes it is never
//!   computed (the time saved is in `replication/measurements/solver.md`);
//! - the gather maps: the local skeleton entries that land on each condensed entry (`src`, in
//!   cell order; built from where each local entry lands, which is not kept), and the cells
//!   where each unknown appears (`inc`, ascending). They let the values be
//!   *gathered* entry by entry in parallel, with sums in the order of a sequential scatter, so
//!   results do not depend on the number of threads. `src` is built here beside the symbolic
//!   factorisation (direct solves, which gather every matrix); a system solved iteratively,
//!   or directly with the factorisation deferred, builds it when a solve first gathers the
//!   skeleton matrix (`gather_sources`, kept in
//!   the [`SolveState`](super::SolveState)), which the solves through the cell system of
//!   [`super::two_point`] never do (HMM on rectangles; the time and memory this saves are in
//!   `replication/measurements/solver.md`).
//!
//! Dirichlet and active unknowns keep their rows and columns in the pattern (with a unit
//! diagonal and zeros elsewhere), so neither the boundary partition nor the active set
//! changes anything here.

use super::SystemOptions;
use super::gather::{cell_chunks, chunks, split_by_ranges};
use super::linear::{LinearSolver, auto_iterative_min};
use super::two_point::likely_cell_system;
use crate::budget::MemoryBudget;
use crate::budget::{try_collect, try_copy, try_filled, try_grow, try_vec};
use crate::linalg::SpdPattern;
use crate::mesh::complex::CellComplex;
use crate::mesh::{PolyMesh, SolveMesh};
use crate::offsets::Offsets;
use crate::scheme::GradientDiscretisation;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// The unknowns of every cell, flattened: cell k's are `dofs[dof_ptr[k]..dof_ptr[k + 1]]`,
/// its `n_int[k]` interior unknowns first.
#[derive(Debug, Clone)]
pub struct DofMap {
    /// Offsets into `dofs`, one per cell plus one.
    pub dof_ptr: Offsets,
    /// The unknowns of the cells, concatenated (32-bit: [`DofMap::new`] checks that the
    /// scheme has fewer than 2^32 unknowns).
    pub dofs: Vec<u32>,
    /// Number of interior unknowns of each cell.
    pub n_int: Vec<u8>,
}

impl DofMap {
    /// The dof map of no cells.
    pub fn empty() -> Self {
        DofMap {
            dof_ptr: Offsets::Uniform { n: 0, stride: 0 },
            dofs: Vec::new(),
            n_int: Vec::new(),
        }
    }

    /// Asks the scheme for the unknowns of every cell (in parallel over chunks of cells).
    pub fn new<M: CellComplex<D> + ?Sized, const D: usize>(
        scheme: &dyn GradientDiscretisation<M, D>,
    ) -> crate::Result<Self> {
        let nc = scheme.mesh().n_cells();
        // per chunk of cells: the number of unknowns of each cell, the unknowns, the interior counts
        type Chunk = (Vec<usize>, Vec<u32>, Vec<u8>);
        let n = scheme.n_unknowns();
        if n >= u32::MAX as usize {
            return Err(crate::Error::InvalidData(format!(
                "{n} unknowns: at most 2^32 - 1 are supported"
            )));
        }
        let chunks: crate::Result<Vec<Chunk>> = cell_chunks(nc)
            .into_par_iter()
            .map(|(c0, c1)| {
                let mut len = try_vec(c1 - c0, "the unknown counts of the cells")?;
                let mut ni = try_vec(c1 - c0, "the interior counts of the cells")?;
                let (mut all, mut ld) = (Vec::new(), Vec::new());
                for k in c0..c1 {
                    scheme.local_dofs(k, &mut ld);
                    len.push(ld.len());
                    try_grow(&mut all, ld.len(), "the unknowns of the cells")?;
                    // below 2^32: checked above
                    all.extend(ld.iter().map(|&d| d as u32));
                    let n = scheme.n_local_interior(k);
                    ni.push(u8::try_from(n).map_err(|_| {
                        crate::Error::InvalidData(format!(
                            "cell {k} has {n} interior unknowns (at most 255 are supported)"
                        ))
                    })?);
                }
                Ok((len, all, ni))
            })
            .collect();
        let chunks = chunks?;
        let dof_ptr = Offsets::from_lengths(chunks.iter().flat_map(|c| c.0.iter().copied()))?;
        let mut dofs = try_vec(dof_ptr.total(), "the unknowns of the cells")?;
        let mut n_int = try_vec(nc, "the interior counts of the cells")?;
        for (_, all, ni) in chunks {
            dofs.extend_from_slice(&all);
            n_int.extend_from_slice(&ni);
        }
        Ok(DofMap {
            dof_ptr,
            dofs,
            n_int,
        })
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.n_int.len()
    }

    /// The unknowns of cell k and its number of interior unknowns.
    #[inline]
    pub fn cell(&self, k: usize) -> (&[u32], usize) {
        (&self.dofs[self.dof_ptr.range(k)], self.n_int[k] as usize)
    }

    /// Estimated peak memory, in bytes, of building the symbolic system and the values on
    /// this dof map, before the Cholesky factor (checked separately once its size is known).
    ///
    /// * With interior unknowns (HMM): per local entry, the local matrix (8 bytes), its scatter
    ///   position and source (4 + 4) and the (column, row) pairs sorted into the pattern (16);
    ///   per local unknown, a few vectors (64).
    /// * Without (P1, CR): the local matrices are computed by batches and added into the
    ///   assembled matrix, never all stored ([`super::ProblemValues::evaluate_assembled`]),
    ///   and there are no scatter positions or gather sources: per local unknown, its cell and
    ///   its place in the incidence lists (4 + 4); per entry of the lower triangles of the cells'
    ///   blocks (an upper bound of the pattern's entries), the pattern built by columns and
    ///   its copy (8 + 8); per unknown, the offsets of the incidences and of the pattern and a
    ///   few vectors (80). Charging these too at 32 bytes per local entry and 64 per local
    ///   unknown refused P1 on 200³ cubes of Kuhn tetrahedra (48M cells, 8.1M unknowns) for
    ///   34.3 GiB; this estimate is 9.2 GiB there.
    pub fn setup_bytes(&self) -> u64 {
        let (mut full, mut lower) = (0u64, 0u64);
        for k in 0..self.n_cells() {
            let l = self.dof_ptr.range(k).len() as u64;
            full = full.saturating_add(l * l);
            lower = lower.saturating_add(l * (l + 1) / 2);
        }
        let local = self.dofs.len() as u64;
        if self.n_int.iter().all(|&ni| ni == 0) {
            let n = self.dofs.iter().max().map_or(0, |&d| d as u64 + 1);
            local
                .saturating_mul(8)
                .saturating_add(lower.saturating_mul(16))
                .saturating_add(n.saturating_mul(80))
        } else {
            full.saturating_mul(32)
                .saturating_add(local.saturating_mul(64))
        }
    }

    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory), with the estimate, if
    /// [`DofMap::setup_bytes`] exceeds `budget`.
    pub fn check_setup_memory(&self, budget: MemoryBudget) -> crate::Result<()> {
        budget.check_computation(
            format!(
                "assembling the system (local matrices, pattern and scatter maps of {} cells)",
                self.n_cells()
            ),
            self.setup_bytes(),
        )
    }

    /// The skeleton unknowns of cell k.
    fn skeleton(&self, k: usize) -> &[u32] {
        &self.dofs[self.dof_ptr.at(k) + self.n_int[k] as usize..self.dof_ptr.at(k + 1)]
    }
}

/// Lists of items, one per key, flattened: list i is `items[ptr[i]..ptr[i + 1]]`. The
/// offsets are 32-bit (at most 2^32 − 1 items, checked by [`Ragged::new`]): the gather maps
/// have one list per condensed entry, and 4 bytes less per offset are 17 MB at 10⁶ P1
/// unknowns.
#[derive(Debug, Clone)]
pub struct Ragged<T> {
    /// Offsets into `items`, one per list plus one.
    pub ptr: Vec<u32>,
    /// The lists, concatenated.
    pub items: Vec<T>,
}

impl<T> Ragged<T> {
    /// The lists from offsets (`ptr[0] = 0`, non-decreasing, last = `items.len()`) and items;
    /// an error if there are 2^32 items or more.
    pub fn new(ptr: Vec<usize>, items: Vec<T>) -> crate::Result<Self> {
        if items.len() >= u32::MAX as usize {
            return Err(crate::Error::Linear(format!(
                "{} entries in a gather map: at most 2^32 - 1 are supported",
                items.len()
            )));
        }
        Ok(Ragged {
            ptr: try_collect(
                ptr.into_iter().map(|p| p as u32),
                "the offsets of a gather map",
            )?,
            items,
        })
    }

    /// List `i`.
    #[inline]
    pub fn list(&self, i: usize) -> &[T] {
        &self.items[self.ptr[i] as usize..self.ptr[i + 1] as usize]
    }
}

/// The scatter and gather maps of the module docs.
#[derive(Debug, Clone)]
pub struct ScatterMaps {
    /// Offsets of the cells' p×p skeleton blocks, symmetric and stored as their lower
    /// triangles (p(p + 1)/2 entries, [`super::condense::packed_index`]), in a buffer of local
    /// blocks, one per cell plus one.
    pub block_ptr: Offsets,
    /// Per condensed entry, the indices in that buffer of the local entries landing on it
    /// (each local entry (a, b), a ≥ b, lands on the entry (max, min) of its two unknowns).
    /// Built with the symbolic factorisation (direct solves); `None` for a system solved
    /// iteratively (the first gather builds it, `gather_sources`) and when no cell has
    /// interior unknowns (the global matrix is then assembled once, [`super::assembled`]).
    pub src: Option<Ragged<u32>>,
    /// Per unknown, the cells where it appears, ascending (empty, no lists, when no cell has
    /// interior unknowns).
    pub inc: Ragged<u32>,
}

/// The symbolic system of a scheme (see the module docs).
pub struct SymbolicSystem<'a, M = PolyMesh, const D: usize = 2>
where
    M: SolveMesh<D> + ?Sized,
{
    scheme: &'a dyn GradientDiscretisation<M, D>,
    /// The unknowns of each cell (shared with whoever built it alongside, e.g. the data
    /// evaluation of [`super::DiscreteSystem::new`]). Empty (no cells) when no cell has
    /// interior unknowns: the solves then read the assembled matrix only, and the assembly of
    /// another problem on this system asks the scheme again ([`DofMap::new`]).
    pub dof_map: Arc<DofMap>,
    /// Pattern and symbolic factorisation of the condensed matrix; `None` once released
    /// ([`SymbolicSystem::release_pattern`]).
    pattern: Option<SpdPattern>,
    /// Stored entries of the condensed matrix's lower triangle (kept when the pattern is not).
    nnz: usize,
    /// Where local entries go.
    pub maps: ScatterMaps,
    /// Every cell has exactly one interior unknown (HMM): parallel recovery.
    pub single_interior: bool,
    /// No cell has interior unknowns (P1, CR): the condensed matrix is the global one,
    /// assembled once per problem on the pattern ([`super::assembled`]); no gather maps.
    pub no_interior: bool,
    /// The solves are direct but the symbolic factorisation of the condensed matrix is left
    /// to the first solve that needs it (built then in its [`SolveState`](super::SolveState)):
    /// HMM on axis-aligned boxes, whose direct solves take the cell system of
    /// [`super::two_point`] and never need it (module docs).
    deferred: bool,
    /// The options it was built with (the linear solver asked for, the ordering).
    pub options: SystemOptions,
    /// Time of the symbolic factorisation, seconds.
    pub symbolic_seconds: f64,
    /// Time to build everything here, seconds.
    pub setup_seconds: f64,
}

impl<'a, M: SolveMesh<D> + ?Sized, const D: usize> SymbolicSystem<'a, M, D> {
    /// Builds the symbolic system of `scheme`.
    pub fn new(
        scheme: &'a dyn GradientDiscretisation<M, D>,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let dof_map = DofMap::new(scheme)?;
        dof_map.check_setup_memory(options.budget)?;
        Self::with_dof_map(scheme, Arc::new(dof_map), options)
    }

    /// As [`SymbolicSystem::new`], from the dof map of `scheme`.
    pub fn with_dof_map(
        scheme: &'a dyn GradientDiscretisation<M, D>,
        dof_map: Arc<DofMap>,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let n_skel = scheme.n_skeleton();
        let n = scheme.n_unknowns();
        if dof_map.dofs.len() >= u32::MAX as usize {
            return Err(crate::Error::Linear("more than 2^32 local unknowns".into()));
        }
        // unknown -> the cells where it appears, ascending
        let inc = incidence(&dof_map, n)?;
        let no_interior = dof_map.n_int.iter().all(|&ni| ni == 0);
        let (col_ptr, row_idx) = condensed_pattern(&dof_map, n_skel, &inc)?;
        let direct = match options.linear {
            LinearSolver::Direct => true,
            LinearSolver::Iterative => false,
            LinearSolver::Auto => n_skel < auto_iterative_min(D),
        };
        let single_interior = dof_map.n_int.iter().all(|&ni| ni == 1);
        // direct solves that will likely take the cell system: no skeleton factorisation now
        let deferred = direct && single_interior && likely_cell_system(scheme.mesh());
        // the symbolic factorisation (sequential) runs beside the scatter maps, on a copy of
        // the pattern; without it the pattern is moved in first and read by the maps (no
        // copy: 40 MB less at the peak of the setup at 1M P1 unknowns)
        let (symbolic, maps) = if direct && !deferred {
            rayon::join(
                || {
                    let t = Instant::now();
                    SpdPattern::with_ordering(
                        n_skel,
                        try_copy(&col_ptr, "the column offsets of the condensed matrix")?,
                        try_copy(&row_idx, "the pattern of the condensed matrix")?,
                        options.ordering,
                    )
                    .map(|p| (p, t.elapsed().as_secs_f64()))
                },
                || scatter_maps(&dof_map, inc, &col_ptr, &row_idx, !no_interior, true),
            )
        } else {
            match SpdPattern::without_factorisation(n_skel, col_ptr, row_idx) {
                Ok(p) => {
                    // the gather sources only if a solve gathers (see the module docs)
                    let maps =
                        scatter_maps(&dof_map, inc, p.col_ptr(), p.row_idx(), !no_interior, false);
                    (Ok((p, 0.0)), maps)
                }
                Err(e) => (Err(e), Err(crate::Error::Linear("no pattern".into()))),
            }
        };
        let symbolic = symbolic.map(|(p, t)| (p.with_threads(options.factor_threads), t));
        let (pattern, symbolic_seconds) = symbolic?;
        let maps = maps?;
        check_numeric_memory(&pattern, &maps, n, options.budget)?;
        let dof_map = if no_interior {
            Arc::new(DofMap::empty())
        } else {
            dof_map
        };
        Ok(SymbolicSystem {
            scheme,
            dof_map,
            nnz: pattern.nnz(),
            pattern: Some(pattern),
            maps,
            single_interior,
            no_interior,
            deferred,
            options,
            symbolic_seconds,
            setup_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The scheme.
    pub fn scheme(&self) -> &'a dyn GradientDiscretisation<M, D> {
        self.scheme
    }
    /// Number of unknowns (skeleton and interior).
    pub fn n_unknowns(&self) -> usize {
        self.scheme.n_unknowns()
    }
    /// Size of the condensed system (the skeleton unknowns).
    pub fn n_condensed(&self) -> usize {
        self.scheme.n_skeleton()
    }
    /// The pattern of the condensed matrix and its symbolic factorisation (`None` once
    /// released: [`SymbolicSystem::release_pattern`]).
    pub fn pattern(&self) -> Option<&SpdPattern> {
        self.pattern.as_ref()
    }
    /// Stored entries of the condensed matrix (lower triangle).
    pub fn nnz(&self) -> usize {
        self.nnz
    }
    /// Stored values of the Cholesky factor of the condensed matrix (0 without one).
    pub fn factor_len(&self) -> usize {
        self.pattern.as_ref().map_or(0, SpdPattern::factor_len)
    }
    /// Whether the symbolic factorisation was computed (the solves are direct).
    pub fn has_factorisation(&self) -> bool {
        self.pattern
            .as_ref()
            .is_some_and(SpdPattern::has_factorisation)
    }
    /// Whether the solves are direct: the symbolic factorisation was computed, or it is
    /// deferred to the first solve that needs it (HMM on boxes: see the module docs).
    pub fn is_direct(&self) -> bool {
        self.deferred || self.has_factorisation()
    }
    /// The kept pattern, or an internal error naming `what` needed it.
    pub(super) fn kept_pattern(&self, what: &str) -> crate::Result<&SpdPattern> {
        self.pattern.as_ref().ok_or_else(|| {
            crate::Error::Internal(format!("{what}: the condensed pattern was released"))
        })
    }
    /// Frees the pattern of a system without interior unknowns solved iteratively, once its
    /// matrix is assembled: the solves read the assembled matrix only (the lower pattern is
    /// 40 bytes per P1 unknown on triangles; `replication/measurements/memory2d.md`). What
    /// needs the pattern afterwards (the assembly of another problem on this system, the
    /// direct solver taking over from a failed iterative one) builds it again from the
    /// scheme. Other systems keep it.
    pub fn release_pattern(&mut self) {
        if self.no_interior && !self.has_factorisation() {
            self.pattern = None;
        }
    }
    /// The lower CSC pattern (column pointers, row indices) of the condensed matrix, built
    /// again from the dof map `dm` of the scheme ([`condensed_pattern`]; for a released one).
    pub(super) fn rebuild_pattern(&self, dm: &DofMap) -> crate::Result<(Vec<usize>, Vec<usize>)> {
        let inc = incidence(dm, self.n_unknowns())?;
        condensed_pattern(dm, self.n_condensed(), &inc)
    }
}

/// The memory, in bytes, the numeric phase will allocate for `n` unknowns: the Cholesky
/// factor (whose size the symbolic factorisation has computed), the condensed values, the
/// condensation and residual buffers and a few vectors of unknowns.
fn numeric_bytes(pattern: &SpdPattern, maps: &ScatterMaps, n: usize) -> u64 {
    8 * (pattern.factor_len() as u64)
        + 8 * (pattern.nnz() as u64)
        + 8 * (maps.block_ptr.total() as u64)
        + 24 * (maps.inc.items.len() as u64)
        + 8 * 6 * (n as u64)
}

/// [`numeric_bytes`] checked against the caller's `budget` before anything is allocated: a
/// typed error with the estimate instead of an abort.
pub(super) fn check_numeric_memory(
    pattern: &SpdPattern,
    maps: &ScatterMaps,
    n: usize,
    budget: MemoryBudget,
) -> crate::Result<()> {
    budget.check_computation(
        format!(
            "the numeric factorisation (a Cholesky factor of {} entries)",
            pattern.factor_len()
        ),
        numeric_bytes(pattern, maps, n),
    )
}

/// For each of the `n` unknowns, the cells where it appears, ascending (a counting sort of the
/// positions of `dofs`, each stored as its cell).
fn incidence(dm: &DofMap, n: usize) -> crate::Result<Ragged<u32>> {
    let mut cell_of = try_filled(dm.dofs.len(), 0u32, "the cells of the local unknowns")?;
    let ranges = cell_chunks(dm.n_cells());
    let slices = split_by_ranges(&mut cell_of, &ranges, |k| dm.dof_ptr.at(k));
    ranges
        .into_par_iter()
        .zip(slices)
        .for_each(|((c0, c1), out)| {
            let base = dm.dof_ptr.at(c0);
            for k in c0..c1 {
                out[dm.dof_ptr.at(k) - base..dm.dof_ptr.at(k + 1) - base].fill(k as u32);
            }
        });
    let (ptr, items) = crate::mesh::buckets::try_par_counting_sort(
        n,
        dm.dofs.len(),
        |i| Some(dm.dofs[i] as usize),
        |i| cell_of[i],
    )?;
    Ragged::new(ptr, items)
}

/// The lower-triangular CSC pattern (column pointers, row indices) of the condensed matrix:
/// column c holds c itself (every unknown has a diagonal, even if isolated) and the skeleton
/// unknowns r > c of the cells where c appears (`inc`), sorted. Columns are built in parallel chunks.
fn condensed_pattern(
    dm: &DofMap,
    n_skel: usize,
    inc: &Ragged<u32>,
) -> crate::Result<(Vec<usize>, Vec<usize>)> {
    type Columns = (Vec<usize>, Vec<usize>);
    let columns: crate::Result<Vec<Columns>> = chunks(n_skel, 1 << 14)
        .into_par_iter()
        .map(|(c0, c1)| {
            let what = "the pattern of the condensed matrix";
            let (mut counts, mut rows) = (try_vec(c1 - c0, what)?, Vec::new());
            for c in c0..c1 {
                let start = rows.len();
                try_grow(&mut rows, 1, what)?;
                rows.push(c);
                for &k in inc.list(c) {
                    let k = k as usize;
                    try_grow(&mut rows, dm.skeleton(k).len(), what)?;
                    rows.extend(
                        dm.skeleton(k)
                            .iter()
                            .map(|&r| r as usize)
                            .filter(|&r| r > c),
                    );
                }
                rows[start..].sort_unstable();
                let mut w = start;
                for i in start..rows.len() {
                    if i == start || rows[i] != rows[w - 1] {
                        rows[w] = rows[i];
                        w += 1;
                    }
                }
                rows.truncate(w);
                counts.push(w - start);
            }
            Ok((counts, rows))
        })
        .collect();
    let columns = columns?;
    let mut col_ptr = try_vec(n_skel + 1, "the column offsets of the condensed matrix")?;
    col_ptr.push(0);
    let nnz = columns.iter().map(|c| c.1.len()).sum();
    let mut row_idx = try_vec(nnz, "the pattern of the condensed matrix")?;
    for (counts, rows) in columns {
        for n in counts {
            col_ptr.push(col_ptr.last().copied().unwrap_or(0) + n);
        }
        row_idx.extend_from_slice(&rows);
    }
    if row_idx.len() >= u32::MAX as usize {
        return Err(crate::Error::Linear(
            "the condensed matrix has more than 2^32 entries".into(),
        ));
    }
    Ok((col_ptr, row_idx))
}

/// The buckets of a counting sort of the items `0..n_items`: item i goes to bucket `key(i)`,
/// buckets ascending, items ascending within a bucket (in parallel, the same result). Items
/// are below 2^32 (checked by the caller).
fn counting_sort(
    n_buckets: usize,
    n_items: usize,
    key: impl Fn(usize) -> usize + Sync,
) -> crate::Result<Ragged<u32>> {
    let (ptr, items) = crate::mesh::buckets::try_par_counting_sort(
        n_buckets,
        n_items,
        |i| Some(key(i)),
        |i| i as u32,
    )?;
    Ragged::new(ptr, items)
}

/// The scatter and gather maps (see the module docs): without `interior` unknowns only the
/// offsets of the blocks (the global matrix is assembled on the pattern: no gather, no
/// incidences); with them the incidences, and the gather sources if `gather` now.
fn scatter_maps(
    dm: &DofMap,
    inc: Ragged<u32>,
    col_ptr: &[usize],
    row_idx: &[usize],
    interior: bool,
    gather: bool,
) -> crate::Result<ScatterMaps> {
    let nc = dm.n_cells();
    let block_ptr =
        Offsets::from_lengths((0..nc).map(|k| super::condense::packed_len(dm.skeleton(k).len())))?;
    if dm.dofs.len() >= u32::MAX as usize {
        return Err(crate::Error::Linear(
            "more than 2^32 local skeleton entries".into(),
        ));
    }
    if !interior {
        drop(inc);
        return Ok(ScatterMaps {
            block_ptr,
            src: None,
            inc: Ragged::new(vec![0], Vec::new())?,
        });
    }
    let src = if gather {
        Some(gather_sources(dm, &block_ptr, col_ptr, row_idx)?)
    } else {
        None
    };
    Ok(ScatterMaps {
        block_ptr,
        src,
        inc,
    })
}

/// [`ScatterMaps::src`]: per entry of the lower pattern (`col_ptr`, `row_idx`) of the condensed
/// matrix, the local entries landing on it, as positions in a buffer of the cells' packed
/// blocks laid out by `block_ptr`, in cell order.
pub(super) fn gather_sources(
    dm: &DofMap,
    block_ptr: &Offsets,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> crate::Result<Ragged<u32>> {
    let nc = dm.n_cells();
    let find = |r: usize, c: usize| -> u32 {
        let s = &row_idx[col_ptr[c]..col_ptr[c + 1]];
        (col_ptr[c] + s.binary_search(&r).expect("entry is in the pattern")) as u32
    };
    // the packed lower triangle of each block (column b, rows a ≥ b, local indices): the
    // entry lands on the condensed entry (max, min) of its two unknowns
    let mut pos: Vec<u32> = try_vec(block_ptr.total(), "the scatter positions")?;
    pos.par_extend(cell_chunks(nc).into_par_iter().flat_map_iter(|(c0, c1)| {
        let mut out = Vec::with_capacity(block_ptr.at(c1) - block_ptr.at(c0));
        for k in c0..c1 {
            let sk = dm.skeleton(k);
            for (b, &j) in sk.iter().enumerate() {
                for &i in &sk[b..] {
                    let (i, j) = (i as usize, j as usize);
                    out.push(find(i.max(j), i.min(j)));
                }
            }
        }
        out
    }));
    // condensed entry -> the local entries landing on it, in cell order
    counting_sort(row_idx.len(), pos.len(), |i| pos[i] as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::DiscreteSystem;
    use crate::mesh::generate::cartesian;
    use crate::problem::paper_test3;
    use crate::scheme::Hmm;

    fn within(budget: MemoryBudget) -> SystemOptions {
        SystemOptions {
            budget,
            ..Default::default()
        }
    }

    fn is_budget_error(e: &crate::Error) -> bool {
        matches!(e, crate::Error::OutOfMemory { .. })
    }

    /// The budget is the caller's: the same system passes with a large budget and is refused
    /// with a tiny one, whatever memory the machine has free.
    #[test]
    fn the_setup_is_checked_against_the_callers_budget() {
        let mesh = cartesian(8, 8).unwrap();
        let hmm = Hmm::new(&mesh);
        let large = MemoryBudget::new(u64::MAX);
        assert!(SymbolicSystem::new(&hmm, within(large)).is_ok());
        let tiny = MemoryBudget::new(1024);
        let e = SymbolicSystem::new(&hmm, within(tiny)).err().unwrap();
        assert!(is_budget_error(&e), "{e}");
        let p = paper_test3(1.0);
        assert!(DiscreteSystem::new(&hmm, &p, within(large)).is_ok());
        let e = DiscreteSystem::new(&hmm, &p, within(tiny)).err().unwrap();
        assert!(is_budget_error(&e), "{e}");
        // the setup estimate itself is the bound
        let dm = DofMap::new(&hmm).unwrap();
        let setup = dm.setup_bytes();
        assert!(dm.check_setup_memory(MemoryBudget::new(setup)).is_ok());
        let e = dm
            .check_setup_memory(MemoryBudget::new(setup - 1))
            .unwrap_err();
        assert!(is_budget_error(&e), "{e}");
    }

    /// Without interior unknowns (P1) the setup estimate charges no local matrices, scatter
    /// positions or gather sources; with them (HMM) it does.
    #[test]
    fn the_setup_estimate_charges_local_matrices_only_where_they_are_stored() {
        let tri = crate::mesh::generate::cartesian_triangles(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let p1 = crate::scheme::P1::new(&tri).unwrap();
        let dm = DofMap::new(&p1).unwrap();
        // 128 triangles of 3 unknowns (6 entries in each lower triangle), 81 vertices
        let (local, lower, n) = (128 * 3, 128 * 6, 81);
        let setup = dm.setup_bytes();
        assert_eq!(setup, 8 * local + 16 * lower + 80 * n);
        assert!(setup < 32 * 128 * 9 + 64 * local);
        assert!(dm.check_setup_memory(MemoryBudget::new(setup)).is_ok());
        let e = dm
            .check_setup_memory(MemoryBudget::new(setup - 1))
            .unwrap_err();
        assert!(is_budget_error(&e), "{e}");
        // HMM on 8 × 8 squares: 64 cells of 5 unknowns (the cell and its 4 edges)
        let mesh = cartesian(8, 8).unwrap();
        let dm = DofMap::new(&Hmm::new(&mesh)).unwrap();
        assert_eq!(dm.setup_bytes(), 32 * 64 * 25 + 64 * 64 * 5);
    }

    /// The numeric phase is refused one byte below its estimate and accepted at it.
    #[test]
    fn the_numeric_phase_is_checked_against_the_callers_budget() {
        let mesh = cartesian(8, 8).unwrap();
        let hmm = Hmm::new(&mesh);
        let sym = SymbolicSystem::new(&hmm, Default::default()).unwrap();
        let n = hmm.n_unknowns();
        let pattern = sym.pattern().unwrap();
        let bytes = numeric_bytes(pattern, &sym.maps, n);
        let at = MemoryBudget::new(bytes);
        assert!(check_numeric_memory(pattern, &sym.maps, n, at).is_ok());
        let below = MemoryBudget::new(bytes - 1);
        let e = check_numeric_memory(pattern, &sym.maps, n, below).unwrap_err();
        assert!(is_budget_error(&e), "{e}");
    }

    /// [`LinearSolver::Auto`] picks the solver by size and dimension: a 3D face system from
    /// `AUTO_ITERATIVE_MIN_3D` unknowns on is solved iteratively (no symbolic factorisation),
    /// one below directly, and a planar one of the same size still directly (it is below
    /// `AUTO_ITERATIVE_MIN`).
    #[test]
    fn auto_switches_to_the_iterative_solver_earlier_in_3d() {
        use crate::assembly::{AUTO_ITERATIVE_MIN, AUTO_ITERATIVE_MIN_3D};
        use crate::mesh3d::generate::kuhn;
        use crate::mesh3d::{Cuboid, PolyMesh3};
        let budget = MemoryBudget::DEFAULT;
        let tets =
            |n| PolyMesh3::from_polyhedra(kuhn(n, Cuboid::UNIT, budget).unwrap(), budget).unwrap();
        let (small, large) = (tets(8), tets(16));
        for (m, direct) in [(&small, true), (&large, false)] {
            let hmm = Hmm::<PolyMesh3, 3>::with_alpha(m, 1.0).unwrap();
            assert_eq!(hmm.n_skeleton() < AUTO_ITERATIVE_MIN_3D, direct);
            let sym = SymbolicSystem::new(&hmm, Default::default()).unwrap();
            assert_eq!(sym.has_factorisation(), direct, "{}", hmm.n_skeleton());
        }
        let mesh = cartesian(100, 100).unwrap();
        let hmm = Hmm::new(&mesh);
        let n = hmm.n_skeleton();
        assert!(
            (AUTO_ITERATIVE_MIN_3D..AUTO_ITERATIVE_MIN).contains(&n),
            "{n}"
        );
        let sym = SymbolicSystem::new(&hmm, Default::default()).unwrap();
        assert!(sym.is_direct());
    }

    /// Direct HMM solves on axis-aligned boxes (2D and 3D) defer the symbolic factorisation
    /// of the skeleton system, which their cell system makes useless; on meshes of other
    /// cells (Kershaw quadrilaterals, triangles, warped hexahedra), for P1, and for iterative
    /// solves, it is computed now or never, as before.
    #[test]
    fn the_skeleton_factorisation_is_deferred_on_boxes_only() {
        use crate::mesh::generate::{cartesian_triangles, kershaw};
        use crate::mesh3d::generate::{cubes, warped};
        use crate::mesh3d::{Cuboid, PolyMesh3};
        use crate::scheme::P1;
        let direct = SystemOptions {
            linear: LinearSolver::Direct,
            ..Default::default()
        };
        let iterative = SystemOptions {
            linear: LinearSolver::Iterative,
            ..Default::default()
        };
        // (is_direct, has_factorisation) of a symbolic system
        let state = |s: &SymbolicSystem<'_, _, 2>| (s.is_direct(), s.has_factorisation());
        let boxes = cartesian(12, 7).unwrap();
        let hmm = Hmm::new(&boxes);
        let deferred = SymbolicSystem::new(&hmm, direct).unwrap();
        assert_eq!(state(&deferred), (true, false));
        assert_eq!(
            state(&SymbolicSystem::new(&hmm, iterative).unwrap()),
            (false, false)
        );
        for mesh in [
            kershaw(1).unwrap(),
            cartesian_triangles(6, 6, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        ] {
            let hmm = Hmm::new(&mesh);
            let s = SymbolicSystem::new(&hmm, direct).unwrap();
            assert_eq!(state(&s), (true, true));
        }
        let tri = cartesian_triangles(6, 6, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let p1 = P1::new(&tri).unwrap();
        assert_eq!(
            state(&SymbolicSystem::new(&p1, direct).unwrap()),
            (true, true)
        );
        let budget = MemoryBudget::DEFAULT;
        for (cells, deferred) in [
            (cubes(4, Cuboid::UNIT, budget).unwrap(), true),
            (warped(4, Cuboid::UNIT, 7, budget).unwrap(), false),
        ] {
            let mesh = PolyMesh3::from_polyhedra(cells, budget).unwrap();
            let hmm = Hmm::<PolyMesh3, 3>::with_alpha(&mesh, 1.0).unwrap();
            let s = SymbolicSystem::new(&hmm, direct).unwrap();
            assert_eq!((s.is_direct(), s.has_factorisation()), (true, !deferred));
        }
    }
}
