//! `skg-solve tune`: the smallest wall width without energy artifacts.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;

use skg_core::output;
use skg_core::scene::SceneFile;

use super::SceneArgs;
use crate::stdio::{note, out};

#[derive(Args)]
pub struct TuneArgs {
    /// Scene file (TOML) with a wall whose width is a parameter.
    #[arg(value_name = "SCENARIO.toml")]
    pub scenario: PathBuf,
    /// Number of time nodes N.
    #[arg(long, value_name = "N")]
    pub nodes: Option<usize>,
    /// Parameter to tune [default: the parameter a wall's width is set to].
    #[arg(long, value_name = "NAME")]
    pub param: Option<String>,
    /// Tolerance on the relative energy artifact.
    #[arg(long, allow_negative_numbers = true, default_value_t = skg_core::tune::DEFAULT_ARTIFACT_TOL)]
    pub tol: f64,
    /// Lower end of the initial bracket [default: the scene's value / 8].
    #[arg(long, allow_negative_numbers = true)]
    pub lo: Option<f64>,
    /// Upper end of the initial bracket [default: the scene's value].
    #[arg(long, allow_negative_numbers = true)]
    pub hi: Option<f64>,
    /// Stop when the bracket's ratio hi/lo is below 1 + REL.
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.02)]
    pub rel: f64,
    /// Write the search (every step) as JSON here.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub scene: SceneArgs,
}

pub fn run(args: TuneArgs, quiet: bool) -> Result<ExitCode> {
    let ov = args.scene.overrides(args.nodes)?;
    let file = SceneFile::load(&args.scenario)?;
    let opts = skg_core::tune::TuneOptions {
        param: args.param.clone(),
        tol: args.tol,
        lo: args.lo,
        hi: args.hi,
        rel: args.rel,
        ..Default::default()
    };
    let r = skg_core::tune::tune_width(&file, &ov, &opts, |s| {
        if quiet {
            return;
        }
        note!(
            "  {:.6e}: {} artifact {:.3e} → {} ({:.2} s)",
            s.value,
            if s.status.is_converged() { "converged," } else { "not converged," },
            s.artifact,
            if s.ok { "ok" } else { "artifacts" },
            s.wall_s
        );
    })?;
    if !quiet {
        for n in &r.notes {
            note!("note: {n}");
        }
    }
    let out = args.output.unwrap_or_else(|| skg_core::tune::default_output(&args.scenario));
    output::write_json(&out, &r)?;
    if quiet {
        return Ok(ExitCode::SUCCESS);
    }
    out!(
        "{} = {:.6e} (1/{:.1}): the smallest value without energy artifacts above {:e} at N = {}{}",
        r.param,
        r.chosen,
        1.0 / r.chosen,
        r.tol,
        r.nodes,
        r.failing.map_or(String::new(), |f| format!("; {:.6e} (1/{:.1}) has artifacts", f, 1.0 / f))
    );
    out!("  wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}
