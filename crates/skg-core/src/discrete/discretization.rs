//! [`Discretization`]: what a solve chooses about the time discretization of a scene's
//! model — the SBP operator, the number of nodes and where they are over the scene's
//! span ([`Grid`]), and how the initial velocity is imposed. The refinement and the
//! fallback ladder's coarse grid vary it while the model stays the one built from the
//! scene; the scene holds the discretization it asks for ([`Discretization::of`]), with a
//! uniform grid: a grid that follows the motion is made from a time stepping
//! ([`adapt`](crate::solve::choice::adapt)).

use super::grid::Grid;
use crate::sbp::{OperatorKind, SbpError, SbpOperator};
use crate::scene::{InitialVelocity, Scene};

/// A discretization of a scene's span (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Discretization {
    /// The SBP operator.
    pub operator: OperatorKind,
    /// The number of nodes over the scene's span.
    pub nodes: usize,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
    /// Where the nodes are.
    pub grid: Grid,
}

impl Discretization {
    /// The discretization the scene asks for (its `[discretization]`, `[time] nodes` and
    /// the command line's overrides) on a uniform grid.
    pub fn of(scene: &Scene) -> Discretization {
        Discretization { operator: scene.operator, nodes: scene.nodes, initial_velocity: scene.initial_velocity, grid: Grid::Uniform }
    }

    /// The same discretization on `nodes` nodes.
    pub fn with_nodes(&self, nodes: usize) -> Discretization {
        Discretization { nodes, ..self.clone() }
    }

    /// The same discretization on the grid `grid`.
    pub fn with_grid(&self, grid: Grid) -> Discretization {
        Discretization { grid, ..self.clone() }
    }

    /// The mean node spacing over the scene's span (the spacing of a uniform grid).
    pub fn spacing(&self, scene: &Scene) -> f64 {
        (scene.t_end - scene.t_start) / (self.nodes as f64 - 1.0)
    }

    /// The node times over the scene's span.
    pub fn times(&self, scene: &Scene) -> Vec<f64> {
        self.grid.times(scene.t_start, scene.t_end, self.nodes)
    }

    /// The operator on the nodes `times` (spread as this discretization's grid spreads
    /// them; [`operator_on`]).
    pub fn operator_on(&self, times: &[f64]) -> Result<SbpOperator, SbpError> {
        operator_on(self.operator, times, !self.grid.is_uniform())
    }
}

/// The operator of `kind` on the nodes `times`: on a uniform grid the uniform operator of
/// their spacing, on a mapped one (`mapped`) the operator on those nodes
/// ([`SbpOperator::on_times`]).
pub fn operator_on(kind: OperatorKind, times: &[f64], mapped: bool) -> Result<SbpOperator, SbpError> {
    if mapped {
        return SbpOperator::on_times(kind, times);
    }
    let n = times.len();
    let dt = if n > 1 { (times[n - 1] - times[0]) / (n - 1) as f64 } else { f64::NAN };
    SbpOperator::new(kind, n, dt)
}
