//! The faces of the standard cell shapes, in gmsh's node numbering (which VTK shares for
//! tetrahedra and hexahedra), and the recognition of those shapes from a cell's faces.
//!
//! Node numbering (gmsh's reference elements, first order):
//! * tetrahedron 0, 1, 2, 3;
//! * hexahedron: 0, 1, 2, 3 around the bottom face, 4, 5, 6, 7 above them;
//! * prism: triangle 0, 1, 2 at the bottom, 3, 4, 5 above them;
//! * pyramid: base 0, 1, 2, 3, apex 4.
//!
//! Faces are listed as gmsh lists them (`MTetrahedron`, `MHexahedron`, `MPrism`, `MPyramid`),
//! each loop pointing out of a positively oriented element.

use crate::mesh3d::{Point3, Polyhedra};

/// Faces of a tetrahedron.
pub(crate) const TET_FACES: [&[usize]; 4] = [&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[3, 1, 2]];

/// Faces of a hexahedron.
pub(crate) const HEX_FACES: [&[usize]; 6] = [
    &[0, 3, 2, 1],
    &[0, 1, 5, 4],
    &[0, 4, 7, 3],
    &[1, 2, 6, 5],
    &[2, 3, 7, 6],
    &[4, 5, 6, 7],
];

/// Faces of a prism.
pub(crate) const PRISM_FACES: [&[usize]; 5] = [
    &[0, 2, 1],
    &[3, 4, 5],
    &[0, 1, 4, 3],
    &[0, 3, 5, 2],
    &[1, 2, 5, 4],
];

/// Faces of a pyramid.
pub(crate) const PYRAMID_FACES: [&[usize]; 5] = [
    &[0, 1, 4],
    &[3, 0, 4],
    &[1, 2, 4],
    &[2, 3, 4],
    &[0, 3, 2, 1],
];

/// Appends to `p` the cell with vertices `nodes` (in the numbering of `faces`); `out` is a
/// scratch buffer for the vertex loops.
pub(crate) fn push_shape(
    p: &mut Polyhedra,
    faces: &[&[usize]],
    nodes: &[u32],
    out: &mut Vec<u32>,
) -> Result<(), crate::error::MeshError> {
    out.clear();
    for f in faces {
        out.extend(f.iter().map(|&i| nodes[i]));
    }
    let mut start = 0;
    let loops = faces.iter().map(|f| {
        let s = &out[start..start + f.len()];
        start += f.len();
        s
    });
    let loops: Vec<&[u32]> = loops.collect();
    p.push_cell(loops.iter().copied())
}

/// The VTK cell a polyhedron can be written as.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Shape {
    /// `VTK_TETRA`, with its 4 vertices.
    Tet([u32; 4]),
    /// `VTK_HEXAHEDRON`, with its 8 vertices.
    Hex([u32; 8]),
}

/// (b − a) × (c − a) · (d − a): six times the signed volume of the tetrahedron a, b, c, d.
fn triple(p: &[Point3], [a, b, c, d]: [u32; 4]) -> f64 {
    let v = |i: u32| p.get(i as usize).copied().unwrap_or([f64::NAN; 3]);
    let (a, b, c, d) = (v(a), v(b), v(c), v(d));
    let u: [f64; 3] = std::array::from_fn(|i| b[i] - a[i]);
    let w: [f64; 3] = std::array::from_fn(|i| c[i] - a[i]);
    let z: [f64; 3] = std::array::from_fn(|i| d[i] - a[i]);
    (u[1] * w[2] - u[2] * w[1]) * z[0]
        + (u[2] * w[0] - u[0] * w[2]) * z[1]
        + (u[0] * w[1] - u[1] * w[0]) * z[2]
}

/// Whether the faces `sides` of `p` are, as vertex sets and in any order, the faces `table`
/// of the element with vertices `nodes` (the faces of `table` are distinct sets, so each is
/// found among as many sides exactly when the two lists agree).
fn matches(
    p: &Polyhedra,
    sides: std::ops::Range<usize>,
    table: &[&[usize]],
    nodes: &[u32],
) -> bool {
    sides.len() == table.len()
        && table.iter().all(|f| {
            sides.clone().any(|s| {
                let l = p.side_vertices(s);
                l.len() == f.len() && f.iter().all(|&i| l.contains(&nodes[i]))
            })
        })
}

/// Recognises cell `k` of `p` as a tetrahedron (4 triangles on 4 vertices) or a hexahedron
/// (6 quadrangles on 8 vertices, connected as a hexahedron), with its vertices in VTK's order
/// (which is gmsh's): the first face gives vertices 0, 2, 1 (tetrahedron) or 0, 3, 2, 1
/// (hexahedron), and the vertices are swapped if needed so that the cell is positively
/// oriented as VTK requires; `None` for any other cell. Readers list the faces of these cells
/// as [`TET_FACES`] and [`HEX_FACES`] do, so that a positively oriented cell read from a file
/// and written again gives back the same faces.
pub(crate) fn shape_of(p: &Polyhedra, k: usize) -> Option<Shape> {
    let sides = p.cell_sides(k);
    let first = p.side_vertices(sides.start);
    match (sides.len(), first.len()) {
        (4, 3) => {
            let rest = p.side_vertices(sides.start + 1);
            let apex = *rest.iter().find(|v| !first.contains(v))?;
            let mut n = [first[0], first[2], first[1], apex];
            if !matches(p, sides, &TET_FACES, &n) {
                return None;
            }
            if triple(&p.vertices, n) < 0.0 {
                n.swap(1, 2);
            }
            Some(Shape::Tet(n))
        }
        (6, 4) => hex_of(p, sides, first),
        _ => None,
    }
}

fn hex_of(p: &Polyhedra, sides: std::ops::Range<usize>, first: &[u32]) -> Option<Shape> {
    let bottom = [first[0], first[3], first[2], first[1]];
    // the vertex above bottom[i]: its neighbour, along a face loop, not on the bottom
    let mut top = [u32::MAX; 4];
    for s in sides.clone().skip(1) {
        let l = p.side_vertices(s);
        for (i, &a) in l.iter().enumerate() {
            let b = l[(i + 1) % l.len()];
            for (j, &v) in bottom.iter().enumerate() {
                let other = if a == v {
                    b
                } else if b == v {
                    a
                } else {
                    continue;
                };
                if !bottom.contains(&other) {
                    if top[j] != u32::MAX && top[j] != other {
                        return None;
                    }
                    top[j] = other;
                }
            }
        }
    }
    let mut n = [
        bottom[0], bottom[1], bottom[2], bottom[3], top[0], top[1], top[2], top[3],
    ];
    let mut sorted = n;
    sorted.sort_unstable();
    if top.contains(&u32::MAX) || sorted.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    if !matches(p, sides, &HEX_FACES, &n) {
        return None;
    }
    if triple(&p.vertices, [n[0], n[1], n[3], n[4]]) < 0.0 {
        n = [n[4], n[5], n[6], n[7], n[0], n[1], n[2], n[3]];
    }
    Some(Shape::Hex(n))
}
