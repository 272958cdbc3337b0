//! HArDCore's RF format: `NAME.node` (vertices) and `NAME.ele` (cells as lists of faces).
//!
//! Lines starting with `#` are comments. `NAME.node` has the header `nv 3 0 0` and then one
//! line `id x y z` per vertex, ids consecutive from 0 or from 1; `NAME.ele` has the header
//! `nc 0` and then, for each cell, a line `id nf` followed by `nf` lines `local_id n v_0 …
//! v_{n−1}`, the vertex ids of one face in order around it (numbered as in `NAME.node`).
//! A face shared by two cells is listed by both, in either orientation. The files carry no
//! tags: the cells and the boundary faces are untagged.

use super::Fields;
use crate::error::{Error, Result};
use crate::mesh::MemoryBudget;
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
    let (vertices, base) = parse_node(&node, Tokens::from_text(&node, &text))?;
    drop(text);
    let text = read_text(&ele, budget)?;
    let mut p = parse_ele(&ele, Tokens::from_text(&ele, &text), vertices.len(), base)?;
    p.vertices = vertices;
    Ok(p)
}

/// The next line that is not blank and not a comment, as fields.
fn data_line<'a>(path: &'a Path, t: &mut Tokens<'a>, what: &str) -> Result<Fields<'a>> {
    loop {
        match t.next_line()? {
            Some((_, l)) if l.starts_with('#') => {}
            Some((line, l)) => return Ok(Fields::new(path, line, l)),
            None => return Err(t.err(format!("unexpected end of file: expected {what}"))),
        }
    }
}

/// The vertices of a `.node` file and the id of the first one (0 or 1).
pub(crate) fn parse_node<'a>(path: &'a Path, mut t: Tokens<'a>) -> Result<(Vec<Point3>, u64)> {
    let mut h = data_line(path, &mut t, "the header \"nv 3 0 0\"")?;
    let nv = h.count("the number of vertices")?;
    let dim = h.count("the dimension")?;
    if dim != 3 {
        return Err(h.err(format!("the dimension is {dim}, not 3")));
    }
    let mut vertices = Vec::with_capacity(capacity(nv, t.remaining()));
    let mut base = 0;
    for i in 0..nv {
        let mut f = data_line(path, &mut t, &format!("vertex {} of {nv}", i + 1))?;
        let id: u64 = f.parse("the vertex id")?;
        if i == 0 && id <= 1 {
            base = id;
        }
        if id != base + i as u64 {
            return Err(f.err(format!(
                "vertex id {id} where {} was expected (ids are consecutive from 0 or 1)",
                base + i as u64
            )));
        }
        let p = [f.coord("x")?, f.coord("y")?, f.coord("z")?];
        f.end()?;
        vertices.push(p);
    }
    end_of_file(&mut t)?;
    Ok((vertices, base))
}

/// `Ok` if only comments and blank lines remain.
fn end_of_file(t: &mut Tokens) -> Result<()> {
    while let Some((line, l)) = t.next_line()? {
        if !l.starts_with('#') {
            return Err(t.err_at(
                line,
                format!("unexpected line after the last record: \"{l}\""),
            ));
        }
    }
    Ok(())
}

/// The cells of a `.ele` file whose vertex ids count from `base` up to `base + nv`.
pub(crate) fn parse_ele<'a>(
    path: &'a Path,
    mut t: Tokens<'a>,
    nv: usize,
    base: u64,
) -> Result<Polyhedra> {
    let mut h = data_line(path, &mut t, "the header \"nc 0\"")?;
    let nc = h.count("the number of cells")?;
    let mut p = Polyhedra::default();
    p.cell_ptr
        .reserve(capacity(nc, t.remaining()).saturating_add(1));
    let (mut loops, mut ends) = (Vec::new(), Vec::new());
    for k in 0..nc {
        let mut c = data_line(path, &mut t, &format!("the header of cell {k}"))?;
        c.parse::<u64>("the cell id")?;
        let nf = c.count("the number of faces")?;
        if nf > t.remaining() / 4 {
            return Err(c.err(format!(
                "cell {k} announces {nf} faces, more than the file holds"
            )));
        }
        c.end()?;
        (loops.clear(), ends.clear());
        for j in 0..nf {
            let mut f = data_line(path, &mut t, &format!("face {j} of cell {k}"))?;
            f.parse::<u64>("the face id")?;
            let n = f.count("the number of vertices")?;
            if n < 3 {
                return Err(f.err(format!(
                    "face {j} of cell {k} has {n} vertices (at least 3)"
                )));
            }
            for _ in 0..n {
                let v: u64 = f.parse("a vertex id")?;
                if v < base || v - base >= nv as u64 {
                    return Err(f.err(format!(
                        "vertex id {v} is out of range {base}..{}",
                        base + nv as u64
                    )));
                }
                loops.push((v - base) as u32);
            }
            f.end()?;
            ends.push(loops.len());
        }
        let faces = (0..ends.len()).map(|j| &loops[if j == 0 { 0 } else { ends[j - 1] }..ends[j]]);
        p.push_cell(faces)
            .map_err(|source| Error::InvalidMeshFile {
                path: path.to_path_buf(),
                source,
            })?;
    }
    end_of_file(&mut t)?;
    if p.cell_ptr.is_empty() {
        return Err(t.err_at(0, "the file has no cells"));
    }
    Ok(p)
}
