//! The CSV schemas of `replication/results/` and of the paper's values, with readers and
//! writers. Every table, plot and report is made from these files.

use gradvi::solver::IterationStep;
use serde::{Deserialize, Serialize, de::DeserializeOwned};
use std::path::Path;

/// One row of `results/meshes.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MeshRow {
    /// Mesh name.
    pub mesh: String,
    /// Where it comes from (gmsh file, generator, FVCA5 file).
    pub source: String,
    /// Number of cells.
    pub n_cells: usize,
    /// Number of vertices.
    pub n_vertices: usize,
    /// Number of edges.
    pub n_edges: usize,
    /// h = max cell diameter.
    pub h: f64,
    /// Boundary edges on x = 0.
    pub edges_x0: usize,
    /// Boundary edges on y = 0.
    pub edges_y0: usize,
}

/// One row of `results/test1.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Test1Row {
    /// hmm or p1.
    pub scheme: String,
    /// Mesh name.
    pub mesh: String,
    /// Mesh size.
    pub h: f64,
    /// Number of cells.
    pub n_cells: usize,
    /// Number of edges on Γ3.
    pub n_gamma3: usize,
    /// Linear solves of the monotony algorithm.
    pub niter: usize,
    /// Abscissa on Γ3 where the constraint switches (NaN if none).
    pub switch_x: f64,
    /// Its resolution (± half the spacing of the unknowns around it).
    pub switch_half_gap: f64,
    /// Number of switches along Γ3.
    pub switch_count: usize,
    /// Certificate: worst scaled quantity.
    pub certificate: f64,
    /// Total solve time, seconds.
    pub time_s: f64,
}

/// One row of `results/test2.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Test2Row {
    /// hmm or p1.
    pub scheme: String,
    /// hexagonal, kershaw, triangles, or fvca5-file.
    pub family: String,
    /// Mesh name.
    pub mesh: String,
    /// Mesh size.
    pub h: f64,
    /// Number of cells.
    pub n_cells: usize,
    /// Number of edges on Γ3.
    pub n_gamma3: usize,
    /// Relative L² error of u at the centroids.
    pub err_u: f64,
    /// Relative L² error of the cell gradients.
    pub err_grad: f64,
    /// Linear solves.
    pub niter: usize,
    /// Ordinate on Γ3 where the constraint switches (NaN if none).
    pub switch_y: f64,
    /// Number of switches along Γ3.
    pub switch_count: usize,
    /// Certificate: worst scaled quantity.
    pub certificate: f64,
    /// Total solve time, seconds.
    pub time_s: f64,
}

/// One row of `results/test3.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Test3Row {
    /// hmm or p1.
    pub scheme: String,
    /// Mesh name.
    pub mesh: String,
    /// Mesh size.
    pub h: f64,
    /// Number of cells (#M).
    pub n_cells: usize,
    /// The constant C.
    pub c: f64,
    /// Linear solves.
    pub niter: usize,
    /// Number of active (contact) unknowns.
    pub n_active: usize,
    /// Measure of the contact set.
    pub contact_area: f64,
    /// Certificate: worst scaled quantity.
    pub certificate: f64,
    /// Total solve time, seconds.
    pub time_s: f64,
}

/// Which solve a row belongs to.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Run {
    /// test1, test2, test3_C-5, …
    pub case: String,
    /// hmm or p1.
    pub scheme: String,
    /// Mesh name.
    pub mesh: String,
}

/// One row of `results/iterations.csv`, a line of the log of the monotony algorithm: the
/// columns of the [`Run`], then those of the [`IterationStep`].
#[derive(Debug, Clone)]
pub struct IterationRow {
    /// The solve.
    pub run: Run,
    /// Its iteration.
    pub step: IterationStep,
}

impl Serialize for IterationRow {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // a pair of structs is one CSV record with the fields of both (the csv crate writes no
        // nested struct, nor a `#[serde(flatten)]` map)
        (&self.run, &self.step).serialize(s)
    }
}

/// One row of `results/timings.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TimingRow {
    /// What was timed.
    pub stage: String,
    /// Seconds.
    pub seconds: f64,
}

/// The paper's Table 1 (stored as data in `paper/table1.csv`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PaperTable1 {
    /// Mesh size.
    pub h: f64,
    /// #{σ ⊂ Γ3}.
    pub n_gamma3: usize,
    /// NITER.
    pub niter: usize,
}

/// The paper's Table 2 and the Kershaw line (`paper/table2.csv`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PaperTable2 {
    /// hexagonal or kershaw.
    pub family: String,
    /// Mesh size as printed.
    pub h: f64,
    /// Relative L² error of u.
    pub err_u: f64,
    /// Relative L² error of ∇u.
    pub err_grad: f64,
    /// #{σ ⊂ Γ3}.
    pub n_gamma3: usize,
    /// NITER.
    pub niter: usize,
}

/// The paper's Table 3 (`paper/table3.csv`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PaperTable3 {
    /// Mesh size as printed.
    pub h: f64,
    /// #M.
    pub n_cells: usize,
    /// C.
    pub c: f64,
    /// NITER.
    pub niter: usize,
}

/// Writes rows to a CSV file (header from the field names).
pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> gradvi::Result<()> {
    let err = |e: csv::Error| gradvi::Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    };
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    for r in rows {
        w.serialize(r).map_err(err)?;
    }
    w.flush().map_err(|source| gradvi::Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads rows from a CSV file with a header. Comment lines starting with `#` are skipped.
pub fn read_csv<T: DeserializeOwned>(path: &Path) -> gradvi::Result<Vec<T>> {
    let err = |e: csv::Error| gradvi::Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    };
    let mut r = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(err)?;
    r.deserialize().map(|x| x.map_err(err)).collect()
}
