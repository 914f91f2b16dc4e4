//! [`Overrides`]: what the command line, a sweep point or the Python API sets on top of
//! a scene file.

use serde::Serialize;

use super::error::SceneError;
use super::settings::{Backend, Formulation, GridChoice, HessianMode, InitialVelocity, Stepper};
use crate::sbp::OperatorKind;

/// Command-line and sweep overrides applied on top of a scene file.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Overrides {
    /// `name=value` parameter assignments (value: number or expression).
    pub set: Vec<(String, String)>,
    /// Number of nodes N.
    pub nodes: Option<usize>,
    /// SBP operator.
    pub operator: Option<OperatorKind>,
    /// Choose the operator (and the initial-velocity condition, unless one is given) by
    /// predicted cost (`--operator auto`).
    pub auto_operator: bool,
    /// Formulation.
    pub formulation: Option<Formulation>,
    /// How the initial velocity is imposed.
    pub initial_velocity: Option<InitialVelocity>,
    /// Where the nodes are (`--grid`).
    pub grid: Option<GridChoice>,
    /// Hessian given to Ipopt.
    pub hessian: Option<HessianMode>,
    /// The iteration limit (Ipopt's, and Newton's).
    pub max_iter: Option<u32>,
    /// The solver of the square system.
    pub backend: Option<Backend>,
    /// Window length in seconds (`--window`; 0 turns windows off).
    pub window: Option<f64>,
    /// Window overlap in seconds (`--overlap`).
    pub overlap: Option<f64>,
    /// Verification tolerance (`--verify-tol`).
    pub verify_tol: Option<f64>,
    /// Skip verification (`--no-verify`).
    pub no_verify: bool,
    /// Do not try the fallback ladder (`--no-fallback`).
    pub no_fallback: bool,
    /// Refine the grid until the verification passes (`--refine`).
    pub refine: bool,
    /// The largest grid refinement may use (`--max-nodes`).
    pub max_nodes: Option<usize>,
    /// Seconds the whole solve may take (`--time-limit`).
    pub time_limit: Option<f64>,
    /// The time stepper of the verification, guess and predictions (`--stepper`).
    pub stepper: Option<Stepper>,
}

impl Overrides {
    /// Parse one `name=value` assignment of `--set`.
    pub fn parse_assignment(s: &str) -> Result<(String, String), SceneError> {
        let bad = |m: &str| SceneError::Override { assignment: s.to_string(), message: m.to_string() };
        let (name, value) = s.split_once('=').ok_or_else(|| bad("expected name=value"))?;
        let name = name.trim();
        if name.is_empty() || value.trim().is_empty() {
            return Err(bad("expected name=value"));
        }
        Ok((name.to_string(), value.trim().to_string()))
    }
}
