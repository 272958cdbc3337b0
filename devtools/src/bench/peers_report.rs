//! The first sections of `BENCHMARKS.md` and `figures/bench_peers.png`, written from
//! `replication/results/bench_peers.csv` only ([`super::peers`]): ex9 at equal cores
//! ([`super::peers_cores`]), PETSc's ex9 side by side, the targets of the performance issue,
//! and the "any domain" family.

use super::Config;
use super::peers::PeerRow;
use super::peers_cores::{linear_us_per_unknown, petsc_at};
use gradvi_cli::markdown::{Doc, NONE, Table, cells, fixed, met, seconds};
use gradvi_cli::plot::{LineOptions, LineSeries, Marker, data_range, plot_panels};

/// The figure of this part.
pub const FIGURE: &str = "replication/figures/bench_peers.png";

/// Target of the growth of the total time with the cells on the any-domain family (the
/// performance issue: N^1.15 across the direct/iterative switch).
const DOMAIN_GROWTH_MAX: f64 = 1.15;

/// Least-squares slope of log y against log x.
pub(super) fn slope(pts: &[(f64, f64)]) -> Option<f64> {
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = pts.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The core counts of the ex9 rows (0 for rows without one), in increasing order.
fn ex9_cores(rows: &[PeerRow]) -> Vec<usize> {
    let mut c: Vec<usize> = rows
        .iter()
        .filter(|r| r.family == "ex9")
        .map(|r| r.cores)
        .collect();
    c.sort_unstable();
    c.dedup();
    c
}

/// A core count for a table (0, not recorded, as [`NONE`]).
fn cores_cell(cores: usize) -> String {
    if cores == 0 {
        NONE.into()
    } else {
        cores.to_string()
    }
}

/// Writes the sections into `md` and the figure (nothing when there are no rows).
pub fn write(cfg: &Config, md: &mut Doc, rows: &[PeerRow]) -> gradvi::Result<()> {
    if rows.is_empty() {
        md.para(
            "*The peer benchmark (`gradvi-dev bench --peers`) has not been run: no `bench_peers.csv`.*",
        );
        return Ok(());
    }
    super::peers_cores::write(md, rows);
    ex9_section(md, rows);
    targets(cfg, md, rows);
    profile(md, rows);
    md.para("![ex9 against PETSc and the any-domain family](figures/bench_peers.png)");
    domains_section(md, rows);
    figure(cfg, rows)
}

fn ex9_section(md: &mut Doc, rows: &[PeerRow]) {
    md.section(
        2,
        "PETSc's obstacle example (ex9) side by side",
        "Bueler's radial obstacle problem (`problems/ex9.toml`), solved in one run by PETSc's `snes/tutorials/ex9.c` (Debian's PETSc, built by `benches/petsc/build.sh`, run by `benches/petsc/run_ex9.sh` with `-snes_grid_sequence K -pc_type mg` from a 5 × 5 grid: Newton RSLS with grid sequencing and geometric multigrid, GMRES at relative tolerance 1e-5 inside Newton at 1e-8) and by gradvi with its defaults (nested start on agglomerated coarse meshes; linear solver as the column says). P1 runs on the G × G grid's squares cut into triangles, the same five-point discrete problem as ex9 with the same G² unknowns (boundary included); HMM on the (G − 1)² squares. Errors against the exact solution are computed as ex9 does: max and mean over all nodes (P1, PETSc) or cell centres (HMM). Time is wall clock: for gradvi from the start of the mesh to the certified solution, its errors computed and everything freed (the benchmark's own timing of the data evaluation, below, taken out); for PETSc the whole process, whose finalisation also frees everything; memory is the peak resident set. NITER: gradvi's fine solves (+ coarse solves), PETSc's Newton steps on the finest grid (+ on the coarser grids); Krylov: CG (gradvi) or GMRES (PETSc) iterations in all. Cores: gradvi's rayon threads, PETSc's MPI processes (– in rows measured before the core count was recorded, when gradvi ran on every core and PETSc on one process); the ratios to PETSc are taken at equal cores only. R: the cost ratio (obstacle solve over its linear variant, previous section), with the linear variant's time per unknown.",
    );
    md.para(runs_note(rows.iter().filter(|r| r.family == "ex9")));
    let mut t = Table::new(
        "G | cores | code | scheme | linear | unknowns | time [s] | peak [MiB] | NITER (+coarse) | Krylov | max error | mean error | time / PETSc | memory / PETSc | R | linear [µs/unknown]",
        "rrlllrrrrrrrrrrr",
    );
    let mut grids: Vec<usize> = rows
        .iter()
        .filter(|r| r.family == "ex9")
        .map(|r| r.grid)
        .collect();
    grids.sort_unstable();
    grids.dedup();
    for g in grids {
        let mut at_g: Vec<&PeerRow> = rows
            .iter()
            .filter(|r| r.family == "ex9" && r.grid == g)
            .collect();
        at_g.sort_by_key(|r| r.cores);
        for r in at_g {
            let petsc = petsc_at(rows, g, r.cores);
            let ratio = |f: fn(&PeerRow) -> f64| match petsc {
                Some(p) if r.code != "petsc" => fixed(f(r) / f(p), 2),
                _ => NONE.into(),
            };
            t.row(cells![
                g,
                cores_cell(r.cores),
                r.code,
                r.scheme,
                r.linear,
                r.unknowns,
                seconds(r.total_s),
                fixed(r.peak_mib, 0),
                format!("{} (+{})", r.niter, r.coarse_niter),
                r.krylov,
                format!("{:.4e}", r.err_max),
                format!("{:.4e}", r.err_mean),
                ratio(|r| r.total_s),
                ratio(|r| r.peak_mib),
                fixed(r.r, 2),
                fixed(linear_us_per_unknown(r), 2)
            ]);
        }
    }
    md.table(&t);
    md.para("P1 and PETSc solve the same discrete problem, so their errors must agree to the digits of the solver tolerances: the table shows it at every size. HMM is a different discretisation (cell unknowns at centroids), with errors of the same order. On these squares with a scalar diffusion HMM's local matrices are two-point (HMM is then the two-point flux scheme), so its solves, iterative and direct, run on the (G − 1)² cell unknowns, the faces eliminated (`assembly::two_point`; the direct ones since issue 34's direct cell solves, before which they solved for the faces); HMM on any other mesh solves for the faces.");
}

fn targets(cfg: &Config, md: &mut Doc, rows: &[PeerRow]) {
    md.section(2, "Targets of the performance issue", "Each verdict is computed from the rows of `bench_peers.csv`; 'not met' comes with the measured numbers. A run restricted by `GRADVI_BENCH_PEERS` (`ex9` or `domains`) redoes its part and keeps the other part's rows, so the ex9 rows and the any-domain rows may come from different runs (the commits of the CSV say which); the ratios to PETSc always come from one run.");
    let mut t = Table::new("target | measured | verdict", "llr");
    super::peers_targets::ex9_targets(&mut t, rows);
    domain_targets(&mut t, rows);
    data_target(&mut t, rows);
    if let Some(row) = super::baseline::target_row(cfg) {
        t.row(row.to_vec());
    }
    md.table(&t);
}

/// The any-domain targets, per scheme: NITER and the steepest growth of the total time over
/// the default solver's series (`auto`, on the seed-1 and the re-seeded meshes) — the issue's
/// growth "across the direct/iterative switch" — then over every series, the forced direct
/// and iterative solvers on the seed-1 meshes included: a stricter reading, reported beside
/// it, on which the forced direct series sits close to the bound (it never switches, and a
/// sparse Cholesky's cost grows faster than N on planar meshes: N^1.12–1.13 in one run,
/// N^1.22 in an earlier one, `replication/measurements/solver.md`).
fn domain_targets(t: &mut Table, rows: &[PeerRow]) {
    for scheme in ["hmm", "p1"] {
        let d: Vec<&PeerRow> = rows
            .iter()
            .filter(|r| r.family != "ex9" && r.scheme == scheme)
            .collect();
        if d.is_empty() {
            continue;
        }
        let all = domain_series();
        let auto: Vec<_> = all.iter().copied().filter(|s| s.2 == "auto").collect();
        for (series, what) in [
            (
                &auto,
                "seed 1 and re-seeded, the default solver across the direct/iterative switch",
            ),
            (
                &all,
                "seed 1 and re-seeded, every series: the forced direct and iterative solvers too",
            ),
        ] {
            let in_series = |r: &&&PeerRow| {
                series
                    .iter()
                    .any(|s| r.family == s.0 && r.mesh == s.1 && r.linear == s.2)
            };
            let max_niter = d.iter().filter(in_series).map(|r| r.niter).max();
            let Some(max_niter) = max_niter else {
                continue;
            };
            let (s, which) = steepest(&d, series).unwrap_or((f64::NAN, String::new()));
            t.row(cells![
                format!(
                    "any domain (2D, the gmsh L-shape, disk and hole, {what}), {}: NITER ≤ 10 at every size, total time ≤ N^{DOMAIN_GROWTH_MAX}",
                    scheme.to_uppercase()
                ),
                format!("NITER ≤ {max_niter}; steepest growth N^{s:.2} ({which})"),
                met(max_niter <= 10 && s <= DOMAIN_GROWTH_MAX)
            ]);
        }
    }
}

/// The steepest fitted growth exponent of the total time over the `series` of the rows `d`,
/// and which series it is.
fn steepest(d: &[&PeerRow], series: &[(&str, &str, &str)]) -> Option<(f64, String)> {
    let mut worst: Option<(f64, String)> = None;
    for &(fam, mesh, linear) in series {
        let pts: Vec<(f64, f64)> = d
            .iter()
            .filter(|r| r.family == fam && r.mesh == mesh && r.linear == linear)
            .map(|r| (r.cells as f64, r.total_s))
            .collect();
        if let Some(s) = slope(&pts)
            && worst.as_ref().is_none_or(|w| s > w.0)
        {
            worst = Some((s, format!("{fam} {} {linear}", mesh_label(mesh))));
        }
    }
    worst
}

/// The series of the any-domain part whose growth is fitted: (domain, `mesh` label, linear
/// solver) — both solvers on the meshes of `peers::DOMAIN_LC`, `auto` on the re-seeded ones.
fn domain_series() -> Vec<(&'static str, &'static str, &'static str)> {
    let mut out = Vec::new();
    for fam in super::peers::DOMAINS {
        for linear in ["direct", "iterative", "auto"] {
            out.push((fam, "", linear));
        }
        out.push((fam, super::peers::RESEED_LABEL, "auto"));
    }
    out
}

/// The meshes of a `mesh` label, for the report.
fn mesh_label(mesh: &str) -> &str {
    if mesh.is_empty() { "seed 1" } else { mesh }
}

/// The linear solver of a row, with the choice of `auto` (CG iterations: iterative).
fn linear_cell(r: &PeerRow) -> String {
    match (r.linear.as_str(), r.krylov) {
        ("auto", 0) => "auto: direct".into(),
        ("auto", _) => "auto: iterative".into(),
        (l, _) => l.into(),
    }
}

/// The data time of a gradvi row and what it is: the solve's own evaluations, replayed, where
/// measured (`data_used_s`), else the bound (`data_s`).
fn data_time(r: &PeerRow) -> (f64, &'static str) {
    if r.data_used_s.is_finite() {
        (r.data_used_s, "the solve's own evaluations, replayed")
    } else {
        (r.data_s, "an upper bound, see the profile")
    }
}

/// The data-evaluation share of the 10⁶-cell solves: the solve's own evaluations where the row
/// measured them, else the bound.
fn data_target(t: &mut Table, rows: &[PeerRow]) {
    let big: Vec<&PeerRow> = rows
        .iter()
        .filter(|r| r.code == "gradvi" && r.cells >= 1_000_000 && data_time(r).0.is_finite())
        .collect();
    let share = |r: &PeerRow| data_time(r).0 / r.total_s;
    if let Some(worst) = big.iter().max_by(|a, b| share(a).total_cmp(&share(b))) {
        let (data, what) = data_time(worst);
        let bounds = big.iter().filter(|r| !r.data_used_s.is_finite()).count();
        let note = if bounds == 0 {
            String::new()
        } else {
            format!("; {bounds} of {} rows with the bound only", big.len())
        };
        t.row(cells![
            "data evaluation (problem-file expressions) under 10% of a 10⁶-cell solve (problem-files issue)",
            format!(
                "at most {:.1}% ({} {} {}, {} cores, on {} cells: {} of {}; {what}{note})",
                100.0 * share(worst),
                worst.family,
                worst.scheme,
                worst.linear,
                worst.cores,
                worst.cells,
                seconds(data),
                seconds(worst.total_s)
            ),
            met(share(worst) < 0.10)
        ]);
    }
}

/// Where the time of the gradvi ex9 runs goes, and the data-evaluation share.
fn profile(md: &mut Doc, rows: &[PeerRow]) {
    md.section(
        2,
        "Profile of the ex9 runs",
        "Seconds per phase of gradvi's ex9 runs (the largest grids): mesh generation; setup (data, local matrices, pattern, symbolic factorisation); the nested start's coarse solves; assembly of the condensed systems; factorisation (direct) or multigrid setup (iterative); triangular solves or conjugate gradients (with the interior recovery); the rest (constraints, residuals, certificates, the look-aheads of the active set, errors, freeing the memory). Data bound: an upper bound of the time spent evaluating the problem's expressions (every datum at every centroid, edge midpoint and vertex, on the solve's threads (rows before 2026-12-06: on one thread); `problems/ex9.toml` is a problem file, so this is the cost of its parsed expressions), and its share of the total. Data used: the evaluations the solve itself made, its errors included (every call of every datum recorded in a second, untimed solve of the case, then evaluated again at the recorded points on the solve's threads and timed, `devtools/src/bench/data_replay.rs`; measured once per case, in its first run; – in rows before this column).",
    );
    let mut t = Table::new(
        "G | cores | scheme | linear | mesh | setup | coarse | assembly | factor / AMG setup | solve / CG | rest | total | data bound (share) | data used (share)",
        "rrllrrrrrrrrrr",
    );
    let mut ex9: Vec<&PeerRow> = rows
        .iter()
        .filter(|r| r.family == "ex9" && r.code == "gradvi" && r.grid >= 1025)
        .collect();
    ex9.sort_by_key(|r| (r.grid, r.scheme.clone(), r.linear.clone(), r.cores));
    for r in ex9 {
        let solve = r.linear_s - r.factor_s;
        let rest = r.total_s - r.mesh_s - r.setup_s - r.coarse_s - r.assemble_s - r.linear_s;
        t.row(cells![
            r.grid,
            cores_cell(r.cores),
            r.scheme,
            r.linear,
            seconds(r.mesh_s),
            seconds(r.setup_s),
            seconds(r.coarse_s),
            seconds(r.assemble_s),
            seconds(r.factor_s),
            seconds(solve),
            seconds(rest),
            seconds(r.total_s),
            share_cell(r.data_s, r.total_s),
            share_cell(r.data_used_s, r.total_s)
        ]);
    }
    md.table(&t);
}

/// Seconds and their share of `total`, or – for NaN.
fn share_cell(s: f64, total: f64) -> String {
    if s.is_finite() {
        format!("{} ({:.1}%)", seconds(s), 100.0 * s / total)
    } else {
        "–".into()
    }
}

/// How many runs each of `rows` took (`GRADVI_BENCH_PEER_REPEAT`), in a sentence.
fn runs_note<'a>(rows: impl Iterator<Item = &'a PeerRow>) -> String {
    let mut runs: Vec<usize> = rows.map(|r| r.runs).collect();
    runs.sort_unstable();
    runs.dedup();
    match runs.as_slice() {
        [] | [1] => "Each row is a single run of its case.".into(),
        [n] => format!(
            "Each row is the run with the median time of {n} runs of its case, interleaved with the other cases of its grid or mesh (`GRADVI_BENCH_PEER_REPEAT={n}`); its peak memory is the largest of the {n}."
        ),
        more => format!(
            "Each row is the run with the median time of its runs ({} to {} runs per case, `GRADVI_BENCH_PEER_REPEAT`), interleaved with the other cases of its grid or mesh; its peak memory is the largest of them.",
            more[0],
            more[more.len() - 1]
        ),
    }
}

fn domains_section(md: &mut Doc, rows: &[PeerRow]) {
    md.section(
        2,
        "Any domain: L-shape, disk, square with a hole",
        "The paper's Test 3 data (C = −5) on gmsh meshes of `benches/domains/*.geo`, with the default nested start (coarse HMM solves on meshes agglomerated from the user's mesh, `mesh::agglomerate`). On the meshes the benchmark was tuned on (mesh 'seed 1': gmsh's seed of the `.geo` files, four sizes) both linear solvers run, and the default one (`auto`, rows before 2026-12-07 without it); the same domains meshed again with another gmsh seed (`Mesh.RandomSeed`, with a larger `Mesh.RandomFactor`) at five other sizes run the default solver `auto`, whose choice the linear column shows (direct below 250 000 condensed unknowns, iterative above: the series crosses the switch). Growth: least-squares exponent of total time against cells over the sizes of the row's domain, meshes, scheme and solver.",
    );
    md.para(runs_note(rows.iter().filter(|r| r.family != "ex9")));
    let mut t = Table::new(
        "domain | mesh | scheme | linear | cells | unknowns | NITER (+coarse) | coarse [s] | linear [s] | total [s] | peak [MiB] | growth",
        "lllllrrrrrrr",
    );
    for (fam, mesh, linear) in domain_series() {
        for scheme in ["hmm", "p1"] {
            let mut d: Vec<&PeerRow> = rows
                .iter()
                .filter(|r| {
                    r.family == fam && r.mesh == mesh && r.scheme == scheme && r.linear == linear
                })
                .collect();
            d.sort_by_key(|r| r.cells);
            let pts: Vec<(f64, f64)> = d.iter().map(|r| (r.cells as f64, r.total_s)).collect();
            let g = slope(&pts).map_or(NONE.to_string(), |s| format!("N^{s:.2}"));
            for (i, r) in d.iter().enumerate() {
                t.row(cells![
                    fam,
                    mesh_label(mesh),
                    scheme,
                    linear_cell(r),
                    r.cells,
                    r.unknowns,
                    format!("{} (+{})", r.niter, r.coarse_niter),
                    seconds(r.coarse_s),
                    seconds(r.linear_s),
                    seconds(r.total_s),
                    fixed(r.peak_mib, 0),
                    if i + 1 == d.len() {
                        g.clone()
                    } else {
                        String::new()
                    }
                ]);
            }
        }
    }
    md.table(&t);
}

fn style(code: &str, linear: &str) -> ([u8; 3], Marker) {
    match (code, linear) {
        ("petsc", _) => ([0, 0, 0], Marker::Cross),
        (_, "direct") => ([31, 119, 180], Marker::Circle),
        (_, "auto") => ([44, 160, 44], Marker::Triangle),
        _ => ([214, 39, 40], Marker::Square),
    }
}

/// The ex9 series of `scheme` (and PETSc's): one per code, linear solver and core count, the
/// largest core count solid, the others dashed.
fn ex9_series(rows: &[PeerRow], scheme: &str) -> Vec<LineSeries> {
    let cores = ex9_cores(rows);
    let most = cores.last().copied().unwrap_or(0);
    let mut series = Vec::new();
    for (code, linear) in [
        ("petsc", "gs+mg"),
        ("gradvi", "direct"),
        ("gradvi", "iterative"),
    ] {
        for &n in &cores {
            let mut pts: Vec<[f64; 2]> = rows
                .iter()
                .filter(|r| {
                    r.family == "ex9"
                        && r.code == code
                        && r.linear == linear
                        && r.cores == n
                        && (code == "petsc" || r.scheme == scheme)
                })
                .map(|r| [r.unknowns as f64, r.total_s])
                .collect();
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            if pts.is_empty() {
                continue;
            }
            let (color, marker) = style(code, linear);
            let name = if code == "petsc" {
                "PETSc gs+mg".to_string()
            } else {
                format!("gradvi {linear}")
            };
            let label = match n {
                0 => name,
                1 => format!("{name}, 1 core"),
                n => format!("{name}, {n} cores"),
            };
            series.push(LineSeries {
                color: Some(color),
                marker,
                dashed: n != most,
                ..LineSeries::new(&label, pts)
            });
        }
    }
    series
}

fn figure(cfg: &Config, rows: &[PeerRow]) -> gradvi::Result<()> {
    let mut charts = Vec::new();
    for (scheme, title) in [
        ("p1", "ex9: P1 (same problem as PETSc)"),
        ("hmm", "ex9: HMM"),
    ] {
        let series = ex9_series(rows, scheme);
        if !series.is_empty() {
            charts.push((
                series,
                LineOptions::log_log(title, "unknowns", "total time [s]"),
            ));
        }
    }
    for scheme in ["hmm", "p1"] {
        let mut series = Vec::new();
        for (fam, mesh, linear) in domain_series() {
            let mut pts: Vec<[f64; 2]> = rows
                .iter()
                .filter(|r| {
                    r.family == fam && r.scheme == scheme && r.linear == linear && r.mesh == mesh
                })
                .map(|r| [r.cells as f64, r.total_s])
                .collect();
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            if pts.is_empty() {
                continue;
            }
            let (color, _) = style("gradvi", linear);
            let i = super::peers::DOMAINS.iter().position(|d| *d == fam);
            let marker = [Marker::Circle, Marker::Square, Marker::Triangle][i.unwrap_or(0) % 3];
            let label = if mesh.is_empty() {
                format!("{fam} {linear}")
            } else {
                format!("{fam} {linear} ({mesh})")
            };
            series.push(LineSeries {
                color: Some(color),
                marker,
                ..LineSeries::new(label, pts)
            });
        }
        if !series.is_empty() {
            charts.push((
                series,
                LineOptions::log_log(
                    format!("any domain: {} (Test 3)", scheme.to_uppercase()),
                    "cells",
                    "total time [s]",
                ),
            ));
        }
    }
    if charts.is_empty() {
        return Ok(());
    }
    for c in &mut charts {
        let s = c.0.clone();
        c.1.x_range = Some(data_range(&s, 0, true));
        c.1.y_range = Some(data_range(&s, 1, true));
    }
    let rows_of_panels = charts.len().div_ceil(2) as u32;
    plot_panels(
        &cfg.path(FIGURE),
        "PETSc ex9 side by side, and any domain",
        (1200, 80 + 460 * rows_of_panels),
        2,
        &charts,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use gradvi_cli::replication::records::read_csv;

    /// Domain rows (`family,mesh,scheme,linear,cells,krylov,total_s`) through the real reader.
    fn rows_of(lines: &[&str]) -> Vec<PeerRow> {
        let dir = std::env::temp_dir().join(format!("gradvi-peers-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bench_peers.csv");
        let mut text = "family,mesh,code,scheme,linear,grid,cells,unknowns,niter,coarse_niter,krylov,total_s,coarse_s,linear_s,peak_mib,err_max,err_mean,certificate\n".to_string();
        for l in lines {
            let f: Vec<&str> = l.split(',').collect();
            text += &format!(
                "{},{},gradvi,{},{},0,{},1,3,4,{},{},0.1,0.5,50,,,1e-12\n",
                f[0], f[1], f[2], f[3], f[4], f[5], f[6]
            );
        }
        std::fs::write(&path, text).unwrap();
        let rows = read_csv(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        rows
    }

    /// The any-domain target rows of `rows`, as markdown.
    fn domain_verdicts(rows: &[PeerRow]) -> String {
        let mut t = Table::new("target | measured | verdict", "llr");
        domain_targets(&mut t, rows);
        let mut md = Doc::default();
        md.table(&t);
        md.to_string()
    }

    #[test]
    fn the_data_verdict_reads_the_replayed_evaluations_where_measured() {
        let mut rows = rows_of(&[
            "ex9,,hmm,iterative,2000000,0,10.0",
            "ex9,,p1,iterative,2000000,0,10.0",
            "ex9,,p1,iterative,500000,0,1.0",
        ]);
        // bound 20%, used 3%; bound only 5%; below 10⁶ cells: not counted
        (rows[0].data_s, rows[0].data_used_s) = (2.0, 0.3);
        rows[1].data_s = 0.5;
        (rows[2].data_s, rows[2].data_used_s) = (0.9, 0.9);
        let verdict = |rows: &[PeerRow]| {
            let mut t = Table::new("target | measured | verdict", "llr");
            data_target(&mut t, rows);
            let mut md = Doc::default();
            md.table(&t);
            md.to_string()
        };
        let text = verdict(&rows);
        assert!(
            text.contains("at most 5.0% (ex9 p1 iterative")
                && text.contains("an upper bound")
                && text.contains("1 of 2 rows with the bound only")
                && text.contains("**met**"),
            "{text}"
        );
        rows[0].data_used_s = 1.2;
        let text = verdict(&rows);
        assert!(
            text.contains("at most 12.0% (ex9 hmm iterative")
                && text.contains("the solve's own evaluations, replayed")
                && text.contains("**not met**"),
            "{text}"
        );
    }

    #[test]
    fn the_domain_verdict_covers_the_reseeded_meshes() {
        // seed 1, direct: time ∝ N; seed 7, auto (direct then iterative): time ∝ N^1.3
        let rows = rows_of(&[
            "lshape,,hmm,direct,10000,0,1.0",
            "lshape,,hmm,direct,100000,0,10.0",
            "lshape,seed 7,hmm,auto,10000,0,1.0",
            "lshape,seed 7,hmm,auto,100000,40,19.952623149688797",
        ]);
        let text = domain_verdicts(&rows);
        assert!(
            text.contains("steepest growth N^1.30 (lshape seed 7 auto)")
                && text.contains("**not met**"),
            "{text}"
        );
        // both rows: the default solver's series, then every series
        assert_eq!(text.matches("steepest growth N^1.30").count(), 2, "{text}");
        assert!(text.contains("the default solver across the direct/iterative switch"));
        // a forced direct series that grows fast fails the second row only
        let rows = rows_of(&[
            "lshape,,hmm,direct,10000,0,1.0",
            "lshape,,hmm,direct,100000,0,19.952623149688797",
            "lshape,seed 7,hmm,auto,10000,0,1.0",
            "lshape,seed 7,hmm,auto,100000,40,10.0",
        ]);
        let text = domain_verdicts(&rows);
        let lines: Vec<&str> = text.lines().filter(|l| l.contains("steepest")).collect();
        assert_eq!(lines.len(), 2, "{text}");
        assert!(
            lines[0].contains("N^1.00 (lshape seed 7 auto)") && lines[0].contains("**met**"),
            "{text}"
        );
        assert!(
            lines[1].contains("N^1.30 (lshape seed 1 direct)") && lines[1].contains("**not met**"),
            "{text}"
        );
        // the default solver on the seed-1 meshes counts for the first row
        let mut with_seed1_auto = rows_of(&[
            "lshape,,hmm,auto,10000,0,1.0",
            "lshape,,hmm,auto,100000,40,19.952623149688797",
        ]);
        with_seed1_auto.extend(rows_of(&[
            "lshape,seed 7,hmm,auto,10000,0,1.0",
            "lshape,seed 7,hmm,auto,100000,40,10.0",
        ]));
        let text = domain_verdicts(&with_seed1_auto);
        let lines: Vec<&str> = text.lines().filter(|l| l.contains("steepest")).collect();
        assert!(
            lines[0].contains("N^1.30 (lshape seed 1 auto)") && lines[0].contains("**not met**"),
            "{text}"
        );
        let mut md = Doc::default();
        domains_section(&mut md, &rows);
        let text = md.to_string();
        assert!(
            text.contains("| lshape | seed 7 | hmm | auto: iterative | 100000 |"),
            "{text}"
        );
        assert!(
            text.contains("| lshape | seed 1 | hmm | direct | 10000 |"),
            "{text}"
        );
    }
}
