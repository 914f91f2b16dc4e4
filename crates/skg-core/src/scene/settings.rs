//! The settings a scene file (or the command line) chooses by name: the formulation,
//! the initial velocity condition, the Hessian given to Ipopt, the backend and the time
//! stepper. Each
//! parses case-insensitively from its name, in a scene file as on the command line and
//! in a sweep's grid (`backend = "Newton"` is `newton` everywhere), and displays as it.

use std::fmt;

use serde::{Deserialize, Serialize};

/// Deserialize a setting from its name with its `FromStr` (case-insensitive), so that a
/// scene file accepts what the command line and a sweep's grid accept.
macro_rules! deserialize_by_name {
    ($($t:ty),*) => {$(
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let name = String::deserialize(deserializer)?;
                name.parse().map_err(serde::de::Error::custom)
            }
        }
    )*};
}

deserialize_by_name!(Formulation, InitialVelocity, HessianMode, Backend, Stepper, GridChoice);

/// How the discrete action is posed to Ipopt (docs/mathematics.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Formulation {
    /// Only the equations ∂S/∂(q-, λ-) = 0 in the unknowns (q+, λ+): half the size.
    #[default]
    Reduced,
    /// The paper's formulation: all doubled unknowns, the square system ∇S = 0.
    Full,
}

/// Error of parsing a [`Formulation`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown formulation `{input}` (expected `reduced` or `full`)")]
pub struct ParseFormulationError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Formulation {
    type Err = ParseFormulationError;

    /// Case-insensitive: `reduced` or `full`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "reduced" => Ok(Formulation::Reduced),
            "full" => Ok(Formulation::Full),
            _ => Err(ParseFormulationError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for Formulation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Formulation::Reduced => "reduced",
            Formulation::Full => "full",
        })
    }
}

/// How the initial velocity enters the discrete action (docs/mathematics.md §5). The
/// initial position is imposed the same way by both (`q+[1] = q_i`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum InitialVelocity {
    /// `(D q+)[1] = q̇_i` through a multiplier, with `q-[1] = 0`: the velocity of the
    /// first node is the initial velocity exactly (the condition set the paper's figures
    /// and the independent implementation use).
    #[default]
    Strong,
    /// The initial momentum `p_i = ∂L/∂q̇(q_i, q̇_i, t_i)` enters the action as the
    /// boundary term `p_i·q-[1]`, and `q-[1]` is free: its row makes the discrete momentum
    /// at the first node equal `p_i` up to the first node's weighted equation of motion
    /// (the action's natural boundary condition; an SBP-SAT term). The first node's
    /// equation of motion and constraints are then imposed too. More accurate for the
    /// higher-order operators (the rolling disk on SBP484: 9× at N = 256).
    Natural,
}

/// Error of parsing an [`InitialVelocity`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown initial velocity condition `{input}` (expected `strong` or `natural`)")]
pub struct ParseInitialVelocityError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for InitialVelocity {
    type Err = ParseInitialVelocityError;

    /// Case-insensitive: `strong` or `natural`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "strong" => Ok(InitialVelocity::Strong),
            "natural" => Ok(InitialVelocity::Natural),
            _ => Err(ParseInitialVelocityError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for InitialVelocity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InitialVelocity::Strong => "strong",
            InitialVelocity::Natural => "natural",
        })
    }
}

/// Where a solve puts its nodes (`[discretization] grid`, `--grid`;
/// docs/scene-file.md#discretization).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum GridChoice {
    /// Equally spaced nodes.
    #[default]
    Uniform,
    /// Nodes along a map that follows the motion, made from the steps of a time stepping
    /// of the scene (dense in contacts, jumps and layers).
    Adaptive,
    /// Chosen with the operator, by predicted cost: the uniform grid or the adaptive one.
    Auto,
}

/// Error of parsing a [`GridChoice`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown grid `{input}` (expected `uniform`, `adaptive` or `auto`)")]
pub struct ParseGridChoiceError {
    /// The rejected input.
    pub input: String,
}

impl GridChoice {
    /// Every choice, in the order `--help` lists them.
    pub const ALL: [GridChoice; 3] = [GridChoice::Uniform, GridChoice::Adaptive, GridChoice::Auto];

    /// The name a scene file and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            GridChoice::Uniform => "uniform",
            GridChoice::Adaptive => "adaptive",
            GridChoice::Auto => "auto",
        }
    }
}

impl std::str::FromStr for GridChoice {
    type Err = ParseGridChoiceError;

    /// Case-insensitive: `uniform`, `adaptive` or `auto`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "uniform" => Ok(GridChoice::Uniform),
            "adaptive" => Ok(GridChoice::Adaptive),
            "auto" => Ok(GridChoice::Auto),
            _ => Err(ParseGridChoiceError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for GridChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What Ipopt is given as the Hessian of its Lagrangian. For the square systems
/// solved here the Newton step does not depend on it (docs/mathematics.md, docs/solver.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum HessianMode {
    /// No Hessian entries (nele_hess = 0): the step is the plain Newton step.
    #[default]
    Zero,
    /// The exact Hessian (reduced formulation only: it is the (q+,λ+) block of ∇²S
    /// evaluated with the minus variables set to Ipopt's multipliers).
    Exact,
}

/// Error of parsing a [`HessianMode`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown hessian `{input}` (expected `zero` or `exact`)")]
pub struct ParseHessianModeError {
    /// The rejected input.
    pub input: String,
}

impl HessianMode {
    /// Every mode, in the order the command line's help lists them.
    pub const ALL: [HessianMode; 2] = [HessianMode::Zero, HessianMode::Exact];

    /// The mode's name in a scene file and on the command line: `zero` or `exact`.
    pub fn name(self) -> &'static str {
        match self {
            HessianMode::Zero => "zero",
            HessianMode::Exact => "exact",
        }
    }
}

impl std::str::FromStr for HessianMode {
    type Err = ParseHessianModeError;

    /// Case-insensitive: `zero` or `exact`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        HessianMode::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| ParseHessianModeError { input: s.to_string() })
    }
}

impl fmt::Display for HessianMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which solver finds the root of the square system (docs/solver.md#choosing-the-backend).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Ipopt with MUMPS on the KKT system (the default, in a build with Ipopt).
    #[cfg_attr(feature = "ipopt", default)]
    Ipopt,
    /// Newton's method with a sparse LU of the square Jacobian and a line search on the
    /// residual norm; hands over to Ipopt when it fails (the default in a build without
    /// Ipopt).
    #[cfg_attr(not(feature = "ipopt"), default)]
    Newton,
}

/// Error of parsing a [`Backend`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown backend `{input}` (expected `ipopt` or `newton`)")]
pub struct ParseBackendError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Backend {
    type Err = ParseBackendError;

    /// Case-insensitive: `ipopt` or `newton`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "ipopt" => Ok(Backend::Ipopt),
            "newton" => Ok(Backend::Newton),
            _ => Err(ParseBackendError { input: s.to_string() }),
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Backend::Ipopt => "ipopt",
            Backend::Newton => "newton",
        })
    }
}

/// Which integrator steps the equations of motion in time: the verification, the
/// references, the initial guess and the refinement's predictions
/// (docs/trust.md#which-stepper-verifies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stepper {
    /// DOP853, explicit, of order 8: cheap where the step is limited by accuracy.
    Dop853,
    /// Radau IIA, implicit and L-stable, of order 5 ([`radau`](crate::stepping::radau)): where the
    /// step of an explicit method is limited by stability (stiff equations).
    Implicit,
    /// DOP853 until it finds the equation stiff (Hairer's test: `h·λ` above 6.1 in 15
    /// steps in a row), runs out of steps or its step underflows; then Radau IIA from
    /// where it stopped.
    #[default]
    Auto,
}

impl Stepper {
    /// Every stepper, in the order of its names.
    pub const ALL: [Stepper; 3] = [Stepper::Auto, Stepper::Dop853, Stepper::Implicit];

    /// The stepper's name: `auto`, `dop853` or `implicit`.
    pub fn name(self) -> &'static str {
        match self {
            Stepper::Auto => "auto",
            Stepper::Dop853 => "dop853",
            Stepper::Implicit => "implicit",
        }
    }
}

impl fmt::Display for Stepper {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of parsing a [`Stepper`] from a string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown stepper `{input}` (expected auto, dop853 or implicit)")]
pub struct ParseStepperError {
    /// The text that named no stepper.
    pub input: String,
}

impl std::str::FromStr for Stepper {
    type Err = ParseStepperError;

    /// Case-insensitive: `auto`, `dop853` or `implicit`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.to_ascii_lowercase();
        Stepper::ALL.into_iter().find(|k| k.name() == lower).ok_or_else(|| ParseStepperError { input: s.to_string() })
    }
}
