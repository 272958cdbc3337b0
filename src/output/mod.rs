//! Outputs: CSV, VTU, PNG plots, markdown.
