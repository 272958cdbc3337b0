//! Parsing: pest parses with the grammar of `expr.pest` (beside this file); [`Builder`] turns
//! the parse tree into a typed tree, resolving names, checking types and folding constants.
//! Each build returns the node, its type and the 1-based character position where it starts;
//! every error carries such a position. The size limits keep every recursion over the input
//! or the tree within the stack.

use super::scope::{Binding, Scope};
use super::tree::{Cmp, F1, F2, Node, b, fun2};
use super::{ExprError, ExprErrorKind, Kind};

/// The pest parser of `expr.pest` and its rules (the enum `Rule`, generated, one variant per
/// rule of the grammar).
mod grammar {
    #![allow(missing_docs)]
    #[derive(pest_derive::Parser)]
    #[grammar = "problem/expr/expr.pest"]
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

/// `Err` (a type error at `pos`) unless `found` is `expected`.
pub(super) fn expect_kind(expected: Kind, found: Kind, pos: usize) -> Result<(), ExprError> {
    if expected == found {
        Ok(())
    } else {
        Err(ExprError {
            position: pos,
            kind: ExprErrorKind::Type { expected, found },
        })
    }
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
pub(super) fn parse_tree(source: &str, scope: &Scope) -> Parsed {
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
    use super::{MAX_DEPTH, MAX_LENGTH, MAX_NESTING};
    use crate::problem::expr::testing::{err, ev, xy};
    use crate::problem::expr::{Expr, ExprError, ExprErrorKind};
    use std::f64::consts::PI;

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
        let c = Expr::parse_condition("x + 1", &xy()).unwrap_err();
        assert!(
            c.to_string()
                .contains("expected a condition, found a number")
        );
    }

    #[test]
    fn sizes_that_could_exhaust_the_stack_are_refused_with_a_position() {
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
    }
}
