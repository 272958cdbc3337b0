//! Static condensation of one cell, and the recovery of its interior unknowns.
//!
//! The local unknowns of a cell are its interior unknowns I (first) and its skeleton unknowns
//! S. Some unknowns are *fixed* (Dirichlet, or active constraints): I = R ∪ F with R free.
//! Eliminating R from the local system gives the Schur complement on S
//!
//!   S_K = M_SS − M_SR M_RR⁻¹ M_RS,
//!   g_K = b_S − M_SF u_F − M_SR M_RR⁻¹ (b_R − M_RF u_F),
//!
//! and, once the skeleton values u_S are known, u_R = M_RR⁻¹ (b_R − M_RS u_S − M_RF u_F).
//! One interior unknown (HMM's u_K) has a scalar fast path; the general path uses a dense
//! Cholesky factorisation of M_RR (SPD as a principal block of an SPD matrix).

use nalgebra::{DMatrix, DVector, Dyn, linalg::Cholesky};

/// Entries of the lower triangle of an n × n matrix: n(n + 1)/2.
#[inline]
pub fn packed_len(n: usize) -> usize {
    n * (n + 1) / 2
}

/// The position of entry (i, j), i ≥ j, of an n × n symmetric matrix stored as its lower
/// triangle column by column (column j holds rows j..n): j(2n − j + 1)/2 + (i − j).
#[inline]
pub fn packed_index(n: usize, i: usize, j: usize) -> usize {
    debug_assert!(j <= i && i < n);
    j * (2 * n - j + 1) / 2 + (i - j)
}

/// A symmetric local matrix, stored as its lower triangle column by column (see
/// [`packed_index`]): the local matrices of the schemes are symmetric, and this takes
/// n(n + 1)/2 numbers instead of n² (a P1 triangle 6 instead of 9, an HMM quadrilateral with
/// its cell unknown 15 instead of 25). The upper entries read the lower ones, so a local
/// matrix whose two triangles differ in the last bits (rounding: HMM's W, P1 with an
/// anisotropic A) is used as its lower half everywhere. (With full storage, each condensed
/// entry read whichever local triangle the global numbering pointed to; the change moved
/// results at round-off level only.)
#[derive(Debug, Clone, Copy)]
pub struct SymMatrix<'c> {
    /// The order n.
    pub n: usize,
    /// The n(n + 1)/2 entries of the lower triangle.
    pub lower: &'c [f64],
}

impl SymMatrix<'_> {
    /// Entry (i, j).
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        self.lower[packed_index(self.n, i, j)]
    }
}

/// Writes the lower triangle of the n × n column-major matrix `m`, column by column, into the
/// first n(n + 1)/2 entries of `out`.
pub fn pack_lower(n: usize, m: &[f64], out: &mut [f64]) {
    let mut w = 0;
    for j in 0..n {
        let col = &m[j * n + j..(j + 1) * n];
        out[w..w + col.len()].copy_from_slice(col);
        w += col.len();
    }
}

/// The block M_RR of the free interior unknowns of a cell is not numerically positive
/// definite: the local matrix is not SPD to working precision (a degenerate cell, or a
/// diffusion tensor whose anisotropy ratio is near 1/ε). An SPD local matrix never gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InteriorNotSpd;

impl InteriorNotSpd {
    /// The error of the library, naming cell `k`.
    pub fn in_cell(self, k: usize) -> crate::Error {
        crate::Error::Linear(format!(
            "the block of the interior unknowns of the local matrix of cell {k} is not \
             numerically positive definite (a degenerate cell, or extreme anisotropy of the \
             diffusion tensor)"
        ))
    }
}

/// The local system of one cell: M_K u_K = b_K in the cell's unknowns.
#[derive(Debug, Clone, Copy)]
pub struct CellSystem<'c> {
    /// The global indices of the local unknowns: the interior ones I first, then the skeleton
    /// ones S.
    pub dofs: &'c [u32],
    /// The number of interior unknowns |I|.
    pub n_interior: usize,
    /// The local matrix M_K (symmetric, packed), in the order of `dofs`.
    pub matrix: SymMatrix<'c>,
    /// The local load b_K, in the order of `dofs`.
    pub load: &'c [f64],
}

impl CellSystem<'_> {
    /// The free interior unknowns R = I \ F (local indices).
    fn free_interior(&self, fx: &dyn Fn(usize) -> Option<f64>) -> Vec<usize> {
        (0..self.n_interior)
            .filter(|&i| fx(self.dofs[i] as usize).is_none())
            .collect()
    }

    /// The Cholesky factorisation of M_RR, the block of the free interior unknowns `free`.
    fn free_block_cholesky(&self, free: &[usize]) -> Result<Cholesky<f64, Dyn>, InteriorNotSpd> {
        let (m, r) = (self.matrix, free.len());
        DMatrix::from_fn(r, r, |a, c| m.at(free[a], free[c]))
            .cholesky()
            .ok_or(InteriorNotSpd)
    }
}

/// Condensation of one cell (see the module docs). `s` (length p²) receives the p×p skeleton
/// matrix S_K (column-major) and `g` (length p) the p skeleton loads g_K, p = |S|.
pub fn condense(
    cell: &CellSystem,
    fx: &dyn Fn(usize) -> Option<f64>,
    s: &mut [f64],
    g: &mut [f64],
) -> Result<(), InteriorNotSpd> {
    let CellSystem {
        dofs: d,
        n_interior: ni,
        matrix: m,
        load: b,
    } = *cell;
    let nl = d.len();
    let p = nl - ni;
    // S_K = M_SS and g_K = b_S before the elimination
    for bcol in 0..p {
        for arow in 0..p {
            s[arow + bcol * p] = m.at(ni + arow, ni + bcol);
        }
    }
    g.copy_from_slice(&b[ni..]);
    match ni {
        0 => Ok(()),
        1 => {
            eliminate_cell_unknown(cell, fx, s, g);
            Ok(())
        }
        _ => eliminate_interior(cell, fx, s, g),
    }
}

/// HMM's fast path, one interior unknown u_K (index 0): if it is fixed to v,
/// g_K −= M_SK v; otherwise S_K −= M_SK M_KS / M_KK and g_K −= M_SK b_K / M_KK.
fn eliminate_cell_unknown(
    cell: &CellSystem,
    fx: &dyn Fn(usize) -> Option<f64>,
    s: &mut [f64],
    g: &mut [f64],
) {
    let (d, m, b) = (cell.dofs, cell.matrix, cell.load);
    let (nl, ni) = (d.len(), 1);
    let p = nl - ni;
    match fx(d[0] as usize) {
        Some(v) => {
            for (arow, ga) in g.iter_mut().enumerate().take(p) {
                *ga -= m.at(ni + arow, 0) * v;
            }
        }
        None => {
            let mkk = m.at(0, 0);
            for bcol in 0..p {
                let mkb = m.at(0, ni + bcol);
                for arow in 0..p {
                    s[arow + bcol * p] -= m.at(ni + arow, 0) * mkb / mkk;
                }
            }
            for (arow, ga) in g.iter_mut().enumerate().take(p) {
                *ga -= m.at(ni + arow, 0) * b[0] / mkk;
            }
        }
    }
}

/// The general path, several interior unknowns: g_K −= M_SF u_F, then with
/// b_R' = b_R − M_RF u_F and the dense Cholesky factorisation of M_RR,
/// S_K −= M_SR (M_RR⁻¹ M_RS) and g_K −= M_SR (M_RR⁻¹ b_R').
fn eliminate_interior(
    cell: &CellSystem,
    fx: &dyn Fn(usize) -> Option<f64>,
    s: &mut [f64],
    g: &mut [f64],
) -> Result<(), InteriorNotSpd> {
    let (d, ni, m, b) = (cell.dofs, cell.n_interior, cell.matrix, cell.load);
    let nl = d.len();
    let p = nl - ni;
    let free = cell.free_interior(fx);
    let fixed: Vec<(usize, f64)> = (0..ni)
        .filter_map(|i| fx(d[i] as usize).map(|v| (i, v)))
        .collect();
    let mut br: Vec<f64> = free.iter().map(|&i| b[i]).collect();
    for &(j, v) in &fixed {
        for (arow, ga) in g.iter_mut().enumerate().take(p) {
            *ga -= m.at(ni + arow, j) * v;
        }
        for (q, &i) in free.iter().enumerate() {
            br[q] -= m.at(i, j) * v;
        }
    }
    if free.is_empty() {
        return Ok(());
    }
    let r = free.len();
    let msr = DMatrix::from_fn(p, r, |a, c| m.at(ni + a, free[c]));
    let chol = cell.free_block_cholesky(&free)?;
    let x = chol.solve(&msr.transpose()); // M_RR⁻¹ M_RS
    let y = chol.solve(&DVector::from_vec(br)); // M_RR⁻¹ b_R'
    for bcol in 0..p {
        for arow in 0..p {
            s[arow + bcol * p] -= (0..r).map(|q| msr[(arow, q)] * x[(q, bcol)]).sum::<f64>();
        }
    }
    for arow in 0..p {
        g[arow] -= (0..r).map(|q| msr[(arow, q)] * y[q]).sum::<f64>();
    }
    Ok(())
}

/// The interior unknown of a cell with exactly one (HMM's u_K), from its skeleton values:
/// the fixed value, or u_K = (b_K − Σ_{j∈S} M_Kj u_j) / M_KK.
pub fn interior_value(cell: &CellSystem, fx: &dyn Fn(usize) -> Option<f64>, u: &[f64]) -> f64 {
    let (d, m, b) = (cell.dofs, cell.matrix, cell.load);
    let nl = d.len();
    match fx(d[0] as usize) {
        Some(v) => v,
        None => {
            let mut r = b[0];
            for j in 1..nl {
                r -= m.at(0, j) * u[d[j] as usize];
            }
            r / m.at(0, 0)
        }
    }
}

/// Recovers the interior unknowns of one cell from its skeleton values:
/// u_F = their fixed values, u_R = M_RR⁻¹ (b_R − Σ_{j∉R} M_Rj u_j).
pub fn recover_interior(
    cell: &CellSystem,
    fx: &dyn Fn(usize) -> Option<f64>,
    u: &mut [f64],
) -> Result<(), InteriorNotSpd> {
    let (d, ni, m, b) = (cell.dofs, cell.n_interior, cell.matrix, cell.load);
    let nl = d.len();
    if ni == 1 {
        u[d[0] as usize] = interior_value(cell, fx, u);
        return Ok(());
    }
    let free = cell.free_interior(fx);
    for i in 0..ni {
        if let Some(v) = fx(d[i] as usize) {
            u[d[i] as usize] = v;
        }
    }
    if free.is_empty() {
        return Ok(());
    }
    let r = free.len();
    let rhs = DVector::from_fn(r, |a, _| {
        let i = free[a];
        let mut v = b[i];
        for j in 0..nl {
            if !free.contains(&j) {
                v -= m.at(i, j) * u[d[j] as usize];
            }
        }
        v
    });
    let x = cell.free_block_cholesky(&free)?.solve(&rhs);
    for (a, &i) in free.iter().enumerate() {
        u[d[i] as usize] = x[a];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vi::dense::spd;

    /// Condenses a cell with `ni` interior unknowns (some fixed) and checks S_K and g_K against
    /// the dense Schur complement, then the recovery against a dense solve of the full system.
    fn check(ni: usize, p: usize, fixed_interior: &[usize], seed: u64) {
        let nl = ni + p;
        let m = spd(nl, seed);
        let b = DVector::from_fn(nl, |i, _| 1.0 + i as f64 * 0.25);
        let d: Vec<u32> = (0..nl as u32).collect();
        let mut packed = vec![0.0; packed_len(nl)];
        pack_lower(nl, m.as_slice(), &mut packed);
        let fixed_val = |i: usize| 0.5 - 0.1 * i as f64;
        let fx = |i: usize| fixed_interior.contains(&i).then(|| fixed_val(i));
        let mut s = vec![0.0; p * p];
        let mut g = vec![0.0; p];
        let cell = CellSystem {
            dofs: &d,
            n_interior: ni,
            matrix: SymMatrix {
                n: nl,
                lower: &packed,
            },
            load: b.as_slice(),
        };
        condense(&cell, &fx, &mut s, &mut g).unwrap();
        // dense reference
        let free: Vec<usize> = (0..ni).filter(|i| !fixed_interior.contains(i)).collect();
        let r = free.len();
        let mrr = DMatrix::from_fn(r, r, |a, c| m[(free[a], free[c])]);
        let msr = DMatrix::from_fn(p, r, |a, c| m[(ni + a, free[c])]);
        let mss = DMatrix::from_fn(p, p, |a, c| m[(ni + a, ni + c)]);
        let uf = DVector::from_fn(nl, |i, _| fx(i).unwrap_or(0.0));
        let br = DVector::from_fn(r, |a, _| {
            b[free[a]] - (0..ni).map(|j| m[(free[a], j)] * uf[j]).sum::<f64>()
        });
        let inv = mrr.clone().try_inverse().unwrap();
        let s_ref = &mss - &msr * &inv * msr.transpose();
        let g_ref = DVector::from_fn(p, |a, _| {
            b[ni + a] - (0..ni).map(|j| m[(ni + a, j)] * uf[j]).sum::<f64>()
        }) - &msr * &inv * &br;
        for a in 0..p {
            assert!((g[a] - g_ref[a]).abs() < 1e-12, "g[{a}]");
            for c in 0..p {
                assert!((s[a + c * p] - s_ref[(a, c)]).abs() < 1e-12, "S[{a},{c}]");
            }
        }
        // skeleton values from the condensed system, then recovery = the full solve
        let us = DMatrix::from_column_slice(p, p, &s)
            .cholesky()
            .unwrap()
            .solve(&DVector::from_column_slice(&g));
        let mut u = vec![0.0; nl];
        for a in 0..p {
            u[ni + a] = us[a];
        }
        recover_interior(&cell, &fx, &mut u).unwrap();
        // reference: the full system with the fixed interior unknowns as unit rows
        let mut mf = m.clone();
        let mut bf = b.clone();
        for &i in fixed_interior {
            for j in 0..nl {
                mf[(i, j)] = if i == j { 1.0 } else { 0.0 };
            }
            bf[i] = fixed_val(i);
        }
        let uref = mf.lu().solve(&bf).unwrap();
        assert!(
            u.iter()
                .zip(uref.iter())
                .all(|(a, b)| (a - b).abs() < 1e-10),
            "u = {u:?}, the full solve gives {uref}"
        );
    }

    #[test]
    fn packed_storage_reads_both_triangles() {
        for n in 1..6 {
            let m = spd(n, 10 + n as u64);
            let mut packed = vec![f64::NAN; packed_len(n) + 1];
            pack_lower(n, m.as_slice(), &mut packed);
            // exactly n(n + 1)/2 entries written
            assert!(packed[packed_len(n)].is_nan());
            let packed = &packed[..packed_len(n)];
            let sym = SymMatrix { n, lower: packed };
            let mut seen = vec![false; packed_len(n)];
            for j in 0..n {
                for i in j..n {
                    let q = packed_index(n, i, j);
                    assert!(!seen[q], "n {n}: ({i}, {j}) at {q} twice");
                    seen[q] = true;
                    assert_eq!(sym.at(i, j), m[(i, j)]);
                    assert_eq!(sym.at(j, i), m[(i, j)]);
                }
            }
            assert!(seen.iter().all(|&s| s));
        }
    }

    #[test]
    fn one_interior_unknown_fast_path() {
        check(1, 4, &[], 1);
        check(1, 3, &[0], 2);
    }

    #[test]
    fn several_interior_unknowns_against_the_dense_schur_complement() {
        check(2, 3, &[], 3);
        check(3, 4, &[], 4);
        check(3, 4, &[1], 5);
        check(2, 5, &[0, 1], 6);
    }

    #[test]
    fn an_interior_block_that_is_not_spd_is_a_typed_error() {
        // two interior unknowns whose block [[1, 2], [2, 1]] is indefinite (what a tensor with
        // an anisotropy ratio near 1/ε can leave after rounding): an error naming the cell,
        // where the condensation used to panic
        let (ni, p) = (2, 2);
        let m = DMatrix::from_row_slice(
            4,
            4,
            &[
                1.0, 2.0, 0.1, 0.0, 2.0, 1.0, 0.0, 0.1, 0.1, 0.0, 3.0, 0.0, 0.0, 0.1, 0.0, 3.0,
            ],
        );
        let mut packed = vec![0.0; packed_len(ni + p)];
        pack_lower(ni + p, m.as_slice(), &mut packed);
        let d: Vec<u32> = (0..4).collect();
        let b = [1.0; 4];
        let cell = CellSystem {
            dofs: &d,
            n_interior: ni,
            matrix: SymMatrix {
                n: ni + p,
                lower: &packed,
            },
            load: &b,
        };
        let (mut s, mut g) = (vec![0.0; p * p], vec![0.0; p]);
        let e = condense(&cell, &|_| None, &mut s, &mut g).unwrap_err();
        assert_eq!(e, InteriorNotSpd);
        let msg = e.in_cell(7).to_string();
        assert!(
            msg.contains("cell 7") && msg.contains("positive definite"),
            "{msg}"
        );
        let mut u = vec![0.0; 4];
        assert_eq!(
            recover_interior(&cell, &|_| None, &mut u),
            Err(InteriorNotSpd)
        );
    }
}
