//! The compiled data of a problem file: expressions with the place they were written, pieces
//! of A and f, boundary parts, and their evaluation at a point.

use crate::problem::expr::Expr;
use crate::problem::{BoundaryKind, ConstraintKind, Side};
use crate::scheme::Tensor;

/// Where in the file a datum comes from: its key and the 1-based place of its value.
#[derive(Debug, Clone)]
pub(super) struct Loc {
    pub(super) key: String,
    pub(super) line: usize,
    pub(super) column: usize,
}

/// A compiled expression and where it was written.
#[derive(Debug, Clone)]
pub(super) struct Field {
    pub(super) expr: Expr,
    pub(super) loc: Loc,
}

impl Field {
    /// Its value at the point `p` of ℝᴰ (the expression was compiled in the scope of the
    /// first D coordinates x, y, z).
    #[inline]
    pub(super) fn at<const D: usize>(&self, p: [f64; D]) -> f64 {
        self.expr.eval(&p)
    }
}

/// A(x) in ℝᴰˣᴰ: a I, a full D×D matrix of expressions, or a constant matrix (when every
/// entry is constant); `Loc` is where the whole value is written.
#[derive(Debug, Clone)]
pub(super) enum TensorField<const D: usize> {
    Scalar(Field),
    Matrix(Box<[[Field; D]; D]>, Loc),
    Constant(Tensor<D>, Loc),
}

/// a I in ℝᴰˣᴰ.
pub(super) fn scaled_identity<const D: usize>(a: f64) -> Tensor<D> {
    let mut t = [[0.0; D]; D];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = a;
    }
    t
}

impl<const D: usize> TensorField<D> {
    /// A full matrix, or a constant one if every entry is.
    pub(super) fn matrix(m: [[Field; D]; D], loc: Loc) -> TensorField<D> {
        let mut c = [[0.0; D]; D];
        for (row, fields) in c.iter_mut().zip(&m) {
            for (v, f) in row.iter_mut().zip(fields) {
                match f.expr.as_constant() {
                    Some(x) => *v = x,
                    None => return TensorField::Matrix(Box::new(m), loc),
                }
            }
        }
        TensorField::Constant(c, loc)
    }

    #[inline]
    pub(super) fn at(&self, p: [f64; D]) -> Tensor<D> {
        match self {
            TensorField::Scalar(a) => scaled_identity(a.at(p)),
            TensorField::Matrix(m, _) => m.each_ref().map(|row| row.each_ref().map(|f| f.at(p))),
            TensorField::Constant(a, _) => *a,
        }
    }

    pub(super) fn loc(&self) -> &Loc {
        match self {
            TensorField::Scalar(a) => &a.loc,
            TensorField::Matrix(_, loc) | TensorField::Constant(_, loc) => loc,
        }
    }
}

/// One piece of a piecewise datum: it applies on the cells whose tag is in `tags` (any cell
/// if empty) and where `cond` holds at the centroid (everywhere if `None`).
#[derive(Debug, Clone)]
pub(super) struct Piece<T> {
    pub(super) cond: Option<Field>,
    pub(super) tags: Vec<i32>,
    /// Where `tags` is written (for errors).
    pub(super) tags_loc: Option<Loc>,
    pub(super) value: T,
}

/// The first piece that applies at centroid `p` of a cell tagged `tag`; `None` if none does,
/// or if a condition is NaN there.
pub(super) fn select<T, const D: usize>(pieces: &[Piece<T>], p: [f64; D], tag: i32) -> Option<&T> {
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
pub(super) struct Part {
    pub(super) kind: BoundaryKind,
    pub(super) section: &'static str,
    pub(super) tags: Vec<i32>,
    pub(super) tags_loc: Option<Loc>,
    pub(super) cond: Option<Field>,
}

impl Part {
    /// Whether it selects the boundary face (an edge in 2D) with centre `x` and tag `tag`
    /// (`None`: its condition is NaN).
    pub(super) fn selects<const D: usize>(&self, x: [f64; D], tag: i32) -> Option<bool> {
        if self.tags.contains(&tag) {
            return Some(true);
        }
        match &self.cond {
            Some(c) => c.expr.holds(&x),
            None => Some(false),
        }
    }
}

/// Everything the closures of the [`Problem<D>`](crate::problem::Problem) evaluate: the file
/// compiled for meshes of dimension D (expressions in the first D of x, y, z; D×D tensors; D
/// components of the exact gradient).
#[derive(Debug)]
pub(super) struct Data<const D: usize> {
    /// Empty: A = I.
    pub(super) diffusion: Vec<Piece<TensorField<D>>>,
    /// Empty: f = 0.
    pub(super) source: Vec<Piece<Field>>,
    pub(super) parts: Vec<Part>,
    /// The kind of the section without selection, if any.
    pub(super) rest: Option<(BoundaryKind, &'static str)>,
    pub(super) dirichlet: Option<Field>,
    pub(super) neumann: Option<Field>,
    pub(super) constraint: Option<(ConstraintKind, Side, Field)>,
    pub(super) exact: Option<(Field, [Field; D])>,
}

impl<const D: usize> Data<D> {
    pub(super) fn diffusion_at(&self, p: [f64; D], tag: i32) -> Tensor<D> {
        if self.diffusion.is_empty() {
            return scaled_identity(1.0);
        }
        select(&self.diffusion, p, tag).map_or([[f64::NAN; D]; D], |a| a.at(p))
    }

    /// f at `p` with the piece chosen at `xk` (NaN where no piece applies).
    pub(super) fn source_at(&self, p: [f64; D], xk: [f64; D], tag: i32) -> f64 {
        if self.source.is_empty() {
            return 0.0;
        }
        select(&self.source, xk, tag).map_or(f64::NAN, |f| f.at(p))
    }

    /// f's value if it is one constant everywhere (no piece, or one piece without tags or
    /// condition whose value is constant): its closure then skips the pieces.
    pub(super) fn constant_source(&self) -> Option<f64> {
        match self.source.as_slice() {
            [] => Some(0.0),
            [p] if p.tags.is_empty() && p.cond.is_none() => p.value.expr.as_constant(),
            _ => None,
        }
    }

    /// Whether some piece of A or f is selected by cell tags.
    pub(super) fn uses_cell_tags(&self) -> bool {
        let tagged = |t: &[i32]| !t.is_empty();
        self.diffusion.iter().any(|p| tagged(&p.tags))
            || self.source.iter().any(|p| tagged(&p.tags))
    }

    /// The section that takes the boundary face (centre `x`, tag `tag`): the first explicit
    /// one that selects it, else the rest; `None` if none does.
    pub(super) fn boundary_at(&self, x: [f64; D], tag: i32) -> Option<BoundaryKind> {
        self.parts
            .iter()
            .find(|p| p.selects(x, tag) == Some(true))
            .map(|p| p.kind)
            .or(self.rest.map(|r| r.0))
    }

    pub(super) fn has_boundary_sections(&self) -> bool {
        !self.parts.is_empty() || self.rest.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::{Field, Loc, Part, Piece, TensorField, select};
    use crate::problem::BoundaryKind;
    use crate::problem::expr::{Expr, Scope};

    fn field(src: &str) -> Field {
        let scope = Scope::new(&["x", "y"]);
        Field {
            expr: Expr::parse_kind(src, &scope, None).unwrap(),
            loc: Loc {
                key: src.into(),
                line: 1,
                column: 1,
            },
        }
    }

    fn piece(cond: Option<&str>, tags: &[i32], value: f64) -> Piece<f64> {
        Piece {
            cond: cond.map(field),
            tags: tags.to_vec(),
            tags_loc: None,
            value,
        }
    }

    #[test]
    fn the_first_piece_that_applies_is_selected() {
        let pieces = [
            piece(Some("x < 0.5"), &[], 1.0),
            piece(None, &[7], 2.0),
            piece(Some("sqrt(y) > 0"), &[], 3.0),
        ];
        assert_eq!(select(&pieces, [0.25, 1.0], 0), Some(&1.0));
        assert_eq!(select(&pieces, [0.25, 1.0], 7), Some(&1.0));
        assert_eq!(select(&pieces, [0.75, 1.0], 7), Some(&2.0));
        assert_eq!(select(&pieces, [0.75, 1.0], 0), Some(&3.0));
        // none applies, or a condition reached is NaN
        assert_eq!(select(&pieces, [0.75, 0.0], 0), None);
        assert_eq!(select(&pieces, [0.75, -1.0], 0), None);
        assert_eq!(select(&pieces, [0.25, -1.0], 0), Some(&1.0));
    }

    #[test]
    fn parts_select_by_tag_then_condition() {
        let part = Part {
            kind: BoundaryKind::Neumann,
            section: "neumann",
            tags: vec![3],
            tags_loc: None,
            cond: Some(field("y > 1 - 1e-12")),
        };
        assert_eq!(part.selects([0.5, 0.0], 3), Some(true));
        assert_eq!(part.selects([0.5, 1.0], 1), Some(true));
        assert_eq!(part.selects([0.5, 0.0], 1), Some(false));
        assert_eq!(part.selects([0.5, f64::NAN], 1), None);
    }

    #[test]
    fn tensors_with_constant_entries_are_constant() {
        let loc = field("1").loc;
        let m = TensorField::matrix([[field("2"), field("1")], [field("1"), field("3")]], loc);
        assert!(matches!(
            m,
            TensorField::Constant([[2.0, 1.0], [1.0, 3.0]], _)
        ));
        let loc = field("1").loc;
        let m = TensorField::matrix(
            [[field("1 + x"), field("0")], [field("0"), field("y")]],
            loc,
        );
        assert!(matches!(m, TensorField::Matrix(..)));
        assert_eq!(m.at([2.0, 5.0]), [[3.0, 0.0], [0.0, 5.0]]);
        assert_eq!(
            TensorField::Scalar(field("x")).at([4.0, 0.0]),
            [[4.0, 0.0], [0.0, 4.0]]
        );
        // 3×3, in the scope x, y, z
        let scope = Scope::new(&["x", "y", "z"]);
        let f = |s: &str| Field {
            expr: Expr::parse(s, &scope).unwrap(),
            loc: field("1").loc,
        };
        let m = TensorField::matrix(
            [
                [f("2"), f("0"), f("0")],
                [f("0"), f("1 + z"), f("0")],
                [f("0"), f("0"), f("3")],
            ],
            field("1").loc,
        );
        let a = m.at([0.0, 0.0, 4.0]);
        assert_eq!(a, [[2.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 3.0]]);
        assert_eq!(
            TensorField::<3>::Scalar(f("z")).at([0.0, 0.0, 2.0])[2][2],
            2.0
        );
    }
}
