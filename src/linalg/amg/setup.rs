//! Building the hierarchy (see [`super`]): the fine matrix is checked, then each level's
//! smoother, strength of connection, aggregates, prolongator and Galerkin operator, down to
//! the coarsest level and its factorisation.

use super::aggregate::aggregate;
use super::coarse::{CoarseSolve, dense_cholesky};
use super::galerkin::galerkin;
use super::prolong::smoothed_prolongator;
use super::smooth::LevelSmoother;
use super::strength::Strength;
use super::{Amg, AmgOptions, CoarseHierarchy, DENSE_MAX, Fine, Transfer, on_fine};
use crate::budget::try_filled;
use crate::linalg::csr::{CsrMatrix, PAR_MIN_NNZ};
use crate::linalg::rows::MaskedRows;
use crate::linalg::rows::Rows;
use rayon::prelude::*;
use std::borrow::Cow;

impl<'a> Amg<'a> {
    /// Builds the hierarchy of `a` (square, symmetric, positive definite; symmetry is the
    /// caller's, e.g. [`CsrMatrix::from_lower_csc`]).
    ///
    /// Errors: a non-finite entry or a non-positive diagonal entry (naming the row), a missing
    /// diagonal, invalid options, or a coarse operator that is not numerically positive
    /// definite (then neither is `a`).
    pub fn new(a: &'a CsrMatrix, opts: &AmgOptions) -> crate::Result<Self> {
        Amg::build(Fine::Csr(Cow::Borrowed(a)), opts)
    }

    /// [`Amg::new`] keeping `a` (for a hierarchy that outlives the caller's borrow, e.g. kept
    /// to continue a solve later); [`Amg::fine`] gives it back.
    pub fn owning(a: CsrMatrix, opts: &AmgOptions) -> crate::Result<Amg<'static>> {
        Amg::build(Fine::Csr(Cow::Owned(a)), opts)
    }

    /// [`Amg::new`] for the masked view `a` (which it keeps).
    pub fn masked(a: MaskedRows, opts: &AmgOptions) -> crate::Result<Amg<'static>> {
        Amg::build(Fine::Masked(a), opts)
    }

    /// [`Amg::new`] for the fine matrix `fine`.
    pub fn build(fine: Fine<'a>, opts: &AmgOptions) -> crate::Result<Self> {
        opts.check()?;
        on_fine!(&fine, a => validate(a))?;
        let h = on_fine!(&fine, a => hierarchy(a, opts))?;
        Ok(Amg { fine, h })
    }
}

/// The levels below the fine matrix `a` (see [`Amg::new`]).
fn hierarchy<A: Rows + ?Sized>(a: &A, opts: &AmgOptions) -> crate::Result<CoarseHierarchy> {
    let mut coarse_ops: Vec<CsrMatrix> = Vec::new();
    let mut transfers = Vec::new();
    let mut smoothers = Vec::new();
    // the near-null space of the current level (the constants on the fine one)
    let near_null = try_filled(a.n_rows(), 1.0, "the near-null vector")?;
    let mut next = level(a, 0, near_null, opts, &mut smoothers)?;
    while let Some((p, ac, near_null)) = next {
        transfers.push(Transfer { p });
        coarse_ops.push(ac);
        let l = coarse_ops.len();
        next = level(&coarse_ops[l - 1], l, near_null, opts, &mut smoothers)?;
    }
    let coarse = match coarse_ops.last() {
        Some(last) if last.n_rows() <= DENSE_MAX => dense_cholesky(last, coarse_ops.len())?,
        None if a.n_rows() <= DENSE_MAX => dense_cholesky(a, 0)?,
        _ => CoarseSolve::Smooth,
    };
    Ok(CoarseHierarchy {
        n: a.n_rows(),
        coarse_ops,
        transfers,
        smoothers,
        coarse,
    })
}

/// One level of the setup: the smoother of level `level` (operator `al`, near-null space
/// `near_null`), pushed on `smoothers`, and unless this is the coarsest level, the
/// prolongator to the next, the next operator and its near-null space.
#[allow(clippy::type_complexity)]
fn level<A: Rows + ?Sized>(
    al: &A,
    level: usize,
    near_null: Vec<f64>,
    opts: &AmgOptions,
    smoothers: &mut Vec<LevelSmoother>,
) -> crate::Result<Option<(CsrMatrix, CsrMatrix, Vec<f64>)>> {
    let diag = al.try_diagonal()?;
    if level > 0
        && let Some(i) = diag.iter().position(|&d| !(d > 0.0 && d.is_finite()))
    {
        return Err(crate::Error::Linear(format!(
            "multigrid setup: the coarse operator of level {level} has the diagonal \
             entry {:e} at row {i}: the matrix is not positive definite",
            diag[i]
        )));
    }
    smoothers.push(LevelSmoother::new(al, &diag, opts)?);
    let n = al.n_rows();
    if n <= opts.max_coarse || level + 1 >= opts.max_levels {
        return Ok(None);
    }
    let (agg, n_agg) = aggregate(al, &Strength::new(&diag, opts.strength_threshold), &diag)?;
    // stop when coarsening stalls (every row decoupled, or barely any reduction)
    if n_agg == 0 || n_agg as f64 > 0.85 * n as f64 {
        return Ok(None);
    }
    let (p, b_next) = smoothed_prolongator(
        al,
        &diag,
        &agg,
        n_agg,
        &near_null,
        opts.smoothing_threshold,
        opts.spectral_steps,
    )?;
    // the Galerkin product is the setup's largest transient: what the level no longer needs
    // is freed first
    drop((diag, agg, near_null));
    let ac = galerkin(al, &p, &p.transpose()?)?;
    Ok(Some((p, ac, b_next)))
}

/// Checks the fine matrix: square, finite, with a positive diagonal entry in every row. The
/// first offending row (in order) is reported.
pub(super) fn validate<A: Rows + ?Sized>(a: &A) -> crate::Result<()> {
    let n = a.n_rows();
    if a.n_cols() != n {
        return Err(crate::Error::Linear(format!(
            "multigrid: the matrix is {}×{}, not square",
            n,
            a.n_cols()
        )));
    }
    let check_row = |i: usize| check_row(a, i);
    let bad = if a.nnz() < PAR_MIN_NNZ {
        (0..n).find_map(check_row)
    } else {
        (0..n).into_par_iter().find_map_first(check_row)
    };
    invalid(bad)
}

/// [`validate`] on the rows `rows` of `a` only (the others checked before), in their order.
pub(super) fn validate_rows<A: Rows + ?Sized>(a: &A, rows: &[u32]) -> crate::Result<()> {
    invalid(rows.iter().find_map(|&i| check_row(a, i as usize)))
}

/// What is wrong with row i of a fine matrix, if anything: a non-finite entry, or a missing or
/// non-positive diagonal entry.
fn check_row<A: Rows + ?Sized>(a: &A, i: usize) -> Option<String> {
    let (cols, vals) = a.row(i);
    if let Some(k) = vals.iter().position(|v| !v.is_finite()) {
        return Some(format!(
            "row {i} has the non-finite entry {} in column {}",
            vals[k], cols[k]
        ));
    }
    match cols.binary_search(&(i as u32)) {
        Ok(p) if vals[p] > 0.0 => None,
        Ok(p) => Some(format!(
            "row {i} has the non-positive diagonal entry {:e}",
            vals[p]
        )),
        Err(_) => Some(format!("row {i} has no diagonal entry")),
    }
}

/// The error of [`validate`] for the message `bad` of an offending row, if any.
fn invalid(bad: Option<String>) -> crate::Result<()> {
    match bad {
        Some(msg) => Err(crate::Error::Linear(format!(
            "multigrid: {msg} (the matrix must be symmetric positive definite)"
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::super::{AmgWork, Smoother};
    use super::*;
    use crate::linalg::pcg::{PcgOptions, pcg};

    /// The hierarchy of a 300 × 300 grid and a solve with it, again and again in a child
    /// process whose data is limited to what it has plus 0, 1, 2, 4, … MiB:
    /// each ends with the solution or with a typed out-of-memory error (from whichever array
    /// of the setup or of the cycle's workspace failed), never an abort; the smaller limits
    /// fail, the largest succeeds.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_setup_the_data_limit_refuses_is_a_typed_error() {
        use crate::budget::child;
        const NAME: &str =
            "linalg::amg::setup::tests::a_setup_the_data_limit_refuses_is_a_typed_error";
        if !child::is_child(NAME) {
            return child::run(NAME);
        }
        let a = grid(300, 1.0, 1.0, &|_, _| 1.0);
        let b = vec![1.0; a.n_rows()];
        // unlimited solves first, on every thread: the dense factorisation of the coarsest
        // level (faer) maps a product buffer per thread on first use, infallibly, and keeps it
        let solve = || {
            let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
            let mut x = vec![0.0; a.n_rows()];
            pcg(
                &a,
                &amg,
                &mut AmgWork::new(),
                &b,
                &mut x,
                &PcgOptions::default(),
            )
            .unwrap();
        };
        solve();
        rayon::broadcast(|_| solve());
        let mut refused = 0;
        for extra_mib in [0, 1, 2, 4, 8, 16, 32, 1024] {
            let mut x = vec![0.0; a.n_rows()];
            let opts = PcgOptions::default();
            child::limit_data(extra_mib << 20);
            let solved = Amg::new(&a, &AmgOptions::default())
                .and_then(|amg| pcg(&a, &amg, &mut AmgWork::new(), &b, &mut x, &opts));
            child::limit_data(4 << 30);
            match solved {
                Ok(r) => assert!(r.residual_norm <= 1e-6 * (a.n_rows() as f64).sqrt()),
                Err(e) if e.is_out_of_memory() => refused += 1,
                Err(e) => panic!("{extra_mib} MiB: {e}"),
            }
        }
        assert!((1..8).contains(&refused), "{refused} solves refused");
    }

    #[test]
    fn bad_input_is_an_error() {
        let a = grid(10, 1.0, 1.0, &|_, _| 1.0);
        let opts = AmgOptions::default();
        // a NaN entry off the diagonal, in row 13
        let mut nan = a.clone();
        let p = a.row_ptr()[13];
        nan.values_mut()[p] = f64::NAN;
        let e = Amg::new(&nan, &opts).unwrap_err().to_string();
        assert!(e.contains("row 13") && e.contains("non-finite"), "{e}");
        // an infinite diagonal entry
        let mut inf = a.clone();
        let d = a.row_ptr()[40] + a.row(40).0.iter().position(|&j| j == 40).unwrap();
        inf.values_mut()[d] = f64::INFINITY;
        assert!(
            Amg::new(&inf, &opts)
                .unwrap_err()
                .to_string()
                .contains("row 40")
        );
        // a zero and a negative diagonal entry
        for v in [0.0, -1.0] {
            let mut z = a.clone();
            z.values_mut()[d] = v;
            let e = Amg::new(&z, &opts).unwrap_err().to_string();
            assert!(e.contains("row 40") && e.contains("non-positive"), "{e}");
        }
        // a missing diagonal entry
        let nodiag = CsrMatrix::new(2, 2, vec![0, 1, 2], vec![1, 0], vec![1.0, 1.0]).unwrap();
        assert!(Amg::new(&nodiag, &opts).is_err());
        // not square
        let rect = CsrMatrix::new(1, 2, vec![0, 1], vec![0], vec![1.0]).unwrap();
        assert!(Amg::new(&rect, &opts).is_err());
        // bad options
        for o in [
            AmgOptions {
                strength_threshold: 1.5,
                ..opts
            },
            AmgOptions {
                strength_threshold: f64::NAN,
                ..opts
            },
            AmgOptions {
                max_coarse: 0,
                ..opts
            },
            AmgOptions {
                max_levels: 0,
                ..opts
            },
            AmgOptions {
                smoother: Smoother::Chebyshev {
                    degree: 0,
                    ratio: 30.0,
                },
                ..opts
            },
            AmgOptions {
                smoother: Smoother::Chebyshev {
                    degree: 2,
                    ratio: 1.0,
                },
                ..opts
            },
        ] {
            assert!(Amg::new(&a, &o).is_err(), "{o:?}");
        }
        // wrong vector lengths
        let amg = Amg::new(&a, &opts).unwrap();
        let mut z = vec![0.0; 99];
        assert!(amg.apply(&[0.0; 100], &mut z, &mut AmgWork::new()).is_err());
        // an indefinite matrix (positive diagonal): the coarsest factorisation fails, or CG
        // breaks down; an error either way, never a panic
        let mut indef = grid(8, 1.0, 1.0, &|_, _| 1.0);
        for p in 0..indef.nnz() {
            if indef.values()[p] < 0.0 {
                indef.values_mut()[p] = -3.0;
            }
        }
        let b = vec![1.0; 64];
        let mut x = vec![0.0; 64];
        let r = Amg::new(&indef, &opts).and_then(|m| {
            pcg(
                &indef,
                &m,
                &mut AmgWork::new(),
                &b,
                &mut x,
                &PcgOptions::default(),
            )
        });
        assert!(r.is_err());
    }

    #[test]
    fn hierarchy_summary() {
        let a = grid(128, 1.0, 1.0, &|_, _| 1.0);
        let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
        let lv = amg.levels();
        assert_eq!(lv[0].n, 128 * 128);
        assert!(lv.last().unwrap().n <= AmgOptions::default().max_coarse);
        // aggregates of about 3 × 3 unknowns
        assert!(lv.windows(2).all(|w| w[1].n * 5 < w[0].n), "{lv:?}");
        let oc = amg.operator_complexity();
        assert!((1.0..1.6).contains(&oc), "{oc}");
        assert!(amg.memory_bytes() < 3 * a.memory_bytes());
        assert!(amg.coarsest_is_exact());
    }
}
