//! Exact symbolic differentiation: [`Graph::diff`] (memoized per node and variable,
//! iterative however deep the expression), [`Graph::gradient`] and [`Graph::hessian`].
//! The derivative of each node is built with the simplifying builders of
//! [`crate::simplify`].

use crate::graph::{ExprId, Graph};
use crate::hash::FxMap;
use crate::node::{Func, Node};

impl Graph {
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

    /// The derivative of node `e` with respect to variable `v` (mask bit `bit`), the
    /// derivatives of its operands being known. The operands' derivatives are taken first,
    /// in operand order, then the rule of the node's kind builds the result.
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
                self.diff_product(a, b, da, db)
            }
            Node::Div(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                self.diff_quotient(e, b, da, db)
            }
            Node::Neg(a) => {
                let da = self.d_of(a, v, bit);
                self.neg(da)
            }
            Node::Powi(a, n) => {
                let da = self.d_of(a, v, bit);
                self.diff_integer_power(a, n, da)
            }
            Node::Pow(a, b) => {
                let (da, db) = (self.d_of(a, v, bit), self.d_of(b, v, bit));
                self.diff_power(e, a, b, da, db)
            }
            Node::Atan2(y, x) => {
                let (dy, dx) = (self.d_of(y, v, bit), self.d_of(x, v, bit));
                self.diff_atan2(y, x, dy, dx)
            }
            Node::Func(f, a) => {
                let da = self.d_of(a, v, bit);
                self.diff_function(e, f, a, da)
            }
        }
    }

    /// `(a*b)' = da*b + a*db`.
    fn diff_product(&mut self, a: ExprId, b: ExprId, da: ExprId, db: ExprId) -> ExprId {
        let t1 = self.mul(da, b);
        let t2 = self.mul(a, db);
        self.add(t1, t2)
    }

    /// `(a/b)' = (da - (a/b)*db) / b`, where `e = a/b`.
    fn diff_quotient(&mut self, e: ExprId, b: ExprId, da: ExprId, db: ExprId) -> ExprId {
        let t = self.mul(e, db);
        let num = self.sub(da, t);
        self.div(num, b)
    }

    /// `(a^n)' = n*a^(n-1)*da` for an integer `n` (`a^(n-1)` a general power when `n - 1`
    /// does not fit in an `i32`).
    fn diff_integer_power(&mut self, a: ExprId, n: i32, da: ExprId) -> ExprId {
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

    /// `(a^b)'`, where `e = a^b`: `c*a^(c-1)*da` for a constant exponent `c`, else
    /// `a^b * (db*log(a) + b*da/a)`.
    fn diff_power(&mut self, e: ExprId, a: ExprId, b: ExprId, da: ExprId, db: ExprId) -> ExprId {
        if let Some(c) = self.konst(b) {
            let cm1 = self.constant(c - 1.0);
            let p = self.pow(a, cm1);
            let cc = self.constant(c);
            let t = self.mul(cc, p);
            self.mul(t, da)
        } else {
            let la = self.log(a);
            let t1 = self.mul(db, la);
            let q = self.div(da, a);
            let t2 = self.mul(b, q);
            let s = self.add(t1, t2);
            self.mul(e, s)
        }
    }

    /// `atan2(y, x)' = (x*dy - y*dx) / (x^2 + y^2)`.
    fn diff_atan2(&mut self, y: ExprId, x: ExprId, dy: ExprId, dx: ExprId) -> ExprId {
        let t1 = self.mul(x, dy);
        let t2 = self.mul(y, dx);
        let num = self.sub(t1, t2);
        let x2 = self.powi(x, 2);
        let y2 = self.powi(y, 2);
        let den = self.add(x2, y2);
        self.div(num, den)
    }

    /// `f(a)' = f'(a)*da`, where `e = f(a)`; `f'` is written with `e` itself where that is
    /// shorter, and `log`, `sqrt` and `atan` divide `da` directly.
    fn diff_function(&mut self, e: ExprId, f: Func, a: ExprId, da: ExprId) -> ExprId {
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
}
