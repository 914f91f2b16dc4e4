//! The walls' geometry: gaps, normals, Hessians and declared friction directions as
//! expressions of the model's graph, evaluated directly (the hard-wall reference needs
//! them only at events and in contact; the contacts of a trajectory use the gaps).

use skg_expr::{ExprId, Graph};

use super::expressions::WallExprs;
use super::layout::LocalLayout;
use super::Model;

/// The walls' geometry as expressions of the model's graph, evaluated directly (not on
/// a tape: the hard-wall reference needs it only at events and in contact).
pub(super) struct WallGeometry {
    graph: Graph,
    layout: LocalLayout,
    /// h_j(q, t).
    h: Vec<ExprId>,
    /// ∇h_j.
    grad: Vec<Vec<ExprId>>,
    /// ∇²h_j, row-major d×d.
    hess: Vec<Vec<ExprId>>,
    /// The declared friction direction of a wall with friction (of q, v and t).
    friction_direction: Vec<Option<Vec<ExprId>>>,
    /// The values of a fit's free parameters (none for a solve's model).
    theta: Vec<f64>,
}

impl WallGeometry {
    /// Keep the graph with the walls' gaps, gradients, Hessians and friction directions,
    /// evaluated at the free parameters' values `theta` (a fit's model; empty otherwise).
    pub(super) fn derive(mut graph: Graph, lay: LocalLayout, walls: Vec<WallExprs>, theta: Vec<f64>) -> WallGeometry {
        let mut hess = Vec::with_capacity(walls.len());
        for w in &walls {
            let mut hj = Vec::with_capacity(lay.d * lay.d);
            for &gi in &w.grad {
                for k in 0..lay.d {
                    hj.push(graph.diff(gi, lay.q(k)));
                }
            }
            hess.push(hj);
        }
        let mut geometry = WallGeometry { graph, layout: lay, h: vec![], grad: vec![], hess, friction_direction: vec![], theta };
        for w in walls {
            geometry.h.push(w.h);
            geometry.grad.push(w.grad);
            geometry.friction_direction.push(w.friction_direction);
        }
        geometry
    }

    /// The model's graph, which the walls' geometry keeps (the exact Jacobian of the
    /// time stepping is built on a copy of it when first needed).
    pub(super) fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Evaluate `exprs` at (t, q, v); `v` may be empty where the expressions do not use it.
    fn eval(&self, exprs: &[ExprId], t: f64, q: &[f64], v: &[f64]) -> Vec<f64> {
        let lay = self.layout;
        let mut inputs = vec![0.0; lay.inputs()];
        inputs[..lay.d].copy_from_slice(q);
        inputs[lay.d..lay.d + v.len()].copy_from_slice(v);
        inputs[lay.time()] = t;
        inputs[lay.time() + 1..].copy_from_slice(&self.theta);
        self.graph.eval_many(exprs, &inputs)
    }
}

impl Model {
    /// The gaps `h_j(q, t)` of every wall (≤ 0 on the allowed side).
    pub fn wall_gaps(&self, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.h, t, q, &[])
    }

    /// Whether wall `j`'s gap depends on the time explicitly (a moving wall).
    pub fn wall_moves(&self, j: usize) -> bool {
        self.geometry.graph.variables(self.geometry.h[j]).contains(&self.layout.time())
    }

    /// The gradient `∇h_j(q, t)` of wall `j`'s gap: its outward normal, not normalized.
    pub fn wall_normal(&self, j: usize, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.grad[j], t, q, &[])
    }

    /// The Hessian `∇²h_j(q, t)` of wall `j`'s gap, row-major d×d.
    pub fn wall_hessian(&self, j: usize, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.hess[j], t, q, &[])
    }

    /// The declared friction direction of wall `j` at (t, q, v), not normalized; `None`
    /// if the wall has no friction or declares no direction (friction then opposes the
    /// velocity along the wall).
    pub fn friction_direction(&self, j: usize, t: f64, q: &[f64], v: &[f64]) -> Option<Vec<f64>> {
        let dir = self.geometry.friction_direction[j].as_ref()?;
        Some(self.geometry.eval(dir, t, q, v))
    }
}
