//! The choice of the discretization: with `--refine` and `--operator auto`, the
//! operator, initial-velocity condition and grid of least predicted cost that meet the
//! verification's tolerance, calibrated by each solve, until one verifies.
//!
//! * [`refine`]: the refinement (the candidates, the next grid, what each solve teaches).
//! * [`predict`]: the error of every candidate on any grid, predicted from the
//!   time-stepping reference: the discretization applied to the reference's own
//!   kinematics.
//! * [`cost`]: the measured time per node of each operator on each backend.
//! * `estimate`: what the refinement expects of a candidate — its calibrated prediction
//!   and its cost (the adaptive grid's with a penalty).
//! * [`adapt`]: the adaptive grid's map, made from the steps of a time stepping.
//!
//! **Place in the flow.** Above the [`ladder`](crate::solve::ladder), which solves each
//! grid it chooses; called by [`solve_scene`](crate::solve::solve_scene) alone.

pub mod adapt;
pub mod cost;
mod estimate;
pub mod predict;
pub mod refine;
