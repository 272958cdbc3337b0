//! Does any pair of segments meet, other than at a shared end point? A Shamos–Hoey sweep.
//!
//! The segments join vertices given by id; two segments that share an end point (a vertex id)
//! may meet there and nowhere else, any other contact (crossing, touching, overlapping) is a
//! *collision*. [`first_collision`] reports one, or proves there is none, in O(n log n) time for
//! n segments whatever their geometry (expected time over the random priorities of the treap;
//! M. I. Shamos and D. Hoey, *Geometric intersection problems*, 1976):
//!
//! * a line sweeps the plane in the lexicographic order of the points (x, then y: the plane
//!   turned by an infinitesimal angle, so that no segment is vertical and no two vertices are
//!   met at once); at every vertex the segments ending there leave the *active list* and the
//!   segments starting there enter it;
//! * the active list holds the segments cut by the sweep line, from bottom to top. As long as
//!   no collision lies behind the sweep line the order of two active segments never changes, so
//!   it can be decided once and for all from the segment that starts later: is its start above
//!   or below the other one (and, if it lies on it, is its end)? That is an exact orientation
//!   test ([`super::predicates::orient`]), so the list can be kept in a balanced search tree
//!   ([`ActiveList`], a treap threaded by a doubly-linked list: neighbours in O(1), removal
//!   without any comparison). The segments starting at a vertex go where the segments ending
//!   there left the list, so only vertices where no segment ends need a search (in a mesh, few);
//! * the leftmost collision is between two segments that are neighbours in the list at some
//!   moment before the sweep line reaches it, so it suffices to test each segment against its
//!   neighbours when it enters, and the two segments that become neighbours when one leaves.
//!
//! Before the sweep the vertices are sorted and renumbered in sweep order ([`Events`]), so that
//! the sweep reads its arrays nearly in order.
//!
//! The sweep also answers *point queries*: for chosen vertices, the segment right below the
//! vertex when the sweep reaches it (the first segment hit by a ray going straight down,
//! segments at the vertex excluded). The mesh checks use it to tell whether a boundary loop lies
//! inside a cell ([`super::validate`]).

use super::predicates::{orient, segments_meet, segments_overlap_from};
use super::{EdgeIndex as Index, Point};
use crate::budget::{AllocFailure, try_filled, try_vec};
use std::cmp::Ordering;

/// An active segment: its end points in sweep order, their ranks in that order and its index
/// (in [`Events::segs`]), ordered from bottom to top by [`Active::compare`] (see the module
/// docs). A query point is a degenerate segment with index `usize::MAX`, above every segment
/// through it.
#[derive(Clone, Copy, Debug)]
struct Active {
    left: Point,
    right: Point,
    ends: [usize; 2],
    id: usize,
}

impl Active {
    /// Where `self`, which starts no earlier than `other`, lies relative to `other`.
    fn cmp_later(&self, other: &Active) -> Ordering {
        orient(other.left, other.right, self.left)
            .then_with(|| orient(other.left, other.right, self.right))
            .then(self.id.cmp(&other.id))
    }

    /// The bottom-to-top order of the active list.
    fn compare(&self, other: &Active) -> Ordering {
        if self.id == other.id {
            Ordering::Equal
        } else if self.ends[0] < other.ends[0] {
            other.cmp_later(self).reverse()
        } else {
            self.cmp_later(other)
        }
    }
}

const NIL: u32 = u32::MAX;

/// A node of [`ActiveList`]: a segment, its tree links and its list links.
#[derive(Clone, Copy, Debug)]
struct Node {
    seg: Active,
    /// Heap priority (a hash of the segment index).
    prio: u32,
    left: u32,
    right: u32,
    parent: u32,
    prev: u32,
    next: u32,
}

/// The active list: a treap (a binary search tree whose nodes are also a max-heap on random
/// priorities, so its expected depth is O(log n) whatever the order of insertions) ordered by
/// [`Active::compare`], threaded by a doubly-linked list in the same order. Nodes live in an
/// arena that holds only the active segments (so it stays small and in cache); `node_of` finds
/// the node of a segment for its removal.
struct ActiveList {
    nodes: Vec<Node>,
    free: Vec<u32>,
    root: u32,
    node_of: Vec<u32>,
}

/// A well-mixed 32-bit hash of `i` (the finaliser of SplitMix64).
fn priority(i: usize) -> u32 {
    let mut z = (i as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as u32
}

impl ActiveList {
    fn new(n_segments: usize) -> Result<Self, AllocFailure> {
        Ok(ActiveList {
            nodes: Vec::new(),
            free: Vec::new(),
            root: NIL,
            node_of: try_filled(n_segments, NIL, "the active list of the sweep")?,
        })
    }

    fn id(&self, n: u32) -> Option<usize> {
        (n != NIL).then(|| self.nodes[n as usize].seg.id)
    }

    /// The segment of node `n`.
    fn seg(&self, n: u32) -> &Active {
        &self.nodes[n as usize].seg
    }

    /// Makes `child` (or nothing) take the place of `old` under `parent`.
    fn replace_child(&mut self, parent: u32, old: u32, child: u32) {
        if parent == NIL {
            self.root = child;
        } else if self.nodes[parent as usize].left == old {
            self.nodes[parent as usize].left = child;
        } else {
            self.nodes[parent as usize].right = child;
        }
        if child != NIL {
            self.nodes[child as usize].parent = parent;
        }
    }

    /// Rotates `x` above its parent.
    fn rotate_up(&mut self, x: u32) {
        let p = self.nodes[x as usize].parent;
        let g = self.nodes[p as usize].parent;
        if self.nodes[p as usize].left == x {
            let b = self.nodes[x as usize].right;
            self.nodes[p as usize].left = b;
            if b != NIL {
                self.nodes[b as usize].parent = p;
            }
            self.nodes[x as usize].right = p;
        } else {
            let b = self.nodes[x as usize].left;
            self.nodes[p as usize].right = b;
            if b != NIL {
                self.nodes[b as usize].parent = p;
            }
            self.nodes[x as usize].left = p;
        }
        self.nodes[p as usize].parent = x;
        self.replace_child(g, p, x);
    }

    /// Makes the new node `x` a leaf at its place in the tree, given its neighbours in the
    /// list (`below`, `above`, either may be `NIL`), and restores the heap order.
    fn attach(&mut self, x: u32, below: u32, above: u32) {
        let parent = if below != NIL && self.nodes[below as usize].right == NIL {
            self.nodes[below as usize].right = x;
            below
        } else if above != NIL {
            // `below` has a right subtree, whose leftmost node is `above`, or there is no
            // `below` and `above` is the first node: either way `above` has no left child
            debug_assert_eq!(self.nodes[above as usize].left, NIL);
            self.nodes[above as usize].left = x;
            above
        } else {
            debug_assert_eq!(self.root, NIL);
            self.root = x;
            NIL
        };
        self.nodes[x as usize].parent = parent;
        while self.nodes[x as usize].parent != NIL
            && self.nodes[x as usize].prio > self.nodes[self.nodes[x as usize].parent as usize].prio
        {
            self.rotate_up(x);
        }
    }

    /// Inserts `s` right above node `below` (`NIL`: at the bottom), which must be its place in
    /// the order; returns its node.
    fn insert_after(&mut self, below: u32, s: Active) -> u32 {
        let above = if below != NIL {
            self.nodes[below as usize].next
        } else {
            self.first()
        };
        let node = Node {
            seg: s,
            prio: priority(s.id),
            left: NIL,
            right: NIL,
            parent: NIL,
            prev: below,
            next: above,
        };
        let x = match self.free.pop() {
            Some(x) => {
                self.nodes[x as usize] = node;
                x
            }
            None => {
                self.nodes.push(node);
                (self.nodes.len() - 1) as u32
            }
        };
        self.node_of[s.id] = x;
        if below != NIL {
            self.nodes[below as usize].next = x;
        }
        if above != NIL {
            self.nodes[above as usize].prev = x;
        }
        self.attach(x, below, above);
        x
    }

    /// The bottom node.
    fn first(&self) -> u32 {
        let mut cur = self.root;
        while cur != NIL && self.nodes[cur as usize].left != NIL {
            cur = self.nodes[cur as usize].left;
        }
        cur
    }

    /// Inserts `s` at its place; returns the segments right below and right above it.
    #[cfg(test)]
    fn insert(&mut self, s: Active) -> (Option<usize>, Option<usize>) {
        let below = self.below_node(&s);
        let x = self.insert_after(below, s);
        let Node { prev, next, .. } = self.nodes[x as usize];
        (self.id(prev), self.id(next))
    }

    /// Removes segment `id` (if active); returns the nodes that were right below and right
    /// above it.
    fn remove_nodes(&mut self, id: usize) -> (u32, u32) {
        let x = std::mem::replace(&mut self.node_of[id], NIL);
        if x == NIL {
            return (NIL, NIL);
        }
        // rotate x down (its higher-priority child up) until it has at most one child
        loop {
            let Node { left, right, .. } = self.nodes[x as usize];
            if left == NIL || right == NIL {
                let child = if left == NIL { right } else { left };
                self.replace_child(self.nodes[x as usize].parent, x, child);
                break;
            }
            let up = if self.nodes[left as usize].prio > self.nodes[right as usize].prio {
                left
            } else {
                right
            };
            self.rotate_up(up);
        }
        let Node { prev, next, .. } = self.nodes[x as usize];
        if prev != NIL {
            self.nodes[prev as usize].next = next;
        }
        if next != NIL {
            self.nodes[next as usize].prev = prev;
        }
        self.free.push(x);
        (prev, next)
    }

    /// As [`ActiveList::remove_nodes`], with segment indices.
    #[cfg(test)]
    fn remove(&mut self, id: usize) -> (Option<usize>, Option<usize>) {
        let (prev, next) = self.remove_nodes(id);
        (self.id(prev), self.id(next))
    }

    /// The node of the highest active segment below `probe` (`NIL` if none).
    fn below_node(&self, probe: &Active) -> u32 {
        let (mut cur, mut found) = (self.root, NIL);
        while cur != NIL {
            if probe.compare(&self.nodes[cur as usize].seg) == Ordering::Greater {
                found = cur;
                cur = self.nodes[cur as usize].right;
            } else {
                cur = self.nodes[cur as usize].left;
            }
        }
        found
    }

    /// The highest active segment below `probe`.
    fn below(&self, probe: &Active) -> Option<usize> {
        self.id(self.below_node(probe))
    }
}

/// What [`first_collision`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Sweep {
    /// Segments `i < j` meet outside their shared end points.
    Collision(usize, usize),
    /// No collision; for each query vertex, the segment right below it (if any).
    Clear(Vec<Option<usize>>),
}

/// An integer whose order is that of the finite float `x`, with `-0.0` and `0.0` equal.
fn sort_key(x: f64) -> u64 {
    let b = (x + 0.0).to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// The input renumbered in sweep order, so that the sweep reads its arrays (nearly) in order
/// instead of jumping around the vertex numbering: vertices by rank, segments by the rank of
/// their left end.
struct Events<I> {
    /// The points in sweep order.
    pts: Vec<Point>,
    /// The rank of every vertex in the sweep order.
    rank: Vec<usize>,
    /// (rank of the left end, rank of the right end, index in the input) of every segment,
    /// by left end; `segs[start_ptr[r]..start_ptr[r + 1]]` start at rank r.
    segs: Vec<(I, I, I)>,
    start_ptr: Vec<usize>,
    /// CSR by the rank of the right end: positions in `segs` of the segments ending there.
    end_ptr: Vec<usize>,
    ends: Vec<I>,
}

/// A CSR of `0..keys.len()` by key (`n` keys), in increasing order within each key.
fn csr<I: Index>(
    keys: impl Iterator<Item = usize> + Clone,
    n: usize,
) -> Result<(Vec<usize>, Vec<I>), AllocFailure> {
    super::buckets::try_counting_sort(n, keys.map(Some), I::from_usize)
}

/// The vertices in sweep order: the part of [`Events`] that depends on the points alone, so
/// that the mesh checks can compute it while they build the edges ([`first_collision_in`]).
pub(crate) struct SweepOrder {
    /// The points in sweep order.
    pts: Vec<Point>,
    /// The rank of every vertex in the sweep order.
    rank: Vec<usize>,
}

impl SweepOrder {
    /// Sorts `pts` in sweep order (in parallel for many points: the keys are distinct, so the
    /// order is the same), or [`AllocFailure`] if its arrays cannot be allocated.
    pub(crate) fn new(pts: &[Point]) -> Result<SweepOrder, AllocFailure> {
        let n = pts.len();
        let keyed = super::buckets::sorted_point_keys(pts, sort_key)?;
        let mut rank = try_filled(n, 0usize, "the sweep order of the vertices")?;
        let mut sorted_pts = try_vec(n, "the vertices in sweep order")?;
        for (r, &(_, _, v)) in keyed.iter().enumerate() {
            rank[v] = r;
            sorted_pts.push(pts[v]);
        }
        Ok(SweepOrder {
            pts: sorted_pts,
            rank,
        })
    }
}

impl<I: Index> Events<I> {
    fn new(order: SweepOrder, segs: &[[usize; 2]]) -> Result<Events<I>, AllocFailure> {
        let SweepOrder {
            pts: sorted_pts,
            rank,
        } = order;
        let n = sorted_pts.len();
        let ranked = segs.iter().map(|&[a, b]| {
            let (ra, rb) = (rank[a], rank[b]);
            (ra.min(rb), ra.max(rb))
        });
        let (start_ptr, by_left) = csr(ranked.clone().map(|(l, _)| l), n)?;
        let mut sorted_segs: Vec<(I, I, I)> = try_vec(by_left.len(), "the segments of the sweep")?;
        sorted_segs.extend(by_left.into_iter().map(|i: I| {
            let i = i.to_usize();
            let [a, b] = segs[i];
            let (ra, rb) = (rank[a], rank[b]);
            (
                I::from_usize(ra.min(rb)),
                I::from_usize(ra.max(rb)),
                I::from_usize(i),
            )
        }));
        let (end_ptr, ends) = csr(sorted_segs.iter().map(|s| s.1.to_usize()), n)?;
        Ok(Events {
            pts: sorted_pts,
            rank,
            segs: sorted_segs,
            start_ptr,
            end_ptr,
            ends,
        })
    }

    /// The active segment for `segs[j]`.
    fn active(&self, j: usize) -> Active {
        let (l, r, _) = self.segs[j];
        let (l, r) = (l.to_usize(), r.to_usize());
        Active {
            left: self.pts[l],
            right: self.pts[r],
            ends: [l, r],
            id: j,
        }
    }
}

/// Whether two segments meet outside the end points they share.
fn collide(s: &Active, t: &Active) -> bool {
    let ([sl, sr], [tl, tr]) = (s.ends, t.ends);
    if (sl, sr) == (tl, tr) {
        // the same vertex pair twice: they overlap entirely
        true
    } else if sl == tl {
        segments_overlap_from(s.left, s.right, t.right)
    } else if sr == tr {
        segments_overlap_from(s.right, s.left, t.left)
    } else if sl == tr || sr == tl {
        // one ends where the other starts: they leave that vertex on opposite sides
        false
    } else {
        segments_meet(s.left, s.right, t.left, t.right)
    }
}

/// Finds two segments of `segs` (pairs of indices into `pts`) that meet anywhere but at an end
/// point they share, or, if there are none, the segment right below each vertex of `queries`
/// (which must be end points of segments). The points must be finite and pairwise distinct; a
/// segment must join two distinct points. O((n + q) log n) for n points and segments and q
/// queries (expected, over the priorities of the treap, whatever the input).
/// [`AllocFailure`] if the arrays of the sweep (proportional to n and q) cannot be allocated.
pub(crate) fn first_collision(
    pts: &[Point],
    segs: &[[usize; 2]],
    queries: &[usize],
) -> Result<Sweep, AllocFailure> {
    first_collision_in(SweepOrder::new(pts)?, segs, queries)
}

/// [`first_collision`] on the points sorted beforehand by [`SweepOrder::new`].
pub(crate) fn first_collision_in(
    order: SweepOrder,
    segs: &[[usize; 2]],
    queries: &[usize],
) -> Result<Sweep, AllocFailure> {
    // the event arrays hold ranks and segment indices: `u32` when they fit (half the memory)
    if u32::try_from(segs.len().max(order.pts.len())).is_ok() {
        sweep_events(Events::<u32>::new(order, segs)?, queries)
    } else {
        sweep_events(Events::<usize>::new(order, segs)?, queries)
    }
}

/// The sweep of [`first_collision`] over its events. Its arrays are allocated once, up front
/// (the active list's nodes grow with the number of segments cut by the sweep line at once).
fn sweep_events<I: Index>(ev: Events<I>, queries: &[usize]) -> Result<Sweep, AllocFailure> {
    let collision = |i: usize, j: usize| {
        let (a, b) = (ev.segs[i].2.to_usize(), ev.segs[j].2.to_usize());
        Sweep::Collision(a.min(b), a.max(b))
    };
    // the queries by rank, last first, with their positions in `queries`
    let mut pending: Vec<(usize, usize)> = try_vec(queries.len(), "the queries of the sweep")?;
    pending.extend(queries.iter().map(|&q| ev.rank[q]).zip(0..));
    pending.sort_unstable_by(|a, b| b.cmp(a));
    let mut below = try_filled(queries.len(), None, "the answers of the sweep")?;
    let mut list = ActiveList::new(ev.segs.len())?;
    let mut starting: Vec<Active> = Vec::new();
    for r in 0..ev.pts.len() {
        let ending = &ev.ends[ev.end_ptr[r]..ev.end_ptr[r + 1]];
        let probe = Active {
            left: ev.pts[r],
            right: ev.pts[r],
            ends: [r, r],
            id: usize::MAX,
        };
        // the segments ending at r are neighbours in the list (or a collision was found
        // earlier); once they are gone, `below_r` and `above_r` are the neighbours of r
        let (mut below_r, mut above_r) = (NIL, NIL);
        for &j in ending {
            (below_r, above_r) = list.remove_nodes(j.to_usize());
        }
        while pending.last().is_some_and(|&(q, _)| q == r) {
            let (_, k) = pending.pop().expect("not empty");
            below[k] = list.below(&probe).map(|j| ev.segs[j].2.to_usize());
        }
        let starts = ev.start_ptr[r]..ev.start_ptr[r + 1];
        if starts.is_empty() {
            if below_r != NIL && above_r != NIL && collide(list.seg(below_r), list.seg(above_r)) {
                return Ok(collision(list.seg(below_r).id, list.seg(above_r).id));
            }
            continue;
        }
        if ending.is_empty() {
            below_r = list.below_node(&probe);
        }
        debug_assert!(below_r == NIL || probe.compare(list.seg(below_r)) == Ordering::Greater);
        // the segments starting at r, bottom to top (a consistent order: they share r)
        starting.clear();
        starting.extend(starts.map(|j| ev.active(j)));
        starting.sort_unstable_by(|a, b| a.compare(b));
        let mut last = below_r;
        for s in &starting {
            if last != NIL && collide(list.seg(last), s) {
                return Ok(collision(list.seg(last).id, s.id));
            }
            last = list.insert_after(last, *s);
        }
        let above = list.nodes[last as usize].next;
        if above != NIL && collide(list.seg(last), list.seg(above)) {
            return Ok(collision(list.seg(last).id, list.seg(above).id));
        }
    }
    Ok(Sweep::Clear(below))
}

/// [`collide`] for segments `i` and `j` of `segs`.
#[cfg(test)]
fn collide_ids(pts: &[Point], segs: &[[usize; 2]], i: usize, j: usize) -> bool {
    use super::predicates::lex;
    let active = |k: usize| {
        let [a, b] = segs[k];
        let (l, r) = if lex(pts[a], pts[b]) == Ordering::Greater {
            (b, a)
        } else {
            (a, b)
        };
        Active {
            left: pts[l],
            right: pts[r],
            ends: [l, r],
            id: k,
        }
    };
    collide(&active(i), &active(j))
}

/// As [`first_collision`] without queries, by testing every pair.
#[cfg(test)]
fn first_collision_brute(pts: &[Point], segs: &[[usize; 2]]) -> Option<(usize, usize)> {
    (0..segs.len())
        .flat_map(|i| (i + 1..segs.len()).map(move |j| (i, j)))
        .find(|&(i, j)| collide_ids(pts, segs, i, j))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::predicates::lex;
    use crate::mesh::test_rng as rng;

    #[test]
    fn sort_key_follows_the_order_of_floats() {
        let xs = [-1e300, -1.0, -1e-300, -0.0, 0.0, 1e-300, 1.0, 1e300];
        for &a in &xs {
            for &b in &xs {
                let expected = a.partial_cmp(&b).unwrap();
                assert_eq!(sort_key(a).cmp(&sort_key(b)), expected, "{a} {b}");
            }
        }
    }

    fn clear(s: &Sweep) -> bool {
        matches!(s, Sweep::Clear(_))
    }

    #[test]
    fn grid_edges_do_not_collide_and_queries_see_below() {
        // the edges of a 3 × 3 grid of unit squares, plus a query at every vertex
        let n = 3;
        let pts: Vec<Point> = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| [i as f64, j as f64]))
            .collect();
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut segs = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                if i < n {
                    segs.push([id(i, j), id(i + 1, j)]);
                }
                if j < n {
                    segs.push([id(i, j), id(i, j + 1)]);
                }
            }
        }
        let queries = [id(1, 1), id(0, 0), id(2, 3)];
        let Sweep::Clear(below) = first_collision(&pts, &segs, &queries).unwrap() else {
            panic!("collision in a grid");
        };
        // right below (1, 1) in the turned plane (x + εy) the segments at (1, 1) do not count:
        // the first one hit is (1, 0)–(2, 0)
        let edge = |a: usize, b: usize| segs.iter().position(|s| *s == [a, b]);
        assert_eq!(below[0], edge(id(1, 0), id(2, 0)));
        assert_eq!(below[1], None);
        assert_eq!(below[2], edge(id(2, 2), id(3, 2)));
    }

    #[test]
    fn finds_crossings_touchings_and_overlaps() {
        let pts = [
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, -1.0],
            [1.0, 1.0],
            [1.0, 0.0],
            [3.0, 0.0],
        ];
        // (the segments, whether they collide)
        let cases: [(&[[usize; 2]], bool); 7] = [
            // a cross
            (&[[0, 1], [2, 3]], true),
            // T-junction: vertex 4 on the segment 0–1
            (&[[0, 1], [4, 3]], true),
            // collinear overlap with a shared end point, and without
            (&[[0, 1], [0, 4]], true),
            (&[[0, 1], [4, 5]], true),
            // a path through shared vertices is fine
            (&[[0, 4], [4, 1], [1, 5]], false),
            // vertical segments
            (&[[2, 4], [4, 3]], false),
            (&[[2, 3], [0, 4]], true),
        ];
        for (segs, collides) in cases {
            let found = first_collision(&pts, segs, &[]).unwrap();
            if collides {
                assert_eq!(found, Sweep::Collision(0, 1), "{segs:?}");
            } else {
                assert!(clear(&found), "{segs:?}");
            }
        }
    }

    /// Random segments: the sweep agrees with the brute-force test on whether there is a
    /// collision, and any pair it reports does collide.
    #[test]
    fn agrees_with_brute_force() {
        let mut r = rng(0x1234_5678_9abc_def1);
        for case in 0..3000 {
            let n = 2 + case % 9;
            // coordinates on a coarse lattice, so that degenerate cases are frequent
            let pts: Vec<Point> = (0..2 * n)
                .map(|_| [(r() * 6.0).floor(), (r() * 6.0).floor()])
                .collect();
            let mut uniq = pts.clone();
            uniq.sort_by(|a, b| lex(*a, *b));
            uniq.dedup();
            let m = uniq.len();
            let segs: Vec<[usize; 2]> = (0..n)
                .filter_map(|_| {
                    let a = (r() * m as f64) as usize % m;
                    let b = (r() * m as f64) as usize % m;
                    (a != b).then_some([a, b])
                })
                .collect();
            let brute = first_collision_brute(&uniq, &segs);
            match first_collision(&uniq, &segs, &[]).unwrap() {
                Sweep::Collision(i, j) => {
                    assert!(brute.is_some(), "case {case}: {segs:?}");
                    assert!(collide_ids(&uniq, &segs, i, j), "case {case}");
                }
                Sweep::Clear(_) => assert_eq!(brute, None, "case {case}: {uniq:?} {segs:?}"),
            }
        }
    }

    /// The segment right below vertex `q` in the turned plane, by brute force: of the segments
    /// the sweep line cuts at `q` (not at `q` itself) that pass below it, the highest at the
    /// abscissa of `q`, ties (a common left end point) going to the steeper one.
    fn below_brute(pts: &[Point], segs: &[[usize; 2]], q: usize) -> Option<usize> {
        let p = pts[q];
        let mut best: Option<(f64, f64, usize)> = None;
        for (i, &[a, b]) in segs.iter().enumerate() {
            let (l, r) = if lex(pts[a], pts[b]) == Ordering::Greater {
                (pts[b], pts[a])
            } else {
                (pts[a], pts[b])
            };
            if a == q || b == q || lex(l, p) != Ordering::Less || lex(p, r) != Ordering::Less {
                continue;
            }
            // not vertical: a vertical segment cut by the sweep line at q would contain q
            let slope = (r[1] - l[1]) / (r[0] - l[0]);
            let y = l[1] + slope * (p[0] - l[0]);
            if y < p[1] && best.is_none_or(|(by, bs, _)| (y, slope) > (by, bs)) {
                best = Some((y, slope, i));
            }
        }
        best.map(|b| b.2)
    }

    /// Large sets of segments that do not collide, grown one random segment at a time on a
    /// small lattice (so that collinear, touching and vertical segments abound): the sweep finds
    /// them clear, and with one more random segment it agrees with the brute-force test.
    #[test]
    fn clear_sets_and_one_more_segment() {
        let mut r = rng(0x0dd_ba11_cafe_f00d);
        let side = 7;
        let pts: Vec<Point> = (0..side * side)
            .map(|i| [(i % side) as f64, (i / side) as f64 + 0.25 * (i % 3) as f64])
            .collect();
        let pick = |r: &mut dyn FnMut() -> f64| (r() * pts.len() as f64) as usize % pts.len();
        for case in 0..200 {
            let mut segs: Vec<[usize; 2]> = Vec::new();
            for _ in 0..400 {
                let (a, b) = (pick(&mut r), pick(&mut r));
                if a == b {
                    continue;
                }
                segs.push([a, b]);
                if first_collision_brute(&pts, &segs).is_some() {
                    segs.pop();
                }
            }
            assert!(segs.len() > 30, "case {case}: only {} segments", segs.len());
            // queries at end points, as in the mesh checks (a point on no segment could lie on
            // a vertical one)
            let queries: Vec<usize> = (0..pts.len())
                .filter(|&v| segs.iter().any(|s| s.contains(&v)))
                .collect();
            let Sweep::Clear(below) = first_collision(&pts, &segs, &queries).unwrap() else {
                panic!("case {case}: collision reported in a clear set");
            };
            for (&q, b) in queries.iter().zip(&below) {
                assert_eq!(*b, below_brute(&pts, &segs, q), "case {case}, vertex {q}");
            }
            for _ in 0..20 {
                let (a, b) = (pick(&mut r), pick(&mut r));
                if a == b {
                    continue;
                }
                segs.push([a, b]);
                let brute = first_collision_brute(&pts, &segs);
                match first_collision(&pts, &segs, &[]).unwrap() {
                    Sweep::Collision(i, j) => {
                        assert!(
                            brute.is_some() && collide_ids(&pts, &segs, i, j),
                            "case {case}"
                        )
                    }
                    Sweep::Clear(_) => assert_eq!(brute, None, "case {case}"),
                }
                segs.pop();
            }
        }
    }

    /// Checks the tree, heap and list invariants of `list` and returns its segments in order.
    fn check_treap(list: &ActiveList) -> Vec<usize> {
        fn walk(l: &ActiveList, n: u32, parent: u32, out: &mut Vec<u32>) {
            if n == NIL {
                return;
            }
            let node = l.nodes[n as usize];
            assert_eq!(node.parent, parent);
            if parent != NIL {
                assert!(node.prio <= l.nodes[parent as usize].prio, "heap order");
            }
            walk(l, node.left, n, out);
            out.push(n);
            walk(l, node.right, n, out);
        }
        let mut in_order = Vec::new();
        walk(list, list.root, NIL, &mut in_order);
        for (i, &n) in in_order.iter().enumerate() {
            let node = list.nodes[n as usize];
            let prev = if i == 0 { NIL } else { in_order[i - 1] };
            let next = in_order.get(i + 1).copied().unwrap_or(NIL);
            assert_eq!((node.prev, node.next), (prev, next), "list links");
            assert_eq!(list.node_of[node.seg.id], n);
        }
        in_order
            .iter()
            .map(|&n| list.nodes[n as usize].seg.id)
            .collect()
    }

    /// Random insertions and removals of horizontal segments at random heights: the treap keeps
    /// its invariants, lists them by height and reports the right neighbours.
    #[test]
    fn active_list_stays_a_treap() {
        let mut r = rng(42);
        let n = 300;
        let heights: Vec<f64> = (0..n).map(|_| r()).collect();
        let seg = |i: usize| Active {
            left: [0.0, heights[i]],
            right: [1.0, heights[i]],
            ends: [0, 1],
            id: i,
        };
        let mut list = ActiveList::new(n).unwrap();
        let mut active: Vec<usize> = Vec::new();
        for step in 0..5000 {
            let i = (r() * n as f64) as usize % n;
            let by_height = |v: &mut Vec<usize>| {
                v.sort_by(|&a, &b| heights[a].total_cmp(&heights[b]).then(a.cmp(&b)))
            };
            let neighbours = |v: &Vec<usize>, i: usize| {
                let pos = v.iter().position(|&j| j == i).unwrap();
                (pos.checked_sub(1).map(|p| v[p]), v.get(pos + 1).copied())
            };
            if active.contains(&i) {
                let expected = neighbours(&active, i);
                assert_eq!(list.remove(i), expected, "step {step}");
                active.retain(|&j| j != i);
            } else {
                active.push(i);
                by_height(&mut active);
                assert_eq!(list.insert(seg(i)), neighbours(&active, i), "step {step}");
            }
            assert_eq!(check_treap(&list), active, "step {step}");
            let probe = Active {
                left: [0.5, 0.5],
                right: [0.5, 0.5],
                ends: [1, 1],
                id: usize::MAX,
            };
            let expected = active.iter().rev().find(|&&j| heights[j] < 0.5).copied();
            assert_eq!(list.below(&probe), expected);
        }
        assert!(list.nodes.len() <= n);
    }
}
