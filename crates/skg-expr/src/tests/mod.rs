//! The crate's tests, one file per concern: `parse.rs` (the parser, its errors, hash
//! consing, the round trip through text, names bound to expressions), `algebra.rs`
//! (simplification, derivatives against finite differences and exact ones,
//! substitution), `tape.rs` (compiled tapes against the graph's evaluation). Here: the
//! seeded generator, the resolvers and the expressions they share.

use super::*;

mod algebra;
mod parse;
mod tape;

/// Deterministic xorshift64* generator, so the tests need no dependency.
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

const NAMES: [&str; 4] = ["x", "y", "z", "w"];

/// Resolver: x, y, z, w are variables 0..4; k = 3 and half = 0.5 are constants.
fn resolver(name: &str) -> Option<Symbol> {
    match name {
        "k" => Some(Symbol::Const(3.0)),
        "half" => Some(Symbol::Const(0.5)),
        _ => NAMES.iter().position(|&n| n == name).map(Symbol::Var),
    }
}

fn parse(g: &mut Graph, src: &str) -> ExprId {
    match g.parse(src, &mut resolver) {
        Ok(e) => e,
        Err(err) => panic!("{err}\n{}", err.caret_line()),
    }
}

fn value(src: &str, vars: &[f64]) -> f64 {
    let mut g = Graph::new();
    let e = parse(&mut g, src);
    g.eval(e, vars)
}

fn parse_err(src: &str) -> ParseError {
    let mut g = Graph::new();
    match g.parse(src, &mut resolver) {
        Ok(e) => panic!("`{src}` parsed to {} but should have failed", g.to_string(e)),
        Err(err) => err,
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

/// Expressions covering every function and operator, with the points where they are
/// tested (each variable drawn from [0.5, 1.5]).
const DIFF_EXPRS: [&str; 16] = [
    "x*y + y/z - x*z^3",
    "sin(x*y) + cos(y - z)^2 + tan(x/2)",
    "exp(-x^2*y) / (1 + z^2)",
    "log(1 + x^2*y) - sqrt(x + y*z)",
    "abs(x - 3)*y + abs(y*z + 2)",
    "sinh(x*y) - cosh(z)/tanh(x + 1) + atan(x*z - y)",
    "atan2(y - x, z + 1) * atan2(x, -y)",
    "x^y + (1 + y^2)^(x*z)",
    "x^2.5 - z^-1.3 + y^-3 + (x*y)^0.5",
    "2^(x*y) - pi^z",
    "-(x*y - z)^3 / -(x + y)",
    "((x + y)^2 - (x - y)^2) / (4*x*y + z)",
    "1/2*M*(x_dot^2 + y_dot^2) + 1/2*IS*theta_dot^2 + 1/2*ID*phi_dot^2 + M*g*x*sin(alpha)",
    "x_dot*sin(phi) - y_dot*cos(phi)",
    "V0/sqrt(2*pi*sigma^2)*exp(-(x^2 + y^2 - R^2)^2/(2*sigma^2))",
    "w*exp(-w*x)*cos(y*w)^3 + sqrt(z^2 + w^2)",
];

/// Variables of the test expressions (the rolling disk's and the wall's included) and
/// their constants.
const DIFF_VARS: [&str; 10] = ["x", "y", "z", "w", "x_dot", "y_dot", "theta_dot", "phi_dot", "phi", "theta"];

fn diff_resolver(name: &str) -> Option<Symbol> {
    let consts = [("M", 1.3), ("IS", 0.4), ("ID", 0.2), ("g", 9.81), ("alpha", 0.3), ("V0", 2.0), ("sigma", 0.7), ("R", 1.1)];
    if let Some(&(_, c)) = consts.iter().find(|(n, _)| *n == name) {
        return Some(Symbol::Const(c));
    }
    DIFF_VARS.iter().position(|&n| n == name).map(Symbol::Var)
}
