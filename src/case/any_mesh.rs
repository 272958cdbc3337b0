//! A mesh of either dimension, its dimension told by the file or by the problem file: what
//! `gradvi mesh info`, `gradvi solve` and Python's `Problem.mesh` read.
//!
//! A mesh file's dimension comes from its format ([`read_any`]): `.typ1` and `.typ2` are 2D;
//! `.vtu`, `.node`, `.ele` and the stem of a `.node`/`.ele` pair (HArDCore's RF format) are
//! 3D; a gmsh `.msh` file is 3D when it has 3D elements (tetrahedra, hexahedra, prisms or
//! pyramids), else 2D. A problem file's `[mesh]` ([`case_mesh`]) is 3D for a generated 3D
//! family, and for a mesh file read as above when the problem file compiles as a 3D problem
//! and the format is not 2D only; else it is the planar mesh of [`build_mesh`], exactly as
//! before 3D solves existed. The faces of a 3D mesh that are not planar are kept whole or
//! split into triangles as the caller's [`WarpedFaces`] says.

use super::{build_mesh, build_mesh3};
use crate::budget::MemoryBudget;
use crate::error::{Error, Result};
use crate::mesh::PolyMesh;
use crate::mesh::io::read_mesh;
use crate::mesh3d::io::{read_mesh3, read_msh3};
use crate::mesh3d::{PolyMesh3, Polyhedra, WarpedFaces};
use crate::problem::file::{MeshSpec, ProblemFile};
use std::path::Path;

/// A validated mesh of either dimension.
#[derive(Debug)]
pub enum AnyMesh {
    /// A 2D polygonal mesh.
    Two(PolyMesh),
    /// A 3D polyhedral mesh.
    Three(PolyMesh3),
}

impl AnyMesh {
    /// The number of cells.
    pub fn n_cells(&self) -> usize {
        match self {
            AnyMesh::Two(m) => m.n_cells(),
            AnyMesh::Three(m) => m.n_cells(),
        }
    }

    /// The mesh size h (the largest cell diameter).
    pub fn h(&self) -> f64 {
        match self {
            AnyMesh::Two(m) => m.h(),
            AnyMesh::Three(m) => m.h(),
        }
    }
}

/// The extension of `path`, lowercase.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Reads and validates the mesh in `path`, 2D or 3D by its format (see the module docs), a 3D
/// mesh's warped faces as `warped` says, within `budget`.
///
/// A `.msh` file is first read by the 3D reader: a file with 3D elements is 3D. When the 3D
/// reader finds no 3D element (its error at line 0), the file is read by the 2D reader, whose
/// error, if any, is the one reported; any other error of the 3D reader (a syntax error, which
/// the 2D reader shares, or an element type neither reads) is reported as it is, unless the 2D
/// reader reads the file. A 3D mesh that fails validation is [`Error::InvalidMeshFile`].
pub fn read_any(path: &Path, warped: WarpedFaces, budget: MemoryBudget) -> Result<AnyMesh> {
    let three = |p: Polyhedra| {
        PolyMesh3::from_file_polyhedra(p, budget, warped)
            .map(AnyMesh::Three)
            .map_err(|source| Error::InvalidMeshFile {
                path: path.to_path_buf(),
                source,
            })
    };
    match extension(path).as_deref() {
        Some("typ1" | "typ2") => Ok(AnyMesh::Two(read_mesh(path, budget)?)),
        Some("msh") => match read_msh3(path, budget) {
            Ok(p) => three(p),
            Err(e3) => match read_mesh(path, budget) {
                Ok(m) => Ok(AnyMesh::Two(m)),
                Err(e2) if no_3d_cells(&e3) => Err(e2),
                Err(_) => Err(e3),
            },
        },
        _ => three(read_mesh3(path, budget)?),
    }
}

/// Whether `e`, an error of the 3D gmsh reader, says that the file has no 3D element (the
/// only error it reports at line 0).
fn no_3d_cells(e: &Error) -> bool {
    matches!(e, Error::MeshIo { line: 0, .. })
}

/// The mesh `spec` (the `[mesh]` of the problem file `pf`, or the command line's) describes,
/// 2D or 3D (see the module docs), a 3D mesh's warped faces as `warped` says, within `budget`.
pub fn case_mesh(
    spec: &MeshSpec,
    pf: &ProblemFile,
    warped: WarpedFaces,
    budget: MemoryBudget,
) -> Result<AnyMesh> {
    let two_d_format = |p: &Path| matches!(extension(p).as_deref(), Some("typ1" | "typ2"));
    Ok(match spec {
        MeshSpec::Generated3 { .. } => {
            AnyMesh::Three(warped.apply(build_mesh3(spec, budget)?, budget)?)
        }
        MeshSpec::File(p) if pf.compiles_for(3) && !two_d_format(p) => read_any(p, warped, budget)?,
        _ => AnyMesh::Two(build_mesh(spec, budget)?),
    })
}

#[cfg(test)]
#[path = "any_mesh_tests.rs"]
mod tests;
