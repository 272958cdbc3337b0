//! The checks of [`PolyMesh3::from_polyhedra`](super::PolyMesh3::from_polyhedra), in the
//! order they run; each names the cell, face, edge or vertex at fault.
//!
//! | # | check | error | cost |
//! |---|---|---|---|
//! | 1 | well-formed offsets, at least one cell, counts below 2³² − 1 | [`MeshError::MalformedPolyhedra`], [`MeshError::Empty`], [`MeshError::TooManyEntities`] | O(n) |
//! | 2 | 4 to [`MAX_CELL_FACES`] faces per cell, 3 to [`MAX_FACE_VERTICES`] vertices per face, existing and distinct; cell tags absent or one per cell (all before allocating) | [`MeshError::BadCell`], [`MeshError::PolyhedronTooLarge`], [`MeshError::FaceTooLarge`], [`MeshError::BadFace`], [`MeshError::VertexOutOfRange`], [`MeshError::CellTagCount`] | O(n) |
//! | 3 | memory estimate ([`mesh3_bytes`](super::mesh3_bytes)) within the budget | [`MeshError::TooLarge`] | O(1) |
//! | 4 | finite, distinct (by coordinates), used vertices | [`MeshError::NonFiniteVertex`], [`MeshError::DuplicateVertex3`], [`MeshError::UnusedVertex`] | O(n log n) |
//! | 5 | faces matched by vertex set: at most two cells per face, not twice the same | [`MeshError::OvercrowdedFace`], [`MeshError::BadCell`] | O(n log n) |
//! | 6 | closed cells: each edge of a cell's faces used exactly twice, in opposite directions once the faces are oriented (one closed orientable surface), non-zero volume | [`MeshError::OpenCell`], [`MeshError::BadCell`], [`MeshError::DegenerateVolume`] | O(n log n) |
//! | 7 | the two cells of an interior face list the same loop and orient it oppositely | [`MeshError::InconsistentFace`] | O(n) |
//! | 8 | non-degenerate faces (\|N_σ\| > 10⁻¹⁴ diam(σ)²) not warped beyond [`WARP_TOL`] | [`MeshError::BadFace`], [`MeshError::WarpedFace`] | O(n) |
//! | 9 | non-negligible volumes: \|K\| > 10⁻¹⁴ h_K³ | [`MeshError::DegenerateVolume`] | O(n) |
//! | 10 | star-shaped cells: d_{K,σ} > 10⁻¹² h_K, and every fan triangle T of σ seen positively from x_K: the tetrahedron (x_K, T) has volume > 10⁻¹⁴ h_K³ | [`MeshError::NotStarShaped3`] | O(n) |
//! | 11 | the memory estimate with the check of the boundary surface added ([`boundary_surface_bytes`](super::boundary_surface_bytes), now that the boundary faces are known) within the budget; then a closed, edge-manifold boundary surface: every boundary edge used by exactly two boundary faces (then in opposite directions), and the boundary faces around each boundary vertex forming one fan (hanging nodes, cells touching along an edge or at a vertex, non-conforming interfaces all fail one of these; see `surface.rs`) | [`MeshError::TooLarge`], [`MeshError::NonConformingEdge`], [`MeshError::NonConformingVertex`] | O(n log n) |
//! | 12a | no overlap: no boundary vertex strictly inside a cell (the volume balance Σ_K \|K\| = (1/3) Σ_{boundary σ} ∫_σ x·n holds by construction once the checks above pass, overlap or not; see `overlap.rs`) | [`MeshError::OverlappingPolyhedra`] | O(n) expected, a grid of buckets |
//! | 12b | no overlap: no boundary edge crossing a boundary face of another cell in its interior (cells overlap only if the boundary surface intersects itself; see `crossing.rs`) | [`MeshError::EdgeThroughFace`] | O(n log n) in the boundary's size, a grid of buckets |
//! | 13 | tagged faces are boundary faces | [`MeshError::BadTaggedFace`] | O(n log n) |
//!
//! ## Warped faces
//! The warp of a face is max_v |(v − x_σ)·n_σ| / diam(σ) over its vertices: 0 for a planar
//! face. For a warped face the fan geometry is not exactly consistent:
//! C_K = Σ_σ |σ| n_{K,σ} (x_σ − x_K)ᵀ differs from |K| I (it equals it to round-off when
//! every face is planar), and HMM then reproduces affine functions only up to
//! ‖C_K/|K| − I‖. On hexahedra with warped faces the defect is of the order of the warp
//! (between half of it and about as much: the test
//! `warped_faces_give_a_consistency_defect_of_the_order_of_their_warp` checks that it stays
//! below twice the warp). [`WARP_TOL`] = 0.1 accepts faces whose vertices lie up to a tenth
//! of their diameter off their plane, so a consistency defect of up to about 10 %, and
//! rejects faces folded beyond that, whose fan normal no longer represents them.
//! HArDCore3D's `Random-Hexahedra` files pass with a wide margin: their faces are planar to
//! round-off. [`WarpedFaces::Split`](super::WarpedFaces) removes the defect by splitting every
//! face warped beyond [`PLANAR_TOL`](super::PLANAR_TOL) into its fan triangles (see
//! `split_faces.rs`); the default, [`WarpedFaces::Fan`](super::WarpedFaces), keeps them whole.

use super::Polyhedra;
use crate::error::MeshError;
use rayon::prelude::*;

/// The most faces a cell may have (a refined Cartesian cell has 24; Voronoi cells rarely more
/// than 40): local HMM matrices are dense in the number of faces.
pub const MAX_CELL_FACES: usize = 1000;

/// The most vertices a face may have.
pub const MAX_FACE_VERTICES: usize = 1000;

/// The largest warp of a face (see the module docs).
pub const WARP_TOL: f64 = 0.1;

/// Check 1 of the module docs: the offset arrays of `p` are well formed.
pub(crate) fn check_offsets(p: &Polyhedra) -> Result<(), MeshError> {
    let bad = |msg: String| Err(MeshError::MalformedPolyhedra(msg));
    check_ptr("cell_ptr", &p.cell_ptr, p.face_ptr.len().saturating_sub(1))?;
    if p.n_cells() == 0 {
        return Err(MeshError::Empty);
    }
    check_ptr("face_ptr", &p.face_ptr, p.face_vertices.len())?;
    if !(p.tagged_ptr.is_empty() && p.tagged_vertices.is_empty()) {
        check_ptr("tagged_ptr", &p.tagged_ptr, p.tagged_vertices.len())?;
    }
    let n_tagged = p.tagged_ptr.len().saturating_sub(1);
    if p.tagged_tags.len() != n_tagged {
        return bad(format!(
            "{} tags for {n_tagged} tagged faces",
            p.tagged_tags.len()
        ));
    }
    for (what, count) in [
        ("vertices", p.vertices.len()),
        ("cells", p.n_cells()),
        ("face sides", p.face_ptr.len() - 1),
        ("face vertices", p.face_vertices.len()),
    ] {
        if count >= u32::MAX as usize {
            return Err(MeshError::TooManyEntities { what, count });
        }
    }
    Ok(())
}

/// `ptr` starts at 0, does not decrease and ends at `len`.
fn check_ptr(name: &str, ptr: &[u32], len: usize) -> Result<(), MeshError> {
    let bad = |msg: String| Err(MeshError::MalformedPolyhedra(format!("{name}: {msg}")));
    match (ptr.first(), ptr.last()) {
        (Some(0), Some(&last)) if last as usize == len => {}
        _ => return bad(format!("must start at 0 and end at {len}")),
    }
    if let Some(i) = ptr.windows(2).position(|w| w[1] < w[0]) {
        return bad(format!("decreases at entry {}", i + 1));
    }
    Ok(())
}

/// Check 2 of the module docs, for every cell.
pub(crate) fn check_cells(p: &Polyhedra) -> Result<(), MeshError> {
    let n_vertices = p.vertices.len();
    // in parallel over the cells; the error is that of the first bad cell, as in a loop
    let bad = (0..p.n_cells())
        .into_par_iter()
        .map_init(Vec::new, |buf, k| check_cell(p, k, n_vertices, buf).err())
        .find_map_first(|e| e);
    if let Some(e) = bad {
        return Err(e);
    }
    if !(p.cell_tags.is_empty() || p.cell_tags.len() == p.n_cells()) {
        return Err(MeshError::CellTagCount {
            tags: p.cell_tags.len(),
            cells: p.n_cells(),
        });
    }
    Ok(())
}

/// Check 2 of the module docs for cell `k` (`buf`: scratch for a face's sorted ids).
fn check_cell(
    p: &Polyhedra,
    k: usize,
    n_vertices: usize,
    buf: &mut Vec<u32>,
) -> Result<(), MeshError> {
    let sides = p.cell_sides(k);
    if sides.len() > MAX_CELL_FACES {
        return Err(MeshError::PolyhedronTooLarge {
            cell: k,
            n_faces: sides.len(),
            max: MAX_CELL_FACES,
        });
    }
    if sides.len() < 4 {
        return Err(MeshError::BadCell {
            cell: k,
            msg: format!("{} faces (a polyhedron has at least 4)", sides.len()),
        });
    }
    for (j, s) in sides.enumerate() {
        check_face(k, j, p.side_vertices(s), n_vertices, buf)?;
    }
    Ok(())
}

/// Local face `j` of cell `k` has 3 to [`MAX_FACE_VERTICES`] distinct, existing vertices.
fn check_face(
    k: usize,
    j: usize,
    l: &[u32],
    n_vertices: usize,
    buf: &mut Vec<u32>,
) -> Result<(), MeshError> {
    let bad = |msg: String| {
        Err(MeshError::BadFace {
            cell: k,
            local_face: j,
            msg,
        })
    };
    if l.len() > MAX_FACE_VERTICES {
        return Err(MeshError::FaceTooLarge {
            cell: k,
            local_face: j,
            n_vertices: l.len(),
            max: MAX_FACE_VERTICES,
        });
    }
    if l.len() < 3 {
        return bad(format!("{} vertices (a face has at least 3)", l.len()));
    }
    if let Some(&v) = l.iter().find(|&&v| v as usize >= n_vertices) {
        return Err(MeshError::VertexOutOfRange {
            cell: k,
            vertex: v as usize,
            n_vertices,
        });
    }
    buf.clear();
    buf.extend_from_slice(l);
    buf.sort_unstable();
    if let Some(w) = buf.windows(2).find(|w| w[0] == w[1]) {
        return bad(format!("lists vertex {} twice", w[0]));
    }
    Ok(())
}

/// Check 4 of the module docs.
pub(crate) fn check_vertices(p: &Polyhedra) -> Result<(), MeshError> {
    let v = &p.vertices;
    if let Some(i) = v.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
        return Err(MeshError::NonFiniteVertex { vertex: i });
    }
    let mut order: Vec<u32> = (0..v.len() as u32).collect();
    let cmp = |a: &u32, b: &u32| {
        // + 0.0 turns −0 into +0, so that equal points sort together
        let (a, b) = (
            v[*a as usize].map(|c| c + 0.0),
            v[*b as usize].map(|c| c + 0.0),
        );
        (a[0].total_cmp(&b[0]))
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
    };
    order.par_sort_unstable_by(|a, b| cmp(a, b).then(a.cmp(b)));
    if let Some(w) = order
        .windows(2)
        .find(|w| v[w[0] as usize] == v[w[1] as usize])
    {
        return Err(MeshError::DuplicateVertex3 {
            a: w[0] as usize,
            b: w[1] as usize,
            point: v[w[0] as usize],
        });
    }
    drop(order);
    let mut used = vec![false; v.len()];
    p.face_vertices
        .iter()
        .for_each(|&i| used[i as usize] = true);
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(MeshError::UnusedVertex { vertex: i });
    }
    Ok(())
}
