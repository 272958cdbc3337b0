//! The mesh of a problem file's `[mesh]` section, 2D or 3D, chosen as `gradvi solve` chooses it
//! (the command line's `solve3d::case_mesh` and `mesh::read_any`).
//!
//! - a generated 3D family (`generate = "cubes"`, ...): [`gradvi::case::build_mesh3`];
//! - a mesh file, when the problem file compiles as a 3D problem and the format is not 2D
//!   only (`.typ1`, `.typ2`): a gmsh `.msh` is 3D when it has 3D elements (else it is read as
//!   a planar mesh), `.vtu` and HArDCore RF files are 3D;
//! - anything else: the planar mesh of [`gradvi::case::build_mesh`].

use gradvi::mesh::{MemoryBudget, PolyMesh};
use gradvi::mesh3d::PolyMesh3;
use gradvi::mesh3d::io::{read_mesh3, read_msh3};
use gradvi::problem::file::{MeshSpec, ProblemFile};
use std::path::Path;

/// A mesh of either dimension.
pub enum CaseMesh {
    Two(PolyMesh),
    Three(PolyMesh3),
}

/// The mesh `spec` describes for the problem file `pf` (see the module docs).
pub fn case_mesh(spec: &MeshSpec, pf: &ProblemFile) -> gradvi::Result<CaseMesh> {
    let budget = MemoryBudget::available();
    let ext = |p: &Path| {
        p.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
    };
    Ok(match spec {
        MeshSpec::Generated3 { .. } => CaseMesh::Three(gradvi::case::build_mesh3(spec, budget)?),
        MeshSpec::File(p) if pf.compiles_for(3) => match ext(p).as_deref() {
            Some("typ1" | "typ2") => CaseMesh::Two(gradvi::case::build_mesh(spec, budget)?),
            Some("msh") => match read_msh3(p, budget) {
                Ok(poly) => CaseMesh::Three(from_polyhedra(p, poly, budget)?),
                // the one error of the 3D gmsh reader at line 0: the file has no 3D element
                Err(gradvi::Error::MeshIo { line: 0, .. }) => {
                    CaseMesh::Two(gradvi::case::build_mesh(spec, budget)?)
                }
                Err(e) => return Err(e),
            },
            _ => CaseMesh::Three(from_polyhedra(p, read_mesh3(p, budget)?, budget)?),
        },
        _ => CaseMesh::Two(gradvi::case::build_mesh(spec, budget)?),
    })
}

/// The validated 3D mesh of the polyhedra read from `path`.
pub(crate) fn from_polyhedra(
    path: &Path,
    poly: gradvi::mesh3d::Polyhedra,
    budget: MemoryBudget,
) -> gradvi::Result<PolyMesh3> {
    PolyMesh3::from_polyhedra(poly, budget).map_err(|source| gradvi::Error::InvalidMeshFile {
        path: path.to_path_buf(),
        source,
    })
}
