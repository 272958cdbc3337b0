//! `gradvi-dev fuzz`: a seeded mutation fuzzer of the whole input path (readers, validation,
//! problem setup, a small solve), run through the `gradvi` command line in child processes so
//! that panics, aborts, hangs and memory exhaustion are all observed.
//!
//! Each case takes a good input (the small meshes of `tests/data/good/` and `meshes/test*_1.msh`,
//! the problem files of `problems/` when present, and the 3D meshes of `tests/data/mesh3d/`:
//! gmsh files, RF `.node`/`.ele` pairs, and VTU files the fuzzed `gradvi` writes into the
//! scratch directory first, from those files and a generated family), mutates it with a seeded
//! generator (bit flips, byte and line deletion, duplication and swaps, truncation, numbers
//! replaced by extreme values, NaN, huge counts), writes it to a scratch directory and runs
//! `gradvi solve` on it (2D meshes and problem files) or `gradvi mesh info` (3D meshes, which
//! cannot be solved on yet; of an RF pair one file is mutated, the other copied) under a
//! memory limit (`ulimit -v`) and a wall-clock limit: the binary given by `--gradvi`
//! (`make fuzz` gives the release build), else this program's `gradvi` mode (the same command
//! line, [`gradvi_cli`]). A case passes when the child exits with 0 (then the CLI has checked
//! the certificate, or read and validated the 3D mesh) or 1 (a typed error, one line on
//! stderr), in time, with no panic message. Anything else is a failure (an abort, status 134
//! or signal 6, as a failed allocation gives, a crash, a panic, a hang), and its input is kept
//! in the scratch directory for reproduction.
//!
//! Before the mutations, the fixed cases of [`HUGE_REQUESTS`] ask for meshes far larger than the
//! memory limit (a 2D solve and a 3D mesh on generated meshes of a huge level): each must be
//! refused with the typed out-of-memory error (exit status 1, `would need about …`), which
//! shows that the limit is there and that a request it cannot hold ends cleanly.

use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Options of `gradvi-dev fuzz`.
#[derive(Args, Debug)]
pub struct FuzzArgs {
    /// Seed of the mutations (the same seed gives the same cases).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of cases (0: until --seconds is used up).
    #[arg(long, default_value_t = 0)]
    pub iterations: usize,
    /// Total time budget in seconds.
    #[arg(long, default_value_t = 60.0)]
    pub seconds: f64,
    /// Time limit of one case, seconds.
    #[arg(long, default_value_t = 20.0)]
    pub case_seconds: f64,
    /// Memory limit of one case, MiB (virtual memory, `ulimit -v`).
    #[arg(long, default_value_t = 4096)]
    pub memory_mib: u64,
    /// The repository root (where tests/data/good, meshes/ and problems/ are).
    #[arg(long, default_value = ".")]
    pub root: PathBuf,
    /// Scratch directory (failing inputs are kept there).
    #[arg(long)]
    pub scratch: Option<PathBuf>,
    /// The `gradvi` binary to fuzz (default: this program's `gradvi` mode).
    #[arg(long)]
    pub gradvi: Option<PathBuf>,
    /// Mutate the 3D meshes only.
    #[arg(long)]
    pub only_3d: bool,
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// What a seed input is, which says how a case runs it.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// A 2D mesh: `gradvi solve --problem test3 --mesh`.
    Mesh,
    /// A problem file: `gradvi solve`.
    Problem,
    /// A 3D mesh: `gradvi mesh info`.
    Mesh3,
}

/// The extension of `p`, or "".
fn ext(p: &Path) -> &str {
    p.extension().and_then(|e| e.to_str()).unwrap_or("")
}

/// The 3D seed inputs: the gmsh files and the RF `.node`/`.ele` files of `tests/data/mesh3d`,
/// and VTU files written into `scratch` by `gradvi` (`exe` after `prefix`) from the first gmsh
/// file, the first RF pair (polyhedra) and the level-1 prisms (written as polyhedra).
fn corpus_3d(root: &Path, exe: &Path, prefix: &[&str], scratch: &Path) -> Result<Vec<PathBuf>> {
    let Ok(entries) = std::fs::read_dir(root.join("tests/data/mesh3d")) else {
        return Ok(Vec::new());
    };
    let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    files.sort();
    files.retain(|f| ["msh", "node", "ele"].contains(&ext(f)));
    let msh = files.iter().find(|f| ext(f) == "msh").cloned();
    let rf = files
        .iter()
        .find(|f| ext(f) == "node")
        .map(|f| f.with_extension(""));
    let mut commands: Vec<(Vec<String>, PathBuf)> = Vec::new();
    for (i, src) in msh.into_iter().chain(rf).enumerate() {
        let out = scratch.join(format!("seed{i}.vtu"));
        let args = ["mesh", "convert"].map(String::from);
        let args = [
            &args[..],
            &[src.display().to_string(), out.display().to_string()],
        ]
        .concat();
        commands.push((args, out));
    }
    let out = scratch.join("seed-prisms.vtu");
    let args = ["mesh", "generate", "prisms", "--level", "1", "-o"].map(String::from);
    commands.push(([&args[..], &[out.display().to_string()]].concat(), out));
    for (args, out) in commands {
        let status = Command::new(exe)
            .args(prefix)
            .args(&args)
            .stderr(Stdio::null())
            .status()
            .context("starting gradvi")?;
        if !status.success() {
            bail!(
                "writing the 3D seed {} failed: gradvi {}",
                out.display(),
                args.join(" ")
            );
        }
        files.push(out);
    }
    Ok(files)
}

/// The seed inputs: (path, kind).
fn corpus(root: &Path) -> Result<Vec<(PathBuf, Kind)>> {
    let mut out = Vec::new();
    let good = root.join("tests/data/good");
    for dir in [good, root.join("meshes")] {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for f in files {
            let name = f.file_name().and_then(|n| n.to_str()).unwrap_or("");
            let small = !name.starts_with("test") || name.ends_with("_1.msh");
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            if small && ["msh", "typ1", "typ2"].contains(&ext) {
                out.push((f, Kind::Mesh));
            }
        }
    }
    if let Ok(entries) = std::fs::read_dir(root.join("problems")) {
        let mut files: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        out.extend(
            files
                .into_iter()
                .filter(|f| f.extension().is_some_and(|e| e == "toml"))
                .map(|f| (f, Kind::Problem)),
        );
    }
    Ok(out)
}

/// Replaces the number starting at a random position of a line by an extreme value.
fn mutate_number(text: &mut Vec<u8>, rng: &mut Rng) {
    const VALUES: [&str; 9] = [
        "nan",
        "inf",
        "-1",
        "0",
        "1e308",
        "4294967296",
        "99999999999",
        "-0",
        "1e-320",
    ];
    let starts: Vec<usize> = (0..text.len())
        .filter(|&i| text[i].is_ascii_digit() && (i == 0 || !text[i - 1].is_ascii_alphanumeric()))
        .collect();
    if starts.is_empty() {
        return;
    }
    let s = starts[rng.below(starts.len())];
    let mut e = s;
    while e < text.len() && (text[e].is_ascii_alphanumeric() || b".-+".contains(&text[e])) {
        e += 1;
    }
    let v = VALUES[rng.below(VALUES.len())];
    text.splice(s..e, v.bytes());
}

/// The line of `t` that holds byte `i`, with its newline if it has one.
fn line_around(t: &[u8], i: usize) -> std::ops::Range<usize> {
    let a = t[..i]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    let b = t[i..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(t.len(), |p| i + p + 1);
    a..b
}

/// One to four random mutations of `data`.
fn mutate(data: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut t = data.to_vec();
    for _ in 0..1 + rng.below(4) {
        if t.is_empty() {
            break;
        }
        let n = t.len();
        match rng.below(7) {
            0 => {
                let i = rng.below(n);
                t[i] ^= 1 << rng.below(8);
            }
            1 => t.truncate(rng.below(n)),
            2 | 3 => mutate_number(&mut t, rng),
            4 => {
                // delete a line
                let line = line_around(&t, rng.below(n));
                t.drain(line);
            }
            5 => {
                // duplicate a line
                let line = line_around(&t, rng.below(n));
                let (copy, end) = (t[line.clone()].to_vec(), line.end);
                t.splice(end..end, copy);
            }
            _ => {
                let (i, j) = (rng.below(n), rng.below(n));
                t.swap(i, j);
            }
        }
    }
    t
}

/// The fixed cases run before the mutations (see the module docs): the arguments of `gradvi`
/// (`{scratch}` stands for the scratch directory). Level 11 of the Cartesian family has 16.8M
/// cells and 50M unknowns (about 6 GB for the mesh alone); level 6 of the Kuhn family 12.6M
/// tetrahedra.
pub const HUGE_REQUESTS: [&[&str]; 2] = [
    &[
        "solve",
        "--problem",
        "test3",
        "--generate",
        "cartesian",
        "--level",
        "11",
    ],
    &[
        "mesh",
        "generate",
        "kuhn",
        "--level",
        "6",
        "-o",
        "{scratch}/huge-kuhn.vtu",
    ],
];

/// Runs the [`HUGE_REQUESTS`] under the limits: the failures (any end other than a one-line
/// typed out-of-memory error with exit status 1).
fn huge_requests(exe: &Path, prefix: &[&str], scratch: &Path, a: &FuzzArgs) -> Result<Vec<String>> {
    let mut failures = Vec::new();
    for case in HUGE_REQUESTS {
        let args: Vec<String> = prefix
            .iter()
            .chain(case)
            .map(|s| s.replace("{scratch}", &scratch.display().to_string()))
            .collect();
        let why = match run_case(exe, &args, a)? {
            (Verdict::Refused, err) if err.contains("would need about") => continue,
            (Verdict::Refused, err) => format!("refused, but not for memory: {err}"),
            (Verdict::Solved, _) => "accepted, but it cannot fit in the memory limit".into(),
            (Verdict::Fail(why), _) => why,
        };
        failures.push(format!("gradvi {}: {why}", args.join(" ")));
    }
    Ok(failures)
}

/// How one case ended.
enum Verdict {
    /// A certified solution (exit 0).
    Solved,
    /// A typed error (exit 1, one line).
    Refused,
    /// Anything else.
    Fail(String),
}

/// Runs `gradvi args` under the limits (`ulimit -v`: `RLIMIT_AS`, and the wall-clock limit)
/// and judges it; also returns its stderr.
fn run_case(exe: &Path, args: &[String], a: &FuzzArgs) -> Result<(Verdict, String)> {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {} && exec \"$0\" \"$@\"",
            a.memory_mib * 1024
        ))
        .arg(exe)
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .context("starting gradvi")?;
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait()? {
            break Some(s);
        }
        if t0.elapsed().as_secs_f64() > a.case_seconds {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    let verdict = match status {
        None => Verdict::Fail(format!("no answer within {} s", a.case_seconds)),
        Some(_) if err.contains("panicked") => Verdict::Fail(format!("panic: {err}")),
        Some(s) if aborted(s) => Verdict::Fail(format!("abort ({s}): {}", err.trim_end())),
        Some(s) if s.code() == Some(0) => Verdict::Solved,
        Some(s)
            if s.code() == Some(1)
                && err
                    .trim_end()
                    .lines()
                    .last()
                    .is_some_and(|l| l.starts_with("error: ")) =>
        {
            Verdict::Refused
        }
        Some(s) => Verdict::Fail(format!("exit {s}: {}", err.trim_end())),
    };
    Ok((verdict, err))
}

/// Whether `s` is an abort: killed by SIGABRT (what `memory allocation of … failed` ends
/// with), or status 134 (128 + 6, as a shell reports it).
fn aborted(s: std::process::ExitStatus) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        // SIGABRT is 6 on Linux and the BSDs
        if s.signal() == Some(6) {
            return true;
        }
    }
    s.code() == Some(134)
}

/// Writes the mutant of `src` as `scratch/case{n}.ext` (and, for one file of an RF pair, the
/// other file of the pair unchanged beside it): the files written and the command line that
/// runs the case.
fn prepare_case(
    src: &Path,
    kind: Kind,
    n: usize,
    scratch: &Path,
    rng: &mut Rng,
) -> Result<(Vec<PathBuf>, Vec<String>)> {
    let data = std::fs::read(src).with_context(|| format!("reading {}", src.display()))?;
    let e = if ext(src).is_empty() { "txt" } else { ext(src) };
    let input = scratch.join(format!("case{n:05}.{e}"));
    std::fs::write(&input, mutate(&data, rng))?;
    let mut files = vec![input.clone()];
    let partner = match e {
        "node" => Some("ele"),
        "ele" => Some("node"),
        _ => None,
    };
    if let Some(p) = partner {
        let other = input.with_extension(p);
        std::fs::copy(src.with_extension(p), &other)
            .with_context(|| format!("copying the RF partner of {}", src.display()))?;
        files.push(other);
    }
    let input_s = input.display().to_string();
    let args: &[&str] = match kind {
        Kind::Mesh => &[
            "solve",
            "--problem",
            "test3",
            "--mesh",
            &input_s,
            "--max-solves",
            "60",
        ],
        Kind::Problem => &["solve", &input_s, "--max-solves", "60"],
        Kind::Mesh3 => &["mesh", "info", &input_s],
    };
    Ok((files, args.iter().map(|s| s.to_string()).collect()))
}

/// `gradvi-dev fuzz` (see the module docs). Fails (nonzero exit) if any case failed.
pub fn run(a: &FuzzArgs) -> Result<()> {
    if !(a.seconds > 0.0 && a.case_seconds > 0.0 && a.seconds.is_finite()) {
        bail!("--seconds and --case-seconds must be positive and finite");
    }
    // the program and the arguments before `solve …` that run the command line
    let (exe, prefix): (PathBuf, &[&str]) = match &a.gradvi {
        Some(g) => (g.clone(), &[]),
        None => (std::env::current_exe()?, &["gradvi"]),
    };
    let scratch = a.scratch.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(format!("gradvi-fuzz-{}", std::process::id()))
    });
    std::fs::create_dir_all(&scratch)?;
    let seeds_3d = corpus_3d(&a.root, &exe, prefix, &scratch)?;
    let mut seeds = if a.only_3d {
        Vec::new()
    } else {
        corpus(&a.root)?
    };
    seeds.extend(seeds_3d.iter().map(|f| (f.clone(), Kind::Mesh3)));
    if seeds.is_empty() {
        bail!("no seed inputs under {}", a.root.display());
    }
    let t0 = Instant::now();
    let huge = huge_requests(&exe, prefix, &scratch, a)?;
    for why in &huge {
        eprintln!("FAIL {why}");
    }
    let mut rng = Rng(a.seed);
    let (mut cases, mut failures) = (0usize, Vec::new());
    let (mut solved, mut read) = (0usize, 0usize);
    while (a.iterations == 0 || cases < a.iterations) && t0.elapsed().as_secs_f64() < a.seconds {
        let (src, kind) = &seeds[rng.below(seeds.len())];
        let (files, case) = prepare_case(src, *kind, cases, &scratch, &mut rng)?;
        let args: Vec<String> = prefix.iter().map(|p| p.to_string()).chain(case).collect();
        let (verdict, _) = run_case(&exe, &args, a)?;
        match &verdict {
            Verdict::Solved | Verdict::Refused => {
                if matches!(verdict, Verdict::Solved) {
                    *(if *kind == Kind::Mesh3 {
                        &mut read
                    } else {
                        &mut solved
                    }) += 1;
                }
                files.iter().for_each(|f| drop(std::fs::remove_file(f)));
            }
            Verdict::Fail(why) => {
                eprintln!(
                    "FAIL {} (from {}): {why}",
                    files[0].display(),
                    src.display()
                );
                failures.push(files[0].clone());
            }
        }
        cases += 1;
    }
    eprintln!(
        "fuzz: {cases} cases in {:.1} s, seed {}: {solved} solved and certified, {read} 3D \
         meshes read and validated, {} refused with a typed error, {} failures; {} of {} huge \
         requests refused for memory under the limit of {} MiB",
        t0.elapsed().as_secs_f64(),
        a.seed,
        cases - solved - read - failures.len(),
        failures.len(),
        HUGE_REQUESTS.len() - huge.len(),
        HUGE_REQUESTS.len(),
        a.memory_mib
    );
    if !failures.is_empty() || !huge.is_empty() {
        bail!(
            "{} of {cases} cases and {} of {} huge requests failed (inputs kept in {})",
            failures.len(),
            huge.len(),
            HUGE_REQUESTS.len(),
            scratch.display()
        );
    }
    for f in seeds_3d.iter().filter(|f| f.starts_with(&scratch)) {
        let _ = std::fs::remove_file(f);
    }
    let _ = std::fs::remove_dir(&scratch);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The status of `sh -c script`.
    fn status_of(script: &str) -> std::process::ExitStatus {
        Command::new("sh").arg("-c").arg(script).status().unwrap()
    }

    /// A child killed by SIGABRT (what a failed allocation ends with) and a shell's 134 are
    /// aborts; a typed error (1), a success and another signal are not.
    #[cfg(unix)]
    #[test]
    fn aborts_are_recognised() {
        assert!(aborted(status_of("kill -ABRT $$")));
        assert!(aborted(status_of("exit 134")));
        assert!(!aborted(status_of("exit 1")));
        assert!(!aborted(status_of("exit 0")));
        assert!(!aborted(status_of("kill -TERM $$")));
    }
}
