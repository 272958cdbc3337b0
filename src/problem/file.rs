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

use super::expr::{Expr, ExprError, ExprErrorKind, Kind, Scope};
use super::{BoundaryKind, ConstraintKind, Problem, Side, check_tensor};
use crate::error::{Error, ProblemFileErrorKind as K, Result};
use crate::mesh::generate::Family;
use crate::mesh::{MemoryBudget, Point, PolyMesh, Rect};
use crate::scheme::{SchemeKind, Tensor};
use rayon::prelude::*;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use toml::Spanned;

// ------------------------------------------------------------------------------------------
// The schema: what the TOML file may contain (unknown keys are rejected everywhere).

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    name: Option<Spanned<String>>,
    description: Option<String>,
    scheme: Option<SchemeKind>,
    mesh: Option<Spanned<RawMesh>>,
    #[serde(default)]
    parameters: BTreeMap<String, Spanned<f64>>,
    #[serde(default)]
    definitions: BTreeMap<String, Spanned<Src>>,
    diffusion: Option<Spanned<RawDiffusion>>,
    source: Option<Spanned<RawSource>>,
    dirichlet: Option<RawDirichlet>,
    neumann: Option<RawNeumann>,
    signorini: Option<RawSignorini>,
    obstacle: Option<RawObstacle>,
    exact: Option<RawExact>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Option<String>,
    generate: Option<String>,
    level: Option<usize>,
    domain: Option<[f64; 4]>,
}

/// A datum given whole (`KEY = ...`) or by pieces (`[[SECTION.piece]]`, each with `where`,
/// `tags` and `KEY`): the section's struct, its piece's struct, and their [`Piecewise`] view.
macro_rules! piecewise_section {
    ($section:ident, $piece:ident, $name:literal, $key:literal, $ty:ty) => {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $section {
            #[serde(rename = $key)]
            value: Option<Spanned<$ty>>,
            piece: Option<Vec<$piece>>,
        }

        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $piece {
            #[serde(rename = "where")]
            cond: Option<Spanned<Src>>,
            tags: Option<Spanned<Vec<i32>>>,
            #[serde(rename = $key)]
            value: Spanned<$ty>,
        }

        impl Piecewise for $section {
            type Value = $ty;
            const SECTION: &'static str = $name;
            const KEY: &'static str = $key;
            fn whole(&self) -> Option<&Spanned<$ty>> {
                self.value.as_ref()
            }
            fn pieces(&self) -> Option<Vec<PieceSrc<'_, $ty>>> {
                let pieces = self.piece.as_ref()?;
                Some(
                    pieces
                        .iter()
                        .map(|p| (&p.cond, &p.tags, &p.value))
                        .collect(),
                )
            }
        }
    };
}

/// One piece as written: its condition (`where`), its cell tags and its value.
type PieceSrc<'a, T> = (
    &'a Option<Spanned<Src>>,
    &'a Option<Spanned<Vec<i32>>>,
    &'a Spanned<T>,
);

/// A piecewise datum as written (made by `piecewise_section!`).
trait Piecewise {
    /// The value as written (an expression, or a tensor).
    type Value;
    /// The section ("diffusion").
    const SECTION: &'static str;
    /// The key of the value ("A").
    const KEY: &'static str;
    /// The value, if given whole.
    fn whole(&self) -> Option<&Spanned<Self::Value>>;
    /// The pieces, if given by pieces.
    fn pieces(&self) -> Option<Vec<PieceSrc<'_, Self::Value>>>;
}

piecewise_section!(RawDiffusion, RawDiffusionPiece, "diffusion", "A", TensorSrc);
piecewise_section!(RawSource, RawSourcePiece, "source", "f", Src);

/// A boundary section: the edges it selects (`tags`, `where`), then its own keys.
macro_rules! boundary_section {
    ($name:ident { $($key:ident: $ty:ty),* }) => {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $name {
            tags: Option<Spanned<Vec<i32>>>,
            #[serde(rename = "where")]
            cond: Option<Spanned<Src>>,
            $($key: $ty,)*
        }
    };
}

boundary_section!(RawDirichlet { value: Option<Spanned<Src>> });
boundary_section!(RawNeumann { flux: Option<Spanned<Src>> });
boundary_section!(RawSignorini { side: RawSide, barrier: Spanned<Src> });

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObstacle {
    side: RawSide,
    barrier: Spanned<Src>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExact {
    u: Spanned<Src>,
    grad: [Spanned<Src>; 2],
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum RawSide {
    Upper,
    Lower,
}

/// An expression as written: a TOML number or a string.
#[derive(Debug, Clone)]
enum Src {
    Number(f64),
    Text(String),
}

struct SrcVisitor;

impl Visitor<'_> for SrcVisitor {
    type Value = Src;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an expression in a string")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Src, E> {
        Ok(Src::Text(v.to_string()))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Src, E> {
        Ok(Src::Number(v as f64))
    }
}

impl<'de> Deserialize<'de> for Src {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(SrcVisitor)
    }
}

/// A diffusion coefficient as written: a scalar a (A = a I) or a 2×2 array.
enum TensorSrc {
    Scalar(Src),
    Matrix([[Spanned<Src>; 2]; 2]),
}

struct TensorVisitor;

impl<'de> Visitor<'de> for TensorVisitor {
    type Value = TensorSrc;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number, an expression in a string, or a 2x2 array [[a11, a12], [a21, a22]]")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_str(v).map(TensorSrc::Scalar)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_f64(v).map(TensorSrc::Scalar)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_i64(v).map(TensorSrc::Scalar)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<TensorSrc, E> {
        SrcVisitor.visit_u64(v).map(TensorSrc::Scalar)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<TensorSrc, A::Error> {
        let r0: [Spanned<Src>; 2] = seq
            .next_element()?
            .ok_or_else(|| de::Error::invalid_length(0, &self))?;
        let r1: [Spanned<Src>; 2] = seq
            .next_element()?
            .ok_or_else(|| de::Error::invalid_length(1, &self))?;
        if seq.next_element::<de::IgnoredAny>()?.is_some() {
            return Err(de::Error::invalid_length(3, &self));
        }
        Ok(TensorSrc::Matrix([r0, r1]))
    }
}

impl<'de> Deserialize<'de> for TensorSrc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        d.deserialize_any(TensorVisitor)
    }
}

// ------------------------------------------------------------------------------------------
// The compiled problem.

/// Where in the file a datum comes from: its key and the 1-based place of its value.
#[derive(Debug, Clone)]
struct Loc {
    key: String,
    line: usize,
    column: usize,
}

/// A compiled expression and where it was written.
#[derive(Debug, Clone)]
struct Field {
    expr: Expr,
    loc: Loc,
}

impl Field {
    #[inline]
    fn at(&self, p: Point) -> f64 {
        self.expr.eval(&p)
    }
}

/// A(x): a I, a full matrix of expressions, or a constant matrix (when every entry is
/// constant); `Loc` is where the whole value is written.
#[derive(Debug, Clone)]
enum TensorField {
    Scalar(Field),
    Matrix(Box<[[Field; 2]; 2]>, Loc),
    Constant(Tensor, Loc),
}

impl TensorField {
    /// A full matrix, or a constant one if every entry is.
    fn matrix(m: [[Field; 2]; 2], loc: Loc) -> TensorField {
        let c = |i: usize, j: usize| m[i][j].expr.as_constant();
        match (c(0, 0), c(0, 1), c(1, 0), c(1, 1)) {
            (Some(a), Some(b), Some(c), Some(d)) => TensorField::Constant([[a, b], [c, d]], loc),
            _ => TensorField::Matrix(Box::new(m), loc),
        }
    }

    #[inline]
    fn at(&self, p: Point) -> Tensor {
        match self {
            TensorField::Scalar(a) => {
                let c = a.at(p);
                [[c, 0.0], [0.0, c]]
            }
            TensorField::Matrix(m, _) => [
                [m[0][0].at(p), m[0][1].at(p)],
                [m[1][0].at(p), m[1][1].at(p)],
            ],
            TensorField::Constant(a, _) => *a,
        }
    }

    fn loc(&self) -> &Loc {
        match self {
            TensorField::Scalar(a) => &a.loc,
            TensorField::Matrix(_, loc) | TensorField::Constant(_, loc) => loc,
        }
    }
}

/// One piece of a piecewise datum: it applies on the cells whose tag is in `tags` (any cell
/// if empty) and where `cond` holds at the centroid (everywhere if `None`).
#[derive(Debug, Clone)]
struct Piece<T> {
    cond: Option<Field>,
    tags: Vec<i32>,
    /// Where `tags` is written (for errors).
    tags_loc: Option<Loc>,
    value: T,
}

/// The first piece that applies at centroid `p` of a cell tagged `tag`; `None` if none does,
/// or if a condition is NaN there.
fn select<T>(pieces: &[Piece<T>], p: Point, tag: i32) -> Option<&T> {
    for piece in pieces {
        if !piece.tags.is_empty() && !piece.tags.contains(&tag) {
            continue;
        }
        match piece.cond.as_ref().map(|c| c.expr.holds(&p)) {
            None | Some(Some(true)) => return Some(&piece.value),
            Some(None) => return None,
            Some(Some(false)) => {}
        }
    }
    None
}

/// A boundary section with an explicit selection (`tags` or `where`).
#[derive(Debug, Clone)]
struct Part {
    kind: BoundaryKind,
    section: &'static str,
    tags: Vec<i32>,
    tags_loc: Option<Loc>,
    cond: Option<Field>,
}

impl Part {
    /// Whether it selects the edge with midpoint `x` and tag `tag` (`None`: its condition is NaN).
    fn selects(&self, x: Point, tag: i32) -> Option<bool> {
        if self.tags.contains(&tag) {
            return Some(true);
        }
        match &self.cond {
            Some(c) => c.expr.holds(&x),
            None => Some(false),
        }
    }
}

/// Everything the closures of the [`Problem`] evaluate.
#[derive(Debug)]
struct Data {
    /// Empty: A = I.
    diffusion: Vec<Piece<TensorField>>,
    /// Empty: f = 0.
    source: Vec<Piece<Field>>,
    parts: Vec<Part>,
    /// The kind of the section without selection, if any.
    rest: Option<(BoundaryKind, &'static str)>,
    dirichlet: Option<Field>,
    neumann: Option<Field>,
    constraint: Option<(ConstraintKind, Side, Field)>,
    exact: Option<(Field, [Field; 2])>,
}

impl Data {
    fn diffusion_at(&self, p: Point, tag: i32) -> Tensor {
        if self.diffusion.is_empty() {
            return [[1.0, 0.0], [0.0, 1.0]];
        }
        select(&self.diffusion, p, tag).map_or([[f64::NAN; 2]; 2], |a| a.at(p))
    }

    /// f at `p` with the piece chosen at `xk` (NaN where no piece applies).
    fn source_at(&self, p: Point, xk: Point, tag: i32) -> f64 {
        if self.source.is_empty() {
            return 0.0;
        }
        select(&self.source, xk, tag).map_or(f64::NAN, |f| f.at(p))
    }

    /// f's value if it is one constant everywhere (no piece, or one piece without tags or
    /// condition whose value is constant): its closure then skips the pieces.
    fn constant_source(&self) -> Option<f64> {
        match self.source.as_slice() {
            [] => Some(0.0),
            [p] if p.tags.is_empty() && p.cond.is_none() => p.value.expr.as_constant(),
            _ => None,
        }
    }

    /// Whether some piece of A or f is selected by cell tags.
    fn uses_cell_tags(&self) -> bool {
        let tagged = |t: &[i32]| !t.is_empty();
        self.diffusion.iter().any(|p| tagged(&p.tags))
            || self.source.iter().any(|p| tagged(&p.tags))
    }

    /// The section that takes the edge (midpoint `x`, tag `tag`): the first explicit one that
    /// selects it, else the rest; `None` if none does.
    fn boundary_at(&self, x: Point, tag: i32) -> Option<BoundaryKind> {
        self.parts
            .iter()
            .find(|p| p.selects(x, tag) == Some(true))
            .map(|p| p.kind)
            .or(self.rest.map(|r| r.0))
    }

    fn has_boundary_sections(&self) -> bool {
        !self.parts.is_empty() || self.rest.is_some()
    }
}

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
        /// Its level (see [`crate::mesh::generate`]).
        level: usize,
        /// The rectangle \[x0, x1\] × \[y0, y1\] the unit square is mapped onto.
        domain: Option<Rect>,
    },
}

impl MeshSpec {
    /// Reads or generates the mesh, within `budget`.
    pub fn build(&self, budget: MemoryBudget) -> Result<PolyMesh> {
        match self {
            MeshSpec::File(p) => crate::mesh::io::read_mesh(p, budget),
            MeshSpec::Generated {
                family,
                level,
                domain,
            } => match domain {
                None => family.generate(*level, budget),
                Some(d) => family.generate_on(*level, *d, budget),
            },
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
        }
    }
}

/// A loaded, checked problem file. Build the [`Problem`] with [`ProblemFile::problem`] after
/// [`ProblemFile::check_against_mesh`].
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
    data: Arc<Data>,
}

/// The built-in problems, as problem files compiled into the library: `(name, TOML text)`.
pub const BUILTIN: [(&str, &str); 4] = [
    ("test1", include_str!("../../problems/test1.toml")),
    ("test2", include_str!("../../problems/test2.toml")),
    ("test3", include_str!("../../problems/test3.toml")),
    ("fvca5-1.1", include_str!("../../problems/fvca5-1.1.toml")),
];

/// Loads the problem file at `path`, with the parameter values `overrides` replacing the
/// defaults of `[parameters]` (an exact name, or a unique case-insensitive match; any other name
/// is an error).
pub fn load(path: impl AsRef<Path>, overrides: &[(String, f64)]) -> Result<ProblemFile> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path, overrides)
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
    let mut scope = Scope::new(&["x", "y"]);
    for (name, v) in &parameters {
        let loc = cx.loc(&format!("parameters.{name}"), raw.parameters[name].span());
        scope
            .set_constant(name, *v)
            .map_err(|m| cx.at(K::Parameter, &loc, m))?;
    }
    cx.definitions(&raw.definitions, &mut scope)?;
    let data = cx.data(&raw, &scope)?;
    let name = match &raw.name {
        Some(n) => cx.name(n, &scope)?,
        None => path
            .file_stem()
            .map_or_else(|| "problem".into(), |s| s.to_string_lossy().into_owned()),
    };
    Ok(ProblemFile {
        path: path.to_path_buf(),
        name,
        description: raw.description.clone(),
        parameters,
        mesh: raw.mesh.as_ref().map(|m| cx.mesh(m)).transpose()?,
        scheme: raw.scheme,
        data: Arc::new(data),
    })
}

// ------------------------------------------------------------------------------------------
// Compilation of the raw file, with errors located in the file.

/// The file being compiled.
struct Cx<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Cx<'_> {
    fn error(&self, kind: K, line: usize, column: usize, msg: String) -> Error {
        Error::ProblemFile {
            path: self.path.to_path_buf(),
            line,
            column,
            kind,
            msg,
        }
    }

    fn at(&self, kind: K, loc: &Loc, msg: String) -> Error {
        self.error(kind, loc.line, loc.column, format!("{}: {msg}", loc.key))
    }

    /// 1-based line and column (in characters) of byte `offset`.
    fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let start = before.rfind('\n').map_or(0, |i| i + 1);
        (line, before[start..].chars().count() + 1)
    }

    fn loc(&self, key: &str, span: Range<usize>) -> Loc {
        let (line, column) = self.line_col(span.start);
        Loc {
            key: key.to_string(),
            line,
            column,
        }
    }

    fn toml_error(&self, kind: K, e: &toml::de::Error) -> Error {
        let (line, column) = e.span().map_or((0, 0), |s| self.line_col(s.start));
        let msg = e.message().trim_end().replace('\n', "; ");
        self.error(kind, line, column, msg)
    }

    /// Compiles an expression of type `kind` written at `src`; errors point at the offending
    /// character in the file when the string has no escapes.
    fn expr(&self, key: &str, src: &Spanned<Src>, scope: &Scope, kind: Kind) -> Result<Field> {
        let loc = self.loc(key, src.span());
        let text = match src.get_ref() {
            Src::Number(v) if kind == Kind::Number => {
                return Ok(Field {
                    expr: Expr::constant(*v),
                    loc,
                });
            }
            Src::Number(v) => format!("{v:?}"),
            Src::Text(t) => t.clone(),
        };
        match Expr::parse_kind(&text, scope, Some(kind)) {
            Ok(expr) => Ok(Field { expr, loc }),
            Err(e) => Err(self.expr_error(&loc, src.span(), &text, &e)),
        }
    }

    fn expr_error(&self, loc: &Loc, span: Range<usize>, text: &str, e: &ExprError) -> Error {
        // the value is written "text" or 'text' verbatim: point at the character itself
        let raw = self.text.get(span.clone()).unwrap_or("");
        let verbatim = raw.len() == text.len() + 2 && raw.get(1..raw.len() - 1) == Some(text);
        let (line, column) = if verbatim {
            let byte = text
                .char_indices()
                .nth(e.position.saturating_sub(1))
                .map_or(text.len(), |(b, _)| b);
            self.line_col(span.start + 1 + byte)
        } else {
            (loc.line, loc.column)
        };
        self.error(
            K::Expression,
            line,
            column,
            format!("{}: \"{text}\" {e}", loc.key),
        )
    }

    fn expr_opt(
        &self,
        key: &str,
        src: &Option<Spanned<Src>>,
        scope: &Scope,
        kind: Kind,
    ) -> Result<Option<Field>> {
        src.as_ref()
            .map(|s| self.expr(key, s, scope, kind))
            .transpose()
    }

    /// The parameters with their values: defaults, replaced by the overrides.
    fn parameters(
        &self,
        raw: &BTreeMap<String, Spanned<f64>>,
        overrides: &[(String, f64)],
    ) -> Result<Vec<(String, f64)>> {
        let mut values: Vec<(String, f64)> =
            raw.iter().map(|(k, v)| (k.clone(), *v.get_ref())).collect();
        for (name, v) in &values {
            if !v.is_finite() {
                let loc = self.loc(&format!("parameters.{name}"), raw[name].span());
                return Err(self.at(K::Parameter, &loc, format!("the value {v} is not finite")));
            }
        }
        for (name, v) in overrides {
            let exact = values.iter().position(|(k, _)| k == name);
            let folded: Vec<usize> = (0..values.len())
                .filter(|&i| values[i].0.eq_ignore_ascii_case(name))
                .collect();
            let i = match (exact, folded.as_slice()) {
                (Some(i), _) => i,
                (None, [i]) => *i,
                _ => {
                    let known: Vec<&str> = values.iter().map(|(k, _)| k.as_str()).collect();
                    return Err(self.error(
                        K::Parameter,
                        0,
                        0,
                        format!(
                            "the problem has no parameter '{name}' (its parameters: {})",
                            if known.is_empty() {
                                "none".into()
                            } else {
                                known.join(", ")
                            }
                        ),
                    ));
                }
            };
            if !v.is_finite() {
                return Err(self.error(
                    K::Parameter,
                    0,
                    0,
                    format!("the value {v} given for parameter '{name}' is not finite"),
                ));
            }
            values[i].1 = *v;
        }
        Ok(values)
    }

    /// Compiles the definitions in dependency order (each may use the parameters and the other
    /// definitions); a cycle is an error.
    fn definitions(&self, raw: &BTreeMap<String, Spanned<Src>>, scope: &mut Scope) -> Result<()> {
        let mut pending: Vec<&String> = raw.keys().collect();
        while !pending.is_empty() {
            let mut deferred = Vec::new();
            for name in &pending {
                let key = format!("definitions.{name}");
                let src = &raw[*name];
                let text = match src.get_ref() {
                    Src::Number(v) => format!("{v:?}"),
                    Src::Text(t) => t.clone(),
                };
                match Expr::parse_kind(&text, scope, None) {
                    Ok(e) => {
                        let loc = self.loc(&key, src.span());
                        scope
                            .define(name, &e)
                            .map_err(|m| self.at(K::Parameter, &loc, m))?;
                    }
                    Err(ExprError {
                        kind: ExprErrorKind::UnknownVariable(v),
                        ..
                    }) if pending.iter().any(|p| **p == v && *p != *name) => deferred.push(*name),
                    Err(e) => {
                        let loc = self.loc(&key, src.span());
                        return Err(self.expr_error(&loc, src.span(), &text, &e));
                    }
                }
            }
            if deferred.len() == pending.len() {
                let names: Vec<&str> = deferred.iter().map(|s| s.as_str()).collect();
                let loc = self.loc(
                    &format!("definitions.{}", names[0]),
                    raw[deferred[0]].span(),
                );
                return Err(self.at(
                    K::Parameter,
                    &loc,
                    format!(
                        "the definitions {} depend on each other in a cycle",
                        names.join(", ")
                    ),
                ));
            }
            pending = deferred;
        }
        Ok(())
    }

    /// `name`, with every `{expr}` replaced by the value of the (constant) expression.
    fn name(&self, raw: &Spanned<String>, scope: &Scope) -> Result<String> {
        let loc = self.loc("name", raw.span());
        let mut out = String::new();
        let mut rest = raw.get_ref().as_str();
        while let Some(i) = rest.find('{') {
            out.push_str(&rest[..i]);
            let Some(j) = rest[i..].find('}') else {
                return Err(self.at(K::Schema, &loc, "a '{' without '}'".into()));
            };
            let inner = &rest[i + 1..i + j];
            let value = Expr::parse(inner, scope)
                .map_err(|e| self.at(K::Expression, &loc, format!("\"{inner}\" {e}")))?;
            let Some(v) = value.as_constant() else {
                return Err(self.at(
                    K::Expression,
                    &loc,
                    format!("\"{inner}\" depends on x or y: a name needs a constant"),
                ));
            };
            out.push_str(&super::format_parameter(v));
            rest = &rest[i + j + 1..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn mesh(&self, raw: &Spanned<RawMesh>) -> Result<MeshSpec> {
        let loc = self.loc("mesh", raw.span());
        let m = raw.get_ref();
        let bad = |msg: &str| self.at(K::Mesh, &loc, msg.to_string());
        match (&m.file, &m.generate) {
            (Some(file), None) => {
                if m.level.is_some() || m.domain.is_some() {
                    return Err(bad(
                        "'level' and 'domain' go with 'generate', not with 'file'",
                    ));
                }
                let dir = self.path.parent().unwrap_or(Path::new(""));
                Ok(MeshSpec::File(dir.join(file)))
            }
            (None, Some(g)) => {
                let family: Family = g.parse().map_err(|e: Error| bad(&e.to_string()))?;
                let level = m.level.ok_or_else(|| bad("'generate' needs a 'level'"))?;
                family.check_level(level).map_err(|e| bad(&e.to_string()))?;
                // the file writes the x range, then the y range
                let domain = m
                    .domain
                    .map(|[x0, x1, y0, y1]| Rect::new([x0, x1], [y0, y1]));
                if domain.is_some_and(|d| !d.is_proper()) {
                    return Err(bad("'domain' = [x0, x1, y0, y1] needs x0 < x1 and y0 < y1"));
                }
                Ok(MeshSpec::Generated {
                    family,
                    level,
                    domain,
                })
            }
            _ => Err(bad("give either 'file' or 'generate' (with 'level')")),
        }
    }

    fn data(&self, raw: &RawFile, scope: &Scope) -> Result<Data> {
        let (parts, rest) = self.boundary(raw, scope)?;
        let constraint = match (&raw.obstacle, &raw.signorini) {
            (Some(_), Some(_)) => {
                return Err(self.error(
                    K::Schema,
                    0,
                    0,
                    "a problem has one barrier: [obstacle] and [signorini] cannot both be given"
                        .into(),
                ));
            }
            (Some(o), None) => Some((
                ConstraintKind::Obstacle,
                side(o.side),
                self.expr("obstacle.barrier", &o.barrier, scope, Kind::Number)?,
            )),
            (None, Some(s)) => Some((
                ConstraintKind::Signorini,
                side(s.side),
                self.expr("signorini.barrier", &s.barrier, scope, Kind::Number)?,
            )),
            (None, None) => None,
        };
        let exact = match &raw.exact {
            Some(e) => Some((
                self.expr("exact.u", &e.u, scope, Kind::Number)?,
                [
                    self.expr("exact.grad[0]", &e.grad[0], scope, Kind::Number)?,
                    self.expr("exact.grad[1]", &e.grad[1], scope, Kind::Number)?,
                ],
            )),
            None => None,
        };
        Ok(Data {
            diffusion: self
                .piecewise(&raw.diffusion, scope, |key, a| self.tensor(key, a, scope))?,
            source: self.piecewise(&raw.source, scope, |key, f| {
                self.expr(key, f, scope, Kind::Number)
            })?,
            parts,
            rest,
            dirichlet: match &raw.dirichlet {
                Some(d) => self.expr_opt("dirichlet.value", &d.value, scope, Kind::Number)?,
                None => None,
            },
            neumann: match &raw.neumann {
                Some(n) => self.expr_opt("neumann.flux", &n.flux, scope, Kind::Number)?,
                None => None,
            },
            constraint,
            exact,
        })
    }

    fn tensor(&self, key: &str, raw: &Spanned<TensorSrc>, scope: &Scope) -> Result<TensorField> {
        let span = raw.span();
        let sub = |s: &Src| Spanned::new(span.clone(), s.clone());
        match raw.get_ref() {
            TensorSrc::Scalar(s) => {
                let a = self.expr(key, &sub(s), scope, Kind::Number)?;
                Ok(match a.expr.as_constant() {
                    Some(c) => TensorField::Constant([[c, 0.0], [0.0, c]], a.loc),
                    None => TensorField::Scalar(a),
                })
            }
            TensorSrc::Matrix(m) => {
                let e = |i: usize, j: usize| {
                    self.expr(&format!("{key}[{i}][{j}]"), &m[i][j], scope, Kind::Number)
                };
                Ok(TensorField::matrix(
                    [[e(0, 0)?, e(0, 1)?], [e(1, 0)?, e(1, 1)?]],
                    self.loc(key, span.clone()),
                ))
            }
        }
    }

    /// Rejects a piece with neither `tags` nor `where` before the last.
    fn check_piece(
        &self,
        key: &str,
        i: usize,
        n: usize,
        has_cond: bool,
        tags: &Option<Spanned<Vec<i32>>>,
    ) -> Result<()> {
        if !has_cond && tags.is_none() && i + 1 < n {
            return Err(self.error(
                K::Schema,
                0,
                0,
                format!(
                    "{key}[{i}]: only the last piece may omit both 'tags' and 'where' (it \
                     takes the rest)"
                ),
            ));
        }
        Ok(())
    }

    /// A piecewise datum (`[diffusion]`, `[source]`), its values compiled by `value`
    /// (given the key); empty if the section is absent.
    fn piecewise<R: Piecewise, V>(
        &self,
        raw: &Option<Spanned<R>>,
        scope: &Scope,
        value: impl Fn(&str, &Spanned<R::Value>) -> Result<V>,
    ) -> Result<Vec<Piece<V>>> {
        let Some(d) = raw else {
            return Ok(Vec::new());
        };
        let (section, key) = (R::SECTION, R::KEY);
        let loc = self.loc(section, d.span());
        match (d.get_ref().whole(), d.get_ref().pieces()) {
            (Some(v), None) => Ok(vec![Piece {
                cond: None,
                tags: Vec::new(),
                tags_loc: None,
                value: value(&format!("{section}.{key}"), v)?,
            }]),
            (None, Some(pieces)) if !pieces.is_empty() => {
                let mut out = Vec::new();
                let list = format!("{section}.piece");
                for (i, &(cond, tags, v)) in pieces.iter().enumerate() {
                    let at = format!("{list}[{i}]");
                    self.check_piece(&list, i, pieces.len(), cond.is_some(), tags)?;
                    out.push(Piece {
                        cond: self.expr_opt(
                            &format!("{at}.where"),
                            cond,
                            scope,
                            Kind::Condition,
                        )?,
                        tags: tags.as_ref().map_or_else(Vec::new, |t| t.get_ref().clone()),
                        tags_loc: tags
                            .as_ref()
                            .map(|t| self.loc(&format!("{at}.tags"), t.span())),
                        value: value(&format!("{at}.{key}"), v)?,
                    });
                }
                Ok(out)
            }
            _ => Err(self.at(
                K::Schema,
                &loc,
                format!("give either '{key}' or one or more [[{section}.piece]]"),
            )),
        }
    }

    /// The boundary sections with a selection, and the kind of the one without (at most one).
    #[allow(clippy::type_complexity)]
    fn boundary(
        &self,
        raw: &RawFile,
        scope: &Scope,
    ) -> Result<(Vec<Part>, Option<(BoundaryKind, &'static str)>)> {
        let sections: [(
            BoundaryKind,
            &'static str,
            Option<(&Option<Spanned<Vec<i32>>>, &Option<Spanned<Src>>)>,
        ); 3] = [
            (
                BoundaryKind::Dirichlet,
                "dirichlet",
                raw.dirichlet.as_ref().map(|s| (&s.tags, &s.cond)),
            ),
            (
                BoundaryKind::Signorini,
                "signorini",
                raw.signorini.as_ref().map(|s| (&s.tags, &s.cond)),
            ),
            (
                BoundaryKind::Neumann,
                "neumann",
                raw.neumann.as_ref().map(|s| (&s.tags, &s.cond)),
            ),
        ];
        let mut parts = Vec::new();
        let mut rest: Option<(BoundaryKind, &'static str)> = None;
        for (kind, section, sel) in sections {
            let Some((tags, cond)) = sel else { continue };
            if tags.is_none() && cond.is_none() {
                if let Some((_, other)) = rest {
                    return Err(self.error(
                        K::Schema,
                        0,
                        0,
                        format!(
                            "[{other}] and [{section}] both have neither 'tags' nor 'where': \
                             only one section may take the rest of the boundary"
                        ),
                    ));
                }
                rest = Some((kind, section));
                continue;
            }
            parts.push(Part {
                kind,
                section,
                tags: tags.as_ref().map_or_else(Vec::new, |t| t.get_ref().clone()),
                tags_loc: tags
                    .as_ref()
                    .map(|t| self.loc(&format!("{section}.tags"), t.span())),
                cond: self.expr_opt(&format!("{section}.where"), cond, scope, Kind::Condition)?,
            });
        }
        Ok((parts, rest))
    }
}

fn side(s: RawSide) -> Side {
    match s {
        RawSide::Upper => Side::Upper,
        RawSide::Lower => Side::Lower,
    }
}

// ------------------------------------------------------------------------------------------
// The problem, and the checks against a mesh.

impl ProblemFile {
    /// The value of parameter `name` (exact name).
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| *v)
    }

    /// Builds the [`Problem`]: closures that evaluate the compiled expressions (cheap; call it
    /// once per solve). Run [`ProblemFile::check_against_mesh`] on the mesh first: on a mesh
    /// it has not checked, a boundary edge no section selects is taken as Dirichlet, and a
    /// point no piece covers gets NaN data (which the assembler rejects).
    pub fn problem(&self) -> Problem {
        let d = Arc::clone(&self.data);
        let mut pb = match self.data.constant_source() {
            Some(c) => Problem::new(&self.name, Box::new(move |_| c)),
            None => Problem::new(&self.name, Box::new(move |p| d.source_at(p, p, 0))),
        };
        if self.data.source.iter().any(|p| p.cond.is_some()) {
            let d = Arc::clone(&self.data);
            pb = pb.with_source_in_cell(Box::new(move |p, xk| d.source_at(p, xk, 0)));
        }
        if !self.data.diffusion.is_empty() {
            let d = Arc::clone(&self.data);
            pb = pb.with_diffusion(Box::new(move |p| d.diffusion_at(p, 0)));
        }
        if self.data.uses_cell_tags() {
            let (d, e) = (Arc::clone(&self.data), Arc::clone(&self.data));
            pb = pb
                .with_diffusion_by_tag(Box::new(move |xk, t| d.diffusion_at(xk, t)))
                .with_source_by_tag(Box::new(move |p, xk, t| e.source_at(p, xk, t)));
        }
        if self.data.has_boundary_sections() {
            let d = Arc::clone(&self.data);
            pb = pb.with_boundary(move |x, tag| {
                d.boundary_at(x, tag).unwrap_or(BoundaryKind::Dirichlet)
            });
        }
        if let Some(g) = &self.data.dirichlet {
            let g = g.expr.clone();
            pb = pb.with_dirichlet(Box::new(move |p| g.eval(&p)));
        }
        if let Some(g) = &self.data.neumann {
            let g = g.expr.clone();
            pb = pb.with_neumann(Box::new(move |p| g.eval(&p)));
        }
        if let Some((kind, side, b)) = &self.data.constraint {
            let b = b.expr.clone();
            pb = pb.with_constraint(*kind, *side, Box::new(move |p| b.eval(&p)));
        }
        if let Some((u, [gx, gy])) = &self.data.exact {
            let (u, gx, gy) = (u.expr.clone(), gx.expr.clone(), gy.expr.clone());
            pb = pb.with_exact(
                Box::new(move |p| u.eval(&p)),
                Box::new(move |p| [gx.eval(&p), gy.eval(&p)]),
            );
        }
        pb
    }

    /// Checks the problem against `mesh`: every tag of the file is on some boundary edge; every
    /// boundary edge is selected by exactly one boundary section (or taken by the rest); a piece
    /// of A and of f applies at every cell; A is symmetric positive definite at every centroid;
    /// and every datum is finite at every point where a scheme evaluates it:
    ///
    /// | datum | points | used there by |
    /// |---|---|---|
    /// | A, exact u and ∇u | cell centroids x_K | every scheme; errors |
    /// | f | x_K and the vertices (piecewise f: the vertices of each cell, with its piece) | HMM; P1 |
    /// | obstacle barrier | x_K, vertices, edge midpoints | HMM; P1; CR |
    /// | Dirichlet value, Signorini barrier | midpoints and end points of the edges of that kind | HMM, CR; P1 |
    /// | Neumann flux | midpoints of the Neumann edges | every scheme |
    ///
    /// (Other quadrature points, such as CR's sub-triangle centroids for f, are checked by the
    /// assembler.) The first failure, in cell, vertex, then edge order, is reported, naming the
    /// key, the cell, vertex or edge, and the point. Cost: a few evaluations per cell, in
    /// parallel.
    pub fn check_against_mesh(&self, mesh: &PolyMesh) -> Result<()> {
        self.check_tags(mesh)?;
        let kinds = self.check_boundary(mesh)?;
        self.check_cells(mesh)?;
        self.check_vertices_and_edges(mesh)?;
        self.check_boundary_values(mesh, &kinds)
    }

    fn fail(&self, kind: K, loc: &Loc, msg: String) -> Error {
        Error::ProblemFile {
            path: self.path.clone(),
            line: loc.line,
            column: loc.column,
            kind,
            msg: format!("{}: {msg}", loc.key),
        }
    }

    fn check_tags(&self, mesh: &PolyMesh) -> Result<()> {
        let mut present: Vec<i32> = mesh
            .boundary_edges()
            .iter()
            .map(|&e| mesh.edge_tag(e))
            .collect();
        present.sort_unstable();
        present.dedup();
        for part in &self.data.parts {
            for t in &part.tags {
                if present.binary_search(t).is_err() {
                    let loc = part.tags_loc.clone().unwrap_or_else(|| Loc {
                        key: format!("{}.tags", part.section),
                        line: 0,
                        column: 0,
                    });
                    let list: Vec<String> = present.iter().map(i32::to_string).collect();
                    return Err(self.fail(
                        K::Tag,
                        &loc,
                        format!(
                            "tag {t} is on no boundary edge of the mesh (its boundary tags: {})",
                            list.join(", ")
                        ),
                    ));
                }
            }
        }
        self.check_cell_tags(mesh)
    }

    /// Every cell tag named by a piece of A or f is the tag of some cell of the mesh.
    fn check_cell_tags(&self, mesh: &PolyMesh) -> Result<()> {
        let mut present: Vec<i32> = (0..mesh.n_cells()).map(|k| mesh.cell_tag(k)).collect();
        present.sort_unstable();
        present.dedup();
        let d = &self.data;
        let named = d
            .diffusion
            .iter()
            .map(|p| ("diffusion.piece", &p.tags, &p.tags_loc))
            .chain(
                d.source
                    .iter()
                    .map(|p| ("source.piece", &p.tags, &p.tags_loc)),
            );
        for (key, tags, tags_loc) in named {
            if let Some(t) = tags.iter().find(|t| present.binary_search(t).is_err()) {
                let list: Vec<String> = present.iter().map(i32::to_string).collect();
                let loc = tags_loc.clone().unwrap_or_else(|| Loc {
                    key: format!("{key}.tags"),
                    line: 0,
                    column: 0,
                });
                return Err(self.fail(
                    K::Tag,
                    &loc,
                    format!(
                        "cell tag {t} is on no cell of the mesh (its cell tags: {})",
                        list.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The kind of every boundary edge (in the order of `mesh.boundary_edges()`).
    fn check_boundary(&self, mesh: &PolyMesh) -> Result<Vec<BoundaryKind>> {
        let d = &self.data;
        let edges = mesh.boundary_edges();
        if !d.has_boundary_sections() {
            return Ok(vec![BoundaryKind::Dirichlet; edges.len()]);
        }
        let kinds: Vec<std::result::Result<BoundaryKind, Error>> =
            edges.par_iter().map(|&e| self.edge_kind(mesh, e)).collect();
        kinds.into_iter().collect()
    }

    fn edge_kind(&self, mesh: &PolyMesh, e: usize) -> Result<BoundaryKind> {
        let d = &self.data;
        let (x, tag) = (mesh.edge_midpoint(e), mesh.edge_tag(e));
        let place = format!(
            "boundary edge {e} (midpoint ({}, {}), tag {tag})",
            x[0], x[1]
        );
        let mut chosen: Option<&Part> = None;
        for p in &d.parts {
            match p.selects(x, tag) {
                None => {
                    let loc = p.cond.as_ref().map_or_else(
                        || {
                            p.tags_loc.clone().unwrap_or(Loc {
                                key: p.section.into(),
                                line: 0,
                                column: 0,
                            })
                        },
                        |c| c.loc.clone(),
                    );
                    return Err(self.fail(
                        K::NonFinite,
                        &loc,
                        format!("the condition is NaN at {place}"),
                    ));
                }
                Some(true) => {
                    if let Some(q) = chosen {
                        let loc = Loc {
                            key: format!("[{}] and [{}]", q.section, p.section),
                            line: 0,
                            column: 0,
                        };
                        return Err(self.fail(
                            K::OverlappingRules,
                            &loc,
                            format!("both select {place}"),
                        ));
                    }
                    chosen = Some(p);
                }
                Some(false) => {}
            }
        }
        match (chosen, d.rest) {
            (Some(p), _) => Ok(p.kind),
            (None, Some((k, _))) => Ok(k),
            (None, None) => {
                let names: Vec<String> =
                    d.parts.iter().map(|p| format!("[{}]", p.section)).collect();
                let loc = Loc {
                    key: "boundary".into(),
                    line: 0,
                    column: 0,
                };
                Err(self.fail(
                    K::UncoveredEdge,
                    &loc,
                    format!("{place} is selected by none of {}; add its tag or widen a 'where', or leave one section without 'tags' and 'where' to take the rest", names.join(", ")),
                ))
            }
        }
    }

    /// Per cell: the pieces of A and f apply, A is SPD; f (piecewise: also at the vertices of
    /// the cell, with its piece), the obstacle barrier and the exact solution are finite at x_K.
    fn check_cells(&self, mesh: &PolyMesh) -> Result<()> {
        let bad = (0..mesh.n_cells())
            .into_par_iter()
            .find_map_first(|k| self.cell_error(mesh, k).err());
        bad.map_or(Ok(()), Err)
    }

    fn cell_error(&self, mesh: &PolyMesh, k: usize) -> Result<()> {
        let d = &self.data;
        let xk = mesh.centroid(k);
        // formatted only on failure
        let place = || format!("cell {k} (x_K = ({}, {}))", xk[0], xk[1]);
        let uncovered = |key: &str| {
            let loc = Loc {
                key: key.into(),
                line: 0,
                column: 0,
            };
            let msg = format!("no piece applies at {}", place());
            self.fail(K::UncoveredPoint, &loc, msg)
        };
        if !d.diffusion.is_empty() {
            let a =
                select(&d.diffusion, xk, mesh.cell_tag(k)).ok_or_else(|| uncovered("diffusion"))?;
            let t = a.at(xk);
            if !t.iter().flatten().all(|v| v.is_finite()) {
                let msg = format!("A = {t:?} at {}", place());
                return Err(self.fail(K::NonFinite, a.loc(), msg));
            }
            if check_tensor(&t, "").is_err() {
                let msg = match check_tensor(&t, &place()) {
                    Err(Error::InvalidData(m)) => m,
                    other => format!("{other:?}"),
                };
                return Err(self.fail(K::NotSpd, a.loc(), msg));
            }
        }
        if !d.source.is_empty() {
            let f = select(&d.source, xk, mesh.cell_tag(k)).ok_or_else(|| uncovered("source"))?;
            let piecewise = d.source.iter().any(|p| p.cond.is_some());
            let verts = mesh
                .cell_vertices(k)
                .iter()
                .map(|&v| mesh.vertex(v as usize));
            let n = if piecewise { usize::MAX } else { 0 };
            for p in std::iter::once(xk).chain(verts.take(n)) {
                self.finite(f, p, &place)?;
            }
        }
        if let Some((ConstraintKind::Obstacle, _, b)) = &d.constraint {
            self.finite(b, xk, &place)?;
        }
        if let Some((u, g)) = &d.exact {
            for f in std::iter::once(u).chain(g) {
                self.finite(f, xk, &place)?;
            }
        }
        Ok(())
    }

    /// An unpiecewise source and the obstacle barrier at every vertex (P1), and the obstacle
    /// barrier at every edge midpoint (Crouzeix–Raviart).
    fn check_vertices_and_edges(&self, mesh: &PolyMesh) -> Result<()> {
        let d = &self.data;
        let source = match d.source.as_slice() {
            [
                Piece {
                    cond: None,
                    value,
                    tags,
                    ..
                },
            ] if tags.is_empty() => Some(value),
            _ => None,
        };
        let obstacle = match &d.constraint {
            Some((ConstraintKind::Obstacle, _, b)) => Some(b),
            _ => None,
        };
        let at_vertices = source.into_iter().chain(obstacle);
        for f in at_vertices {
            let bad = (0..mesh.n_vertices()).into_par_iter().find_map_first(|v| {
                self.finite(f, mesh.vertex(v), &|| format!("vertex {v}"))
                    .err()
            });
            bad.map_or(Ok(()), Err)?;
        }
        if let Some(b) = obstacle {
            let bad = (0..mesh.n_edges()).into_par_iter().find_map_first(|e| {
                self.finite(b, mesh.edge_midpoint(e), &|| format!("edge {e}"))
                    .err()
            });
            bad.map_or(Ok(()), Err)?;
        }
        Ok(())
    }

    /// `Err` naming the datum, the point and the place if `f` is not finite at `p`.
    fn finite(&self, f: &Field, p: Point, place: &dyn Fn() -> String) -> Result<()> {
        let v = f.at(p);
        if v.is_finite() {
            return Ok(());
        }
        let msg = format!(
            "\"{}\" is {v} at ({}, {}), {}",
            f.expr.source(),
            p[0],
            p[1],
            place()
        );
        Err(self.fail(K::NonFinite, &f.loc, msg))
    }

    /// Dirichlet values, Neumann fluxes and the Signorini barrier on the edges of their kind
    /// (the Dirichlet value and the barrier also at the end points, for P1).
    fn check_boundary_values(&self, mesh: &PolyMesh, kinds: &[BoundaryKind]) -> Result<()> {
        let d = &self.data;
        let sig = match &d.constraint {
            Some((ConstraintKind::Signorini, _, b)) => Some(b),
            _ => None,
        };
        let bad = mesh
            .boundary_edges()
            .par_iter()
            .zip(kinds)
            .find_map_first(|(&e, kind)| {
                let (field, ends) = match kind {
                    BoundaryKind::Dirichlet => (d.dirichlet.as_ref(), true),
                    BoundaryKind::Neumann => (d.neumann.as_ref(), false),
                    BoundaryKind::Signorini => (sig, true),
                };
                let f = field?;
                let place = || format!("boundary edge {e}");
                let [a, b] = mesh.edge_vertices(e).map(|v| mesh.vertex(v));
                let pts = [mesh.edge_midpoint(e), a, b];
                let n = if ends { 3 } else { 1 };
                pts[..n]
                    .iter()
                    .find_map(|&p| self.finite(f, p, &place).err())
            });
        bad.map_or(Ok(()), Err)
    }
}
