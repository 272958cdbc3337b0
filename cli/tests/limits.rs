//! The command line under real limits: an address-space limit (a typed out-of-memory error,
//! never an abort) and interrupts (a clear message, a nonzero status, no output left behind).

use std::process::Command;

/// The repository, where the commands run: the workspace root, above this package.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// `gradvi solve --problem test3 --generate cartesian --level 11` (16.8M cells, 50M
/// unknowns) under `ulimit -v` of 3 GiB: refused by the estimate of the mesh's memory before
/// anything large is allocated, with the estimate and what to do, in seconds; not
/// `memory allocation of … failed` and status 134 (abort).
#[cfg(target_os = "linux")]
#[test]
fn a_solve_too_large_for_the_address_space_limit_is_refused_with_the_estimate() {
    let t = std::time::Instant::now();
    let out = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 3145728 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_gradvi"))
        .args(["solve", "--problem", "test3", "--generate", "cartesian"])
        .args(["--level", "11"])
        .current_dir(ROOT)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run gradvi under ulimit -v");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("memory allocation of"), "{err}");
    assert!(err.contains("would need about"), "no estimate: {err}");
    assert!(err.contains("GiB"), "{err}");
    assert!(
        err.contains("coarser mesh") && err.contains("ulimit -v"),
        "{err}"
    );
    assert!(t.elapsed().as_secs() < 30, "took {:?}", t.elapsed());
}
