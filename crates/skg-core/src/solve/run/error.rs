//! The errors of the solve stage: [`SolveError`] (why a solve could not be attempted or
//! completed) and [`WindowError`] (why windows do not fit a scene's grid).

use super::backend::BackendError;
use crate::sbp::{OperatorKind, SbpError};
use crate::scene::{readable_number, SceneError};

/// Why a solve could not be attempted or completed (a non-converged run is not an
/// error: it is an [`Outcome`](crate::solve::Outcome) whose [`SolveStatus`](crate::solve::SolveStatus)
/// says so).
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The scene's model cannot be built (an expression, the initial state).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The SBP operator cannot be built on the scene's grid.
    #[error(transparent)]
    Sbp(#[from] SbpError),
    /// The backend could not be run (Ipopt's options, sizes, a callback error it did not
    /// recover from; Newton's structure).
    #[error(transparent)]
    Backend(#[from] BackendError),
    /// The prediction of the discretization error failed (its time-stepping reference
    /// could not be computed): the reason.
    #[error("the error of the discretizations cannot be predicted: {0}")]
    Prediction(String),
    /// The scene's windows do not fit its grid.
    #[error("{scene}: [time] window: {error}")]
    Windows {
        /// The scene file.
        scene: String,
        /// Why (said in the message, so not also its source).
        error: WindowError,
    },
}

/// Why windows of a given length and overlap do not fit a scene's grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WindowError {
    /// A window has fewer nodes than the operator needs.
    #[error(
        "a window of {} s has {nodes} nodes at the scene's spacing Δt = {} s; {operator} needs at least {min}",
        readable_number(*length),
        readable_number(*dt)
    )]
    TooFewNodes {
        /// The window's length, seconds.
        length: f64,
        /// Its nodes at the scene's spacing.
        nodes: usize,
        /// The scene's node spacing.
        dt: f64,
        /// The scene's operator.
        operator: OperatorKind,
        /// The operator's minimum of nodes.
        min: usize,
    },
    /// The overlap leaves no node of a window to keep.
    #[error("an overlap of {} s leaves nothing to keep of a {} s window", readable_number(*overlap), readable_number(*length))]
    NothingKept {
        /// The overlap, seconds.
        overlap: f64,
        /// The window's length, seconds.
        length: f64,
    },
}
