//! Faces of a 3D mesh as a VTK XML unstructured grid (`.vtu`, ASCII), with data per face: what
//! ParaView shows of a solution on ∂Ω (the face values u_σ, the Signorini contact zone and its
//! multiplier, the boundary parts), or on every face of the mesh (the interior face unknowns
//! u_σ of HMM and CR), which the volume file of [`crate::mesh3d::io::write_vtu3`] can only show
//! on the cells.
//!
//! [`write_faces_vtu`] writes a list of faces; [`write_boundary_vtu`] is that list taken as
//! [`PolyMesh3::boundary_faces`]. Each listed face σ is one `VTK_POLYGON` (7) cell, in the
//! order of the list, with the mesh's own vertex loop: counter-clockwise seen from outside
//! `face_cells(σ)[0]`, so on the boundary counter-clockwise seen from outside Ω (its normal is
//! the outward normal n_σ). The points are the vertices of the listed faces, in increasing
//! order of their index in the mesh. The file always holds the cell data `face` (Int64: the
//! index σ of each face in the mesh, to join the file with the mesh's face arrays) and
//! `boundary_tag` (Int32: the face's tag, the gmsh physical surface; 0 for interior faces and
//! untagged boundary faces), then the caller's arrays: point data given per mesh vertex and
//! face data given per mesh face (one value per face, interior faces included), of which the
//! writer keeps the values on the listed faces. Floats are written as by the other VTU writers
//! (17 significant digits, exact on reading back).

use crate::error::{Error, Result};
use crate::mesh::io::vtu::{
    check_arrays, write_cell_array, write_data, write_f64, write_file, write_header,
    write_polygons_and_end,
};
use crate::mesh3d::PolyMesh3;
use std::io::Write;
use std::path::Path;

/// Writes the boundary surface of `mesh` to `path` (see the module docs), with `point_data`
/// (one value per mesh vertex) and `face_data` (one value per mesh face), all `Float64`:
/// [`write_faces_vtu`] of the boundary faces.
///
/// [`Error::InvalidData`] if an array has the wrong length, a name is empty, reserved
/// (`face`, `boundary_tag`) or given twice; [`Error::Io`] if the file cannot be written.
pub fn write_boundary_vtu(
    path: impl AsRef<Path>,
    mesh: &PolyMesh3,
    point_data: &[(&str, &[f64])],
    face_data: &[(&str, &[f64])],
) -> Result<()> {
    write_faces_vtu(path, mesh, mesh.boundary_faces(), point_data, face_data)
}

/// Writes the faces `faces` of `mesh` (indices into the mesh's faces, in the order of the
/// cells of the file) to `path` (see the module docs), with `point_data` (one value per mesh
/// vertex) and `face_data` (one value per mesh face), all `Float64`.
///
/// [`Error::InvalidData`] if a face index is out of range, an array has the wrong length, a
/// name is empty, reserved (`face`, `boundary_tag`) or given twice; [`Error::Io`] if the file
/// cannot be written.
pub fn write_faces_vtu(
    path: impl AsRef<Path>,
    mesh: &PolyMesh3,
    faces: &[u32],
    point_data: &[(&str, &[f64])],
    face_data: &[(&str, &[f64])],
) -> Result<()> {
    let path = path.as_ref();
    if let Some((i, f)) = faces
        .iter()
        .enumerate()
        .find(|(_, f)| **f as usize >= mesh.n_faces())
    {
        return Err(Error::InvalidData(format!(
            "face {f} (entry {i} of the faces to write) is out of range: the mesh has {} faces",
            mesh.n_faces()
        )));
    }
    check_arrays("point", point_data, mesh.n_vertices(), "vertices")?;
    check_arrays("face", face_data, mesh.n_faces(), "faces")?;
    if let Some((name, _)) = face_data
        .iter()
        .find(|(n, _)| matches!(*n, "face" | "boundary_tag"))
    {
        return Err(Error::InvalidData(format!(
            "the face-data name \"{name}\" is reserved: the face VTU file writes it itself"
        )));
    }
    write_file(path, |w| write_to(w, mesh, faces, point_data, face_data))
}

/// The vertices of `faces` in increasing order, and the point index of each mesh vertex
/// (`u32::MAX` off those faces).
fn face_points(mesh: &PolyMesh3, faces: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut on = vec![false; mesh.n_vertices()];
    for &f in faces {
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
    faces: &[u32],
    point_data: &[(&str, &[f64])],
    face_data: &[(&str, &[f64])],
) -> std::io::Result<()> {
    let nf = faces.len();
    let (used, index) = face_points(mesh, faces);
    write_header(w, used.len(), nf)?;
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
    write_polygons_and_end(
        w,
        nf,
        |i| mesh.face_vertices(faces[i] as usize),
        |v| index[v as usize],
    )
}

#[cfg(test)]
#[path = "vtu_boundary_tests.rs"]
mod tests;
