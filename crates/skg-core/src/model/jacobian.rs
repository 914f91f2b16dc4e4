//! The exact Jacobian of the index-reduced equations' right-hand side
//! `y = (q, v) ↦ (v, q̈)` ([`Model::state_jacobian`]), differentiated through the
//! saddle-point solve for the accelerations (docs/mathematics.md, section 11).
//!
//! At a state the accelerations `a = q̈` and the multipliers `λ` are the root of the
//! residual of the Lagrange–d'Alembert equations, linear in `(a, λ)`:
//!
//! ```text
//! R(t, q, v; a, λ) = [ W a + Gᵀλ + (∂p/∂q) v + ∂p/∂t − f − F ]  =  A [a; λ] − b,   A = [W Gᵀ; G 0].
//!                    [ G a + (∂g/∂q) v + ∂g/∂t               ]
//! ```
//!
//! Differentiating `R(x; a(x), λ(x)) = 0` in `x = (q, v)` gives
//! `A ∂[a; λ]/∂x = −∂R/∂x`, the partial derivative taken at fixed `(a, λ)`: one solve
//! with the matrix the accelerations were solved with, for all `2d` columns at once.
//! `∂R/∂x` holds third derivatives of the Lagrangian (through `W`, `∂p/∂q`) and the
//! derivatives of the forces and constraints; it is one more tape of the model's graph
//! ([`ResidualDerivatives`]), whose nonzero entries only are computed. The tape is
//! compiled on first use: a solve whose time stepping never goes implicit does not pay
//! for it. The solve with `A` and the Jacobian itself are dense, as the implicit
//! stepper's systems are (twice the coordinates: tens of unknowns on the shipped
//! many-body scenes); against forward differences, which factor `A` once per column,
//! this is never slower.

use std::sync::OnceLock;

use nalgebra::DMatrix;
use skg_expr::{ExprId, Graph, Tape};

use super::derivatives::Mechanics;
use super::layout::LocalLayout;
use super::{DynamicsError, Model, Workspace};

/// The nonzero partial derivatives `∂R_r/∂x_c` of the residual `R` (module docs) in
/// `x = (q, v)`, at fixed accelerations and multipliers, and the tape computing them.
/// The tape's inputs are a model's: the accelerations sit in the slots of `dw`, the
/// multipliers in those of `λ` (no physical quantity depends on `dw`).
pub(super) struct ResidualDerivatives {
    /// `(r, c)` of each output: rows `0..d` the momentum balance, `d..d+n` the
    /// differentiated constraints; columns `0..d` the coordinates, `d..2d` the velocities.
    entries: Vec<(usize, usize)>,
    tape: Tape,
}

impl ResidualDerivatives {
    /// Build `R` on (a copy of) the model's graph, differentiate it and compile the tape.
    fn compile(mut g: Graph, lay: LocalLayout, m: &Mechanics) -> ResidualDerivatives {
        let (d, n) = (lay.d, lay.n);
        let a: Vec<ExprId> = (0..d).map(|j| g.var(lay.dw(j))).collect();
        let lambda: Vec<ExprId> = (0..n).map(|k| g.var(lay.lambda(k))).collect();
        let v: Vec<ExprId> = (0..d).map(|j| g.var(lay.v(j))).collect();
        let mut rows = Vec::with_capacity(d + n);
        for i in 0..d {
            let mut terms = vec![m.dpdt[i]];
            for j in 0..d {
                let w = g.diff(m.p[i], lay.v(j));
                terms.push(g.mul(w, a[j]));
                let pq = g.diff(m.p[i], lay.q(j));
                terms.push(g.mul(pq, v[j]));
            }
            for (gk, &lk) in m.gv.iter().zip(&lambda) {
                terms.push(g.mul(gk[i], lk));
            }
            let sum = g.sum(&terms);
            rows.push(g.sub(sum, m.total_force[i]));
        }
        for k in 0..n {
            let mut terms = vec![m.gt[k]];
            for j in 0..d {
                terms.push(g.mul(m.gv[k][j], a[j]));
                terms.push(g.mul(m.gq[k][j], v[j]));
            }
            rows.push(g.sum(&terms));
        }
        let columns: Vec<usize> = (0..d).map(|j| lay.q(j)).chain((0..d).map(|j| lay.v(j))).collect();
        let (mut entries, mut exprs) = (Vec::new(), Vec::new());
        for (r, &row) in rows.iter().enumerate() {
            for (c, &x) in columns.iter().enumerate() {
                let e = g.diff(row, x);
                if !g.is_zero(e) {
                    entries.push((r, c));
                    exprs.push(e);
                }
            }
        }
        ResidualDerivatives { tape: Tape::compile(&g, &exprs, lay.inputs()), entries }
    }
}

/// The recipe of the [`ResidualDerivatives`] a model compiles on first use.
pub(super) struct LazyJacobian {
    /// The mechanics' expressions in the model's graph.
    pub(super) mechanics: Mechanics,
    pub(super) compiled: OnceLock<ResidualDerivatives>,
}

impl Model {
    /// The Jacobian `∂(v, q̈)/∂(q, v)` of the index-reduced equations' right-hand side at
    /// `(t, q, v)`, written into `jac` (`2d × 2d`, resized if needed): `[0 I; ∂a/∂q ∂a/∂v]`
    /// with `∂[a; λ]/∂x = −A⁻¹ ∂R/∂x` (module docs). Exact up to round-off; it fails
    /// where [`Model::accelerations`] does.
    pub fn state_jacobian(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace, jac: &mut DMatrix<f64>) -> Result<(), DynamicsError> {
        let (d, n, lay) = (self.layout.d, self.layout.n, self.layout);
        let (lu, sol) = self.saddle_point(t, q, v, ws)?;
        let rd = self
            .jacobian
            .compiled
            .get_or_init(|| ResidualDerivatives::compile(self.geometry.graph().clone(), lay, &self.jacobian.mechanics));
        // `saddle_point` left q, v and t in the inputs and zeros in the other local slots.
        ws.u[lay.dw(0)..lay.dw(0) + d].copy_from_slice(sol.rows(0, d).as_slice());
        ws.u[lay.lambda(0)..lay.lambda(0) + n].copy_from_slice(sol.rows(d, n).as_slice());
        if ws.scratch.len() < rd.tape.scratch_len() {
            ws.scratch.resize(rd.tape.scratch_len(), 0.0);
        }
        if ws.out.len() < rd.entries.len() {
            ws.out.resize(rd.entries.len(), 0.0);
        }
        let out = &mut ws.out[..rd.entries.len()];
        rd.tape.eval(&ws.u, &mut ws.scratch, out);
        let mut rx = DMatrix::zeros(d + n, 2 * d);
        for (&(r, c), &value) in rd.entries.iter().zip(out.iter()) {
            rx[(r, c)] = -value;
        }
        let dx = lu.solve(&rx).ok_or(DynamicsError::SingularMassMatrix)?;
        if dx.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite);
        }
        jac.resize_mut(2 * d, 2 * d, 0.0);
        jac.fill(0.0);
        for i in 0..d {
            jac[(i, d + i)] = 1.0;
        }
        jac.view_mut((d, 0), (d, 2 * d)).copy_from(&dx.rows(0, d));
        Ok(())
    }
}
