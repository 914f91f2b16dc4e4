//! [`Discretization`]: what a solve chooses about the time discretization of a scene's
//! model — the SBP operator, the number of nodes of the grid over the scene's span, and
//! how the initial velocity is imposed. The refinement and the fallback ladder's coarse
//! grid vary it while the model stays the one built from the scene; the scene holds the
//! discretization it asks for ([`Discretization::of`]).

use crate::sbp::OperatorKind;
use crate::scene::{InitialVelocity, Scene};

/// A discretization of a scene's span (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Discretization {
    /// The SBP operator.
    pub operator: OperatorKind,
    /// The number of nodes over the scene's span.
    pub nodes: usize,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
}

impl Discretization {
    /// The discretization the scene asks for (its `[discretization]`, `[time] nodes` and
    /// the command line's overrides).
    pub fn of(scene: &Scene) -> Discretization {
        Discretization { operator: scene.operator, nodes: scene.nodes, initial_velocity: scene.initial_velocity }
    }

    /// The same discretization on `nodes` nodes.
    pub fn with_nodes(self, nodes: usize) -> Discretization {
        Discretization { nodes, ..self }
    }

    /// The node spacing over the scene's span.
    pub fn spacing(&self, scene: &Scene) -> f64 {
        (scene.t_end - scene.t_start) / (self.nodes as f64 - 1.0)
    }

    /// The node times over the scene's span, and their spacing.
    pub fn grid(&self, scene: &Scene) -> (Vec<f64>, f64) {
        let dt = self.spacing(scene);
        ((0..self.nodes).map(|k| scene.t_start + k as f64 * dt).collect(), dt)
    }
}
