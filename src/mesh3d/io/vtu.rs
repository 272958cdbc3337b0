//! VTK XML unstructured-grid (`.vtu`) writer for 3D meshes, ASCII, for ParaView and meshio.
//!
//! Cells are written in the order of the [`Polyhedra`]. When every cell is a tetrahedron (4
//! triangles on 4 vertices) or a hexahedron (6 quadrangles on 8 vertices, connected as a
//! hexahedron), they are written as `VTK_TETRA` (10) and `VTK_HEXAHEDRON` (12), with VTK's
//! vertex order and positive orientation. Otherwise every cell is a `VTK_POLYHEDRON` (42)
//! (meshio reads no mix of polyhedra and other cells): its connectivity lists the cell's
//! vertices (each once, in order of appearance), the `faces` stream lists, per cell, the number
//! of faces and then each face as its number of vertices and its vertex loop, as given, and
//! `faceoffsets` holds the end of each cell's part of that stream.
//!
//! The cell tags, when the mesh has them, are the `Int32` cell-data array `cell_tag`. The
//! tagged boundary faces, when there are any, are `FieldData` of the grid (which ParaView and
//! meshio read but do not draw): `tagged_faces`, their number followed by each face as its
//! number of vertices and its vertex loop, and `tagged_tags`, their tags. Floats follow the 2D
//! writer ([`crate::mesh::io::vtu`]): 17 significant digits, deterministic, exact on reading
//! back.

use super::cells::{Shape, shape_of};
use crate::error::{Error, Result};
use crate::mesh::io::vtu::{check_arrays, write_cell_array, write_data, write_f64};
use crate::mesh3d::Polyhedra;
use std::io::Write;
use std::path::Path;

/// VTK cell types.
pub(crate) const VTK_TETRA: i64 = 10;
pub(crate) const VTK_HEXAHEDRON: i64 = 12;
pub(crate) const VTK_POLYHEDRON: i64 = 42;

/// Writes `p` to `path` as an ASCII `.vtu` file (see the module docs), with named point-data
/// arrays (one value per vertex) and cell-data arrays (one value per cell), all `Float64`.
///
/// [`Error::InvalidData`] if an array has the wrong length, a name is empty or two arrays of
/// the same kind share a name; [`Error::Io`] if the file cannot be written.
pub fn write_vtu3(
    path: impl AsRef<Path>,
    p: &Polyhedra,
    point_data: &[(&str, &[f64])],
    cell_data: &[(&str, &[f64])],
) -> Result<()> {
    let path = path.as_ref();
    check_arrays("point", point_data, p.vertices.len(), "vertices")?;
    check_arrays("cell", cell_data, p.n_cells(), "cells")?;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(file);
    write_to(&mut w, p, point_data, cell_data).map_err(io)?;
    w.flush().map_err(io)
}

/// How one VTK cell is written.
enum Out {
    Shape(Shape),
    Polyhedron(usize),
}

impl Polyhedra {
    /// The vertex loop of tagged face `j`.
    pub(crate) fn tagged_face(&self, j: usize) -> &[u32] {
        &self.tagged_vertices[self.tagged_ptr[j] as usize..self.tagged_ptr[j + 1] as usize]
    }
}

/// The distinct vertices of cell `k`, in order of appearance.
fn cell_vertices(p: &Polyhedra, k: usize) -> Vec<u32> {
    let mut v: Vec<u32> = Vec::new();
    for s in p.cell_sides(k) {
        for &a in p.side_vertices(s) {
            if !v.contains(&a) {
                v.push(a);
            }
        }
    }
    v
}

pub(super) fn write_to(
    w: &mut impl Write,
    p: &Polyhedra,
    point_data: &[(&str, &[f64])],
    cell_data: &[(&str, &[f64])],
) -> std::io::Result<()> {
    let nc = p.n_cells();
    let shapes: Option<Vec<Out>> = (0..nc).map(|k| shape_of(p, k).map(Out::Shape)).collect();
    let cells = shapes.unwrap_or_else(|| (0..nc).map(Out::Polyhedron).collect());
    let n = cells.len();
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    write_tagged_faces(w, p)?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n}\">",
        p.vertices.len()
    )?;
    if !point_data.is_empty() {
        writeln!(w, "      <PointData>")?;
        for (name, values) in point_data {
            write_data(w, name, values)?;
        }
        writeln!(w, "      </PointData>")?;
    }
    write_cell_data(w, p, cell_data)?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for x in &p.vertices {
        write!(w, "          ")?;
        for (i, &c) in x.iter().enumerate() {
            write!(w, "{}", if i == 0 { "" } else { " " })?;
            write_f64(w, c)?;
        }
        writeln!(w)?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    write_cells(w, p, &cells)?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// The tagged boundary faces, as `FieldData` (see the module docs).
fn write_tagged_faces(w: &mut impl Write, p: &Polyhedra) -> std::io::Result<()> {
    let nt = p.tagged_tags.len();
    if nt == 0 {
        return Ok(());
    }
    let len = 1 + nt + p.tagged_vertices.len();
    writeln!(w, "    <FieldData>")?;
    writeln!(
        w,
        "      <DataArray type=\"Int64\" Name=\"tagged_faces\" NumberOfTuples=\"{len}\" \
         format=\"ascii\">"
    )?;
    writeln!(w, "        {nt}")?;
    for j in 0..nt {
        let l = p.tagged_face(j);
        write!(w, "        {}", l.len())?;
        for v in l {
            write!(w, " {v}")?;
        }
        writeln!(w)?;
    }
    writeln!(w, "      </DataArray>")?;
    writeln!(
        w,
        "      <DataArray type=\"Int32\" Name=\"tagged_tags\" NumberOfTuples=\"{nt}\" \
         format=\"ascii\">"
    )?;
    for t in &p.tagged_tags {
        writeln!(w, "        {t}")?;
    }
    writeln!(w, "      </DataArray>")?;
    writeln!(w, "    </FieldData>")
}

/// The `<CellData>` block: the cell tags and the caller's arrays.
fn write_cell_data(
    w: &mut impl Write,
    p: &Polyhedra,
    cell_data: &[(&str, &[f64])],
) -> std::io::Result<()> {
    if cell_data.is_empty() && p.cell_tags.is_empty() {
        return Ok(());
    }
    writeln!(w, "      <CellData>")?;
    if !p.cell_tags.is_empty() {
        write_cell_array(w, "Int32", "cell_tag", p.n_cells(), |w, k| {
            writeln!(w, "          {}", p.cell_tags[k])
        })?;
    }
    for (name, values) in cell_data {
        write_data(w, name, values)?;
    }
    writeln!(w, "      </CellData>")
}

/// The `<Cells>` block.
fn write_cells(w: &mut impl Write, p: &Polyhedra, cells: &[Out]) -> std::io::Result<()> {
    let n = cells.len();
    let conn = |c: &Out| match c {
        Out::Shape(Shape::Tet(v)) => v.to_vec(),
        Out::Shape(Shape::Hex(v)) => v.to_vec(),
        Out::Polyhedron(k) => cell_vertices(p, *k),
    };
    writeln!(w, "      <Cells>")?;
    write_cell_array(w, "Int64", "connectivity", n, |w, k| {
        write!(w, "         ")?;
        for v in conn(&cells[k]) {
            write!(w, " {v}")?;
        }
        writeln!(w)
    })?;
    let mut offset = 0usize;
    write_cell_array(w, "Int64", "offsets", n, |w, k| {
        offset += conn(&cells[k]).len();
        writeln!(w, "          {offset}")
    })?;
    write_cell_array(w, "UInt8", "types", n, |w, k| {
        let ty = match cells[k] {
            Out::Shape(Shape::Tet(_)) => VTK_TETRA,
            Out::Shape(Shape::Hex(_)) => VTK_HEXAHEDRON,
            Out::Polyhedron(_) => VTK_POLYHEDRON,
        };
        writeln!(w, "          {ty}")
    })?;
    if cells.iter().any(|c| matches!(c, Out::Polyhedron(_))) {
        write_cell_array(w, "Int64", "faces", n, |w, k| {
            let Out::Polyhedron(k) = cells[k] else {
                return Ok(());
            };
            write!(w, "          {}", p.cell_sides(k).len())?;
            for s in p.cell_sides(k) {
                let l = p.side_vertices(s);
                write!(w, "  {}", l.len())?;
                for v in l {
                    write!(w, " {v}")?;
                }
            }
            writeln!(w)
        })?;
        let mut end = 0usize;
        write_cell_array(w, "Int64", "faceoffsets", n, |w, k| {
            let Out::Polyhedron(k) = cells[k] else {
                return Ok(());
            };
            end += 1 + p
                .cell_sides(k)
                .map(|s| 1 + p.side_vertices(s).len())
                .sum::<usize>();
            writeln!(w, "          {end}")
        })?;
    }
    writeln!(w, "      </Cells>")
}
