//! Memory estimates: a solve or a reference on a huge grid is refused before anything
//! is allocated, with a message that states the estimate and the limit, instead of
//! running out of memory (or panicking on a capacity overflow) part-way.
//!
//! The estimates are fits to the measured peak resident memory of whole solves
//! (verification and files included; release build, Debian's Ipopt 3.11.9 with MUMPS
//! 5.5, QAMD ordering and scaling 7 for position constraints): the shipped scenes at N
//! from 4096 to 10⁶, chains of 8 to 32 links in Cartesian coordinates (24 to 96
//! unknowns per node), the operators and formulations, solves in windows.
//! docs/benchmarks.md#memory lists the measurements and the ratios. A solve needs
//!
//! * a base of [`BASE_BYTES`] (the process, the tapes, Ipopt and MUMPS workspaces);
//! * what it keeps of the whole span, [`TRAJECTORY_BYTES_PER_CELL`] per node and CSV
//!   column (the trajectory, the guess, the verification's reference, the rows written);
//! * the system of the nodes solved at once: all N nodes of a global solve, one
//!   window's `round(length/Δt) + 1` nodes of a solve in windows (the windows reuse
//!   one system). Per node it needs `a · u + c · u²` bytes, `u = d + n` the unknowns
//!   per node: `a` ([`IPOPT_BYTES_PER_UNKNOWN`], [`NEWTON_BYTES_PER_UNKNOWN`]) for what
//!   grows with the unknowns (the Jacobian, the KKT matrix, the vectors), `c`
//!   ([`IPOPT_BYTES_PER_PAIR`], [`NEWTON_BYTES_PER_PAIR`]) for the factors, whose
//!   blocks fill up as the coupling of a node's unknowns does (a chain's links).
//!   SBP121 needs about 0.6 times, SBP363 1.6 and SBP484 2.2 times the system of SBP242
//!   (the dissipative operators 1.1, 1.6, 2.0 and 2.5 times), the full formulation 3
//!   times. MUMPS's fill per node stays about constant in N (the disk: 20 kB per node
//!   at N = 4096, 18 kB at 65536, with the process's other memory).
//!
//! Every measurement lies between a third of the estimate and the estimate (a test
//! checks the measurements written down in crates/skg-core/tests/memory.rs). The
//! estimate is of the backend the scene chooses: a Newton solve that fails and hands
//! its system over to Ipopt needs Ipopt's memory, up to 2.7 times Newton's (the knife
//! edge). The fallback ladder's attempts keep their trajectories, so a ladder that runs
//! several needs more than its first solve; the estimate is of that first solve. A
//! reference needs half the base and, per sample, [`REFERENCE_BYTES_PER_SAMPLE`],
//! [`REFERENCE_BYTES_PER_CELL`] per CSV column and [`REFERENCE_BYTES_PER_PAIR`] per
//! pair of coordinates (measured: 0.75 kB per sample for the free fall, 104 kB for a
//! chain of 32 links). The limit is the memory the kernel reports as available
//! (`MemAvailable` in `/proc/meminfo`); where that cannot be read, nothing is refused.
//! Reading one line of `/proc/meminfo` needs no crate (`sysinfo` would bring a large
//! dependency for it).
//!
//! **Place in the flow.** Right after the scene: it uses only [`sbp`](crate::sbp) and
//! [`scene`](crate::scene) (an estimate needs the resolved scene, nothing built from
//! it), so that whatever allocates later can ask it first.

use crate::sbp::OperatorKind;
use crate::scene::{Backend, Formulation, Location, Scene, SceneError};

/// Bytes of a solve independent of the grid (the process, tapes, Ipopt, MUMPS).
pub const BASE_BYTES: f64 = 15.0e6;
/// Bytes a solve keeps per node and CSV column of the whole span.
pub const TRAJECTORY_BYTES_PER_CELL: f64 = 260.0;
/// Bytes per node and unknown of Ipopt's system (SBP242, reduced).
pub const IPOPT_BYTES_PER_UNKNOWN: f64 = 2700.0;
/// Bytes per node and pair of unknowns of Ipopt's system (MUMPS's factors).
pub const IPOPT_BYTES_PER_PAIR: f64 = 270.0;
/// Bytes per node and unknown of the Newton backend's system.
pub const NEWTON_BYTES_PER_UNKNOWN: f64 = 720.0;
/// Bytes per node and pair of unknowns of the Newton backend's system (the LU). Fitted to
/// the chains, whose LU is in single precision (docs/solver.md#mixed-precision); their
/// double-precision factors (a chain below 10 000 unknowns, or one that falls back to
/// double precision) take up to 1.6 times as much and stay below the estimate.
pub const NEWTON_BYTES_PER_PAIR: f64 = 120.0;
/// Bytes a reference keeps per sample, besides its columns.
pub const REFERENCE_BYTES_PER_SAMPLE: f64 = 800.0;
/// Bytes a reference keeps per sample and CSV column.
pub const REFERENCE_BYTES_PER_CELL: f64 = 32.0;
/// Bytes a reference keeps per sample and pair of coordinates.
pub const REFERENCE_BYTES_PER_PAIR: f64 = 32.0;

/// The columns of the scene's trajectory CSV, as the estimates count them (an upper
/// bound of `trajectory_header`'s count).
fn columns(scene: &Scene) -> f64 {
    (1 + 2 * scene.coordinates.len() + 3 * scene.constraints.len() + 2 * scene.walls.len() + 2) as f64
}

/// The nodes of the system a solve of `scene` on `nodes` nodes solves at once: one
/// window's when it is solved in windows, else all.
pub fn system_nodes(scene: &Scene, nodes: usize) -> f64 {
    match scene.windows {
        Some(w) => {
            let dt = (scene.t_end - scene.t_start) / (nodes as f64 - 1.0);
            ((w.length / dt).round() + 1.0).min(nodes as f64)
        }
        None => nodes as f64,
    }
}

/// Estimated peak memory in bytes of solving `scene` on its own grid with its own
/// operator (see the module documentation).
pub fn solve_bytes(scene: &Scene) -> f64 {
    solve_bytes_with(scene, scene.operator, scene.nodes)
}

/// Estimated peak memory in bytes of solving `scene` with `operator` on `nodes` nodes
/// (see the module documentation).
pub fn solve_bytes_with(scene: &Scene, operator: OperatorKind, nodes: usize) -> f64 {
    let unknowns = (scene.coordinates.len() + scene.constraints.len()) as f64;
    let stencil = match operator {
        OperatorKind::Sbp121 => 0.6,
        OperatorKind::Sbp242 => 1.0,
        OperatorKind::Sbp121Ad => 1.1,
        OperatorKind::Sbp363 | OperatorKind::Sbp242Ad => 1.6,
        OperatorKind::Sbp363Ad => 2.0,
        OperatorKind::Sbp484 => 2.2,
        OperatorKind::Sbp484Ad => 2.5,
    };
    let formulation = if scene.formulation == Formulation::Full { 3.0 } else { 1.0 };
    let n = system_nodes(scene, nodes);
    let (per_unknown, per_pair) = match scene.solver.backend {
        Backend::Ipopt => (IPOPT_BYTES_PER_UNKNOWN, IPOPT_BYTES_PER_PAIR),
        Backend::Newton => (NEWTON_BYTES_PER_UNKNOWN, NEWTON_BYTES_PER_PAIR),
    };
    let system = n * (per_unknown * unknowns + per_pair * unknowns * unknowns) * stencil * formulation;
    BASE_BYTES + nodes as f64 * columns(scene) * TRAJECTORY_BYTES_PER_CELL + system
}

/// Estimated peak memory in bytes of a reference of `scene` sampled at `samples` times.
pub fn reference_bytes(scene: &Scene, samples: usize) -> f64 {
    let d = scene.coordinates.len() as f64;
    let per_sample = REFERENCE_BYTES_PER_SAMPLE + columns(scene) * REFERENCE_BYTES_PER_CELL + d * d * REFERENCE_BYTES_PER_PAIR;
    BASE_BYTES / 2.0 + samples as f64 * per_sample
}

/// The memory available to this run in bytes (`MemAvailable`), if the system says.
pub fn available_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Refuse `what` (e.g. "the solve") of `scene` on `nodes` nodes when its estimate
/// `bytes` exceeds the available memory; the error stands at the scene's `time.nodes`.
pub fn check(scene: &Scene, what: &str, nodes: usize, bytes: f64) -> Result<(), SceneError> {
    check_against(scene, what, nodes, bytes, available_bytes())
}

/// [`check`] against a given limit (`None`: nothing is refused), for a caller that
/// checks many scenes against one reading of the available memory (a sweep's points).
pub fn check_against(scene: &Scene, what: &str, nodes: usize, bytes: f64, limit: Option<f64>) -> Result<(), SceneError> {
    match limit {
        Some(limit) if bytes > limit => Err(SceneError::Invalid {
            location: nodes_location(scene),
            message: format!(
                "{what} on N = {nodes} nodes needs an estimated {} of memory, more than the {} available: use fewer nodes",
                bytes_text(bytes),
                bytes_text(limit)
            ),
        }),
        _ => Ok(()),
    }
}

/// Where the scene's node count is written.
fn nodes_location(scene: &Scene) -> Location {
    scene.file.origin.locate_in(&scene.file.time.nodes, None)
}

/// Bytes as `12.3 GB` (decimal units).
fn bytes_text(bytes: f64) -> String {
    let units = [("TB", 1e12), ("GB", 1e9), ("MB", 1e6)];
    for (name, size) in units {
        if bytes >= size {
            return format!("{:.1} {name}", bytes / size);
        }
    }
    format!("{:.1} kB", bytes / 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_read_as_decimal_units() {
        assert_eq!(bytes_text(2.5e10), "25.0 GB");
        assert_eq!(bytes_text(3.2e6), "3.2 MB");
        assert_eq!(bytes_text(1.5e13), "15.0 TB");
    }
}
