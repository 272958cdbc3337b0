//! Assembly of the condensed (skeleton) system with some unknowns fixed: every cell condensed
//! in parallel, then the global values *gathered* entry by entry (each entry of the condensed
//! matrix and each right-hand-side row knows its contributions, listed in cell order) instead
//! of scattered, so that the sums do not depend on the number of threads.

use super::condense::{self, condense};
use super::symbolic::{Ragged, gather_sources};
use super::{DiscreteSystem, SolveState};
use crate::budget::{try_filled, try_resize};
use crate::mesh::SolveMesh;
use crate::vi::FixedValues;
use rayon::prelude::*;

/// Cells per parallel task in the cell loops (large enough to amortise the task, small enough
/// to balance two or more threads).
pub(super) const CHUNK: usize = 4096;

/// The cell ranges `[c0, c1)` of the parallel tasks.
pub(super) fn cell_chunks(nc: usize) -> Vec<(usize, usize)> {
    chunks(nc, CHUNK)
}

/// The ranges `[c0, c1)` of `size` consecutive indices (the last one shorter) covering `0..n`.
pub(super) fn chunks(n: usize, size: usize) -> Vec<(usize, usize)> {
    (0..n.div_ceil(size))
        .map(|c| (c * size, ((c + 1) * size).min(n)))
        .collect()
}

/// Rows (or items) per parallel task of the row-by-row gathers.
pub(super) const PAR_ROWS: usize = 4096;

/// `f(i)` for every i in `0..n`, computed in parallel (at least 4096 per task) into a vector
/// allocated fallibly ([`try_filled`], `what` naming it); an error of `f` is returned instead
/// (one of them if several). Each value is computed on its own: the same whatever the threads.
pub(super) fn par_try_fill<T: Clone + Default + Send + 'static>(
    n: usize,
    what: &str,
    f: impl Fn(usize) -> crate::Result<T> + Sync,
) -> crate::Result<Vec<T>> {
    let mut v = try_filled(n, T::default(), what)?;
    // fallible per chunk rather than per item: rayon's try_for_each moves its error-carrying
    // state through every item it consumes
    v.par_chunks_mut(PAR_ROWS)
        .enumerate()
        .try_for_each(|(c, chunk)| {
            for (o, out) in chunk.iter_mut().enumerate() {
                *out = f(c * PAR_ROWS + o)?;
            }
            Ok::<(), crate::Error>(())
        })?;
    Ok(v)
}

/// Splits a buffer laid out by the offsets `ptr` (entity e owns `ptr(e)..ptr(e + 1)`, relative to
/// `ptr(ranges[0].0)`) into the consecutive slices of the entity `ranges`, so that each
/// parallel task writes its own slice.
pub(super) fn split_by_ranges<'b, T>(
    mut buf: &'b mut [T],
    ranges: &[(usize, usize)],
    ptr: impl Fn(usize) -> usize,
) -> Vec<&'b mut [T]> {
    let mut slices = Vec::with_capacity(ranges.len());
    for &(c0, c1) in ranges {
        let (here, next) = std::mem::take(&mut buf).split_at_mut(ptr(c1) - ptr(c0));
        buf = next;
        slices.push(here);
    }
    slices
}

/// The position of unknown `g` among the unknowns `d` of a cell where it appears. The
/// incidence maps of the symbolic system list, for each unknown, only cells that have it, so
/// an error here means that the symbolic system and the values disagree (a bug), reported
/// instead of reading another unknown's entry.
#[inline]
pub(super) fn local_index(d: &[u32], g: usize) -> crate::Result<usize> {
    d.iter().position(|&x| x as usize == g).ok_or_else(|| {
        crate::Error::Internal(format!(
            "unknown {g} is listed in a cell whose unknowns are {d:?}"
        ))
    })
}

/// The value of each fixed unknown: a Dirichlet one (its Dirichlet value first), or one fixed
/// by the caller. Two views, no third array of the order of the system.
#[derive(Clone, Copy)]
pub(super) struct Pinned<'a> {
    dirichlet: &'a FixedValues,
    fixed: &'a FixedValues,
}

impl<'a> Pinned<'a> {
    pub(super) fn new(dirichlet: &'a FixedValues, fixed: &'a FixedValues) -> Self {
        Pinned { dirichlet, fixed }
    }
    /// The value of unknown `d` if it is fixed.
    #[inline]
    pub(super) fn get(&self, d: usize) -> Option<f64> {
        self.dirichlet.get(d).or_else(|| self.fixed.get(d))
    }
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// The lower-triangular CSC pattern (column pointers, row indices) of the condensed
    /// matrix; `None` for a system without interior unknowns solved iteratively, which keeps
    /// its assembled matrix only
    /// ([`SymbolicSystem::release_pattern`](super::SymbolicSystem::release_pattern)).
    pub fn condensed_pattern(&self) -> Option<(&[usize], &[usize])> {
        self.sym.pattern().map(|p| (p.col_ptr(), p.row_idx()))
    }

    /// Condensed matrix values (in the order of [`Self::condensed_pattern`]) and right-hand
    /// side, with `fixed` and the Dirichlet unknowns fixed (unit rows). The condensation
    /// buffers are kept in `state` for the next call.
    ///
    /// With P_K the map from the global skeleton unknowns to those of cell K, and F the fixed
    /// unknowns (value u_F),
    ///
    ///   S_ij = Σ_K (P_Kᵀ S_K P_K)_ij            for i, j ∉ F,   S_ii = 1 and S_ij = 0 else,
    ///   c_i  = b^N_i + Σ_K (P_Kᵀ (g_K − S_K P_K u_F))_i   for i ∉ F,   c_i = u_i for i ∈ F,
    ///
    /// where b^N is the Neumann load and (S_K, g_K) the condensed block and load of cell K
    /// ([`condense()`]). Then S u_S = c is the skeleton system with u_F moved to the right.
    ///
    /// [`Error::InvalidData`](crate::Error::InvalidData) for a system whose pattern was
    /// released ([`Self::condensed_pattern`] is `None`).
    pub fn assemble_condensed(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        self.bind(state);
        let fixed = self.fixed_values(fixed);
        // without interior unknowns, S and c are masked from the global matrix
        if let Some(a) = self.assembled() {
            let pattern = self.sym.pattern().ok_or_else(|| {
                crate::Error::InvalidData(
                    "assemble_condensed: this system keeps no condensed pattern (a P1 or CR \
                     system built by DiscreteSystem::new for an iterative solve releases it); \
                     build it with DiscreteSystem::with_symbolic on a SymbolicSystem::new"
                        .into(),
                )
            })?;
            return Ok((
                self.masked_lower(a, &fixed, pattern)?,
                self.masked_rhs(a, &fixed)?,
            ));
        }
        // the gather sources, built by the first gather if the symbolic system has none
        if self.sym.maps.src.is_none() && state.sources.is_none() {
            let p = self.sym.kept_pattern("the gather sources")?;
            state.sources = Some(gather_sources(
                &self.sym.dof_map,
                &self.sym.maps.block_ptr,
                p.col_ptr(),
                p.row_idx(),
            )?);
        }
        let SolveState {
            scratch: (sbuf, gbuf),
            sources,
            ..
        } = state;
        let src = (self.sym.maps.src.as_ref().or(sources.as_ref()))
            .ok_or_else(|| crate::Error::Internal("the gather sources were not built".into()))?;
        // buffers kept between calls (they are entirely rewritten where read)
        let (blocks, local) = (self.sym.maps.block_ptr.total(), self.sym.dof_map.dofs.len());
        try_resize(sbuf, blocks, 0.0, "the condensed blocks")?;
        try_resize(gbuf, local, 0.0, "the condensed loads")?;
        self.condense_cells(&fixed, sbuf, gbuf)?;
        let values = self.gather_matrix(&fixed, src, sbuf)?;
        let dof_ptr = &self.sym.dof_map.dof_ptr;
        let rhs = self.gather_rhs(&fixed, |k, i| gbuf[dof_ptr.at(k) + i])?;
        Ok((values, rhs))
    }

    /// Condenses every cell (some with interior unknowns), in parallel: cell k's p×p block
    /// S_K at `block_ptr[k]` in `sbuf`, and its right-hand side g_K − S_K P_K u_F (its
    /// condensed load minus the columns of its fixed skeleton unknowns) at the positions of
    /// its skeleton unknowns in `gbuf` (laid out like `dofs`). The first failure in cell order
    /// is returned.
    fn condense_cells(
        &self,
        fixed: &Pinned,
        sbuf: &mut [f64],
        gbuf: &mut [f64],
    ) -> crate::Result<()> {
        let dof_ptr = &self.sym.dof_map.dof_ptr;
        let ranges = cell_chunks(self.sym.scheme().mesh().n_cells());
        let g_slices = split_by_ranges(gbuf, &ranges, |k| dof_ptr.at(k));
        let block_ptr = &self.sym.maps.block_ptr;
        let s_slices = split_by_ranges(sbuf, &ranges, |k| block_ptr.at(k));
        let tasks: Vec<_> = ranges.into_iter().zip(s_slices).zip(g_slices).collect();
        let results: Vec<crate::Result<()>> = tasks
            .into_par_iter()
            .map(|(((c0, c1), s), g)| {
                let mut full = Vec::new();
                for k in c0..c1 {
                    let (so, go) = (
                        block_ptr.at(k) - block_ptr.at(c0),
                        dof_ptr.at(k) - dof_ptr.at(c0),
                    );
                    self.condense_cell(k, fixed, &mut full, &mut s[so..], &mut g[go..])?;
                }
                Ok(())
            })
            .collect();
        results.into_iter().collect()
    }

    /// Condenses cell k: its block S_K, packed ([`condense::packed_index`]), into the first p(p + 1)/2
    /// entries of `s`, and its right-hand side g_K − S_K P_K u_F into `g` after its `ni`
    /// interior entries (the cell's stretch of a buffer laid out like `dofs` starts at `g`).
    /// `full` is scratch for the whole p × p block.
    fn condense_cell(
        &self,
        k: usize,
        fixed: &Pinned,
        full: &mut Vec<f64>,
        s: &mut [f64],
        g: &mut [f64],
    ) -> crate::Result<()> {
        let fx = |d: usize| fixed.get(d);
        let cell = self.local(k);
        let (d, ni) = (cell.dofs, cell.n_interior);
        let p = d.len() - ni;
        full.resize(p * p, 0.0);
        let sk = &mut full[..];
        let gk = &mut g[ni..ni + p];
        condense(&cell, &fx, sk, gk).map_err(|e| e.in_cell(k))?;
        // g_K −= S_K P_K u_F, column by column
        for bcol in 0..p {
            if let Some(vj) = fx(d[ni + bcol] as usize) {
                for arow in 0..p {
                    gk[arow] -= sk[arow + bcol * p] * vj;
                }
            }
        }
        condense::pack_lower(p, sk, s);
        Ok(())
    }

    /// The values of the condensed matrix, gathered entry by entry (column by column in
    /// parallel): entry q is the sum of its sources `src.list(q)` in
    /// `blocks` (the condensed blocks), listed in cell
    /// order (the order of a sequential scatter, whatever the number of
    /// threads); zero in the rows and columns of fixed unknowns, whose diagonal is 1.
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory) if the values cannot be allocated.
    fn gather_matrix(
        &self,
        fixed: &Pinned,
        src: &Ragged<u32>,
        blocks: &[f64],
    ) -> crate::Result<Vec<f64>> {
        let pattern = self.sym.kept_pattern("the gathered matrix")?;
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let is_fixed: Vec<bool> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| fixed.get(d).is_some())
            .collect();
        let nnz = pattern.nnz();
        let mut values = try_filled(nnz, 0.0, "the values of the condensed matrix")?;
        let ranges = chunks(self.n_skel, CHUNK * 4);
        let slices = split_by_ranges(&mut values, &ranges, |k| col_ptr[k]);
        let tasks: Vec<_> = ranges.into_iter().zip(slices).collect();
        tasks.into_par_iter().for_each(|((c0, c1), out)| {
            let base = col_ptr[c0];
            for c in c0..c1 {
                let col_fixed = is_fixed[c];
                for q in col_ptr[c]..col_ptr[c + 1] {
                    let r = row_idx[q];
                    out[q - base] = if col_fixed || is_fixed[r] {
                        if r == c { 1.0 } else { 0.0 }
                    } else {
                        let mut v = 0.0;
                        for &i in src.list(q) {
                            v += blocks[i as usize];
                        }
                        v
                    };
                }
            }
        });
        Ok(values)
    }

    /// The right-hand side of the condensed system, gathered row by row: the Neumann load plus
    /// the contributions `cell_value(k, local index)` of the cells k of `inc.list(i)` (in cell
    /// order); the value on fixed rows.
    fn gather_rhs(
        &self,
        fixed: &Pinned,
        cell_value: impl Fn(usize, usize) -> f64 + Sync,
    ) -> crate::Result<Vec<f64>> {
        let inc = &self.sym.maps.inc;
        par_try_fill(self.n_skel, "the right-hand side", |gi| {
            Ok(match fixed.get(gi) {
                Some(v) => v,
                None => {
                    let mut acc = self.values.neumann_load.get(gi).copied().unwrap_or(0.0);
                    for &k in inc.list(gi) {
                        let k = k as usize;
                        let (d, _) = self.sym.dof_map.cell(k);
                        acc += cell_value(k, local_index(d, gi)?);
                    }
                    acc
                }
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_index_finds_the_position_and_refuses_a_missing_unknown() {
        assert_eq!(local_index(&[7, 3, 5], 5).unwrap(), 2);
        // an unknown that is not among the cell's: a typed error, never position 0
        let e = local_index(&[7, 3, 5], 4).unwrap_err();
        assert!(matches!(e, crate::Error::Internal(_)), "{e}");
        assert!(e.to_string().contains("unknown 4"), "{e}");
    }

    #[test]
    fn chunks_cover_the_range_in_order() {
        assert_eq!(chunks(10, 4), vec![(0, 4), (4, 8), (8, 10)]);
        assert!(chunks(0, 4).is_empty());
        let mut buf = [0, 1, 2, 3, 4, 5];
        let s = split_by_ranges(&mut buf, &[(0, 1), (1, 3)], |k| 2 * k);
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].len(), s[1].len()), (2, 4));
    }

    #[test]
    fn fixed_values_take_dirichlet_first() {
        let d = FixedValues::from_options([Some(1.0), None, None]).unwrap();
        let x = FixedValues::from_options([Some(2.0), Some(3.0), None]).unwrap();
        let f = Pinned::new(&d, &x);
        assert_eq!((f.get(0), f.get(1), f.get(2)), (Some(1.0), Some(3.0), None));
    }
}
