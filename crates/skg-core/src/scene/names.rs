//! The names of a scene's expressions: the reserved ones, the velocity suffix, the time
//! `t`, what a name means in a model expression ([`ExpressionNames`]), the parsing of
//! such an expression with its errors located in the file, and the rule for names.

use indexmap::IndexMap;
use skg_expr::{ExprId, Graph, ParseErrorKind, Symbol};
use toml::Spanned;

use super::error::SceneError;
use super::file::SceneFile;

/// Names the expression language reserves.
pub const RESERVED: &[&str] = &["pi", "sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sinh", "cosh", "tanh", "atan"];

/// Suffix that turns a coordinate name into its velocity: `x` → `x_dot`.
pub const VELOCITY_SUFFIX: &str = "_dot";

/// The name of the time in the model's expressions (Lagrangian, constraints, forces,
/// walls); no parameter or coordinate may take it.
pub const TIME: &str = "t";

/// What the names of a scene's model expressions mean: coordinate `i` is variable `i`,
/// its velocity `<name>_dot` variable `d + i`, the time `t` variable `time`, and a
/// parameter its value, or, in a fit's model, the expression `symbols` binds it to (a
/// free parameter is a variable, a parameter defined through one an expression of it).
#[derive(Debug, Clone, Copy)]
pub struct ExpressionNames<'a> {
    /// Coordinate names, in order.
    pub coordinates: &'a [String],
    /// Parameter values.
    pub parameters: &'a IndexMap<String, f64>,
    /// The variable index of the time `t`.
    pub time: usize,
    /// Parameters that stand for expressions of the graph parsed into (they take
    /// precedence over `parameters`); `None` outside a fit.
    pub symbols: Option<&'a IndexMap<String, ExprId>>,
}

impl ExpressionNames<'_> {
    /// What `name` means, or `None` if it is unknown.
    pub fn resolve(&self, name: &str) -> Option<Symbol> {
        let coordinate = |c: &str| self.coordinates.iter().position(|x| x == c);
        if let Some(i) = coordinate(name) {
            return Some(Symbol::Var(i));
        }
        if let Some(i) = name.strip_suffix(VELOCITY_SUFFIX).and_then(coordinate) {
            return Some(Symbol::Var(self.coordinates.len() + i));
        }
        if name == TIME {
            return Some(Symbol::Var(self.time));
        }
        if let Some(&e) = self.symbols.and_then(|s| s.get(name)) {
            return Some(Symbol::Expr(e));
        }
        self.parameters.get(name).map(|v| Symbol::Const(*v))
    }

    /// The list of valid names, for the hint of an unknown-name error.
    fn hint(&self) -> String {
        let mut names: Vec<String> = Vec::new();
        for c in self.coordinates {
            names.push(c.clone());
            names.push(format!("{c}{VELOCITY_SUFFIX}"));
        }
        names.push(TIME.to_string());
        names.extend(self.parameters.keys().cloned());
        format!("known names: {}, pi", names.join(", "))
    }
}

impl SceneFile {
    /// Parse a model expression (Lagrangian, constraint, force, wall) at the spanned
    /// string `src` into `graph`, with the meaning of names given by `names`. An error
    /// carries its position in the file and, for an unknown name, the list of known ones.
    pub fn parse_expression(
        &self,
        graph: &mut Graph,
        src: &Spanned<String>,
        key: &str,
        names: &ExpressionNames,
    ) -> Result<ExprId, SceneError> {
        graph.parse(src.get_ref(), &mut |name| names.resolve(name)).map_err(|mut e| {
            if e.kind == ParseErrorKind::UnknownSymbol {
                e.hint = Some(names.hint());
            }
            self.expression_error(src, key, e)
        })
    }
}

/// A name that cannot be a parameter, coordinate, constraint or wall.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{name}` is not a valid name (letters, digits and _, not starting with a digit)")]
pub struct InvalidName {
    /// The rejected name.
    pub name: String,
}

/// Check that `name` is an identifier of the expression language: ASCII letters, digits
/// and `_`, not starting with a digit.
pub(super) fn check_identifier(name: &str) -> Result<(), InvalidName> {
    let mut chars = name.chars();
    let ok = matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(InvalidName { name: name.to_string() })
    }
}
