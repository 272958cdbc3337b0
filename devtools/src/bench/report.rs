//! `BENCHMARKS.md` and `figures/bench.png`, written from `replication/results/bench.csv` only:
//! one function per section, and the figure as small multiples (one panel per scheme and mesh
//! family, a fixed colour and marker per variant).

use super::{BenchRow, C, CSV, Config, FIGURE, FIT_RANGE, P1_TARGET_MIN_CELLS, REPORT, bad};
use gradvi_cli::markdown::{Doc, NONE, Table, cells, fixed, list, met, seconds};
use gradvi_cli::plot::{LineOptions, LineSeries, Marker, data_range, palette, plot_panels};
use gradvi_cli::replication::records::read_csv;

/// The rows of one series (code, scheme, variant, family) in order of cells, and its name.
struct Series<'a> {
    name: String,
    rows: Vec<&'a BenchRow>,
}

fn series_key(r: &BenchRow) -> String {
    if r.code == "dolfinx" {
        format!("dolfinx P1 ({})", r.family)
    } else {
        let scheme = r.scheme.to_uppercase();
        format!("gradvi {scheme} {} ({})", r.variant, r.family)
    }
}

/// The series in order of first appearance in the CSV.
fn series(rows: &[BenchRow]) -> Vec<Series<'_>> {
    let mut out: Vec<Series> = Vec::new();
    for r in rows {
        let name = series_key(r);
        match out.iter_mut().find(|s| s.name == name) {
            Some(s) => s.rows.push(r),
            None => out.push(Series {
                name,
                rows: vec![r],
            }),
        }
    }
    for s in &mut out {
        s.rows.sort_by_key(|r| r.cells);
    }
    out
}

/// Writes `BENCHMARKS.md` and `bench.png` from `bench.csv` (nothing else is read).
pub fn write_report(cfg: &Config) -> gradvi::Result<()> {
    let rows: Vec<BenchRow> = read_csv(&cfg.path(CSV))?;
    if rows.is_empty() {
        return Err(bad(format!("{}: no rows", cfg.path(CSV).display())));
    }
    figure(cfg, &rows)?;
    let all = series(&rows);
    let gradvi: Vec<&Series> = all
        .iter()
        .filter(|s| s.name.starts_with("gradvi"))
        .collect();
    let mut md = Doc::default();
    intro(&mut md);
    super::peers_report::write(cfg, &mut md, &super::peers::read_rows(cfg)?)?;
    super::peers3d_report::write(&mut md, &super::peers3d::read_rows(cfg)?);
    super::hmm3d_report::write(&mut md, &super::hmm3d::read_rows(cfg)?);
    super::domains3d_report::write(&mut md, &super::domains3d::read_rows(cfg)?);
    md.section(
        2,
        "The scaling benchmark (Test 3 on the unit square, direct solver)",
        "The sections below measure the direct solver (sparse Cholesky) with the cold and nested starts and two levers, and compare with dolfinx.",
    );
    targets(&mut md, &rows, &gradvi);
    md.para("![total time against cells](figures/bench.png)");
    growth(&mut md, &all);
    against_dolfinx(&mut md, &rows);
    lever(
        &mut md,
        &rows,
        "nested-par",
        "Lever: threads of the numeric factorisation",
        "The nested variant with the default sequential factorisation (`FactorThreads::Sequential`) against the same run with faer's parallel one (`nested-par`, `FactorThreads::Global`); the assembly is parallel (rayon) in both.",
    );
    lever(
        &mut md,
        &rows,
        "nested-nd",
        "Lever: fill-reducing ordering",
        "The nested variant with the default AMD ordering against the same run with our nested dissection by level-set separators (`nested-nd`, `Ordering::NestedDissection`). Fill = stored values of the Cholesky factor.",
    );
    active_set_changes(&mut md, &all);
    let runs: std::collections::BTreeSet<u64> = rows.iter().map(|r| r.run).collect();
    if runs.len() > 1 {
        md.para(format!("The rows above come from {} benchmark runs (`GRADVI_BENCH_MERGE`; column `run` of the CSV, 0 for rows written before the column existed): timings of different runs are comparable only up to the load of the machine at the time.", runs.len()));
    }
    profile(&mut md, &gradvi);
    obstacles(&mut md, &gradvi);
    all_cases(&mut md, &rows);
    measurements(&mut md, cfg)?;
    md.write(&cfg.path(REPORT))
}

/// Where the measurements behind the defaults are kept, one markdown file per part of the code.
pub const MEASUREMENTS_DIR: &str = "replication/measurements";

/// The last section: every file of [`MEASUREMENTS_DIR`] (`*.md`, in the order of their names),
/// verbatim. Doc comments cite this section for the measurements behind a default.
fn measurements(md: &mut Doc, cfg: &Config) -> gradvi::Result<()> {
    let dir = cfg.path(MEASUREMENTS_DIR);
    let mut files: Vec<std::path::PathBuf> = match std::fs::read_dir(&dir) {
        Ok(entries) => entries
            .map(|e| e.map(|e| e.path()).map_err(|e| super::io_err(&dir, e)))
            .collect::<gradvi::Result<_>>()?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(super::io_err(&dir, e)),
    };
    files.retain(|f| f.extension().is_some_and(|e| e == "md"));
    files.sort();
    md.section(
        2,
        "Measurements behind the defaults",
        format!("The measurements that the code's documentation cites, from the files of `{MEASUREMENTS_DIR}/` as they are, in the order of their names."),
    );
    for f in &files {
        let text = std::fs::read_to_string(f).map_err(|e| super::io_err(f, e))?;
        md.para(text.trim_end());
    }
    Ok(())
}

/// Colour and marker of a variant, the same in every panel (dolfinx: black crosses).
fn variant_style(variant: &str) -> ([u8; 3], Marker) {
    match variant {
        "cold" => (palette(1), Marker::Circle),
        "nested" => (palette(0), Marker::Square),
        "nested-par" => (palette(2), Marker::Triangle),
        "nested-nd" => (palette(3), Marker::Diamond),
        _ => ([0, 0, 0], Marker::Cross),
    }
}

/// `bench.png`: total time against cells, one panel per gradvi scheme and mesh family with its
/// variants, the dolfinx P1 runs on the panels of their meshes, the target growth N^1.3 from the
/// fastest first point of the panel, and the same log axes everywhere.
fn figure(cfg: &Config, rows: &[BenchRow]) -> gradvi::Result<()> {
    let family_order = |f: &str| {
        ["gmsh", "hexagonal", "cartesian"]
            .iter()
            .position(|&x| x == f)
    };
    let mut panels: Vec<(&str, &str)> = (rows.iter().filter(|r| r.code == "gradvi"))
        .map(|r| (r.scheme.as_str(), r.family.as_str()))
        .collect();
    panels.sort_by_key(|&(scheme, family)| (family_order(family), family, scheme));
    panels.dedup();
    let x1 = rows.iter().map(|r| r.cells as f64).fold(0.0, f64::max);
    let mut charts = Vec::new();
    for (scheme, family) in panels {
        let on_panel = |r: &&BenchRow| {
            r.family == family && (r.scheme == scheme || r.code == "dolfinx") && r.total_s > 0.0
        };
        let mut series: Vec<LineSeries> = Vec::new();
        for variant in ["cold", "nested", "nested-par", "nested-nd", "snes-vi"] {
            let mut pts: Vec<[f64; 2]> = (rows.iter().filter(on_panel))
                .filter(|r| r.variant == variant)
                .map(|r| [r.cells as f64, r.total_s])
                .collect();
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            if pts.is_empty() {
                continue;
            }
            let (color, marker) = variant_style(variant);
            let label = if variant == "snes-vi" {
                "dolfinx P1"
            } else {
                variant
            };
            series.push(LineSeries {
                color: Some(color),
                marker,
                ..LineSeries::new(label, pts)
            });
        }
        let (a, t) = (series.iter().filter_map(|s| s.points.first()))
            .fold((f64::INFINITY, f64::INFINITY), |(a, t), p| {
                (a.min(p[0]), t.min(p[1]))
            });
        if x1 > a {
            series.push(LineSeries {
                color: Some([120, 120, 120]),
                marker: Marker::None,
                dashed: true,
                ..LineSeries::new("N^1.3 (target)", vec![[a, t], [x1, t * (x1 / a).powf(1.3)]])
            });
        }
        let opts = LineOptions::log_log(
            format!("{} on {family} meshes", scheme.to_uppercase()),
            "cells",
            "total time [s]",
        );
        charts.push((series, opts));
    }
    if charts.is_empty() {
        return Ok(());
    }
    // the same axes on every panel
    let every: Vec<LineSeries> = charts
        .iter()
        .flat_map(|c: &(Vec<LineSeries>, LineOptions)| c.0.clone())
        .collect();
    for (_, opts) in &mut charts {
        opts.x_range = Some(data_range(&every, 0, true));
        opts.y_range = Some(data_range(&every, 1, true));
    }
    let title = format!("Test 3 (C = {C}): total time against cells");
    let rows_of_panels = charts.len().div_ceil(2).max(1) as u32;
    let size = (1200, 80 + 460 * rows_of_panels);
    plot_panels(&cfg.path(FIGURE), &title, size, 2, &charts)
}

fn intro(md: &mut Doc) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    md.section(1, "Benchmarks: performance and scale", format!("Generated by `make bench` (`gradvi-dev bench`, `devtools/src/bench.rs`) from `replication/results/bench.csv`; every number below is read from that file. Test 3 of the paper (obstacle problem u ≥ ψ, f = C = {C}) on the unit square; {threads} hardware threads on the machine that wrote this report. `gradvi-dev bench --report-only` rewrites this page from the CSV."));
    md.para("The scaling benchmark below (`bench.csv`) measures the direct solver only (`LinearSolver::Direct`); the peer benchmark above compares it with the iterative one. Variants: **cold** is the monotony algorithm of `gradvi solve` and `solve_problem` from A₀ = ∅ (sparse Cholesky, AMD ordering, the symbolic factorisation built once); **nested** (`gradvi solve --warm-start nested`, `solver::warm_start`) starts the same algorithm from an active set predicted by coarse HMM solves of the same problem on meshes agglomerated from the fine one (`mesh::agglomerate`; the first with about 1/16 of the fine unknowns, each further one 16 times coarser), whose cost is included in the total; **nested-par** and **nested-nd** are the nested variant with faer's parallel factorisation and with a nested-dissection ordering (the levers below). dolfinx is P1 with PETSc SNES `vinewtonrsls` and LU (`reference/solve.py`); its time is its own `setup + solve` (mesh reading, assembly and the SNES loop; the Python start-up and JIT are excluded). gradvi's total includes mesh reading or generation.");
}

/// The gradvi row of `scheme` and `variant` on the mesh of the dolfinx row `d`.
fn same_mesh<'a>(
    rows: &'a [BenchRow],
    d: &BenchRow,
    scheme: &str,
    variant: &str,
) -> Option<&'a BenchRow> {
    rows.iter().find(|r| {
        r.code == "gradvi"
            && r.family == d.family
            && r.mesh == d.mesh
            && r.scheme == scheme
            && r.variant == variant
    })
}

/// Speed-ups dolfinx time / gradvi time with the cells, on the meshes of the dolfinx rows that
/// pass `keep`.
fn speed_ups(
    rows: &[BenchRow],
    scheme: &str,
    variant: &str,
    keep: impl Fn(&BenchRow) -> bool,
) -> Vec<(f64, usize)> {
    (rows.iter().filter(|d| d.code == "dolfinx" && keep(d)))
        .filter_map(|d| {
            same_mesh(rows, d, scheme, variant).map(|g| (d.total_s / g.total_s, d.cells))
        })
        .collect()
}

/// The targets of the benchmark, each with its measured value and verdict.
fn targets(md: &mut Doc, rows: &[BenchRow], gradvi: &[&Series]) {
    md.heading(2, "Targets");
    let mut t = Table::new("target | measured | verdict", "lll");
    for variant in ["cold", "nested"] {
        let largest = (rows.iter())
            .filter(|r| {
                r.code == "gradvi"
                    && r.scheme == "hmm"
                    && r.variant == variant
                    && r.family == "gmsh"
            })
            .max_by_key(|r| r.cells);
        if let Some(r) = largest.filter(|r| r.cells >= 500_000) {
            t.row(cells![
                format!("HMM ({variant}) on a 10⁶-cell mesh: < 30 s and < 4 GiB"),
                format!(
                    "{} cells: {} s, {:.0} MiB",
                    r.cells,
                    seconds(r.total_s),
                    r.peak_mib
                ),
                met(r.total_s < 30.0 && r.peak_mib < 4096.0)
            ]);
        }
    }
    let worst = |v: &[(f64, usize)]| v.iter().map(|b| b.0).fold(f64::INFINITY, f64::min);
    for variant in ["cold", "nested"] {
        // the mesh generated for 10⁵ cells has slightly fewer: count it in
        let big = speed_ups(rows, "p1", variant, |d| d.cells >= P1_TARGET_MIN_CELLS);
        if !big.is_empty() {
            t.row(cells![
                format!("gradvi-P1 ({variant}) ≥ 10× faster than dolfinx-P1 at ≥ 100k cells"),
                list(big.iter().map(|(s, n)| format!("{s:.1}× ({n} cells)"))),
                met(worst(&big) >= 10.0)
            ]);
        }
        let hmm = speed_ups(rows, "hmm", variant, |_| true);
        if !hmm.is_empty() {
            let best = hmm.iter().map(|b| b.0).fold(0.0, f64::max);
            t.row(cells![
                format!("gradvi-HMM ({variant}) faster than dolfinx-P1 at equal cells"),
                format!(
                    "speed-up from {:.2}× to {best:.2}× over {} meshes",
                    worst(&hmm),
                    hmm.len()
                ),
                met(worst(&hmm) > 1.0)
            ]);
        }
    }
    for s in gradvi {
        if let Some((p, lo, hi)) = growth_exponent(&s.rows) {
            t.row(cells![
                format!("{}: total time ≤ N^1.3 from 10⁴ to 10⁶ cells", s.name),
                format!("N^{p:.2} (fit over {lo}–{hi} cells)"),
                met(p <= 1.3)
            ]);
        }
    }
    md.table(&t);
}

/// The rows with cells in [`FIT_RANGE`].
fn in_fit_range<'a>(rows: &[&'a BenchRow]) -> Vec<&'a BenchRow> {
    (rows.iter().copied())
        .filter(|r| r.cells >= FIT_RANGE.0 && r.cells <= FIT_RANGE.1)
        .collect()
}

/// Least-squares exponent of total time against cells over [`FIT_RANGE`], with the range
/// actually used; `None` with fewer than three points.
fn growth_exponent(rows: &[&BenchRow]) -> Option<(f64, usize, usize)> {
    let pts: Vec<&BenchRow> = in_fit_range(rows)
        .into_iter()
        .filter(|r| r.total_s > 0.0)
        .collect();
    let p = exponent(&pts, |r| r.total_s)?;
    let cells = pts.iter().map(|r| r.cells);
    Some((
        p,
        cells.clone().min().unwrap_or(0),
        cells.max().unwrap_or(0),
    ))
}

/// Least-squares exponent of `f(row)` against cells over [`FIT_RANGE`] (`None` with fewer
/// than three points).
fn exponent(rows: &[&BenchRow], f: impl Fn(&BenchRow) -> f64) -> Option<f64> {
    let (n, y): (Vec<f64>, Vec<f64>) = (in_fit_range(rows).into_iter())
        .map(|r| (r.cells as f64, f(r)))
        .filter(|p| p.1 > 0.0 && p.1.is_finite())
        .unzip();
    (n.len() >= 3).then(|| gradvi::post::fitted_slope(&n, &y))
}

/// The growth exponents of time, NITER, factorisation and memory of every series.
fn growth(md: &mut Doc, all: &[Series]) {
    md.section(2, "Growth exponents", format!("Least-squares slopes against ln(cells) (`post::fitted_slope`) of ln(total time), ln(NITER), ln(numeric factorisation time per iteration) and ln(peak memory), over the cases with {} to {} cells.", FIT_RANGE.0, FIT_RANGE.1));
    let mut t = Table::new(
        "series | points | total time | NITER | factorisation per iteration | peak memory",
        "llllll",
    );
    let show = |x: Option<f64>| x.map_or(NONE.to_string(), |p| format!("{p:.2}"));
    for s in all {
        t.row(cells![
            s.name,
            in_fit_range(&s.rows).len(),
            show(exponent(&s.rows, |r| r.total_s)),
            show(exponent(&s.rows, |r| r.niter as f64)),
            show(exponent(&s.rows, |r| r.factor_s / r.niter.max(1) as f64)),
            show(exponent(&s.rows, |r| r.peak_mib))
        ]);
    }
    md.table(&t);
}

/// gradvi's four (scheme, variant) pairs against dolfinx, mesh by mesh.
fn against_dolfinx(md: &mut Doc, rows: &[BenchRow]) {
    let dolf: Vec<&BenchRow> = rows.iter().filter(|r| r.code == "dolfinx").collect();
    if dolf.is_empty() {
        return;
    }
    md.section(
        2,
        "gradvi against dolfinx on the same gmsh meshes",
        "Speed-up = dolfinx time / gradvi time (> 1: gradvi is faster).",
    );
    let mut t = Table::new(
        "mesh | cells | dolfinx P1 [s] | SNES its | P1 cold [s] | speed-up | P1 nested [s] | speed-up | HMM cold [s] | speed-up | HMM nested [s] | speed-up",
        "llllllllllll",
    );
    for d in dolf {
        let mut row = cells![d.mesh, d.cells, seconds(d.total_s), d.niter];
        for (scheme, variant) in [
            ("p1", "cold"),
            ("p1", "nested"),
            ("hmm", "cold"),
            ("hmm", "nested"),
        ] {
            match same_mesh(rows, d, scheme, variant) {
                Some(g) => row.extend(cells![
                    seconds(g.total_s),
                    format!("{:.1}×", d.total_s / g.total_s)
                ]),
                None => row.extend(cells![NONE, NONE]),
            }
        }
        t.row(row);
    }
    md.table(&t);
}

/// A table comparing the `nested` rows with those of `variant` on the same meshes (a lever).
fn lever(md: &mut Doc, rows: &[BenchRow], variant: &str, title: &str, intro: &str) {
    let pairs: Vec<(&BenchRow, &BenchRow)> = (rows.iter())
        .filter(|r| r.code == "gradvi" && r.variant == "nested")
        .filter_map(|s| {
            let same = |p: &&BenchRow| {
                p.variant == variant
                    && p.family == s.family
                    && p.scheme == s.scheme
                    && p.cells == s.cells
            };
            rows.iter().find(same).map(|p| (s, p))
        })
        .collect();
    if pairs.is_empty() {
        return;
    }
    md.section(
        2,
        title,
        format!("{intro} Ratio = {variant} / nested (> 1: the default is faster)."),
    );
    let header = format!(
        "family | scheme | cells | fill nested | fill {variant} | factor/it nested [s] | factor/it {variant} [s] | ratio | total nested [s] | total {variant} [s]"
    );
    let mut t = Table::new(&header, "llllllllll");
    let per_it = |r: &BenchRow| r.factor_s / r.niter.max(1) as f64;
    let fill = |r: &BenchRow| {
        if r.factor_len > 0 {
            r.factor_len.to_string()
        } else {
            NONE.into()
        }
    };
    for (d, v) in &pairs {
        t.row(cells![
            d.family,
            d.scheme,
            d.cells,
            fill(d),
            fill(v),
            seconds(per_it(d)),
            seconds(per_it(v)),
            format!("{:.2}", per_it(v) / per_it(d)),
            seconds(d.total_s),
            seconds(v.total_s)
        ]);
    }
    md.table(&t);
    let faster = pairs.iter().filter(|(d, v)| per_it(d) < per_it(v)).count();
    md.para(format!(
        "The default factorisation is the faster one on {faster} of the {} cases.",
        pairs.len()
    ));
}

/// The sizes of the active-set changes per solve of the largest case of each series.
fn active_set_changes(md: &mut Doc, all: &[Series]) {
    // the levers nested-par and nested-nd follow the iterates of nested exactly
    let shown = |r: &&&BenchRow| {
        r.code == "gradvi"
            && !r.changes.is_empty()
            && (r.variant == "cold" || r.variant == "nested")
    };
    let mut largest: Vec<(&str, &BenchRow)> = (all.iter())
        .filter_map(|s| {
            Some((
                s.name.as_str(),
                *s.rows.iter().filter(shown).max_by_key(|r| r.cells)?,
            ))
        })
        .collect();
    if largest.is_empty() {
        return;
    }
    largest.sort_by_key(|(name, _)| *name);
    md.section(2, "Size of the active-set changes", "For the largest case of each series: the unknowns that entered and left the active set before each fine solve (`+entered/-left`; the first solve of the nested variant starts from the prediction, the cold one from the empty set; `nested-par` and `nested-nd` follow the iterates of `nested`). Long lists show their first six and last three steps.");
    let mut t = Table::new("series | cells | NITER | changes", "llll");
    for (name, r) in largest {
        let steps: Vec<&str> = r.changes.split(' ').collect();
        let changes = if steps.len() > 9 {
            format!(
                "{} … {}",
                steps[..6].join(" "),
                steps[steps.len() - 3..].join(" ")
            )
        } else {
            steps.join(" ")
        };
        t.row(cells![name, r.cells, r.niter, changes]);
    }
    md.table(&t);
}

/// The share of each phase in the total of the largest case of each gradvi series.
fn profile(md: &mut Doc, gradvi: &[&Series]) {
    md.section(2, "Where the time goes", "Share of the total of each phase for the largest case of each gradvi series (factor = numeric Cholesky, all iterations; assemble = condensation and scatter; solve = triangular solves and recovery of the cell unknowns; other = the active-set loop's residuals and certificates; coarse = the coarse solves of the nested variant).");
    let mut t = Table::new(
        "series | cells | NITER | total [s] | mesh | setup | symbolic | coarse | assemble | factor | solve | other",
        "llllllllllll",
    );
    for s in gradvi {
        let Some(r) = s.rows.last() else { continue };
        let mut row = cells![s.name, r.cells, r.niter, seconds(r.total_s)];
        let phases = [
            r.mesh_s,
            r.setup_s,
            r.symbolic_s,
            r.coarse_s,
            r.assemble_s,
            r.factor_s,
            r.solve_s,
            r.other_s,
        ];
        row.extend(phases.map(|x| format!("{:.0}%", 100.0 * x / r.total_s)));
        t.row(row);
    }
    md.table(&t);
}

/// For the largest case of each gradvi series: the linear solves against everything else.
fn obstacles(md: &mut Doc, gradvi: &[&Series]) {
    md.section(2, "What stands in the way", "For the largest case of each gradvi series: the linear solves (NITER of them, plus the coarse ones of the nested variant) against everything else.");
    let mut items = Vec::new();
    for s in gradvi {
        let Some(r) = s.rows.last() else { continue };
        let it = r.niter.max(1) as f64;
        let per_it = (r.assemble_s + r.factor_s + r.solve_s + r.other_s) / it;
        items.push(format!(
            "- {}, {} cells: NITER = {}; numeric factorisations {} s ({:.0}% of the {} s total), {} s each; one whole active-set step (assembly, factorisation, solves, residuals and certificate) {} s; setup, symbolic analysis, mesh and coarse solves {} s; peak {:.0} MiB.",
            s.name,
            r.cells,
            r.niter,
            seconds(r.factor_s),
            100.0 * r.factor_s / r.total_s,
            seconds(r.total_s),
            seconds(r.factor_s / it),
            seconds(per_it),
            seconds(r.total_s - per_it * it),
            r.peak_mib
        ));
    }
    md.para(items.join("\n"));
    md.para("The cold iteration puts every violated unknown in the active set at once and then frees one layer of cells along the free boundary per solve, so NITER grows like the number of cell layers between the first contact zone and the final one, ∝ 1/h ∝ N^½ (NITER exponents above). Every solve needs one numeric factorisation, whose cost per iteration grows at least linearly in N (factorisation exponents above, AMD fill). The cold total therefore grows like N raised to the sum of the two exponents whatever the constant factors of the linear algebra, and the growth target can only be met by bounding NITER: the nested variant does it with coarse solves, whose cost is a fraction of the fine one. Reusing a factorisation across active sets (the factor of an earlier active set as a preconditioner of conjugate gradients) would replace one factorisation by several triangular solves per step while each step changes hundreds to thousands of unknowns; the per-iteration `solve` column (one pair of triangular solves and the recovery of the cell unknowns) against the `factor/it` column gives the break-even number of such iterations.");
}

/// Every row, one table per mesh family.
fn all_cases(md: &mut Doc, rows: &[BenchRow]) {
    md.section(2, "All cases", "Times in seconds; per-iteration columns are divided by NITER (the fine iteration); `coarse` lists the coarse solves of the nested variant as linear solves / seconds. dolfinx: setup = everything before SNES (mesh reading included), solve = SNES.");
    let header = "cells | code | scheme | variant | unknowns | condensed | NITER | coarse | mesh | setup | symbolic | assemble/it | factor/it | solve/it | other | total | peak MiB | certificate";
    for family in ["gmsh", "hexagonal", "cartesian"] {
        let mut fr: Vec<&BenchRow> = rows.iter().filter(|r| r.family == family).collect();
        if fr.is_empty() {
            continue;
        }
        fr.sort_by(|a, b| {
            (a.cells, &a.code, &a.scheme, &a.variant)
                .cmp(&(b.cells, &b.code, &b.scheme, &b.variant))
        });
        md.heading(3, family);
        let mut t = Table::new(header, &"l".repeat(18));
        for r in fr {
            let it = r.niter.max(1) as f64;
            let coarse = if r.coarse_niter > 0 {
                format!("{} / {}", r.coarse_niter, seconds(r.coarse_s))
            } else {
                NONE.into()
            };
            let cert = if r.certificate.is_finite() {
                format!("{:.0e}", r.certificate)
            } else {
                NONE.into()
            };
            t.row(cells![
                r.cells,
                r.code,
                r.scheme,
                r.variant,
                r.unknowns,
                r.condensed,
                r.niter,
                coarse,
                seconds(r.mesh_s),
                seconds(r.setup_s),
                seconds(r.symbolic_s),
                seconds(r.assemble_s / it),
                seconds(r.factor_s / it),
                seconds(r.solve_s / it),
                seconds(r.other_s),
                seconds(r.total_s),
                fixed(r.peak_mib, 0),
                cert
            ]);
        }
        md.table(&t);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_measurements_section_holds_every_markdown_file_verbatim_in_name_order() {
        let root = std::env::temp_dir().join(format!("gradvi-measurements-{}", std::process::id()));
        let dir = root.join(MEASUREMENTS_DIR);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("b.md"), "# B\n\nsecond, 1.5 s on abc1234\n").unwrap();
        std::fs::write(
            dir.join("a.md"),
            "# A\n\n| x | y |\n|---|---|\n| 1 | 2 |\n\n",
        )
        .unwrap();
        std::fs::write(dir.join("notes.txt"), "not markdown").unwrap();
        let cfg = Config {
            root: root.clone(),
            max_cells: 0,
            dolfinx_max_cells: 0,
            variants: Vec::new(),
            python: std::path::PathBuf::from("/nonexistent"),
        };
        let mut md = Doc::default();
        md.para("before");
        measurements(&mut md, &cfg).unwrap();
        let out = root.join("out.md");
        md.write(&out).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let section = text.find("## Measurements behind the defaults").unwrap();
        let (a, b) = (text.find("# A\n").unwrap(), text.find("# B\n").unwrap());
        assert!(section < a && a < b, "{text}");
        assert!(
            text.contains("# A\n\n| x | y |\n|---|---|\n| 1 | 2 |\n\n# B"),
            "{text}"
        );
        assert!(text.ends_with("second, 1.5 s on abc1234\n"), "{text}");
        assert!(!text.contains("not markdown"));
        std::fs::remove_dir_all(&root).ok();
    }
}
