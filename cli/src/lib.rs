//! The `gradvi` command line: mesh tools, single solves, the replication of the paper and the
//! cross-check against dolfinx. Run `gradvi --help` or `gradvi <command> --help`.
//!
//! The binary (`src/main.rs`) calls [`main_with_args`]; the commands are this library so that
//! the developer tools (`devtools/`) run the same command line in their child processes and
//! reuse the report ([`markdown`]), figure ([`plot`]) and CSV ([`replication::records`])
//! helpers.

pub mod crosscheck;
pub mod interrupt;
pub mod markdown;
pub mod mesh;
pub mod output;
pub mod plot;
pub mod replication;
pub mod solve;
pub mod solve3d;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};
use std::ffi::OsString;
use std::path::PathBuf;

/// Gradient schemes (HMM, P1) for the obstacle and Signorini problems.
#[derive(Parser)]
#[command(name = "gradvi", version, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh tools (2D and 3D): statistics, generation, conversion.
    #[command(subcommand)]
    Mesh(mesh::MeshCommand),
    /// Solve one problem on one mesh with one scheme; prints NITER, the certificate, errors and
    /// timings; optionally writes VTU and JSON.
    Solve(solve::SolveArgs),
    /// Reproduce the paper's tables and figures (results/*.csv, figures/*.png, REPORT.md).
    Replicate(ReplicateArgs),
    /// Compare gradvi's P1 and HMM with the dolfinx reference solves (CROSSCHECK.md).
    Crosscheck(crosscheck::CrosscheckArgs),
}

#[derive(Args)]
struct ReplicateArgs {
    /// The replication directory.
    #[arg(long, default_value = "replication")]
    out: PathBuf,
    /// The directory of the gmsh meshes.
    #[arg(long, default_value = "meshes")]
    meshes: PathBuf,
    /// The directory of the paper's values (CSV data typed from the paper).
    #[arg(long, default_value = "replication/paper")]
    paper: PathBuf,
    /// Directory of the original FVCA5 mesh files (hexa1_*.typ2, mesh4_1_2.typ2), optional.
    #[arg(long)]
    fvca5: Option<PathBuf>,
    /// Coarsest meshes only (a smoke run).
    #[arg(long)]
    quick: bool,
    /// Only rewrite REPORT.md and the CSV-based plots from existing CSV files.
    #[arg(long)]
    report_only: bool,
}

fn replicate(a: &ReplicateArgs) -> Result<()> {
    let cfg = replication::Config {
        out: a.out.clone(),
        meshes: a.meshes.clone(),
        fvca5: a.fvca5.clone(),
        paper: a.paper.clone(),
        quick: a.quick,
    };
    let root = std::env::current_dir()?;
    let mut progress = |s: &str| eprintln!("  {s}");
    if !a.report_only {
        let t0 = std::time::Instant::now();
        eprintln!("running the experiments of the paper's Section 4 (HMM and P1)...");
        let mut timings = replication::experiments::run(&cfg, &mut progress)?;
        let t = std::time::Instant::now();
        eprintln!("drawing the figures...");
        replication::figures::run(&cfg, &mut progress)?;
        timings.push(replication::records::TimingRow {
            stage: "figures".into(),
            seconds: t.elapsed().as_secs_f64(),
        });
        replication::records::write_csv(&cfg.results().join("timings.csv"), &timings)?;
        eprintln!(
            "experiments and figures: {:.1} s",
            t0.elapsed().as_secs_f64()
        );
    } else {
        replication::figures::plots_from_csv(&cfg)?;
    }
    replication::report::write(&cfg, &root)?;
    eprintln!("wrote {}", cfg.out.join("REPORT.md").display());
    Ok(())
}

/// Runs the command line `args` (the program name first); a user error is one clean line on
/// stderr (`error: ...` with its causes) and exit status 1, whatever `RUST_BACKTRACE` says.
/// Arguments clap rejects print its message and exit with its status (2).
pub fn main_with_args<I, T>(args: I) -> std::process::ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    match run(Cli::parse_from(args)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            if let Some((msg, status)) = interrupt::report(&e) {
                eprintln!("{msg}");
                return std::process::ExitCode::from(status);
            }
            eprintln!("error: {}{}", one_line(&e), advice(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

/// What to do after a mesh refused as too large for the memory (the library's
/// [`gradvi::Error::OutOfMemory`] says it already); empty for other errors.
fn advice(e: &anyhow::Error) -> String {
    let too_large = e.chain().any(|c| {
        matches!(
            c.downcast_ref::<gradvi::Error>(),
            Some(g @ (gradvi::Error::InvalidMesh(_) | gradvi::Error::InvalidMeshFile { .. }))
                if g.is_out_of_memory()
        )
    });
    if too_large {
        format!(" ({})", gradvi::error::MEMORY_ADVICE)
    } else {
        String::new()
    }
}

/// The error and its causes on one line, each cause once: the library's errors show their
/// cause in their own message (so that they read whole alone, e.g. from Python), which
/// anyhow's `{:#}` would repeat ("x.msh: No such file …: No such file …").
pub fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if line.is_empty() {
            line = c;
        } else if !line.contains(&c) {
            line.push_str(": ");
            line.push_str(&c);
        }
    }
    line
}

/// The allocator settings of gradvi's processes (glibc): one malloc arena for all threads,
/// unless `MALLOC_ARENA_MAX` says otherwise, and blocks of up to [`MMAP_THRESHOLD`] bytes
/// taken from the heap rather than mapped afresh, unless `MALLOC_MMAP_THRESHOLD_` or
/// `GLIBC_TUNABLES` says otherwise. Call it first thing in `main`, before any other thread
/// exists.
///
/// glibc gives each thread that allocates (here rayon's workers) its own arena and returns
/// the freed memory of those arenas to the system far less readily than that of the main
/// one, so the vectors freed between two active-set steps stayed resident: one arena lowers
/// the peak resident memory at an unchanged time.
///
/// glibc maps every block above its mmap threshold (at most 32 MiB by default) afresh and
/// unmaps it when freed, so each large array of a pass (a mesh build, an assembly, an
/// active-set step) pays page faults and the kernel's zeroing of its pages, even when the
/// array freed just before would have served. With the threshold at [`MMAP_THRESHOLD`] such
/// blocks are reused from the heap; larger ones are still mapped, so the peak does not grow
/// with the largest arrays of big problems.
///
/// The benchmark's children (`gradvi-dev`) call it too, so they measure the same settings.
/// The measurements behind these choices, and the alternatives measured and rejected, are in
/// `replication/BENCHMARKS.md` ("Measurements behind the defaults").
pub fn tune_malloc() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::ffi::c_int;
        unsafe extern "C" {
            fn mallopt(param: c_int, value: c_int) -> c_int;
        }
        /// `M_ARENA_MAX` of glibc's `<malloc.h>`.
        const M_ARENA_MAX: c_int = -8;
        /// `M_MMAP_THRESHOLD` of glibc's `<malloc.h>`.
        const M_MMAP_THRESHOLD: c_int = -3;
        let unset = |v: &str| std::env::var_os(v).is_none();
        // SAFETY: mallopt only sets a parameter of the allocator; it is called first thing in
        // main, before any other thread exists. A failure (return 0) leaves the default.
        if unset("MALLOC_ARENA_MAX") {
            unsafe {
                mallopt(M_ARENA_MAX, 1);
            }
        }
        if unset("MALLOC_MMAP_THRESHOLD_") && unset("GLIBC_TUNABLES") {
            unsafe {
                mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD);
            }
        }
    }
}

/// The mmap threshold [`tune_malloc`] sets: 256 MiB (measured against glibc's default and
/// against no threshold in `replication/measurements/cli.md`).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub const MMAP_THRESHOLD: std::ffi::c_int = 256 << 20;

fn run(cli: Cli) -> Result<()> {
    match &cli.command {
        Command::Mesh(c) => mesh::run(c),
        Command::Solve(a) => solve::run(a),
        Command::Replicate(a) => replicate(a),
        Command::Crosscheck(a) => crosscheck::run(a),
    }
}
