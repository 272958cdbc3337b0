use super::{AnyMesh, case_mesh, read_any};
use crate::budget::MemoryBudget;
use crate::mesh3d::WarpedFaces;
use crate::mesh3d::generate::Family3;
use crate::problem::file::{ProblemFile, parse};
use std::path::Path;

const B: MemoryBudget = MemoryBudget::DEFAULT;

/// A problem file: `data` and `[mesh]` `mesh`, read as if from tests/data/case.toml.
fn problem(data: &str, mesh: &str) -> ProblemFile {
    let text = format!("{data}\n[mesh]\n{mesh}\n");
    parse(&text, Path::new("tests/data/case.toml"), &[]).unwrap()
}

fn dims(m: &AnyMesh) -> (usize, usize) {
    match m {
        AnyMesh::Two(m) => (2, m.n_cells()),
        AnyMesh::Three(m) => (3, m.n_cells()),
    }
}

#[test]
fn files_are_read_in_the_dimension_of_their_format() {
    let fan = WarpedFaces::Fan;
    let two = read_any(Path::new("tests/data/good/square_22.msh"), fan, B).unwrap();
    assert_eq!(dims(&two).0, 2);
    let three = read_any(Path::new("tests/data/mesh3d/hex_41.msh"), fan, B).unwrap();
    assert_eq!(dims(&three).0, 3);
    let rf = read_any(Path::new("tests/data/mesh3d/two_cells"), fan, B).unwrap();
    assert_eq!(dims(&rf), (3, 2));
    let typ2 = read_any(Path::new("tests/data/good/hanging.typ2"), fan, B).unwrap();
    assert_eq!(dims(&typ2).0, 2);
    // a missing 3D file: the 3D reader's error, with the path
    let e = read_any(Path::new("tests/data/missing.vtu"), fan, B).unwrap_err();
    assert!(e.to_string().contains("missing.vtu"), "{e}");
}

#[test]
fn a_problem_files_mesh_is_3d_only_for_a_3d_problem() {
    // a file of 3D elements with a problem that compiles in 3D (no z: in both dimensions)
    let pf = problem("[source]\nf = 1", "file = \"mesh3d/hex_41.msh\"");
    let m = case_mesh(pf.mesh.as_ref().unwrap(), &pf, WarpedFaces::Fan, B).unwrap();
    assert_eq!(dims(&m).0, 3);
    // a problem using a 2×2 tensor does not compile in 3D: its mesh file is read as 2D (the
    // 2D reader reads or refuses a file of 3D elements; it never gives a 3D mesh)
    let pf = problem(
        "[source]\nf = 1\n[diffusion]\nA = [[1, 0], [0, 1]]",
        "file = \"mesh3d/hex_41.msh\"",
    );
    assert!(!pf.compiles_for(3));
    let m = case_mesh(pf.mesh.as_ref().unwrap(), &pf, WarpedFaces::Split, B);
    assert!(!matches!(m, Ok(AnyMesh::Three(_))));
    let pf = problem("[source]\nf = 1", "file = \"good/square_22.msh\"");
    let m = case_mesh(pf.mesh.as_ref().unwrap(), &pf, WarpedFaces::Fan, B).unwrap();
    assert_eq!(dims(&m).0, 2);
    let pf = problem("[source]\nf = 1", "generate = \"cubes\"\nlevel = 1");
    let m = case_mesh(pf.mesh.as_ref().unwrap(), &pf, WarpedFaces::Fan, B).unwrap();
    assert_eq!(dims(&m), (3, 64));
}

#[test]
fn warped_faces_are_split_when_asked_for_generated_and_read_meshes() {
    let faces = |m: AnyMesh| match m {
        AnyMesh::Three(m) => m.n_faces(),
        AnyMesh::Two(_) => panic!("a 3D mesh was expected"),
    };
    let pf = problem("[source]\nf = 1", "generate = \"warped\"\nlevel = 1");
    let spec = pf.mesh.as_ref().unwrap();
    let fan = faces(case_mesh(spec, &pf, WarpedFaces::Fan, B).unwrap());
    let split = faces(case_mesh(spec, &pf, WarpedFaces::Split, B).unwrap());
    assert!(split > fan, "{split} faces split, {fan} whole");
    // the same mesh from a file
    let dir = std::env::temp_dir().join(format!("gradvi-any-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("warped.vtu");
    let m = Family3::Warped.generate(1, B).unwrap();
    crate::mesh3d::io::write_vtu3(&path, &m.to_polyhedra(), &[], &[]).unwrap();
    assert_eq!(faces(read_any(&path, WarpedFaces::Fan, B).unwrap()), fan);
    assert_eq!(
        faces(read_any(&path, WarpedFaces::Split, B).unwrap()),
        split
    );
    std::fs::remove_dir_all(&dir).ok();
}
