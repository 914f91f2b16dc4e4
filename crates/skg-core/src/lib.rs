//! skg-solve: the motion of mechanical systems with velocity constraints, walls and
//! friction from the critical point of the discretized Schwinger–Keldysh–Galley action.
//!
//! # The flow
//!
//! A scene file is resolved into a [`Scene`], built into a [`Model`] (exact derivatives
//! compiled into tapes), discretized on the time grid (the action of [`discrete`]),
//! solved for the whole trajectory at once ([`solve_scene`]: the square system ∇S = 0,
//! verified against time stepping of the same scene, with a fallback ladder) and written
//! ([`output`]). Each stage is a module that uses only the stages before it:
//!
//! ```text
//! convergence, sbp → scene → memory → model → discrete → stepping → solve → output → check, tune, fit
//! ```
//!
//! 1. [`convergence`]: observed orders of a refinement study; [`sbp`]: the
//!    summation-by-parts operators (both numbers only, no scene).
//! 2. [`scene`]: the TOML file, validated and resolved to numbers ([`Scene`]), and the
//!    [`provenance`](scene::provenance) every written file carries; [`memory`]: what a
//!    solve or a reference of a scene would need, checked before anything is allocated.
//! 3. [`model`]: the scene's expressions, their exact derivatives compiled into tapes
//!    ([`expr`]), the physical quantities and the walls' geometry.
//! 4. [`discrete`]: the SBP-discretized action on the time grid, the [`Trajectory`] at
//!    the nodes, and contact at the nodes.
//! 5. [`stepping`]: the DOP853 integrator, the model's equations integrated in time, the
//!    verification of a trajectory against them, and reference solutions.
//! 6. [`solve`]: Newton's method and the backends (Ipopt through [`ipopt`], or Newton),
//!    one solve of one action, runs in one piece or in windows, and the fallback ladder,
//!    whose entry point is [`solve_scene`] ([`Outcome`]).
//! 7. [`output`]: writes what a solve and a reference produced (CSV, JSON), atomically,
//!    by the pairing rule, into locked directories.
//! 8. Consumers of results: [`check`] (a trajectory against a reference) and [`tune`]
//!    (the wall width σ); `fit` (with the `ipopt` feature): parameters and initial data
//!    estimated from measured motion, with Ipopt as the optimizer.
//!
//! # Example
//!
//! Free fall solved with the Newton backend on SBP242, whose fourth-order interior and
//! second-order boundary closure differentiate the quadratic closed form
//! `x(t) = v₀ t − g t²/2` exactly, so the solution matches it to round-off:
//!
//! ```
//! use skg_core::{solve_scene, Overrides, SceneFile};
//!
//! let text = r#"
//! [scene]
//! name = "free fall"
//! lagrangian = "x_dot^2/2 - g*x"
//!
//! [parameters]
//! g = 9.81
//!
//! [[coordinates]]
//! name = "x"
//! initial = 0
//! velocity = 2
//!
//! [time]
//! start = 0
//! end = 1
//! nodes = 32
//!
//! [solver]
//! backend = "newton"
//! "#;
//! let scene = SceneFile::parse(text, "free_fall.toml")?.resolve(&Overrides::default())?;
//! let outcome = solve_scene(&scene)?;
//! // Converged, and verified against time stepping of the same scene.
//! assert!(outcome.trusted(), "{}", outcome.verification.reason);
//! let tr = &outcome.trajectory;
//! let exact = |t: f64| 2.0 * t - 9.81 * t * t / 2.0;
//! let error = tr.t.iter().zip(&tr.q).map(|(&t, q)| (q[0] - exact(t)).abs()).fold(0.0, f64::max);
//! assert!(error < 1e-10, "max |x − (v₀t − gt²/2)| = {error:e}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]
// Numerical kernels index several arrays by the same node/coordinate index; the
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

// The stages, in the order of the flow: each uses only the ones above it.
pub mod convergence;
pub mod sbp;

pub mod scene;

pub mod memory;

pub mod model;

pub mod discrete;

pub mod stepping;

pub mod solve;

pub mod output;

pub mod check;
#[cfg(feature = "ipopt")]
pub mod fit;
pub mod tune;

pub use discrete::Trajectory;
pub use model::Model;
pub use scene::{Overrides, Scene, SceneError, SceneFile};
pub use skg_expr as expr;
#[cfg(feature = "ipopt")]
pub use skg_ipopt as ipopt;
pub use solve::{solve_scene, Outcome, SolveError};

/// The text of an error and its causes, joined by `: ` like anyhow's `{:#}`, each text
/// once (many errors already include their source's message in their own): what the
/// command line prints after `error: ` and the message of the Python module's exceptions.
pub fn error_text(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(e);
    while let Some(c) = cause {
        let t = c.to_string();
        if !text.contains(&t) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&t);
        }
        cause = c.source();
    }
    text
}
