//! The simplifying builders of the operations: [`Graph::add`], [`Graph::sub`],
//! [`Graph::mul`], [`Graph::div`], [`Graph::neg`], [`Graph::powi`], [`Graph::pow`],
//! [`Graph::func`] and the functions by name, [`Graph::atan2`], [`Graph::sum`], and
//! [`Graph::substitute`], which rebuilds an expression through them. Each folds
//! constants and applies identities (listed in the crate documentation) before it interns
//! the node. The order in which a builder creates nodes fixes their ids, and with them
//! the canonical order of operands and the tapes' arithmetic, so it must not change.

use crate::graph::{ExprId, Graph};
use crate::hash::FxMap;
use crate::node::{powi, Func, Node};

impl Graph {
    pub(crate) fn konst(&self, e: ExprId) -> Option<f64> {
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

    /// `e` with each variable `v` of `substitutions` (pairs `(v, expression)`) replaced
    /// by its expression, rebuilt through the simplifying builders (so constants that
    /// meet are folded). Variables not listed stay. Iterative, however deep `e` is.
    pub fn substitute(&mut self, e: ExprId, substitutions: &[(usize, ExprId)]) -> ExprId {
        let replace: FxMap<u32, ExprId> = substitutions.iter().filter_map(|&(v, x)| Some((u32::try_from(v).ok()?, x))).collect();
        let mut new: FxMap<ExprId, ExprId> = FxMap::default();
        for n in self.reachable(&[e]) {
            let get = |x: ExprId| new[&x];
            let built = match self.node(n) {
                Node::Const(_) => n,
                Node::Var(v) => replace.get(&v).copied().unwrap_or(n),
                Node::Add(a, b) => self.add(get(a), get(b)),
                Node::Sub(a, b) => self.sub(get(a), get(b)),
                Node::Mul(a, b) => self.mul(get(a), get(b)),
                Node::Div(a, b) => self.div(get(a), get(b)),
                Node::Neg(a) => self.neg(get(a)),
                Node::Powi(a, k) => self.powi(get(a), k),
                Node::Pow(a, b) => self.pow(get(a), get(b)),
                Node::Func(f, a) => self.func(f, get(a)),
                Node::Atan2(y, x) => self.atan2(get(y), get(x)),
            };
            new.insert(n, built);
        }
        new[&e]
    }
}
