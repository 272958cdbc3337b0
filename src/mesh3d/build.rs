//! Building a [`PolyMesh3`] from a [`Polyhedra`]: checks on the input, memory estimate, face
//! matching, orientation, geometry, then the checks on the geometry (the list is in
//! [`validate`](super::validate)).

use super::faces::{NO_SIDE, match_faces, same_direction, side_cells};
use super::geometry::{cell_volume_centroid, diameter, face_geometry, norm, vertex_average};
use super::orient::orient_cells;
use super::validate::{check_cells, check_offsets, check_vertices};
use super::{PolyMesh3, Polyhedra};
use crate::error::MeshError;
use crate::mesh::MemoryBudget;
use rayon::prelude::*;

/// Estimated peak memory, in bytes, of [`PolyMesh3::from_polyhedra`] on a [`Polyhedra`] with
/// `cells` cells, `sides` face sides (faces counted once per cell), `side_vertices` entries in
/// the face loops and `vertices` vertices, on top of the [`Polyhedra`] itself.
///
/// Per vertex: 24 bytes of coordinates, 4 of sort order, 1 of use flag. Per cell: 4 (offset),
/// 8 (volume), 24 (centroid), 8 (diameter), 4 (tag). Per side: 4 (its cell), 4 (sort order),
/// 4 (partner side), 4 (its face), 1 (orientation), 4 (face id in the cell's list). Per face,
/// counting as many faces as sides (an upper bound): 8 (sides), 4 (offset), 8 (cells), 4
/// (tag), 8 (area), 24 (centroid), 24 (normal), 4 (boundary list). Per loop entry: 4 (sorted
/// key), 4 (stored loop), and 16 for the directed boundary edges and 24 for the corners of the
/// boundary surface checks (counting every loop entry as a boundary one, an upper bound).
pub fn mesh3_bytes(cells: u64, sides: u64, side_vertices: u64, vertices: u64) -> u64 {
    let per_vertex = 24 + 4 + 1;
    let per_cell = 4 + 8 + 24 + 8 + 4;
    let per_side = (4 + 4 + 4 + 4 + 1 + 4) + (8 + 4 + 8 + 4 + 8 + 24 + 24 + 4);
    let per_loop_entry = 4 + 4 + 16 + 24;
    cells
        .saturating_mul(per_cell)
        .saturating_add(sides.saturating_mul(per_side))
        .saturating_add(side_vertices.saturating_mul(per_loop_entry))
        .saturating_add(vertices.saturating_mul(per_vertex))
}

impl PolyMesh3 {
    /// Builds and validates the mesh described by `p` (see [`crate::mesh3d`] for the geometry
    /// and [`validate`](super::validate) for the checks, each a typed error naming the cell,
    /// face, edge or vertex at fault). The memory needed ([`mesh3_bytes`]) is compared with
    /// `budget` before anything large is allocated.
    pub fn from_polyhedra(p: Polyhedra, budget: MemoryBudget) -> Result<PolyMesh3, MeshError> {
        check_offsets(&p)?;
        check_cells(&p)?;
        let sides = p.face_ptr.len() - 1;
        let bytes = mesh3_bytes(
            p.n_cells() as u64,
            sides as u64,
            p.face_vertices.len() as u64,
            p.vertices.len() as u64,
        );
        budget.check(
            format!("a 3D mesh of {} cells and {sides} face sides", p.n_cells()),
            bytes,
        )?;
        check_vertices(&p)?;
        let side_cell = side_cells(&p);
        let matched = match_faces(&p, &side_cell)?;
        let inward = orient_cells(&p)?;
        let mut m = assemble(
            &p,
            &side_cell,
            &matched.face_of_side,
            &matched.face_sides,
            &inward,
        )?;
        drop((side_cell, matched, inward));
        m.compute_face_geometry()?;
        m.compute_cell_geometry()?;
        m.check_shapes()?;
        m.check_boundary_surface()?;
        m.check_overlap()?;
        m.cell_tags = if p.cell_tags.is_empty() {
            vec![0; p.n_cells()]
        } else {
            p.cell_tags.clone()
        };
        m.set_face_tags(&p)?;
        Ok(m)
    }
}

/// The topology of the mesh (face loops, incidences, boundary list), geometry left empty:
/// every face's loop is the outward loop of its first side, checked against its second.
fn assemble(
    p: &Polyhedra,
    side_cell: &[u32],
    face_of_side: &[u32],
    face_sides: &[[u32; 2]],
    inward: &[bool],
) -> Result<PolyMesh3, MeshError> {
    let n_faces = face_sides.len();
    let mut face_ptr = Vec::with_capacity(n_faces + 1);
    face_ptr.push(0u32);
    let mut face_verts = Vec::new();
    let mut face_cells = Vec::with_capacity(n_faces);
    for &[s, t] in face_sides {
        let l = p.side_vertices(s as usize);
        let start = face_verts.len();
        if inward[s as usize] {
            face_verts.extend(l.iter().rev());
        } else {
            face_verts.extend_from_slice(l);
        }
        face_ptr.push(face_verts.len() as u32);
        let second = if t == NO_SIDE {
            u32::MAX
        } else {
            let stored = &face_verts[start..];
            let other = p.side_vertices(t as usize);
            let cells = [
                side_cell[s as usize] as usize,
                side_cell[t as usize] as usize,
            ];
            let bad = |msg: &str| MeshError::InconsistentFace {
                cells,
                vertices: l.iter().map(|&v| v as usize).collect(),
                msg: msg.into(),
            };
            match same_direction(stored, other) {
                None => return Err(bad("list its vertices in different cyclic orders")),
                // the second cell's outward loop must be the reverse of the first's
                Some(same) if same != inward[t as usize] => {
                    return Err(bad(
                        "both lie on the same side of it (their outward normals agree)",
                    ));
                }
                Some(_) => side_cell[t as usize],
            }
        };
        face_cells.push([side_cell[s as usize], second]);
    }
    let boundary_faces = (0..n_faces as u32)
        .filter(|&f| face_cells[f as usize][1] == u32::MAX)
        .collect();
    Ok(PolyMesh3 {
        vertices: p.vertices.clone(),
        cell_ptr: p.cell_ptr.clone(),
        cell_faces: face_of_side.to_vec(),
        face_ptr,
        face_verts,
        face_cells,
        face_tags: vec![0; n_faces],
        cell_tags: Vec::new(),
        cell_volume: Vec::new(),
        cell_centroid: Vec::new(),
        cell_diameter: Vec::new(),
        face_area: Vec::new(),
        face_centroid: Vec::new(),
        face_normal: Vec::new(),
        boundary_faces,
        h: 0.0,
    })
}

impl PolyMesh3 {
    /// |σ|, x_σ and n_σ of every face; [`MeshError::BadFace`] for a face whose vector area is
    /// negligible (|N_σ| ≤ 10⁻¹⁴ diam(σ)²: no normal).
    fn compute_face_geometry(&mut self) -> Result<(), MeshError> {
        let geo: Vec<_> = (0..self.n_faces())
            .into_par_iter()
            .map(|f| face_geometry(&self.vertices, self.face_vertices(f)))
            .collect();
        for (f, g) in geo.iter().enumerate() {
            let d = diameter(&self.vertices, self.face_vertices(f));
            if !(norm(g.vector_area) > 1e-14 * d * d) {
                let k = self.face_cells[f][0] as usize;
                return Err(MeshError::BadFace {
                    cell: k,
                    local_face: self.local_face(k, f),
                    msg: format!("zero area ({:e})", norm(g.vector_area)),
                });
            }
        }
        self.face_area = geo.iter().map(|g| g.area).collect();
        self.face_centroid = geo.iter().map(|g| g.centroid).collect();
        self.face_normal = geo
            .iter()
            .map(|g| g.vector_area.map(|x| x / norm(g.vector_area)))
            .collect();
        Ok(())
    }

    /// The local index of face `f` in cell `k` (which has it).
    pub(crate) fn local_face(&self, k: usize, f: usize) -> usize {
        self.cell_faces(k)
            .iter()
            .position(|&g| g as usize == f)
            .unwrap_or(usize::MAX)
    }

    /// |K|, x_K and h_K of every cell, and h; [`MeshError::DegenerateVolume`] for
    /// |K| ≤ 10⁻¹⁴ h_K³.
    fn compute_cell_geometry(&mut self) -> Result<(), MeshError> {
        let geo: Vec<(f64, [f64; 3], f64)> = (0..self.n_cells())
            .into_par_iter()
            .map_init(Vec::new, |ids: &mut Vec<u32>, k| {
                ids.clear();
                for &f in self.cell_faces(k) {
                    ids.extend_from_slice(self.face_vertices(f as usize));
                }
                ids.sort_unstable();
                ids.dedup();
                let apex = vertex_average(&self.vertices, ids);
                let sides = self.cell_faces(k).iter().map(|&f| {
                    let f = f as usize;
                    (self.face_vertices(f), self.face_cells[f][0] as usize != k)
                });
                let (vol, c) = cell_volume_centroid(&self.vertices, apex, sides);
                (vol, c, diameter(&self.vertices, ids))
            })
            .collect();
        if let Some(k) = geo.iter().position(|&(v, _, d)| !(v > 1e-14 * d * d * d)) {
            return Err(MeshError::DegenerateVolume {
                cell: k,
                volume: geo[k].0,
            });
        }
        self.cell_volume = geo.iter().map(|g| g.0).collect();
        self.cell_centroid = geo.iter().map(|g| g.1).collect();
        self.cell_diameter = geo.iter().map(|g| g.2).collect();
        self.h = self.cell_diameter.iter().copied().fold(0.0, f64::max);
        Ok(())
    }
}
