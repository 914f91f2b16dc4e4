//! The discrete action's square system in either formulation as a [`SquareSystem`]:
//! `Reduced` (`R(P) = ∂S/∂M = 0` in the plus block `P`) and `Full` (`∇S(Z) = 0` in all
//! unknowns), with their values computed by the action on the sparsity plans the
//! [`SquareSolver`](super::SquareSolver) keeps.

use crate::discrete::action::{Action, MatrixPlan};
use crate::model::Workspace;
use crate::solve::linalg::{EvalError, SquareSystem};

/// The reduced system R(P) = ∂S/∂M = 0.
pub(crate) struct Reduced<'a> {
    action: &'a Action,
    /// The whole unknown vector: the plus block set from `x`, the minus block zero (or
    /// the Hessian's weights).
    z: Vec<f64>,
    ws: Workspace,
    jac: &'a MatrixPlan,
    hess: Option<&'a MatrixPlan>,
}

impl<'a> Reduced<'a> {
    /// The reduced system of `action` with the plans `jac` (and `hess`), starting from
    /// the whole unknown vector `z0` (its minus block is not used).
    pub(crate) fn new(action: &'a Action, z0: &[f64], jac: &'a MatrixPlan, hess: Option<&'a MatrixPlan>) -> Self {
        Reduced::with_workspace(action, z0, jac, hess, action.model.workspace())
    }

    /// The same, evaluated with `ws` (a fit's workspace, which holds its parameters).
    pub(crate) fn with_workspace(action: &'a Action, z0: &[f64], jac: &'a MatrixPlan, hess: Option<&'a MatrixPlan>, ws: Workspace) -> Self {
        Reduced { action, z: z0.to_vec(), ws, jac, hess }
    }

    /// The workspace back (the reduced fit's, `fit/reduced.rs`).
    #[cfg(feature = "ipopt")]
    pub(crate) fn into_workspace(self) -> Workspace {
        self.ws
    }

    fn set(&mut self, x: &[f64], minus: Option<&[f64]>) {
        let n_p = self.action.layout.n_p;
        self.z[..n_p].copy_from_slice(x);
        match minus {
            Some(y) => self.z[n_p..].copy_from_slice(y),
            None => self.z[n_p..].iter_mut().for_each(|v| *v = 0.0),
        }
    }
}

impl SquareSystem for Reduced<'_> {
    fn size(&self) -> usize {
        self.action.layout.n_p
    }
    fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        self.action.gradient(&self.z, true, c, &mut self.ws);
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jac.structure
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        self.action.matrix_values(self.jac, &self.z, values, &mut self.ws);
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        self.hess.map_or(&[], |h| &h.structure)
    }
    fn hessian_values(&mut self, x: &[f64], lambda: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        if let Some(plan) = self.hess {
            self.set(x, Some(lambda));
            self.action.matrix_values(plan, &self.z, values, &mut self.ws);
        }
        Ok(())
    }
}

/// The full system ∇S(Z) = 0.
pub(super) struct Full<'a> {
    action: &'a Action,
    ws: Workspace,
    jac: &'a MatrixPlan,
}

impl<'a> Full<'a> {
    /// The full system of `action` with the Jacobian plan `jac`.
    pub(super) fn new(action: &'a Action, jac: &'a MatrixPlan) -> Self {
        Full { action, ws: action.model.workspace(), jac }
    }
}

impl SquareSystem for Full<'_> {
    fn size(&self) -> usize {
        self.action.layout.len()
    }
    fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.action.gradient(x, false, c, &mut self.ws);
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jac.structure
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.action.matrix_values(self.jac, x, values, &mut self.ws);
        Ok(())
    }
}
