//! The choice of the discretization (placeholder docs).

pub mod cost;
pub mod predict;
pub mod refine;
