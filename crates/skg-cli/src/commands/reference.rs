//! `skg-solve reference`: tight-tolerance reference CSV of a scene.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use skg_core::check::Table;
use skg_core::output;
use skg_core::scene::{readable_number, Overrides, Stepper};
use skg_core::solve;
use skg_core::stepping::reference::{self, ReferenceError, ReferenceOptions};

use super::load;
use crate::stdio::out;

#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML).
    #[arg(value_name = "SCENARIO.toml")]
    pub scenario: PathBuf,
    /// Output CSV [default: out/<scene>/reference.regularized.csv, or reference.hard.csv with
    /// --hard-walls; not reference.csv, which is a solve's own verification reference].
    #[arg(short, long, value_name = "FILE.csv")]
    pub output: Option<PathBuf>,
    /// Relative tolerance of the integrator.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1e-12, value_name = "RTOL")]
    pub rtol: f64,
    /// Absolute tolerance of the integrator [default: the relative tolerance].
    #[arg(long, allow_negative_numbers = true, value_name = "ATOL")]
    pub atol: Option<f64>,
    /// The integrator: `auto` (default, or the scene's `[verify] stepper`: DOP853, and
    /// Radau IIA from where the scene turns out stiff), `dop853` or `implicit` (Radau IIA
    /// throughout; not with --hard-walls, whose impacts are located on DOP853's dense
    /// output).
    #[arg(long, value_name = "NAME", value_parser = super::stepper_parser())]
    pub stepper: Option<Stepper>,
    /// Ideal elastic walls (event location at h = 0, specular reflection) instead of the
    /// scene's Gaussian walls: the reference for the model error.
    #[arg(long)]
    pub hard_walls: bool,
    /// Sample on the scene's grid with N nodes (overrides time.nodes).
    #[arg(long, value_name = "N", conflicts_with = "grid_from")]
    pub nodes: Option<usize>,
    /// Sample at the times (column t) of this CSV, e.g. a solver's trajectory.csv.
    #[arg(long, value_name = "FILE.csv")]
    pub grid_from: Option<PathBuf>,
    /// Set a scene parameter, e.g. `--set sigma=1/200` (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

pub fn run(args: ReferenceArgs, quiet: bool) -> Result<ExitCode> {
    let mut set = Vec::new();
    for a in &args.set {
        set.push(Overrides::parse_assignment(a)?);
    }
    let ov = Overrides { set, nodes: args.nodes, stepper: args.stepper, ..Overrides::default() };
    let scene = load(&args.scenario, &ov)?;
    let times = match &args.grid_from {
        Some(p) => Table::read(p)?.times(),
        None => solve::grid(&scene).0,
    };
    if !(args.rtol > 0.0 && args.rtol.is_finite()) {
        anyhow::bail!("--rtol must be a positive number, got {}", readable_number(args.rtol));
    }
    let atol = args.atol.unwrap_or(args.rtol);
    if !(atol >= 0.0 && atol.is_finite()) {
        anyhow::bail!("--atol must be a number ≥ 0, got {}", readable_number(atol));
    }
    let opts = ReferenceOptions { rtol: args.rtol, atol, stepper: scene.verify.stepper };
    let r = if args.hard_walls { reference::hard_wall(&scene, &times, &opts) } else { reference::regularized(&scene, &times, &opts) };
    // A scene error names its file and line already; any other names the scene file here.
    let r = r.map_err(|e| match e {
        ReferenceError::Scene(e) => anyhow::Error::from(e),
        other => anyhow::anyhow!("{}: {other}", args.scenario.display()),
    })?;
    let out = args.output.unwrap_or_else(|| {
        let stem = args.scenario.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(stem).join(if args.hard_walls { "reference.hard.csv" } else { "reference.regularized.csv" })
    });
    output::write_reference(&out, &scene, &args.scenario.display().to_string(), &r)?;
    if !quiet {
        out!(
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
        out!("  wrote {}", out.display());
    }
    Ok(ExitCode::SUCCESS)
}
