//! Scalar expressions of the point (x, y) for problem files: parsed and checked once, then
//! evaluated at many points, from many threads.
//!
//! ## The language
//! | construct | meaning |
//! |---|---|
//! | `1`, `2.5`, `1e-10` | numbers |
//! | `x`, `y` | the coordinates of the evaluation point (the variables of the [`Scope`]) |
//! | `pi`, `e` | π, Euler's number |
//! | parameters, definitions | the names the [`Scope`] binds (a definition is inlined) |
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
//! ## Why not an expression crate
//! The crates that were considered: evalexpr is AGPL from version 12 on (excluded); fasteval
//! (MIT) and meval (MIT/Unlicense) have had no release since 2020 and 2017; exmex (MIT/Apache,
//! maintained) builds operators as unary or binary functions over one operand type, so
//! conditions are numbers and `if(c, a, b)` is not a native construct. What this module must
//! guarantee, and what none of them gives as such: conditions typed apart from numbers, with
//! the character position of every error; NaN propagated through comparisons, `if`, `min`
//! and `max` (a NaN must reach validation, not silently choose a branch); and the same
//! floating-point operations, in the same order, as the Rust closures of the built-in
//! problems, which the regression tests pin bit for bit through `problems/*.toml`. A crate
//! would need a layer re-checking all three; the parser here is about as large as that layer.
//!
//! An [`Expr`] keeps its tree (for inlining definitions and folding) and the tree compiled to
//! nested closures, one per node, with constant and variable operands of arithmetic inlined:
//! [`Expr::eval`] calls them, allocating nothing, from any thread (`Send + Sync`). This runs
//! 3 to 6 times faster than walking the tree ([`Expr::eval_tree`], the reference semantics,
//! which gives the same bits), and within a small factor of a Rust closure.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

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

/// Functions of one argument.
#[derive(Debug, Clone, Copy, PartialEq)]
enum F1 {
    Sqrt,
    Exp,
    Ln,
    Log10,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Abs,
    Floor,
    Ceil,
}

impl F1 {
    fn from_name(n: &str) -> Option<F1> {
        Some(match n {
            "sqrt" => F1::Sqrt,
            "exp" => F1::Exp,
            "ln" | "log" => F1::Ln,
            "log10" => F1::Log10,
            "sin" => F1::Sin,
            "cos" => F1::Cos,
            "tan" => F1::Tan,
            "asin" => F1::Asin,
            "acos" => F1::Acos,
            "atan" => F1::Atan,
            "sinh" => F1::Sinh,
            "cosh" => F1::Cosh,
            "tanh" => F1::Tanh,
            "abs" => F1::Abs,
            "floor" => F1::Floor,
            "ceil" => F1::Ceil,
            _ => return None,
        })
    }
    fn apply(self, a: f64) -> f64 {
        match self {
            F1::Sqrt => a.sqrt(),
            F1::Exp => a.exp(),
            F1::Ln => a.ln(),
            F1::Log10 => a.log10(),
            F1::Sin => a.sin(),
            F1::Cos => a.cos(),
            F1::Tan => a.tan(),
            F1::Asin => a.asin(),
            F1::Acos => a.acos(),
            F1::Atan => a.atan(),
            F1::Sinh => a.sinh(),
            F1::Cosh => a.cosh(),
            F1::Tanh => a.tanh(),
            F1::Abs => a.abs(),
            F1::Floor => a.floor(),
            F1::Ceil => a.ceil(),
        }
    }
}

/// Binary operators on numbers, and the functions of two arguments.
#[derive(Debug, Clone, Copy, PartialEq)]
enum F2 {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Atan2,
    Hypot,
    Min,
    Max,
}

impl F2 {
    fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            F2::Add => a + b,
            F2::Sub => a - b,
            F2::Mul => a * b,
            F2::Div => a / b,
            F2::Pow => a.powf(b),
            F2::Atan2 => a.atan2(b),
            F2::Hypot => a.hypot(b),
            // NaN-propagating, unlike f64::min and f64::max
            F2::Min if a.is_nan() || b.is_nan() => f64::NAN,
            F2::Max if a.is_nan() || b.is_nan() => f64::NAN,
            F2::Min => a.min(b),
            F2::Max => a.max(b),
        }
    }
}

/// Comparisons.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

impl Cmp {
    fn apply(self, a: f64, b: f64) -> f64 {
        if a.is_nan() || b.is_nan() {
            return f64::NAN;
        }
        let t = match self {
            Cmp::Lt => a < b,
            Cmp::Le => a <= b,
            Cmp::Gt => a > b,
            Cmp::Ge => a >= b,
            Cmp::Eq => a == b,
            Cmp::Ne => a != b,
        };
        bool_value(t)
    }
}

fn bool_value(t: bool) -> f64 {
    if t { 1.0 } else { 0.0 }
}

/// The expression tree. Conditions evaluate to 1.0 (true), 0.0 (false) or NaN (undecidable).
#[derive(Debug, Clone, PartialEq)]
enum Node {
    Const(f64),
    Var(usize),
    Neg(Box<Node>),
    Not(Box<Node>),
    Call1(F1, Box<Node>),
    Call2(F2, Box<Node>, Box<Node>),
    PowI(Box<Node>, i32),
    Cmp(Cmp, Box<Node>, Box<Node>),
    And(Box<Node>, Box<Node>),
    Or(Box<Node>, Box<Node>),
    If(Box<Node>, Box<Node>, Box<Node>),
}

/// A child's value: leaves inline (no call), anything else recursively.
#[inline(always)]
fn ev(n: &Node, v: &[f64]) -> f64 {
    match n {
        Node::Const(c) => *c,
        Node::Var(i) => v[*i],
        n => n.eval(v),
    }
}

impl Node {
    fn eval(&self, v: &[f64]) -> f64 {
        match self {
            Node::Const(c) => *c,
            Node::Var(i) => v[*i],
            Node::Neg(a) => -ev(a, v),
            Node::Not(a) => match ev(a, v) {
                c if c.is_nan() => f64::NAN,
                c => bool_value(c == 0.0),
            },
            Node::Call1(f, a) => f.apply(ev(a, v)),
            Node::Call2(f, a, b) => f.apply(ev(a, v), ev(b, v)),
            Node::PowI(a, n) => {
                let a = ev(a, v);
                if *n == 2 { a * a } else { a.powi(*n) }
            }
            Node::Cmp(c, a, b) => c.apply(ev(a, v), ev(b, v)),
            Node::And(a, b) => {
                let c = ev(a, v);
                if c.is_nan() || c == 0.0 { c } else { ev(b, v) }
            }
            Node::Or(a, b) => match ev(a, v) {
                c if c.is_nan() => f64::NAN,
                c if c != 0.0 => 1.0,
                _ => ev(b, v),
            },
            Node::If(c, a, b) => match ev(c, v) {
                t if t.is_nan() => f64::NAN,
                t if t != 0.0 => ev(a, v),
                _ => ev(b, v),
            },
        }
    }

    /// This node, with a constant value if it has no variable (evaluated now, exactly as it
    /// would be later).
    fn folded(self) -> Node {
        if self.is_constant() {
            Node::Const(self.eval(&[]))
        } else {
            self
        }
    }

    fn is_constant(&self) -> bool {
        match self {
            Node::Const(_) => true,
            Node::Var(_) => false,
            Node::Neg(a) | Node::Not(a) | Node::Call1(_, a) | Node::PowI(a, _) => a.is_constant(),
            Node::Call2(_, a, b) | Node::Cmp(_, a, b) | Node::And(a, b) | Node::Or(a, b) => {
                a.is_constant() && b.is_constant()
            }
            Node::If(c, a, b) => c.is_constant() && a.is_constant() && b.is_constant(),
        }
    }
}

/// A compiled expression.
type Fun = Box<dyn Fn(&[f64]) -> f64 + Send + Sync>;

/// Compiles a tree into nested closures with the same semantics as [`Node::eval`]: each node
/// becomes a closure that calls its children's, so evaluation has no `match` on the node kind;
/// arithmetic with a constant or a variable operand is specialised so that leaves cost no call.
fn compile(n: &Node) -> Fun {
    /// An arithmetic operator on two operands, each a constant (`c`), a variable (`v`) or a
    /// compiled sub-expression (`f`), for the operator `$op`.
    macro_rules! arith {
        ($a:expr, $b:expr, $op:tt) => {
            match ($a, $b) {
                (Node::Var(i), Node::Const(c)) => { let (i, c) = (*i, *c); Box::new(move |v: &[f64]| v[i] $op c) as Fun }
                (Node::Const(c), Node::Var(i)) => { let (i, c) = (*i, *c); Box::new(move |v: &[f64]| c $op v[i]) }
                (Node::Var(i), Node::Var(j)) => { let (i, j) = (*i, *j); Box::new(move |v: &[f64]| v[i] $op v[j]) }
                (Node::Const(c), b) => { let (c, b) = (*c, compile(b)); Box::new(move |v: &[f64]| c $op b(v)) }
                (a, Node::Const(c)) => { let (a, c) = (compile(a), *c); Box::new(move |v: &[f64]| a(v) $op c) }
                (Node::Var(i), b) => { let (i, b) = (*i, compile(b)); Box::new(move |v: &[f64]| v[i] $op b(v)) }
                (a, Node::Var(j)) => { let (a, j) = (compile(a), *j); Box::new(move |v: &[f64]| a(v) $op v[j]) }
                (a, b) => { let (a, b) = (compile(a), compile(b)); Box::new(move |v: &[f64]| a(v) $op b(v)) }
            }
        };
    }
    match n {
        Node::Const(c) => {
            let c = *c;
            Box::new(move |_| c)
        }
        Node::Var(i) => {
            let i = *i;
            Box::new(move |v| v[i])
        }
        Node::Neg(a) => {
            let a = compile(a);
            Box::new(move |v| -a(v))
        }
        Node::Call2(F2::Add, a, b) => arith!(&**a, &**b, +),
        Node::Call2(F2::Sub, a, b) => arith!(&**a, &**b, -),
        Node::Call2(F2::Mul, a, b) => arith!(&**a, &**b, *),
        Node::Call2(F2::Div, a, b) => arith!(&**a, &**b, /),
        Node::Call2(f, a, b) => {
            let (f, a, b) = (*f, compile(a), compile(b));
            Box::new(move |v| f.apply(a(v), b(v)))
        }
        Node::Call1(f, a) => compile_call1(*f, compile(a)),
        Node::PowI(a, 2) => {
            let a = compile(a);
            Box::new(move |v| {
                let x = a(v);
                x * x
            })
        }
        Node::PowI(a, k) => {
            let (a, k) = (compile(a), *k);
            Box::new(move |v| a(v).powi(k))
        }
        n => compile_logic(n),
    }
}

/// Comparisons, logic and conditionals (the other nodes of [`compile`]).
fn compile_logic(n: &Node) -> Fun {
    match n {
        Node::Cmp(c, a, b) => {
            let (c, a, b) = (*c, compile(a), compile(b));
            Box::new(move |v| c.apply(a(v), b(v)))
        }
        Node::Not(a) => {
            let a = compile(a);
            Box::new(move |v| match a(v) {
                c if c.is_nan() => f64::NAN,
                c => bool_value(c == 0.0),
            })
        }
        Node::And(a, b) => {
            let (a, b) = (compile(a), compile(b));
            Box::new(move |v| {
                let c = a(v);
                if c.is_nan() || c == 0.0 { c } else { b(v) }
            })
        }
        Node::Or(a, b) => {
            let (a, b) = (compile(a), compile(b));
            Box::new(move |v| match a(v) {
                c if c.is_nan() => f64::NAN,
                c if c != 0.0 => 1.0,
                _ => b(v),
            })
        }
        Node::If(c, a, b) => {
            let (c, a, b) = (compile(c), compile(a), compile(b));
            Box::new(move |v| match c(v) {
                t if t.is_nan() => f64::NAN,
                t if t != 0.0 => a(v),
                _ => b(v),
            })
        }
        // (every other node is compiled by `compile`; walk the tree if one ever comes here)
        n => {
            let n = n.clone();
            Box::new(move |v| n.eval(v))
        }
    }
}

/// A function of one argument, monomorphised for the common ones.
fn compile_call1(f: F1, a: Fun) -> Fun {
    match f {
        F1::Sqrt => Box::new(move |v| a(v).sqrt()),
        F1::Sin => Box::new(move |v| a(v).sin()),
        F1::Cos => Box::new(move |v| a(v).cos()),
        F1::Exp => Box::new(move |v| a(v).exp()),
        F1::Ln => Box::new(move |v| a(v).ln()),
        F1::Abs => Box::new(move |v| a(v).abs()),
        f => Box::new(move |v| f.apply(a(v))),
    }
}

/// What a name stands for in a [`Scope`].
#[derive(Debug, Clone)]
enum Binding {
    Var(usize),
    Value(Node, Kind),
}

/// The names an expression may use: the evaluation variables (in the order of the slice passed
/// to [`Expr::eval`]), the constants `pi` and `e`, and named parameters and definitions.
#[derive(Debug, Clone)]
pub struct Scope {
    names: HashMap<String, Binding>,
    n_vars: usize,
}

/// Words that cannot be names of variables, parameters or definitions.
pub const RESERVED: [&str; 4] = ["and", "or", "not", "if"];

impl Scope {
    /// A scope with the variables `vars` (evaluated as `eval(&[v0, v1, …])`) and `pi`, `e`.
    pub fn new(vars: &[&str]) -> Scope {
        let mut names = HashMap::new();
        for (i, v) in vars.iter().enumerate() {
            names.insert(v.to_string(), Binding::Var(i));
        }
        names.insert(
            "pi".into(),
            Binding::Value(Node::Const(std::f64::consts::PI), Kind::Number),
        );
        names.insert(
            "e".into(),
            Binding::Value(Node::Const(std::f64::consts::E), Kind::Number),
        );
        Scope {
            names,
            n_vars: vars.len(),
        }
    }

    /// Whether `name` can be bound: an identifier that is not yet bound, not a function name and
    /// not a reserved word. `Err` says why not.
    pub fn check_new_name(&self, name: &str) -> Result<(), String> {
        let mut chars = name.chars();
        let ident = chars
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !ident {
            return Err(format!(
                "'{name}' is not a valid name (letters, digits and _, not starting with a digit)"
            ));
        }
        if RESERVED.contains(&name) || F1::from_name(name).is_some() || fun2(name).is_some() {
            return Err(format!("'{name}' is a reserved word or a function name"));
        }
        if self.names.contains_key(name) {
            return Err(format!("'{name}' is already defined"));
        }
        Ok(())
    }

    /// Binds `name` to a constant value.
    pub fn set_constant(&mut self, name: &str, value: f64) -> Result<(), String> {
        self.check_new_name(name)?;
        self.names.insert(
            name.to_string(),
            Binding::Value(Node::Const(value), Kind::Number),
        );
        Ok(())
    }

    /// Binds `name` to an expression parsed in this scope (inlined wherever it is used).
    pub fn define(&mut self, name: &str, expr: &Expr) -> Result<(), String> {
        self.check_new_name(name)?;
        self.names.insert(
            name.to_string(),
            Binding::Value(expr.root.clone(), expr.kind),
        );
        Ok(())
    }

    /// Whether `name` is bound.
    pub fn contains(&self, name: &str) -> bool {
        self.names.contains_key(name)
    }
}

/// A parsed, checked expression. See the module docs.
#[derive(Clone)]
pub struct Expr {
    root: Node,
    kind: Kind,
    n_vars: usize,
    source: String,
    /// `root` compiled to nested closures (see [`compile`]).
    fun: Arc<Fun>,
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
        let tokens = lex(source)?;
        let mut p = Parser {
            tokens: &tokens,
            at: 0,
            scope,
            end: source.chars().count() + 1,
        };
        let (root, kind, pos) = p.or()?;
        if let Some(t) = tokens.get(p.at) {
            return Err(syntax(t.pos, format!("unexpected {}", t.tok)));
        }
        if let Some(e) = expected {
            expect_kind(e, kind, pos)?;
        }
        Ok(Expr {
            fun: Arc::new(compile(&root)),
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
            fun: Arc::new(compile(&Node::Const(value))),
            kind: Kind::Number,
            n_vars: 0,
            source: format!("{value:?}"),
        }
    }

    /// Its value at the variables `vars` (in the order of the scope it was parsed in; a
    /// condition gives 1, 0 or NaN). Panics if `vars` is shorter than the scope's variables.
    #[inline]
    pub fn eval(&self, vars: &[f64]) -> f64 {
        (self.fun)(vars)
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

// ------------------------------------------------------------------------------------------
// Lexer

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    /// Operators and punctuation: + - * / ^ ( ) , < <= > >= == != ! && ||
    Op(&'static str),
}

impl fmt::Display for Tok {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tok::Num(v) => write!(f, "number {v}"),
            Tok::Ident(s) => write!(f, "'{s}'"),
            Tok::Op(s) => write!(f, "'{s}'"),
        }
    }
}

struct Token {
    tok: Tok,
    /// 1-based character position.
    pos: usize,
}

fn syntax(pos: usize, msg: String) -> ExprError {
    ExprError {
        position: pos,
        kind: ExprErrorKind::Syntax(msg),
    }
}

const OPS: [&str; 18] = [
    "**", "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "^", "(", ")", ",", "<", ">", "!",
];

fn lex(src: &str) -> Result<Vec<Token>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let pos = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            let (v, n) = lex_number(&chars[i..], pos)?;
            out.push(Token {
                tok: Tok::Num(v),
                pos,
            });
            i += n;
        } else if c.is_ascii_alphabetic() || c == '_' {
            let n = chars[i..]
                .iter()
                .take_while(|c| c.is_ascii_alphanumeric() || **c == '_')
                .count();
            let s: String = chars[i..i + n].iter().collect();
            out.push(Token {
                tok: Tok::Ident(s),
                pos,
            });
            i += n;
        } else {
            let op = OPS.iter().find(|op| {
                op.chars()
                    .enumerate()
                    .all(|(j, oc)| chars.get(i + j) == Some(&oc))
            });
            let Some(op) = op else {
                return Err(syntax(pos, format!("unexpected character '{c}'")));
            };
            let op = if *op == "**" { "^" } else { op };
            out.push(Token {
                tok: Tok::Op(op),
                pos,
            });
            i += if op == "^" && chars[i] == '*' {
                2
            } else {
                op.len()
            };
        }
    }
    Ok(out)
}

/// A decimal number `digits[.digits][(e|E)[+|-]digits]` at the start of `c`; returns its value
/// and length.
fn lex_number(c: &[char], pos: usize) -> Result<(f64, usize), ExprError> {
    let digits = |from: usize| c[from..].iter().take_while(|c| c.is_ascii_digit()).count();
    let mut n = digits(0);
    if c.get(n) == Some(&'.') {
        n += 1 + digits(n + 1);
    }
    if matches!(c.get(n), Some('e' | 'E')) {
        let sign = usize::from(matches!(c.get(n + 1), Some('+' | '-')));
        let d = digits(n + 1 + sign);
        if d == 0 {
            return Err(syntax(pos, "malformed exponent in number".into()));
        }
        n += 1 + sign + d;
    }
    let s: String = c[..n].iter().collect();
    s.parse::<f64>()
        .map(|v| (v, n))
        .map_err(|_| syntax(pos, format!("malformed number '{s}'")))
}

// ------------------------------------------------------------------------------------------
// Parser: recursive descent, one function per precedence level; each returns the node, its
// type and the position where it starts.

type Parsed = Result<(Node, Kind, usize), ExprError>;

struct Parser<'a> {
    tokens: &'a [Token],
    at: usize,
    scope: &'a Scope,
    /// Position just past the end (for "unexpected end").
    end: usize,
}

fn expect_kind(expected: Kind, found: Kind, pos: usize) -> Result<(), ExprError> {
    if expected == found {
        Ok(())
    } else {
        Err(ExprError {
            position: pos,
            kind: ExprErrorKind::Type { expected, found },
        })
    }
}

fn fun2(name: &str) -> Option<F2> {
    Some(match name {
        "atan2" => F2::Atan2,
        "hypot" => F2::Hypot,
        "min" => F2::Min,
        "max" => F2::Max,
        _ => return None,
    })
}

fn b(n: Node) -> Box<Node> {
    Box::new(n)
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.tokens.get(self.at).map(|t| &t.tok)
    }

    fn pos(&self) -> usize {
        self.tokens.get(self.at).map_or(self.end, |t| t.pos)
    }

    /// Consumes the operator `op` (or the keyword `op`) if it comes next.
    fn eat(&mut self, ops: &[&str]) -> Option<&'static str> {
        let found = match self.peek() {
            Some(Tok::Op(o)) => ops.iter().find(|x| *x == o).map(|_| *o),
            Some(Tok::Ident(w)) => match w.as_str() {
                "and" if ops.contains(&"&&") => Some("&&"),
                "or" if ops.contains(&"||") => Some("||"),
                "not" if ops.contains(&"!") => Some("!"),
                _ => None,
            },
            _ => None,
        };
        if found.is_some() {
            self.at += 1;
        }
        found
    }

    fn expect(&mut self, op: &'static str) -> Result<(), ExprError> {
        if self.eat(&[op]).is_some() {
            return Ok(());
        }
        let found = match self.tokens.get(self.at) {
            Some(t) => t.tok.to_string(),
            None => "the end of the expression".into(),
        };
        Err(syntax(
            self.pos(),
            format!("expected '{op}', found {found}"),
        ))
    }

    fn or(&mut self) -> Parsed {
        self.logical("||", Self::and, Node::Or)
    }

    fn and(&mut self) -> Parsed {
        self.logical("&&", Self::not, Node::And)
    }

    /// `operand (op operand)*`, left-associative, for a logical operator `op` whose operands
    /// (parsed by `operand`) are conditions.
    fn logical(
        &mut self,
        op: &'static str,
        operand: fn(&mut Self) -> Parsed,
        node: fn(Box<Node>, Box<Node>) -> Node,
    ) -> Parsed {
        let (mut a, k, pos) = operand(self)?;
        while self.eat(&[op]).is_some() {
            let p = self.pos();
            expect_kind(Kind::Condition, k, pos)?;
            let (c, kc, _) = operand(self)?;
            expect_kind(Kind::Condition, kc, p)?;
            a = node(b(a), b(c)).folded();
        }
        Ok((a, k, pos))
    }

    fn not(&mut self) -> Parsed {
        let pos = self.pos();
        if self.eat(&["!"]).is_some() {
            let p = self.pos();
            let (a, k, _) = self.not()?;
            expect_kind(Kind::Condition, k, p)?;
            return Ok((Node::Not(b(a)).folded(), Kind::Condition, pos));
        }
        self.comparison()
    }

    fn comparison(&mut self) -> Parsed {
        let (a, k, pos) = self.sum()?;
        let op = match self.eat(&["<", "<=", ">", ">=", "==", "!="]) {
            Some(op) => op,
            None => return Ok((a, k, pos)),
        };
        let cmp = match op {
            "<" => Cmp::Lt,
            "<=" => Cmp::Le,
            ">" => Cmp::Gt,
            ">=" => Cmp::Ge,
            "==" => Cmp::Eq,
            _ => Cmp::Ne,
        };
        expect_kind(Kind::Number, k, pos)?;
        let p = self.pos();
        let (c, kc, _) = self.sum()?;
        expect_kind(Kind::Number, kc, p)?;
        if let Some(Tok::Op(o @ ("<" | "<=" | ">" | ">=" | "==" | "!="))) = self.peek() {
            return Err(syntax(
                self.pos(),
                format!("comparisons cannot be chained ('{o}'): use 'and'"),
            ));
        }
        Ok((Node::Cmp(cmp, b(a), b(c)).folded(), Kind::Condition, pos))
    }

    /// Left-associative binary levels on numbers.
    fn binary(&mut self, ops: &[&str], next: fn(&mut Self) -> Parsed, f: fn(&str) -> F2) -> Parsed {
        let (mut a, k, pos) = next(self)?;
        while let Some(op) = self.eat(ops) {
            expect_kind(Kind::Number, k, pos)?;
            let p = self.pos();
            let (c, kc, _) = next(self)?;
            expect_kind(Kind::Number, kc, p)?;
            a = Node::Call2(f(op), b(a), b(c)).folded();
        }
        Ok((a, k, pos))
    }

    fn sum(&mut self) -> Parsed {
        self.binary(&["+", "-"], Self::product, |op| {
            if op == "+" { F2::Add } else { F2::Sub }
        })
    }

    fn product(&mut self) -> Parsed {
        self.binary(&["*", "/"], Self::unary, |op| {
            if op == "*" { F2::Mul } else { F2::Div }
        })
    }

    fn unary(&mut self) -> Parsed {
        let pos = self.pos();
        match self.eat(&["-", "+"]) {
            Some(op) => {
                let (a, k, _) = self.unary()?;
                expect_kind(Kind::Number, k, pos)?;
                let n = if op == "-" {
                    Node::Neg(b(a)).folded()
                } else {
                    a
                };
                Ok((n, Kind::Number, pos))
            }
            None => self.power(),
        }
    }

    fn power(&mut self) -> Parsed {
        let (a, k, pos) = self.primary()?;
        if self.eat(&["^"]).is_none() {
            return Ok((a, k, pos));
        }
        expect_kind(Kind::Number, k, pos)?;
        let p = self.pos();
        // right-associative; the exponent may carry a sign: 2^-x^2 = 2^(-(x^2))
        let (e, ke, _) = self.unary()?;
        expect_kind(Kind::Number, ke, p)?;
        let node = match e {
            Node::Const(n) if n.fract() == 0.0 && n.abs() <= 1024.0 => Node::PowI(b(a), n as i32),
            e => Node::Call2(F2::Pow, b(a), b(e)),
        };
        Ok((node.folded(), Kind::Number, pos))
    }

    fn primary(&mut self) -> Parsed {
        let pos = self.pos();
        let Some(tok) = self.peek().cloned() else {
            return Err(syntax(pos, "unexpected end of the expression".into()));
        };
        self.at += 1;
        match tok {
            Tok::Num(v) => Ok((Node::Const(v), Kind::Number, pos)),
            Tok::Op("(") => {
                let (a, k, _) = self.or()?;
                self.expect(")")?;
                Ok((a, k, pos))
            }
            Tok::Ident(name) if self.peek() == Some(&Tok::Op("(")) => {
                self.at += 1;
                self.call(&name, pos)
            }
            Tok::Ident(name) => self.name(&name, pos),
            Tok::Op(o) => Err(syntax(pos, format!("unexpected '{o}'"))),
        }
    }

    fn name(&mut self, name: &str, pos: usize) -> Parsed {
        match self.scope.names.get(name) {
            Some(Binding::Var(i)) => Ok((Node::Var(*i), Kind::Number, pos)),
            Some(Binding::Value(n, k)) => Ok((n.clone(), *k, pos)),
            None if F1::from_name(name).is_some() || fun2(name).is_some() || name == "if" => Err(
                syntax(pos, format!("'{name}' is a function: write {name}(...)")),
            ),
            None => Err(ExprError {
                position: pos,
                kind: ExprErrorKind::UnknownVariable(name.to_string()),
            }),
        }
    }

    /// The arguments of a call, after its '(' : (node, type, position) of each.
    fn arguments(&mut self) -> Result<Vec<(Node, Kind, usize)>, ExprError> {
        let mut args = Vec::new();
        if self.eat(&[")"]).is_some() {
            return Ok(args);
        }
        loop {
            args.push(self.or()?);
            if self.eat(&[")"]).is_some() {
                return Ok(args);
            }
            if self.eat(&[","]).is_none() {
                let found = match self.tokens.get(self.at) {
                    Some(t) => t.tok.to_string(),
                    None => "the end of the expression".into(),
                };
                return Err(syntax(
                    self.pos(),
                    format!("expected ',' or ')', found {found}"),
                ));
            }
        }
    }

    fn call(&mut self, name: &str, pos: usize) -> Parsed {
        let (f1, f2) = (F1::from_name(name), fun2(name));
        if f1.is_none() && f2.is_none() && name != "if" {
            return Err(ExprError {
                position: pos,
                kind: ExprErrorKind::UnknownFunction(name.to_string()),
            });
        }
        let args = self.arguments()?;
        let found = args.len();
        let arity = |expected: &'static str| ExprError {
            position: pos,
            kind: ExprErrorKind::Arity {
                name: name.to_string(),
                expected,
                found,
            },
        };
        if name == "if" {
            let Ok([(c, kc, pc), (a, ka, _), (e, ke, pe)]) = <[_; 3]>::try_from(args) else {
                return Err(arity("3"));
            };
            expect_kind(Kind::Condition, kc, pc)?;
            expect_kind(ka, ke, pe)?;
            return Ok((Node::If(b(c), b(a), b(e)).folded(), ka, pos));
        }
        for (_, k, p) in &args {
            expect_kind(Kind::Number, *k, *p)?;
        }
        let mut nodes = args.iter().map(|(n, _, _)| n.clone());
        let node = match (f1, f2) {
            (Some(f), _) if args.len() == 1 => {
                Node::Call1(f, b(nodes.next().unwrap_or(Node::Const(0.0))))
            }
            (Some(_), _) => return Err(arity("1")),
            (_, Some(f @ (F2::Min | F2::Max))) if args.len() >= 2 => {
                let first = nodes.next().unwrap_or(Node::Const(0.0));
                nodes.fold(first, |acc, n| Node::Call2(f, b(acc), b(n)).folded())
            }
            (_, Some(F2::Min | F2::Max)) => return Err(arity("at least 2")),
            (_, Some(f)) if args.len() == 2 => {
                let a = nodes.next().unwrap_or(Node::Const(0.0));
                let c = nodes.next().unwrap_or(Node::Const(0.0));
                Node::Call2(f, b(a), b(c))
            }
            _ => return Err(arity("2")),
        };
        Ok((node.folded(), Kind::Number, pos))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn xy() -> Scope {
        Scope::new(&["x", "y"])
    }

    fn ev(s: &str, x: f64, y: f64) -> f64 {
        Expr::parse_kind(s, &xy(), None).unwrap().eval(&[x, y])
    }

    #[test]
    fn arithmetic_precedence_and_associativity() {
        assert_eq!(ev("1 + 2 * 3", 0.0, 0.0), 7.0);
        assert_eq!(ev("2 ^ 3 ^ 2", 0.0, 0.0), 512.0);
        assert_eq!(ev("-x^2", 3.0, 0.0), -9.0);
        assert_eq!(ev("2^-1", 0.0, 0.0), 0.5);
        assert_eq!(ev("x ** 2", 3.0, 0.0), 9.0);
        assert_eq!(ev("8 / 4 / 2", 0.0, 0.0), 1.0);
        assert_eq!(ev("10 - 4 - 3", 0.0, 0.0), 3.0);
        assert_eq!(ev("1.5e1 + .5 + 2E-1", 0.0, 0.0), 15.7);
        assert_eq!(ev("min(3, x, 2, y)", 5.0, 4.0), 2.0);
        assert_eq!(ev("max(x, y)", 5.0, 4.0), 5.0);
        assert_eq!(ev("atan2(y, x)", 1.0, 1.0), PI / 4.0);
        assert_eq!(ev("if(x < 0, -1, 1) * abs(x)", -2.0, 0.0), -2.0);
        assert_eq!(ev("x < 1 and not (y >= 2 || y == 0)", 0.0, 1.0), 1.0);
        assert_eq!(ev("x < 1 && !(y > 0)", 0.0, 1.0), 0.0);
        assert_eq!(ev("ln(e) + log10(100) + sqrt(4) + exp(0)", 0.0, 0.0), 6.0);
    }

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
    fn compiled_closures_give_the_bits_of_the_tree() {
        let mut s = xy();
        s.set_constant("c", 0.3).unwrap();
        let exprs = [
            "x + 1",
            "1 - x",
            "x*y",
            "2/x",
            "x - y",
            "c*x + y/c - 1",
            "-x^2 + y^3 - x^-1",
            "sqrt(x) + sin(x)*cos(y) - exp(-x) + ln(y) + abs(x - y) + tan(x) + atan2(y, x)",
            "min(x, 1 - x, y, 1 - y)",
            "max(sqrt(x - 0.5), y)",
            "hypot(x, y)^0.5",
            "if(x < 0.5 and not (y >= 0.5 or x == y), x < y, y != 0.25)",
            "if(sqrt(x - 0.5) < 1, 1, 2)",
            "floor(10*x) + ceil(10*y) + log10(x) + asin(y)",
        ];
        let pts = [-0.5, 0.0, 0.25, 0.5, 0.7, 1.0, f64::NAN];
        for src in exprs {
            let e = Expr::parse_kind(src, &s, None).unwrap();
            for &x in &pts {
                for &y in &pts {
                    let (a, b) = (e.eval(&[x, y]), e.eval_tree(&[x, y]));
                    assert!(
                        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                        "{src} at ({x}, {y}): {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn constants_fold_and_nan_propagates() {
        let e = Expr::parse("2*pi + 1", &xy()).unwrap();
        assert_eq!(e.as_constant(), Some(2.0 * PI + 1.0));
        assert!(ev("if(sqrt(x) > 1, 1, 2)", -1.0, 0.0).is_nan());
        assert!(ev("min(sqrt(x), 1)", -1.0, 0.0).is_nan());
        assert!(
            Expr::parse_condition("x < sqrt(y)", &xy())
                .unwrap()
                .holds(&[0.0, -1.0])
                .is_none()
        );
        // the branch not taken is not evaluated, so its NaN does not matter
        assert_eq!(ev("if(x <= 1, sqrt(1 - x^2), -1)", 2.0, 0.0), -1.0);
    }

    #[test]
    fn scope_binds_parameters_and_definitions() {
        let mut s = xy();
        s.set_constant("C", -5.0).unwrap();
        let r = Expr::parse("sqrt(x^2 + y^2)", &s).unwrap();
        s.define("r", &r).unwrap();
        let e = Expr::parse("C * r", &s).unwrap();
        assert_eq!(e.eval(&[3.0, 4.0]), -25.0);
        assert!(s.set_constant("x", 1.0).is_err());
        assert!(s.set_constant("sin", 1.0).is_err());
        assert!(s.set_constant("and", 1.0).is_err());
        assert!(s.set_constant("2a", 1.0).is_err());
    }

    fn err(s: &str) -> ExprError {
        Expr::parse(s, &xy()).unwrap_err()
    }

    #[test]
    fn errors_have_positions() {
        assert_eq!(
            err("sin(2*pi*z)"),
            ExprError {
                position: 10,
                kind: ExprErrorKind::UnknownVariable("z".into())
            }
        );
        assert_eq!(
            err("1 + foo(x)").kind,
            ExprErrorKind::UnknownFunction("foo".into())
        );
        assert_eq!(err("1 + foo(x)").position, 5);
        assert_eq!(err("(x + 1").position, 7);
        assert_eq!(err("x + * 2").position, 5);
        assert_eq!(err("x $ 2").position, 3);
        assert_eq!(err("1e+").position, 1);
        assert!(matches!(
            err("atan2(x)").kind,
            ExprErrorKind::Arity { found: 1, .. }
        ));
        assert!(matches!(err("min(x)").kind, ExprErrorKind::Arity { .. }));
        assert!(matches!(err("x < 1").kind, ExprErrorKind::Type { .. }));
        assert_eq!(err("if(x, 1, 2)").position, 4);
        assert_eq!(err("(x < 1) + 2").position, 1);
        assert_eq!(err("0 < x < 1").position, 7);
        assert_eq!(err("sin + 1").position, 1);
        assert_eq!(err("").position, 1);
        assert_eq!(err("x y").position, 3);
        assert!(err("x y").to_string().contains("at character 3"));
        let c = Expr::parse_condition("x + 1", &xy()).unwrap_err();
        assert!(
            c.to_string()
                .contains("expected a condition, found a number")
        );
    }

    #[test]
    fn expressions_are_shareable_between_threads() {
        fn sync<T: Send + Sync>() {}
        sync::<Expr>();
    }
}
