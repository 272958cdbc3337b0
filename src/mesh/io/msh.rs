//! gmsh `.msh` files, ASCII formats 4.1 and 2.2 (2.0 and 2.1 are read as 2.2).
//!
//! * Triangles (element type 2) and quadrangles (type 3) become the cells. Each cell gets a
//!   cell tag ([`PolyMesh::cell_tag`]): in format 4.1 the first physical tag of its surface
//!   entity, in format 2.2 its first tag; 0 when it has none (heterogeneous media given as
//!   gmsh physical surfaces).
//! * Line elements (type 1) carry boundary tags: in format 4.1 the first physical tag of the
//!   curve entity the elements belong to (from the `$Entities` section), in format 2.2 the first
//!   tag of the element (its physical tag). Lines without a physical tag, or with tag 0, leave
//!   their edges untagged (0). Lines that are not boundary edges of the mesh (interior
//!   interfaces, or lines whose nodes no cell uses) are ignored.
//! * Points (type 15) and every other element type are ignored.
//! * Nodes that no cell uses (gmsh also lists geometry nodes) are dropped; the remaining nodes
//!   keep the order of the `$Nodes` section. The z coordinate is ignored.
//! * The names of `$PhysicalNames` are returned in [`MshMesh::physical_names`]; other sections
//!   (`$Periodic`, `$NodeData`, comments, …) are skipped.
//!
//! Binary files and the formats 4.0 and 3.0 are rejected with a clear message.

use super::{Tokens, capacity, read_text};
use crate::budget::MemoryBudget;
use crate::budget::{try_reserve, try_vec};
use crate::error::Result;
use crate::mesh::{NonBoundaryTag, Overlap, Point, PolyMesh, drop_unused_vertices_flat};
use std::collections::{BTreeSet, HashMap};
use std::fmt::Display;
use std::path::Path;

/// A gmsh mesh together with its physical-group names.
#[derive(Debug, Clone)]
pub struct MshMesh {
    /// The mesh; boundary edges carry the physical tags of the line elements on them.
    pub mesh: PolyMesh,
    /// `(dimension, physical tag, name)` from the `$PhysicalNames` section (empty if absent),
    /// in file order.
    pub physical_names: Vec<(i32, i32, String)>,
}

impl MshMesh {
    /// The tag of the physical group of dimension `dim` called `name`, if any.
    pub fn physical_tag(&self, dim: i32, name: &str) -> Option<i32> {
        self.physical_names
            .iter()
            .find(|(d, _, n)| *d == dim && n == name)
            .map(|&(_, tag, _)| tag)
    }
}

/// Reads a gmsh ASCII mesh (format 4.1 or 2.2); see the module docs.
/// No file larger than [`MemoryBudget::max_file_bytes`] of `budget` is read.
pub fn read_msh(path: impl AsRef<Path>, budget: MemoryBudget) -> Result<MshMesh> {
    let path = path.as_ref();
    let text = read_text(path, budget)?;
    let mut raw = Raw::default();
    let sections = parse_sections(Tokens::from_text(path, &text), point2, &mut raw)?;
    // the text is no longer needed: free it before the mesh is built
    drop(text);
    build(path, sections, raw)
}

#[derive(Clone, Copy, PartialEq)]
enum Version {
    V22,
    V41,
}

/// How a line element gets its boundary tag (and a cell its cell tag).
#[derive(Clone, Copy)]
enum LineTag {
    /// Format 2.2: the element's own physical tag.
    Physical(i32),
    /// Format 4.1: the physical tag of this curve (surface, for a cell) entity.
    Curve(i32),
}

/// Position in `$Nodes` of each node tag.
///
/// gmsh numbers nodes 1, 2, …, n, so tags below a limit proportional to the announced number of
/// nodes are kept in a vector indexed by tag (no hashing, and lookups in file order stay
/// cache-friendly); larger tags, which only sparse numberings produce, go to a hash map. The
/// limit also bounds the vector by a small multiple of the file size, whatever the header says.
#[derive(Default)]
pub(crate) struct NodeIndex {
    /// Position of node `tag` for `tag < dense_limit` ([`NodeIndex::ABSENT`] if not defined);
    /// grows on demand up to `dense_limit`.
    dense: Vec<usize>,
    dense_limit: u64,
    sparse: HashMap<u64, usize>,
}

impl NodeIndex {
    const ABSENT: usize = usize::MAX;

    /// An index for `count` nodes announced in a section of `len` bytes: dense for tags below
    /// 2·min(`count`, `len`/8) + 1024 (a node takes at least 8 bytes in either format).
    fn new(count: usize, len: usize) -> Result<Self> {
        let expected = count.min(len / 8);
        let limit = expected.saturating_mul(2).saturating_add(1024);
        Ok(NodeIndex {
            dense: try_vec(expected.saturating_add(1), "the index of the nodes")?,
            dense_limit: u64::try_from(limit).unwrap_or(u64::MAX),
            sparse: HashMap::new(),
        })
    }

    /// Records node `tag` at position `pos`; `false` (and no change) if the tag is already known.
    fn insert(&mut self, tag: u64, pos: usize) -> bool {
        if tag < self.dense_limit {
            // tag < dense_limit, which came from a usize
            let i = tag as usize;
            if i >= self.dense.len() {
                self.dense.resize(i + 1, Self::ABSENT);
            }
            if self.dense[i] != Self::ABSENT {
                return false;
            }
            self.dense[i] = pos;
            true
        } else {
            match self.sparse.entry(tag) {
                std::collections::hash_map::Entry::Occupied(_) => false,
                std::collections::hash_map::Entry::Vacant(v) => {
                    v.insert(pos);
                    true
                }
            }
        }
    }

    /// The position of node `tag`, if it was defined.
    pub(crate) fn get(&self, tag: u64) -> Option<usize> {
        if tag < self.dense_limit {
            self.dense
                .get(tag as usize)
                .copied()
                .filter(|&p| p != Self::ABSENT)
        } else {
            self.sparse.get(&tag).copied()
        }
    }
}

/// What every gmsh mesh needs from the file, whatever its dimension: the nodes (points of
/// type `P`), the physical tag of each entity and the physical names.
pub(crate) struct Sections<P> {
    pub(crate) nodes: Vec<P>,
    pub(crate) node_index: NodeIndex,
    /// `entity_phys[d]`: the first physical tag of each entity of dimension `d` (format 4.1).
    pub(crate) entity_phys: [HashMap<i32, i32>; 4],
    pub(crate) physical_names: Vec<(i32, i32, String)>,
}

impl<P> Default for Sections<P> {
    fn default() -> Self {
        Sections {
            nodes: Vec::new(),
            node_index: NodeIndex::default(),
            entity_phys: Default::default(),
            physical_names: Vec::new(),
        }
    }
}

/// Where an element record gets its tags: format 2.2 gives the element's first tag (its
/// physical tag), format 4.1 the dimension and tag of the entity of its block.
#[derive(Clone, Copy)]
pub(crate) enum ElementTag {
    Physical(i32),
    Entity { dim: i32, tag: i32 },
}

/// A reader of gmsh element records: given the type, tags and id of an element, reads its
/// node tags from `t` and files it.
pub(crate) trait ElementSink {
    fn element(&mut self, t: &mut Tokens, ty: i32, tag: ElementTag, id: u64) -> Result<()>;
}

/// The 2D elements read from the file, before node tags are resolved.
struct Raw {
    /// Node tags of the cells, CSR by `cell_ptr`.
    cell_nodes: Vec<u64>,
    cell_ptr: Vec<usize>,
    cell_line: Vec<usize>,
    /// The tag of each cell, as for lines: its physical tag (2.2) or its surface entity (4.1).
    cell_tag: Vec<LineTag>,
    lines: Vec<([u64; 2], LineTag, usize)>,
    ignored_types: BTreeSet<i32>,
}

impl Default for Raw {
    fn default() -> Self {
        Raw {
            cell_nodes: Vec::new(),
            cell_ptr: vec![0],
            cell_line: Vec::new(),
            cell_tag: Vec::new(),
            lines: Vec::new(),
            ignored_types: BTreeSet::new(),
        }
    }
}

impl ElementSink for Raw {
    fn element(&mut self, t: &mut Tokens, ty: i32, tag: ElementTag, id: u64) -> Result<()> {
        let tag = match tag {
            ElementTag::Physical(p) => LineTag::Physical(p),
            ElementTag::Entity { dim: 1 | 2, tag } => LineTag::Curve(tag),
            ElementTag::Entity { .. } => LineTag::Physical(0),
        };
        read_element(t, self, ty, tag, id)
    }
}

/// Number of nodes of the gmsh element types (`None` for types not in this table).
pub(crate) fn nodes_of_type(ty: i32) -> Option<usize> {
    Some(match ty {
        1 => 2,
        2 => 3,
        3 => 4,
        4 => 4,
        5 => 8,
        6 => 6,
        7 => 5,
        8 => 3,
        9 => 6,
        10 => 9,
        11 => 10,
        12 => 27,
        13 => 18,
        14 => 14,
        15 => 1,
        16 => 8,
        17 => 20,
        18 => 15,
        19 => 13,
        20 => 9,
        21 => 10,
        22 => 12,
        23 => 15,
        24 => 15,
        25 => 21,
        26 => 4,
        27 => 5,
        28 => 6,
        29 => 20,
        30 => 35,
        31 => 56,
        92 => 64,
        93 => 125,
        _ => return None,
    })
}

/// Parses the contents of a `.msh` file (`path` is only used in error messages); what
/// [`read_msh`] does, for tests that work in memory.
#[cfg(test)]
pub(crate) fn parse_msh(path: &Path, bytes: &[u8]) -> Result<MshMesh> {
    let mut raw = Raw::default();
    let sections = parse_sections(Tokens::new(path, bytes), point2, &mut raw)?;
    build(path, sections, raw)
}

/// The 2D point of a gmsh node: z is dropped.
fn point2([x, y, _]: [f64; 3]) -> Point {
    [x, y]
}

/// Reads the sections of a `.msh` file, checking its syntax: the nodes, converted by `point`,
/// physical names and entities are returned, the elements handed to `elements`.
pub(crate) fn parse_sections<P, E: ElementSink>(
    mut t: Tokens,
    point: fn([f64; 3]) -> P,
    elements: &mut E,
) -> Result<Sections<P>> {
    match t.next_opt()? {
        Some("$MeshFormat") => {}
        Some(tok) => {
            return Err(t.err(format!(
                "expected \"$MeshFormat\" (is this a gmsh file?), found \"{tok}\""
            )));
        }
        None => return Err(t.err("empty file: expected \"$MeshFormat\"")),
    }
    let version_tok = t.next("the format version")?;
    let version_line = t.token_line();
    let file_type: i32 = t.parse("the file type (0 for ASCII)")?;
    if file_type != 0 {
        return Err(t.err(
            "binary .msh files are not supported: save the mesh as ASCII \
             (gmsh option -format msh41 or msh22, with Mesh.Binary = 0)",
        ));
    }
    let _data_size: u32 = t.parse("the data size")?;
    let version = match version_tok {
        "4.1" => Version::V41,
        v if v.starts_with("2.") && v.parse::<f64>().is_ok() => Version::V22,
        v => {
            return Err(t.err_at(
                version_line,
                format!("unsupported .msh format version {v}: only 4.1 and 2.2 are read"),
            ));
        }
    };
    expect(&mut t, "$EndMeshFormat")?;

    let mut raw = Sections::default();
    let mut seen: Vec<&str> = Vec::new();
    while let Some(tok) = t.next_opt()? {
        let section = tok;
        let known = matches!(
            section,
            "$PhysicalNames" | "$Entities" | "$Nodes" | "$Elements"
        );
        if known {
            if seen.contains(&section) {
                return Err(t.err(format!("a second {section} section")));
            }
            seen.push(section);
        }
        match (section, version) {
            ("$PhysicalNames", _) => read_physical_names(&mut t, &mut raw)?,
            ("$Entities", Version::V41) => read_entities(&mut t, &mut raw)?,
            ("$Nodes", Version::V41) => read_nodes41(&mut t, &mut raw, point)?,
            ("$Nodes", Version::V22) => read_nodes22(&mut t, &mut raw, point)?,
            ("$Elements", Version::V41) => read_elements41(&mut t, elements)?,
            ("$Elements", Version::V22) => read_elements22(&mut t, elements)?,
            (s, _) if s.starts_with('$') && !s.starts_with("$End") => skip_section(&mut t, s)?,
            (s, _) => {
                return Err(t.err(format!(
                    "expected a section header such as \"$Nodes\", found \"{s}\""
                )));
            }
        }
    }
    for needed in ["$Nodes", "$Elements"] {
        if !seen.contains(&needed) {
            return Err(t.err_at(0, format!("the file has no {needed} section")));
        }
    }
    Ok(raw)
}

/// Reads the next token and checks it is `what` (a section end marker).
fn expect(t: &mut Tokens, what: &str) -> Result<()> {
    let tok = t.next(&format!("\"{what}\""))?;
    if tok == what {
        Ok(())
    } else {
        Err(t.err(format!(
            "expected \"{what}\", found \"{tok}\" (wrong count or truncated block?)"
        )))
    }
}

fn skip_section(t: &mut Tokens, section: &str) -> Result<()> {
    let end = format!("$End{}", &section[1..]);
    let start = t.token_line();
    loop {
        match t.next_opt()? {
            Some(tok) if tok == end => return Ok(()),
            Some(_) => {}
            None => {
                return Err(t.err(format!("section {section} (line {start}) has no \"{end}\"")));
            }
        }
    }
}

fn read_physical_names<P>(t: &mut Tokens, raw: &mut Sections<P>) -> Result<()> {
    let n = t.count("the number of physical names")?;
    raw.physical_names.reserve(capacity(n, t.remaining()));
    for i in 1..=n {
        let dim: i32 = t.parse_with(format_args!("the dimension of physical name {i}"))?;
        let tag: i32 = t.parse_with(format_args!("the tag of physical name {i}"))?;
        let rest = t.rest_of_line()?;
        let name = rest
            .strip_prefix('"')
            .and_then(|s| s.strip_suffix('"'))
            .unwrap_or(rest);
        if name.is_empty() {
            return Err(t.err(format!("physical name {i} has no name")));
        }
        raw.physical_names.push((dim, tag, name.to_string()));
    }
    expect(t, "$EndPhysicalNames")
}

/// Skips a bounding box or coordinates, checking they are numbers.
fn skip_floats(t: &mut Tokens, n: usize, what: impl Display) -> Result<()> {
    for _ in 0..n {
        t.parse_with::<f64>(&what)?;
    }
    Ok(())
}

fn read_entities<P>(t: &mut Tokens, raw: &mut Sections<P>) -> Result<()> {
    let mut counts = [0usize; 4];
    for (d, c) in counts.iter_mut().enumerate() {
        *c = t.count_with(format_args!("the number of entities of dimension {d}"))?;
    }
    for (dim, &n) in counts.iter().enumerate() {
        for i in 1..=n {
            let what = format_args!("entity {i} of dimension {dim}");
            let tag: i32 = t.parse_with(format_args!("the tag of {what}"))?;
            skip_floats(
                t,
                if dim == 0 { 3 } else { 6 },
                format_args!("the box of {what}"),
            )?;
            let nphys = t.count_with(format_args!("the number of physical tags of {what}"))?;
            for j in 0..nphys {
                let p: i32 = t.parse_with(format_args!("a physical tag of {what}"))?;
                if dim > 0 && j == 0 {
                    raw.entity_phys[dim].insert(tag, p);
                }
            }
            if dim > 0 {
                let nb = t.count_with(format_args!("the number of bounding entities of {what}"))?;
                for _ in 0..nb {
                    t.parse_with::<i32>(format_args!("a bounding entity of {what}"))?;
                }
            }
        }
    }
    expect(t, "$EndEntities")
}

fn add_node<P>(t: &Tokens, raw: &mut Sections<P>, tag: u64, p: P) -> Result<()> {
    if !raw.node_index.insert(tag, raw.nodes.len()) {
        return Err(t.err(format!("node {tag} is defined twice")));
    }
    raw.nodes.push(p);
    Ok(())
}

/// The x, y and z coordinates of node `tag`.
fn read_xyz(t: &mut Tokens, tag: u64) -> Result<[f64; 3]> {
    let x = t.coord_with(format_args!("x of node {tag}"))?;
    let y = t.coord_with(format_args!("y of node {tag}"))?;
    let z = t.coord_with(format_args!("z of node {tag}"))?;
    Ok([x, y, z])
}

fn read_nodes22<P>(t: &mut Tokens, raw: &mut Sections<P>, point: fn([f64; 3]) -> P) -> Result<()> {
    let n = t.count("the number of nodes")?;
    try_reserve(&mut raw.nodes, capacity(n, t.remaining()), "the nodes")?;
    raw.node_index = NodeIndex::new(n, t.remaining())?;
    for i in 1..=n {
        let tag = t.parse_u64_with(format_args!("the tag of node {i}"))?;
        let p = read_xyz(t, tag)?;
        add_node(t, raw, tag, point(p))?;
    }
    expect(t, "$EndNodes")
}

/// The header of a gmsh 4.1 `$Nodes` or `$Elements` section (`what`: "node" or "element"):
/// the numbers of blocks and of items, and the line of the latter; the tag range is skipped.
fn read_block_header41(t: &mut Tokens, what: &str) -> Result<(usize, usize, usize)> {
    let nblocks = t.count_with(format_args!("the number of {what} blocks"))?;
    let n = t.count_with(format_args!("the number of {what}s"))?;
    let header_line = t.token_line();
    t.parse_with::<u64>(format_args!("the smallest {what} tag"))?;
    t.parse_with::<u64>(format_args!("the largest {what} tag"))?;
    Ok((nblocks, n, header_line))
}

fn read_nodes41<P>(t: &mut Tokens, raw: &mut Sections<P>, point: fn([f64; 3]) -> P) -> Result<()> {
    let (nblocks, n, header_line) = read_block_header41(t, "node")?;
    try_reserve(&mut raw.nodes, capacity(n, t.remaining()), "the nodes")?;
    raw.node_index = NodeIndex::new(n, t.remaining())?;
    let mut tags = Vec::new();
    for b in 1..=nblocks {
        let dim: i32 = t.parse_with(format_args!("the entity dimension of node block {b}"))?;
        t.parse_with::<i32>(format_args!("the entity tag of node block {b}"))?;
        let parametric: i32 =
            t.parse_with(format_args!("the parametric flag of node block {b}"))?;
        let m = t.count_with(format_args!("the number of nodes of block {b}"))?;
        let extra = match parametric {
            0 => 0,
            1 => usize::try_from(dim.clamp(0, 3)).unwrap_or(0),
            p => {
                return Err(t.err(format!(
                    "parametric flag {p} of node block {b} is not 0 or 1"
                )));
            }
        };
        tags.clear();
        try_reserve(&mut tags, capacity(m, t.remaining()), "the node tags")?;
        for _ in 0..m {
            tags.push(t.parse_u64_with(format_args!("a node tag of block {b}"))?);
        }
        for &tag in &tags {
            let p = read_xyz(t, tag)?;
            skip_floats(
                t,
                extra,
                format_args!("a parametric coordinate of node {tag}"),
            )?;
            add_node(t, raw, tag, point(p))?;
        }
    }
    if raw.nodes.len() != n {
        return Err(t.err_at(
            header_line,
            format!(
                "the $Nodes header announces {n} nodes but the blocks hold {}",
                raw.nodes.len()
            ),
        ));
    }
    expect(t, "$EndNodes")
}

/// Reads the node tags of element `id` of type `ty` and files it.
fn read_element(t: &mut Tokens, raw: &mut Raw, ty: i32, tag: LineTag, id: u64) -> Result<()> {
    let what = format_args!("a node of element {id}");
    match ty {
        1 => {
            let a = t.parse_u64_with(what)?;
            let b = t.parse_u64_with(what)?;
            raw.lines.push(([a, b], tag, t.token_line()));
        }
        2 | 3 => {
            for _ in 0..ty + 1 {
                raw.cell_nodes.push(t.parse_u64_with(what)?);
            }
            raw.cell_ptr.push(raw.cell_nodes.len());
            raw.cell_line.push(t.token_line());
            raw.cell_tag.push(tag);
        }
        _ => {
            raw.ignored_types.insert(ty);
            match nodes_of_type(ty) {
                Some(n) => {
                    for _ in 0..n {
                        t.parse_u64_with(what)?;
                    }
                }
                None => {
                    t.rest_of_line()?;
                }
            }
        }
    }
    Ok(())
}

fn read_elements22(t: &mut Tokens, elements: &mut impl ElementSink) -> Result<()> {
    let n = t.count("the number of elements")?;
    for i in 1..=n {
        let id = t.parse_u64_with(format_args!("the tag of element {i}"))?;
        let ty: i32 = t.parse_with(format_args!("the type of element {id}"))?;
        let ntags = t.count_with(format_args!("the number of tags of element {id}"))?;
        let mut phys = 0;
        for j in 0..ntags {
            let tag: i32 = t.parse_with(format_args!("a tag of element {id}"))?;
            if j == 0 {
                phys = tag;
            }
        }
        elements.element(t, ty, ElementTag::Physical(phys), id)?;
    }
    expect(t, "$EndElements")
}

fn read_elements41(t: &mut Tokens, elements: &mut impl ElementSink) -> Result<()> {
    let (nblocks, n, header_line) = read_block_header41(t, "element")?;
    let mut total = 0usize;
    for b in 1..=nblocks {
        let dim: i32 = t.parse_with(format_args!("the entity dimension of element block {b}"))?;
        let entity: i32 = t.parse_with(format_args!("the entity tag of element block {b}"))?;
        let ty: i32 = t.parse_with(format_args!("the element type of element block {b}"))?;
        let m = t.count_with(format_args!("the number of elements of block {b}"))?;
        let tag = ElementTag::Entity { dim, tag: entity };
        for _ in 0..m {
            let id = t.parse_u64_with(format_args!("an element tag of block {b}"))?;
            elements.element(t, ty, tag, id)?;
        }
        total = total.saturating_add(m);
    }
    if total != n {
        return Err(t.err_at(
            header_line,
            format!("the $Elements header announces {n} elements but the blocks hold {total}"),
        ));
    }
    expect(t, "$EndElements")
}

/// The error of a file without cells, naming the element types that were skipped.
fn no_cells(t: &Tokens, ignored_types: &BTreeSet<i32>) -> crate::Error {
    let ignored = if ignored_types.is_empty() {
        String::new()
    } else {
        format!(
            " (ignored element types: {})",
            ignored_types
                .iter()
                .map(i32::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    t.err_at(
        0,
        format!("no triangles (type 2) or quadrangles (type 3) in the file{ignored}"),
    )
}

/// Resolves node tags, drops unused nodes, builds the mesh and tags its boundary edges.
///
/// Errors come in this order: a cell naming an unknown node (first such cell in file order),
/// a line element naming an unknown node, then the mesh checks of [`PolyMesh::from_cells`].
/// Tagged lines that are not boundary edges of the mesh are skipped: they are looked up among
/// the boundary edges of the constructed mesh ([`PolyMesh::set_boundary_tags`] with
/// [`NonBoundaryTag::Ignore`]), so no second pass over all cell sides is needed.
fn build(path: &Path, sections: Sections<Point>, raw: Raw) -> Result<MshMesh> {
    // only for its error constructors (errors name the file and a line)
    let t = &Tokens::new(path, &[]);
    let Sections {
        nodes,
        node_index,
        entity_phys,
        physical_names,
    } = sections;
    let [_, curve_phys, surface_phys, _] = &entity_phys;
    let Raw {
        cell_nodes,
        cell_ptr,
        cell_line,
        cell_tag,
        lines,
        ignored_types,
    } = raw;
    let node = |tag: u64, line: usize| {
        node_index.get(tag).ok_or_else(|| {
            t.err_at(
                line,
                format!("element refers to node {tag}, which is not in $Nodes"),
            )
        })
    };
    let nc = cell_line.len();
    if nc == 0 {
        return Err(no_cells(t, &ignored_types));
    }
    // cells, flat: the node tags of cell k are cell_nodes[cell_ptr[k]..cell_ptr[k + 1]], and
    // cell_ptr has nc + 1 entries starting at 0 (read_elements* push them)
    let mut cell_verts = try_vec(cell_nodes.len(), "the vertices of the cells")?;
    for (k, &line) in cell_line.iter().enumerate() {
        let tags = cell_ptr
            .get(k)
            .zip(cell_ptr.get(k + 1))
            .and_then(|(&s, &e)| cell_nodes.get(s..e))
            .unwrap_or_default();
        for &tag in tags {
            cell_verts.push(node(tag, line)?);
        }
    }
    if cell_ptr.len() != nc + 1 || cell_ptr.last() != Some(&cell_verts.len()) {
        // not reached (read_elements* keep cell_ptr in step with cell_line), but never panic
        return Err(t.err_at(0, "inconsistent element records"));
    }
    drop((cell_nodes, cell_line));
    let (vertices, mut new_id) = drop_unused_vertices_flat(&nodes, &mut cell_verts);
    drop(nodes);
    let vertices = crate::mesh::renumber::space_order(vertices, &mut cell_verts, &mut new_id);

    // tagged lines, in file order, as new vertex ids; lines on unused nodes are dropped
    let mut tagged = Vec::new();
    for &([a, b], tag, line) in &lines {
        let tag = match tag {
            LineTag::Physical(p) => p,
            LineTag::Curve(c) => curve_phys.get(&c).copied().unwrap_or(0),
        };
        let (a, b) = (node(a, line)?, node(b, line)?);
        if tag == 0 {
            continue;
        }
        match (new_id.get(a), new_id.get(b)) {
            (Some(&a), Some(&b)) if a != usize::MAX && b != usize::MAX && a != b => {
                tagged.push((a, b, tag));
            }
            _ => {}
        }
    }
    let invalid = |source| crate::Error::InvalidMeshFile {
        path: t.path.to_path_buf(),
        source,
    };
    // cell tags: the physical tag (2.2) or the physical tag of the surface entity (4.1)
    let cell_tags: Vec<i32> = cell_tag
        .iter()
        .map(|t| match *t {
            LineTag::Physical(p) => p,
            LineTag::Curve(s) => surface_phys.get(&s).copied().unwrap_or(0),
        })
        .collect();
    let mut mesh = PolyMesh::from_flat_cells(vertices, cell_ptr, cell_verts, Overlap::Sweep)
        .and_then(|m| m.with_cell_tags(cell_tags))
        .map_err(invalid)?;
    mesh.set_boundary_tags(&tagged, NonBoundaryTag::Ignore)
        .map_err(invalid)?;
    Ok(MshMesh {
        mesh,
        physical_names,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    const SQUARE22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n\
1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n9 5 5 0\n$EndNodes\n$Elements\n4\n\
1 15 2 0 1 9\n2 1 2 7 1 1 2\n3 2 2 1 1 1 2 3\n4 2 2 1 1 1 3 4\n$EndElements\n";

    #[test]
    fn reads_22() {
        let m = parse_msh(Path::new("s.msh"), SQUARE22.as_bytes()).unwrap();
        assert_eq!(
            (m.mesh.n_vertices(), m.mesh.n_cells(), m.mesh.n_edges()),
            (4, 2, 5)
        );
        let tags: Vec<i32> = m
            .mesh
            .boundary_edges()
            .iter()
            .map(|&e| m.mesh.edge_tag(e))
            .collect();
        assert_eq!(tags.iter().filter(|&&t| t == 7).count(), 1);
    }

    /// SQUARE22 with its node tags replaced (the node tags of the elements too).
    fn square22_with_tags(tags: [&str; 5]) -> String {
        let mut s = SQUARE22.to_string();
        for (old, new) in [
            ("1 0 0 0\n", 0),
            ("2 1 0 0\n", 1),
            ("3 1 1 0\n", 2),
            ("4 0 1 0\n", 3),
        ] {
            s = s.replace(old, &format!("{} {}", tags[new], &old[2..]));
        }
        s.replace("9 5 5 0\n", &format!("{} 5 5 0\n", tags[4]))
            .replace("1 15 2 0 1 9\n", &format!("1 15 2 0 1 {}\n", tags[4]))
            .replace(
                "2 1 2 7 1 1 2\n3 2 2 1 1 1 2 3\n4 2 2 1 1 1 3 4\n",
                &format!(
                    "2 1 2 7 1 {a} {b}\n3 2 2 1 1 {a} {b} {c}\n4 2 2 1 1 {a} {c} {d}\n",
                    a = tags[0],
                    b = tags[1],
                    c = tags[2],
                    d = tags[3]
                ),
            )
    }

    #[test]
    fn sparse_node_tags_read_like_dense_ones() {
        let dense = parse_msh(Path::new("d.msh"), SQUARE22.as_bytes()).unwrap();
        let sparse = square22_with_tags(["1000000007", "3", "18446744073709551615", "2", "77"]);
        let sparse = parse_msh(Path::new("s.msh"), sparse.as_bytes()).unwrap();
        assert_eq!(sparse.mesh.vertices(), dense.mesh.vertices());
        for k in 0..dense.mesh.n_cells() {
            assert_eq!(sparse.mesh.cell_vertices(k), dense.mesh.cell_vertices(k));
        }
        for e in 0..dense.mesh.n_edges() {
            assert_eq!(sparse.mesh.edge_tag(e), dense.mesh.edge_tag(e));
        }
        // a tag defined twice is an error whether it is stored densely or not
        for tag in ["3", "1000000007"] {
            let twice = square22_with_tags([tag, "5", "6", "7", tag]);
            let e = parse_msh(Path::new("t.msh"), twice.as_bytes()).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("t.msh:10: node {tag} is defined twice")
            );
        }
        let mut index = NodeIndex::new(3, 1000).unwrap();
        assert!(index.insert(2, 0) && index.insert(u64::MAX, 1) && index.insert(1 << 40, 2));
        assert!(!index.insert(2, 3) && !index.insert(u64::MAX, 3));
        assert_eq!(
            [0, 1, 2, 3, u64::MAX, 1 << 40].map(|t| index.get(t)),
            [None, None, Some(0), None, Some(1), Some(2)]
        );
    }

    #[test]
    fn tagged_lines_off_the_boundary_are_ignored() {
        // the diagonal 1-3 is interior, the line 1-9 joins a node no cell uses; 2-3 is tagged 8
        let extra = SQUARE22
            .replace("$Elements\n4\n", "$Elements\n7\n")
            .replace(
                "$EndElements",
                "5 1 2 5 1 1 3\n6 1 2 6 1 1 9\n7 1 2 8 1 3 2\n$EndElements",
            );
        let m = parse_msh(Path::new("s.msh"), extra.as_bytes())
            .unwrap()
            .mesh;
        // the edges by the coordinates of their end points (the reader numbers the vertices
        // in space order)
        let mut tags: Vec<([[i64; 2]; 2], i32)> = (0..m.n_edges())
            .map(|e| {
                let [a, b] = m
                    .edge_vertices(e)
                    .map(|v| m.vertices()[v].map(|x| x as i64));
                ([a.min(b), a.max(b)], m.edge_tag(e))
            })
            .collect();
        tags.sort_unstable();
        assert_eq!(
            tags,
            vec![
                ([[0, 0], [0, 1]], 0),
                ([[0, 0], [1, 0]], 7),
                ([[0, 0], [1, 1]], 0),
                ([[0, 1], [1, 1]], 0),
                ([[1, 0], [1, 1]], 8),
            ]
        );
        // an unknown node on a line is still an error, before any mesh check
        let bad = extra.replace("6 1 2 6 1 1 9", "6 1 2 6 1 1 99");
        let e = parse_msh(Path::new("s.msh"), bad.as_bytes()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "s.msh:19: element refers to node 99, which is not in $Nodes"
        );
    }

    #[test]
    fn rejects_binary_and_unknown_nodes() {
        let e = parse_msh(
            Path::new("b.msh"),
            b"$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\xff",
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("b.msh:2:") && e.to_string().contains("binary"),
            "{e}"
        );
        let bad = SQUARE22.replace("2 1 2 7 1 1 2", "2 1 2 7 1 1 8");
        let e = parse_msh(Path::new("s.msh"), bad.as_bytes()).unwrap_err();
        assert!(e.to_string().starts_with("s.msh:15:"), "{e}");
        assert!(matches!(e, Error::MeshIo { .. }));
    }
}
