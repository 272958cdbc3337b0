//! The `gradvi` binary: the command line of [`gradvi_cli`].

fn main() -> std::process::ExitCode {
    gradvi_cli::tune_malloc();
    gradvi_cli::main_with_args(std::env::args_os())
}
