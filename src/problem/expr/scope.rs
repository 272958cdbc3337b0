//! The names an expression may use, and what each stands for.

use super::Expr;
use super::Kind;
use super::tree::{F1, Node, fun2};
use std::collections::HashMap;

/// What a name stands for in a [`Scope`].
#[derive(Debug, Clone)]
pub(super) enum Binding {
    Var(usize),
    Value(Node, Kind),
}

/// The names an expression may use: the evaluation variables (in the order of the slice passed
/// to [`Expr::eval`]), the constants `pi` and `e`, and named parameters and definitions.
#[derive(Debug, Clone)]
pub struct Scope {
    pub(super) names: HashMap<String, Binding>,
    pub(super) n_vars: usize,
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

#[cfg(test)]
mod tests {
    use crate::problem::expr::Expr;
    use crate::problem::expr::testing::xy;

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
}
