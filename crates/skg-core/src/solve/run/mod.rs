//! One run of one discretization of a scene's model: the square system handed to a
//! backend, the pieces it is solved in, and the assessment of what came out.
//!
//! In the order in which its parts use each other:
//!
//! * [`backend`]: the action's system in either formulation as a
//!   [`SquareSystem`](crate::solve::linalg::SquareSystem), and [`SquareSolver`](backend::SquareSolver):
//!   Ipopt or Newton with the sparsity plans and the LU analysis kept between solves of
//!   equal structure; the statuses and reports of the backends.
//! * [`deadline`]: the whole solve's time limit as the moment it ends, checked by the
//!   backends inside their iterations and by the ladder and the refinement between
//!   attempts.
//! * `status.rs`: [`SolveStatus`](crate::solve::SolveStatus), how a solve ended, judged
//!   on the unscaled residual; `error.rs`: [`SolveError`](crate::solve::SolveError),
//!   [`WindowError`](crate::solve::WindowError); `outcome.rs`:
//!   [`Outcome`](crate::solve::Outcome), what a solve produced, and its parts.
//! * `piece.rs`: one solve of one action's system from an initial guess (time stepping,
//!   or states from another solve), and the trajectory it gives.
//! * `global.rs`: a run over the whole span in one piece ([`Run`](crate::solve::Run));
//!   [`window`]: a run in windows of equal node count.
//! * `assess.rs`: a run's [`Outcome`](crate::solve::Outcome): verification against time
//!   stepping, diagnostics, warnings.
//!
//! **Place in the flow.** It uses [`linalg`](crate::solve::linalg) and the stages before
//! the solve; the ladder and the choice of the discretization use it.

pub(crate) mod assess;
pub mod backend;
pub mod deadline;
pub(crate) mod error;
pub(crate) mod global;
pub(crate) mod outcome;
pub(crate) mod piece;
pub(crate) mod status;
pub mod window;
