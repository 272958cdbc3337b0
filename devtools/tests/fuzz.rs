//! A short deterministic slice of the fuzzer (`make fuzz` runs it for minutes): 40 seeded
//! mutations of the good meshes and problem files through `gradvi solve` (the command line run
//! by `gradvi-dev gradvi`), each in a child process under a memory and a time limit; every case
//! must end with a certified solution or a one-line typed error, never a panic, an abort or a
//! hang.

#[test]
fn forty_seeded_mutations_end_cleanly() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gradvi-dev"))
        .args([
            "fuzz",
            "--seed",
            "7",
            "--iterations",
            "40",
            "--seconds",
            "240",
        ])
        .args(["--case-seconds", "30", "--memory-mib", "4096", "--root"])
        // the repository: the workspace root, above this package
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("fuzz: 40 cases"), "{err}");
    // the slice exercises both outcomes: some mutants are valid inputs, solved and certified;
    // most are refused
    let summary = err
        .lines()
        .find(|l| l.starts_with("fuzz: "))
        .unwrap_or_default();
    let count = |what: &str| -> usize {
        summary
            .split([':', ','])
            .find_map(|p| {
                p.trim()
                    .strip_suffix(what)
                    .and_then(|n| n.trim().parse().ok())
            })
            .unwrap_or(0)
    };
    assert!(count("solved and certified") > 0, "{summary}");
    assert!(count("refused with a typed error") > 0, "{summary}");
}
