//! The mechanics and the node density `s` as expressions, and the tapes of `s` and of its
//! first and second derivatives: the residual, Jacobian and Hessian densities of the
//! discrete action.

use skg_expr::{ExprId, Graph, Tape};

use super::expressions::Expressions;
use super::layout::LocalLayout;

/// A set of second derivatives of `s`: the unordered local pairs `(a, b)`, `a ≥ b`,
/// whose derivative is not identically zero, and the tape computing them.
pub struct PairTape {
    /// The pairs `(a, b)` of local variables, in the tape's output order.
    pub pairs: Vec<(usize, usize)>,
    /// Computes ∂²s/∂u_a∂u_b for every pair.
    pub tape: Tape,
}

/// The Lagrangian's derivatives and the constraints' Jacobians.
pub(super) struct Mechanics {
    /// p = ∂L/∂v.
    pub(super) p: Vec<ExprId>,
    /// G_ai = ∂g^a/∂v_i.
    pub(super) gv: Vec<Vec<ExprId>>,
    /// ∂g^a/∂q_i.
    pub(super) gq: Vec<Vec<ExprId>>,
    /// f + F = ∂L/∂q plus every generalized force.
    pub(super) total_force: Vec<ExprId>,
    /// ∂p_i/∂t.
    pub(super) dpdt: Vec<ExprId>,
    /// ∂g^a/∂t.
    pub(super) gt: Vec<ExprId>,
}

impl Mechanics {
    pub(super) fn derive(g: &mut Graph, lay: LocalLayout, e: &Expressions, forces: &[ExprId]) -> Mechanics {
        let d = lay.d;
        let p: Vec<ExprId> = (0..d).map(|i| g.diff(e.lagrangian, lay.v(i))).collect();
        let f: Vec<ExprId> = (0..d).map(|i| g.diff(e.lagrangian, lay.q(i))).collect();
        let gv = e.constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.v(i))).collect()).collect();
        let gq = e.constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.q(i))).collect()).collect();
        let total_force = (0..d).map(|i| g.add(f[i], forces[i])).collect();
        let dpdt = p.iter().map(|&pi| g.diff(pi, lay.time())).collect();
        let gt = e.constraints.iter().map(|&c| g.diff(c, lay.time())).collect();
        Mechanics { p, gv, gq, total_force, dpdt, gt }
    }
}

/// The node density
/// `s = Σ_i p_i dw_i + (f_i + F_i − Σ_a λ_a G_ai) w_i + Σ_a μ_a g^a`.
pub(super) fn density(g: &mut Graph, lay: LocalLayout, m: &Mechanics, constraints: &[ExprId]) -> ExprId {
    let mut s = g.constant(0.0);
    for i in 0..lay.d {
        let dw = g.var(lay.dw(i));
        let t = g.mul(m.p[i], dw);
        s = g.add(s, t);
        let mut coef = m.total_force[i];
        for a in 0..lay.n {
            let la = g.var(lay.lambda(a));
            let t = g.mul(la, m.gv[a][i]);
            coef = g.sub(coef, t);
        }
        let w = g.var(lay.w(i));
        let t = g.mul(coef, w);
        s = g.add(s, t);
    }
    for (a, &c) in constraints.iter().enumerate() {
        let mu = g.var(lay.mu(a));
        let t = g.mul(mu, c);
        s = g.add(s, t);
    }
    s
}

/// The tapes of `s` and of its first and second derivatives.
pub(super) struct DerivativeTapes {
    pub(super) density: Tape,
    pub(super) minus_gradient: Tape,
    pub(super) gradient: Tape,
    pub(super) mixed: PairTape,
    pub(super) plus_plus: PairTape,
    pub(super) all_pairs: PairTape,
}

impl DerivativeTapes {
    /// Differentiate `s` once and twice and compile the residual, Jacobian and Hessian
    /// densities. Pairs of two minus variables are skipped: `s` is linear in them.
    pub(super) fn compile(g: &mut Graph, lay: LocalLayout, s: ExprId) -> DerivativeTapes {
        let (m, inputs) = (lay.len(), lay.inputs());
        let grad: Vec<ExprId> = (0..m).map(|a| g.diff(s, a)).collect();
        let minus: Vec<usize> = (0..m).filter(|&a| !lay.kind(a).0.is_plus()).collect();
        let minus_gradient = Tape::compile(g, &minus.iter().map(|&a| grad[a]).collect::<Vec<_>>(), inputs);
        let gradient = Tape::compile(g, &grad, inputs);
        let density = Tape::compile(g, &[s], inputs);

        let mut mixed = (Vec::new(), Vec::new());
        let mut plus_plus = (Vec::new(), Vec::new());
        let mut all_pairs = (Vec::new(), Vec::new());
        for a in 0..m {
            for b in 0..=a {
                let (pa, pb) = (lay.kind(a).0.is_plus(), lay.kind(b).0.is_plus());
                if !pa && !pb {
                    continue; // s is linear in the minus variables
                }
                let h = g.diff(grad[a], b);
                if g.is_zero(h) {
                    continue;
                }
                all_pairs.0.push((a, b));
                all_pairs.1.push(h);
                let block = if pa && pb { &mut plus_plus } else { &mut mixed };
                block.0.push((a, b));
                block.1.push(h);
            }
        }
        let pair_tape =
            |g: &Graph, (pairs, exprs): (Vec<(usize, usize)>, Vec<ExprId>)| PairTape { tape: Tape::compile(g, &exprs, inputs), pairs };
        DerivativeTapes {
            density,
            minus_gradient,
            gradient,
            mixed: pair_tape(g, mixed),
            plus_plus: pair_tape(g, plus_plus),
            all_pairs: pair_tape(g, all_pairs),
        }
    }
}
