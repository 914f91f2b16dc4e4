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
//!   time `t`, or a named constant such as a mass `M`, which is folded in as a number). A name the
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

use std::borrow::Cow;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::hash::{BuildHasherDefault, Hasher};

mod parse;
mod tape;
#[cfg(test)]
mod tests;

pub use parse::{ParseError, ParseErrorKind};
pub use tape::Tape;

/// Index of a node in a [`Graph`]. Only meaningful for the graph that created it.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(u32);

impl ExprId {
    /// The node's index in its graph (nodes are numbered in creation order; every node's
    /// operands have smaller indices than the node itself).
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a name in an expression refers to, answered by the caller's resolver
/// (see [`Graph::parse`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Symbol {
    /// Variable number `i`: entry `i` of the variable vector given to
    /// [`Graph::eval`] and [`Tape::eval`].
    Var(usize),
    /// A named constant, folded into the expression as a number.
    Const(f64),
}

/// The elementary functions of one argument.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    /// `sin`
    Sin,
    /// `cos`
    Cos,
    /// `tan`
    Tan,
    /// `exp`
    Exp,
    /// `log`, the natural logarithm.
    Log,
    /// `sqrt`
    Sqrt,
    /// `abs` (derivative `x/abs(x)`: not differentiable at 0).
    Abs,
    /// `sinh`
    Sinh,
    /// `cosh`
    Cosh,
    /// `tanh`
    Tanh,
    /// `atan`
    Atan,
}

impl Func {
    /// All functions of one argument, in declaration order.
    pub const ALL: [Func; 11] =
        [Func::Sin, Func::Cos, Func::Tan, Func::Exp, Func::Log, Func::Sqrt, Func::Abs, Func::Sinh, Func::Cosh, Func::Tanh, Func::Atan];

    /// The function's name in the expression grammar.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
            Func::Tanh => "tanh",
            Func::Atan => "atan",
        }
    }

    /// The function called `name` in the expression grammar, if any.
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.iter().copied().find(|f| f.name() == name)
    }

    /// Evaluate the function.
    #[inline]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Exp => x.exp(),
            Func::Log => x.ln(),
            Func::Sqrt => x.sqrt(),
            Func::Abs => x.abs(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
            Func::Tanh => x.tanh(),
            Func::Atan => x.atan(),
        }
    }
}

/// Integer power, shared by [`Graph::eval`] and [`Tape::eval`] so both agree bit for bit.
#[inline]
pub(crate) fn powi(x: f64, n: i32) -> f64 {
    match n {
        2 => x * x,
        _ => x.powi(n),
    }
}

/// One node of the DAG. Constants are stored as bit patterns so nodes can be hashed.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Node {
    Const(u64),
    Var(u32),
    Add(ExprId, ExprId),
    Sub(ExprId, ExprId),
    Mul(ExprId, ExprId),
    Div(ExprId, ExprId),
    Neg(ExprId),
    Powi(ExprId, i32),
    Pow(ExprId, ExprId),
    Func(Func, ExprId),
    Atan2(ExprId, ExprId),
}

impl Node {
    /// The node's operands (at most two).
    fn operands(&self) -> ([ExprId; 2], usize) {
        let z = ExprId(0);
        match *self {
            Node::Const(_) | Node::Var(_) => ([z, z], 0),
            Node::Neg(a) | Node::Powi(a, _) | Node::Func(_, a) => ([a, z], 1),
            Node::Add(a, b) | Node::Sub(a, b) | Node::Mul(a, b) | Node::Div(a, b) | Node::Pow(a, b) | Node::Atan2(a, b) => ([a, b], 2),
        }
    }
}

/// A small, fast, non-cryptographic hasher (FxHash) for the graph's internal tables.
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher(u64);

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut buf = [0u8; 8];
            buf[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(buf));
        }
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.write_u64(i as u64)
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64)
    }
    #[inline]
    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64)
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64)
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

pub(crate) type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// A hash-consed expression DAG.
///
/// Nodes are created through the simplifying builders ([`Graph::constant`],
/// [`Graph::var`], [`Graph::add`], …) or by [`Graph::parse`]; structurally equal nodes are
/// created once, so parsing the same string twice gives the same [`ExprId`]. Nodes are
/// never removed. A node's operands always have smaller ids than the node itself.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    nodes: Vec<Node>,
    /// Per node: bit `v % 64` is set if the node may depend on variable `v`.
    masks: Vec<u64>,
    index: FxMap<Node, ExprId>,
    diff_memo: FxMap<(ExprId, u32), ExprId>,
}

/// Operator precedence used by [`Graph::to_string`].
const PREC_SUM: u8 = 1;
const PREC_PRODUCT: u8 = 2;
const PREC_UNARY: u8 = 3;
const PREC_POWER: u8 = 4;
const PREC_ATOM: u8 = 5;

/// Longest string [`Graph::to_string`] produces before truncating with `…`.
const MAX_RENDER_LEN: usize = 1 << 20;

impl Graph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of nodes in the graph.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if the graph has no nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub(crate) fn node(&self, e: ExprId) -> Node {
        self.nodes[e.0 as usize]
    }

    fn mask(&self, e: ExprId) -> u64 {
        self.masks[e.0 as usize]
    }

    /// Intern a node (no simplification).
    fn make(&mut self, node: Node) -> ExprId {
        if let Some(&id) = self.index.get(&node) {
            return id;
        }
        let mask = match node {
            Node::Const(_) => 0,
            Node::Var(v) => 1u64 << (v % 64),
            _ => {
                let (ops, n) = node.operands();
                ops[..n].iter().fold(0, |m, &o| m | self.mask(o))
            }
        };
        let id = ExprId(u32::try_from(self.nodes.len()).expect("expression graph has more than 2^32 nodes"));
        self.nodes.push(node);
        self.masks.push(mask);
        self.index.insert(node, id);
        id
    }

    // ------------------------------------------------------------------ inspection

    /// The value of `e` if it is a constant node.
    pub fn as_constant(&self, e: ExprId) -> Option<f64> {
        match self.node(e) {
            Node::Const(bits) => Some(f64::from_bits(bits)),
            _ => None,
        }
    }

    /// The variable index of `e` if it is a plain variable.
    pub fn as_var(&self, e: ExprId) -> Option<usize> {
        match self.node(e) {
            Node::Var(v) => Some(v as usize),
            _ => None,
        }
    }

    /// True if `e` is the constant 0.
    pub fn is_zero(&self, e: ExprId) -> bool {
        self.as_constant(e) == Some(0.0)
    }

    /// True if `e` is the constant 1.
    pub fn is_one(&self, e: ExprId) -> bool {
        self.as_constant(e) == Some(1.0)
    }

    /// All nodes reachable from `roots` (including the roots), in increasing id order,
    /// which is a topological order (operands first).
    pub(crate) fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<ExprId> = Vec::new();
        let mut out = Vec::new();
        for &r in roots {
            if !seen[r.0 as usize] {
                seen[r.0 as usize] = true;
                stack.push(r);
            }
        }
        while let Some(e) = stack.pop() {
            out.push(e);
            let (ops, n) = self.node(e).operands();
            for &o in &ops[..n] {
                if !seen[o.0 as usize] {
                    seen[o.0 as usize] = true;
                    stack.push(o);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The variables `e` depends on, sorted and without duplicates.
    pub fn variables(&self, e: ExprId) -> Vec<usize> {
        let mut vars: Vec<usize> = self.reachable(&[e]).into_iter().filter_map(|n| self.as_var(n)).collect();
        vars.sort_unstable();
        vars.dedup();
        vars
    }

    /// Number of distinct nodes (operations, variables and constants) in the sub-DAG of
    /// `e`: a measure of its size with shared subexpressions counted once.
    pub fn dag_size(&self, e: ExprId) -> usize {
        self.reachable(&[e]).len()
    }

    // ------------------------------------------------------------------ builders

    /// The constant `c` (`-0.0` is stored as `0.0`).
    pub fn constant(&mut self, c: f64) -> ExprId {
        let c = if c == 0.0 { 0.0 } else { c };
        self.make(Node::Const(c.to_bits()))
    }

    /// Variable number `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub fn var(&mut self, i: usize) -> ExprId {
        let i = u32::try_from(i).expect("variable index does not fit in u32");
        self.make(Node::Var(i))
    }

    fn konst(&self, e: ExprId) -> Option<f64> {
        self.as_constant(e)
    }

    /// `a + b`.
    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.constant(x + y),
            (Some(0.0), _) => return b,
            (_, Some(0.0)) => return a,
            _ => {}
        }
        if let Node::Neg(y) = self.node(b) {
            return self.sub(a, y);
        }
        if let Node::Neg(y) = self.node(a) {
            return self.sub(b, y);
        }
        if a == b {
            let two = self.constant(2.0);
            return self.mul(two, a);
        }
        // constants first
        let (a, b) = if self.konst(b).is_some() { (b, a) } else { (a, b) };
        if let Some(c1) = self.konst(a) {
            match self.node(b) {
                Node::Add(x, y) => {
                    if let Some(c2) = self.konst(x) {
                        let c = self.constant(c1 + c2);
                        return self.add(c, y);
                    }
                }
                Node::Sub(x, y) => {
                    if let Some(c2) = self.konst(x) {
                        let c = self.constant(c1 + c2);
                        return self.sub(c, y);
                    }
                }
                _ => {}
            }
            return self.make(Node::Add(a, b));
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.make(Node::Add(a, b))
    }

    /// `a - b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.constant(x - y),
            (_, Some(0.0)) => return a,
            (Some(0.0), _) => return self.neg(b),
            (_, Some(y)) => {
                // a - c = (-c) + a, which is exact in IEEE arithmetic
                let c = self.constant(-y);
                return self.add(c, a);
            }
            _ => {}
        }
        if a == b {
            return self.constant(0.0);
        }
        if let Node::Neg(y) = self.node(b) {
            return self.add(a, y);
        }
        if let Node::Neg(x) = self.node(a) {
            let s = self.add(x, b);
            return self.neg(s);
        }
        self.make(Node::Sub(a, b))
    }

    /// `a * b`.
    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.constant(x * y),
            (Some(x), _) | (_, Some(x)) if x == 0.0 => return self.constant(0.0),
            (Some(1.0), _) => return b,
            (_, Some(1.0)) => return a,
            (Some(-1.0), _) => return self.neg(b),
            (_, Some(-1.0)) => return self.neg(a),
            _ => {}
        }
        if let Node::Neg(x) = self.node(a) {
            let p = self.mul(x, b);
            return self.neg(p);
        }
        if let Node::Neg(y) = self.node(b) {
            let p = self.mul(a, y);
            return self.neg(p);
        }
        if a == b {
            return self.powi(a, 2);
        }
        let (a, b) = if self.konst(b).is_some() { (b, a) } else { (a, b) };
        if let Some(c1) = self.konst(a) {
            match self.node(b) {
                Node::Mul(x, y) => {
                    if let Some(c2) = self.konst(x) {
                        let c = self.constant(c1 * c2);
                        return self.mul(c, y);
                    }
                }
                Node::Div(x, y) => {
                    if let Some(c2) = self.konst(x) {
                        let c = self.constant(c1 * c2);
                        return self.div(c, y);
                    }
                }
                _ => {}
            }
            return self.make(Node::Mul(a, b));
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.make(Node::Mul(a, b))
    }

    /// `a / b`.
    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.constant(x / y),
            (Some(0.0), _) => return self.constant(0.0),
            (_, Some(1.0)) => return a,
            (_, Some(-1.0)) => return self.neg(a),
            _ => {}
        }
        if a == b {
            return self.constant(1.0);
        }
        if let Node::Neg(x) = self.node(a) {
            let q = self.div(x, b);
            return self.neg(q);
        }
        if let Node::Neg(y) = self.node(b) {
            let q = self.div(a, y);
            return self.neg(q);
        }
        self.make(Node::Div(a, b))
    }

    /// `-a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        if let Some(x) = self.konst(a) {
            return self.constant(-x);
        }
        match self.node(a) {
            Node::Neg(x) => x,
            Node::Sub(x, y) => self.sub(y, x),
            Node::Mul(x, y) if self.konst(x).is_some() => {
                let c = self.constant(-self.konst(x).unwrap_or(0.0));
                self.mul(c, y)
            }
            _ => self.make(Node::Neg(a)),
        }
    }

    /// `a^n` for an integer `n` (evaluated by repeated multiplication; `a^0 = 1`).
    pub fn powi(&mut self, a: ExprId, n: i32) -> ExprId {
        if n == 0 {
            return self.constant(1.0);
        }
        if n == 1 {
            return a;
        }
        if let Some(x) = self.konst(a) {
            return self.constant(powi(x, n));
        }
        match self.node(a) {
            Node::Powi(x, m) => {
                if let Some(k) = m.checked_mul(n) {
                    return self.powi(x, k);
                }
            }
            Node::Neg(x) => {
                let p = self.powi(x, n);
                return if n % 2 == 0 { p } else { self.neg(p) };
            }
            _ => {}
        }
        self.make(Node::Powi(a, n))
    }

    /// `a^b`. A constant integer exponent gives [`Graph::powi`], a constant exponent 0.5
    /// gives `sqrt(a)`.
    pub fn pow(&mut self, a: ExprId, b: ExprId) -> ExprId {
        if let Some(y) = self.konst(b) {
            if y.fract() == 0.0 && y >= i32::MIN as f64 && y <= i32::MAX as f64 {
                return self.powi(a, y as i32);
            }
            if y == 0.5 {
                return self.sqrt(a);
            }
            if let Some(x) = self.konst(a) {
                return self.constant(x.powf(y));
            }
        }
        if self.konst(a) == Some(1.0) {
            return a;
        }
        self.make(Node::Pow(a, b))
    }

    /// `f(a)` for a function of one argument.
    pub fn func(&mut self, f: Func, a: ExprId) -> ExprId {
        if let Some(x) = self.konst(a) {
            return self.constant(f.apply(x));
        }
        match (f, self.node(a)) {
            (Func::Abs, Node::Neg(x)) => return self.func(Func::Abs, x),
            (Func::Abs, Node::Func(Func::Abs, _)) => return a,
            (Func::Abs, Node::Func(Func::Sqrt, _)) => return a,
            (Func::Abs, Node::Func(Func::Exp, _)) => return a,
            (Func::Abs, Node::Func(Func::Cosh, _)) => return a,
            (Func::Cos | Func::Cosh, Node::Neg(x)) => return self.func(f, x),
            (Func::Sin | Func::Tan | Func::Sinh | Func::Tanh | Func::Atan, Node::Neg(x)) => {
                let y = self.func(f, x);
                return self.neg(y);
            }
            (Func::Sqrt, Node::Powi(x, 2)) => return self.func(Func::Abs, x),
            _ => {}
        }
        self.make(Node::Func(f, a))
    }

    /// `sin(a)`.
    pub fn sin(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Sin, a)
    }
    /// `cos(a)`.
    pub fn cos(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Cos, a)
    }
    /// `tan(a)`.
    pub fn tan(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Tan, a)
    }
    /// `exp(a)`.
    pub fn exp(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Exp, a)
    }
    /// `log(a)`, the natural logarithm.
    pub fn log(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Log, a)
    }
    /// `sqrt(a)`.
    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Sqrt, a)
    }
    /// `abs(a)` (derivative `a/abs(a)`, NaN at 0: regularize if that matters).
    pub fn abs(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Abs, a)
    }
    /// `sinh(a)`.
    pub fn sinh(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Sinh, a)
    }
    /// `cosh(a)`.
    pub fn cosh(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Cosh, a)
    }
    /// `tanh(a)`.
    pub fn tanh(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Tanh, a)
    }
    /// `atan(a)`.
    pub fn atan(&mut self, a: ExprId) -> ExprId {
        self.func(Func::Atan, a)
    }

    /// `atan2(y, x)`: the angle of the point `(x, y)`, in `(-pi, pi]`.
    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        if let (Some(a), Some(b)) = (self.konst(y), self.konst(x)) {
            return self.constant(a.atan2(b));
        }
        self.make(Node::Atan2(y, x))
    }

    /// Sum of several terms (0 for none).
    pub fn sum(&mut self, terms: &[ExprId]) -> ExprId {
        let mut acc = self.constant(0.0);
        for &t in terms {
            acc = self.add(acc, t);
        }
        acc
    }

    // ------------------------------------------------------------------ derivatives

    /// Symbolic partial derivative of `e` with respect to variable `var`.
    ///
    /// Memoized per (node, variable), so repeated and higher derivatives share work and
    /// nodes. Rules of note: `d abs(a) = a/abs(a) * da` (NaN at `a = 0`; regularize, e.g.
    /// `sqrt(a^2 + eps^2)`); `a^c` with constant `c` gives `c*a^(c-1)*da`; `a^b` with
    /// non-constant `b` gives `a^b * (db*log(a) + b*da/a)`, which needs `a > 0`.
    pub fn diff(&mut self, e: ExprId, var: usize) -> ExprId {
        let Ok(v) = u32::try_from(var) else {
            return self.constant(0.0);
        };
        let bit = 1u64 << (v % 64);
        if self.mask(e) & bit == 0 {
            return self.constant(0.0);
        }
        if let Some(&d) = self.diff_memo.get(&(e, v)) {
            return d;
        }
        // Collect the nodes below e that may depend on v and whose derivative is not yet
        // known, then differentiate them operands first (ids increase from operands to
        // users), so no recursion is needed however deep the expression.
        let mut todo = Vec::new();
        let mut stack = vec![e];
        let mut seen: FxMap<ExprId, ()> = FxMap::default();
        seen.insert(e, ());
        while let Some(n) = stack.pop() {
            todo.push(n);
            let (ops, k) = self.node(n).operands();
            for &o in &ops[..k] {
                if self.mask(o) & bit != 0 && !self.diff_memo.contains_key(&(o, v)) && seen.insert(o, ()).is_none() {
                    stack.push(o);
                }
            }
        }
        todo.sort_unstable();
        for n in todo {
            let d = self.diff_node(n, v, bit);
            self.diff_memo.insert((n, v), d);
        }
        self.diff_memo[&(e, v)]
    }

    /// Derivative of an operand whose own derivative has already been computed.
    fn d_of(&mut self, o: ExprId, v: u32, bit: u64) -> ExprId {
        if self.mask(o) & bit == 0 {
            return self.constant(0.0);
        }
        match self.diff_memo.get(&(o, v)) {
            Some(&d) => d,
            None => unreachable!("operand derivative computed before its user"),
        }
    }

    fn diff_node(&mut self, e: ExprId, v: u32, bit: u64) -> ExprId {
        match self.node(e) {
            Node::Const(_) => self.constant(0.0),
            Node::Var(i) => self.constant(if i == v { 1.0 } else { 0.0 }),
            Node::Add(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                self.add(da, db)
            }
            Node::Sub(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                self.sub(da, db)
            }
            Node::Mul(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                let t1 = self.mul(da, b);
                let t2 = self.mul(a, db);
                self.add(t1, t2)
            }
            Node::Div(a, b) => {
                // (a/b)' = (da - (a/b)*db) / b
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                let t = self.mul(e, db);
                let num = self.sub(da, t);
                self.div(num, b)
            }
            Node::Neg(a) => {
                let da = self.d_of(a, v, bit);
                self.neg(da)
            }
            Node::Powi(a, n) => {
                let da = self.d_of(a, v, bit);
                let p = match n.checked_sub(1) {
                    Some(m) => self.powi(a, m),
                    None => {
                        let c = self.constant(n as f64 - 1.0);
                        self.pow(a, c)
                    }
                };
                let c = self.constant(n as f64);
                let t = self.mul(c, p);
                self.mul(t, da)
            }
            Node::Pow(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                if let Some(c) = self.konst(b) {
                    let cm1 = self.constant(c - 1.0);
                    let p = self.pow(a, cm1);
                    let cc = self.constant(c);
                    let t = self.mul(cc, p);
                    self.mul(t, da)
                } else {
                    // (a^b)' = a^b * (db*log(a) + b*da/a)
                    let la = self.log(a);
                    let t1 = self.mul(db, la);
                    let q = self.div(da, a);
                    let t2 = self.mul(b, q);
                    let s = self.add(t1, t2);
                    self.mul(e, s)
                }
            }
            Node::Atan2(y, x) => {
                // (x*dy - y*dx) / (x^2 + y^2)
                let (dy, dx) = (self.d_of(y, v, bit), self.d_of(x, v, bit));
                let t1 = self.mul(x, dy);
                let t2 = self.mul(y, dx);
                let num = self.sub(t1, t2);
                let x2 = self.powi(x, 2);
                let y2 = self.powi(y, 2);
                let den = self.add(x2, y2);
                self.div(num, den)
            }
            Node::Func(f, a) => {
                let da = self.d_of(a, v, bit);
                let one = self.constant(1.0);
                let inner = match f {
                    Func::Sin => self.cos(a),
                    Func::Cos => {
                        let s = self.sin(a);
                        self.neg(s)
                    }
                    Func::Tan => {
                        let e2 = self.powi(e, 2);
                        self.add(one, e2)
                    }
                    Func::Exp => e,
                    Func::Log => return self.div(da, a),
                    Func::Sqrt => {
                        let two = self.constant(2.0);
                        let den = self.mul(two, e);
                        return self.div(da, den);
                    }
                    Func::Abs => self.div(a, e),
                    Func::Sinh => self.cosh(a),
                    Func::Cosh => self.sinh(a),
                    Func::Tanh => {
                        let e2 = self.powi(e, 2);
                        self.sub(one, e2)
                    }
                    Func::Atan => {
                        let a2 = self.powi(a, 2);
                        let den = self.add(one, a2);
                        return self.div(da, den);
                    }
                };
                self.mul(inner, da)
            }
        }
    }

    /// The gradient of `e` with respect to the variables `vars`.
    pub fn gradient(&mut self, e: ExprId, vars: &[usize]) -> Vec<ExprId> {
        vars.iter().map(|&v| self.diff(e, v)).collect()
    }

    /// The Hessian of `e` with respect to `vars`, as a dense symmetric row-major matrix
    /// (entry `i*vars.len() + j` is `d²e/dvars[i]dvars[j]`; the two triangles hold the
    /// same ids).
    pub fn hessian(&mut self, e: ExprId, vars: &[usize]) -> Vec<ExprId> {
        let n = vars.len();
        let grad = self.gradient(e, vars);
        let mut h = vec![ExprId(0); n * n];
        for i in 0..n {
            for j in 0..=i {
                let d = self.diff(grad[i], vars[j]);
                h[i * n + j] = d;
                h[j * n + i] = d;
            }
        }
        h
    }

    // ------------------------------------------------------------------ evaluation

    /// Evaluate `e` directly (the slow path, for tests and validation): `vars[i]` is the
    /// value of variable `i`. Use a [`Tape`] for repeated evaluation.
    ///
    /// # Panics
    /// If `e` depends on a variable `i >= vars.len()`.
    pub fn eval(&self, e: ExprId, vars: &[f64]) -> f64 {
        self.eval_many(&[e], vars)[0]
    }

    /// Evaluate several expressions directly, sharing common subexpressions.
    ///
    /// # Panics
    /// If an expression depends on a variable `i >= vars.len()`.
    pub fn eval_many(&self, es: &[ExprId], vars: &[f64]) -> Vec<f64> {
        let order = self.reachable(es);
        let mut vals: Vec<f64> = Vec::with_capacity(order.len());
        let get = |vals: &Vec<f64>, x: ExprId| -> f64 {
            let pos = order.binary_search(&x).unwrap_or_else(|_| unreachable!());
            vals[pos]
        };
        for &n in &order {
            let val = match self.node(n) {
                Node::Const(bits) => f64::from_bits(bits),
                Node::Var(i) => vars[i as usize],
                Node::Add(a, b) => get(&vals, a) + get(&vals, b),
                Node::Sub(a, b) => get(&vals, a) - get(&vals, b),
                Node::Mul(a, b) => get(&vals, a) * get(&vals, b),
                Node::Div(a, b) => get(&vals, a) / get(&vals, b),
                Node::Neg(a) => -get(&vals, a),
                Node::Powi(a, k) => powi(get(&vals, a), k),
                Node::Pow(a, b) => get(&vals, a).powf(get(&vals, b)),
                Node::Func(f, a) => f.apply(get(&vals, a)),
                Node::Atan2(y, x) => get(&vals, y).atan2(get(&vals, x)),
            };
            vals.push(val);
        }
        es.iter().map(|&e| get(&vals, e)).collect()
    }

    // ------------------------------------------------------------------ rendering

    /// Render `e` as a string in the expression grammar, naming variable `i` as `v{i}`.
    /// Shared subexpressions are written out at each use; output longer than about a
    /// million characters is cut off with `…`.
    pub fn to_string(&self, e: ExprId) -> String {
        self.to_string_with(e, &|i| format!("v{i}"))
    }

    /// Render `e` as a string, naming variable `i` as `name(i)`. With the names the
    /// expression was parsed with, the result parses back to an equal expression.
    pub fn to_string_with(&self, e: ExprId, name: &dyn Fn(usize) -> String) -> String {
        enum Task {
            Node(ExprId, u8),
            Text(Cow<'static, str>),
        }
        let mut out = String::new();
        let mut stack = vec![Task::Node(e, 0)];
        while let Some(task) = stack.pop() {
            if out.len() > MAX_RENDER_LEN {
                out.push('…');
                break;
            }
            let (n, min_prec) = match task {
                Task::Text(s) => {
                    out.push_str(&s);
                    continue;
                }
                Task::Node(n, p) => (n, p),
            };
            let node = self.node(n);
            let prec = match node {
                Node::Const(bits) => {
                    if f64::from_bits(bits) < 0.0 {
                        PREC_UNARY
                    } else {
                        PREC_ATOM
                    }
                }
                Node::Var(_) | Node::Func(..) | Node::Atan2(..) => PREC_ATOM,
                Node::Add(..) | Node::Sub(..) => PREC_SUM,
                Node::Mul(..) | Node::Div(..) => PREC_PRODUCT,
                Node::Neg(_) => PREC_UNARY,
                Node::Powi(..) | Node::Pow(..) => PREC_POWER,
            };
            let paren = prec < min_prec;
            if paren {
                out.push('(');
                stack.push(Task::Text(Cow::Borrowed(")")));
            }
            // Push in reverse order of output.
            let binary = |stack: &mut Vec<Task>, a, op, b, pa, pb| {
                stack.push(Task::Node(b, pb));
                stack.push(Task::Text(Cow::Borrowed(op)));
                stack.push(Task::Node(a, pa));
            };
            match node {
                Node::Const(bits) => out.push_str(&format_constant(f64::from_bits(bits))),
                Node::Var(i) => out.push_str(&name(i as usize)),
                Node::Add(a, b) => binary(&mut stack, a, " + ", b, PREC_SUM, PREC_PRODUCT),
                Node::Sub(a, b) => binary(&mut stack, a, " - ", b, PREC_SUM, PREC_PRODUCT),
                Node::Mul(a, b) => binary(&mut stack, a, "*", b, PREC_PRODUCT, PREC_UNARY),
                Node::Div(a, b) => binary(&mut stack, a, "/", b, PREC_PRODUCT, PREC_UNARY),
                Node::Pow(a, b) => binary(&mut stack, a, "^", b, PREC_ATOM, PREC_POWER),
                Node::Neg(a) => {
                    out.push('-');
                    stack.push(Task::Node(a, PREC_POWER));
                }
                Node::Powi(a, k) => {
                    if k < 0 {
                        stack.push(Task::Text(Cow::Owned(format!("^({k})"))));
                    } else {
                        stack.push(Task::Text(Cow::Owned(format!("^{k}"))));
                    }
                    stack.push(Task::Node(a, PREC_ATOM));
                }
                Node::Func(f, a) => {
                    out.push_str(f.name());
                    out.push('(');
                    stack.push(Task::Text(Cow::Borrowed(")")));
                    stack.push(Task::Node(a, 0));
                }
                Node::Atan2(y, x) => {
                    out.push_str("atan2(");
                    stack.push(Task::Text(Cow::Borrowed(")")));
                    stack.push(Task::Node(x, 0));
                    stack.push(Task::Text(Cow::Borrowed(", ")));
                    stack.push(Task::Node(y, 0));
                }
            }
        }
        out
    }
}

/// Format a constant so that it parses back to the same value.
fn format_constant(c: f64) -> String {
    if c.fract() == 0.0 && c.abs() < 1e15 {
        format!("{}", c as i64)
    } else if c.is_nan() {
        "(0/0)".to_string() // parses back to NaN
    } else if c.is_infinite() {
        if c > 0.0 {
            "(1/0)".to_string()
        } else {
            "(-1/0)".to_string()
        }
    } else {
        let mut s = String::new();
        let _ = write!(s, "{c:?}");
        s
    }
}
