//! Coarse polygonal meshes of the *same domain* by agglomerating the cells of a fine mesh.
//!
//! The warm start of the active-set solver ([`crate::solver::warm_start`]) solves the problem
//! on coarser meshes of the domain first. A user's mesh comes alone (a gmsh file, no geometry
//! description), so the coarse meshes are made from it: HMM accepts any star-shaped polygons,
//! so unions of fine cells are admissible cells once their boundaries are simplified.
//!
//! ## Construction, for a target cell size H
//! 1. **Aggregates.** Each fine cell K gets the key (⌊(x_K − x₀)/H⌋, ⌊(y_K − y₀)/H⌋, tag of K)
//!    ((x₀, y₀) the corner of the mesh's bounding box). The point (x_K, y_K) is K's centroid,
//!    except on a cell that fills its bounding box (an axis-parallel rectangle) or is a right
//!    triangle with axis-parallel legs (its vertices are corners of its box): there it is the
//!    centre of the box. That keeps the two triangles of a square together (their centroids
//!    may fall in two squares, their boxes are the square), so a triangulated Cartesian grid
//!    agglomerates into rectangles, on which HMM solves on the cells ([`crate::assembly`]'s
//!    `two_point`). On other cells the centroid is kept, so that the coarse meshes of
//!    unstructured meshes do not change (the measurements behind both choices are in
//!    `replication/BENCHMARKS.md`, "Measurements behind the defaults"). Aggregates are the
//!    connected components (through interior edges) of the cells sharing a key, so an
//!    aggregate never mixes two materials (cell tags) and is a patch of about (H/h)² fine
//!    cells. Aggregates of area below H²/4 (slivers along the boundary or along material
//!    interfaces) are merged into the neighbour of the same tag with which they share the
//!    longest interface.
//! 2. **Corners.** A fine vertex is a corner (a coarse vertex) if it lies on the boundary of
//!    the domain, or at least three interface edges meet there (an interface edge separates two
//!    aggregates). Between two corners, the interface of two aggregates is a chain of fine
//!    edges; it is replaced by the straight segment joining its corners. Both aggregates use the
//!    same segment, so the straightened cells still tile the domain, whose boundary is kept
//!    exactly: every fine boundary edge is a coarse boundary edge with its tag, so Dirichlet,
//!    Neumann and Signorini data and the Signorini unknowns carry over one to one.
//! 3. **Checks.** A straightened aggregate is kept if its boundary is one loop without pinches
//!    and the polygon through its corners is star-shaped with respect to its centroid with some
//!    margin: every d_{K,σ} ≥ [`MIN_DIST_RATIO`] · r_K (r_K the largest distance from the
//!    centroid to a corner), and the angles of its sides seen from the centroid are positive and
//!    add up to 2π (so the polygon is simple). An aggregate that fails is *dissolved*: its fine
//!    cells become coarse cells of their own, with all their vertices as corners. This can only
//!    add corners to neighbours, and is repeated until no aggregate fails; a fine cell alone is
//!    always admissible, so it terminates. A repetition checks again only the aggregates with a
//!    vertex that became a corner, and the new one-cell ones: the polygon of an aggregate
//!    depends on nothing but its fine cells and the corners among their vertices.
//! 4. The coarse mesh is then built and validated like any input mesh
//!    ([`PolyMesh::from_cells_tagged`]: conformity, no overlap, star-shapedness), in
//!    O(n log n). A failure there (two straightened chords crossing) is returned as an error: the
//!    caller then does without coarse meshes.
//!
//! Cost: linear in the fine mesh apart from sorting the half-edges of each aggregate.
//!
//! ## Parallelism
//! The passes over all fine edges (which cells to join in step 1, the interfaces of small
//! aggregates in step 1, in edge order) and over all aggregates (the boundary loop and checks
//! of step 3, each aggregate on its own from the fine cells of its bucket) run on every core
//! (rayon); what depends on an order (the unions, the first-appearance numbering, the sums of
//! areas and interface lengths) stays sequential, in the order above. Each parallel result is
//! collected in index order and is a function of its index alone, so the coarse meshes do not
//! depend on the number of threads (the tests check them against the sequential definition).

use super::{NO_CELL, Point, PolyMesh, polygon_area_centroid};
use crate::error::MeshError;
use rayon::prelude::*;

/// Marker for "no coarse edge" in [`Agglomeration::boundary_edge_of`] (interior fine edges).
pub const NO_EDGE: u32 = u32::MAX;

/// Least ratio d_{K,σ} / r_K of a straightened aggregate (see the module docs): below it the
/// aggregate is dissolved, so coarse cells stay reasonably shaped.
pub const MIN_DIST_RATIO: f64 = 0.1;

/// Aggregates smaller than this fraction of H² are merged into a neighbour.
const SMALL_FRACTION: f64 = 0.25;

/// Least number of items (fine edges, aggregates) of one parallel task.
const MIN_TASK: usize = 1 << 12;

/// Rounds of dissolution before giving up (each dissolves at least one aggregate; in practice
/// one or two rounds suffice).
const MAX_ROUNDS: usize = 50;

/// A coarse mesh made of unions of the cells of a fine one, and the maps between them.
#[derive(Debug, Clone)]
pub struct Agglomeration {
    /// The coarse mesh (validated; cell tags and boundary tags from the fine mesh).
    pub mesh: PolyMesh,
    /// The coarse cell of each fine cell (32-bit, as the meshes' own indices: these maps are
    /// the size of the fine mesh).
    pub cell_of: Vec<u32>,
    /// The coarse edge of each fine boundary edge (the same segment); [`NO_EDGE`] for interior
    /// fine edges.
    pub boundary_edge_of: Vec<u32>,
    /// Fine cells left alone because their aggregate could not be straightened.
    pub dissolved_cells: usize,
}

/// Agglomerates `fine` into cells of size about `size` (see the module docs).
pub fn agglomerate(fine: &PolyMesh, size: f64) -> Result<Agglomeration, MeshError> {
    if !(size.is_finite() && size > 0.0) {
        return Err(MeshError::NonConforming(format!(
            "agglomeration size must be positive and finite, got {size}"
        )));
    }
    let mut label = initial_aggregates(fine, size);
    merge_small(fine, &mut label, SMALL_FRACTION * size * size);
    let mut dissolved = vec![false; fine.n_cells()];
    let mut previous: Option<Previous> = None;
    for _ in 0..MAX_ROUNDS {
        let corner = corners(fine, &label, &dissolved);
        let polys = polygons(fine, &label, &corner, previous.take());
        let failed: Vec<bool> = polys.iter().map(Option::is_none).collect();
        if !failed.contains(&true) {
            return build(fine, label, &corner, polys, &dissolved);
        }
        dissolve(&mut label, &mut dissolved, &failed);
        let id = renumber(&mut label);
        // the aggregates that were kept, under their new labels
        let mut old_of = vec![usize::MAX; label.iter().max().map_or(0, |m| m + 1)];
        for (a, _) in failed.iter().enumerate().filter(|(_, f)| !**f) {
            old_of[id[a]] = a;
        }
        previous = Some(Previous {
            corner,
            polys,
            old_of,
        });
    }
    Err(MeshError::NonConforming(format!(
        "agglomeration did not settle in {MAX_ROUNDS} rounds"
    )))
}

/// Union–find with path halving.
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Dense labels 0.. in order of first appearance of each root.
fn labels_from_roots(parent: &mut [usize]) -> Vec<usize> {
    let n = parent.len();
    let mut id = vec![usize::MAX; n];
    let mut next = 0;
    (0..n)
        .map(|k| {
            let r = find(parent, k);
            if id[r] == usize::MAX {
                id[r] = next;
                next += 1;
            }
            id[r]
        })
        .collect()
}

/// ⌊x⌋ as an integer: exactly `x.floor() as i64` (saturating, NaN → 0), without the call to
/// libm's `floor` that the baseline x86-64 target makes.
#[inline]
pub(crate) fn floor_i64(x: f64) -> i64 {
    let t = x as i64; // rounds towards zero, saturating
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Dense labels 0.. of the components of a union–find forest whose roots are the least
/// elements of their components and where `parent[i] ≤ i` (in order of first appearance, as
/// [`labels_from_roots`] numbers them): one pass, as the parent of i is labelled before i.
fn labels_from_least_roots(parent: &[usize]) -> Vec<usize> {
    let mut label = Vec::with_capacity(parent.len());
    let mut next = 0;
    for (i, &p) in parent.iter().enumerate() {
        if p == i {
            label.push(next);
            next += 1;
        } else {
            let l = label[p];
            label.push(l);
        }
    }
    label
}

/// Relative tolerance of [`key_point`]'s comparison of a cell's area with its bounding box's.
const BOX_TOL: f64 = 1e-9;

/// The point that places cell k in a square of step 1 (module docs): the centre of its
/// bounding box [x_min, x_max] × [y_min, y_max] if the cell fills the box (its area is the
/// box's up to [`BOX_TOL`]: an axis-parallel rectangle, possibly with more vertices along its
/// sides) or is a triangle whose three vertices are corners of the box (a right triangle with
/// axis-parallel legs, half of the box; the comparison is exact, the box being made of the
/// vertices' own coordinates); its centroid otherwise. Computed from the cell's vertices;
/// [`initial_aggregates`] evaluates it once per cell.
pub(crate) fn key_point(mesh: &PolyMesh, k: usize) -> Point {
    let c = mesh.cell_vertices(k);
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for &v in c {
        let p = mesh.vertex(v as usize);
        b = [
            b[0].min(p[0]),
            b[1].min(p[1]),
            b[2].max(p[0]),
            b[3].max(p[1]),
        ];
    }
    let corner = |v: &u32| {
        let p = mesh.vertex(*v as usize);
        (p[0] == b[0] || p[0] == b[2]) && (p[1] == b[1] || p[1] == b[3])
    };
    // the corner test first: it needs no area, which a right triangle then skips (the box
    // cover of 2M triangles evaluates this once per triangle)
    let fills = || {
        let box_area = (b[2] - b[0]) * (b[3] - b[1]);
        (mesh.measure(k) - box_area).abs() <= BOX_TOL * box_area
    };
    if (c.len() == 3 && c.iter().all(corner)) || fills() {
        [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])]
    } else {
        mesh.centroid(k)
    }
}

/// Step 1: connected components of the cells with the same (square, tag) key.
fn initial_aggregates(fine: &PolyMesh, size: f64) -> Vec<usize> {
    let bb = fine.bounding_box();
    // the key of each cell, computed once (in parallel, in cell order), not per edge
    let keys: Vec<(i64, i64, i32)> = (0..fine.n_cells())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|k| {
            let c = key_point(fine, k);
            (
                floor_i64((c[0] - bb.x[0]) / size),
                floor_i64((c[1] - bb.y[0]) / size),
                fine.cell_tag(k),
            )
        })
        .collect();
    // whether each edge joins two cells of one key (in parallel), then the unions in edge order
    let joins: Vec<bool> = (0..fine.n_edges())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .map(|e| {
            let [a, b] = fine.edge_cells(e);
            b != NO_CELL && keys[a] == keys[b]
        })
        .collect();
    drop(keys);
    let pairs = (joins.iter().enumerate())
        .filter(|(_, j)| **j)
        .map(|(e, _)| fine.edge_cells(e));
    components(fine.n_cells(), pairs)
}

/// Dense labels 0.. (in order of first appearance) of the connected components of the graph
/// on `n` nodes with the edges `pairs`, joined in the order given.
pub(crate) fn components(n: usize, pairs: impl Iterator<Item = [usize; 2]>) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    for [a, b] in pairs {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    // the unions link the larger root to the smaller one and path halving only lowers parents
    labels_from_least_roots(&parent)
}

/// Merges the aggregates of area below `min_area` into the neighbour of the same tag with the
/// longest common interface (one pass, in label order).
fn merge_small(fine: &PolyMesh, label: &mut [usize], min_area: f64) {
    let na = label.iter().max().map_or(0, |m| m + 1);
    let mut area = vec![0.0; na];
    for (k, &a) in label.iter().enumerate() {
        area[a] += fine.measure(k);
    }
    // interfaces (a, b, length) between aggregates of the same tag, in edge order (found in
    // parallel), then both directions
    let small: Vec<(usize, usize, f64)> = (0..fine.n_edges())
        .into_par_iter()
        .with_min_len(MIN_TASK)
        .filter_map(|e| {
            let [k, l] = fine.edge_cells(e);
            if l == NO_CELL || fine.cell_tag(k) != fine.cell_tag(l) {
                return None;
            }
            let (a, b) = (label[k], label[l]);
            (a != b && (area[a] < min_area || area[b] < min_area))
                .then(|| (a, b, fine.edge_measure(e)))
        })
        .collect();
    merge_into_neighbours(label, &area, &small, min_area);
}

/// Merges each aggregate `a` with `area[a] < min_area` into the neighbour with which it shares
/// the largest interface measure, from the interfaces `small` (a, b, measure) between
/// aggregates of the same tag (each listed once, in a fixed order; at least one side small),
/// then renumbers `label` densely in order of first appearance (one pass, in label order).
pub(crate) fn merge_into_neighbours(
    label: &mut [usize],
    area: &[f64],
    small: &[(usize, usize, f64)],
    min_area: f64,
) {
    let na = area.len();
    let mut iface: Vec<(usize, usize, f64)> = Vec::with_capacity(2 * small.len());
    for &(a, b, len) in small {
        iface.push((a, b, len));
        iface.push((b, a, len));
    }
    iface.sort_by_key(|x| (x.0, x.1));
    let mut parent: Vec<usize> = (0..na).collect();
    let mut i = 0;
    while i < iface.len() {
        let a = iface[i].0;
        let mut best: Option<(usize, f64)> = None;
        while i < iface.len() && iface[i].0 == a {
            let b = iface[i].1;
            let mut len = 0.0;
            while i < iface.len() && iface[i].0 == a && iface[i].1 == b {
                len += iface[i].2;
                i += 1;
            }
            if best.is_none_or(|(_, l)| len > l) {
                best = Some((b, len));
            }
        }
        if let Some((b, _)) = best
            && area[a] < min_area
        {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra] = rb;
            }
        }
    }
    // label ← renumber(agg ∘ label), in one pass
    let agg = labels_from_roots(&mut parent);
    let mut id = vec![usize::MAX; na];
    let mut next = 0;
    for l in label.iter_mut() {
        let a = agg[*l];
        if id[a] == usize::MAX {
            id[a] = next;
            next += 1;
        }
        *l = id[a];
    }
}

/// Renumbers `label` densely in order of first appearance; returns the new label of each old
/// one (`usize::MAX` for those that do not appear).
pub(crate) fn renumber(label: &mut [usize]) -> Vec<usize> {
    let na = label.iter().max().map_or(0, |m| m + 1);
    let mut id = vec![usize::MAX; na];
    let mut next = 0;
    for a in label.iter_mut() {
        if id[*a] == usize::MAX {
            id[*a] = next;
            next += 1;
        }
        *a = id[*a];
    }
    id
}

/// Gives each fine cell of the aggregates `a` with `failed[a]` a label of its own (fresh labels
/// at the end), in one pass.
pub(crate) fn dissolve(label: &mut [usize], dissolved: &mut [bool], failed: &[bool]) {
    let mut next = failed.len();
    for (k, l) in label.iter_mut().enumerate() {
        if failed[*l] {
            dissolved[k] = true;
            *l = next;
            next += 1;
        }
    }
}

/// Step 2: the corners (see the module docs), and every vertex of a dissolved cell.
fn corners(fine: &PolyMesh, label: &[usize], dissolved: &[bool]) -> Vec<bool> {
    let mut count = vec![0u32; fine.n_vertices()];
    let mut corner = vec![false; fine.n_vertices()];
    for e in 0..fine.n_edges() {
        let [k, l] = fine.edge_cells(e);
        let [v, w] = fine.edge_vertices(e);
        if l == NO_CELL {
            corner[v] = true;
            corner[w] = true;
        } else if label[k] != label[l] {
            count[v] += 1;
            count[w] += 1;
        }
    }
    for (k, &d) in dissolved.iter().enumerate() {
        if d {
            for &v in fine.cell_vertices(k) {
                corner[v as usize] = true;
            }
        }
    }
    for (c, &n) in corner.iter_mut().zip(&count) {
        *c |= n >= 3;
    }
    corner
}

/// The fine cells of each aggregate, in increasing order (CSR: offsets, cell ids, which fit
/// in 32 bits as the mesh stores them so).
fn buckets(label: &[usize], na: usize) -> (Vec<usize>, Vec<u32>) {
    super::buckets::counting_sort(na, label.iter().map(|&a| Some(a)), |k| k as u32)
}

/// What a round of [`polygons`] found, for the next round after a dissolution.
struct Previous {
    /// The corners of that round.
    corner: Vec<bool>,
    /// Its polygons, under its labels.
    polys: Vec<Option<Vec<usize>>>,
    /// The label in that round of each aggregate kept since (`usize::MAX` for the fine cells
    /// dissolved since).
    old_of: Vec<usize>,
}

/// Step 3: for each aggregate, its corners in counter-clockwise order, or `None` if its
/// straightened polygon is not admissible (several boundary loops, a pinch, fewer than three
/// corners, or not star-shaped with margin). Aggregates of one cell are always admissible.
/// The aggregates are traced in parallel, each from the fine cells of its bucket.
///
/// After a dissolution (`previous`), an aggregate that was kept has the same fine cells, and
/// its polygon depends only on them and on the corner flags of their vertices (dissolving only
/// adds corners, at the vertices of the dissolved cells): if none of these flags changed, its
/// polygon is the previous one and is not traced again.
fn polygons(
    fine: &PolyMesh,
    label: &[usize],
    corner: &[bool],
    previous: Option<Previous>,
) -> Vec<Option<Vec<usize>>> {
    let na = label.iter().max().map_or(0, |m| m + 1);
    let (ptr, cells) = buckets(label, na);
    // Err(old label) for a polygon to take from the previous round
    let traced: Vec<Result<Option<Vec<usize>>, usize>> = (0..na)
        .into_par_iter()
        .with_min_len(MIN_TASK / 16)
        .map_init(Vec::new, |half, a| {
            let members = &cells[ptr[a]..ptr[a + 1]];
            if let Some(p) = &previous
                && let Some(old) = p.old_of.get(a).copied().filter(|&o| o != usize::MAX)
                && members.iter().all(|&k| {
                    fine.cell_vertices(k as usize)
                        .iter()
                        .all(|&v| corner[v as usize] == p.corner[v as usize])
                })
            {
                return Err(old);
            }
            // boundary half-edges (from, to) of aggregate a, counter-clockwise for it
            half.clear();
            for &k in members {
                let k = k as usize;
                let (vs, es) = (fine.cell_vertices(k), fine.cell_edges(k));
                for (i, &e) in es.iter().enumerate() {
                    let [c0, c1] = fine.edge_cells(e as usize);
                    let other = if c0 == k { c1 } else { c0 };
                    if other == NO_CELL || label[other] != a {
                        let (from, to) = (vs[i], vs[(i + 1) % vs.len()]);
                        half.push((from as usize, to as usize));
                    }
                }
            }
            half.sort_unstable();
            Ok(trace(fine, half, corner, members.len() == 1))
        })
        .collect();
    let mut kept = previous.map(|p| p.polys).unwrap_or_default();
    traced
        .into_iter()
        .map(|t| t.unwrap_or_else(|old| std::mem::take(&mut kept[old])))
        .collect()
}

/// The corners of one aggregate's boundary loop (its half-edges (from, to) sorted), or `None`
/// if it is not admissible.
fn trace(
    fine: &PolyMesh,
    half: &[(usize, usize)],
    corner: &[bool],
    single: bool,
) -> Option<Vec<usize>> {
    if half.windows(2).any(|w| w[0].0 == w[1].0) {
        return None; // two half-edges leave one vertex: a pinch
    }
    let next = |v: usize| -> Option<usize> {
        half.binary_search_by(|h| h.0.cmp(&v))
            .ok()
            .map(|i| half[i].1)
    };
    let start = half.iter().map(|h| h.0).find(|&v| corner[v])?;
    let mut poly = vec![start];
    let mut v = next(start)?;
    let mut steps = 1;
    while v != start {
        if corner[v] {
            poly.push(v);
        }
        v = next(v)?;
        steps += 1;
        if steps > half.len() {
            return None;
        }
    }
    if steps != half.len() || poly.len() < 3 {
        return None; // several loops (a hole), or a lens
    }
    if single || admissible(&poly.iter().map(|&v| fine.vertex(v)).collect::<Vec<_>>()) {
        Some(poly)
    } else {
        None
    }
}

/// Whether the counter-clockwise polygon `p` is star-shaped with respect to its centroid with
/// margin [`MIN_DIST_RATIO`] and simple (angles seen from the centroid positive, summing to 2π).
fn admissible(p: &[Point]) -> bool {
    let (area, c) = polygon_area_centroid(p);
    if !(area > 0.0) {
        return false;
    }
    let r = p
        .iter()
        .map(|q| (q[0] - c[0]).hypot(q[1] - c[1]))
        .fold(0.0, f64::max);
    let mut angle = 0.0;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        let (u, w) = ([a[0] - c[0], a[1] - c[1]], [b[0] - c[0], b[1] - c[1]]);
        let cross = u[0] * w[1] - u[1] * w[0];
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        if !(cross / len >= MIN_DIST_RATIO * r) {
            return false;
        }
        angle += cross.atan2(u[0] * w[0] + u[1] * w[1]);
    }
    (angle - std::f64::consts::TAU).abs() < 1e-6
}

/// Step 4: the coarse mesh from the admissible polygons.
fn build(
    fine: &PolyMesh,
    label: Vec<usize>,
    corner: &[bool],
    polys: Vec<Option<Vec<usize>>>,
    dissolved: &[bool],
) -> Result<Agglomeration, MeshError> {
    let mut id = vec![usize::MAX; fine.n_vertices()];
    let mut vertices = Vec::new();
    for (v, &c) in corner.iter().enumerate() {
        if c {
            id[v] = vertices.len();
            vertices.push(fine.vertex(v));
        }
    }
    let cells: Vec<Vec<usize>> = polys
        .into_par_iter()
        .with_min_len(MIN_TASK / 16)
        .map(|p| p.unwrap_or_default().into_iter().map(|v| id[v]).collect())
        .collect();
    let tagged: Vec<(usize, usize, i32)> = fine
        .boundary_edges()
        .iter()
        .filter(|&&e| fine.edge_tag(e) != 0)
        .map(|&e| {
            let [a, b] = fine.edge_vertices(e);
            (id[a], id[b], fine.edge_tag(e))
        })
        .collect();
    let na = cells.len();
    let mut cell_tags = vec![0; na];
    for (k, &a) in label.iter().enumerate() {
        cell_tags[a] = fine.cell_tag(k);
    }
    let mesh = PolyMesh::from_cells_tagged(vertices, cells, &tagged)?.with_cell_tags(cell_tags)?;
    // fine boundary edge → coarse edge with the same (renumbered) end points
    let mut boundary_edge_of = vec![NO_EDGE; fine.n_edges()];
    for &e in fine.boundary_edges() {
        let [a, b] = fine.edge_vertices(e);
        let pos = mesh.boundary_position(id[a], id[b]).ok_or_else(|| {
            MeshError::NonConforming(format!(
                "agglomeration lost the boundary edge {e} ({a}, {b})"
            ))
        })?;
        boundary_edge_of[e] = mesh.boundary_edges()[pos] as u32;
    }
    // exact: the labels are coarse cells, and a mesh has fewer than u32::MAX cells and edges
    // (its build refuses more, `MeshError::TooManyEntities`)
    let cell_of = label.into_iter().map(|a| a as u32).collect();
    Ok(Agglomeration {
        mesh,
        cell_of,
        boundary_edge_of,
        dissolved_cells: dissolved.iter().filter(|&&d| d).count(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::cartesian_rect;

    fn total_area(m: &PolyMesh) -> f64 {
        (0..m.n_cells()).map(|k| m.measure(k)).sum()
    }

    #[test]
    fn cartesian_agglomerates_to_cartesian() {
        let fine = cartesian_rect(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let agg = agglomerate(&fine, 0.125).unwrap();
        assert_eq!(agg.mesh.n_cells(), 64);
        assert_eq!(agg.dissolved_cells, 0);
        assert!((total_area(&agg.mesh) - 1.0).abs() < 1e-12);
        // every coarse cell holds 16 fine cells, and contains their centroids' square
        let mut count = [0usize; 64];
        for &c in &agg.cell_of {
            count[c as usize] += 1;
        }
        assert!(count.iter().all(|&n| n == 16));
        for (k, &c) in agg.cell_of.iter().enumerate() {
            let (p, q) = (fine.centroid(k), agg.mesh.centroid(c as usize));
            assert!((p[0] - q[0]).abs() < 0.0625 && (p[1] - q[1]).abs() < 0.0625);
        }
        // boundary edges carry over one to one
        let mut seen = std::collections::HashSet::new();
        for &e in fine.boundary_edges() {
            let ce = agg.boundary_edge_of[e] as usize;
            assert!(agg.mesh.is_boundary_edge(ce));
            assert!(seen.insert(ce));
            assert!((agg.mesh.edge_measure(ce) - fine.edge_measure(e)).abs() < 1e-15);
        }
        assert_eq!(seen.len(), agg.mesh.boundary_edges().len());
    }

    #[test]
    fn cells_placed_by_their_box() {
        use crate::mesh::generate::cartesian_triangles;
        // whether key_point is the box centre rather than the centroid (both are exact here)
        let by_box = |m: &PolyMesh| -> Vec<bool> {
            (0..m.n_cells())
                .map(|k| {
                    let p = key_point(m, k);
                    let b = m.cell_vertices(k).iter().map(|&v| m.vertex(v as usize));
                    let lo = b
                        .clone()
                        .fold([f64::INFINITY; 2], |a, q| [a[0].min(q[0]), a[1].min(q[1])]);
                    let hi = b.fold([f64::NEG_INFINITY; 2], |a, q| {
                        [a[0].max(q[0]), a[1].max(q[1])]
                    });
                    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
                    assert!(p == centre || p == m.centroid(k), "cell {k}: {p:?}");
                    p == centre
                })
                .collect()
        };
        // the two triangles of each rectangle of a triangulated grid (their centroids differ
        // from the rectangle's centre)
        let tri = cartesian_triangles(5, 4, [0.0, 1.0], [0.0, 0.7]).unwrap();
        assert!(by_box(&tri).iter().all(|&b| b));
        // a right triangle with axis-parallel legs, next to a half square cut in three through
        // an inner point, whose triangles are not placed by their boxes
        let pts = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.7, 0.6]];
        let cells = vec![vec![0, 1, 3], vec![1, 2, 4], vec![2, 3, 4], vec![3, 1, 4]];
        let lone = PolyMesh::from_cells(pts, cells).unwrap();
        assert_eq!(by_box(&lone), vec![true, false, false, false]);
        // triangles with one side parallel to an axis fill half their box too (the lattices of
        // gmsh's frontal algorithm are full of them), without being right triangles
        let pts = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.8], [1.5, 0.8]];
        let lattice = PolyMesh::from_cells(pts, vec![vec![0, 1, 2], vec![1, 3, 2]]).unwrap();
        assert_eq!(by_box(&lattice), vec![false; 2]);
    }

    #[test]
    fn gmsh_meshes_keep_area_tags_and_boundary() {
        // the two-material dam of problems/signorini-layers.toml (cell tags) and the L-shape
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
        for name in ["dam.msh", "lshape.msh", "hole.msh"] {
            let fine =
                crate::mesh::io::read_mesh(dir.join(name), crate::budget::MemoryBudget::DEFAULT)
                    .unwrap();
            let area = total_area(&fine);
            let size = (area / (fine.n_cells() / 16) as f64).sqrt();
            let agg = agglomerate(&fine, size).unwrap();
            let coarse = &agg.mesh;
            assert!(
                coarse.n_cells() * 4 < fine.n_cells(),
                "{name}: {} cells",
                coarse.n_cells()
            );
            assert!((total_area(coarse) - area).abs() < 1e-12 * area, "{name}");
            // a coarse cell holds fine cells of one tag, and has that tag
            for (k, &c) in agg.cell_of.iter().enumerate() {
                assert_eq!(
                    fine.cell_tag(k),
                    coarse.cell_tag(c as usize),
                    "{name}: cell {k}"
                );
            }
            // every boundary edge is kept, with its tag
            for &e in fine.boundary_edges() {
                let ce = agg.boundary_edge_of[e] as usize;
                assert_eq!(fine.edge_tag(e), coarse.edge_tag(ce), "{name}: edge {e}");
                assert_eq!(fine.edge_midpoint(e), coarse.edge_midpoint(ce));
            }
            assert_eq!(coarse.boundary_edges().len(), fine.boundary_edges().len());
        }
    }

    /// A fingerprint of every part of an agglomeration, bit for bit (FNV-1a over the labels,
    /// the boundary map, the coarse vertices' bits, cells, edges and tags).
    fn fingerprint(a: &Agglomeration) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            for byte in x.to_le_bytes() {
                h = (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
            }
        };
        a.cell_of.iter().for_each(|&c| eat(u64::from(c)));
        // the marker as it was when the maps were usize, so the pinned values still hold
        let wide = |e: u32| if e == NO_EDGE { u64::MAX } else { u64::from(e) };
        a.boundary_edge_of.iter().for_each(|&e| eat(wide(e)));
        eat(a.dissolved_cells as u64);
        let m = &a.mesh;
        for v in m.vertices() {
            eat(v[0].to_bits());
            eat(v[1].to_bits());
        }
        for k in 0..m.n_cells() {
            eat(m.cell_vertices(k).len() as u64);
            m.cell_vertices(k).iter().for_each(|&v| eat(u64::from(v)));
            m.cell_edges(k).iter().for_each(|&e| eat(u64::from(e)));
            eat(m.cell_tag(k) as u64);
        }
        for e in 0..m.n_edges() {
            m.edge_vertices(e).iter().for_each(|&v| eat(v as u64));
            m.edge_cells(e).iter().for_each(|&c| eat(c as u64));
            eat(m.edge_tag(e) as u64);
        }
        h
    }

    /// Fingerprints of the agglomerations of [`agglomeration_does_not_depend_on_threads`]'s
    /// cases, on one thread; the test compares 1, 2 and 3 threads with them, so that any
    /// change of the agglomeration fails it. The grids (cases 0-3), the gmsh meshes (cases
    /// 4-6) and the sheared grid (case 7) exercise both keys of `key_point` (box centre and
    /// centroid). Where each value was computed: `replication/BENCHMARKS.md` ("Measurements
    /// behind the defaults"); those of the gmsh meshes were computed again when the reader
    /// began numbering the vertices in space order (`mesh::renumber::space_order`).
    const PINNED_FINGERPRINTS: [u64; 24] = [
        0x25644aaa565376d3,
        0x9c26ca14ef49281f,
        0x53fa66213d582242,
        0x07789c8ea0dbd937,
        0xa75f3ce82ed31551,
        0x95dee4a3eadeba74,
        0x297d73cce314784f,
        0xa515823bca22620d,
        0x624d0663259e1db7,
        0x10f97bfdf1e9b6aa,
        0xfeca08a6cf36bc43,
        0xbf2df633a0aae56d,
        0xa4237d9c2dbaa995,
        0x8eafffa170514af8,
        0x1857a6957b4c1d9a,
        0xd16acb4f183c49e1,
        0xa8b5bfd862d18da5,
        0xda252e597fa135a0,
        0x8ceb09be1870319a,
        0x0cdffae9c64ff6f8,
        0xf8b1e4397ff1265f,
        0xcf224259b493ecc0,
        0x72f7091ec4efcc18,
        0x6951c6558ad44ec5,
    ];

    #[test]
    fn agglomeration_does_not_depend_on_threads() {
        use crate::mesh::generate::cartesian_triangles;
        // the ex9 meshes (triangulated grids), a Cartesian grid, the gmsh meshes and a sheared
        // grid
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
        let mut cases = vec![
            cartesian_triangles(256, 256, [-2.0, 2.0], [-2.0, 2.0]).unwrap(),
            cartesian_triangles(200, 120, [0.0, 1.0], [0.0, 0.7]).unwrap(),
            cartesian_rect(300, 300, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        ];
        // a polygonal mesh: the next level of the warm start agglomerates an agglomeration
        let size = (16.0 / (cases[0].n_cells() / 16) as f64).sqrt();
        let coarse = agglomerate(&cases[0], size).unwrap().mesh;
        cases.push(coarse);
        for name in ["dam.msh", "lshape.msh", "hole.msh"] {
            cases.push(
                crate::mesh::io::read_mesh(dir.join(name), crate::budget::MemoryBudget::DEFAULT)
                    .unwrap(),
            );
        }
        // a sheared triangulated grid with its inner vertices moved by up to 0.3 h (a fixed
        // pseudo-random pattern): some aggregates fail and are dissolved, so that later rounds
        // reuse polygons
        let (nx, ny) = (120, 100);
        let grid = cartesian_triangles(nx, ny, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let jitter = |i: usize, prime: usize, m: usize, n: usize| {
            0.6 * (((i * prime) % m) as f64 / m as f64 - 0.5) / n as f64
        };
        let sheared: Vec<Point> = (grid.vertices().iter().enumerate())
            .map(|(i, p)| {
                let inner =
                    (1e-9..1.0 - 1e-9).contains(&p[0]) && (1e-9..1.0 - 1e-9).contains(&p[1]);
                let (jx, jy) = if inner {
                    (jitter(i, 7919, 1000, nx), jitter(i, 104_729, 997, ny))
                } else {
                    (0.0, 0.0)
                };
                [p[0] + jx + 0.37 * p[1], p[1] + jy]
            })
            .collect();
        let cells = (0..grid.n_cells())
            .map(|k| grid.cell_vertices(k).iter().map(|&v| v as usize).collect())
            .collect();
        cases.push(PolyMesh::from_cells(sheared, cells).unwrap());
        let pools: Vec<_> = [1, 2, 3]
            .iter()
            .map(|&t| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap()
            })
            .collect();
        let mut dissolved = 0;
        let mut pinned = PINNED_FINGERPRINTS.iter();
        for (c, fine) in cases.iter().enumerate() {
            let area = total_area(fine);
            // the fine cells per coarse cell of the warm start's levels (HMM, P1, and above)
            for per_cell in [8, 16, 48] {
                let size = (area / (fine.n_cells() / per_cell) as f64).sqrt();
                let want = pinned.next().copied();
                for (t, pool) in pools.iter().enumerate() {
                    let got = pool.install(|| agglomerate(fine, size)).unwrap();
                    let what = format!("case {c}, size {size}, {} threads", t + 1);
                    assert_eq!(Some(fingerprint(&got)), want, "{what}");
                    dissolved += got.dissolved_cells;
                }
            }
        }
        assert!(dissolved > 0, "no case dissolves an aggregate");
    }

    #[test]
    fn floor_is_libm_floor() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - f64::EPSILON,
            -1.0 + f64::EPSILON / 2.0,
            2f64.powi(52) + 0.5,
            -(2f64.powi(52)) - 1.5,
            2f64.powi(53) + 2.0,
            2f64.powi(63),
            -(2f64.powi(63)),
            -(2f64.powi(63)) * (1.0 + f64::EPSILON),
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        xs.extend((-2000..2000).map(|i| i as f64 * 0.37));
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn bad_size_is_an_error() {
        let fine = cartesian_rect(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
        for size in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(agglomerate(&fine, size).is_err(), "{size}");
        }
    }
}
