//! `fit`: estimate a scene's parameters and initial data from measured motion, with
//! Ipopt as the optimizer (docs/fitting.md), and write the fitted motion, the data beside
//! it, the fitted scene and the summary with its `fit` object.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use skg_core::fit::{self, Data, Fit, FitError, FitHessian, FitIntoError, FitMethod, FitSettings, FitStart, FitWritten, FreeParameter};
use skg_core::scene::Scene;
use skg_core::stepping::verify::VerifyStatus;

use super::{load, SceneArgs, UsageError, EXIT_NOT_CONVERGED, EXIT_NOT_VERIFIED};
use crate::stdio::{note, out};

#[derive(Args)]
pub struct FitArgs {
    /// Scene file (TOML) whose parameters are fitted; its values are the starting values.
    #[arg(value_name = "SCENE.toml")]
    pub scenario: PathBuf,
    /// The measured motion (CSV): a column `t` and any of the scene's coordinates, named
    /// as in trajectory.csv; optional columns sigma_<coordinate> give each value's
    /// standard deviation (default: equal weights, the covariance scaled by the residual
    /// variance as curve_fit does). An empty cell is a value not measured. Default: the
    /// scene's `[fit] data`, relative to the scene file.
    #[arg(long, value_name = "FILE.csv")]
    pub data: Option<PathBuf>,
    /// The scene parameters to fit, comma-separated, each optionally with bounds:
    /// `NAME`, `NAME>=LO`, `NAME<=HI` or `NAME in [LO, HI]`, e.g. --free 'c>=0,mu in [0, 2]'
    /// (repeatable). Initial positions and velocities are fitted by writing them as
    /// parameters in the scene (velocity = "v0"). Default: the scene's `[fit] free`,
    /// which --free replaces as a whole.
    #[arg(long, value_name = "NAME[,NAME…]")]
    pub free: Vec<String>,
    /// Output directory [default: out/<scene file name without .toml>-fit].
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Number of time nodes N (overrides the scene's time.nodes).
    #[arg(long, value_name = "N")]
    pub nodes: Option<usize>,
    /// Fit on the discretization the solve's refinement chooses (docs/trust.md#refinement):
    /// the nodes and, unless --operator names one, the operator predicted to verify at the
    /// least cost; chosen at the starting values, and again at the fitted values when the
    /// fitted motion does not verify (docs/fitting.md#the-discretization).
    #[arg(long)]
    pub refine: bool,
    /// The largest grid --refine may use [default: the scene's [verify] max_nodes, else
    /// the largest the available memory allows, at most 1048576].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(2..=100_000_000))]
    pub max_nodes: Option<u64>,
    /// Seconds the whole fit may take (the refinement's choice of the discretization
    /// included; default: the scene's [solver] time_limit, else none), checked at every
    /// Ipopt iteration: the fit then ends as not converged (exit 3), its last values in
    /// summary.json.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = super::positive)]
    pub time_limit: Option<f64>,
    /// How the fit is handed to Ipopt: `all-at-once` (default; the trajectory and the
    /// parameters together, the equations of motion as constraints) or `reduced` (the
    /// parameters alone, the trajectory solved from the equations at every point: single
    /// shooting on the discrete equations, faster, but it can stop where shooting does;
    /// docs/fitting.md#two-ways-to-hand-the-fit-to-ipopt).
    #[arg(long = "fit-method", value_name = "METHOD", default_value = "all-at-once", value_parser = super::by_name::<FitMethod>(["all-at-once", "reduced"]))]
    pub fit_method: FitMethod,
    /// Hessian of the Lagrangian given to Ipopt: `exact` (default; second derivatives of
    /// the stationarity equations) or `limited-memory` (Ipopt's quasi-Newton approximation).
    #[arg(long = "fit-hessian", value_name = "MODE", default_value = "exact", value_parser = super::by_name::<FitHessian>(["exact", "limited-memory"]))]
    pub fit_hessian: FitHessian,
    /// Where the trajectory starts: `data` (the data where they observe a coordinate, the
    /// solve at the starting values elsewhere), `solve` (the solve everywhere) or `auto`
    /// (default: `data` for a scene without constraints or data that observe every
    /// coordinate, else `solve`).
    #[arg(long, value_name = "FROM", default_value = "auto", value_parser = super::by_name::<FitStart>(["auto", "data", "solve"]))]
    pub start: FitStart,
    /// Ipopt's tolerance of the fit (its scaled optimality error).
    #[arg(long, value_name = "TOL", default_value_t = fit::DEFAULT_TOL, value_parser = super::positive)]
    pub tol: f64,
    #[command(flatten)]
    pub scene: SceneArgs,
}

pub fn run(args: FitArgs, quiet: bool) -> Result<ExitCode> {
    let mut ov = args.scene.overrides(args.nodes)?;
    ov.refine = args.refine;
    ov.max_nodes = args.max_nodes.map(|n| n as usize);
    ov.time_limit = args.time_limit;
    let mut scene = load(&args.scenario, &ov)?;
    if !quiet {
        for n in &scene.notes {
            note!("note: {}: {n}", args.scenario.display());
        }
    }
    let settings = settings(&args, &scene)?;
    let data = Data::read(&data_path(&args, &scene)?, &scene)?;
    let dir = args.output.clone().unwrap_or_else(|| default_dir(&args.scenario));
    let spinner = super::solve::progress_spinner(quiet, &scene.name);
    spinner.set_message(if scene.choose_operator || scene.verify.refine {
        "choosing the discretization by the refinement, then fitting"
    } else {
        "fitting"
    });
    let result = fit::fit_into(&dir, &mut scene, &ov, &data, &settings);
    spinner.finish_and_clear();
    let (fitted, written) = match result {
        Ok(done) => done,
        Err(FitIntoError::Fit(e)) if e.not_converged().is_some() => {
            note!("error: {}: the fit did not converge: {}", scene.name, e.not_converged().unwrap_or_default());
            let remedy = match e {
                FitError::NotAMinimum(_) => stationary_point_remedy(settings.method),
                _ => not_evaluated_remedy(settings.method),
            };
            note!("  remedy: {remedy}");
            return Ok(ExitCode::from(EXIT_NOT_CONVERGED));
        }
        Err(e) => return Err(e.into()),
    };
    let fit_warnings = &fitted.report.warnings;
    for w in fit_warnings.iter().chain(fitted.outcome.warnings.iter().filter(|w| !fit_warnings.contains(w))) {
        note!("warning: {w}");
    }
    // A converged fit's values are shown even when its motion does not verify: the
    // error and the remedy follow them.
    if !quiet && fitted.report.converged {
        print_report(&fitted, &written);
    }
    Ok(report_untrusted(&fitted, &written).unwrap_or(ExitCode::SUCCESS))
}

/// What to do when the fit ended at a stationary point that is not the misfit's minimum.
fn stationary_point_remedy(method: FitMethod) -> &'static str {
    match method {
        FitMethod::Reduced => {
            "fit all at once (--fit-method all-at-once: it starts from the data where they observe every coordinate), or start \
             nearer the values the data suggest (--set NAME=VALUE)"
        }
        FitMethod::AllAtOnce => {
            "start nearer the values the data suggest (--set NAME=VALUE; --start data starts the trajectory from the data \
             where they observe it)"
        }
    }
}

/// What to do when Ipopt tried a point where the fit could not be evaluated.
fn not_evaluated_remedy(method: FitMethod) -> &'static str {
    match method {
        FitMethod::Reduced => {
            "fit all at once (--fit-method all-at-once: its trajectory need not solve the equations of motion at every point \
             Ipopt tries), start nearer the values the data suggest (--set NAME=VALUE), or bound the parameters to where the \
             equations can be solved (--free 'NAME in [LO, HI]')"
        }
        FitMethod::AllAtOnce => {
            "start nearer the values the data suggest (--set NAME=VALUE), or bound the parameters to where the scene's \
             expressions are defined (--free 'NAME in [LO, HI]')"
        }
    }
}

/// The fit's settings from the command line, the free parameters from the scene's
/// `[fit] free` when `--free` is not given (a malformed `--free`, or no free parameter
/// anywhere, is a usage error; a malformed `[fit]` entry an error at its line).
fn settings(args: &FitArgs, scene: &Scene) -> Result<FitSettings> {
    let free = if args.free.is_empty() {
        fit::free_of_scene(&scene.file)?
    } else {
        args.free
            .iter()
            .flat_map(|list| fit::split_list(list))
            .map(|item| FreeParameter::parse(&item).map_err(|e| UsageError(format!("--free: {e}"))))
            .collect::<Result<Vec<_>, _>>()?
    };
    if free.is_empty() {
        let message = "no free parameter: name the parameters to fit with --free, or with free = [...] in the scene's [fit] table";
        return Err(UsageError(format!("{}: {message}", args.scenario.display())).into());
    }
    let mut settings = FitSettings::new(free);
    settings.method = args.fit_method;
    settings.hessian = args.fit_hessian;
    settings.start = args.start;
    settings.tol = args.tol;
    if let Some(n) = args.scene.max_iter {
        settings.max_iter = n;
    }
    Ok(settings)
}

/// `--data`, or the scene's `[fit] data` (relative to the scene file); neither is a usage
/// error.
fn data_path(args: &FitArgs, scene: &Scene) -> Result<PathBuf> {
    if let Some(path) = &args.data {
        return Ok(path.clone());
    }
    match fit::data_of_scene(&scene.file)? {
        Some(path) => Ok(path),
        None => {
            let message = "no data: give --data FILE.csv, or data = \"FILE.csv\" in the scene's [fit] table";
            Err(UsageError(format!("{}: {message}", args.scenario.display())).into())
        }
    }
}

/// `out/<stem>-fit`.
fn default_dir(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from("out").join(format!("{stem}-fit"))
}

/// For a fit that did not converge, or whose fitted motion did not converge or verify:
/// say why and where the summary is, and give the exit status (3 or 4).
fn report_untrusted(f: &Fit, written: &FitWritten) -> Option<ExitCode> {
    let summary = written.written.summary.display();
    let scene = &f.outcome.scene;
    let code = if !f.report.converged {
        note!(
            "error: {scene}: the fit did not converge: {} ({} Ipopt iterations); summary in {summary}",
            f.report.status_text,
            f.report.iterations
        );
        EXIT_NOT_CONVERGED
    } else if !f.outcome.converged() {
        note!("error: {scene}: the solve at the fitted values did not converge: {}; summary in {summary}", f.outcome.status);
        EXIT_NOT_CONVERGED
    } else if !f.outcome.trusted() {
        let verdict = if f.outcome.verification.status == VerifyStatus::Unverified { "could not run" } else { "failed" };
        note!(
            "error: {scene}: the fit converged but the verification of the fitted motion {verdict}: {}; summary in {summary}",
            f.outcome.verification.reason
        );
        if let Some(r) = &f.outcome.remedy {
            note!("  remedy: {r}");
        }
        EXIT_NOT_VERIFIED
    } else {
        return None;
    };
    Some(ExitCode::from(code))
}

/// The report of a converged fit on stdout: the iterations, each parameter with its
/// standard error, the misfit, the discretization the refinement chose (if it did), the
/// verification and the files written.
fn print_report(f: &Fit, written: &FitWritten) {
    let r = &f.report;
    let method = match &r.equations_of_motion {
        Some(w) => format!(" of the reduced fit ({} solves of the equations of motion)", w.solves),
        None => String::new(),
    };
    out!(
        "{}: fit converged in {} Ipopt iterations{method} ({}), {} values, {:.3} s",
        f.outcome.scene,
        r.iterations,
        r.status,
        r.misfit.points,
        r.timings.total_s
    );
    let width = r.parameters.keys().map(|n| n.chars().count()).max().unwrap_or(0);
    for (name, p) in &r.parameters {
        let se = p.std_error.map_or("(no standard error)".to_string(), |s| format!("± {s:.3e}"));
        let bound = if p.at_bound { ", at its bound" } else { "" };
        out!("  {name:<width$} = {:<22} {se} (from {}{bound})", format!("{:.10}", p.value), p.initial);
    }
    let m = &r.misfit;
    out!(
        "  misfit: rms residual {:.3e}, max |residual| {:.3e}, sum of squares {:.3e}",
        m.rms_residual,
        m.max_abs_residual,
        m.sum_of_squares
    );
    for d in &r.discretization {
        let verified = if d.verified { "" } else { ", where it did not verify" };
        out!("  discretization: {}, chosen by the refinement at {}{verified}", d.describe(), d.chosen_at);
    }
    out!("  verified: {} ({})", f.outcome.verification.status, f.outcome.verification.reason);
    for path in written.paths() {
        out!("  wrote {}", path.display());
    }
}
