//! The ex9 rows of the targets table of `BENCHMARKS.md`: the 2D targets of the performance
//! issue (equal cores), each verdict computed from the ex9 rows of `bench_peers.csv`
//! ([`super::peers`]).
//!
//! - P1 against PETSc's gs+mg at 1M and 4M unknowns (1025² and 2049² grids), at every core
//!   count measured: time ≤ [`TIME_RATIO`] × PETSc's, peak memory ≤ [`MEMORY_RATIO`] × PETSc's,
//!   errors no larger (to 0.1 %, the solver tolerances), gradvi's fastest linear solver;
//! - HMM on 1024² and 2048² cells (the 1025² and 2049² rows): time ≤ PETSc's at equal cores;
//! - the cost ratio R ≤ [`R_MAX`] from 1M unknowns up, P1 and HMM, on the iterative rows
//!   (`auto`'s choice from 250 000 unknowns in 2D);
//! - the time per unknown of P1 at 16.8M (4097²) within [`GROWTH_MAX`] × that at 1M, on the
//!   most cores measured; and the 4097² solve within 24 GiB, memory ≤ [`MEMORY_RATIO`] ×
//!   PETSc's there.
//!
//! A target whose rows are missing is 'not run' with no verdict.

use super::peers::PeerRow;
use super::peers_cores::petsc_at;
use gradvi_cli::markdown::{NONE, Table, cells, met};

/// Target of gradvi's time over PETSc's (P1, 1M and 4M unknowns).
pub const TIME_RATIO: f64 = 0.75;
/// Target of gradvi's peak memory over PETSc's.
pub const MEMORY_RATIO: f64 = 0.5;
/// Target of the cost ratio R in 2D, from 1M unknowns.
pub const R_MAX: f64 = 1.25;
/// Target of the growth of the time per unknown from 1M to 16.8M unknowns.
pub const GROWTH_MAX: f64 = 1.15;
/// The grids of the 1M and 4M targets, with their labels.
const GRIDS: [(usize, &str); 2] = [(1025, "1M"), (2049, "4M")];

/// The fastest gradvi row of `scheme` at `grid` on `cores` cores (over the linear solvers).
pub fn best<'a>(
    rows: &'a [PeerRow],
    scheme: &str,
    grid: usize,
    cores: usize,
) -> Option<&'a PeerRow> {
    gradvi_ex9(rows)
        .filter(|r| r.scheme == scheme && r.grid == grid && r.cores == cores)
        .min_by(|a, b| a.total_s.total_cmp(&b.total_s))
}

/// gradvi's ex9 rows with a core count.
fn gradvi_ex9(rows: &[PeerRow]) -> impl Iterator<Item = &PeerRow> {
    rows.iter()
        .filter(|r| r.family == "ex9" && r.code == "gradvi" && r.cores > 0)
}

/// "1 core", "N cores".
fn cores_label(n: usize) -> String {
    if n == 1 {
        "1 core".into()
    } else {
        format!("{n} cores")
    }
}

/// The core counts of the ex9 rows that have one, in increasing order.
fn ex9_cores(rows: &[PeerRow]) -> Vec<usize> {
    let mut c: Vec<usize> = rows
        .iter()
        .filter(|r| r.family == "ex9" && r.cores > 0)
        .map(|r| r.cores)
        .collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// Appends the ex9 target rows to `t`.
pub fn ex9_targets(t: &mut Table, rows: &[PeerRow]) {
    let cores = ex9_cores(rows);
    if cores.is_empty() {
        t.row(cells![
            "ex9 against PETSc at equal cores",
            "not run (no row with a core count)",
            NONE
        ]);
        return;
    }
    for &n in &cores {
        p1_against_petsc(t, rows, n);
        hmm_against_petsc(t, rows, n);
    }
    for scheme in ["p1", "hmm"] {
        cost_ratio(t, rows, scheme);
    }
    let most = cores[cores.len() - 1];
    growth(t, rows, most);
    big_grid(t, rows);
}

/// Target 1 on `n` cores: P1's time and memory against PETSc's at 1M and 4M unknowns.
fn p1_against_petsc(t: &mut Table, rows: &[PeerRow], n: usize) {
    for (g, label) in GRIDS {
        let what = format!(
            "ex9 P1 at {label} unknowns ({g}²), {}: time ≤ {TIME_RATIO}× and memory ≤ {MEMORY_RATIO}× PETSc gs+mg, errors no larger",
            cores_label(n)
        );
        let (Some(p), Some(b)) = (petsc_at(rows, g, n), best(rows, "p1", g, n)) else {
            t.row(cells![what, "not run", NONE]);
            continue;
        };
        let (tr, mr) = (b.total_s / p.total_s, b.peak_mib / p.peak_mib);
        let ok = tr <= TIME_RATIO && mr <= MEMORY_RATIO && b.err_max <= p.err_max * (1.0 + 1e-3);
        t.row(cells![
            what,
            format!(
                "gradvi P1 ({}) {:.2} s, {:.0} MiB, max error {:.4e}; PETSc {:.2} s, {:.0} MiB, {:.4e}: time ratio {tr:.2}, memory ratio {mr:.2}",
                b.linear, b.total_s, b.peak_mib, b.err_max, p.total_s, p.peak_mib, p.err_max
            ),
            met(ok)
        ]);
    }
}

/// Target 2 on `n` cores: HMM on 1024² and 2048² cells against PETSc at 1M and 4M unknowns.
fn hmm_against_petsc(t: &mut Table, rows: &[PeerRow], n: usize) {
    for (g, label) in GRIDS {
        let what = format!(
            "ex9 HMM on {c}² cells, {}: time ≤ PETSc gs+mg at {label} unknowns",
            cores_label(n),
            c = g - 1
        );
        match (petsc_at(rows, g, n), best(rows, "hmm", g, n)) {
            (Some(p), Some(h)) => t.row(cells![
                what,
                format!(
                    "gradvi HMM ({}) {:.2} s; PETSc {:.2} s: ratio {:.2}",
                    h.linear,
                    h.total_s,
                    p.total_s,
                    h.total_s / p.total_s
                ),
                met(h.total_s <= p.total_s)
            ]),
            _ => t.row(cells![what, "not run", NONE]),
        }
    }
}

/// Target 3: the largest R of `scheme`'s iterative rows from 1M unknowns, over grids and cores.
fn cost_ratio(t: &mut Table, rows: &[PeerRow], scheme: &str) {
    let what = format!(
        "ex9 {}: R ≤ {R_MAX} from 1M unknowns (iterative solver, every core count)",
        scheme.to_uppercase()
    );
    let worst = gradvi_ex9(rows)
        .filter(|r| {
            r.scheme == scheme
                && r.linear == "iterative"
                && r.unknowns >= 1_000_000
                && r.r.is_finite()
        })
        .max_by(|a, b| a.r.total_cmp(&b.r));
    match worst {
        Some(w) => t.row(cells![
            what,
            format!(
                "largest R {:.2} ({}², {} cores: {:.2} s against {:.2} s for the linear variant{})",
                w.r,
                w.grid,
                w.cores,
                w.total_s,
                w.linear_seconds,
                runs_ratios(w)
            ),
            met(w.r <= R_MAX)
        ]),
        None => t.row(cells![what, "not run", NONE]),
    }
}

/// The ratios of every run of `row` when it has several (`pairs`): "; medians of n runs, R
/// the median of their ratios a, b, c"; empty for a row of one run or without its pairs.
pub(super) fn runs_ratios(row: &PeerRow) -> String {
    match super::peers::pairs_of(&row.pairs) {
        Some(p) if p.len() > 1 => {
            let r: Vec<String> = p.iter().map(|(o, l)| format!("{:.2}", o / l)).collect();
            format!(
                "; medians of {} runs, R the median of their ratios {}",
                p.len(),
                r.join(", ")
            )
        }
        _ => String::new(),
    }
}

/// Target 4 on `n` cores: P1's time per unknown at 16.8M unknowns over that at 1M.
fn growth(t: &mut Table, rows: &[PeerRow], n: usize) {
    let what = format!(
        "ex9 P1, {}: time per unknown at 16.8M (4097²) ≤ {GROWTH_MAX}× that at 1M (1025²)",
        cores_label(n)
    );
    let per = |g| best(rows, "p1", g, n).map(|r| (r.total_s / r.unknowns as f64, r));
    match (per(1025), per(4097)) {
        (Some((a, ra)), Some((b, rb))) => t.row(cells![
            what,
            format!(
                "{:.2} µs at 1M ({}), {:.2} µs at 16.8M ({}): ratio {:.2}",
                1e6 * a,
                ra.linear,
                1e6 * b,
                rb.linear,
                b / a
            ),
            met(b / a <= GROWTH_MAX)
        ]),
        _ => t.row(cells![
            what,
            "not run (the 4097² grid runs where 21 GiB are available and GRADVI_BENCH_EX9_MAX_GRID allows it)",
            NONE
        ]),
    }
}

/// The 4097² grid: gradvi P1 within 24 GiB, and its memory against PETSc's at equal cores.
fn big_grid(t: &mut Table, rows: &[PeerRow]) {
    let what = format!(
        "ex9 at 4097² (16.8M P1 unknowns): within 24 GiB, memory ≤ {MEMORY_RATIO}× PETSc's at equal cores"
    );
    let big = gradvi_ex9(rows)
        .filter(|r| r.scheme == "p1" && r.grid == 4097)
        .max_by_key(|r| r.cores);
    let limit_mib = 24.0 * 1024.0;
    let Some(r) = big else {
        t.row(cells![
            what,
            "not run (the benchmark runs it where 21 GiB are available and GRADVI_BENCH_EX9_MAX_GRID allows it)",
            NONE
        ]);
        return;
    };
    let petsc = petsc_at(rows, 4097, r.cores);
    let ratio = petsc.map(|p| r.peak_mib / p.peak_mib);
    t.row(cells![
        what,
        format!(
            "gradvi P1 ({}, {} cores) {:.0} s, peak {:.0} MiB (limit {limit_mib:.0}), certificate {:.1e}, max error {:.4e}{}",
            r.linear,
            r.cores,
            r.total_s,
            r.peak_mib,
            r.certificate,
            r.err_max,
            petsc.map_or(String::new(), |p| format!(
                "; PETSc {:.0} s, {:.0} MiB, {:.4e}: memory ratio {:.2}",
                p.total_s,
                p.peak_mib,
                p.err_max,
                r.peak_mib / p.peak_mib
            ))
        ),
        met(r.peak_mib <= limit_mib && ratio.is_some_and(|m| m <= MEMORY_RATIO))
    ]);
}
