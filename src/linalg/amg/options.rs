//! The parameters of the multigrid hierarchy and of its smoother.

use super::DENSE_MAX;

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
    /// off-diagonal entries, where the Gershgorin bound overestimates; 0 uses the Gershgorin
    /// bound alone.
    pub spectral_steps: usize,
    /// θ_P of the prolongator smoothing: the entries |a_ij| < θ_P a_ii of row i are lumped
    /// into the diagonal of the smoothing matrix A_F (see the module documentation), in [0, 1).
    pub smoothing_threshold: f64,
}

impl Default for AmgOptions {
    /// θ = 0.08, θ_P = 0.04, at most 1000 coarsest unknowns and 25 levels, the l1
    /// Gauss–Seidel smoother and 10 Lanczos steps: chosen by measurement (`benches/amg.rs`,
    /// `make bench-amg`), see `replication/BENCHMARKS.md` ("Measurements behind the defaults").
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
    /// The options are in range (see each field), else an error naming the first that is not.
    pub(super) fn check(&self) -> crate::Result<()> {
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
