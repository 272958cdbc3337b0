//! 3D mesh readers and writers: files to and from [`Polyhedra`].
//!
//! | format | read | write | notes |
//! |---|---|---|---|
//! | gmsh `.msh` (ASCII 4.1 and 2.2) | [`read_msh3`] | – | tetrahedra, hexahedra, prisms, pyramids; physical volumes and surfaces become cell and boundary-face tags |
//! | HArDCore RF (`.node` + `.ele`) | [`read_rf`] | – | general polyhedra, untagged |
//! | VTK `.vtu` (ASCII XML) | [`read_vtu3`] (what [`write_vtu3`] writes) | [`write_vtu3`] | `VTK_TETRA`, `VTK_HEXAHEDRON`, `VTK_POLYHEDRON`; tags as cell data |
//!
//! [`read_mesh3`] picks the reader from the file name. The readers give the guarantees of the
//! 2D ones ([`crate::mesh::io`]): [`Error::MeshIo`] with the file and the 1-based line when the
//! text cannot be parsed, never a panic; reading stops at the first line that is not text or is
//! longer than [`crate::mesh::io::MAX_LINE_BYTES`]; no file larger than
//! [`MemoryBudget::max_file_bytes`] is read, and counts announced by a file never reserve more
//! memory than the rest of the file could fill. The faces are not matched, oriented or
//! checked here: that is done when the mesh is built from the [`Polyhedra`].

mod cells;
pub mod msh3;
pub mod rf;
pub mod vtu;
mod vtu_read;

#[cfg(test)]
mod tests;

pub use msh3::read_msh3;
pub use rf::read_rf;
pub use vtu::write_vtu3;
pub use vtu_read::read_vtu3;

use crate::budget::MemoryBudget;
use crate::budget::{try_filled, try_vec};
use crate::error::{Error, MeshError, Result};
use crate::mesh3d::{Point3, Polyhedra};
use std::path::Path;

/// Reads a 3D mesh, choosing the reader from the extension of `path` (case-insensitive):
/// `.msh` ([`read_msh3`]), `.vtu` ([`read_vtu3`]), `.node` or `.ele` ([`read_rf`]); a path
/// with another extension (or none) is read as the stem of an RF pair if `path.node` exists.
pub fn read_mesh3(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<Polyhedra> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("msh") => read_msh3(path, budget),
        Some("vtu") => read_vtu3(path, budget),
        Some("node" | "ele") => read_rf(path, budget),
        _ if rf::rf_files(path).0.is_file() => read_rf(path, budget),
        _ => Err(Error::MeshIo {
            path: path.to_path_buf(),
            line: 0,
            msg: "unknown 3D mesh format: expected the extension .msh, .vtu, .node or .ele, \
                  or the stem of a .node/.ele pair"
                .into(),
        }),
    }
}

/// A mesh error of the file at `path` (a size limit, for readers).
pub(crate) fn too_large(path: &Path, source: MeshError) -> Error {
    Error::InvalidMeshFile {
        path: path.to_path_buf(),
        source,
    }
}

/// Keeps the vertices that `cells` uses, in their order, and renumbers `cells` and `faces`
/// (ids into `nodes`) accordingly; a face vertex no cell uses becomes `u32::MAX`.
/// [`Error::OutOfMemory`] if the renumbering or the vertices cannot be allocated.
pub(crate) fn compact_vertices(
    nodes: &[Point3],
    cells: &mut [u32],
    faces: &mut [u32],
) -> Result<Vec<Point3>> {
    let mut new_id = try_filled(nodes.len(), u32::MAX, "the renumbering of the nodes")?;
    for &v in cells.iter() {
        new_id[v as usize] = 0;
    }
    let used = new_id.iter().filter(|&&id| id == 0).count();
    let mut vertices = try_vec(used, "the vertices")?;
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = vertices.len() as u32;
            vertices.push(nodes[v]);
        }
    }
    for v in cells.iter_mut().chain(faces.iter_mut()) {
        *v = new_id[*v as usize];
    }
    Ok(vertices)
}
