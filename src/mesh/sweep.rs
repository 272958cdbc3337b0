//! Does any pair of segments meet, other than at a shared end point? A Shamos–Hoey sweep.
//!
//! The segments join vertices given by id; two segments that share an end point (a vertex id)
//! may meet there and nowhere else, any other contact (crossing, touching, overlapping) is a
//! *collision*. [`first_collision`] reports one, or proves there is none, in O(n log n) time for
//! n segments whatever their geometry (M. I. Shamos and D. Hoey, *Geometric intersection
//! problems*, 1976):
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
//!   ([`ActiveList`], a treap threaded by a doubly-linked list: one search per insertion,
//!   neighbours in O(1), removal without any comparison);
//! * the leftmost collision is between two segments that are neighbours in the list at some
//!   moment before the sweep line reaches it, so it suffices to test each segment against its
//!   neighbours when it enters, and the two segments that become neighbours when one leaves.
//!
//! The sweep also answers *point queries*: for chosen vertices, the segment right below the
//! vertex when the sweep reaches it (the first segment hit by a ray going straight down,
//! segments at the vertex excluded). The mesh checks use it to tell whether a boundary loop lies
//! inside a cell ([`super::validate`]).

use super::Point;
use super::predicates::{lex, orient, segments_meet, segments_overlap_from};
use std::cmp::Ordering;

/// An active segment: its end points in sweep order and its index, ordered from bottom to top
/// by [`Active::compare`] (see the module docs). A query point is a degenerate segment with
/// index `usize::MAX`, above every segment through it.
#[derive(Clone, Copy, Debug)]
struct Active {
    left: Point,
    right: Point,
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
        } else if lex(self.left, other.left) == Ordering::Less {
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
    fn new(n_segments: usize) -> Self {
        ActiveList {
            nodes: Vec::new(),
            free: Vec::new(),
            root: NIL,
            node_of: vec![NIL; n_segments],
        }
    }

    fn id(&self, n: u32) -> Option<usize> {
        (n != NIL).then(|| self.nodes[n as usize].seg.id)
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

    /// Inserts `s`; returns the segments right below and right above it.
    fn insert(&mut self, s: Active) -> (Option<usize>, Option<usize>) {
        let (mut cur, mut parent, mut below, mut above) = (self.root, NIL, NIL, NIL);
        while cur != NIL {
            parent = cur;
            if s.compare(&self.nodes[cur as usize].seg) == Ordering::Less {
                above = cur;
                cur = self.nodes[cur as usize].left;
            } else {
                below = cur;
                cur = self.nodes[cur as usize].right;
            }
        }
        let node = Node {
            seg: s,
            prio: priority(s.id),
            left: NIL,
            right: NIL,
            parent,
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
        if parent == NIL {
            self.root = x;
        } else if above == parent {
            self.nodes[parent as usize].left = x;
        } else {
            self.nodes[parent as usize].right = x;
        }
        if below != NIL {
            self.nodes[below as usize].next = x;
        }
        if above != NIL {
            self.nodes[above as usize].prev = x;
        }
        while self.nodes[x as usize].parent != NIL
            && self.nodes[x as usize].prio
                > self.nodes[self.nodes[x as usize].parent as usize].prio
        {
            self.rotate_up(x);
        }
        (self.id(below), self.id(above))
    }

    /// Removes segment `id` (if active); returns the segments that were right below and right
    /// above it.
    fn remove(&mut self, id: usize) -> (Option<usize>, Option<usize>) {
        let x = std::mem::replace(&mut self.node_of[id], NIL);
        if x == NIL {
            return (None, None);
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
        (self.id(prev), self.id(next))
    }

    /// The highest active segment below `probe`.
    fn below(&self, probe: &Active) -> Option<usize> {
        let (mut cur, mut found) = (self.root, NIL);
        while cur != NIL {
            if probe.compare(&self.nodes[cur as usize].seg) == Ordering::Greater {
                found = cur;
                cur = self.nodes[cur as usize].right;
            } else {
                cur = self.nodes[cur as usize].left;
            }
        }
        self.id(found)
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

/// The segments that start (`starts`) and end (`ends`) at every vertex, CSR by vertex, and
/// the vertices in sweep order.
struct Events {
    order: Vec<usize>,
    start_ptr: Vec<usize>,
    starts: Vec<usize>,
    end_ptr: Vec<usize>,
    ends: Vec<usize>,
}

impl Events {
    fn new(pts: &[Point], segs: &[[usize; 2]]) -> Events {
        let mut keyed: Vec<(u64, u64, usize)> = pts
            .iter()
            .enumerate()
            .map(|(i, p)| (sort_key(p[0]), sort_key(p[1]), i))
            .collect();
        keyed.sort_unstable();
        let order = keyed.into_iter().map(|(_, _, i)| i).collect();
        let left_right = |&[a, b]: &[usize; 2]| {
            if lex(pts[a], pts[b]) == Ordering::Greater {
                (b, a)
            } else {
                (a, b)
            }
        };
        let csr = |end: fn((usize, usize)) -> usize| {
            let mut ptr = vec![0usize; pts.len() + 1];
            for s in segs {
                ptr[end(left_right(s)) + 1] += 1;
            }
            for v in 0..pts.len() {
                ptr[v + 1] += ptr[v];
            }
            let mut fill = ptr.clone();
            let mut ids = vec![0usize; segs.len()];
            for (i, s) in segs.iter().enumerate() {
                let v = end(left_right(s));
                ids[fill[v]] = i;
                fill[v] += 1;
            }
            (ptr, ids)
        };
        let (start_ptr, starts) = csr(|(l, _)| l);
        let (end_ptr, ends) = csr(|(_, r)| r);
        Events {
            order,
            start_ptr,
            starts,
            end_ptr,
            ends,
        }
    }
}

/// Whether segments `i` and `j` meet outside the end points they share.
fn collide(pts: &[Point], segs: &[[usize; 2]], i: usize, j: usize) -> bool {
    let ([a, b], [c, d]) = (segs[i], segs[j]);
    let shared = if a == c || a == d {
        Some((a, b, if a == c { d } else { c }))
    } else if b == c || b == d {
        Some((b, a, if b == c { d } else { c }))
    } else {
        None
    };
    match shared {
        // the same vertex pair twice: they overlap entirely
        Some((_, p, q)) if p == q => true,
        Some((v, p, q)) => segments_overlap_from(pts[v], pts[p], pts[q]),
        None => segments_meet(pts[a], pts[b], pts[c], pts[d]),
    }
}

/// Finds two segments of `segs` (pairs of indices into `pts`) that meet anywhere but at an end
/// point they share, or, if there are none, the segment right below each vertex of `queries`.
/// The points must be finite and pairwise distinct; a segment must join two distinct points.
/// O((n + q) log n) for n points and segments and q queries.
pub(crate) fn first_collision(pts: &[Point], segs: &[[usize; 2]], queries: &[usize]) -> Sweep {
    let ev = Events::new(pts, segs);
    let active_seg = |i: usize| {
        let [a, b] = segs[i];
        let (l, r) = if lex(pts[a], pts[b]) == Ordering::Greater {
            (b, a)
        } else {
            (a, b)
        };
        Active {
            left: pts[l],
            right: pts[r],
            id: i,
        }
    };
    let collision = |i: usize, j: usize| Sweep::Collision(i.min(j), i.max(j));
    // the queries in sweep order, with their positions in `queries`
    let mut pending: Vec<(usize, usize)> = queries.iter().copied().zip(0..).collect();
    pending.sort_unstable_by(|a, b| lex(pts[b.0], pts[a.0]));
    let mut below = vec![None; queries.len()];
    let mut list = ActiveList::new(segs.len());
    for &v in &ev.order {
        for &i in &ev.ends[ev.end_ptr[v]..ev.end_ptr[v + 1]] {
            if let (Some(lo), Some(up)) = list.remove(i)
                && collide(pts, segs, lo, up)
            {
                return collision(lo, up);
            }
        }
        while pending.last().is_some_and(|&(q, _)| q == v) {
            let (_, k) = pending.pop().expect("not empty");
            let probe = Active {
                left: pts[v],
                right: pts[v],
                id: usize::MAX,
            };
            below[k] = list.below(&probe);
        }
        for &i in &ev.starts[ev.start_ptr[v]..ev.start_ptr[v + 1]] {
            let (lo, up) = list.insert(active_seg(i));
            for n in [lo, up].into_iter().flatten() {
                if collide(pts, segs, i, n) {
                    return collision(i, n);
                }
            }
        }
    }
    Sweep::Clear(below)
}

/// As [`first_collision`] without queries, by testing every pair.
#[cfg(test)]
fn first_collision_brute(pts: &[Point], segs: &[[usize; 2]]) -> Option<(usize, usize)> {
    (0..segs.len())
        .flat_map(|i| (i + 1..segs.len()).map(move |j| (i, j)))
        .find(|&(i, j)| collide(pts, segs, i, j))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small xorshift generator (deterministic tests without a crate).
    fn rng(mut s: u64) -> impl FnMut() -> f64 {
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

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
        let Sweep::Clear(below) = first_collision(&pts, &segs, &queries) else {
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
        // a cross
        assert_eq!(
            first_collision(&pts, &[[0, 1], [2, 3]], &[]),
            Sweep::Collision(0, 1)
        );
        // T-junction: vertex 4 on the segment 0–1
        assert_eq!(
            first_collision(&pts, &[[0, 1], [4, 3]], &[]),
            Sweep::Collision(0, 1)
        );
        // collinear overlap with a shared end point, and without
        assert_eq!(
            first_collision(&pts, &[[0, 1], [0, 4]], &[]),
            Sweep::Collision(0, 1)
        );
        assert_eq!(
            first_collision(&pts, &[[0, 1], [4, 5]], &[]),
            Sweep::Collision(0, 1)
        );
        // a path through shared vertices is fine
        assert!(clear(&first_collision(&pts, &[[0, 4], [4, 1], [1, 5]], &[])));
        // vertical segments
        assert!(clear(&first_collision(&pts, &[[2, 4], [4, 3]], &[])));
        assert_eq!(
            first_collision(&pts, &[[2, 3], [0, 4]], &[]),
            Sweep::Collision(0, 1)
        );
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
            match first_collision(&uniq, &segs, &[]) {
                Sweep::Collision(i, j) => {
                    assert!(brute.is_some(), "case {case}: {segs:?}");
                    assert!(collide(&uniq, &segs, i, j), "case {case}");
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
            let Sweep::Clear(below) = first_collision(&pts, &segs, &queries) else {
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
                match first_collision(&pts, &segs, &[]) {
                    Sweep::Collision(i, j) => {
                        assert!(brute.is_some() && collide(&pts, &segs, i, j), "case {case}")
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
        in_order.iter().map(|&n| list.nodes[n as usize].seg.id).collect()
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
            id: i,
        };
        let mut list = ActiveList::new(n);
        let mut active: Vec<usize> = Vec::new();
        for step in 0..5000 {
            let i = (r() * n as f64) as usize % n;
            let by_height = |v: &mut Vec<usize>| {
                v.sort_by(|&a, &b| heights[a].total_cmp(&heights[b]).then(a.cmp(&b)))
            };
            let neighbours = |v: &Vec<usize>, i: usize| {
                let pos = v.iter().position(|&j| j == i).unwrap();
                (
                    pos.checked_sub(1).map(|p| v[p]),
                    v.get(pos + 1).copied(),
                )
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
                id: usize::MAX,
            };
            let expected = active.iter().rev().find(|&&j| heights[j] < 0.5).copied();
            assert_eq!(list.below(&probe), expected);
        }
        assert!(list.nodes.len() <= n);
    }
}
