//! `gradvi-dev`: gradvi's developer tools, apart from the `gradvi` binary that users install.
//!
//! - `gradvi-dev bench [ARGS]`: the benchmarks ([`mod@bench`]): the scaling benchmark (`make
//!   bench`), the peer benchmark (`--peers`, `make bench-peers`), the regression check against
//!   an earlier build (`--baseline EXE`, `make bench-baseline`), the report writer
//!   (`--report-only`) and the 3D mesh benchmark (`--mesh3d`: reading and building
//!   tetrahedral meshes); run from the repository root.
//! - `gradvi-dev fuzz [OPTIONS]`: the seeded mutation fuzzer ([`fuzz`], `make fuzz`).
//! - `gradvi-dev gradvi ARGS`: the `gradvi` command line itself ([`gradvi_cli`]), run by the
//!   fuzzer's children unless it is given a `gradvi` binary.
//!
//! The benchmark's cases run in child processes of this binary (`gradvi-dev bench --child …`),
//! with the same arguments that drive an earlier build's `gradvi bench --child …` (the builds
//! before the workspace, such as the regression check's default revision, had the benchmark
//! in their `gradvi` binary). A user error is one line on stderr and exit status 1.

mod bench;
mod fuzz;

use clap::{Parser, Subcommand};
use std::ffi::OsString;
use std::process::ExitCode;

/// gradvi's developer tools: benchmarks, regression check, fuzzer.
#[derive(Parser)]
#[command(name = "gradvi-dev", about, long_about = None)]
struct Dev {
    #[command(subcommand)]
    command: DevCommand,
}

#[derive(Subcommand)]
enum DevCommand {
    /// The benchmarks, run from the repository root (see README "Performance"): no argument
    /// runs the scaling benchmark; `--peers` the peer benchmark; `--baseline EXE
    /// [--baseline-rev REV]` the regression check against an earlier gradvi build;
    /// `--report-only` rewrites BENCHMARKS.md (and REGRESSION.md) from the CSV files;
    /// `--mesh3d` times reading and building tetrahedral meshes of the unit cube;
    /// `--peers3d` the 3D peer benchmark; `--domains3d` the 3D any-domain benchmark;
    /// `--hmm3d` HMM on n³ cubes of (−2,2)³ (target 5: 200³ cubes within 24 GiB).
    Bench {
        /// Arguments passed to the benchmark driver.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Seeded mutation fuzzing of the readers, validation and solver (run by `make fuzz`).
    Fuzz(fuzz::FuzzArgs),
}

fn main() -> ExitCode {
    gradvi_cli::tune_malloc();
    let args: Vec<OsString> = std::env::args_os().collect();
    // `gradvi-dev gradvi ARGS` is `gradvi ARGS`, its arguments untouched by this parser
    if args.get(1).is_some_and(|a| a == "gradvi") {
        return gradvi_cli::main_with_args(&args[1..]);
    }
    let result = match Dev::parse_from(args).command {
        DevCommand::Bench { args } => std::env::current_dir()
            .map_err(anyhow::Error::from)
            .and_then(|root| Ok(bench::main_with_args(&root, &args)?)),
        DevCommand::Fuzz(a) => fuzz::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", gradvi_cli::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
