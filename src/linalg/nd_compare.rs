use super::ordering::nested_dissection;
/// Leaves of the dissection at most this size are ordered as they are.
const ND_LEAF: usize = 64;

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
pub fn old_nd(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    // full adjacency, no diagonal
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
    drop(fill);

    enum Task {
        Split(Vec<usize>),
        Emit(Vec<usize>),
    }
    let mut order = Vec::with_capacity(n);
    let mut mark = vec![0u32; n]; // part id of each vertex
    let mut level = vec![u32::MAX; n];
    let mut next_id = 1u32;
    let mut stack = vec![Task::Split((0..n).collect())];
    // breadth-first search inside part `id` from `root`; returns the vertices in BFS order
    // and the start of each level in it (levels left in `level`, to be reset by the caller)
    let bfs = |root: usize,
               id: u32,
               mark: &[u32],
               level: &mut [u32],
               out: &mut Vec<usize>,
               starts: &mut Vec<usize>| {
        out.clear();
        starts.clear();
        out.push(root);
        level[root] = 0;
        let mut head = 0;
        while head < out.len() {
            let v = out[head];
            let lv = level[v];
            if starts.len() == lv as usize {
                starts.push(head);
            }
            head += 1;
            for &w in &adj[ptr[v]..ptr[v + 1]] {
                if mark[w] == id && level[w] == u32::MAX {
                    level[w] = lv + 1;
                    out.push(w);
                }
            }
        }
    };
    let mut reached = Vec::new();
    let mut starts = Vec::new();
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
        let id = next_id;
        next_id = next_id.wrapping_add(1).max(1);
        for &v in &part {
            mark[v] = id;
        }
        // pseudo-peripheral root: repeat BFS from a minimum-degree vertex of the last level
        let mut root = part[0];
        let mut depth = 0usize;
        for _ in 0..4 {
            bfs(root, id, &mark, &mut level, &mut reached, &mut starts);
            for &v in &reached {
                level[v] = u32::MAX;
            }
            let d = starts.len();
            let last = &reached[starts[d - 1]..];
            let cand = last
                .iter()
                .copied()
                .min_by_key(|&v| ptr[v + 1] - ptr[v])
                .unwrap_or(root);
            if d <= depth {
                break;
            }
            depth = d;
            root = cand;
        }
        bfs(root, id, &mark, &mut level, &mut reached, &mut starts);
        if reached.len() < part.len() {
            // disconnected: this component, then the rest
            let rest: Vec<usize> = part
                .iter()
                .copied()
                .filter(|&v| level[v] == u32::MAX)
                .collect();
            for &v in &reached {
                level[v] = u32::MAX;
            }
            stack.push(Task::Split(rest));
            stack.push(Task::Split(reached.clone()));
            continue;
        }
        let nlev = starts.len();
        // the level holding the median vertex
        let half = reached.len() / 2;
        let m = starts.iter().rposition(|&s| s <= half).unwrap_or(0);
        if m == 0 || m + 1 >= nlev {
            order.extend_from_slice(&reached);
            for &v in &reached {
                level[v] = u32::MAX;
            }
            continue;
        }
        let m32 = m as u32;
        let mut a: Vec<usize> = reached[..starts[m]].to_vec();
        let end_m = starts[m + 1];
        let b: Vec<usize> = reached[end_m..].to_vec();
        let mut sep = Vec::new();
        for &v in &reached[starts[m]..end_m] {
            let touches_b = adj[ptr[v]..ptr[v + 1]]
                .iter()
                .any(|&w| mark[w] == id && level[w] == m32 + 1);
            if touches_b {
                sep.push(v);
            } else {
                a.push(v);
            }
        }
        for &v in &reached {
            level[v] = u32::MAX;
        }
        stack.push(Task::Emit(sep));
        stack.push(Task::Split(b));
        stack.push(Task::Split(a));
    }
    order
}


#[cfg(test)]
mod cmp {
    use super::*;
    fn rng(seed: &mut u64) -> u64 { *seed ^= *seed << 13; *seed ^= *seed >> 7; *seed ^= *seed << 17; *seed }
    fn lower(n: usize, edges: &[(usize, usize)]) -> (Vec<usize>, Vec<usize>) {
        let mut cols = vec![vec![]; n];
        for c in 0..n { cols[c].push(c); }
        for &(a, b) in edges { let (r, c) = if a > b { (a, b) } else { (b, a) }; if r != c { cols[c].push(r); } }
        let mut cp = vec![0]; let mut ri = vec![];
        for mut c in cols { c.sort(); c.dedup(); ri.extend(c); cp.push(ri.len()); }
        (cp, ri)
    }
    #[test]
    fn same_as_old() {
        let mut seed = 88172645463325252u64;
        let mut cases = 0;
        for (nx, ny, comps, extra) in [(30, 20, 1, 0), (200, 150, 1, 0), (57, 91, 3, 100), (10, 10, 5, 0), (300, 7, 2, 500), (120, 120, 1, 3000), (1, 1000, 1, 0), (40, 40, 4, 20000)] {
            let per = nx * ny;
            let n = per * comps;
            let mut e = vec![];
            for k in 0..comps { for j in 0..ny { for i in 0..nx {
                let v = k * per + j * nx + i;
                if i + 1 < nx { e.push((v, v + 1)); }
                if j + 1 < ny { e.push((v, v + nx)); }
                if i + 1 < nx && j + 1 < ny && (i + j) % 3 == 0 { e.push((v, v + nx + 1)); }
            }}}
            for _ in 0..extra { let a = (rng(&mut seed) as usize) % n; let b = (rng(&mut seed) as usize) % n; e.push((a, b)); }
            // shuffle labels
            let mut lab: Vec<usize> = (0..n).collect();
            for i in (1..n).rev() { let j = (rng(&mut seed) as usize) % (i + 1); lab.swap(i, j); }
            for shuffled in [false, true] {
                let ee: Vec<(usize, usize)> = if shuffled { e.iter().map(|&(a, b)| (lab[a], lab[b])).collect() } else { e.clone() };
                let (cp, ri) = lower(n, &ee);
                assert_eq!(old_nd(n, &cp, &ri), nested_dissection(n, &cp, &ri));
                cases += 1;
            }
        }
        eprintln!("cases {cases}");
    }
}
