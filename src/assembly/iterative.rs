//! The iterative solves: multigrid-preconditioned conjugate gradients on the condensed (or
//! cell) system, started from the previous solution, with the hierarchy of the previous solve
//! reused while it stays good ([`super::linear::REUSE_MAX_CHANGED`],
//! [`super::linear::REUSE_MAX_SLOWDOWN`]) and, on planar meshes, corrected by exact solves on a
//! patch around the unknowns whose status changed since it was built
//! ([`super::linear::PATCH_LAYERS`], [`crate::linalg::PatchCorrected`]). Everything carried
//! from one solve to the next lives in the caller's [`SolveState`].
//!
//! What is reused (`Reused`): the coarse levels, the fine level built again for the new
//! matrix; or, for the systems of an assembled matrix (P1, Crouzeix–Raviart: the fine matrix is
//! a masked view of M, [`crate::linalg::MaskedRows`]), the whole hierarchy, whose view and fine
//! smoother are then remade in the rows that the unknowns whose status changed touch
//! ([`crate::linalg::MaskedRows::remask`], [`Amg::with_changed_fine`]): the same view and the
//! same hierarchy, bit for bit, without a pass over M (measured in
//! `replication/measurements/solver.md`).

use super::linear::{
    ITERATIVE_MAX_ITER, ITERATIVE_RTOL, PATCH_MAX_FRACTION, REUSE_MAX_CHANGED_UNPATCHED,
    REUSE_MAX_SLOWDOWN, SCREENING_REDUCTION, patch_layers, reuse_max_changed,
};
use super::two_point::CellSystemAll;
use super::{DiscreteSystem, DofMap, SolveState};
use crate::budget::{AllocFailure, try_copy, try_filled, try_vec};
use crate::linalg::amg::Fine;
use crate::linalg::{
    Amg, AmgOptions, AmgWork, CoarseHierarchy, CsrMatrix, PatchCorrected, PcgOptions, PcgReport,
    Rows,
};
use crate::mesh::SolveMesh;
use crate::vi::FixedValues;
use crate::vi::SolveTimings;
use std::time::Instant;

/// The multigrid hierarchy of the last iterative solve, kept in the [`SolveState`] until the
/// next solve: to continue that solve ([`DiscreteSystem::refine`]) when it was a screening
/// solve that stopped early, and to precondition the next solve's matrix.
pub(super) struct KeptHierarchy {
    /// The hierarchy (it owns the condensed matrix of that solve, or the patch of its masked
    /// view of the shared M).
    pub(super) amg: Amg<'static>,
    /// For a screening solve that stopped early: the right-hand side c of S x = c and the
    /// [`fingerprint`] of the fixed unknowns.
    pub(super) screened: Option<(Vec<f64>, u64)>,
    /// ln of the mean residual reduction per CG iteration of the first solve with this
    /// hierarchy (negative; `None` if it took no iteration).
    pub(super) fresh_rate: Option<f64>,
    /// The last solve with it converged more than [`REUSE_MAX_SLOWDOWN`] times slower than
    /// that: build a fresh hierarchy for the next solve.
    pub(super) stale: bool,
    /// The fixed unknowns (Dirichlet or fixed by the caller) of the matrix it was built for,
    /// one bit per unknown.
    pub(super) fixed_mask: Vec<u64>,
    /// The fixed unknowns of its fine matrix now, the last solve's (`fixed_mask` for the solve
    /// it was built for, another mask once its coarse levels were reused).
    pub(super) fine_mask: Vec<u64>,
    /// Built for the cell system ([`super::two_point`]), not the skeleton one.
    pub(super) cells: bool,
}

/// One bit per unknown: set where the unknown is fixed (Dirichlet, or by `fixed`).
pub(super) fn fixed_mask(
    dirichlet: &FixedValues,
    fixed: &FixedValues,
) -> Result<Vec<u64>, AllocFailure> {
    let mut mask = try_filled(dirichlet.len().div_ceil(64), 0u64, "the fixed-unknown mask")?;
    for (i, (d, f)) in dirichlet.iter().zip(fixed.iter()).enumerate() {
        if d.is_some() || f.is_some() {
            mask[i / 64] |= 1 << (i % 64);
        }
    }
    Ok(mask)
}

/// What the next iterative solve reuses of the last hierarchy.
pub(super) enum Reused {
    /// Its coarse levels: the fine level is built again for the new matrix
    /// ([`CoarseHierarchy::with_fine`]).
    Coarse(CoarseHierarchy),
    /// All of it, with the fixed unknowns of its fine matrix: a masked view of the shared
    /// assembled matrix ([`crate::linalg::MaskedRows`]), which costs its patch to keep. The
    /// next view is then made from it in the rows the changed unknowns touch
    /// ([`crate::linalg::MaskedRows::remask`]), becoming [`Reused::Rows`].
    Whole {
        amg: Box<Amg<'static>>,
        fine_mask: Vec<u64>,
    },
    /// All of it, and the rows (ascending) in which the new fine matrix differs from its own:
    /// the fine level is updated in those rows only ([`Amg::with_changed_fine`]).
    Rows {
        amg: Box<Amg<'static>>,
        rows: Vec<u32>,
    },
}

/// Where the hierarchy of the next iterative solve comes from.
pub(super) enum NextHierarchy {
    /// Levels of the last one ([`Reused`]), with its [`KeptHierarchy::fresh_rate`] and
    /// [`KeptHierarchy::fixed_mask`].
    Reuse {
        levels: Reused,
        fresh_rate: Option<f64>,
        built_for: Vec<u64>,
        /// The fixed unknowns of this solve (from which the changed rows are found).
        current: Vec<u64>,
    },
    /// A new one, for the matrix with these fixed unknowns.
    New { fixed_mask: Vec<u64> },
}

/// A multigrid hierarchy in use: new, or the coarse levels of an earlier one.
pub(super) struct Hierarchy {
    pub(super) amg: Amg<'static>,
    /// See [`KeptHierarchy::fresh_rate`].
    pub(super) fresh_rate: Option<f64>,
    /// See [`KeptHierarchy::fixed_mask`].
    pub(super) fixed_mask: Vec<u64>,
    /// See [`KeptHierarchy::fine_mask`].
    pub(super) fine_mask: Vec<u64>,
    /// `Some(the fixed unknowns of this solve)`: built for an earlier matrix (its coarse
    /// levels), whose fixed unknowns were `fixed_mask`; `None`: built for this one.
    pub(super) reused: Option<Vec<u64>>,
    /// See [`KeptHierarchy::cells`].
    pub(super) cells: bool,
}

/// The multigrid hierarchy for the matrix `a` (of the cell system if `cells`), as `next` says.
/// A new one frees the cycle's vectors `work` first (sized again by the first cycle).
pub(super) fn hierarchy(
    a: Fine<'static>,
    next: NextHierarchy,
    cells: bool,
    work: &mut AmgWork,
) -> crate::Result<Hierarchy> {
    let opts = AmgOptions::default();
    Ok(match next {
        NextHierarchy::Reuse {
            levels,
            fresh_rate,
            built_for,
            current,
        } => Hierarchy {
            amg: match levels {
                Reused::Coarse(coarse) => coarse.with_fine(a, &opts)?,
                Reused::Rows { amg, rows } => (*amg).with_changed_fine(a, &rows, &opts)?,
                Reused::Whole { amg, .. } => (*amg)
                    .into_coarse()
                    .ok_or_else(|| {
                        crate::Error::Internal("a reused hierarchy without coarse levels".into())
                    })?
                    .with_fine(a, &opts)?,
            },
            fresh_rate,
            fixed_mask: built_for,
            fine_mask: try_copy(&current, "the fixed-unknown mask")?,
            reused: Some(current),
            cells,
        },
        NextHierarchy::New { fixed_mask } => Hierarchy {
            amg: {
                // the setup is the largest transient of a solve: on the live data, not also on
                // the cycle's vectors of the last hierarchy (three vectors of the fine order)
                // or on the holes the previous phases left in the heap (see crate::heap)
                *work = AmgWork::default();
                crate::heap::release_free_pages();
                Amg::build(a, &opts)?
            },
            fresh_rate: None,
            fine_mask: try_copy(&fixed_mask, "the fixed-unknown mask")?,
            fixed_mask,
            reused: None,
            cells,
        },
    })
}

/// The rows of a system of `n_rows` rows whose matrix row changed between the masks `a` and
/// `b` of fixed unknowns: of the cell system `cs`, the rows whose unknown has a different bit;
/// of the skeleton system (row i is unknown i), the skeleton unknowns with a different bit and,
/// with `interior` = (the dof map, the number of skeleton unknowns), the skeleton unknowns of
/// every cell one of whose interior unknowns has a different bit (condensed into them).
fn changed_rows(
    a: &[u64],
    b: &[u64],
    n_rows: usize,
    cs: Option<&CellSystemAll>,
    interior: Option<(&DofMap, usize)>,
) -> Result<Vec<u32>, AllocFailure> {
    let differs = |i: usize| (a[i / 64] ^ b[i / 64]) >> (i % 64) & 1 == 1;
    let mut rows = try_vec(0, "the changed rows")?;
    match cs {
        Some(cs) => rows.extend(
            (0..n_rows)
                .filter(|&i| differs(cs.dof(i)))
                .map(|i| i as u32),
        ),
        None => {
            for (w, (x, y)) in a.iter().zip(b).enumerate() {
                let mut d = x ^ y;
                while d != 0 {
                    let i = w * 64 + d.trailing_zeros() as usize;
                    if i < n_rows {
                        rows.push(i as u32);
                    }
                    d &= d - 1;
                }
            }
            if let Some((map, n_skel)) = interior {
                for k in 0..map.n_cells() {
                    let (dofs, _) = map.cell(k);
                    if dofs
                        .iter()
                        .any(|&j| j as usize >= n_skel && differs(j as usize))
                    {
                        rows.extend(dofs.iter().filter(|&&j| (j as usize) < n_rows));
                    }
                }
            }
        }
    }
    Ok(rows)
}

/// Conjugate gradients on `a` x = c preconditioned by `amg` corrected on the patch of `layers`
/// around `seeds` in `graph` ([`PatchCorrected`]). A patch too large ([`PATCH_MAX_FRACTION`]
/// of the rows, or a Cholesky factor with more entries than `a`: less memory than the new
/// hierarchy the reuse saves) is declined: `amg` then preconditions alone if the seeds are at
/// most [`REUSE_MAX_CHANGED_UNPATCHED`] of the rows, else the result is an error, on which the
/// caller builds a new hierarchy (x untouched).
#[allow(clippy::too_many_arguments)]
fn patched_pcg<A: Rows + ?Sized>(
    a: &A,
    graph: &CsrMatrix,
    amg: &Amg,
    work: &mut AmgWork,
    seeds: &[u32],
    layers: usize,
    c: &[f64],
    x: &mut [f64],
    opts: &PcgOptions,
) -> crate::Result<PcgReport> {
    let max_rows = (PATCH_MAX_FRACTION * a.n_rows() as f64) as usize;
    match PatchCorrected::new(a, amg, graph, seeds, layers, max_rows, a.nnz())? {
        Some(pc) => {
            let mut w = pc.work_with(std::mem::take(work))?;
            let report = crate::linalg::pcg(a, &pc, &mut w, c, x, opts);
            *work = w.into_inner();
            report
        }
        None if seeds.len() as f64 <= REUSE_MAX_CHANGED_UNPATCHED * a.n_rows() as f64 => {
            amg.pcg(work, c, x, opts)
        }
        None => Err(crate::Error::Linear(format!(
            "the patch around {} changed rows is too large to correct a reused hierarchy",
            seeds.len()
        ))),
    }
}

/// Number of unknowns whose bit differs.
fn changed(a: &[u64], b: &[u64]) -> usize {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x ^ y).count_ones() as usize)
        .sum()
}

/// What one run of conjugate gradients did (all zero or false: a direct solve).
#[derive(Default)]
pub(super) struct PcgOutcome {
    pub(super) iterations: usize,
    /// The residual is above [`ITERATIVE_RTOL`] ‖c‖ (a screening solve that stopped early).
    pub(super) inexact: bool,
    /// ln of the mean residual reduction per iteration (`None` without iterations).
    pub(super) rate: Option<f64>,
    /// Preconditioned with the coarse levels of an earlier hierarchy.
    pub(super) reused: bool,
}

impl PcgOutcome {
    /// The timings of a solve that started at `t[0]`, assembled until `t[1]`, set up its
    /// factorisation or hierarchy until `t[2]` and solved until `t[3]`.
    pub(super) fn timings(&self, t: [Instant; 4]) -> SolveTimings {
        SolveTimings {
            assemble: (t[1] - t[0]).as_secs_f64(),
            factor: (t[2] - t[1]).as_secs_f64(),
            solve: (t[3] - t[2]).as_secs_f64(),
            krylov: self.iterations,
            inexact: self.inexact,
            reused: self.reused,
            partial: false,
        }
    }
}

/// A hash of the fixed unknowns and their values (to check that a refinement continues the
/// solve it belongs to): the multiply–rotate mix of rustc's FxHasher over the pairs (i, bits
/// of v), a consistency check and not a defence against crafted input. It reads every unknown
/// of every screened solve, so it is the cheap mix rather than std's SipHash (whose cost on ex9
/// is in `replication/measurements/solver.md`).
pub(super) fn fingerprint(fixed: &FixedValues) -> u64 {
    const K: u64 = 0x517c_c1b7_2722_0a95;
    let mix = |h: u64, x: u64| (h.rotate_left(5) ^ x).wrapping_mul(K);
    let mut h = mix(0, fixed.len() as u64);
    for (i, v) in fixed.iter().enumerate() {
        if let Some(v) = v {
            h = mix(mix(h, i as u64), v.to_bits());
        }
    }
    h
}

impl<M: SolveMesh<D> + ?Sized, const D: usize> DiscreteSystem<'_, M, D> {
    /// Where the hierarchy of the next iterative solve (of the cell system if `cells`) comes
    /// from: the kept hierarchy's levels are reused unless they went stale, were built for the
    /// other system, or too many unknowns changed status since; its matrix (and a screening
    /// solve not refined) are freed before the next system is built, but a masked view of M
    /// (its patch), from which the next view is made ([`Reused::Whole`]).
    pub(super) fn next_hierarchy(
        &self,
        state: &mut SolveState,
        fixed: &FixedValues,
        cells: bool,
    ) -> crate::Result<NextHierarchy> {
        let mask = fixed_mask(&self.values.dirichlet, fixed)?;
        let max_changed = (reuse_max_changed(D) * self.n as f64) as usize;
        let next = state.kept.take().filter(|k| {
            !k.stale && k.cells == cells && changed(&k.fixed_mask, &mask) <= max_changed
        });
        let next = match next {
            Some(k) => {
                let (fresh_rate, built_for) = (k.fresh_rate, k.fixed_mask);
                // a masked view is kept whole (its patch is small, its matrix shared), so
                // that the next view and the fine level are updated where they changed
                let whole = matches!(k.amg.fine(), Fine::Masked(_)) && k.amg.n_levels() > 1;
                let levels = if whole {
                    Some(Reused::Whole {
                        amg: Box::new(k.amg),
                        fine_mask: k.fine_mask,
                    })
                } else {
                    k.amg.into_coarse().map(Reused::Coarse)
                };
                match levels {
                    Some(levels) => NextHierarchy::Reuse {
                        levels,
                        fresh_rate,
                        built_for,
                        current: mask,
                    },
                    None => NextHierarchy::New { fixed_mask: mask },
                }
            }
            None => NextHierarchy::New { fixed_mask: mask },
        };
        Ok(next)
    }

    /// The condensed matrix with lower-triangle `values`, both triangles stored by rows.
    pub(super) fn csr(&self, values: &[f64]) -> crate::Result<CsrMatrix> {
        let pattern = self.sym.kept_pattern("the condensed matrix by rows")?;
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut a = CsrMatrix::from_lower_csc(self.n_skel, col_ptr, row_idx, values)?;
        a.drop_zeros();
        Ok(a)
    }

    /// Solves S x = c (S in `a`, stored by rows or a masked view; c in `rhs`, overwritten by x) by
    /// multigrid-preconditioned conjugate gradients from the previous solution, to the
    /// relative residual `rtol`, with the hierarchy `next` says; returns when the
    /// multigrid setup ended and what the conjugate gradients did (x short of
    /// [`ITERATIVE_RTOL`]: the system is kept for [`Self::refine`], with the fingerprint of
    /// `fixed`).
    pub(super) fn solve_csr(
        &self,
        state: &mut SolveState,
        a: Fine<'static>,
        rhs: &mut [f64],
        rtol: f64,
        fixed: &FixedValues,
        next: NextHierarchy,
    ) -> crate::Result<(Instant, PcgOutcome)> {
        let hier = hierarchy(a, next, false, &mut state.amg)?;
        let t2 = Instant::now();
        let mut x = self.take_initial_guess(state)?;
        let out = self.run_pcg(state, hier, rhs, &mut x, rtol, fixed, None)?;
        rhs.copy_from_slice(&x);
        self.keep_solution(state, x);
        Ok((t2, out))
    }

    /// [`Self::pcg`] with the hierarchy `hier` (of the cell system `cs` if given, else of the
    /// skeleton one), which is then kept in `state` for the next solve (with c and the
    /// fingerprint of `fixed` if the solve stopped early). A reused hierarchy is corrected on
    /// the patch of the unknowns whose status changed since it was built ([`patched_pcg`]); one
    /// that fails is replaced by a new one, once; one that converged more than
    /// [`REUSE_MAX_SLOWDOWN`] times slower than when fresh is marked stale.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_pcg(
        &self,
        state: &mut SolveState,
        hier: Hierarchy,
        c: &[f64],
        x: &mut [f64],
        rtol: f64,
        fixed: &FixedValues,
        cs: Option<&CellSystemAll>,
    ) -> crate::Result<PcgOutcome> {
        let Hierarchy {
            mut amg,
            mut fresh_rate,
            mut fixed_mask,
            fine_mask,
            reused,
            cells,
        } = hier;
        let seeds = match &reused {
            Some(now) if patch_layers(D) > 0 => {
                let interior = (cs.is_none() && self.n > self.n_skel)
                    .then_some((&*self.sym.dof_map, self.n_skel));
                changed_rows(&fixed_mask, now, amg.n(), cs, interior)?
            }
            _ => Vec::new(),
        };
        let graph = cs.map(CellSystemAll::matrix);
        let first = self.pcg(&amg, &mut state.amg, c, x, rtol, (&seeds, graph));
        let (mut out, reused) = match (first, reused) {
            (Ok(out), reused) => (out, reused.is_some()),
            // a reused hierarchy that fails: a new one, for this solve's fixed unknowns
            (Err(_), Some(now)) => {
                amg = Amg::build(amg.into_fine(), &AmgOptions::default())?;
                (fresh_rate, fixed_mask) = (None, now);
                (
                    self.pcg(&amg, &mut state.amg, c, x, rtol, (&[], None))?,
                    false,
                )
            }
            (Err(e), None) => return Err(e),
        };
        out.reused = reused;
        let stale = match (reused, out.rate, fresh_rate) {
            (true, Some(r), Some(f)) => r > f / REUSE_MAX_SLOWDOWN,
            _ => false,
        };
        let screened = if out.inexact {
            Some((
                try_copy(c, "the screened right-hand side")?,
                fingerprint(fixed),
            ))
        } else {
            None
        };
        state.kept = Some(KeptHierarchy {
            amg,
            screened,
            fresh_rate: fresh_rate.or(out.rate),
            stale,
            fixed_mask,
            fine_mask,
            cells,
        });
        Ok(out)
    }

    /// The initial guess of an iterative solve: the last solution (completed from its cells if
    /// it was a partial iterate of the cell system), or zero.
    pub(super) fn take_initial_guess(&self, state: &mut SolveState) -> crate::Result<Vec<f64>> {
        let x = std::mem::take(&mut state.last_solution);
        if x.len() == self.n_skel {
            return Ok(x);
        }
        match self.skeleton_guess_from_cells(state)? {
            Some(x) => Ok(x),
            None => Ok(try_filled(self.n_skel, 0.0, "the initial guess")?),
        }
    }

    /// Conjugate gradients on S x = c (S the fine matrix of `amg`) from `x` to the relative
    /// residual `rtol`: the iterations, whether the true residual is above
    /// [`ITERATIVE_RTOL`] ‖c‖, and the mean reduction per iteration. With `patch` = (rows,
    /// graph) and rows not empty, the multigrid preconditioner is corrected on the patch of
    /// [`patch_layers`] around those rows in the graph (`None`: S's own unmasked rows), if the
    /// patch is small enough ([`PATCH_MAX_FRACTION`] of the rows, a factor no larger than S).
    fn pcg(
        &self,
        amg: &Amg,
        work: &mut AmgWork,
        c: &[f64],
        x: &mut [f64],
        rtol: f64,
        patch: (&[u32], Option<&CsrMatrix>),
    ) -> crate::Result<PcgOutcome> {
        let c_norm = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        let opts = if rtol > ITERATIVE_RTOL {
            // screening: the residual reduced by SCREENING_REDUCTION from where this solve
            // starts, and at most rtol ‖c‖ (never below the full target)
            let r0 = amg.fine().residual_norm(c, x);
            PcgOptions {
                rtol: ITERATIVE_RTOL,
                atol: (SCREENING_REDUCTION * r0).min(rtol * c_norm),
                max_iter: ITERATIVE_MAX_ITER,
            }
        } else {
            PcgOptions {
                rtol,
                atol: 0.0,
                max_iter: ITERATIVE_MAX_ITER,
            }
        };
        let report = match patch {
            (seeds, graph) if !seeds.is_empty() => {
                let layers = patch_layers(D);
                match amg.fine() {
                    Fine::Csr(m) => {
                        let a: &CsrMatrix = m;
                        patched_pcg(a, graph.unwrap_or(a), amg, work, seeds, layers, c, x, &opts)?
                    }
                    Fine::Masked(m) => {
                        let g = graph.unwrap_or(m.unmasked());
                        patched_pcg(m, g, amg, work, seeds, layers, c, x, &opts)?
                    }
                }
            }
            _ => amg.pcg(work, c, x, &opts)?,
        };
        let rate = (report.iterations > 0
            && report.residual_norm > 0.0
            && report.initial_residual_norm > 0.0)
            .then(|| {
                (report.residual_norm / report.initial_residual_norm).ln()
                    / report.iterations as f64
            });
        Ok(PcgOutcome {
            iterations: report.iterations,
            inexact: report.residual_norm > ITERATIVE_RTOL * c_norm,
            rate,
            reused: false,
        })
    }

    /// Keeps `x` as the initial guess of the next iterative solve.
    pub(super) fn keep_solution(&self, state: &mut SolveState, x: Vec<f64>) {
        state.last_solution = x;
        state.last_cells = Vec::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::cartesian_triangles;
    use crate::scheme::{GradientDiscretisation, Hmm};

    /// Masks of `n` unknowns with the unknowns `set` set.
    fn mask(n: usize, set: &[usize]) -> Vec<u64> {
        let mut m = vec![0u64; n.div_ceil(64)];
        for &i in set {
            m[i / 64] |= 1 << (i % 64);
        }
        m
    }

    #[test]
    fn the_changed_rows_of_the_skeleton_system_include_the_faces_of_changed_cells() {
        let mesh = cartesian_triangles(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let hmm = Hmm::new(&mesh);
        let map = DofMap::new(&hmm).unwrap();
        let (n, n_skel) = (hmm.n_unknowns(), hmm.n_skeleton());
        assert!(n > n_skel);
        // cell 5's interior unknown and face 2 change status
        let (dofs, _) = map.cell(5);
        let interior = dofs
            .iter()
            .map(|&j| j as usize)
            .find(|&j| j >= n_skel)
            .unwrap();
        let (a, b) = (mask(n, &[0, 1]), mask(n, &[0, 1, 2, interior]));
        let mut want: Vec<u32> = dofs
            .iter()
            .copied()
            .filter(|&j| (j as usize) < n_skel)
            .collect();
        assert_eq!(want.len(), 3);
        want.push(2);
        want.sort_unstable();
        let mut got = changed_rows(&a, &b, n_skel, None, Some((&map, n_skel))).unwrap();
        got.sort_unstable();
        got.dedup();
        assert_eq!(got, want);
        // without the dof map: the skeleton unknown alone; unchanged masks: nothing
        assert_eq!(changed_rows(&a, &b, n_skel, None, None).unwrap(), vec![2]);
        assert!(
            changed_rows(&b, &b, n_skel, None, Some((&map, n_skel)))
                .unwrap()
                .is_empty()
        );
    }

    #[test]
    fn the_fingerprint_tells_fixed_sets_and_values_apart() {
        let fixed = |v: &[Option<f64>]| FixedValues::from_options(v.iter().copied()).unwrap();
        let a = fixed(&[None, Some(1.0), None, Some(-2.0)]);
        assert_eq!(fingerprint(&a), fingerprint(&a.clone()));
        for b in [
            fixed(&[None, Some(1.0), None, Some(-2.5)]),
            fixed(&[Some(1.0), None, None, Some(-2.0)]),
            fixed(&[None, Some(1.0), Some(0.0), Some(-2.0)]),
            fixed(&[None, Some(1.0), None, None]),
            fixed(&[None, Some(1.0), None, Some(-2.0), None]),
            fixed(&[None, Some(-0.0)]),
        ] {
            assert_ne!(fingerprint(&a), fingerprint(&b), "{b:?}");
        }
        assert_ne!(
            fingerprint(&fixed(&[None, Some(0.0)])),
            fingerprint(&fixed(&[None, Some(-0.0)]))
        );
    }

    #[test]
    fn a_declined_patch_around_many_changes_asks_for_a_new_hierarchy() {
        use crate::linalg::amg::testing::grid;
        let a = grid(40, 1.0, 1.0, &|_, _| 1.0);
        let n = a.n_rows();
        let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
        let opts = PcgOptions {
            rtol: 1e-10,
            atol: 0.0,
            max_iter: 100,
        };
        let b = vec![1.0; n];
        let run = |seeds: &[u32]| {
            let mut x = vec![0.0; n];
            let r = patched_pcg(
                &a,
                &a,
                &amg,
                &mut AmgWork::new(),
                seeds,
                6,
                &b,
                &mut x,
                &opts,
            );
            (r, x)
        };
        // one seed: a patch of 85 of the 1600 rows, corrected, and converged
        let (r, x) = run(&[820]);
        assert!(r.unwrap().iterations > 0 && x.iter().all(|v| v.is_finite() && *v > 0.0));
        // every row: above PATCH_MAX_FRACTION, declined; more than 10⁻³ of the rows changed,
        // so an error (the caller then builds a new hierarchy), x untouched
        let all: Vec<u32> = (0..n as u32).collect();
        let (r, x) = run(&all);
        assert!(r.unwrap_err().to_string().contains("1600 changed rows"));
        assert!(x.iter().all(|&v| v == 0.0));
    }
}
