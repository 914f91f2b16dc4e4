//! How a fit is run: its free parameters, how it is handed to Ipopt, the Hessian, where the
//! trajectory starts, and Ipopt's tolerance and limits ([`FitSettings`]), with their
//! defaults and their names on the command line and in Python; and their checks against
//! the scene ([`check_settings`]).

use std::fmt;
use std::str::FromStr;

use serde::Serialize;

use super::free::FreeParameter;
use super::FitError;
use crate::scene::{Overrides, Scene};

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

/// The checks of the settings against the scene; the notes on what the fit does not
/// use of the scene.
pub(super) fn check_settings(scene: &Scene, overrides: &Overrides, settings: &FitSettings) -> Result<Vec<String>, FitError> {
    let mut notes = Vec::new();
    if settings.free.is_empty() {
        return Err(FitError::Settings("no free parameter: name the parameters to fit (--free, or free = [...] in [fit])".into()));
    }
    let known = || scene.parameters.keys().map(String::as_str).collect::<Vec<_>>().join(", ");
    for (j, p) in settings.free.iter().enumerate() {
        let Some(&value) = scene.parameters.get(&p.name) else {
            return Err(FitError::Settings(format!(
                "free parameter `{}` is not a parameter of the scene (its parameters: {}); to fit an initial position or \
                 velocity, write it as a parameter in the scene (velocity = \"v0\")",
                p.name,
                known()
            )));
        };
        if settings.free[..j].iter().any(|q| q.name == p.name) {
            return Err(FitError::Settings(format!("free parameter `{}` is named twice", p.name)));
        }
        if !p.admits(value) {
            return Err(FitError::Settings(format!(
                "the starting value of `{}` ({value}) is outside its bounds {}: start inside them (--set {}=…)",
                p.name,
                p.bounds_text(),
                p.name
            )));
        }
        if moves_the_grid(scene, overrides, &p.name, value) {
            return Err(FitError::Settings(format!(
                "`{}` sets the time span or the grid ([time]): a fit keeps the grid fixed, so it cannot be free",
                p.name
            )));
        }
    }
    if scene.grid == crate::scene::GridChoice::Adaptive {
        notes.push(
            "the adaptive grid's map follows the motion at the values the fit starts from; the fit keeps that grid while the \
             parameters move the motion"
                .into(),
        );
    }
    if scene.windows.is_some() {
        notes.push("the fit optimizes the whole span at once: the scene's [time] window is not used".into());
    }
    if scene.formulation == crate::scene::Formulation::Full {
        notes.push("the fit's constraints are the reduced system: the full formulation is not used".into());
    }
    if settings.method == FitMethod::Reduced {
        if settings.hessian == FitHessian::LimitedMemory {
            return Err(FitError::Settings(
                "the reduced fit gives Ipopt the exact Hessian of the misfit in the parameters: the limited-memory Hessian is \
                 for the all-at-once fit"
                    .into(),
            ));
        }
        if settings.start == FitStart::Data {
            return Err(FitError::Settings(
                "the reduced fit starts from the solve at the starting values (its trajectory solves the equations of motion \
                 at every point): starting from the data is for the all-at-once fit"
                    .into(),
            ));
        }
    }
    if settings.tol.is_nan() || settings.tol <= 0.0 || settings.max_iter == 0 {
        return Err(FitError::Settings(format!("the fit's tol ({}) and max_iter ({}) must be positive", settings.tol, settings.max_iter)));
    }
    Ok(notes)
}

/// Whether changing parameter `name` from `value` changes the scene's time span or grid.
fn moves_the_grid(scene: &Scene, overrides: &Overrides, name: &str, value: f64) -> bool {
    let other = if value == 0.0 { 1e-3 } else { value * (1.0 + 1e-3) };
    let mut ov = overrides.clone();
    ov.set.retain(|(n, _)| n != name);
    ov.set.push((name.to_string(), format!("{other:?}")));
    match scene.file.clone().resolve(&ov) {
        Ok(s) => (s.t_start, s.t_end, s.nodes) != (scene.t_start, scene.t_end, scene.nodes),
        Err(_) => false,
    }
}
