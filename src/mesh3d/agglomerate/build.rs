//! Step 3 of [`agglomerate3`](super::agglomerate3): the coarse mesh from the aggregates, and
//! the maps from the fine mesh to it.

use super::check::boundary_sides;
use super::{Agglomeration3, MIN_TASK, NO_FACE, Polyhedra, members};
use crate::error::MeshError;
use crate::mesh::MemoryBudget;
use crate::mesh3d::PolyMesh3;
use rayon::prelude::*;

/// Builds the coarse mesh whose cells are the aggregates `label` (dense, 0..) of `fine`: each
/// coarse cell lists the fine faces on its boundary, outward, its member cells in increasing
/// order and their faces in local order; cell tags from the members, boundary tags from the
/// fine boundary faces. The coarse mesh has at most as many face sides and loop entries as
/// the fine one, so its 32-bit offsets cannot overflow.
pub(super) fn build(
    fine: &PolyMesh3,
    label: Vec<usize>,
    dissolved_cells: usize,
    budget: MemoryBudget,
) -> Result<Agglomeration3, MeshError> {
    let (ptr, cells) = members(&label);
    let na = ptr.len() - 1;
    let sides: Vec<Vec<(u32, bool)>> = (0..na)
        .into_par_iter()
        .with_min_len(MIN_TASK / 16)
        .map(|a| {
            (cells[ptr[a]..ptr[a + 1]].iter())
                .flat_map(|&k| boundary_sides(fine, &label, a, k as usize))
                .collect()
        })
        .collect();
    let mut p = Polyhedra {
        vertices: fine.vertices().to_vec(),
        cell_ptr: vec![0],
        face_ptr: vec![0],
        cell_tags: (0..na)
            .map(|a| fine.cell_tag(cells[ptr[a]] as usize))
            .collect(),
        ..Polyhedra::default()
    };
    drop((ptr, cells));
    // the side index of each fine boundary face, until the coarse face ids are known
    let mut boundary_face_of = vec![NO_FACE; fine.n_faces()];
    for cell in &sides {
        for &(f, reversed) in cell {
            let l = fine.face_vertices(f as usize);
            if reversed {
                p.face_vertices.extend(l.iter().rev());
            } else {
                p.face_vertices.extend_from_slice(l);
            }
            if fine.is_boundary_face(f as usize) {
                boundary_face_of[f as usize] = (p.face_ptr.len() - 1) as u32;
            }
            p.face_ptr.push(p.face_vertices.len() as u32);
        }
        p.cell_ptr.push((p.face_ptr.len() - 1) as u32);
    }
    drop(sides);
    p.tagged_ptr.push(0);
    for &f in fine.boundary_faces() {
        let tag = fine.face_tag(f as usize);
        if tag != 0 {
            p.tagged_vertices
                .extend_from_slice(fine.face_vertices(f as usize));
            p.tagged_ptr.push(p.tagged_vertices.len() as u32);
            p.tagged_tags.push(tag);
        }
    }
    p.drop_unused_vertices();
    let mesh = PolyMesh3::from_polyhedra(p, budget)?;
    for &f in fine.boundary_faces() {
        let s = boundary_face_of[f as usize];
        let coarse = mesh.cell_faces.get(s as usize).copied().unwrap_or(NO_FACE);
        if coarse == NO_FACE || !mesh.is_boundary_face(coarse as usize) {
            return Err(MeshError::NonConforming(format!(
                "agglomeration lost the boundary face {f} ({:?})",
                fine.face_vertices(f as usize)
            )));
        }
        boundary_face_of[f as usize] = coarse;
    }
    Ok(Agglomeration3 {
        mesh,
        cell_of: label.into_iter().map(|a| a as u32).collect(),
        boundary_face_of,
        dissolved_cells,
    })
}
