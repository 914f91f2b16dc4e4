//! The linear algebra of the square system (placeholder docs).

pub mod band;
pub mod newton;
