//! A run over the scene's whole span in one global solve ([`solve_global`]); a [`Run`]
//! is what a global solve or a solve in windows ([`window`](super::window)) produced,
//! before its assessment ([`assess`](super::assess)).

use std::sync::Arc;
use std::time::Instant;

use super::assess::sizes;
use super::backend::SquareSolver;
use super::deadline::Deadline;
use super::error::SolveError;
use super::outcome::{Method, Sizes};
use super::piece::{action_on, solve_piece, Guess, Piece};
use crate::discrete::Discretization;
use crate::model::Model;
use crate::scene::Scene;

/// One attempt at the whole span: a global solve or a sequence of windows, on one
/// discretization of the scene's model.
#[derive(Debug, Clone)]
pub struct Run {
    /// How the span was covered.
    pub method: Method,
    /// The discretization solved.
    pub discretization: Discretization,
    /// The sizes of one piece's system.
    pub sizes: Sizes,
    /// The solution over the whole span. For windows, the pieces joined: converged only
    /// if every window converged (else the status of the first that did not),
    /// iterations, iteration tables and times one after the other, residuals maximized.
    pub solution: Piece,
}

/// Solve the scene's whole span with its model `model` and the discretization `disc` in
/// one piece from `guess`, its backend stopped at `deadline` (if any).
pub fn solve_global(
    scene: &Scene,
    model: &Arc<Model>,
    disc: &Discretization,
    guess: &Guess,
    deadline: Option<Deadline>,
) -> Result<Run, SolveError> {
    let t_setup = Instant::now();
    let times = disc.times(scene);
    let action = action_on(model, scene, disc, &times)?;
    let mut solver = SquareSolver::new(scene, &action);
    solver.set_deadline(deadline);
    let setup_s = t_setup.elapsed().as_secs_f64();
    let mut solution = solve_piece(scene, &action, &mut solver, &times, guess)?;
    solution.timings.setup_s = setup_s;
    Ok(Run { method: Method::Global, discretization: disc.clone(), sizes: sizes(scene, &action, &solver), solution })
}
