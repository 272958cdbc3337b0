//! Helpers shared by the test binaries.
#![allow(dead_code)]
use std::path::PathBuf;

/// `../shared/meshes/fvca5` next to the repository, if present. Tests that need the original
/// FVCA5 files call this and return early (printing a message) when it is `None`.
pub fn fvca5_dir() -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes/fvca5");
    if d.is_dir() {
        Some(d)
    } else {
        eprintln!("skipping: ../shared/meshes/fvca5 is not present next to the repository");
        None
    }
}
