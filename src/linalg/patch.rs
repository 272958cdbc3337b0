//! A preconditioner corrected by exact solves on a patch of unknowns.
//!
//! When a matrix A changes in a few rows and columns only (the unknowns whose status changed
//! from one active set to the next), a preconditioner M built for the earlier matrix (the
//! coarse levels of its multigrid hierarchy) still treats most of the error well, but not the
//! error near the changes: an unknown freed since has no coarse basis function, and the coarse
//! operators around an unknown fixed since are those of the earlier matrix. A patch P of the
//! unknowns around the changes is small, and A_PP can be factorised exactly: with
//! L = R_Pᵀ A_PP⁻¹ R_P (R_P the restriction to P), the symmetric multiplicative combination
//!
//!   z₁ = L r,   z₂ = z₁ + M (r − A z₁),   z = z₂ + L (r − A z₂)
//!
//! has the error propagation I − B A = (I − L A)(I − M A)(I − L A). Since I − L A is the
//! A-orthogonal projection onto the complement of the patch space, B is symmetric positive
//! definite whenever M is (its A-Rayleigh quotients of I − M A are below 1), and the error on
//! the patch is solved exactly twice per application.
//!
//! Cost: one sparse Cholesky factorisation of A_PP when built (and A_RP kept, the entries on
//! P of the rows R coupled to P); per application, two solves with it, M once, a copy of r,
//! A_RP z₁ (z₁ vanishes off P, so r − A z₁ differs from r on R only, by A_RP z₁) and the rows
//! of A on P.

use super::cholesky::{CholeskyWork, SpdPattern};
use super::pcg::{Preconditioner, zip_chunks2};
use super::rows::{Rows, dot_row};
use crate::budget::{try_filled, try_vec};

/// M corrected by exact solves on a patch (see the module docs).
pub struct PatchCorrected<'a, A: Rows + ?Sized, M: Preconditioner + ?Sized> {
    a: &'a A,
    m: &'a M,
    /// The rows of the patch, increasing.
    patch: Vec<u32>,
    /// The rows coupled to the patch (the patch included), increasing.
    ring: Vec<u32>,
    /// A_RP by rows (R the ring): offsets into `coupling`, one per ring row and one more.
    coupling_ptr: Vec<usize>,
    /// A_RP's entries: the column's position in the patch and the value, in A's column order.
    coupling: Vec<(u32, f64)>,
    /// The symbolic factorisation of A_PP.
    pattern: SpdPattern,
    /// Its numeric factor.
    factor: CholeskyWork,
}

/// The workspace of a [`PatchCorrected`] application: M's own, and two vectors.
pub struct PatchWork<W> {
    /// M's workspace.
    pub inner: W,
    /// r − A z₁ (order of A).
    t: Vec<f64>,
    /// Values on the patch: z₁, and the second correction.
    z1: Vec<f64>,
    local: Vec<f64>,
}

impl<W> PatchWork<W> {
    /// M's workspace back (to keep for the next solve).
    pub fn into_inner(self) -> W {
        self.inner
    }
}

impl<'a, A: Rows + ?Sized, M: Preconditioner + ?Sized> PatchCorrected<'a, A, M> {
    /// M corrected on the patch of the rows within `layers` steps of the rows `seeds` in the
    /// graph of `graph` (a matrix of A's order whose pattern holds A's, such as A before its
    /// unknowns were fixed: an unknown fixed in A keeps its neighbours there). A_PP, read from
    /// A, is factorised here, unless the patch has more than `max_rows` rows or its Cholesky
    /// factor more than `max_factor_len` entries (known from the symbolic analysis, before the
    /// numeric factorisation allocates it): `None` then. Errors: orders that differ, a seed out
    /// of range, A_PP not numerically positive definite, or memory.
    pub fn new<G: Rows + ?Sized>(
        a: &'a A,
        m: &'a M,
        graph: &G,
        seeds: &[u32],
        layers: usize,
        max_rows: usize,
        max_factor_len: usize,
    ) -> crate::Result<Option<Self>> {
        let n = a.n_rows();
        if m.n() != n || graph.n_rows() != n {
            return Err(crate::Error::Linear(format!(
                "patch correction: a matrix of order {n}, a preconditioner of order {} and a \
                 graph of order {}",
                m.n(),
                graph.n_rows()
            )));
        }
        if let Some(&s) = seeds.iter().find(|&&s| s as usize >= n) {
            return Err(crate::Error::Linear(format!(
                "patch correction: seed {s} outside the {n} rows"
            )));
        }
        // breadth-first from the seeds, layer by layer
        let mut seen = try_filled(n.div_ceil(64), 0u64, "the patch mask")?;
        let mark = |i: usize, seen: &mut [u64]| {
            let (w, b) = (i / 64, 1u64 << (i % 64));
            let new = seen[w] & b == 0;
            seen[w] |= b;
            new
        };
        let mut front: Vec<u32> = Vec::new();
        for &s in seeds {
            if mark(s as usize, &mut seen) {
                front.push(s);
            }
        }
        let mut patch = front.clone();
        for _ in 0..layers {
            let mut next = Vec::new();
            for &i in &front {
                for &j in graph.row(i as usize).0 {
                    if mark(j as usize, &mut seen) {
                        next.push(j);
                    }
                }
            }
            patch.extend_from_slice(&next);
            if patch.len() > max_rows {
                return Ok(None);
            }
            front = next;
        }
        if patch.len() > max_rows {
            return Ok(None);
        }
        patch.sort_unstable();
        // the rows coupled to the patch: the columns of its rows in A (A is symmetric)
        let mut ring = patch.clone();
        for &i in &patch {
            for &j in a.row(i as usize).0 {
                if mark(j as usize, &mut seen) {
                    ring.push(j);
                }
            }
        }
        ring.sort_unstable();
        let np = patch.len();
        let local = |j: u32| patch.binary_search(&j).ok();
        // A_RP, so that r − A z₁ is formed on the ring from z₁'s patch values alone
        let mut coupling_ptr = try_vec(ring.len() + 1, "the patch coupling")?;
        let mut coupling = Vec::new();
        coupling_ptr.push(0);
        for &i in &ring {
            let (cols, vals) = a.row(i as usize);
            for (&j, &v) in cols.iter().zip(vals) {
                if let Some(l) = local(j) {
                    coupling.push((l as u32, v));
                }
            }
            coupling_ptr.push(coupling.len());
        }
        // A_PP's lower triangle by columns: column k (row i = patch[k]) holds the entries
        // (j ≥ i, j in P) of row i of A, by symmetry
        let mut col_ptr = try_vec(np + 1, "the patch pattern")?;
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        col_ptr.push(0);
        for &i in &patch {
            let (cols, vals) = a.row(i as usize);
            for (&j, &v) in cols.iter().zip(vals) {
                if j >= i
                    && let Some(l) = local(j)
                {
                    row_idx.push(l);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let pattern = SpdPattern::new(np, col_ptr, row_idx)?;
        if pattern.factor_len() > max_factor_len {
            return Ok(None);
        }
        let mut factor = CholeskyWork::new();
        pattern.factor(&values, &mut factor)?;
        Ok(Some(PatchCorrected {
            a,
            m,
            patch,
            ring,
            coupling_ptr,
            coupling,
            pattern,
            factor,
        }))
    }

    /// Unknowns of the patch.
    pub fn patch_len(&self) -> usize {
        self.patch.len()
    }

    /// A workspace with M's workspace `inner`.
    pub fn work_with(&self, inner: M::Work) -> crate::Result<PatchWork<M::Work>> {
        Ok(PatchWork {
            inner,
            t: try_filled(self.a.n_rows(), 0.0, "the patch correction's residual")?,
            z1: try_filled(self.patch.len(), 0.0, "the patch correction's values")?,
            local: try_filled(self.patch.len(), 0.0, "the patch correction's values")?,
        })
    }
}

impl<A: Rows + ?Sized, M: Preconditioner + ?Sized> Preconditioner for PatchCorrected<'_, A, M> {
    type Work = PatchWork<M::Work>;
    fn n(&self) -> usize {
        self.a.n_rows()
    }
    fn work(&self) -> Self::Work {
        PatchWork {
            inner: self.m.work(),
            t: vec![0.0; self.a.n_rows()],
            z1: vec![0.0; self.patch.len()],
            local: vec![0.0; self.patch.len()],
        }
    }
    fn apply(&self, r: &[f64], z: &mut [f64], work: &mut Self::Work) -> crate::Result<()> {
        let n = self.a.n_rows();
        if r.len() != n || z.len() != n || work.t.len() != n {
            return Err(crate::Error::Linear(format!(
                "patch correction of order {n}: vectors of {}, {} and {} entries",
                r.len(),
                z.len(),
                work.t.len()
            )));
        }
        let factor = self.pattern.factored(&self.factor)?;
        let PatchWork {
            inner,
            t,
            z1,
            local,
        } = work;
        if z1.len() != self.patch.len() || local.len() != self.patch.len() {
            return Err(crate::Error::Linear(format!(
                "patch correction on {} rows: a workspace for {}",
                self.patch.len(),
                z1.len()
            )));
        }
        // z₁ = L r, on the patch (zero off it)
        for (l, &i) in z1.iter_mut().zip(&self.patch) {
            *l = r[i as usize];
        }
        factor.solve_in_place(z1);
        // t = r − A z₁, which differs from r on the ring only, where A z₁ = A_RP z₁ (the
        // terms of A's row on the patch, in A's column order: the sum of the row's full
        // product with z₁ extended by zeros)
        zip_chunks2(t, r, r, |t, r, _| t.copy_from_slice(r));
        for (q, &i) in self.ring.iter().enumerate() {
            let row = &self.coupling[self.coupling_ptr[q]..self.coupling_ptr[q + 1]];
            let mut s = 0.0;
            for &(l, v) in row {
                s += v * z1[l as usize];
            }
            t[i as usize] -= s;
        }
        // z₂ = z₁ + M t (M t written into z, z₁ added back from the patch values)
        self.m.apply(t, z, inner)?;
        for (&l, &i) in z1.iter().zip(&self.patch) {
            z[i as usize] += l;
        }
        // z = z₂ + L (r − A z₂) on the patch
        for (l, &i) in local.iter_mut().zip(&self.patch) {
            let (cols, vals) = self.a.row(i as usize);
            *l = r[i as usize] - dot_row(cols, vals, z);
        }
        factor.solve_in_place(local);
        for (&l, &i) in local.iter().zip(&self.patch) {
            z[i as usize] += l;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::amg::testing::{disc, fix, grid, iterations_with};
    use crate::linalg::pcg::{Jacobi, dot};
    use crate::linalg::{Amg, AmgOptions};

    /// B r for the preconditioner `p`.
    fn apply<P: Preconditioner>(p: &P, r: &[f64]) -> Vec<f64> {
        let mut z = vec![0.0; r.len()];
        p.apply(r, &mut z, &mut p.work()).unwrap();
        z
    }

    #[test]
    fn the_correction_is_symmetric_and_exact_on_a_patch_of_every_row() {
        let a = grid(20, 1.0, 3.0, &|i, j| 1.0 + ((i * 7 + j * 3) % 5) as f64);
        let n = a.n_rows();
        let jacobi = Jacobi::new(&a).unwrap();
        // a patch of 2 layers around two unknowns: B is symmetric (uᵀ B v = vᵀ B u)
        let pc = PatchCorrected::new(&a, &jacobi, &a, &[45, 210], 2, n, usize::MAX)
            .unwrap()
            .unwrap();
        assert_eq!(pc.patch_len(), 2 * 13);
        let u: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        let (uv, vu) = (dot(&u, &apply(&pc, &v)), dot(&v, &apply(&pc, &u)));
        assert!((uv - vu).abs() <= 1e-12 * uv.abs().max(1.0), "{uv} {vu}");
        // PCG converges with it (B is positive definite)
        assert!(iterations_with(&a, &pc) > 1);
        // a patch of every row: B = A⁻¹, one iteration
        let whole = PatchCorrected::new(&a, &jacobi, &a, &[0], 2 * 20, n, usize::MAX)
            .unwrap()
            .unwrap();
        assert_eq!(whole.patch_len(), n);
        assert_eq!(iterations_with(&a, &whole), 1);
    }

    #[test]
    fn a_reused_hierarchy_corrected_on_the_patch_converges_like_a_new_one() {
        // the thick rings of `amg::reuse`'s test, where the coarse levels of the earlier
        // matrix alone took at least 5 more iterations than new ones
        let m = 150;
        let opts = AmgOptions::default();
        let disc = |r2: f64| disc(m, r2);
        let base = grid(m, 1.0, 1.0, &|_, _| 1.0);
        let a0 = fix(&base, &disc(0.09));
        for r2 in [0.1, 0.08] {
            let a1 = fix(&base, &disc(r2));
            let fresh = iterations_with(&a1, &Amg::owning(a1.clone(), &opts).unwrap());
            let reused = Amg::owning(a0.clone(), &opts)
                .unwrap()
                .into_coarse()
                .unwrap()
                .with_fine(a1.clone().into(), &opts)
                .unwrap();
            let alone = iterations_with(&a1, &reused);
            let seeds: Vec<u32> = (0..m * m)
                .filter(|&k| disc(0.09)(k) != disc(r2)(k))
                .map(|k| k as u32)
                .collect();
            let pc = PatchCorrected::new(&a1, &reused, &base, &seeds, 6, m * m, a1.nnz())
                .unwrap()
                .unwrap();
            let patched = iterations_with(&a1, &pc);
            // measured (fresh, reused alone, reused and patched): (12, 19, 13) growing,
            // (12, 26, 12) shrinking, on patches of 3872 and 3664 of the 22 500 unknowns
            assert!(
                patched <= fresh + 1 && patched + 5 <= alone,
                "r² = {r2}: fresh {fresh}, reused {alone}, patched {patched}"
            );
        }
    }

    #[test]
    fn a_patch_too_large_is_declined_and_bad_input_refused() {
        let a = grid(20, 1.0, 1.0, &|_, _| 1.0);
        let n = a.n_rows();
        let jacobi = Jacobi::new(&a).unwrap();
        // 13 rows within two layers of an inner unknown
        let new =
            |max_rows, max_len| PatchCorrected::new(&a, &jacobi, &a, &[45], 2, max_rows, max_len);
        assert!(new(12, usize::MAX).unwrap().is_none());
        assert!(new(13, usize::MAX).unwrap().is_some());
        assert!(new(n, 0).unwrap().is_none());
        // a seed outside the matrix, a graph of another order
        assert!(PatchCorrected::new(&a, &jacobi, &a, &[n as u32], 2, n, usize::MAX).is_err());
        let small = grid(10, 1.0, 1.0, &|_, _| 1.0);
        assert!(PatchCorrected::new(&a, &jacobi, &small, &[0], 2, n, usize::MAX).is_err());
        // a workspace of another patch
        let pc = new(n, usize::MAX).unwrap().unwrap();
        let other = PatchCorrected::new(&a, &jacobi, &a, &[45], 1, n, usize::MAX)
            .unwrap()
            .unwrap();
        let r = vec![1.0; n];
        let mut z = vec![0.0; n];
        assert!(pc.apply(&r, &mut z, &mut other.work()).is_err());
    }
}
