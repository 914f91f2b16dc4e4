//! The truth of the dissipative operators' study and the study itself, shared by
//! `tests/dissipative.rs` and `examples/dissipative_order_study.rs` (each includes this
//! file by its path, beside `tests/common/mod.rs` as `common`).
//!
//! Truth is a closed form (the damped oscillator, the rolling disk, the knife edge) or a
//! classical Runge–Kutta integration, written here, of equations derived by hand for the
//! scene (the 2-D contracting scene, the block on the incline, the pendulum), at a step
//! far below the grid's: never the tool's own output.
#![allow(dead_code)]

use skg_core::convergence::fit_order;
use skg_core::scene::{Backend, InitialVelocity, Overrides};
use skg_core::solve::{self, Outcome};

use crate::common;

/// Overrides for one global solve (no fallback ladder) on `nodes` with `operator`, the
/// initial velocity condition `iv` and `backend`.
pub fn global(nodes: usize, operator: &str, iv: InitialVelocity, backend: Backend) -> Overrides {
    Overrides { initial_velocity: Some(iv), backend: Some(backend), ..common::grid(nodes, operator) }
}

/// Classical fourth-order Runge–Kutta for `y' = f(t, y)` from `t0`, `y0`, with steps of
/// at most `h`, sampled at `times` (ascending, from `t0`).
pub fn rk4(f: impl Fn(f64, &[f64]) -> Vec<f64>, t0: f64, y0: &[f64], times: &[f64], h: f64) -> Vec<Vec<f64>> {
    let axpy = |y: &[f64], a: f64, k: &[f64]| -> Vec<f64> { y.iter().zip(k).map(|(y, k)| y + a * k).collect() };
    let mut out = Vec::with_capacity(times.len());
    let (mut t, mut y) = (t0, y0.to_vec());
    for &target in times {
        while t < target {
            let dt = h.min(target - t);
            let k1 = f(t, &y);
            let k2 = f(t + dt / 2.0, &axpy(&y, dt / 2.0, &k1));
            let k3 = f(t + dt / 2.0, &axpy(&y, dt / 2.0, &k2));
            let k4 = f(t + dt, &axpy(&y, dt, &k3));
            y = (0..y.len()).map(|i| y[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])).collect();
            t = if target - t <= h { target } else { t + dt };
        }
        out.push(y.clone());
    }
    out
}

/// The damped oscillator's closed form (scenarios/damped_oscillator.toml: m = 1, k = 4,
/// c = 3, x0 = 1, v0 = 0).
pub fn damped_exact(t: f64) -> Vec<f64> {
    let (m, k, c, x0, v0) = (1.0_f64, 4.0_f64, 3.0_f64, 1.0_f64, 0.0_f64);
    let w = (k / m - c * c / (4.0 * m * m)).sqrt();
    vec![(-c * t / (2.0 * m)).exp() * (x0 * (w * t).cos() + (v0 + c * x0 / (2.0 * m)) / w * (w * t).sin())]
}

/// crates/skg-core/tests/scenes/overdamped_2d.toml by hand: L = ½(ẋ² + ẏ²) − ½(x² + 4y²)
/// − x⁴/4, forces −c ẋ and −c ẏ − x ẏ, c = 10, from (2, −1) with velocity (0, 3):
/// ẍ = −x − x³ − c ẋ, ÿ = −4y − (c + x) ẏ.
pub fn overdamped_truth(times: &[f64]) -> Vec<Vec<f64>> {
    let c = 10.0;
    let f = |_t: f64, s: &[f64]| vec![s[2], s[3], -s[0] - s[0].powi(3) - c * s[2], -4.0 * s[1] - (c + s[0]) * s[3]];
    rk4(f, 0.0, &[2.0, -1.0, 0.0, 3.0], times, 2e-4).into_iter().map(|s| vec![s[0], s[1]]).collect()
}

/// crates/skg-core/tests/scenes/incline_stop.toml by hand: the block stays at the distance
/// d0 from the plane (the wall's force balances the normal part of gravity, friction acts
/// along the slope), and its distance s down the slope obeys
/// s̈ = g sin α − μ g cos α ṡ/√(ṡ² + ε²); (x, y) = (x0, y0) + s (−cos α, −sin α).
pub fn incline_truth(times: &[f64]) -> Vec<Vec<f64>> {
    let (m, g, alpha, mu, v0, a, sigma, eps) = (1.0_f64, 9.8_f64, std::f64::consts::PI / 6.0, 0.8, 2.0, 2.0, 0.01, 1e-3);
    let d0 = sigma * (2.0 * (a / ((2.0 * std::f64::consts::PI).sqrt() * sigma * m * g * alpha.cos())).ln()).sqrt();
    let (x0, y0) = (-d0 * alpha.sin(), d0 * alpha.cos());
    // At rest the friction is a damper of rate μ g cos α / ε = 6.8e3 /s: RK4 needs steps
    // below 2.8/6.8e3 = 4e-4 s to be stable there; 2e-5 s resolves it.
    let f = |_t: f64, s: &[f64]| vec![s[1], g * alpha.sin() - mu * g * alpha.cos() * s[1] / (s[1] * s[1] + eps * eps).sqrt()];
    rk4(f, 0.0, &[0.0, v0], times, 2e-5).into_iter().map(|s| vec![x0 - s[0] * alpha.cos(), y0 - s[0] * alpha.sin()]).collect()
}

/// scenarios/pendulum.toml by hand: θ̈ = −(g/l) sin θ from θ0 = 1 at rest,
/// (x, y) = l (sin θ, −cos θ).
pub fn pendulum_truth(times: &[f64]) -> Vec<Vec<f64>> {
    let (g, l) = (common::G, 1.0_f64);
    let f = |_t: f64, s: &[f64]| vec![s[1], -(g / l) * s[0].sin()];
    rk4(f, 0.0, &[1.0, 0.0], times, 1e-4).into_iter().map(|s| vec![l * s[0].sin(), -l * s[0].cos()]).collect()
}

/// The truth of a scene at times `t`.
pub fn truth(scene: &str, t: &[f64]) -> Vec<Vec<f64>> {
    match scene {
        "damped_oscillator" => t.iter().map(|&t| damped_exact(t)).collect(),
        "overdamped_2d" => overdamped_truth(t),
        "incline_stop" => incline_truth(t),
        "pendulum" => pendulum_truth(t),
        "rolling_disk" => t.iter().map(|&t| common::rolling_disk_exact(t)).collect(),
        "knife_edge" => t.iter().map(|&t| common::knife_edge_exact(t)).collect(),
        other => panic!("no truth for {other}"),
    }
}

/// Solve a shipped scene or a test scene with `ov`.
pub fn solve_any(scene: &str, ov: &Overrides) -> Outcome {
    let s = if common::scenario(scene).exists() { common::load(scene, ov) } else { common::load_test_scene(scene, ov) };
    solve::solve_scene(&s).unwrap()
}

/// Errors against the truth on a ladder of grids (every node but the last two, the
/// end closure, as the accuracy studies of the documentation) and the fitted order.
/// A grid whose solve does not converge is left out (`skip_failed`, for the measurement)
/// or fails the test.
pub fn study(scene: &str, operator: &str, ladder: &[usize], skip_failed: bool) -> (Vec<f64>, Option<f64>) {
    let mut h = Vec::new();
    let mut errors = Vec::new();
    for &n in ladder {
        let o = solve_any(scene, &global(n, operator, InitialVelocity::Strong, Backend::Newton));
        if !o.converged() && skip_failed {
            println!("| {scene} | {operator} | N = {n} did not converge | |");
            continue;
        }
        assert!(o.converged(), "{scene} {operator} N = {n}: {}", o.status);
        let truth = truth(scene, &o.trajectory.t);
        let keep = o.trajectory.t.len() - 2;
        let d = truth[0].len();
        let e = (0..keep)
            .flat_map(|k| (0..d).map(move |i| (k, i)))
            .map(|(k, i)| (o.trajectory.q[k][i] - truth[k][i]).abs())
            .fold(0.0, f64::max);
        h.push(1.0 / (n as f64 - 1.0));
        errors.push(e);
    }
    let order = fit_order(&h, &errors, 1e-11).map(|fit| fit.order);
    (errors, order)
}

/// The order study: (scene, centred operator, ladder), each ladder in the operators'
/// asymptotic range (the centred operators' coarser grids are pre-asymptotic, some from
/// above: SBP363 on the pendulum shows 7.5 between N = 96 and 128).
pub const ORDER_STUDY: &[(&str, &str, &[usize])] = &[
    ("rolling_disk", "SBP121", &[64, 128, 256]),
    ("rolling_disk", "SBP242", &[64, 128, 256]),
    ("rolling_disk", "SBP363", &[128, 256, 512]),
    ("rolling_disk", "SBP484", &[256, 384, 512]),
    ("knife_edge", "SBP121", &[64, 128, 256]),
    ("knife_edge", "SBP242", &[64, 128, 256]),
    ("knife_edge", "SBP363", &[128, 256, 512]),
    ("knife_edge", "SBP484", &[256, 384, 512]),
    ("pendulum", "SBP121", &[256, 384, 512]),
    ("pendulum", "SBP242", &[128, 256, 512]),
    ("pendulum", "SBP363", &[128, 256, 512]),
    ("pendulum", "SBP484", &[256, 384, 512]),
];
