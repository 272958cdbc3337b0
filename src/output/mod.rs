//! Outputs: CSV, VTU, PNG plots, markdown.

pub mod plot;
