//! Fill-reducing orderings of a symmetric sparsity pattern: the choice ([`Ordering`]) and the
//! nested dissection by breadth-first level-set separators ([`nested_dissection`]).
//!
//! Nested dissection: find a small set S of vertices (the *separator*) whose removal splits
//! the graph into two halves A and B with no edge between them, and number A, then B, then
//! S. Eliminating A cannot fill B (and conversely), so the fill of the Cholesky factor is
//! confined to the diagonal blocks and the rows of S; recursing on A and B gives, on 2D mesh
//! graphs with separators of O(√n) vertices, a factor of O(n log n) entries.

/// The fill-reducing ordering of the symbolic factorisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Ordering {
    /// faer's approximate minimum degree (AMD).
    #[default]
    Amd,
    /// Nested dissection with breadth-first level-set separators ([`nested_dissection`]).
    NestedDissection,
}

/// Leaves of the dissection at most this size are ordered as they are.
const ND_LEAF: usize = 64;

/// Marks a vertex that the current breadth-first search has not reached.
const UNREACHED: u32 = u32::MAX;

/// The adjacency of a symmetric pattern in CSR form, both triangles, without the diagonal:
/// the neighbours of v are `adj[ptr[v]..ptr[v + 1]]`.
struct Graph {
    ptr: Vec<usize>,
    adj: Vec<usize>,
}

impl Graph {
    /// The graph of the symmetric pattern given by one triangle in CSC form: each off-diagonal
    /// entry (r, c) is the two edges r → c and c → r.
    fn from_triangle(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Graph {
        // degrees, then their prefix sums
        let mut ptr = vec![0usize; n + 1];
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if r != c {
                    ptr[r + 1] += 1;
                    ptr[c + 1] += 1;
                }
            }
        }
        for i in 0..n {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut adj = vec![0usize; ptr[n]];
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                if r != c {
                    adj[fill[r]] = c;
                    fill[r] += 1;
                    adj[fill[c]] = r;
                    fill[c] += 1;
                }
            }
        }
        Graph { ptr, adj }
    }
    fn neighbours(&self, v: usize) -> &[usize] {
        &self.adj[self.ptr[v]..self.ptr[v + 1]]
    }
    fn degree(&self, v: usize) -> usize {
        self.ptr[v + 1] - self.ptr[v]
    }
}

/// What the dissection does with one part of the graph.
enum Split {
    /// The part is disconnected: the component `first` (in breadth-first order) and the `rest`.
    Components { first: Vec<usize>, rest: Vec<usize> },
    /// The level structure is too shallow to split: a leaf, in breadth-first order.
    Leaf(Vec<usize>),
    /// Two halves `a` and `b` with no edge between them, and their separator `sep`.
    Halves {
        a: Vec<usize>,
        b: Vec<usize>,
        sep: Vec<usize>,
    },
}

/// The state of the dissection: which part each vertex belongs to, and the level structure of
/// the last breadth-first search.
struct Dissection<'g> {
    graph: &'g Graph,
    /// Part id of each vertex (ids are recycled after 2³² − 1 parts; 0 is never an id).
    mark: Vec<u32>,
    /// Breadth-first level of each reached vertex, [`UNREACHED`] elsewhere (reset after use).
    level: Vec<u32>,
    next_id: u32,
    /// The vertices of the last search, in breadth-first order.
    reached: Vec<usize>,
    /// The start of each level in `reached`.
    starts: Vec<usize>,
}

impl<'g> Dissection<'g> {
    fn new(graph: &'g Graph, n: usize) -> Self {
        Dissection {
            graph,
            mark: vec![0u32; n],
            level: vec![UNREACHED; n],
            next_id: 1,
            reached: Vec::new(),
            starts: Vec::new(),
        }
    }

    /// Gives the vertices of `part` a fresh part id, and returns it.
    fn mark_part(&mut self, part: &[usize]) -> u32 {
        let id = self.next_id;
        self.next_id = self.next_id.wrapping_add(1).max(1);
        for &v in part {
            self.mark[v] = id;
        }
        id
    }

    /// Breadth-first search inside part `id` from `root`: the vertices in `reached`, the start
    /// of each level in `starts`, the levels in `level` (to be reset by [`Self::reset_levels`]).
    fn bfs(&mut self, root: usize, id: u32) {
        let (reached, starts, level) = (&mut self.reached, &mut self.starts, &mut self.level);
        reached.clear();
        starts.clear();
        reached.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < reached.len() {
            let v = reached[head];
            let lv = level[v];
            if starts.len() == lv as usize {
                starts.push(head);
            }
            head += 1;
            for &w in self.graph.neighbours(v) {
                if self.mark[w] == id && level[w] == UNREACHED {
                    level[w] = lv + 1;
                    reached.push(w);
                }
            }
        }
    }

    /// Marks the vertices of the last search unreached again.
    fn reset_levels(&mut self) {
        for &v in &self.reached {
            self.level[v] = UNREACHED;
        }
    }

    /// A pseudo-peripheral vertex of the component of `start` in part `id` (one of the ends
    /// of a long path, whose level structure is deep and thin): repeat the breadth-first
    /// search from a minimum-degree vertex of the last level while the depth grows (at most
    /// four searches).
    fn pseudo_peripheral_root(&mut self, start: usize, id: u32) -> usize {
        let mut root = start;
        let mut depth = 0usize;
        for _ in 0..4 {
            self.bfs(root, id);
            self.reset_levels();
            let d = self.starts.len();
            let last = &self.reached[self.starts[d - 1]..];
            let cand = last
                .iter()
                .copied()
                .min_by_key(|&v| self.graph.degree(v))
                .unwrap_or(root);
            if d <= depth {
                break;
            }
            depth = d;
            root = cand;
        }
        root
    }

    /// Splits the connected level structure of the last search at level m: the levels before m
    /// are half a, those after m half b; a vertex of level m with a neighbour in level m + 1
    /// is in the separator, the others join a (the separator is thinned).
    fn level_set_split(&self, m: usize, id: u32) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
        let (reached, starts) = (&self.reached, &self.starts);
        let next_level = m as u32 + 1;
        let mut a: Vec<usize> = reached[..starts[m]].to_vec();
        let end_m = starts[m + 1];
        let b: Vec<usize> = reached[end_m..].to_vec();
        let mut sep = Vec::new();
        for &v in &reached[starts[m]..end_m] {
            let touches_b = self
                .graph
                .neighbours(v)
                .iter()
                .any(|&w| self.mark[w] == id && self.level[w] == next_level);
            if touches_b {
                sep.push(v);
            } else {
                a.push(v);
            }
        }
        (a, b, sep)
    }

    /// One step of the dissection of `part` (more than [`ND_LEAF`] vertices).
    fn split(&mut self, part: &[usize]) -> Split {
        let id = self.mark_part(part);
        let root = self.pseudo_peripheral_root(part[0], id);
        self.bfs(root, id);
        if self.reached.len() < part.len() {
            // disconnected: this component, then the rest
            let rest: Vec<usize> = part
                .iter()
                .copied()
                .filter(|&v| self.level[v] == UNREACHED)
                .collect();
            self.reset_levels();
            return Split::Components {
                first: self.reached.clone(),
                rest,
            };
        }
        let nlev = self.starts.len();
        // the level holding the median vertex
        let half = self.reached.len() / 2;
        let m = self.starts.iter().rposition(|&s| s <= half).unwrap_or(0);
        let split = if m == 0 || m + 1 >= nlev {
            Split::Leaf(self.reached.clone())
        } else {
            let (a, b, sep) = self.level_set_split(m, id);
            Split::Halves { a, b, sep }
        };
        self.reset_levels();
        split
    }
}

/// A nested-dissection ordering of the symmetric pattern given by its lower (or upper)
/// triangle in CSC form: `order[new] = old`.
///
/// A part is split by the breadth-first level structure rooted at a pseudo-peripheral vertex:
/// the level holding the median vertex is the separator (thinned: a separator vertex with no
/// neighbour beyond it joins the first half), the levels before and after it are the two
/// halves, ordered recursively before the separator. Disconnected parts are split into their
/// components; parts of at most 64 vertices, or whose level structure is too shallow to
/// split, are leaves ordered breadth-first. On the graphs of 2D meshes the level sets are
/// curves of O(√n) vertices, which gives the O(n log n) fill of nested dissection.
pub fn nested_dissection(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    enum Task {
        /// Order this part (recursively).
        Split(Vec<usize>),
        /// Append these vertices to the order as they are (a separator).
        Emit(Vec<usize>),
    }
    let graph = Graph::from_triangle(n, col_ptr, row_idx);
    let mut dissection = Dissection::new(&graph, n);
    let mut order = Vec::with_capacity(n);
    // a stack, so that the tasks pushed last are done first: a, then b, then their separator
    let mut stack = vec![Task::Split((0..n).collect())];
    while let Some(task) = stack.pop() {
        let part = match task {
            Task::Emit(v) => {
                order.extend_from_slice(&v);
                continue;
            }
            Task::Split(p) => p,
        };
        if part.len() <= ND_LEAF {
            order.extend_from_slice(&part);
            continue;
        }
        match dissection.split(&part) {
            Split::Components { first, rest } => {
                stack.push(Task::Split(rest));
                stack.push(Task::Split(first));
            }
            Split::Leaf(v) => order.extend_from_slice(&v),
            Split::Halves { a, b, sep } => {
                stack.push(Task::Emit(sep));
                stack.push(Task::Split(b));
                stack.push(Task::Split(a));
            }
        }
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::SpdPattern;

    #[test]
    fn nested_dissection_is_a_permutation_and_factorises_a_grid_laplacian() {
        // 5-point Laplacian (+ identity) on a 30 × 20 grid, lower triangle
        let (nx, ny) = (30, 20);
        let n = nx * ny;
        let id = |i: usize, j: usize| j * nx + i;
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for c in 0..n {
            let (i, j) = (c % nx, c / nx);
            row_idx.push(c);
            if i + 1 < nx {
                row_idx.push(id(i + 1, j));
            }
            if j + 1 < ny {
                row_idx.push(id(i, j + 1));
            }
            col_ptr.push(row_idx.len());
        }
        let order = nested_dissection(n, &col_ptr, &row_idx);
        let mut seen = vec![false; n];
        for &v in &order {
            assert!(!seen[v]);
            seen[v] = true;
        }
        assert_eq!(order.len(), n);
        let mut values = vec![-1.0; row_idx.len()];
        for c in 0..n {
            values[col_ptr[c]] = 5.0;
        }
        let mut x = [vec![1.0; n], vec![1.0; n]];
        // one workspace for both factorisations (of different fill)
        let mut work = crate::linalg::CholeskyWork::new();
        for (o, ordering) in [Ordering::Amd, Ordering::NestedDissection]
            .iter()
            .enumerate()
        {
            let p =
                SpdPattern::with_ordering(n, col_ptr.clone(), row_idx.clone(), *ordering).unwrap();
            p.factor(&values, &mut work)
                .unwrap()
                .solve_in_place(&mut x[o]);
        }
        for (a, b) in x[0].iter().zip(&x[1]) {
            assert!((a - b).abs() < 1e-12);
        }
    }
}
