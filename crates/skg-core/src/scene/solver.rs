//! The solver's settings of a scene (`[solver]`) and its verification settings
//! (`[verify]`), with the command line's overrides.

use std::path::PathBuf;

use indexmap::IndexMap;

use super::error::SceneError;
use super::file::SceneFile;
use super::overrides::Overrides;
use super::resolved::{SolverSettings, VerifySettings};
use super::settings::{Formulation, HessianMode};

impl SceneFile {
    /// `[solver]` with the command line's overrides: a positive tolerance, an exact
    /// Hessian only for the reduced formulation, Ipopt's range of print levels.
    pub(super) fn resolve_solver(&self, ov: &Overrides, formulation: Formulation) -> Result<SolverSettings, SceneError> {
        let s = &self.solver;
        let tol = s.tol.as_ref().map_or(1e-11, |t| *t.get_ref());
        if !(tol > 0.0 && tol.is_finite()) {
            let t = s.tol.as_ref().expect("the default is positive");
            return Err(self.invalid(t, format!("solver.tol must be a positive number, got {tol}")));
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
        Ok(SolverSettings {
            backend: ov.backend.or(s.backend).unwrap_or_default(),
            tol,
            max_iter: ov.max_iter.or(s.max_iter).unwrap_or(100),
            print_level,
            linear_solver: s.linear_solver.as_ref().map(|l| l.get_ref().clone()),
            hessian,
            log_file: s.log_file.as_ref().map(PathBuf::from),
            ipopt: s.ipopt.iter().map(|(k, v)| (k.clone(), v.get_ref().clone())).collect(),
            fallback: !ov.no_fallback && s.fallback.unwrap_or(true),
        })
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
                let message = format!("the verification tolerance must be a positive number, got {t}");
                return Err(match (&self.verify.tol, ov.verify_tol) {
                    (Some(v), None) => self.invalid(v, message),
                    _ => SceneError::Setting { setting: format!("--verify-tol {t}"), message },
                });
            }
        }
        Ok(VerifySettings { enabled: !ov.no_verify, tol })
    }
}
