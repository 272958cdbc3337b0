//! The smoothers of the cycle (see [`super`]): the data of each level's smoother, built once
//! per hierarchy, and the pre- and post-smoothing sweeps.

use super::cycle::LevelWork;
use super::options::{AmgOptions, Smoother};
use super::spectral::{gershgorin, lanczos_lambda_max};
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::linalg::csr::{PAR_MIN_NNZ, ROW_CHUNK};
use crate::linalg::rows::Rows;
use rayon::prelude::*;

/// The data of the smoother on one level.
#[derive(Debug, Clone)]
pub(super) enum LevelSmoother {
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

/// 1 / Σ_j |a_ij|: the l1-Jacobi smoother's entry of row i.
#[inline]
fn inv_l1_row<A: Rows + ?Sized>(a: &A, i: usize) -> f64 {
    1.0 / a.row(i).1.iter().map(|x| x.abs()).sum::<f64>()
}

/// 1 / (a_ii + Σ_{j outside the block of i} |a_ij|), `diag` = a_ii: the l1-Gauss-Seidel
/// smoother's entry of row i with blocks of `block` rows.
#[inline]
fn inv_l1_gs_row<A: Rows + ?Sized>(a: &A, i: usize, diag: f64, block: usize) -> f64 {
    let n = a.n_rows();
    let (b0, b1) = ((i / block) * block, ((i / block + 1) * block).min(n));
    let (cols, vals) = a.row(i);
    let off: f64 = cols
        .iter()
        .zip(vals)
        .filter(|(j, _)| !(b0..b1).contains(&(**j as usize)))
        .map(|(_, x)| x.abs())
        .sum();
    1.0 / (diag + off)
}

impl LevelSmoother {
    /// The smoother `opts` names for the matrix `a` with diagonal `diag`, or [`AllocFailure`]
    /// if its vectors cannot be allocated.
    pub(super) fn new<A: Rows + ?Sized>(
        a: &A,
        diag: &[f64],
        opts: &AmgOptions,
    ) -> Result<Self, AllocFailure> {
        let n = a.n_rows();
        Ok(match opts.smoother {
            Smoother::Chebyshev { degree, ratio } => {
                let g = gershgorin(a, diag);
                let hi = if opts.spectral_steps > 0 {
                    (1.1 * lanczos_lambda_max(a, diag, opts.spectral_steps)?).min(g)
                } else {
                    g
                };
                let mut inv_diag = try_vec(n, "the smoother's inverse diagonal")?;
                inv_diag.extend(diag.iter().map(|d| 1.0 / d));
                LevelSmoother::Chebyshev {
                    inv_diag,
                    lo: hi / ratio,
                    hi,
                    degree,
                }
            }
            Smoother::L1Jacobi => {
                let mut inv_l1 = try_filled(n, 0.0, "the smoother's inverse row sums")?;
                a.for_row_chunks(&mut inv_l1, |i0, chunk| {
                    for (k, v) in chunk.iter_mut().enumerate() {
                        *v = inv_l1_row(a, i0 + k);
                    }
                });
                LevelSmoother::L1Jacobi { inv_l1 }
            }
            Smoother::L1GaussSeidel => {
                let block = gs_block(n);
                let mut inv_diag = try_filled(n, 0.0, "the smoother's inverse diagonal")?;
                a.for_row_chunks(&mut inv_diag, |i0, chunk| {
                    for (k, v) in chunk.iter_mut().enumerate() {
                        let i = i0 + k;
                        *v = inv_l1_gs_row(a, i, diag[i], block);
                    }
                });
                LevelSmoother::L1GaussSeidel { inv_diag, block }
            }
        })
    }

    /// The smoother of `a`, a matrix of the same order whose rows differ from those of the
    /// matrix it was built for in the ascending `rows` at most (the caller's guarantee): the
    /// data of those rows rebuilt, the same bits as [`Self::new`] for `a`. `false`, and nothing
    /// changed, for a smoother whose data is not row by row (Chebyshev's spectral bounds) or
    /// not of the kind `opts` names.
    pub(super) fn update_rows<A: Rows + ?Sized>(
        &mut self,
        a: &A,
        rows: &[u32],
        opts: &AmgOptions,
    ) -> bool {
        let n = a.n_rows();
        match (self, opts.smoother) {
            (LevelSmoother::L1Jacobi { inv_l1 }, Smoother::L1Jacobi) if inv_l1.len() == n => {
                for &i in rows {
                    inv_l1[i as usize] = inv_l1_row(a, i as usize);
                }
                true
            }
            (LevelSmoother::L1GaussSeidel { inv_diag, block }, Smoother::L1GaussSeidel)
                if inv_diag.len() == n && *block == gs_block(n) =>
            {
                for &i in rows {
                    let i = i as usize;
                    let (cols, vals) = a.row(i);
                    // the diagonal as `Rows::try_diagonal` reads it
                    let d = cols.binary_search(&(i as u32)).map_or(0.0, |p| vals[p]);
                    inv_diag[i] = inv_l1_gs_row(a, i, d, *block);
                }
                true
            }
            _ => false,
        }
    }

    /// A placeholder holding no data, for the fine level of a [`super::CoarseHierarchy`]
    /// (rebuilt by [`super::CoarseHierarchy::with_fine`]).
    pub(super) fn empty() -> Self {
        LevelSmoother::L1Jacobi { inv_l1: Vec::new() }
    }

    /// How many of the vectors d0, d1 of [`LevelWork`] the smoother uses.
    pub(super) fn vectors(&self) -> usize {
        match self {
            LevelSmoother::Chebyshev { .. } => 2,
            LevelSmoother::L1Jacobi { .. } => 0,
            LevelSmoother::L1GaussSeidel { .. } => 1,
        }
    }

    /// Bytes of its data.
    pub(super) fn memory_bytes(&self) -> usize {
        let f = std::mem::size_of::<f64>();
        match self {
            LevelSmoother::Chebyshev { inv_diag, .. } => inv_diag.len() * f,
            LevelSmoother::L1Jacobi { inv_l1 } => inv_l1.len() * f,
            LevelSmoother::L1GaussSeidel { inv_diag, .. } => inv_diag.len() * f,
        }
    }

    /// The Chebyshev smoother's step ([`chebyshev`]): as pre-smoother (from x = 0, leaving
    /// the residual in `w.r`) or as post-smoother; nothing for the other smoothers.
    fn chebyshev<A: Rows + ?Sized>(
        &self,
        a: &A,
        b: &[f64],
        x: &mut [f64],
        w: &mut LevelWork,
        pre: bool,
    ) {
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
    pub(super) fn pre<A: Rows + ?Sized>(&self, a: &A, b: &[f64], x: &mut [f64], w: &mut LevelWork) {
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
    pub(super) fn post<A: Rows + ?Sized>(
        &self,
        a: &A,
        b: &[f64],
        x: &mut [f64],
        w: &mut LevelWork,
    ) {
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
fn rows3<A: Rows + ?Sized, F>(a: &A, u: &mut [f64], v: &mut [f64], w: &mut [f64], f: F)
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
fn rows2<A: Rows + ?Sized, F>(a: &A, u: &mut [f64], v: &mut [f64], f: F)
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
fn rows1<A: Rows + ?Sized, F>(a: &A, u: &mut [f64], f: F)
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
fn chebyshev<A: Rows + ?Sized>(
    a: &A,
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
fn gauss_seidel<A: Rows + ?Sized>(
    a: &A,
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
                a.for_rows(i0..i1, |i, cols, vals| {
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
                });
            }
            Some(xo) => {
                a.for_rows_rev(i0..i1, |i, cols, vals| {
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
                });
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
mod tests {
    use super::super::testing::{grid, iterations};
    use super::*;

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
}
