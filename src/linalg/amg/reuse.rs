//! Keeping the coarse levels of a hierarchy to precondition a changed fine matrix of the same
//! order ([`CoarseHierarchy`]).

use super::setup::{validate, validate_rows};
use super::smooth::LevelSmoother;
use super::{Amg, AmgOptions, CoarseHierarchy, Fine, on_fine};
use crate::linalg::rows::Rows;

impl Amg<'_> {
    /// The hierarchy without its fine matrix (which is freed), to precondition a changed
    /// fine matrix later ([`CoarseHierarchy::with_fine`]); `None` for a one-level hierarchy,
    /// whose only operator is the fine matrix (factorised: nothing to reuse).
    pub fn into_coarse(self) -> Option<CoarseHierarchy> {
        if self.h.coarse_ops.is_empty() {
            return None;
        }
        // the fine level's smoother data is rebuilt by `with_fine`: freed now (8 bytes per
        // fine unknown less while the next matrix is assembled)
        let mut h = self.h;
        h.smoothers[0] = LevelSmoother::empty();
        Some(h)
    }
}

impl Amg<'static> {
    /// This hierarchy for the fine matrix `a` of the same order, whose rows differ from those
    /// of its own fine matrix in the ascending `rows` at most (the caller's guarantee, as
    /// [`crate::linalg::MaskedRows::remask`] gives it): those rows are checked as
    /// [`CoarseHierarchy::with_fine`] checks a whole matrix, the fine smoother's data of those
    /// rows is rebuilt, and the rest is kept. The result is the hierarchy `with_fine` makes
    /// of `a` from these coarse levels, to the bit, at a cost in the rows only; a smoother
    /// whose data is not row by row (Chebyshev) is rebuilt whole.
    pub fn with_changed_fine(
        self,
        a: Fine<'static>,
        rows: &[u32],
        opts: &AmgOptions,
    ) -> crate::Result<Amg<'static>> {
        opts.check()?;
        if a.n() != self.h.n {
            return Err(crate::Error::Linear(format!(
                "multigrid: a hierarchy built for order {} cannot precondition a matrix of \
                 order {}",
                self.h.n,
                a.n()
            )));
        }
        if let Some(&r) = rows.last().filter(|&&r| r as usize >= a.n()) {
            return Err(crate::Error::Linear(format!(
                "multigrid: changed row {r} of a matrix of order {}",
                a.n()
            )));
        }
        on_fine!(&a, m => validate_rows(m, rows))?;
        let mut h = self.h;
        if !on_fine!(&a, m => h.smoothers[0].update_rows(m, rows, opts)) {
            on_fine!(&a, m => validate(m))?;
            h.smoothers[0] = on_fine!(&a, m => LevelSmoother::new(m, &m.try_diagonal()?, opts))?;
        }
        Ok(Amg { fine: a, h })
    }
}

impl CoarseHierarchy {
    /// Order of the fine matrix it was built for.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The hierarchy of `a` (square, symmetric, positive definite, of order [`Self::n`]) with
    /// these coarse levels (see the type's docs). Errors: another order, or what
    /// [`Amg::new`] rejects in a fine matrix (a non-finite entry, a missing or non-positive
    /// diagonal entry).
    pub fn with_fine(self, a: Fine<'static>, opts: &AmgOptions) -> crate::Result<Amg<'static>> {
        opts.check()?;
        if a.n() != self.n {
            return Err(crate::Error::Linear(format!(
                "multigrid: a hierarchy built for order {} cannot precondition a matrix of \
                 order {}",
                self.n,
                a.n()
            )));
        }
        on_fine!(&a, m => validate(m))?;
        let mut h = self;
        h.smoothers[0] = on_fine!(&a, m => LevelSmoother::new(m, &m.try_diagonal()?, opts))?;
        Ok(Amg { fine: a, h })
    }
}

#[cfg(test)]
mod tests {
    use super::super::AmgWork;
    use super::super::testing::{disc, fix, grid, iterations_with};
    use super::*;

    #[test]
    fn a_coarse_hierarchy_preconditions_a_changed_matrix() {
        let m = 150;
        let opts = AmgOptions::default();
        let disc = |r2: f64| disc(m, r2);
        let base = grid(m, 1.0, 1.0, &|_, _| 1.0);
        let a0 = fix(&base, &disc(0.09));
        let fresh0 = Amg::owning(a0.clone(), &opts).unwrap();
        // the same matrix again: the same cycle, to the bit
        let same = Amg::owning(a0.clone(), &opts)
            .unwrap()
            .into_coarse()
            .unwrap()
            .with_fine(a0.clone().into(), &opts)
            .unwrap();
        let r: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.11).cos()).collect();
        let (mut z0, mut z1) = (vec![0.0; m * m], vec![0.0; m * m]);
        fresh0.apply(&r, &mut z0, &mut AmgWork::new()).unwrap();
        same.apply(&r, &mut z1, &mut AmgWork::new()).unwrap();
        assert_eq!(z0, z1);
        // the contact disc grows or shrinks by a ring of unknowns: the old coarse levels still
        // precondition (the cycle is SPD: PCG reaches the true residual), about as well as
        // new ones when the ring is thin
        let iters = |r2: f64| {
            let a1 = fix(&base, &disc(r2));
            let fresh = iterations_with(&a1, &Amg::owning(a1.clone(), &opts).unwrap());
            let coarse = Amg::owning(a0.clone(), &opts)
                .unwrap()
                .into_coarse()
                .unwrap();
            assert_eq!(coarse.n(), m * m);
            let reused = iterations_with(&a1, &coarse.with_fine(a1.clone().into(), &opts).unwrap());
            (fresh, reused)
        };
        // measured (fresh, reused) iterations: a thin ring, 32 to 84 unknowns (0.1–0.4%):
        // (12, 12) to (12, 14); a thick one, about 700 (3%): (12, 19) growing, (12, 26)
        // shrinking — hence the bound on the changed fraction of `assembly::REUSE_MAX_CHANGED`
        for r2 in [0.0895, 0.0905, 0.089, 0.091] {
            let (fresh, reused) = iters(r2);
            assert!(
                reused <= fresh + 3,
                "r² = {r2}: reused {reused}, fresh {fresh}"
            );
        }
        for r2 in [0.1, 0.08] {
            let (fresh, reused) = iters(r2);
            assert!(
                reused >= fresh + 5 && reused <= 3 * fresh,
                "r² = {r2}: reused {reused}, fresh {fresh}"
            );
        }
        // another order is an error; a one-level hierarchy has no coarse levels to keep
        let coarse = fresh0.into_coarse().unwrap();
        let small = grid(10, 1.0, 1.0, &|_, _| 1.0);
        assert!(coarse.with_fine(small.clone().into(), &opts).is_err());
        assert!(Amg::owning(small, &opts).unwrap().into_coarse().is_none());
    }

    #[test]
    fn a_hierarchy_updated_in_the_changed_rows_is_the_one_rebuilt_on_its_coarse_levels() {
        use crate::linalg::MaskedRows;
        use std::sync::Arc;
        let m = 120;
        let base = Arc::new(grid(m, 1.0, 1.0, &|_, _| 1.0));
        let (f0, f1) = (disc(m, 0.09), disc(m, 0.0905));
        let v0 = MaskedRows::new(base.clone(), &f0).unwrap();
        let changed: Vec<u32> = (0..m * m)
            .filter(|&k| f0(k) != f1(k))
            .map(|k| k as u32)
            .collect();
        assert!(!changed.is_empty());
        let rows = v0.rows_touched_by(&changed).unwrap();
        let v1 = v0.remask(&f1, &rows).unwrap();
        let r: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.11).cos()).collect();
        let apply = |amg: &Amg| {
            let mut z = vec![0.0; m * m];
            amg.apply(&r, &mut z, &mut AmgWork::new()).unwrap();
            z
        };
        let chebyshev = AmgOptions {
            smoother: crate::linalg::amg::Smoother::Chebyshev {
                degree: 2,
                ratio: 30.0,
            },
            ..AmgOptions::default()
        };
        let jacobi = AmgOptions {
            smoother: crate::linalg::amg::Smoother::L1Jacobi,
            ..AmgOptions::default()
        };
        for opts in [AmgOptions::default(), jacobi, chebyshev] {
            let amg0 = Amg::masked(v0.clone(), &opts).unwrap();
            assert!(amg0.n_levels() > 1);
            let rebuilt = amg0
                .clone()
                .into_coarse()
                .unwrap()
                .with_fine(v1.clone().into(), &opts)
                .unwrap();
            let updated = amg0
                .clone()
                .with_changed_fine(v1.clone().into(), &rows, &opts)
                .unwrap();
            assert_eq!(apply(&updated), apply(&rebuilt), "{:?}", opts.smoother);
            // the old fine level's smoother on the new matrix: another cycle (so the
            // comparison above can fail)
            if opts.smoother != chebyshev.smoother {
                let stale = amg0
                    .clone()
                    .with_changed_fine(v1.clone().into(), &[], &opts)
                    .unwrap();
                assert_ne!(apply(&stale), apply(&rebuilt), "{:?}", opts.smoother);
            }
        }
        // a row out of range, another order, a changed row that is not positive definite:
        // errors
        let opts = AmgOptions::default();
        let amg0 = Amg::masked(v0.clone(), &opts).unwrap();
        let n = (m * m) as u32;
        assert!(
            amg0.clone()
                .with_changed_fine(v1.clone().into(), &[n], &opts)
                .is_err()
        );
        let small = grid(10, 1.0, 1.0, &|_, _| 1.0);
        assert!(
            amg0.clone()
                .with_changed_fine(small.into(), &[], &opts)
                .is_err()
        );
        let mut bad = fix(&base, &f1);
        let d = bad.row_ptr()[77] + bad.row(77).0.binary_search(&77).unwrap();
        bad.values_mut()[d] = -1.0;
        let e = amg0
            .with_changed_fine(bad.into(), &[3, 77], &opts)
            .unwrap_err();
        assert!(e.to_string().contains("row 77"), "{e}");
    }
}
