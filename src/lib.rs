//! gradvi (placeholder tour; written in full below once modules land)
#![warn(missing_docs)]
pub mod error;
pub mod mesh;
pub use error::{Error, MeshError, Result, SolverError};
