//! Sweeps: `plan_sweep` and `NativeSweepPlan` (a sweep planned and run as `skg-solve
//! sweep` does, its points in worker processes), `plan_shards` and `merge_shards` (the
//! sharded directory whose shards an executor runs, and their merge).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use skg_core::output;
use skg_sweep as sweep;

use crate::errors::{raise, sweep_err};

/// A sweep about to run: what [`plan_sweep`] found and what `run` needs.
#[pyclass(module = "skg._skg", frozen)]
pub(crate) struct NativeSweepPlan {
    file: sweep::SweepFile,
    plan: sweep::Plan,
    opts: sweep::SweepOptions,
}

#[pymethods]
impl NativeSweepPlan {
    /// The line `skg-solve sweep` prints before it starts.
    #[getter]
    fn text(&self) -> &str {
        &self.plan.text
    }

    /// Run (or resume) the sweep; returns the run's report as a dict.
    fn run<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = py.detach(|| sweep::run_sweep(&self.file, &self.plan.expanded, &self.opts)).map_err(|e| sweep_err(py, &e))?;
        let d = PyDict::new(py);
        d.set_item("name", self.file.name())?;
        d.set_item("total", r.total)?;
        d.set_item("in_shard", r.in_shard)?;
        d.set_item("skipped", r.skipped)?;
        d.set_item("ran", r.ran)?;
        d.set_item("failed", r.failed)?;
        d.set_item("duplicates", r.duplicates)?;
        d.set_item("results", r.results)?;
        d.set_item("superseded", r.superseded)?;
        d.set_item("wall_s", r.wall_s)?;
        d.set_item("estimate_s", self.plan.estimate_s)?;
        d.set_item("jobs", self.opts.jobs)?;
        Ok(d)
    }
}

/// Load and expand a sweep file as `skg-solve sweep` does before it starts
/// ([`sweep::plan`]): its points run in worker processes of the `skg-solve` executable
/// `exe`.
/// Why `name` cannot name a sweep, if it cannot ([`sweep::name_problem`]): the command
/// line's check, for a sweep given as a mapping before its files are written.
#[pyfunction]
pub(crate) fn sweep_name_problem(name: &str) -> Option<&'static str> {
    sweep::name_problem(name)
}

#[pyfunction]
#[pyo3(signature = (path, *, exe, out=None, jobs=None, shard=None, retry_failed=false, new_results=false, yes=false, progress=true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_sweep(
    py: Python<'_>,
    path: PathBuf,
    exe: PathBuf,
    out: Option<PathBuf>,
    jobs: Option<usize>,
    shard: Option<&str>,
    retry_failed: bool,
    new_results: bool,
    yes: bool,
    progress: bool,
) -> PyResult<NativeSweepPlan> {
    let shard = shard.map(|s| s.parse::<sweep::Shard>().map_err(|e| PyValueError::new_err(format!("shard: {e}")))).transpose()?;
    let file = py.detach(|| sweep::SweepFile::load(&path)).map_err(|e| sweep_err(py, &e))?;
    let opts = sweep::SweepOptions {
        out_dir: out.unwrap_or_else(|| sweep::default_out_dir(&file)),
        jobs: jobs.unwrap_or_else(sweep::default_jobs).max(1),
        shard,
        worker_exe: exe,
        progress,
        retry_failed,
        new_results,
    };
    let plan = py.detach(|| sweep::plan(&file, &opts, yes)).map_err(|e| sweep_err(py, &e))?;
    Ok(NativeSweepPlan { file, plan, opts })
}

/// Make (or check) the sharded directory of a sweep whose shards an executor runs
/// ([`sweep::shards::prepare`], under the directory's lock): a dict with the directory,
/// the sweep's name and file, the number of shards and points, the plan's line and each
/// shard's state (`k`, `points`, `converged`, `failed`, `missing`).
#[pyfunction]
#[pyo3(signature = (path, *, out=None, shards=None, yes=false))]
pub(crate) fn plan_shards<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: Option<PathBuf>,
    shards: Option<usize>,
    yes: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let file = py.detach(|| sweep::SweepFile::load(&path)).map_err(|e| sweep_err(py, &e))?;
    let out = out.unwrap_or_else(|| sweep::default_out_dir(&file));
    let dir = std::path::absolute(&out).map_err(|e| raise(py, "OutputError", &e))?;
    let opts = sweep::SweepOptions {
        out_dir: dir.clone(),
        jobs: 1,
        shard: None,
        worker_exe: PathBuf::from("skg-solve"),
        progress: false,
        retry_failed: false,
        new_results: false,
    };
    let prepare = sweep::shards::PrepareOptions { shards, runner: sweep::shards::Runner::Executor };
    let (plan, layout, states) = py
        .detach(|| {
            let plan = sweep::plan(&file, &opts, yes)?;
            let lock = output::OutputDir::lock(&dir)?;
            let (layout, states) = sweep::shards::prepare(&file, &plan.expanded, &dir, &prepare)?;
            drop(lock);
            Ok((plan, layout, states))
        })
        .map_err(|e: sweep::SweepError| sweep_err(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("dir", &dir)?;
    d.set_item("name", &layout.name)?;
    d.set_item("sweep_file", &layout.sweep_file)?;
    d.set_item("shards", layout.shards)?;
    d.set_item("total", layout.total_points)?;
    d.set_item("text", &plan.text)?;
    let list = PyList::empty(py);
    for s in &states {
        let e = PyDict::new(py);
        e.set_item("k", s.k)?;
        e.set_item("points", s.points)?;
        e.set_item("converged", s.converged)?;
        e.set_item("failed", s.failed)?;
        e.set_item("missing", s.missing)?;
        e.set_item("dir", sweep::shards::shard_dir(&dir, s.k))?;
        list.append(e)?;
    }
    d.set_item("states", list)?;
    Ok(d)
}

/// Merge the shards of a sharded directory into its results.csv
/// ([`sweep::shards::merge_shards`]: nothing is written unless every point is there);
/// returns `rows`, `total` and `duplicates`.
#[pyfunction]
pub(crate) fn merge_shards<'py>(py: Python<'py>, dir: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let r = py.detach(|| sweep::shards::merge_shards(&dir)).map_err(|e| sweep_err(py, &e))?;
    let d = PyDict::new(py);
    d.set_item("rows", r.rows)?;
    d.set_item("total", r.total)?;
    d.set_item("duplicates", r.duplicates)?;
    Ok(d)
}
