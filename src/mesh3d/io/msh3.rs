//! gmsh `.msh` files in 3D, ASCII formats 4.1 and 2.2 (the sections are read by the 2D
//! reader's parser, [`crate::mesh::io::msh`], so both check the syntax alike).
//!
//! * Tetrahedra (element type 4), hexahedra (5), prisms (6) and pyramids (7) become the cells,
//!   their faces spelled out in gmsh's node ordering (faces of each element as gmsh lists them). Each cell gets a cell
//!   tag: in format 4.1 the first physical tag of its volume entity, in format 2.2 its first
//!   tag; 0 when it has none.
//! * Triangles (2) and quadrangles (3) are tagged boundary faces: in format 4.1 with the first
//!   physical tag of their surface entity, in format 2.2 with their first tag. Those without a
//!   physical tag (or with tag 0) are dropped; which of them are really boundary faces is
//!   checked when the mesh is built.
//! * Points (15) and lines (1) are ignored. Every other element type (second-order elements,
//!   or types this reader does not know) is an error naming the type and its line.
//! * Nodes that no cell uses are dropped; the others keep the order of the `$Nodes` section.

use super::{compact_vertices, too_large};
use crate::budget::MemoryBudget;
use crate::budget::{try_reserve, try_vec};
use crate::error::Result;
use crate::mesh::io::msh::{ElementSink, ElementTag, Sections, nodes_of_type, parse_sections};
use crate::mesh::io::{Tokens, read_text};
use crate::mesh3d::io::cells::{HEX_FACES, PRISM_FACES, PYRAMID_FACES, TET_FACES, push_shape};
use crate::mesh3d::{Point3, Polyhedra};
use std::path::Path;

/// Reads a gmsh ASCII mesh (format 4.1 or 2.2) of tetrahedra, hexahedra, prisms and pyramids;
/// see the module docs. No file larger than [`MemoryBudget::max_file_bytes`] of `budget` is
/// read.
pub fn read_msh3(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<Polyhedra> {
    let path = path.as_ref();
    let text = read_text(path, budget)?;
    let mut raw = Raw::default();
    let sections = parse_sections(Tokens::from_text(path, &text), point3, &mut raw)?;
    drop(text);
    build(path, sections, raw, budget)
}

/// Parses the contents of a `.msh` file in memory (`path` only names it in errors).
#[cfg(test)]
pub(crate) fn parse_msh3(path: &Path, bytes: &[u8]) -> Result<Polyhedra> {
    let mut raw = Raw::default();
    let sections = parse_sections(Tokens::new(path, bytes), point3, &mut raw)?;
    build(path, sections, raw, MemoryBudget::DEFAULT)
}

fn point3(p: [f64; 3]) -> Point3 {
    p
}

/// The elements read, before node tags are resolved: cells and tagged faces, each with the
/// node tags of its element (CSR), its gmsh type, its tag and its line.
#[derive(Default)]
struct Raw {
    cells: Elements,
    faces: Elements,
}

#[derive(Default)]
struct Elements {
    nodes: Vec<u64>,
    ty: Vec<u8>,
    tag: Vec<ElementTag>,
    line: Vec<u32>,
}

impl Elements {
    fn len(&self) -> usize {
        self.ty.len()
    }
}

/// The faces of gmsh element type `ty` (cells) and its number of nodes.
fn cell_faces(ty: u8) -> (&'static [&'static [usize]], usize) {
    match ty {
        4 => (&TET_FACES, 4),
        5 => (&HEX_FACES, 8),
        6 => (&PRISM_FACES, 6),
        _ => (&PYRAMID_FACES, 5),
    }
}

/// A name for gmsh element type `ty`, for error messages.
fn type_name(ty: i32) -> &'static str {
    match ty {
        8 | 26 | 27 | 28 => "a high-order line",
        9 | 16 | 10 | 20 | 21 | 22 | 23 | 24 | 25 => "a high-order surface element",
        11 | 29 | 30 | 31 => "a high-order tetrahedron",
        12 | 17 | 92 | 93 => "a high-order hexahedron",
        13 | 18 => "a high-order prism",
        14 | 19 => "a high-order pyramid",
        _ => "an element type this reader does not know",
    }
}

impl ElementSink for Raw {
    fn element(&mut self, t: &mut Tokens, ty: i32, tag: ElementTag, id: u64) -> Result<()> {
        let what = format_args!("a node of element {id}");
        let (list, n) = match ty {
            1 | 15 => (None, nodes_of_type(ty).unwrap_or(1)),
            2 | 3 => (Some(&mut self.faces), ty as usize + 1),
            4..=7 => (Some(&mut self.cells), cell_faces(ty as u8).1),
            _ => {
                return Err(t.err(format!(
                    "element {id} has type {ty} ({}): only first-order tetrahedra (4), \
                     hexahedra (5), prisms (6), pyramids (7), triangles (2), quadrangles (3), \
                     lines (1) and points (15) are read",
                    type_name(ty)
                )));
            }
        };
        match list {
            None => {
                for _ in 0..n {
                    t.parse_u64_with(what)?;
                }
            }
            Some(e) => {
                for _ in 0..n {
                    e.nodes.push(t.parse_u64_with(what)?);
                }
                e.ty.push(ty as u8);
                e.tag.push(tag);
                e.line
                    .push(u32::try_from(t.token_line()).unwrap_or(u32::MAX));
            }
        }
        Ok(())
    }
}

/// Resolves node tags, drops unused nodes and spells out the faces of every cell.
fn build(
    path: &Path,
    sections: Sections<Point3>,
    raw: Raw,
    budget: MemoryBudget,
) -> Result<Polyhedra> {
    let t = &Tokens::new(path, &[]);
    let Sections {
        nodes,
        node_index,
        entity_phys,
        ..
    } = sections;
    let Raw { cells, faces } = raw;
    if cells.len() == 0 {
        return Err(t.err_at(
            0,
            "no tetrahedra, hexahedra, prisms or pyramids (types 4 to 7) in the file",
        ));
    }
    let tag_of = |tag: ElementTag| match tag {
        ElementTag::Physical(p) => p,
        ElementTag::Entity { dim, tag } => usize::try_from(dim)
            .ok()
            .and_then(|d| entity_phys.get(d))
            .and_then(|m| m.get(&tag).copied())
            .unwrap_or(0),
    };
    // node tags → positions in $Nodes, in place
    let resolve = |e: &Elements| -> Result<Vec<u32>> {
        let mut out = try_vec(e.nodes.len(), "the vertices of the elements")?;
        let mut at = 0;
        for k in 0..e.len() {
            let n = if e.ty[k] <= 3 {
                e.ty[k] as usize + 1
            } else {
                cell_faces(e.ty[k]).1
            };
            for &tag in &e.nodes[at..at + n] {
                let v = node_index.get(tag).ok_or_else(|| {
                    t.err_at(
                        e.line[k] as usize,
                        format!("element refers to node {tag}, which is not in $Nodes"),
                    )
                })?;
                out.push(v as u32);
            }
            at += n;
        }
        Ok(out)
    };
    let mut cell_nodes = resolve(&cells)?;
    let mut face_nodes = resolve(&faces)?;
    let sides: usize = cells.ty.iter().map(|&ty| cell_faces(ty).0.len()).sum();
    let verts: usize = cells
        .ty
        .iter()
        .map(|&ty| cell_faces(ty).0.iter().map(|f| f.len()).sum::<usize>())
        .sum();
    let bytes = 4 * (sides + verts + cells.len()) as u64 + 24 * nodes.len() as u64;
    budget
        .check("the 3D mesh", bytes)
        .map_err(|e| too_large(path, e))?;
    let vertices = compact_vertices(&nodes, &mut cell_nodes, &mut face_nodes)?;
    drop(nodes);
    let mut p = Polyhedra {
        vertices,
        ..Polyhedra::default()
    };
    try_reserve(&mut p.cell_ptr, cells.len() + 1, "the cell offsets")?;
    try_reserve(&mut p.face_ptr, sides + 1, "the face offsets")?;
    try_reserve(&mut p.face_vertices, verts, "the face loops")?;
    let mut scratch = Vec::new();
    let mut at = 0;
    for k in 0..cells.len() {
        let (table, n) = cell_faces(cells.ty[k]);
        push_shape(&mut p, table, &cell_nodes[at..at + n], &mut scratch)
            .map_err(|e| too_large(path, e))?;
        at += n;
    }
    p.cell_tags = cells.tag.iter().map(|&g| tag_of(g)).collect();
    if p.cell_tags.iter().all(|&g| g == 0) {
        p.cell_tags.clear();
    }
    push_tagged(&mut p, &faces, &face_nodes, tag_of);
    Ok(p)
}

/// Appends to `p` the faces with a non-zero tag whose vertices some cell uses (`face_nodes`:
/// their vertex ids, `u32::MAX` for a vertex no cell uses).
fn push_tagged(
    p: &mut Polyhedra,
    faces: &Elements,
    face_nodes: &[u32],
    tag_of: impl Fn(ElementTag) -> i32,
) {
    let mut at = 0;
    p.tagged_ptr.push(0);
    for k in 0..faces.len() {
        let n = faces.ty[k] as usize + 1;
        let (tag, loop_) = (tag_of(faces.tag[k]), &face_nodes[at..at + n]);
        at += n;
        if tag == 0 || loop_.contains(&u32::MAX) {
            continue;
        }
        p.tagged_vertices.extend_from_slice(loop_);
        p.tagged_ptr.push(p.tagged_vertices.len() as u32);
        p.tagged_tags.push(tag);
    }
    if p.tagged_tags.is_empty() {
        p.tagged_ptr.clear();
    }
}
