//! Global assembly with static condensation, built once and refilled.
//!
//! [`DiscreteSystem::new`] evaluates the data (A_K, f, boundary partition, Dirichlet and Neumann
//! data), asks the scheme for every local matrix and load, stores them, builds the sparsity
//! pattern of the condensed (skeleton) matrix and its symbolic Cholesky factorisation, and
//! precomputes, for each cell, where each local entry lands in the global value array.
//!
//! [`DiscreteSystem::solve`] then takes a set of *fixed* unknowns (Dirichlet unknowns are always
//! fixed; the active-set solver adds active constrained unknowns) and:
//! 1. condenses each cell: with interior unknowns R (free) and F (fixed) and skeleton unknowns S,
//!    S_K = M_SS − M_SR M_RR⁻¹ M_RS and g_K = b_S − M_SF u_F − M_SR M_RR⁻¹ (b_R − M_RF u_F)
//!    (for HMM, R = {u_K} or ∅ when the cell is active);
//! 2. assembles into the fixed pattern; a fixed skeleton unknown keeps its row and column in the
//!    pattern with a unit diagonal and zeros elsewhere, its value moved to the right-hand side;
//! 3. refactorises numerically, solves, and recovers the interior unknowns.
//!
//! The pattern and the symbolic factorisation never change, whatever is fixed.
//!
//! Performance (see `replication/BENCHMARKS.md`): the cell loops (local matrices,
//! condensation, residual, recovery) run in parallel with rayon; the global arrays are then
//! *gathered* entry by entry (each entry of the condensed matrix and each residual row knows
//! its contributions, listed in cell order) instead of scattered, so that the sums do not
//! depend on the number of threads; the symbolic factorisation runs beside the local
//! matrices; the buffers of the condensation, of the residual and of the Cholesky factor are
//! kept between solves; the residual of the last u is remembered (the active-set loop asks for
//! it twice).

use crate::mesh::Point;
use crate::problem::{BoundaryKind, Problem, check_finite, check_tensor};
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::solver::linear::{FactorThreads, Ordering, SpdPattern};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::Instant;

/// Cells per parallel task in the cell loops (large enough to amortise the task, small enough
/// to balance two or more threads).
const CHUNK: usize = 4096;

/// The cell ranges `[c0, c1)` of the parallel tasks.
fn cell_chunks(nc: usize) -> Vec<(usize, usize)> {
    (0..nc.div_ceil(CHUNK))
        .map(|c| (c * CHUNK, ((c + 1) * CHUNK).min(nc)))
        .collect()
}

/// What one parallel task of [`DiscreteSystem::new`] computes for its cells.
#[derive(Default)]
struct LocalChunk {
    mat_len: Vec<usize>,
    mats: Vec<f64>,
    loads: Vec<f64>,
    bad_tensor: Option<crate::Error>,
    bad_source: Option<String>,
}

/// Timings of one [`DiscreteSystem::solve`], in seconds.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SolveTimings {
    /// Condensation and scatter.
    pub assemble: f64,
    /// Numeric factorisation.
    pub factor: f64,
    /// Triangular solves and recovery of interior unknowns.
    pub solve: f64,
}

/// The part of [`DiscreteSystem::with_options`] computed beside the symbolic factorisation.
struct Rest {
    mat_ptr: Vec<usize>,
    mats: Vec<f64>,
    loads: Vec<f64>,
    load: Vec<f64>,
    neumann_load: Vec<f64>,
    dirichlet: Vec<Option<f64>>,
    signorini: Vec<PointDof>,
    pos_ptr: Vec<usize>,
    pos: Vec<u32>,
    inc_ptr: Vec<usize>,
    inc: Vec<usize>,
    src_ptr: Vec<usize>,
    src: Vec<u32>,
}

/// Options of [`DiscreteSystem::with_options`].
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemOptions {
    /// Fill-reducing ordering of the symbolic factorisation (default: AMD).
    pub ordering: Ordering,
    /// Threads of the numeric factorisations (default: one; see [`FactorThreads`]).
    pub factor_threads: FactorThreads,
}

/// u, r = b − Mu and the scale of [`DiscreteSystem::residual`].
type ResidualMemo = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The assembled discrete problem (see the module docs).
pub struct DiscreteSystem<'a> {
    scheme: &'a dyn GradientDiscretisation,
    n_skel: usize,
    n: usize,
    // flattened local data, one block per cell
    dof_ptr: Vec<usize>,
    dofs: Vec<usize>,
    n_int: Vec<u8>,
    mat_ptr: Vec<usize>,
    mats: Vec<f64>,
    loads: Vec<f64>,
    // positions in `values` of the skeleton×skeleton local entries (lower triangle only;
    // u32::MAX for upper entries)
    pos_ptr: Vec<usize>,
    pos: Vec<u32>,
    pattern: SpdPattern,
    /// For each unknown, where it appears in the local blocks (its positions in `dofs`), cells
    /// in increasing order: the residual is computed cell by cell, then gathered row by row,
    /// both in parallel, and the result does not depend on the number of threads.
    inc_ptr: Vec<usize>,
    inc: Vec<usize>,
    /// For each entry q of the condensed pattern, the local skeleton entries that land on it
    /// (their indices in `pos`, in increasing order, i.e. in the order of a sequential scatter
    /// over the cells): the values are gathered entry by entry in parallel.
    src_ptr: Vec<usize>,
    src: Vec<u32>,
    /// Every cell has exactly one interior unknown (HMM): parallel recovery.
    single_interior: bool,
    /// Buffers of [`DiscreteSystem::assemble_condensed`], kept between calls.
    scratch: Mutex<(Vec<f64>, Vec<f64>)>,
    /// Buffer of [`DiscreteSystem::residual`], kept between calls.
    residual_scratch: Mutex<Vec<[f64; 2]>>,
    /// The last residual computed, with its u (the active-set loop asks twice for the same u).
    last_residual: Mutex<Option<ResidualMemo>>,
    /// Full load vector b (local loads and Neumann data), indexed by unknown.
    load: Vec<f64>,
    /// The Neumann part of the load on the skeleton unknowns.
    neumann_load: Vec<f64>,
    /// Dirichlet unknowns and their values.
    dirichlet: Vec<Option<f64>>,
    /// Unknowns carrying the trace on Γ3, with their points and measures (Dirichlet ones too).
    signorini: Vec<PointDof>,
    /// Time to build (data, local matrices, pattern, symbolic factorisation), seconds.
    pub setup_seconds: f64,
    /// The symbolic factorisation, seconds. It runs beside the local matrices and the rest of
    /// the setup, so `setup_seconds − symbolic_seconds` is what it did not hide.
    pub symbolic_seconds: f64,
}

impl<'a> DiscreteSystem<'a> {
    /// Evaluates the data of `problem` on the scheme's mesh and builds the system.
    pub fn new(scheme: &'a dyn GradientDiscretisation, problem: &Problem) -> crate::Result<Self> {
        Self::with_options(scheme, problem, SystemOptions::default())
    }

    /// As [`DiscreteSystem::new`], with options.
    pub fn with_options(
        scheme: &'a dyn GradientDiscretisation,
        problem: &Problem,
        options: SystemOptions,
    ) -> crate::Result<Self> {
        let t0 = Instant::now();
        let mesh = scheme.mesh();
        let nc = mesh.n_cells();
        let n_skel = scheme.n_skeleton();
        let n = scheme.n_unknowns();

        // --- the unknowns of each cell, in parallel over chunks of cells, concatenated in order
        let dof_chunks: Vec<(Vec<usize>, Vec<usize>, Vec<u8>)> = cell_chunks(nc)
            .into_par_iter()
            .map(|(c0, c1)| {
                let (mut len, mut all, mut ni) = (Vec::new(), Vec::new(), Vec::new());
                let mut ld = Vec::new();
                for k in c0..c1 {
                    scheme.local_dofs(k, &mut ld);
                    len.push(ld.len());
                    all.extend_from_slice(&ld);
                    ni.push(scheme.n_local_interior(k) as u8);
                }
                (len, all, ni)
            })
            .collect();
        let mut dof_ptr = Vec::with_capacity(nc + 1);
        dof_ptr.push(0);
        let mut dofs = Vec::with_capacity(dof_chunks.iter().map(|c| c.1.len()).sum());
        let mut n_int = Vec::with_capacity(nc);
        for (len, all, ni) in dof_chunks {
            for l in len {
                dof_ptr.push(dof_ptr.last().copied().unwrap_or(0) + l);
            }
            dofs.extend_from_slice(&all);
            n_int.extend_from_slice(&ni);
        }

        // --- pattern of the condensed matrix (lower triangle), built once
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for k in 0..nc {
            let ni = n_int[k] as usize;
            let sk = &dofs[dof_ptr[k] + ni..dof_ptr[k + 1]];
            for &i in sk {
                for &j in sk {
                    if i >= j {
                        pairs.push((j, i)); // (column, row)
                    }
                }
            }
        }
        for d in 0..n_skel {
            pairs.push((d, d)); // every unknown has a diagonal, even if isolated
        }
        pairs.par_sort_unstable();
        pairs.dedup();
        let mut col_ptr = vec![0usize; n_skel + 1];
        let mut row_idx = Vec::with_capacity(pairs.len());
        for &(c, r) in &pairs {
            col_ptr[c + 1] += 1;
            row_idx.push(r);
        }
        for c in 0..n_skel {
            col_ptr[c + 1] += col_ptr[c];
        }
        drop(pairs);
        if row_idx.len() >= u32::MAX as usize {
            return Err(crate::Error::Linear(
                "the condensed matrix has more than 2^32 entries".into(),
            ));
        }
        // --- the symbolic factorisation (sequential) runs beside everything else
        let (symbolic, rest) = rayon::join(
            || {
                let t_sym = Instant::now();
                SpdPattern::with_ordering(
                    n_skel,
                    col_ptr.clone(),
                    row_idx.clone(),
                    options.ordering,
                )
                .map(|p| {
                    (
                        p.with_threads(options.factor_threads),
                        t_sym.elapsed().as_secs_f64(),
                    )
                })
            },
            || -> crate::Result<Rest> {
                // --- local matrices and loads, in parallel over chunks of cells, concatenated in order
                let chunks: Vec<LocalChunk> = cell_chunks(nc)
                    .into_par_iter()
                    .map(|(c0, c1)| {
                        let mut out = LocalChunk::default();
                        let mut m = DMatrix::zeros(0, 0);
                        let mut b = DVector::zeros(0);
                        for k in c0..c1 {
                            let xk = mesh.centroid(k);
                            let a = (problem.diffusion)(xk);
                            // the message is formatted only for a bad tensor
                            if check_tensor(&a, "").is_err() {
                                out.bad_tensor =
                                    check_tensor(&a, &format!("x_K = {xk:?} (cell {k})")).err();
                                break;
                            }
                            scheme.local_matrix(k, &a, &mut m);
                            let f = |p: Point| -> f64 {
                                match &problem.source_in_cell {
                                    Some(g) => g(p, xk),
                                    None => (problem.source)(p),
                                }
                            };
                            scheme.local_load(k, &f, &mut b);
                            if out.bad_source.is_none() && b.iter().any(|x| !x.is_finite()) {
                                out.bad_source = Some(format!(
                                    "the source term f is not finite in cell {k} (x_K = {xk:?})"
                                ));
                            }
                            // column-major storage of the local matrix
                            out.mats.extend_from_slice(m.as_slice());
                            out.mat_len.push(m.len());
                            out.loads.extend(b.iter());
                        }
                        out
                    })
                    .collect();
                // the first error in cell order, as in a sequential loop: a bad tensor stops the loop,
                // a bad source is reported after it
                let bad_source = chunks.iter().find_map(|c| c.bad_source.clone());
                let mut mat_ptr = Vec::with_capacity(nc + 1);
                mat_ptr.push(0);
                let n_dofs: usize = chunks.iter().map(|c| c.loads.len()).sum();
                let n_mats: usize = chunks.iter().map(|c| c.mats.len()).sum();
                let mut mats = Vec::with_capacity(n_mats);
                let mut loads = Vec::with_capacity(n_dofs);
                for mut c in chunks {
                    if let Some(e) = c.bad_tensor.take() {
                        return Err(e);
                    }
                    for &l in &c.mat_len {
                        mat_ptr.push(mat_ptr.last().copied().unwrap_or(0) + l);
                    }
                    mats.extend_from_slice(&c.mats);
                    loads.extend_from_slice(&c.loads);
                }
                if let Some(msg) = bad_source {
                    return Err(crate::Error::InvalidData(msg));
                }

                // --- boundary conditions
                let mut load = vec![0.0; n];
                for k in 0..nc {
                    for (i, &d) in dofs[dof_ptr[k]..dof_ptr[k + 1]].iter().enumerate() {
                        load[d] += loads[dof_ptr[k] + i];
                    }
                }
                let mut neumann_load = vec![0.0; n_skel];
                let mut dirichlet: Vec<Option<f64>> = vec![None; n];
                let mut sig_meas: Vec<f64> = vec![0.0; n];
                let mut sig_point: Vec<Option<Point>> = vec![None; n];
                let mut tr = Vec::new();
                for &e in mesh.boundary_edges() {
                    let xs = mesh.edge_midpoint(e);
                    let kind = (problem.boundary)(xs, mesh.edge_tag(e));
                    scheme.edge_trace_dofs(e, &mut tr);
                    match kind {
                        BoundaryKind::Dirichlet => {
                            for t in &tr {
                                let v = check_finite(
                                    (problem.dirichlet)(t.point),
                                    &format!("the Dirichlet value at {:?}", t.point),
                                )?;
                                dirichlet[t.dof] = Some(v);
                            }
                        }
                        BoundaryKind::Neumann => {
                            let g = check_finite(
                                (problem.neumann)(xs),
                                &format!("the Neumann flux at {xs:?}"),
                            )?;
                            for t in &tr {
                                load[t.dof] += t.measure * g;
                                neumann_load[t.dof] += t.measure * g;
                            }
                        }
                        BoundaryKind::Signorini => {
                            for t in &tr {
                                sig_meas[t.dof] += t.measure;
                                sig_point[t.dof] = Some(t.point);
                            }
                        }
                    }
                }
                // Γ3 carries natural (zero-flux) data where inactive: nothing to add to the load.
                let signorini: Vec<PointDof> = (0..n)
                    .filter(|&d| sig_point[d].is_some())
                    .map(|d| PointDof {
                        dof: d,
                        point: sig_point[d].unwrap_or([0.0, 0.0]),
                        measure: sig_meas[d],
                    })
                    .collect();

                let find = |r: usize, c: usize| -> u32 {
                    let s = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                    (col_ptr[c] + s.binary_search(&r).expect("entry is in the pattern")) as u32
                };
                let mut pos_ptr = Vec::with_capacity(nc + 1);
                pos_ptr.push(0);
                for k in 0..nc {
                    let p = dof_ptr[k + 1] - dof_ptr[k] - n_int[k] as usize;
                    pos_ptr.push(pos_ptr[k] + p * p);
                }
                let pos: Vec<u32> = cell_chunks(nc)
                    .into_par_iter()
                    .flat_map_iter(|(c0, c1)| {
                        let mut out = Vec::with_capacity(pos_ptr[c1] - pos_ptr[c0]);
                        for k in c0..c1 {
                            let ni = n_int[k] as usize;
                            let sk = &dofs[dof_ptr[k] + ni..dof_ptr[k + 1]];
                            for &j in sk {
                                for &i in sk {
                                    out.push(if i >= j { find(i, j) } else { u32::MAX });
                                }
                            }
                        }
                        out
                    })
                    .collect();
                // --- incidence unknown -> positions in `dofs`, cells ascending (counting sort)
                let mut inc_ptr = vec![0usize; n + 1];
                for &d in &dofs {
                    inc_ptr[d + 1] += 1;
                }
                for i in 0..n {
                    inc_ptr[i + 1] += inc_ptr[i];
                }
                let mut fill = inc_ptr.clone();
                let mut inc = vec![0usize; dofs.len()];
                for (q, &d) in dofs.iter().enumerate() {
                    inc[fill[d]] = q;
                    fill[d] += 1;
                }
                drop(fill);
                // --- sources of each condensed entry (counting sort of the positions by entry)
                if pos.len() >= u32::MAX as usize {
                    return Err(crate::Error::Linear(
                        "more than 2^32 local skeleton entries".into(),
                    ));
                }
                let nnz = row_idx.len();
                let mut src_ptr = vec![0usize; nnz + 1];
                for &q in &pos {
                    if q != u32::MAX {
                        src_ptr[q as usize + 1] += 1;
                    }
                }
                for q in 0..nnz {
                    src_ptr[q + 1] += src_ptr[q];
                }
                let mut fill = src_ptr.clone();
                let mut src = vec![0u32; src_ptr[nnz]];
                for (idx, &q) in pos.iter().enumerate() {
                    if q != u32::MAX {
                        src[fill[q as usize]] = idx as u32;
                        fill[q as usize] += 1;
                    }
                }
                drop(fill);
                Ok(Rest {
                    mat_ptr,
                    mats,
                    loads,
                    load,
                    neumann_load,
                    dirichlet,
                    signorini,
                    pos_ptr,
                    pos,
                    inc_ptr,
                    inc,
                    src_ptr,
                    src,
                })
            },
        );
        let Rest {
            mat_ptr,
            mats,
            loads,
            load,
            neumann_load,
            dirichlet,
            signorini,
            pos_ptr,
            pos,
            inc_ptr,
            inc,
            src_ptr,
            src,
        } = rest?;
        let (pattern, symbolic_seconds) = symbolic?;
        let single_interior = n_int.iter().all(|&ni| ni == 1);
        Ok(DiscreteSystem {
            scheme,
            n_skel,
            n,
            dof_ptr,
            dofs,
            n_int,
            mat_ptr,
            mats,
            loads,
            pos_ptr,
            pos,
            pattern,
            inc_ptr,
            inc,
            src_ptr,
            src,
            single_interior,
            scratch: Mutex::new((Vec::new(), Vec::new())),
            residual_scratch: Mutex::new(Vec::new()),
            last_residual: Mutex::new(None),
            load,
            neumann_load,
            dirichlet,
            signorini,
            setup_seconds: t0.elapsed().as_secs_f64(),
            symbolic_seconds,
        })
    }

    /// The scheme.
    pub fn scheme(&self) -> &'a dyn GradientDiscretisation {
        self.scheme
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
        self.pattern.nnz()
    }
    /// Stored values of the Cholesky factor of the condensed matrix (its fill).
    pub fn factor_len(&self) -> usize {
        self.pattern.factor_len()
    }
    /// Dirichlet unknowns and their values (`None`: not Dirichlet).
    pub fn dirichlet(&self) -> &[Option<f64>] {
        &self.dirichlet
    }
    /// The unknowns carrying the trace on Γ3, including those that are also Dirichlet unknowns
    /// (P1 vertices at Γ1 ∩ Γ3), which are never constrained but must satisfy the barrier.
    pub fn signorini_dofs(&self) -> &[PointDof] {
        &self.signorini
    }
    /// The full load vector b.
    pub fn load(&self) -> &[f64] {
        &self.load
    }

    fn local(&self, k: usize) -> (&[usize], usize, &[f64], &[f64]) {
        let d = &self.dofs[self.dof_ptr[k]..self.dof_ptr[k + 1]];
        (
            d,
            self.n_int[k] as usize,
            &self.mats[self.mat_ptr[k]..self.mat_ptr[k + 1]],
            &self.loads[self.dof_ptr[k]..self.dof_ptr[k + 1]],
        )
    }

    /// Solves the linear system in which the unknowns with `fixed[d] = Some(v)` (and the
    /// Dirichlet unknowns) are fixed. Returns the full unknown vector.
    pub fn solve(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let t0 = Instant::now();
        let fx = |d: usize| -> Option<f64> { self.dirichlet[d].or(fixed[d]) };
        let (values, mut rhs) = self.assemble_condensed(fixed);
        let t1 = Instant::now();
        let factor = self.pattern.factor(&values)?;
        let t2 = Instant::now();
        factor.solve_in_place(&mut rhs);
        let mut u = vec![0.0; self.n];
        u[..self.n_skel].copy_from_slice(&rhs);
        let nc = self.scheme.mesh().n_cells();
        if self.single_interior {
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
        (self.pattern.col_ptr(), self.pattern.row_idx())
    }

    /// Condensed matrix values (in the order of [`Self::condensed_pattern`]) and right-hand
    /// side, with `fixed` and the Dirichlet unknowns fixed (unit rows).
    pub fn assemble_condensed(&self, fixed: &[Option<f64>]) -> (Vec<f64>, Vec<f64>) {
        // the value of each fixed unknown, NaN for a free one (data and barriers are finite)
        let fixed_val: Vec<f64> = (0..self.n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| self.dirichlet[d].or(fixed[d]).unwrap_or(f64::NAN))
            .collect();
        let fx = |d: usize| -> Option<f64> {
            let v = fixed_val[d];
            if v.is_nan() { None } else { Some(v) }
        };
        let nc = self.scheme.mesh().n_cells();
        // condensed local blocks, in parallel: cell k's p×p block at pos_ptr[k], its p loads
        // (minus the fixed columns) at the positions of its skeleton unknowns in `dofs`
        // buffers kept between calls (they are entirely rewritten where read)
        let (mut sbuf, mut gbuf) = self
            .scratch
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        sbuf.resize(self.pos.len(), 0.0);
        gbuf.resize(self.dofs.len(), 0.0);
        {
            let mut tasks = Vec::new();
            let (mut s_rest, mut g_rest) = (&mut sbuf[..], &mut gbuf[..]);
            for (c0, c1) in cell_chunks(nc) {
                let (s_here, s_next) =
                    std::mem::take(&mut s_rest).split_at_mut(self.pos_ptr[c1] - self.pos_ptr[c0]);
                let (g_here, g_next) =
                    std::mem::take(&mut g_rest).split_at_mut(self.dof_ptr[c1] - self.dof_ptr[c0]);
                s_rest = s_next;
                g_rest = g_next;
                tasks.push((c0, c1, s_here, g_here));
            }
            tasks.into_par_iter().for_each(|(c0, c1, s_out, g_out)| {
                for k in c0..c1 {
                    let (d, ni, m, b) = self.local(k);
                    let nl = d.len();
                    let p = nl - ni;
                    let so = self.pos_ptr[k] - self.pos_ptr[c0];
                    let go = self.dof_ptr[k] - self.dof_ptr[c0] + ni;
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
        let (col_ptr, row_idx) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let is_fixed: Vec<bool> = (0..self.n_skel)
            .into_par_iter()
            .with_min_len(4096)
            .map(|d| fx(d).is_some())
            .collect();
        let mut values = vec![0.0; self.pattern.nnz()];
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
                            for &i in &self.src[self.src_ptr[q]..self.src_ptr[q + 1]] {
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
                        let mut acc = self.neumann_load[gi];
                        for &qd in &self.inc[self.inc_ptr[gi]..self.inc_ptr[gi + 1]] {
                            acc += gbuf[qd];
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
        let same = |a: &[f64]| {
            a.len() == u.len() && a.iter().zip(u).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        if let Ok(memo) = self.last_residual.lock()
            && let Some((mu, r, scale)) = memo.as_ref()
            && same(mu)
        {
            return (r.clone(), scale.clone());
        }
        // cell by cell: (M_K u_K)_i and Σ_j |(M_K)_ij u_j| at the position of local entry i
        let nc = self.scheme.mesh().n_cells();
        let mut local = self
            .residual_scratch
            .lock()
            .map(|mut b| std::mem::take(&mut *b))
            .unwrap_or_default();
        local.clear();
        local.resize(self.dofs.len(), [0.0f64; 2]);
        {
            let mut tasks = Vec::new();
            let mut rest = &mut local[..];
            for (c0, c1) in cell_chunks(nc) {
                let (here, next) =
                    std::mem::take(&mut rest).split_at_mut(self.dof_ptr[c1] - self.dof_ptr[c0]);
                rest = next;
                tasks.push((c0, c1, here));
            }
            tasks.into_par_iter().for_each(|(c0, c1, out)| {
                let base = self.dof_ptr[c0];
                for k in c0..c1 {
                    let (d, _, m, _) = self.local(k);
                    let nl = d.len();
                    let o = &mut out[self.dof_ptr[k] - base..self.dof_ptr[k + 1] - base];
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
                let mut a = self.load[gi];
                let mut b = a.abs();
                for &q in &self.inc[self.inc_ptr[gi]..self.inc_ptr[gi + 1]] {
                    a -= local[q][0];
                    b += local[q][1];
                }
                *ri = a;
                *si = b;
            });
        if let Ok(mut b) = self.residual_scratch.lock() {
            *b = local;
        }
        if let Ok(mut memo) = self.last_residual.lock() {
            *memo = Some((u.to_vec(), r.clone(), scale.clone()));
        }
        (r, scale)
    }

    /// The discrete energy ½ uᵀMu − bᵀu (the VI solution minimises it over the convex set).
    pub fn energy(&self, u: &[f64]) -> f64 {
        let (r, _) = self.residual(u);
        // ½uᵀMu − bᵀu = ½uᵀ(Mu − b) − ½bᵀu = −½uᵀr − ½bᵀu
        -0.5 * u.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>()
            - 0.5 * u.iter().zip(&self.load).map(|(a, b)| a * b).sum::<f64>()
    }

    /// The entries of the full (uncondensed) matrix, cell by cell (repeated entries sum).
    pub fn full_matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        let mut t = Vec::new();
        for k in 0..self.scheme.mesh().n_cells() {
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

impl crate::solver::active_set::LinearSystem for DiscreteSystem<'_> {
    fn n_unknowns(&self) -> usize {
        self.n
    }
    fn dirichlet(&self) -> &[Option<f64>] {
        &self.dirichlet
    }
    fn load(&self) -> &[f64] {
        &self.load
    }
    fn solve(&self, fixed: &[Option<f64>]) -> crate::Result<(Vec<f64>, SolveTimings)> {
        DiscreteSystem::solve(self, fixed)
    }
    fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        DiscreteSystem::residual(self, u)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.full_matrix_triplets()
    }
}

/// Condensation of one cell (see the module docs). `s` (length p²) receives the p×p skeleton
/// matrix (column-major) and `g` (length p) the p skeleton loads.
fn condense(
    d: &[usize],
    ni: usize,
    m: &[f64],
    b: &[f64],
    fx: &dyn Fn(usize) -> Option<f64>,
    s: &mut [f64],
    g: &mut [f64],
) {
    let nl = d.len();
    let p = nl - ni;
    for bcol in 0..p {
        for arow in 0..p {
            s[arow + bcol * p] = m[(ni + arow) + (ni + bcol) * nl];
        }
    }
    g.copy_from_slice(&b[ni..]);
    if ni == 0 {
        return;
    }
    if ni == 1 {
        // HMM fast path: one cell unknown
        match fx(d[0]) {
            Some(v) => {
                for arow in 0..p {
                    g[arow] -= m[ni + arow] * v;
                }
            }
            None => {
                let mkk = m[0];
                for bcol in 0..p {
                    let mkb = m[(ni + bcol) * nl];
                    for arow in 0..p {
                        s[arow + bcol * p] -= m[ni + arow] * mkb / mkk;
                    }
                }
                for arow in 0..p {
                    g[arow] -= m[ni + arow] * b[0] / mkk;
                }
            }
        }
        return;
    }
    // general path
    let free: Vec<usize> = (0..ni).filter(|&i| fx(d[i]).is_none()).collect();
    let fixed: Vec<(usize, f64)> = (0..ni).filter_map(|i| fx(d[i]).map(|v| (i, v))).collect();
    let mut br: Vec<f64> = free.iter().map(|&i| b[i]).collect();
    for &(j, v) in &fixed {
        for arow in 0..p {
            g[arow] -= m[(ni + arow) + j * nl] * v;
        }
        for (q, &i) in free.iter().enumerate() {
            br[q] -= m[i + j * nl] * v;
        }
    }
    if free.is_empty() {
        return;
    }
    let r = free.len();
    let mrr = DMatrix::from_fn(r, r, |a, c| m[free[a] + free[c] * nl]);
    let msr = DMatrix::from_fn(p, r, |a, c| m[(ni + a) + free[c] * nl]);
    let chol = mrr
        .cholesky()
        .expect("interior block of an SPD local matrix is SPD");
    let x = chol.solve(&msr.transpose()); // M_RR⁻¹ M_RS
    let y = chol.solve(&DVector::from_vec(br)); // M_RR⁻¹ b_R
    for bcol in 0..p {
        for arow in 0..p {
            s[arow + bcol * p] -= (0..r).map(|q| msr[(arow, q)] * x[(q, bcol)]).sum::<f64>();
        }
    }
    for arow in 0..p {
        g[arow] -= (0..r).map(|q| msr[(arow, q)] * y[q]).sum::<f64>();
    }
}

/// The interior unknown of a cell with exactly one (HMM's u_K), from its skeleton values.
fn interior_value(
    d: &[usize],
    m: &[f64],
    b: &[f64],
    fx: &dyn Fn(usize) -> Option<f64>,
    u: &[f64],
) -> f64 {
    let nl = d.len();
    match fx(d[0]) {
        Some(v) => v,
        None => {
            let mut r = b[0];
            for j in 1..nl {
                r -= m[j * nl] * u[d[j]];
            }
            r / m[0]
        }
    }
}

/// Recovers the interior unknowns of one cell from its skeleton values.
fn recover_interior(
    d: &[usize],
    ni: usize,
    m: &[f64],
    b: &[f64],
    fx: &dyn Fn(usize) -> Option<f64>,
    u: &mut [f64],
) {
    let nl = d.len();
    if ni == 1 {
        u[d[0]] = match fx(d[0]) {
            Some(v) => v,
            None => {
                let mut r = b[0];
                for j in 1..nl {
                    r -= m[j * nl] * u[d[j]];
                }
                r / m[0]
            }
        };
        return;
    }
    let free: Vec<usize> = (0..ni).filter(|&i| fx(d[i]).is_none()).collect();
    for i in 0..ni {
        if let Some(v) = fx(d[i]) {
            u[d[i]] = v;
        }
    }
    if free.is_empty() {
        return;
    }
    let r = free.len();
    let mrr = DMatrix::from_fn(r, r, |a, c| m[free[a] + free[c] * nl]);
    let rhs = DVector::from_fn(r, |a, _| {
        let i = free[a];
        let mut v = b[i];
        for j in 0..nl {
            if !free.contains(&j) {
                v -= m[i + j * nl] * u[d[j]];
            }
        }
        v
    });
    let x = mrr.cholesky().expect("SPD interior block").solve(&rhs);
    for (a, &i) in free.iter().enumerate() {
        u[d[i]] = x[a];
    }
}
