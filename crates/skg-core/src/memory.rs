//! Memory estimates: a solve or a reference on a huge grid is refused before anything
//! is allocated, with a message that states the estimate and the limit, instead of
//! running out of memory (or panicking on a capacity overflow) part-way.
//!
//! The estimates are fits to measured peak resident memory (release build, Debian's
//! Ipopt 3.11.9 with MUMPS; docs/benchmarks.md): a solve needs about
//! `N · (d + n)² · c_op` bytes (MUMPS's factors of the KKT matrix dominate), `c_op`
//! growing with the operator's stencil and doubled by the full formulation; a reference
//! stores its samples (a few dozen doubles per node) and the integrator's steps. They
//! err on the high side. The limit is the memory the kernel reports as available
//! (`MemAvailable` in `/proc/meminfo`); where that cannot be read, nothing is refused.
//! Reading one line of `/proc/meminfo` needs no crate (the `sysinfo` crate would bring a
//! large dependency for it).

use crate::sbp::OperatorKind;
use crate::scenario::{Formulation, Location, Scene, SceneError};

/// Bytes per node and per (d + n)² of a reduced solve with `SBP242`, fitted to the
/// measured peak memory (see the module docs).
const SOLVE_BYTES_PER_NODE_UNIT: f64 = 2.0e3;
/// Bytes of a solve independent of the grid (tapes, Ipopt, MUMPS workspaces).
const SOLVE_BASE_BYTES: f64 = 64.0e6;
/// Doubles a reference stores per node and per column.
const REFERENCE_DOUBLES_PER_CELL: f64 = 8.0;

/// Estimated peak memory in bytes of solving `scene`.
pub fn solve_bytes(scene: &Scene) -> f64 {
    let unknowns = (scene.coordinates.len() + scene.constraints.len()) as f64;
    let stencil = match scene.operator {
        OperatorKind::Sbp121 => 0.6,
        OperatorKind::Sbp242 => 1.0,
        _ => 1.6,
    };
    let formulation = if scene.formulation == Formulation::Full { 3.0 } else { 1.0 };
    SOLVE_BASE_BYTES + scene.nodes as f64 * unknowns * unknowns * SOLVE_BYTES_PER_NODE_UNIT * stencil * formulation
}

/// Estimated peak memory in bytes of a reference of `scene` sampled at `samples` times.
pub fn reference_bytes(scene: &Scene, samples: usize) -> f64 {
    let columns = (1 + 2 * scene.coordinates.len() + 3 * scene.constraints.len() + 2 * scene.walls.len() + 2) as f64;
    SOLVE_BASE_BYTES / 4.0 + samples as f64 * columns * REFERENCE_DOUBLES_PER_CELL * 8.0
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
    match available_bytes() {
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
