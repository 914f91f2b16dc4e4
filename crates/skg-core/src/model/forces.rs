//! The walls' forces as expressions: the Gaussian normal force and kinetic friction,
//! added to the generalized forces of a model with regularized walls. A wall's numbers
//! (strength, width, friction coefficient and velocity) are constants folded into the
//! expressions, or, in a fit's model where they depend on a free parameter, expressions
//! of it ([`Number`]).

use skg_expr::{ExprId, Graph};

use super::expressions::{Number, WallExprs};
use super::layout::LocalLayout;

/// `sqrt(floor² + Σ c_i²)`.
fn norm(g: &mut Graph, comps: &[ExprId], floor: Number) -> ExprId {
    let mut sq = match floor {
        Number::Value(floor) => g.constant(floor * floor),
        Number::Expr(e) => g.powi(e, 2),
    };
    for &c in comps {
        let t = g.powi(c, 2);
        sq = g.add(sq, t);
    }
    g.sqrt(sq)
}

/// `Σ a_i b_i`.
fn dot(g: &mut Graph, a: &[ExprId], b: &[ExprId]) -> ExprId {
    let mut sum = g.constant(0.0);
    for (&x, &y) in a.iter().zip(b) {
        let t = g.mul(x, y);
        sum = g.add(sum, t);
    }
    sum
}

/// The Gaussian's amplitude `A/√(2πσ²)`: a constant, or an expression where `A` or `σ`
/// is one.
fn amplitude(g: &mut Graph, strength: Number, width: Number) -> ExprId {
    if let (Number::Value(strength), Number::Value(sigma)) = (strength, width) {
        return g.constant(strength / (2.0 * std::f64::consts::PI * sigma * sigma).sqrt());
    }
    let (a, sigma) = (strength.expr(g), width.expr(g));
    let sigma2 = g.powi(sigma, 2);
    let two_pi = g.constant(2.0 * std::f64::consts::PI);
    let variance = g.mul(two_pi, sigma2);
    let root = g.sqrt(variance);
    g.div(a, root)
}

/// The factor `−1/(2σ²)` of `h²` in the Gaussian's exponent.
fn exponent_factor(g: &mut Graph, width: Number) -> ExprId {
    match width {
        Number::Value(sigma) => g.constant(-1.0 / (2.0 * sigma * sigma)),
        Number::Expr(sigma) => {
            let sigma2 = g.powi(sigma, 2);
            let minus_half = g.constant(-0.5);
            g.div(minus_half, sigma2)
        }
    }
}

/// A wall's Gaussian normal force `F_N = −A δ_σ(h) ∇h`, subtracted from `forces`.
/// Returns `A δ_σ(h)` (≥ 0), which the friction force scales with.
pub(super) fn add_normal_force(g: &mut Graph, w: &WallExprs, forces: &mut [ExprId]) -> ExprId {
    // In this order (the graph's node ids, and with them the tapes, depend on it).
    let amp = amplitude(g, w.strength, w.width);
    let h2 = g.powi(w.h, 2);
    let scale = exponent_factor(g, w.width);
    let arg = g.mul(scale, h2);
    let gauss = g.exp(arg);
    let delta = g.mul(amp, gauss);
    for (f, &gi) in forces.iter_mut().zip(&w.grad) {
        let fi = g.mul(delta, gi);
        *f = g.sub(*f, fi);
    }
    delta
}

/// A wall's kinetic friction force `F_R = μ |F_N| d̂`, added to `forces`: `d̂` is the
/// normalized declared direction, or, without one, `−v∥ / sqrt(|v∥|² + ε²)` against the
/// velocity along the wall (`v∥ = v − (v·n̂) n̂`, `n̂ = ∇h/|∇h|`, ε the wall's
/// friction velocity), which keeps the force differentiable at rest.
pub(super) fn add_friction_force(g: &mut Graph, lay: LocalLayout, w: &WallExprs, delta: ExprId, forces: &mut [ExprId]) {
    let grad_norm = norm(g, &w.grad, Number::Value(0.0));
    let normal_force = g.mul(delta, grad_norm); // |F_N|
    let mu = w.friction.expr(g);
    let magnitude = g.mul(mu, normal_force);
    let direction: Vec<ExprId> = match &w.friction_direction {
        Some(dir) => {
            let n = norm(g, dir, Number::Value(0.0));
            dir.iter().map(|&c| g.div(c, n)).collect()
        }
        None => {
            let nhat: Vec<ExprId> = w.grad.iter().map(|&gi| g.div(gi, grad_norm)).collect();
            let v: Vec<ExprId> = (0..lay.d).map(|i| g.var(lay.v(i))).collect();
            let vn = dot(g, &v, &nhat);
            let vpar: Vec<ExprId> = v
                .iter()
                .zip(&nhat)
                .map(|(&vi, &ni)| {
                    let t = g.mul(vn, ni);
                    g.sub(vi, t)
                })
                .collect();
            let speed = norm(g, &vpar, w.friction_velocity);
            vpar.iter()
                .map(|&c| {
                    let q = g.div(c, speed);
                    g.neg(q)
                })
                .collect()
        }
    };
    for (f, &di) in forces.iter_mut().zip(&direction) {
        let fi = g.mul(magnitude, di);
        *f = g.add(*f, fi);
    }
}
