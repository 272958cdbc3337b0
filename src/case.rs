//! A problem file's case: its mesh built from `[mesh]`.
//!
//! A problem file ([`crate::problem::file`]) describes its mesh as data, a
//! [`MeshSpec`]: a mesh file or a generated family at a level. Reading or generating that mesh
//! is the job of this module, above the problem layer, so that `problem` depends on no mesh
//! reader or generator. [`read_any`] and [`case_mesh`] tell a mesh's dimension from its file
//! and from the problem file ([`AnyMesh`], in `any_mesh.rs`).

mod any_mesh;
pub use any_mesh::{AnyMesh, case_mesh, read_any};

use crate::budget::MemoryBudget;
use crate::error::{Error, Result};
use crate::mesh::PolyMesh;
use crate::mesh3d::PolyMesh3;
use crate::problem::file::MeshSpec;

/// The mesh `spec` describes: the file read ([`crate::mesh::io::read_mesh`], which knows the
/// formats by their extension), or the family generated at its level
/// ([`crate::mesh::Family::generate`]), on `domain` if one is given
/// ([`crate::mesh::Family::generate_on`]), within the caller's memory `budget` (the command
/// line and Python pass [`MemoryBudget::available`]).
pub fn build_mesh(spec: &MeshSpec, budget: MemoryBudget) -> Result<PolyMesh> {
    match spec {
        MeshSpec::File(p) => crate::mesh::io::read_mesh(p, budget),
        MeshSpec::Generated {
            family,
            level,
            domain,
        } => match domain {
            None => family.generate(*level, budget),
            Some(d) => family.generate_on(*level, *d, budget),
        },
        MeshSpec::Generated3 { .. } => Err(Error::InvalidData(format!(
            "the mesh {spec} is 3D: build it with case::build_mesh3"
        ))),
    }
}

/// The 3D mesh `spec` describes: the file read ([`crate::mesh3d::io::read_mesh3`]), or the 3D
/// family generated at its level on `domain` (the unit cube if none), within `budget`.
pub fn build_mesh3(spec: &MeshSpec, budget: MemoryBudget) -> Result<PolyMesh3> {
    match spec {
        MeshSpec::File(p) => {
            let poly = crate::mesh3d::io::read_mesh3(p, budget)?;
            Ok(PolyMesh3::from_file_polyhedra(
                poly,
                budget,
                crate::mesh3d::WarpedFaces::default(),
            )?)
        }
        MeshSpec::Generated3 {
            family,
            level,
            domain,
        } => family.generate_on(
            *level,
            domain.unwrap_or(crate::mesh3d::Cuboid::UNIT),
            budget,
        ),
        MeshSpec::Generated { .. } => Err(Error::InvalidData(format!(
            "the mesh {spec} is 2D: build it with case::build_mesh"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::build_mesh;
    use crate::budget::MemoryBudget;
    use crate::mesh::{Family, Rect};
    use crate::problem::file::{MeshSpec, parse};
    use std::path::Path;

    /// The mesh of a `[mesh]` section, as a problem file gives it.
    fn mesh_of(section: &str) -> crate::mesh::PolyMesh {
        let text = format!("[mesh]\n{section}\n");
        let pf = parse(&text, Path::new("tests/data/case.toml"), &[]).unwrap();
        build_mesh(pf.mesh.as_ref().unwrap(), MemoryBudget::DEFAULT).unwrap()
    }

    #[test]
    fn generated_meshes_are_the_family_at_its_level_on_its_domain() {
        let m = mesh_of("generate = \"cartesian\"\nlevel = 2");
        let g = Family::Cartesian
            .generate(2, MemoryBudget::DEFAULT)
            .unwrap();
        assert_eq!((m.n_cells(), m.vertices()), (g.n_cells(), g.vertices()));
        let m = mesh_of("generate = \"kershaw\"\nlevel = 1\ndomain = [-1, 3, 0, 0.5]");
        let g = Family::Kershaw
            .generate_on(1, Rect::new([-1.0, 3.0], [0.0, 0.5]), MemoryBudget::DEFAULT)
            .unwrap();
        assert_eq!((m.n_cells(), m.vertices()), (g.n_cells(), g.vertices()));
        let [x0, x1, y0, y1] = m.vertices().iter().fold(
            [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ],
            |[a, b, c, d], p| [a.min(p[0]), b.max(p[0]), c.min(p[1]), d.max(p[1])],
        );
        assert_eq!([x0, x1, y0, y1], [-1.0, 3.0, 0.0, 0.5]);
    }

    #[test]
    fn mesh_files_are_read_relative_to_the_problem_file() {
        let m = mesh_of("file = \"good/square_22.msh\"");
        let r = crate::mesh::io::read_mesh("tests/data/good/square_22.msh", MemoryBudget::DEFAULT)
            .unwrap();
        assert_eq!((m.n_cells(), m.vertices()), (r.n_cells(), r.vertices()));
        let spec = MeshSpec::File(Path::new("tests/data").join("missing.msh"));
        let e = build_mesh(&spec, MemoryBudget::DEFAULT)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.msh"), "{e}");
    }
}
