//! The smoothed prolongator P = (I − ω D_F⁻¹ A_F) T (steps 3 and 4 of the setup, see
//! [`super`]).

use super::NONE;
use super::rows::build_counted_rows;
use super::spectral::lanczos_lambda_max;
use crate::budget::{AllocFailure, try_filled};
use crate::linalg::csr::{CsrMatrix, ROW_CHUNK};
use crate::linalg::rows::Rows;
use rayon::prelude::*;

/// P = (I − ω D_F⁻¹ A_F) T (see the module documentation): row i is
/// (1 − ω) T_i − (ω / d^F_i) Σ_{j kept} a_ij T_j, where row i of A_F keeps the a_ij (j ≠ i) with
/// |a_ij| ≥ θ_P a_ii and lumps the others into d^F_i = a_ii + Σ_{j dropped} a_ij; for the
/// near-null vector `b` of this level. Also returns the near-null vector of the next level.
/// [`AllocFailure`] if P or the vectors of its construction cannot be allocated.
pub(super) fn smoothed_prolongator<A: Rows + ?Sized>(
    a: &A,
    diag: &[f64],
    agg: &[u32],
    n_agg: usize,
    b: &[f64],
    theta_p: f64,
    spectral_steps: usize,
) -> Result<(CsrMatrix, Vec<f64>), AllocFailure> {
    let n = a.n_rows();
    let b_coarse = coarse_near_null(agg, n_agg, b)?;
    // T_iJ = b_i / ‖b|𝒜_J‖
    let t = |i: usize| -> f64 {
        match agg[i] {
            NONE => 0.0,
            g => {
                let nb = b_coarse[g as usize];
                if nb > 0.0 { b[i] / nb } else { 0.0 }
            }
        }
    };
    let filter = Filter { diag, theta_p };
    let dfil = filtered_diagonal(a, filter)?;
    let omega = damping(a, filter, &dfil, spectral_steps)?;
    // row i into the scratch (columns sorted), computed twice: to count it, then to write it
    // in place (build_counted_rows: the prolongator is held once)
    let row = |(cols, vals): &mut (Vec<u32>, Vec<f64>), i: usize| {
        cols.clear();
        vals.clear();
        let scale = omega / dfil[i];
        let mut add = |g: u32, v: f64| {
            if let Some(p) = cols.iter().position(|&c| c == g) {
                vals[p] += v;
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
            if g != NONE && filter.kept(i, j, v) {
                add(g, -scale * v * t(j as usize));
            }
        }
        sort_tail(cols, vals, 0);
    };
    let p = build_counted_rows(
        n,
        n_agg,
        || Ok((Vec::new(), Vec::new())),
        |s, i| {
            row(s, i);
            s.0.len()
        },
        |s, i, cols, vals| {
            row(s, i);
            cols.copy_from_slice(&s.0);
            vals.copy_from_slice(&s.1);
        },
    )?;
    Ok((p, b_coarse))
}

/// The near-null vector of the next level, b^c_J = ‖b|𝒜_J‖, so that T b^c = b on the
/// aggregated unknowns with T_iJ = b_i / ‖b|𝒜_J‖ (the QR factorisation of b restricted to
/// each aggregate).
fn coarse_near_null(agg: &[u32], n_agg: usize, b: &[f64]) -> Result<Vec<f64>, AllocFailure> {
    let mut b_coarse = try_filled(n_agg, 0.0, "the coarse near-null vector")?;
    for (&g, &bi) in agg.iter().zip(b) {
        if g != NONE {
            b_coarse[g as usize] += bi * bi;
        }
    }
    b_coarse.iter_mut().for_each(|v| *v = v.sqrt());
    Ok(b_coarse)
}

/// Which off-diagonal entries the smoothing matrix A_F keeps: |a_ij| ≥ θ_P a_ii.
#[derive(Clone, Copy)]
struct Filter<'d> {
    diag: &'d [f64],
    theta_p: f64,
}

impl Filter<'_> {
    /// Whether the entry a_ij = `v` of row i, column j, is an off-diagonal entry of A_F.
    fn kept(&self, i: usize, j: u32, v: f64) -> bool {
        j as usize != i && v.abs() >= self.theta_p * self.diag[i]
    }
}

/// The diagonal of A_F, d^F_i = a_ii + Σ_{j dropped} a_ij (a_ii where lumping positive entries
/// would leave it non-positive).
fn filtered_diagonal<A: Rows + ?Sized>(a: &A, filter: Filter) -> Result<Vec<f64>, AllocFailure> {
    let diag = filter.diag;
    let mut dfil = try_filled(a.n_rows(), 0.0, "the filtered diagonal")?;
    a.for_row_chunks(&mut dfil, |i0, chunk| {
        for (k, d) in chunk.iter_mut().enumerate() {
            let i = i0 + k;
            let (cols, vals) = a.row(i);
            let dropped: f64 = cols
                .iter()
                .zip(vals)
                .filter(|&(&j, &v)| j as usize != i && !filter.kept(i, j, v))
                .map(|(_, v)| v)
                .sum();
            let f = diag[i] + dropped;
            *d = if f > 1e-12 * diag[i] { f } else { diag[i] };
        }
    });
    Ok(dfil)
}

/// ω = 4 / (3 ρ) of the prolongator smoothing, with ρ the Gershgorin bound of
/// ρ(D_F⁻¹ A_F), max_i 1 + Σ_{j kept} |a_ij| / d^F_i, or, on a level with positive
/// off-diagonal entries, 1.1 times the Lanczos estimate of λ_max(D⁻¹A) when smaller.
fn damping<A: Rows + ?Sized>(
    a: &A,
    filter: Filter,
    dfil: &[f64],
    spectral_steps: usize,
) -> Result<f64, AllocFailure> {
    let n = a.n_rows();
    let rho = (0..n)
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| {
            let (cols, vals) = a.row(i);
            let off: f64 = cols
                .iter()
                .zip(vals)
                .filter(|&(&j, &v)| filter.kept(i, j, v))
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
        (1.1 * lanczos_lambda_max(a, filter.diag, spectral_steps)?).min(rho)
    } else {
        rho
    };
    Ok(4.0 / (3.0 * rho))
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

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::*;

    #[test]
    fn the_prolongator_is_one_jacobi_step_on_the_tentative_one() {
        // Poisson on a 9 × 9 grid, aggregates of 3 × 3 unknowns, the constant near-null
        // vector, nothing filtered (θ_P = 0) and the Gershgorin bound (no Lanczos): ρ = 2, as
        // the interior rows sum to zero, ω = 2/3, and P b^c = (I − ω D⁻¹ A) b
        let m = 9;
        let a = grid(m, 1.0, 1.0, &|_, _| 1.0);
        let n = m * m;
        let agg: Vec<u32> = (0..n)
            .map(|k| ((k / m / 3) * 3 + (k % m) / 3) as u32)
            .collect();
        let b = vec![1.0; n];
        let (p, bc) = smoothed_prolongator(&a, &a.diagonal(), &agg, 9, &b, 0.0, 0).unwrap();
        assert_eq!((p.n_rows(), p.n_cols()), (n, 9));
        assert!(bc.iter().all(|&v| (v - 3.0).abs() < 1e-15), "{bc:?}");
        let mut pb = vec![0.0; n];
        p.spmv(&bc, &mut pb).unwrap();
        let mut ab = vec![0.0; n];
        a.spmv(&b, &mut ab).unwrap();
        let d = a.diagonal();
        for i in 0..n {
            let expected = b[i] - 2.0 / 3.0 * ab[i] / d[i];
            assert!(
                (pb[i] - expected).abs() < 1e-14,
                "row {i}: {} vs {expected}",
                pb[i]
            );
        }
        // an unknown in no aggregate (the centre of aggregate 4, left with 8 unknowns) has no
        // tentative entry, only its neighbours' smoothed ones: −(ω / 4) Σ_j a_ij / √8
        let mut agg1 = agg.clone();
        agg1[40] = NONE;
        let (p1, bc1) = smoothed_prolongator(&a, &a.diagonal(), &agg1, 9, &b, 0.0, 0).unwrap();
        assert!((bc1[4] - 8f64.sqrt()).abs() < 1e-15);
        let (cols, vals) = p1.row(40);
        assert_eq!(cols, [4]);
        assert!(
            (vals[0] - 2.0 / 3.0 / 8f64.sqrt()).abs() < 1e-15,
            "{vals:?}"
        );
        assert!((0..n).all(|i| p1.row(i).0.windows(2).all(|w| w[0] < w[1])));
    }
}
