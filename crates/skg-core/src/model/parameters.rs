//! The free parameters of a fit's model: scene parameters that stay symbolic, tape inputs
//! `θ` after the time, with the derivatives of the node density and of the initial state
//! with respect to them ([`ParameterTapes`]).
//!
//! A free parameter is the variable `θ_j` (input [`LocalLayout::theta`]); a parameter
//! whose definition uses one is that definition as an expression of `θ`
//! ([`symbolic_parameters`]); every other parameter stays its resolved value, folded into
//! the expressions as in any model. So a free parameter reaches the density `s` through
//! the Lagrangian, the constraints, the forces and the walls (their gaps, friction
//! directions and numbers), and the boundary terms through the initial state `q₀(θ)`,
//! `q̇₀(θ)` and, for the natural initial velocity, the momentum
//! `p₀(θ) = ∂L/∂q̇ (q₀(θ), q̇₀(θ), t₀; θ)`.
//!
//! What the fit needs beyond a solve's tapes, all exact and symbolic:
//! * `∂²s/∂u_a∂θ_j` for the minus variables `a`: the density of the residual's Jacobian
//!   in the parameters, `∂R/∂θ`;
//! * `∂²s/∂u_a∂θ_j` for the plus variables and `∂²s/∂θ_j∂θ_l`: with the minus variables
//!   set to the constraints' multipliers, the blocks `(θ, P)` and `(θ, θ)` of the
//!   Hessian of the fit's Lagrangian (the block `(P, P)` is a solve's
//!   [`Model::plus_plus`](super::Model::plus_plus));
//! * the initial state and momentum with their first and second derivatives in `θ`
//!   ([`InitialTape`]).

use indexmap::IndexMap;
use skg_expr::{ExprId, Graph, Symbol, Tape};

use super::derivatives::{Mechanics, PairTape};
use super::expressions::Expressions;
use super::layout::LocalLayout;
use crate::scene::{NumOrExpr, Scene, SceneError};

/// The parameters of `scene` as the names of a fit's expressions: each free parameter
/// (`free[j]`) the variable `θ_j`, each parameter whose definition depends on one its
/// definition as an expression of `θ`, in `graph`. The other parameters are not listed:
/// they stay their resolved values. A name in `free` that is not a parameter of the
/// scene is an error.
pub(super) fn symbolic_parameters(
    graph: &mut Graph,
    scene: &Scene,
    free: &[String],
    lay: LocalLayout,
) -> Result<IndexMap<String, ExprId>, SceneError> {
    let mut symbols: IndexMap<String, ExprId> = IndexMap::new();
    for (j, name) in free.iter().enumerate() {
        if !scene.parameters.contains_key(name) {
            let known: Vec<&str> = scene.parameters.keys().map(String::as_str).collect();
            return Err(SceneError::Invalid {
                location: scene.file.origin.whole(),
                message: format!(
                    "`{name}` is not a parameter of the scene, so it cannot be free (parameters: {})",
                    if known.is_empty() { "none".to_string() } else { known.join(", ") }
                ),
            });
        }
        let var = graph.var(lay.theta(j));
        symbols.insert(name.clone(), var);
    }
    // The definitions in dependency order: a definition is parsed once every parameter
    // it names is known (the scene was resolved, so there is no cycle).
    let mut done: Vec<&str> = free.iter().map(String::as_str).collect();
    let mut pending: Vec<&String> = scene.definitions.keys().filter(|n| !done.contains(&n.as_str())).collect();
    while !pending.is_empty() {
        let before = pending.len();
        let mut still = Vec::new();
        for name in pending {
            let NumOrExpr::Expr(text) = &scene.definitions[name] else {
                done.push(name);
                continue;
            };
            let ready = |n: &str| done.contains(&n);
            let parsed = graph.parse(text, &mut |n| match symbols.get(n) {
                Some(&e) => Some(Symbol::Expr(e)),
                None if ready(n) => scene.parameters.get(n).map(|&x| Symbol::Const(x)),
                None => None,
            });
            match parsed {
                Ok(e) => {
                    // A definition that folds to a number is that parameter's resolved
                    // value, exactly as in a solve's model.
                    if graph.as_constant(e).is_none() {
                        symbols.insert(name.clone(), e);
                    }
                    done.push(name);
                }
                Err(_) => still.push(name),
            }
        }
        if still.len() == before {
            // No progress: cannot happen for a resolved scene; said rather than looped.
            let name = still[0];
            let location = match scene.file.parameters.get(name) {
                Some(v) => scene.file.origin.locate_in(v, None),
                None => scene.file.origin.whole(),
            };
            return Err(SceneError::Invalid { location, message: format!("parameter `{name}`: its definition cannot be made symbolic") });
        }
        pending = still;
    }
    Ok(symbols)
}

/// The initial state and momentum of a fit's model as functions of `θ`, and their first
/// and second derivatives: one tape whose inputs are a tape's inputs (only the time and
/// `θ` are read) and whose outputs are, for each of `q₀`, `q̇₀`, `p₀` (blocks 0, 1, 2),
/// the `d` values, then the `d × nθ` first derivatives, then the `d × nθ(nθ+1)/2`
/// second derivatives `∂²/∂θ_j∂θ_l`, `j ≥ l`.
pub struct InitialTape {
    /// The tape.
    pub tape: Tape,
    /// Per output: whether it is identically zero (a derivative of an initial value that
    /// does not depend on that parameter).
    pub zero: Vec<bool>,
    d: usize,
    free: usize,
}

impl InitialTape {
    /// The number of parameter pairs `(j, l)`, `j ≥ l`.
    pub fn pairs(&self) -> usize {
        self.free * (self.free + 1) / 2
    }

    /// The index of the pair `(j, l)`, `j ≥ l`, among the pairs.
    pub fn pair(j: usize, l: usize) -> usize {
        j * (j + 1) / 2 + l
    }

    fn block_len(&self) -> usize {
        self.d * (1 + self.free + self.pairs())
    }

    /// Output index of component `i` of block `b` (0: `q₀`, 1: `q̇₀`, 2: `p₀`).
    pub fn value(&self, b: usize, i: usize) -> usize {
        b * self.block_len() + i
    }

    /// Output index of `∂/∂θ_j` of component `i` of block `b`.
    pub fn first(&self, b: usize, i: usize, j: usize) -> usize {
        b * self.block_len() + self.d + i * self.free + j
    }

    /// Output index of `∂²/∂θ_j∂θ_l` (`j ≥ l`) of component `i` of block `b`.
    pub fn second(&self, b: usize, i: usize, j: usize, l: usize) -> usize {
        b * self.block_len() + self.d * (1 + self.free) + i * self.pairs() + Self::pair(j, l)
    }
}

/// The tapes of a fit's model in its free parameters (module documentation).
pub struct ParameterTapes {
    /// The free parameters' names, in the order of their inputs `θ_j`.
    pub names: Vec<String>,
    /// The values the model was built with (the scene's): every workspace of the model
    /// starts with them in its `θ` inputs.
    pub values: Vec<f64>,
    /// `∂²s/∂u_a∂θ_j` for the minus variables `a`, as pairs `(a, j)`.
    pub minus: PairTape,
    /// `∂²s/∂u_a∂θ_j` for the plus variables `a`, as pairs `(a, j)`.
    pub plus: PairTape,
    /// `∂²s/∂θ_j∂θ_l`, `j ≥ l`, as pairs `(j, l)`.
    pub theta: PairTape,
    /// The initial state and momentum and their derivatives in `θ`.
    pub initial: InitialTape,
}

impl ParameterTapes {
    /// Differentiate the density `s` and the initial state in the free parameters and
    /// compile the tapes.
    pub(super) fn compile(
        g: &mut Graph,
        lay: LocalLayout,
        s: ExprId,
        e: &Expressions,
        mech: &Mechanics,
        scene: &Scene,
        free: &[String],
    ) -> Self {
        let (m, inputs) = (lay.len(), lay.inputs());
        let thetas: Vec<usize> = (0..lay.free).map(|j| lay.theta(j)).collect();
        let mut minus = (Vec::new(), Vec::new());
        let mut plus = (Vec::new(), Vec::new());
        for a in 0..m {
            let grad = g.diff(s, a);
            for (j, &theta) in thetas.iter().enumerate() {
                let h = g.diff(grad, theta);
                if g.is_zero(h) {
                    continue;
                }
                let block = if lay.kind(a).0.is_plus() { &mut plus } else { &mut minus };
                block.0.push((a, j));
                block.1.push(h);
            }
        }
        let mut theta = (Vec::new(), Vec::new());
        for (j, &tj) in thetas.iter().enumerate() {
            let ds = g.diff(s, tj);
            for (l, &tl) in thetas.iter().enumerate().take(j + 1) {
                let h = g.diff(ds, tl);
                if !g.is_zero(h) {
                    theta.0.push((j, l));
                    theta.1.push(h);
                }
            }
        }
        let pair_tape =
            |g: &Graph, (pairs, exprs): (Vec<(usize, usize)>, Vec<ExprId>)| PairTape { tape: Tape::compile(g, &exprs, inputs), pairs };
        ParameterTapes {
            names: free.to_vec(),
            values: free.iter().map(|n| scene.parameters[n]).collect(),
            minus: pair_tape(g, minus),
            plus: pair_tape(g, plus),
            theta: pair_tape(g, theta),
            initial: initial_tape(g, lay, e, mech),
        }
    }
}

/// The tape of the initial state `q₀(θ)`, `q̇₀(θ)` and momentum `p₀(θ)` with their first
/// and second derivatives ([`InitialTape`]).
fn initial_tape(g: &mut Graph, lay: LocalLayout, e: &Expressions, mech: &Mechanics) -> InitialTape {
    let d = lay.d;
    let q0: Vec<ExprId> = e.initial_q.iter().map(|x| x.expr(g)).collect();
    let v0: Vec<ExprId> = e.initial_v.iter().map(|x| x.expr(g)).collect();
    let state: Vec<(usize, ExprId)> = (0..d).map(|i| (lay.q(i), q0[i])).chain((0..d).map(|i| (lay.v(i), v0[i]))).collect();
    let p0: Vec<ExprId> = mech.p.iter().map(|&p| g.substitute(p, &state)).collect();
    let mut outs = Vec::new();
    for block in [&q0, &v0, &p0] {
        outs.extend(block.iter().copied());
        for &x in block.iter() {
            for j in 0..lay.free {
                outs.push(g.diff(x, lay.theta(j)));
            }
        }
        for &x in block.iter() {
            for j in 0..lay.free {
                let dj = g.diff(x, lay.theta(j));
                for l in 0..=j {
                    outs.push(g.diff(dj, lay.theta(l)));
                }
            }
        }
    }
    let zero = outs.iter().map(|&x| g.is_zero(x)).collect();
    InitialTape { tape: Tape::compile(g, &outs, lay.inputs()), zero, d, free: lay.free }
}
