//! Strength of connection: which couplings of A_ℓ are strong (step 1 of the setup, see
//! [`super`]).

/// The strong off-diagonal entries of A (diagonal `diag`): a_ij ≠ 0 with
/// a_ij² ≥ θ² a_ii a_jj, whatever their sign. (`replication/BENCHMARKS.md`, "Measurements
/// behind the defaults", compares this rule with counting only the negative couplings as
/// strong.)
///
/// The rule is evaluated where the aggregation reads an entry (two products and a
/// comparison), not stored: a flag per stored entry would be an array of the size of A's
/// entries, and for a masked view of A ([`crate::linalg::MaskedRows`]) also the offsets of its
/// rows (8 bytes per unknown), held through the setup of the fine level.
pub(super) struct Strength<'d> {
    diag: &'d [f64],
    /// θ².
    t2: f64,
}

impl<'d> Strength<'d> {
    /// The rule for the matrix with diagonal `diag` and the threshold θ = `theta`.
    pub(super) fn new(diag: &'d [f64], theta: f64) -> Self {
        Strength {
            diag,
            t2: theta * theta,
        }
    }

    /// Whether the entry a_ij = `v` of row i, column j, is strong.
    #[inline]
    pub(super) fn strong(&self, i: usize, j: usize, v: f64) -> bool {
        j != i && v != 0.0 && v * v >= self.t2 * self.diag[i] * self.diag[j]
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::grid;
    use super::*;

    #[test]
    fn only_the_strong_direction_of_an_anisotropic_diffusion_is_strong() {
        // couplings 0.01 in x (neighbours j = i ± 1), 1 in y (j = i ± m); a_ii ≈ 2
        for m in [12, 150] {
            let a = grid(m, 0.01, 1.0, &|_, _| 1.0);
            let d = a.diagonal();
            let (rule, all) = (Strength::new(&d, 0.08), Strength::new(&d, 0.0));
            let (mut n_strong, mut n_all) = (0, 0);
            for i in 0..a.n_rows() {
                let (cols, vals) = a.row(i);
                for (&j, &v) in cols.iter().zip(vals) {
                    let s = rule.strong(i, j as usize, v);
                    let vertical = (j as usize).abs_diff(i) == m;
                    assert_eq!(s, vertical, "m = {m}, entry ({i}, {j})");
                    n_strong += s as usize;
                    n_all += all.strong(i, j as usize, v) as usize;
                }
            }
            assert_eq!(n_strong, 2 * m * (m - 1));
            // θ = 0: every off-diagonal nonzero
            assert_eq!(n_all, a.nnz() - a.n_rows());
        }
    }
}
