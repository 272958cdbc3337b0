//! The checks of [`PolyMesh::from_cells`](super::PolyMesh::from_cells): what a mesh must satisfy
//! before any scheme sees it, why, and at what cost.
//!
//! A mesh is a list of vertices and of cells given by vertex lists. HMM and P1 need a
//! *partition* of a polygonal domain into simple polygons, each strictly star-shaped with respect
//! to its centroid, meeting edge to edge. Anything else gives a wrong answer without any warning
//! (overlapping cells count their common part twice; a self-crossing cell has a meaningless
//! centroid and normals), so every property is checked, in this order, and the first violation is
//! returned as a [`MeshError`] naming the cells, edges or vertices at fault. n below is the size of
//! the input (vertices plus cell vertex lists); m the number of vertices of one cell.
//!
//! | # | check | error | cost |
//! |---|---|---|---|
//! | 1 | at least one cell; finite coordinates | [`MeshError::Empty`], [`MeshError::NonFiniteVertex`] | O(n) |
//! | 2 | every cell has 3 to [`MAX_CELL_VERTICES`] vertices, all existing | [`MeshError::BadCell`], [`MeshError::CellTooLarge`], [`MeshError::VertexOutOfRange`] | O(n) |
//! | 3 | no cell lists a vertex twice | [`MeshError::BadCell`] | O(m) for m ≤ 16 (pairs), else O(m log m) (sort) |
//! | 4 | non-negligible area: \|K\| > 10⁻¹⁴ h_K² (the diameter h_K is the largest vertex distance) | [`MeshError::DegenerateCell`] | O(m) area; h_K by pairs for m ≤ 16, else convex hull and rotating calipers, O(m log m) |
//! | 5 | every vertex is used | [`MeshError::UnusedVertex`] | O(n) |
//! | 6 | no two vertices closer than 10⁻¹³ × (extent of the coordinates) in both x and y | [`MeshError::DuplicateVertex`] | O(n log n): sort by square of a grid of that side, compare with the neighbouring squares |
//! | 7 | every edge has one or two cells, traversed in opposite directions | [`MeshError::BadEdge`] | O(n) |
//! | 8 | every cell is a simple polygon: no two sides meet except consecutive sides at their common vertex | [`MeshError::SelfIntersectingCell`] | per cell: O(m²) pairs for m ≤ 16, else the sweep below on its sides, O(m log m) |
//! | 9 | every cell is strictly star-shaped with respect to its centroid: d_{K,σ} > 10⁻¹² h_K | [`MeshError::NotStarShaped`] | O(n) |
//! | 10 | the boundary splits into closed loops, none pinched, none of zero area (hanging nodes) | [`MeshError::NonConforming`] | O(n) |
//! | 11 | no two edges meet except at a common vertex (crossing, touching or overlapping edges of different cells) | [`MeshError::CrossingEdges`] | O(n log n), a Shamos–Hoey sweep (module `mesh::sweep`) |
//! | 12 | cells do not overlap: a boundary loop lies inside a cell exactly if it turns clockwise (a hole), and the cell areas add up to the area enclosed by the loops, holes counted negatively (to 10⁻⁹, relative) | [`MeshError::OverlappingCells`] | O(n log n), the same sweep |
//!
//! All the geometric tests of 8, 11 and 12 use exact predicates (module `mesh::predicates`), so a
//! valid mesh is never rejected because of rounding.
//!
//! **Why 11 and 12 together exclude overlaps.** Once 1–10 hold, every cell is a simple
//! counter-clockwise polygon and interior edges are traversed once in each direction, so the
//! number of cells covering a point x equals the winding number around x of the boundary loops
//! (the interior edges cancel out). If, moreover, no two edges meet (11), the loops are disjoint
//! simple polygons, nested in one another, and the cells overlap somewhere exactly when some loop
//! has the wrong orientation for its nesting: an outer boundary (counter-clockwise) lying inside a
//! cell, or a hole (clockwise) lying in no cell. Check 12 looks at the point right below the
//! lowest vertex of every loop, found during the sweep of 11: it is inside a cell if the first
//! edge below it is an interior edge, or a boundary edge whose cell lies above it. Equivalently,
//! the area enclosed by the loops, counting holes negatively, must equal Σ_K |K| (which, by
//! Green's formula, is the area counted with orientations); the error reports both numbers.
//! Two nested squares (areas 1 and 0.25) give Σ_K |K| = 1.25 against 1 − 0.25 = 0.75.
//!
//! **Why a vertex limit.** HMM assembles, for every cell, dense local matrices of size m × m;
//! [`MAX_CELL_VERTICES`] = 1000 keeps one of them at 8 MB and its factorisation at about 10⁹
//! flops, while a cell of 3·10⁴ vertices would need 7 GB. No mesh of the benchmarks comes close
//! (their largest cells have 8 vertices).
//!
//! **Bounded cost elsewhere.** The readers stop at the first line that is not text and read no
//! file larger than a quarter of the memory budget ([`io`](super::io)); the generators refuse a
//! mesh whose estimated memory exceeds the budget ([`budget`](crate::budget)).

use super::predicates::{lex, orient, segments_meet, segments_overlap_from};
use super::sweep::{self, Sweep};
use super::{NO_CELL, Point, dist, polygon_area_centroid, side_normal_dist, sub};
use crate::budget::{AllocFailure, try_filled, try_vec};
use crate::error::MeshError;
use std::cmp::Ordering;

/// The largest number of vertices of a cell (see the module docs for why).
pub const MAX_CELL_VERTICES: usize = 1000;

/// Cells with at most this many vertices are checked by comparing all pairs (cheaper than
/// sorting at this size); larger ones by the O(m log m) methods.
const SMALL_CELL: usize = 16;

const NONE: usize = usize::MAX;

/// Cached geometry of the cells, as checks 2–5 compute it. The per-side quantities n_{K,σ} and
/// d_{K,σ} are not kept: the mesh recomputes them on demand ([`side_normal_dist`]), and check 9
/// only needs them one side at a time.
pub(crate) struct CellGeometry {
    /// Σ_K |K|, summed in the order of the cells (check 12).
    pub(crate) total_area: f64,
    /// h = max_K h_K.
    pub(crate) h: f64,
    /// The cells given clockwise, whose vertex lists were reversed: a bit per cell, or empty
    /// when there are none (the mesh recomputes |K| and x_K from the given order, see
    /// [`PolyMesh::area_centroid`](super::PolyMesh::area_centroid)).
    pub(crate) reversed: Vec<u64>,
    /// The first cell that is not strictly star-shaped (check 9, reported after checks 5–8).
    pub(crate) not_star_shaped: Option<MeshError>,
}

/// Checks 1 (finite coordinates), 2–5, and computes the geometry of every cell; clockwise cells
/// are reversed in place in `cell_verts`.
pub(crate) fn cell_geometry(
    vertices: &[Point],
    cell_ptr: &[usize],
    cell_verts: &mut [usize],
) -> Result<CellGeometry, MeshError> {
    let nv = vertices.len();
    let nc = cell_ptr.len().saturating_sub(1);
    if let Some(v) = vertices
        .iter()
        .position(|p| !p[0].is_finite() || !p[1].is_finite())
    {
        return Err(MeshError::NonFiniteVertex { vertex: v });
    }
    let mut g = CellGeometry {
        total_area: 0.0,
        h: 0.0,
        reversed: Vec::new(),
        not_star_shaped: None,
    };
    let mut used = try_filled(nv, false, "the used flags of the vertices")?;
    let mut pts: Vec<Point> = Vec::new();
    for k in 0..nc {
        let (s, e) = (cell_ptr[k], cell_ptr[k + 1]);
        check_cell_vertices(k, &cell_verts[s..e], nv)?;
        for &v in &cell_verts[s..e] {
            used[v] = true;
        }
        pts.clear();
        pts.extend(cell_verts[s..e].iter().map(|&v| vertices[v]));
        let (area, centroid) = polygon_area_centroid(&pts);
        let diam = diameter(&pts);
        if !(area.abs() > 1e-14 * diam * diam) {
            return Err(MeshError::DegenerateCell { cell: k, area });
        }
        // `area` is now non-zero and not NaN: negative means clockwise
        if area < 0.0 {
            cell_verts[s..e].reverse();
            pts.reverse();
            if g.reversed.is_empty() {
                g.reversed = try_filled(nc.div_ceil(64), 0u64, "the reversed cells")?;
            }
            g.reversed[k / 64] |= 1 << (k % 64);
        }
        if g.not_star_shaped.is_none() {
            g.not_star_shaped = check_star_shaped(k, &pts, centroid, diam).err();
        }
        g.total_area += area.abs();
        g.h = g.h.max(diam);
    }
    if let Some(v) = used.iter().position(|u| !u) {
        return Err(MeshError::UnusedVertex { vertex: v });
    }
    Ok(g)
}

/// Check 2 and 3 for cell `k` with vertex list `c`.
fn check_cell_vertices(k: usize, c: &[usize], nv: usize) -> Result<(), MeshError> {
    if c.len() < 3 {
        return Err(MeshError::BadCell {
            cell: k,
            msg: format!("has {} vertices, at least 3 are needed", c.len()),
        });
    }
    if c.len() > MAX_CELL_VERTICES {
        return Err(MeshError::CellTooLarge {
            cell: k,
            n_vertices: c.len(),
            max: MAX_CELL_VERTICES,
        });
    }
    if let Some(&v) = c.iter().find(|&&v| v >= nv) {
        return Err(MeshError::VertexOutOfRange {
            cell: k,
            vertex: v,
            n_vertices: nv,
        });
    }
    match repeated_vertex(c) {
        Some(v) => Err(MeshError::BadCell {
            cell: k,
            msg: format!("lists vertex {v} twice"),
        }),
        None => Ok(()),
    }
}

/// Check 9 for the counter-clockwise cell `k` with corners `pts` and centroid x_K: the first
/// side with d_{K,σ} ≤ 10⁻¹² h_K, as [`MeshError::NotStarShaped`]. d_{K,σ} is computed by
/// [`side_normal_dist`], exactly as [`PolyMesh::cell_dist`](super::PolyMesh::cell_dist) later
/// computes it from the stored vertices and centroid (the same bits).
fn check_star_shaped(k: usize, pts: &[Point], centroid: Point, diam: f64) -> Result<(), MeshError> {
    let n = pts.len();
    for i in 0..n {
        let (_, d) = side_normal_dist(pts[i], pts[(i + 1) % n], centroid);
        if !(d > 1e-12 * diam) {
            return Err(MeshError::NotStarShaped {
                cell: k,
                local_edge: i,
                dist: d,
            });
        }
    }
    Ok(())
}

/// A vertex listed twice in `c`: of those, the one listed first (check 3).
fn repeated_vertex(c: &[usize]) -> Option<usize> {
    if c.len() <= SMALL_CELL {
        return (0..c.len())
            .find(|&i| c[i + 1..].contains(&c[i]))
            .map(|i| c[i]);
    }
    let mut sorted: Vec<(usize, usize)> = c.iter().copied().zip(0..).collect();
    sorted.sort_unstable();
    // a run of equal vertices starts at its first listing; take the earliest such listing
    sorted
        .windows(2)
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| w[0])
        .min_by_key(|&(_, pos)| pos)
        .map(|(v, _)| v)
}

/// h_K, the largest distance between two of the points (check 4): all pairs for a small cell,
/// else the rotating calipers over the convex hull (the farthest pair is a pair of hull
/// vertices, and an antipodal one).
pub(crate) fn diameter(pts: &[Point]) -> f64 {
    if pts.len() <= SMALL_CELL {
        let mut d: f64 = 0.0;
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                d = d.max(dist(pts[i], pts[j]));
            }
        }
        return d;
    }
    let h = convex_hull(pts);
    let n = h.len();
    if n < 3 {
        return if n == 2 { dist(h[0], h[1]) } else { 0.0 };
    }
    let cross = |u: Point, v: Point| u[0] * v[1] - u[1] * v[0];
    let mut d: f64 = 0.0;
    let mut j = 1;
    for i in 0..n {
        let i1 = (i + 1) % n;
        let edge = sub(h[i1], h[i]);
        // the vertex farthest from the line of side (i, i+1): advance while the next one is
        // farther (the steps are bounded, for safety against rounding)
        let mut steps = 0;
        while steps < n && cross(edge, sub(h[(j + 1) % n], h[j])) > 0.0 {
            j = (j + 1) % n;
            steps += 1;
        }
        d = d.max(dist(h[i], h[j])).max(dist(h[i1], h[j]));
    }
    d
}

/// The convex hull of `pts`, counter-clockwise without collinear points (Andrew's monotone
/// chain with exact orientation tests), O(m log m).
fn convex_hull(pts: &[Point]) -> Vec<Point> {
    let mut p = pts.to_vec();
    p.sort_unstable_by(|a, b| lex(*a, *b));
    p.dedup_by(|a, b| lex(*a, *b) == Ordering::Equal);
    if p.len() < 3 {
        return p;
    }
    let chain = |points: &mut dyn Iterator<Item = Point>| {
        let mut h: Vec<Point> = Vec::new();
        for q in points {
            while h.len() >= 2 && orient(h[h.len() - 2], h[h.len() - 1], q) != Ordering::Greater {
                h.pop();
            }
            h.push(q);
        }
        // the last point starts the other chain
        h.pop();
        h
    };
    let mut hull = chain(&mut p.iter().copied());
    hull.extend(chain(&mut p.iter().rev().copied()));
    hull
}

/// Two sides of the polygon `pts` (local indices i < j; side i joins corners i and i+1) that
/// meet other than consecutive sides at their common corner, if any. All pairs for a small
/// polygon, else the sweep of [`super::sweep`] on its sides. The corners must be distinct points.
/// [`AllocFailure`] if the sweep's arrays (proportional to the polygon) cannot be allocated.
pub(crate) fn self_crossing(pts: &[Point]) -> Result<Option<(usize, usize)>, AllocFailure> {
    let m = pts.len();
    if m > SMALL_CELL {
        let mut sides: Vec<[usize; 2]> = try_vec(m, "the sides of a cell")?;
        sides.extend((0..m).map(|i| [i, (i + 1) % m]));
        return Ok(match sweep::first_collision(pts, &sides, &[])? {
            Sweep::Collision(i, j) => Some((i, j)),
            Sweep::Clear(_) => None,
        });
    }
    for i in 0..m {
        let (a, b) = (pts[i], pts[(i + 1) % m]);
        // the next side folds back onto this one
        if segments_overlap_from(b, a, pts[(i + 2) % m]) {
            return Ok(Some(if i + 1 < m { (i, i + 1) } else { (0, i) }));
        }
        // sides not adjacent to side i (with j > i; side m−1 is adjacent to side 0)
        let last = if i == 0 { m - 1 } else { m };
        for j in i + 2..last {
            if segments_meet(a, b, pts[j], pts[(j + 1) % m]) {
                return Ok(Some((i, j)));
            }
        }
    }
    Ok(None)
}

/// Check 8: every cell is a simple polygon.
pub(crate) fn check_simple_cells(
    vertices: &[Point],
    cell_ptr: &[usize],
    cell_verts: &[usize],
) -> Result<(), MeshError> {
    let mut pts: Vec<Point> = Vec::new();
    for k in 0..cell_ptr.len().saturating_sub(1) {
        let c = &cell_verts[cell_ptr[k]..cell_ptr[k + 1]];
        pts.clear();
        pts.extend(c.iter().map(|&v| vertices[v]));
        if let Some((i, j)) = self_crossing(&pts)? {
            let side = |i: usize| [c[i], c[(i + 1) % c.len()]];
            return Err(MeshError::SelfIntersectingCell {
                cell: k,
                sides: [side(i), side(j)],
            });
        }
    }
    Ok(())
}

/// Check 6: two vertices closer than `tol` = 10⁻¹³ × (extent of all coordinates) in both x and y.
///
/// The plane is cut into squares of side `tol`; two vertices in one square are duplicates, and
/// a vertex can only be a duplicate of one in a neighbouring square. So the vertices are sorted
/// by square (column, row), O(n log n) whatever the coordinates; if no square holds two
/// vertices, each vertex is compared with the vertices of the next square of its column and of
/// the three neighbouring squares of the next column, found by a pointer that only moves forward.
pub(crate) fn check_duplicate_vertices(vertices: &[Point]) -> Result<(), MeshError> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in vertices {
        lo = lo.min(p[0]).min(p[1]);
        hi = hi.max(p[0]).max(p[1]);
    }
    let extent = hi - lo;
    // halves avoid an overflow of hi − lo for coordinates near the largest double
    let half_tol = if extent.is_finite() {
        0.5 * (1e-13 * extent.max(1e-300))
    } else {
        1e-13 * (0.5 * hi - 0.5 * lo)
    };
    let tol = 2.0 * half_tol;
    let square = |x: f64| ((0.5 * x - 0.5 * lo) / half_tol).floor() as i64;
    let keys = super::buckets::sorted_point_keys(vertices, square)?;
    let duplicate = |a: usize, b: usize| {
        let (a, b) = (a.min(b), a.max(b));
        MeshError::DuplicateVertex {
            a,
            b,
            x: vertices[a][0],
            y: vertices[a][1],
        }
    };
    if let Some(w) = keys
        .windows(2)
        .find(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1))
    {
        return Err(duplicate(w[0].2, w[1].2));
    }
    let close = |a: usize, b: usize| {
        let (p, q) = (vertices[a], vertices[b]);
        (p[0] - q[0]).abs() <= tol && (p[1] - q[1]).abs() <= tol
    };
    let mut next_col = 0;
    for (i, &(cx, cy, a)) in keys.iter().enumerate() {
        if let Some(&(nx, ny, b)) = keys.get(i + 1)
            && (nx, ny) == (cx, cy.saturating_add(1))
            && close(a, b)
        {
            return Err(duplicate(a, b));
        }
        let (right, below, above) = (
            cx.saturating_add(1),
            cy.saturating_sub(1),
            cy.saturating_add(1),
        );
        while next_col < keys.len() && (keys[next_col].0, keys[next_col].1) < (right, below) {
            next_col += 1;
        }
        for &(nx, ny, b) in keys[next_col..].iter().take(3) {
            if nx == right && ny <= above && close(a, b) {
                return Err(duplicate(a, b));
            }
        }
    }
    Ok(())
}

/// A closed loop of boundary edges.
pub(crate) struct BoundaryLoop {
    /// Its smallest vertex id.
    start: usize,
    /// Its signed area (positive if counter-clockwise: an outer boundary).
    area: f64,
    /// Its lowest vertex in the sweep order (smallest x, then smallest y).
    lowest: usize,
}

/// The boundary, oriented by its cells (counter-clockwise, so the cells lie on the left).
pub(crate) struct Boundary {
    /// The vertex after each boundary vertex along the boundary (`NONE` off the boundary).
    next: Vec<usize>,
    loops: Vec<BoundaryLoop>,
}

/// Check 10: the boundary, oriented by its cells, splits into simple closed loops of non-zero
/// area. A hanging node (a cell side that is split in its neighbours but not in the cell itself)
/// shows up as a zero-area loop; a pinched vertex as a vertex with two outgoing boundary edges.
/// O(n): the orientation of every boundary edge is read off the cell sides in one pass.
/// The cell arrays are the mesh's 32-bit ones.
pub(crate) fn boundary_loops(
    vertices: &[Point],
    edges: &[[usize; 2]],
    cell_verts: &[u32],
    cell_ptr: &[u32],
    cell_edges: &[u32],
    boundary_edges: &[usize],
) -> Result<Boundary, MeshError> {
    // whether each edge is traversed from its smaller to its larger vertex by (the last of) its
    // cells; for a boundary edge, by its only cell
    let mut forward = try_filled(edges.len(), false, "the orientations of the edges")?;
    for k in 0..cell_ptr.len().saturating_sub(1) {
        let (s, t) = (cell_ptr[k] as usize, cell_ptr[k + 1] as usize);
        for slot in s..t {
            let next = if slot + 1 < t { slot + 1 } else { s };
            forward[cell_edges[slot] as usize] = cell_verts[slot] < cell_verts[next];
        }
    }
    let mut next = try_filled(
        vertices.len(),
        NONE,
        "the boundary successors of the vertices",
    )?;
    for &e in boundary_edges {
        let [lo, hi] = edges[e];
        let (a, b) = if forward[e] { (lo, hi) } else { (hi, lo) };
        if next[a] != NONE {
            return Err(MeshError::NonConforming(format!(
                "vertex {a} starts two boundary edges (pinched boundary or hanging node)"
            )));
        }
        next[a] = b;
    }
    let loops = trace_loops(vertices, &next)?;
    let total: f64 = loops.iter().map(|l| l.area.abs()).sum();
    if let Some(l) = loops.iter().find(|l| l.area.abs() <= 1e-10 * total) {
        return Err(MeshError::NonConforming(format!(
            "the boundary loop through vertex {} encloses no area: a hanging node \
             (a cell side split in the neighbouring cells but not in the cell itself)",
            l.start
        )));
    }
    Ok(Boundary { next, loops })
}

/// Follows `next` from every boundary vertex, in increasing vertex order, into closed loops.
fn trace_loops(vertices: &[Point], next: &[usize]) -> Result<Vec<BoundaryLoop>, MeshError> {
    let mut loops = Vec::new();
    let mut seen = try_filled(
        vertices.len(),
        false,
        "the seen flags of the boundary vertices",
    )?;
    let mut pts = Vec::new();
    for start in 0..next.len() {
        if next[start] == NONE || seen[start] {
            continue;
        }
        pts.clear();
        let (mut v, mut lowest) = (start, start);
        loop {
            if std::mem::replace(&mut seen[v], true) {
                return Err(MeshError::NonConforming(format!(
                    "boundary loop through vertex {v} does not close"
                )));
            }
            pts.push(vertices[v]);
            if lex(vertices[v], vertices[lowest]) == Ordering::Less {
                lowest = v;
            }
            v = match next[v] {
                NONE => {
                    return Err(MeshError::NonConforming(format!(
                        "boundary edge ending at vertex {v} has no successor"
                    )));
                }
                w => w,
            };
            if v == start {
                break;
            }
        }
        let (area, _) = polygon_area_centroid(&pts);
        loops.push(BoundaryLoop {
            start,
            area,
            lowest,
        });
    }
    Ok(loops)
}

/// The mesh arrays checks 11 and 12 read (the cell arrays are the mesh's 32-bit ones).
pub(crate) struct Topology<'a> {
    pub(crate) vertices: &'a [Point],
    pub(crate) cell_ptr: &'a [u32],
    pub(crate) cell_verts: &'a [u32],
    pub(crate) edges: &'a [[usize; 2]],
    pub(crate) edge_cells: &'a [[usize; 2]],
    /// Σ_K |K|.
    pub(crate) cells_area: f64,
}

impl Topology<'_> {
    /// The cell on the upper side of edge `e` (the one traversing it from its lower end point in
    /// the sweep order to the other, since cells are counter-clockwise), if any.
    fn cell_above(&self, e: usize, boundary: &Boundary) -> Option<usize> {
        let [a, b] = self.edges[e];
        let (l, r) = if lex(self.vertices[a], self.vertices[b]) == Ordering::Greater {
            (b, a)
        } else {
            (a, b)
        };
        let [k0, k1] = self.edge_cells[e];
        if k1 == NO_CELL {
            return (boundary.next[l] == r).then_some(k0);
        }
        let c = &self.cell_verts[self.cell_ptr[k0] as usize..self.cell_ptr[k0 + 1] as usize];
        let i = c.iter().position(|&v| v as usize == l)?;
        Some(if c[(i + 1) % c.len()] as usize == r {
            k0
        } else {
            k1
        })
    }
}

/// Checks 11 and 12 (see the module docs): no two edges meet except at a common vertex, and
/// every boundary loop lies in a cell exactly if it is a hole.
/// `order` is [`t.vertices`](Topology::vertices) in sweep order ([`sweep::SweepOrder::new`]).
pub(crate) fn check_no_overlap(
    t: &Topology,
    boundary: &Boundary,
    order: sweep::SweepOrder,
) -> Result<(), MeshError> {
    let mut queries: Vec<usize> = try_vec(boundary.loops.len(), "the boundary loops")?;
    queries.extend(boundary.loops.iter().map(|l| l.lowest));
    let below = match sweep::first_collision_in(order, t.edges, &queries)? {
        Sweep::Collision(e, f) => {
            return Err(MeshError::CrossingEdges {
                edges: [t.edges[e], t.edges[f]],
                cells: [t.edge_cells[e][0], t.edge_cells[f][0]],
            });
        }
        Sweep::Clear(below) => below,
    };
    let cells_area = t.cells_area;
    let mut enclosed_area = 0.0;
    let mut culprit = None;
    for (l, e) in boundary.loops.iter().zip(below) {
        let around = e.and_then(|e| t.cell_above(e, boundary));
        let hole = around.is_some();
        enclosed_area += if hole { -l.area.abs() } else { l.area.abs() };
        if hole != (l.area < 0.0) && culprit.is_none() {
            culprit = Some((l.lowest, around));
        }
    }
    let mismatch = !((cells_area - enclosed_area).abs() <= 1e-9 * cells_area);
    if culprit.is_some() || mismatch {
        return Err(MeshError::OverlappingCells {
            cells_area,
            enclosed_area,
            loop_vertex: culprit.map(|c| c.0),
            cell: culprit.and_then(|c| c.1),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::mesh::test_rng as rng;

    /// A random polygon, star-shaped around the origin when `simple` (increasing angles),
    /// else with its corners in random order.
    fn polygon(r: &mut impl FnMut() -> f64, m: usize, simple: bool) -> Vec<Point> {
        let mut angles: Vec<f64> = (0..m).map(|_| 2.0 * std::f64::consts::PI * r()).collect();
        if simple {
            angles.sort_by(f64::total_cmp);
        }
        angles
            .iter()
            .map(|a| {
                let rad = 0.2 + r();
                [rad * a.cos(), rad * a.sin()]
            })
            .collect()
    }

    #[test]
    fn diameter_by_calipers_is_the_largest_distance() {
        let mut r = rng(7);
        for case in 0..300 {
            let m = 17 + case % 60;
            let pts = polygon(&mut r, m, case % 2 == 0);
            let mut brute: f64 = 0.0;
            for p in &pts {
                for q in &pts {
                    brute = brute.max(dist(*p, *q));
                }
            }
            assert_eq!(diameter(&pts), brute, "case {case}");
        }
        // collinear and repeated points
        let line: Vec<Point> = (0..40)
            .map(|i| [(i % 20) as f64, 2.0 * (i % 20) as f64])
            .collect();
        assert_eq!(diameter(&line), dist([0.0, 0.0], [19.0, 38.0]));
    }

    #[test]
    fn repeated_vertex_by_sort_is_the_first_listed() {
        let mut r = rng(11);
        for case in 0..500 {
            let m = 17 + case % 40;
            let c: Vec<usize> = (0..m).map(|_| (r() * 2.0 * m as f64) as usize).collect();
            let brute = (0..m).find(|&i| c[i + 1..].contains(&c[i])).map(|i| c[i]);
            assert_eq!(repeated_vertex(&c), brute, "case {case}");
        }
    }

    #[test]
    fn self_crossing_by_sweep_agrees_with_all_pairs() {
        let mut r = rng(13);
        for case in 0..400 {
            let m = 17 + case % 30;
            let pts = polygon(&mut r, m, case % 3 != 0);
            let sides: Vec<[usize; 2]> = (0..m).map(|i| [i, (i + 1) % m]).collect();
            let brute = (0..m)
                .flat_map(|i| (i + 1..m).map(move |j| (i, j)))
                .find(|&(i, j)| {
                    let ([a, b], [c, d]) = (sides[i], sides[j]);
                    if j == i + 1 {
                        segments_overlap_from(pts[b], pts[a], pts[d])
                    } else if i == 0 && j == m - 1 {
                        segments_overlap_from(pts[a], pts[b], pts[c])
                    } else {
                        segments_meet(pts[a], pts[b], pts[c], pts[d])
                    }
                });
            let found = self_crossing(&pts).unwrap();
            assert_eq!(found.is_some(), brute.is_some(), "case {case}");
            assert_eq!(found.is_none(), case % 3 != 0, "case {case}");
        }
    }

    #[test]
    fn duplicates_by_grid_agree_with_all_pairs() {
        let mut r = rng(17);
        for case in 0..300 {
            // points on a grid of step 1e-13 (the tolerance for an extent of 1), some coinciding
            // or one step apart
            let n = 2 + case % 50;
            let mut v: Vec<Point> = (0..n)
                .map(|_| [(r() * 40.0).floor() * 1e-13, (r() * 40.0).floor() * 1e-13])
                .collect();
            v.push([0.0, 0.0]);
            v.push([1.0, 1.0]);
            let tol = 1e-13;
            let brute = (0..v.len()).any(|i| {
                (i + 1..v.len())
                    .any(|j| (v[i][0] - v[j][0]).abs() <= tol && (v[i][1] - v[j][1]).abs() <= tol)
            });
            let found = check_duplicate_vertices(&v);
            if let Err(MeshError::DuplicateVertex { a, b, .. }) = found {
                assert!((v[a][0] - v[b][0]).abs() <= tol && (v[a][1] - v[b][1]).abs() <= tol);
            }
            // pairs at exactly the tolerance may fall either way (rounding of the grid)
            let strict = (0..v.len()).any(|i| {
                (i + 1..v.len()).any(|j| {
                    (v[i][0] - v[j][0]).abs() < 0.5 * tol && (v[i][1] - v[j][1]).abs() < 0.5 * tol
                })
            });
            if strict {
                assert!(found.is_err(), "case {case}");
            }
            if !brute {
                assert!(found.is_ok(), "case {case}");
            }
        }
    }

    /// The per-cell checks are O(m log m): on a polygon of 2·10⁵ corners (far beyond
    /// [`MAX_CELL_VERTICES`]) they take well under a second, where pairs would take hours.
    #[test]
    fn per_cell_checks_scale_as_m_log_m() {
        // an odd number of corners, so that visiting every second one is a permutation
        let m = 200_001;
        let pts: Vec<Point> = (0..m)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / m as f64;
                [a.cos(), a.sin()]
            })
            .collect();
        let t0 = std::time::Instant::now();
        assert!((diameter(&pts) - 2.0).abs() < 1e-9);
        assert_eq!(self_crossing(&pts), Ok(None));
        let ids: Vec<usize> = (0..m).collect();
        assert_eq!(repeated_vertex(&ids), None);
        let twice: Vec<Point> = (0..m).map(|k| pts[2 * k % m]).collect();
        assert!(self_crossing(&twice).unwrap().is_some());
        let mut again = ids.clone();
        again[m - 1] = 5;
        assert_eq!(repeated_vertex(&again), Some(5));
        assert!(t0.elapsed().as_secs_f64() < 30.0);
    }
}
