//! The discretization on the time grid: the SBP-discretized action of a model, the
//! trajectory at the nodes, and contact at the nodes.
//!
//! * [`discretization`]: what a solve chooses about the discretization of a scene's model
//!   (operator, nodes, initial-velocity condition; [`Discretization`]).
//! * [`grid`]: where the nodes are — uniformly, or along a map that follows the motion,
//!   made from the steps of a time stepping ([`Grid`], [`TimeMap`]).
//! * [`action`]: the discrete action on the grid — the layout of the unknowns, the node
//!   times, the boundary terms, the residual and the sparsity plans of its Jacobian and
//!   Hessian ([`Action`]).
//! * [`trajectory`]: the states at the nodes with their physical columns, the common
//!   result type of a solve and a reference, and the CSV layout of a trajectory
//!   ([`Trajectory`]).
//! * [`interpolate`]: a trajectory between its nodes — cubic Hermite interpolation of
//!   the coordinates with their velocities as slopes, linear interpolation of any node
//!   series.
//! * [`parameters`]: the action's derivatives in the free parameters of a fit's model —
//!   the residual's Jacobian in them and the Hessian blocks they add
//!   ([`ParameterPlan`]).
//! * [`contact`]: when a node is in contact with a wall, contact episodes, and how
//!   finely the nodes of a trajectory resolve a wall's contacts. It sits here rather than
//!   with the model because it is about nodes: it measures trajectories.
//!
//! **Place in the flow.** After the model: it uses [`sbp`](crate::sbp),
//! [`scene`](crate::scene) and [`model`](crate::model), and nothing later. The time
//! stepping, the solve and the output take its trajectories; the solve assembles its
//! action.

pub mod action;
pub mod contact;
pub mod discretization;
pub mod grid;
pub mod interpolate;
pub mod parameters;
pub mod trajectory;

pub use action::Action;
pub use discretization::Discretization;
pub use grid::{Grid, TimeMap};
pub use parameters::ParameterPlan;
pub use trajectory::{trajectory_header, trajectory_rows, NodeSeries, States, Trajectory};
