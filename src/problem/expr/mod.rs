//! Scalar expressions of the point (x, y) for problem files: parsed and checked once, then
//! evaluated at many points, from many threads.
//!
//! ## The language
//! | construct | meaning |
//! |---|---|
//! | `1`, `2.5`, `1e-10` | numbers |
//! | `x`, `y` | the coordinates of the evaluation point (the variables of the [`Scope`]) |
//! | `pi`, `e` | π, Euler's number |
//! | parameters, definitions | the names the [`Scope`] binds (a definition is inlined; one used several times is computed once per evaluation, see below) |
//! | `a + b`, `a - b`, `a * b`, `a / b`, `-a` | arithmetic |
//! | `a ^ b` (or `a ** b`) | power, right-associative, binds tighter than unary minus (`-x^2` = −(x²)); an integer constant exponent n is computed as `a.powi(n)`, any other as `a.powf(b)` |
//! | `a < b`, `<=`, `>`, `>=`, `==`, `!=` | comparisons (conditions) |
//! | `c and d`, `c or d`, `not c` (or `&&`, `\|\|`, `!`) | logic on conditions |
//! | `if(c, a, b)` | a if the condition c holds, else b |
//! | `sqrt exp ln log log10 sin cos tan asin acos atan sinh cosh tanh abs floor ceil` | functions of one argument (`log` = `ln`) |
//! | `atan2(y, x)`, `hypot(a, b)` | functions of two arguments |
//! | `min(a, b, …)`, `max(a, b, …)` | of two or more arguments, folded from the left |
//!
//! Precedence, loosest first: `or`; `and`; `not`; comparisons (not chained); `+ -`; `* /`;
//! unary `-`; `^`. Products and sums are left-associative, as in Rust, so `2*pi*sin(2*pi*x)`
//! performs the same floating-point operations as the Rust expression
//! `2.0 * PI * (2.0 * PI * x).sin()` and gives the same bits.
//!
//! Conditions and numbers are distinct types, checked when parsing: `if(x, 1, 2)` and
//! `(x < 1) + 2` are errors. Every name is resolved when parsing: an unknown variable or
//! function, a wrong number of arguments, a syntax error, each is an [`ExprError`] with the
//! 1-based character position in the expression.
//!
//! Sub-expressions without variables are folded into constants when parsing, in the order they
//! would be computed, so folding never changes a result. NaN propagates through everything:
//! a comparison, a logical operator or a condition of `if` with a NaN operand gives NaN, and so
//! do `min` and `max` (unlike `f64::min`), so that a NaN anywhere is seen by validation instead of
//! silently choosing a branch.
//!
//! ## Parsing: pest, with the grammar in `expr.pest`
//! The text is parsed by [pest](https://pest.rs) (MIT/Apache-2.0, maintained) from the grammar
//! `src/problem/expr/expr.pest`, which fixes the precedence above; pest reports syntax errors at
//! the furthest position it reached, with what it expected there. This module turns pest's tree
//! into a typed tree: it resolves names, checks types (with the position of the offending
//! operand), inlines definitions, folds constants and compiles the result for evaluation.
//!
//! Evaluation is this module's, not an expression crate's. On this language, the maintained,
//! permissively licensed evaluator exmex (0.20, `parse::<f64>`; MIT/Apache-2.0; evalexpr is AGPL
//! from 12.0 on, fasteval and meval have had no release since 2020 and 2017) gives +9 for
//! `-x^2` at x = 3 (unary minus binds tighter than `^`), `2^3^2` gives 64 (`^` is
//! left-associative), `1e-10*x` is a parse error, `min(x, y, 3)` is a parse error, and its errors
//! carry no position. Its value type for conditions (`a if c else b`) makes a comparison with a
//! NaN operand false, so a NaN silently chooses a branch. A user's `-x^2` silently meaning x² is
//! a wrong answer with exit status 0, which this project does not allow; so the grammar is
//! pest's, and the semantics (the table above, NaN propagation, the floating-point operations
//! of the built-in problems bit for bit) are written and tested here.
//!
//! An [`Expr`] keeps its tree (for inlining definitions and folding) and the tree compiled to
//! nested closures, one per node, with constant and variable operands of arithmetic inlined:
//! [`Expr::eval`] calls them, allocating nothing, from any thread (`Send + Sync`). It is faster
//! than walking the tree ([`Expr::eval_tree`], the reference semantics), and gives the same
//! bits; the measurements are in `replication/BENCHMARKS.md` ("Measurements behind the
//! defaults").
//!
//! A definition is inlined where it is used, so a definition used several times would be
//! computed several times. Before compiling, every sub-tree used more than once is hoisted into
//! a slot computed once per evaluation, before the rest, which reads it like a variable (see
//! `hoist`); `problems/ex9.toml`, where `r = sqrt(x^2 + y^2)` is used three or four times per
//! expression, is the case this serves.
//!
//! ## The modules, one job each
//! | module | job |
//! |---|---|
//! | `tree` | the typed syntax tree, its operators and functions, direct evaluation and folding |
//! | `parse` | the pest grammar, the build of a typed tree from the parse tree, errors with positions, the size limits |
//! | `scope` | the names an expression may use: variables, constants, parameters, definitions |
//! | `hoist` | the sub-trees used more than once, computed once per evaluation |
//! | `compile` | the tree compiled to nested closures |
//! | this file | [`Expr`], [`Kind`], [`ExprError`]: the public API |

mod compile;
mod hoist;
mod parse;
mod scope;
mod tree;

pub use parse::{MAX_DEPTH, MAX_LENGTH, MAX_NESTING};
pub use scope::{RESERVED, Scope};

use compile::Compiled;
use parse::{expect_kind, parse_tree};
use std::fmt;
use std::sync::Arc;
use tree::Node;

/// The type of an expression: a number, or a condition (true or false).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A real number.
    Number,
    /// A condition; evaluated as 1 (true) or 0 (false).
    Condition,
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Kind::Number => "a number",
            Kind::Condition => "a condition",
        })
    }
}

/// What is wrong with an expression.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprErrorKind {
    /// A character or token that does not fit the grammar (the message says what was expected).
    Syntax(String),
    /// A name that is neither a variable, a parameter, a definition nor a constant.
    UnknownVariable(String),
    /// A call of a function that does not exist.
    UnknownFunction(String),
    /// A known function called with the wrong number of arguments.
    Arity {
        /// The function.
        name: String,
        /// What it takes ("1", "2", "at least 2").
        expected: &'static str,
        /// What it was given.
        found: usize,
    },
    /// A number where a condition is needed, or the converse.
    Type {
        /// What the context needs.
        expected: Kind,
        /// What was found.
        found: Kind,
    },
}

/// A parse error: its kind and the 1-based character position in the expression.
#[derive(Debug, Clone, PartialEq)]
pub struct ExprError {
    /// 1-based position (in characters) of the offending token.
    pub position: usize,
    /// What is wrong.
    pub kind: ExprErrorKind,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "at character {}: ", self.position)?;
        match &self.kind {
            ExprErrorKind::Syntax(m) => f.write_str(m),
            ExprErrorKind::UnknownVariable(n) => write!(f, "unknown variable '{n}'"),
            ExprErrorKind::UnknownFunction(n) => write!(f, "unknown function '{n}'"),
            ExprErrorKind::Arity {
                name,
                expected,
                found,
            } => write!(f, "{name}() takes {expected} argument(s), {found} given"),
            ExprErrorKind::Type { expected, found } => {
                write!(f, "expected {expected}, found {found}")
            }
        }
    }
}

impl std::error::Error for ExprError {}

/// A parsed, checked expression. See the module docs.
#[derive(Clone)]
pub struct Expr {
    root: Node,
    kind: Kind,
    n_vars: usize,
    source: String,
    /// `root` compiled to nested closures (see [`compile::compile`]), its shared sub-trees
    /// hoisted (see [`hoist::hoist`]).
    fun: Arc<Compiled>,
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Expr")
            .field("source", &self.source)
            .field("kind", &self.kind)
            .field("root", &self.root)
            .finish()
    }
}

impl PartialEq for Expr {
    fn eq(&self, other: &Expr) -> bool {
        (&self.root, self.kind, self.n_vars, &self.source)
            == (&other.root, other.kind, other.n_vars, &other.source)
    }
}

impl Expr {
    /// Parses a number-valued expression.
    pub fn parse(source: &str, scope: &Scope) -> Result<Expr, ExprError> {
        Self::parse_kind(source, scope, Some(Kind::Number))
    }

    /// Parses a condition.
    pub fn parse_condition(source: &str, scope: &Scope) -> Result<Expr, ExprError> {
        Self::parse_kind(source, scope, Some(Kind::Condition))
    }

    /// Parses an expression of the type `expected` (`None`: either).
    pub fn parse_kind(
        source: &str,
        scope: &Scope,
        expected: Option<Kind>,
    ) -> Result<Expr, ExprError> {
        let (root, kind, pos) = parse_tree(source, scope)?;
        if let Some(e) = expected {
            expect_kind(e, kind, pos)?;
        }
        Ok(Expr {
            fun: Arc::new(Compiled::new(&root, scope.n_vars)),
            root,
            kind,
            n_vars: scope.n_vars,
            source: source.to_string(),
        })
    }

    /// The constant `value` as an expression.
    pub fn constant(value: f64) -> Expr {
        Expr {
            root: Node::Const(value),
            fun: Arc::new(Compiled::new(&Node::Const(value), 0)),
            kind: Kind::Number,
            n_vars: 0,
            source: format!("{value:?}"),
        }
    }

    /// Its value at the variables `vars` (in the order of the scope it was parsed in; a
    /// condition gives 1, 0 or NaN). Panics if `vars` is shorter than the scope's variables.
    #[inline]
    pub fn eval(&self, vars: &[f64]) -> f64 {
        self.fun.eval(vars)
    }

    /// As [`Expr::eval`], walking the tree (the reference semantics of the compiled closures).
    pub fn eval_tree(&self, vars: &[f64]) -> f64 {
        self.root.eval(vars)
    }

    /// Whether the condition holds at `vars` (`None` if it is NaN: undecidable).
    #[inline]
    pub fn holds(&self, vars: &[f64]) -> Option<bool> {
        let v = self.eval(vars);
        if v.is_nan() { None } else { Some(v != 0.0) }
    }

    /// Number or condition.
    pub fn kind(&self) -> Kind {
        self.kind
    }

    /// The text it was parsed from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Its value if it depends on no variable.
    pub fn as_constant(&self) -> Option<f64> {
        match self.root {
            Node::Const(c) => Some(c),
            _ => None,
        }
    }

    /// Number of variables it expects in [`Expr::eval`].
    pub fn n_vars(&self) -> usize {
        self.n_vars
    }
}

/// What the tests of the sub-modules share.
#[cfg(test)]
mod testing {
    use super::{Expr, ExprError, Scope};

    /// The scope of the tests: the variables x and y.
    pub(super) fn xy() -> Scope {
        Scope::new(&["x", "y"])
    }

    /// The value of `s` (a number or a condition) parsed in [`xy`], at (x, y).
    pub(super) fn ev(s: &str, x: f64, y: f64) -> f64 {
        Expr::parse_kind(s, &xy(), None).unwrap().eval(&[x, y])
    }

    /// The error of parsing the number `s` in [`xy`].
    pub(super) fn err(s: &str) -> ExprError {
        Expr::parse(s, &xy()).unwrap_err()
    }
}

#[cfg(test)]
mod tests {
    use super::Expr;
    use super::testing::ev;
    use std::f64::consts::PI;

    #[test]
    fn same_bits_as_rust() {
        for &(x, y) in &[(0.1234, 0.9876), (0.5, 0.25), (1.0 / 3.0, 2.0 / 7.0)] {
            let r = 2.0 * PI * (2.0 * PI * x).sin();
            assert_eq!(ev("2*pi*sin(2*pi*x)", x, y).to_bits(), r.to_bits());
            let p = -y * (y - 0.5) * (y - 0.5);
            assert_eq!(ev("-y*(y - 0.5)*(y - 0.5)", x, y).to_bits(), p.to_bits());
            let s = (0.5 * PI * x).sin().powi(2);
            assert_eq!(ev("sin(0.5*pi*x)^2", x, y).to_bits(), s.to_bits());
            let m = -(x.min(1.0 - x).min(y).min(1.0 - y));
            assert_eq!(ev("-min(x, 1 - x, y, 1 - y)", x, y).to_bits(), m.to_bits());
        }
    }

    #[test]
    fn expressions_are_shareable_between_threads() {
        fn sync<T: Send + Sync>() {}
        sync::<Expr>();
    }
}
