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
//! chain of 32 links). The limit ([`memory_limit`]) is the least of three: the memory
//! the kernel reports as available (`MemAvailable` in `/proc/meminfo`), what the
//! address-space limit (`RLIMIT_AS`, `ulimit -v`) leaves beside the process's current
//! virtual size, and what the memory limit of the process's cgroup and of each of its
//! ancestors (cgroup v2 `memory.max`, v1 `memory.limit_in_bytes`: a batch job's memory
//! on a cluster, a container's) leaves beside the group's use less its reclaimable page
//! cache. Where none can be read, nothing is refused. Reading these few files of
//! `/proc` and `/sys/fs/cgroup` needs no crate (`sysinfo` would bring a large dependency
//! for it).
//!
//! **Place in the flow.** Right after the scene: it uses only [`sbp`](crate::sbp) and
//! [`scene`](crate::scene) (an estimate needs the resolved scene, nothing built from
//! it), so that whatever allocates later can ask it first.

use std::path::Path;

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

/// A limit on the memory of this process: how many bytes it may still allocate, and
/// which limit says so.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryLimit {
    /// The bytes left.
    pub bytes: f64,
    /// Which limit: `available` (`MemAvailable`), `left under the address-space limit
    /// (ulimit -v)`, `left under the memory limit of the cgroup /sys/fs/cgroup/…`.
    pub source: String,
}

/// The memory available to this run in bytes ([`memory_limit`]), if the system says.
pub fn available_bytes() -> Option<f64> {
    memory_limit().map(|l| l.bytes)
}

/// The least of the limits on this process's memory (see the module documentation), if
/// any can be read.
pub fn memory_limit() -> Option<MemoryLimit> {
    let proc_cgroups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    [mem_available(), address_space_left(), cgroup_left(Path::new("/sys/fs/cgroup"), &proc_cgroups)]
        .into_iter()
        .flatten()
        .min_by(|a, b| a.bytes.total_cmp(&b.bytes))
}

/// `MemAvailable` of `/proc/meminfo`.
fn mem_available() -> Option<MemoryLimit> {
    let kib = kib_field(&std::fs::read_to_string("/proc/meminfo").ok()?, "MemAvailable:")?;
    Some(MemoryLimit { bytes: kib * 1024.0, source: "available".into() })
}

/// The number of kB on the line of `text` that starts with `key` (`/proc` files).
fn kib_field(text: &str, key: &str) -> Option<f64> {
    text.lines().find(|l| l.starts_with(key))?.split_whitespace().nth(1)?.parse().ok()
}

/// What the soft `RLIMIT_AS` (`Max address space` of `/proc/self/limits`) leaves beside
/// the process's virtual size (`VmSize`): under `ulimit -v` an allocation beyond it fails
/// and the process aborts.
fn address_space_left() -> Option<MemoryLimit> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let soft: f64 = limits.lines().find(|l| l.starts_with("Max address space"))?.split_whitespace().nth(3)?.parse().ok()?;
    let used = kib_field(&std::fs::read_to_string("/proc/self/status").ok()?, "VmSize:")? * 1024.0;
    Some(MemoryLimit { bytes: (soft - used).max(0.0), source: "left under the address-space limit (ulimit -v)".into() })
}

/// Values of a cgroup v1 limit at or above this mean no limit (the kernel writes
/// `PAGE_COUNTER_MAX`, about 9.2·10¹⁸).
const CGROUP_V1_UNLIMITED: f64 = 4.6e18;

/// What the memory limits of the process's cgroup and its ancestors leave, the least of
/// them: `proc_cgroups` is `/proc/self/cgroup`, `root` where the hierarchies are mounted
/// (`/sys/fs/cgroup`: v2 there or in `unified/`, v1's memory controller in `memory/`).
/// A group's path that does not exist under the mount (a container that sees only its
/// own group, mounted at the root) is read at the mount's root.
fn cgroup_left(root: &Path, proc_cgroups: &str) -> Option<MemoryLimit> {
    let mut found = Vec::new();
    for line in proc_cgroups.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (fields.next(), fields.next(), fields.next()) else { continue };
        let path = path.trim_start_matches('/');
        if controllers.is_empty() {
            for mount in [root.to_path_buf(), root.join("unified")] {
                found.extend(cgroup_levels(&mount, path, "memory.max", "memory.current", "inactive_file"));
            }
        } else if controllers.split(',').any(|c| c == "memory") {
            let mount = root.join("memory");
            found.extend(cgroup_levels(&mount, path, "memory.limit_in_bytes", "memory.usage_in_bytes", "total_inactive_file"));
        }
    }
    found.into_iter().min_by(|a, b| a.bytes.total_cmp(&b.bytes))
}

/// The least of what the limits of the group `path` under `mount` and of its ancestors
/// up to the mount leave: `limit` less the group's `usage` less its reclaimable page
/// cache (`inactive` in `memory.stat`).
fn cgroup_levels(mount: &Path, path: &str, limit: &str, usage: &str, inactive: &str) -> Option<MemoryLimit> {
    let group = Some(mount.join(path)).filter(|g| g.is_dir()).unwrap_or_else(|| mount.to_path_buf());
    let read = |dir: &Path, name: &str| std::fs::read_to_string(dir.join(name)).ok();
    let mut least: Option<MemoryLimit> = None;
    for dir in group.ancestors().take_while(|d| d.starts_with(mount)) {
        let Some(max) = read(dir, limit).and_then(|t| t.trim().parse::<f64>().ok()) else { continue };
        if max >= CGROUP_V1_UNLIMITED {
            continue;
        }
        let used = read(dir, usage).and_then(|t| t.trim().parse::<f64>().ok()).unwrap_or(0.0);
        let cache = read(dir, "memory.stat")
            .and_then(|t| t.lines().find_map(|l| l.strip_prefix(inactive)?.strip_prefix(' ')?.trim().parse::<f64>().ok()))
            .unwrap_or(0.0);
        let left = (max - (used - cache).max(0.0)).max(0.0);
        if least.as_ref().is_none_or(|l| left < l.bytes) {
            least = Some(MemoryLimit { bytes: left, source: format!("left under the memory limit of the cgroup {}", dir.display()) });
        }
    }
    least
}

/// Refuse `what` (e.g. "the solve") of `scene` on `nodes` nodes when its estimate
/// `bytes` exceeds the memory this process may use ([`memory_limit`]); the error
/// stands at the scene's `time.nodes`.
pub fn check(scene: &Scene, what: &str, nodes: usize, bytes: f64) -> Result<(), SceneError> {
    check_against(scene, what, nodes, bytes, memory_limit().as_ref())
}

/// [`check`] against a given limit (`None`: nothing is refused), for a caller that
/// checks many scenes against one reading of the limit (a sweep's points).
pub fn check_against(scene: &Scene, what: &str, nodes: usize, bytes: f64, limit: Option<&MemoryLimit>) -> Result<(), SceneError> {
    match limit {
        Some(limit) if bytes > limit.bytes => Err(SceneError::Invalid {
            location: nodes_location(scene),
            message: format!(
                "{what} on N = {nodes} nodes needs an estimated {} of memory, more than the {} {}: use fewer nodes",
                bytes_text(bytes),
                bytes_text(limit.bytes),
                limit.source
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

    /// Write `files` (path relative to `root`, content) into a fake cgroup tree.
    fn tree(root: &Path, files: &[(&str, &str)]) {
        for (path, text) in files {
            let path = root.join(path);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
    }

    #[test]
    fn a_cgroup_v2_limit_counts_on_the_group_and_its_ancestors() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        // A Slurm job's group limited to 4 GB (1 GB used, 0.25 GB of it reclaimable
        // cache), its step below it unlimited, the root without a limit file.
        tree(
            root,
            &[
                ("job_1/memory.max", "4000000000\n"),
                ("job_1/memory.current", "1000000000\n"),
                ("job_1/memory.stat", "anon 750000000\ninactive_file 250000000\nactive_file 0\n"),
                ("job_1/step_0/memory.max", "max\n"),
                ("job_1/step_0/memory.current", "900000000\n"),
            ],
        );
        let limit = cgroup_left(root, "0::/job_1/step_0\n").unwrap();
        assert_eq!(limit.bytes, 3.25e9);
        assert!(limit.source.contains("job_1") && !limit.source.contains("step_0"), "{}", limit.source);
        // The same tree mounted at unified/ (a hybrid system) is found too.
        let hybrid = tempfile::tempdir().unwrap();
        tree(&hybrid.path().join("unified"), &[("a/memory.max", "2000000000"), ("a/memory.current", "500000000")]);
        assert_eq!(cgroup_left(hybrid.path(), "0::/a").unwrap().bytes, 1.5e9);
        // No limit anywhere: none.
        assert!(cgroup_left(root, "0::/").is_none());
    }

    #[test]
    fn a_cgroup_v1_memory_limit_counts_and_its_unlimited_value_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        tree(
            root,
            &[
                ("memory/memory.limit_in_bytes", "9223372036854771712"),
                ("memory/docker/abc/memory.limit_in_bytes", "2147483648"),
                ("memory/docker/abc/memory.usage_in_bytes", "147483648"),
                ("memory/docker/abc/memory.stat", "cache 0\ntotal_inactive_file 47483648\n"),
            ],
        );
        let text = "4:memory:/docker/abc\n3:cpu,cpuacct:/docker/abc\n";
        assert_eq!(cgroup_left(root, text).unwrap().bytes, 2147483648.0 - 100000000.0);
        // A container that sees its own group at the mount's root (the path of
        // /proc/self/cgroup does not exist under the mount).
        let inside = tempfile::tempdir().unwrap();
        tree(inside.path(), &[("memory/memory.limit_in_bytes", "1000000000"), ("memory/memory.usage_in_bytes", "0")]);
        assert_eq!(cgroup_left(inside.path(), "4:memory:/docker/abc").unwrap().bytes, 1e9);
        // Only the memory controller's line counts.
        assert!(cgroup_left(inside.path(), "3:cpu:/docker/abc").is_none());
    }
}
