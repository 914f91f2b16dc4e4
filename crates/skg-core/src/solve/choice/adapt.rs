//! The grid that follows the motion: a [`TimeMap`] made from the steps of a time stepping
//! of the scene (module [`grid`](crate::discrete::grid)
//! says how the steps become a node spacing). One map serves every node count, so a
//! refinement changes `N` and keeps it; a solve on `[discretization] grid = "adaptive"`
//! puts its nodes along it, and `grid = "auto"` (or the operator chosen) weighs it
//! against the uniform grid by predicted cost.

use crate::discrete::grid::TimeMap;
use crate::model::Model;
use crate::scene::Scene;
use crate::stepping::equations::{step_budget, step_ends};
use crate::stepping::ode::{OdeOptions, OdeStats};
use crate::stepping::verify::{REFERENCE_ATOL, REFERENCE_RTOL};

/// The relative tolerance of the time stepping that places the nodes.
const MAP_RTOL: f64 = 1e-8;

/// With walls, the time stepping that places the nodes takes no step longer than this
/// fraction of the span (the spacing of 256 nodes), whatever the scene's nodes: free
/// flight then weighs the same in every map. The bound was the scene's own spacing, so a
/// larger `--nodes` made free flight ask for shorter steps and spent the nodes there
/// instead of in the contacts: `--grid adaptive --nodes 1517` did not verify the ball on
/// a floor 1e-4 thin (nor the tumbler at σ = 1e-4), which the map of 256 nodes verifies
/// on 1517. Without a bound (the walls' step test alone keeps steps from crossing a
/// wall's layer), the map puts still more nodes into the contacts: the tumbler at
/// σ = 1e-4 verified on 256 nodes, but at σ = 1e-5 the refinement's first grid, on 256
/// nodes, missed its prediction by 8500× and the refinement stopped there.
const MAP_STEPS_WITH_WALLS: f64 = 255.0;

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
        max_step: if model.walls.is_empty() { None } else { Some((scene.t_end - scene.t_start) / MAP_STEPS_WITH_WALLS) },
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
