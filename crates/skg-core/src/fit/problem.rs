//! The problem a fit hands to Ipopt ([`FitProblem`]): unknowns `x = (P, θ)`, the plus
//! block of the trajectory and the free parameters; constraints `R(P; θ) = 0`, the
//! reduced system of a solve, with its exact sparse Jacobian `(∂R/∂P, ∂R/∂θ)`; objective
//! the misfit `½ Σ w_i (e_i·P − d_i)²`; bounds on `θ` where the user gave them; and the
//! exact Hessian of Ipopt's Lagrangian `σ f + yᵀR`, which is `σ Σ w_i e_i e_iᵀ` plus the
//! Hessian of `S(P, y; θ)` in `(P, θ)`: the action is linear in its minus block, so
//! `yᵀR(P; θ) = S(P, M = y; θ)` (docs/fitting.md). With the limited-memory option no
//! Hessian is given and Ipopt builds its own quasi-Newton approximation.

use skg_ipopt::{EvalError, Problem, INFINITY_BOUND};

use super::free::FreeParameter;
use super::observe::Observations;
use crate::discrete::action::{Action, MatrixPlan};
use crate::discrete::ParameterPlan;
use crate::model::Workspace;

/// The plans of the derivatives a fit's problem fills.
pub(super) struct Plans {
    /// `∂R/∂P`: a solve's reduced Jacobian.
    pub jacobian: MatrixPlan,
    /// The Hessian block `(P, P)` of `yᵀR`: a solve's reduced Hessian (exact Hessian only).
    pub hessian: Option<MatrixPlan>,
    /// `∂R/∂θ` and the Hessian blocks `(θ, P)`, `(θ, θ)`.
    pub parameters: ParameterPlan,
}

/// A fit as Ipopt's problem (module documentation).
pub(super) struct FitProblem<'a> {
    action: &'a mut Action,
    plans: &'a Plans,
    observations: &'a Observations,
    free: &'a [FreeParameter],
    ws: Workspace,
    /// The whole unknown vector of the action: `P` from `x`, the minus block zero (or the
    /// Hessian's weights).
    z: Vec<f64>,
    /// The parameters the action was last set to.
    theta: Vec<f64>,
    jacobian: Vec<(u32, u32)>,
    hessian: Vec<(u32, u32)>,
}

impl<'a> FitProblem<'a> {
    pub(super) fn new(action: &'a mut Action, plans: &'a Plans, observations: &'a Observations, free: &'a [FreeParameter]) -> Self {
        let n_p = action.layout.n_p as u32;
        let mut jacobian = plans.jacobian.structure.clone();
        jacobian.extend(plans.parameters.jacobian.iter().map(|&(r, j)| (r, n_p + j)));
        let mut hessian = Vec::new();
        if let Some(h) = &plans.hessian {
            hessian.extend(&h.structure);
            hessian.extend(&observations.hessian);
            hessian.extend(&plans.parameters.hessian);
        }
        let ws = action.model.workspace();
        let z = vec![0.0; action.layout.len()];
        FitProblem { action, plans, observations, free, ws, z, theta: Vec::new(), jacobian, hessian }
    }

    /// Set the action to `x`'s parameters (when they changed) and `z` to its plus block,
    /// with the minus block `minus` (the Hessian's weights) or zero.
    fn set(&mut self, x: &[f64], minus: Option<&[f64]>) {
        let n_p = self.action.layout.n_p;
        if self.theta.as_slice() != &x[n_p..] {
            self.theta = x[n_p..].to_vec();
            self.action.set_parameters(&self.theta, &mut self.ws);
        }
        self.z[..n_p].copy_from_slice(&x[..n_p]);
        match minus {
            Some(y) => self.z[n_p..].copy_from_slice(y),
            None => self.z[n_p..].fill(0.0),
        }
    }
}

impl Problem for FitProblem<'_> {
    fn num_variables(&self) -> usize {
        self.action.layout.n_p + self.free.len()
    }
    fn num_constraints(&self) -> usize {
        self.action.layout.n_m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(-INFINITY_BOUND);
        upper.fill(INFINITY_BOUND);
        let n_p = self.action.layout.n_p;
        for (j, p) in self.free.iter().enumerate() {
            lower[n_p + j] = p.lower.unwrap_or(-INFINITY_BOUND);
            upper[n_p + j] = p.upper.unwrap_or(INFINITY_BOUND);
        }
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(self.observations.misfit(x))
    }
    fn objective_gradient(&mut self, x: &[f64], grad: &mut [f64]) -> Result<(), EvalError> {
        self.observations.gradient(x, grad);
        Ok(())
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        self.action.gradient(&self.z, true, c, &mut self.ws);
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jacobian
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        let (solve, params) = values.split_at_mut(self.plans.jacobian.structure.len());
        self.action.matrix_values(&self.plans.jacobian, &self.z, solve, &mut self.ws);
        self.action.parameter_jacobian(&self.plans.parameters, &self.z, params, &mut self.ws);
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &self.hessian
    }
    fn hessian_values(&mut self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        let Some(plan) = &self.plans.hessian else { return Ok(()) };
        self.set(x, Some(lambda));
        let (solve, rest) = values.split_at_mut(plan.structure.len());
        let (misfit, params) = rest.split_at_mut(self.observations.hessian.len());
        self.action.matrix_values(plan, &self.z, solve, &mut self.ws);
        self.observations.hessian_values(obj_factor, misfit);
        self.action.parameter_hessian(&self.plans.parameters, &self.z, params, &mut self.ws);
        Ok(())
    }
}
