//! Randomly perturbed hexahedra: the cubes of the grid (numbered and listed as in
//! [`cubes`](super::cubes())) with every interior grid point moved, coordinate by coordinate,
//! by a random fraction of the grid step, so that the faces are no longer planar.
//!
//! Interior point p (0 < i, j, k < n), with id `id`, moves to
//!
//! ```text
//! p + A · (u₀ h_x, u₁ h_y, u₂ h_z),    u_a = 2 U(seed, 3·id + a) − 1 ∈ [−1, 1),
//! ```
//!
//! h_a the grid step along axis a and A = [`AMPLITUDE`] = 0.05. U(seed, m) ∈ [0, 1) is the
//! top 53 bits of SplitMix64's finaliser applied to `seed + finaliser(m)`: a function of the
//! seed and the point alone, so the mesh is the same whatever the order in which points are
//! filled. Points on the boundary stay on the grid, so the boundary faces are planar rectangles
//! and the mesh covers the box exactly.
//!
//! The amplitude: every point stays within A h_a of its grid position along each axis, so a face
//! (a rectangle of sides h_a, h_b) has its four vertices within A h of the rectangle's plane,
//! its warp (largest distance of a vertex from the plane through x_σ normal to n_σ, over the
//! face's diameter, see [`validate`](crate::mesh3d::validate)) is at most about
//! 2A h / (√2 h) = √2 A ≈ 0.07 for a cube, below [`WARP_TOL`](crate::mesh3d::WARP_TOL) = 0.1,
//! and the cells, moved by a twentieth of their size, stay star-shaped with respect to their
//! centroid (the distance from the centre of a cube to its faces is h/2). The consistency
//! defect ‖Σ_σ |σ| n_{K,σ}(x_σ − x_K)ᵀ/|K| − I‖ that warped faces cause is of the order of the
//! warp (below twice the warp); the tests check it below 2 `WARP_TOL` on every cell of levels
//! 1 to 3.

use super::cubes::CUBE;
use super::split;
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh3d::{Cuboid, Polyhedra};

/// How far an interior point moves, per coordinate, as a fraction of the grid step.
pub const AMPLITUDE: f64 = 0.05;

/// The seed of the `warped` family ([`Family3::Warped`](super::Family3::Warped)).
pub const SEED: u64 = 0x3d_9e37_79b9;

/// The n × n × n cubes of `domain` with their interior points moved at random (see the module
/// docs), drawn from `seed`: the same seed gives the same mesh, bit for bit. Errors as
/// [`cubes`](super::cubes()).
pub fn warped(n: usize, domain: Cuboid, seed: u64, budget: MemoryBudget) -> Result<Polyhedra> {
    let what = format!("a {n}³ mesh of warped hexahedra");
    let h = domain.ranges().map(|r| (r[1] - r[0]) / n as f64);
    split::build(&what, n, domain, budget, CUBE, |id, p| {
        if p.iter().any(|&c| c == 0 || c == n) {
            return [0.0; 3];
        }
        std::array::from_fn(|a| {
            let u = uniform(seed, 3 * id as u64 + a as u64);
            AMPLITUDE * (2.0 * u - 1.0) * h[a]
        })
    })
}

/// The finaliser of SplitMix64: a bijection of u64 that mixes every input bit into every output
/// bit.
fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// U(seed, m) ∈ [0, 1): the top 53 bits of `mix(seed + mix(m))`.
fn uniform(seed: u64, m: u64) -> f64 {
    (mix(seed.wrapping_add(mix(m))) >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_are_uniform_looking_and_depend_on_the_seed() {
        let draws: Vec<f64> = (0..10_000).map(|m| uniform(SEED, m)).collect();
        assert!(draws.iter().all(|u| (0.0..1.0).contains(u)));
        let mean = draws.iter().sum::<f64>() / draws.len() as f64;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert_ne!(uniform(SEED, 7), uniform(SEED + 1, 7));
        assert_eq!(uniform(SEED, 7), uniform(SEED, 7));
    }
}
