//! HArDCore's RF format: `NAME.node` (vertices) and `NAME.ele` (cells as lists of faces).
//!
//! The files are read as whitespace-separated numbers (a record may span lines, as in
//! HArDCore's own files); `#` starts a comment that runs to the end of its line. `NAME.node`
//! has the header `nv 3 0 0` and then `id x y z` per vertex, ids consecutive from 0 or from 1;
//! `NAME.ele` has the header `nc 0` and then, for each cell, `id nf` followed by `nf` faces
//! `local_id n v_0 … v_{n−1}`, the vertex ids of one face in order around it (numbered as in
//! `NAME.node`).
//! A face shared by two cells is listed by both, in either orientation. The files carry no
//! tags: the cells and the boundary faces are untagged.

use crate::budget::MemoryBudget;
use crate::budget::{try_reserve, try_vec};
use crate::error::{Error, Result};
use crate::mesh::io::{Tokens, capacity, read_text};
use crate::mesh3d::{Point3, Polyhedra};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// The `.node` and `.ele` files of an RF mesh given by the path of either or by their common
/// stem (`cube.1` for `cube.1.node` and `cube.1.ele`).
pub fn rf_files(path: &Path) -> (PathBuf, PathBuf) {
    let ext = path.extension().and_then(|e| e.to_str());
    let stem = match ext {
        Some("node" | "ele") => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let with = |ext: &str| {
        let mut s = OsString::from(stem.as_os_str());
        s.push(ext);
        PathBuf::from(s)
    };
    (with(".node"), with(".ele"))
}

/// Reads an RF mesh (see the module docs); `path` is the `.node` file, the `.ele` file or their
/// stem. Neither file may be larger than [`MemoryBudget::max_file_bytes`] of `budget`.
pub fn read_rf(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<Polyhedra> {
    let (node, ele) = rf_files(path.as_ref());
    let text = read_text(&node, budget)?;
    let (vertices, base) = parse_node(Tokens::from_text(&node, &text))?;
    drop(text);
    let text = read_text(&ele, budget)?;
    let mut p = parse_ele(&ele, Tokens::from_text(&ele, &text), vertices.len(), base)?;
    p.vertices = vertices;
    Ok(p)
}

/// The tokens of an RF file: [`Tokens`] with `#` comments skipped.
struct Rf<'a> {
    t: Tokens<'a>,
}

impl<'a> Rf<'a> {
    /// The next token that is not in a comment, or `None` at the end of the file.
    fn next_opt(&mut self) -> Result<Option<&'a str>> {
        loop {
            match self.t.next_opt()? {
                Some(tok) if tok.starts_with('#') => {
                    self.t.rest_of_line()?;
                }
                other => return Ok(other),
            }
        }
    }

    fn next(&mut self, what: &str) -> Result<&'a str> {
        self.next_opt()?.ok_or_else(|| {
            self.t
                .err(format!("unexpected end of file while reading {what}"))
        })
    }

    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Result<T> {
        let tok = self.next(what)?;
        tok.parse()
            .map_err(|_| self.t.err(format!("cannot read {what} from \"{tok}\"")))
    }

    fn count(&mut self, what: &str) -> Result<usize> {
        let tok = self.next(what)?;
        tok.parse().map_err(|_| {
            self.t.err(format!(
                "cannot read {what} from \"{tok}\" (expected a non-negative integer)"
            ))
        })
    }

    fn coord(&mut self, what: &str) -> Result<f64> {
        match self.parse::<f64>(what)? {
            x if x.is_finite() => Ok(x),
            x => Err(self.t.err(format!("{what} is not finite: {x}"))),
        }
    }

    /// `Ok` if only comments and blanks remain.
    fn end(&mut self) -> Result<()> {
        match self.next_opt()? {
            None => Ok(()),
            Some(tok) => Err(self
                .t
                .err(format!("unexpected \"{tok}\" after the last record"))),
        }
    }
}

/// The vertices of a `.node` file and the id of the first one (0 or 1).
pub(crate) fn parse_node(t: Tokens) -> Result<(Vec<Point3>, u64)> {
    let mut t = Rf { t };
    let nv = t.count("the number of vertices")?;
    let dim = t.count("the dimension")?;
    if dim != 3 {
        return Err(t.t.err(format!("the dimension is {dim}, not 3")));
    }
    t.count("the first flag")?;
    t.count("the second flag")?;
    let mut vertices = try_vec(capacity(nv, t.t.remaining()), "the vertices")?;
    let mut base = 0;
    for i in 0..nv {
        let id: u64 = t.parse("a vertex id")?;
        if i == 0 && id <= 1 {
            base = id;
        }
        if id != base + i as u64 {
            return Err(t.t.err(format!(
                "vertex id {id} where {} was expected (ids are consecutive from 0 or 1)",
                base + i as u64
            )));
        }
        vertices.push([t.coord("x")?, t.coord("y")?, t.coord("z")?]);
    }
    t.end()?;
    Ok((vertices, base))
}

/// The cells of a `.ele` file whose vertex ids count from `base` up to `base + nv`.
pub(crate) fn parse_ele(path: &Path, t: Tokens, nv: usize, base: u64) -> Result<Polyhedra> {
    let mut t = Rf { t };
    let nc = t.count("the number of cells")?;
    t.count("the flag of the header")?;
    let mut p = Polyhedra::default();
    let cap = capacity(nc, t.t.remaining()).saturating_add(1);
    try_reserve(&mut p.cell_ptr, cap, "the cell offsets")?;
    let (mut loops, mut ends) = (Vec::new(), Vec::new());
    for k in 0..nc {
        t.parse::<u64>(&format!("the id of cell {k}"))?;
        let nf = t.count("the number of faces")?;
        loops.clear();
        ends.clear();
        for j in 0..nf {
            t.parse::<u64>(&format!("the id of face {j} of cell {k}"))?;
            let n = t.count("the number of vertices of a face")?;
            if n < 3 {
                return Err(t.t.err(format!(
                    "face {j} of cell {k} has {n} vertices (at least 3)"
                )));
            }
            for _ in 0..n {
                let v: u64 = t.parse("a vertex id")?;
                if v < base || v - base >= nv as u64 {
                    return Err(t.t.err(format!(
                        "vertex id {v} is out of range {base}..{}",
                        base + nv as u64
                    )));
                }
                loops.push((v - base) as u32);
            }
            ends.push(loops.len());
        }
        let faces = (0..ends.len()).map(|j| &loops[if j == 0 { 0 } else { ends[j - 1] }..ends[j]]);
        p.push_cell(faces)
            .map_err(|source| Error::InvalidMeshFile {
                path: path.to_path_buf(),
                source,
            })?;
    }
    t.end()?;
    if p.cell_ptr.is_empty() {
        return Err(t.t.err_at(0, "the file has no cells"));
    }
    Ok(p)
}
