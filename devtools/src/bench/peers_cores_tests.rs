//! Tests of the equal-core tables on a small hand-made `bench_peers.csv`.

use super::*;
use gradvi_cli::replication::records::read_csv;

const HEADER: &str = "family,code,scheme,linear,grid,cells,unknowns,niter,coarse_niter,krylov,total_s,coarse_s,linear_s,peak_mib,err_max,err_mean,certificate";

/// Rows of a CSV written with `HEADER` plus `extra` columns, through the real reader (`tag`
/// names the temporary directory of the calling test).
fn rows_of(tag: &str, extra: &str, lines: &[&str]) -> Vec<PeerRow> {
    let dir = std::env::temp_dir().join(format!("gradvi-peers-cores-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bench_peers.csv");
    let mut text = format!("{HEADER}{extra}\n");
    for l in lines {
        text += &format!("{l}\n");
    }
    std::fs::write(&path, text).unwrap();
    let rows = read_csv(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    rows
}

/// PETSc at 1 and 2 processes, gradvi P1 at 1 and 2 threads (grid 257, 66 049 unknowns);
/// gradvi HMM on 4 threads only; a row without a core count (written before the column);
/// grid 513: PETSc on 2 processes, gradvi on 1 thread.
fn sample(tag: &str) -> Vec<PeerRow> {
    rows_of(
        tag,
        ",cores,linear_seconds,r",
        &[
            "ex9,petsc,fd,gs+mg,257,0,66049,3,14,80,2.0,,,100,1e-4,1e-5,,1,1.0,2.0",
            "ex9,petsc,fd,gs+mg,257,0,66049,3,14,80,1.6,,,180,1e-4,1e-5,,2,0.8,2.0",
            "ex9,gradvi,p1,iterative,257,131072,66049,2,5,40,2.4,0.1,1.0,90,1e-4,1e-5,1e-12,1,1.6,1.5",
            "ex9,gradvi,p1,iterative,257,131072,66049,2,5,40,1.5,0.1,0.6,95,1e-4,1e-5,1e-12,2,1.0,1.5",
            "ex9,gradvi,hmm,direct,257,65536,197120,2,5,0,1.0,0.1,0.5,120,1e-4,1e-5,1e-12,4,0.5,2.0",
            "ex9,gradvi,p1,direct,257,131072,66049,2,5,0,0.7,0.1,0.3,99,1e-4,1e-5,1e-12,0,,",
            "ex9,petsc,fd,gs+mg,513,0,263169,3,16,90,5.0,,,400,1e-5,1e-6,,2,2.5,2.0",
            "ex9,gradvi,p1,iterative,513,524288,263169,2,5,40,6.0,0.4,3.0,380,1e-5,1e-6,1e-12,1,4.0,1.5",
        ],
    )
}

fn table_lines(md: &Doc) -> Vec<String> {
    md.to_string()
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| G "))
        .map(str::to_string)
        .collect()
}

#[test]
fn pairs_only_equal_core_counts() {
    let rows = sample("pairs");
    assert!(petsc_at(&rows, 257, 1).is_some_and(|p| p.total_s == 2.0));
    assert!(petsc_at(&rows, 257, 2).is_some_and(|p| p.total_s == 1.6));
    assert!(petsc_at(&rows, 257, 4).is_none());
    assert!(petsc_at(&rows, 513, 1).is_none());
    // a row without a core count never pairs, not even with another such row
    assert_eq!(rows[5].cores, 0);
    assert!(ex9_row(&rows, ("gradvi", "p1", "direct"), 257, 0).is_none());
}

#[test]
fn ratios_r_and_speedups_in_the_tables() {
    let rows = sample("tables");
    let mut md = Doc::default();
    write(&mut md, &rows);
    let lines = table_lines(&md);
    let expected = [
        // by grid, scheme, linear solver, cores; no PETSc on 4 processes: no ratio
        "| 257 | 4 | hmm | direct | 1.00 | – | – | 120 | – | – | 2.00 | – | 2.54 | – |",
        // equal cores: time 2.4/2.0, memory 90/100, linear 1.6 s and 1.0 s over 66 049 unknowns
        "| 257 | 1 | p1 | iterative | 2.40 | 2.00 | 1.20 | 90 | 100 | 0.90 | 1.50 | 2.00 | 24.22 | 15.14 |",
        // 1.5/1.6 = 0.9375, 95/180 = 0.528, 0.8 s / 66 049 = 12.11 µs
        "| 257 | 2 | p1 | iterative | 1.50 | 1.60 | 0.94 | 95 | 180 | 0.53 | 1.50 | 2.00 | 15.14 | 12.11 |",
        // PETSc at 513 ran on 2 processes only
        "| 513 | 1 | p1 | iterative | 6.00 | – | – | 380 | – | – | 1.50 | – | 15.20 | – |",
        // speed-ups: PETSc 2.0/1.6, its linear variant 1.0/0.8; gradvi 2.4/1.5 and 1.6/1.0
        "| 257 | petsc | fd | gs+mg | 2 | 2.00 | 1.60 | 1.25 | 1.25 |",
        "| 257 | gradvi | hmm | direct | 4 | – | 1.00 | – | – |",
        "| 257 | gradvi | p1 | iterative | 2 | 2.40 | 1.50 | 1.60 | 1.60 |",
        "| 513 | petsc | fd | gs+mg | 2 | – | 5.00 | – | – |",
    ];
    assert_eq!(lines, expected, "{md}");
    assert_eq!(speedup(&rows, &rows[3]), Some(2.4 / 1.5));
    assert_eq!(speedup(&rows, &rows[2]), None);
}

#[test]
fn rows_before_the_core_column_read_and_give_no_equal_core_section() {
    let rows = rows_of(
        "old",
        "",
        &["ex9,gradvi,p1,iterative,257,131072,66049,2,5,40,2.4,0.1,1.0,90,1e-4,1e-5,1e-12"],
    );
    assert_eq!(rows[0].cores, 0);
    assert!(rows[0].linear_seconds.is_nan() && rows[0].r.is_nan());
    let mut md = Doc::default();
    write(&mut md, &rows);
    assert!(md.to_string().is_empty(), "{md}");
}

/// Target 3's line lists every run's ratio from the `pairs` column, and a row of one run or
/// written before the column lists none.
#[test]
fn the_cost_ratio_lists_every_runs_ratio() {
    let rows = rows_of(
        "pairs-column",
        ",cores,linear_seconds,r,runs,pairs",
        &[
            "ex9,gradvi,p1,iterative,1025,2097152,1050625,3,9,16,2.6,0.3,1.4,420,1e-5,1e-6,1e-12,1,2.1,1.25,3,2.0/1.6 3.0/2.0 2.6/2.2",
            "ex9,gradvi,p1,iterative,1025,2097152,1050625,3,9,16,2.6,0.3,1.4,420,1e-5,1e-6,1e-12,2,2.1,1.25,1,2.6/2.1",
        ],
    );
    assert_eq!(
        crate::bench::peers_targets::runs_ratios(&rows[0]),
        "; medians of 3 runs, R the median of their ratios 1.25, 1.50, 1.18"
    );
    assert_eq!(crate::bench::peers_targets::runs_ratios(&rows[1]), "");
    assert_eq!(
        crate::bench::peers_targets::runs_ratios(&sample("no-pairs")[2]),
        ""
    );
}
