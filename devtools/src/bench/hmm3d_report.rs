//! The section of `BENCHMARKS.md` on HMM on n³ cubes, written from
//! `replication/results/bench_hmm3d.csv` only ([`super::hmm3d`]): a table per core count and
//! the verdict of target 5 (HMM on 200³ cubes within 24 GiB), computed from the rows.

use super::hmm3d::{BYTES_PER_CELL, Hmm3Row, TARGET_MIB, TARGET_N, estimated_bytes};
use gradvi::budget::human_bytes;
use gradvi_cli::markdown::{Doc, Table, cells, fixed, met, seconds};

/// The verdict of target 5 from the rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// No row at n = [`TARGET_N`].
    NotRun,
    /// A row at n = [`TARGET_N`], on some core count, with a peak within [`TARGET_MIB`] and a
    /// passed certificate.
    Met,
    /// Rows at n = [`TARGET_N`], none of them within the memory with a passed certificate.
    NotMet,
}

/// Whether `r` meets target 5: n = [`TARGET_N`], peak ≤ [`TARGET_MIB`], certificate passed.
fn meets(r: &Hmm3Row) -> bool {
    r.n == TARGET_N && r.peak_mib <= TARGET_MIB && r.certified
}

/// The verdict of target 5 ([`Verdict`]).
pub fn verdict(rows: &[Hmm3Row]) -> Verdict {
    if !rows.iter().any(|r| r.n == TARGET_N) {
        Verdict::NotRun
    } else if rows.iter().any(meets) {
        Verdict::Met
    } else {
        Verdict::NotMet
    }
}

/// The core counts of the rows, ascending.
fn core_counts(rows: &[Hmm3Row]) -> Vec<usize> {
    let mut c: Vec<usize> = rows.iter().map(|r| r.cores).collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// The certificate's balance residual, and "failed" when the certificate did not pass.
fn certificate_cell(r: &Hmm3Row) -> String {
    let failed = if r.certified { "" } else { " (failed)" };
    format!("{:.1e}{failed}", r.balance_residual)
}

/// The table of the rows on `cores` cores, by n.
fn table(rows: &[Hmm3Row], cores: usize) -> Table {
    let mut t = Table::new(
        "n | cells | unknowns | NITER (+coarse) | Krylov | time [s] | time per cell [µs] | peak [MiB] | bytes per cell | R | certificate residual | L2 error of u",
        "rrrlrrrrrrrr",
    );
    let mut of: Vec<&Hmm3Row> = rows.iter().filter(|r| r.cores == cores).collect();
    of.sort_by_key(|r| r.n);
    for r in of {
        t.row(cells![
            r.n,
            r.cells,
            r.unknowns,
            format!("{} (+{})", r.niter, r.coarse_niter),
            r.krylov,
            seconds(r.total_s),
            fixed(r.us_per_cell(), 2),
            fixed(r.peak_mib, 0),
            fixed(r.bytes_per_cell(), 0),
            fixed(r.r, 2),
            certificate_cell(r),
            format!("{:.3e}", r.l2_u)
        ]);
    }
    t
}

/// The verdict line of target 5.
fn verdict_line(rows: &[Hmm3Row]) -> String {
    let target = format!(
        "Target 5, HMM on {TARGET_N}³ cubes within {:.0} GiB",
        TARGET_MIB / 1024.0
    );
    let measured: Vec<String> = rows
        .iter()
        .filter(|r| r.n == TARGET_N)
        .map(|r| {
            format!(
                "{} cores: peak {:.0} MiB, certificate {}",
                r.cores,
                r.peak_mib,
                if r.certified {
                    "passed".to_string()
                } else if r.error.is_empty() {
                    "failed".to_string()
                } else {
                    format!(
                        "failed: the solve stopped with the typed error '{}'",
                        r.error
                    )
                }
            )
        })
        .collect();
    match verdict(rows) {
        Verdict::NotRun => format!(
            "{target}: not run (`GRADVI_BENCH_HMM3D_MAX_N={TARGET_N} make bench-hmm3d`; estimated peak {} at {BYTES_PER_CELL:.0} bytes per cell).",
            human_bytes(estimated_bytes(TARGET_N) as u64)
        ),
        v => format!(
            "{target}: {} ({}).",
            met(v == Verdict::Met),
            measured.join("; ")
        ),
    }
}

/// Writes the section into `md` ("not run" without rows).
pub fn write(md: &mut Doc, rows: &[Hmm3Row]) {
    md.section(
        2,
        format!(
            "HMM on n³ cubes (target 5: {TARGET_N}³ within {:.0} GiB)",
            TARGET_MIB / 1024.0
        ),
        "The 3D radial obstacle problem (`problems/ex9-3d.toml`) on (−2,2)³ cut into n³ cubes, gradvi alone: HMM with the iterative solver (multigrid CG, nested warm start) on that many rayon threads, each case in its own process. Time is the wall clock of the whole process (mesh generation included), per cell next to it; peak is the process's peak resident set, per cell next to it. R is the obstacle solve over its linear variant (the same system without the constraint, same solver and cores). The certificate residual is the scaled balance residual of the certificate; the L2 error is the relative L² error of u at the centroids against the exact solution. Each row is a single run.",
    );
    if rows.is_empty() {
        md.para("*The HMM cubes benchmark (`gradvi-dev bench --hmm3d`, `make bench-hmm3d`) has not been run: no `bench_hmm3d.csv`.*");
    } else {
        for cores in core_counts(rows) {
            md.para(format!(
                "On {cores} core{}:",
                if cores == 1 { "" } else { "s" }
            ));
            md.table(&table(rows, cores));
        }
    }
    md.para(verdict_line(rows));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A certified row at `n` on `cores` cores with peak `peak` MiB.
    fn row(n: usize, cores: usize, peak: f64) -> Hmm3Row {
        Hmm3Row {
            n,
            cells: n * n * n,
            faces: 3 * n * n * (n + 1),
            unknowns: n * n * n + 3 * n * n * (n + 1),
            cores,
            niter: 4,
            coarse_niter: 2,
            krylov: 60,
            setup_s: 1.0,
            solve_s: 2.0,
            total_s: 4.0,
            phases: String::new(),
            peak_mib: peak,
            violation: 0.0,
            balance_residual: 2e-12,
            certificate: 2e-12,
            certified: true,
            l2_u: 1e-3,
            l2_grad: 1e-2,
            linear_seconds: 2.0,
            linear_krylov: 20,
            r: 2.0,
            error: String::new(),
        }
    }

    #[test]
    fn the_verdict_needs_a_certified_200_cubed_row_within_24_gib() {
        assert_eq!(verdict(&[]), Verdict::NotRun);
        assert_eq!(verdict(&[row(128, 2, 3000.0)]), Verdict::NotRun);
        assert_eq!(verdict(&[row(200, 1, 24_577.0)]), Verdict::NotMet);
        // within the memory on one core count suffices
        let rows = [row(200, 1, 25_000.0), row(200, 2, 24_576.0)];
        assert_eq!(verdict(&rows), Verdict::Met);
        let mut failed = row(200, 2, 14_000.0);
        failed.certified = false;
        assert_eq!(verdict(&[failed]), Verdict::NotMet);
        assert_eq!(verdict(&[row(200, 2, f64::NAN)]), Verdict::NotMet);
    }

    #[test]
    fn a_failed_solve_is_not_met_and_its_error_is_in_the_verdict() {
        let mut failed = row(200, 2, 14_000.0);
        failed.certified = false;
        failed.error = "active-set solver: certificate failed".into();
        assert_eq!(verdict(std::slice::from_ref(&failed)), Verdict::NotMet);
        let line = verdict_line(&[failed]);
        assert!(line.contains("not met"), "{line}");
        assert!(
            line.contains("active-set solver: certificate failed"),
            "{line}"
        );
    }

    #[test]
    fn the_section_has_a_table_per_core_count_and_the_verdict() {
        let rows = [row(64, 2, 512.0), row(32, 1, 64.0), row(32, 2, 64.0)];
        let mut md = Doc::default();
        write(&mut md, &rows);
        let text = md.to_string();
        assert!(
            text.contains("On 1 core:") && text.contains("On 2 cores:"),
            "{text}"
        );
        // 512 MiB over 64³ cells: 2048 bytes per cell; 4 s over 262 144 cells: 15.26 µs
        let line = text.lines().find(|l| l.starts_with("| 64 |")).unwrap();
        assert!(
            line.contains("| 2048 |") && line.contains("| 15.26 |"),
            "{line}"
        );
        assert!(text.contains("not run"), "{text}");
        let mut md = Doc::default();
        write(&mut md, &[row(200, 2, 14_000.0)]);
        assert!(
            md.to_string()
                .contains("**met** (2 cores: peak 14000 MiB, certificate passed)")
        );
    }

    #[test]
    fn without_rows_the_section_says_not_run() {
        let mut md = Doc::default();
        write(&mut md, &[]);
        let text = md.to_string();
        assert!(text.contains("has not been run") && text.contains(": not run"));
    }
}
