//! The smoothed prolongator P = (I − ω D_F⁻¹ A_F) T (steps 3 and 4 of the setup, see
//! [`super`]).

use super::NONE;
use super::rows::build_rows;
use super::spectral::lanczos_lambda_max;
use crate::linalg::csr::{CsrMatrix, ROW_CHUNK};
use rayon::prelude::*;

/// P = (I − ω D_F⁻¹ A_F) T (see the module documentation): row i is
/// (1 − ω) T_i − (ω / d^F_i) Σ_{j kept} a_ij T_j, where row i of A_F keeps the a_ij (j ≠ i) with
/// |a_ij| ≥ θ_P a_ii and lumps the others into d^F_i = a_ii + Σ_{j dropped} a_ij; for the
/// near-null vector `b` of this level. Also returns the near-null vector of the next level.
pub(super) fn smoothed_prolongator(
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
