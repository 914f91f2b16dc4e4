//! The grid that follows the motion: a [`TimeMap`] made from the steps of a time stepping
//! of the scene (module [`grid`](crate::discrete::grid)
//! says how the steps become a node spacing). One map serves every node count, so a
//! refinement changes `N` and keeps it; a solve on `[discretization] grid = "adaptive"`
//! puts its nodes along it, and `grid = "auto"` (or the operator chosen) weighs it
//! against the uniform grid by predicted cost.

use crate::discrete::grid::TimeMap;
use crate::discrete::Discretization;
use crate::model::Model;
use crate::scene::Scene;
use crate::stepping::equations::{step_budget, step_ends};
use crate::stepping::ode::{OdeOptions, OdeStats};
use crate::stepping::verify::{REFERENCE_ATOL, REFERENCE_RTOL};

/// The relative tolerance of the time stepping that places the nodes.
const MAP_RTOL: f64 = 1e-8;

/// When the grid is chosen, the adaptive one is weighed only if its spacings vary by at
/// least this factor: otherwise it cannot save the half of the nodes it must save to be
/// chosen (its nodes are at least the uniform grid's over the longest spacing's span),
/// and predicting it would only cost time.
pub const WORTH_ADAPTING: f64 = 4.0;

/// The map of `scene`'s span whose nodes follow the steps of a time stepping of its model
/// (with the verification's stepper, at a relative tolerance of 1e-8), graded for grids of at least the scene's own nodes,
/// and that time stepping's work; or why there is none
/// (the time stepping failed, or took fewer than two steps).
pub fn motion_map(scene: &Scene, model: &Model) -> Result<(TimeMap, OdeStats), String> {
    // Where the steps are short does not depend on the tolerance (they all shrink alike
    // as it tightens): a looser one than the verification's takes fewer of them.
    let opts = OdeOptions {
        rtol: MAP_RTOL,
        atol: MAP_RTOL * (REFERENCE_ATOL / REFERENCE_RTOL),
        // As the verification's: with walls no step longer than the scene's own spacing.
        max_step: if model.walls.is_empty() { None } else { Some(Discretization::of(scene).spacing(scene)) },
        max_steps: step_budget(scene.nodes),
        stepper: scene.verify.stepper,
        ..OdeOptions::default()
    };
    let (ends, stats) = step_ends(model, &scene.initial_q, &scene.initial_v, (scene.t_start, scene.t_end), &opts)
        .map_err(|e| format!("the time stepping that places the nodes failed: {e}"))?;
    let map = TimeMap::from_steps(scene.t_start, scene.t_end, &ends, scene.nodes)
        .ok_or_else(|| format!("the time stepping that places the nodes took {} steps, too few to follow", ends.len()))?;
    Ok((map, stats))
}
