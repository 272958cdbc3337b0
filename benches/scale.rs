//! `make bench` / `cargo bench --bench scale`: the scaling benchmark (see `gradvi::bench`).
//! `cargo bench --bench scale -- --report-only` rewrites `replication/BENCHMARKS.md` from
//! `replication/results/bench.csv`.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Err(e) = gradvi::bench::main_with_args(root, &args) {
        eprintln!("bench: error: {e}");
        std::process::exit(1);
    }
}
