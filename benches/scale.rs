//! `make bench` / `cargo bench --bench scale`: the scaling benchmark, run by the `gradvi` binary
//! (`gradvi bench`, `src/app/bench.rs`) from the repository root.
//! `cargo bench --bench scale -- --report-only` rewrites `replication/BENCHMARKS.md` from
//! `replication/results/bench.csv`.
fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_gradvi"))
        .arg("bench")
        .args(&args)
        .current_dir(root)
        .status();
    match status {
        Ok(s) if s.success() => {}
        Ok(s) => {
            eprintln!("bench: gradvi bench failed ({s})");
            std::process::exit(1);
        }
        Err(e) => {
            eprintln!("bench: cannot run gradvi: {e}");
            std::process::exit(1);
        }
    }
}
