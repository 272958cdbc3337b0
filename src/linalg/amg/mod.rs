//! Algebraic multigrid by smoothed aggregation (Vaněk, Mandel & Brezina 1996), a
//! preconditioner for the conjugate gradients of [`mod@super::pcg`] on the symmetric positive
//! definite systems of the active-set solver.
//!
//! ## The hierarchy (setup, [`Amg::new`])
//! From A₀ = A (n₀ × n₀), each level ℓ builds a prolongator P_ℓ (n_ℓ × n_{ℓ+1}) and the
//! Galerkin operator A_{ℓ+1} = P_ℓᵀ A_ℓ P_ℓ, until n_ℓ ≤ `max_coarse`, where A_ℓ is factorised
//! densely (A_ℓ = L Lᵀ). With D = diag(A_ℓ):
//!
//! 1. **Strength of connection**: j ≠ i is strongly connected to i when
//!    a_ij ≠ 0 and |a_ij| ≥ θ √(a_ii a_jj) (symmetric in i and j). S is the strong part of A;
//!    the *filtered* matrix A_F keeps the strong entries and lumps the weak ones into the
//!    diagonal, d^F_i = a_ii − Σ_{j weak} a_ij (so A_F 1 = A 1: it keeps the constants' image).
//!    θ = 0 keeps every nonzero (right for the isotropic M-matrices of P1 on Cartesian grids);
//!    θ > 0 drops the weak direction of an anisotropic diffusion, so that aggregates follow the
//!    strong one (semi-coarsening) and P does not smear across it.
//! 2. **Aggregation** (greedy, three phases, in the order of the unknowns): (i) an unknown whose
//!    strong neighbours are all free founds an aggregate with them; (ii) each unknown left
//!    joins the aggregate of phase (i) it is most strongly connected to; (iii) whatever is
//!    left founds aggregates with its free strong neighbours. An unknown with no strong
//!    neighbour (*isolated*: the unit rows of fixed unknowns, or rows whose couplings are all
//!    weak) belongs to no aggregate; the smoother alone corrects it, exactly so for a unit row.
//! 3. **Tentative prolongator**: the constant near-null space restricted to each aggregate
//!    𝒜_J, normalised: T_iJ = 1/√|𝒜_J| for i ∈ 𝒜_J, 0 else (orthonormal columns).
//! 4. **Prolongator smoothing**: one damped Jacobi step on the filtered matrix,
//!    P = (I − ω D_F⁻¹ A_F) T, ω = 4 / (3 ρ(D_F⁻¹ A_F)), with ρ bounded by Gershgorin,
//!    ρ ≤ max_i (d^F_i + Σ_j |s_ij|) / d^F_i (= 2 for a zero-row-sum M-matrix, where it is
//!    sharp); on levels with positive off-diagonal entries, where that bound overestimates,
//!    by a Lanczos estimate of λ_max(D⁻¹A) × 1.1 when smaller ([`AmgOptions::spectral_steps`]).
//!    P's columns are then smooth, low-energy basis functions overlapping their
//!    neighbours.
//! 5. **Galerkin product** A_{ℓ+1} = Pᵀ A P row by row, in parallel, with R = Pᵀ: row J of
//!    R A, Σ_{i : r_Ji ≠ 0} r_Ji A_i (= ((A P)ᵀ)_J, A symmetric), is accumulated in a dense
//!    array with a list of the touched columns, then row J of A_{ℓ+1} = Σ_k (R A)_Jk P_k in a
//!    second one (two per thread); R A is never stored. Entries a_ij stored as zeros (the
//!    diagonal couplings of P1 on right triangles, the zeroed couplings of unit rows) and
//!    zero entries of P are skipped. Storing R A between two products, as this did before,
//!    held a matrix with as many entries as A P, twice while its rows were concatenated: the
//!    peak of the 2D solves (`replication/BENCHMARKS.md`, "Measurements behind the defaults").
//!
//! The strength of connection is not stored: the aggregation evaluates the rule where it
//! reads an entry of A_ℓ (a flag per entry would be an array of the size of A_ℓ's entries).
//!
//! ## The cycle (one application of M⁻¹, [`Amg::apply`])
//! A V(1,1)-cycle: on level ℓ with right-hand side b, from x = 0,
//!
//!   x ← S_ℓ(b) (pre-smoothing), r = b − A_ℓ x, x_c = cycle_{ℓ+1}(Pᵀ r), x ← x + P x_c,
//!   x ← x + S_ℓ'(b − A_ℓ x) (post-smoothing),
//!
//! and x = A_L⁻¹ b on the coarsest level (two triangular solves). With a post-smoother the
//! adjoint of the pre-smoother and both convergent in the A-norm, the cycle is a symmetric
//! positive definite operator (a requirement of conjugate gradients).
//!
//! Smoothers ([`Smoother`]):
//! - **Chebyshev** of degree k on D⁻¹A: x ← x + q(D⁻¹A) D⁻¹ r where
//!   1 − λq(λ) is the Chebyshev polynomial of degree k on [λ_max/ratio, λ_max], scaled to 1 at 0;
//!   it damps that interval (the oscillatory modes; the coarse grid takes the rest) uniformly.
//!   λ_max is the Gershgorin bound max_i Σ_j |a_ij|/a_ii (an upper bound, as the polynomial
//!   needs, and sharp for the M-matrices of these schemes), or with `spectral_steps` > 0 (the
//!   default) a few Lanczos steps
//!   (× 1.1, capped by Gershgorin). Pre and post are the same polynomial, which is symmetric
//!   in the A-inner product; every step is a product with A, run on all cores.
//! - **l1-Jacobi**: x ← x + D_1⁻¹ (b − A x) with (D_1)_ii = Σ_j |a_ij| (convergent for any SPD
//!   A; weaker: a damping of about ½ on the 5-point stencil).
//! - **l1-Gauss–Seidel** (the default; hybrid; Baker, Falgout, Kolev & Yang 2011): the rows are cut into
//!   blocks of consecutive rows (their size depends on n only, so the result does not depend
//!   on the number of threads); Gauss–Seidel within a block, Jacobi across blocks, with the
//!   diagonal increased by Σ_{j outside the block} |a_ij| (which makes it convergent for any
//!   SPD A). Forward sweep before, backward sweep after the coarse correction (the adjoint).
//!
//! The choice of smoother and of θ was made by measurement (`benches/amg.rs`,
//! `make bench-amg`); see [`AmgOptions::default`].
//!
//! ## State
//! A hierarchy ([`Amg`]) does not change once built: [`Amg::apply`] takes `&self` and the
//! vectors of the cycle in a workspace the caller owns and passes `&mut` ([`AmgWork`], sized
//! on first use and reused by the next cycles). The workspace's contents never change a
//! result: every vector is written before it is read, so a cycle gives the same bits through a
//! fresh workspace or a used one.
//!
//! ## Files
//! One step per file of `src/linalg/amg/`: `options.rs` (the parameters), `setup.rs`
//! (building the hierarchy and checking the matrix), `strength.rs` (step 1), `aggregate.rs`
//! (step 2), `prolong.rs` (steps 3 and 4), `galerkin.rs` (step 5), `rows.rs` (building a
//! matrix row by row in parallel), `spectral.rs` (bounds of λ_max(D⁻¹A)), `smooth.rs` (the
//! smoothers), `coarse.rs` (the coarsest solve), `cycle.rs` (the V-cycle and its workspace)
//! and `reuse.rs` (keeping the coarse levels for a changed matrix); each with its tests.
//!
//! The fine level is a [`Fine`]: a matrix stored by rows or a masked view of one
//! ([`MaskedRows`], the system of a solve with fixed unknowns without a copy of the matrix).
//! Every step reads it through [`Rows`], compiled for its own type (`on_fine!` dispatches
//! once per product or sweep, not per row); the coarse operators are stored by rows.

mod aggregate;
mod coarse;
mod cycle;
mod galerkin;
mod options;
mod prolong;
mod reuse;
mod rows;
mod setup;
mod smooth;
mod spectral;
mod strength;
#[cfg(test)]
pub(crate) mod testing;

pub use cycle::AmgWork;
pub use options::{AmgOptions, Smoother};

use crate::linalg::csr::CsrMatrix;
use crate::linalg::rows::{MaskedRows, Rows};
use coarse::CoarseSolve;
use smooth::LevelSmoother;
use std::borrow::Cow;

/// "No aggregate" / "no position".
const NONE: u32 = u32::MAX;

/// Largest coarsest level that is factorised densely; if coarsening stalls above it (rows
/// with no strong connection everywhere), the last level is smoothed instead (see
/// [`Amg::new`]).
const DENSE_MAX: usize = 4000;

/// Size of one level of the hierarchy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelSummary {
    /// Unknowns.
    pub n: usize,
    /// Stored entries of A_ℓ.
    pub nnz: usize,
}

/// The transfer between level ℓ and ℓ + 1: P; the restriction applies Pᵀ by scattering the
/// rows of P ([`CsrMatrix::mul_transpose_to`]). R = Pᵀ is formed only for the Galerkin product
/// and freed: stored, it would be about a third of the hierarchy, for a faster restriction
/// (`replication/BENCHMARKS.md`, "Measurements behind the defaults").
#[derive(Debug, Clone)]
struct Transfer {
    p: CsrMatrix,
}

/// The fine matrix A₀ of a hierarchy: stored by rows (borrowed or owned), or the masked
/// view of a shared matrix ([`MaskedRows`]: the system of a solve with fixed unknowns,
/// without a copy of the matrix).
#[derive(Debug, Clone)]
pub enum Fine<'a> {
    /// Stored by rows.
    Csr(Cow<'a, CsrMatrix>),
    /// A masked view.
    Masked(MaskedRows),
}

/// `$body` with `$a` bound to the fine matrix `$fine` ([`Fine`]) as its own type, so that
/// the loops over its rows are compiled for that type (no dispatch per row).
macro_rules! on_fine {
    ($fine:expr, $a:ident => $body:expr) => {
        match $fine {
            $crate::linalg::amg::Fine::Csr(m) => {
                let $a: &$crate::linalg::CsrMatrix = m;
                $body
            }
            $crate::linalg::amg::Fine::Masked(m) => {
                let $a: &$crate::linalg::MaskedRows = m;
                $body
            }
        }
    };
}
pub(crate) use on_fine;

impl From<CsrMatrix> for Fine<'static> {
    fn from(a: CsrMatrix) -> Self {
        Fine::Csr(Cow::Owned(a))
    }
}

impl From<MaskedRows> for Fine<'static> {
    fn from(a: MaskedRows) -> Self {
        Fine::Masked(a)
    }
}

impl Fine<'_> {
    /// Order.
    pub fn n(&self) -> usize {
        on_fine!(self, a => a.n_rows())
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        on_fine!(self, a => Rows::nnz(a))
    }

    /// ‖b − A₀ x‖₂.
    pub fn residual_norm(&self, b: &[f64], x: &[f64]) -> f64 {
        on_fine!(self, a => a.residual_norm(b, x))
    }
}

/// A smoothed-aggregation multigrid preconditioner for a symmetric positive definite matrix
/// (see the module documentation): the fine matrix ([`Fine`]) and the hierarchy built from
/// it. Built by [`Amg::new`], [`Amg::owning`] or [`Amg::masked`], applied by [`Amg::apply`]
/// with a workspace ([`AmgWork`]) the caller owns.
#[derive(Debug, Clone)]
pub struct Amg<'a> {
    /// A₀.
    fine: Fine<'a>,
    /// Everything else.
    h: CoarseHierarchy,
}

/// A multigrid hierarchy without its fine level ([`Amg::into_coarse`]): the transfers, the
/// coarse operators A_1, …, A_L, their smoothers and the coarsest solve, built for a fine
/// matrix A₀.
///
/// [`CoarseHierarchy::with_fine`] makes it the hierarchy of another matrix A₀' of the same
/// order: the fine level takes A₀' and its smoother is rebuilt from A₀'; P and the coarse
/// levels stay those of A₀. The cycle is still a symmetric positive definite operator (its
/// smoother converges in the A₀'-norm, the coarse correction P A_1⁻¹ Pᵀ is semi-definite), so
/// conjugate gradients converge on A₀' with it; how fast depends on how far A₀' is from A₀.
/// The active-set iteration changes the condensed matrix only in the rows and columns of
/// the unknowns whose status changed (a small fraction after the first solves), and saves a
/// whole setup per solve this way ([`crate::assembly::DiscreteSystem`]).
#[derive(Debug, Clone)]
pub struct CoarseHierarchy {
    /// Order of the fine matrix it was built for.
    n: usize,
    coarse_ops: Vec<CsrMatrix>,
    transfers: Vec<Transfer>,
    /// Every level's; the fine level's is empty (freed by [`Amg::into_coarse`]) until
    /// [`CoarseHierarchy::with_fine`] builds it for the new matrix.
    smoothers: Vec<LevelSmoother>,
    coarse: CoarseSolve,
}

impl<'a> Amg<'a> {
    /// The fine matrix A₀, given back (a copy if it was borrowed).
    pub fn into_fine(self) -> Fine<'static> {
        match self.fine {
            Fine::Csr(a) => Fine::Csr(Cow::Owned(a.into_owned())),
            Fine::Masked(m) => Fine::Masked(m),
        }
    }

    /// The fine matrix A₀.
    pub fn fine(&self) -> &Fine<'a> {
        &self.fine
    }

    /// Order of the fine matrix.
    pub fn n(&self) -> usize {
        self.fine.n()
    }

    /// Number of levels (≥ 1).
    pub fn n_levels(&self) -> usize {
        self.h.coarse_ops.len() + 1
    }

    /// Unknowns and stored entries of each level, fine to coarse.
    pub fn levels(&self) -> Vec<LevelSummary> {
        let fine = LevelSummary {
            n: self.fine.n(),
            nnz: self.fine.nnz(),
        };
        std::iter::once(fine)
            .chain(self.h.coarse_ops.iter().map(|a| LevelSummary {
                n: a.n_rows(),
                nnz: a.nnz(),
            }))
            .collect()
    }

    /// Operator complexity Σ_ℓ nnz(A_ℓ) / nnz(A₀).
    pub fn operator_complexity(&self) -> f64 {
        let total: usize = self.levels().iter().map(|l| l.nnz).sum();
        total as f64 / self.fine.nnz().max(1) as f64
    }

    /// Whether the coarsest level is solved exactly (false when coarsening stalled above the
    /// dense limit and that level is only smoothed).
    pub fn coarsest_is_exact(&self) -> bool {
        matches!(self.h.coarse, CoarseSolve::Dense { .. })
    }

    /// Bytes held by the hierarchy (coarse operators, transfers, smoother data and the
    /// coarsest factor), the fine matrix and the workspace ([`AmgWork::memory_bytes`])
    /// excluded.
    pub fn memory_bytes(&self) -> usize {
        let ops: usize = self.h.coarse_ops.iter().map(|a| a.memory_bytes()).sum();
        let tr: usize = self.h.transfers.iter().map(|t| t.p.memory_bytes()).sum();
        let sm: usize = self.h.smoothers.iter().map(|s| s.memory_bytes()).sum();
        ops + tr + sm + self.h.coarse.memory_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::testing::{fix, grid, iterations};
    use super::*;
    use crate::linalg::pcg::{PcgOptions, pcg};

    #[test]
    fn poisson_iterations_do_not_grow_with_the_grid() {
        let opts = AmgOptions::default();
        let counts: Vec<usize> = [64, 128, 256, 512]
            .iter()
            .map(|&m| iterations(&grid(m, 1.0, 1.0, &|_, _| 1.0), &opts))
            .collect();
        // measured (default options): [11, 11, 14, 13]; bound ≤ 18, and the count at 512 at
        // most 4 above the count at 64
        assert!(counts.iter().all(|&c| c <= 18), "{counts:?}");
        assert!(counts[3] <= counts[0] + 4, "{counts:?}");
    }

    #[test]
    fn anisotropic_and_jump_coefficients() {
        let opts = AmgOptions::default();
        // ε = 0.01 in x, m = 64, 128, 256: measured [10, 10, 11]; bound ≤ 16, growth ≤ 4
        let aniso: Vec<usize> = [64, 128, 256]
            .iter()
            .map(|&m| iterations(&grid(m, 0.01, 1.0, &|_, _| 1.0), &opts))
            .collect();
        assert!(aniso.iter().all(|&c| c <= 16), "{aniso:?}");
        assert!(aniso[2] <= aniso[0] + 4, "{aniso:?}");
        // checkerboard of 8 × 8 blocks, coefficients 1 and 1000, m = 64, 128, 256: measured
        // [11, 11, 14]; bound ≤ 20, growth ≤ 6
        let jump: Vec<usize> = [64, 128, 256]
            .iter()
            .map(|&m| {
                let k = move |i: usize, j: usize| {
                    if (i * 8 / m + j * 8 / m).is_multiple_of(2) {
                        1.0
                    } else {
                        1000.0
                    }
                };
                iterations(&grid(m, 1.0, 1.0, &k), &opts)
            })
            .collect();
        assert!(jump.iter().all(|&c| c <= 20), "{jump:?}");
        assert!(jump[2] <= jump[0] + 6, "{jump:?}");
    }

    #[test]
    fn fixed_unknowns_as_unit_rows() {
        // a disc and a band of fixed unknowns, plus scattered single ones
        let m = 200;
        let fixed = |k: usize| {
            let (i, j) = (k % m, k / m);
            let (x, y) = (i as f64 / m as f64 - 0.5, j as f64 / m as f64 - 0.5);
            x * x + y * y < 0.09 || (j == 20) || k.is_multiple_of(97)
        };
        let a = fix(&grid(m, 1.0, 1.0, &|_, _| 1.0), &fixed);
        let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
        // the fixed unknowns are in no aggregate: the first coarse level is smaller than the
        // free unknowns / 3
        let free = (0..m * m).filter(|&k| !fixed(k)).count();
        assert!(amg.levels()[1].n < free / 3, "{:?}", amg.levels());
        let c = iterations(&a, &AmgOptions::default());
        // measured 12; the bound of the Poisson test
        assert!(c <= 18, "{c}");
        // every unknown fixed: a diagonal matrix, no coarse level, one iteration
        let all = fix(&grid(80, 1.0, 1.0, &|_, _| 1.0), &|_| true);
        let amg = Amg::new(&all, &AmgOptions::default()).unwrap();
        assert_eq!(amg.n_levels(), 1);
        assert!(!amg.coarsest_is_exact());
        assert!(iterations(&all, &AmgOptions::default()) <= 2);
    }

    #[test]
    fn a_masked_view_gives_the_hierarchy_and_solve_of_its_copy() {
        // large enough that the setup, the sweeps and the products run in parallel
        let m = 260;
        let a = grid(m, 1.0, 0.5, &|i, _| 1.0 + (i % 5) as f64);
        let fixed = |k: usize| {
            let (x, y) = (
                (k % m) as f64 / m as f64 - 0.4,
                (k / m) as f64 / m as f64 - 0.5,
            );
            x * x + y * y < 0.04 || k.is_multiple_of(89)
        };
        let mut copy = fix(&a, &fixed);
        copy.drop_zeros();
        let view = MaskedRows::new(std::sync::Arc::new(a), fixed).unwrap();
        assert!(view.patched_rows() > 0);
        let opts = AmgOptions::default();
        let (from_copy, from_view) = (
            Amg::new(&copy, &opts).unwrap(),
            Amg::masked(view, &opts).unwrap(),
        );
        assert!(from_copy.n_levels() >= 3);
        assert_eq!(from_copy.levels(), from_view.levels());
        let b: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.23).sin()).collect();
        let opts = PcgOptions {
            rtol: 1e-10,
            atol: 0.0,
            max_iter: 100,
        };
        let solve = |amg: &Amg| {
            let mut x = vec![0.0; m * m];
            let rep = amg.pcg(&mut AmgWork::new(), &b, &mut x, &opts).unwrap();
            (x, rep.iterations, rep.residual_norm)
        };
        let (x0, x1) = (solve(&from_copy), solve(&from_view));
        assert!(x0.1 > 3 && x0.2 <= 1e-10 * b.iter().map(|v| v * v).sum::<f64>().sqrt());
        assert_eq!(x0, x1);
        // reused coarse levels under another view of the same matrix: again the same bits
        let other = |k: usize| fixed(k) || k % m == 7;
        let mut copy2 = fix(&copy, &other);
        copy2.drop_zeros();
        let view2 = match from_view.fine() {
            Fine::Masked(v) => MaskedRows::new(v.unmasked().clone(), other).unwrap(),
            Fine::Csr(_) => unreachable!("built from a view"),
        };
        let c0 = from_copy
            .into_coarse()
            .unwrap()
            .with_fine(copy2.into(), &AmgOptions::default());
        let c1 = from_view
            .into_coarse()
            .unwrap()
            .with_fine(view2.into(), &AmgOptions::default());
        assert_eq!(solve(&c0.unwrap()), solve(&c1.unwrap()));
    }

    #[test]
    fn empty_and_tiny_matrices() {
        let empty = CsrMatrix::new(0, 0, vec![0], vec![], vec![]).unwrap();
        let amg = Amg::new(&empty, &AmgOptions::default()).unwrap();
        assert_eq!(amg.n_levels(), 1);
        let rep = pcg(
            &empty,
            &amg,
            &mut amg.work(),
            &[],
            &mut [],
            &PcgOptions::default(),
        )
        .unwrap();
        assert_eq!(rep.iterations, 0);
        // 1 × 1: solved exactly by the coarsest factorisation
        let one = CsrMatrix::new(1, 1, vec![0, 1], vec![0], vec![4.0]).unwrap();
        let amg = Amg::new(&one, &AmgOptions::default()).unwrap();
        let mut z = [0.0];
        amg.apply(&[2.0], &mut z, &mut AmgWork::new()).unwrap();
        assert!((z[0] - 0.5).abs() < 1e-15);
    }
}
