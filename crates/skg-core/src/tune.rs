//! The energy artifact of a wall scene and the choice of the wall width σ (the paper's
//! procedure: the smallest σ whose energy shows no oscillation artifacts at the given N).
//!
//! **Energy artifact** ([`energy_artifact`]). The energy column E(t) of a solution leaves
//! out the walls' potential, which is nonzero only in contact, so E is constant between
//! contacts in the continuum. The artifact is
//!
//! ```text
//! A = max |E_k − E_1| / max(max_k |E_k|, 1e-300)
//! ```
//!
//! over the *free* nodes k: nodes in contact with no wall ([`contact::in_contact`]:
//! every gap h ≤ −6σ, where the Gaussian force is below 1.5e-8 of its peak), not within
//! 3 nodes of a node in contact (the SBP stencil of Dq reaches that far), and not among the last `skip_last` nodes (benign
//! boundary nodes, docs/solver.md). A σ too small for N makes the discrete solution ring after
//! each impact and A jumps by orders of magnitude (paper, fig. 3; docs/solver.md). A scene
//! without walls uses every node but the last `skip_last`, so A is the relative energy
//! drift.
//!
//! Measured on the tumbler (SBP242): at N = 256, A = 3e-7 (σ = 1/80), 5e-6 (1/110),
//! 3e-5 (1/120), 2e-4 (1/140), 1e-3 (1/200); at N = 512, A ≤ 2e-6 up to σ = 1/200 and
//! 2e-4 at 1/300; at N = 1024, A ≤ 3e-8 down to 1/300. The default tolerance 1e-5
//! therefore reproduces the paper's choice σ = 1/110 at N = 256 (docs/scenes.md, docs/solver.md).
//!
//! **σ selection** ([`tune_width`]): bisection in log σ between a σ with artifacts and one
//! without, over in-process solves; it assumes the artifact decreases as σ grows.
//!
//! **Place in the flow.** A consumer of results, at the end: it uses
//! [`scene`](crate::scene) (the σ of a scene file), [`model`](crate::model),
//! [`discrete`](crate::discrete) (contact) and [`solve`].

// Errors carry a SceneError (with its file:line:column text), as in the core modules.
#![allow(clippy::result_large_err)]

use std::path::PathBuf;

use crate::discrete::contact;
use crate::discrete::trajectory::Trajectory;
use crate::scene::{readable_number, NumOrExpr, Overrides, Scene, SceneFile};
use crate::solve::{self, SolveStatus};

/// Default tolerance on the relative energy artifact.
pub const DEFAULT_ARTIFACT_TOL: f64 = 1e-5;
/// Nodes on each side of a contact node that are not counted as free.
pub const CONTACT_GUARD: usize = 3;

/// The energy artifact of a solution and how many nodes it was measured on.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Artifact {
    /// The relative energy artifact A.
    pub value: f64,
    /// The number of free nodes it was measured on.
    pub free_nodes: usize,
}

/// Whether the energy `energy + wall_energy` of `scene` is conserved by the motion, so
/// that its energy artifact means something: no declared forces, no wall friction and no
/// explicit time dependence (of the `model` built from it).
pub fn conserves_energy(scene: &Scene, model: &crate::model::Model) -> bool {
    !scene.has_non_conservative_forces() && !model.depends_on_time
}

/// What keeps a scene's energy from being conserved, in words (for a scene that
/// [`conserves_energy`] refuses).
fn non_conservative_part(scene: &Scene) -> &'static str {
    if !scene.file.forces.is_empty() {
        "declares forces ([forces])"
    } else if scene.walls.iter().any(|w| w.friction != 0.0) {
        "has wall friction"
    } else {
        "depends on the time t explicitly"
    }
}

/// The energy artifact of a trajectory of `scene` (see the module documentation).
pub fn energy_artifact(scene: &Scene, tr: &Trajectory, skip_last: usize) -> Artifact {
    let n = tr.energy.len();
    let end = n.saturating_sub(skip_last);
    let mut contact = vec![false; n];
    for (k, h) in tr.h.iter().enumerate() {
        if scene.walls.iter().zip(h).any(|(w, &hk)| contact::in_contact(hk, w.width)) {
            let lo = k.saturating_sub(CONTACT_GUARD);
            let hi = (k + CONTACT_GUARD + 1).min(n);
            contact[lo..hi].iter_mut().for_each(|c| *c = true);
        }
    }
    let e0 = tr.energy.first().copied().unwrap_or(0.0);
    let scale = tr.energy.iter().fold(0.0_f64, |m, e| m.max(e.abs())).max(1e-300);
    let mut value = 0.0_f64;
    let mut free_nodes = 0;
    for (e, _) in tr.energy[..end].iter().zip(&contact).filter(|(_, c)| !**c) {
        free_nodes += 1;
        value = value.max((e - e0).abs() / scale);
    }
    Artifact { value, free_nodes }
}

/// Options of [`tune_width`].
#[derive(Debug, Clone)]
pub struct TuneOptions {
    /// Parameter to tune (default: the parameter a wall's width is set to).
    pub param: Option<String>,
    /// Tolerance on the relative energy artifact.
    pub tol: f64,
    /// Lower end of the initial bracket (default: hi/8).
    pub lo: Option<f64>,
    /// Upper end of the initial bracket (default: the scene's value).
    pub hi: Option<f64>,
    /// Stop when hi/lo < 1 + rel.
    pub rel: f64,
    /// Most solves in the bisection phase.
    pub max_solves: usize,
    /// Last nodes left out of the artifact (the boundary closure).
    pub skip_last: usize,
}

impl Default for TuneOptions {
    fn default() -> Self {
        TuneOptions { param: None, tol: DEFAULT_ARTIFACT_TOL, lo: None, hi: None, rel: 0.02, max_solves: 20, skip_last: 2 }
    }
}

/// One solve of the search.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TuneStep {
    /// The parameter's value.
    pub value: f64,
    /// How the solve ended (serialized as `converged`, `status`, `status_text`,
    /// `solve_status`).
    #[serde(flatten)]
    pub status: SolveStatus,
    /// The energy artifact of the solution.
    pub artifact: f64,
    /// Converged and artifact ≤ tol.
    pub ok: bool,
    /// Wall time of the solve, in seconds.
    pub wall_s: f64,
}

/// Result of [`tune_width`].
#[derive(Debug, Clone, serde::Serialize)]
pub struct TuneResult {
    /// The tuned parameter.
    pub param: String,
    /// The number of nodes N of every solve.
    pub nodes: usize,
    /// The tolerance on the energy artifact.
    pub tol: f64,
    /// The smallest value found without artifacts.
    pub chosen: f64,
    /// The largest value found with artifacts (or failing), if any.
    pub failing: Option<f64>,
    /// Every solve, in order.
    pub steps: Vec<TuneStep>,
    /// Notes (e.g. the lower end of the bracket had no artifacts either).
    pub notes: Vec<String>,
}

/// Why a width could not be tuned.
#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    /// The scene, or the scene with a trial value, is invalid.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// A solve could not be attempted.
    #[error(transparent)]
    Solve(#[from] crate::solve::SolveError),
    /// No wall's width is written as a parameter, and none was named.
    #[error("no wall's width is a parameter (write e.g. `width = \"sigma\"` with `sigma` under [parameters], or pass --param)")]
    NoWidthParameter,
    /// The walls' widths are several parameters, and none was named.
    #[error("walls use several width parameters ({}): pass --param", .0.join(", "))]
    SeveralWidthParameters(Vec<String>),
    /// The tolerance on the artifact is not positive.
    #[error("the tolerance must be positive, got {}", readable_number(*.0))]
    BadTolerance(f64),
    /// A bracket end or the bracket's relative width is not a positive number.
    #[error("{name} must be a positive number, got {}", readable_number(*value))]
    BadSearchOption {
        /// The option (`lo`, `hi`, `rel`).
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The parameter to tune is not one of the scene's.
    #[error("the scene has no parameter `{param}` (parameters: {})", .known.join(", "))]
    UnknownParameter {
        /// The parameter asked for.
        param: String,
        /// The scene's parameters.
        known: Vec<String>,
    },
    /// The scene's energy is not conserved between contacts (it depends on the time
    /// explicitly, declares forces, or has wall friction), so the energy artifact
    /// measures nothing.
    #[error("the scene {0}, so its energy is not conserved between contacts and the energy artifact cannot choose the wall width")]
    NotConservative(&'static str),
    /// The starting value of the parameter is not positive.
    #[error("`{param}` must be positive to be tuned, got {}", readable_number(*value))]
    NotPositive {
        /// The parameter.
        param: String,
        /// Its value.
        value: f64,
    },
    /// Even the largest value tried shows artifacts or fails.
    #[error("even {param} = {value:.6e} shows energy artifacts above {tol:e} (or fails) at N = {nodes}: raise N or the tolerance")]
    ArtifactsEverywhere {
        /// The parameter.
        param: String,
        /// The largest value tried.
        value: f64,
        /// The tolerance on the artifact.
        tol: f64,
        /// The number of nodes.
        nodes: usize,
    },
}

/// The parameter a wall's width is written as (`width = "sigma"`), if exactly one.
pub fn width_parameter(file: &SceneFile) -> Result<String, TuneError> {
    let mut names: Vec<String> = Vec::new();
    for w in &file.walls {
        if let NumOrExpr::Expr(s) = w.width.get_ref() {
            let s = s.trim();
            if file.parameters.contains_key(s) && !names.iter().any(|n| n == s) {
                names.push(s.to_string());
            }
        }
    }
    match names.len() {
        1 => Ok(names.remove(0)),
        0 => Err(TuneError::NoWidthParameter),
        _ => Err(TuneError::SeveralWidthParameters(names)),
    }
}

/// Find the smallest value of the width parameter whose energy artifact stays below
/// `opts.tol` at the scene's N (bisection in log scale). `progress` sees every step.
pub fn tune_width(file: &SceneFile, ov: &Overrides, opts: &TuneOptions, progress: impl FnMut(&TuneStep)) -> Result<TuneResult, TuneError> {
    let param = match &opts.param {
        Some(p) => p.clone(),
        None => width_parameter(file)?,
    };
    check_search_options(opts)?;
    let base = file.clone().resolve(ov)?;
    if !conserves_energy(&base, &crate::model::Model::build(&base)?) {
        return Err(TuneError::NotConservative(non_conservative_part(&base)));
    }
    let current = *base
        .parameters
        .get(&param)
        .ok_or_else(|| TuneError::UnknownParameter { param: param.clone(), known: base.parameters.keys().cloned().collect() })?;
    let mut trials = Trials { file, ov, opts, param: &param, progress, steps: Vec::new() };
    let mut notes = Vec::new();
    let hi = opts.hi.unwrap_or(current);
    if hi.is_nan() || hi <= 0.0 {
        return Err(TuneError::NotPositive { param, value: hi });
    }
    let hi = trials.first_without_artifacts(hi, base.nodes)?;
    let (mut lo, mut hi, mut failing) = trials.first_with_artifacts(hi, &mut notes)?;
    if failing.is_some() {
        let mut solves = 0;
        while hi / lo > 1.0 + opts.rel && solves < opts.max_solves {
            let mid = (hi * lo).sqrt();
            if trials.passes(mid)? {
                hi = mid;
            } else {
                lo = mid;
            }
            solves += 1;
        }
        failing = Some(lo);
    }
    let steps = trials.steps;
    Ok(TuneResult { param, nodes: base.nodes, tol: opts.tol, chosen: hi, failing, steps, notes })
}

/// The tolerance is positive, and the bracket's ends and relative width positive numbers.
fn check_search_options(opts: &TuneOptions) -> Result<(), TuneError> {
    if opts.tol.is_nan() || opts.tol <= 0.0 {
        return Err(TuneError::BadTolerance(opts.tol));
    }
    for (name, value) in [("lo", opts.lo), ("hi", opts.hi), ("rel", Some(opts.rel))] {
        if let Some(value) = value.filter(|v| !(*v > 0.0 && v.is_finite())) {
            return Err(TuneError::BadSearchOption { name, value });
        }
    }
    Ok(())
}

/// The solves of the search: the scene with the parameter set to a trial value, each
/// recorded and shown to `progress`.
struct Trials<'a, P> {
    file: &'a SceneFile,
    ov: &'a Overrides,
    opts: &'a TuneOptions,
    /// The parameter tuned.
    param: &'a str,
    progress: P,
    /// Every solve so far, in order.
    steps: Vec<TuneStep>,
}

impl<P: FnMut(&TuneStep)> Trials<'_, P> {
    /// Whether the solve with the parameter at `value` converges with an energy artifact
    /// within the tolerance.
    fn passes(&mut self, value: f64) -> Result<bool, TuneError> {
        let mut o = self.ov.clone();
        o.set.retain(|(k, _)| *k != self.param);
        o.set.push((self.param.to_string(), format!("{value:?}")));
        let scene = self.file.clone().resolve(&o)?;
        let t = std::time::Instant::now();
        let out = solve::solve_scene(&scene)?;
        let artifact = energy_artifact(&scene, &out.trajectory, self.opts.skip_last).value;
        let step = TuneStep {
            value,
            status: out.status,
            artifact,
            ok: out.converged() && artifact <= self.opts.tol,
            wall_s: t.elapsed().as_secs_f64(),
        };
        (self.progress)(&step);
        let ok = step.ok;
        self.steps.push(step);
        Ok(ok)
    }

    /// The bracket's upper end: `hi`, doubled until it passes (at most four times; an
    /// error if even `16 hi` does not at the scene's `nodes`).
    fn first_without_artifacts(&mut self, mut hi: f64, nodes: usize) -> Result<f64, TuneError> {
        let mut grow = 0;
        while !self.passes(hi)? {
            grow += 1;
            if grow > 4 {
                return Err(TuneError::ArtifactsEverywhere { param: self.param.to_string(), value: hi, tol: self.opts.tol, nodes });
            }
            hi *= 2.0;
        }
        Ok(hi)
    }

    /// The bracket's lower end below the passing `hi`: the option's `lo` (default
    /// `hi/8`, at most `hi/(1 + rel)`), halved while it passes (moving `hi` down to it),
    /// at most four times. Returns `(lo, hi, failing)`, `failing` the value that failed,
    /// if one did (else a note says where the search stopped).
    fn first_with_artifacts(&mut self, mut hi: f64, notes: &mut Vec<String>) -> Result<(f64, f64, Option<f64>), TuneError> {
        let mut lo = self.opts.lo.unwrap_or(hi / 8.0).min(hi / (1.0 + self.opts.rel));
        let mut shrink = 0;
        loop {
            if !self.passes(lo)? {
                return Ok((lo, hi, Some(lo)));
            }
            hi = lo;
            shrink += 1;
            if shrink > 4 {
                notes.push(format!("no artifacts down to {} = {lo:.6e}: the search stopped there", self.param));
                return Ok((lo, hi, None));
            }
            lo /= 2.0;
        }
    }
}

/// Where a tune result is written (beside the scene's usual output).
pub fn default_output(scene_path: &std::path::Path) -> PathBuf {
    let stem = scene_path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from("out").join(stem).join("tune.json")
}
