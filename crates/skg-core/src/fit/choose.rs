//! `--operator auto` and `--refine` for a fit: the discretization chosen by the solve's
//! refinement ([`crate::solve::refine`]) for the scene at given parameter values, then
//! held fixed while the fit moves the parameters.
//!
//! A fit optimizes over one discretization (its grid and operator define the unknowns
//! and the interpolation of the data). The refinement chooses, by predicted cost, the
//! operator, its initial-velocity condition and the node count that verify at the
//! scene's tolerance; it does so for one set of parameter values, so the fit asks for it
//! at the starting values and, when the fitted motion then fails its verification, once
//! more at the fitted values (`fit` in the module above). An adaptive grid chosen is
//! made from the motion at the values it was chosen at, and kept while the fit moves
//! the parameters.

use serde::Serialize;

use super::FitError;
use crate::scene::{GridChoice, InitialVelocity, Overrides, Scene};
use crate::solve::{solve_scene, Deadline, Refinement};

/// The discretization a refinement chose for a fit, as `summary.json`'s
/// `fit.discretization` lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ChosenDiscretization {
    /// The parameter values it was chosen at (`"the starting values"`, or the fitted
    /// values of a first fit).
    pub chosen_at: String,
    /// The operator chosen.
    pub operator: String,
    /// The number of nodes.
    pub nodes: usize,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
    /// `uniform` or `adaptive`.
    pub grid: &'static str,
    /// Whether the solve at those values verified on it.
    pub verified: bool,
    /// The refinement's grids and result at those values.
    pub refinement: Option<Refinement>,
}

impl ChosenDiscretization {
    /// The same discretization as `other`: the same operator, initial velocity and
    /// nodes on a uniform grid (an adaptive grid's map follows the motion it was chosen
    /// at, so two chosen at different values differ).
    pub fn same_as(&self, other: &ChosenDiscretization) -> bool {
        self.operator == other.operator
            && self.nodes == other.nodes
            && self.initial_velocity == other.initial_velocity
            && self.grid == "uniform"
            && other.grid == "uniform"
    }

    /// `SBP363-AD (natural initial velocity) on 2000 uniform nodes`.
    pub fn describe(&self) -> String {
        format!("{} ({} initial velocity) on {} {} nodes", self.operator, self.initial_velocity, self.nodes, self.grid)
    }
}

/// The scene (and the overrides that resolve its file to it) on the discretization the
/// refinement chooses for `scene` at its parameter values (`at` names them), with what
/// was chosen, the refinement ending by `deadline`. A scene the refinement cannot verify
/// at these values keeps the grid its refinement ended on, and the choice says so
/// (`verified: false`).
pub(super) fn discretization(
    scene: &Scene,
    overrides: &Overrides,
    at: &str,
    deadline: Option<Deadline>,
) -> Result<(Scene, Overrides, ChosenDiscretization), FitError> {
    let mut probe = scene.clone();
    // The refinement runs under what is left of the fit's time limit.
    if let Some(d) = deadline {
        probe.solver.time_limit = Some(d.left_s());
    }
    let outcome = solve_scene(&probe)?;
    let s = &outcome.settings;
    let operator = s.operator.parse().map_err(|e| FitError::Settings(format!("the refinement's operator `{}`: {e}", s.operator)))?;
    let mut ov = overrides.clone();
    ov.operator = Some(operator);
    ov.auto_operator = false;
    ov.refine = false;
    ov.nodes = Some(s.nodes);
    ov.initial_velocity = Some(s.initial_velocity);
    ov.grid = Some(if s.grid == "adaptive" { GridChoice::Adaptive } else { GridChoice::Uniform });
    let mut chosen = scene.file.clone().resolve(&ov)?;
    fixed(&mut chosen);
    let report = ChosenDiscretization {
        chosen_at: at.to_string(),
        operator: s.operator.clone(),
        nodes: s.nodes,
        initial_velocity: s.initial_velocity,
        grid: s.grid,
        verified: outcome.trusted(),
        refinement: outcome.refinement.clone(),
    };
    Ok((chosen, ov, report))
}

/// `scene` with its discretization as resolved, none of it left to choose (a scene
/// file's `[verify] refine = true` stays in its file, not in the fit).
pub(super) fn fixed(scene: &mut Scene) {
    scene.verify.refine = false;
    scene.choose_operator = false;
    scene.choose_initial_velocity = false;
    scene.choose_grid = false;
}
