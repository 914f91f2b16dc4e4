//! The RAII handle of an Ipopt problem: it owns the process-wide lock
//! ([`crate::lock`]) and frees the problem under it when dropped; through it the
//! [`Options`] are applied to the problem, in a fixed order, by Ipopt's typed setters.

use std::ffi::CString;
use std::fmt;
use std::os::raw::c_char;
use std::path::Path;
use std::ptr::NonNull;
use std::sync::MutexGuard;

use crate::ffi::{self, Bool};
use crate::options::{OptionValue, Options};
use crate::solution::SolveError;
use crate::FALSE;

/// An `IpoptProblem` that owns the process-wide lock; freed (under the lock) on drop.
pub(crate) struct Handle {
    raw: NonNull<ffi::IpoptProblemInfo>,
    /// Dropped after `Drop::drop` has freed the problem.
    _lock: MutexGuard<'static, ()>,
}

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: `raw` came from a successful CreateIpoptProblem (the contract of
        // `Handle::new`), is freed exactly once (here), and the lock is still held because
        // fields drop after this body.
        unsafe { ffi::FreeIpoptProblem(self.raw.as_ptr()) };
    }
}

impl Handle {
    /// Takes ownership of a problem and of the lock it was created under.
    ///
    /// # Safety
    /// `raw` must be the result of a successful `CreateIpoptProblem` made while `lock`,
    /// the process-wide lock of [`crate::lock`], was held, and nothing else may free it.
    pub(crate) unsafe fn new(raw: NonNull<ffi::IpoptProblemInfo>, lock: MutexGuard<'static, ()>) -> Self {
        Handle { raw, _lock: lock }
    }

    pub(crate) fn raw(&self) -> ffi::IpoptProblem {
        self.raw.as_ptr()
    }

    fn c_name(name: &str, value: &dyn fmt::Display) -> Result<CString, SolveError> {
        CString::new(name).map_err(|_| Self::bad(name, value))
    }

    fn bad(name: &str, value: &dyn fmt::Display) -> SolveError {
        SolveError::BadOption { name: name.to_owned(), value: value.to_string() }
    }

    fn set_str(&self, name: &str, value: &str) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        let val = CString::new(value).map_err(|_| Self::bad(name, &value))?;
        // SAFETY: valid problem; both strings are NUL-terminated and outlive the call;
        // Ipopt only reads them (the C prototype lacks `const`) and copies them.
        let ok = unsafe { ffi::AddIpoptStrOption(self.raw(), key.as_ptr() as *mut c_char, val.as_ptr() as *mut c_char) };
        Self::check(ok, name, &format!("{value:?}"))
    }

    fn set_num(&self, name: &str, value: f64) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        // SAFETY: valid problem; NUL-terminated key that outlives the call, only read.
        let ok = unsafe { ffi::AddIpoptNumOption(self.raw(), key.as_ptr() as *mut c_char, value) };
        Self::check(ok, name, &value)
    }

    fn set_int(&self, name: &str, value: i32) -> Result<(), SolveError> {
        let key = Self::c_name(name, &value)?;
        // SAFETY: valid problem; NUL-terminated key that outlives the call, only read.
        let ok = unsafe { ffi::AddIpoptIntOption(self.raw(), key.as_ptr() as *mut c_char, value) };
        Self::check(ok, name, &value)
    }

    fn set(&self, name: &str, value: &OptionValue) -> Result<(), SolveError> {
        match value {
            OptionValue::Str(s) => self.set_str(name, s),
            OptionValue::Num(v) => self.set_num(name, *v),
            OptionValue::Int(v) => self.set_int(name, *v),
        }
    }

    fn check(ok: Bool, name: &str, value: &dyn fmt::Display) -> Result<(), SolveError> {
        if ok == FALSE {
            Err(Self::bad(name, value))
        } else {
            Ok(())
        }
    }

    fn open_output_file(&self, path: &Path, level: i32) -> Result<(), SolveError> {
        let bytes = path_bytes(path)?;
        let c_path =
            CString::new(bytes).map_err(|_| SolveError::Create(format!("output file path {} contains a NUL byte", path.display())))?;
        // SAFETY: valid problem; NUL-terminated path that outlives the call, only read.
        let ok = unsafe { ffi::OpenIpoptOutputFile(self.raw(), c_path.as_ptr() as *mut c_char, level) };
        if ok == FALSE {
            return Err(SolveError::Create(format!("cannot open Ipopt output file {} (print level {level})", path.display())));
        }
        Ok(())
    }

    /// Applies `options` in a fixed order; [`Options::extra`] last.
    pub(crate) fn apply(&self, options: &Options) -> Result<(), SolveError> {
        self.set_str("option_file_name", "")?;
        self.set_int("print_level", options.print_level)?;
        if options.print_level == 0 {
            self.set_str("sb", "yes")?;
        }
        self.set_num("tol", options.tol)?;
        self.set_num("constr_viol_tol", options.constr_viol_tol)?;
        let max_iter = i32::try_from(options.max_iter).map_err(|_| Self::bad("max_iter", &options.max_iter))?;
        self.set_int("max_iter", max_iter)?;
        if !options.scaling {
            self.set_str("nlp_scaling_method", "none")?;
        }
        self.set_str("check_derivatives_for_naninf", "yes")?;
        if let Some(solver) = &options.linear_solver {
            self.set_str("linear_solver", solver)?;
        }
        if let Some(path) = &options.output_file {
            self.open_output_file(path, options.output_file_level)?;
        }
        for (name, value) in &options.extra {
            self.set(name, value)?;
        }
        Ok(())
    }
}

#[cfg(unix)]
fn path_bytes(path: &Path) -> Result<Vec<u8>, SolveError> {
    use std::os::unix::ffi::OsStrExt;
    Ok(path.as_os_str().as_bytes().to_vec())
}

#[cfg(not(unix))]
fn path_bytes(path: &Path) -> Result<Vec<u8>, SolveError> {
    path.to_str()
        .map(|s| s.as_bytes().to_vec())
        .ok_or_else(|| SolveError::Create(format!("output file path {} is not UTF-8", path.display())))
}
