//! skg-solve: the motion of mechanical systems with velocity constraints, walls and
//! friction from the critical point of the discretized Schwinger–Keldysh–Galley action.
//!
//! Data flows one way through the modules; each uses only modules listed before it:
//!
//! 1. [`sbp`] (the
//!    summation-by-parts operators) and [`scene`]: the TOML scene, validated and
//!    resolved to numbers ([`scene::Scene`]); [`memory`]: what a solve or a
//!    reference of a scene would need, checked before anything is allocated.
//! 2. [`model`]: the scene's expressions, their exact derivatives compiled into tapes
//!    ([`expr`]), and the walls' geometry; [`contact`]: when a node is in contact with
//!    a wall.
//! 3. [`action`]: the SBP-discretized action on the time grid and its derivatives.
//! 4. [`trajectory`]: the states at the nodes with their physical columns, the common
//!    result type; [`ode`] (DOP853) and [`time_stepping`]: the index-reduced
//!    Lagrange–d'Alembert equations of a model integrated in time.
//! 5. [`newton`] (Newton's method with a sparse LU) and [`backend`]: the solvers of the
//!    square system, Ipopt ([`ipopt`]) or Newton; [`solve`]: the square system ∇S = 0
//!    handed to the backend from a time-stepping initial guess, and its diagnostics
//!    ([`solve::Outcome`]); [`verify`]: the solution compared with time stepping of the
//!    same scene; [`window`]: a span solved in windows; [`ladder`]: the scene's own
//!    solve and the fallback ladder, what [`solve::solve_scene`] runs;
//!    [`reference`](mod@reference): reference solutions by time stepping, regularized
//!    or with hard walls.
//! 6. [`output`]: writes what solve and reference produced (CSV, JSON), atomically.
//! 7. Consumers of results: [`check`] (a trajectory against a reference),
//!    [`convergence`] (observed orders), [`tune`] (the wall width σ).
#![warn(missing_docs)]
// Numerical kernels index several arrays by the same node/coordinate index; the
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod check;
pub mod convergence;
pub mod discrete;
pub mod memory;
pub mod model;
pub mod output;
pub mod sbp;
pub mod scene;
pub mod solve;
pub mod stepping;
pub mod tune;

pub use skg_expr as expr;
pub use skg_ipopt as ipopt;

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
