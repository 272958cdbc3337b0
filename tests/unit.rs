//! Unit-tier tests (fast): exactness, readers, generators, solver certificates.
//! One binary pulling in submodules, so linking stays fast.
mod common;
#[path = "unit/cr.rs"]
mod cr;
#[path = "unit/generators.rs"]
mod generators;
#[path = "unit/linear_solver.rs"]
mod linear_solver;
#[path = "unit/mesh_io.rs"]
mod mesh_io;
#[path = "unit/mesh_validity.rs"]
mod mesh_validity;
#[path = "unit/schemes3d.rs"]
mod schemes3d;
#[path = "unit/solver.rs"]
mod solver;
#[path = "unit/warm_start.rs"]
mod warm_start;
#[path = "unit/well_posed.rs"]
mod well_posed;
