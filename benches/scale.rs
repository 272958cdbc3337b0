//! `make bench` / `cargo bench --bench scale`: the scaling benchmark (see `gradvi::bench`).
fn main() {
    eprintln!("the benchmark driver is being written (issue: performance and scale)");
}
