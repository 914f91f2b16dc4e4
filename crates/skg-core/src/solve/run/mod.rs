//! One run of one discretization (placeholder docs, rewritten below).

pub(crate) mod assess;
pub mod backend;
pub(crate) mod error;
pub(crate) mod global;
pub(crate) mod outcome;
pub(crate) mod piece;
pub(crate) mod status;
pub mod window;
