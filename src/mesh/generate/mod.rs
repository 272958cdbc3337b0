//! Deterministic mesh generators.
