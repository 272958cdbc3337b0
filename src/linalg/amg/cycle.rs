//! The V(1,1)-cycle, one application of M⁻¹ (see [`super`]), and its workspace.

use super::coarse::{CoarseSolve, dense_solve};
use super::{Amg, on_fine};
use crate::budget::{AllocFailure, try_resize};
use crate::linalg::pcg::{PcgOptions, PcgReport, Preconditioner, check_len, pcg};
use crate::linalg::rows::Rows;

/// Vectors of one level.
#[derive(Debug, Clone, Default)]
pub(super) struct LevelWork {
    /// Right-hand side and solution of this level (unused on the fine level: the caller's).
    pub(super) b: Vec<f64>,
    pub(super) x: Vec<f64>,
    /// Residual and two smoother vectors.
    pub(super) r: Vec<f64>,
    pub(super) d0: Vec<f64>,
    pub(super) d1: Vec<f64>,
}

impl LevelWork {
    /// Gives each vector the length `level` of `amg` needs (keeping its memory when it has
    /// it already), or [`AllocFailure`] if it cannot be had.
    fn fit(&mut self, amg: &Amg, level: usize) -> Result<(), AllocFailure> {
        let n = amg.order(level);
        let bx = if level > 0 { n } else { 0 };
        let dd = amg.h.smoothers[level].vectors();
        let what = "the vectors of the multigrid cycle";
        try_resize(&mut self.b, bx, 0.0, what)?;
        try_resize(&mut self.x, bx, 0.0, what)?;
        try_resize(&mut self.r, n, 0.0, what)?;
        try_resize(&mut self.d0, if dd >= 1 { n } else { 0 }, 0.0, what)?;
        try_resize(&mut self.d1, if dd >= 2 { n } else { 0 }, 0.0, what)
    }

    /// Stored values.
    fn len(&self) -> usize {
        self.b.len() + self.x.len() + self.r.len() + self.d0.len() + self.d1.len()
    }
}

/// The workspace of the multigrid cycle ([`Amg::apply`]): the vectors of every level, owned by
/// the caller and kept from one cycle to the next (a conjugate-gradient solve applies the
/// cycle once per iteration). One workspace serves any hierarchy: each application gives its
/// vectors the lengths that hierarchy needs, allocating only when they change. Its contents
/// never change a result (every vector is written before it is read).
#[derive(Debug, Clone, Default)]
pub struct AmgWork {
    /// Level ℓ's vectors at index ℓ.
    levels: Vec<LevelWork>,
}

impl AmgWork {
    /// Empty: the first cycle sizes it.
    pub fn new() -> Self {
        Self::default()
    }

    /// Bytes held by the vectors.
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(LevelWork::len).sum::<usize>() * std::mem::size_of::<f64>()
    }

    /// Gives the vectors the lengths `amg` needs, or [`AllocFailure`] if they cannot be had.
    fn fit(&mut self, amg: &Amg) -> Result<(), AllocFailure> {
        self.levels.resize_with(amg.n_levels(), LevelWork::default);
        for (level, w) in self.levels.iter_mut().enumerate() {
            w.fit(amg, level)?;
        }
        Ok(())
    }
}

impl Amg<'_> {
    /// A workspace sized for this hierarchy (the same as [`AmgWork::new`] after one cycle);
    /// aborts, as `vec!` does, if it cannot be allocated (a solve passes [`AmgWork::new`]
    /// instead, which [`Amg::apply`] sizes or fails with a typed error).
    pub fn work(&self) -> AmgWork {
        let mut work = AmgWork::new();
        work.fit(self).unwrap_or_else(|f| f.abort());
        work
    }

    /// z = M⁻¹ r: one V(1,1)-cycle from z = 0, with the vectors of `work`.
    pub fn apply(&self, r: &[f64], z: &mut [f64], work: &mut AmgWork) -> crate::Result<()> {
        check_len("multigrid preconditioner", self.n(), r.len(), z.len())?;
        work.fit(self)?;
        self.cycle(0, r, z, &mut work.levels);
        Ok(())
    }

    /// Order of level ℓ.
    fn order(&self, level: usize) -> usize {
        match level {
            0 => self.n(),
            l => self.h.coarse_ops[l - 1].n_rows(),
        }
    }

    /// x = cycle_ℓ(b) (x is overwritten); `work[k]` holds the vectors of level ℓ + k.
    fn cycle(&self, level: usize, b: &[f64], x: &mut [f64], work: &mut [LevelWork]) {
        match level {
            0 => on_fine!(&self.fine, a => self.cycle_on(a, 0, b, x, work)),
            l => self.cycle_on(&self.h.coarse_ops[l - 1], l, b, x, work),
        }
    }

    /// [`Self::cycle`] on level ℓ, whose operator is `a`.
    fn cycle_on<A: Rows + ?Sized>(
        &self,
        a: &A,
        level: usize,
        b: &[f64],
        x: &mut [f64],
        work: &mut [LevelWork],
    ) {
        let Some((w, rest)) = work.split_first_mut() else {
            return;
        };
        let sm = &self.h.smoothers[level];
        if level + 1 == self.n_levels() {
            match &self.h.coarse {
                CoarseSolve::Dense { n, l } => dense_solve(*n, l, b, x),
                CoarseSolve::Smooth => {
                    sm.pre(a, b, x, w);
                    sm.post(a, b, x, w);
                }
            }
            return;
        }
        sm.pre(a, b, x, w);
        let t = &self.h.transfers[level];
        if let Some((next, _)) = rest.split_first_mut() {
            let (mut nb, mut nx) = (std::mem::take(&mut next.b), std::mem::take(&mut next.x));
            t.p.mul_transpose_to(&w.r, &mut nb);
            self.cycle(level + 1, &nb, &mut nx, rest);
            t.p.mul_add_to(&nx, x);
            let next = &mut rest[0];
            next.b = nb;
            next.x = nx;
        }
        sm.post(a, b, x, w);
    }
}

impl Amg<'_> {
    /// Conjugate gradients on A₀ x = b (A₀ the fine matrix) from `x`, preconditioned by this
    /// hierarchy with the workspace `work` (see [`pcg()`]).
    pub fn pcg(
        &self,
        work: &mut AmgWork,
        b: &[f64],
        x: &mut [f64],
        opts: &PcgOptions,
    ) -> crate::Result<PcgReport> {
        on_fine!(&self.fine, a => pcg(a, self, work, b, x, opts))
    }
}

impl Preconditioner for Amg<'_> {
    type Work = AmgWork;
    fn n(&self) -> usize {
        Amg::n(self)
    }
    fn work(&self) -> AmgWork {
        Amg::work(self)
    }
    fn apply(&self, r: &[f64], z: &mut [f64], work: &mut AmgWork) -> crate::Result<()> {
        Amg::apply(self, r, z, work)
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::super::{AmgOptions, Smoother};
    use super::*;
    use crate::linalg::pcg::{PcgOptions, dot};

    #[test]
    fn the_cycle_is_symmetric_positive_definite() {
        let k = |i: usize, j: usize| {
            if (i / 7 + j / 5).is_multiple_of(2) {
                1.0
            } else {
                50.0
            }
        };
        let a = grid(70, 1.0, 0.3, &k);
        for smoother in [
            Smoother::Chebyshev {
                degree: 2,
                ratio: 30.0,
            },
            Smoother::L1Jacobi,
            Smoother::L1GaussSeidel,
        ] {
            let amg = Amg::new(
                &a,
                &AmgOptions {
                    smoother,
                    max_coarse: 40,
                    ..AmgOptions::default()
                },
            )
            .unwrap();
            assert!(amg.n_levels() >= 3);
            let n = a.n_rows();
            let u: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).sin()).collect();
            let v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos() + 0.1).collect();
            let (mut mu, mut mv) = (vec![0.0; n], vec![0.0; n]);
            let mut work = AmgWork::new();
            amg.apply(&u, &mut mu, &mut work).unwrap();
            amg.apply(&v, &mut mv, &mut work).unwrap();
            let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
            assert!(
                (vmu - umv).abs() <= 1e-10 * vmu.abs().max(umv.abs()),
                "{smoother:?}: {vmu} vs {umv}"
            );
            assert!(dot(&u, &mu) > 0.0 && dot(&v, &mv) > 0.0);
            // deterministic: the same result twice
            let mut again = vec![0.0; n];
            amg.apply(&u, &mut again, &mut work).unwrap();
            assert_eq!(again, mu);
        }
    }

    /// The solution of A x = b by conjugate gradients with the hierarchy `amg` and `work`,
    /// from x = 0, to 1e-10, and the iterations.
    fn solve(amg: &Amg, b: &[f64], work: &mut AmgWork) -> (Vec<f64>, usize) {
        let mut x = vec![0.0; b.len()];
        let opts = PcgOptions {
            rtol: 1e-10,
            atol: 0.0,
            max_iter: 200,
        };
        let rep = amg.pcg(work, b, &mut x, &opts).unwrap();
        (x, rep.iterations)
    }

    #[test]
    fn a_reused_workspace_gives_the_bits_of_a_fresh_one() {
        // large enough that the products and sweeps run in parallel
        let a = grid(300, 1.0, 0.2, &|i, _| 1.0 + (i % 7) as f64);
        let n = a.n_rows();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        for smoother in [
            Smoother::L1GaussSeidel,
            Smoother::Chebyshev {
                degree: 2,
                ratio: 30.0,
            },
        ] {
            let opts = AmgOptions {
                smoother,
                ..AmgOptions::default()
            };
            let amg = Amg::new(&a, &opts).unwrap();
            assert!(amg.n_levels() >= 3);
            // two solves through fresh workspaces (one empty, one sized): the same bits
            let (x0, it0) = solve(&amg, &b, &mut AmgWork::new());
            assert!(it0 > 3);
            assert_eq!(solve(&amg, &b, &mut amg.work()), (x0.clone(), it0));
            // a workspace that served another hierarchy and right-hand side, then this one
            // twice: the same bits, and no growth from one solve to the next
            let small = grid(40, 1.0, 1.0, &|_, _| 1.0);
            let other = Amg::new(&small, &opts).unwrap();
            let mut work = AmgWork::new();
            solve(&other, &vec![1.0; small.n_rows()], &mut work);
            let b2: Vec<f64> = b.iter().map(|v| v.cos()).collect();
            assert_ne!(solve(&amg, &b2, &mut work).0, x0);
            assert_eq!(solve(&amg, &b, &mut work), (x0.clone(), it0));
            let bytes = work.memory_bytes();
            assert_eq!(bytes, amg.work().memory_bytes());
            assert_eq!(solve(&amg, &b, &mut work), (x0.clone(), it0));
            assert_eq!(work.memory_bytes(), bytes);
        }
    }
}
