//! The boundary surface of a 3D mesh as a VTK XML unstructured grid (`.vtu`, ASCII), with data
//! per boundary face: what ParaView shows of a solution on ∂Ω (the face values u_σ, the
//! Signorini contact zone and its multiplier, the boundary parts), which the volume file of
//! [`crate::mesh3d::io::write_vtu3`] can only show on the cells.
//!
//! Each boundary face σ of the [`PolyMesh3`] is one `VTK_POLYGON` (7) cell, in the order of
//! [`PolyMesh3::boundary_faces`], with its vertex loop counter-clockwise seen from outside Ω
//! (the mesh's own loop: its normal is the outward normal n_σ). The points are the vertices of
//! the boundary faces, in increasing order of their index in the mesh. The file always holds
//! the cell data `face` (Int64: the index σ of each face in the mesh, to join the file with the
//! mesh's face arrays) and `boundary_tag` (Int32: the face's tag, the gmsh physical surface, 0
//! when untagged), then the caller's arrays: point data given per mesh vertex and face data given
//! per mesh face (one value per face, interior faces included), of which the writer keeps the
//! values on the boundary. Floats are written as by the other VTU writers (17 significant
//! digits, exact on reading back).

use crate::error::{Error, Result};
use crate::mesh::io::vtu::{check_arrays, write_cell_array, write_data, write_f64};
use crate::mesh3d::PolyMesh3;
use std::io::Write;
use std::path::Path;

/// The VTK cell type of a polygon.
const VTK_POLYGON: u8 = 7;

/// Writes the boundary surface of `mesh` to `path` (see the module docs), with `point_data`
/// (one value per mesh vertex) and `face_data` (one value per mesh face), all `Float64`.
///
/// [`Error::InvalidData`] if an array has the wrong length, a name is empty, reserved
/// (`face`, `boundary_tag`) or given twice; [`Error::Io`] if the file cannot be written.
pub fn write_boundary_vtu(
    path: impl AsRef<Path>,
    mesh: &PolyMesh3,
    point_data: &[(&str, &[f64])],
    face_data: &[(&str, &[f64])],
) -> Result<()> {
    let path = path.as_ref();
    check_arrays("point", point_data, mesh.n_vertices(), "vertices")?;
    check_arrays("face", face_data, mesh.n_faces(), "faces")?;
    if let Some((name, _)) = face_data
        .iter()
        .find(|(n, _)| matches!(*n, "face" | "boundary_tag"))
    {
        return Err(Error::InvalidData(format!(
            "the face-data name \"{name}\" is reserved: the boundary VTU file writes it itself"
        )));
    }
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::new(file);
    write_to(&mut w, mesh, point_data, face_data).map_err(io)?;
    w.flush().map_err(io)
}

/// The vertices of the boundary faces in increasing order, and the point index of each mesh
/// vertex (`u32::MAX` off the boundary).
fn boundary_points(mesh: &PolyMesh3) -> (Vec<u32>, Vec<u32>) {
    let mut on = vec![false; mesh.n_vertices()];
    for &f in mesh.boundary_faces() {
        for &v in mesh.face_vertices(f as usize) {
            on[v as usize] = true;
        }
    }
    let used: Vec<u32> = (0..mesh.n_vertices() as u32)
        .filter(|&v| on[v as usize])
        .collect();
    let mut index = vec![u32::MAX; mesh.n_vertices()];
    for (i, &v) in used.iter().enumerate() {
        index[v as usize] = i as u32;
    }
    (used, index)
}

fn write_to(
    w: &mut impl Write,
    mesh: &PolyMesh3,
    point_data: &[(&str, &[f64])],
    face_data: &[(&str, &[f64])],
) -> std::io::Result<()> {
    let faces = mesh.boundary_faces();
    let nf = faces.len();
    let (used, index) = boundary_points(mesh);
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{nf}\">",
        used.len()
    )?;
    if !point_data.is_empty() {
        writeln!(w, "      <PointData>")?;
        for (name, values) in point_data {
            let on: Vec<f64> = used.iter().map(|&v| values[v as usize]).collect();
            write_data(w, name, &on)?;
        }
        writeln!(w, "      </PointData>")?;
    }
    writeln!(w, "      <CellData>")?;
    write_cell_array(w, "Int64", "face", nf, |w, i| {
        writeln!(w, "          {}", faces[i])
    })?;
    write_cell_array(w, "Int32", "boundary_tag", nf, |w, i| {
        writeln!(w, "          {}", mesh.face_tag(faces[i] as usize))
    })?;
    for (name, values) in face_data {
        let on: Vec<f64> = faces.iter().map(|&f| values[f as usize]).collect();
        write_data(w, name, &on)?;
    }
    writeln!(w, "      </CellData>")?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for &v in &used {
        write!(w, "          ")?;
        for (i, &c) in mesh.vertices()[v as usize].iter().enumerate() {
            write!(w, "{}", if i == 0 { "" } else { " " })?;
            write_f64(w, c)?;
        }
        writeln!(w)?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    write_cell_array(w, "Int64", "connectivity", nf, |w, i| {
        write!(w, "         ")?;
        for &v in mesh.face_vertices(faces[i] as usize) {
            write!(w, " {}", index[v as usize])?;
        }
        writeln!(w)
    })?;
    let mut offset = 0usize;
    write_cell_array(w, "Int64", "offsets", nf, |w, i| {
        offset += mesh.face_vertices(faces[i] as usize).len();
        writeln!(w, "          {offset}")
    })?;
    write_cell_array(w, "UInt8", "types", nf, |w, _| {
        writeln!(w, "          {VTK_POLYGON}")
    })?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

#[cfg(test)]
#[path = "vtu_boundary_tests.rs"]
mod tests;
