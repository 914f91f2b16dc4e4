//! The discrete action's derivatives in the free parameters `θ` of a fit's model
//! ([`Model::with_free_parameters`](crate::model::Model::with_free_parameters)).
//!
//! `θ` enters the action `S(P, M; θ) = Σ_k H_kk s(T_k Z, t_k; θ) + ½ Zᵀ K Z + l(θ)ᵀ Z`
//! through the node density and through the linear boundary terms `l(θ)`: `−q₀(θ)` on
//! `ν_x`, then `−q̇₀(θ)` on `ν_v` (strong initial velocity) or `p₀(θ)` on `q-[1]`
//! (natural). `S` stays linear in `M`, so the residual `R(P; θ) = ∂S/∂M` and
//!
//! * its Jacobian in the parameters,
//!   `∂R/∂θ_j = Σ_k H_kk T_kᵀ ∂²s/∂u_minus∂θ_j + ∂l_M/∂θ_j`;
//! * the Hessian of `yᵀR(P; θ) = S(P, y; θ)` in `(P, θ)`: its block `(P, P)` is a
//!   solve's reduced Hessian ([`Block::ReducedHessian`](super::action::Block)) at `M = y`;
//!   its blocks `(θ, P)` and `(θ, θ)` are `Σ_k H_kk ∂²s/∂θ∂u_plus T_k` and
//!   `Σ_k H_kk ∂²s/∂θ∂θ + ∂²(l(θ)ᵀy)/∂θ²` at `M = y`.
//!
//! [`ParameterPlan`] holds their sparsity structures, computed once, and the recipe to
//! fill their values in place, as the action's own plans do. The values of `θ` are the
//! workspace's (`Workspace::u` after the time); [`Action::set_parameters`] sets them
//! there and moves the boundary terms to the initial state they give.

use rustc_hash::FxHashMap;

use super::action::Action;
use crate::model::{InitialTape, Workspace};
use crate::scene::InitialVelocity;

const NONE: u32 = u32::MAX;

/// The distinct entries of a matrix and the slot of each, in the order first met.
#[derive(Default)]
struct Entries {
    index: FxHashMap<(u32, u32), u32>,
    structure: Vec<(u32, u32)>,
}

impl Entries {
    fn slot(&mut self, entry: (u32, u32)) -> u32 {
        let next = self.structure.len() as u32;
        *self.index.entry(entry).or_insert_with(|| {
            self.structure.push(entry);
            next
        })
    }
}

/// A linear boundary term's derivative: `sign · (initial tape output)` at `slot`, for the
/// Hessian weighted by the multiplier at Z index `weight`.
#[derive(Debug, Clone, Copy)]
struct BoundaryTerm {
    slot: u32,
    output: usize,
    weight: u32,
    sign: f64,
}

/// The sparsity structures of the action's derivatives in the free parameters and the
/// recipes to fill them (module documentation).
pub struct ParameterPlan {
    /// The entries `(row of R, j)` of `∂R/∂θ`.
    pub jacobian: Vec<(u32, u32)>,
    /// The entries of the Hessian blocks `(θ, P)` and `(θ, θ)` in the numbering of the
    /// unknowns `x = (P, θ)`, lower triangle: `(n_p + j, i)` and `(n_p + j, n_p + l)`
    /// with `j ≥ l`.
    pub hessian: Vec<(u32, u32)>,
    /// The Jacobian's slot of every product of the density part, in visiting order.
    jacobian_density: Vec<u32>,
    jacobian_boundary: Vec<BoundaryTerm>,
    /// The Hessian's slot of every product of the `(θ, P)` density part, then of the
    /// `(θ, θ)` density part, in visiting order.
    hessian_plus: Vec<u32>,
    hessian_theta: Vec<u32>,
    hessian_boundary: Vec<BoundaryTerm>,
}

impl Action {
    /// The plan of the action's derivatives in its model's free parameters (empty for a
    /// model without any).
    pub fn parameter_plan(&self) -> ParameterPlan {
        let mut plan = ParameterPlan {
            jacobian: Vec::new(),
            hessian: Vec::new(),
            jacobian_density: Vec::new(),
            jacobian_boundary: Vec::new(),
            hessian_plus: Vec::new(),
            hessian_theta: Vec::new(),
            hessian_boundary: Vec::new(),
        };
        let Some(params) = &self.model.parameters else { return plan };
        let lay = &self.layout;
        let n_p = lay.n_p as u32;
        let (mut jac, mut hess) = (Entries::default(), Entries::default());
        for k in 0..lay.nodes {
            for &(a, j) in &params.minus.pairs {
                for &(i, _) in self.entries(k, a) {
                    plan.jacobian_density.push(jac.slot((i - n_p, j as u32)));
                }
            }
            for &(a, j) in &params.plus.pairs {
                for &(i, _) in self.entries(k, a) {
                    plan.hessian_plus.push(hess.slot((n_p + j as u32, i)));
                }
            }
            for &(j, l) in &params.theta.pairs {
                plan.hessian_theta.push(hess.slot((n_p + j as u32, n_p + l as u32)));
            }
        }
        let free = params.names.len();
        for (block, row, i, sign) in self.boundary_rows() {
            let tape = &params.initial;
            for j in 0..free {
                let output = tape.first(block, i, j);
                if !tape.zero[output] {
                    plan.jacobian_boundary.push(BoundaryTerm { slot: jac.slot((row - n_p, j as u32)), output, weight: row, sign });
                }
                for l in 0..=j {
                    let output = tape.second(block, i, j, l);
                    if !tape.zero[output] {
                        let slot = hess.slot((n_p + j as u32, n_p + l as u32));
                        plan.hessian_boundary.push(BoundaryTerm { slot, output, weight: row, sign });
                    }
                }
            }
        }
        plan.jacobian = jac.structure;
        plan.hessian = hess.structure;
        plan
    }

    /// The rows of `R` (as Z indices) that carry the linear boundary terms, with the
    /// initial tape's block (0: `q₀`, 1: `q̇₀`, 2: `p₀`), the component and the sign of
    /// the term: `−q₀` on `ν_x`, `−q̇₀` on `ν_v` (strong) or `+p₀` on `q-[1]` (natural).
    fn boundary_rows(&self) -> Vec<(usize, u32, usize, f64)> {
        let lay = &self.layout;
        let mut rows: Vec<(usize, u32, usize, f64)> = lay.nu_x.iter().enumerate().map(|(i, &z)| (0, z, i, -1.0)).collect();
        match lay.initial_velocity {
            InitialVelocity::Strong => rows.extend(lay.nu_v.iter().enumerate().map(|(i, &z)| (1, z, i, -1.0))),
            InitialVelocity::Natural => rows.extend(lay.qm[..lay.d].iter().enumerate().map(|(i, &z)| (2, z, i, 1.0))),
        }
        rows
    }

    /// The initial tape's outputs at the workspace's `θ` and the action's start time.
    fn initial_outputs(&self, tape: &InitialTape, ws: &mut Workspace) -> Vec<f64> {
        ws.u[self.model.layout.time()] = self.t0();
        let mut out = vec![0.0; tape.tape.n_outputs()];
        tape.tape.eval(&ws.u, &mut ws.scratch, &mut out);
        out
    }

    /// Set the free parameters to `theta`: into the workspace's inputs, and the boundary
    /// terms to the initial state (and, for the natural initial velocity, the momentum)
    /// they give. Nothing happens for a model without free parameters.
    ///
    /// # Panics
    /// If `theta` does not have one entry per free parameter.
    pub fn set_parameters(&mut self, theta: &[f64], ws: &mut Workspace) {
        let Some(params) = &self.model.parameters else { return };
        assert_eq!(theta.len(), params.names.len(), "one value per free parameter");
        let lay = self.model.layout;
        ws.u[lay.theta(0)..lay.theta(0) + theta.len()].copy_from_slice(theta);
        let out = self.initial_outputs(&params.initial, ws);
        let tape = &params.initial;
        let block = |b: usize| (0..lay.d).map(|i| out[tape.value(b, i)]).collect::<Vec<f64>>();
        let p0 = match self.layout.initial_velocity {
            InitialVelocity::Natural => block(2),
            InitialVelocity::Strong => vec![0.0; lay.d],
        };
        self.set_boundary_data(block(0), block(1), p0);
    }

    /// `∂R/∂θ` at `z` and the workspace's `θ`, into `values` in the order of
    /// `plan.jacobian`.
    pub fn parameter_jacobian(&self, plan: &ParameterPlan, z: &[f64], values: &mut [f64], ws: &mut Workspace) {
        values.fill(0.0);
        let Some(params) = &self.model.parameters else { return };
        let h = self.op.norm();
        let tape = &params.minus.tape;
        let mut slots = plan.jacobian_density.iter();
        for k in 0..self.layout.nodes {
            self.gather(k, z, &mut ws.u);
            tape.eval(&ws.u, &mut ws.scratch, &mut ws.out[..tape.n_outputs()]);
            for (e, &(a, _)) in params.minus.pairs.iter().enumerate() {
                let val = h[k] * ws.out[e];
                for &(_, c) in self.entries(k, a) {
                    let slot = *slots.next().unwrap_or(&NONE);
                    values[slot as usize] += c * val;
                }
            }
        }
        let out = self.initial_outputs(&params.initial, ws);
        for b in &plan.jacobian_boundary {
            values[b.slot as usize] += b.sign * out[b.output];
        }
    }

    /// The Hessian blocks `(θ, P)` and `(θ, θ)` of `S(P, M; θ)` at `z` (whose minus block
    /// holds the weights `y`) and the workspace's `θ`, into `values` in the order of
    /// `plan.hessian`.
    pub fn parameter_hessian(&self, plan: &ParameterPlan, z: &[f64], values: &mut [f64], ws: &mut Workspace) {
        values.fill(0.0);
        let Some(params) = &self.model.parameters else { return };
        let h = self.op.norm();
        let (plus, theta) = (&params.plus, &params.theta);
        let (mut plus_slots, mut theta_slots) = (plan.hessian_plus.iter(), plan.hessian_theta.iter());
        for k in 0..self.layout.nodes {
            self.gather(k, z, &mut ws.u);
            plus.tape.eval(&ws.u, &mut ws.scratch, &mut ws.out[..plus.tape.n_outputs()]);
            for (e, &(a, _)) in plus.pairs.iter().enumerate() {
                let val = h[k] * ws.out[e];
                for &(_, c) in self.entries(k, a) {
                    let slot = *plus_slots.next().unwrap_or(&NONE);
                    values[slot as usize] += c * val;
                }
            }
            theta.tape.eval(&ws.u, &mut ws.scratch, &mut ws.out[..theta.tape.n_outputs()]);
            for e in 0..theta.pairs.len() {
                let slot = *theta_slots.next().unwrap_or(&NONE);
                values[slot as usize] += h[k] * ws.out[e];
            }
        }
        let out = self.initial_outputs(&params.initial, ws);
        for b in &plan.hessian_boundary {
            values[b.slot as usize] += b.sign * z[b.weight as usize] * out[b.output];
        }
    }
}
