//! Regression check against an earlier build, measured in the same run
//! (`make bench-baseline BASE=REV`, or `gradvi-dev bench --baseline EXE [--baseline-rev REV]`).
//!
//! Run-to-run noise on the benchmark machine is about ±10%, so two benchmark runs on different
//! days cannot show that a change did not slow a case down. Here every gradvi case of the two
//! benchmarks (the scaling cases of [`super::plan`], and the gradvi cases of the peer
//! benchmark: ex9 up to `GRADVI_BENCH_EX9_MAX_GRID`, default [`DEFAULT_EX9_MAX_GRID`], and the
//! any-domain meshes) runs as a child process of the current executable and of EXE (the
//! `gradvi-dev` binary of the earlier revision, or its `gradvi` binary for revisions before the
//! workspace: both take the same child arguments, `bench --child …` and `bench --peer-child
//! …`), alternately (which one runs first alternates from
//! case to case and repeat to repeat), `GRADVI_BENCH_REPEAT` times each (default
//! [`DEFAULT_REPEAT`]); the medians are compared. The scaling cases use the variants of
//! `GRADVI_BENCH_VARIANTS`, here `nested` (the default of `gradvi solve`) unless set, since the
//! cold variant alone takes 25 minutes per pass.
//!
//! **Confirmation.** With 87 cases and medians of a few runs on a machine whose run-to-run
//! noise is about ±10%, a case or two lands above the bound in most checks by chance alone
//! (`replication/BENCHMARKS.md`, "Measurements behind the defaults"). A case found slower
//! after the first pass is therefore measured again, `GRADVI_BENCH_CONFIRM` more runs of each
//! build (default [`DEFAULT_CONFIRM`], alternating as before), and judged on the medians of all
//! its runs, the first ones included; the report shows the first-pass ratio beside. The bound
//! is the same; only flagged cases get the extra runs, so a true slowdown of more than 10%
//! stays flagged, with more runs behind it.
//!
//! **Span.** The peer children of this build report `solved_s`, from the mesh to the certified
//! solution, beside `total_s`, which also covers the errors and the freeing; a child that does
//! not report `solved_s` (the earlier builds whose `total_s` ended at the certified solution,
//! the default revision of `make bench-baseline` among them) reports that span as `total_s`.
//! The check compares `solved_s` when a child reports it, else `total_s`: the same span on
//! both sides (a NaN `solved_s` is written as null and not read). Which builds are which is in
//! `replication/BENCHMARKS.md` ("Measurements behind the defaults").
//!
//! A case the earlier build cannot run (a benchmark it did not have yet, or an error) is
//! listed with its reason, not hidden. Rows go to [`CSV`] as they come; the report is
//! [`REPORT`], with the verdict: a case regresses when its median time is more than
//! [`MAX_SLOWDOWN`] times the earlier build's and more than [`MIN_SLOWDOWN_S`] longer, or its
//! peak memory more than [`MAX_MEMORY`] times and more than [`MIN_MEMORY_MIB`] larger; the NITER
//! of both builds are shown beside. The report also shows how much the peaks of one build vary
//! over the repeats of one case (their largest spread in the run), the noise the memory floor
//! stands for, and the cases above [`MAX_MEMORY`] that the floor lets through.

use super::{Config, bad, json_row, peers, plan, stdout_of};
use gradvi_cli::markdown::{Doc, Table, fixed, met};
use gradvi_cli::replication::records::{read_csv, write_csv};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::process::Command;

/// The CSV of the comparison.
pub const CSV: &str = "replication/results/bench_baseline.csv";
/// Its report.
pub const REPORT: &str = "replication/REGRESSION.md";
/// Runs of each build per case (medians are compared).
pub const DEFAULT_REPEAT: usize = 3;
/// Further runs of each build for a case found slower after the first pass.
pub const DEFAULT_CONFIRM: usize = 6;
/// Largest ex9 grid of the comparison, unless `GRADVI_BENCH_EX9_MAX_GRID` says otherwise.
pub const DEFAULT_EX9_MAX_GRID: usize = 1025;
/// A case regresses in time above this ratio of medians (the machine's run-to-run noise).
pub const MAX_SLOWDOWN: f64 = 1.10;
/// ... and by more than this many seconds (below it, process start and timer noise dominate).
pub const MIN_SLOWDOWN_S: f64 = 0.05;
/// A case regresses in memory above this ratio of peaks ...
pub const MAX_MEMORY: f64 = 1.05;
/// ... and by more than this many MiB. The peak resident memory of one binary on one case
/// varies from run to run (thread stacks, allocator arenas and packing buffers touched or
/// not; the spread behind this floor is in `replication/BENCHMARKS.md`, "Measurements behind
/// the defaults"). The report shows the spread measured in its own run beside it.
pub const MIN_MEMORY_MIB: f64 = 2.0;

/// One case measured with both builds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BaselineRow {
    /// scale or peers.
    pub bench: String,
    /// The case (family, size, scheme, variant or linear solver).
    pub case: String,
    /// The earlier build (its revision, or the path of its executable).
    pub baseline: String,
    /// Median total time of the current build, s.
    pub new_s: f64,
    /// Median total time of the earlier build, s (NaN if it could not run the case).
    pub base_s: f64,
    /// Peak memory of the current build, MiB (largest over the repeats).
    pub new_mib: f64,
    /// Peak memory of the earlier build, MiB.
    pub base_mib: f64,
    /// Largest minus smallest peak over the repeats of the current build, MiB (NaN in rows
    /// written before this column existed).
    #[serde(default = "nan")]
    pub new_mib_spread: f64,
    /// The same for the earlier build.
    #[serde(default = "nan")]
    pub base_mib_spread: f64,
    /// NITER of the current build.
    pub new_niter: usize,
    /// NITER of the earlier build (0 if it could not run the case).
    pub base_niter: usize,
    /// Why the earlier build could not run the case (empty if it did).
    pub note: String,
    /// Runs of each build behind the medians (0 in rows written before this column).
    #[serde(default)]
    pub runs: usize,
    /// The time ratio after the first pass, when the case was measured again (confirmation,
    /// module docs); NaN otherwise.
    #[serde(default = "nan")]
    pub first_ratio: f64,
}

fn nan() -> f64 {
    f64::NAN
}

/// A child process to run with both builds: its arguments after the executable.
struct Job {
    bench: &'static str,
    case: String,
    args: Vec<String>,
}

/// The jobs: the scaling cases, then the gradvi cases of the peer benchmark.
fn jobs(cfg: &Config) -> gradvi::Result<Vec<Job>> {
    let mut out: Vec<Job> = plan(cfg)?
        .iter()
        .map(|c| Job {
            bench: "scale",
            case: c.label(),
            args: c.child_args(),
        })
        .collect();
    let max_grid = super::usize_from_env("GRADVI_BENCH_EX9_MAX_GRID", DEFAULT_EX9_MAX_GRID)?;
    for (family, scheme, linear, size, file) in peers::gradvi_cases(cfg, max_grid)? {
        let case = match &file {
            Some(f) => format!(
                "{family} {scheme} {linear} {}",
                f.file_stem().unwrap_or_default().to_string_lossy()
            ),
            None => format!("{family} {scheme} {linear} {size}²"),
        };
        out.push(Job {
            bench: "peers",
            case,
            args: peers::child_args(&family, scheme, linear, size, file.as_deref()),
        });
    }
    Ok(out)
}

/// What a child reports that is compared: its time (module docs: span), peak memory, NITER.
#[derive(Debug, Clone, Copy)]
struct Sample {
    total_s: f64,
    peak_mib: f64,
    niter: usize,
}

/// Runs `args` with `exe` from the repository root and reads its JSON row.
fn sample(cfg: &Config, exe: &Path, args: &[String]) -> gradvi::Result<Sample> {
    let mut cmd = Command::new(exe);
    cmd.args(args).current_dir(&cfg.root);
    let what = args.join(" ");
    let text = stdout_of(cmd, exe, &what)?;
    let v: serde_json::Value = json_row(&text, &format!("{what}: bad child output"))?;
    let num = |k: &str| v.get(k).and_then(serde_json::Value::as_f64);
    // the span up to the certified solution (module docs)
    let time = num("solved_s").or(num("total_s"));
    match (time, num("peak_mib"), num("niter")) {
        (Some(total_s), Some(peak_mib), Some(niter)) => Ok(Sample {
            total_s,
            peak_mib,
            niter: niter as usize,
        }),
        _ => Err(bad(format!(
            "{}: no total_s, peak_mib or niter",
            args.join(" ")
        ))),
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The row of one job from its samples (`base` is `Err(why)` if the earlier build failed).
fn row(job: &Job, baseline: &str, new: &[Sample], base: Result<&[Sample], String>) -> BaselineRow {
    let peak = |s: &[Sample]| s.iter().map(|x| x.peak_mib).fold(f64::NAN, f64::max);
    let spread = |s: &[Sample]| peak(s) - s.iter().map(|x| x.peak_mib).fold(f64::NAN, f64::min);
    let (base_s, base_mib, base_mib_spread, base_niter, note) = match base {
        Ok(b) => (
            median(b.iter().map(|x| x.total_s).collect()),
            peak(b),
            spread(b),
            b.last().map_or(0, |x| x.niter),
            String::new(),
        ),
        Err(why) => (f64::NAN, f64::NAN, f64::NAN, 0, why),
    };
    BaselineRow {
        bench: job.bench.into(),
        case: job.case.clone(),
        baseline: baseline.into(),
        new_s: median(new.iter().map(|x| x.total_s).collect()),
        base_s,
        new_mib: peak(new),
        base_mib,
        new_mib_spread: spread(new),
        base_mib_spread,
        new_niter: new.last().map_or(0, |x| x.niter),
        base_niter,
        note,
        runs: new.len(),
        first_ratio: f64::NAN,
    }
}

/// The earlier build's samples, or why it failed.
fn base_result<'a>(old: &'a [Sample], error: &Option<String>) -> Result<&'a [Sample], String> {
    match error {
        Some(why) => Err(why.clone()),
        None => Ok(old),
    }
}

/// Runs `job` `runs` times with each build, alternately (which one runs first alternates with
/// `i + r`), adding to `new` and `old`; the first failure of the earlier build stops its runs
/// and is kept in `base_error`.
#[allow(clippy::too_many_arguments)]
fn measure(
    cfg: &Config,
    (exe, base): (&Path, &Path),
    job: &Job,
    (i, runs): (usize, usize),
    new: &mut Vec<Sample>,
    old: &mut Vec<Sample>,
    base_error: &mut Option<String>,
) -> gradvi::Result<()> {
    for r in 0..runs {
        let base_first = (i + r) % 2 == 0;
        for first in [true, false] {
            if first == base_first {
                if base_error.is_none() {
                    match sample(cfg, base, &job.args) {
                        Ok(s) => old.push(s),
                        Err(e) => *base_error = Some(e.to_string()),
                    }
                }
            } else {
                new.push(sample(cfg, exe, &job.args)?);
            }
        }
    }
    Ok(())
}

/// Runs the comparison of the current executable `exe` with `base` (named `baseline` in the
/// report), writing [`CSV`] as rows come and then [`REPORT`].
pub fn run(cfg: &Config, exe: &Path, base: &Path, baseline: &str) -> gradvi::Result<()> {
    if !base.is_file() {
        return Err(bad(format!(
            "the baseline executable {} does not exist",
            base.display()
        )));
    }
    let repeat = super::repeat_from_env("GRADVI_BENCH_REPEAT", DEFAULT_REPEAT)?;
    let confirm = super::repeat_from_env("GRADVI_BENCH_CONFIRM", DEFAULT_CONFIRM)?;
    let jobs = jobs(cfg)?;
    eprintln!(
        "[bench] regression check: {} cases, {repeat} runs of each build, against {baseline}",
        jobs.len()
    );
    let mut rows = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        eprintln!(
            "[bench] ({}/{}) {} {} ...",
            i + 1,
            jobs.len(),
            job.bench,
            job.case
        );
        let row = check_job(cfg, (exe, base), job, i, (repeat, confirm), baseline)?;
        eprintln!(
            "[bench]   new {:.3} s / {:.0} MiB, {baseline} {:.3} s / {:.0} MiB (ratio {:.2}){}",
            row.new_s,
            row.new_mib,
            row.base_s,
            row.base_mib,
            row.new_s / row.base_s,
            if row.note.is_empty() {
                String::new()
            } else {
                format!(" — earlier build failed: {}", row.note)
            }
        );
        rows.push(row);
        write_csv(&cfg.path(CSV), &rows)?;
    }
    write_report(cfg)
}

/// Measures the `i`-th job with the current executable and the earlier one (`exes`):
/// `repeat` runs of each, then `confirm` more if the case is found slower (module docs).
fn check_job(
    cfg: &Config,
    exes: (&Path, &Path),
    job: &Job,
    i: usize,
    (repeat, confirm): (usize, usize),
    baseline: &str,
) -> gradvi::Result<BaselineRow> {
    let (mut new, mut old) = (Vec::new(), Vec::new());
    let mut base_error = None;
    measure(
        cfg,
        exes,
        job,
        (i, repeat),
        &mut new,
        &mut old,
        &mut base_error,
    )?;
    let mut r = row(job, baseline, &new, base_result(&old, &base_error));
    if regresses(&r).is_some_and(|g| g.0) {
        let first = r.new_s / r.base_s;
        eprintln!(
            "[bench]   ratio {first:.2} after {repeat} runs: {confirm} more runs of each build"
        );
        measure(
            cfg,
            exes,
            job,
            (i + repeat, confirm),
            &mut new,
            &mut old,
            &mut base_error,
        )?;
        r = row(job, baseline, &new, base_result(&old, &base_error));
        r.first_ratio = first;
    }
    Ok(r)
}

/// Whether a row regresses in time and in memory (`None` if the earlier build did not run it).
fn regresses(r: &BaselineRow) -> Option<(bool, bool)> {
    (r.base_s.is_finite() && r.base_s > 0.0).then_some((
        r.new_s > MAX_SLOWDOWN * r.base_s && r.new_s - r.base_s > MIN_SLOWDOWN_S,
        heavier(r, MIN_MEMORY_MIB),
    ))
}

/// Whether the peak memory of the current build exceeds [`MAX_MEMORY`] times the earlier
/// build's and by more than `floor` MiB.
fn heavier(r: &BaselineRow, floor: f64) -> bool {
    r.new_mib > MAX_MEMORY * r.base_mib && r.new_mib - r.base_mib > floor
}

/// The verdict of a comparison: cases compared, those slower and heavier, the time ratios.
struct Summary {
    compared: usize,
    slow: usize,
    heavy: usize,
    /// Above [`MAX_MEMORY`] by at most [`MIN_MEMORY_MIB`].
    heavy_in_floor: usize,
    /// Largest spread of one build's peaks over the repeats of one case, MiB.
    spread: f64,
    min: f64,
    max: f64,
    geometric_mean: f64,
    /// Cases measured again after the first pass (confirmation).
    remeasured: usize,
}

fn summarise(rows: &[BaselineRow]) -> Summary {
    let verdicts: Vec<(f64, (bool, bool))> = rows
        .iter()
        .filter_map(|r| regresses(r).map(|g| (r.new_s / r.base_s, g)))
        .collect();
    let compared = || rows.iter().filter(|r| regresses(r).is_some());
    let n = verdicts.len();
    let log_sum: f64 = verdicts.iter().map(|(x, _)| x.ln()).sum();
    Summary {
        compared: n,
        slow: verdicts.iter().filter(|(_, g)| g.0).count(),
        heavy: verdicts.iter().filter(|(_, g)| g.1).count(),
        heavy_in_floor: compared()
            .filter(|r| heavier(r, 0.0) && !heavier(r, MIN_MEMORY_MIB))
            .count(),
        spread: compared()
            .flat_map(|r| [r.new_mib_spread, r.base_mib_spread])
            .fold(f64::NAN, f64::max),
        min: verdicts.iter().map(|v| v.0).fold(f64::NAN, f64::min),
        max: verdicts.iter().map(|v| v.0).fold(f64::NAN, f64::max),
        geometric_mean: (log_sum / n.max(1) as f64).exp(),
        remeasured: compared().filter(|r| r.first_ratio.is_finite()).count(),
    }
}

/// The row of the peer report's targets for "no regression of the existing benchmark rows",
/// from [`CSV`] (`None` if the comparison has not been run).
pub fn target_row(cfg: &Config) -> Option<[String; 3]> {
    let rows: Vec<BaselineRow> = read_csv(&cfg.path(CSV)).ok()?;
    let s = summarise(&rows);
    let rev = &rows.first()?.baseline;
    Some([
        format!(
            "no regression of the existing benchmark rows (same-run check against {rev}, `{REPORT}`)"
        ),
        format!(
            "{} of {} cases slower than {MAX_SLOWDOWN}×{}, {} above {MAX_MEMORY}× memory and by \
             more than {MIN_MEMORY_MIB} MiB{}; time \
             ratios {} to {}, geometric mean {}",
            s.slow,
            s.compared,
            remeasured_note(&s),
            s.heavy,
            floor_note(&s),
            fixed(s.min, 2),
            fixed(s.max, 2),
            fixed(s.geometric_mean, 2)
        ),
        met(s.compared > 0 && s.slow == 0 && s.heavy == 0).into(),
    ])
}

/// " (N above after the first pass, measured again)", if any case was.
fn remeasured_note(s: &Summary) -> String {
    match s.remeasured {
        0 => String::new(),
        n => format!(" ({n} above after the first pass, measured again)"),
    }
}

/// The memory cases the floor lets through, if any: ", N more above 1.05× by at most F MiB
/// (one build's peaks on one case vary by up to S MiB in this run)".
fn floor_note(s: &Summary) -> String {
    if s.heavy_in_floor == 0 {
        return String::new();
    }
    format!(
        ", {} more above {MAX_MEMORY}× by at most {MIN_MEMORY_MIB} MiB ({})",
        s.heavy_in_floor,
        spread_text(s)
    )
}

/// "one build's peaks on one case vary by up to S MiB in this run" (or that they were not
/// recorded: rows written before the spread columns).
fn spread_text(s: &Summary) -> String {
    if s.spread.is_finite() {
        format!(
            "one build's peaks on one case vary by up to {} MiB in this run",
            fixed(s.spread, 1)
        )
    } else {
        "the spread of the peaks was not recorded in this run".into()
    }
}

/// Writes [`REPORT`] from [`CSV`].
pub fn write_report(cfg: &Config) -> gradvi::Result<()> {
    let rows: Vec<BaselineRow> = read_csv(&cfg.path(CSV))?;
    let baseline = rows.first().map_or("?", |r| r.baseline.as_str());
    let s = summarise(&rows);
    let mut md = Doc::default();
    md.heading(1, format!("Regression check against {baseline}"));
    md.para(format!(
        "Written by `make bench-baseline BASE={baseline}` from `{CSV}`. Every case ran as a \
         child process of the current build and of the earlier one, alternately, and the medians \
         of their total times are compared in the same run (`devtools/src/bench/baseline.rs`). A case \
         regresses when its median time exceeds {MAX_SLOWDOWN} times the earlier build's (this \
         machine's run-to-run noise is about ±10%) and by more than {MIN_SLOWDOWN_S} s, or its \
         peak memory (the largest of its runs) exceeds {MAX_MEMORY} times the earlier build's \
         and by more than {MIN_MEMORY_MIB} MiB. That floor stands for the noise of the peak: \
         {} (the largest spread over the repeats of a case, over the cases and both builds).",
        spread_text(&s)
    ));
    md.para(format!(
        "A case above the time bound after the first pass ({} of each build) is measured \
         again ({} more runs of each build by default, `GRADVI_BENCH_CONFIRM`) and judged on the \
         medians of all its runs, the first ones included; the table shows its first-pass ratio \
         and the runs behind its medians. The peer cases compare the time up to the certified \
         solution (`solved_s`, or `total_s` from builds that do not report it, which is the same \
         span for builds before ac00c7d): the errors against the exact solution and the freeing, \
         which this build's `total_s` includes since ac00c7d, are left out of both sides.",
        match rows
            .iter()
            .filter(|r| !r.first_ratio.is_finite())
            .map(|r| r.runs)
            .max()
        {
            Some(n) if n > 0 => format!("{n} runs"),
            _ => "`GRADVI_BENCH_REPEAT` runs".into(),
        },
        DEFAULT_CONFIRM
    ));
    let mut t = Table::new("check | measured | verdict", "lll");
    t.row(vec![
        format!("time ≤ {MAX_SLOWDOWN} × earlier build, every case"),
        format!(
            "{} of {} cases above{}; ratios {} to {}, geometric mean {}",
            s.slow,
            s.compared,
            remeasured_note(&s),
            fixed(s.min, 2),
            fixed(s.max, 2),
            fixed(s.geometric_mean, 2)
        ),
        met(s.slow == 0 && s.compared > 0).into(),
    ]);
    t.row(vec![
        format!("peak memory ≤ {MAX_MEMORY} × earlier build (or within {MIN_MEMORY_MIB} MiB), every case"),
        format!("{} of {} cases above{}", s.heavy, s.compared, floor_note(&s)),
        met(s.heavy == 0 && s.compared > 0).into(),
    ]);
    md.heading(2, "Verdict");
    md.table(&t);
    let skipped = rows.len() - s.compared;
    if skipped > 0 {
        md.para(format!(
            "{skipped} cases could not be run by the earlier build (reasons in the table below) \
             and are not in the verdict."
        ));
    }
    md.heading(2, "All cases");
    let mut t = Table::new(
        "bench | case | new s | earlier s | ratio | first-pass ratio | runs | new MiB | earlier MiB | NITER new / earlier | note",
        "llrrrrrrrcl",
    );
    for r in &rows {
        t.row(vec![
            r.bench.clone(),
            r.case.clone(),
            fixed(r.new_s, 3),
            fixed(r.base_s, 3),
            fixed(r.new_s / r.base_s, 2),
            if r.first_ratio.is_finite() {
                fixed(r.first_ratio, 2)
            } else {
                String::new()
            },
            if r.runs > 0 {
                r.runs.to_string()
            } else {
                String::new()
            },
            fixed(r.new_mib, 0),
            fixed(r.base_mib, 0),
            format!("{} / {}", r.new_niter, r.base_niter),
            r.note.lines().next().unwrap_or("").to_string(),
        ]);
    }
    md.table(&t);
    md.write(&cfg.path(REPORT))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> Job {
        Job {
            bench: "scale",
            case: "c".into(),
            args: vec![],
        }
    }

    fn s(t: f64, m: f64) -> Sample {
        Sample {
            total_s: t,
            peak_mib: m,
            niter: 3,
        }
    }

    /// A fake child: a shell script printing one JSON row per run, its time read from `times`
    /// (one per line, the n-th run takes line n; the last line repeats), counting its runs in
    /// `dir/NAME.count`.
    fn fake_child(dir: &Path, name: &str, times: &[&str], key: &str) -> std::path::PathBuf {
        use std::os::unix::fs::PermissionsExt;
        let list = dir.join(format!("{name}.times"));
        std::fs::write(&list, times.join("\n") + "\n").unwrap();
        let count = dir.join(format!("{name}.count"));
        let exe = dir.join(name);
        let (c, l) = (count.display(), list.display());
        // a child reporting solved_s also reports a longer total_s, which is not compared
        let extra = if key == "solved_s" {
            "\"total_s\":99,"
        } else {
            ""
        };
        let script = [
            "#!/bin/sh".to_string(),
            format!("n=$(cat '{c}' 2>/dev/null || echo 0); n=$((n+1)); echo $n > '{c}'"),
            format!("t=$(sed -n \"${{n}}p\" '{l}'); [ -n \"$t\" ] || t=$(tail -n 1 '{l}')"),
            format!("echo '{{{extra}\"{key}\":'$t',\"peak_mib\":10,\"niter\":3}}'"),
        ]
        .join("\n")
            + "\n";
        std::fs::write(&exe, script).unwrap();
        std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).unwrap();
        exe
    }

    fn runs_of(dir: &Path, name: &str) -> usize {
        std::fs::read_to_string(dir.join(format!("{name}.count")))
            .map_or(0, |s| s.trim().parse().unwrap())
    }

    #[test]
    fn flagged_cases_are_measured_again_on_all_their_runs() {
        let dir = std::env::temp_dir().join(format!("gradvi-baseline-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = Config {
            root: dir.clone(),
            max_cells: 0,
            dolfinx_max_cells: 0,
            variants: vec![],
            python: "/nonexistent".into(),
        };
        // the earlier build: 1.0 s, reported as total_s (a build before solved_s)
        let old = fake_child(&dir, "old", &["1.0"], "total_s");
        // slow in its first 3 runs only: flagged, then judged on 9 runs (median 1.0)
        let noisy = fake_child(&dir, "noisy", &["1.3", "1.3", "1.3", "1.0"], "solved_s");
        let r = check_job(&cfg, (&noisy, &old), &job(), 0, (3, 6), "old").unwrap();
        assert_eq!(
            (runs_of(&dir, "noisy"), runs_of(&dir, "old"), r.runs),
            (9, 9, 9)
        );
        assert!((r.first_ratio - 1.3).abs() < 1e-12 && r.new_s == 1.0 && r.base_s == 1.0);
        assert_eq!(regresses(&r), Some((false, false)));
        // slow in every run: flagged, measured again, still slow; solved_s read, not total_s
        let slow = fake_child(&dir, "slow", &["1.3"], "solved_s");
        let r = check_job(&cfg, (&slow, &old), &job(), 1, (3, 6), "old").unwrap();
        assert_eq!((r.runs, r.new_s, r.base_s), (9, 1.3, 1.0));
        assert_eq!(regresses(&r), Some((true, false)));
        // within the bound: no further runs
        let fine = fake_child(&dir, "fine", &["1.05"], "solved_s");
        let r = check_job(&cfg, (&fine, &old), &job(), 2, (3, 6), "old").unwrap();
        assert_eq!((runs_of(&dir, "fine"), r.runs), (3, 3));
        assert!(r.first_ratio.is_nan() && regresses(&r) == Some((false, false)));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn medians_ratios_and_verdicts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        let new = [s(1.0, 100.0), s(1.3, 101.0), s(1.2, 99.0)];
        let old = [s(1.0, 100.0), s(1.05, 100.0), s(2.0, 100.0)];
        // 15% slower but by 0.015 s only: noise, not a regression
        let tiny = row(&job(), "abc", &[s(0.115, 9.0)], Ok(&[s(0.1, 9.0)]));
        assert_eq!(regresses(&tiny), Some((false, false)));
        let r = row(&job(), "abc", &new, Ok(&old));
        assert_eq!(
            (r.new_s, r.base_s, r.new_mib, r.base_mib),
            (1.2, 1.05, 101.0, 100.0)
        );
        // 1.2 / 1.05 = 1.14 > 1.10: slower; 101 / 100 ≤ 1.05: memory kept
        assert_eq!(regresses(&r), Some((true, false)));
        let fast = row(&job(), "abc", &old, Ok(&new));
        assert_eq!(regresses(&fast), Some((false, false)));
        let failed = row(&job(), "abc", &new, Err("unknown --peer-child".into()));
        assert_eq!(regresses(&failed), None);
        assert!(failed.base_s.is_nan() && failed.note.contains("peer-child"));
        // 8% heavier: by 1.5 MiB, within the floor; by 8 MiB, a regression
        let light = [s(1.0, 20.0), s(1.0, 18.5)];
        let floor = row(&job(), "abc", &[s(1.0, 21.5)], Ok(&light));
        assert_eq!(regresses(&floor), Some((false, false)));
        assert_eq!((floor.new_mib_spread, floor.base_mib_spread), (0.0, 1.5));
        let heavy = row(&job(), "abc", &[s(1.0, 108.0)], Ok(&[s(1.0, 100.0)]));
        assert_eq!(regresses(&heavy), Some((false, true)));
        // the summary counts the compared cases only
        let sum = summarise(&[r, fast, failed, tiny, floor, heavy]);
        assert_eq!(
            (sum.compared, sum.slow, sum.heavy, sum.heavy_in_floor),
            (5, 1, 1, 1)
        );
        assert_eq!(sum.spread, 2.0);
        assert!(floor_note(&sum).contains("1 more above"));
        assert!(sum.min < 1.0 && sum.max > 1.1 && sum.geometric_mean > 0.0);
    }
}
