//! One module per subcommand: its arguments (a clap `Args` struct) and its `run`
//! function. `main.rs` only parses the command line and dispatches here.
//!
//! Exit codes, the same for every subcommand: 0 success, 1 an error in the input or
//! while reading or writing files, 2 a command-line usage error (clap), 3 a solve that
//! did not converge, 4 a tolerance exceeded (`check`).

// The doc comments of the clap arguments are the command line's help text, written for
// the terminal: `[default: …]`, `<scene>` and `[verify] tol` are not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

pub mod animate;
pub mod bench;
pub mod check;
pub mod fit;
pub mod gallery;
pub mod plot;
pub mod reference;
pub mod solve;
pub mod status;
pub mod sweep;
pub mod tune;

use std::path::Path;
use std::str::FromStr;

use anyhow::Result;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;

use skg_core::sbp::OperatorKind;
use skg_core::scene::{Backend, Formulation, GridChoice, HessianMode, InitialVelocity, Overrides, Scene, SceneFile, Stepper};

/// Exit code of a solve that ran but did not converge.
pub const EXIT_NOT_CONVERGED: u8 = 3;
/// Exit code of a solve that converged but did not verify, and of `check` when a
/// tolerance is exceeded.
pub const EXIT_NOT_VERIFIED: u8 = 4;
/// Exit code of `check` when a tolerance is exceeded (the same meaning as a solve that
/// fails verification).
pub const EXIT_TOLERANCE_EXCEEDED: u8 = EXIT_NOT_VERIFIED;

#[derive(Args, Clone)]
pub struct SceneArgs {
    /// Set a scene parameter, e.g. `--set sigma=1/200` (repeatable; value: number or expression).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Override the SBP operator: SBP121, SBP242 (alias SBP424), SBP363, SBP484, or one
    /// with artificial dissipation, SBP121-AD, SBP242-AD, SBP363-AD, SBP484-AD (damps the
    /// odd-even mode that damping or contraction amplifies; docs/mathematics.md §3); or
    /// `auto`: the one (with its initial-velocity condition, unless one is given)
    /// predicted to meet the verification's tolerance at the least cost.
    #[arg(long, value_name = "NAME")]
    pub operator: Option<OperatorArg>,
    /// Formulation: `reduced` (physical limit, half the unknowns; default) or `full`
    /// (the paper's doubled unknowns).
    #[arg(long, value_name = "KIND")]
    pub formulation: Option<Formulation>,
    /// How the initial velocity is imposed: `strong` (default; the first node's velocity
    /// `Dq` equals it) or `natural` (the initial momentum enters the action as a boundary
    /// term and the first node's equations are kept; more accurate on the higher-order
    /// operators, see docs/mathematics.md §5).
    #[arg(long, value_name = "KIND")]
    pub initial_velocity: Option<InitialVelocity>,
    /// Where the nodes are: `uniform` (default), `adaptive` (along a map made from a time
    /// stepping of the scene: dense in contacts, jumps and initial layers, so that a
    /// brief fast motion does not need fine nodes over the whole span; docs/grids.md) or
    /// `auto` (chosen with the operator by predicted cost, the default with `--operator
    /// auto` or `--refine`). Overrides `[discretization] grid`.
    #[arg(long, value_name = "KIND", value_parser = by_name::<GridChoice>(GridChoice::ALL.map(GridChoice::name)))]
    pub grid: Option<GridChoice>,
    /// Hessian given to Ipopt: `zero` (default; the Newton step of a square system does
    /// not depend on it) or `exact` (reduced formulation only).
    #[arg(long, value_name = "MODE", value_parser = by_name::<HessianMode>(HessianMode::ALL.map(HessianMode::name)))]
    pub hessian: Option<HessianMode>,
    /// Maximum number of iterations (Ipopt's, or Newton's), at most 2147483647.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(0..=i32::MAX as i64))]
    pub max_iter: Option<u32>,
    /// Solver of the square system: `ipopt` (default; Ipopt with MUMPS) or `newton`
    /// (Newton's method with a sparse LU of the Jacobian and a line search on the
    /// residual; hands over to Ipopt if it fails). Overrides `[solver] backend`.
    #[arg(long, value_name = "NAME")]
    pub backend: Option<Backend>,
    /// Solve in successive windows of SECONDS (each starts from the state the previous one
    /// reached and discards its last --overlap); bounds the odd-even mode that damping
    /// amplifies (an -AD operator damps it) and makes long spans linear in cost. 0 turns
    /// the scene's windows off.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = non_negative)]
    pub window: Option<f64>,
    /// Seconds discarded at the end of each window [default: a quarter of the window].
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = non_negative)]
    pub overlap: Option<f64>,
    /// Verification tolerance: max |q − q_reference| allowed, in coordinate units
    /// [default: the scene's [verify] tol, else 1e-4 × each coordinate's range, at least
    /// 1e-7 × the largest one].
    #[arg(long, value_name = "TOL", allow_negative_numbers = true, value_parser = positive)]
    pub verify_tol: Option<f64>,
    /// Time stepping of the verification, the initial guess and the refinement's
    /// predictions: `auto` (default: DOP853, and Radau IIA from where the scene turns out
    /// stiff), `dop853` (explicit only) or `implicit` (Radau IIA throughout).
    /// Overrides `[verify] stepper`.
    #[arg(long, value_name = "NAME", value_parser = stepper_parser())]
    pub stepper: Option<Stepper>,
    /// Skip the comparison with time stepping (the result is still checked for
    /// non-finite numbers and a positive-definite kinetic matrix); a converged solve
    /// then exits 0 unless one of those checks fails. A scene's `[verify] refine` is
    /// then off, and --refine with it is refused (the refinement needs the verification).
    #[arg(long)]
    pub no_verify: bool,
    /// Report the scene's own solve even if it fails, without trying the fallback ladder
    /// (coarse-to-fine guess, wall-width continuation, windows).
    #[arg(long)]
    pub no_fallback: bool,
}

/// `--operator`: an operator's name, or `auto`.
#[derive(Clone, Copy, Debug)]
pub enum OperatorArg {
    /// Chosen by predicted cost.
    Auto,
    /// This operator.
    Named(OperatorKind),
}

impl FromStr for OperatorArg {
    type Err = skg_core::sbp::ParseOperatorKindError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(OperatorArg::Auto);
        }
        s.parse().map(OperatorArg::Named)
    }
}

impl SceneArgs {
    /// The overrides these options describe, with an optional node count.
    pub fn overrides(&self, nodes: Option<usize>) -> Result<Overrides> {
        let set = self.set.iter().map(|s| Overrides::parse_assignment(s)).collect::<Result<Vec<_>, _>>()?;
        Ok(Overrides {
            set,
            nodes,
            operator: match self.operator {
                Some(OperatorArg::Named(k)) => Some(k),
                _ => None,
            },
            auto_operator: matches!(self.operator, Some(OperatorArg::Auto)),
            formulation: self.formulation,
            initial_velocity: self.initial_velocity,
            grid: self.grid,
            hessian: self.hessian,
            max_iter: self.max_iter,
            backend: self.backend,
            window: self.window,
            overlap: self.overlap,
            verify_tol: self.verify_tol,
            stepper: self.stepper,
            no_verify: self.no_verify,
            no_fallback: self.no_fallback,
            ..Overrides::default()
        })
    }
}

/// Load a scene file and resolve it with the overrides.
pub fn load(path: &Path, ov: &Overrides) -> Result<Scene> {
    Ok(SceneFile::load(path)?.resolve(ov)?)
}

/// A command-line usage error found after parsing, by a command (options that do not fit
/// together, a count beyond its bound): exit status 2, as clap's own usage errors.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// A command-line value that clap refuses (a usage error, exit status 2); clap prints
/// it after the option's name and value.
#[derive(Debug, thiserror::Error)]
pub enum ArgError {
    /// Not a number at all.
    #[error("`{text}` is not a number: {error}")]
    NotANumber {
        /// The value as given.
        text: String,
        /// The parser's error (printed in this message, so not a `source`).
        error: std::num::ParseFloatError,
    },
    /// A number that must be finite and positive.
    #[error("must be a positive number, got {0}")]
    NotPositive(String),
    /// A number that must be finite and not negative.
    #[error("must be a number ≥ 0, got {0}")]
    Negative(String),
    /// A picture size that is not `WIDTHxHEIGHT` within 64…4096.
    #[error("bad size `{0}`: expected WIDTHxHEIGHT, e.g. 640x480, each 64…4096")]
    Size(String),
}

/// The value parser of a setting that skg-core names (`--hessian`, `--stepper`): one of `names` (the
/// core's, listed as the possible values in `--help` and in clap's message for any other
/// value), read by the core's `FromStr`, so that the command line and a scene file accept
/// the same words.
fn by_name<T>(names: impl IntoIterator<Item = &'static str>) -> impl TypedValueParser<Value = T>
where
    T: FromStr + Clone + Send + Sync + 'static,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    PossibleValuesParser::new(names).try_map(|name| name.parse::<T>())
}

/// The value parser of `--stepper`: `auto`, `dop853` or `implicit`.
pub(crate) fn stepper_parser() -> impl TypedValueParser<Value = Stepper> {
    by_name::<Stepper>(Stepper::ALL.map(Stepper::name))
}

/// A command-line number that must be finite and positive (a usage error otherwise).
pub(crate) fn positive(text: &str) -> Result<f64, ArgError> {
    let x = number(text)?;
    (x > 0.0 && x.is_finite()).then_some(x).ok_or_else(|| ArgError::NotPositive(text.to_string()))
}

/// A command-line number that must be finite and not negative (a usage error otherwise).
fn non_negative(text: &str) -> Result<f64, ArgError> {
    let x = number(text)?;
    (x >= 0.0 && x.is_finite()).then_some(x).ok_or_else(|| ArgError::Negative(text.to_string()))
}

/// A command-line number, or clap's message for a value that is not one.
fn number(text: &str) -> Result<f64, ArgError> {
    text.parse().map_err(|error| ArgError::NotANumber { text: text.to_string(), error })
}
