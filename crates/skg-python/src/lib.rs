//! `skg._skg`: the native part of the Python package `skg` (python/skg wraps it).
//!
//! Every function here calls the same code as the `skg-solve` command line: a scene is
//! loaded and resolved by `skg_core::scene`, solved by `skg_core::solve::solve_scene`
//! (verification and fallback ladder included), integrated by `skg_core::stepping::reference`,
//! written (into a locked directory) by `skg_core::output`, planned and swept by
//! `skg_sweep::plan` and `skg_sweep::run_sweep` (split into shards for an executor by
//! `skg_sweep::shards`). Errors are raised as the exceptions of `skg._errors` with the
//! command line's message ([`skg_core::error_text`]). The GIL is released while Rust
//! computes.
//!
//! Trajectories cross into Python as a dict of NumPy arrays (`arrays::trajectory_dict`);
//! the Python classes (`skg.Trajectory`, `skg.Solution`, …) are written in Python.
//!
//! Its modules: `errors` raises the exceptions; `arrays` makes the NumPy arrays and the
//! trajectory's dict; `toml_values` converts Python values to TOML and back (a scene or a
//! sweep built from a mapping); `scene` holds `NativeScene`, the `set=` overrides and the
//! loading of a scene argument; `solve`, `fit`, `reference` and `sweep` the functions of those
//! names with their result classes; `readers` reads the files skg-solve writes.

#![warn(missing_docs)]

use pyo3::prelude::*;

use skg_core::scene::provenance;

mod arrays;
mod errors;
mod fit;
mod readers;
mod reference;
mod scene;
mod solve;
mod sweep;
mod toml_values;

/// The native module.
#[pymodule]
fn _skg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(solve::solve_scene, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit_scene, m)?)?;
    m.add_function(wrap_pyfunction!(reference::integrate_reference, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::plan_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::plan_shards, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::merge_shards, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_name_problem, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_results, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_table, m)?)?;
    m.add_function(wrap_pyfunction!(toml_values::toml_text, m)?)?;
    m.add_class::<scene::NativeScene>()?;
    m.add_class::<solve::NativeSolution>()?;
    m.add_class::<fit::NativeFit>()?;
    m.add_class::<reference::NativeReference>()?;
    m.add_class::<sweep::NativeSweepPlan>()?;
    m.add("VERSION", provenance::VERSION)?;
    m.add("SCHEMA_VERSION", provenance::SCHEMA_VERSION)?;
    // Where this module was built from: the workspace's target directory holds an
    // `skg-solve` built from the same sources (one of the places `skg.sweep` looks).
    m.add("TARGET_DIR", concat!(env!("CARGO_MANIFEST_DIR"), "/../../target"))?;
    Ok(())
}
