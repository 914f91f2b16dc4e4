//! The solver's settings of a scene (`[solver]`) and its verification settings
//! (`[verify]`), with the command line's overrides.

use std::path::PathBuf;

use indexmap::IndexMap;
use toml::Spanned;

use super::error::{quoted_excerpt, readable_number, SceneError};
use super::file::{IpoptValue, SceneFile};
use super::overrides::Overrides;
use super::resolved::{SolverSettings, VerifySettings};
#[cfg(not(feature = "ipopt"))]
use super::settings::Backend;
use super::settings::{Formulation, HessianMode};
use super::time::MAX_NODES;

/// The largest `max_iter` (Ipopt's `int`).
pub const MAX_ITER: u32 = i32::MAX as u32;

/// The longest part of a `log_file` path, in bytes: the staged log's name adds a prefix
/// of about 40 bytes, and a file name may have 255.
pub const MAX_LOG_NAME_BYTES: usize = 200;

impl SceneFile {
    /// `[solver]` with the command line's overrides: a positive tolerance, an exact
    /// Hessian only for the reduced formulation, Ipopt's range of print levels.
    pub(super) fn resolve_solver(&self, ov: &Overrides, formulation: Formulation) -> Result<SolverSettings, SceneError> {
        let s = &self.solver;
        let tol = s.tol.as_ref().map_or(1e-11, |t| *t.get_ref());
        if !(tol > 0.0 && tol.is_finite()) {
            let t = s.tol.as_ref().expect("the default is positive");
            return Err(self.invalid(t, format!("solver.tol must be a positive number, got {}", readable_number(tol))));
        }
        let hessian = ov.hessian.or(s.hessian.as_ref().map(|h| *h.get_ref())).unwrap_or_default();
        if hessian == HessianMode::Exact && formulation == Formulation::Full {
            let message = "solver.hessian = \"exact\" is available for the reduced formulation only \
                 (the full formulation's Lagrangian Hessian would need fourth derivatives of L; \
                 for a square system Ipopt's step does not depend on it)";
            return Err(match (&s.hessian, ov.hessian) {
                (Some(h), None) => self.invalid(h, message),
                _ => self.toml_error(format!("{message} (the exact Hessian or the full formulation was asked for on the command line)")),
            });
        }
        let print_level = s.print_level.as_ref().map_or(0, |p| *p.get_ref());
        if !(0..=12).contains(&print_level) {
            let p = s.print_level.as_ref().expect("the default is in range");
            return Err(self.invalid(p, format!("solver.print_level must be 0 (silent) … 12 (Ipopt's range), got {print_level}")));
        }
        let backend = ov.backend.or(s.backend).unwrap_or_default();
        #[cfg(not(feature = "ipopt"))]
        if backend == Backend::Ipopt {
            return Err(self.toml_error(
                "backend = \"ipopt\": this build of skg-solve has no Ipopt (it was built without the `ipopt` feature); use \
                 backend = \"newton\""
                    .to_string(),
            ));
        }
        Ok(SolverSettings {
            backend,
            tol,
            max_iter: self.resolve_max_iter(ov)?,
            print_level,
            linear_solver: s.linear_solver.as_ref().map(|l| l.get_ref().clone()),
            hessian,
            log_file: s.log_file.as_ref().map(|l| self.confined_log_file(l)).transpose()?,
            ipopt_log: None,
            ipopt: self.pass_through_options()?,
            fallback: !ov.no_fallback && s.fallback.unwrap_or(true),
            time_limit: self.resolve_time_limit(ov)?,
        })
    }

    /// `[solver] log_file` as a path relative to the output directory, refused unless it
    /// stays inside it: a scene file is shared and downloaded, and must not be able to
    /// write anywhere else. Only plain names are allowed (no `..`, no root, no `.`, no
    /// empty part), none of them hidden (the directory's lock and temporary files start
    /// with a dot) or longer than [`MAX_LOG_NAME_BYTES`] (the staged log adds a prefix
    /// to the name, and a file name may have 255 bytes).
    fn confined_log_file(&self, name: &Spanned<String>) -> Result<PathBuf, SceneError> {
        let text = name.get_ref();
        let plain = |part: &str| !part.is_empty() && part != "." && !part.starts_with('.') && part.len() <= MAX_LOG_NAME_BYTES;
        if !text.split('/').all(plain) || text.chars().any(char::is_control) {
            return Err(self.invalid(
                name,
                format!(
                    "solver.log_file must be a file name inside the output directory (like \"ipopt.log\" or \"logs/ipopt.log\": \
                     no absolute path, no `..` or `.`, no empty part, no name starting with a dot or longer than \
                     {MAX_LOG_NAME_BYTES} bytes, no control character), got {}",
                    quoted_excerpt(text)
                ),
            ));
        }
        Ok(PathBuf::from(text))
    }

    /// `[solver] max_iter` or `--max-iter` (default 100), at most [`MAX_ITER`]: both
    /// backends count iterations in Ipopt's range (a C `int`).
    fn resolve_max_iter(&self, ov: &Overrides) -> Result<u32, SceneError> {
        let message = |n: u32| format!("must be a whole number from 0 to {MAX_ITER} (Ipopt's range), got {n}");
        match (ov.max_iter, &self.solver.max_iter) {
            (Some(n), _) if n > MAX_ITER => Err(SceneError::Setting { setting: format!("--max-iter {n}"), message: message(n) }),
            (Some(n), _) => Ok(n),
            (None, Some(n)) if *n.get_ref() > MAX_ITER => Err(self.invalid(n, format!("solver.max_iter {}", message(*n.get_ref())))),
            (None, Some(n)) => Ok(*n.get_ref()),
            (None, None) => Ok(100),
        }
    }

    /// `[solver.ipopt]`, passed to Ipopt verbatim once checked: no option that names a
    /// file (Ipopt would open it wherever it points: `output_file` truncates it,
    /// `option_file_name` reads it; the log has `[solver] log_file`), and no non-finite
    /// number.
    fn pass_through_options(&self) -> Result<IndexMap<String, IpoptValue>, SceneError> {
        let mut options = IndexMap::new();
        for (key, value) in &self.solver.ipopt {
            if names_a_file(key) {
                return Err(self.invalid(
                    value,
                    format!(
                        "[solver.ipopt] {key} names a file, which a scene may not (Ipopt would open it wherever it points); \
                         Ipopt's log goes to [solver] log_file, inside the output directory"
                    ),
                ));
            }
            if let IpoptValue::Num(x) = value.get_ref() {
                if !x.is_finite() {
                    return Err(self.invalid(value, format!("[solver.ipopt] {key} must be a finite number, got {x}")));
                }
            }
            options.insert(key.clone(), value.get_ref().clone());
        }
        Ok(options)
    }

    /// `[verify] tol` with the command line's overrides.
    pub(super) fn resolve_verify(&self, ov: &Overrides, params: &IndexMap<String, f64>) -> Result<VerifySettings, SceneError> {
        let tol = match (ov.verify_tol, &self.verify.tol) {
            (Some(t), _) => Some(t),
            (None, Some(v)) => Some(self.eval_value(v, "verify.tol", params)?),
            (None, None) => None,
        };
        if let Some(t) = tol {
            if t.is_nan() || t <= 0.0 {
                let message = format!("the verification tolerance must be a positive number, got {}", readable_number(t));
                return Err(match (&self.verify.tol, ov.verify_tol) {
                    (Some(v), None) => self.invalid(v, message),
                    _ => SceneError::Setting { setting: format!("--verify-tol {}", readable_number(t)), message },
                });
            }
        }
        let max_nodes = match (ov.max_nodes, &self.verify.max_nodes) {
            (Some(n), _) => Some(n),
            (None, Some(n)) => {
                let value = *n.get_ref();
                if value < 2 || value > MAX_NODES as i64 {
                    return Err(self.invalid(n, format!("verify.max_nodes must be an integer from 2 to {MAX_NODES}, got {value}")));
                }
                Some(value as usize)
            }
            (None, None) => None,
        };
        // The refinement solves until the verification passes: without the verification
        // there is nothing to refine to. Both asked for at once is refused; a scene's
        // `refine = true` under `--no-verify` is off.
        if ov.refine && ov.no_verify {
            return Err(SceneError::Setting {
                setting: "--refine with --no-verify".into(),
                message: "the refinement solves until the verification passes, so it needs the verification: leave out one of them".into(),
            });
        }
        let refine = ov.refine || (!ov.no_verify && self.verify.refine.unwrap_or(false));
        let stepper = ov.stepper.or(self.verify.stepper).unwrap_or_default();
        Ok(VerifySettings { enabled: !ov.no_verify, tol, refine, max_nodes, stepper })
    }

    /// `[solver] time_limit` or `--time-limit`: a positive number of seconds.
    fn resolve_time_limit(&self, ov: &Overrides) -> Result<Option<f64>, SceneError> {
        let limit = match (ov.time_limit, &self.solver.time_limit) {
            (Some(t), _) => t,
            (None, Some(t)) => {
                let value = *t.get_ref();
                if !(value > 0.0 && value.is_finite()) {
                    return Err(self.invalid(t, format!("solver.time_limit must be a positive number of seconds, got {value}")));
                }
                value
            }
            (None, None) => return Ok(None),
        };
        if !(limit > 0.0 && limit.is_finite()) {
            return Err(SceneError::Setting {
                setting: format!("--time-limit {limit}"),
                message: "must be a positive number of seconds".into(),
            });
        }
        Ok(Some(limit))
    }
}

/// Whether an Ipopt option names a file: `output_file`, `option_file_name`, and any
/// option of another Ipopt version whose name says it does (`…_file`, `…file_name`, a
/// library path `…lib` like 3.14's `hsllib`). `file_print_level` names a level.
fn names_a_file(option: &str) -> bool {
    let option = option.to_ascii_lowercase();
    option.ends_with("_file") || option.ends_with("file_name") || option.ends_with("lib")
}
