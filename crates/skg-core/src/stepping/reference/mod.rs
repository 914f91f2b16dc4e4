//! Reference solutions of a scene, independent of the SBP discretization (docs/validation.md).
//!
//! * **Regularized** ([`regularized`]): the Lagrange–d'Alembert equations of exactly the
//!   scene the solver discretizes (same TOML, same symbolic model and derivatives,
//!   Gaussian walls included) integrated by [`equations`](super::equations) (the DOP853
//!   of [`ode`]) at a tight tolerance and sampled at the requested times from its
//!   dense output. Explicit time is the integrator's time. Velocity constraints enter
//!   index-reduced: accelerations and multipliers solve
//!   `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) q̇ − ∂p/∂t; −(∂g/∂q) q̇ − ∂g/∂t]`
//!   ([`Model::accelerations`]); a position constraint `h(q, t) = 0` enters as its time
//!   derivative, so its second derivative is what is enforced. `g = 0` and `h = 0` then
//!   hold only up to the integrator's drift, which is reported (the `residual_*` and
//!   `drift_*` columns, `max |g|` and `max |h|` in the provenance). The distance of a
//!   solve from this reference is its *discretization error*.
//! * **Hard-wall** ([`hard_wall`]): the same scene with every wall an ideal elastic wall,
//!   the σ → 0 limit of the Gaussian wall (the model of [`Model::with_hard_walls`]: the
//!   walls' geometry, no wall force). Between impacts the particle moves under the
//!   scene's other forces; an impact is the first upward zero crossing of `max_j h_j(q)`,
//!   located on the dense output ([`ode::integrate_to_event`]); the velocity is then
//!   reflected in the kinetic metric `W`: `v⁺ = v − 2 (n·v)/(nᵀW⁻¹n) W⁻¹n` with `n = ∇h`.
//!   A wall with friction adds the limit of its friction force over the (vanishing)
//!   contact time: an impulse `μ |J_N|` along the wall's `friction_direction` (the
//!   paper's fixed direction), or, without one, against the tangential velocity and
//!   capped so that it at most stops the tangential motion (Coulomb). The distance of a
//!   solve from this reference is its *model error* (plus its discretization error).
//!
//! Sustained contact — a start on a wall, or an arrival with vanishing normal speed
//! (`≤ 1e-7 (1 + max|q̇₀|)`) — while the wall pushes (`N > 0`): the motion is constrained to
//! `h_j = 0` (index-reduced: `∇h·q̈ + q̇ᵀ∇²h q̇ = 0`) with kinetic Coulomb friction
//! `μ N |∇h| d̂` along the friction direction, until lift-off, located as the zero crossing
//! of `N` ([`Contact`] phases are listed in the provenance).
//!
//! Explicit time in the Lagrangian and the forces is integrated like any other state
//! dependence. Not covered, each an error rather than a wrong answer: walls together with
//! velocity or position constraints (the impact law would have to respect the
//! constraints), moving walls (a gap that depends on `t`: the impact law would need the
//! wall's velocity, the sliding law its acceleration; the regularized reference covers
//! them), sticking under velocity-dependent friction (a particle coming to rest in
//! contact), and impacts that accumulate without settling into contact.
//!
//! Data flow: scene → model → time stepping → [`Reference`] (a [`Trajectory`] and how it
//! was made); the output stage writes it as CSV with its [`provenance`].

// `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// `SceneError` (wrapped in `ReferenceError`) is large; it is the crate-wide error type.
#![allow(clippy::result_large_err)]
use std::fmt;

mod hard_wall;

pub use hard_wall::{check_hard_walls, hard_wall, HardWallError};

use crate::discrete::trajectory::Trajectory;
use crate::model::Model;
use crate::scene::{ConstraintKind, Scene, SceneError, Stepper};
use crate::stepping::equations::{integrate_model, mean_spacing, Stepped};
use crate::stepping::ode::{self, OdeOptions, OdeStats};

/// Errors of building a reference. The message of a wrapped error is part of the
/// variant's text (it is not also reported as its `source`, which would print it twice).
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The integrator failed.
    #[error("integrating the Lagrange–d'Alembert equations failed: {0}")]
    Ode(ode::OdeError),
    /// The hard-wall reference does not model the scene, or its laws broke down.
    #[error("hard-wall reference: {0}")]
    HardWall(HardWallError),
    /// The sample times are unusable.
    #[error("bad sample times: {0}")]
    Times(TimesError),
    /// The hard-wall reference was asked of the implicit stepper.
    #[error(
        "the hard-wall reference locates its impacts on DOP853's dense output and cannot step implicitly: \
         use --stepper auto or dop853 with --hard-walls"
    )]
    ImplicitHardWall,
}

impl From<ode::OdeError> for ReferenceError {
    fn from(e: ode::OdeError) -> Self {
        ReferenceError::Ode(e)
    }
}

impl From<HardWallError> for ReferenceError {
    fn from(e: HardWallError) -> Self {
        ReferenceError::HardWall(e)
    }
}

impl From<TimesError> for ReferenceError {
    fn from(e: TimesError) -> Self {
        ReferenceError::Times(e)
    }
}

/// Sample times a reference cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TimesError {
    /// No times at all.
    #[error("no sample times")]
    Empty,
    /// The times do not increase strictly.
    #[error("sample times must increase strictly: t[{index}] = {t} is followed by {next}")]
    NotIncreasing {
        /// Position of the first offending time.
        index: usize,
        /// That time.
        t: f64,
        /// The time after it (≤ `t`, or NaN).
        next: f64,
    },
    /// The first time is not the scene's start time.
    #[error("the first sample time {first} must be the scene's start time {start} (where its initial state is given)")]
    NotAtStart {
        /// The first sample time.
        first: f64,
        /// The scene's start time.
        start: f64,
    },
}

/// Settings of a reference integration.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct ReferenceOptions {
    /// Relative tolerance of the integrator (default 1e-12).
    pub rtol: f64,
    /// Absolute tolerance of the integrator (default 1e-12).
    pub atol: f64,
    /// The integrator of a regularized reference (default `auto`: DOP853, and Radau IIA
    /// from where the scene turns out stiff). A hard-wall reference locates its impacts
    /// on DOP853's dense output and refuses `implicit`.
    pub stepper: Stepper,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { rtol: 1e-12, atol: 1e-12, stepper: Stepper::Auto }
    }
}

impl ReferenceOptions {
    /// Integrator options for sampling at `times`: the step is capped at the mean sample
    /// spacing, as the verification's is (walls of any width are sampled by the
    /// integrator's own bound on each step's change of their gaps). Not at the smallest
    /// spacing: on an adaptive grid that can be 1e-5 of the mean, and the damped spring of
    /// `scenarios/damped_spring_stiffness.toml` at `c = 1292` on its adaptive grid of
    /// 2466 nodes (finest step 1.1e-4 s over 6463 s) ran out of 2e7 steps at t = 2181 s
    /// under Radau IIA, where it takes 0.02 s on the uniform grid.
    fn ode(&self, times: &[f64]) -> OdeOptions {
        OdeOptions {
            rtol: self.rtol,
            atol: self.atol,
            max_steps: 20_000_000,
            initial_step: None,
            max_step: mean_spacing(times),
            stepper: self.stepper,
            deadline: None,
        }
    }
}

/// One impact of the hard-wall reference.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Impact {
    /// Time of the impact.
    pub t: f64,
    /// The wall hit.
    pub wall: String,
    /// Outward normal speed `n̂·v` just before the impact.
    pub normal_speed: f64,
    /// Position at the impact.
    pub q: Vec<f64>,
}

/// A phase of sustained contact of the hard-wall reference: sliding along a wall.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Contact {
    /// The wall slid along.
    pub wall: String,
    /// Start of the contact (a grazing arrival, or the start time).
    pub t_start: f64,
    /// Lift-off time; `None` if still in contact at the end.
    pub t_end: Option<f64>,
}

/// The two references of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceKind {
    /// The scene's own model, Gaussian walls included ([`regularized`]).
    Regularized,
    /// Every wall ideal and elastic ([`hard_wall`]).
    HardWall,
}

impl fmt::Display for ReferenceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ReferenceKind::Regularized => "regularized",
            ReferenceKind::HardWall => "hard-wall",
        })
    }
}

/// A reference trajectory and how it was made.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Same layout as the solver's trajectory (CSV columns via [`crate::discrete::trajectory::trajectory_rows`]).
    pub trajectory: Trajectory,
    /// Which reference it is.
    pub kind: ReferenceKind,
    /// The integrator's tolerances.
    pub options: ReferenceOptions,
    /// The integrator's work.
    pub stats: OdeStats,
    /// The method that ran, in words.
    pub method: String,
    /// Impacts (hard-wall reference only).
    pub impacts: Vec<Impact>,
    /// Phases of sustained contact (hard-wall reference only).
    pub contacts: Vec<Contact>,
    /// max |g^a| over the samples: the drift of the index-reduced integration.
    pub constraint_drift: f64,
    /// max |h| of the position constraints over the samples (0 without any).
    pub position_drift: f64,
    /// max |E − E(t₀)| over the samples.
    pub energy_drift: f64,
}

fn check_times(scene: &Scene, times: &[f64]) -> Result<(), ReferenceError> {
    if times.is_empty() {
        return Err(TimesError::Empty.into());
    }
    if let Some(i) = times.windows(2).position(|w| !(w[1] > w[0])) {
        return Err(TimesError::NotIncreasing { index: i, t: times[i], next: times[i + 1] }.into());
    }
    if (times[0] - scene.t_start).abs() > 1e-12 * (1.0 + scene.t_start.abs()) {
        return Err(TimesError::NotAtStart { first: times[0], start: scene.t_start }.into());
    }
    crate::memory::check(scene, "the reference", times.len(), crate::memory::reference_bytes(scene, times.len()))?;
    Ok(())
}

/// The drifts of a reference: max |g|, max |h| of the position constraints, and max
/// |E − E₀| of the total energy (mechanical plus the walls' potential).
fn drifts(tr: &Trajectory) -> (f64, f64, f64) {
    let g = tr.g.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let h = tr.max_drift().into_iter().fold(0.0_f64, f64::max);
    let total: Vec<f64> = tr.energy.iter().zip(&tr.wall_energy).map(|(e, w)| e + w).collect();
    let e = total.iter().fold(0.0_f64, |m, x| m.max((x - total[0]).abs()));
    (g, h, e)
}

/// The regularized reference of `scene` sampled at `times` (the first one must be the
/// scene's start time).
pub fn regularized(scene: &Scene, times: &[f64], opts: &ReferenceOptions) -> Result<Reference, ReferenceError> {
    check_times(scene, times)?;
    let model = Model::build(scene)?;
    let Stepped { states, stats, method } = integrate_model(&model, &scene.initial_q, &scene.initial_v, times, &opts.ode(times))?;
    let tr = Trajectory::with_physical_columns(&model, times, states);
    let (constraint_drift, position_drift, energy_drift) = drifts(&tr);
    Ok(Reference {
        trajectory: tr,
        kind: ReferenceKind::Regularized,
        options: *opts,
        stats,
        method,
        impacts: vec![],
        contacts: vec![],
        constraint_drift,
        position_drift,
        energy_drift,
    })
}

/// The provenance comment of a reference CSV (deterministic: no dates, no paths other
/// than the scene file as given).
pub fn provenance(scene: &Scene, scene_path: &str, r: &Reference) -> String {
    let mut s = format!(
        "skg-solve {} reference ({}) of {} (scene \"{}\"): {}, rtol {:e}, atol {:e}, step at most the mean sample spacing; index-reduced Lagrange-d'Alembert equations ([W G^T; G 0] solve for accelerations and multipliers); {} samples from t = {} to {}; {} accepted steps, {} rejected, {} right-hand-side evaluations; max |g| {:.3e}, max |E - E0| {:.3e}",
        crate::scene::provenance::VERSION,
        r.kind,
        scene_path,
        scene.name,
        r.method,
        r.options.rtol,
        r.options.atol,
        r.trajectory.t.len(),
        r.trajectory.t[0],
        r.trajectory.t[r.trajectory.t.len() - 1],
        r.stats.accepted,
        r.stats.rejected,
        r.stats.rhs_evals,
        r.constraint_drift,
        r.energy_drift,
    );
    if scene.constraints.iter().any(|c| c.kind == ConstraintKind::Position) {
        s.push_str(&format!(", max |h| of the position constraints {:.3e}", r.position_drift));
    }
    if !scene.parameters.is_empty() {
        let p: Vec<String> = scene.parameters.iter().map(|(k, v)| format!("{k}={v:?}")).collect();
        s.push_str(&format!("\nparameters: {}", p.join(", ")));
    }
    if r.kind == ReferenceKind::HardWall {
        s.push_str(&format!(
            "\nhard walls: ideal elastic reflection in the kinetic metric at h = 0 (event location on the dense output){}; {} impacts",
            if scene.walls.iter().any(|w| w.friction > 0.0) { ", friction impulse mu |J_N|" } else { "" },
            r.impacts.len()
        ));
        for (i, im) in r.impacts.iter().enumerate() {
            s.push_str(&format!("\nimpact {}: t = {:?}, wall {}, normal speed {:?}", i + 1, im.t, im.wall, im.normal_speed));
        }
        for (i, c) in r.contacts.iter().enumerate() {
            s.push_str(&format!(
                "\ncontact {}: sliding on wall {} from t = {:?} {}",
                i + 1,
                c.wall,
                c.t_start,
                c.t_end.map_or("to the end".to_string(), |t| format!("to lift-off at t = {t:?}"))
            ));
        }
    }
    s
}
