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
//! 2. scatters into the fixed pattern; a fixed skeleton unknown keeps its row and column in the
//!    pattern with a unit diagonal and zeros elsewhere, its value moved to the right-hand side;
//! 3. refactorises numerically, solves, and recovers the interior unknowns.
//!
//! The pattern and the symbolic factorisation never change, whatever is fixed.

use crate::mesh::Point;
use crate::problem::{BoundaryKind, Problem, check_finite, check_tensor};
use crate::scheme::{GradientDiscretisation, PointDof};
use crate::solver::linear::SpdPattern;
use nalgebra::{DMatrix, DVector};
use std::time::Instant;

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
    diag_pos: Vec<u32>,
    pattern: SpdPattern,
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
    /// Of which: the symbolic factorisation, seconds.
    pub symbolic_seconds: f64,
}

impl<'a> DiscreteSystem<'a> {
    /// Evaluates the data of `problem` on the scheme's mesh and builds the system.
    pub fn new(scheme: &'a dyn GradientDiscretisation, problem: &Problem) -> crate::Result<Self> {
        let t0 = Instant::now();
        let mesh = scheme.mesh();
        let nc = mesh.n_cells();
        let n_skel = scheme.n_skeleton();
        let n = scheme.n_unknowns();

        // --- local matrices and loads
        let mut dof_ptr = Vec::with_capacity(nc + 1);
        dof_ptr.push(0);
        let mut dofs = Vec::new();
        let mut n_int = Vec::with_capacity(nc);
        let mut mat_ptr = Vec::with_capacity(nc + 1);
        mat_ptr.push(0);
        let mut mats = Vec::new();
        let mut loads = Vec::new();
        let mut ld = Vec::new();
        let mut m = DMatrix::zeros(0, 0);
        let mut b = DVector::zeros(0);
        let mut bad_source: Option<crate::Error> = None;
        for k in 0..nc {
            let xk = mesh.centroid(k);
            let a = (problem.diffusion)(xk);
            check_tensor(&a, &format!("x_K = {xk:?} (cell {k})"))?;
            scheme.local_dofs(k, &mut ld);
            scheme.local_matrix(k, &a, &mut m);
            let f = |p: Point| -> f64 {
                match &problem.source_in_cell {
                    Some(g) => g(p, xk),
                    None => (problem.source)(p),
                }
            };
            scheme.local_load(k, &f, &mut b);
            if bad_source.is_none() && b.iter().any(|x| !x.is_finite()) {
                bad_source = Some(crate::Error::InvalidData(format!(
                    "the source term f is not finite in cell {k} (x_K = {xk:?})"
                )));
            }
            let ni = scheme.n_local_interior(k);
            n_int.push(ni as u8);
            dofs.extend_from_slice(&ld);
            dof_ptr.push(dofs.len());
            // column-major storage of the local matrix
            mats.extend_from_slice(m.as_slice());
            mat_ptr.push(mats.len());
            loads.extend(b.iter());
        }
        if let Some(e) = bad_source {
            return Err(e);
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
        pairs.sort_unstable();
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
        let find = |r: usize, c: usize| -> u32 {
            let s = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            (col_ptr[c] + s.binary_search(&r).expect("entry is in the pattern")) as u32
        };
        let mut pos_ptr = Vec::with_capacity(nc + 1);
        pos_ptr.push(0);
        let mut pos = Vec::new();
        for k in 0..nc {
            let ni = n_int[k] as usize;
            let sk = &dofs[dof_ptr[k] + ni..dof_ptr[k + 1]];
            for &j in sk {
                for &i in sk {
                    pos.push(if i >= j { find(i, j) } else { u32::MAX });
                }
            }
            pos_ptr.push(pos.len());
        }
        let diag_pos: Vec<u32> = (0..n_skel).map(|d| find(d, d)).collect();
        let t_sym = Instant::now();
        let pattern = SpdPattern::new(n_skel, col_ptr, row_idx)?;
        let symbolic_seconds = t_sym.elapsed().as_secs_f64();
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
            diag_pos,
            pattern,
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
        for k in 0..self.scheme.mesh().n_cells() {
            let (d, ni, m, b) = self.local(k);
            if ni > 0 {
                recover_interior(d, ni, m, b, &fx, &mut u);
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
        let fx = |d: usize| -> Option<f64> { self.dirichlet[d].or(fixed[d]) };
        let mut values = vec![0.0; self.pattern.nnz()];
        // boundary (Neumann) loads; the local loads are added by the condensation below
        let mut rhs = self.neumann_load.clone();
        let mut s = Vec::new();
        let mut gvec = Vec::new();
        for k in 0..self.scheme.mesh().n_cells() {
            let (d, ni, m, b) = self.local(k);
            let nl = d.len();
            let p = nl - ni;
            condense(d, ni, m, b, &fx, &mut s, &mut gvec);
            let pos = &self.pos[self.pos_ptr[k]..self.pos_ptr[k + 1]];
            for bcol in 0..p {
                let gj = d[ni + bcol];
                let fj = fx(gj);
                for arow in 0..p {
                    let gi = d[ni + arow];
                    if fx(gi).is_some() {
                        continue;
                    }
                    let v = s[arow + bcol * p];
                    match fj {
                        Some(vj) => rhs[gi] -= v * vj,
                        None => {
                            let q = pos[arow + bcol * p];
                            if q != u32::MAX {
                                values[q as usize] += v;
                            }
                        }
                    }
                }
            }
            for arow in 0..p {
                let gi = d[ni + arow];
                if fx(gi).is_none() {
                    rhs[gi] += gvec[arow];
                }
            }
        }
        for dd in 0..self.n_skel {
            if let Some(v) = fx(dd) {
                values[self.diag_pos[dd] as usize] = 1.0;
                rhs[dd] = v;
            }
        }
        (values, rhs)
    }

    /// The residual r = b − M u of the full (uncondensed) system, and for each unknown the
    /// scale |b_i| + Σ_j |M_ij u_j| against which it is small. On Dirichlet unknowns r is the
    /// reaction, not a balance; on constrained unknowns it is the multiplier (up to sign).
    pub fn residual(&self, u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut r = self.load.clone();
        let mut scale: Vec<f64> = self.load.iter().map(|x| x.abs()).collect();
        for k in 0..self.scheme.mesh().n_cells() {
            let (d, _, m, _) = self.local(k);
            let nl = d.len();
            for (j, &gj) in d.iter().enumerate() {
                let uj = u[gj];
                for (i, &gi) in d.iter().enumerate() {
                    let v = m[i + j * nl] * uj;
                    r[gi] -= v;
                    scale[gi] += v.abs();
                }
            }
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

/// Condensation of one cell (see the module docs). `s` receives the p×p skeleton matrix
/// (column-major) and `g` the p skeleton loads.
fn condense(
    d: &[usize],
    ni: usize,
    m: &[f64],
    b: &[f64],
    fx: &dyn Fn(usize) -> Option<f64>,
    s: &mut Vec<f64>,
    g: &mut Vec<f64>,
) {
    let nl = d.len();
    let p = nl - ni;
    s.clear();
    g.clear();
    for bcol in 0..p {
        for arow in 0..p {
            s.push(m[(ni + arow) + (ni + bcol) * nl]);
        }
    }
    g.extend_from_slice(&b[ni..]);
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
