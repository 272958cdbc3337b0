//! Global assembly with static condensation: a symbolic part built once per scheme, and
//! values refilled per problem and per active set.
//!
//! - [`symbolic::SymbolicSystem`] (what depends only on the scheme): the unknowns of each cell,
//!   the pattern of the condensed (skeleton) matrix and its symbolic Cholesky factorisation,
//!   and the scatter maps. Share it (`Arc`) between problems posed on the same scheme, e.g.
//!   the four values of C of the paper's Test 3.
//! - [`values::ProblemValues`] (per problem): data evaluation, local matrices and loads,
//!   boundary conditions.
//! - [`DiscreteSystem`] = both; [`DiscreteSystem::solve`] takes a set of *fixed* unknowns
//!   (Dirichlet unknowns are always fixed; the active-set solver adds active constrained
//!   unknowns) and
//!   1. condenses each cell ([`condense`]): interior unknowns are eliminated, for HMM the cell
//!      value u_K (or nothing when the cell is active);
//!   2. assembles into the fixed pattern; a fixed skeleton unknown keeps its row and column in
//!      the pattern with a unit diagonal and zeros elsewhere, its value moved to the right-hand
//!      side;
//!   3. refactorises numerically, solves, and recovers the interior unknowns.
//!
//! Performance (see `replication/BENCHMARKS.md`): the cell loops (local matrices,
//! condensation, residual, recovery) run in parallel with rayon; the global arrays are then
//! *gathered* entry by entry (each entry of the condensed matrix and each residual row knows
//! its contributions, listed in cell order) instead of scattered, so that the sums do not
//! depend on the number of threads; the symbolic factorisation runs beside the local
//! matrices; the buffers of the condensation, of the residual and of the Cholesky factor are
//! kept between solves.

pub mod condense;
pub mod symbolic;
pub mod values;

use crate::linalg::{FactorThreads, Ordering};
use crate::problem::Problem;
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::vi::{QuadraticEnergy, SolveTimings};
use condense::{condense, interior_value, recover_interior};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::Instant;
pub use symbolic::{DofMap, SymbolicSystem};
pub use values::ProblemValues;

/// Cells per parallel task in the cell loops (large enough to amortise the task, small enough
/// to balance two or more threads).
const CHUNK: usize = 4096;

/// The cell ranges `[c0, c1)` of the parallel tasks.
fn cell_chunks(nc: usize) -> Vec<(usize, usize)> {
    (0..nc.div_ceil(CHUNK))
        .map(|c| (c * CHUNK, ((c + 1) * CHUNK).min(nc)))
        .collect()
}

/// Options of the symbolic system.
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemOptions {
    /// Fill-reducing ordering of the symbolic factorisation (default: AMD).
    pub ordering: Ordering,
    /// Threads of the numeric factorisations (default: one; see [`FactorThreads`]).
    pub factor_threads: FactorThreads,
}

/// The assembled discrete problem (see the module docs).
pub struct DiscreteSystem<'a> {
    sym: Arc<SymbolicSystem<'a>>,
    values: ProblemValues,
    n_skel: usize,
    n: usize,
    /// Buffers of [`DiscreteSystem::assemble_condensed`], kept between calls.
    scratch: Mutex<(Vec<f64>, Vec<f64>)>,
    /// Buffer of [`DiscreteSystem::residual`], kept between calls.
    residual_scratch: Mutex<Vec<[f64; 2]>>,
    /// Time to build (data, local matrices, and the symbolic system when built here), seconds.
    pub setup_seconds: f64,
    /// The symbolic factorisation, seconds (0 when the symbolic system was given). It runs
    /// beside the local matrices, so `setup_seconds − symbolic_seconds` is what it did not hide.
    pub symbolic_seconds: f64,
}

impl<'a> DiscreteSystem<'a> {
    /// Builds the symbolic system of `scheme` and the values of `problem`, side by side.
    pub fn new(
        scheme: &'a dyn GradientDiscretisation,
        problem: &Problem,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let dof_map = DofMap::new(scheme)?;
        let (values, sym) = rayon::join(
            || ProblemValues::evaluate(scheme, &dof_map, problem),
            || SymbolicSystem::with_dof_map(scheme, dof_map.clone(), options),
        );
        let sym = Arc::new(sym?);
        let symbolic_seconds = sym.symbolic_seconds;
        let mut s = Self::from_parts(sym, values?);
        s.setup_seconds = t0.elapsed().as_secs_f64();
        s.symbolic_seconds = symbolic_seconds;
        Ok(s)
    }

    /// The values of `problem` on a symbolic system built before (and shared).
    pub fn with_symbolic(sym: Arc<SymbolicSystem<'a>>, problem: &Problem) -> crate::Result<Self> {
        let t0 = Instant::now();
        let values = ProblemValues::evaluate(sym.scheme(), &sym.dof_map, problem)?;
        let mut s = Self::from_parts(sym, values);
        s.setup_seconds = t0.elapsed().as_secs_f64();
        Ok(s)
    }

    fn from_parts(sym: Arc<SymbolicSystem<'a>>, values: ProblemValues) -> Self {
        DiscreteSystem {
            n_skel: sym.n_condensed(),
            n: sym.n_unknowns(),
            sym,
            values,
            scratch: Mutex::new((Vec::new(), Vec::new())),
            residual_scratch: Mutex::new(Vec::new()),
            setup_seconds: 0.0,
            symbolic_seconds: 0.0,
        }
    }

    /// The symbolic system (shareable with other problems on the same scheme).
    pub fn symbolic(&self) -> &Arc<SymbolicSystem<'a>> {
        &self.sym
    }
    /// The scheme.
    pub fn scheme(&self) -> &'a dyn GradientDiscretisation {
        self.sym.scheme()
    }
    /// Number of unknowns (skeleton and interior).
    pub fn n_unknowns(&self) -> usize {
        self.n
    }
    /// Size of the condensed system.
    pub fn n_condensed(&self) -> usize {
        self.n_skel
    }
    /// Stored entries of the condensed matrix (lower triangle).
    pub fn nnz(&self) -> usize {
        self.sym.pattern.nnz()
    }
    /// Stored values of the Cholesky factor of the condensed matrix (its fill).
    pub fn factor_len(&self) -> usize {
        self.sym.pattern.factor_len()
    }
    /// Dirichlet unknowns and their values (`None`: not Dirichlet).
    pub fn dirichlet(&self) -> &[Option<f64>] {
        &self.values.dirichlet
    }
    /// The unknowns carrying the trace on Γ3, including those that are also Dirichlet unknowns
    /// (P1 vertices at Γ1 ∩ Γ3), which are never constrained but must satisfy the barrier.
    pub fn signorini_dofs(&self) -> &[PointDof] {
        &self.values.signorini
    }
    /// The full load vector b.
    pub fn load(&self) -> &[f64] {
        &self.values.load
    }

    /// The unknowns of cell k, its number of interior unknowns, its local matrix and load.
    fn local(&self, k: usize) -> (&[usize], usize, &[f64], &[f64]) {
        let (d, ni) = self.sym.dof_map.cell(k);
        let r = self.sym.dof_map.dof_ptr[k]..self.sym.dof_map.dof_ptr[k + 1];
        let v = &self.values;
        (d, ni, &v.mats[v.mat_ptr[k]..v.mat_ptr[k + 1]], &v.loads[r])
    }

    /// Solves the linear system in which the unknowns with `fixed[d] = Some(v)` (and the
    /// Dirichlet unknowns) are fixed. Returns the full unknown vector.
    pub fn solve(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let t0 = Instant::now();
        let fx = |d: usize| -> Option<f64> { self.values.dirichlet[d].or(fixed[d]) };
        let (values, mut rhs) = self.assemble_condensed(fixed);
        let t1 = Instant::now();
        let factor = self.sym.pattern.factor(&values)?;
        let t2 = Instant::now();
        factor.solve_in_place(&mut rhs);
        let mut u = vec![0.0; self.n];
        u[..self.n_skel].copy_from_slice(&rhs);
        let nc = self.sym.scheme().mesh().n_cells();
        if self.sym.single_interior {
            // one interior unknown per cell, computed in parallel from the skeleton values
            let interior: Vec<(usize, f64)> = (0..nc)
                .into_par_iter()
                .map(|k| {
                    let (d, _, m, b) = self.local(k);
                    (d[0], interior_value(d, m, b, &fx, &u))
                })
                .collect();
            for (dof, v) in interior {
                u[dof] = v;
            }
        } else {
            for k in 0..nc {
                let (d, ni, m, b) = self.local(k);
                if ni > 0 {
                    recover_interior(d, ni, m, b, &fx, &mut u);
                }
            }
        }
        if let Some(i) = u.iter().position(|x| !x.is_finite()) {
            return Err(crate::Error::Linear(format!(
                "the solution is not finite at unknown {i}"
            )));
        }
        let t3 = Instant::now();
        Ok((
            u,
            SolveTimings {
                assemble: (t1 - t0).as_secs_f64(),
                factor: (t2 - t1).as_secs_f64(),
                solve: (t3 - t2).as_secs_f64(),
            },
        ))
    }

    /// The lower-triangular CSC pattern (column pointers, row indices) of the condensed matrix.
    pub fn condensed_pattern(&self) -> (&[usize], &[usize]) {
        (self.sym.pattern.col_ptr(), self.sym.pattern.row_idx())
    }

    /// Condensed matrix values (in the order of [`Self::condensed_pattern`]) and right-hand
    /// side, with `fixed` and the Dirichlet unknowns fixed (unit rows).
    pub fn assemble_condensed(&self, fixed: &[Option<f64>]) -> (Vec<f64>, Vec<f64>) {
        // the value of each fixed unknown, NaN for a free one (data and barriers are finite)
        let fixed_val: Vec<f64> = (0..self.n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| self.values.dirichlet[d].or(fixed[d]).unwrap_or(f64::NAN))
            .collect();
        let fx = |d: usize| -> Option<f64> {
            let v = fixed_val[d];
            if v.is_nan() { None } else { Some(v) }
        };
        let nc = self.sym.scheme().mesh().n_cells();
        // condensed local blocks, in parallel: cell k's p×p block at pos_ptr[k], its p loads
        // (minus the fixed columns) at the positions of its skeleton unknowns in `dofs`
        // buffers kept between calls (they are entirely rewritten where read)
        let (mut sbuf, mut gbuf) = self
            .scratch
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        sbuf.resize(self.sym.maps.pos.len(), 0.0);
        gbuf.resize(self.sym.dof_map.dofs.len(), 0.0);
        {
            let mut tasks = Vec::new();
            let (mut s_rest, mut g_rest) = (&mut sbuf[..], &mut gbuf[..]);
            for (c0, c1) in cell_chunks(nc) {
                let (s_here, s_next) =
                    std::mem::take(&mut s_rest).split_at_mut(self.sym.maps.pos_ptr[c1] - self.sym.maps.pos_ptr[c0]);
                let (g_here, g_next) =
                    std::mem::take(&mut g_rest).split_at_mut(self.sym.dof_map.dof_ptr[c1] - self.sym.dof_map.dof_ptr[c0]);
                s_rest = s_next;
                g_rest = g_next;
                tasks.push((c0, c1, s_here, g_here));
            }
            tasks.into_par_iter().for_each(|(c0, c1, s_out, g_out)| {
                for k in c0..c1 {
                    let (d, ni, m, b) = self.local(k);
                    let nl = d.len();
                    let p = nl - ni;
                    let so = self.sym.maps.pos_ptr[k] - self.sym.maps.pos_ptr[c0];
                    let go = self.sym.dof_map.dof_ptr[k] - self.sym.dof_map.dof_ptr[c0] + ni;
                    let sk = &mut s_out[so..so + p * p];
                    let gk = &mut g_out[go..go + p];
                    condense(d, ni, m, b, &fx, sk, gk);
                    // the cell's right-hand side: its condensed load minus the columns of the
                    // fixed skeleton unknowns
                    for bcol in 0..p {
                        if let Some(vj) = fx(d[ni + bcol]) {
                            for arow in 0..p {
                                gk[arow] -= sk[arow + bcol * p] * vj;
                            }
                        }
                    }
                }
            });
        }
        // values, gathered entry by entry (column by column in parallel): the sum of the
        // sources in the order of a sequential scatter; zero in the rows and columns of fixed
        // unknowns, whose diagonal is 1
        let (col_ptr, row_idx) = (self.sym.pattern.col_ptr(), self.sym.pattern.row_idx());
        let is_fixed: Vec<bool> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| fx(d).is_some())
            .collect();
        let mut values = vec![0.0; self.sym.pattern.nnz()];
        {
            let mut tasks = Vec::new();
            let mut rest = &mut values[..];
            let step = CHUNK * 4;
            for c0 in (0..self.n_skel).step_by(step) {
                let c1 = (c0 + step).min(self.n_skel);
                let (here, next) =
                    std::mem::take(&mut rest).split_at_mut(col_ptr[c1] - col_ptr[c0]);
                rest = next;
                tasks.push((c0, c1, here));
            }
            tasks.into_par_iter().for_each(|(c0, c1, out)| {
                let base = col_ptr[c0];
                for c in c0..c1 {
                    let col_fixed = is_fixed[c];
                    for q in col_ptr[c]..col_ptr[c + 1] {
                        let r = row_idx[q];
                        out[q - base] = if col_fixed || is_fixed[r] {
                            if r == c { 1.0 } else { 0.0 }
                        } else {
                            let mut v = 0.0;
                            for &i in &self.sym.maps.src[self.sym.maps.src_ptr[q]..self.sym.maps.src_ptr[q + 1]] {
                                v += sbuf[i as usize];
                            }
                            v
                        };
                    }
                }
            });
        }
        // right-hand side, gathered row by row: the Neumann load plus the cells' loads; the
        // value on fixed rows
        let mut rhs = vec![0.0; self.n_skel];
        rhs.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(gi, out)| {
                *out = match fx(gi) {
                    Some(v) => v,
                    None => {
                        let mut acc = self.values.neumann_load[gi];
                        for &qd in &self.sym.maps.inc[self.sym.maps.inc_ptr[gi]..self.sym.maps.inc_ptr[gi + 1]] {
                            acc += gbuf[qd as usize];
                        }
                        acc
                    }
                };
            });
        if let Ok(mut b) = self.scratch.lock() {
            *b = (sbuf, gbuf);
        }
        (values, rhs)
    }

    /// The residual r = b − M u of the full (uncondensed) system, and for each unknown the
    /// scale |b_i| + Σ_j |M_ij u_j| against which it is small. On Dirichlet unknowns r is the
    /// reaction, not a balance; on constrained unknowns it is the multiplier (up to sign).
    pub fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        // cell by cell: (M_K u_K)_i and Σ_j |(M_K)_ij u_j| at the position of local entry i
        let nc = self.sym.scheme().mesh().n_cells();
        let mut local = self
            .residual_scratch
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        local.clear();
        local.resize(self.sym.dof_map.dofs.len(), [0.0f64; 2]);
        {
            let mut tasks = Vec::new();
            let mut rest = &mut local[..];
            for (c0, c1) in cell_chunks(nc) {
                let (here, next) =
                    std::mem::take(&mut rest).split_at_mut(self.sym.dof_map.dof_ptr[c1] - self.sym.dof_map.dof_ptr[c0]);
                rest = next;
                tasks.push((c0, c1, here));
            }
            tasks.into_par_iter().for_each(|(c0, c1, out)| {
                let base = self.sym.dof_map.dof_ptr[c0];
                for k in c0..c1 {
                    let (d, _, m, _) = self.local(k);
                    let nl = d.len();
                    let o = &mut out[self.sym.dof_map.dof_ptr[k] - base..self.sym.dof_map.dof_ptr[k + 1] - base];
                    for (j, &gj) in d.iter().enumerate() {
                        let uj = u[gj];
                        for (i, oi) in o.iter_mut().enumerate() {
                            let v = m[i + j * nl] * uj;
                            oi[0] += v;
                            oi[1] += v.abs();
                        }
                    }
                }
            });
        }
        // row by row
        let mut r = vec![0.0; self.n];
        let mut scale = vec![0.0; self.n];
        r.par_iter_mut()
            .zip(scale.par_iter_mut())
            .enumerate()
            .with_min_len(4096)
            .for_each(|(gi, (ri, si))| {
                let mut a = self.values.load[gi];
                let mut b = a.abs();
                for &q in &self.sym.maps.inc[self.sym.maps.inc_ptr[gi]..self.sym.maps.inc_ptr[gi + 1]] {
                    a -= local[q as usize][0];
                    b += local[q as usize][1];
                }
                *ri = a;
                *si = b;
            });
        if let Ok(mut b) = self.residual_scratch.lock() {
            *b = local;
        }
        (r, scale)
    }

    /// The discrete energy ½ uᵀMu − bᵀu (the VI solution minimises it over the convex set).
    pub fn energy(&self, u: &[f64]) -> f64 {
        let (r, _) = self.residual(u);
        // ½uᵀMu − bᵀu = ½uᵀ(Mu − b) − ½bᵀu = −½uᵀr − ½bᵀu
        -0.5 * u.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>()
            - 0.5 * u.iter().zip(&self.values.load).map(|(a, b)| a * b).sum::<f64>()
    }

    /// The entries of the full (uncondensed) matrix, cell by cell (repeated entries sum).
    pub fn full_matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for k in 0..self.sym.scheme().mesh().n_cells() {
            let (d, _, m, _) = self.local(k);
            let nl = d.len();
            for (j, &gj) in d.iter().enumerate() {
                for (i, &gi) in d.iter().enumerate() {
                    t.push((gi, gj, m[i + j * nl]));
                }
            }
        }
        t
    }
}

impl QuadraticEnergy for DiscreteSystem<'_> {
    fn n_unknowns(&self) -> usize {
        self.n
    }
    fn dirichlet(&self) -> &[Option<f64>] {
        &self.values.dirichlet
    }
    fn load(&self) -> &[f64] {
        &self.values.load
    }
    fn minimise_with_fixed(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        DiscreteSystem::solve(self, fixed)
    }
    fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        DiscreteSystem::residual(self, u)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.full_matrix_triplets()
    }
}
