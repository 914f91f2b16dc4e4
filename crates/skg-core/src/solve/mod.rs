//! The solve: the critical point of the discrete action, found by a backend, assessed,
//! and, when it fails, the fallback ladder.
//!
//! In the order in which its parts use each other (each only the ones before it):
//!
//! * [`newton`]: Newton's method for a square sparse system with a sparse LU;
//!   [`backend`]: the system of either formulation as an Ipopt [`Problem`], and
//!   [`SquareSolver`], the chosen backend with its sparsity plans and LU analysis kept
//!   between solves of equal structure.
//! * `error.rs`: [`SolveError`], [`WindowError`]; `status.rs`: [`SolveStatus`], how a
//!   solve ended; `outcome.rs`: [`Outcome`], what a solve produced, and [`Method`].
//! * `piece.rs`: one solve of one action's system from an initial guess
//!   ([`solve_piece`], [`Guess`], [`Piece`]) and the action of a scene ([`grid`],
//!   [`build_action`]).
//! * `run.rs`: a global run over the span ([`solve_global`], [`Run`]) and its
//!   assessment ([`outcome`]: verification, diagnostics, warnings).
//! * [`window`]: a run in windows of equal node count.
//! * [`ladder`]: the entry point, [`solve_scene`]: the scene's own run, then the
//!   fallback ladder until a run converges and verifies.
//!
//! **Place in the flow.** After time stepping: it uses [`scene`](crate::scene),
//! [`memory`](crate::memory), [`model`](crate::model), [`discrete`](crate::discrete) and
//! [`stepping`](crate::stepping) (the initial guess and the verification). The output
//! and the consumers (check, tune, the command line, Python) call [`solve_scene`];
//! nothing below the ladder calls up into it.
//!
//! [`Problem`]: skg_ipopt::Problem

pub mod choice;
pub mod ladder;
pub mod linalg;
pub mod run;

pub use choice::{cost, predict, refine};
pub use linalg::{band, newton};
pub use run::{backend, window};

pub use choice::refine::{solve_scene, solve_scene_with_progress};
pub use run::backend::SquareSolver;
pub use run::error::{SolveError, WindowError};
pub use run::global::{energy_drift_skip, outcome, sizes, solve_global, Run};
pub use run::outcome::{Attempt, Diagnostics, KineticLoss, Method, Outcome, RefinedGrid, Refinement, Settings, Sizes, Timings, Work};
pub use run::piece::{build_action, build_action_on, grid, solve_piece, Guess, Piece};
pub use run::status::{SolveStatus, CONVERGED_RESIDUAL};
