//! Meshes made of the cubes of the grid, every cube cut into the same cells.
//!
//! A [`CubeSplit`] lists the cells of one cube, each as its faces, each face as a loop of the
//! cube's local corners (corner `dx + 2·dy + 4·dz`, see [`grid`](super::grid)), listed
//! counter-clockwise seen from outside the cell. The mesh of the n × n × n grid has, for every
//! cube in the order of its id, the cells of the split in their order. The split families are
//! conforming when the split of a cube face depends on that face alone, the same seen from both
//! cubes: true of the whole cube, of Kuhn's six tetrahedra and of the two prisms.

use super::fill::{Sink, fill_layers};
use super::grid::{self, cube_corners};
use super::{Counts3, check_request};
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh3d::{Cuboid, Point3, Polyhedra};

/// The cells of one cube: faces as loops of local corners (see the module docs).
pub(crate) type CubeSplit = &'static [&'static [&'static [u8]]];

/// Cells, face sides and face vertices of one split cube.
fn per_cube(split: CubeSplit) -> [u64; 3] {
    let sides = split.iter().map(|c| c.len()).sum::<usize>();
    let verts = split
        .iter()
        .flat_map(|c| c.iter())
        .map(|f| f.len())
        .sum::<usize>();
    [split.len(), sides, verts].map(|x| x as u64)
}

/// Cells, face sides, face vertices and vertices of the n × n × n grid split by `split`.
pub(crate) fn counts(n: usize, split: CubeSplit) -> Counts3 {
    let n = n as u64;
    let cubes = n.checked_mul(n)?.checked_mul(n)?;
    let n1 = n.checked_add(1)?;
    let [c, s, v] = per_cube(split);
    Some([
        cubes.checked_mul(c)?,
        cubes.checked_mul(s)?,
        cubes.checked_mul(v)?,
        n1.checked_mul(n1)?.checked_mul(n1)?,
    ])
}

/// The mesh of the n × n × n grid with these `vertices` (numbered as the grid points) whose
/// cubes are cut by `split`, filled one z-layer of cubes at a time in parallel. The counts must
/// have been checked to fit 32-bit offsets.
pub(crate) fn split_cubes(n: usize, vertices: Vec<Point3>, split: CubeSplit) -> Result<Polyhedra> {
    let [c, s, v] = per_cube(split).map(|x| x as usize * n * n);
    let layer_counts = vec![[c, s, v]; n];
    let [cell_ptr, face_ptr, face_vertices] = fill_layers(&layer_counts, |k, sink| {
        let mut face = [0u32; 4];
        for j in 0..n {
            for i in 0..n {
                let corners = cube_corners(n, [i, j, k]);
                for cell in split {
                    for f in *cell {
                        for (out, &c) in face.iter_mut().zip(*f) {
                            *out = corners[c as usize];
                        }
                        sink.face(&face[..f.len()]);
                    }
                    sink.end_cell();
                }
            }
        }
    })?;
    Ok(Polyhedra {
        vertices,
        cell_ptr,
        face_ptr,
        face_vertices,
        ..Polyhedra::default()
    })
}

/// The checked request (`what`, n, `domain`, `budget`: see [`check_request`]) built: the grid
/// points moved by `shift` (see [`grid::points`]), the cubes cut by `split`.
pub(crate) fn build(
    what: &str,
    n: usize,
    domain: Cuboid,
    budget: MemoryBudget,
    split: CubeSplit,
    shift: impl Fn(usize, [usize; 3]) -> Point3 + Sync,
) -> Result<Polyhedra> {
    check_request(what, n, domain, counts(n, split), 0, budget)?;
    let axes = grid::axes(domain, n)?;
    split_cubes(n, grid::points(&axes, shift)?, split)
}
