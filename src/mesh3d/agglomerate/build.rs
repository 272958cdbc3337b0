//! Step 3 of [`agglomerate3`](super::agglomerate3): the coarse mesh from the aggregates, and
//! the maps from the fine mesh to it.

use super::check::boundary_sides;
use super::merge::{self, Interfaces, Scratch};
use super::{Agglomeration3, MIN_TASK, NO_FACE, Polyhedra, members};
use crate::budget::MemoryBudget;
use crate::error::MeshError;
use crate::mesh3d::PolyMesh3;
use rayon::prelude::*;

/// Builds the coarse mesh whose cells are the aggregates `label` (dense, 0..) of `fine`: each
/// coarse cell lists, outward, the fine boundary faces of its member cells (members in
/// increasing order, their faces in local order), then its merged faces toward aggregates of
/// higher index ([`merge::interfaces`]), then those of lower index; cell tags from the
/// members, boundary tags from the fine boundary faces. The coarse mesh has at most as many
/// face sides and loop entries as the fine one, so its 32-bit offsets cannot overflow.
pub(super) fn build(
    fine: &PolyMesh3,
    label: Vec<usize>,
    dissolved_cells: usize,
    boundary_key: Option<&[u32]>,
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
    let (merged, bnd): (Vec<Interfaces>, Vec<merge::BoundaryFaces>) = (0..na)
        .into_par_iter()
        .with_min_len(MIN_TASK / 16)
        .map_init(Scratch::default, |s, a| {
            (
                merge::interfaces(fine, &label, a, &sides[a], s),
                merge::boundary(fine, boundary_key, &sides[a], s),
            )
        })
        .unzip();
    // the merged faces each aggregate b receives from the aggregates c < b: (c, face of c)
    let (in_ptr, incoming) = crate::mesh::buckets::counting_sort(
        na,
        merged
            .iter()
            .flat_map(|m| m.faces.iter().map(|&(b, _)| Some(b as usize))),
        |i| i,
    );
    let face_owner: Vec<(u32, u32)> = (merged.iter().enumerate())
        .flat_map(|(c, m)| (0..m.faces.len()).map(move |j| (c as u32, j as u32)))
        .collect();
    // the side index of each fine boundary face, until the coarse face ids are known
    let mut boundary_face_of = vec![NO_FACE; fine.n_faces()];
    p.tagged_ptr.push(0);
    for (a, b) in bnd.iter().enumerate() {
        push_boundary(fine, &mut p, b, &mut boundary_face_of);
        for j in 0..merged[a].faces.len() {
            p.face_vertices.extend_from_slice(merged[a].face_loop(j));
            p.face_ptr.push(p.face_vertices.len() as u32);
        }
        for &i in &incoming[in_ptr[a]..in_ptr[a + 1]] {
            let (c, j) = face_owner[i];
            let l = merged[c as usize].face_loop(j as usize);
            p.face_vertices.extend(l.iter().rev());
            p.face_ptr.push(p.face_vertices.len() as u32);
        }
        p.cell_ptr.push((p.face_ptr.len() - 1) as u32);
    }
    drop((sides, merged, bnd, face_owner, incoming));
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

/// Appends the boundary faces `faces` of one aggregate to `p` with their tags (a merged face
/// has the tag of its fine faces, which share a key), and records the side of each fine
/// boundary face in `boundary_face_of`.
fn push_boundary(
    fine: &PolyMesh3,
    p: &mut Polyhedra,
    (faces, face_of): &merge::BoundaryFaces,
    boundary_face_of: &mut [u32],
) {
    let first = (p.face_ptr.len() - 1) as u32;
    for j in 0..faces.faces.len() {
        p.face_vertices.extend_from_slice(faces.face_loop(j));
        p.face_ptr.push(p.face_vertices.len() as u32);
    }
    for &(f, j) in face_of {
        boundary_face_of[f as usize] = first + j;
    }
    let mut tagged = (face_of.iter())
        .map(|&(f, j)| (j, fine.face_tag(f as usize)))
        .collect::<Vec<_>>();
    tagged.sort_unstable();
    tagged.dedup_by_key(|t| t.0);
    for (j, tag) in tagged.into_iter().filter(|t| t.1 != 0) {
        p.tagged_vertices
            .extend_from_slice(faces.face_loop(j as usize));
        p.tagged_ptr.push(p.tagged_vertices.len() as u32);
        p.tagged_tags.push(tag);
    }
}
