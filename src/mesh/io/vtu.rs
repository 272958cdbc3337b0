//! VTK XML unstructured-grid (`.vtu`) writer, ASCII, for ParaView, meshio, VisIt.
//!
//! Every cell is written as a `VTK_POLYGON` (type 7) with its counter-clockwise vertex list;
//! points get z = 0. Floats are written with 17 significant digits in scientific notation
//! (`{:.16e}`), so the output is deterministic and round-trips exactly; non-finite values are
//! written as `nan`, `inf` and `-inf`.

use crate::error::{Error, Result};
use crate::mesh::PolyMesh;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// VTK cell type of a polygon.
const VTK_POLYGON: u8 = 7;

/// Writes `mesh` to `path` as an ASCII `.vtu` file, with named point-data arrays (one value per
/// vertex) and cell-data arrays (one value per cell), all `Float64`.
///
/// Returns [`Error::InvalidData`] if an array has the wrong length, a name is empty, or two
/// arrays of the same kind share a name; [`Error::Io`] if the file cannot be written.
pub fn write_vtu(
    path: impl AsRef<Path>,
    mesh: &PolyMesh,
    point_data: &[(&str, &[f64])],
    cell_data: &[(&str, &[f64])],
) -> Result<()> {
    let path = path.as_ref();
    check_arrays("point", point_data, mesh.n_vertices(), "vertices")?;
    check_arrays("cell", cell_data, mesh.n_cells(), "cells")?;
    write_file(path, |w| write_to(w, mesh, point_data, cell_data))
}

/// Creates `path` and writes it, buffered, through `write`; an I/O error is [`Error::Io`]
/// with the path.
pub(crate) fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut w = BufWriter::new(File::create(path).map_err(io)?);
    write(&mut w).map_err(io)?;
    w.flush().map_err(io)
}

/// The start of an unstructured grid of one piece of `n_points` points and `n_cells` cells, up
/// to the opening `<Piece>` tag.
pub(crate) fn write_header(
    w: &mut impl Write,
    n_points: usize,
    n_cells: usize,
) -> std::io::Result<()> {
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    )
}

/// The `<Cells>` block of `n_cells` polygons, cell k the loop of points `point(v)` for the
/// vertices v of `vertex_loop(k)`, then the end of the piece and of the file.
pub(crate) fn write_polygons_and_end<'a, W: Write>(
    w: &mut W,
    n_cells: usize,
    vertex_loop: impl Fn(usize) -> &'a [u32],
    point: impl Fn(u32) -> u32,
) -> std::io::Result<()> {
    writeln!(w, "      <Cells>")?;
    write_cell_array(w, "Int64", "connectivity", n_cells, |w, k| {
        write!(w, "         ")?;
        for &v in vertex_loop(k) {
            write!(w, " {}", point(v))?;
        }
        writeln!(w)
    })?;
    let mut offset = 0usize;
    write_cell_array(w, "Int64", "offsets", n_cells, |w, k| {
        offset += vertex_loop(k).len();
        writeln!(w, "          {offset}")
    })?;
    write_cell_array(w, "UInt8", "types", n_cells, |w, _| {
        writeln!(w, "          {VTK_POLYGON}")
    })?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

pub(crate) fn check_arrays(
    kind: &str,
    arrays: &[(&str, &[f64])],
    n: usize,
    what: &str,
) -> Result<()> {
    for (i, (name, values)) in arrays.iter().enumerate() {
        if name.is_empty() {
            return Err(Error::InvalidData(format!(
                "{kind}-data array {i} has an empty name"
            )));
        }
        if values.len() != n {
            return Err(Error::InvalidData(format!(
                "{kind}-data array \"{name}\" has {} values, but the mesh has {n} {what}",
                values.len()
            )));
        }
        if arrays[..i].iter().any(|(other, _)| other == name) {
            return Err(Error::InvalidData(format!(
                "two {kind}-data arrays are called \"{name}\""
            )));
        }
    }
    Ok(())
}

/// Escapes the XML special characters of an attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

pub(crate) fn write_f64(w: &mut impl Write, x: f64) -> std::io::Result<()> {
    if x.is_nan() {
        write!(w, "nan")
    } else if x.is_infinite() {
        write!(w, "{}", if x > 0.0 { "inf" } else { "-inf" })
    } else {
        write!(w, "{x:.16e}")
    }
}

pub(crate) fn write_data(w: &mut impl Write, name: &str, values: &[f64]) -> std::io::Result<()> {
    writeln!(
        w,
        "        <DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
        xml_escape(name)
    )?;
    for chunk in values.chunks(6) {
        write!(w, "         ")?;
        for &x in chunk {
            write!(w, " ")?;
            write_f64(w, x)?;
        }
        writeln!(w)?;
    }
    writeln!(w, "        </DataArray>")
}

/// A `DataArray` of the `<Cells>` block, of type `ty` and named `name`: one line per cell
/// `k < n_cells`, written by `line`.
pub(crate) fn write_cell_array<W: Write>(
    w: &mut W,
    ty: &str,
    name: &str,
    n_cells: usize,
    mut line: impl FnMut(&mut W, usize) -> std::io::Result<()>,
) -> std::io::Result<()> {
    writeln!(
        w,
        "        <DataArray type=\"{ty}\" Name=\"{name}\" format=\"ascii\">"
    )?;
    for k in 0..n_cells {
        line(w, k)?;
    }
    writeln!(w, "        </DataArray>")
}

fn write_to(
    w: &mut impl Write,
    mesh: &PolyMesh,
    point_data: &[(&str, &[f64])],
    cell_data: &[(&str, &[f64])],
) -> std::io::Result<()> {
    write_header(w, mesh.n_vertices(), mesh.n_cells())?;
    if !point_data.is_empty() {
        writeln!(w, "      <PointData>")?;
        for (name, values) in point_data {
            write_data(w, name, values)?;
        }
        writeln!(w, "      </PointData>")?;
    }
    if !cell_data.is_empty() {
        writeln!(w, "      <CellData>")?;
        for (name, values) in cell_data {
            write_data(w, name, values)?;
        }
        writeln!(w, "      </CellData>")?;
    }
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in mesh.vertices() {
        write!(w, "          ")?;
        write_f64(w, p[0])?;
        write!(w, " ")?;
        write_f64(w, p[1])?;
        writeln!(w, " 0")?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    write_polygons_and_end(w, mesh.n_cells(), |k| mesh.cell_vertices(k), |v| v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> PolyMesh {
        let v = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]];
        PolyMesh::from_cells(v, vec![vec![0, 1, 2, 3], vec![1, 4, 2]]).unwrap()
    }

    #[test]
    fn deterministic_output() {
        let m = square();
        let u = [0.5, 0.2, 0.3, 0.4, f64::NAN];
        let mut a = Vec::new();
        let mut b = Vec::new();
        write_to(&mut a, &m, &[("u", &u)], &[("a<b", &[1.0, 2.0])]).unwrap();
        write_to(&mut b, &m, &[("u", &u)], &[("a<b", &[1.0, 2.0])]).unwrap();
        assert_eq!(a, b);
        let s = String::from_utf8(a).unwrap();
        assert!(s.contains("Name=\"a&lt;b\""));
        assert!(s.contains("5.0000000000000000e-1"));
        assert!(s.contains(" nan"));
    }

    #[test]
    fn rejects_bad_lengths_and_names() {
        let m = square();
        let p = std::env::temp_dir().join("gradvi_vtu_never_written.vtu");
        let e = write_vtu(&p, &m, &[("u", &[1.0])], &[]).unwrap_err();
        assert!(matches!(e, Error::InvalidData(_)), "{e}");
        let e = write_vtu(&p, &m, &[], &[("k", &[1.0, 2.0]), ("k", &[1.0, 2.0])]).unwrap_err();
        assert!(matches!(e, Error::InvalidData(_)), "{e}");
        let e = write_vtu(&p, &m, &[], &[("", &[1.0, 2.0])]).unwrap_err();
        assert!(matches!(e, Error::InvalidData(_)), "{e}");
        assert!(!p.exists());
    }
}
