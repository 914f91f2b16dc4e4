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
//! | SBP121 | 45 | 0.92 | 120 | 0.92 |
//! | SBP242 | 49 | 1 | 130 | 1 |
//! | SBP363 | 65 | 1.33 | 215 | 1.65 |
//! | SBP484 | 91 | 1.86 | 452 | 3.5 |
//!
//! On the tumbler (2 coordinates) the four cost within 1.5× of each other on both
//! backends: the table errs toward the lower orders on small scenes. The initial
//! velocity condition does not change the cost, and a dissipative operator costs what
//! its centred one does (measured the same way: 44, 49, 62, 71 µs per node on Newton,
//! 120, 135, 199, 306 on Ipopt, within the spread of repeated runs of the table's).

use crate::sbp::OperatorKind;
use crate::scene::Backend;

/// The time per node of a solve with `operator` on `backend`, relative to `SBP242` on
/// the same backend (see the module docs).
pub fn relative_cost_per_node(operator: OperatorKind, backend: Backend) -> f64 {
    match (backend, operator.centred()) {
        (_, OperatorKind::Sbp121) => 0.92,
        (Backend::Newton, OperatorKind::Sbp363) => 1.33,
        (Backend::Ipopt, OperatorKind::Sbp363) => 1.65,
        (Backend::Newton, OperatorKind::Sbp484) => 1.86,
        (Backend::Ipopt, OperatorKind::Sbp484) => 3.5,
        _ => 1.0,
    }
}

/// The relative cost of a solve with `operator` on `nodes` nodes.
pub fn relative_cost(operator: OperatorKind, backend: Backend, nodes: usize) -> f64 {
    relative_cost_per_node(operator, backend) * nodes as f64
}
