//! A smoke run of the whole replication pipeline (`gradvi replicate --quick`) into a temporary
//! directory: the report names every table and figure, the figures are PNG files, the CSV files
//! are written.

use std::path::{Path, PathBuf};

/// The repository: the workspace root, above this package.
fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

#[test]
fn quick_replication_writes_csv_figures_and_report() {
    // the replication is an application of the library: run it through the `gradvi` binary
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("replicate-test-{}", std::process::id()));
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_gradvi"))
        .args(["replicate", "--quick", "--out"])
        .arg(&out)
        .arg("--meshes")
        .arg(root().join("meshes"))
        .arg("--paper")
        .arg(root().join("replication/paper"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success(),
        "gradvi replicate --quick failed: {stderr}"
    );
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    for needle in [
        "Table 1",
        "Table 2",
        "Table 3",
        "Figure 4.1",
        "Figure 4.5",
        "paper",
    ] {
        assert!(report.contains(needle), "REPORT.md lacks {needle}");
    }
    for f in [
        "fig4_1_test1.png",
        "fig4_3_test2_hexagonal.png",
        "fig4_5_test3.png",
        "test3_niter.png",
    ] {
        let bytes = std::fs::read(out.join("figures").join(f)).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{f}");
    }
    for f in [
        "test1.csv",
        "test2.csv",
        "test3.csv",
        "iterations.csv",
        "timings.csv",
    ] {
        assert!(out.join("results").join(f).is_file(), "{f}");
    }
    assert!(stderr.lines().count() > 10, "progress lines on stderr");
    std::fs::remove_dir_all(&out).ok();
}
