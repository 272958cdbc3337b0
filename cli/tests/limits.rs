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

/// `gradvi solve` on `args` under `ulimit -v kib` (none: unlimited).
#[cfg(target_os = "linux")]
fn solve_limited(kib: Option<u64>, args: &[&str]) -> std::process::Output {
    let limit = kib.map_or(String::new(), |k| format!("ulimit -v {k} && "));
    Command::new("sh")
        .arg("-c")
        .arg(format!("{limit}exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_gradvi"))
        .arg("solve")
        .args(args)
        .current_dir(ROOT)
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("run gradvi")
}

/// The NITER line of a solve's output.
fn niter(stdout: &str) -> Option<&str> {
    stdout.lines().find(|l| l.starts_with("NITER"))
}

/// Test 3 with HMM on the 256 × 256 grid (131 000 condensed unknowns: faer factorises it
/// supernodally, so the factorisation runs faer's dense product kernel, whose per-thread
/// workspace is twice the last-level cache size the system reports) with the direct solver,
/// under `ulimit -v` from 128 MiB to 8 GiB: every run ends with status 0 and the NITER of the
/// unlimited run, or with status 1 and the typed out-of-memory message (the estimate and what
/// to do); never `memory allocation of … failed`, an abort or a signal. The smallest limit is
/// refused, the largest solves, whatever the machine's cache sizes.
#[cfg(target_os = "linux")]
#[test]
fn a_direct_solve_under_a_sweep_of_address_space_limits_solves_or_is_refused() {
    let args = [
        "--problem",
        "test3",
        "--generate",
        "cartesian",
        "--level",
        "7",
        "--linear",
        "direct",
    ];
    let free = solve_limited(None, &args);
    let said = String::from_utf8_lossy(&free.stdout).to_string();
    assert!(
        free.status.success(),
        "{}",
        String::from_utf8_lossy(&free.stderr)
    );
    let expected = niter(&said).expect("no NITER").to_string();
    let mut solved = Vec::new();
    for mib in [128u64, 256, 384, 512, 768, 1024, 1536, 2048, 3072, 8192] {
        let out = solve_limited(Some(mib << 10), &args);
        let err = String::from_utf8_lossy(&out.stderr);
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(!err.contains("memory allocation of"), "{mib} MiB: {err}");
        match out.status.code() {
            Some(0) => {
                assert_eq!(niter(&said), Some(expected.as_str()), "{mib} MiB");
                solved.push(true);
            }
            Some(1) => {
                assert!(
                    err.contains("would need about") && err.contains("ulimit -v"),
                    "{mib} MiB: not the typed out-of-memory error: {err}"
                );
                solved.push(false);
            }
            _ => panic!("{mib} MiB: ended with {}: {err}", out.status),
        }
    }
    assert_eq!(solved.first(), Some(&false), "{solved:?}");
    assert_eq!(solved.last(), Some(&true), "{solved:?}");
}
