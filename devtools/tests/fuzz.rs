//! A short deterministic slice of the fuzzer (`make fuzz` runs it for minutes): seeded
//! mutations of the good meshes and problem files through `gradvi solve`, and of the 3D meshes
//! through `gradvi mesh info` (the command line run by `gradvi-dev gradvi`), each in a child
//! process under a memory and a time limit; every case must end with a certified solution, a
//! validated 3D mesh or a one-line typed error, never a panic, an abort or a hang; and requests
//! of huge generated meshes, run first, must be refused for memory under the limit.

/// Runs `gradvi-dev fuzz --seed seed --iterations n` with `extra` arguments on the repository
/// and returns its summary line, after checking that it succeeded with `n` cases.
fn fuzz(seed: u64, n: usize, extra: &[&str]) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gradvi-dev"))
        .args([
            "fuzz",
            "--seed",
            &seed.to_string(),
            "--iterations",
            &n.to_string(),
        ])
        .args([
            "--seconds",
            "240",
            "--case-seconds",
            "30",
            "--memory-mib",
            "4096",
        ])
        .args(extra)
        // the repository: the workspace root, above this package
        .arg("--root")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains(&format!("fuzz: {n} cases")), "{err}");
    // the fixed cases: a 2D solve and a 3D mesh of huge generated levels, refused with the
    // typed out-of-memory error under the memory limit (never an abort)
    assert!(
        err.contains("2 of 2 huge requests refused for memory under the limit of 4096 MiB"),
        "{err}"
    );
    err.lines()
        .find(|l| l.starts_with("fuzz: "))
        .unwrap_or_default()
        .to_string()
}

/// The number before `what` in the summary line.
fn count(summary: &str, what: &str) -> usize {
    summary
        .split([':', ','])
        .find_map(|p| {
            p.trim()
                .strip_suffix(what)
                .and_then(|n| n.trim().parse().ok())
        })
        .unwrap_or(0)
}

#[test]
fn forty_seeded_mutations_end_cleanly() {
    // the slice exercises all outcomes: some mutants are valid inputs, solved and certified or
    // (3D meshes) read and validated; most are refused
    let summary = fuzz(6, 40, &[]);
    assert!(count(&summary, "solved and certified") > 0, "{summary}");
    assert!(
        count(&summary, "3D meshes read and validated") > 0,
        "{summary}"
    );
    assert!(
        count(&summary, "refused with a typed error") > 0,
        "{summary}"
    );
}

#[test]
fn forty_seeded_mutations_of_3d_meshes_end_cleanly() {
    let summary = fuzz(7, 40, &["--only-3d"]);
    assert!(
        count(&summary, "3D meshes read and validated") > 0,
        "{summary}"
    );
    assert!(
        count(&summary, "refused with a typed error") > 0,
        "{summary}"
    );
    assert_eq!(count(&summary, "solved and certified"), 0, "{summary}");
}
