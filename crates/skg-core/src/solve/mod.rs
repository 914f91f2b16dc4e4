//! The solve: the critical point of the discrete action of a scene's model, found by a
//! backend, assessed against time stepping, and, when it fails, the fallback ladder;
//! with `--refine` or `--operator auto`, the discretization chosen to meet a tolerance.
//!
//! The front door is [`solve_scene`]: it builds the scene's model once and hands it,
//! with the discretization the scene asks for ([`Discretization`]), to the ladder or the
//! refinement. In the order in which the parts use each other (each only the ones
//! before it):
//!
//! * [`linalg`]: the linear algebra of a square sparse system — the project's own
//!   [`SquareSystem`](linalg::SquareSystem) trait, Newton's method over a sparse LU (in
//!   double or single precision), the round-off level of a residual, the band solver.
//!   It knows nothing of scenes.
//! * [`run`]: one run of one discretization — the backend ([`SquareSolver`]: Ipopt or
//!   Newton on the action's system), one piece (the initial guess, the backend's solve,
//!   the trajectory), a global run or a run in windows, and its assessment (the
//!   [`Outcome`]: verification, diagnostics, warnings), statuses and errors.
//! * [`ladder`]: the scene's own run, then the fallback ladder (coarse-to-fine guess,
//!   wall-width continuation, past the end, windows) until a run converges and verifies.
//! * [`choice`]: the choice of the discretization — the refinement, the prediction of
//!   every candidate's error from the time-stepping reference, the measured cost of
//!   each operator.
//!
//! **Place in the flow.** After time stepping: it uses [`scene`](crate::scene),
//! [`memory`], [`model`](crate::model), [`discrete`](crate::discrete) and
//! [`stepping`](crate::stepping) (the initial guess and the verification). The output
//! and the consumers (check, tune, the command line, Python) call [`solve_scene`].

use std::sync::Arc;

use crate::discrete::{Discretization, Grid};
use crate::memory;
use crate::model::Model;
use crate::scene::{GridChoice, InitialVelocity, Scene};
use crate::stepping::layer::initial_layer;

pub mod choice;
pub mod ladder;
pub mod linalg;
pub mod run;

pub use choice::{adapt, cost, predict, refine};
pub use linalg::{band, newton};
pub use run::{backend, deadline, window};

pub use run::assess::{energy_drift_skip, outcome, sizes};
pub use run::backend::SquareSolver;
pub use run::deadline::Deadline;
pub use run::error::{SolveError, WindowError};
pub use run::global::{solve_global, Run};
pub use run::outcome::{Attempt, Diagnostics, KineticLoss, Method, Outcome, RefinedGrid, Refinement, Settings, Sizes, Timings, Work};
pub use run::piece::{action_on, build_action, grid, point_from_states, solve_piece, Guess, Piece};
pub use run::status::{SolveStatus, CONVERGED_RESIDUAL};

/// Solve a resolved scene: the solve the scene asks for (in one piece or in windows),
/// verified against time stepping of the same scene, the fallback ladder when it fails
/// to converge or to verify, and the refinement or the operator choice when asked for
/// ([`refine`]).
///
/// Refused before anything is allocated if its memory estimate exceeds the available
/// memory ([`memory`]).
pub fn solve_scene(scene: &Scene) -> Result<Outcome, SolveError> {
    solve_scene_with_progress(scene, &mut |_| {})
}

/// [`solve_scene`], telling `progress` what each attempt is about to do ("2. coarse to
/// fine (…)", "grid 2: SBP484 (natural) on 513 nodes"), for a progress display.
pub fn solve_scene_with_progress(scene: &Scene, progress: &mut dyn FnMut(&str)) -> Result<Outcome, SolveError> {
    let deadline = Deadline::after(scene.solver.time_limit);
    let chooses = scene.verify.refine || scene.choose_operator || scene.choose_grid;
    if !chooses {
        memory::check(scene, "the solve", scene.nodes, memory::solve_bytes(scene))?;
    }
    let model = Arc::new(Model::build(scene)?);
    let (own, note) = scene_discretization(scene, &model);
    let mut outcome = if chooses {
        refine::refine(scene, &model, &own, deadline, progress)?
    } else {
        let limits = run::deadline::Limits { time_limit: deadline, budget: None };
        ladder::climb(scene, &model, &own, &Guess::TimeStepping, ladder::Rungs::All, limits, progress)?
    };
    outcome.notes.extend(note);
    Ok(outcome)
}

/// The discretization a scene is solved (or fitted) on before any choice: the one it asks
/// for ([`own_discretization`]) on the grid it asks for ([`adaptive_grid`]), with the
/// note of what was changed or could not be made.
pub(crate) fn scene_discretization(scene: &Scene, model: &Model) -> (Discretization, Option<String>) {
    let (own, note) = own_discretization(scene, model);
    match adaptive_grid(scene, model, &own) {
        Ok(own) => (own, note),
        Err(why) => (own, Some(note.map_or(why.clone(), |n| format!("{n}; {why}")))),
    }
}

/// The discretization the scene asks for, with the natural initial-velocity condition in
/// place of the default strong one when the scene names none and its motion starts with
/// a fast layer the grid does not resolve ([`initial_layer`]); the note that says so.
fn own_discretization(scene: &Scene, model: &Model) -> (Discretization, Option<String>) {
    let mut own = Discretization::of(scene);
    if scene.initial_velocity_named || own.initial_velocity == InitialVelocity::Natural {
        return (own, None);
    }
    let Some(layer) = initial_layer(scene, model, own.spacing(scene)) else { return (own, None) };
    own.initial_velocity = InitialVelocity::Natural;
    let note = format!(
        "the initial velocity is imposed by the natural condition (as --initial-velocity natural): the motion starts with {layer}, \
         which a strong condition would carry into the first node (--initial-velocity strong keeps it)"
    );
    (own, Some(note))
}

/// `own` on the grid that follows the motion when the scene asks for it
/// (`grid = "adaptive"`, [`adapt::motion_map`]); or why it stays uniform.
fn adaptive_grid(scene: &Scene, model: &Model, own: &Discretization) -> Result<Discretization, String> {
    if scene.grid != GridChoice::Adaptive {
        return Ok(own.clone());
    }
    let (map, _) = adapt::motion_map(scene, model).map_err(|e| format!("the grid is uniform: {e}"))?;
    Ok(own.with_grid(Grid::Mapped(Arc::new(map))))
}
