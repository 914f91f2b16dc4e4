//! What a solve costs, relative to others: the measured time per node of each operator
//! on each backend, for choosing the cheapest discretization that meets a tolerance
//! ([`refine`](super::refine)).
//!
//! The time of a solve and its verification grows linearly with N on both backends
//! (docs/benchmarks.md), with a factor per node that depends on the operator's stencil:
//! wider stencils mean more Jacobian entries per node and, for MUMPS, more fill. Measured
//! with `skg-solve bench` on the rolling disk (4 coordinates, 2 constraints: the shipped
//! scene with the most unknowns per node, where the operators differ most), release
//! build, N = 4096, solve and verification per node, relative to `SBP242`:
//!
//! | operator | Newton µs/node | relative | Ipopt µs/node | relative |
//! |---|---:|---:|---:|---:|
//! | SBP121 | 20.5 | 0.94 | 120 | 0.92 |
//! | SBP242 | 21.9 | 1 | 130 | 1 |
//! | SBP363 | 25.6 | 1.17 | 215 | 1.65 |
//! | SBP484 | 30.1 | 1.37 | 452 | 3.5 |
//! | SBP121-AD | 24.6 | 1.12 | 120 | 0.92 |
//! | SBP242-AD | 30.7 | 1.40 | 135 | 1.04 |
//! | SBP363-AD | 35.8 | 1.63 | 199 | 1.53 |
//! | SBP484-AD | 43.7 | 2.00 | 306 | 2.35 |
//!
//! On Ipopt a dissipative operator costs what its centred one does (within the spread of
//! repeated runs). On Newton, whose LU uses SIMD kernels and one factorization per solve,
//! the dissipative operators' wider, unsymmetric stencils show: 1.2–1.45× their centred
//! ones (Newton best of five, Ipopt best of three; docs/benchmarks.md). The choice still counts a dissipative
//! operator at its centred one's cost, on both backends: on a contracting scene only a
//! dissipative operator verifies, and the prediction does not see the centred ones'
//! odd-even mode. With the measured costs, the damped oscillator on Newton at tolerances
//! 1e-3 … 1e-8 first solved `SBP484` and failed (two grids at every tolerance); counted
//! at the centred cost, `SBP484-AD` verifies on the first grid (at 1e-3, 1e-5, 1e-8).
//! On the tumbler (2 coordinates) the four centred operators cost within 1.5× of each
//! other on both backends: the table errs toward the lower orders on small scenes. The
//! initial-velocity condition does not change the cost.

use crate::sbp::OperatorKind;
use crate::scene::Backend;

/// The time per node of a solve with `operator` on `backend`, relative to `SBP242` on
/// the same backend (see the module docs).
pub fn relative_cost_per_node(operator: OperatorKind, backend: Backend) -> f64 {
    use OperatorKind::*;
    // A dissipative operator is counted at its centred one's cost (module docs).
    match (backend, operator.centred()) {
        (Backend::Newton, Sbp121) => 0.94,
        (Backend::Newton, Sbp363) => 1.17,
        (Backend::Newton, Sbp484) => 1.37,
        (Backend::Ipopt, Sbp121) => 0.92,
        (Backend::Ipopt, Sbp363) => 1.65,
        (Backend::Ipopt, Sbp484) => 3.5,
        _ => 1.0,
    }
}

/// The relative cost of a solve with `operator` on `nodes` nodes.
pub fn relative_cost(operator: OperatorKind, backend: Backend, nodes: usize) -> f64 {
    relative_cost_per_node(operator, backend) * nodes as f64
}

/// Seconds of a whole solve per unit of [`relative_cost`] on `backend`, for estimates of
/// wall time (a sweep's plan), not for choosing: the wall time per node of an `SBP242`
/// solve as [`solve_scene`](crate::solve::solve_scene) runs it (setup, guess, solve and
/// verification), measured as sweep points on the rolling disk at N = 4096 (`wall_s` of
/// results.csv, release build, one worker, the 2-core machine shared with other work):
/// Newton 34 µs, Ipopt 81 µs. From N = 1024 to 16384 the disk took 29–42 and 81–145 µs,
/// the tumbler (fewer unknowns per node, but walls) 33–52 and 42–60 µs.
pub fn seconds_per_cost(backend: Backend) -> f64 {
    match backend {
        Backend::Newton => 34e-6,
        Backend::Ipopt => 81e-6,
    }
}
