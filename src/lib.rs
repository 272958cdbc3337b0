//! gradvi (tour written below)
#![warn(missing_docs)]
pub mod assembly;
pub mod error;
pub mod mesh;
pub mod output;
pub mod post;
pub mod problem;
pub mod replication;
pub mod scheme;
pub mod solver;
pub use error::{Error, MeshError, Result, SolverError};
