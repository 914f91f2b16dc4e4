//! `skg-solve plot`: charts from sweep results and solutions.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use crate::stdio::{note, out};
use skg_core::check::Table;
use skg_plot as plot;
use skg_sweep as sweep;

#[derive(Subcommand)]
pub enum PlotKind {
    /// Error against the reference versus wall time, one line per operator and
    /// formulation, the reference integrator's tolerance ladder as the peer line.
    WorkPrecision(ResultsPlotArgs),
    /// Error versus N (log-log), the fitted order in the legend.
    Convergence(ResultsPlotArgs),
    /// Accuracy asked versus reached: a sweep over `verify_tol` with `refine = true`,
    /// error and wall time over the tolerance asked (one line per backend), beside the
    /// time stepper's rtol ladder (writes STEM and STEM-time).
    Tolerance(ResultsPlotArgs),
    /// The errors of each converged point over a column (a parameter such as `sigma`),
    /// log-log: `error_max` against the sweep's reference and `verify_error`, the
    /// verification's against time stepping of the same scene, each tagged with the
    /// operator and nodes it was solved on; the tolerance when the sweep has a
    /// `verify_tol` column. With `reference = "hard_walls"` the first is the model error
    /// and the second the discretization error: the hard-contact limit.
    Errors {
        #[command(flatten)]
        common: ResultsPlotArgs,
        /// Column on the horizontal axis.
        #[arg(long, default_value = "sigma")]
        x: String,
    },
    /// Map over two grid axes: verified / verified with energy artifacts / converged but
    /// not verified / failed, each cell labelled with a column's value.
    Stability {
        #[command(flatten)]
        common: ResultsPlotArgs,
        /// Column on the horizontal axis.
        #[arg(long, default_value = "nodes")]
        x: String,
        /// Column on the vertical axis.
        #[arg(long, default_value = "sigma")]
        y: String,
        /// Column whose value is written in each cell (e.g. `error_max`, `verify_error`).
        #[arg(long, default_value = "energy_artifact")]
        value: String,
    },
    /// The path in the plane of two coordinates (or a coordinate and t) with the walls
    /// drawn as their curves h = 0 and the reference overlaid.
    #[command(after_long_help = super::animate::WALLS_HELP)]
    Path {
        #[command(flatten)]
        motion: super::animate::MotionArgs,
        /// Output path without extension (writes .svg and .png).
        #[arg(short, long, value_name = "STEM")]
        output: PathBuf,
    },
    /// Solve time versus N (log-log) from `skg-solve bench --csv` files, one line per
    /// file, with a line of slope 1 (cost proportional to N) through the last file's
    /// largest N.
    Scaling {
        /// CSV files written by `skg-solve bench --csv`.
        #[arg(required = true, value_name = "BENCH.csv")]
        inputs: Vec<PathBuf>,
        /// Legend label of each file, in order [default: the file name and its backend].
        #[arg(long, value_name = "TEXT")]
        label: Vec<String>,
        /// Output path without extension (writes .svg and .png).
        #[arg(short, long, value_name = "STEM")]
        output: PathBuf,
        /// Chart title.
        #[arg(long, default_value = "solve time against N")]
        title: String,
    },
    /// Coordinates over time (reference overlaid as a thin black line) and the energy over time.
    Trajectory {
        /// Solutions: output directories, trajectory CSV files, or sweep directories
        /// (their kept trajectories); several are overlaid.
        #[arg(required = true, value_name = "SOLUTION")]
        inputs: Vec<PathBuf>,
        /// Reference CSV to overlay (e.g. from `skg-solve reference`) [default: the first
        /// solution directory's reference.csv, the verification's time stepping, if any].
        #[arg(long, value_name = "FILE.csv")]
        reference: Option<PathBuf>,
        /// Legend label of each solution, in order [default: the directory or file name].
        #[arg(long, value_name = "TEXT")]
        label: Vec<String>,
        /// Output path without extension (writes .svg and .png).
        #[arg(short, long, value_name = "STEM")]
        output: PathBuf,
        /// Chart title.
        #[arg(long, default_value = "trajectory and energy")]
        title: String,
    },
    /// A fit's data against its fitted motion (points with error bars of one standard
    /// deviation where the data give them, lines), and the residuals: from the output
    /// directory of `skg-solve fit` (its data.csv and trajectory.csv).
    Fit {
        /// The output directory of `skg-solve fit`.
        #[arg(value_name = "DIR")]
        dir: PathBuf,
        /// Output path without extension (writes .svg and .png).
        #[arg(short, long, value_name = "STEM")]
        output: PathBuf,
        /// Chart title [default: the scene's name from the fit's summary.json, else the
        /// directory's name].
        #[arg(long)]
        title: Option<String>,
    },
}

#[derive(Args)]
pub struct ResultsPlotArgs {
    /// A sweep's results.csv, or its output directory.
    #[arg(value_name = "RESULTS")]
    pub results: PathBuf,
    /// Output path without extension (writes .svg and .png).
    #[arg(short, long, value_name = "STEM")]
    pub output: PathBuf,
    /// Keep only rows whose column equals the value, e.g. `--where sigma=1/110` (repeatable):
    /// equal as text, as the sweep file wrote it (the `<column>_expr` column), or as numbers
    /// to a relative 1e-12 (the value may be a constant expression). Rows that leave the
    /// column blank (the peer rows) are kept.
    #[arg(long = "where", value_name = "COLUMN=VALUE")]
    pub filters: Vec<String>,
    /// Chart title [default: the kind of chart and the sweep directory].
    #[arg(long)]
    pub title: Option<String>,
}

pub fn run(kind: PlotKind, quiet: bool) -> Result<ExitCode> {
    let written = match kind {
        PlotKind::WorkPrecision(c) => {
            let r = sweep::Results::read(&c.results)?;
            plot::work_precision(&r, &filters(&c.filters)?, &c.title_or("work-precision"), &c.output)?
        }
        PlotKind::Tolerance(c) => {
            let r = sweep::Results::read(&c.results)?;
            plot::tolerance(&r, &filters(&c.filters)?, &c.title_or("accuracy asked and reached"), &c.output)?
        }
        PlotKind::Convergence(c) => {
            let r = sweep::Results::read(&c.results)?;
            plot::convergence(&r, &filters(&c.filters)?, &c.title_or("convergence"), &c.output)?
        }
        PlotKind::Errors { common: c, x } => {
            let r = sweep::Results::read(&c.results)?;
            let reference = sweep::SweepInfo::read(&c.dir()).ok().and_then(|i| i.settings.reference);
            plot::errors(&r, &x, reference.as_deref(), &filters(&c.filters)?, &c.title_or("errors"), &c.output)?
        }
        PlotKind::Stability { common: c, x, y, value } => {
            let r = sweep::Results::read(&c.results)?;
            plot::stability(&r, &x, &y, &value, &filters(&c.filters)?, &c.title_or("stability"), &c.output)?
        }
        PlotKind::Path { motion, output } => {
            let (m, view) = motion.load()?;
            plot::motion::path(&m, &view, &output)?
        }
        PlotKind::Scaling { inputs, label, output: out, title } => {
            check_labels(&label, &inputs)?;
            plot::scaling(&benchmarks(&inputs, &label)?, &title, &out)?
        }
        PlotKind::Trajectory { inputs, reference, label, output: out, title } => {
            check_labels(&label, &inputs)?;
            let sols = solutions(&inputs, &label)?;
            let verification_reference = || inputs.iter().find(|p| p.is_dir()).map(|d| d.join("reference.csv")).filter(|f| f.is_file());
            let r = reference.or_else(verification_reference).as_deref().map(Table::read).transpose()?;
            plot::trajectory(&sols, r.as_ref(), &title, &out)?
        }
        PlotKind::Fit { dir, output, title } => {
            let data = Table::read(&dir.join(skg_core::fit::DATA_FILE))?;
            let (trajectory, pairing) = Table::read_paired(&dir.join("trajectory.csv"))?;
            if let Some(w) = pairing.warning(&dir.join("trajectory.csv")) {
                note!("warning: {w}");
            }
            plot::fit(&data, &trajectory, &title.unwrap_or_else(|| fit_title(&dir)), &output)?
        }
    };
    if !quiet {
        for w in written {
            out!("wrote {}", w.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

impl ResultsPlotArgs {
    /// `--title`, else the kind of chart and the sweep directory's name:
    /// `convergence: tumbler_convergence`.
    fn title_or(&self, kind: &str) -> String {
        self.title.clone().unwrap_or_else(|| {
            let name = self.dir().file_name().map_or(String::new(), |n| format!(": {}", n.to_string_lossy()));
            format!("{kind}{name}")
        })
    }

    /// The sweep's directory: the results' own, or the directory holding the results file.
    fn dir(&self) -> PathBuf {
        let c = &self.results;
        if c.is_dir() {
            c.clone()
        } else {
            c.parent().map(Path::to_path_buf).unwrap_or_default()
        }
    }
}

/// `fit: <scene name>` from a fit's summary.json, else `fit: <directory name>`.
fn fit_title(dir: &Path) -> String {
    let summary = std::fs::read_to_string(dir.join("summary.json")).ok().and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
    let name = summary.as_ref().and_then(|s| s["scene"].as_str().map(str::to_string));
    let name = name.unwrap_or_else(|| dir.file_name().map_or(dir.display().to_string(), |n| n.to_string_lossy().into_owned()));
    format!("fit: {name}")
}

/// The `--where COLUMN=VALUE` filters as (column, value) pairs.
fn filters(f: &[String]) -> Result<Vec<(String, String)>> {
    f.iter()
        .map(|s| {
            s.split_once('=')
                .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
                .ok_or_else(|| anyhow::anyhow!("--where {s}: expected COLUMN=VALUE"))
        })
        .collect()
}

/// One line of `plot scaling`: its label and its points (N, total seconds).
type Benchmark = (String, Vec<(f64, f64)>);

/// The lines of `plot scaling`: each `bench --csv` file's points, labelled by its
/// `--label` or by its file name and backend.
fn benchmarks(inputs: &[PathBuf], labels: &[String]) -> Result<Vec<Benchmark>> {
    let mut benchmarks = Vec::new();
    for (k, p) in inputs.iter().enumerate() {
        let (backend, points) = read_bench_csv(p)?;
        let name = p.file_stem().map_or(String::new(), |n| n.to_string_lossy().into_owned());
        benchmarks.push((labels.get(k).cloned().unwrap_or_else(|| format!("{name} ({backend})")), points));
    }
    Ok(benchmarks)
}

/// The solutions of `plot trajectory`, labelled: a sweep directory's kept trajectories,
/// or a solve's directory or trajectory CSV (labelled by its `--label` or its
/// directory's name; a trajectory its summary does not vouch for gets a warning).
fn solutions(inputs: &[PathBuf], labels: &[String]) -> Result<Vec<(String, Table)>> {
    let mut sols = Vec::new();
    for (k, p) in inputs.iter().enumerate() {
        if p.is_dir() && p.join("results.csv").is_file() {
            sols.extend(plot::sweep_solutions(p)?);
            continue;
        }
        let file = if p.is_dir() { p.join("trajectory.csv") } else { p.clone() };
        let (t, pairing) = Table::read_paired(&file)?;
        if let Some(w) = pairing.warning(&file) {
            note!("warning: {w}");
        }
        let name = labels.get(k).cloned().unwrap_or_else(|| {
            let base = if p.is_dir() { p.as_path() } else { p.parent().unwrap_or(p) };
            base.file_name().map_or(file.display().to_string(), |n| n.to_string_lossy().into_owned())
        });
        sols.push((name, t));
    }
    Ok(sols)
}

/// One `--label` per input at most: an extra one would label nothing (a usage error).
fn check_labels(labels: &[String], inputs: &[PathBuf]) -> Result<()> {
    if labels.len() > inputs.len() {
        let message = format!(
            "{} --label given for {} input(s): each labels one input, in order (the extra: {})",
            labels.len(),
            inputs.len(),
            labels[inputs.len()..].iter().map(|l| format!("{l:?}")).collect::<Vec<_>>().join(", ")
        );
        return Err(super::UsageError(message).into());
    }
    Ok(())
}

/// The backend and the points (N, total seconds) of a `bench --csv` file.
fn read_bench_csv(path: &Path) -> Result<(String, Vec<(f64, f64)>)> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| anyhow::anyhow!("{}: no column `{name}` (not a `bench --csv` file?)", path.display()))
    };
    let (nodes, total, backend) = (column("nodes")?, column("total_s")?, column("backend")?);
    let mut points = Vec::new();
    let mut backends = Vec::new();
    for (i, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let number = |c: usize| cells.get(c).and_then(|v| v.parse::<f64>().ok());
        let (Some(n), Some(t)) = (number(nodes), number(total)) else {
            anyhow::bail!("{}:{}: expected numbers in the columns nodes and total_s", path.display(), i + 2);
        };
        points.push((n, t));
        if let Some(b) = cells.get(backend).filter(|b| !backends.contains(*b)) {
            backends.push(*b);
        }
    }
    Ok((backends.join("/"), points))
}
