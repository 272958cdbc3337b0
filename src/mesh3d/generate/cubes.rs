//! Cartesian hexahedra: the n × n × n cubes of the grid (see [`grid`](super::grid) for the
//! numbering), each one cell with its six faces in the order x = x_i, x = x_{i+1}, y = y_j,
//! y = y_{j+1}, z = z_k, z = z_{k+1}, each listed counter-clockwise seen from outside.
//!
//! Counts: n³ cells, 6n³ face sides (3n²(n+1) faces, 6n² on the boundary), 24n³ face vertices,
//! (n+1)³ vertices.

use super::split::{self, CubeSplit};
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh3d::{Cuboid, Polyhedra};

/// The cube as one cell: its faces x−, x+, y−, y+, z−, z+ in local corners.
pub(crate) const CUBE: CubeSplit = &[&[
    &[0, 4, 6, 2],
    &[1, 3, 7, 5],
    &[0, 1, 5, 4],
    &[2, 6, 7, 3],
    &[0, 2, 3, 1],
    &[4, 5, 7, 6],
]];

/// The n × n × n cubes of `domain`. [`Error::InvalidData`](crate::Error::InvalidData) for
/// n = 0, a domain that is not a finite box, or more than
/// [`MAX_CELLS`](crate::mesh::generate::MAX_CELLS) cells;
/// [`MeshError::TooLarge`](crate::MeshError::TooLarge) if the description would not fit in
/// `budget` (checked before allocating).
pub fn cubes(n: usize, domain: Cuboid, budget: MemoryBudget) -> Result<Polyhedra> {
    let what = format!("a {n}³ mesh of cubes");
    split::build(&what, n, domain, budget, CUBE, |_, _| [0.0; 3])
}
