//! Reads back the `.vtu` files of [`super::write_vtu3`]: ASCII XML with one `<Piece>`, every
//! `DataArray` element on a line of its own and its values on the lines after it.
//!
//! `VTK_TETRA` and `VTK_HEXAHEDRON` cells get the faces gmsh lists for them, `VTK_POLYHEDRON`
//! cells the faces of their `faces` stream as written; the `cell_tag` cell data gives the
//! cell tags, the `tagged_faces` and `tagged_tags` field data the tagged boundary faces. Other
//! cell types and other layouts (binary or appended data) are errors naming the line.

use super::cells::{HEX_FACES, TET_FACES, push_shape};
use super::too_large;
use super::vtu::{VTK_HEXAHEDRON, VTK_POLYHEDRON, VTK_TETRA};
use crate::budget::MemoryBudget;
use crate::error::Result;
use crate::mesh::io::{Tokens, read_text};
use crate::mesh3d::Polyhedra;
use std::path::Path;

/// Reads a `.vtu` file written by [`super::write_vtu3`] (see the module docs). No file larger
/// than [`MemoryBudget::max_file_bytes`] of `budget` is read.
pub fn read_vtu3(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<Polyhedra> {
    let path = path.as_ref();
    let text = read_text(path, budget)?;
    parse_vtu3(path, Tokens::from_text(path, &text))
}

/// The arrays of the file that the mesh is made of, each with the line of its `DataArray`.
#[derive(Default)]
struct Arrays {
    n_points: Option<usize>,
    n_cells: Option<usize>,
    points: (Vec<f64>, usize),
    ints: Vec<(&'static str, Vec<i64>, usize)>,
}

const INT_ARRAYS: [&str; 8] = [
    "connectivity",
    "offsets",
    "types",
    "faces",
    "faceoffsets",
    "cell_tag",
    "tagged_faces",
    "tagged_tags",
];

/// The value of attribute `name` in the tag `line`.
fn attribute<'a>(line: &'a str, name: &str) -> Option<&'a str> {
    let pat = format!(" {name}=\"");
    let start = line.find(&pat)? + pat.len();
    line[start..].split('"').next()
}

/// Parses the text of a `.vtu` file.
pub(crate) fn parse_vtu3(path: &Path, mut t: Tokens) -> Result<Polyhedra> {
    let mut a = Arrays::default();
    let mut in_points = false;
    while let Some((line, l)) = t.next_line()? {
        if l.starts_with("<Piece") {
            if a.n_points.is_some() {
                return Err(t.err_at(line, "a second <Piece>: only one is read"));
            }
            let count = |name| {
                attribute(l, name)
                    .and_then(|v| v.parse::<usize>().ok())
                    .ok_or_else(|| t.err_at(line, format!("<Piece> has no valid {name}")))
            };
            a.n_points = Some(count("NumberOfPoints")?);
            a.n_cells = Some(count("NumberOfCells")?);
        } else if l.starts_with("<Points") {
            in_points = true;
        } else if l.starts_with("</Points") {
            in_points = false;
        } else if l.starts_with("<DataArray") {
            read_array(&mut t, &mut a, line, l, in_points)?;
        }
    }
    let (Some(np), Some(nc)) = (a.n_points, a.n_cells) else {
        return Err(t.err_at(0, "no <Piece> element: is this a .vtu file?"));
    };
    if a.points.0.len() != 3 * np {
        return Err(t.err_at(
            a.points.1,
            format!("{} point coordinates for {np} points", a.points.0.len()),
        ));
    }
    build(path, &t, a, np, nc)
}

/// Reads the values of the `DataArray` opened at `line` (`l`) up to `</DataArray>`.
fn read_array(t: &mut Tokens, a: &mut Arrays, line: usize, l: &str, in_points: bool) -> Result<()> {
    if attribute(l, "format") != Some("ascii") {
        return Err(t.err_at(line, "only ASCII data arrays (format=\"ascii\") are read"));
    }
    let name = attribute(l, "Name").unwrap_or("");
    let int = INT_ARRAYS.iter().find(|&&n| n == name);
    let mut ints = Vec::new();
    let mut floats = Vec::new();
    loop {
        let tok = t.next("\"</DataArray>\"")?;
        if tok == "</DataArray>" {
            break;
        }
        if in_points {
            floats.push(
                tok.parse::<f64>()
                    .map_err(|_| t.err(format!("cannot read a coordinate from \"{tok}\"")))?,
            );
        } else if int.is_some() {
            ints.push(
                tok.parse::<i64>().map_err(|_| {
                    t.err(format!("cannot read an integer of {name} from \"{tok}\""))
                })?,
            );
        }
    }
    if in_points {
        a.points = (floats, line);
    } else if let Some(&n) = int {
        if a.ints.iter().any(|(m, ..)| *m == n) {
            return Err(t.err_at(line, format!("a second array \"{n}\"")));
        }
        a.ints.push((n, ints, line));
    }
    Ok(())
}

/// The arrays of the `<Cells>` block and the tags.
struct CellArrays {
    offsets: Vec<i64>,
    types: Vec<i64>,
    conn: Vec<i64>,
    faces: Vec<i64>,
    faceoffsets: Vec<i64>,
    /// Lines of `offsets`, `types`, `connectivity`, `faces`.
    lines: [usize; 4],
}

/// Builds the mesh from the arrays of a file with `np` points and `nc` cells.
fn build(path: &Path, t: &Tokens, mut a: Arrays, np: usize, nc: usize) -> Result<Polyhedra> {
    let mut take = |name: &str, len: Option<usize>| -> Result<(Vec<i64>, usize)> {
        let Some(i) = a.ints.iter().position(|(n, ..)| *n == name) else {
            return match len {
                Some(_) if !name.contains("tag") => {
                    Err(t.err_at(0, format!("no \"{name}\" array")))
                }
                _ => Ok((Vec::new(), 0)),
            };
        };
        let (_, v, line) = a.ints.swap_remove(i);
        match len {
            Some(n) if v.len() != n => Err(t.err_at(
                line,
                format!("\"{name}\" has {} values for {n} cells", v.len()),
            )),
            _ => Ok((v, line)),
        }
    };
    let (offsets, l0) = take("offsets", Some(nc))?;
    let (types, l1) = take("types", Some(nc))?;
    let (conn, l2) = take("connectivity", None)?;
    let (faces, l3) = take("faces", None)?;
    let faceoffsets = take("faceoffsets", None)?.0;
    let cell_tag = take("cell_tag", Some(nc))?.0;
    let (tagged, tagged_line) = take("tagged_faces", None)?;
    let tagged_tags = take("tagged_tags", None)?.0;
    let arrays = CellArrays {
        offsets,
        types,
        conn,
        faces,
        faceoffsets,
        lines: [l0, l1, l2, l3],
    };
    let mut p = Polyhedra {
        vertices: a
            .points
            .0
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        cell_tags: cell_tag.iter().map(|&g| g as i32).collect(),
        ..Polyhedra::default()
    };
    read_cells(path, t, &arrays, np, &mut p)?;
    if tagged.is_empty() && tagged_tags.is_empty() {
        return Ok(p);
    }
    let (mut loops, mut ends) = (Vec::new(), Vec::new());
    let valid = polyhedron(&tagged, &mut loops, &mut ends).is_some()
        && ends.len() == tagged_tags.len()
        && loops.iter().all(|&v| (v as usize) < np);
    if !valid {
        return Err(t.err_at(
            tagged_line,
            "\"tagged_faces\" and \"tagged_tags\" do not match",
        ));
    }
    p.tagged_ptr = std::iter::once(0)
        .chain(ends.iter().map(|&e| e as u32))
        .collect();
    p.tagged_vertices = loops;
    p.tagged_tags = tagged_tags.iter().map(|&g| g as i32).collect();
    Ok(p)
}

/// Appends the cells described by `a` to `p`.
fn read_cells(path: &Path, t: &Tokens, a: &CellArrays, np: usize, p: &mut Polyhedra) -> Result<()> {
    let [off_line, ty_line, conn_line, faces_line] = a.lines;
    let vertex = |v: i64, line: usize| {
        u32::try_from(v)
            .ok()
            .filter(|&v| (v as usize) < np)
            .ok_or_else(|| t.err_at(line, format!("vertex {v} is out of range 0..{np}")))
    };
    let mesh_err = |e| too_large(path, e);
    let (mut start, mut face_start) = (0usize, 0usize);
    let (mut nodes, mut scratch, mut ends) = (Vec::new(), Vec::new(), Vec::new());
    for (c, (&off, &ty)) in a.offsets.iter().zip(&a.types).enumerate() {
        let end = usize::try_from(off)
            .ok()
            .filter(|&e| e >= start && e <= a.conn.len())
            .ok_or_else(|| {
                t.err_at(
                    off_line,
                    format!("offset {off} of cell {c} is out of range"),
                )
            })?;
        nodes.clear();
        for &v in &a.conn[start..end] {
            nodes.push(vertex(v, conn_line)?);
        }
        start = end;
        let (table, len): (&[&[usize]], usize) = match ty {
            VTK_TETRA => (&TET_FACES, 4),
            VTK_HEXAHEDRON => (&HEX_FACES, 8),
            VTK_POLYHEDRON => (&[], 0),
            _ => {
                return Err(t.err_at(
                    ty_line,
                    format!("cell {c} has the VTK type {ty}: only 10, 12 and 42 are read"),
                ));
            }
        };
        if ty != VTK_POLYHEDRON {
            if nodes.len() != len {
                return Err(t.err_at(
                    conn_line,
                    format!(
                        "cell {c} of type {ty} has {} vertices, not {len}",
                        nodes.len()
                    ),
                ));
            }
            push_shape(p, table, &nodes, &mut scratch).map_err(mesh_err)?;
            continue;
        }
        let fend = a.faceoffsets.get(c).and_then(|&e| usize::try_from(e).ok());
        let stream = fend.and_then(|e| a.faces.get(face_start..e));
        face_start = fend.unwrap_or(face_start);
        let ok = stream
            .and_then(|s| polyhedron(s, &mut scratch, &mut ends))
            .is_some()
            && scratch.iter().all(|&v| (v as usize) < np);
        if !ok {
            return Err(t.err_at(
                faces_line,
                format!("the faces of cell {c} are not a valid stream"),
            ));
        }
        let loops =
            (0..ends.len()).map(|j| &scratch[if j == 0 { 0 } else { ends[j - 1] }..ends[j]]);
        p.push_cell(loops).map_err(mesh_err)?;
    }
    if p.n_cells() == 0 {
        return Err(t.err_at(0, "the file has no cells"));
    }
    Ok(())
}

/// Splits the face stream of one polyhedron (`nf`, then per face `n` and `n` vertex ids) into
/// `loops` (the vertex ids, concatenated) and `ends` (the end of each face in `loops`);
/// `None` if the stream is malformed.
fn polyhedron(stream: &[i64], loops: &mut Vec<u32>, ends: &mut Vec<usize>) -> Option<()> {
    loops.clear();
    ends.clear();
    let (&nf, mut rest) = stream.split_first()?;
    for _ in 0..nf {
        let (&n, tail) = rest.split_first()?;
        let n = usize::try_from(n)
            .ok()
            .filter(|&n| n >= 3 && n <= tail.len())?;
        for &v in &tail[..n] {
            loops.push(u32::try_from(v).ok()?);
        }
        ends.push(loops.len());
        rest = &tail[n..];
    }
    rest.is_empty().then_some(())
}
