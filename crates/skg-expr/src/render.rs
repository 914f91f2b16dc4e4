//! Rendering an expression as a string in the expression grammar
//! ([`Graph::to_string`], [`Graph::to_string_with`]), with the fewest parentheses the
//! precedence of the operators allows and constants written so that they parse back to
//! the same value.

use std::borrow::Cow;
use std::fmt::Write as _;

use crate::graph::{ExprId, Graph};
use crate::node::Node;

/// Operator precedence used by [`Graph::to_string`].
const PREC_SUM: u8 = 1;
const PREC_PRODUCT: u8 = 2;
const PREC_UNARY: u8 = 3;
const PREC_POWER: u8 = 4;
const PREC_ATOM: u8 = 5;

/// Longest string [`Graph::to_string`] produces before truncating with `…`.
const MAX_RENDER_LEN: usize = 1 << 20;

impl Graph {
    /// Render `e` as a string in the expression grammar, naming variable `i` as `v{i}`.
    /// Shared subexpressions are written out at each use; output longer than about a
    /// million characters is cut off with `…`.
    pub fn to_string(&self, e: ExprId) -> String {
        self.to_string_with(e, &|i| format!("v{i}"))
    }

    /// Render `e` as a string, naming variable `i` as `name(i)`. With the names the
    /// expression was parsed with, the result parses back to an equal expression.
    pub fn to_string_with(&self, e: ExprId, name: &dyn Fn(usize) -> String) -> String {
        let mut out = String::new();
        let mut stack = vec![Task::Node(e, 0)];
        while let Some(task) = stack.pop() {
            if out.len() > MAX_RENDER_LEN {
                out.push('…');
                break;
            }
            match task {
                Task::Text(s) => out.push_str(&s),
                Task::Node(n, min_prec) => self.render_node(n, min_prec, name, &mut out, &mut stack),
            }
        }
        out
    }

    /// Writes the beginning of node `n` to `out`, in parentheses if its precedence is
    /// below `min_prec`, and pushes the rest (operands, operators, closing parentheses)
    /// on `stack`, in reverse order of output.
    fn render_node(&self, n: ExprId, min_prec: u8, name: &dyn Fn(usize) -> String, out: &mut String, stack: &mut Vec<Task>) {
        let node = self.node(n);
        if precedence(node) < min_prec {
            out.push('(');
            stack.push(Task::Text(Cow::Borrowed(")")));
        }
        match node {
            Node::Const(bits) => out.push_str(&format_constant(f64::from_bits(bits))),
            Node::Var(i) => out.push_str(&name(i as usize)),
            Node::Add(a, b) => push_binary(stack, a, " + ", b, PREC_SUM, PREC_PRODUCT),
            Node::Sub(a, b) => push_binary(stack, a, " - ", b, PREC_SUM, PREC_PRODUCT),
            Node::Mul(a, b) => push_binary(stack, a, "*", b, PREC_PRODUCT, PREC_UNARY),
            Node::Div(a, b) => push_binary(stack, a, "/", b, PREC_PRODUCT, PREC_UNARY),
            Node::Pow(a, b) => push_binary(stack, a, "^", b, PREC_ATOM, PREC_POWER),
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
}

/// What is left to write: a node, with the least precedence it may have without
/// parentheses, or text.
enum Task {
    Node(ExprId, u8),
    Text(Cow<'static, str>),
}

/// The precedence of a node as written (a negative constant is written with a minus).
fn precedence(node: Node) -> u8 {
    match node {
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
    }
}

/// Pushes `a op b` on the stack (in reverse order of output), `a` needing at least
/// precedence `pa` and `b` at least `pb` to go without parentheses.
fn push_binary(stack: &mut Vec<Task>, a: ExprId, op: &'static str, b: ExprId, pa: u8, pb: u8) {
    stack.push(Task::Node(b, pb));
    stack.push(Task::Text(Cow::Borrowed(op)));
    stack.push(Task::Node(a, pa));
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
