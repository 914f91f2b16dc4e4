//! The convergence study of the shipped scenes against their regularized references and
//! the tumbler's σ ladder: the tables of docs/validation.md ("Convergence against the
//! references", "Model error and the wall width").
//!
//! For each shipped scene of the study, on its ladder of grids, and each of SBP121,
//! SBP242 and SBP363: one solve of the scene (no fallback ladder), the largest error of
//! its coordinates against the regularized reference on the same grid (last two nodes
//! excluded), the order between each pair of grids, the solve's time and the
//! least-squares order over the ladder (round-off plateau masked). Then, for the tumbler
//! at N = 256 and σ from 1/10 to 1/110, the distance from the hard-wall reference (the
//! model error) and from the regularized one (the discretization error). It prints
//! Markdown tables; `tests/regression.rs` asserts the errors and orders it measured.
//!
//! Run it with `cargo run --release -p skg-core --example reference_convergence_study`
//! (a few seconds).

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/studies/reference_errors.rs"]
mod reference_errors;

use reference_errors::{model_error, try_discretization_error};
use skg_core::convergence::{fit_order, pairwise_orders};

/// (scene, N ladder) of the study.
const STUDY: &[(&str, &[usize])] = &[
    ("free_fall", &[16, 32, 64, 128]),
    ("rolling_disk", &[32, 64, 128, 256]),
    ("tumbler", &[256, 512, 1024]),
    ("incline_friction", &[64, 128, 256, 512]),
    ("incline_frictionless", &[64, 128, 256, 512]),
    ("knife_edge", &[32, 64, 128, 256]),
    ("driven_oscillator", &[64, 128, 256, 512]),
    ("pendulum", &[64, 128, 256, 512]),
    ("vibrating_plate", &[256, 512, 1024, 2048]),
];

/// The operators of the study.
const OPERATORS: &[&str] = &["SBP121", "SBP242", "SBP363"];

fn main() {
    convergence_table();
    println!();
    sigma_ladder_table();
}

/// The discretization error of every scene and operator of [`STUDY`] on its ladder.
fn convergence_table() {
    println!("| scene | operator | N | max error of q | pairwise order | solve s |");
    println!("|---|---|---:|---:|---:|---:|");
    for (name, ns) in STUDY {
        for op in OPERATORS {
            let mut errs = Vec::new();
            let mut hs = Vec::new();
            for &n in *ns {
                let t = std::time::Instant::now();
                let (e, o) = try_discretization_error(name, n, op);
                let s = t.elapsed().as_secs_f64();
                if !o.converged() {
                    println!("| {name} | {op} | {n} | no convergence ({}, {} iterations) | | {s:.2} |", o.status, o.iterations);
                    continue;
                }
                hs.push(1.0 / (n as f64 - 1.0));
                errs.push(e);
                let ord = if errs.len() > 1 { format!("{:.2}", pairwise_orders(&hs, &errs).last().unwrap()) } else { String::new() };
                println!("| {name} | {op} | {n} | {e:.3e} | {ord} | {s:.2} |");
            }
            let fit = fit_order(&hs, &errs, 1e-11);
            println!("| {name} | {op} | fit | {fit:?} | | |");
        }
    }
}

/// The tumbler's model and discretization errors at N = 256 as σ shrinks.
fn sigma_ladder_table() {
    println!("| σ | model error (x, y vs hard wall) | discretization error (vs regularized) |");
    println!("|---|---:|---:|");
    for k in [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110] {
        let (m, d) = model_error(&format!("1/{k}"), 256);
        println!("| 1/{k} | {m:.3e} | {d:.3e} |");
    }
}
