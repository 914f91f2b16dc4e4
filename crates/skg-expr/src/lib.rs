//! Symbolic expressions: parsing, simplification, exact derivatives of any order and
//! compiled evaluation tapes.
//!
//! A scene's Lagrangian `L(q, q̇, t)`, its constraints `g(q, q̇, t)` and its forces are
//! written as expression strings. They are parsed into a hash-consed DAG (a [`Graph`]):
//! every distinct subexpression exists once and is named by an [`ExprId`], so equal
//! subexpressions share one node no matter where, or in which expression, they appear.
//! [`Graph::diff`] differentiates symbolically (memoized per node and variable), so first,
//! second and third derivatives are exact expressions in the same graph. [`Tape::compile`]
//! turns any set of outputs (say a gradient, a Hessian and a third-derivative tensor) into
//! one straight-line program in which each shared subexpression is computed once;
//! [`Tape::eval`] runs it without allocating.
//!
//! ```
//! use skg_expr::{Graph, Symbol, Tape};
//!
//! let mut g = Graph::new();
//! // The caller decides what names mean: here x and x_dot are variables 0 and 1, m = 2.
//! let mut resolve = |name: &str| match name {
//!     "x" => Some(Symbol::Var(0)),
//!     "x_dot" => Some(Symbol::Var(1)),
//!     "m" => Some(Symbol::Const(2.0)),
//!     _ => None,
//! };
//! let lagrangian = g.parse("1/2*m*x_dot^2 - 1/2*x^2", &mut resolve).unwrap();
//! let p = g.diff(lagrangian, 1); // momentum m*x_dot
//! let dp = g.diff(p, 1); // mass m: a constant
//! assert_eq!(g.as_constant(dp), Some(2.0));
//!
//! let tape = Tape::compile(&g, &[lagrangian, p, dp], 2);
//! let mut scratch = vec![0.0; tape.scratch_len()];
//! let mut out = [0.0; 3];
//! tape.eval(&[1.0, 3.0], &mut scratch, &mut out);
//! assert_eq!(out, [8.5, 6.0, 2.0]);
//!
//! let err = g.parse("x + * x_dot", &mut resolve).unwrap_err();
//! assert_eq!(err.position, 4);
//! assert_eq!(err.caret_line(), "x + * x_dot\n    ^");
//! ```
//!
//! # Expression grammar
//!
//! ```text
//! expr    := term (("+" | "-") term)*
//! term    := unary (("*" | "/") unary)*
//! unary   := ("-" | "+") unary | power
//! power   := primary (("^" | "**") unary)?   (right-associative)
//! primary := number | name | name "(" expr ("," expr)* ")" | "(" expr ")"
//! number  := digits ["." digits] [exponent] | "." digits [exponent]
//!            (also "1." ; exponent := ("e" | "E") ["+" | "-"] digits)
//! name    := [A-Za-z_][A-Za-z0-9_]*
//! ```
//!
//! * `^` binds tighter than unary minus and is right-associative: `-x^2 = -(x^2)`,
//!   `2^3^2 = 2^(3^2) = 512`, and `x^-2 = x^(-2)`. `*` and `/` are left-associative
//!   (`8/4/2 = 1`), as are `+` and `-` (`1-2-3 = -4`). There is no implicit
//!   multiplication: write `2*x`, not `2x`. `**` is the same operator as `^` (Python's and
//!   SymPy's spelling of a power): `x**2 = x^2`, `2**3**2 = 512`.
//! * Functions of one argument: `sin cos tan exp log sqrt abs sinh cosh tanh atan`
//!   (`log` is the natural logarithm); of two arguments: `atan2(y, x)`.
//!   A name followed by `(` is always a function call.
//! * `pi` is built in. Every other name is the caller's business: the parser asks the
//!   caller's resolver what it means (a variable of the problem, such as a coordinate
//!   `x` or a velocity `x_dot` — whatever velocity syntax the caller has chosen — or the
//!   time `t`, or a named constant such as a mass `M`, which is folded in as a number, or
//!   an expression already in the graph, [`Symbol::Expr`]). A name the
//!   resolver does not know is a [`ParseError`] at that name's position, to which the
//!   caller can attach a hint listing the valid names ([`ParseError::with_hint`]).
//! * Whitespace is ignored. Positions in errors count characters (not bytes) from 0.
//!
//! # Differentiability
//!
//! `abs` is not differentiable at 0: its derivative is taken as `x/abs(x)`, which is NaN
//! at `x = 0`. Regularize kinks yourself, e.g. write `sqrt(x^2 + eps^2)` instead of
//! `abs(x)`. Likewise `a^b` with a non-constant exponent is differentiated as
//! `exp(b*log(a))` and so needs `a > 0`; with a constant exponent `c` the rule
//! `c*a^(c-1)*a'` is used and any base is fine.
//!
//! # Simplification
//!
//! The builders ([`Graph::add`], [`Graph::mul`], …) fold constants and apply identities
//! such as `x+0 = x`, `0*x = 0`, `1*x = x`, `x^1 = x`, `x^0 = 1`, `-(-x) = x`, `x-x = 0`,
//! `x/x = 1`, `c1*(c2*x) = (c1*c2)*x`. They follow IEEE semantics except that `0*x`,
//! `x-x` and `x/x` are simplified even where `x` might be infinite, NaN or zero.
//! Integer powers are kept as a separate node kind and evaluated by repeated
//! multiplication.
#![warn(missing_docs)]

// The modules, each using only those before it: `hash` (the tables' hasher), `node` (the
// node kinds and the elementary functions), `graph` (the hash-consed graph: interning,
// inspection, direct evaluation), `simplify` (the simplifying builders), `diff`
// (derivatives), `render` (to a string), `parse` (from a string), `tape` (compiled
// evaluation). The public items are re-exported here.
mod diff;
mod graph;
mod hash;
mod node;
mod parse;
mod render;
mod simplify;
mod tape;
#[cfg(test)]
mod tests;

pub use graph::{ExprId, Graph};
pub use node::Func;
pub use parse::{ParseError, ParseErrorKind};
pub use tape::Tape;

/// What a name in an expression refers to, answered by the caller's resolver
/// (see [`Graph::parse`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Symbol {
    /// Variable number `i`: entry `i` of the variable vector given to
    /// [`Graph::eval`] and [`Tape::eval`].
    Var(usize),
    /// A named constant, folded into the expression as a number.
    Const(f64),
    /// A name that stands for an expression already in the graph being parsed into
    /// (for instance a named quantity defined by another expression of the variables):
    /// the parse uses that node as it is. An id the graph does not hold is an error at
    /// the name's position.
    Expr(ExprId),
}
