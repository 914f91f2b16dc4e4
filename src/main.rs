//! Command-line interface of skg-solve.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use skg_solve::check::{self, CheckOptions, Table, Tolerances};
use skg_solve::output;
use skg_solve::reference::{self, ReferenceOptions};
use skg_solve::sbp::OperatorKind;
use skg_solve::scenario::{Formulation, HessianMode, Overrides, Scene, SceneFile};
use skg_solve::solve;
use skg_solve::sweep;

/// Exit code of a solve that ran but did not converge.
const EXIT_NOT_CONVERGED: u8 = 3;
/// Exit code of `check` when a tolerance is exceeded.
const EXIT_TOLERANCE_EXCEEDED: u8 = 2;

#[derive(Parser)]
#[command(
    name = "skg-solve",
    version,
    about = "Motion of mechanical systems with velocity constraints, walls and friction \
             from the critical point of the discretized Schwinger–Keldysh–Galley action",
    long_about = "Solves a mechanical scene written in TOML: the classical Schwinger–Keldysh–Galley \
action of the scene is discretized in time with summation-by-parts operators and its critical point \
— the whole trajectory at once — is found by Ipopt with exact sparse derivatives.\n\n\
Writes DIR/trajectory.csv (t, each coordinate and its velocity Dq, each multiplier, the energy, the \
walls' potential energy, each constraint residual, each wall gap) and DIR/summary.json (status, iterations, timings, sizes, \
residuals). Exit status: 0 converged, 1 error in the input or while writing, 3 solve did not converge \
(the summary is still written, marked \"converged\": false).",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    solve: SolveArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Time solves of one scene over a ladder of node counts and print a table
    /// (wall time split into setup, initial guess, evaluations and Ipopt).
    Bench(BenchArgs),
    /// Run a parameter sweep: every point of the sweep file's grid in its own worker
    /// process, each finished point appended to DIR/results.csv. Rerunning resumes.
    Sweep(SweepArgs),
    /// Join the results of a sweep's shards into one results.csv.
    Merge(MergeArgs),
    /// Find the smallest wall width σ whose energy artifact stays below a tolerance
    /// at the scene's N (bisection over solves).
    Tune(TuneArgs),
    /// Charts (SVG and PNG) from a sweep's results.csv or from solutions.
    #[command(subcommand)]
    Plot(PlotKind),
    /// Worker process of a sweep (internal).
    #[command(hide = true)]
    SweepWorker {
        job: PathBuf,
        result: PathBuf,
    },
    /// Integrate the Lagrange–d'Alembert equations of a scene with a tight-tolerance
    /// adaptive integrator (DOP853) and write a reference CSV with the solver's columns.
    Reference(ReferenceArgs),
    /// Compare a trajectory CSV with a reference CSV column by column (exit status 2 when
    /// a tolerance is exceeded).
    Check(CheckArgs),
}

#[derive(Args)]
struct ReferenceArgs {
    /// Scene file (TOML).
    #[arg(value_name = "SCENARIO.toml")]
    scenario: PathBuf,
    /// Output CSV [default: out/<scene>/reference.csv, or reference.hard.csv with --hard-walls].
    #[arg(short, long, value_name = "FILE.csv")]
    output: Option<PathBuf>,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-12, value_name = "RTOL")]
    rtol: f64,
    /// Absolute tolerance of the integrator [default: the relative tolerance].
    #[arg(long, value_name = "ATOL")]
    atol: Option<f64>,
    /// Ideal elastic walls (event location at h = 0, specular reflection) instead of the
    /// scene's Gaussian walls: the reference for the model error.
    #[arg(long)]
    hard_walls: bool,
    /// Sample on the scene's grid with N nodes (overrides time.nodes).
    #[arg(long, value_name = "N", conflicts_with = "grid_from")]
    nodes: Option<usize>,
    /// Sample at the times (column t) of this CSV, e.g. a solver's trajectory.csv.
    #[arg(long, value_name = "FILE.csv")]
    grid_from: Option<PathBuf>,
    /// Set a scene parameter, e.g. `--set sigma=1/200` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Print only errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct CheckArgs {
    /// The trajectory to check (e.g. out/tumbler/trajectory.csv).
    #[arg(value_name = "SOLUTION.csv")]
    solution: PathBuf,
    /// The reference (e.g. tests/reference/tumbler.csv).
    #[arg(value_name = "REFERENCE.csv")]
    reference: PathBuf,
    /// Leave out the last K rows of the solution (e.g. 2 for the SBP end nodes).
    #[arg(long, default_value_t = 0, value_name = "K")]
    skip_last: usize,
    /// Compare only these columns (comma-separated) [default: every shared column except t].
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    columns: Option<Vec<String>>,
    /// Tolerance on every compared column's max |error|.
    #[arg(long, value_name = "TOL")]
    tol: Option<f64>,
    /// Tolerance on every compared column's RMS error.
    #[arg(long, value_name = "TOL")]
    tol_rms: Option<f64>,
    /// Tolerance on one column's max |error| (repeatable; overrides --tol for it).
    #[arg(long, value_name = "COLUMN=TOL")]
    tol_column: Vec<String>,
    /// JSON report [default: <SOLUTION without .csv>.check.json].
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Print only errors and exceeded tolerances.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args, Clone)]
struct SceneArgs {
    /// Set a scene parameter, e.g. `--set sigma=1/200` (repeatable; value: number or expression).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Override the SBP operator: SBP121, SBP242 (alias SBP424), SBP363.
    #[arg(long, value_name = "NAME")]
    operator: Option<OperatorKind>,
    /// Formulation: `reduced` (physical limit, half the unknowns; default) or `full`
    /// (the paper's doubled unknowns).
    #[arg(long, value_name = "KIND")]
    formulation: Option<Formulation>,
    /// Hessian given to Ipopt: `zero` (default; the Newton step of a square system does
    /// not depend on it) or `exact` (reduced formulation only).
    #[arg(long, value_enum, value_name = "MODE")]
    hessian: Option<HessianArg>,
    /// Maximum number of Ipopt iterations.
    #[arg(long, value_name = "N")]
    max_iter: Option<u32>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum HessianArg {
    Zero,
    Exact,
}

#[derive(Args)]
struct SolveArgs {
    /// Scene file (TOML), e.g. scenarios/rolling_disk.toml.
    #[arg(required = true, value_name = "SCENARIO.toml")]
    scenario: Option<PathBuf>,
    /// Output directory [default: out/<scene file name without .toml>].
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Number of time nodes N (overrides the scene's time.nodes).
    #[arg(long, value_name = "N")]
    nodes: Option<usize>,
    #[command(flatten)]
    scene: SceneArgs,
    /// Print only errors.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Args)]
struct BenchArgs {
    /// Scene file (TOML).
    #[arg(value_name = "SCENARIO.toml")]
    scenario: PathBuf,
    /// Comma-separated node counts.
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024,2048,4096,8192,16384")]
    nodes: Vec<usize>,
    /// Repetitions per node count (the fastest is reported).
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    #[command(flatten)]
    scene: SceneArgs,
}

#[derive(Args)]
struct SweepArgs {
    /// Sweep file (TOML), e.g. scenarios/sweeps/tumbler_sigma.toml.
    #[arg(value_name = "SWEEP.toml")]
    sweep: PathBuf,
    /// Output directory [default: out/sweeps/<sweep file name without .toml>].
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Worker processes at once [default: the number of cores].
    #[arg(short, long, value_name = "K")]
    jobs: Option<usize>,
    /// Run only the points whose index is k−1 mod n (1 ≤ k ≤ n), e.g. `--shard 3/8`.
    #[arg(long, value_name = "k/n")]
    shard: Option<sweep::Shard>,
    /// No progress bar and no summary line.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Subcommand)]
enum PlotKind {
    /// Error against the reference versus wall time, one line per operator and
    /// formulation, the reference integrator's tolerance ladder as the peer line.
    WorkPrecision(ResultsPlotArgs),
    /// Error versus N (log-log), the fitted order in the legend.
    Convergence(ResultsPlotArgs),
    /// Map over two grid axes: converged / failed / converged with energy artifacts.
    Stability {
        #[command(flatten)]
        common: ResultsPlotArgs,
        /// Column on the horizontal axis.
        #[arg(long, default_value = "nodes")]
        x: String,
        /// Column on the vertical axis.
        #[arg(long, default_value = "sigma")]
        y: String,
    },
    /// Coordinates over time (reference overlaid as a thin black line) and the energy over time.
    Trajectory {
        /// Solutions: output directories, trajectory CSV files, or sweep directories
        /// (their kept trajectories); several are overlaid.
        #[arg(required = true, value_name = "SOLUTION")]
        inputs: Vec<PathBuf>,
        /// Reference CSV to overlay (e.g. from `skg-solve reference`).
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
}

#[derive(Args)]
struct ResultsPlotArgs {
    /// A sweep's results.csv, or its output directory.
    #[arg(value_name = "RESULTS")]
    results: PathBuf,
    /// Output path without extension (writes .svg and .png).
    #[arg(short, long, value_name = "STEM")]
    output: PathBuf,
    /// Keep only rows whose column equals the value, e.g. `--where sigma=1/110` (repeatable).
    #[arg(long = "where", value_name = "COLUMN=VALUE")]
    filters: Vec<String>,
    /// Chart title [default: the kind of chart and the sweep directory].
    #[arg(long)]
    title: Option<String>,
}

#[derive(Args)]
struct MergeArgs {
    /// The shards' output directories (or their results.csv files).
    #[arg(required = true, value_name = "SHARD")]
    inputs: Vec<PathBuf>,
    /// Output directory of the merged results.csv.
    #[arg(short, long, value_name = "DIR")]
    output: PathBuf,
}

#[derive(Args)]
struct TuneArgs {
    /// Scene file (TOML) with a wall whose width is a parameter.
    #[arg(value_name = "SCENARIO.toml")]
    scenario: PathBuf,
    /// Number of time nodes N.
    #[arg(long, value_name = "N")]
    nodes: Option<usize>,
    /// Parameter to tune [default: the parameter a wall's width is set to].
    #[arg(long, value_name = "NAME")]
    param: Option<String>,
    /// Tolerance on the relative energy artifact.
    #[arg(long, default_value_t = skg_solve::tune::DEFAULT_ARTIFACT_TOL)]
    tol: f64,
    /// Lower end of the initial bracket [default: the scene's value / 8].
    #[arg(long)]
    lo: Option<f64>,
    /// Upper end of the initial bracket [default: the scene's value].
    #[arg(long)]
    hi: Option<f64>,
    /// Stop when the bracket's ratio hi/lo is below 1 + REL.
    #[arg(long, default_value_t = 0.02)]
    rel: f64,
    /// Write the search (every step) as JSON here.
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
}

impl SceneArgs {
    fn overrides(&self, nodes: Option<usize>) -> Result<Overrides> {
        let set = self
            .set
            .iter()
            .map(|s| Overrides::parse_assignment(s))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Overrides {
            set,
            nodes,
            operator: self.operator,
            formulation: self.formulation,
            hessian: self.hessian.map(|h| match h {
                HessianArg::Zero => HessianMode::Zero,
                HessianArg::Exact => HessianMode::Exact,
            }),
            max_iter: self.max_iter,
        })
    }
}

fn load(path: &Path, ov: &Overrides) -> Result<Scene> {
    Ok(SceneFile::load(path)?.resolve(ov)?)
}

fn run_solve(args: SolveArgs) -> Result<ExitCode> {
    let path = args.scenario.expect("clap requires the scenario");
    let ov = args.scene.overrides(args.nodes)?;
    let mut scene = load(&path, &ov)?;
    let dir = args.output.unwrap_or_else(|| {
        let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(stem)
    });
    if let Some(log) = &scene.solver.log_file {
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        scene.solver.log_file = Some(dir.join(log));
    }
    let mut outcome = solve::solve_scene(&scene)?;
    let (csv, json) = output::write_outcome(&dir, &mut outcome, &scene)
        .context("writing the results")?;
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    let t = &outcome.timings;
    let total = t.setup_s + t.initial_guess_s + t.ipopt_total_s + t.postprocess_s + t.output_s;
    if outcome.converged {
        if !args.quiet {
            let d = &outcome.diagnostics;
            println!(
                "{}: converged in {} Ipopt iterations ({}), {} {} N={} {}, {:.3} s",
                outcome.scene,
                outcome.iterations,
                outcome.status_text,
                outcome.settings.operator,
                outcome.settings.formulation,
                outcome.settings.nodes,
                if scene.constraints.is_empty() { String::new() } else { format!("max |g| interior {:.1e}", d.max_constraint_interior) },
                total
            );
            println!("  residual {:.1e}, energy drift {:.3e} (last two nodes excluded)", d.max_residual, d.energy_drift);
            println!("  wrote {}", csv.display());
            println!("  wrote {}", json.display());
        }
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!(
            "error: {}: the solve did not converge: {} ({} iterations, residual {:.3e}); summary in {}",
            outcome.scene,
            outcome.status_text,
            outcome.iterations,
            outcome.diagnostics.max_residual,
            json.display()
        );
        Ok(ExitCode::from(EXIT_NOT_CONVERGED))
    }
}

fn run_bench(args: BenchArgs) -> Result<ExitCode> {
    let bar = indicatif::ProgressBar::new((args.nodes.len() * args.repeat) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} solves, {elapsed} elapsed, ETA {eta} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    for &n in &args.nodes {
        let ov = args.scene.overrides(Some(n))?;
        let scene = load(&args.scenario, &ov)?;
        let mut best: Option<(f64, solve::Outcome)> = None;
        for _ in 0..args.repeat.max(1) {
            bar.set_message(format!("N={n}"));
            let start = Instant::now();
            let outcome = solve::solve_scene(&scene)?;
            let wall = start.elapsed().as_secs_f64();
            bar.inc(1);
            if best.as_ref().map_or(true, |(w, _)| wall < *w) {
                best = Some((wall, outcome));
            }
        }
        let (wall, o) = best.expect("at least one repetition");
        rows.push((n, wall, o));
    }
    bar.finish_and_clear();
    println!("| N | variables | Jacobian nnz | iterations | converged | setup s | guess s | eval s | Ipopt internal s | total s |");
    println!("|---:|---:|---:|---:|:---:|---:|---:|---:|---:|---:|");
    for (n, wall, o) in &rows {
        let t = &o.timings;
        println!(
            "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |",
            n,
            o.sizes.variables,
            o.sizes.jacobian_nonzeros,
            o.iterations,
            if o.converged { "yes" } else { "no" },
            t.setup_s,
            t.initial_guess_s,
            t.evaluation_s,
            t.ipopt_internal_s,
            wall
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn run_reference(args: ReferenceArgs) -> Result<ExitCode> {
    let mut set = Vec::new();
    for a in &args.set {
        set.push(Overrides::parse_assignment(a)?);
    }
    let ov = Overrides {
        set,
        nodes: args.nodes,
        ..Overrides::default()
    };
    let scene = load(&args.scenario, &ov)?;
    let times = match &args.grid_from {
        Some(p) => Table::read(p)?.times(),
        None => solve::grid(&scene).0,
    };
    if !(args.rtol > 0.0 && args.rtol.is_finite()) {
        anyhow::bail!("--rtol must be a positive number, got {}", args.rtol);
    }
    let opts = ReferenceOptions {
        rtol: args.rtol,
        atol: args.atol.unwrap_or(args.rtol),
    };
    let r = if args.hard_walls {
        reference::hard_wall(&scene, &times, &opts)?
    } else {
        reference::regularized(&scene, &times, &opts)?
    };
    let out = args.output.unwrap_or_else(|| {
        let stem = args.scenario.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out")
            .join(stem)
            .join(if args.hard_walls { "reference.hard.csv" } else { "reference.csv" })
    });
    reference::write(&out, &scene, &args.scenario.display().to_string(), &r)?;
    if !args.quiet {
        println!(
            "{}: {} reference, {} samples, {} steps ({} rejected), max |g| {:.1e}, max |E - E0| {:.3e}{}",
            scene.name,
            r.kind,
            r.trajectory.t.len(),
            r.stats.accepted,
            r.stats.rejected,
            r.constraint_drift,
            r.energy_drift,
            if args.hard_walls { format!(", {} impacts", r.impacts.len()) } else { String::new() }
        );
        println!("  wrote {}", out.display());
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(serde::Serialize)]
struct CheckReport<'a> {
    solution: String,
    reference: String,
    options: &'a CheckOptions,
    tolerances: &'a Tolerances,
    passed: bool,
    violations: Vec<String>,
    comparison: &'a check::Comparison,
}

fn run_check(args: CheckArgs) -> Result<ExitCode> {
    let solution = Table::read(&args.solution)?;
    let reference = Table::read(&args.reference)?;
    let opts = CheckOptions {
        skip_last: args.skip_last,
        columns: args.columns.clone(),
    };
    let mut per_column = Vec::new();
    for a in &args.tol_column {
        let (name, value) = a
            .split_once('=')
            .with_context(|| format!("--tol-column `{a}`: expected COLUMN=TOL"))?;
        let v: f64 = value
            .trim()
            .parse()
            .with_context(|| format!("--tol-column `{a}`: `{value}` is not a number"))?;
        per_column.push((name.trim().to_string(), v));
    }
    let tol = Tolerances {
        max_abs: args.tol,
        rms: args.tol_rms,
        per_column,
    };
    let cmp = check::compare(&solution, &reference, &opts)
        .with_context(|| format!("comparing {} with {}", args.solution.display(), args.reference.display()))?;
    let violations = cmp.violations(&tol);
    let json = args.json.clone().unwrap_or_else(|| args.solution.with_extension("check.json"));
    let report = CheckReport {
        solution: args.solution.display().to_string(),
        reference: args.reference.display().to_string(),
        options: &opts,
        tolerances: &tol,
        passed: violations.is_empty(),
        violations: violations.clone(),
        comparison: &cmp,
    };
    output::write_json(&json, &report)?;
    if !args.quiet {
        println!("| column | max abs error | at t | RMS error |");
        println!("|---|---:|---:|---:|");
        for c in &cmp.columns {
            println!("| {} | {:.3e} | {} | {:.3e} |", c.column, c.max_abs, c.at_t, c.rms);
        }
        println!(
            "{} rows compared ({} interpolated, last {} skipped); worst: {} {:.3e}",
            cmp.rows_compared, cmp.rows_interpolated, cmp.skipped_last, cmp.worst_column, cmp.max_abs
        );
        if !cmp.missing_in_reference.is_empty() {
            println!("not in the reference (not compared): {}", cmp.missing_in_reference.join(", "));
        }
        println!("wrote {}", json.display());
    }
    if violations.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        for v in &violations {
            eprintln!("tolerance exceeded: {v}");
        }
        Ok(ExitCode::from(EXIT_TOLERANCE_EXCEEDED))
    }
}

fn run_sweep(args: SweepArgs) -> Result<ExitCode> {
    let file = sweep::SweepFile::load(&args.sweep)?;
    let out = args.output.unwrap_or_else(|| PathBuf::from("out/sweeps").join(file.name()));
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let opts = sweep::SweepOptions {
        out_dir: out,
        jobs,
        shard: args.shard,
        worker_exe: std::env::current_exe().context("locating the skg-solve executable for the workers")?,
        progress: !args.quiet,
    };
    let r = sweep::run_sweep(&file, &opts)?;
    if !args.quiet {
        println!(
            "{}: {} points{}, {} already done, {} run ({} failed) with {} worker(s) in {:.1} s{}",
            file.name(),
            r.total,
            args.shard.map_or(String::new(), |s| format!(" ({} in shard {}/{})", r.in_shard, s.k, s.n)),
            r.skipped,
            r.ran,
            r.failed,
            jobs,
            r.wall_s,
            if r.duplicates > 0 { format!("; {} duplicate points dropped", r.duplicates) } else { String::new() }
        );
        println!("  wrote {}", r.results.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn run_sweep_worker(job: &Path, result: &Path) -> Result<ExitCode> {
    let text = std::fs::read_to_string(job).with_context(|| format!("reading {}", job.display()))?;
    let job: sweep::Job = serde_json::from_str(&text).with_context(|| format!("parsing {}", job.display()))?;
    let rec = sweep::run_job(&job);
    output::write_json(result, &rec)?;
    Ok(ExitCode::SUCCESS)
}

fn run_merge(args: MergeArgs) -> Result<ExitCode> {
    let r = sweep::merge(&args.inputs, &args.output)?;
    println!(
        "merged {} rows into {}{}{}",
        r.rows,
        args.output.join("results.csv").display(),
        if r.duplicates > 0 { format!("; {} duplicate rows dropped", r.duplicates) } else { String::new() },
        match r.missing {
            Some(0) => "; every point of the sweep is present".to_string(),
            Some(m) => format!("; {m} points of the sweep have no row yet"),
            None => String::new(),
        }
    );
    Ok(ExitCode::SUCCESS)
}

fn run_plot(kind: PlotKind) -> Result<ExitCode> {
    use skg_solve::plot;
    let parse_filters = |f: &[String]| -> Result<Vec<(String, String)>> {
        f.iter()
            .map(|s| {
                s.split_once('=')
                    .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
                    .ok_or_else(|| anyhow::anyhow!("--where {s}: expected COLUMN=VALUE"))
            })
            .collect()
    };
    let title_for = |c: &ResultsPlotArgs, kind: &str| {
        c.title.clone().unwrap_or_else(|| {
            let dir = if c.results.is_dir() { c.results.clone() } else { c.results.parent().map(Path::to_path_buf).unwrap_or_default() };
            let name = dir.file_name().map_or(String::new(), |n| format!(": {}", n.to_string_lossy()));
            format!("{kind}{name}")
        })
    };
    let written = match kind {
        PlotKind::WorkPrecision(c) => {
            let r = sweep::Results::read(&c.results)?;
            plot::work_precision(&r, &parse_filters(&c.filters)?, &title_for(&c, "work-precision"), &c.output)?
        }
        PlotKind::Convergence(c) => {
            let r = sweep::Results::read(&c.results)?;
            plot::convergence(&r, &parse_filters(&c.filters)?, &title_for(&c, "convergence"), &c.output)?
        }
        PlotKind::Stability { common: c, x, y } => {
            let r = sweep::Results::read(&c.results)?;
            plot::stability(&r, &x, &y, &parse_filters(&c.filters)?, &title_for(&c, "stability"), &c.output)?
        }
        PlotKind::Trajectory { inputs, reference, label, output: out, title } => {
            let mut sols = Vec::new();
            for (k, p) in inputs.iter().enumerate() {
                if p.is_dir() && p.join("results.csv").is_file() {
                    sols.extend(plot::sweep_solutions(p)?);
                    continue;
                }
                let file = if p.is_dir() { p.join("trajectory.csv") } else { p.clone() };
                let t = Table::read(&file)?;
                let name = label.get(k).cloned().unwrap_or_else(|| {
                    let base = if p.is_dir() { p.as_path() } else { p.parent().unwrap_or(p) };
                    base.file_name().map_or(file.display().to_string(), |n| n.to_string_lossy().into_owned())
                });
                sols.push((name, t));
            }
            let r = reference.as_deref().map(Table::read).transpose()?;
            plot::trajectory(&sols, r.as_ref(), &title, &out)?
        }
    };
    for w in written {
        println!("wrote {}", w.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn run_tune(args: TuneArgs) -> Result<ExitCode> {
    let ov = args.scene.overrides(args.nodes)?;
    let file = SceneFile::load(&args.scenario)?;
    let opts = skg_solve::tune::TuneOptions {
        param: args.param.clone(),
        tol: args.tol,
        lo: args.lo,
        hi: args.hi,
        rel: args.rel,
        ..Default::default()
    };
    let r = skg_solve::tune::tune_width(&file, &ov, &opts, |s| {
        eprintln!(
            "  {:.6e}: {} artifact {:.3e} → {} ({:.2} s)",
            s.value,
            if s.converged { "converged," } else { "not converged," },
            s.artifact,
            if s.ok { "ok" } else { "artifacts" },
            s.wall_s
        );
    })?;
    for n in &r.notes {
        eprintln!("note: {n}");
    }
    println!(
        "{} = {:.6e} (1/{:.1}): the smallest value without energy artifacts above {:e} at N = {}{}",
        r.param,
        r.chosen,
        1.0 / r.chosen,
        r.tol,
        r.nodes,
        r.failing.map_or(String::new(), |f| format!("; {:.6e} (1/{:.1}) has artifacts", f, 1.0 / f))
    );
    let out = args.output.unwrap_or_else(|| skg_solve::tune::default_output(&args.scenario));
    output::write_json(&out, &r)?;
    println!("  wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Bench(b)) => run_bench(b),
        Some(Command::Sweep(a)) => run_sweep(a),
        Some(Command::Merge(a)) => run_merge(a),
        Some(Command::Tune(a)) => run_tune(a),
        Some(Command::Plot(k)) => run_plot(k),
        Some(Command::SweepWorker { job, result }) => run_sweep_worker(&job, &result),
        Some(Command::Reference(r)) => run_reference(r),
        Some(Command::Check(c)) => run_check(c),
        None => run_solve(cli.solve),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
