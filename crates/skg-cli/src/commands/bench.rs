//! `skg-solve bench`: time solves over a ladder of node counts.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;
use clap::Args;

use skg_core::solve;

use super::{load, SceneArgs};

#[derive(Args)]
pub struct BenchArgs {
    /// Scene file (TOML).
    #[arg(value_name = "SCENARIO.toml")]
    pub scenario: PathBuf,
    /// Comma-separated node counts.
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024,2048,4096,8192,16384")]
    pub nodes: Vec<usize>,
    /// Repetitions per node count (the fastest is reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    #[command(flatten)]
    pub scene: SceneArgs,
}

pub fn run(args: BenchArgs) -> Result<ExitCode> {
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
            if best.as_ref().is_none_or(|(w, _)| wall < *w) {
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
            if o.converged() { "yes" } else { "no" },
            t.setup_s,
            t.initial_guess_s,
            t.evaluation_s,
            t.ipopt_internal_s,
            wall
        );
    }
    Ok(ExitCode::SUCCESS)
}
