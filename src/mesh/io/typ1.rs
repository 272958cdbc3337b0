//! FVCA5 `.typ1` files: triangles and quadrangles with explicit edge lists.
//!
//! ```text
//! vertices                 Nv, then Nv records "x y"
//! triangles                Nt, then Nt records "a b c"       (1-based vertex ids)
//! quadrangles              Nq, then Nq records "a b c d"
//! edges of the boundary    Nb, then Nb records "a b"
//! all edges                Ne, then Ne records "a b K L"     (cells K, L: triangles first,
//!                                                             then quadrangles; L = 0 on ∂Ω)
//! ```
//!
//! Headers are matched case-insensitively, ignoring extra blanks. Cell orientation is not
//! reliable in these files (most quadrangles of `mesh3_*.typ1` are clockwise) and is fixed by
//! [`PolyMesh::from_cells`].
//!
//! **Hanging nodes.** In the non-conforming meshes (`mesh3`, `mesh5`, `mesh7`) a quadrangle lists
//! only its four corners, while the `all edges` list splits a side into several edges through
//! hanging nodes. The reader follows, for every side of every cell, the chain of that cell's
//! edges from one corner to the next and inserts the intermediate nodes into the cell's vertex
//! list, so that the cell becomes a polygon with 180° angles and the mesh is conforming (the
//! same mesh as the `.typ2` version of the file). Afterwards both edge lists are checked against
//! the mesh: every listed edge must be an edge of the mesh between the cells it names, and every
//! edge (boundary edge) of the mesh must be listed exactly once.

use super::{Tokens, capacity, read_text};
use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_reserve, try_vec};
use crate::error::Result;
use crate::mesh::{NO_CELL, Point, PolyMesh};
use std::path::Path;

/// Reads a `.typ1` mesh, inserting the hanging nodes of the `all edges` list into the cells
/// (see the module docs). No file larger than [`MemoryBudget::max_file_bytes`] of `budget` is
/// read.
pub fn read_typ1(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<PolyMesh> {
    let path = path.as_ref();
    let text = read_text(path, budget)?;
    parse_tokens(path, Tokens::from_text(path, &text))
}

/// One record of the `all edges` list (0-based; `l == NO_CELL` on the boundary).
struct EdgeRecord {
    a: usize,
    b: usize,
    k: usize,
    l: usize,
    line: usize,
}

const NONE: usize = usize::MAX;

/// Parses the contents of a `.typ1` file (`path` is only used in error messages); what the
/// reader does, for tests that work in memory.
#[cfg(test)]
pub(crate) fn parse_typ1(path: &Path, bytes: &[u8]) -> Result<PolyMesh> {
    parse_tokens(path, Tokens::new(path, bytes))
}

/// Parses a `.typ1` file from its tokens.
fn parse_tokens(path: &Path, mut t: Tokens) -> Result<PolyMesh> {
    t.expect_header(&["vertices"])?;
    let nv = t.count("the number of vertices")?;
    let mut vertices: Vec<Point> = try_vec(capacity(nv, t.remaining()), "the vertices")?;
    for i in 1..=nv {
        let x = t.coord(&format!("x of vertex {i}"))?;
        let y = t.coord(&format!("y of vertex {i}"))?;
        vertices.push([x, y]);
    }

    let mut corners: Vec<Vec<usize>> = Vec::new();
    let mut cell_line: Vec<usize> = Vec::new();
    for (header, name, n_corners) in [
        ("triangles", "triangle", 3),
        ("quadrangles", "quadrangle", 4),
    ] {
        t.expect_header(&[header])?;
        let n = t.count(&format!("the number of {header}"))?;
        let cap = capacity(n, t.remaining());
        try_reserve(&mut corners, cap, "the cells")?;
        try_reserve(&mut cell_line, cap, "the cells")?;
        for i in 1..=n {
            let mut c = Vec::with_capacity(n_corners);
            for _ in 0..n_corners {
                c.push(t.index1(&format!("a vertex id of {name} {i}"), nv)?);
            }
            corners.push(c);
            cell_line.push(t.token_line());
        }
    }
    let nc = corners.len();

    t.expect_header(&["edges of the boundary"])?;
    let nb = t.count("the number of boundary edges")?;
    let mut boundary: Vec<(usize, usize, usize)> =
        try_vec(capacity(nb, t.remaining()), "the boundary edges")?;
    for i in 1..=nb {
        let a = t.index1(&format!("a vertex id of boundary edge {i}"), nv)?;
        let b = t.index1(&format!("a vertex id of boundary edge {i}"), nv)?;
        boundary.push((a, b, t.token_line()));
    }

    t.expect_header(&["all edges"])?;
    let ne = t.count("the number of edges")?;
    let mut all: Vec<EdgeRecord> = try_vec(capacity(ne, t.remaining()), "the edges")?;
    for i in 1..=ne {
        let a = t.index1(&format!("a vertex id of edge {i}"), nv)?;
        let b = t.index1(&format!("a vertex id of edge {i}"), nv)?;
        let k = t.index1(&format!("the first cell of edge {i}"), nc)?;
        let l_tok = t.next(&format!("the second cell of edge {i}"))?;
        let l = match l_tok.parse::<u64>() {
            Ok(0) => NONE,
            Ok(l) if l <= nc as u64 => l as usize - 1,
            _ => {
                return Err(t.err(format!(
                    "cannot read the second cell of edge {i} from \"{l_tok}\" \
                     (expected 0 for the boundary or a cell id in 1..={nc})"
                )));
            }
        };
        if a == b {
            return Err(t.err(format!("edge {i} joins vertex {} to itself", a + 1)));
        }
        if k == l {
            return Err(t.err(format!("edge {i} has cell {} on both sides", k + 1)));
        }
        all.push(EdgeRecord {
            a,
            b,
            k,
            l,
            line: t.token_line(),
        });
    }
    if let Some((line, text)) = t.next_line()? {
        return Err(t.err_at(
            line,
            format!("unexpected data after the {ne} edges: \"{text}\" (wrong edge count?)"),
        ));
    }

    let cells = insert_hanging_nodes(&t, &vertices, &corners, &cell_line, &all)?;
    let mesh =
        PolyMesh::from_cells(vertices, cells).map_err(|source| crate::Error::InvalidMeshFile {
            path: path.to_path_buf(),
            source,
        })?;
    check_edge_lists(&t, &mesh, &boundary, &all)?;
    Ok(mesh)
}

/// Builds the cell vertex lists: the corners, with the nodes of the `all edges` chains that
/// split a side inserted between its two corners. Linear in the size of the file.
fn insert_hanging_nodes(
    t: &Tokens,
    vertices: &[Point],
    corners: &[Vec<usize>],
    cell_line: &[usize],
    all: &[EdgeRecord],
) -> Result<Vec<Vec<usize>>> {
    let nc = corners.len();
    // CSR: the records of the edges of every cell
    let mut ptr = try_filled(nc + 1, 0usize, "the edges of the cells")?;
    for r in all {
        for c in [r.k, r.l] {
            if c < nc {
                ptr[c + 1] += 1;
            }
        }
    }
    for i in 0..nc {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut ids = try_filled(ptr[nc], 0usize, "the edges of the cells")?;
    for (i, r) in all.iter().enumerate() {
        for c in [r.k, r.l] {
            if c < nc {
                ids[fill[c]] = i;
                fill[c] += 1;
            }
        }
    }

    // scratch adjacency of the current cell's edges, reset after each cell
    let mut nbr = try_filled(vertices.len(), [NONE; 2], "the neighbours of the vertices")?;
    let mut cells = try_vec(nc, "the cells")?;
    for (k, c) in corners.iter().enumerate() {
        let recs = &ids[ptr[k]..ptr[k + 1]];
        let mut result = Ok(());
        for &i in recs {
            let r = &all[i];
            for (p, q) in [(r.a, r.b), (r.b, r.a)] {
                let slot = &mut nbr[p];
                if slot[0] == NONE {
                    slot[0] = q;
                } else if slot[1] == NONE {
                    slot[1] = q;
                } else if result.is_ok() {
                    result = Err(t.err_at(
                        r.line,
                        format!(
                            "vertex {} has more than two edges of cell {} in the `all edges` list",
                            p + 1,
                            k + 1
                        ),
                    ));
                }
            }
        }
        let mut poly = Vec::with_capacity(c.len());
        if result.is_ok() {
            for (i, &ci) in c.iter().enumerate() {
                let cj = c[(i + 1) % c.len()];
                poly.push(ci);
                if nbr[ci].contains(&cj) {
                    continue;
                }
                let chain = nbr[ci]
                    .iter()
                    .filter(|&&s| s != NONE)
                    .find_map(|&s| walk(&nbr, c, ci, s, cj, recs.len()));
                match chain {
                    Some(chain) => poly.extend(chain),
                    None => {
                        result = Err(t.err_at(
                            cell_line.get(k).copied().unwrap_or(0),
                            format!(
                                "side {}-{} of cell {} is neither an edge of the `all edges` \
                                 list nor split into such edges by hanging nodes",
                                ci + 1,
                                cj + 1,
                                k + 1
                            ),
                        ));
                        break;
                    }
                }
            }
        }
        for &i in recs {
            nbr[all[i].a] = [NONE; 2];
            nbr[all[i].b] = [NONE; 2];
        }
        result?;
        cells.push(poly);
    }
    Ok(cells)
}

/// Follows the cell's edges from corner `from` through `first` until another corner; returns
/// the nodes passed if that corner is `to`.
fn walk(
    nbr: &[[usize; 2]],
    corners: &[usize],
    from: usize,
    first: usize,
    to: usize,
    max_steps: usize,
) -> Option<Vec<usize>> {
    let mut path = Vec::new();
    let (mut prev, mut cur) = (from, first);
    for _ in 0..=max_steps {
        if cur == to {
            return Some(path);
        }
        if corners.contains(&cur) {
            return None;
        }
        path.push(cur);
        let nb = nbr.get(cur)?;
        let next = if nb[0] == prev { nb[1] } else { nb[0] };
        if next == NONE {
            return None;
        }
        (prev, cur) = (cur, next);
    }
    None
}

/// Checks that record `r` of the `all edges` list, edge `e` of the mesh, names the cells on
/// either side of `e` (in either order).
fn check_edge_cells(t: &Tokens, mesh: &PolyMesh, r: &EdgeRecord, e: usize) -> Result<()> {
    let mut file_cells = [r.k, r.l];
    let mut mesh_cells = mesh.edge_cells(e);
    file_cells.sort_unstable();
    mesh_cells.sort_unstable();
    if file_cells == mesh_cells {
        return Ok(());
    }
    let show = |c: usize| {
        if c == NO_CELL {
            "0 (boundary)".to_string()
        } else {
            (c + 1).to_string()
        }
    };
    Err(t.err_at(
        r.line,
        format!(
            "edge {}-{} lies between cells {} and {} according to the cell lists, \
             not {} and {}",
            r.a + 1,
            r.b + 1,
            show(mesh_cells[0]),
            show(mesh_cells[1]),
            show(file_cells[0]),
            show(file_cells[1])
        ),
    ))
}

/// Checks the `all edges` and `edges of the boundary` lists against the mesh built from the
/// cells: same edges, each listed once, between the cells the file names.
fn check_edge_lists(
    t: &Tokens,
    mesh: &PolyMesh,
    boundary: &[(usize, usize, usize)],
    all: &[EdgeRecord],
) -> Result<()> {
    let mut keys: Vec<((usize, usize), usize)> = (0..mesh.n_edges())
        .map(|e| {
            let [a, b] = mesh.edge_vertices(e);
            ((a.min(b), a.max(b)), e)
        })
        .collect();
    keys.sort_unstable();
    let find = |a: usize, b: usize| {
        let key = (a.min(b), a.max(b));
        keys.binary_search_by(|probe| probe.0.cmp(&key))
            .ok()
            .map(|pos| keys[pos].1)
    };
    let mut seen = vec![false; mesh.n_edges()];
    for r in all {
        let Some(e) = find(r.a, r.b) else {
            return Err(t.err_at(
                r.line,
                format!("edge {}-{} is not a side of any cell", r.a + 1, r.b + 1),
            ));
        };
        if std::mem::replace(&mut seen[e], true) {
            return Err(t.err_at(
                r.line,
                format!("edge {}-{} is listed twice", r.a + 1, r.b + 1),
            ));
        }
        check_edge_cells(t, mesh, r, e)?;
    }
    if let Some(e) = seen.iter().position(|s| !s) {
        let [a, b] = mesh.edge_vertices(e);
        return Err(t.err_at(
            0,
            format!(
                "the `all edges` list has {} edges but the cells have {} (edge {}-{} is missing)",
                all.len(),
                mesh.n_edges(),
                a + 1,
                b + 1
            ),
        ));
    }
    seen.iter_mut().for_each(|s| *s = false);
    for &(a, b, line) in boundary {
        match find(a, b) {
            Some(e) if mesh.is_boundary_edge(e) => {
                if std::mem::replace(&mut seen[e], true) {
                    return Err(t.err_at(
                        line,
                        format!("boundary edge {}-{} is listed twice", a + 1, b + 1),
                    ));
                }
            }
            _ => {
                return Err(t.err_at(
                    line,
                    format!("{}-{} is not a boundary edge of the mesh", a + 1, b + 1),
                ));
            }
        }
    }
    if boundary.len() != mesh.boundary_edges().len() {
        return Err(t.err_at(
            0,
            format!(
                "the `edges of the boundary` list has {} edges but the mesh has {} boundary edges",
                boundary.len(),
                mesh.boundary_edges().len()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::error::{Error, MeshError};

    /// Unit square: a clockwise left half [0,0.5]x[0,1] next to two squares sharing the hanging
    /// node 7 = (0.5, 0.5).
    pub(in crate::mesh::io) const HANGING: &str = " vertices\n 8\n0 0\n0.5 0\n1 0\n0 1\n0.5 1\n1 1\n0.5 0.5\n1 0.5\n\
 triangles \n 0\n quadrangles \n 3\n1 4 5 2\n2 3 8 7\n7 8 6 5\n edges of the boundary \n 7\n\
1 2\n2 3\n3 8\n8 6\n6 5\n5 4\n4 1\n all edges\n 10\n1 2 1 0\n2 3 2 0\n3 8 2 0\n8 6 3 0\n\
6 5 3 0\n5 4 1 0\n4 1 1 0\n2 7 1 2\n7 5 3 1\n7 8 2 3\n";

    #[test]
    fn inserts_hanging_nodes() {
        let m = parse_typ1(Path::new("h.typ1"), HANGING.as_bytes()).unwrap();
        assert_eq!((m.n_vertices(), m.n_cells(), m.n_edges()), (8, 3, 10));
        assert_eq!(m.cell_vertices(0).len(), 5);
        assert!(m.cell_vertices(0).contains(&6));
        assert!((m.measure(0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn unlisted_hanging_node_is_non_conforming() {
        let bad = HANGING
            .replace("2 7 1 2\n7 5 3 1\n", "2 7 2 0\n7 5 3 0\n2 5 1 0\n")
            .replace(" all edges\n 10\n", " all edges\n 11\n");
        let e = parse_typ1(Path::new("h.typ1"), bad.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidMeshFile {
                    source: MeshError::NonConforming(_),
                    ..
                }
            ),
            "{e}"
        );
    }
}
