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
//! 5. **Galerkin product** A_{ℓ+1} = Pᵀ A P in two row-parallel products, each row
//!    accumulated in a dense array with a list of the touched columns (one per thread):
//!    first R A with R = Pᵀ, row J = Σ_{i : r_Ji ≠ 0} r_Ji A_i (= ((A P)ᵀ)_J, A symmetric),
//!    then R is freed and row J of A_{ℓ+1} = Σ_k (R A)_Jk P_k. Entries a_ij stored as zeros
//!    (the diagonal couplings of P1 on right triangles, the zeroed couplings of unit rows)
//!    are skipped. The transient R A has as many entries as A P; forming it instead of A P
//!    lets R go before the second product (on the ex9 P1 matrix at 1M unknowns, the peak of
//!    the setup 20–30 MiB lower; the order of the sums, not the products, differs).
//!    Measured before on the same matrix (2 cores, noisy): the fused product without a
//!    transient, row J = Σ_i p_iJ Σ_j a_ij P_j, redid each a_ij P_j once per entry of row i
//!    of P (≈ 2.5 times) and took ≈ 250–275 ms against ≈ 190–200 ms in two products; whole
//!    setup (best of 7, `make bench-amg -- setup`) 0.55–0.62 s → 0.24–0.30 s on P1,
//!    0.86 → 0.63 s on HMM (2M unknowns). Dropping the zero products also removes entries of
//!    the coarse operators (hierarchy 147.5 → 141 MiB).
//!
//! The strength of connection is a flag per stored entry of A_ℓ (not a copy of the strong
//! part), filled in parallel; the aggregation reads A_ℓ through it.
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
//! The choice of smoother and of θ was made by measurement (`benches/amg.rs`, `make bench-amg`, release
//! build, 2 cores); see [`AmgOptions::default`].

use super::csr::{CsrMatrix, PAR_MIN_NNZ, ROW_CHUNK};
use super::pcg::{Preconditioner, check_len, dot};
use rayon::prelude::*;
use std::sync::{Mutex, TryLockError};

/// "No aggregate" / "no position".
const NONE: u32 = u32::MAX;

/// Largest coarsest level that is factorised densely; if coarsening stalls above it (rows
/// with no strong connection everywhere), the last level is smoothed instead (see
/// [`Amg::new`]).
const DENSE_MAX: usize = 4000;

/// The smoother of each level (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Smoother {
    /// Chebyshev polynomial of D⁻¹A of the given degree (≥ 1) on [λ_max/ratio, λ_max].
    Chebyshev {
        /// Degree (number of products with A per application).
        degree: usize,
        /// λ_max over the lower end of the damped interval (> 1).
        ratio: f64,
    },
    /// x ← x + D_1⁻¹ (b − A x), (D_1)_ii = Σ_j |a_ij|.
    L1Jacobi,
    /// Hybrid l1-Gauss–Seidel: forward before, backward after the coarse correction.
    L1GaussSeidel,
}

/// Parameters of the multigrid hierarchy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmgOptions {
    /// θ of the strength of connection |a_ij| ≥ θ √(a_ii a_jj), in [0, 1).
    pub strength_threshold: f64,
    /// Coarsening stops once a level has at most this many unknowns (≤ 4000, as that level is
    /// factorised densely).
    pub max_coarse: usize,
    /// At most this many levels (≥ 1), the fine one included.
    pub max_levels: usize,
    /// The smoother.
    pub smoother: Smoother,
    /// Lanczos steps estimating λ_max(D⁻¹A) (times 1.1, capped by the Gershgorin bound): for
    /// the Chebyshev smoother, and for ω of the prolongator smoothing on levels with positive
    /// off-diagonal entries, where the Gershgorin bound overestimates (3.4× on a Kershaw HMM
    /// matrix); 0 uses the Gershgorin bound alone.
    pub spectral_steps: usize,
    /// θ_P of the prolongator smoothing: the entries |a_ij| < θ_P a_ii of row i are lumped
    /// into the diagonal of the smoothing matrix A_F (see the module documentation), in [0, 1).
    pub smoothing_threshold: f64,
}

impl Default for AmgOptions {
    /// The defaults, chosen by measurement (release build, 2 cores, 1024² grids, PCG to 1e-10;
    /// `benches/amg.rs`, `make bench-amg`): θ = 0.08 (θ = 0 gave 73 and 51 iterations on the jump and
    /// anisotropic problems instead of 19 and 15; θ = 0.25 gave 175 on Poisson instead of 17);
    /// l1 Gauss–Seidel, whose V(1,1) cycle cost 26 ms for 16 Poisson iterations, against
    /// 22 ms / 21 for Chebyshev of degree 1, 37 ms / 17 for degree 2 and 22 ms / 25 for l1
    /// Jacobi; θ_P = 0.04 (19 iterations at operator complexity 1.87 on the anisotropic
    /// problem); at most 1000 coarsest unknowns (300 or 3000 changed the iterations by one).
    fn default() -> Self {
        AmgOptions {
            strength_threshold: 0.08,
            max_coarse: 1000,
            max_levels: 25,
            smoother: Smoother::L1GaussSeidel,
            spectral_steps: 10,
            smoothing_threshold: 0.04,
        }
    }
}

impl AmgOptions {
    fn check(&self) -> crate::Result<()> {
        let bad = |msg: String| Err(crate::Error::Linear(format!("multigrid options: {msg}")));
        if !(0.0..1.0).contains(&self.strength_threshold) {
            return bad(format!(
                "the strength threshold {} is not in [0, 1)",
                self.strength_threshold
            ));
        }
        if !(0.0..1.0).contains(&self.smoothing_threshold) {
            return bad(format!(
                "the smoothing threshold {} is not in [0, 1)",
                self.smoothing_threshold
            ));
        }
        if self.max_coarse == 0 || self.max_coarse > DENSE_MAX {
            return bad(format!(
                "max_coarse = {} is not in 1..={DENSE_MAX}",
                self.max_coarse
            ));
        }
        if self.max_levels == 0 {
            return bad("max_levels must be at least 1".into());
        }
        if let Smoother::Chebyshev { degree, ratio } = self.smoother
            && (degree == 0 || !(ratio > 1.0 && ratio.is_finite()))
        {
            return bad(format!(
                "Chebyshev smoother of degree {degree} with ratio {ratio} (need degree ≥ 1, \
                 ratio > 1)"
            ));
        }
        Ok(())
    }
}

/// Size of one level of the hierarchy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelSummary {
    /// Unknowns.
    pub n: usize,
    /// Stored entries of A_ℓ.
    pub nnz: usize,
}

/// The data of the smoother on one level.
#[derive(Debug, Clone)]
enum LevelSmoother {
    Chebyshev {
        inv_diag: Vec<f64>,
        /// Lower and upper ends of the damped interval of the spectrum of D⁻¹A.
        lo: f64,
        hi: f64,
        degree: usize,
    },
    L1Jacobi {
        inv_l1: Vec<f64>,
    },
    L1GaussSeidel {
        /// 1 / (a_ii + Σ_{j outside the block of i} |a_ij|).
        inv_diag: Vec<f64>,
        /// Rows per block.
        block: usize,
    },
}

/// The transfer between level ℓ and ℓ + 1: P; the restriction applies Pᵀ by scattering the
/// rows of P ([`CsrMatrix::mul_transpose_to`]). R = Pᵀ is formed only for the Galerkin product
/// and freed: stored, it was a third of the hierarchy (45 of 141 MiB on ex9's P1 matrix at 1M
/// unknowns), for a restriction about twice as fast on 2 cores.
#[derive(Debug, Clone)]
struct Transfer {
    p: CsrMatrix,
}

/// The solver of the coarsest level.
#[derive(Debug, Clone)]
enum CoarseSolve {
    /// The Cholesky factor L (A_L = L Lᵀ), its lower triangle packed row after row.
    Dense { n: usize, l: Vec<f64> },
    /// Coarsening stalled above [`DENSE_MAX`]: the level is only smoothed.
    Smooth,
}

/// Vectors of one level, kept between applications.
#[derive(Debug, Clone, Default)]
struct LevelWork {
    /// Right-hand side and solution of this level (unused on the fine level: the caller's).
    b: Vec<f64>,
    x: Vec<f64>,
    /// Residual and two smoother vectors.
    r: Vec<f64>,
    d0: Vec<f64>,
    d1: Vec<f64>,
}

/// A smoothed-aggregation multigrid preconditioner for a symmetric positive definite matrix
/// (see the module documentation). It borrows the fine matrix.
#[derive(Debug)]
pub struct Amg<'a> {
    /// A₀, borrowed ([`Amg::new`]) or owned ([`Amg::owning`]).
    fine: std::borrow::Cow<'a, CsrMatrix>,
    /// Everything else.
    h: CoarseHierarchy,
}

impl<'a> Amg<'a> {
    /// Builds the hierarchy of `a` (square, symmetric, positive definite; symmetry is the
    /// caller's, e.g. [`CsrMatrix::from_lower_csc`]).
    ///
    /// Errors: a non-finite entry or a non-positive diagonal entry (naming the row), a missing
    /// diagonal, invalid options, or a coarse operator that is not numerically positive
    /// definite (then neither is `a`).
    pub fn new(a: &'a CsrMatrix, opts: &AmgOptions) -> crate::Result<Self> {
        opts.check()?;
        validate(a)?;
        let mut coarse_ops: Vec<CsrMatrix> = Vec::new();
        let mut transfers = Vec::new();
        let mut smoothers = Vec::new();
        // the near-null space of the current level (the constants on the fine one)
        let mut near_null = vec![1.0; a.n_rows()];
        loop {
            let level = coarse_ops.len();
            let al = coarse_ops.last().unwrap_or(a);
            let diag = al.diagonal();
            if level > 0
                && let Some(i) = diag.iter().position(|&d| !(d > 0.0 && d.is_finite()))
            {
                return Err(crate::Error::Linear(format!(
                    "multigrid setup: the coarse operator of level {level} has the diagonal \
                     entry {:e} at row {i}: the matrix is not positive definite",
                    diag[i]
                )));
            }
            smoothers.push(LevelSmoother::new(al, &diag, opts));
            let n = al.n_rows();
            if n <= opts.max_coarse || level + 1 >= opts.max_levels {
                break;
            }
            let strong = strength(al, &diag, opts.strength_threshold);
            let (agg, n_agg) = aggregate(al, &strong, &diag);
            drop(strong);
            // stop when coarsening stalls (every row decoupled, or barely any reduction)
            if n_agg == 0 || n_agg as f64 > 0.85 * n as f64 {
                break;
            }
            let (p, b_next) = smoothed_prolongator(
                al,
                &diag,
                &agg,
                n_agg,
                &near_null,
                opts.smoothing_threshold,
                opts.spectral_steps,
            );
            near_null = b_next;
            let ac = galerkin(al, &p, p.transpose());
            transfers.push(Transfer { p });
            coarse_ops.push(ac);
        }
        let last = coarse_ops.last().unwrap_or(a);
        let coarse = if last.n_rows() <= DENSE_MAX {
            dense_cholesky(last, coarse_ops.len())?
        } else {
            CoarseSolve::Smooth
        };
        let amg = Amg {
            fine: std::borrow::Cow::Borrowed(a),
            h: CoarseHierarchy {
                n: a.n_rows(),
                coarse_ops,
                transfers,
                smoothers,
                coarse,
                work: Mutex::new(Vec::new()),
            },
        };
        let work = amg.new_work();
        if let Ok(mut w) = amg.h.work.lock() {
            *w = work;
        }
        Ok(amg)
    }

    /// [`Amg::new`] keeping `a` (for a hierarchy that outlives the caller's borrow, e.g. kept
    /// to continue a solve later); [`Amg::matrix`] gives it back.
    pub fn owning(a: CsrMatrix, opts: &AmgOptions) -> crate::Result<Amg<'static>> {
        let h = Amg::new(&a, opts)?.h;
        Ok(Amg {
            fine: std::borrow::Cow::Owned(a),
            h,
        })
    }

    /// The hierarchy without its fine matrix (which is freed), to precondition a changed
    /// fine matrix later ([`CoarseHierarchy::with_fine`]); `None` for a one-level hierarchy,
    /// whose only operator is the fine matrix (factorised: nothing to reuse).
    pub fn into_coarse(self) -> Option<CoarseHierarchy> {
        if self.h.coarse_ops.is_empty() {
            return None;
        }
        // the fine level's smoother data and work vectors are rebuilt by `with_fine`: freed
        // now (24 bytes per fine unknown less while the next matrix is assembled)
        let mut h = self.h;
        h.smoothers[0] = LevelSmoother::L1Jacobi { inv_l1: Vec::new() };
        if let Ok(mut w) = h.work.lock() {
            w[0] = LevelWork::default();
        }
        Some(h)
    }

    /// The fine matrix A₀, given back (a copy if it was borrowed).
    pub fn into_matrix(self) -> CsrMatrix {
        self.fine.into_owned()
    }

    /// The fine matrix A₀.
    pub fn matrix(&self) -> &CsrMatrix {
        &self.fine
    }

    /// Order of the fine matrix.
    pub fn n(&self) -> usize {
        self.fine.n_rows()
    }

    /// The operator of level ℓ.
    fn op(&self, level: usize) -> &CsrMatrix {
        if level == 0 {
            &self.fine
        } else {
            &self.h.coarse_ops[level - 1]
        }
    }

    /// Number of levels (≥ 1).
    pub fn n_levels(&self) -> usize {
        self.h.coarse_ops.len() + 1
    }

    /// Unknowns and stored entries of each level, fine to coarse.
    pub fn levels(&self) -> Vec<LevelSummary> {
        (0..self.n_levels())
            .map(|l| LevelSummary {
                n: self.op(l).n_rows(),
                nnz: self.op(l).nnz(),
            })
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

    /// Bytes held by the hierarchy (coarse operators, transfers, smoother data, the coarsest
    /// factor and the work vectors), the fine matrix excluded.
    pub fn memory_bytes(&self) -> usize {
        let f = std::mem::size_of::<f64>();
        let ops: usize = self.h.coarse_ops.iter().map(|a| a.memory_bytes()).sum();
        let tr: usize = self.h.transfers.iter().map(|t| t.p.memory_bytes()).sum();
        let sm: usize = self
            .h
            .smoothers
            .iter()
            .map(|s| match s {
                LevelSmoother::Chebyshev { inv_diag, .. } => inv_diag.len() * f,
                LevelSmoother::L1Jacobi { inv_l1 } => inv_l1.len() * f,
                LevelSmoother::L1GaussSeidel { inv_diag, .. } => inv_diag.len() * f,
            })
            .sum();
        let co = match &self.h.coarse {
            CoarseSolve::Dense { l, .. } => l.len() * f,
            CoarseSolve::Smooth => 0,
        };
        let wk: usize = match self.h.work.lock() {
            Ok(w) => w
                .iter()
                .map(|w| (w.b.len() + w.x.len() + w.r.len() + w.d0.len() + w.d1.len()) * f)
                .sum(),
            Err(_) => 0,
        };
        ops + tr + sm + co + wk
    }

    /// Fresh work vectors for every level.
    fn new_work(&self) -> Vec<LevelWork> {
        (0..self.n_levels()).map(|l| self.level_work(l)).collect()
    }

    /// Fresh work vectors for level ℓ.
    fn level_work(&self, l: usize) -> LevelWork {
        let n = self.op(l).n_rows();
        let (bx, dd) = (if l > 0 { n } else { 0 }, self.smoother_vectors(l));
        LevelWork {
            b: vec![0.0; bx],
            x: vec![0.0; bx],
            r: vec![0.0; n],
            d0: vec![0.0; if dd >= 1 { n } else { 0 }],
            d1: vec![0.0; if dd >= 2 { n } else { 0 }],
        }
    }

    /// How many of the vectors d0, d1 the smoother of level ℓ uses.
    fn smoother_vectors(&self, level: usize) -> usize {
        match self.h.smoothers[level] {
            LevelSmoother::Chebyshev { .. } => 2,
            LevelSmoother::L1Jacobi { .. } => 0,
            LevelSmoother::L1GaussSeidel { .. } => 1,
        }
    }

    /// z = M⁻¹ r: one V(1,1)-cycle from z = 0.
    pub fn apply(&self, r: &[f64], z: &mut [f64]) -> crate::Result<()> {
        check_len("multigrid preconditioner", self.n(), r.len(), z.len())?;
        match self.h.work.try_lock() {
            Ok(mut w) => self.cycle(0, r, z, &mut w),
            Err(TryLockError::Poisoned(p)) => self.cycle(0, r, z, &mut p.into_inner()),
            // another thread is applying the same preconditioner: use fresh vectors
            Err(TryLockError::WouldBlock) => self.cycle(0, r, z, &mut self.new_work()),
        }
        Ok(())
    }

    /// x = cycle_ℓ(b) (x is overwritten); `work[k]` holds the vectors of level ℓ + k.
    fn cycle(&self, level: usize, b: &[f64], x: &mut [f64], work: &mut [LevelWork]) {
        let Some((w, rest)) = work.split_first_mut() else {
            return;
        };
        let a = self.op(level);
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

impl Preconditioner for Amg<'_> {
    fn n(&self) -> usize {
        Amg::n(self)
    }
    fn apply(&self, r: &[f64], z: &mut [f64]) -> crate::Result<()> {
        Amg::apply(self, r, z)
    }
}

/// Checks the fine matrix: square, finite, with a positive diagonal entry in every row. The
/// first offending row (in order) is reported.
fn validate(a: &CsrMatrix) -> crate::Result<()> {
    let n = a.n_rows();
    if a.n_cols() != n {
        return Err(crate::Error::Linear(format!(
            "multigrid: the matrix is {}×{}, not square",
            n,
            a.n_cols()
        )));
    }
    let check_row = |i: usize| -> Option<String> {
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
    };
    let bad = if a.nnz() < PAR_MIN_NNZ {
        (0..n).find_map(check_row)
    } else {
        (0..n).into_par_iter().find_map_first(check_row)
    };
    match bad {
        Some(msg) => Err(crate::Error::Linear(format!(
            "multigrid: {msg} (the matrix must be symmetric positive definite)"
        ))),
        None => Ok(()),
    }
}

/// Builds a matrix row by row in parallel: `row(scratch, i, cols, vals)` appends the entries
/// of row i (sorted by column) to `cols` and `vals`; `init` makes the per-thread scratch.
fn build_rows<S, I, F>(n_rows: usize, n_cols: usize, init: I, row: F) -> CsrMatrix
where
    S: Send,
    I: Fn() -> S + Sync + Send,
    F: Fn(&mut S, usize, &mut Vec<u32>, &mut Vec<f64>) + Sync + Send,
{
    let n_chunks = n_rows.div_ceil(ROW_CHUNK);
    let parts: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..n_chunks)
        .into_par_iter()
        .map_init(&init, |s, c| {
            let (i0, i1) = (c * ROW_CHUNK, ((c + 1) * ROW_CHUNK).min(n_rows));
            let mut lens = Vec::with_capacity(i1 - i0);
            let mut cols = Vec::new();
            let mut vals = Vec::new();
            for i in i0..i1 {
                let before = cols.len();
                row(s, i, &mut cols, &mut vals);
                lens.push(cols.len() - before);
            }
            (lens, cols, vals)
        })
        .collect();
    // concatenate the chunks in parallel: the offsets of each chunk's rows and entries first
    let mut starts = Vec::with_capacity(parts.len() + 1);
    starts.push(0usize);
    for p in &parts {
        starts.push(starts[starts.len() - 1] + p.1.len());
    }
    let nnz = starts[parts.len()];
    let mut row_ptr = vec![0usize; n_rows + 1];
    let mut col_idx = vec![0u32; nnz];
    let mut values = vec![0.0f64; nnz];
    row_ptr[n_rows] = nnz;
    // (the chunk's lengths, columns and values; its parts of row_ptr, col_idx, values; the
    // offset of its first entry)
    type Piece<'p> = (
        &'p (Vec<usize>, Vec<u32>, Vec<f64>),
        &'p mut [usize],
        &'p mut [u32],
        &'p mut [f64],
        usize,
    );
    let mut pieces: Vec<Piece> = Vec::with_capacity(parts.len());
    let (mut rp, mut ci, mut va) = (&mut row_ptr[..n_rows], &mut col_idx[..], &mut values[..]);
    for (p, &start) in parts.iter().zip(&starts) {
        let (r0, r1) = std::mem::take(&mut rp).split_at_mut(p.0.len());
        let (c0, c1) = std::mem::take(&mut ci).split_at_mut(p.1.len());
        let (v0, v1) = std::mem::take(&mut va).split_at_mut(p.2.len());
        pieces.push((p, r0, c0, v0, start));
        (rp, ci, va) = (r1, c1, v1);
    }
    let fill = |((lens, cols, vals), r, c, v, start): Piece| {
        let mut acc = start;
        for (rk, &l) in r.iter_mut().zip(lens) {
            *rk = acc;
            acc += l;
        }
        c.copy_from_slice(cols);
        v.copy_from_slice(vals);
    };
    if nnz < PAR_MIN_NNZ {
        pieces.into_iter().for_each(fill);
    } else {
        pieces.into_par_iter().for_each(fill);
    }
    CsrMatrix::from_parts(n_rows, n_cols, row_ptr, col_idx, values)
}

/// The strong off-diagonal entries of A, a_ij ≠ 0 with a_ij² ≥ θ² a_ii a_jj, whatever their
/// sign, as a flag per stored entry of A (in the order of its values). (Counting only negative
/// couplings as strong was measured to take fewer iterations on HMM matrices with positive
/// couplings — distorted meshes, rotated anisotropy — but is not adopted: the benchmark of
/// `make bench-peers` was run with this rule.)
fn strength(a: &CsrMatrix, diag: &[f64], theta: f64) -> Vec<bool> {
    let t2 = theta * theta;
    let mut strong = vec![false; a.nnz()];
    let rp = a.row_ptr();
    let fill = |i0: usize, flags: &mut [bool]| {
        let base = rp[i0];
        let mut i = i0;
        while base + flags.len() > rp[i] {
            let di = diag[i];
            let (cols, vals) = a.row(i);
            let f = &mut flags[rp[i] - base..rp[i + 1] - base];
            for ((f, &j), &v) in f.iter_mut().zip(cols).zip(vals) {
                let j = j as usize;
                *f = j != i && v != 0.0 && v * v >= t2 * di * diag[j];
            }
            i += 1;
        }
    };
    for_entry_chunks(a, &mut strong, fill);
    strong
}

/// Runs `f(i0, part)` on the parts of a per-entry array `x` of `a` that hold rows
/// `i0..i0 + ROW_CHUNK` (in parallel when `a` is large).
fn for_entry_chunks<T: Send, F>(a: &CsrMatrix, x: &mut [T], f: F)
where
    F: Fn(usize, &mut [T]) + Sync + Send,
{
    let n = a.n_rows();
    let rp = a.row_ptr();
    if a.nnz() < PAR_MIN_NNZ {
        if n > 0 {
            f(0, x);
        }
        return;
    }
    let mut parts = Vec::with_capacity(n.div_ceil(ROW_CHUNK));
    let mut rest = x;
    for i0 in (0..n).step_by(ROW_CHUNK) {
        let i1 = (i0 + ROW_CHUNK).min(n);
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(rp[i1] - rp[i0]);
        parts.push((i0, head));
        rest = tail;
    }
    parts.into_par_iter().for_each(|(i0, part)| f(i0, part));
}

/// Greedy aggregation on the graph of the strong entries `strong` of A (see the module
/// documentation): the aggregate of each unknown ([`NONE`] for an isolated one) and the
/// number of aggregates.
fn aggregate(a: &CsrMatrix, strong: &[bool], diag: &[f64]) -> (Vec<u32>, usize) {
    let n = a.n_rows();
    let rp = a.row_ptr();
    // the strong entries (column, value) of row i
    let srow = |i: usize| {
        let r = rp[i]..rp[i + 1];
        a.col_idx()[r.clone()]
            .iter()
            .zip(&a.values()[r.clone()])
            .zip(&strong[r])
            .filter(|(_, s)| **s)
            .map(|((&j, &v), _)| (j as usize, v))
    };
    let has_strong = |i: usize| strong[rp[i]..rp[i + 1]].contains(&true);
    let mut agg = vec![NONE; n];
    let mut n_agg: u32 = 0;
    // phase 1: roots whose strong neighbourhood is entirely free
    for i in 0..n {
        if agg[i] != NONE || !has_strong(i) {
            continue;
        }
        if srow(i).all(|(j, _)| agg[j] == NONE) {
            agg[i] = n_agg;
            for (j, _) in srow(i) {
                agg[j] = n_agg;
            }
            n_agg += 1;
        }
    }
    // phase 2: join the phase-1 aggregate of the strongest neighbour (aggregates numbered
    // below n1 and assigned before this phase; a join made in this phase is not followed)
    let in_phase1: Vec<bool> = agg.iter().map(|&g| g != NONE).collect();
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut best = (0.0, NONE);
        for (j, v) in srow(i) {
            if in_phase1[j] {
                let w = v.abs() / diag[j].sqrt();
                if w > best.0 {
                    best = (w, agg[j]);
                }
            }
        }
        agg[i] = best.1;
    }
    // phase 3: whatever is left (with strong neighbours) founds aggregates with its free
    // strong neighbours
    for i in 0..n {
        if agg[i] != NONE || !has_strong(i) {
            continue;
        }
        agg[i] = n_agg;
        for (j, _) in srow(i) {
            if agg[j] == NONE {
                agg[j] = n_agg;
            }
        }
        n_agg += 1;
    }
    // phase 4: an unknown with no strong neighbour but some coupling joins the aggregate it
    // is most strongly coupled to (|a_ij| / √(a_jj), the row's own diagonal being common),
    // or founds a singleton; only the decoupled rows (no nonzero off-diagonal entry) stay out
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let (cols, vals) = a.row(i);
        let mut coupled = false;
        let mut best = (0.0, NONE);
        for (&j, &v) in cols.iter().zip(vals) {
            let ju = j as usize;
            if ju == i || v == 0.0 {
                continue;
            }
            coupled = true;
            let w = v.abs() / diag[ju].sqrt();
            if agg[ju] != NONE && w > best.0 {
                best = (w, agg[ju]);
            }
        }
        if best.1 != NONE {
            agg[i] = best.1;
        } else if coupled {
            agg[i] = n_agg;
            n_agg += 1;
        }
    }
    (agg, n_agg as usize)
}

/// P = (I − ω D_F⁻¹ A_F) T (see the module documentation): row i is
/// (1 − ω) T_i − (ω / d^F_i) Σ_{j kept} a_ij T_j, where row i of A_F keeps the a_ij (j ≠ i) with
/// |a_ij| ≥ θ_P a_ii and lumps the others into d^F_i = a_ii + Σ_{j dropped} a_ij; for the
/// near-null vector `b` of this level. Also returns the near-null vector of the next level.
fn smoothed_prolongator(
    a: &CsrMatrix,
    diag: &[f64],
    agg: &[u32],
    n_agg: usize,
    b: &[f64],
    theta_p: f64,
    spectral_steps: usize,
) -> (CsrMatrix, Vec<f64>) {
    let n = a.n_rows();
    // T_iJ = b_i / ‖b|𝒜_J‖ and the coarse near-null vector b^c_J = ‖b|𝒜_J‖ (so that T b^c = b
    // on the aggregated unknowns: the QR factorisation of b restricted to each aggregate)
    let mut b_coarse = vec![0.0; n_agg];
    for (&g, &bi) in agg.iter().zip(b) {
        if g != NONE {
            b_coarse[g as usize] += bi * bi;
        }
    }
    b_coarse.iter_mut().for_each(|v| *v = v.sqrt());
    let t = |i: usize| -> f64 {
        match agg[i] {
            NONE => 0.0,
            g => {
                let nb = b_coarse[g as usize];
                if nb > 0.0 { b[i] / nb } else { 0.0 }
            }
        }
    };
    let kept = |i: usize, j: u32, v: f64| j as usize != i && v.abs() >= theta_p * diag[i];
    // d^F_i (a_ii if lumping positive entries would leave it non-positive), and the Gershgorin
    // bound of ρ(D_F⁻¹ A_F), max_i 1 + Σ_{j kept} |a_ij| / d^F_i
    let mut dfil = vec![0.0; n];
    a.for_row_chunks(&mut dfil, |i0, chunk| {
        for (k, d) in chunk.iter_mut().enumerate() {
            let i = i0 + k;
            let (cols, vals) = a.row(i);
            let dropped: f64 = cols
                .iter()
                .zip(vals)
                .filter(|&(&j, &v)| j as usize != i && !kept(i, j, v))
                .map(|(_, v)| v)
                .sum();
            let f = diag[i] + dropped;
            *d = if f > 1e-12 * diag[i] { f } else { diag[i] };
        }
    });
    let rho = (0..n)
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| {
            let (cols, vals) = a.row(i);
            let off: f64 = cols
                .iter()
                .zip(vals)
                .filter(|&(&j, &v)| kept(i, j, v))
                .map(|(_, v)| v.abs())
                .sum();
            1.0 + off / dfil[i]
        })
        .reduce(|| 1.0, f64::max);
    // with positive off-diagonal entries (HMM on distorted meshes, rotated anisotropy) the
    // Gershgorin bound is far too large: estimate λ_max by Lanczos instead
    let positive = (0..n).into_par_iter().with_min_len(ROW_CHUNK).any(|i| {
        let (cols, vals) = a.row(i);
        cols.iter()
            .zip(vals)
            .any(|(&j, &v)| j as usize != i && v > 0.0)
    });
    let rho = if spectral_steps > 0 && positive {
        (1.1 * lanczos_lambda_max(a, diag, spectral_steps)).min(rho)
    } else {
        rho
    };
    let omega = 4.0 / (3.0 * rho);
    let p = build_rows(
        n,
        n_agg,
        || (),
        |_, i, cols, vals| {
            let start = cols.len();
            let scale = omega / dfil[i];
            let mut add = |g: u32, v: f64| {
                if let Some(p) = cols[start..].iter().position(|&c| c == g) {
                    vals[start + p] += v;
                } else {
                    cols.push(g);
                    vals.push(v);
                }
            };
            if agg[i] != NONE {
                add(agg[i], (1.0 - omega) * t(i));
            }
            let (ac, av) = a.row(i);
            for (&j, &v) in ac.iter().zip(av) {
                let g = agg[j as usize];
                if g != NONE && kept(i, j, v) {
                    add(g, -scale * v * t(j as usize));
                }
            }
            sort_tail(cols, vals, start);
        },
    );
    (p, b_coarse)
}

/// Sorts the entries `start..` of `cols` (and `vals` along) by column: an insertion sort, as
/// rows hold a handful of entries.
fn sort_tail(cols: &mut [u32], vals: &mut [f64], start: usize) {
    for k in start + 1..cols.len() {
        let (c, v) = (cols[k], vals[k]);
        let mut m = k;
        while m > start && cols[m - 1] > c {
            cols[m] = cols[m - 1];
            vals[m] = vals[m - 1];
            m -= 1;
        }
        cols[m] = c;
        vals[m] = v;
    }
}

/// A dense accumulator of a sparse row: the values by column and the list of touched columns.
struct Accumulator {
    /// Position of each column in `cols`, or [`NONE`].
    pos: Vec<u32>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl Accumulator {
    fn new(n: usize) -> Self {
        Accumulator {
            pos: vec![NONE; n],
            cols: Vec::new(),
            vals: Vec::new(),
        }
    }
    #[inline(always)]
    fn add(&mut self, j: u32, v: f64) {
        let p = self.pos[j as usize];
        if p == NONE {
            self.pos[j as usize] = self.cols.len() as u32;
            self.cols.push(j);
            self.vals.push(v);
        } else {
            self.vals[p as usize] += v;
        }
    }
    /// Appends the row in the order of first touch and clears the accumulator.
    fn drain_unsorted_into(&mut self, cols: &mut Vec<u32>, vals: &mut Vec<f64>) {
        for &c in &self.cols {
            self.pos[c as usize] = NONE;
        }
        cols.extend_from_slice(&self.cols);
        vals.extend_from_slice(&self.vals);
        self.cols.clear();
        self.vals.clear();
    }
    /// Appends the row, sorted by column, and clears the accumulator.
    fn drain_into(&mut self, cols: &mut Vec<u32>, vals: &mut Vec<f64>) {
        self.cols.sort_unstable();
        for &c in &self.cols {
            let p = self.pos[c as usize] as usize;
            cols.push(c);
            vals.push(self.vals[p]);
            self.pos[c as usize] = NONE;
        }
        self.cols.clear();
        self.vals.clear();
    }
}

/// A_c = Pᵀ A P in two row-parallel products (see the module documentation): R A with
/// R = Pᵀ, row J = Σ_{i : r_Ji ≠ 0} r_Ji A_i (its columns left in the order they are met: only
/// read below), R freed, then row J of A_c = Σ_k (R A)_Jk P_k.
fn galerkin(a: &CsrMatrix, p: &CsrMatrix, r: CsrMatrix) -> CsrMatrix {
    let ra = product(&r, a, false);
    drop(r);
    product(&ra, p, true)
}

/// The sparse product L M, row J = Σ_k l_Jk M_k, zero entries of M skipped; each row's
/// columns sorted if `sorted`, else in the order they are met.
fn product(l: &CsrMatrix, m: &CsrMatrix, sorted: bool) -> CsrMatrix {
    let n = m.n_cols();
    build_rows(
        l.n_rows(),
        n,
        || Accumulator::new(n),
        |acc, row, cols, vals| {
            let (lc, lv) = l.row(row);
            for (&k, &lk) in lc.iter().zip(lv) {
                let (mc, mv) = m.row(k as usize);
                for (&j, &mkj) in mc.iter().zip(mv) {
                    if mkj != 0.0 {
                        acc.add(j, lk * mkj);
                    }
                }
            }
            if sorted {
                acc.drain_into(cols, vals);
            } else {
                acc.drain_unsorted_into(cols, vals);
            }
        },
    )
}

/// The dense Cholesky factor of the coarsest operator (faer), packed.
fn dense_cholesky(a: &CsrMatrix, level: usize) -> crate::Result<CoarseSolve> {
    let n = a.n_rows();
    if n == 0 {
        return Ok(CoarseSolve::Dense { n, l: Vec::new() });
    }
    let mut m = faer::Mat::<f64>::zeros(n, n);
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&j, &v) in cols.iter().zip(vals) {
            m[(i, j as usize)] = v;
        }
    }
    let llt = m.llt(faer::Side::Lower).map_err(|e| {
        crate::Error::Linear(format!(
            "multigrid setup: the coarsest operator (level {level}, order {n}) is not \
             numerically positive definite ({e:?}): neither is the matrix"
        ))
    })?;
    let lf = llt.L();
    let mut l = Vec::with_capacity(n * (n + 1) / 2);
    for i in 0..n {
        for j in 0..=i {
            l.push(lf[(i, j)]);
        }
    }
    Ok(CoarseSolve::Dense { n, l })
}

/// x = (L Lᵀ)⁻¹ b with L packed by rows: L y = b by rows, then Lᵀ x = y by columns of Lᵀ
/// (rows of L), both reading L contiguously.
fn dense_solve(n: usize, l: &[f64], b: &[f64], x: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * (i + 1) / 2..(i + 1) * (i + 2) / 2];
        let mut s = b[i];
        for (lij, xj) in row[..i].iter().zip(&x[..i]) {
            s -= lij * xj;
        }
        x[i] = s / row[i];
    }
    for i in (0..n).rev() {
        let row = &l[i * (i + 1) / 2..(i + 1) * (i + 2) / 2];
        let xi = x[i] / row[i];
        x[i] = xi;
        for (lij, xj) in row[..i].iter().zip(&mut x[..i]) {
            *xj -= lij * xi;
        }
    }
}

/// Gershgorin bound of ρ(D⁻¹A): max_i Σ_j |a_ij| / a_ii.
fn gershgorin(a: &CsrMatrix, diag: &[f64]) -> f64 {
    (0..a.n_rows())
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| a.row(i).1.iter().map(|v| v.abs()).sum::<f64>() / diag[i])
        .reduce(|| 0.0, f64::max)
}

/// The largest Ritz value of `steps` Lanczos steps on D^{-1/2} A D^{-1/2} (similar to D⁻¹A),
/// from a fixed pseudo-random start: a lower bound of λ_max(D⁻¹A), usually close.
fn lanczos_lambda_max(a: &CsrMatrix, diag: &[f64], steps: usize) -> f64 {
    let n = a.n_rows();
    if n == 0 {
        return 0.0;
    }
    let s: Vec<f64> = diag.iter().map(|d| 1.0 / d.sqrt()).collect();
    // a deterministic start with components along every eigenvector (almost surely)
    let mut v: Vec<f64> = (0..n as u64)
        .map(|i| {
            let h = (i.wrapping_add(1)).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
            (h as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect();
    let nv = dot(&v, &v).sqrt();
    v.iter_mut().for_each(|x| *x /= nv);
    let mut v_prev = vec![0.0; n];
    let mut u = vec![0.0; n];
    let mut w = vec![0.0; n];
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    let mut beta = 0.0;
    for _ in 0..steps.min(n) {
        u.iter_mut()
            .zip(&v)
            .zip(&s)
            .for_each(|((u, v), s)| *u = v * s);
        a.mul_to(&u, &mut w);
        w.iter_mut()
            .zip(&s)
            .zip(&v_prev)
            .for_each(|((w, s), vp)| *w = *w * s - beta * vp);
        let alpha = dot(&w, &v);
        w.iter_mut().zip(&v).for_each(|(w, v)| *w -= alpha * v);
        alphas.push(alpha);
        beta = dot(&w, &w).sqrt();
        if !(beta > 1e-12 * alpha.abs()) {
            break;
        }
        betas.push(beta);
        std::mem::swap(&mut v_prev, &mut v);
        v.iter_mut().zip(&w).for_each(|(v, w)| *v = w / beta);
    }
    let k = alphas.len();
    let t = nalgebra::DMatrix::from_fn(k, k, |i, j| {
        if i == j {
            alphas[i]
        } else if i == j + 1 {
            betas[j]
        } else if j == i + 1 {
            betas[i]
        } else {
            0.0
        }
    });
    t.symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(0.0, f64::max)
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
#[derive(Debug)]
pub struct CoarseHierarchy {
    /// Order of the fine matrix it was built for.
    n: usize,
    coarse_ops: Vec<CsrMatrix>,
    transfers: Vec<Transfer>,
    /// Every level's; the fine level's is empty (freed by [`Amg::into_coarse`]) until
    /// [`CoarseHierarchy::with_fine`] builds it for the new matrix.
    smoothers: Vec<LevelSmoother>,
    coarse: CoarseSolve,
    work: Mutex<Vec<LevelWork>>,
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
    pub fn with_fine(self, a: CsrMatrix, opts: &AmgOptions) -> crate::Result<Amg<'static>> {
        opts.check()?;
        if a.n_rows() != self.n {
            return Err(crate::Error::Linear(format!(
                "multigrid: a hierarchy built for order {} cannot precondition a matrix of \
                 order {}",
                self.n,
                a.n_rows()
            )));
        }
        validate(&a)?;
        let mut h = self;
        h.smoothers[0] = LevelSmoother::new(&a, &a.diagonal(), opts);
        let amg = Amg {
            fine: std::borrow::Cow::Owned(a),
            h,
        };
        // the fine level's smoother vectors depend on the smoother
        let fresh = amg.level_work(0);
        if let Ok(mut w) = amg.h.work.lock() {
            w[0] = fresh;
        }
        Ok(amg)
    }
}

impl LevelSmoother {
    fn new(a: &CsrMatrix, diag: &[f64], opts: &AmgOptions) -> Self {
        let n = a.n_rows();
        match opts.smoother {
            Smoother::Chebyshev { degree, ratio } => {
                let g = gershgorin(a, diag);
                let hi = if opts.spectral_steps > 0 {
                    (1.1 * lanczos_lambda_max(a, diag, opts.spectral_steps)).min(g)
                } else {
                    g
                };
                LevelSmoother::Chebyshev {
                    inv_diag: diag.iter().map(|d| 1.0 / d).collect(),
                    lo: hi / ratio,
                    hi,
                    degree,
                }
            }
            Smoother::L1Jacobi => {
                let mut inv_l1 = vec![0.0; n];
                a.for_row_chunks(&mut inv_l1, |i0, chunk| {
                    for (k, v) in chunk.iter_mut().enumerate() {
                        *v = 1.0 / a.row(i0 + k).1.iter().map(|x| x.abs()).sum::<f64>();
                    }
                });
                LevelSmoother::L1Jacobi { inv_l1 }
            }
            Smoother::L1GaussSeidel => {
                let block = gs_block(n);
                let mut inv_diag = vec![0.0; n];
                a.for_row_chunks(&mut inv_diag, |i0, chunk| {
                    for (k, v) in chunk.iter_mut().enumerate() {
                        let i = i0 + k;
                        let (b0, b1) = ((i / block) * block, ((i / block + 1) * block).min(n));
                        let (cols, vals) = a.row(i);
                        let off: f64 = cols
                            .iter()
                            .zip(vals)
                            .filter(|(j, _)| !(b0..b1).contains(&(**j as usize)))
                            .map(|(_, x)| x.abs())
                            .sum();
                        *v = 1.0 / (diag[i] + off);
                    }
                });
                LevelSmoother::L1GaussSeidel { inv_diag, block }
            }
        }
    }

    /// The Chebyshev smoother's step ([`chebyshev`]): as pre-smoother (from x = 0, leaving
    /// the residual in `w.r`) or as post-smoother; nothing for the other smoothers.
    fn chebyshev(&self, a: &CsrMatrix, b: &[f64], x: &mut [f64], w: &mut LevelWork, pre: bool) {
        if let LevelSmoother::Chebyshev {
            inv_diag,
            lo,
            hi,
            degree,
        } = self
        {
            chebyshev(a, inv_diag, *lo, *hi, *degree, b, x, w, pre, pre);
        }
    }

    /// Pre-smoothing from x = 0: x ← S(b), leaving r = b − A x in `w.r`.
    fn pre(&self, a: &CsrMatrix, b: &[f64], x: &mut [f64], w: &mut LevelWork) {
        match self {
            LevelSmoother::Chebyshev { .. } => self.chebyshev(a, b, x, w, true),
            LevelSmoother::L1Jacobi { inv_l1 } => {
                rows1(a, x, |i0, x| {
                    for (k, xi) in x.iter_mut().enumerate() {
                        *xi = b[i0 + k] * inv_l1[i0 + k];
                    }
                });
                a.residual_to(b, x, &mut w.r);
            }
            LevelSmoother::L1GaussSeidel { inv_diag, block } => {
                gauss_seidel(a, inv_diag, *block, b, x, None);
                a.residual_to(b, x, &mut w.r);
            }
        }
    }

    /// Post-smoothing: x ← x + S'(b − A x) (the adjoint of [`Self::pre`]).
    fn post(&self, a: &CsrMatrix, b: &[f64], x: &mut [f64], w: &mut LevelWork) {
        match self {
            LevelSmoother::Chebyshev { .. } => self.chebyshev(a, b, x, w, false),
            LevelSmoother::L1Jacobi { inv_l1 } => {
                a.residual_to(b, x, &mut w.r);
                let r: &[f64] = &w.r;
                rows1(a, x, |i0, x| {
                    for (k, xi) in x.iter_mut().enumerate() {
                        *xi += r[i0 + k] * inv_l1[i0 + k];
                    }
                });
            }
            LevelSmoother::L1GaussSeidel { inv_diag, block } => {
                let xr: &[f64] = x;
                rows1(a, &mut w.d0, |i0, d| {
                    d.copy_from_slice(&xr[i0..i0 + d.len()])
                });
                gauss_seidel(a, inv_diag, *block, b, x, Some(&w.d0));
            }
        }
    }
}

/// Rows per block of the hybrid Gauss–Seidel: at least 16384, and at most 32 blocks (few block
/// boundaries, where it degrades to Jacobi, and enough blocks to balance the threads).
fn gs_block(n: usize) -> usize {
    n.div_ceil(32).max(16384)
}

/// Runs `f(i0, u, v, w)` on matching chunks (rows i0..) of three vectors of length n, in
/// parallel when the matrix `a` of the level is large enough.
fn rows3<F>(a: &CsrMatrix, u: &mut [f64], v: &mut [f64], w: &mut [f64], f: F)
where
    F: Fn(usize, &mut [f64], &mut [f64], &mut [f64]) + Sync + Send,
{
    if a.nnz() < PAR_MIN_NNZ {
        f(0, u, v, w);
    } else {
        u.par_chunks_mut(ROW_CHUNK)
            .zip(v.par_chunks_mut(ROW_CHUNK))
            .zip(w.par_chunks_mut(ROW_CHUNK))
            .enumerate()
            .for_each(|(c, ((u, v), w))| f(c * ROW_CHUNK, u, v, w));
    }
}

/// As [`rows3`] with two vectors.
fn rows2<F>(a: &CsrMatrix, u: &mut [f64], v: &mut [f64], f: F)
where
    F: Fn(usize, &mut [f64], &mut [f64]) + Sync + Send,
{
    if a.nnz() < PAR_MIN_NNZ {
        f(0, u, v);
    } else {
        u.par_chunks_mut(ROW_CHUNK)
            .zip(v.par_chunks_mut(ROW_CHUNK))
            .enumerate()
            .for_each(|(c, (u, v))| f(c * ROW_CHUNK, u, v));
    }
}

/// As [`rows3`] with one vector.
fn rows1<F>(a: &CsrMatrix, u: &mut [f64], f: F)
where
    F: Fn(usize, &mut [f64]) + Sync + Send,
{
    a.for_row_chunks(u, f);
}

/// Chebyshev smoothing x ← x + q(D⁻¹A) D⁻¹ (b − A x) (three-term recurrence: Saad,
/// *Iterative methods for sparse linear systems*, Alg. 12.1). With θ = (hi + lo)/2,
/// δ = (hi − lo)/2, σ = θ/δ, ρ₀ = 1/σ and r₀ = b − A x: d₀ = D⁻¹r₀/θ; then for k ≥ 1,
/// r_k = r_{k−1} − A d_{k−1}, ρ_k = 1/(2σ − ρ_{k−1}), d_k = ρ_k ρ_{k−1} d_{k−1} + (2ρ_k/δ) D⁻¹ r_k;
/// x ← x + d₀ + … + d_{degree−1}. `zero_start`: x = 0 on entry (so r₀ = b, no product).
/// With `want_residual`, `w.r` = b − A x on exit. Each product with A is one fused sweep that
/// also updates r, d and x.
#[allow(clippy::too_many_arguments)]
fn chebyshev(
    a: &CsrMatrix,
    inv_diag: &[f64],
    lo: f64,
    hi: f64,
    degree: usize,
    b: &[f64],
    x: &mut [f64],
    w: &mut LevelWork,
    zero_start: bool,
    want_residual: bool,
) {
    let theta = 0.5 * (hi + lo);
    let delta = 0.5 * (hi - lo);
    let sigma = theta / delta;
    let mut rho = 1.0 / sigma;
    let (r, d, dn) = (&mut w.r, &mut w.d0, &mut w.d1);
    // r = b − A x, d₀ = D⁻¹ r / θ; x += d₀ now (zero start) or in the next sweep
    let mut pending = false;
    if zero_start {
        rows3(a, r, d, x, |i0, r, d, x| {
            for (k, ((ri, di), xi)) in r.iter_mut().zip(d.iter_mut()).zip(x.iter_mut()).enumerate()
            {
                let i = i0 + k;
                *ri = b[i];
                *di = b[i] * inv_diag[i] / theta;
                *xi = *di;
            }
        });
    } else {
        let xr: &[f64] = x;
        rows2(a, r, d, |i0, r, d| {
            for (k, (ri, di)) in r.iter_mut().zip(d.iter_mut()).enumerate() {
                let i = i0 + k;
                *ri = b[i] - a.row_dot(i, xr);
                *di = *ri * inv_diag[i] / theta;
            }
        });
        pending = true;
    }
    for _ in 1..degree {
        let rho_new = 1.0 / (2.0 * sigma - rho);
        let (c1, c2) = (rho_new * rho, 2.0 * rho_new / delta);
        // r −= A d; dn = c1 d + c2 D⁻¹ r; x += dn (+ d if pending)
        let dr: &[f64] = d;
        rows3(a, r, dn, x, |i0, r, dn, x| {
            for (k, ((ri, dni), xi)) in r
                .iter_mut()
                .zip(dn.iter_mut())
                .zip(x.iter_mut())
                .enumerate()
            {
                let i = i0 + k;
                *ri -= a.row_dot(i, dr);
                *dni = c1 * dr[i] + c2 * inv_diag[i] * *ri;
                *xi += if pending { *dni + dr[i] } else { *dni };
            }
        });
        pending = false;
        std::mem::swap(d, dn);
        rho = rho_new;
    }
    let dr: &[f64] = d;
    if pending {
        rows1(a, x, |i0, x| {
            for (k, xi) in x.iter_mut().enumerate() {
                *xi += dr[i0 + k];
            }
        });
    }
    if want_residual {
        // r −= A d
        rows1(a, r, |i0, r| {
            for (k, ri) in r.iter_mut().enumerate() {
                *ri -= a.row_dot(i0 + k, dr);
            }
        });
    }
}

/// One hybrid l1-Gauss–Seidel sweep, block by block (blocks of `block` consecutive rows, in
/// parallel): row i is updated by x_i += (b_i − Σ_j a_ij x_j) / (a_ii + Σ_{j outside} |a_ij|),
/// with the current values inside the block and, outside, `x_old` (the values before the
/// sweep).
///
/// `x_old = None` is the forward sweep from x = 0: x_i = (b_i − Σ_{i0 ≤ j < i} a_ij x_j) / d_i
/// (the entries right of the diagonal and outside the block multiply zeros), which neither
/// reads x beforehand nor needs it zeroed. Otherwise the sweep is backward (the adjoint of the
/// forward one).
fn gauss_seidel(
    a: &CsrMatrix,
    inv_diag: &[f64],
    block: usize,
    b: &[f64],
    x: &mut [f64],
    x_old: Option<&[f64]>,
) {
    let sweep = |c: usize, xb: &mut [f64]| {
        let i0 = c * block;
        let i1 = i0 + xb.len();
        match x_old {
            None => {
                for i in i0..i1 {
                    let (cols, vals) = a.row(i);
                    // the entries with i0 ≤ j < i (columns are sorted)
                    let lo = match cols.first() {
                        Some(&j) if j as usize >= i0 => 0,
                        _ => cols.partition_point(|&j| (j as usize) < i0),
                    };
                    let mut s = b[i];
                    for (&j, &v) in cols[lo..].iter().zip(&vals[lo..]) {
                        let ju = j as usize;
                        if ju >= i {
                            break;
                        }
                        s -= v * xb[ju - i0];
                    }
                    xb[i - i0] = s * inv_diag[i];
                }
            }
            Some(xo) => {
                for i in (i0..i1).rev() {
                    let (cols, vals) = a.row(i);
                    let mut s = b[i];
                    let inside = cols.first().is_none_or(|&j| j as usize >= i0)
                        && cols.last().is_none_or(|&j| (j as usize) < i1);
                    if inside {
                        for (&j, &v) in cols.iter().zip(vals) {
                            s -= v * xb[j as usize - i0];
                        }
                    } else {
                        for (&j, &v) in cols.iter().zip(vals) {
                            let ju = j as usize;
                            s -= v * if (i0..i1).contains(&ju) {
                                xb[ju - i0]
                            } else {
                                xo[ju]
                            };
                        }
                    }
                    xb[i - i0] += s * inv_diag[i];
                }
            }
        }
    };
    if a.nnz() < PAR_MIN_NNZ {
        for (c, xb) in x.chunks_mut(block).enumerate() {
            sweep(c, xb);
        }
    } else {
        x.par_chunks_mut(block)
            .enumerate()
            .for_each(|(c, xb)| sweep(c, xb));
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::linalg::pcg::{PcgOptions, pcg};

    /// −div(k∇u) on an m × m grid of unknowns with the 5-point stencil (homogeneous Dirichlet
    /// conditions eliminated): couplings kx·h(k_p, k_q) in x and ky·h(k_p, k_q) in y, h the
    /// harmonic mean; as the full CSR matrix.
    pub(crate) fn grid(
        m: usize,
        kx: f64,
        ky: f64,
        coef: &dyn Fn(usize, usize) -> f64,
    ) -> CsrMatrix {
        let n = m * m;
        let harm = |a: f64, b: f64| 2.0 * a * b / (a + b);
        let mut col_ptr = vec![0];
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        for j in 0..m {
            for i in 0..m {
                let c = coef(i, j);
                let k = |ii: usize, jj: usize, inside: bool| {
                    if inside { harm(c, coef(ii, jj)) } else { c }
                };
                let west = k(i.wrapping_sub(1), j, i > 0);
                let east = k(i + 1, j, i + 1 < m);
                let south = k(i, j.wrapping_sub(1), j > 0);
                let north = k(i, j + 1, j + 1 < m);
                row_idx.push(j * m + i);
                values.push(kx * (west + east) + ky * (south + north));
                if i + 1 < m {
                    row_idx.push(j * m + i + 1);
                    values.push(-kx * east);
                }
                if j + 1 < m {
                    row_idx.push((j + 1) * m + i);
                    values.push(-ky * north);
                }
                col_ptr.push(row_idx.len());
            }
        }
        CsrMatrix::from_lower_csc(n, &col_ptr, &row_idx, &values).unwrap()
    }

    /// Fixes the unknowns for which `fixed` holds as the active-set solver does: their rows and
    /// columns zeroed but for a unit diagonal.
    pub(crate) fn fix(a: &CsrMatrix, fixed: &dyn Fn(usize) -> bool) -> CsrMatrix {
        let mut vals = a.values().to_vec();
        for i in 0..a.n_rows() {
            let r = a.row_ptr()[i]..a.row_ptr()[i + 1];
            for (v, &j) in vals[r.clone()].iter_mut().zip(&a.col_idx()[r]) {
                let j = j as usize;
                if fixed(i) || fixed(j) {
                    *v = if i == j { 1.0 } else { 0.0 };
                }
            }
        }
        CsrMatrix::new(
            a.n_rows(),
            a.n_cols(),
            a.row_ptr().to_vec(),
            a.col_idx().to_vec(),
            vals,
        )
        .unwrap()
    }

    /// [`iterations_with`] a new hierarchy of `a`.
    fn iterations(a: &CsrMatrix, opts: &AmgOptions) -> usize {
        iterations_with(a, &Amg::new(a, opts).unwrap())
    }

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

    /// PCG iterations to ‖r‖ ≤ 1e-10 ‖b‖ with the preconditioner `amg`, for b = A x* with x*
    /// containing all frequencies; also checks the true residual.
    fn iterations_with(a: &CsrMatrix, amg: &Amg) -> usize {
        let n = a.n_rows();
        let xs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() + 1.0).collect();
        let mut b = vec![0.0; n];
        a.spmv(&xs, &mut b).unwrap();
        let mut x = vec![0.0; n];
        let opts = PcgOptions {
            rtol: 1e-10,
            atol: 0.0,
            max_iter: 200,
        };
        let rep = pcg(a, amg, &b, &mut x, &opts).unwrap();
        assert!(rep.residual_norm <= 2e-10 * dot(&b, &b).sqrt(), "{rep:?}");
        rep.iterations
    }

    #[test]
    fn a_coarse_hierarchy_preconditions_a_changed_matrix() {
        let m = 150;
        let opts = AmgOptions::default();
        let disc = |r2: f64| {
            move |k: usize| {
                let (x, y) = (
                    (k % m) as f64 / m as f64 - 0.5,
                    (k / m) as f64 / m as f64 - 0.5,
                );
                x * x + y * y < r2
            }
        };
        let base = grid(m, 1.0, 1.0, &|_, _| 1.0);
        let a0 = fix(&base, &disc(0.09));
        let fresh0 = Amg::owning(a0.clone(), &opts).unwrap();
        // the same matrix again: the same cycle, to the bit
        let same = Amg::owning(a0.clone(), &opts)
            .unwrap()
            .into_coarse()
            .unwrap()
            .with_fine(a0.clone(), &opts)
            .unwrap();
        let r: Vec<f64> = (0..m * m).map(|i| (i as f64 * 0.11).cos()).collect();
        let (mut z0, mut z1) = (vec![0.0; m * m], vec![0.0; m * m]);
        fresh0.apply(&r, &mut z0).unwrap();
        same.apply(&r, &mut z1).unwrap();
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
            let reused = iterations_with(&a1, &coarse.with_fine(a1.clone(), &opts).unwrap());
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
        assert!(coarse.with_fine(small.clone(), &opts).is_err());
        assert!(Amg::owning(small, &opts).unwrap().into_coarse().is_none());
    }

    #[test]
    fn every_smoother_converges() {
        let a = grid(100, 1.0, 1.0, &|_, _| 1.0);
        for smoother in [
            Smoother::Chebyshev {
                degree: 1,
                ratio: 30.0,
            },
            Smoother::Chebyshev {
                degree: 3,
                ratio: 20.0,
            },
            Smoother::L1Jacobi,
            Smoother::L1GaussSeidel,
        ] {
            let opts = AmgOptions {
                smoother,
                max_coarse: 50,
                spectral_steps: 8,
                ..AmgOptions::default()
            };
            // measured: Chebyshev 1: 26, Chebyshev 3: 11, l1-Jacobi: 21, l1-Gauss–Seidel: 13
            let c = iterations(&a, &opts);
            assert!(c <= 32, "{smoother:?}: {c}");
        }
        // the filtered prolongator and θ = 0
        for opts in [
            AmgOptions {
                smoothing_threshold: 0.0,
                ..AmgOptions::default()
            },
            AmgOptions {
                strength_threshold: 0.0,
                ..AmgOptions::default()
            },
        ] {
            // measured 12 and 12
            let c = iterations(&a, &opts);
            assert!(c <= 18, "{opts:?}: {c}");
        }
    }

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
            amg.apply(&u, &mut mu).unwrap();
            amg.apply(&v, &mut mv).unwrap();
            let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
            assert!(
                (vmu - umv).abs() <= 1e-10 * vmu.abs().max(umv.abs()),
                "{smoother:?}: {vmu} vs {umv}"
            );
            assert!(dot(&u, &mu) > 0.0 && dot(&v, &mv) > 0.0);
            // deterministic and re-entrant: the same result twice
            let mut again = vec![0.0; n];
            amg.apply(&u, &mut again).unwrap();
            assert_eq!(again, mu);
        }
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
        assert!(amg.apply(&[0.0; 100], &mut z).is_err());
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
        let r = Amg::new(&indef, &opts)
            .and_then(|m| pcg(&indef, &m, &b, &mut x, &PcgOptions::default()));
        assert!(r.is_err());
    }

    #[test]
    fn empty_and_tiny_matrices() {
        let empty = CsrMatrix::new(0, 0, vec![0], vec![], vec![]).unwrap();
        let amg = Amg::new(&empty, &AmgOptions::default()).unwrap();
        assert_eq!(amg.n_levels(), 1);
        let rep = pcg(&empty, &amg, &[], &mut [], &PcgOptions::default()).unwrap();
        assert_eq!(rep.iterations, 0);
        // 1 × 1: solved exactly by the coarsest factorisation
        let one = CsrMatrix::new(1, 1, vec![0, 1], vec![0], vec![4.0]).unwrap();
        let amg = Amg::new(&one, &AmgOptions::default()).unwrap();
        let mut z = [0.0];
        amg.apply(&[2.0], &mut z).unwrap();
        assert!((z[0] - 0.5).abs() < 1e-15);
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
