//! Triangular prisms: every cube of the grid cut into two by the vertical plane through its
//! edges (x_i, y_j)–(x_{i+1}, y_{j+1}) at z_k and z_{k+1}, its "lower-left to upper-right"
//! diagonal, the diagonal of the 2D `triangles` family extruded.
//!
//! In local corners (x = 1, y = 2, z = 4): prism A (below the diagonal, x > y) has the bottom
//! (0, 3, 1), the top (4, 5, 7), the faces y = y_j (0, 1, 5, 4) and x = x_{i+1} (1, 3, 7, 5)
//! and the cut (0, 4, 7, 3); prism B the bottom (0, 2, 3), the top (4, 7, 6), the faces
//! x = x_i (0, 4, 6, 2) and y = y_{j+1} (2, 6, 7, 3) and the cut (0, 3, 7, 4). All loops run
//! counter-clockwise seen from outside. The vertical cube faces are whole faces of one prism
//! each, and the horizontal ones are cut by the same diagonal from above and below, so the
//! prisms are conforming.
//!
//! Counts: 2n³ cells, 10n³ face sides, 36n³ face vertices, (n+1)³ vertices.

use super::split::{self, CubeSplit};
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh3d::{Cuboid, Polyhedra};

/// Prisms A and B of a cube, faces in local corners.
pub(crate) const PRISMS: CubeSplit = &[
    &[
        &[0, 3, 1],
        &[4, 5, 7],
        &[0, 1, 5, 4],
        &[1, 3, 7, 5],
        &[0, 4, 7, 3],
    ],
    &[
        &[0, 2, 3],
        &[4, 7, 6],
        &[0, 4, 6, 2],
        &[2, 6, 7, 3],
        &[0, 3, 7, 4],
    ],
];

/// The n × n × n cubes of `domain` cut into 2n³ prisms. Errors as [`cubes`](super::cubes()),
/// with 2n³ cells against the limit.
pub fn prisms(n: usize, domain: Cuboid, budget: MemoryBudget) -> Result<Polyhedra> {
    let what = format!("a mesh of 2 × {n}³ prisms");
    split::build(&what, n, domain, budget, PRISMS, |_, _| [0.0; 3])
}
