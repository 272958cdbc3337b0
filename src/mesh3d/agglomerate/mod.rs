//! Coarse polyhedral meshes of the *same domain* by agglomerating the cells of a fine 3D mesh:
//! the 3D counterpart of [`crate::mesh::agglomerate`], for the warm start's coarse levels.
//!
//! HMM accepts any polyhedra that are star-shaped with respect to their centroid, with any
//! number of faces, so a union of fine cells is an admissible coarse cell as it is: unlike the
//! 2D construction, faces are not straightened. A coarse cell is the union of its fine cells;
//! the fine faces between two aggregates are merged into one polygon per plane and connected
//! piece where the union is bounded by one simple loop (so a block of cubes or of Kuhn
//! tetrahedra has one face per neighbouring block; see `merge.rs` for the maths and the
//! conditions), the others are kept with their loops; the fine faces on the boundary of the
//! domain are kept as they are.
//!
//! ## Construction, for a target cell size H
//! 1. **Aggregates.** Each fine cell K gets the key (⌊(x − x₀)/H⌋, ⌊(y − y₀)/H⌋,
//!    ⌊(z − z₀)/H⌋, tag of K) ((x₀, y₀, z₀) the corner of the mesh's bounding box). The point
//!    (x, y, z) is the centre of K's bounding box if every vertex of K is a corner of that box
//!    (axis-parallel boxes, and the tetrahedra and prisms a box is cut into: Kuhn's six
//!    tetrahedra, two triangular prisms), so that the pieces of one box stay together and a
//!    cut Cartesian grid agglomerates into boxes; it is the centroid x_K otherwise (the test is
//!    exact: the box is made of the vertices' own coordinates). Aggregates are the connected
//!    components (through interior faces) of the cells sharing a key, so an aggregate never
//!    mixes two cell tags and is a patch of about (H/h)³ fine cells. Aggregates of volume below
//!    H³/8 (slivers along the boundary or along material interfaces) are merged into the
//!    neighbour of the same tag with which they share the largest face area.
//! 2. **Checks.** An aggregate A of several cells, with the fine faces σ on its boundary
//!    oriented outward, is kept if
//!    * it has at most [`MAX_CELL_FACES`] faces;
//!    * its boundary is a closed surface without pinched edges: every edge of the outward
//!      loops is traversed exactly once in each direction;
//!    * it is star-shaped with respect to its centroid x_A = Σ_{K ⊂ A} |K| x_K / |A|
//!      (|A| = Σ_{K ⊂ A} |K|: the fans of an interior face are the same for both its cells,
//!      so this is the centroid the coarse mesh computes from the boundary fans, up to
//!      round-off) with margin: with r_A the largest distance from x_A to a vertex of A,
//!      d_{A,σ} = (x_σ − x_A)·n_{A,σ} ≥ [`MIN_DIST_RATIO`] · r_A on every face, and the plane of
//!      every fan triangle T of σ (the triangles of the mesh's geometry, see
//!      [`crate::mesh3d`]) at distance at least [`MIN_DIST_RATIO`] · r_A from x_A on the
//!      inner side;
//!    * its fan triangles, all seen positively from x_A, cover the sphere of directions once:
//!      their solid angles Ω_T (Van Oosterom and Strackee's formula
//!      tan(Ω_T/2) = a·(b × c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|), with a, b, c
//!      the corners of T minus x_A) add up to 4π (to 10⁻⁶). The radial projection from x_A
//!      is then a bijection from the boundary onto the sphere, so A is a topological ball (no
//!      cavity, no handle, no pinched vertex).
//!
//!    An aggregate that fails is *regrouped*: its cells are grouped again as in step 1, within
//!    it, by boxes of half the size (the aggregates that pass keep their cells), and the new
//!    aggregates are checked (small ones are not merged again). Whether an aggregate passes
//!    depends on nothing but its own fine cells, so those kept stay admissible and only the
//!    new ones are checked. After
//!    [`MAX_SPLITS`] halvings the cells of the aggregates that still fail are *dissolved*:
//!    each becomes a coarse cell of its own (a fine cell is a cell of a validated mesh, so it
//!    passes the mesh's checks; aggregates of one cell are not checked). So the construction
//!    ends after at most [`MAX_SPLITS`] + 1 rounds of checks.
//! 3. The faces between aggregates are merged (`merge.rs`), and the coarse mesh is then built
//!    and validated like any input mesh ([`PolyMesh3::from_polyhedra`], after
//!    [`Polyhedra::drop_unused_vertices`]: the fine vertices inside aggregates and inside
//!    merged faces are dropped). Every fine boundary face is a coarse boundary face, or part of
//!    one,
//!    with its tag ([`Agglomeration3::boundary_face_of`]), so boundary data and Signorini
//!    unknowns carry over one to one, unless the caller asks for boundary faces to be merged
//!    ([`agglomerate3_merging`]: then several fine boundary faces of one part map to one coarse
//!    face); every coarse cell has the tag of its fine cells. A failure
//!    there is returned as an error: the caller then does without coarse meshes.
//!
//! Cost: each round is linear in the fine mesh apart from sorting the boundary edges of each
//! aggregate checked; then the merging (sorting the faces and edges of each interface, and
//! grouping its faces by plane: quadratic in the number of planes of one interface, one or a
//! few on meshes of boxes, at most [`MAX_CELL_FACES`]) and the build of the coarse mesh
//! (O(n log n)).
//!
//! ## Parallelism
//! The passes over all fine cells (keys), over all fine faces (which cells to join, the
//! interfaces of small aggregates) and over all aggregates (the checks of step 2, the faces of
//! each coarse cell) run on every core (rayon), each collected in index order as a function of
//! its index alone; what depends on an order (the unions, the first-appearance numbering, the
//! sums of volumes and face areas) stays sequential, in fine cell or fine face order. The
//! coarse meshes therefore do not depend on the number of threads.

mod boxes;
mod build;
mod check;
mod merge;
#[cfg(test)]
mod tests;

use super::{Point3, PolyMesh3, Polyhedra, validate::MAX_CELL_FACES};
use crate::budget::MemoryBudget;
use crate::error::MeshError;
use crate::mesh::NO_CELL;
use crate::mesh::agglomerate::{components, dissolve, floor_i64, merge_into_neighbours, renumber};
use rayon::prelude::*;

pub use crate::mesh::agglomerate::MIN_DIST_RATIO;
pub use boxes::box_cover;
pub use merge::KEEP;

/// Marker for "no coarse face" in [`Agglomeration3::boundary_face_of`] (interior fine faces).
pub const NO_FACE: u32 = u32::MAX;

/// Aggregates smaller than this fraction of H³ are merged into a neighbour.
const SMALL_FRACTION: f64 = 0.125;

/// Times the size of the boxes is halved to regroup the cells of failed aggregates before
/// those that still fail are dissolved into single cells.
pub const MAX_SPLITS: usize = 8;

/// Least number of items (fine cells, faces, aggregates) of one parallel task.
const MIN_TASK: usize = 1 << 12;

/// A coarse 3D mesh made of unions of the cells of a fine one, and the maps between them.
#[derive(Debug, Clone)]
pub struct Agglomeration3 {
    /// The coarse mesh (validated; cell tags and boundary tags from the fine mesh).
    pub mesh: PolyMesh3,
    /// The coarse cell of each fine cell.
    pub cell_of: Vec<u32>,
    /// The coarse face of each fine boundary face (the same polygon, or the merged face
    /// containing it, with the same tag); [`NO_FACE`] for interior fine faces. Indexed by fine
    /// face.
    pub boundary_face_of: Vec<u32>,
    /// Fine cells whose first aggregate failed the checks (regrouped into smaller aggregates
    /// or left alone).
    pub dissolved_cells: usize,
}

/// Agglomerates `fine` into cells of size about `size` (see the module docs). The working
/// memory ([`agglomerate3_bytes`]) and the coarse mesh's are compared with `budget` first.
/// [`MeshError::NonConforming`] for a `size` that is not positive and finite, or a coarse mesh
/// that loses a boundary face; the errors of [`PolyMesh3::from_polyhedra`] if the coarse mesh
/// fails its validation.
pub fn agglomerate3(
    fine: &PolyMesh3,
    size: f64,
    budget: MemoryBudget,
) -> Result<Agglomeration3, MeshError> {
    agglomerate3_merging(fine, size, None, 1.0, budget)
}

/// [`agglomerate3`], the fine boundary faces of each aggregate merged by plane and piece among
/// those with the same key in `boundary_key` (indexed by fine face, read on boundary faces
/// only; [`KEEP`] keeps a face as it is, and so does `None` every face: then this is
/// [`agglomerate3`]). A merged boundary face is one coarse face with the tag of its fine
/// faces, so faces of different tags must have different keys (`merge.rs` has the maths).
/// [`MeshError::NonConforming`] if `boundary_key` does not have one entry per fine face, and
/// if more than the fraction `max_failed` of the fine cells lie in aggregates that fail the
/// first checks (then the mesh does not agglomerate at this size, as on unstructured
/// tetrahedra, whose aggregates have jagged boundaries: a caller that would use the coarse
/// mesh only if it is coarser learns it after one round of checks instead of
/// [`MAX_SPLITS`] + 1; 1 never stops).
pub fn agglomerate3_merging(
    fine: &PolyMesh3,
    size: f64,
    boundary_key: Option<&[u32]>,
    max_failed: f64,
    budget: MemoryBudget,
) -> Result<Agglomeration3, MeshError> {
    if let Some(k) = boundary_key.filter(|k| k.len() != fine.n_faces()) {
        return Err(MeshError::NonConforming(format!(
            "{} boundary merge keys for a mesh of {} faces",
            k.len(),
            fine.n_faces()
        )));
    }
    if !(size.is_finite() && size > 0.0) {
        return Err(MeshError::NonConforming(format!(
            "agglomeration size must be positive and finite, got {size}"
        )));
    }
    budget.check(
        format!("agglomerating a 3D mesh of {} cells", fine.n_cells()),
        agglomerate3_bytes(fine),
    )?;
    let mut label = keyed_components(fine, size, None);
    merge_small(fine, &mut label, SMALL_FRACTION * size * size * size);
    let mut regrouped = vec![false; fine.n_cells()];
    let mut settled = vec![false; fine.n_cells()];
    let mut level = size;
    for round in 0..=MAX_SPLITS {
        let failed = check_all(fine, &label, &settled);
        if !failed.contains(&true) {
            break;
        }
        for (k, &a) in label.iter().enumerate() {
            regrouped[k] |= failed[a];
            settled[k] = !failed[a];
        }
        let bad = regrouped.iter().filter(|&&r| r).count();
        if round == 0 && bad as f64 > max_failed * fine.n_cells() as f64 {
            return Err(MeshError::NonConforming(format!(
                "{bad} of {} cells lie in aggregates of size {size} that fail the checks: \
                 the mesh does not agglomerate at this size",
                fine.n_cells()
            )));
        }
        if round == MAX_SPLITS {
            dissolve(&mut label, &mut regrouped, &failed);
            renumber(&mut label);
            break;
        }
        level *= 0.5;
        label = keyed_components(fine, level, Some((&label, &failed)));
    }
    let n_dissolved = regrouped.iter().filter(|&&d| d).count();
    drop((regrouped, settled));
    build::build(fine, label, n_dissolved, boundary_key, budget)
}

/// Estimated peak working memory, in bytes, of [`agglomerate3`] on `fine`, before the coarse
/// mesh is built (whose own estimate [`PolyMesh3::from_polyhedra`] checks): per fine cell 32
/// (key), 8 (label), 8 (parent), 8 (volume), 4 (bucket entry) and 1 (dissolved flag); per
/// fine face 1 (join flag), 4 (boundary map), 24 (an interface entry, an upper bound) and the
/// coarse [`Polyhedra`]'s share, at most twice the face with its loop (8 + 8 per loop entry),
/// and the merged interfaces (8 + 4 per loop entry, at most once per fine face); 24 per vertex
/// (the coarse vertices before the unused ones are dropped).
pub fn agglomerate3_bytes(fine: &PolyMesh3) -> u64 {
    let cells = fine.n_cells() as u64;
    let faces = fine.n_faces() as u64;
    let loops = fine.face_verts.len() as u64;
    let vertices = fine.n_vertices() as u64;
    cells
        .saturating_mul(32 + 8 + 8 + 8 + 4 + 1)
        .saturating_add(faces.saturating_mul(1 + 4 + 24 + 8 + 8))
        .saturating_add(loops.saturating_mul(8 + 4))
        .saturating_add(vertices.saturating_mul(24))
}

/// The fine cells of each aggregate, in increasing order (CSR: offsets, cell ids).
fn members(label: &[usize]) -> (Vec<usize>, Vec<u32>) {
    let na = label.iter().max().map_or(0, |m| m + 1);
    crate::mesh::buckets::counting_sort(na, label.iter().map(|&a| Some(a)), |k| k as u32)
}

/// The vertices of cell `k` (each once per face that has it).
fn cell_vertex_ids(mesh: &PolyMesh3, k: usize) -> impl Iterator<Item = u32> + '_ {
    mesh.cell_faces(k)
        .iter()
        .flat_map(move |&f| mesh.face_vertices(f as usize).iter().copied())
}

/// The point that places cell k in a box of step 1 (module docs): the centre of its bounding
/// box if every vertex of k is a corner of the box (exact comparisons), its centroid
/// otherwise.
fn key_point(mesh: &PolyMesh3, k: usize) -> Point3 {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in cell_vertex_ids(mesh, k) {
        let p = mesh.vertices()[v as usize];
        for r in 0..3 {
            lo[r] = lo[r].min(p[r]);
            hi[r] = hi[r].max(p[r]);
        }
    }
    let corner = |v: u32| {
        let p = mesh.vertices()[v as usize];
        (0..3).all(|r| p[r] == lo[r] || p[r] == hi[r])
    };
    if cell_vertex_ids(mesh, k).all(corner) {
        std::array::from_fn(|r| 0.5 * (lo[r] + hi[r]))
    } else {
        mesh.centroid(k)
    }
}

/// Whether each aggregate of `label` fails the checks of step 2 (aggregates of one cell, and
/// those whose cells are `settled`, being known to pass).
fn check_all(fine: &PolyMesh3, label: &[usize], settled: &[bool]) -> Vec<bool> {
    let (ptr, cells) = members(label);
    (0..ptr.len() - 1)
        .into_par_iter()
        .with_min_len(MIN_TASK / 16)
        .map_init(check::Scratch::default, |scratch, a| {
            let m = &cells[ptr[a]..ptr[a + 1]];
            m.len() > 1 && !settled[m[0] as usize] && !check::admissible(fine, label, a, m, scratch)
        })
        .collect()
}

/// The connected components (through interior faces) of the cells with the same key: for
/// step 1 (`previous` = `None`), the box of size `size` and the tag; for a regrouping
/// (`previous` = the labels and which aggregates failed), the cells of a kept aggregate keep
/// it, those of a failed one are grouped by boxes of size `size` within it.
fn keyed_components(
    fine: &PolyMesh3,
    size: f64,
    previous: Option<(&[usize], &[bool])>,
) -> Vec<usize> {
    let origin = fine.bounding_box().ranges().map(|r| r[0]);
    let keys: Vec<([i64; 3], i32)> = (0..fine.n_cells())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|k| {
            if previous.is_some_and(|(label, failed)| !failed[label[k]]) {
                return ([0; 3], fine.cell_tag(k));
            }
            let c = key_point(fine, k);
            (
                std::array::from_fn(|r| floor_i64((c[r] - origin[r]) / size)),
                fine.cell_tag(k),
            )
        })
        .collect();
    let joins: Vec<bool> = (0..fine.n_faces())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|f| {
            let [a, b] = fine.face_cells(f);
            b != NO_CELL
                && keys[a] == keys[b]
                && previous.is_none_or(|(label, _)| label[a] == label[b])
        })
        .collect();
    drop(keys);
    let pairs = (joins.iter().enumerate())
        .filter(|(_, j)| **j)
        .map(|(f, _)| fine.face_cells(f));
    components(fine.n_cells(), pairs)
}

/// Merges the aggregates of volume below `min_volume` into the neighbour of the same tag with
/// the largest common face area (one pass, in label order).
fn merge_small(fine: &PolyMesh3, label: &mut [usize], min_volume: f64) {
    let na = label.iter().max().map_or(0, |m| m + 1);
    let mut volume = vec![0.0; na];
    for (k, &a) in label.iter().enumerate() {
        volume[a] += fine.measure(k);
    }
    let small: Vec<(usize, usize, f64)> = (0..fine.n_faces())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .filter_map(|f| {
            let [k, l] = fine.face_cells(f);
            if l == NO_CELL || fine.cell_tag(k) != fine.cell_tag(l) {
                return None;
            }
            let (a, b) = (label[k], label[l]);
            (a != b && (volume[a] < min_volume || volume[b] < min_volume))
                .then(|| (a, b, fine.face_measure(f)))
        })
        .collect();
    merge_into_neighbours(label, &volume, &small, min_volume);
}
