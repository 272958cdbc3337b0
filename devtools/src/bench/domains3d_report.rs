//! The 3D "any domain" section of `BENCHMARKS.md`, written from
//! `replication/results/bench_domains3d.csv` only ([`super::domains3d`]): every row, the fitted
//! growth of the time per domain, scheme and core count, and the 3D verdicts of target 6 of the
//! performance issue (NITER ≤ [`NITER_MAX`] at every size, time growing no faster than
//! N^[`GROWTH_MAX`] from 10⁴ to 10⁶ cells, across the direct/iterative switch).
//!
//! The growth exponent of a (domain, scheme, cores) series is the least-squares slope of
//! log(total time) against log(cells) over its solved rows with cells in
//! [`super::FIT_RANGE`] (10⁴ to 10⁶ with slack), whichever linear solver `auto` chose for each.
//! A series with fewer than two such rows has no exponent (the Voronoi family, whose largest
//! mesh has 4 913 cells, has none: its rows count for NITER only).

use super::domains3d::Domain3Row;
use gradvi_cli::markdown::{Doc, NONE, Table, cells, fixed, met, seconds};

/// Target of NITER at every size.
pub const NITER_MAX: usize = 10;
/// Target of the growth exponent of the total time against the cells.
pub const GROWTH_MAX: f64 = 1.15;

/// The solved rows of `domain`, `scheme` and `cores`, by cells.
fn series<'a>(
    rows: &'a [Domain3Row],
    domain: &str,
    scheme: &str,
    cores: usize,
) -> Vec<&'a Domain3Row> {
    let mut s: Vec<&Domain3Row> = rows
        .iter()
        .filter(|r| r.ok() && r.domain == domain && r.scheme == scheme && r.cores == cores)
        .collect();
    s.sort_by_key(|r| r.cells);
    s
}

/// The growth exponent of a series (see the module docs) and the number of rows it is fitted on.
pub fn growth(series: &[&Domain3Row]) -> (Option<f64>, usize) {
    let (lo, hi) = super::FIT_RANGE;
    let pts: Vec<(f64, f64)> = series
        .iter()
        .filter(|r| (lo..=hi).contains(&r.cells))
        .map(|r| (r.cells as f64, r.total_s))
        .collect();
    (super::peers_report::slope(&pts), pts.len())
}

/// The distinct values of `key` over `rows`, in order of first appearance.
fn distinct<T: PartialEq + Clone>(rows: &[Domain3Row], key: impl Fn(&Domain3Row) -> T) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for r in rows {
        let k = key(r);
        if !out.contains(&k) {
            out.push(k);
        }
    }
    out
}

/// An error in scientific notation ([`NONE`] for NaN).
fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3e}")
    } else {
        NONE.into()
    }
}

/// Writes the section into `md` ("not run" without rows).
pub fn write(md: &mut Doc, rows: &[Domain3Row]) {
    md.section(
        2,
        "3D any domain: ball, cube with a hole, gmsh cube, Voronoi cells",
        "The 3D radial obstacle problem (`problems/ex9-3d.toml`: −Δu = 0, u ≥ ψ, Dirichlet data from the exact solution, which holds on any domain containing the contact ball r ≤ 1/√2) on unstructured gmsh tetrahedra of `benches/domains3d/*.geo` — the ball of radius 2, the cube (−2,2)³ with a spherical hole (centre (1.1, 1.1, 1.1), radius 0.4), the cube (−2,2)³ — and on HArDCore3D's Voronoi family (`Voro-small-0`, polyhedral cells of the unit cube mapped onto (−2,2)³; HMM only, P1 needs tetrahedra). gradvi with the defaults of `gradvi solve`: linear solver `auto` (the column says which it chose), nested warm start; 1 and N rayon threads. Time is the child process's wall clock (mesh reading, solve, errors, freeing), memory its peak resident set; gmsh's meshing time is apart. Errors against the exact solution: P1 at the vertices, HMM at the cell centres (max and mean). Growth: the least-squares exponent of time against cells of the row's domain, scheme and core count over its rows from 10⁴ to 10⁶ cells (shown on its last row). Each row is a single run.",
    );
    if rows.is_empty() {
        md.para("*The 3D any-domain benchmark (`gradvi-dev bench --domains3d`, `make bench-domains3d`) has not been run: no `bench_domains3d.csv`.*");
        return;
    }
    let not_run: Vec<&Domain3Row> = rows
        .iter()
        .filter(|r| r.status.starts_with("not run"))
        .collect();
    for r in &not_run {
        md.para(format!("*{}: {}.*", r.domain, r.status));
    }
    let run: Vec<Domain3Row> = rows
        .iter()
        .filter(|r| !r.status.starts_with("not run"))
        .cloned()
        .collect();
    voronoi_note(md, &run);
    warm_start_note(md, &run);
    table(md, &run);
    targets(md, &run);
}

/// How far the Voronoi family goes against the target's range.
fn voronoi_note(md: &mut Doc, rows: &[Domain3Row]) {
    if let Some(big) = rows
        .iter()
        .filter(|r| r.domain == "voronoi" && r.ok())
        .max_by_key(|r| r.cells)
    {
        md.para(format!(
            "The Voronoi family's largest mesh ({}) has {} cells, below the target's 10⁴ to 10⁶: its rows count for the NITER verdict, not for the growth exponent.",
            big.mesh, big.cells
        ));
    }
}

/// How many solved rows ran without the nested warm start (no coarse solve), and why.
fn warm_start_note(md: &mut Doc, rows: &[Domain3Row]) {
    let solved: Vec<&Domain3Row> = rows.iter().filter(|r| r.ok()).collect();
    let skipped: Vec<&&Domain3Row> = solved
        .iter()
        .filter(|r| !r.warm_skipped.is_empty())
        .collect();
    if skipped.is_empty() {
        return;
    }
    // reasons that differ only by a number (a cell count) are one reason
    let mut reasons: Vec<(String, usize)> = Vec::new();
    for r in &skipped {
        let mut why = String::new();
        for c in r.warm_skipped.chars() {
            match (c.is_ascii_digit(), why.ends_with('N')) {
                (true, true) => {}
                (true, false) => why.push('N'),
                _ => why.push(c),
            }
        }
        match reasons.iter_mut().find(|(w, _)| *w == why) {
            Some((_, n)) => *n += 1,
            None => reasons.push((why, 1)),
        }
    }
    let list: Vec<String> = reasons
        .iter()
        .map(|(w, n)| format!("'{w}' ({n})"))
        .collect();
    md.para(format!(
        "The nested warm start was skipped (the iteration started cold) in {} of the {} solved rows: {}.",
        skipped.len(),
        solved.len(),
        list.join("; ")
    ));
}

/// Every row, grouped by domain, scheme and cores, with the growth of each group.
fn table(md: &mut Doc, rows: &[Domain3Row]) {
    let mut t = Table::new(
        "domain | mesh | scheme | cores | cells | unknowns | solver | NITER (+coarse) | Krylov | gmsh [s] | time [s] | peak [MiB] | max error | mean error | growth | status",
        "lllrrrlrrrrrrrrl",
    );
    for domain in distinct(rows, |r| r.domain.clone()) {
        for scheme in ["hmm", "p1"] {
            for cores in distinct(rows, |r| r.cores) {
                let mut d: Vec<&Domain3Row> = rows
                    .iter()
                    .filter(|r| r.domain == domain && r.scheme == scheme && r.cores == cores)
                    .collect();
                d.sort_by_key(|r| (r.cells, r.mesh.clone()));
                let (g, _) = growth(&series(rows, &domain, scheme, cores));
                let g = g.map_or(NONE.to_string(), |s| format!("N^{s:.2}"));
                for (i, r) in d.iter().enumerate() {
                    t.row(cells![
                        r.domain,
                        r.mesh,
                        r.scheme,
                        r.cores,
                        r.cells,
                        r.unknowns,
                        if r.linear.is_empty() {
                            NONE
                        } else {
                            r.linear.as_str()
                        },
                        format!("{} (+{})", r.niter, r.coarse_niter),
                        r.krylov,
                        seconds(r.gmsh_s),
                        seconds(r.total_s),
                        fixed(r.peak_mib, 0),
                        sci(r.err_max),
                        sci(r.err_mean),
                        if i + 1 == d.len() {
                            g.clone()
                        } else {
                            String::new()
                        },
                        r.status
                    ]);
                }
            }
        }
    }
    md.table(&t);
}

/// The verdicts of target 6 in 3D, per scheme and core count.
fn targets(md: &mut Doc, rows: &[Domain3Row]) {
    md.section(
        3,
        "3D any-domain targets of the performance issue",
        "Target 6 in 3D, computed from the rows above: NITER ≤ 10 on every mesh, and the steepest growth exponent over the domains at most 1.15; a failed case fails its verdict.",
    );
    let mut t = Table::new("target | measured | verdict", "llr");
    let mut cores = distinct(rows, |r| r.cores);
    cores.sort_unstable();
    for scheme in ["hmm", "p1"] {
        for &n in &cores {
            let of: Vec<&Domain3Row> = rows
                .iter()
                .filter(|r| r.scheme == scheme && r.cores == n)
                .collect();
            if of.is_empty() {
                continue;
            }
            t.row(verdict(rows, &of, scheme, n));
        }
    }
    md.table(&t);
}

/// The target row of `scheme` on `n` cores, from its rows `of` (all rows in `rows`).
fn verdict(rows: &[Domain3Row], of: &[&Domain3Row], scheme: &str, n: usize) -> Vec<String> {
    let what = format!(
        "3D any domain, {}, {n} core{}: NITER ≤ {NITER_MAX} at every size, time ≤ N^{GROWTH_MAX} from 10⁴ to 10⁶ cells",
        scheme.to_uppercase(),
        if n == 1 { "" } else { "s" }
    );
    let failed: Vec<&&Domain3Row> = of.iter().filter(|r| !r.ok()).collect();
    let worst_niter = of.iter().filter(|r| r.ok()).max_by_key(|r| r.niter);
    let mut steepest: Option<(f64, String, usize)> = None;
    for domain in distinct(rows, |r| r.domain.clone()) {
        if let (Some(s), k) = growth(&series(rows, &domain, scheme, n))
            && steepest.as_ref().is_none_or(|w| s > w.0)
        {
            steepest = Some((s, domain, k));
        }
    }
    let (Some(w), Some((s, domain, k))) = (worst_niter, &steepest) else {
        return cells![what, format!("not run ({} failed)", failed.len()), NONE];
    };
    let mut measured = format!(
        "NITER ≤ {} ({} {}, {} cells); steepest growth N^{s:.2} ({domain}, {k} sizes, {} to {} cells)",
        w.niter,
        w.domain,
        w.mesh,
        w.cells,
        series(rows, domain, scheme, n)
            .first()
            .map_or(0, |r| r.cells),
        series(rows, domain, scheme, n)
            .last()
            .map_or(0, |r| r.cells),
    );
    if !failed.is_empty() {
        let names: Vec<String> = failed
            .iter()
            .map(|r| format!("{} {}", r.domain, r.mesh))
            .collect();
        measured += &format!("; failed: {}", names.join(", "));
    }
    let ok = failed.is_empty() && w.niter <= NITER_MAX && *s <= GROWTH_MAX;
    cells![what, measured, met(ok)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A solved row of `domain`/`scheme` on one core with `cells` cells, `total_s` seconds and
    /// `niter` fine solves.
    fn row(domain: &str, scheme: &str, cells: usize, total_s: f64, niter: usize) -> Domain3Row {
        Domain3Row {
            domain: domain.into(),
            mesh: format!("{domain}3d_{cells}"),
            scheme: scheme.into(),
            linear: "iterative".into(),
            cores: 1,
            cells,
            unknowns: 3 * cells,
            niter,
            coarse_niter: 0,
            krylov: 50,
            gmsh_s: 1.0,
            mesh_s: 0.1,
            coarse_s: 0.0,
            solve_s: total_s - 0.2,
            total_s,
            peak_mib: 100.0,
            err_max: 1e-3,
            err_mean: 1e-4,
            certificate: 1e-12,
            warm_skipped: String::new(),
            status: "ok".into(),
        }
    }

    /// The verdict cell of the target row that starts with `what`.
    fn verdict_of(text: &str, what: &str) -> String {
        let line = text.lines().find(|l| l.starts_with(what)).unwrap();
        line.rsplit('|').nth(1).unwrap().trim().to_string()
    }

    #[test]
    fn growth_is_fitted_from_ten_thousand_cells_and_judged() {
        // ball: time ∝ N (exponent 1); cube: time ∝ N^1.5; a Voronoi mesh below the range
        let mut rows = vec![
            row("ball", "hmm", 10_000, 1.0, 5),
            row("ball", "hmm", 100_000, 10.0, 6),
            row("cube", "p1", 10_000, 1.0, 4),
            row("cube", "p1", 1_000_000, 1000.0, 4),
            row("voronoi", "hmm", 4_913, 50.0, 5),
        ];
        rows[0].warm_skipped = "the mesh (10000 cells) is too coarse".into();
        rows[1].warm_skipped = "the mesh (100000 cells) is too coarse".into();
        let (g, k) = growth(&series(&rows, "ball", "hmm", 1));
        assert_eq!(k, 2);
        assert!((g.unwrap() - 1.0).abs() < 1e-12);
        // the Voronoi row is outside the fitted range: no exponent
        assert_eq!(growth(&series(&rows, "voronoi", "hmm", 1)), (None, 0));
        let mut md = Doc::default();
        write(&mut md, &rows);
        let text = md.to_string();
        assert_eq!(verdict_of(&text, "| 3D any domain, HMM, 1 core"), "**met**");
        assert_eq!(
            verdict_of(&text, "| 3D any domain, P1, 1 core"),
            "**not met**"
        );
        assert!(text.contains("N^1.50") && text.contains("voro") && text.contains("4913 cells"));
        assert!(text.contains("skipped (the iteration started cold) in 2 of the 5 solved rows: 'the mesh (N cells) is too coarse' (2)"), "{text}");
        // NITER above 10 fails the verdict, and so does a failed case
        rows[1].niter = 11;
        let mut md = Doc::default();
        write(&mut md, &rows);
        assert_eq!(
            verdict_of(&md.to_string(), "| 3D any domain, HMM, 1 core"),
            "**not met**"
        );
        rows[1].niter = 6;
        rows.push(Domain3Row {
            status: "failed: out of memory".into(),
            ..row("ball", "hmm", 1_000_000, f64::NAN, 0)
        });
        let mut md = Doc::default();
        write(&mut md, &rows);
        let text = md.to_string();
        assert_eq!(
            verdict_of(&text, "| 3D any domain, HMM, 1 core"),
            "**not met**"
        );
        assert!(text.contains("failed: ball ball3d_1000000"), "{text}");
    }

    #[test]
    fn a_missing_family_is_said_not_run() {
        let mut md = Doc::default();
        write(&mut md, &[]);
        assert!(md.to_string().contains("has not been run"));
        let missing = Domain3Row {
            domain: "voronoi".into(),
            status: "not run: ../shared/meshes/hardcore3d/Voro-small-0 missing".into(),
            ..row("voronoi", "hmm", 0, f64::NAN, 0)
        };
        let mut md = Doc::default();
        write(&mut md, &[missing, row("ball", "p1", 10_000, 1.0, 3)]);
        let text = md.to_string();
        assert!(
            text.contains("*voronoi: not run: ../shared/meshes/hardcore3d/Voro-small-0 missing.*")
        );
        // the missing family is no row of the table
        assert!(!text.lines().any(|l| l.starts_with("| voronoi")), "{text}");
    }
}
