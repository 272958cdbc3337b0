//! An expression tree compiled to nested closures, one per node, with constant and variable
//! operands of arithmetic inlined; its shared sub-trees are computed first, into slots (see
//! `hoist`).

use super::hoist::{MAX_SLOTS, hoist};
use super::tree::{F1, F2, Node, bool_value};

/// A compiled expression.
type Fun = Box<dyn Fn(&[f64]) -> f64 + Send + Sync>;

/// Compiles a tree into nested closures with the same semantics as [`Node::eval`]: each node
/// becomes a closure that calls its children's, so evaluation has no `match` on the node kind;
/// arithmetic with a constant or a variable operand is specialised so that leaves cost no call.
pub(super) fn compile(n: &Node) -> Fun {
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

/// A tree compiled for evaluation: its shared sub-trees (see [`hoist`]) and its root.
pub(super) struct Compiled {
    n_vars: usize,
    pub(super) slots: Vec<Fun>,
    root: Fun,
}

impl Compiled {
    pub(super) fn new(root: &Node, n_vars: usize) -> Compiled {
        let (defs, root) = hoist(root, n_vars);
        Compiled {
            n_vars,
            slots: defs.iter().map(compile).collect(),
            root: compile(&root),
        }
    }

    /// The value at `vars`: the slots in order, then the root.
    #[inline]
    pub(super) fn eval(&self, vars: &[f64]) -> f64 {
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

#[cfg(test)]
mod tests {
    use crate::problem::expr::Expr;
    use crate::problem::expr::testing::xy;

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
}
