//! One small invalid [`Polyhedra`] per error of [`PolyMesh3::from_polyhedra`], each giving
//! exactly that error variant.

use super::test_meshes::{cubes, dented_pair, hex_faces, tet_faces};
use super::{MAX_CELL_FACES, MAX_FACE_VERTICES, Point3, PolyMesh3, Polyhedra};
use crate::budget::MemoryBudget;
use crate::error::MeshError;

fn build(p: Polyhedra) -> Result<PolyMesh3, MeshError> {
    PolyMesh3::from_polyhedra(p, MemoryBudget::DEFAULT)
}

/// A mesh of the given vertices and cells (each a list of face loops).
fn mesh(vertices: Vec<Point3>, cells: &[Vec<Vec<u32>>]) -> Polyhedra {
    let mut p = Polyhedra {
        vertices,
        ..Polyhedra::default()
    };
    for c in cells {
        p.push_cell(c.iter().map(|f| &f[..])).unwrap();
    }
    p
}

/// The corners of the box [x0, x1] × [y0, y1] × [z0, z1], in the order of `hex_faces`.
fn box_corners(r: [[f64; 2]; 3]) -> Vec<Point3> {
    (0..8)
        .map(|c: usize| [r[0][c & 1], r[1][c >> 1 & 1], r[2][c >> 2 & 1]])
        .collect()
}

/// The unit cube as one hexahedron, vertices 0..8.
fn unit_cube() -> Polyhedra {
    mesh(
        box_corners([[0.0, 1.0]; 3]),
        &[hex_faces(std::array::from_fn(|i| i as u32))],
    )
}

/// Boxes with their own vertices (no sharing unless coordinates are repeated on purpose).
fn boxes(rs: &[[[f64; 2]; 3]]) -> Polyhedra {
    let mut v = Vec::new();
    let mut cells = Vec::new();
    for (b, &r) in rs.iter().enumerate() {
        v.extend(box_corners(r));
        cells.push(hex_faces(std::array::from_fn(|i| (8 * b + i) as u32)));
    }
    mesh(v, &cells)
}

/// Merges vertices with equal coordinates (first occurrence kept), renumbering the loops.
fn merge_equal_vertices(mut p: Polyhedra) -> Polyhedra {
    let mut keep: Vec<Point3> = Vec::new();
    let map: Vec<u32> = p
        .vertices
        .iter()
        .map(|x| match keep.iter().position(|y| y == x) {
            Some(i) => i as u32,
            None => {
                keep.push(*x);
                (keep.len() - 1) as u32
            }
        })
        .collect();
    p.face_vertices
        .iter_mut()
        .for_each(|v| *v = map[*v as usize]);
    p.vertices = keep;
    p
}

#[test]
fn malformed_offsets_and_empty_meshes() {
    let mut p = unit_cube();
    p.cell_ptr = vec![0, 5];
    assert!(matches!(build(p), Err(MeshError::MalformedPolyhedra(_))));
    let mut p = unit_cube();
    p.tagged_tags = vec![1];
    assert!(matches!(build(p), Err(MeshError::MalformedPolyhedra(_))));
    let p = Polyhedra {
        cell_ptr: vec![0],
        face_ptr: vec![0],
        ..Polyhedra::default()
    };
    assert_eq!(build(p).unwrap_err(), MeshError::Empty);
}

#[test]
fn size_limits_are_checked_before_allocating() {
    let mut p = unit_cube();
    let faces: Vec<Vec<u32>> = (0..=MAX_CELL_FACES).map(|_| vec![0, 1, 2]).collect();
    p.push_cell(faces.iter().map(|f| &f[..])).unwrap();
    assert!(matches!(
        build(p),
        Err(MeshError::PolyhedronTooLarge { cell: 1, .. })
    ));
    let mut p = unit_cube();
    let big: Vec<u32> = (0..=MAX_FACE_VERTICES as u32).collect();
    p.push_cell([&big[..], &[0, 1, 2], &[0, 1, 3], &[1, 2, 3]])
        .unwrap();
    let e = build(p).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::FaceTooLarge {
                cell: 1,
                local_face: 0,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn bad_cells_and_faces_are_named() {
    let mut p = unit_cube();
    p.push_cell([&[0, 1, 2][..], &[0, 1, 3], &[1, 2, 3]])
        .unwrap();
    assert!(matches!(build(p), Err(MeshError::BadCell { cell: 1, .. })));
    let mut p = unit_cube();
    p.face_ptr[1] = 2; // face 0 of the cube has 2 vertices, face 1 six
    assert!(matches!(
        build(p),
        Err(MeshError::BadFace {
            cell: 0,
            local_face: 0,
            ..
        })
    ));
    let mut p = unit_cube();
    p.face_vertices[2] = p.face_vertices[0];
    let e = build(p).unwrap_err();
    assert!(
        matches!(&e, MeshError::BadFace { msg, .. } if msg.contains("twice")),
        "{e:?}"
    );
    let mut p = unit_cube();
    p.face_vertices[5] = 8;
    assert!(matches!(
        build(p),
        Err(MeshError::VertexOutOfRange {
            cell: 0,
            vertex: 8,
            ..
        })
    ));
    let mut p = unit_cube();
    p.cell_tags = vec![1, 2];
    assert_eq!(
        build(p).unwrap_err(),
        MeshError::CellTagCount { tags: 2, cells: 1 }
    );
}

#[test]
fn bad_vertices_are_named() {
    let mut p = unit_cube();
    p.vertices[3][1] = f64::NAN;
    assert_eq!(
        build(p).unwrap_err(),
        MeshError::NonFiniteVertex { vertex: 3 }
    );
    let mut p = unit_cube();
    p.vertices.push([1.0, 1.0, 0.0]);
    assert_eq!(
        build(p).unwrap_err(),
        MeshError::DuplicateVertex3 {
            a: 3,
            b: 8,
            point: [1.0, 1.0, 0.0]
        }
    );
    let mut p = unit_cube();
    p.vertices.push([2.0, 1.0, 0.0]);
    assert_eq!(build(p).unwrap_err(), MeshError::UnusedVertex { vertex: 8 });
}

fn tet_points() -> Vec<Point3> {
    vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.2, 0.2, 1.0],
        [0.3, 0.1, -1.0],
    ]
}

#[test]
fn faces_of_more_than_two_cells_or_twice_of_one() {
    let cells: Vec<_> = [3, 4, 5].iter().map(|&a| tet_faces([0, 1, 2, a])).collect();
    let e = build(mesh(tet_points(), &cells)).unwrap_err();
    assert_eq!(
        e,
        MeshError::OvercrowdedFace {
            vertices: vec![0, 1, 2],
            cells: [0, 1, 2]
        }
    );
    let mut faces = tet_faces([0, 1, 2, 3]);
    faces.push(vec![2, 1, 0]);
    let e = build(mesh(tet_points()[..4].to_vec(), &[faces])).unwrap_err();
    assert!(matches!(e, MeshError::BadCell { cell: 0, .. }), "{e:?}");
}

#[test]
fn open_and_disconnected_cells() {
    let mut faces = hex_faces(std::array::from_fn(|i| i as u32));
    faces.pop();
    let e = build(mesh(box_corners([[0.0, 1.0]; 3]), &[faces])).unwrap_err();
    assert!(
        matches!(&e, MeshError::OpenCell { cell: 0, msg, .. } if msg.contains("1 of its")),
        "{e:?}"
    );
    let mut v = tet_points()[..4].to_vec();
    v.extend(tet_points()[..4].iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let mut faces = tet_faces([0, 1, 2, 3]);
    faces.extend(tet_faces([4, 5, 6, 7]));
    let e = build(mesh(v, &[faces])).unwrap_err();
    assert!(
        matches!(&e, MeshError::BadCell { cell: 0, msg } if msg.contains("closed surface")),
        "{e:?}"
    );
}

#[test]
fn flat_cells_have_no_volume() {
    let v = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let e = build(mesh(v, &[tet_faces([0, 1, 2, 3])])).unwrap_err();
    assert!(
        matches!(e, MeshError::DegenerateVolume { cell: 0, .. }),
        "{e:?}"
    );
}

#[test]
fn two_cells_on_the_same_side_of_their_face() {
    // both apexes above the triangle (0, 1, 2)
    let cells: Vec<_> = [3, 4].iter().map(|&a| tet_faces([0, 1, 2, a])).collect();
    let e = build(mesh(tet_points()[..5].to_vec(), &cells)).unwrap_err();
    assert!(
        matches!(e, MeshError::InconsistentFace { cells: [0, 1], .. }),
        "{e:?}"
    );
}

#[test]
fn warped_faces_beyond_the_tolerance() {
    let mut p = unit_cube();
    p.vertices[7][2] = 2.5;
    let e = build(p).unwrap_err();
    assert!(
        matches!(&e, MeshError::WarpedFace { cell: 0, warp, .. } if *warp > 0.1),
        "{e:?}"
    );
}

#[test]
fn cells_not_star_shaped_with_respect_to_their_centroid() {
    // the dent reaches below the centroid of the lower cell
    let e = build(dented_pair(0.05, 3)).unwrap_err();
    assert!(
        matches!(e, MeshError::NotStarShaped3 { cell: 0, .. }),
        "{e:?}"
    );
}

#[test]
fn cells_meeting_along_an_edge_only_or_with_hanging_nodes() {
    let p = boxes(&[[[0.0, 1.0]; 3], [[1.0, 2.0], [1.0, 2.0], [0.0, 1.0]]]);
    let e = build(merge_equal_vertices(p)).unwrap_err();
    assert!(
        matches!(&e, MeshError::NonConformingEdge { msg, .. } if msg.contains("4 boundary")),
        "{e:?}"
    );
    // one cube below two half-cubes: the nodes (½, 0, 1) and (½, 1, 1) hang on its top face,
    // whose edges are used by four boundary faces (two of the cube, two of a half-cube)
    let p = boxes(&[
        [[0.0, 1.0]; 3],
        [[0.0, 0.5], [0.0, 1.0], [1.0, 2.0]],
        [[0.5, 1.0], [0.0, 1.0], [1.0, 2.0]],
    ]);
    let e = build(merge_equal_vertices(p)).unwrap_err();
    assert!(matches!(e, MeshError::NonConformingEdge { .. }), "{e:?}");
}

#[test]
fn cells_touching_at_a_vertex_only() {
    let p = boxes(&[[[0.0, 1.0]; 3], [[1.0, 2.0]; 3]]);
    let e = build(merge_equal_vertices(p)).unwrap_err();
    assert_eq!(e, MeshError::NonConformingVertex { vertex: 7, fans: 2 });
}

#[test]
fn a_cell_inside_another_overlaps_it() {
    let p = boxes(&[[[0.0, 1.0]; 3], [[0.25, 0.5], [0.25, 0.5], [0.25, 0.5]]]);
    let e = build(p).unwrap_err();
    assert!(
        matches!(e, MeshError::OverlappingPolyhedra { vertex: 8, cell: 0 }),
        "{e:?}"
    );
}

#[test]
fn an_edge_through_a_face_overlaps_without_a_vertex_inside() {
    // a flat tent (cell 0) pierced by a needle (cell 1) whose long edges cross its base and
    // sides: no vertex of either lies in the other, so check 12a passes and 12b names the
    // first crossing edge
    let v = vec![
        [-3.0, -3.0, 0.0],
        [3.0, -3.0, 0.0],
        [0.0, 3.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.9, -0.1, -1.0],
        [1.1, -0.1, -1.0],
        [1.0, 0.1, -1.0],
        [1.0, 0.0, 5.0],
    ];
    let e = build(mesh(v, &[tet_faces([0, 1, 2, 3]), tet_faces([4, 5, 6, 7])])).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::EdgeThroughFace {
                a: 4,
                b: 7,
                edge_cell: 1,
                face_cell: 0,
                ..
            }
        ),
        "{e:?}"
    );
    // two bars crossing: the edges of the bar along y pass through the quadrilateral sides
    // of the bar along x
    let p = boxes(&[
        [[0.0, 4.0], [0.0, 1.0], [0.0, 1.0]],
        [[1.5, 2.5], [-1.0, 2.0], [0.25, 0.75]],
    ]);
    let e = build(p).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::EdgeThroughFace {
                a: 8,
                b: 10,
                edge_cell: 1,
                face_cell: 0,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .contains("the edge (8, 10) of cell 1 crosses face"),
        "{e}"
    );
}

#[test]
fn bars_side_by_side_or_touching_do_not_cross() {
    // the same bars apart, and meeting face to face with a shared face: valid
    let apart = boxes(&[
        [[0.0, 4.0], [0.0, 1.0], [0.0, 1.0]],
        [[1.5, 2.5], [1.5, 4.0], [0.25, 0.75]],
    ]);
    assert!(build(apart).is_ok());
    let stacked = boxes(&[[[0.0, 1.0]; 3], [[0.0, 1.0], [0.0, 1.0], [1.0, 2.0]]]);
    assert!(build(merge_equal_vertices(stacked)).is_ok());
}

#[test]
fn tagged_faces_must_be_boundary_faces() {
    let mut p = cubes(2, 29);
    // the square x = ½ between y, z ∈ [0, ½]: nodes 1, 4, 13, 10 of the 3³ grid
    p.tagged_ptr = vec![0, 4];
    p.tagged_vertices = vec![1, 4, 13, 10];
    p.tagged_tags = vec![3];
    let e = build(p).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::BadTaggedFace {
                index: 0,
                tag: 3,
                ..
            }
        ),
        "{e:?}"
    );
}
