//! Tests of the boundary-surface VTU writer: the file is parsed back (its counts, cell types,
//! connectivity and data arrays) and compared with the mesh.

use super::{write_boundary_vtu, write_faces_vtu};
use crate::budget::MemoryBudget;
use crate::mesh3d::PolyMesh3;
use crate::mesh3d::generate::Family3;

/// The values of the `DataArray` named `name` (the lines after its opening tag, up to its
/// closing tag), as floats.
fn array(text: &str, name: &str) -> Vec<f64> {
    let start = text
        .find(&format!("Name=\"{name}\""))
        .unwrap_or_else(|| panic!("no array {name}"));
    let body = &text[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    body.split_whitespace()
        .map(|t| t.parse::<f64>().unwrap())
        .collect()
}

/// The coordinates of the `<Points>` block.
fn points(text: &str) -> Vec<[f64; 3]> {
    let body = &text[text.find("<Points>").unwrap()..text.find("</Points>").unwrap()];
    let body = &body[body.find("ascii\">").unwrap() + 7..body.find("</DataArray>").unwrap()];
    let v: Vec<f64> = body
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

fn attribute(text: &str, name: &str) -> usize {
    let s = &text[text.find(&format!("{name}=\"")).unwrap() + name.len() + 2..];
    s[..s.find('"').unwrap()].parse().unwrap()
}

fn tagged_cubes() -> PolyMesh3 {
    let m = Family3::Cubes.generate(1, MemoryBudget::DEFAULT).unwrap();
    // tag the face x = 0 with 5, the others with 0
    m.with_boundary_tags(|x| if x[0] == 0.0 { 5 } else { 0 })
}

#[test]
fn every_boundary_face_is_one_polygon_with_its_data() {
    let mesh = tagged_cubes();
    let dir = std::env::temp_dir().join(format!("gradvi-vtu-boundary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("b.vtu");
    let per_face: Vec<f64> = (0..mesh.n_faces()).map(|f| 0.25 * f as f64 + 0.1).collect();
    let per_vertex: Vec<f64> = mesh.vertices().iter().map(|x| x[0] + 2.0 * x[2]).collect();
    write_boundary_vtu(
        &path,
        &mesh,
        &[("x_plus_2z", &per_vertex)],
        &[("value", &per_face)],
    )
    .unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let bf = mesh.boundary_faces();
    // 4 × 4 squares on each of the 6 sides of the cube of 4 × 4 × 4 cubes
    assert_eq!(bf.len(), 6 * 16);
    assert_eq!(attribute(&text, "NumberOfCells"), bf.len());
    // the 5³ vertices but the 3³ interior ones
    assert_eq!(attribute(&text, "NumberOfPoints"), 125 - 27);
    let types = array(&text, "types");
    assert_eq!(types.len(), bf.len());
    assert!(types.iter().all(|&t| t == 7.0));
    let faces = array(&text, "face");
    let want: Vec<f64> = bf.iter().map(|&f| f as f64).collect();
    assert_eq!(faces, want);
    let tags = array(&text, "boundary_tag");
    for (i, &f) in bf.iter().enumerate() {
        assert_eq!(tags[i], f64::from(mesh.face_tag(f as usize)));
        assert_eq!(array(&text, "value")[i], per_face[f as usize]);
    }
    assert_eq!(tags.iter().filter(|&&t| t == 5.0).count(), 16);
    // each polygon is the face's loop, through the points written
    let pts = points(&text);
    let conn = array(&text, "connectivity");
    let offsets = array(&text, "offsets");
    let pd = array(&text, "x_plus_2z");
    assert_eq!(pd.len(), pts.len());
    for (p, v) in pts.iter().zip(&pd) {
        assert_eq!(*v, p[0] + 2.0 * p[2]);
    }
    let mut start = 0;
    for (i, &f) in bf.iter().enumerate() {
        let end = offsets[i] as usize;
        let loop_: Vec<[f64; 3]> = conn[start..end].iter().map(|&j| pts[j as usize]).collect();
        let want: Vec<[f64; 3]> = mesh
            .face_vertices(f as usize)
            .iter()
            .map(|&v| mesh.vertices()[v as usize])
            .collect();
        assert_eq!(loop_, want, "face {f}");
        start = end;
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn wrong_lengths_and_reserved_names_are_refused() {
    let mesh = tagged_cubes();
    let path =
        std::env::temp_dir().join(format!("gradvi-vtu-boundary-x-{}.vtu", std::process::id()));
    let short = vec![0.0; mesh.n_faces() - 1];
    let e = write_boundary_vtu(&path, &mesh, &[], &[("v", &short)]).unwrap_err();
    assert!(e.to_string().contains("faces"), "{e}");
    let full = vec![0.0; mesh.n_faces()];
    let e = write_boundary_vtu(&path, &mesh, &[], &[("boundary_tag", &full)]).unwrap_err();
    assert!(e.to_string().contains("reserved"), "{e}");
    let e = write_boundary_vtu(&path, &mesh, &[("p", &full)], &[]).unwrap_err();
    assert!(e.to_string().contains("vertices"), "{e}");
    assert!(!path.exists());
}

#[test]
fn every_face_is_one_polygon_and_the_boundary_list_gives_the_boundary_file() {
    let mesh = tagged_cubes();
    let dir = std::env::temp_dir().join(format!("gradvi-vtu-faces-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let per_face: Vec<f64> = (0..mesh.n_faces()).map(|f| 0.5 * f as f64 - 3.0).collect();
    let per_vertex: Vec<f64> = mesh.vertices().iter().map(|x| x[1] - x[2]).collect();
    let (pd, fd) = (
        [("p", per_vertex.as_slice())],
        [("value", per_face.as_slice())],
    );
    let all: Vec<u32> = (0..mesh.n_faces() as u32).collect();
    let path = dir.join("all.vtu");
    write_faces_vtu(&path, &mesh, &all, &pd, &fd).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    // 3 directions × 5 planes × 4 × 4 squares
    assert_eq!(mesh.n_faces(), 240);
    assert_eq!(attribute(&text, "NumberOfCells"), 240);
    assert_eq!(attribute(&text, "NumberOfPoints"), 125);
    assert_eq!(array(&text, "types").len(), 240);
    assert_eq!(
        array(&text, "face"),
        all.iter().map(|&f| f as f64).collect::<Vec<_>>()
    );
    assert_eq!(array(&text, "value"), per_face);
    let tags = array(&text, "boundary_tag");
    assert_eq!(tags.len(), mesh.n_faces());
    for (f, &t) in tags.iter().enumerate() {
        assert_eq!(t, f64::from(mesh.face_tag(f)), "face {f}");
        if !mesh.is_boundary_face(f) {
            assert_eq!(t, 0.0, "interior face {f}");
        }
    }
    assert_eq!(tags.iter().filter(|&&t| t == 5.0).count(), 16);
    let offsets = array(&text, "offsets");
    assert_eq!(*offsets.last().unwrap(), 4.0 * 240.0);
    // the boundary file is the faces file of the boundary faces, byte for byte
    let (b1, b2) = (dir.join("b1.vtu"), dir.join("b2.vtu"));
    write_boundary_vtu(&b1, &mesh, &pd, &fd).unwrap();
    write_faces_vtu(&b2, &mesh, mesh.boundary_faces(), &pd, &fd).unwrap();
    assert_eq!(std::fs::read(&b1).unwrap(), std::fs::read(&b2).unwrap());
    // a face out of range is refused, naming it
    let e = write_faces_vtu(dir.join("x.vtu"), &mesh, &[3, 240], &pd, &fd).unwrap_err();
    assert!(e.to_string().contains("face 240 (entry 1"), "{e}");
    assert!(!dir.join("x.vtu").exists());
    std::fs::remove_dir_all(&dir).ok();
}
