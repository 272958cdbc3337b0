//! FVCA5 / HArDCore2D `.typ2` files: polygonal cells given by their vertex lists.
//!
//! ```text
//! Vertices                 (header: any case and spacing)
//! Nv
//! x y                      (Nv records)
//! cells                    (or "Control volumes")
//! Nc
//! n v_1 ... v_n            (Nc records, 1-based vertex ids, either orientation)
//! [centers                 (optional, ignored: these are not always centroids)
//!  x y ...]
//! ```
//!
//! The file is read as a stream of whitespace-separated tokens (headers are whole lines), so
//! leading/trailing blanks and float spellings such as `0.` or `7.8E-002` are accepted.
//! Edges are derived from consecutive vertices; hanging nodes must be listed as cell vertices
//! (180° angles), as in every typ2 file of the FVCA5 benchmark.

use super::{Tokens, capacity, read_text};
use crate::budget::MemoryBudget;
use crate::budget::try_vec;
use crate::error::{Error, Result};
use crate::mesh::{MAX_CELL_VERTICES, Point, PolyMesh};
use std::io::Write;
use std::path::Path;

/// Reads a `.typ2` mesh. Cells may be listed in either orientation; the `centers` block, if
/// present, is ignored (centroids are recomputed). Any other data after the cells block is an
/// error, as it usually means a wrong count. No file larger than
/// [`MemoryBudget::max_file_bytes`] of `budget` is read.
pub fn read_typ2(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<PolyMesh> {
    let path = path.as_ref();
    let text = read_text(path, budget)?;
    parse_tokens(path, Tokens::from_text(path, &text))
}

/// Parses the contents of a `.typ2` file (`path` is only used in error messages); what the
/// reader does, for tests that work in memory.
#[cfg(test)]
pub(crate) fn parse_typ2(path: &Path, bytes: &[u8]) -> Result<PolyMesh> {
    parse_tokens(path, Tokens::new(path, bytes))
}

/// Parses a `.typ2` file from its tokens.
fn parse_tokens(path: &Path, mut t: Tokens) -> Result<PolyMesh> {
    let (vertices, cells) = parse_records(&mut t)?;
    match t.next_line()? {
        None => {}
        // the block is not read, but it must be text like the rest of the file
        Some((_, text)) if super::normalize_header(text) == "centers" => t.check_text()?,
        Some((line, text)) => {
            return Err(t.err_at(
                line,
                format!(
                    "unexpected data after the {} cells: \"{text}\" (wrong cell count?)",
                    cells.len()
                ),
            ));
        }
    }
    PolyMesh::from_cells(vertices, cells).map_err(|source| crate::Error::InvalidMeshFile {
        path: path.to_path_buf(),
        source,
    })
}

/// Parses the `Vertices` and `cells` blocks (0-based cells).
fn parse_records(t: &mut Tokens) -> Result<(Vec<Point>, Vec<Vec<usize>>)> {
    t.expect_header(&["vertices"])?;
    let nv = t.count("the number of vertices")?;
    let mut vertices = try_vec(capacity(nv, t.remaining()), "the vertices")?;
    for i in 1..=nv {
        let x = t.coord(&format!("x of vertex {i}"))?;
        let y = t.coord(&format!("y of vertex {i}"))?;
        vertices.push([x, y]);
    }
    t.expect_header(&["cells", "control volumes"])?;
    let nc = t.count("the number of cells")?;
    // a cell record takes at least 8 bytes ("3 1 2 3\n")
    let mut cells = try_vec(capacity(nc, t.remaining() / 2), "the cells")?;
    for k in 1..=nc {
        let n = t.count(&format!("the number of vertices of cell {k}"))?;
        if n < 3 {
            return Err(t.err(format!("cell {k} has {n} vertices, at least 3 are needed")));
        }
        if n > MAX_CELL_VERTICES {
            return Err(t.err(format!(
                "cell {k} has {n} vertices, more than the limit of {MAX_CELL_VERTICES}"
            )));
        }
        let mut c = Vec::with_capacity(capacity(n, t.remaining()));
        for _ in 0..n {
            c.push(t.index1(&format!("a vertex id of cell {k}"), nv)?);
        }
        cells.push(c);
    }
    Ok((vertices, cells))
}

/// Writes `mesh` as a `.typ2` file: a `Vertices` block (coordinates with 17 significant
/// digits, so that reading the file back gives bit-identical coordinates) and a `cells` block
/// (counter-clockwise, 1-based vertex ids). No `centers` block.
pub fn write_typ2(path: impl AsRef<Path>, mesh: &PolyMesh) -> Result<()> {
    let path = path.as_ref();
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(file);
    write_typ2_to(&mut w, mesh).map_err(io)?;
    w.flush().map_err(io)
}

fn write_typ2_to(w: &mut impl Write, mesh: &PolyMesh) -> std::io::Result<()> {
    writeln!(w, "Vertices")?;
    writeln!(w, "{}", mesh.n_vertices())?;
    for p in mesh.vertices() {
        writeln!(w, "{:.16e} {:.16e}", p[0], p[1])?;
    }
    writeln!(w, "cells")?;
    writeln!(w, "{}", mesh.n_cells())?;
    for k in 0..mesh.n_cells() {
        let c = mesh.cell_vertices(k);
        write!(w, "{}", c.len())?;
        for &v in c {
            write!(w, " {}", v + 1)?;
        }
        writeln!(w)?;
    }
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::error::MeshError;

    pub(in crate::mesh::io) const SQUARE: &str = " Vertices \n 4\n0. 0.\n 1.0 0\n1 1.0E+000\n0 1\n CONTROL   volumes\n1\n4 1 2 3 4\ncenters\n0.5 0.5\n";

    #[test]
    fn reads_a_square_with_centers_block() {
        let m = parse_typ2(Path::new("sq.typ2"), SQUARE.as_bytes()).unwrap();
        assert_eq!((m.n_vertices(), m.n_cells(), m.n_edges()), (4, 1, 4));
        assert_eq!(m.measure(0), 1.0);
    }

    #[test]
    fn reports_bad_cells() {
        let bad = SQUARE.replace("4 1 2 3 4", "4 1 2 3 3");
        let e = parse_typ2(Path::new("sq.typ2"), bad.as_bytes()).unwrap_err();
        assert!(
            matches!(
                e,
                Error::InvalidMeshFile {
                    source: MeshError::BadCell { .. },
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn writes_17_digits() {
        let v = vec![[0.0, 0.0], [1.0 / 3.0, 0.0], [0.1, 0.7]];
        let m = PolyMesh::from_cells(v, vec![vec![0, 1, 2]]).unwrap();
        let mut out = Vec::new();
        write_typ2_to(&mut out, &m).unwrap();
        let back = parse_typ2(Path::new("x.typ2"), &out).unwrap();
        assert_eq!(back.vertices(), m.vertices());
        assert_eq!(back.cell_vertices(0), m.cell_vertices(0));
    }
}
