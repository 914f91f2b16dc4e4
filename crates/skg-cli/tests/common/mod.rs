//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use skg_core::scene::{Overrides, Scene, SceneFile};
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
}

/// Rows of a results directory's `results.csv` by id (each line must have the header's
/// field count and the file must end with a complete line).
pub fn rows_by_id(dir: &Path) -> (skg_sweep::Results, std::collections::HashMap<String, usize>) {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    assert!(text.ends_with('\n'), "results.csv ends with a complete line");
    let r = skg_sweep::Results::read(dir).unwrap();
    let id = r.column_index("id").unwrap();
    let mut count = std::collections::HashMap::new();
    for row in &r.rows {
        assert_eq!(row.len(), r.header.len());
        *count.entry(row[id].clone()).or_insert(0) += 1;
    }
    (r, count)
}
