//! Problem files: a [`Problem`] described in TOML, so that a problem is posed without writing
//! Rust. The format is documented, with a complete annotated example, in `problems/README.md`;
//! the built-in problems are files of that folder ([`builtin`]).
//!
//! ```toml
//! name = "membrane"
//! [parameters]            # overridable by the caller: load(path, &[("C".into(), -10.0)])
//! C = -5
//! [source]
//! f = "C"                 # expressions of x, y, parameters and definitions
//! [obstacle]
//! side = "lower"          # u ≥ ψ
//! barrier = "-min(x, 1 - x, y, 1 - y)"
//! ```
//!
//! Loading ([`load`], [`parse`]) checks everything that does not depend on a mesh: TOML
//! syntax (line and column), unknown keys, expressions (position in the expression, unknown
//! names, number versus condition), parameters and definitions.
//! [`ProblemFile::check_against_mesh`] checks the rest on a given mesh: tags the mesh does not
//! carry, boundary edges selected by no section or by two, points where no piece of a
//! piecewise datum applies, tensors that are not symmetric positive definite, and NaN or
//! infinite values of every datum at the points where the schemes evaluate it (see the table
//! there). [`ProblemFile::problem`] then builds the [`Problem`] whose
//! closures evaluate the compiled expressions. Every failure is an
//! [`Error::ProblemFile`] naming the file, the line and column, and the key.
//!
//! ## Pieces, boundary sections and where data is evaluated
//! - `[[diffusion.piece]]` and `[[source.piece]]`: the first piece whose `where` holds applies; a
//!   piece without `where` applies everywhere (the rest). Diffusion pieces are chosen at the
//!   cell centroid x_K (the schemes take A_K = A(x_K)); source pieces at x_K too
//!   ([`Problem::source_in_cell`]), so a vertex on an interface takes the formula of the cell
//!   being assembled.
//! - `[dirichlet]`, `[neumann]`, `[signorini]`: each selects the boundary edges whose gmsh tag is
//!   in `tags` or whose midpoint x_σ satisfies `where`; at most one section may have neither,
//!   and it takes every edge the others leave. Without any section, the whole boundary is
//!   Dirichlet with u = 0.
//!
//! Cell (surface) tags: a piece of A or f may be selected by `tags` (gmsh physical surfaces,
//! [`crate::mesh::PolyMesh::cell_tag`]) and/or `where` (a condition on the cell centroid).

//!
//! ## The modules, one job each
//! | module | job |
//! |---|---|
//! | `schema` | what the file may contain: the serde types, with the spans of the values |
//! | `build` | the raw file compiled into the data, every error located in the file |
//! | `data` | the compiled data (expressions, pieces, boundary parts) and its evaluation at a point |
//! | `checks` | the checks against a mesh ([`ProblemFile::check_against_mesh`]) |
//! | this file | the public API: [`load`], [`builtin`], [`parse`], [`ProblemFile`], [`MeshSpec`] |
//!
//! A [`MeshSpec`] is data: the layers above this one read or generate the mesh it describes.

mod build;
mod checks;
mod data;
mod schema;

use super::expr::Scope;
use super::{BoundaryKind, Problem};
use crate::error::{Error, ProblemFileErrorKind as K, Result};
use crate::mesh::{Family, Rect};
use crate::mesh3d::Cuboid;
use crate::mesh3d::generate::Family3;
use crate::scheme::SchemeKind;
use build::Cx;
use data::Data;
use schema::RawFile;
use std::any::Any;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The coordinates, in the order of a point's components: a D-dimensional problem's
/// expressions use the first D.
const COORDINATES: [&str; 3] = ["x", "y", "z"];

/// How the mesh of a problem file is obtained (`[mesh]`).
#[derive(Debug, Clone, PartialEq)]
pub enum MeshSpec {
    /// A mesh file (`.msh`, `.typ1`, `.typ2`), its path resolved against the problem file's folder.
    File(PathBuf),
    /// A generated mesh of the unit square, optionally mapped affinely onto
    /// `domain` = \[x0, x1, y0, y1\].
    Generated {
        /// The family.
        family: Family,
        /// Its level (checked by [`Family::check_level`] when the file is loaded).
        level: usize,
        /// The rectangle \[x0, x1\] × \[y0, y1\] the unit square is mapped onto.
        domain: Option<Rect>,
    },
    /// A generated 3D mesh of the unit cube, optionally mapped affinely onto
    /// `domain` = \[x0, x1, y0, y1, z0, z1\].
    Generated3 {
        /// The family.
        family: Family3,
        /// Its level (checked by [`Family3::check_level`] when the file is loaded).
        level: usize,
        /// The box the unit cube is mapped onto.
        domain: Option<Cuboid>,
    },
}

impl MeshSpec {
    /// The dimension of the mesh, when the spec says it (a generated mesh); `None` for a file.
    pub fn dimension(&self) -> Option<usize> {
        match self {
            MeshSpec::File(_) => None,
            MeshSpec::Generated { .. } => Some(2),
            MeshSpec::Generated3 { .. } => Some(3),
        }
    }
}

impl fmt::Display for MeshSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshSpec::File(p) => write!(f, "{}", p.display()),
            MeshSpec::Generated {
                family,
                level,
                domain,
            } => {
                write!(f, "{} level {level}", family.name())?;
                if let Some(d) = domain {
                    write!(f, " on {d}")?;
                }
                Ok(())
            }
            MeshSpec::Generated3 {
                family,
                level,
                domain,
            } => {
                write!(f, "3D {} level {level}", family.name())?;
                if let Some(d) = domain {
                    write!(f, " on {d}")?;
                }
                Ok(())
            }
        }
    }
}

/// A loaded, checked problem file. Build the [`Problem`] with [`ProblemFile::problem`] (2D)
/// or [`ProblemFile::problem_in`] (2D or 3D) after [`ProblemFile::check_against_mesh`] or
/// [`ProblemFile::check_against_mesh3`].
///
/// The file is compiled for both dimensions when it is loaded: expressions in x, y (2D) and in
/// x, y, z (3D), tensors and exact gradients of the matching size. It loads if it compiles for
/// at least one (for the dimension of its `[mesh]` when that is a generated family); the error
/// of the other dimension is kept and reported, with its place in the file, when the problem
/// is checked against or built for a mesh of that dimension.
#[derive(Debug, Clone)]
pub struct ProblemFile {
    /// The file (for built-in problems, `problems/NAME.toml`).
    pub path: PathBuf,
    /// The problem's name (`name`, with `{expr}` replaced by its value formatted by
    /// [`super::format_parameter`]; default: the file stem).
    pub name: String,
    /// `description`, if given.
    pub description: Option<String>,
    /// Every parameter with the value used (default or override), sorted by name.
    pub parameters: Vec<(String, f64)>,
    /// `[mesh]`, if given.
    pub mesh: Option<MeshSpec>,
    /// `scheme`, if given.
    pub scheme: Option<SchemeKind>,
    data2: std::result::Result<Arc<Data<2>>, Stored>,
    data3: std::result::Result<Arc<Data<3>>, Stored>,
}

/// A problem-file error kept for later (the file did not compile for one dimension).
#[derive(Debug, Clone)]
struct Stored {
    line: usize,
    column: usize,
    kind: K,
    msg: String,
}

impl Stored {
    fn new(e: Error) -> Stored {
        match e {
            Error::ProblemFile {
                line,
                column,
                kind,
                msg,
                ..
            } => Stored {
                line,
                column,
                kind,
                msg,
            },
            other => Stored {
                line: 0,
                column: 0,
                kind: K::Schema,
                msg: other.to_string(),
            },
        }
    }

    fn error(&self, path: &Path) -> Error {
        Error::ProblemFile {
            path: path.to_path_buf(),
            line: self.line,
            column: self.column,
            kind: self.kind,
            msg: self.msg.clone(),
        }
    }
}

/// The file compiled for meshes of dimension D: the scope of the first D coordinates with the
/// parameters and definitions, then the data.
fn compile<const D: usize>(
    cx: &Cx,
    raw: &RawFile,
    parameters: &[(String, f64)],
) -> Result<(Data<D>, Scope)> {
    let mut scope = Scope::new(&COORDINATES[..D]);
    for (name, v) in parameters {
        let loc = cx.loc(&format!("parameters.{name}"), raw.parameters[name].span());
        scope
            .set_constant(name, *v)
            .map_err(|m| cx.at(K::Parameter, &loc, m))?;
    }
    cx.definitions(&raw.definitions, &mut scope)?;
    let data = cx.data::<D>(raw, &scope)?;
    Ok((data, scope))
}

/// The built-in problems, as problem files compiled into the library: `(name, TOML text)`.
pub const BUILTIN: [(&str, &str); 4] = [
    ("test1", include_str!("../../../problems/test1.toml")),
    ("test2", include_str!("../../../problems/test2.toml")),
    ("test3", include_str!("../../../problems/test3.toml")),
    (
        "fvca5-1.1",
        include_str!("../../../problems/fvca5-1.1.toml"),
    ),
];

/// Loads the problem file at `path`, with the parameter values `overrides` replacing the
/// defaults of `[parameters]` (an exact name, or a unique case-insensitive match; any other name
/// is an error).
pub fn load(path: impl AsRef<Path>, overrides: &[(String, f64)]) -> Result<ProblemFile> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text =
        String::from_utf8(bytes).map_err(|e| not_utf8(path, e.as_bytes(), e.utf8_error()))?;
    parse(&text, path, overrides)
}

/// The error of a problem file that is not UTF-8: the line and column (in characters) of the
/// first byte that is not, and its byte offset.
fn not_utf8(path: &Path, bytes: &[u8], e: std::str::Utf8Error) -> Error {
    let offset = e.valid_up_to();
    let valid = std::str::from_utf8(&bytes[..offset]).unwrap_or_default();
    let line_start = valid.rfind('\n').map_or(0, |i| i + 1);
    Error::ProblemFile {
        path: path.to_path_buf(),
        line: valid.matches('\n').count() + 1,
        column: valid[line_start..].chars().count() + 1,
        kind: K::Syntax,
        msg: format!(
            "byte 0x{:02x} at byte offset {offset} is not UTF-8 (a problem file is UTF-8 text)",
            bytes[offset]
        ),
    }
}

/// One of the [`BUILTIN`] problems, by name.
pub fn builtin(name: &str, overrides: &[(String, f64)]) -> Result<ProblemFile> {
    let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
        return Err(Error::InvalidData(format!(
            "unknown problem '{name}' (expected one of: {})",
            names.join(", ")
        )));
    };
    parse(
        text,
        &Path::new("problems").join(format!("{name}.toml")),
        overrides,
    )
}

/// Parses the text of a problem file; `path` is used in messages and to resolve `[mesh] file`.
pub fn parse(text: &str, path: &Path, overrides: &[(String, f64)]) -> Result<ProblemFile> {
    let cx = Cx { path, text };
    // syntax first, so that a syntax error is reported as such
    if let Err(e) = toml::from_str::<toml::Table>(text) {
        return Err(cx.toml_error(K::Syntax, &e));
    }
    let raw: RawFile = toml::from_str(text).map_err(|e| {
        let kind = if e.message().starts_with("unknown field") {
            K::UnknownKey
        } else {
            K::Schema
        };
        cx.toml_error(kind, &e)
    })?;
    let parameters = cx.parameters(&raw.parameters, overrides)?;
    let mesh = raw.mesh.as_ref().map(|m| cx.mesh(m)).transpose();
    let wanted = mesh
        .as_ref()
        .ok()
        .and_then(|m| m.as_ref())
        .and_then(MeshSpec::dimension);
    let (c2, c3) = (
        compile::<2>(&cx, &raw, &parameters),
        compile::<3>(&cx, &raw, &parameters),
    );
    // the error of the dimension the file's mesh has; else the file must compile for one
    let (c2, c3) = match (wanted, c2, c3) {
        (Some(3), _, Err(e)) | (Some(2), Err(e), _) | (_, Err(e), Err(_)) => return Err(e),
        (_, c2, c3) => (c2, c3),
    };
    let scope = match (&c2, &c3) {
        (Ok((_, s)), _) | (Err(_), Ok((_, s))) => s,
        (Err(e), Err(_)) => return Err(Error::Internal(format!("both dimensions failed: {e}"))),
    };
    let name = match &raw.name {
        Some(n) => cx.name(n, scope)?,
        None => path
            .file_stem()
            .map_or_else(|| "problem".into(), |s| s.to_string_lossy().into_owned()),
    };
    Ok(ProblemFile {
        path: path.to_path_buf(),
        name,
        description: raw.description.clone(),
        parameters,
        mesh: mesh?,
        scheme: raw.scheme,
        data2: c2.map(|(d, _)| Arc::new(d)).map_err(Stored::new),
        data3: c3.map(|(d, _)| Arc::new(d)).map_err(Stored::new),
    })
}

impl ProblemFile {
    /// The value of parameter `name` (exact name).
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| *v)
    }

    /// Whether the file compiled for meshes of dimension `d` (2 or 3).
    pub fn compiles_for(&self, d: usize) -> bool {
        match d {
            2 => self.data2.is_ok(),
            3 => self.data3.is_ok(),
            _ => false,
        }
    }

    /// The data compiled for dimension D, or the error (with its place in the file) that
    /// prevented it.
    fn data<const D: usize>(&self) -> Result<Arc<Data<D>>> {
        let any: std::result::Result<Arc<dyn Any + Send + Sync>, &Stored> = match D {
            2 => self.data2.as_ref().map(|d| Arc::clone(d) as _),
            3 => self.data3.as_ref().map(|d| Arc::clone(d) as _),
            _ => {
                return Err(Error::InvalidData(format!(
                    "problems are posed in 2 or 3 dimensions, not {D}"
                )));
            }
        };
        any.map_err(|s| s.error(&self.path))?
            .downcast::<Data<D>>()
            .map_err(|_| Error::Internal("problem data of the wrong dimension".into()))
    }

    /// Builds the 2D [`Problem`] ([`ProblemFile::problem_in`] for D = 2). Run
    /// [`ProblemFile::check_against_mesh`] on the mesh first: that reports a file that is not a
    /// 2D problem (a `z`, a 3×3 tensor) with its place; built without that check, such a file
    /// gives a problem whose source is NaN everywhere, which the assembler rejects.
    pub fn problem(&self) -> Problem {
        self.problem_in::<2>()
            .unwrap_or_else(|_| Problem::new(&self.name, Box::new(|_| f64::NAN)))
    }

    /// Builds the [`Problem<D>`]: closures that evaluate the compiled expressions (cheap; call
    /// it once per solve). `Err` (a [`Error::ProblemFile`] with its place) if the file is not
    /// a D-dimensional problem. Run [`ProblemFile::check_against_mesh`] (2D) or
    /// [`ProblemFile::check_against_mesh3`] (3D) on the mesh first: on a mesh it has not
    /// checked, a boundary face no section selects is taken as Dirichlet, and a point no piece
    /// covers gets NaN data (which the assembler rejects).
    pub fn problem_in<const D: usize>(&self) -> Result<Problem<D>> {
        let data = self.data::<D>()?;
        let d = Arc::clone(&data);
        let mut pb = match data.constant_source() {
            Some(c) => Problem::new(&self.name, Box::new(move |_| c)),
            None => Problem::new(&self.name, Box::new(move |p| d.source_at(p, p, 0))),
        };
        if data.source.iter().any(|p| p.cond.is_some()) {
            let d = Arc::clone(&data);
            pb = pb.with_source_in_cell(Box::new(move |p, xk| d.source_at(p, xk, 0)));
        }
        if !data.diffusion.is_empty() {
            let d = Arc::clone(&data);
            pb = pb.with_diffusion(Box::new(move |p| d.diffusion_at(p, 0)));
        }
        if data.uses_cell_tags() {
            let (d, e) = (Arc::clone(&data), Arc::clone(&data));
            pb = pb
                .with_diffusion_by_tag(Box::new(move |xk, t| d.diffusion_at(xk, t)))
                .with_source_by_tag(Box::new(move |p, xk, t| e.source_at(p, xk, t)));
        }
        if data.has_boundary_sections() {
            let d = Arc::clone(&data);
            pb = pb.with_boundary(move |x, tag| {
                d.boundary_at(x, tag).unwrap_or(BoundaryKind::Dirichlet)
            });
        }
        Ok(with_values(pb, &data))
    }
}

/// The Dirichlet and Neumann data, the barrier and the exact solution of `data` set on `pb`.
fn with_values<const D: usize>(mut pb: Problem<D>, data: &Data<D>) -> Problem<D> {
    if let Some(g) = &data.dirichlet {
        let g = g.expr.clone();
        pb = pb.with_dirichlet(Box::new(move |p| g.eval(&p)));
    }
    if let Some(g) = &data.neumann {
        let g = g.expr.clone();
        pb = pb.with_neumann(Box::new(move |p| g.eval(&p)));
    }
    if let Some((kind, side, b)) = &data.constraint {
        let b = b.expr.clone();
        pb = pb.with_constraint(*kind, *side, Box::new(move |p| b.eval(&p)));
    }
    if let Some((u, grad)) = &data.exact {
        let (u, grad) = (u.expr.clone(), grad.clone());
        pb = pb.with_exact(
            Box::new(move |p| u.eval(&p)),
            Box::new(move |p| grad.each_ref().map(|g| g.at(p))),
        );
    }
    pb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_that_is_not_utf8_is_refused_at_its_line_column_and_byte() {
        let path =
            std::env::temp_dir().join(format!("gradvi-not-utf8-{}.toml", std::process::id()));
        // line 2, after "é = " (4 characters, 5 bytes): a Latin-1 é
        std::fs::write(&path, b"[mesh]\n\xc3\xa9 = \xe9t\xe9\n").unwrap();
        let e = load(&path, &[]).unwrap_err();
        std::fs::remove_file(&path).ok();
        match &e {
            Error::ProblemFile {
                line, column, kind, ..
            } => assert_eq!((*line, *column, *kind), (2, 5, K::Syntax), "{e}"),
            other => panic!("{other}"),
        }
        let said = e.to_string();
        assert!(
            said.ends_with(
                ":2:5: byte 0xe9 at byte offset 12 is not UTF-8 (a problem file is UTF-8 text)"
            ),
            "{said}"
        );
    }
}
