//! The equal-core tables of `BENCHMARKS.md`, the first of the peer sections, written from the
//! ex9 rows of `bench_peers.csv` only ([`super::peers`]): every gradvi variant next to PETSc's
//! ex9 at the same grid *and the same number of cores*, the ratios gradvi / PETSc, the cost
//! ratio R of each code with its linear solve's time per unknown, and each code's parallel
//! speed-up.
//!
//! Pairing: a gradvi row and a PETSc row are compared only when their `cores` are equal and
//! known (rows written before the `cores` column have 0 and are never paired: gradvi then ran
//! on every core and PETSc on one process). The speed-up of a row on N cores is
//! T(1 core) / T(N cores) of the same code, scheme, linear solver and grid.

use super::peers::PeerRow;
use gradvi_cli::markdown::{Doc, NONE, Table, cells, fixed, seconds};

/// The ex9 row of `code`, `scheme`, `linear` at `grid` on `cores` cores (`None` for
/// `cores == 0`, the rows without a core count).
pub fn ex9_row<'a>(
    rows: &'a [PeerRow],
    (code, scheme, linear): (&str, &str, &str),
    grid: usize,
    cores: usize,
) -> Option<&'a PeerRow> {
    rows.iter().find(|r| {
        cores > 0
            && r.family == "ex9"
            && r.code == code
            && r.scheme == scheme
            && r.linear == linear
            && r.grid == grid
            && r.cores == cores
    })
}

/// PETSc's ex9 row (gs+mg) at `grid` on `cores` MPI processes.
pub fn petsc_at(rows: &[PeerRow], grid: usize, cores: usize) -> Option<&PeerRow> {
    ex9_row(rows, ("petsc", "fd", "gs+mg"), grid, cores)
}

/// The parallel speed-up of `r`: the time of the same code, scheme, linear solver and grid on
/// one core over `r`'s (`None` for a one-core row or without the one-core row).
pub fn speedup(rows: &[PeerRow], r: &PeerRow) -> Option<f64> {
    if r.cores <= 1 {
        return None;
    }
    let one = ex9_row(rows, (&r.code, &r.scheme, &r.linear), r.grid, 1)?;
    Some(one.total_s / r.total_s)
}

/// The time per unknown of `r`'s linear variant, in µs (NaN without it).
pub fn linear_us_per_unknown(r: &PeerRow) -> f64 {
    1e6 * r.linear_seconds / r.unknowns as f64
}

/// `a / b` with two decimals ([`NONE`] when either is missing).
fn ratio(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => fixed(a / b, 2),
        _ => NONE.into(),
    }
}

/// The gradvi ex9 rows with a known core count, by grid, scheme, linear solver and cores.
fn gradvi_rows(rows: &[PeerRow]) -> Vec<&PeerRow> {
    let mut g: Vec<&PeerRow> = rows
        .iter()
        .filter(|r| r.family == "ex9" && r.code == "gradvi" && r.cores > 0)
        .collect();
    g.sort_by(|a, b| {
        (a.grid, &a.scheme, &a.linear, a.cores).cmp(&(b.grid, &b.scheme, &b.linear, b.cores))
    });
    g
}

/// Writes the equal-core sections into `md` (nothing when no ex9 row has a core count).
pub fn write(md: &mut Doc, rows: &[PeerRow]) {
    let gradvi = gradvi_rows(rows);
    if gradvi.is_empty() {
        return;
    }
    md.section(
        2,
        "ex9 at equal cores: gradvi against PETSc",
        "Each gradvi variant next to PETSc's ex9 (gs+mg) on the same G × G grid with the same number of cores: gradvi with that many rayon threads (`RAYON_NUM_THREADS`), PETSc with that many MPI processes (one process alone, `mpiexec -n N` above; its peak memory is the sum of the ranks' peaks, each measured by `/usr/bin/time` around the rank). Ratios are gradvi / PETSc. R is the cost ratio of each code: the obstacle solve's time over that of its linear variant (the same mesh, Dirichlet data, solver and cores without the barrier: gradvi with the constraint dropped, PETSc's `ex9_linear` with Newton line search instead of the VI solver), both timed as whole runs (with several runs of a case, the times are the medians and R the median of the runs' own ratios, every run's pair in the CSV's `pairs`); next to it the linear variant's own time per unknown, so that R cannot improve by a slower linear solve. The speed-up of each code is in the next table.",
    );
    let mut t = Table::new(
        "G | cores | scheme | linear | gradvi [s] | PETSc [s] | time ratio | gradvi [MiB] | PETSc [MiB] | memory ratio | R gradvi | R PETSc | linear gradvi [µs/unknown] | linear PETSc [µs/unknown]",
        "rrllrrrrrrrrrr",
    );
    for r in &gradvi {
        let p = petsc_at(rows, r.grid, r.cores);
        t.row(cells![
            r.grid,
            r.cores,
            r.scheme,
            r.linear,
            seconds(r.total_s),
            p.map_or(NONE.into(), |p| seconds(p.total_s)),
            ratio(Some(r.total_s), p.map(|p| p.total_s)),
            fixed(r.peak_mib, 0),
            p.map_or(NONE.into(), |p| fixed(p.peak_mib, 0)),
            ratio(Some(r.peak_mib), p.map(|p| p.peak_mib)),
            fixed(r.r, 2),
            p.map_or(NONE.into(), |p| fixed(p.r, 2)),
            fixed(linear_us_per_unknown(r), 2),
            p.map_or(NONE.into(), |p| fixed(linear_us_per_unknown(p), 2))
        ]);
    }
    md.table(&t);
    speedup_table(md, rows);
}

/// The parallel speed-up of every ex9 row on more than one core, PETSc's first at each grid.
fn speedup_table(md: &mut Doc, rows: &[PeerRow]) {
    md.section(
        3,
        "Parallel speed-up",
        "Time on one core over time on N cores, per code, scheme and linear solver (gradvi: rayon threads; PETSc: MPI processes), for the obstacle solve and for its linear variant.",
    );
    let mut t = Table::new(
        "G | code | scheme | linear | N | time, 1 core [s] | time, N cores [s] | speed-up | linear variant speed-up",
        "rlllrrrrr",
    );
    let mut many: Vec<&PeerRow> = rows
        .iter()
        .filter(|r| r.family == "ex9" && r.cores > 1)
        .collect();
    many.sort_by(|a, b| {
        let key = |r: &PeerRow| {
            (
                r.grid,
                r.code != "petsc",
                r.scheme.clone(),
                r.linear.clone(),
            )
        };
        key(a).cmp(&key(b)).then(a.cores.cmp(&b.cores))
    });
    for r in many {
        let one = ex9_row(rows, (&r.code, &r.scheme, &r.linear), r.grid, 1);
        t.row(cells![
            r.grid,
            r.code,
            r.scheme,
            r.linear,
            r.cores,
            one.map_or(NONE.into(), |o| seconds(o.total_s)),
            seconds(r.total_s),
            fixed(speedup(rows, r).unwrap_or(f64::NAN), 2),
            ratio(one.map(|o| o.linear_seconds), Some(r.linear_seconds))
        ]);
    }
    md.table(&t);
}

#[cfg(test)]
#[path = "peers_cores_tests.rs"]
mod tests;
