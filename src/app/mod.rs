//! The applications built on the gradvi library, compiled into the `gradvi` binary only: the
//! replication of the paper, the cross-check against dolfinx, the scaling benchmark, and the
//! plots they draw. The library (`src/lib.rs`) does not depend on any of this.

pub mod bench;
pub mod crosscheck;
pub mod fuzz;
pub mod markdown;
pub mod output;
pub mod plot;
pub mod replication;
pub mod solve;
