//! The syntax tree of an expression, its operators and functions, and its direct evaluation
//! (the reference semantics: the compiled closures of `compile` give the same bits).

/// Functions of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum F1 {
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
    pub(super) fn from_name(n: &str) -> Option<F1> {
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
    pub(super) fn apply(self, a: f64) -> f64 {
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
pub(super) enum F2 {
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
    pub(super) fn apply(self, a: f64, b: f64) -> f64 {
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
pub(super) enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

impl Cmp {
    pub(super) fn apply(self, a: f64, b: f64) -> f64 {
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

pub(super) fn bool_value(t: bool) -> f64 {
    if t { 1.0 } else { 0.0 }
}

/// The expression tree. Conditions evaluate to 1.0 (true), 0.0 (false) or NaN (undecidable).
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Node {
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
    pub(super) fn eval(&self, v: &[f64]) -> f64 {
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
    pub(super) fn folded(self) -> Node {
        if self.is_constant() {
            Node::Const(self.eval(&[]))
        } else {
            self
        }
    }

    /// The depth of the tree (a leaf is 1), computed without recursion.
    pub(super) fn depth(&self) -> usize {
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

/// The children of a node, in order.
pub(super) fn children(n: &Node) -> Vec<&Node> {
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
pub(super) fn with_children(n: &Node, kids: Vec<Node>) -> Node {
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

/// `n`, boxed (a child of a node).
pub(super) fn b(n: Node) -> Box<Node> {
    Box::new(n)
}

/// The function of two arguments called `name`.
pub(super) fn fun2(name: &str) -> Option<F2> {
    Some(match name {
        "atan2" => F2::Atan2,
        "hypot" => F2::Hypot,
        "min" => F2::Min,
        "max" => F2::Max,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::{Cmp, F1, F2, Node, b, children, with_children};
    use crate::problem::expr::Expr;
    use crate::problem::expr::testing::{ev, xy};
    use std::f64::consts::PI;

    #[test]
    fn children_and_with_children_rebuild_every_node() {
        let (x, y) = (|| b(Node::Var(0)), || b(Node::Var(1)));
        let nodes = [
            Node::Const(2.5),
            Node::Var(1),
            Node::Neg(x()),
            Node::Not(x()),
            Node::Call1(F1::Sin, x()),
            Node::Call2(F2::Sub, x(), y()),
            Node::PowI(y(), 3),
            Node::Cmp(Cmp::Le, x(), y()),
            Node::And(x(), y()),
            Node::Or(y(), x()),
            Node::If(b(Node::Cmp(Cmp::Lt, x(), y())), y(), x()),
        ];
        for n in nodes {
            let kids: Vec<Node> = children(&n).into_iter().cloned().collect();
            assert_eq!(with_children(&n, kids), n);
        }
        let xy = Node::Call2(F2::Sub, x(), y());
        let k = children(&xy);
        assert_eq!((k[0], k[1]), (&Node::Var(0), &Node::Var(1)));
        // `If` picks the branch, evaluated at (x, y) = (1, 2); depth counts the levels
        let n = Node::If(b(Node::Cmp(Cmp::Lt, x(), y())), b(Node::Neg(y())), x());
        assert_eq!(n.eval(&[1.0, 2.0]), -2.0);
        assert_eq!(n.eval(&[3.0, 2.0]), 3.0);
        assert_eq!(n.depth(), 3);
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
}
