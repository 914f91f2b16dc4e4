//! The hash-consed expression graph: [`ExprId`], [`Graph`] with its node table, the
//! interning of nodes (structurally equal nodes exist once), the dependency masks, the
//! leaves ([`Graph::constant`], [`Graph::var`]), inspection and direct evaluation. The
//! simplifying builders of the operations are in [`crate::simplify`], differentiation in
//! [`crate::diff`], rendering in [`crate::render`], parsing in [`crate::parse`].

use crate::hash::FxMap;
use crate::node::{powi, Node};
#[cfg(doc)]
use crate::Tape;

/// Index of a node in a [`Graph`]. Only meaningful for the graph that created it.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(pub(crate) u32);

impl ExprId {
    /// The node's index in its graph (nodes are numbered in creation order; every node's
    /// operands have smaller indices than the node itself).
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

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
    /// Per (node, variable): the derivative, once computed (see [`Graph::diff`]).
    pub(crate) diff_memo: FxMap<(ExprId, u32), ExprId>,
}

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

    pub(crate) fn mask(&self, e: ExprId) -> u64 {
        self.masks[e.0 as usize]
    }

    /// Intern a node (no simplification).
    pub(crate) fn make(&mut self, node: Node) -> ExprId {
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
}
