//! Solves with the Cholesky factor of an earlier matrix, corrected for a change of low rank
//! (the Sherman–Morrison–Woodbury formula): the last steps of an active-set iteration change
//! the condensed matrix in a few rows and columns only, and a new factorisation then costs
//! several times the triangular solves that the correction needs.
//!
//! Let S₀ = L Lᵀ (up to the permutation) be factorised and S = S₀ + D, with D nonzero only in
//! the rows and columns of a small set Q of unknowns (q = |Q|), given by its nonzero entries
//! (the caller records them while it assembles S over S₀'s values, so the two matrices never
//! take memory side by side: [`crate::assembly`]). D_QQ is symmetric: with its
//! eigen-decomposition D_QQ = V Λ Vᵀ, keeping the r eigenvalues above round-off
//! (|λ| > [`EIGEN_RTOL`] max |λ|), D = U Λ Uᵀ with U = P_Q V (n × r, P_Q the columns of the
//! identity on Q). Then
//!
//!   S⁻¹ c = y − Z (Λ⁻¹ + Uᵀ Z)⁻¹ Uᵀ y,   y = S₀⁻¹ c,   Z = S₀⁻¹ U,
//!
//! which needs one pass of the triangular solves over the r + 1 columns [c, U] and an r × r
//! solve (LU with full pivoting: Λ⁻¹ + Uᵀ Z is symmetric but indefinite when D is, as when
//! some unknowns are freed and others fixed). The rank r is what it costs: one cell of HMM
//! entering or leaving the active set changes its condensed block by a rank-one term, a P1
//! node freed or fixed changes its row and column, rank two.
//!
//! The formula is exact in exact arithmetic; in floating point its accuracy depends on the
//! conditioning of the r × r capacitance matrix. So the backward error of the result,
//! ‖c − S x‖∞ / (‖|S| |x|‖∞ + ‖c‖∞), is computed; above [`MAX_BACKWARD_ERROR`] one step of
//! iterative refinement (the same formula on the residual, one more triangular solve) is made,
//! and if that is not enough the caller factorises S instead. The answer is therefore one a
//! new factorisation would give to round-off.

use super::SpdFactor;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Eigenvalues of D_QQ below this fraction of the largest in magnitude are round-off.
pub const EIGEN_RTOL: f64 = 1e-13;

/// Largest normwise backward error of an accepted solve (a sparse Cholesky solve reaches a
/// small multiple of the machine epsilon).
pub const MAX_BACKWARD_ERROR: f64 = 1e-14;

/// What an updated solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateReport {
    /// q: the unknowns whose rows or columns changed.
    pub support: usize,
    /// r: the rank of the change.
    pub rank: usize,
    /// Steps of iterative refinement made (0 or 1).
    pub refinements: usize,
    /// Normwise backward error of the result.
    pub backward_error: f64,
}

/// y = S x for S symmetric, its lower triangle stored by columns (`col_ptr`, `row_idx`,
/// `values`).
pub fn symmetric_lower_mul(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    x: &[f64],
    y: &mut [f64],
    abs: bool,
) {
    y.fill(0.0);
    let f = |v: f64| if abs { v.abs() } else { v };
    for j in 0..col_ptr.len() - 1 {
        let xj = f(x[j]);
        let mut acc = 0.0;
        for p in col_ptr[j]..col_ptr[j + 1] {
            let (i, v) = (row_idx[p], f(values[p]));
            y[i] += v * xj;
            if i != j {
                acc += v * f(x[i]);
            }
        }
        y[j] += acc;
    }
}

/// The change D = S − S₀ as U Λ Uᵀ on the unknowns `q` (`v`: q × r, column-major).
struct Change {
    q: Vec<usize>,
    v: DMatrix<f64>,
    lambda: Vec<f64>,
}

/// The change D given by its nonzero lower-triangle entries `diff` (position in the pattern,
/// value), or `None` if it touches more than `max_support` unknowns or has rank above
/// `max_rank`.
fn change(
    col_ptr: &[usize],
    row_idx: &[usize],
    diff: &[(usize, f64)],
    max_support: usize,
    max_rank: usize,
) -> Option<Change> {
    if diff.len() > max_support * max_support {
        return None;
    }
    let mut entries = Vec::with_capacity(diff.len());
    let mut q: Vec<usize> = Vec::new();
    for &(p, d) in diff {
        if !d.is_finite() || p >= row_idx.len() {
            return None;
        }
        if d != 0.0 {
            let (i, j) = (row_idx[p], col_ptr.partition_point(|&c| c <= p) - 1);
            entries.push((i, j, d));
            q.push(i);
            q.push(j);
        }
    }
    q.sort_unstable();
    q.dedup();
    if q.len() > max_support {
        return None;
    }
    let pos = |g: usize| q.binary_search(&g).unwrap_or(0);
    let mut dq = DMatrix::<f64>::zeros(q.len(), q.len());
    for &(i, j, d) in &entries {
        let (a, b) = (pos(i), pos(j));
        dq[(a, b)] = d;
        dq[(b, a)] = d;
    }
    if q.is_empty() {
        return Some(Change {
            q,
            v: DMatrix::zeros(0, 0),
            lambda: Vec::new(),
        });
    }
    // non-finite values are left to the factorisation, which reports them
    let eig = SymmetricEigen::try_new(dq, f64::EPSILON, 10_000)?;
    let big = eig.eigenvalues.iter().fold(0.0f64, |m, l| m.max(l.abs()));
    let keep: Vec<usize> = (0..q.len())
        .filter(|&k| eig.eigenvalues[k].abs() > EIGEN_RTOL * big)
        .collect();
    if keep.len() > max_rank {
        return None;
    }
    let v = DMatrix::from_fn(q.len(), keep.len(), |a, k| eig.eigenvectors[(a, keep[k])]);
    let lambda = keep.iter().map(|&k| eig.eigenvalues[k]).collect();
    Some(Change { q, v, lambda })
}

/// The system S x = c (lower triangle `values`), solved through the factor of S₀.
struct Updated<'a> {
    factor: &'a SpdFactor,
    change: Change,
    /// Z = S₀⁻¹ U, n × r column-major.
    z: &'a [f64],
    /// LU of the capacitance matrix Λ⁻¹ + Uᵀ Z.
    cap: nalgebra::linalg::FullPivLU<f64, nalgebra::Dyn, nalgebra::Dyn>,
}

impl Updated<'_> {
    /// Uᵀ w (r entries) for a vector w of all unknowns.
    fn ut(&self, w: &[f64]) -> DVector<f64> {
        let c = &self.change;
        DVector::from_fn(c.lambda.len(), |k, _| {
            c.q.iter()
                .enumerate()
                .map(|(a, &g)| c.v[(a, k)] * w[g])
                .sum()
        })
    }

    /// x = y − Z (Λ⁻¹ + UᵀZ)⁻¹ Uᵀ y in place, y = S₀⁻¹ c given.
    fn correct(&self, y: &mut [f64]) -> bool {
        if self.change.lambda.is_empty() {
            return true;
        }
        let Some(w) = self.cap.solve(&self.ut(y)) else {
            return false;
        };
        let n = y.len();
        for (k, wk) in w.iter().enumerate() {
            let zk = &self.z[k * n..(k + 1) * n];
            for (yi, zi) in y.iter_mut().zip(zk) {
                *yi -= wk * zi;
            }
        }
        true
    }
}

/// The normwise backward error of x for S x = c (`y`: a buffer of x's length).
fn backward_error(
    (col_ptr, row_idx): (&[usize], &[usize]),
    s: &[f64],
    x: &[f64],
    c: &[f64],
    y: &mut [f64],
) -> f64 {
    let inf = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, |m, a| m.max(a.abs()));
    // S x, then |S| |x|, in the same buffer
    symmetric_lower_mul(col_ptr, row_idx, s, x, y, false);
    let r = inf(&mut c.iter().zip(y.iter()).map(|(a, b)| a - b));
    symmetric_lower_mul(col_ptr, row_idx, s, x, y, true);
    let scale = inf(&mut y.iter().copied()) + inf(&mut c.iter().copied());
    if scale > 0.0 { r / scale } else { r }
}

/// When an updated solve is tried: at most `support` unknowns whose rows or columns changed,
/// and a change of rank at most `rank`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// q at most.
    pub support: usize,
    /// r at most.
    pub rank: usize,
}

/// The memory of an updated solve, lent by the caller: `columns` holds the r + 1 columns
/// ((r + 1) n values) and, if its capacity allows, two more vectors (2n), which otherwise go
/// in `vectors`. Their capacity is reused, so a caller
/// that lends buffers it keeps anyway (the assembly's) adds no memory when they are large
/// enough; they are resized and overwritten.
pub struct Buffers<'a> {
    /// For [c, U], then [x, Z].
    pub columns: &'a mut Vec<f64>,
    /// For the residual and the backward error.
    pub vectors: &'a mut Vec<f64>,
}

/// Solves S x = c in place (`rhs`: c, overwritten by x), S with the lower-triangle `new`
/// values on the `pattern` (column pointers, row indices) of S₀ = S − D, which `factor`
/// factorises, D given by its nonzero lower-triangle entries `diff` (position in the pattern,
/// value; see the module docs). `None` (and `rhs` untouched) when the change exceeds
/// `limits`, or when the result is not accurate to [`MAX_BACKWARD_ERROR`] after one
/// refinement: factorise S instead.
pub fn solve_updated(
    factor: &SpdFactor,
    pattern: (&[usize], &[usize]),
    new: &[f64],
    diff: &[(usize, f64)],
    rhs: &mut [f64],
    limits: Limits,
    buf: Buffers<'_>,
) -> Option<UpdateReport> {
    let n = rhs.len();
    let (col_ptr, row_idx) = pattern;
    let change = change(col_ptr, row_idx, diff, limits.support, limits.rank)?;
    let (q, r) = (change.q.len(), change.lambda.len());
    // one pass over the factor for [c, U]
    // the two vectors after the columns when the columns' buffer has room for them
    let (cols, vecs) = (buf.columns, buf.vectors);
    let together = cols.capacity() >= (r + 3) * n;
    cols.clear();
    cols.resize((r + 1) * n, 0.0);
    if together {
        cols.resize((r + 3) * n, 0.0);
    } else {
        vecs.clear();
        vecs.resize(2 * n, 0.0);
    }
    let (cols, vecs) = if together {
        let (c, v) = cols.split_at_mut((r + 1) * n);
        (c, v)
    } else {
        (&mut cols[..], &mut vecs[..])
    };
    cols[..n].copy_from_slice(rhs);
    for k in 0..r {
        for (a, &g) in change.q.iter().enumerate() {
            cols[(k + 1) * n + g] = change.v[(a, k)];
        }
    }
    factor.solve_columns_in_place(cols, r + 1);
    let (x, z) = cols.split_at_mut(n);
    // Λ⁻¹ + Uᵀ Z
    let mut cap = DMatrix::<f64>::zeros(r, r);
    for k in 0..r {
        let zk = &z[k * n..(k + 1) * n];
        for j in 0..r {
            cap[(j, k)] = change
                .q
                .iter()
                .enumerate()
                .map(|(a, &g)| change.v[(a, j)] * zk[g])
                .sum();
        }
        cap[(k, k)] += 1.0 / change.lambda[k];
    }
    let up = Updated {
        factor,
        change,
        z,
        cap: cap.full_piv_lu(),
    };
    if !up.correct(x) {
        return None;
    }
    let (res, y) = vecs.split_at_mut(n);
    let mut err = backward_error(pattern, new, x, rhs, y);
    let mut refinements = 0;
    if !(err <= MAX_BACKWARD_ERROR) {
        // one step of iterative refinement: x += S⁻¹ (c − S x)
        symmetric_lower_mul(col_ptr, row_idx, new, x, res, false);
        for (ri, ci) in res.iter_mut().zip(rhs.iter()) {
            *ri = ci - *ri;
        }
        up.factor.solve_in_place(res);
        if !up.correct(res) {
            return None;
        }
        for (xi, di) in x.iter_mut().zip(res.iter()) {
            *xi += di;
        }
        refinements = 1;
        err = backward_error(pattern, new, x, rhs, y);
        if !(err <= MAX_BACKWARD_ERROR) {
            return None;
        }
    }
    rhs.copy_from_slice(x);
    Some(UpdateReport {
        support: q,
        rank: r,
        refinements,
        backward_error: err,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SpdPattern;

    /// The 5-point Laplacian on an m × m grid (lower triangle by columns), with the unknowns
    /// in `fixed` replaced by unit rows and columns — the matrices of an active-set iteration.
    fn laplacian(m: usize, fixed: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let n = m * m;
        let is_fixed = |i: usize| fixed.contains(&i);
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for j in 0..n {
            let (x, y) = (j % m, j / m);
            let mut col = vec![(j, if is_fixed(j) { 1.0 } else { 4.0 })];
            if x + 1 < m {
                col.push((j + 1, -1.0));
            }
            if y + 1 < m {
                col.push((j + m, -1.0));
            }
            for (i, a) in col {
                ri.push(i);
                v.push(if i != j && (is_fixed(i) || is_fixed(j)) {
                    0.0
                } else {
                    a
                });
            }
            cp.push(ri.len());
        }
        (cp, ri, v)
    }

    /// The nonzero entries of new − old.
    fn diff(old: &[f64], new: &[f64]) -> Vec<(usize, f64)> {
        old.iter()
            .zip(new)
            .enumerate()
            .filter(|(_, (a, b))| a.to_bits() != b.to_bits())
            .map(|(p, (a, b))| (p, b - a))
            .collect()
    }

    fn lim(support: usize, rank: usize) -> Limits {
        Limits { support, rank }
    }

    /// New buffers for one solve.
    macro_rules! bufs {
        () => {
            Buffers {
                columns: &mut Vec::new(),
                vectors: &mut Vec::new(),
            }
        };
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
    }

    #[test]
    fn updated_solves_match_a_new_factorisation() {
        let m = 30;
        let n = m * m;
        let old_fixed: Vec<usize> = (200..260).collect();
        // two unknowns freed, three fixed
        let mut new_fixed: Vec<usize> = (202..260).collect();
        new_fixed.extend([500, 501, 530]);
        let (cp, ri, old) = laplacian(m, &old_fixed);
        let (_, _, new) = laplacian(m, &new_fixed);
        let pat = SpdPattern::new(n, cp.clone(), ri.clone()).unwrap();
        let f_old = pat.factor(&old).unwrap();
        let c: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 101.0 - 0.3)
            .collect();
        let mut x = c.clone();
        let rep = solve_updated(
            &f_old,
            (&cp, &ri),
            &new,
            &diff(&old, &new),
            &mut x,
            lim(64, 16),
            bufs!(),
        )
        .unwrap();
        // freeing or fixing an unknown changes its row and column: rank two each
        assert!((5..=10).contains(&rep.rank), "{rep:?}");
        assert!(rep.backward_error <= MAX_BACKWARD_ERROR, "{rep:?}");
        let mut exact = c.clone();
        pat.factor(&new).unwrap().solve_in_place(&mut exact);
        let scale = exact.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        assert!(
            max_diff(&x, &exact) <= 1e-12 * scale,
            "{}",
            max_diff(&x, &exact)
        );
        // and the residual of the result is that of a solve
        let mut sx = vec![0.0; n];
        symmetric_lower_mul(&cp, &ri, &new, &x, &mut sx, false);
        assert!(max_diff(&sx, &c) <= 1e-12, "{}", max_diff(&sx, &c));
    }

    #[test]
    fn large_or_absent_changes_are_left_to_a_factorisation() {
        let m = 20;
        let n = m * m;
        let (cp, ri, old) = laplacian(m, &[]);
        let fixed: Vec<usize> = (0..40).collect();
        let (_, _, new) = laplacian(m, &fixed);
        let pat = SpdPattern::new(n, cp.clone(), ri.clone()).unwrap();
        let f = pat.factor(&old).unwrap();
        let c = vec![1.0; n];
        let mut x = c.clone();
        // S₀ = `old` to S = `s` with these limits
        let solve = |s: &[f64], x: &mut [f64], support: usize, rank: usize| {
            solve_updated(
                &f,
                (&cp, &ri),
                s,
                &diff(&old, s),
                x,
                lim(support, rank),
                bufs!(),
            )
        };
        // 40 unknowns fixed: rank 80 > 16
        assert!(solve(&new, &mut x, 1000, 16).is_none());
        assert_eq!(x, c, "the right-hand side is left untouched");
        // support above the cap
        assert!(solve(&new, &mut x, 30, 1000).is_none());
        // non-finite values: left to the factorisation, which reports them
        let mut bad = old.clone();
        bad[5] = f64::NAN;
        assert!(solve(&bad, &mut x, 1000, 16).is_none());
        assert_eq!(x, c);
        // no change at all: a plain solve
        let rep = solve(&old, &mut x, 10, 10).unwrap();
        assert_eq!((rep.support, rep.rank), (0, 0));
        let mut exact = c.clone();
        f.solve_in_place(&mut exact);
        assert_eq!(x, exact);
    }
}
