//! Kuhn's tetrahedra: every cube of the grid cut into six tetrahedra around its main diagonal
//! from corner 0 = (x_i, y_j, z_k) to corner 7 = (x_{i+1}, y_{j+1}, z_{k+1}).
//!
//! For each permutation (a, b, c) of the axes, the tetrahedron with vertices corner 0,
//! 0 + e_a, 0 + e_a + e_b, corner 7 (the monotone path from 0 to 7 along a, then b, then c):
//! in local corners (x = 1, y = 2, z = 4), xyz = (0, 1, 3, 7), xzy = (0, 1, 5, 7),
//! yxz = (0, 2, 3, 7), yzx = (0, 2, 6, 7), zxy = (0, 4, 5, 7), zyx = (0, 4, 6, 7), each of
//! volume |cube|/6. Every cube face is cut by its diagonal from its lowest to its highest corner,
//! whichever of its two cubes looks at it, so the tetrahedra are conforming across cubes (the
//! Freudenthal–Kuhn triangulation). Faces are listed counter-clockwise seen from outside: for
//! a positively oriented (p₀, p₁, p₂, p₃), the faces (p₀, p₂, p₁), (p₀, p₁, p₃), (p₀, p₃, p₂),
//! (p₁, p₂, p₃); the odd permutations xzy, yxz and zyx are listed with p₁ and p₂ swapped.
//!
//! Counts: 6n³ cells, 24n³ face sides, 72n³ face vertices, (n+1)³ vertices.

use super::split::{self, CubeSplit};
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh3d::{Cuboid, Polyhedra};

/// The six tetrahedra xyz, xzy, yxz, yzx, zxy, zyx of a cube, faces in local corners.
pub(crate) const KUHN: CubeSplit = &[
    &[&[0, 3, 1], &[0, 1, 7], &[0, 7, 3], &[1, 3, 7]],
    &[&[0, 1, 5], &[0, 5, 7], &[0, 7, 1], &[5, 1, 7]],
    &[&[0, 2, 3], &[0, 3, 7], &[0, 7, 2], &[3, 2, 7]],
    &[&[0, 6, 2], &[0, 2, 7], &[0, 7, 6], &[2, 6, 7]],
    &[&[0, 5, 4], &[0, 4, 7], &[0, 7, 5], &[4, 5, 7]],
    &[&[0, 4, 6], &[0, 6, 7], &[0, 7, 4], &[6, 4, 7]],
];

/// The n × n × n cubes of `domain` cut into 6n³ tetrahedra. Errors as
/// [`cubes`](super::cubes()), with 6n³ cells against the limit.
pub fn kuhn(n: usize, domain: Cuboid, budget: MemoryBudget) -> Result<Polyhedra> {
    let what = format!("a mesh of 6 × {n}³ Kuhn tetrahedra");
    split::build(&what, n, domain, budget, KUHN, |_, _| [0.0; 3])
}
