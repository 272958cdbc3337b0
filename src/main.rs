//! The `gradvi` command line: mesh tools, single solves, the replication of the paper and the
//! cross-check against dolfinx. Run `gradvi --help` or `gradvi <command> --help`.

mod app;

use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use gradvi::mesh::MemoryBudget;
use gradvi::mesh::io::{read_mesh, write_typ2, write_vtu};
use std::path::PathBuf;

/// Gradient schemes (HMM, P1) for the obstacle and Signorini problems.
#[derive(Parser)]
#[command(name = "gradvi", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh tools: statistics, generation, conversion.
    #[command(subcommand)]
    Mesh(MeshCommand),
    /// Solve one problem on one mesh with one scheme; prints NITER, the certificate, errors and
    /// timings; optionally writes VTU and JSON.
    Solve(app::solve::SolveArgs),
    /// Reproduce the paper's tables and figures (results/*.csv, figures/*.png, REPORT.md).
    Replicate(ReplicateArgs),
    /// Compare gradvi's P1 and HMM with the dolfinx reference solves (CROSSCHECK.md).
    Crosscheck(app::crosscheck::CrosscheckArgs),
    /// Seeded mutation fuzzing of the readers, validation and solver (run by `make fuzz`).
    #[command(hide = true)]
    Fuzz(app::fuzz::FuzzArgs),
    /// The scaling benchmark (run by `make bench`; see README "Performance"). Arguments:
    /// `--report-only` rewrites BENCHMARKS.md from bench.csv; `--root DIR` is the repository.
    #[command(hide = true)]
    Bench {
        /// Arguments passed to the benchmark driver.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

#[derive(Subcommand)]
enum MeshCommand {
    /// Print the statistics of a mesh file (.msh, .typ1, .typ2).
    Info {
        /// The mesh file.
        file: PathBuf,
    },
    /// Generate a mesh of the unit square and write it (.typ2 or .vtu, by extension).
    Generate {
        /// cartesian, hexagonal, kershaw or triangles.
        family: String,
        /// Level (hexagonal k: the FVCA5 hexa1_k mesh; kershaw k: mesh4_1_k; cartesian k:
        /// 2^(k+1) × 2^(k+1) squares; triangles k: those squares, each cut into two triangles
        /// by its diagonal from lower left to upper right).
        #[arg(long)]
        level: usize,
        /// Output file (.typ2 or .vtu).
        #[arg(short, long)]
        output: PathBuf,
    },
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

fn mesh_info(file: &PathBuf) -> Result<()> {
    let m = read_mesh(file, MemoryBudget::available())?;
    let mut sides = std::collections::BTreeMap::new();
    for k in 0..m.n_cells() {
        *sides.entry(m.cell_vertices(k).len()).or_insert(0usize) += 1;
    }
    let area: f64 = (0..m.n_cells()).map(|k| m.measure(k)).sum();
    let bb = m.bounding_box();
    let mut tags = std::collections::BTreeMap::new();
    for &e in m.boundary_edges() {
        *tags.entry(m.edge_tag(e)).or_insert(0usize) += 1;
    }
    println!("file            {}", file.display());
    println!("cells           {}", m.n_cells());
    println!("vertices        {}", m.n_vertices());
    println!(
        "edges           {} ({} on the boundary)",
        m.n_edges(),
        m.boundary_edges().len()
    );
    println!("h (max diam.)   {:.6}", m.h());
    println!("total area      {area:.12}");
    println!(
        "bounding box    [{}, {}] x [{}, {}]",
        bb.x[0], bb.x[1], bb.y[0], bb.y[1]
    );
    let s: Vec<String> = sides.iter().map(|(n, c)| format!("{n}:{c}")).collect();
    println!("cells by sides  {}", s.join(" "));
    let t: Vec<String> = tags.iter().map(|(t, c)| format!("tag {t}: {c}")).collect();
    println!("boundary edges  {}", t.join(", "));
    Ok(())
}

fn replicate(a: &ReplicateArgs) -> Result<()> {
    let cfg = app::replication::Config {
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
        let mut timings = app::replication::experiments::run(&cfg, &mut progress)?;
        let t = std::time::Instant::now();
        eprintln!("drawing the figures...");
        app::replication::figures::run(&cfg, &mut progress)?;
        timings.push(app::replication::records::TimingRow {
            stage: "figures".into(),
            seconds: t.elapsed().as_secs_f64(),
        });
        app::replication::records::write_csv(&cfg.results().join("timings.csv"), &timings)?;
        eprintln!(
            "experiments and figures: {:.1} s",
            t0.elapsed().as_secs_f64()
        );
    } else {
        app::replication::figures::plots_from_csv(&cfg)?;
    }
    app::replication::report::write(&cfg, &root)?;
    eprintln!("wrote {}", cfg.out.join("REPORT.md").display());
    Ok(())
}

/// Runs the command; a user error is one clean line on stderr (`error: ...` with its causes)
/// and exit status 1, whatever `RUST_BACKTRACE` says.
fn main() -> std::process::ExitCode {
    limit_malloc_arenas();
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, each cause once: the library's errors show their
/// cause in their own message (so that they read whole alone, e.g. from Python), which
/// anyhow's `{:#}` would repeat ("x.msh: No such file …: No such file …").
fn one_line(e: &anyhow::Error) -> String {
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

/// One malloc arena for all threads (glibc), unless `MALLOC_ARENA_MAX` says otherwise.
///
/// glibc gives each thread that allocates (here rayon's workers) its own arena and returns
/// the freed memory of those arenas to the system far less readily than that of the main
/// one, so the vectors freed between two active-set steps stayed resident. Measured with
/// `gradvi solve problems/ex9.toml --scheme p1 --generate triangles --level 9` (1M unknowns,
/// 2 cores, three runs each): peak resident memory 1505–1568 MB with glibc's default, 1366–1378
/// MB with one arena, 1393–1450 MB with two; total time 6.9–7.9 s and 6.7–7.3 s (unchanged
/// within the noise). The
/// benchmark's cases run this binary, so they measure the same setting. (Also measured:
/// mimalloc, 1636–1679 MB; a fixed mmap threshold of 128 kB, 1323–1341 MB but 30% slower
/// from the page faults of fresh mappings.) Those faults remain the cost of the large arrays
/// each active-set step allocates and frees (above glibc's 32 MB mmap limit they are always
/// fresh mappings): at 4M unknowns the kernel's page zeroing (`clear_page_erms`) is 15% of
/// the profile. No mmap at all (`MALLOC_MMAP_MAX_=0`, no trimming) was 12–20% faster at 1M
/// unknowns but raised the peak from 1041–1043 to 1256–1257 MB (two runs each, a loaded
/// machine); reusing those arrays across steps is the remedy that keeps both. (Also measured
/// and rejected: a global allocator asking `madvise(MADV_HUGEPAGE)` for every block of 4 MB or
/// more, against those faults: ex9 HMM at 1024² cells took 6.1–8.0 s instead of 5.2–6.1 s,
/// its kernel time 3.4–4.0 s instead of 1.3–1.6 s, the huge pages being compacted and zeroed
/// on the fault path; two runs each, alternating.)
fn limit_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        use std::ffi::c_int;
        unsafe extern "C" {
            fn mallopt(param: c_int, value: c_int) -> c_int;
        }
        /// `M_ARENA_MAX` of glibc's `<malloc.h>`.
        const M_ARENA_MAX: c_int = -8;
        // SAFETY: mallopt only sets a parameter of the allocator; it is called first thing in
        // main, before any other thread exists. A failure (return 0) leaves the default.
        unsafe {
            mallopt(M_ARENA_MAX, 1);
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match &cli.command {
        Command::Mesh(MeshCommand::Info { file }) => mesh_info(file),
        Command::Mesh(MeshCommand::Generate {
            family,
            level,
            output,
        }) => {
            let m = app::solve::generate(family, *level)?;
            match output.extension().and_then(|e| e.to_str()) {
                Some("typ2") => app::output::atomic(output, |tmp| Ok(write_typ2(tmp, &m)?))?,
                Some("vtu") => {
                    app::output::atomic(output, |tmp| Ok(write_vtu(tmp, &m, &[], &[])?))?
                }
                _ => bail!(
                    "unknown output format for {} (use .typ2 or .vtu)",
                    output.display()
                ),
            }
            eprintln!(
                "wrote {} ({} cells, h = {:.6})",
                output.display(),
                m.n_cells(),
                m.h()
            );
            Ok(())
        }
        Command::Solve(a) => app::solve::run(a),
        Command::Replicate(a) => replicate(a),
        Command::Crosscheck(a) => app::crosscheck::run(a),
        Command::Fuzz(a) => app::fuzz::run(a),
        Command::Bench { args } => {
            let root = std::env::current_dir()?;
            Ok(app::bench::main_with_args(&root, args)?)
        }
    }
}
