//! How a fit is run: its free parameters, how it is handed to Ipopt, the Hessian, where the
//! trajectory starts, and Ipopt's tolerance and limits ([`FitSettings`]), with their
//! defaults and their names on the command line and in Python.

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use super::free::FreeParameter;

/// The Hessian of the Lagrangian given to Ipopt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitHessian {
    /// Exact: second derivatives of the stationarity equations and of the misfit.
    #[default]
    Exact,
    /// Ipopt's limited-memory quasi-Newton approximation (`hessian_approximation =
    /// limited-memory`).
    LimitedMemory,
}

/// Where the fit's trajectory starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitStart {
    /// [`FitStart::Data`] for a scene without constraints or data that observe every
    /// coordinate, [`FitStart::Solve`] otherwise: the data put in place of some
    /// coordinates violate the constraints that tie them to the others, and Ipopt then
    /// starts far from feasibility (data of every coordinate satisfy the constraints up to
    /// their noise).
    #[default]
    Auto,
    /// The data themselves where they observe a coordinate (interpolated at the nodes
    /// between its first and last observation), the solve at the starting values
    /// elsewhere.
    Data,
    /// The solve at the starting values everywhere.
    Solve,
}

/// How the fit is handed to Ipopt (docs/fitting.md#two-ways-to-hand-the-fit-to-ipopt).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitMethod {
    /// The trajectory and the parameters at once, the equations of motion as Ipopt's
    /// constraints (`problem.rs`).
    #[default]
    AllAtOnce,
    /// The parameters alone, the trajectory solved from the equations of motion at every
    /// point Ipopt evaluates (`reduced.rs`): single shooting on the discrete equations.
    Reduced,
}

/// An unknown name of a fit's setting.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{given}` is not one of {expected}")]
pub struct ParseFitSettingError {
    given: String,
    expected: &'static str,
}

impl FitHessian {
    /// The setting's name.
    pub fn name(self) -> &'static str {
        match self {
            FitHessian::Exact => "exact",
            FitHessian::LimitedMemory => "limited-memory",
        }
    }
}

impl FromStr for FitHessian {
    type Err = ParseFitSettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "exact" => Ok(FitHessian::Exact),
            "limited-memory" => Ok(FitHessian::LimitedMemory),
            _ => Err(ParseFitSettingError { given: s.to_string(), expected: "exact, limited-memory" }),
        }
    }
}

impl fmt::Display for FitHessian {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FitMethod {
    /// The setting's name.
    pub fn name(self) -> &'static str {
        match self {
            FitMethod::AllAtOnce => "all-at-once",
            FitMethod::Reduced => "reduced",
        }
    }
}

impl FromStr for FitMethod {
    type Err = ParseFitSettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "all-at-once" => Ok(FitMethod::AllAtOnce),
            "reduced" => Ok(FitMethod::Reduced),
            _ => Err(ParseFitSettingError { given: s.to_string(), expected: "all-at-once, reduced" }),
        }
    }
}

impl fmt::Display for FitMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FitStart {
    /// The setting's name.
    pub fn name(self) -> &'static str {
        match self {
            FitStart::Auto => "auto",
            FitStart::Data => "data",
            FitStart::Solve => "solve",
        }
    }
}

impl FromStr for FitStart {
    type Err = ParseFitSettingError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(FitStart::Auto),
            "data" => Ok(FitStart::Data),
            "solve" => Ok(FitStart::Solve),
            _ => Err(ParseFitSettingError { given: s.to_string(), expected: "auto, data, solve" }),
        }
    }
}

impl fmt::Display for FitStart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The free parameters and their bounds, in the order of the report.
    pub free: Vec<FreeParameter>,
    /// How the fit is handed to Ipopt.
    pub method: FitMethod,
    /// The Hessian given to Ipopt.
    pub hessian: FitHessian,
    /// Where the trajectory starts.
    pub start: FitStart,
    /// Ipopt's `tol` (its scaled optimality error); the constraints are held to the
    /// scene's `[solver] tol` (Ipopt's `constr_viol_tol`).
    pub tol: f64,
    /// Ipopt's iteration limit.
    pub max_iter: u32,
}

/// Ipopt's `tol` for a fit unless the scene or the caller gives one (its default, 1e-8,
/// left the noise-free fits of the tests at 1e-7 of the parameters' values).
pub const DEFAULT_TOL: f64 = 1e-10;

/// Ipopt's `acceptable_iter` for a fit: the iterations at its acceptable level after
/// which it stops (its default is 15).
pub const ACCEPTABLE_ITER: i32 = 5;

/// MUMPS's pivot tolerance in an all-at-once fit whose equations of motion are
/// nonlinear in the trajectory (Ipopt's `mumps_pivtol`; its default is 1e-6) unless the
/// scene's `[solver.ipopt]` gives one.
pub const MUMPS_PIVTOL: f64 = 0.1;

/// MUMPS's pivot tolerance where the KKT matrix's trajectory block holds the misfit's
/// curvature alone: equations linear in the trajectory, or the limited-memory Hessian.
/// Its saddle point has a zero diagonal almost everywhere, and at 0.1 MUMPS delayed
/// pivots until its factor held a quarter of a dense matrix (two masses on springs,
/// 1003 unknowns: 3.6 s, against 0.65 s at 1e-4 and 1.3 s at 1e-6;
/// docs/benchmarks.md#the-reduced-fit).
pub const MUMPS_PIVTOL_LINEAR: f64 = 1e-4;

/// Ipopt's iteration limit for a fit unless the scene or the caller gives one.
pub const DEFAULT_MAX_ITER: u32 = 200;

impl FitSettings {
    /// The defaults for these free parameters: [`FitMethod::AllAtOnce`], exact Hessian,
    /// [`FitStart::Auto`], [`DEFAULT_TOL`], [`DEFAULT_MAX_ITER`].
    pub fn new(free: Vec<FreeParameter>) -> FitSettings {
        FitSettings {
            free,
            method: FitMethod::AllAtOnce,
            hessian: FitHessian::Exact,
            start: FitStart::Auto,
            tol: DEFAULT_TOL,
            max_iter: DEFAULT_MAX_ITER,
        }
    }

    /// The names of the free parameters.
    pub fn names(&self) -> Vec<String> {
        self.free.iter().map(|p| p.name.clone()).collect()
    }
}
