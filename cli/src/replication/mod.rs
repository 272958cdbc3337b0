//! Replication of the paper's Section 4: Tests 1–3, Tables 1–3 and Figures 4.1–4.5.
//!
//! The pipeline is CSV-centred:
//! 1. [`experiments::run`] solves every case (HMM and, as an extension, P1) and writes
//!    `results/*.csv` (one row per solve, plus per-iteration logs and mesh statistics);
//! 2. [`figures::run`] draws the figures (PNG) and writes VTU files of the plotted solutions;
//! 3. [`report::write`] reads *only* the CSV files (ours and the paper's values, stored as data
//!    in `replication/paper/`) and writes `REPORT.md`.
//!
//! Paths: meshes are read from `meshes/` (the committed gmsh files) or built by the generators
//! (hexagonal, Kershaw); the original FVCA5 files are used too when a directory is given.
//!
//! Beyond the paper, [`three_d`] solves 3D problems with exact solutions in the same steps:
//! `results/convergence3d.csv`, its figures and `REPORT-3D.md`.

pub mod experiments;
pub mod figures;
pub mod records;
pub mod report;
pub mod three_d;

use std::path::PathBuf;

/// What to run and where.
#[derive(Debug, Clone)]
pub struct Config {
    /// The replication directory (`replication/`): results/, figures/, REPORT.md go there.
    pub out: PathBuf,
    /// The directory of the committed gmsh meshes (`meshes/`).
    pub meshes: PathBuf,
    /// Optional directory with the original FVCA5 files (hexa1_*.typ2, mesh4_1_2.typ2).
    pub fvca5: Option<PathBuf>,
    /// The directory of the paper's values (`replication/paper`).
    pub paper: PathBuf,
    /// Coarsest meshes only (a smoke run).
    pub quick: bool,
}

impl Config {
    /// `out/results`.
    pub fn results(&self) -> PathBuf {
        self.out.join("results")
    }
    /// `out/figures`.
    pub fn figures(&self) -> PathBuf {
        self.out.join("figures")
    }
    /// `out/vtu` (not committed).
    pub fn vtu(&self) -> PathBuf {
        self.out.join("vtu")
    }
}

/// Creates a directory and its parents, as a typed error.
pub fn create_dir(p: &std::path::Path) -> gradvi::Result<()> {
    std::fs::create_dir_all(p).map_err(|source| gradvi::Error::Io {
        path: p.to_path_buf(),
        source,
    })
}
