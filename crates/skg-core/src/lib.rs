//! skg-solve: the motion of mechanical systems with velocity constraints, walls and
//! friction from the critical point of the discretized Schwinger–Keldysh–Galley action.
//!
//! Data flows one way through the modules:
//! `scenario` (TOML) → `model` (symbolic expressions and exact derivatives, `expr`)
//! → `action` (SBP-discretized action on the time grid, `sbp`) → `ipopt` (the square
//! system ∇S = 0) → `solve` (driver, initial guess, post-processing) → `output`.
// Numerical kernels index several arrays by the same node/coordinate index; the
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod action;
pub mod check;
pub mod convergence;
pub mod model;
pub mod ode;
pub mod output;
pub mod provenance;
pub mod reference;
pub mod sbp;
pub mod scenario;
pub mod solve;
pub mod tune;

pub use skg_expr as expr;
pub use skg_ipopt as ipopt;
