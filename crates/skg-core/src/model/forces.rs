//! The walls' forces as expressions: the Gaussian normal force and kinetic friction,
//! added to the generalized forces of a model with regularized walls.

use skg_expr::{ExprId, Graph};

use super::expressions::WallExprs;
use super::layout::LocalLayout;
use crate::scene::Wall;

/// `sqrt(floor² + Σ c_i²)`.
fn norm(g: &mut Graph, comps: &[ExprId], floor: f64) -> ExprId {
    let mut sq = g.constant(floor * floor);
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

/// A wall's Gaussian normal force `F_N = −A δ_σ(h) ∇h`, subtracted from `forces`.
/// Returns `A δ_σ(h)` (≥ 0), which the friction force scales with.
pub(super) fn add_normal_force(g: &mut Graph, wall: &Wall, w: &WallExprs, forces: &mut [ExprId]) -> ExprId {
    let sigma = wall.width;
    let amp = g.constant(wall.strength / (2.0 * std::f64::consts::PI * sigma * sigma).sqrt());
    let h2 = g.powi(w.h, 2);
    let scale = g.constant(-1.0 / (2.0 * sigma * sigma));
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
pub(super) fn add_friction_force(g: &mut Graph, lay: LocalLayout, wall: &Wall, w: &WallExprs, delta: ExprId, forces: &mut [ExprId]) {
    let grad_norm = norm(g, &w.grad, 0.0);
    let normal_force = g.mul(delta, grad_norm); // |F_N|
    let mu = g.constant(wall.friction);
    let magnitude = g.mul(mu, normal_force);
    let direction: Vec<ExprId> = match &w.friction_direction {
        Some(dir) => {
            let n = norm(g, dir, 0.0);
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
            let speed = norm(g, &vpar, wall.friction_velocity);
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
