//! A dense quadratic energy, to drive the algorithms of [`super`] with crafted matrices in the
//! unit tests.

use super::{ConstrainedDof, Constraints, FixedValues, QuadraticEnergy, Side, SolveTimings};
use nalgebra::{DMatrix, DVector};

/// ½uᵀMu − bᵀu with dense M and Dirichlet unknowns.
#[derive(Clone)]
pub struct Dense {
    pub m: DMatrix<f64>,
    pub b: Vec<f64>,
    pub dir: FixedValues,
}

impl QuadraticEnergy for Dense {
    fn n_unknowns(&self) -> usize {
        self.b.len()
    }
    fn dirichlet(&self) -> &FixedValues {
        &self.dir
    }
    fn load(&self) -> &[f64] {
        &self.b
    }
    fn minimise_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.solve(fixed)
    }
    fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        let n = self.b.len();
        let mut r = self.b.clone();
        let mut s: Vec<f64> = self.b.iter().map(|x| x.abs()).collect();
        for i in 0..n {
            for (j, uj) in u.iter().enumerate() {
                r[i] -= self.m[(i, j)] * uj;
                s[i] += (self.m[(i, j)] * uj).abs();
            }
        }
        Ok((r, s))
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        let n = self.b.len();
        (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| (i, j, self.m[(i, j)]))
            .collect()
    }
    fn row_entries(&self, rows: &[usize]) -> crate::Result<Option<Vec<(usize, usize, f64)>>> {
        let n = self.b.len();
        Ok(Some(
            rows.iter()
                .flat_map(|&i| (0..n).map(move |j| (i, j)))
                .filter(|&(i, j)| self.m[(i, j)] != 0.0)
                .map(|(i, j)| (i, j, self.m[(i, j)]))
                .collect(),
        ))
    }
}

impl Dense {
    /// The minimiser with `fixed` (a dense Cholesky solve; nothing kept between solves).
    pub fn solve(&self, fixed: &FixedValues) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let n = self.b.len();
        let fx = |i: usize| self.dir.get(i).or(fixed.get(i));
        let free: Vec<usize> = (0..n).filter(|&i| fx(i).is_none()).collect();
        let mut u: Vec<f64> = (0..n).map(|i| fx(i).unwrap_or(0.0)).collect();
        let a = DMatrix::from_fn(free.len(), free.len(), |i, j| self.m[(free[i], free[j])]);
        let r = DVector::from_fn(free.len(), |i, _| {
            let fi = free[i];
            self.b[fi]
                - (0..n)
                    .filter(|&j| fx(j).is_some())
                    .map(|j| self.m[(fi, j)] * u[j])
                    .sum::<f64>()
        });
        let x = a
            .cholesky()
            .ok_or_else(|| crate::Error::Linear("dense test matrix is not SPD".into()))?
            .solve(&r);
        for (i, &fi) in free.iter().enumerate() {
            u[fi] = x[i];
        }
        Ok((u, SolveTimings::default()))
    }
}

/// [`Dense`] with inexact screening solves: [`QuadraticEnergy::screen_with_fixed`] returns the
/// exact minimiser plus `error` · (−1)^i on the free unknowns (marked inexact), and
/// [`QuadraticEnergy::refine`] the exact one; counts the refinements.
pub struct Screening {
    pub exact: Dense,
    pub error: f64,
    pub refinements: usize,
}

impl QuadraticEnergy for Screening {
    fn n_unknowns(&self) -> usize {
        self.exact.n_unknowns()
    }
    fn dirichlet(&self) -> &FixedValues {
        self.exact.dirichlet()
    }
    fn load(&self) -> &[f64] {
        self.exact.load()
    }
    fn minimise_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.exact.solve(fixed)
    }
    fn screen_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let (mut u, t) = self.exact.solve(fixed)?;
        for (i, ui) in u.iter_mut().enumerate() {
            if !fixed.is_fixed(i) && !self.exact.dir.is_fixed(i) {
                *ui += if i % 2 == 0 { self.error } else { -self.error };
            }
        }
        Ok((u, SolveTimings { inexact: true, ..t }))
    }
    fn refine(&mut self, fixed: &FixedValues) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.refinements += 1;
        self.exact.solve(fixed).map(Some)
    }
    fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        self.exact.residual(u)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.exact.matrix_triplets()
    }
    fn row_entries(&self, rows: &[usize]) -> crate::Result<Option<Vec<(usize, usize, f64)>>> {
        self.exact.row_entries(rows)
    }
}

/// [`Screening`] whose inexact iterates are partial ([`SolveTimings::partial`]): the `derived`
/// unknowns (never constrained, never coupled with each other, like HMM's eliminated faces)
/// are NaN, and recovered from their rows, u_σ = (b_σ − Σ_{j≠σ} M_σj u_j) / M_σσ. Counts the
/// partial iterates it returned.
pub struct Partial {
    pub inner: Screening,
    pub derived: Vec<bool>,
    pub partial_iterates: usize,
}

impl Partial {
    /// The value of derived unknown `s` from the others of `u`.
    fn recovered(&self, u: &[f64], s: usize) -> f64 {
        let m = &self.inner.exact.m;
        let sum: f64 = (0..u.len())
            .filter(|&j| j != s && m[(s, j)] != 0.0)
            .map(|j| m[(s, j)] * u[j])
            .sum();
        (self.inner.exact.b[s] - sum) / m[(s, s)]
    }
}

impl QuadraticEnergy for Partial {
    fn n_unknowns(&self) -> usize {
        self.inner.n_unknowns()
    }
    fn dirichlet(&self) -> &FixedValues {
        self.inner.dirichlet()
    }
    fn load(&self) -> &[f64] {
        self.inner.load()
    }
    fn minimise_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        self.inner.minimise_with_fixed(fixed)
    }
    fn screen_with_fixed(
        &mut self,
        fixed: &FixedValues,
    ) -> crate::Result<(Vec<f64>, SolveTimings)> {
        let (mut u, t) = self.inner.screen_with_fixed(fixed)?;
        for (ui, &d) in u.iter_mut().zip(&self.derived) {
            if d {
                *ui = f64::NAN;
            }
        }
        self.partial_iterates += 1;
        Ok((u, SolveTimings { partial: true, ..t }))
    }
    fn refine(&mut self, fixed: &FixedValues) -> crate::Result<Option<(Vec<f64>, SolveTimings)>> {
        self.inner.refine(fixed)
    }
    fn residual(&self, u: &[f64]) -> crate::Result<(Vec<f64>, Vec<f64>)> {
        self.inner.residual(u)
    }
    fn partial_values(&self, u: &[f64], at: &[usize]) -> crate::Result<Vec<f64>> {
        Ok(at
            .iter()
            .map(|&j| {
                if self.derived[j] {
                    self.recovered(u, j)
                } else {
                    u[j]
                }
            })
            .collect())
    }
    fn complete(&self, u: &mut [f64]) -> crate::Result<()> {
        for s in (0..u.len()).filter(|&s| self.derived[s]) {
            u[s] = self.recovered(u, s);
        }
        Ok(())
    }
    fn partial_residual_at(
        &self,
        u: &[f64],
        len: usize,
        row: &(dyn Fn(usize) -> usize + Sync),
    ) -> crate::Result<(Vec<f64>, f64)> {
        let mut whole = u.to_vec();
        self.complete(&mut whole)?;
        self.residual_at(&whole, len, row)
    }
    fn matrix_triplets(&self) -> Vec<(usize, usize, f64)> {
        self.inner.matrix_triplets()
    }
    fn row_entries(&self, rows: &[usize]) -> crate::Result<Option<Vec<(usize, usize, f64)>>> {
        self.inner.row_entries(rows)
    }
}

/// Constraints s(u_j − g_j) ≤ 0 on every unknown, with unit measures.
pub fn all_constrained(n: usize, barrier: Vec<f64>, side: Side) -> Constraints {
    Constraints {
        dofs: (0..n)
            .map(|i| ConstrainedDof {
                dof: i,
                point: (),
                measure: 1.0,
            })
            .collect(),
        barrier,
        side,
    }
}

/// The 1D Laplacian tridiag(−1, 2, −1) of size n (an M-matrix).
pub fn laplacian_1d(n: usize) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |i, j| match i.abs_diff(j) {
        0 => 2.0,
        1 => -1.0,
        _ => 0.0,
    })
}

/// A deterministic SPD matrix (full, diagonally shifted) of size n.
pub fn spd(n: usize, seed: u64) -> DMatrix<f64> {
    let mut s = seed;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let b = DMatrix::from_fn(n, n, |_, _| rnd());
    &b * b.transpose() + DMatrix::identity(n, n) * 0.5
}

/// The 3×3 system on which the plain active-set method cycles (found by a random search: SPD,
/// not an M-matrix), with upper barriers 0 on all three unknowns.
pub fn cycling_system() -> (Dense, Constraints) {
    let m = DMatrix::from_row_slice(3, 3, &[2.25, -2.5, 4.0, -2.5, 4.75, -5.5, 4.0, -5.5, 8.0]);
    let sys = Dense {
        m,
        b: vec![0.0, 0.75, -0.75],
        dir: FixedValues::free(3).unwrap(),
    };
    (sys, all_constrained(3, vec![0.0; 3], Side::Upper))
}
