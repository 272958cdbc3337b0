//! Unit tests of the 3D readers and the VTU writer, in memory (the files of
//! `tests/data/mesh3d` through the public API are in `tests/mesh3d_io.rs`).

use super::cells::{Shape, shape_of};
use super::msh3::parse_msh3;
use super::vtu_read::parse_vtu3;
use super::{rf, vtu};
use crate::error::Error;
use crate::mesh::io::Tokens;
use crate::mesh3d::Polyhedra;
use std::path::Path;

const CUBE6_41: &str = include_str!("../../../tests/data/mesh3d/cube6_41.msh");
const CUBE5_22: &str = include_str!("../../../tests/data/mesh3d/cube5_22.msh");
const HEX_41: &str = include_str!("../../../tests/data/mesh3d/hex_41.msh");
const PRISM_22: &str = include_str!("../../../tests/data/mesh3d/prism_22.msh");
const PYRAMID_41: &str = include_str!("../../../tests/data/mesh3d/pyramid_41.msh");
const RF_NODE: &str = include_str!("../../../tests/data/mesh3d/two_cells.node");
const RF_ELE: &str = include_str!("../../../tests/data/mesh3d/two_cells.ele");

fn msh(text: &str) -> crate::Result<Polyhedra> {
    parse_msh3(Path::new("m.msh"), text.as_bytes())
}

fn rf_parse(node: &str, ele: &str) -> crate::Result<Polyhedra> {
    let (pn, pe) = (Path::new("r.node"), Path::new("r.ele"));
    let (vertices, base) = rf::parse_node(Tokens::new(pn, node.as_bytes()))?;
    let mut p = rf::parse_ele(pe, Tokens::new(pe, ele.as_bytes()), vertices.len(), base)?;
    p.vertices = vertices;
    Ok(p)
}

fn to_vtu(p: &Polyhedra) -> Vec<u8> {
    let mut out = Vec::new();
    vtu::write_to(&mut out, p, &[], &[]).unwrap();
    out
}

fn from_vtu(bytes: &[u8]) -> crate::Result<Polyhedra> {
    let path = Path::new("v.vtu");
    parse_vtu3(path, Tokens::new(path, bytes))
}

/// 6 · the volume of cell `k` by the divergence theorem on its faces fanned from their first
/// vertex, up to the sign of the orientation of each face: the faces as listed must be
/// consistently oriented for this to be the volume (true of the gmsh tables).
fn six_volume(p: &Polyhedra, k: usize) -> f64 {
    let mut v = 0.0;
    for s in p.cell_sides(k) {
        let l = p.side_vertices(s);
        let a = p.vertices[l[0] as usize];
        for w in l[1..].windows(2) {
            let (b, c) = (p.vertices[w[0] as usize], p.vertices[w[1] as usize]);
            v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
    }
    v
}

#[test]
fn gmsh_cells_have_their_faces_and_tags() {
    let p = msh(CUBE6_41).unwrap();
    assert_eq!(
        (p.vertices.len(), p.n_cells(), p.face_ptr.len()),
        (8, 6, 25)
    );
    assert_eq!(p.cell_tags, vec![1; 6]);
    assert_eq!(p.tagged_tags, vec![10, 10, 20, 20]);
    assert_eq!(p.tagged_ptr, vec![0, 3, 6, 9, 12]);
    // tet 1 2 3 7 (0-based 0 1 2 6): faces 0 2 1, 0 1 3, 0 3 2, 3 1 2 of gmsh
    assert_eq!(p.side_vertices(0), &[0, 2, 1]);
    assert_eq!(p.side_vertices(3), &[6, 1, 2]);
    // the gmsh face tables point outward of positive elements: volumes are positive
    let total: f64 = (0..6).map(|k| six_volume(&p, k)).sum();
    assert!((total - 6.0).abs() < 1e-14, "{total}");

    let p = msh(CUBE5_22).unwrap();
    // node 9 is used by a point element only: dropped
    assert_eq!((p.vertices.len(), p.n_cells()), (8, 5));
    assert_eq!(p.cell_tags, vec![1, 1, 1, 1, 2]);
    assert_eq!(p.tagged_tags, vec![10, 10]);
    assert!((0..5).all(|k| six_volume(&p, k) > 0.0));

    let hex = msh(HEX_41).unwrap();
    assert_eq!(
        (hex.n_cells(), hex.face_ptr.len(), hex.face_vertices.len()),
        (1, 7, 24)
    );
    assert!(hex.cell_tags.is_empty());
    assert_eq!(
        (hex.tagged_tags.clone(), hex.tagged_vertices.clone()),
        (vec![5], vec![0, 1, 2, 3])
    );
    assert!((six_volume(&hex, 0) - 12.0).abs() < 1e-14);
    let prism = msh(PRISM_22).unwrap();
    assert_eq!(
        (prism.face_ptr.len(), prism.tagged_tags.clone()),
        (6, vec![4, 7])
    );
    assert!((six_volume(&prism, 0) - 9.0).abs() < 1e-14);
    let pyr = msh(PYRAMID_41).unwrap();
    assert_eq!(pyr.face_ptr.len(), 6);
    assert!((six_volume(&pyr, 0) - 1.5).abs() < 1e-14);
}

#[test]
fn tets_and_hexahedra_are_recognised() {
    let p = msh(CUBE6_41).unwrap();
    assert_eq!(shape_of(&p, 0), Some(Shape::Tet([0, 1, 2, 6])));
    let hex = msh(HEX_41).unwrap();
    assert_eq!(
        shape_of(&hex, 0),
        Some(Shape::Hex([0, 1, 2, 3, 4, 5, 6, 7]))
    );
    // a mirrored hexahedron is written with its top and bottom swapped (positive for VTK)
    let mut flipped = hex.clone();
    flipped.vertices.iter_mut().for_each(|v| v[2] = -v[2]);
    assert_eq!(
        shape_of(&flipped, 0),
        Some(Shape::Hex([4, 5, 6, 7, 0, 1, 2, 3]))
    );
    // prisms, pyramids and the RF polyhedron are not
    assert_eq!(shape_of(&msh(PRISM_22).unwrap(), 0), None);
    assert_eq!(shape_of(&msh(PYRAMID_41).unwrap(), 0), None);
    let rf = rf_parse(RF_NODE, RF_ELE).unwrap();
    assert!(matches!(shape_of(&rf, 0), Some(Shape::Hex(_))));
    assert_eq!(shape_of(&rf, 1), None);
    // 4 triangles that do not close a tetrahedron
    let mut bad = Polyhedra {
        vertices: p.vertices.clone(),
        ..Polyhedra::default()
    };
    bad.push_cell([&[0, 1, 2][..], &[0, 1, 3], &[0, 3, 2], &[4, 1, 2]])
        .unwrap();
    assert_eq!(shape_of(&bad, 0), None);
}

#[test]
fn rf_pairs_are_read() {
    let p = rf_parse(RF_NODE, RF_ELE).unwrap();
    assert_eq!(
        (p.vertices.len(), p.n_cells(), p.face_ptr.len()),
        (12, 2, 14)
    );
    assert_eq!(p.side_vertices(7), &[1, 5, 2]);
    assert!(p.cell_tags.is_empty() && p.tagged_tags.is_empty());
    // a face may continue on the next line (as in HArDCore's Random-Hexahedra files)
    let split = RF_ELE.replace("  6  4    7  8  11  10", "  6  4\n    7  8  11  10 # top");
    assert_eq!(rf_parse(RF_NODE, &split).unwrap(), p);
    // ids from 1
    let node1 = RF_NODE.replace("\n11 2 1 1", "\n12 2 1 1");
    let node1: String = node1
        .lines()
        .map(|l| match l.split_once(' ') {
            Some((id, rest))
                if !l.starts_with('#') && l.split_whitespace().count() == 4 && id != "12" =>
            {
                format!(
                    "{} {rest}\n",
                    id.parse::<u32>()
                        .map_or(id.to_string(), |i| (i + 1).to_string())
                )
            }
            _ => format!("{l}\n"),
        })
        .collect();
    assert!(
        node1.contains("\n1 0 0 0\n") && node1.contains("\n12 2 1 1\n"),
        "{node1}"
    );
    let ele1: String = RF_ELE
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            if l.starts_with('#') || f.len() < 5 {
                return format!("{l}\n");
            }
            let v: Vec<String> = f[2..]
                .iter()
                .map(|v| (v.parse::<u32>().unwrap() + 1).to_string())
                .collect();
            format!("{} {} {}\n", f[0], f[1], v.join(" "))
        })
        .collect();
    assert_eq!(rf_parse(&node1, &ele1).unwrap(), p);
}

/// Edits of valid files give an error at the expected line, with the expected words.
#[test]
fn edited_files_are_rejected_with_their_line() {
    let cases: [(&str, &str, &str, &str); 9] = [
        (
            CUBE5_22,
            "9 4 2 2 1 2 4 5 7",
            "9 11 2 2 1 2 4 5 7 1 1 1 1 1 1",
            "m.msh:32: element 9 has type 11 (a high-order tetrahedron)",
        ),
        (
            CUBE5_22,
            "9 4 2 2 1 2 4 5 7",
            "9 4 2 2 1 2 4 5 17",
            "m.msh:32: element refers to node 17",
        ),
        (
            CUBE5_22,
            "1 15 2 0 1 1",
            "1 16 2 0 1 1",
            "m.msh:24: element 1 has type 16 (a high-order surface element)",
        ),
        (
            CUBE5_22,
            "3 1 1 0\n",
            "3 1 x 0\n",
            "m.msh:14: cannot read y of node 3",
        ),
        (
            CUBE5_22,
            "$Elements\n10\n",
            "$Elements\n11\n",
            "m.msh:34: cannot read the tag of element 11 from \"$EndElements\"",
        ),
        (
            CUBE6_41,
            "10 1 6 2 7\n",
            "10 1 6 2 7 3\n",
            "m.msh:50: expected \"$EndElements\", found \"3\"",
        ),
        (
            CUBE6_41,
            "3 1 0 8\n",
            "3 1 0 9\n",
            "m.msh:35: cannot read z of node 8 from \"$EndNodes\"",
        ),
        (
            HEX_41,
            "3 1 5 1",
            "3 1 12 1",
            "m.msh:34: element 2 has type 12 (a high-order hexahedron)",
        ),
        (
            PYRAMID_41,
            "3 1 7 1",
            "3 1 99 1",
            "m.msh:21: element 1 has type 99 (an element type this reader does not know)",
        ),
    ];
    for (text, from, to, expected) in cases {
        assert!(text.contains(from), "no {from:?}");
        let e = msh(&text.replacen(from, to, 1)).unwrap_err();
        assert!(matches!(e, Error::MeshIo { .. }), "{e}");
        assert!(
            e.to_string().starts_with(expected),
            "{e}\nexpected {expected}"
        );
    }
    let (head, _) = CUBE5_22.split_once("$Elements").unwrap();
    let e = msh(&format!(
        "{head}$Elements\n1\n1 2 2 10 1 1 2 4\n$EndElements\n"
    ))
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "m.msh:0: no tetrahedra, hexahedra, prisms or pyramids (types 4 to 7) in the file"
    );
    let rf_cases: [(&str, &str, &str, bool, &str); 6] = [
        (
            RF_ELE,
            "  6  4    7  8  11  10",
            "  6  4    7  8  11  12",
            false,
            "r.ele:18: vertex id 12 is out of range 0..12",
        ),
        (
            RF_ELE,
            "  6  4    7  8  11  10",
            "  6  4    7  8  11",
            false,
            "r.ele:19: unexpected end of file while reading a vertex id",
        ),
        (
            RF_ELE,
            "1  7\n",
            "1  8\n",
            false,
            "r.ele:19: unexpected end of file while reading the id of face 7 of cell 1",
        ),
        (
            RF_ELE,
            "0  6\n",
            "0  6 x\n",
            false,
            "r.ele:4: cannot read the id of face 0 of cell 0 from \"x\"",
        ),
        (
            RF_NODE,
            "4 1 1 0",
            "5 1 1 0",
            true,
            "r.node:7: vertex id 5 where 4 was expected",
        ),
        (
            RF_NODE,
            "4 1 1 0",
            "4 1 1 inf",
            true,
            "r.node:7: z is not finite",
        ),
    ];
    for (text, from, to, is_node, expected) in rf_cases {
        assert!(text.contains(from), "no {from:?}");
        let bad = text.replacen(from, to, 1);
        let e = if is_node {
            rf_parse(&bad, RF_ELE)
        } else {
            rf_parse(RF_NODE, &bad)
        }
        .unwrap_err();
        assert!(
            e.to_string().starts_with(expected),
            "{e}\nexpected {expected}"
        );
    }
}

/// `p` with each face loop rotated and turned to its smallest form and each cell's faces
/// sorted: equal for two descriptions of the same cells with the same faces.
fn canonical(p: &Polyhedra) -> Polyhedra {
    let mut q = Polyhedra {
        vertices: p.vertices.clone(),
        cell_tags: p.cell_tags.clone(),
        ..Polyhedra::default()
    };
    for k in 0..p.n_cells() {
        let mut faces: Vec<Vec<u32>> = p
            .cell_sides(k)
            .map(|s| {
                let l = p.side_vertices(s);
                let n = l.len();
                (0..n)
                    .flat_map(|r| {
                        let fwd: Vec<u32> = (0..n).map(|i| l[(r + i) % n]).collect();
                        let bwd: Vec<u32> = (0..n).map(|i| l[(r + n - i) % n]).collect();
                        [fwd, bwd]
                    })
                    .min()
                    .unwrap()
            })
            .collect();
        faces.sort();
        q.push_cell(faces.iter().map(|f| &f[..])).unwrap();
    }
    q
}

/// Polyhedra → VTU → Polyhedra gives back the same description when the tetrahedra and
/// hexahedra list their faces as the readers do (gmsh's tables), and the same cells, faces
/// and tags otherwise; a second round trip changes nothing.
#[test]
fn vtu_round_trips() {
    for p in [
        msh(CUBE6_41).unwrap(),
        msh(CUBE5_22).unwrap(),
        msh(HEX_41).unwrap(),
        msh(PRISM_22).unwrap(),
        msh(PYRAMID_41).unwrap(),
    ] {
        let bytes = to_vtu(&p);
        assert_eq!(
            from_vtu(&bytes).unwrap(),
            p,
            "{}",
            String::from_utf8_lossy(&bytes)
        );
    }
    // a mix of a hexahedron and a polyhedron: every cell a VTK_POLYHEDRON, faces as given
    let p = rf_parse(RF_NODE, RF_ELE).unwrap();
    let text = String::from_utf8(to_vtu(&p)).unwrap();
    assert_eq!(from_vtu(text.as_bytes()).unwrap(), p);
    assert_eq!(text.matches("          42\n").count(), 2, "{text}");
    // the hexahedron alone, its faces not in gmsh's order: a VTK_HEXAHEDRON, the same faces
    let mut hex = Polyhedra {
        vertices: p.vertices.clone(),
        ..Polyhedra::default()
    };
    hex.push_cell(p.cell_sides(0).map(|s| p.side_vertices(s)))
        .unwrap();
    let back = from_vtu(&to_vtu(&hex)).unwrap();
    assert_ne!(back, hex);
    assert_eq!(canonical(&back), canonical(&hex));
    assert_eq!(from_vtu(&to_vtu(&back)).unwrap(), back);
    let bad = text.replacen("          42\n", "          13\n", 1);
    let e = from_vtu(bad.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("cell 0 has the VTK type 13"), "{e}");
    let bad = text.replacen("format=\"ascii\"", "format=\"binary\"", 1);
    let e = from_vtu(bad.as_bytes()).unwrap_err().to_string();
    assert!(e.starts_with("v.vtu:") && e.contains("only ASCII"), "{e}");
}

/// Every prefix and many random corruptions of the test files: errors, never panics.
#[test]
fn fuzz_truncations_and_corruptions() {
    let vtu_text = to_vtu(&rf_parse(RF_NODE, RF_ELE).unwrap());
    let cases: [(&str, &[u8]); 5] = [
        ("m", CUBE6_41.as_bytes()),
        ("m", CUBE5_22.as_bytes()),
        ("n", RF_NODE.as_bytes()),
        ("e", RF_ELE.as_bytes()),
        ("v", &vtu_text),
    ];
    let parse = |kind: &str, b: &[u8]| match kind {
        "m" => parse_msh3(Path::new("m.msh"), b).map(|_| ()),
        "n" => rf_parse(&String::from_utf8_lossy(b), RF_ELE).map(|_| ()),
        "e" => rf_parse(RF_NODE, &String::from_utf8_lossy(b)).map(|_| ()),
        _ => from_vtu(b).map(|_| ()),
    };
    let mut rand = crate::mesh::xorshift(0x9e37_79b9_7f4a_7c15);
    const NOISE: &[u8] = b"0123456789-.eE+ \n$\"x\xff";
    for (kind, bytes) in cases {
        assert!(parse(kind, bytes).is_ok(), "{kind}");
        let run = |b: &[u8]| {
            let r = std::panic::catch_unwind(|| parse(kind, b));
            assert!(r.is_ok(), "panic on {:?}", String::from_utf8_lossy(b));
        };
        for len in 0..bytes.len() {
            run(&bytes[..len]);
        }
        for _ in 0..2000 {
            let mut b = bytes.to_vec();
            for _ in 0..1 + rand() % 3 {
                let i = (rand() % b.len() as u64) as usize;
                b[i] = NOISE[(rand() % NOISE.len() as u64) as usize];
            }
            run(&b);
        }
    }
}
