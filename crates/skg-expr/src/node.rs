//! The kinds of node of an expression graph ([`Node`], crate-private) and the elementary
//! functions ([`Func`]), with the arithmetic that the graph's direct evaluation, its
//! constant folding and the tapes share so that they agree bit for bit
//! ([`Func::apply`], [`powi`]).

use crate::graph::ExprId;
#[cfg(doc)]
use crate::{Graph, Tape};

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
    pub(crate) fn operands(&self) -> ([ExprId; 2], usize) {
        let z = ExprId(0);
        match *self {
            Node::Const(_) | Node::Var(_) => ([z, z], 0),
            Node::Neg(a) | Node::Powi(a, _) | Node::Func(_, a) => ([a, z], 1),
            Node::Add(a, b) | Node::Sub(a, b) | Node::Mul(a, b) | Node::Div(a, b) | Node::Pow(a, b) | Node::Atan2(a, b) => ([a, b], 2),
        }
    }
}
