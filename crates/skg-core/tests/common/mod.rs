//! Helpers shared by the integration tests: the repository's scenes, loading and
//! solving them, closed forms, a seeded random generator.
//!
//! The tests of the crates above skg-core include this file too (skg-sweep's
//! `tests/common/mod.rs` by its path, and skg-cli's through skg-sweep's), so that each
//! crate's tests get these helpers without a copy and without skg-core's tests
//! depending on a crate above it. Only the standard library and skg-core are used here.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use skg_core::discrete::action::Action;
use skg_core::scene::{Overrides, Scene, SceneFile};
use skg_core::solve::{self, Outcome};

/// The repository's root (every crate whose tests include this file lives in
/// `crates/<name>`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repository root")
}

/// Path of a shipped scenario.
pub fn scenario(name: &str) -> PathBuf {
    root().join("scenarios").join(format!("{name}.toml"))
}

/// Standard gravity of the shipped scenes (`g = 9.8`).
pub const G: f64 = 9.8;

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

/// Path of a scene written for the tests (crates/skg-core/tests/scenes).
pub fn test_scene(name: &str) -> PathBuf {
    root().join("crates/skg-core/tests/scenes").join(format!("{name}.toml"))
}

/// Load and resolve a test scene.
pub fn load_test_scene(name: &str, ov: &Overrides) -> Scene {
    SceneFile::load(&test_scene(name)).unwrap().resolve(ov).unwrap()
}

/// A variant of a shipped scene with text replaced (each `from` must occur), written to
/// `dir/name`.
pub fn variant(dir: &Path, scene: &str, name: &str, replacements: &[(&str, &str)]) -> PathBuf {
    let mut s = std::fs::read_to_string(scenario(scene)).unwrap();
    for (from, to) in replacements {
        assert!(s.contains(from), "{from} not in {scene}");
        s = s.replacen(from, to, 1);
    }
    let p = dir.join(name);
    std::fs::write(&p, s).unwrap();
    p
}

/// A small seeded generator (xorshift64*), so that randomized tests are reproducible
/// and need no dependency.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in [0, n) (0 for n = 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }
}

/// A random point near the initial state: plus coordinates perturbed around the
/// initial values, every other unknown random of order one.
pub fn random_point(action: &Action, rng: &mut Rng) -> Vec<f64> {
    let lay = &action.layout;
    let mut z: Vec<f64> = (0..lay.len()).map(|_| rng.signed()).collect();
    for k in 0..lay.nodes {
        for i in 0..lay.d {
            z[lay.qp[k * lay.d + i] as usize] = action.q0()[i] + 0.05 * rng.signed();
        }
    }
    z
}
