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
//! `src/problem/expr.pest`, which fixes the precedence above; pest reports syntax errors at the
//! furthest position it reached, with what it expected there. This module turns pest's tree into
//! a typed tree: it resolves names, checks types (with the position of the offending operand),
//! inlines definitions, folds constants and compiles the result for evaluation.
//!
//! Evaluation is this module's, not an expression crate's. The maintained, permissively licensed
//! evaluator, exmex (MIT/Apache-2.0; evalexpr is AGPL from 12.0 on, fasteval and meval have had
//! no release since 2020 and 2017), was tried on this language (exmex 0.20, `parse::<f64>`):
//! `-x^2` at x = 3 gives +9 (unary minus binds tighter than `^`), `2^3^2` gives 64 (`^` is
//! left-associative), `1e-10*x` is a parse error, `min(x, y, 3)` is a parse error, and its errors
//! carry no position. Its value type for conditions (`a if c else b`) makes a comparison with a
//! NaN operand false, so a NaN silently chooses a branch. A user's `-x^2` silently meaning x² is
//! a wrong answer with exit status 0, which this project does not allow; so the grammar is
//! pest's, and the semantics (the table above, NaN propagation, the floating-point operations
//! of the built-in problems bit for bit) are written and tested here.
//!
//! An [`Expr`] keeps its tree (for inlining definitions and folding) and the tree compiled to
//! nested closures, one per node, with constant and variable operands of arithmetic inlined:
//! [`Expr::eval`] calls them, allocating nothing, from any thread (`Send + Sync`). This runs
//! 3 to 6 times faster than walking the tree ([`Expr::eval_tree`], the reference semantics,
//! which gives the same bits), and within a small factor of a Rust closure.
//!
//! A definition is inlined where it is used, so a definition used several times would be
//! computed several times. Before compiling, every sub-tree used more than once is hoisted into
//! a slot computed once per evaluation, before the rest, which reads it like a variable (see
//! `hoist`). On `problems/ex9.toml`, where `r = sqrt(x^2 + y^2)` is used three or four times
//! per expression, this makes the exact solution about 1.4 times faster to evaluate.

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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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

    /// The depth of the tree (a leaf is 1), computed without recursion.
    fn depth(&self) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(self, 1)];
        while let Some((n, d)) = stack.pop() {
            deepest = deepest.max(d);
            stack.extend(children(n).into_iter().map(|c| (c, d + 1)));
        }
        deepest
    }

    fn is_constant(&self) -> bool {
        match self {
            Node::Const(_) => true,
            Node::Var(_) => false,
            n => children(n).iter().all(|c| c.is_constant()),
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
        Node::PowI(a, 2) if matches!(**a, Node::Var(_)) => {
            let Node::Var(i) = **a else {
                unreachable!("matched above")
            };
            Box::new(move |v| v[i] * v[i])
        }
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
        Node::Cmp(c, a, b) if matches!(**b, Node::Const(_)) => {
            let Node::Const(k) = **b else {
                unreachable!("matched above")
            };
            let (c, a) = (*c, compile(a));
            Box::new(move |v| c.apply(a(v), k))
        }
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

// ------------------------------------------------------------------------------------------
// Shared sub-expressions. A definition is inlined wherever it is used, so `r = sqrt(x^2 + y^2)`
// used three times puts three copies of its tree into the expression. [`hoist`] finds every
// sub-tree that occurs more than once (by structure, constants compared by their bits), and
// [`Compiled`] computes each once per evaluation, into a slot after the variables, before the
// root, which reads the slot as a variable. Each slot is the same operations on the same
// operands as every copy it replaces, so the value has the same bits as the tree's.
//
// A slot is computed even when its copies all lie in a branch of `if` that is not taken (or
// after an `and`/`or` that stops early): that costs its operations, but the value is not used,
// so a NaN there does not matter, exactly as for the tree.

/// The most values one evaluation keeps on the stack: the variables, then the slots.
const MAX_SLOTS: usize = 16;

/// A node of the tree, for hash-consing: its kind and payload, and its children by id.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Const(u64),
    Var(usize),
    Neg(u32),
    Not(u32),
    Call1(F1, u32),
    Call2(F2, u32, u32),
    PowI(u32, i32),
    Cmp(Cmp, u32, u32),
    And(u32, u32),
    Or(u32, u32),
    If(u32, u32, u32),
}

/// The state of [`hoist`]: an id per distinct sub-tree, how often each occurs, and the slots
/// given so far.
struct Hoist {
    ids: HashMap<Key, u32>,
    count: Vec<u32>,
    slot: Vec<Option<usize>>,
    defs: Vec<Node>,
    n_vars: usize,
}

impl Hoist {
    /// The id of `n`'s sub-tree, given its children's ids (registered if new).
    fn id(&mut self, n: &Node, c: &[u32]) -> u32 {
        let key = match n {
            Node::Const(v) => Key::Const(v.to_bits()),
            Node::Var(i) => Key::Var(*i),
            Node::Neg(_) => Key::Neg(c[0]),
            Node::Not(_) => Key::Not(c[0]),
            Node::Call1(f, _) => Key::Call1(*f, c[0]),
            Node::Call2(f, _, _) => Key::Call2(*f, c[0], c[1]),
            Node::PowI(_, k) => Key::PowI(c[0], *k),
            Node::Cmp(f, _, _) => Key::Cmp(*f, c[0], c[1]),
            Node::And(..) => Key::And(c[0], c[1]),
            Node::Or(..) => Key::Or(c[0], c[1]),
            Node::If(..) => Key::If(c[0], c[1], c[2]),
        };
        let next = self.count.len() as u32;
        let id = *self.ids.entry(key).or_insert(next);
        if id == next {
            self.count.push(0);
            self.slot.push(None);
        }
        id
    }

    /// First pass: registers every sub-tree of `n`, and counts for each how many distinct
    /// sub-trees use it as a child (with multiplicity: `a*a` uses `a` twice). Those counts are
    /// the uses once every sub-tree is computed once (a DAG); only a sub-tree used twice or more
    /// needs a slot. In `if(r <= 1, sqrt(1 - r^2), -1)`, r is used three times but the `x^2`
    /// inside it once: it is computed once, as part of r.
    fn count(&mut self, n: &Node) -> u32 {
        let c: Vec<u32> = children(n).into_iter().map(|a| self.count(a)).collect();
        let known = self.count.len();
        let id = self.id(n, &c);
        if id as usize >= known {
            for &k in &c {
                self.count[k as usize] += 1;
            }
        }
        id
    }

    /// Second pass: `n` with every sub-tree that occurs more than once replaced by its slot,
    /// the slot's definition pushed (after those of its own shared sub-trees) at its first
    /// occurrence.
    fn rewrite(&mut self, n: &Node) -> (u32, Node) {
        let (c, kids): (Vec<u32>, Vec<Node>) =
            children(n).into_iter().map(|a| self.rewrite(a)).unzip();
        let id = self.id(n, &c);
        let node = with_children(n, kids);
        let shared = self.count[id as usize] > 1 && !c.is_empty();
        if !shared {
            return (id, node);
        }
        if let Some(s) = self.slot[id as usize] {
            return (id, Node::Var(self.n_vars + s));
        }
        if self.n_vars + self.defs.len() >= MAX_SLOTS {
            return (id, node);
        }
        let s = self.defs.len();
        self.defs.push(node);
        self.slot[id as usize] = Some(s);
        (id, Node::Var(self.n_vars + s))
    }
}

/// The children of a node, in order.
fn children(n: &Node) -> Vec<&Node> {
    match n {
        Node::Const(_) | Node::Var(_) => vec![],
        Node::Neg(a) | Node::Not(a) | Node::Call1(_, a) | Node::PowI(a, _) => vec![a],
        Node::Call2(_, a, b) | Node::Cmp(_, a, b) | Node::And(a, b) | Node::Or(a, b) => {
            vec![a, b]
        }
        Node::If(c, a, b) => vec![c, a, b],
    }
}

/// `n` with its children replaced by `kids` (in the order of [`children`]).
fn with_children(n: &Node, kids: Vec<Node>) -> Node {
    let mut k = kids.into_iter().map(Box::new);
    let mut next = || k.next().expect("one child per child of the node");
    match n {
        Node::Const(_) | Node::Var(_) => n.clone(),
        Node::Neg(_) => Node::Neg(next()),
        Node::Not(_) => Node::Not(next()),
        Node::Call1(f, _) => Node::Call1(*f, next()),
        Node::Call2(f, _, _) => Node::Call2(*f, next(), next()),
        Node::PowI(_, p) => Node::PowI(next(), *p),
        Node::Cmp(f, _, _) => Node::Cmp(*f, next(), next()),
        Node::And(..) => Node::And(next(), next()),
        Node::Or(..) => Node::Or(next(), next()),
        Node::If(..) => Node::If(next(), next(), next()),
    }
}

/// The sub-trees of `root` that occur more than once, as slot definitions (slot j is variable
/// `n_vars + j`; a definition reads only the variables and earlier slots), and `root` reading
/// them. At most `MAX_SLOTS - n_vars` slots; a shared sub-tree beyond them stays inline.
fn hoist(root: &Node, n_vars: usize) -> (Vec<Node>, Node) {
    let mut h = Hoist {
        ids: HashMap::new(),
        count: Vec::new(),
        slot: Vec::new(),
        defs: Vec::new(),
        n_vars,
    };
    h.count(root);
    let (_, root) = h.rewrite(root);
    (h.defs, root)
}

/// A tree compiled for evaluation: its shared sub-trees (see [`hoist`]) and its root.
struct Compiled {
    n_vars: usize,
    slots: Vec<Fun>,
    root: Fun,
}

impl Compiled {
    fn new(root: &Node, n_vars: usize) -> Compiled {
        let (defs, root) = hoist(root, n_vars);
        Compiled {
            n_vars,
            slots: defs.iter().map(compile).collect(),
            root: compile(&root),
        }
    }

    /// The value at `vars`: the slots in order, then the root.
    #[inline]
    fn eval(&self, vars: &[f64]) -> f64 {
        if self.slots.is_empty() {
            return (self.root)(vars);
        }
        let n = self.n_vars;
        let mut buf = [0.0; MAX_SLOTS];
        buf[..n].copy_from_slice(&vars[..n]);
        for (j, f) in self.slots.iter().enumerate() {
            buf[n + j] = f(&buf[..n + j]);
        }
        (self.root)(&buf[..n + self.slots.len()])
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
    /// `root` compiled to nested closures (see [`compile`]), its shared sub-trees hoisted
    /// (see [`hoist`]).
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

// ------------------------------------------------------------------------------------------
// Parser: pest parses with the grammar of `expr.pest`; `Builder` turns the parse tree into a
// typed tree, resolving names and folding constants. Each build returns the node, its type and
// the 1-based character position where it starts.

/// The pest parser of `expr.pest` and its rules (the enum `Rule`, generated, one variant per
/// rule of the grammar).
mod grammar {
    #![allow(missing_docs)]
    #[derive(pest_derive::Parser)]
    #[grammar = "problem/expr.pest"]
    pub(super) struct Grammar;
}
use grammar::{Grammar, Rule};

type Pair<'i> = pest::iterators::Pair<'i, Rule>;

type Parsed = Result<(Node, Kind, usize), ExprError>;

/// What [`Builder::head`] returns.
type Head<'i> = (
    (Node, Kind, usize),
    Option<(Pair<'i>, Pair<'i>)>,
    pest::iterators::Pairs<'i, Rule>,
);

fn syntax(pos: usize, msg: String) -> ExprError {
    ExprError {
        position: pos,
        kind: ExprErrorKind::Syntax(msg),
    }
}

/// 1-based character position of the byte offset `byte` of `src`.
fn char_position(src: &str, byte: usize) -> usize {
    src.get(..byte).map_or(byte, |s| s.chars().count()) + 1
}

/// A pest error as an [`ExprError`]: what the grammar expected at the furthest position it
/// reached, and what it found there.
fn syntax_error(src: &str, e: &pest::error::Error<Rule>) -> ExprError {
    use pest::error::{ErrorVariant, InputLocation};
    let byte = match e.location {
        InputLocation::Pos(p) => p,
        InputLocation::Span((s, _)) => s,
    };
    let found = match src.get(byte..).and_then(|s| s.chars().next()) {
        Some(c) => format!("'{c}'"),
        None => "the end of the expression".into(),
    };
    let expected = match &e.variant {
        ErrorVariant::ParsingError { positives, .. } => {
            // each description once, in the order pest gives the rules
            let mut what: Vec<&str> = Vec::new();
            for w in positives.iter().map(|r| describe(*r)) {
                if !what.contains(&w) {
                    what.push(w);
                }
            }
            match what.split_last() {
                Some((last, [])) => last.to_string(),
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => "something else".into(),
            }
        }
        ErrorVariant::CustomError { message } => message.clone(),
    };
    syntax(
        char_position(src, byte),
        format!("expected {expected}, found {found}"),
    )
}

/// What a grammar rule is, for error messages.
fn describe(r: Rule) -> &'static str {
    match r {
        Rule::EOI => "the end of the expression",
        Rule::open => "'('",
        Rule::close => "')'",
        Rule::comma => "','",
        Rule::or_op
        | Rule::and_op
        | Rule::cmp_op
        | Rule::sum_op
        | Rule::product_op
        | Rule::pow_op => "an operator",
        _ => "a number, a name or '('",
    }
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

/// The longest expression accepted, in characters: it bounds the depth of the tree (a chain
/// of n operators is n deep), which the recursive folding, compilation and evaluation walk.
pub const MAX_LENGTH: usize = 4096;
/// The deepest nesting of parentheses accepted: it bounds the recursion of the parser.
pub const MAX_NESTING: usize = 64;

/// The deepest tree accepted, definitions inlined: it bounds the recursion of compilation and
/// evaluation (a definition used in a definition adds its depth).
pub const MAX_DEPTH: usize = 2048;

/// An error if `source` is longer than [`MAX_LENGTH`] or nests parentheses deeper than
/// [`MAX_NESTING`] (so that no input can exhaust the stack).
fn check_size(source: &str) -> Result<(), ExprError> {
    let n = source.chars().count();
    if n > MAX_LENGTH {
        return Err(syntax(
            MAX_LENGTH + 1,
            format!("the expression has {n} characters, more than the {MAX_LENGTH} accepted"),
        ));
    }
    let mut depth = 0usize;
    for (i, c) in source.chars().enumerate() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            _ => {}
        }
        if depth > MAX_NESTING {
            return Err(syntax(
                i + 1,
                format!("parentheses nested more than {MAX_NESTING} deep"),
            ));
        }
    }
    Ok(())
}

/// Parses `source` in `scope` into a typed tree.
fn parse_tree(source: &str, scope: &Scope) -> Parsed {
    use pest::Parser as _;
    check_size(source)?;
    let mut pairs =
        Grammar::parse(Rule::expression, source).map_err(|e| syntax_error(source, &e))?;
    let top = pairs.next().and_then(|p| p.into_inner().next());
    let Some(top) = top else {
        return Err(syntax(1, "empty expression".into()));
    };
    let (root, kind, pos) = Builder { scope, source }.build(top)?;
    let depth = root.depth();
    if depth > MAX_DEPTH {
        return Err(syntax(
            1,
            format!(
                "the expression is {depth} operations deep (definitions inlined), more than \
                 the {MAX_DEPTH} accepted"
            ),
        ));
    }
    Ok((root, kind, pos))
}

/// Builds typed trees from pest pairs.
struct Builder<'a> {
    scope: &'a Scope,
    source: &'a str,
}

impl Builder<'_> {
    /// The first operand of `it`, built.
    fn first(&self, it: &mut pest::iterators::Pairs<Rule>) -> Parsed {
        let first = it
            .next()
            .ok_or_else(|| syntax(1, "missing operand".into()))?;
        self.build(first)
    }

    /// For `operand (op operand)…` rules (comparison, power): the first operand built, the
    /// operator and operand after it if any, and the pairs that follow.
    fn head<'i>(&self, p: Pair<'i>) -> Result<Head<'i>, ExprError> {
        let mut it = p.into_inner();
        let first = self.first(&mut it)?;
        let next = match (it.next(), it.next()) {
            (Some(op), Some(operand)) => Some((op, operand)),
            _ => None,
        };
        Ok((first, next, it))
    }

    fn pos(&self, p: &Pair) -> usize {
        char_position(self.source, p.as_span().start())
    }

    fn build(&self, p: Pair) -> Parsed {
        match p.as_rule() {
            Rule::disjunction => self.left_fold(p, Kind::Condition, |_, a, c| Node::Or(b(a), b(c))),
            Rule::conjunction => {
                self.left_fold(p, Kind::Condition, |_, a, c| Node::And(b(a), b(c)))
            }
            Rule::negation => {
                self.prefixed(p, Kind::Condition, false, |_, a| Node::Not(b(a)).folded())
            }
            Rule::comparison => self.comparison(p),
            Rule::sum | Rule::product => self.left_fold(p, Kind::Number, |op, a, c| {
                let f = match op {
                    "+" => F2::Add,
                    "-" => F2::Sub,
                    "*" => F2::Mul,
                    _ => F2::Div,
                };
                Node::Call2(f, b(a), b(c))
            }),
            Rule::signed => self.prefixed(p, Kind::Number, true, |op, a| match op {
                "-" => Node::Neg(b(a)).folded(),
                _ => a,
            }),
            Rule::power => self.power(p),
            Rule::primary => self.primary(p),
            r => Err(syntax(self.pos(&p), format!("unexpected {r:?}"))),
        }
    }

    /// `operand (op operand)*`, left-associative, on operands of type `kind` (logical
    /// operators on conditions, `+ -` and `* /` on numbers); `combine(op, a, c)` is the node.
    fn left_fold(&self, p: Pair, kind: Kind, combine: fn(&str, Node, Node) -> Node) -> Parsed {
        let mut it = p.into_inner();
        let (mut a, k, pos) = self.first(&mut it)?;
        while let (Some(op), Some(operand)) = (it.next(), it.next()) {
            expect_kind(kind, k, pos)?;
            let (c, kc, pc) = self.build(operand)?;
            expect_kind(kind, kc, pc)?;
            a = combine(op.as_str(), a, c).folded();
        }
        Ok((a, k, pos))
    }

    /// `sum (cmp sum)?`; a second comparison operator is an error.
    fn comparison(&self, p: Pair) -> Parsed {
        let ((a, k, pos), next, mut it) = self.head(p)?;
        let Some((op, second)) = next else {
            return Ok((a, k, pos));
        };
        let cmp = match op.as_str() {
            "<" => Cmp::Lt,
            "<=" => Cmp::Le,
            ">" => Cmp::Gt,
            ">=" => Cmp::Ge,
            "==" => Cmp::Eq,
            _ => Cmp::Ne,
        };
        expect_kind(Kind::Number, k, pos)?;
        let (c, kc, pc) = self.build(second)?;
        expect_kind(Kind::Number, kc, pc)?;
        if let Some(chained) = it.next() {
            return Err(syntax(
                self.pos(&chained),
                format!(
                    "comparisons cannot be chained ('{}'): use 'and'",
                    chained.as_str()
                ),
            ));
        }
        Ok((Node::Cmp(cmp, b(a), b(c)).folded(), Kind::Condition, pos))
    }

    /// `op* operand` for the prefix operators `not` (`negation`) and signs (`signed`): they
    /// apply from the innermost (last) out, to an operand of type `needs`; a type error is
    /// reported at the operand, or at the last operator if `at_operator`.
    fn prefixed(
        &self,
        p: Pair,
        needs: Kind,
        at_operator: bool,
        apply: fn(&str, Node) -> Node,
    ) -> Parsed {
        let pos = self.pos(&p);
        let mut ops = Vec::new();
        let mut operand = None;
        for q in p.into_inner() {
            match q.as_rule() {
                Rule::not_op | Rule::sign => ops.push((q.as_str(), self.pos(&q))),
                _ => operand = Some(q),
            }
        }
        let operand = operand.ok_or_else(|| syntax(pos, "missing operand".into()))?;
        let (mut a, k, pc) = self.build(operand)?;
        let Some(&(_, last)) = ops.last() else {
            return Ok((a, k, pc));
        };
        expect_kind(needs, k, if at_operator { last } else { pc })?;
        for &(op, _) in ops.iter().rev() {
            a = apply(op, a);
        }
        Ok((a, needs, pos))
    }

    /// `primary (^ signed)?`; an integer constant exponent becomes `powi`.
    fn power(&self, p: Pair) -> Parsed {
        let ((a, k, pos), next, _) = self.head(p)?;
        let Some((_op, exponent)) = next else {
            return Ok((a, k, pos));
        };
        expect_kind(Kind::Number, k, pos)?;
        let (e, ke, pe) = self.build(exponent)?;
        expect_kind(Kind::Number, ke, pe)?;
        let node = match e {
            Node::Const(n) if n.fract() == 0.0 && n.abs() <= 1024.0 => Node::PowI(b(a), n as i32),
            e => Node::Call2(F2::Pow, b(a), b(e)),
        };
        Ok((node.folded(), Kind::Number, pos))
    }

    /// A number, a call, a name or a parenthesised expression (which starts at its '(').
    fn primary(&self, p: Pair) -> Parsed {
        let pos = self.pos(&p);
        let mut it = p.into_inner();
        let q = it
            .next()
            .ok_or_else(|| syntax(pos, "missing operand".into()))?;
        match q.as_rule() {
            Rule::number => {
                let s = q.as_str();
                let v = s
                    .parse::<f64>()
                    .map_err(|_| syntax(pos, format!("malformed number '{s}'")))?;
                Ok((Node::Const(v), Kind::Number, pos))
            }
            Rule::malformed => Err(syntax(
                pos,
                format!("malformed exponent in number '{}'", q.as_str()),
            )),
            Rule::name => self.name(q.as_str(), pos),
            Rule::call => self.call(q, pos),
            _ => {
                let inner = it
                    .next()
                    .ok_or_else(|| syntax(pos, "missing operand".into()))?;
                let (a, k, _) = self.build(inner)?;
                Ok((a, k, pos))
            }
        }
    }

    fn name(&self, name: &str, pos: usize) -> Parsed {
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

    fn call(&self, p: Pair, pos: usize) -> Parsed {
        let mut it = p.into_inner();
        let name = it.next().map(|n| n.as_str()).unwrap_or_default();
        let (f1, f2) = (F1::from_name(name), fun2(name));
        if f1.is_none() && f2.is_none() && name != "if" {
            return Err(ExprError {
                position: pos,
                kind: ExprErrorKind::UnknownFunction(name.to_string()),
            });
        }
        let args = it
            .filter(|q| !matches!(q.as_rule(), Rule::open | Rule::close | Rule::comma))
            .map(|q| self.build(q))
            .collect::<Result<Vec<_>, _>>()?;
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
            // shared sub-trees (hoisted into slots), nested, and in a branch not taken
            "sqrt(x^2 + y^2) + ln(sqrt(x^2 + y^2)) * sqrt(x^2 + y^2)",
            "if(sqrt(x^2 + y^2) <= 0.7, if(sqrt(x^2 + y^2) <= 1, sqrt(1 - sqrt(x^2 + y^2)^2), -1), -ln(sqrt(x^2 + y^2)))",
            "if(x < 0, sqrt(x - 1) + sqrt(x - 1), y)",
            "exp(x*y) * exp(x*y) - (x*y) + sin(exp(x*y) + (x*y)) + if(x*y < 0.1 and x*y > -0.1, x*y, 2)",
            "0.0*x + -0.0*x + 0.0*x - -0.0*x",
            "(x+1)*(x+1) + (x+2)*(x+2) + (x+3)*(x+3) + (x+4)*(x+4) + (x+5)*(x+5) + (x+6)*(x+6) + (x+7)*(x+7) + (x+8)*(x+8) + (x+9)*(x+9) + (x+10)*(x+10) + (x+11)*(x+11) + (x+12)*(x+12) + (x+13)*(x+13) + (x+14)*(x+14) + (x+15)*(x+15) + (x+16)*(x+16) + (y+1)/(y+1)",
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
    fn shared_sub_trees_are_computed_once() {
        let mut s = xy();
        let r = Expr::parse("sqrt(x^2 + y^2)", &s).unwrap();
        s.define("r", &r).unwrap();
        let slots = |src: &str| Expr::parse(src, &s).unwrap().fun.slots.len();
        // r, and nothing inside it (x^2 is used once, by r)
        assert_eq!(
            slots("if(r <= 0.7, if(r <= 1, sqrt(1 - r^2), -1), -ln(r))"),
            1
        );
        assert_eq!(slots("r + r^2 + r*(x^2 + 1)"), 2);
        assert_eq!(slots("r"), 0);
        assert_eq!(slots("x*x + x*y"), 0);
        assert_eq!(slots("(x + 1)*(x + 1)"), 1);
        // constants equal by value but not by bits are not merged
        assert_eq!(slots("(0.0*x)*(-0.0*x)"), 0);
        // at most MAX_SLOTS values: the two variables and 14 slots
        let many: Vec<String> = (1..=20).map(|k| format!("(x+{k})*(x+{k})")).collect();
        let e = Expr::parse(&many.join(" + "), &s).unwrap();
        assert_eq!(e.fun.slots.len(), MAX_SLOTS - 2);
        assert_eq!(e.eval(&[0.5, 0.0]), e.eval_tree(&[0.5, 0.0]));
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
        assert_eq!(err("1e+").position, 1);
        assert!(err("1e+").to_string().contains("malformed exponent"));
        assert!(
            err("(x + 1")
                .to_string()
                .contains("expected an operator or ')'")
        );
        assert!(err("x $ 2").to_string().contains("found '$'"));
        assert_eq!(err("x < 1 andy").position, 7);
        assert_eq!(err("x or").position, 5);
        assert_eq!(err("not x").position, 5);
        assert_eq!(err("1 + and").position, 5);
        assert_eq!(err("é + 1").position, 1);
        // sizes that could exhaust the stack are refused, with a position
        let deep = format!("{}x{}", "(".repeat(100), ")".repeat(100));
        assert_eq!(err(&deep).position, MAX_NESTING + 1);
        assert_eq!(err(&"-x".repeat(3000)).position, MAX_LENGTH + 1);
        let nested = format!("{}x{}", "(".repeat(MAX_NESTING), ")".repeat(MAX_NESTING));
        assert!(Expr::parse(&nested, &xy()).is_ok());
        let chain = format!("x{}", " + x".repeat((MAX_LENGTH - 1) / 4));
        let e = Expr::parse(&chain, &xy()).unwrap();
        assert_eq!(e.eval(&[1.0, 0.0]), (1 + (MAX_LENGTH - 1) / 4) as f64);
        // a definition used in a definition adds its depth
        let mut s = xy();
        let mut def = String::from("x");
        for k in 0..4 {
            let e = Expr::parse(&format!("{def}{}", " + x".repeat(600)), &s);
            if k < 3 {
                s.define(&format!("d{k}"), &e.unwrap()).unwrap();
                def = format!("d{k}");
            } else {
                assert!(e.unwrap_err().to_string().contains("more than the 2048"));
            }
        }
        let signs = format!("{}x", "-".repeat(MAX_DEPTH - 1));
        assert_eq!(Expr::parse(&signs, &xy()).unwrap().eval(&[1.0, 0.0]), -1.0);
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
