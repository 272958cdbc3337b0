//! Typed errors. The library never panics on bad input: every failure a user can cause
//! (a malformed file, a non-conforming mesh, infeasible constraints, NaN data, a solver that
//! does not converge) is one of these variants, with enough context to find the culprit.

use crate::units::human_bytes;
use std::path::PathBuf;
use thiserror::Error;

/// Result alias used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Every error gradvi can report.
#[derive(Debug, Error)]
pub enum Error {
    /// A mesh file could not be read or parsed; `line` is 1-based (0 when unknown).
    #[error("{}:{line}: {msg}", path.display())]
    MeshIo {
        /// File being read.
        path: PathBuf,
        /// 1-based line number (0 if the error is not tied to a line).
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// The mesh data is geometrically or topologically invalid.
    #[error("invalid mesh: {0}")]
    InvalidMesh(#[from] MeshError),
    /// A mesh file whose data is geometrically or topologically invalid.
    #[error("{}: invalid mesh: {source}", path.display())]
    InvalidMeshFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: MeshError,
    },
    /// Problem data (diffusion tensor, source, boundary values, barriers) is invalid.
    #[error("invalid data: {0}")]
    InvalidData(String),
    /// The discrete convex set is empty (e.g. Dirichlet data above an upper barrier).
    #[error("infeasible constraints: {0}")]
    Infeasible(String),
    /// A linear solve failed (e.g. the matrix is not numerically positive definite).
    #[error("linear solver: {0}")]
    Linear(String),
    /// The discrete problem has no unique solution (the energy is not bounded below on the
    /// convex set, or is flat along some direction), detected before solving.
    #[error("ill-posed problem: {0}")]
    IllPosed(String),
    /// The active-set iteration did not converge, cycled, or its certificate failed.
    #[error("active-set solver: {0}")]
    Solver(#[from] SolverError),
    /// A problem file is invalid: TOML syntax, an unknown key, a bad expression, or data that
    /// does not fit the mesh. `line` and `column` are 1-based (0 when
    /// the error is not tied to a place in the file); the message names the key.
    #[error("{}: {msg}", place(path, *line, *column))]
    ProblemFile {
        /// The problem file.
        path: PathBuf,
        /// 1-based line of the offending value (0 if unknown).
        line: usize,
        /// 1-based column (in characters) of the offending character (0 if unknown).
        column: usize,
        /// What kind of mistake it is.
        kind: ProblemFileErrorKind,
        /// What is wrong, and where (key, point, cell or edge).
        msg: String,
    },
    /// Plain I/O (writing outputs).
    #[error("{}: {source}", path.display())]
    Io {
        /// File being written or read.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// An internal invariant does not hold (two parts of gradvi disagree): a bug, reported as
    /// an error instead of a wrong answer or a panic.
    #[error("internal error (please report): {0}")]
    Internal(String),
    /// A computation would need more memory than the caller's budget
    /// ([`MemoryBudget`](crate::budget::MemoryBudget)): refused by its estimate before the
    /// allocation, or an allocation that failed. A mesh too large to build is
    /// [`MeshError::TooLarge`] instead.
    #[error(
        "{what} would need about {}, more than the {} of memory this process may take ({})",
        human_bytes(*bytes),
        human_bytes(*budget),
        MEMORY_ADVICE
    )]
    OutOfMemory {
        /// What needed the memory.
        what: String,
        /// The estimate (or the failed request), in bytes.
        bytes: u64,
        /// The budget it was compared with, in bytes.
        budget: u64,
    },
    /// The caller's cancellation hook ([`Cancel`](crate::vi::Cancel)) asked the solve to stop;
    /// it stopped between two linear solves, with no result.
    #[error("the solve was interrupted")]
    Interrupted,
}

/// What to do when the memory runs out: the end of [`Error::OutOfMemory`]'s message, which the
/// command line adds to a [`MeshError::TooLarge`].
pub const MEMORY_ADVICE: &str = "use a coarser mesh, or give the process more memory: free \
     some, or raise its limit, e.g. `ulimit -v` or the job's memory request";

impl Error {
    /// True for the errors that say the memory ran out: [`Error::OutOfMemory`] and a mesh
    /// refused as [`MeshError::TooLarge`] (alone or from a file).
    pub fn is_out_of_memory(&self) -> bool {
        matches!(
            self,
            Error::OutOfMemory { .. }
                | Error::InvalidMesh(MeshError::TooLarge { .. })
                | Error::InvalidMeshFile {
                    source: MeshError::TooLarge { .. },
                    ..
                }
        )
    }
}

/// `path:line:column`, `path:line` or `path`, whichever is known.
fn place(path: &std::path::Path, line: usize, column: usize) -> String {
    match (line, column) {
        (0, _) => path.display().to_string(),
        (l, 0) => format!("{}:{l}", path.display()),
        (l, c) => format!("{}:{l}:{c}", path.display()),
    }
}

/// The kinds of mistakes in a problem file ([`Error::ProblemFile`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ProblemFileErrorKind {
    /// The text is not valid TOML.
    Syntax,
    /// A key the format does not know.
    UnknownKey,
    /// Valid TOML that does not fit the format: a missing key, a value of the wrong type,
    /// contradictory sections.
    Schema,
    /// An expression that does not parse: syntax, unknown variable or function, wrong type.
    Expression,
    /// A parameter or definition: unknown override, bad name, cyclic definitions.
    Parameter,
    /// The `[mesh]` section, or a mesh that cannot carry the problem.
    Mesh,
    /// A tag used in the file that no boundary edge of the mesh carries.
    Tag,
    /// A boundary edge that no boundary section selects.
    UncoveredEdge,
    /// A boundary edge that two boundary sections select.
    OverlappingRules,
    /// A point where no piece of a piecewise datum applies.
    UncoveredPoint,
    /// A diffusion tensor that is not symmetric positive definite at some cell.
    NotSpd,
    /// A datum that is NaN or infinite at some evaluation point.
    NonFinite,
    /// The file and the mesh have different dimensions: a 2×2 tensor or a 2-component
    /// gradient on a 3D mesh, a 3×3 tensor or 3 components on a 2D mesh, a 3D `[mesh]` for a
    /// 2D problem. (A `z` in a 2D problem is an [`Expression`](Self::Expression) error: an
    /// unknown variable there, at its character.)
    Dimension,
}

/// Invalid mesh: each variant names the cell, edge or vertex at fault.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no cells.
    #[error("the mesh has no cells")]
    Empty,
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFiniteVertex {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// A cell refers to a vertex that does not exist.
    #[error("cell {cell} refers to vertex {vertex}, but there are only {n_vertices} vertices")]
    VertexOutOfRange {
        /// 0-based cell index.
        cell: usize,
        /// Offending (0-based) vertex index.
        vertex: usize,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// A cell with fewer than three vertices, or listing a vertex twice.
    #[error("cell {cell}: {msg}")]
    BadCell {
        /// 0-based cell index.
        cell: usize,
        /// What is wrong.
        msg: String,
    },
    /// A cell with zero (or numerically negligible) area.
    #[error("cell {cell} has zero area ({area:e})")]
    DegenerateCell {
        /// 0-based cell index.
        cell: usize,
        /// Its signed area.
        area: f64,
    },
    /// Two vertices at the same place.
    #[error("vertices {a} and {b} coincide at ({x}, {y})")]
    DuplicateVertex {
        /// First vertex.
        a: usize,
        /// Second vertex.
        b: usize,
        /// x coordinate.
        x: f64,
        /// y coordinate.
        y: f64,
    },
    /// A vertex used by no cell.
    #[error("vertex {vertex} is used by no cell")]
    UnusedVertex {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// An edge shared by more than two cells, or two cells that traverse an edge in the same
    /// direction (overlapping cells).
    #[error("edge ({a}, {b}): {msg}")]
    BadEdge {
        /// First vertex of the edge.
        a: usize,
        /// Second vertex of the edge.
        b: usize,
        /// What is wrong.
        msg: String,
    },
    /// A cell that is not strictly star-shaped with respect to its centroid
    /// (some d_{K,σ} ≤ 0), which HMM requires.
    #[error(
        "cell {cell} is not strictly star-shaped with respect to its centroid: d_(K,sigma) = {dist:e} on its local edge {local_edge}"
    )]
    NotStarShaped {
        /// 0-based cell index.
        cell: usize,
        /// Local edge index in the cell.
        local_edge: usize,
        /// The signed distance from the centroid to the edge line.
        dist: f64,
    },
    /// More vertices, cells, cell sides (entries of the cell vertex lists) or edges than the
    /// 32-bit ids and offsets of the mesh arrays can number.
    #[error("the mesh has {count} {what}: at most 2^32 - 2 are supported")]
    TooManyEntities {
        /// "vertices", "cells", "cell sides" or "edges".
        what: &'static str,
        /// How many there are.
        count: usize,
    },
    /// The boundary is not a union of simple closed polygons (hanging nodes, pinched vertices).
    #[error("non-conforming mesh: {0}")]
    NonConforming(String),
    /// A cell with more vertices than the limit a mesh accepts.
    #[error("cell {cell} has {n_vertices} vertices, more than the limit of {max}")]
    CellTooLarge {
        /// 0-based cell index.
        cell: usize,
        /// Its number of vertices.
        n_vertices: usize,
        /// The largest number of vertices a cell may have.
        max: usize,
    },
    /// A cell whose boundary crosses or touches itself (not a simple polygon).
    #[error(
        "cell {cell} is not a simple polygon: its sides ({}, {}) and ({}, {}) intersect",
        sides[0][0], sides[0][1], sides[1][0], sides[1][1]
    )]
    SelfIntersectingCell {
        /// 0-based cell index.
        cell: usize,
        /// The two sides that meet, as vertex pairs in the cell's order.
        sides: [[usize; 2]; 2],
    },
    /// Two edges that meet away from a common vertex (crossing, touching or overlapping): the
    /// cells overlap, or a vertex lies on an edge it is not an end of.
    #[error(
        "edges ({}, {}) of cell {} and ({}, {}) of cell {} intersect: the cells overlap",
        edges[0][0], edges[0][1], cells[0], edges[1][0], edges[1][1], cells[1]
    )]
    CrossingEdges {
        /// The two edges, as vertex pairs (smaller vertex first).
        edges: [[usize; 2]; 2],
        /// A cell of each edge.
        cells: [usize; 2],
    },
    /// The cells cover some region more than once: their areas add up to more than the area
    /// enclosed by the boundary loops (holes counted negatively).
    #[error(
        "cells overlap: their areas add up to {cells_area} but the boundary loops enclose {enclosed_area}{}",
        overlap_detail(*loop_vertex, *cell)
    )]
    OverlappingCells {
        /// Σ_K |K|.
        cells_area: f64,
        /// The area enclosed by the boundary loops, holes counted negatively.
        enclosed_area: f64,
        /// A vertex of a boundary loop that lies inside a cell, or of a hole that lies in none.
        loop_vertex: Option<usize>,
        /// The cell that contains that loop, if any.
        cell: Option<usize>,
    },
    /// Building the mesh would need more memory than the budget the caller gave.
    #[error(
        "{what} would need about {}, more than the memory budget of {}",
        human_bytes(*bytes),
        human_bytes(*budget)
    )]
    TooLarge {
        /// What was asked for.
        what: String,
        /// The estimated peak memory, in bytes.
        bytes: u64,
        /// The budget, in bytes.
        budget: u64,
    },
    /// A [`Polyhedra`](crate::mesh3d::Polyhedra) whose offset arrays are malformed (not
    /// starting at 0, decreasing, or not ending at the length of what they index).
    #[error("malformed polyhedra: {0}")]
    MalformedPolyhedra(String),
    /// A polyhedron with more faces than the limit a 3D mesh accepts.
    #[error("cell {cell} has {n_faces} faces, more than the limit of {max}")]
    PolyhedronTooLarge {
        /// 0-based cell index.
        cell: usize,
        /// Its number of faces.
        n_faces: usize,
        /// The largest number of faces a cell may have.
        max: usize,
    },
    /// A face with more vertices than the limit a 3D mesh accepts.
    #[error(
        "cell {cell}, local face {local_face}: {n_vertices} vertices, more than the limit of {max}"
    )]
    FaceTooLarge {
        /// 0-based cell index.
        cell: usize,
        /// The face's index among the faces of the cell.
        local_face: usize,
        /// Its number of vertices.
        n_vertices: usize,
        /// The largest number of vertices a face may have.
        max: usize,
    },
    /// A face with fewer than three vertices, or listing a vertex twice.
    #[error("cell {cell}, local face {local_face}: {msg}")]
    BadFace {
        /// 0-based cell index.
        cell: usize,
        /// The face's index among the faces of the cell.
        local_face: usize,
        /// What is wrong.
        msg: String,
    },
    /// Two vertices of a 3D mesh at the same place.
    #[error("vertices {a} and {b} coincide at ({}, {}, {})", point[0], point[1], point[2])]
    DuplicateVertex3 {
        /// First vertex.
        a: usize,
        /// Second vertex.
        b: usize,
        /// Their coordinates.
        point: [f64; 3],
    },
    /// A polyhedron whose faces do not close up: an edge of its faces is used `uses` times
    /// instead of twice, or twice in the same direction once the faces are oriented.
    #[error("cell {cell} is not a closed polyhedron: its edge ({a}, {b}) {msg}")]
    OpenCell {
        /// 0-based cell index.
        cell: usize,
        /// First vertex of the edge.
        a: usize,
        /// Second vertex of the edge.
        b: usize,
        /// What is wrong with it.
        msg: String,
    },
    /// A face (given by its vertices) listed by more than two cells.
    #[error("the face with vertices {vertices:?} belongs to cells {}, {} and {} (at most two)", cells[0], cells[1], cells[2])]
    OvercrowdedFace {
        /// Its vertices, sorted.
        vertices: Vec<usize>,
        /// Three of the cells listing it.
        cells: [usize; 3],
    },
    /// A polyhedron with zero or numerically negligible volume.
    #[error("cell {cell} has zero volume ({volume:e})")]
    DegenerateVolume {
        /// 0-based cell index.
        cell: usize,
        /// Its volume.
        volume: f64,
    },
    /// Two cells sharing a face that they orient the same way (both on the same side of it:
    /// the cells overlap), or list with the same vertices in different cyclic orders.
    #[error("cells {} and {} share the face with vertices {vertices:?} but {msg}", cells[0], cells[1])]
    InconsistentFace {
        /// The two cells.
        cells: [usize; 2],
        /// The face's vertex loop as the first cell lists it.
        vertices: Vec<usize>,
        /// What is wrong.
        msg: String,
    },
    /// The boundary surface of a 3D mesh is not edge-manifold: a boundary edge used by more
    /// than two boundary faces (cells meeting along an edge only, a non-conforming interface).
    #[error("non-conforming mesh: the boundary edge ({a}, {b}) {msg}")]
    NonConformingEdge {
        /// First vertex of the edge.
        a: usize,
        /// Second vertex of the edge.
        b: usize,
        /// What is wrong with it.
        msg: String,
    },
    /// A vertex where the boundary surface of a 3D mesh is pinched: its boundary faces form
    /// more than one fan (two cells touching at a vertex only, or a non-conforming interface).
    #[error(
        "non-conforming mesh: the boundary faces around vertex {vertex} form {fans} separate fans"
    )]
    NonConformingVertex {
        /// 0-based vertex index.
        vertex: usize,
        /// The number of fans of boundary faces around it.
        fans: usize,
    },
    /// A polyhedron not strictly star-shaped with respect to its centroid: d_{K,σ} ≤ 0 on one
    /// of its faces, or a triangle of a face's fan seen negatively from x_K.
    #[error(
        "cell {cell} is not strictly star-shaped with respect to its centroid: {what} = {value:e} on its local face {local_face}"
    )]
    NotStarShaped3 {
        /// 0-based cell index.
        cell: usize,
        /// Local face index in the cell.
        local_face: usize,
        /// Which quantity is not positive.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A face further from planar than the tolerance of a 3D mesh.
    #[error(
        "face {face} (of cell {cell}, vertices {vertices:?}) is warped: a vertex lies {warp:e} times its diameter off its plane, more than {tol:e}"
    )]
    WarpedFace {
        /// 0-based face index.
        face: usize,
        /// A cell of the face.
        cell: usize,
        /// Its vertex loop.
        vertices: Vec<usize>,
        /// max over its vertices v of |(v − x_σ)·n_σ| / diam(σ).
        warp: f64,
        /// The tolerance.
        tol: f64,
    },
    /// The polyhedra cover some region more than once: a vertex of the boundary surface lies
    /// strictly inside a cell.
    #[error("cells overlap: the boundary vertex {vertex} lies inside cell {cell}")]
    OverlappingPolyhedra {
        /// The boundary vertex.
        vertex: usize,
        /// The cell holding it.
        cell: usize,
    },
    /// The polyhedra cover some region more than once: an edge of the boundary surface
    /// crosses, in its interior, a boundary face of a cell that does not have the edge.
    #[error(
        "cells overlap: the edge ({a}, {b}) of cell {edge_cell} crosses face {face} of cell {face_cell}"
    )]
    EdgeThroughFace {
        /// The smaller vertex of the edge.
        a: usize,
        /// The larger vertex of the edge.
        b: usize,
        /// A cell having the edge.
        edge_cell: usize,
        /// The face crossed.
        face: usize,
        /// The cell of that face.
        face_cell: usize,
    },
    /// Cell tags that are neither absent nor one per cell.
    #[error("{tags} cell tags for {cells} cells")]
    CellTagCount {
        /// The number of tags.
        tags: usize,
        /// The number of cells.
        cells: usize,
    },
    /// A tagged face of a 3D mesh that is not one of its boundary faces.
    #[error("tagged face {index} (vertices {vertices:?}, tag {tag}) {msg}")]
    BadTaggedFace {
        /// Its index among the tagged faces.
        index: usize,
        /// Its vertex loop.
        vertices: Vec<usize>,
        /// Its tag.
        tag: i32,
        /// What is wrong.
        msg: String,
    },
}

/// The end of the message of [`MeshError::OverlappingCells`].
fn overlap_detail(loop_vertex: Option<usize>, cell: Option<usize>) -> String {
    match (loop_vertex, cell) {
        (Some(v), Some(k)) => {
            format!(" (the boundary loop through vertex {v} lies inside cell {k})")
        }
        (Some(v), None) => {
            format!(
                " (the boundary loop through vertex {v} turns clockwise but no cell surrounds it)"
            )
        }
        _ => String::new(),
    }
}

/// Failure of the active-set ("monotony") algorithm.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    /// The iteration cap was reached.
    #[error("no convergence after {iterations} linear solves; active-set sizes: {history:?}")]
    MaxIterations {
        /// Linear solves performed.
        iterations: usize,
        /// Size of the active set at each iterate.
        history: Vec<usize>,
    },
    /// An active set already visited came back (and it was not the previous one).
    #[error(
        "active-set cycling: the active set of iterate {iteration} repeats iterate {repeats}; active-set sizes: {history:?}"
    )]
    Cycling {
        /// Iterate at which the cycle was found.
        iteration: usize,
        /// Earlier iterate with the same active set.
        repeats: usize,
        /// Size of the active set at each iterate.
        history: Vec<usize>,
    },
    /// Exhaustive enumeration found no active set satisfying the KKT conditions.
    #[error(
        "exhaustive enumeration: none of the {candidates} active sets satisfies the KKT conditions"
    )]
    NoKktPoint {
        /// Active sets tried.
        candidates: usize,
    },
    /// The final iterate does not satisfy the discrete variational inequality.
    #[error("certificate failed ({quantity} = {value:e} > tolerance {tol:e})")]
    Certificate {
        /// Which quantity failed.
        quantity: String,
        /// Its value.
        value: f64,
        /// The tolerance.
        tol: f64,
    },
}
