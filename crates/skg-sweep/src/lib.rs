//! Parameter sweeps: a sweep file (TOML) names a base scene and a grid of values; the
//! points of the grid are solved in worker processes, each worker running one point after
//! another, and each point is appended to `results.csv` as soon as it finishes.
//!
//! The crate in the order of a run, one concern per module (the private modules' items
//! are re-exported here, so every public item is `skg_sweep::X`):
//!
//! * `sweep_file.rs`: the sweep file as written ([`SweepFile`]);
//! * `point.rs`: a point ([`Point`]), its **id** (a hash of its canonical text, axis
//!   names sorted, so it does not depend on the order of the file), and a [`Shard`];
//! * `expand.rs`: grid expansion ([`SweepFile::expand`]) into an [`Expanded`] sweep,
//!   every point checked against the base scene before anything runs;
//! * `plan.rs`: what a run will do and a rough estimate of its time ([`plan()`]), from the
//!   measured time per node of each operator and backend in
//!   [`skg_core::solve::cost`]; more than [`CONFIRM_ABOVE`] points only when confirmed;
//! * `job.rs`: the job a worker runs, one point, and its [`Record`] ([`run_job`]);
//! * [`workers`]: the worker processes and their protocol with the driver;
//! * `driver.rs`: the driver ([`run_sweep`]): the only writer of `results.csv`, resumable;
//! * `results.rs` and `status.rs`: `results.csv`, its columns ([`results_columns`]) and
//!   reading it back ([`Results`]), and how a point ended ([`PointStatus`]);
//! * `info.rs`: `sweep.json` beside it ([`SweepInfo`]);
//! * `merge.rs`: the merge of shards' results ([`merge()`]); [`shards`]: a sweep split into
//!   shards in one directory; [`slurm`]: those shards as a Slurm job array;
//! * `error.rs`: [`SweepError`] and the errors it carries.

#![warn(missing_docs)]
// Errors carry file:line:column text, as in the core modules.
#![allow(clippy::result_large_err)]

mod driver;
mod error;
mod expand;
mod info;
mod job;
mod merge;
mod plan;
mod point;
mod results;
pub mod shards;
pub mod slurm;
mod status;
mod sweep_file;
pub mod workers;

pub use driver::{run_sweep, SweepOptions, SweepReport};
pub use error::{list_points, AxisError, SceneOf, SweepError, SweepSceneError};
pub use expand::{structure_key, Expanded, MAX_POINTS};
pub use info::{RowSettings, SweepInfo};
pub use job::{run_job, Job, Record};
pub use merge::{merge, MergeReport};
pub use plan::{default_jobs, default_out_dir, estimated_cost, estimated_wall_s, plan, Plan, CONFIRM_ABOVE};
pub use point::{Method, ParseShardError, Point, Shard, SETTING_AXES};
pub use results::{
    csv_line, header_names, results_columns, results_row, Column, Provenance, Results, SchemaError, CUT_LINE, EXPR_SUFFIX, LEADING_COLUMNS,
    PROVENANCE_COLUMNS, RESULT_COLUMNS,
};
pub use status::{PointStatus, UnknownStatus};
pub use sweep_file::{
    name_problem, AxisValue, AxisValues, PeerSpec, ReferenceSpec, SweepFile, SweepMeta, MAX_NAME_BYTES, REFERENCE_HARD_WALLS,
    REFERENCE_INTEGRATE,
};
pub use workers::{die_of, serve_points, stop_on_signals, stop_signal};
