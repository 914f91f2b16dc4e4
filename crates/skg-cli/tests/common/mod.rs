//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use skg_core::scenario::{Overrides, Scene, SceneFile};
use skg_core::solve::{self, Outcome};

/// The repository's root (this crate lives in `crates/skg-cli`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repository root")
}

/// Path of a shipped scenario.
pub fn scenario(name: &str) -> PathBuf {
    root().join("scenarios").join(format!("{name}.toml"))
}

/// Standard gravity of the shipped scenes (`g = 9.8`).
pub const G: f64 = 9.8;

/// Write `dir/sweep.toml` whose base scene is `scene`, followed by `body`.
pub fn sweep_file(dir: &Path, scene: &Path, body: &str) -> PathBuf {
    let p = dir.join("sweep.toml");
    let text = format!("[sweep]\nscene = \"{}\"\n{body}", scene.display());
    std::fs::write(&p, text).unwrap();
    p
}

/// Every shipped scene.
pub const SHIPPED: &[&str] = &[
    "free_fall",
    "rolling_disk",
    "tumbler",
    "incline_friction",
    "incline_frictionless",
    "knife_edge",
    "driven_oscillator",
    "pendulum",
    "vibrating_plate",
];

pub fn load(name: &str, ov: &Overrides) -> Scene {
    SceneFile::load(&scenario(name)).unwrap().resolve(ov).unwrap()
}

pub fn solve(name: &str, ov: &Overrides) -> Outcome {
    let scene = load(name, ov);
    let o = solve::solve_scene(&scene).unwrap();
    assert!(o.converged(), "{name}: {} after {} iterations, residual {:e}", o.status, o.iterations, o.diagnostics.max_residual);
    o
}

/// Overrides with a node count and operator.
/// The scene's own solve is reported (no fallback ladder): the studies of the
/// discretization measure the plain SBP solution at every grid, verified or not.
pub fn grid(nodes: usize, operator: &str) -> Overrides {
    Overrides { nodes: Some(nodes), operator: Some(operator.parse().unwrap()), no_fallback: true, ..Default::default() }
}

/// max over nodes 0..N-skip and the given coordinates of |q - exact(t)|.
pub fn max_error(o: &Outcome, coords: &[usize], skip_last: usize, exact: impl Fn(f64) -> Vec<f64>) -> f64 {
    let tr = &o.trajectory;
    let n = tr.t.len() - skip_last;
    let mut e = 0.0_f64;
    for k in 0..n {
        let ex = exact(tr.t[k]);
        for &i in coords {
            e = e.max((tr.q[k][i] - ex[i]).abs());
        }
    }
    e
}

/// Run the `skg-solve` binary with `args` in the working directory `dir`.
pub fn skg(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skg-solve")).args(args).current_dir(dir).output().unwrap()
}

/// Everything a run printed: stdout, then stderr.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// The rolling disk's closed form (docs/scenes.md): (x, y, θ, φ) at t, with
/// `k = g sin α / (1 + I_S/(M R²))`.
pub fn rolling_disk_exact(t: f64) -> Vec<f64> {
    let k = G * 0.5 / 1.5;
    vec![
        5.0 * t.sin() + k * t.sin().powi(2) / 2.0,
        5.0 * (1.0 - t.cos()) + k * (t / 2.0 - (2.0 * t).sin() / 4.0),
        5.0 * t + k * (1.0 - t.cos()),
        t,
    ]
}

/// The knife edge's closed form (scenarios/knife_edge.toml, ω = 2, u0 = 1, α = π/6):
/// (x, y, φ) at t.
pub fn knife_edge_exact(t: f64) -> Vec<f64> {
    let (w, u0, gs) = (2.0, 1.0, G * 0.5);
    let s = (w * t).sin();
    vec![
        u0 * s / w + gs / (2.0 * w * w) * s * s,
        u0 * (1.0 - (w * t).cos()) / w + gs / (2.0 * w) * (t - (2.0 * w * t).sin() / (2.0 * w)),
        w * t,
    ]
}

/// Path of a scene written for the tests (crates/skg-cli/tests/scenes).
pub fn test_scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/scenes").join(format!("{name}.toml"))
}

/// Load and resolve a test scene.
pub fn load_test_scene(name: &str, ov: &Overrides) -> Scene {
    SceneFile::load(&test_scene(name)).unwrap().resolve(ov).unwrap()
}
