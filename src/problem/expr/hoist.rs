//! Shared sub-expressions. A definition is inlined wherever it is used, so `r = sqrt(x^2 + y^2)`
//! used three times puts three copies of its tree into the expression. [`hoist`] finds every
//! sub-tree that occurs more than once (by structure, constants compared by their bits), and
//! [`Compiled`](super::compile::Compiled) computes each once per evaluation, into a slot after the variables, before the
//! root, which reads the slot as a variable. Each slot is the same operations on the same
//! operands as every copy it replaces, so the value has the same bits as the tree's.
//!
//! A slot is computed even when its copies all lie in a branch of `if` that is not taken (or
//! after an `and`/`or` that stops early): that costs its operations, but the value is not used,
//! so a NaN there does not matter, exactly as for the tree.

use super::tree::{Cmp, F1, F2, Node, children, with_children};
use std::collections::HashMap;

/// The most values one evaluation keeps on the stack: the variables, then the slots.
pub(super) const MAX_SLOTS: usize = 16;

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

/// The sub-trees of `root` that occur more than once, as slot definitions (slot j is variable
/// `n_vars + j`; a definition reads only the variables and earlier slots), and `root` reading
/// them. At most `MAX_SLOTS - n_vars` slots; a shared sub-tree beyond them stays inline.
pub(super) fn hoist(root: &Node, n_vars: usize) -> (Vec<Node>, Node) {
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

#[cfg(test)]
mod tests {
    use super::MAX_SLOTS;
    use crate::problem::expr::Expr;
    use crate::problem::expr::testing::xy;

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
}
