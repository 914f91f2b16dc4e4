//! Charts (SVG and PNG) from a sweep's `results.csv` or from solutions' CSVs, drawn with
//! plotters. Text uses DejaVu Sans embedded in the binary (`assets/fonts`, registered
//! through plotters' `ab_glyph` feature), so no system font or fontconfig is needed.
//!
//! * [`work_precision`]: error against the reference versus wall time, one line per
//!   operator and formulation, the reference integrator at a ladder of tolerances as the
//!   peer line.
//! * [`convergence`]: error versus N, log-log, the fitted order in the legend.
//! * [`errors`]: the error against the sweep's reference and the verification's error
//!   versus a parameter (with the hard-wall reference: the model error beside the
//!   discretization error as the wall thins), log-log.
//! * [`scaling`]: solve time versus N from `skg-solve bench --csv`, log-log, with a
//!   line of slope 1.
//! * [`trajectory`]: the coordinates over time with the reference overlaid, and the
//!   energy over time.
//! * [`fit`](fn@fit): a fit's data against its fitted motion, and the residuals.
//! * [`stability`]: a map over two grid axes, each cell converged / failed / converged
//!   with energy artifacts / not run.
//! * [`motion`]: the motion itself: a solution's path in the plane of two coordinates
//!   with the walls drawn as their curves `h = 0` ([`motion::path`]), an animation
//!   ([`motion::animate`], GIF or MP4) and a strip of frames ([`motion::strip`]).
//!
//! Points are judged by their [`PointStatus`](skg_sweep::PointStatus) (the `status` column of results.csv).
//! Axis values are read as numbers; where a sweep wrote them as expressions (the
//! `<axis>_expr` column), labels show the expression (`1/110`).
//!
//! The crate's modules, each named after what it holds:
//!
//! * `error`: [`PlotError`] and [`DrawError`];
//! * `render`: the embedded font, the palette, the chart size and the writing of a
//!   chart to its SVG and PNG files (through temporary files, then renamed);
//! * `results`: reading a sweep's results (cells as numbers, `--where` filters, the
//!   converged SKG points by line, the kept trajectories);
//! * `loglog`: the log-log chart that the charts of `line_charts` draw, with its axes'
//!   labels and the corner for its legend;
//! * `line_charts`: [`work_precision`], [`tolerance`], [`convergence`], [`errors`], [`scaling`];
//! * `trajectory`: [`trajectory`];
//! * `fit`: [`fit`](fn@fit);
//! * `stability`: [`stability`] and its [`Cell`];
//! * [`motion`]: the pictures of the motion.

#![warn(missing_docs)]

mod error;
mod render;

mod fit;
mod line_charts;
mod loglog;
mod results;
mod stability;
mod trajectory;

pub mod motion;

pub use error::{DrawError, PlotError};
pub use fit::fit;
pub use line_charts::{convergence, errors, scaling, tolerance, work_precision};
pub use render::SIZE;
pub use results::{cell_value, sweep_solutions};
pub use stability::{stability, Cell};
pub use trajectory::trajectory;
