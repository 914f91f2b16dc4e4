//! The scene: the TOML file a user writes, its validation and its resolution into
//! numbers.
//!
//! A scene file is read in two steps. [`SceneFile::parse`] (or [`SceneFile::load`], or
//! [`SceneFile::from_table`] for a scene built in code) deserializes the TOML (unknown
//! keys and type errors are reported with file, line and column by the `toml` crate,
//! through [`parse_toml`], which sweep files use too; with the field's name for a scene
//! built in code).
//! [`SceneFile::resolve`] then evaluates the parameters (numbers or expressions of other
//! parameters), applies the [`Overrides`] of the command line, a sweep point or Python,
//! and checks every number a solve depends on, giving a [`Scene`]. Expressions of the
//! model itself (Lagrangian, constraints, forces, walls) are parsed later, when the
//! model is built, through [`SceneFile::parse_expression`], which reports errors as
//! [`SceneError::Expression`] with the position in the file.
//!
//! The format is documented key by key in docs/scene-file.md.
//!
//! **What it holds**, one part per file:
//! * `file.rs`: [`SceneFile`], the TOML document, with one part per table
//!   ([`SceneMeta`], [`CoordinateSpec`], [`ConstraintSpec`], [`WallSpec`], [`TimeSpec`],
//!   [`DiscretizationSpec`], [`SolverSpec`], [`VerifySpec`], [`FitSpec`]);
//! * `location.rs`: [`Location`] and [`Origin`] (`file:line:column` of a value) and the
//!   reading of TOML ([`read_toml`], [`parse_toml`], [`TomlError`]); `error.rs`:
//!   [`SceneError`];
//! * `settings.rs`: the settings chosen by name ([`Formulation`], [`InitialVelocity`],
//!   [`HessianMode`], [`Backend`]); `overrides.rs`: [`Overrides`];
//! * `names.rs`: the names of the expressions ([`ExpressionNames`], [`TIME`],
//!   [`VELOCITY_SUFFIX`], [`RESERVED`]);
//! * the resolution into a [`Scene`] (`resolved.rs`): `resolve.rs` (names, initial
//!   state, constraints, forces, walls), `parameters.rs`, `time.rs` (span, operator,
//!   nodes, windows), `solver.rs` (solver and verification settings);
//! * [`emit`]: the TOML text of a scene built in code (Python's `skg.Scene`), one key
//!   per line with the key path of each, read by [`SceneFile::from_table`];
//! * [`provenance`]: the tool's version, the output's schema version and the content
//!   hash that every written file carries.
//!
//! **Place in the flow.** The scene is the first stage after the operators: it uses
//! only [`sbp`](crate::sbp) (the scene names its operator, [`OperatorKind`], and is
//! checked against the operator's minimum node count) and the expression language
//! (`skg-expr`). Everything after it takes a [`Scene`].
//!
//! [`OperatorKind`]: crate::sbp::OperatorKind

pub mod emit;
mod error;
mod file;
mod location;
mod names;
mod overrides;
mod parameters;
pub mod provenance;
mod resolve;
mod resolved;
mod settings;
mod solver;
mod time;

#[cfg(test)]
mod tests;

pub use error::{readable_number, rounded_number, SceneError};
pub use file::{
    ConstraintSpec, CoordinateSpec, DiscretizationSpec, FitSpec, IpoptValue, NumOrExpr, SceneFile, SceneMeta, SolverSpec, TimeSpec,
    VerifySpec, WallSpec,
};
pub use location::{parse_toml, read_toml, Location, Origin, TomlError};
pub use names::{ExpressionNames, InvalidName, RESERVED, TIME, VELOCITY_SUFFIX};
pub use overrides::Overrides;
pub use parameters::eval_constant;
pub use resolved::{Constraint, ConstraintKind, Scene, SolverSettings, VerifySettings, Wall, Windows};
pub use settings::{
    Backend, Formulation, GridChoice, HessianMode, InitialVelocity, ParseBackendError, ParseFormulationError, ParseGridChoiceError,
    ParseHessianModeError, ParseInitialVelocityError, ParseStepperError, Stepper,
};
pub use solver::{MAX_ITER, MAX_LOG_NAME_BYTES};
pub use time::{TimeResolutionError, MAX_NODES};
