//! Greedy aggregation of the unknowns on the graph of the strong couplings (step 2 of the
//! setup, see [`super`]).

use super::NONE;
use super::strength::Strength;
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::linalg::rows::Rows;

/// Greedy aggregation on the graph of the strong entries of A (`strength`; see the module
/// documentation): the aggregate of each unknown ([`NONE`] for an isolated one) and the
/// number of aggregates; [`AllocFailure`] if its arrays cannot be allocated.
pub(super) fn aggregate<A: Rows + ?Sized>(
    a: &A,
    strength: &Strength,
    diag: &[f64],
) -> Result<(Vec<u32>, usize), AllocFailure> {
    let n = a.n_rows();
    // the strong entries (column, value) of row i
    let srow = |i: usize| {
        let (cols, vals) = a.row(i);
        cols.iter()
            .zip(vals)
            .filter(move |&(&j, &v)| strength.strong(i, j as usize, v))
            .map(|(&j, &v)| (j as usize, v))
    };
    let has_strong = |i: usize| srow(i).next().is_some();
    let mut agg = try_filled(n, NONE, "the aggregates of the unknowns")?;
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
    let mut in_phase1: Vec<bool> = try_vec(n, "the first aggregation phase")?;
    in_phase1.extend(agg.iter().map(|&g| g != NONE));
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
    Ok((agg, n_agg as usize))
}

#[cfg(test)]
mod tests {
    use super::super::strength::Strength;
    use super::super::testing::{fix, grid};
    use super::*;

    #[test]
    fn every_coupled_unknown_is_aggregated_with_strong_neighbours() {
        let m = 30;
        // a row of unit rows (fixed unknowns) across the grid
        let a = fix(&grid(m, 1.0, 1.0, &|_, _| 1.0), &|k| k / m == 10);
        let d = a.diagonal();
        let strength = Strength::new(&d, 0.08);
        let (agg, n_agg) = aggregate(&a, &strength, &d).unwrap();
        // the decoupled rows belong to no aggregate, every other unknown to one
        for (k, &g) in agg.iter().enumerate() {
            assert_eq!(g == NONE, k / m == 10, "unknown {k}");
            assert!(g == NONE || (g as usize) < n_agg);
        }
        // aggregates of about 3 × 3 unknowns, each used
        let free = m * m - m;
        assert!(n_agg * 5 < free && n_agg * 12 > free, "{n_agg}");
        let mut size = vec![0; n_agg];
        agg.iter()
            .filter(|&&g| g != NONE)
            .for_each(|&g| size[g as usize] += 1);
        assert!(size.iter().all(|&s| s > 0));
        // each aggregated unknown has a strong neighbour in its aggregate
        for i in 0..m * m {
            if agg[i] == NONE {
                continue;
            }
            let (cols, vals) = a.row(i);
            let with = cols
                .iter()
                .zip(vals)
                .any(|(&j, &v)| strength.strong(i, j as usize, v) && agg[j as usize] == agg[i]);
            assert!(with, "unknown {i}");
        }
    }
}
