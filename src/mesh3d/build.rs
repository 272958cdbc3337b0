//! Building a [`PolyMesh3`] from a [`Polyhedra`]: checks on the input, memory estimate, face
//! matching, orientation, geometry, then the checks on the geometry (the list is in
//! [`validate`](super::validate)).

use super::faces::{FaceMatch, NO_SIDE, match_faces, same_direction, side_cells};
use super::geometry::{cell_volume_centroid, diameter, face_geometry, norm, vertex_average};
use super::orient::orient_cells;
use super::validate::{check_cells, check_offsets, check_vertices};
use super::{PolyMesh3, Polyhedra};
use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_vec};
use crate::error::MeshError;
use crate::offsets::Offsets;
use rayon::prelude::*;

/// Estimated peak memory, in bytes, of [`PolyMesh3::from_polyhedra`] on a [`Polyhedra`] with
/// `cells` cells, `sides` face sides (faces counted once per cell), `side_vertices` entries in
/// the face loops and `vertices` vertices, on top of the [`Polyhedra`] itself.
///
/// Per vertex: 24 bytes of coordinates, 4 of sort order, 1 of use flag. Per cell: 4 (offset),
/// 8 (volume), 24 (centroid), 8 (diameter, while the shapes are checked), 4 (tag), 16 (its
/// slice of the orientations while they are computed in parallel). Per side: 4 (its cell), 4
/// (place in its bucket), 1 (pair flag), 4 (partner side), 4 (its face), 1 (orientation), 4
/// (face id in the cell's list). Per face, counting as many faces as sides (an upper bound): 8
/// (sides), 4 (offset), 8 (cells), 4 (boundary tag), 4 (boundary list); face areas, centroids
/// and normals are not stored.
/// Per loop entry: 4 (stored loop), 4 (the pieces in which the loops are gathered in parallel,
/// and the per-thread scratch of face matching). The check of the boundary surface, which
/// needs memory per *boundary* loop entry, is counted once the boundary faces are known
/// ([`boundary_surface_bytes`]; it used to be counted here for every loop entry, 48 bytes per
/// entry instead of 8, which made 200³ cubes of Kuhn tetrahedra — 48M cells — ask for
/// 37.8 GiB).
pub fn mesh3_bytes(cells: u64, sides: u64, side_vertices: u64, vertices: u64) -> u64 {
    let per_vertex = 24 + 4 + 1;
    let per_cell = 4 + 8 + 24 + 8 + 4 + 16;
    let per_side = (4 + 4 + 1 + 4 + 4 + 1 + 4) + (8 + 4 + 8 + 4 + 4);
    let per_loop_entry = 4 + 4;
    cells
        .saturating_mul(per_cell)
        .saturating_add(sides.saturating_mul(per_side))
        .saturating_add(side_vertices.saturating_mul(per_loop_entry))
        .saturating_add(vertices.saturating_mul(per_vertex))
}

/// Memory, in bytes, of the check of the boundary surface ([`PolyMesh3::from_polyhedra`]'s
/// check 11) on `entries` boundary loop entries and `vertices` vertices: per entry 4 (its
/// vertex), 4 (the next corner of its loop), 12 (its directed edge), 4 (the next corner around
/// its vertex), 1 (seen), with the sort's scratch bounded by another 12, hence 40 rounded
/// up; per vertex 4 (its count of fans).
pub fn boundary_surface_bytes(entries: u64, vertices: u64) -> u64 {
    entries
        .saturating_mul(40)
        .saturating_add(vertices.saturating_mul(4))
}

impl PolyMesh3 {
    /// Builds and validates the mesh described by `p` (see [`crate::mesh3d`] for the geometry
    /// and [`validate`](super::validate) for the checks, each a typed error naming the cell,
    /// face, edge or vertex at fault). The memory needed ([`mesh3_bytes`]) is compared with
    /// `budget` before anything large is allocated, and again, with the check of the boundary
    /// surface added ([`boundary_surface_bytes`]), once the boundary faces are known.
    pub fn from_polyhedra(mut p: Polyhedra, budget: MemoryBudget) -> Result<PolyMesh3, MeshError> {
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
        let side_cell = side_cells(&p)?;
        let FaceMatch {
            face_of_side,
            face_sides,
        } = match_faces(&p, &side_cell)?;
        let inward = orient_cells(&p)?;
        let mut m = assemble(&p, &side_cell, face_of_side, &face_sides, &inward)?;
        drop((side_cell, face_sides, inward));
        // the mesh takes over the vertices and cell offsets; the face loops are no longer needed
        m.vertices = std::mem::take(&mut p.vertices);
        m.cell_ptr = Offsets::from_offsets(std::mem::take(&mut p.cell_ptr));
        drop((
            std::mem::take(&mut p.face_ptr),
            std::mem::take(&mut p.face_vertices),
        ));
        m.check_face_geometry()?;
        let (diameters, star) = m.compute_cell_geometry()?;
        m.check_shapes(&diameters, &star)?;
        drop((diameters, star));
        let entries: usize = (m.boundary_faces.iter())
            .map(|&f| m.face_vertices(f as usize).len())
            .sum();
        let surface = bytes.saturating_add(boundary_surface_bytes(
            entries as u64,
            m.n_vertices() as u64,
        ));
        budget.check(
            format!(
                "a 3D mesh of {} cells and {sides} face sides, {} of them on the boundary",
                m.n_cells(),
                m.boundary_faces.len()
            ),
            surface,
        )?;
        m.check_boundary_surface()?;
        m.check_overlap()?;
        m.check_crossings()?;
        m.cell_tags = if p.cell_tags.iter().all(|&t| t == 0) {
            Vec::new()
        } else {
            std::mem::take(&mut p.cell_tags)
        };
        m.set_face_tags(&p)?;
        Ok(m)
    }
}

/// The topology of the mesh (face loops, incidences, boundary list), geometry left empty, and
/// vertices and cell offsets left for the caller to move in from `p`: every face's loop is the
/// outward loop of its first side, checked against its second.
fn assemble(
    p: &Polyhedra,
    side_cell: &[u32],
    face_of_side: Vec<u32>,
    face_sides: &[[u32; 2]],
    inward: &[bool],
) -> Result<PolyMesh3, MeshError> {
    let n_faces = face_sides.len();
    // the loop lengths in parallel, then their running sum
    let mut face_ptr = try_vec(n_faces + 1, "the face offsets")?;
    face_ptr.push(0u32);
    face_ptr.par_extend(
        face_sides
            .par_iter()
            .map(|&[s, _]| p.side_vertices(s as usize).len() as u32),
    );
    let mut end = 0u32;
    for x in &mut face_ptr[1..] {
        end += *x;
        *x = end;
    }
    // the loops written in place by blocks of consecutive faces, each interior face checked
    // against its second side in the same pass (the error is that of the first bad face)
    let mut face_verts: Vec<u32> = try_filled(end as usize, 0, "the face loops")?;
    let mut blocks = Vec::with_capacity(n_faces.div_ceil(FACE_BLOCK));
    let mut rest = face_verts.as_mut_slice();
    for start in (0..n_faces).step_by(FACE_BLOCK) {
        let stop = (start + FACE_BLOCK).min(n_faces);
        let (block, tail) = rest.split_at_mut((face_ptr[stop] - face_ptr[start]) as usize);
        blocks.push((start..stop, block));
        rest = tail;
    }
    let bad = blocks
        .into_par_iter()
        .map(|(faces, block)| {
            let base = face_ptr[faces.start] as usize;
            faces.into_iter().find_map(|f| {
                let [s, t] = face_sides[f];
                let l = p.side_vertices(s as usize);
                let stored =
                    &mut block[face_ptr[f] as usize - base..face_ptr[f + 1] as usize - base];
                if inward[s as usize] {
                    stored
                        .iter_mut()
                        .zip(l.iter().rev())
                        .for_each(|(o, &v)| *o = v);
                } else {
                    stored.copy_from_slice(l);
                }
                (t != NO_SIDE)
                    .then(|| pair_defect(p, side_cell, inward, stored, [s, t]))
                    .flatten()
            })
        })
        .find_map_first(|e| e);
    if let Some(e) = bad {
        return Err(e);
    }
    let mut face_cells: Vec<[u32; 2]> = try_vec(n_faces, "the cells of the faces")?;
    face_cells.par_extend(face_sides.par_iter().map(|&[s, t]| {
        let second = if t == NO_SIDE {
            u32::MAX
        } else {
            side_cell[t as usize]
        };
        [side_cell[s as usize], second]
    }));
    let boundary_faces: Vec<u32> = (0..n_faces as u32)
        .into_par_iter()
        .filter(|&f| face_cells[f as usize][1] == u32::MAX)
        .collect();
    let boundary_tags = try_filled(boundary_faces.len(), 0, "the boundary tags")?;
    Ok(PolyMesh3 {
        vertices: Vec::new(),
        cell_ptr: Offsets::from_offsets(vec![0]),
        cell_faces: face_of_side,
        face_ptr: Offsets::from_offsets(face_ptr),
        face_verts,
        face_cells,
        cell_tags: Vec::new(),
        cell_volume: Vec::new(),
        cell_centroid: Vec::new(),
        boundary_faces,
        boundary_tags,
        h: 0.0,
    })
}

/// Faces per parallel task of [`assemble`].
const FACE_BLOCK: usize = 4096;

/// The defect of interior face [s, t] (its sides), whose loop as stored is `stored` (the
/// outward loop of side s): [`MeshError::InconsistentFace`] unless side t lists the same loop
/// in the opposite direction once turned outward.
fn pair_defect(
    p: &Polyhedra,
    side_cell: &[u32],
    inward: &[bool],
    stored: &[u32],
    [s, t]: [u32; 2],
) -> Option<MeshError> {
    let l = p.side_vertices(s as usize);
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
        None => Some(bad("list its vertices in different cyclic orders")),
        // the second cell's outward loop must be the reverse of the first's
        Some(same) if same != inward[t as usize] => Some(bad(
            "both lie on the same side of it (their outward normals agree)",
        )),
        Some(_) => None,
    }
}

impl PolyMesh3 {
    /// Checks the faces, in parallel (|σ|, x_σ and n_σ are computed when asked for:
    /// [`PolyMesh3::face_measure`], [`PolyMesh3::face_frame`]): [`MeshError::BadFace`] for the
    /// first face whose vector area is negligible (|N_σ| ≤ 10⁻¹⁴ diam(σ)²: no normal).
    fn check_face_geometry(&self) -> Result<(), MeshError> {
        let n = self.n_faces();
        let has_normal = |f: usize, vector_area: [f64; 3]| {
            let d = diameter(&self.vertices, self.face_vertices(f));
            norm(vector_area) > 1e-14 * d * d
        };
        let bad = (0..n).into_par_iter().find_first(|&f| {
            let g = face_geometry(&self.vertices, self.face_vertices(f));
            !has_normal(f, g.vector_area)
        });
        if let Some(f) = bad {
            let k = self.face_cells[f][0] as usize;
            let g = face_geometry(&self.vertices, self.face_vertices(f));
            return Err(MeshError::BadFace {
                cell: k,
                local_face: self.local_face(k, f),
                msg: format!("zero area ({:e})", norm(g.vector_area)),
            });
        }
        Ok(())
    }

    /// The local index of face `f` in cell `k` (which has it).
    pub(crate) fn local_face(&self, k: usize, f: usize) -> usize {
        self.cell_faces(k)
            .iter()
            .position(|&g| g as usize == f)
            .unwrap_or(usize::MAX)
    }

    /// |K| and x_K of every cell, in parallel, written in place, and h; returns h_K of every
    /// cell (for the shape checks; [`PolyMesh3::diameter`] computes it when asked for later)
    /// and whether each cell is strictly star-shaped with respect to x_K
    /// ([`PolyMesh3::star_defect`], evaluated here while the cell's vertices are at hand and
    /// reported by [`PolyMesh3::check_shapes`], after the volume and warp checks).
    /// [`MeshError::DegenerateVolume`] for the first cell with |K| ≤ 10⁻¹⁴ h_K³.
    fn compute_cell_geometry(&mut self) -> Result<(Vec<f64>, Vec<bool>), MeshError> {
        let n = self.n_cells();
        let mut volume = try_filled(n, 0.0, "the cell volumes")?;
        let mut centroid = try_filled(n, [0.0; 3], "the cell centroids")?;
        let mut diam = try_filled(n, 0.0, "the cell diameters")?;
        let mut star = try_filled(n, false, "the star-shapedness flags")?;
        (
            volume.par_iter_mut(),
            centroid.par_iter_mut(),
            diam.par_iter_mut(),
            star.par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .for_each_init(Vec::new, |ids: &mut Vec<u32>, (k, (vol, c, d, ok))| {
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
                (*vol, *c) = cell_volume_centroid(&self.vertices, apex, sides);
                *d = diameter(&self.vertices, ids);
                *ok = self.star_defect(k, *c, *d).is_none();
            });
        let bad = (0..n)
            .into_par_iter()
            .find_first(|&k| !(volume[k] > 1e-14 * diam[k] * diam[k] * diam[k]));
        if let Some(k) = bad {
            return Err(MeshError::DegenerateVolume {
                cell: k,
                volume: volume[k],
            });
        }
        self.h = diam.iter().copied().fold(0.0, f64::max);
        self.cell_volume = volume;
        self.cell_centroid = centroid;
        Ok((diam, star))
    }
}
