//! The solver's options as the caller gives them: [`Options`] (tolerances, iteration
//! limit, printing, the log file, the linear solver, scaling) and the verbatim extra
//! options ([`OptionValue`]). They are plain data; [`crate::handle`] applies them to an
//! Ipopt problem.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// A value of an Ipopt option, matching Ipopt's typed setters.
///
/// (De)serializes untagged: a string, an integer or a float.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OptionValue {
    /// String option (`AddIpoptStrOption`).
    Str(String),
    /// Integer option (`AddIpoptIntOption`).
    Int(i32),
    /// Floating-point option (`AddIpoptNumOption`).
    Num(f64),
}

/// Solver options. [`Default`] gives the values documented on each field.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Options {
    /// Ipopt `tol` (overall NLP error tolerance). Default 1e-11.
    pub tol: f64,
    /// Ipopt `constr_viol_tol` (absolute, unscaled constraint violation). Default 1e-11.
    pub constr_viol_tol: f64,
    /// Ipopt `max_iter`. Default 100.
    pub max_iter: u32,
    /// Ipopt `print_level` for the console (0..=12). Default 0, which also sets `sb yes`
    /// so nothing at all is printed.
    pub print_level: i32,
    /// Write Ipopt's log to this file (`OpenIpoptOutputFile`). Default none.
    pub output_file: Option<PathBuf>,
    /// Print level of [`Options::output_file`]. Default 5 (the usual iteration table).
    pub output_file_level: i32,
    /// Ipopt `linear_solver`, e.g. `"mumps"` (Debian's build has only MUMPS).
    /// Default none = Ipopt's default.
    pub linear_solver: Option<String>,
    /// `false` (default) sets `nlp_scaling_method none`; `true` keeps Ipopt's
    /// gradient-based scaling.
    pub scaling: bool,
    /// Further options passed through verbatim, after all of the above (so they can
    /// override them, e.g. `("check_derivatives_for_naninf", Str("no"))`).
    pub extra: Vec<(String, OptionValue)>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            constr_viol_tol: 1e-11,
            max_iter: 100,
            print_level: 0,
            output_file: None,
            output_file_level: 5,
            linear_solver: None,
            scaling: false,
            extra: Vec::new(),
        }
    }
}
