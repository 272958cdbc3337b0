//! Compilation of the raw file ([`RawFile`]) into [`Data`], with every error located in the
//! file (line, column and key).

use super::MeshSpec;
use super::data::{Data, Field, Loc, Part, Piece, TensorField, scaled_identity};
use super::schema::{Piecewise, RawFile, RawMesh, RawSide, Src, TensorSrc};
use crate::error::{Error, ProblemFileErrorKind as K, Result};
use crate::mesh::{Family, Rect};
use crate::mesh3d::Cuboid;
use crate::mesh3d::generate::Family3;
use crate::problem::expr::{Expr, ExprError, ExprErrorKind, Kind, Scope};
use crate::problem::{BoundaryKind, ConstraintKind, Side, format_parameter};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The file being compiled.
pub(super) struct Cx<'a> {
    pub(super) path: &'a Path,
    pub(super) text: &'a str,
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

    pub(super) fn at(&self, kind: K, loc: &Loc, msg: String) -> Error {
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

    pub(super) fn loc(&self, key: &str, span: Range<usize>) -> Loc {
        let (line, column) = self.line_col(span.start);
        Loc {
            key: key.to_string(),
            line,
            column,
        }
    }

    pub(super) fn toml_error(&self, kind: K, e: &toml::de::Error) -> Error {
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
        let hint = match &e.kind {
            ExprErrorKind::UnknownVariable(v) if v == "z" => {
                " (z is a coordinate of 3D meshes; this problem is compiled for a 2D mesh)"
            }
            _ => "",
        };
        self.error(
            K::Expression,
            line,
            column,
            format!("{}: \"{text}\" {e}{hint}", loc.key),
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
    pub(super) fn parameters(
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
    pub(super) fn definitions(
        &self,
        raw: &BTreeMap<String, Spanned<Src>>,
        scope: &mut Scope,
    ) -> Result<()> {
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
    pub(super) fn name(&self, raw: &Spanned<String>, scope: &Scope) -> Result<String> {
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
                let vars = if scope.contains("z") {
                    "x, y or z"
                } else {
                    "x or y"
                };
                return Err(self.at(
                    K::Expression,
                    &loc,
                    format!("\"{inner}\" depends on {vars}: a name needs a constant"),
                ));
            };
            out.push_str(&format_parameter(v));
            rest = &rest[i + j + 1..];
        }
        out.push_str(rest);
        Ok(out)
    }

    pub(super) fn mesh(&self, raw: &Spanned<RawMesh>) -> Result<MeshSpec> {
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
                let level = m.level.ok_or_else(|| bad("'generate' needs a 'level'"))?;
                // a 2D family name first (the names are distinct), then a 3D one
                let family = match (g.parse::<Family>(), g.parse::<Family3>()) {
                    (Ok(f), _) => f,
                    (Err(_), Ok(f3)) => return self.mesh3(f3, level, m.domain.as_deref(), &loc),
                    (Err(e), Err(e3)) => return Err(bad(&format!("{e}; {e3}"))),
                };
                family.check_level(level).map_err(|e| bad(&e.to_string()))?;
                // the file writes the x range, then the y range
                let domain = match m.domain.as_deref() {
                    None => None,
                    Some(&[x0, x1, y0, y1]) => Some(Rect::new([x0, x1], [y0, y1])),
                    Some(d) => {
                        return Err(bad(&format!(
                            "'domain' of a 2D family is [x0, x1, y0, y1] (4 values), not {} \
                             values",
                            d.len()
                        )));
                    }
                };
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

    /// `[mesh]` with a 3D family: its level, and `domain` = \[x0, x1, y0, y1, z0, z1\].
    fn mesh3(
        &self,
        family: Family3,
        level: usize,
        domain: Option<&[f64]>,
        loc: &Loc,
    ) -> Result<MeshSpec> {
        let bad = |msg: String| self.at(K::Mesh, loc, msg);
        family.check_level(level).map_err(|e| bad(e.to_string()))?;
        let domain = match domain {
            None => None,
            Some(&[x0, x1, y0, y1, z0, z1]) => Some(Cuboid::new([x0, x1], [y0, y1], [z0, z1])),
            Some(d) => {
                return Err(bad(format!(
                    "'domain' of a 3D family is [x0, x1, y0, y1, z0, z1] (6 values), not {} \
                     values",
                    d.len()
                )));
            }
        };
        if domain.is_some_and(|d| !d.is_proper()) {
            return Err(bad(
                "'domain' = [x0, x1, y0, y1, z0, z1] needs x0 < x1, y0 < y1 and z0 < z1".into(),
            ));
        }
        Ok(MeshSpec::Generated3 {
            family,
            level,
            domain,
        })
    }

    /// The data compiled for meshes of dimension D, in `scope` (whose variables are the first
    /// D of x, y, z): D×D tensors and D components of the exact gradient.
    pub(super) fn data<const D: usize>(&self, raw: &RawFile, scope: &Scope) -> Result<Data<D>> {
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
                self.gradient::<D>(&e.grad, scope)?,
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

    /// `exact.grad`: exactly D components.
    fn gradient<const D: usize>(
        &self,
        raw: &Spanned<Vec<Spanned<Src>>>,
        scope: &Scope,
    ) -> Result<[Field; D]> {
        let g = raw.get_ref();
        if g.len() != D {
            let loc = self.loc("exact.grad", raw.span());
            let msg = format!(
                "{} components on a {D}D mesh: the gradient has {D} components there",
                g.len()
            );
            return Err(self.at(K::Dimension, &loc, msg));
        }
        let fields = g
            .iter()
            .enumerate()
            .map(|(i, c)| self.expr(&format!("exact.grad[{i}]"), c, scope, Kind::Number))
            .collect::<Result<Vec<Field>>>()?;
        Ok(to_array(fields))
    }

    fn tensor<const D: usize>(
        &self,
        key: &str,
        raw: &Spanned<TensorSrc>,
        scope: &Scope,
    ) -> Result<TensorField<D>> {
        let span = raw.span();
        let sub = |s: &Src| Spanned::new(span.clone(), s.clone());
        match raw.get_ref() {
            TensorSrc::Scalar(s) => {
                let a = self.expr(key, &sub(s), scope, Kind::Number)?;
                Ok(match a.expr.as_constant() {
                    Some(c) => TensorField::Constant(scaled_identity(c), a.loc),
                    None => TensorField::Scalar(a),
                })
            }
            TensorSrc::Matrix(m) if m.len() != D => {
                let n = m.len();
                let msg =
                    format!("a {n}x{n} tensor on a {D}D mesh: give a {D}x{D} array or a scalar");
                Err(self.at(K::Dimension, &self.loc(key, span.clone()), msg))
            }
            TensorSrc::Matrix(m) => {
                let mut rows = Vec::with_capacity(D);
                for (i, row) in m.iter().enumerate() {
                    let mut entries = Vec::with_capacity(D);
                    for (j, a) in row.iter().enumerate() {
                        let k = format!("{key}[{i}][{j}]");
                        entries.push(self.expr(&k, a, scope, Kind::Number)?);
                    }
                    rows.push(to_array::<Field, D>(entries));
                }
                let loc = self.loc(key, span.clone());
                Ok(TensorField::matrix(to_array(rows), loc))
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

/// A vector of length D (checked by the caller) as an array.
fn to_array<T, const D: usize>(v: Vec<T>) -> [T; D] {
    v.try_into()
        .unwrap_or_else(|_| unreachable!("the length was checked"))
}

/// The side of a barrier as written.
fn side(s: RawSide) -> Side {
    match s {
        RawSide::Upper => Side::Upper,
        RawSide::Lower => Side::Lower,
    }
}

#[cfg(test)]
mod tests {
    use super::Cx;
    use crate::error::{Error, ProblemFileErrorKind as K};
    use crate::problem::file::parse;
    use std::path::Path;

    #[test]
    fn lines_and_columns_count_characters_from_one() {
        let text = "a = 1\né = \"x\"\n";
        let cx = Cx {
            path: Path::new("t.toml"),
            text,
        };
        assert_eq!(cx.line_col(0), (1, 1));
        assert_eq!(cx.line_col(4), (1, 5));
        assert_eq!(cx.line_col(6), (2, 1));
        // 'é' is two bytes and one character
        assert_eq!(cx.line_col(text.rfind('=').unwrap()), (2, 3));
        assert_eq!(cx.line_col(text.len() + 10), (3, 1));
    }

    /// The line, column and message of the error of the file `text`.
    fn error(text: &str) -> (usize, usize, K, String) {
        match parse(text, Path::new("t.toml"), &[]) {
            Err(Error::ProblemFile {
                line,
                column,
                kind,
                msg,
                ..
            }) => (line, column, kind, msg),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn expression_errors_point_at_the_character_when_the_string_is_verbatim() {
        let (line, column, kind, msg) = error("[source]\nf = \"x + w\"\n");
        assert_eq!((line, column, kind), (2, 10, K::Expression));
        assert_eq!(
            msg,
            "source.f: \"x + w\" at character 5: unknown variable 'w'"
        );
        // with an escape, the string is not the text: the error points at the value
        let (line, column, _, msg) = error("[source]\nf = \"x + \\u0077\"\n");
        assert_eq!((line, column), (2, 5));
        assert!(msg.ends_with("unknown variable 'w'"), "{msg}");
    }

    /// The error of building the file `text` for dimension D.
    fn error_in<const D: usize>(text: &str) -> (usize, usize, K, String) {
        let pf = parse(text, Path::new("t.toml"), &[]).unwrap();
        match pf.problem_in::<D>() {
            Err(Error::ProblemFile {
                line,
                column,
                kind,
                msg,
                ..
            }) => (line, column, kind, msg),
            Err(e) => panic!("{e:?}"),
            Ok(_) => panic!("{text}: no error in {D}D"),
        }
    }

    #[test]
    fn a_dimension_mismatch_is_an_error_at_its_place() {
        // a z in a 2D problem: an unknown variable there, at its character
        let text = "[source]\nf = \"x + z\"\n";
        let (line, column, kind, msg) = error_in::<2>(text);
        assert_eq!((line, column, kind), (2, 10, K::Expression));
        assert_eq!(
            msg,
            "source.f: \"x + z\" at character 5: unknown variable 'z' (z is a coordinate of 3D \
             meshes; this problem is compiled for a 2D mesh)"
        );
        let f = parse(text, Path::new("t.toml"), &[]).unwrap();
        assert!(!f.compiles_for(2) && f.compiles_for(3));
        assert_eq!((f.problem_in::<3>().unwrap().source)([1.0, 2.0, 3.0]), 4.0);
        // a 2x2 tensor on a 3D mesh, a 3x3 one on a 2D mesh, at the value
        let a2 = "\n[diffusion]\nA = [[1, 0], [0, 1]]\n";
        let (line, column, kind, msg) = error_in::<3>(a2);
        assert_eq!((line, column, kind), (3, 5, K::Dimension));
        assert!(
            msg.contains("diffusion.A: a 2x2 tensor on a 3D mesh"),
            "{msg}"
        );
        let a3 = "[diffusion]\nA = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n";
        let (line, column, kind, msg) = error_in::<2>(a3);
        assert_eq!((line, column, kind), (2, 5, K::Dimension));
        assert!(msg.contains("a 3x3 tensor on a 2D mesh"), "{msg}");
        // two gradient components on a 3D mesh
        let g = "[exact]\nu = \"x*y\"\ngrad = [\"y\", \"x\"]\n";
        let (line, column, kind, msg) = error_in::<3>(g);
        assert_eq!((line, column, kind), (3, 8, K::Dimension));
        assert!(
            msg.contains("exact.grad: 2 components on a 3D mesh"),
            "{msg}"
        );
        // a file whose own mesh is 3D must compile for 3D when it is loaded
        let (line, column, kind, _) =
            error(&format!("[mesh]\ngenerate = \"cubes\"\nlevel = 1\n{a2}"));
        assert_eq!((line, column, kind), (6, 5, K::Dimension));
        // and a file that compiles for neither reports its 2D error
        let (_, _, kind, msg) = error(&format!("{a2}[source]\nf = \"z\"\n"));
        assert_eq!(kind, K::Expression, "{msg}");
        assert!(msg.contains("unknown variable 'z'"), "{msg}");
    }

    #[test]
    fn definitions_are_compiled_in_dependency_order_and_cycles_rejected() {
        let text = "[definitions]\na = \"b + 1\"\nb = \"2*x\"\n[source]\nf = \"a\"\n";
        let pf = parse(text, Path::new("t.toml"), &[]).unwrap();
        assert_eq!((pf.problem().source)([1.5, 0.0]), 4.0);
        let (line, column, kind, msg) = error("[definitions]\na = \"b\"\nb = \"a\"\n");
        assert_eq!((line, column, kind), (2, 5, K::Parameter));
        assert!(
            msg.contains("the definitions a, b depend on each other in a cycle"),
            "{msg}"
        );
    }
}
