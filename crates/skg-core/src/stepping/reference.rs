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

use crate::discrete::trajectory::Trajectory;
use crate::model::{Model, Workspace, ON_WALL_TOLERANCE};
use crate::scene::Stepper;
use crate::scene::{ConstraintKind, Location, Scene, SceneError};
use crate::stepping::equations::{integrate_model, min_spacing, rhs, split_states, Stepped};
use crate::stepping::ode::{self, EventHit, OdeOptions, OdeSolution, OdeStats, RhsError};

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

/// What the hard-wall reference does not model, or where its impact and contact laws
/// break down.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HardWallError {
    /// The scene has no walls.
    #[error("scene `{scene}` has no walls; its regularized reference is the reference")]
    NoWalls {
        /// The scene's name.
        scene: String,
    },
    /// The scene has walls and constraints.
    #[error("scene `{scene}` has walls and constraints; impacts of constrained systems are not supported")]
    WallsWithConstraints {
        /// The scene's name.
        scene: String,
    },
    /// A wall's gap depends on the time.
    #[error(
        "wall `{wall}` moves (its h depends on t); the hard-wall reference supports fixed walls only \
         (the regularized reference supports moving walls)"
    )]
    MovingWall {
        /// The wall.
        wall: String,
    },
    /// The initial state lies on a wall that does not push it.
    #[error("the initial state lies on wall `{wall}` and moves away from it or outwards; start strictly inside")]
    StartsLeaving {
        /// The wall.
        wall: String,
    },
    /// The kinetic matrix W is singular.
    #[error("the kinetic matrix is singular")]
    SingularKineticMatrix,
    /// Sliding under velocity-dependent friction comes to rest.
    #[error("wall `{wall}`: the particle comes to rest in contact (sticking under velocity-dependent friction is not supported)")]
    Sticking {
        /// The wall.
        wall: String,
    },
    /// The normal force of sliding contact is undetermined.
    #[error("wall `{wall}`: the contact force law is singular")]
    SingularContactLaw {
        /// The wall.
        wall: String,
    },
    /// The wall's normal ∇h vanishes at an impact.
    #[error("wall `{wall}`: ∇h vanishes at the impact point {q:?}")]
    VanishingNormal {
        /// The wall.
        wall: String,
        /// The impact position.
        q: Vec<f64>,
    },
    /// The declared friction direction vanishes at an impact.
    #[error("wall `{wall}`: the friction direction vanishes at the impact")]
    VanishingFrictionDirection {
        /// The wall.
        wall: String,
    },
    /// The friction impulse cannot reverse the normal velocity.
    #[error("wall `{wall}`: friction impulse law is singular at the impact")]
    SingularFrictionImpulse {
        /// The wall.
        wall: String,
    },
    /// Impacts follow each other ever faster without settling into sliding contact.
    #[error("impacts accumulate near t = {t} on wall `{wall}` (normal speed {normal_speed:.3e}) without settling into contact")]
    ImpactsAccumulate {
        /// The time of the last impact.
        t: f64,
        /// The wall.
        wall: String,
        /// The normal speed at the last impact.
        normal_speed: f64,
    },
}

/// A breakdown of the contact law while sliding fails the integrator's right-hand side.
impl From<HardWallError> for RhsError {
    fn from(e: HardWallError) -> Self {
        RhsError(e.to_string())
    }
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
    /// Integrator options for sampling at `times`: the step is capped at the smallest
    /// sample spacing, so no wall narrower than the grid can be stepped over unseen.
    fn ode(&self, times: &[f64]) -> OdeOptions {
        OdeOptions {
            rtol: self.rtol,
            atol: self.atol,
            max_steps: 20_000_000,
            initial_step: None,
            max_step: min_spacing(times),
            stepper: self.stepper,
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

/// The wall with the largest gap at `q` and that gap.
fn max_gap(model: &Model, t: f64, q: &[f64]) -> (usize, f64) {
    model.wall_gaps(t, q).into_iter().enumerate().fold((0, f64::NEG_INFINITY), |best, (j, h)| if h > best.1 { (j, h) } else { best })
}

/// Sliding on wall `j` (h_j = 0 kept at the acceleration level): the accelerations
/// and the normal force magnitude `N` (≥ 0 while in contact) of
/// `W q̈ = f + F − (∂p/∂q) q̇ − ∂p/∂t − N ∇h + μ N |∇h| d̂`, `∇h·q̈ + q̇ᵀ(∇²h) q̇ = 0`,
/// with `d̂` the wall's friction direction (kinetic Coulomb friction).
fn sliding(model: &Model, ws: &mut Workspace, j: usize, t: f64, q: &[f64], v: &[f64]) -> Result<(Vec<f64>, f64), HardWallError> {
    use nalgebra::{DMatrix, DVector};
    let d = q.len();
    let wall = || model.walls[j].name.clone();
    let ph = model.physical(t, q, v, ws);
    let vv = DVector::from_column_slice(v);
    let rhs = ph.free_force(v);
    let n = DVector::from_vec(model.wall_normal(j, t, q));
    let hm = DMatrix::from_row_slice(d, d, &model.wall_hessian(j, t, q));
    let curv = vv.dot(&(&hm * &vv));
    let mut b = -&n;
    let mu = model.walls[j].friction;
    if mu > 0.0 {
        let dhat = match model.friction_direction(j, t, q, v) {
            Some(dir) => DVector::from_vec(dir),
            None => {
                let nhat = &n / n.norm();
                let vpar = &vv - nhat.dot(&vv) * &nhat;
                if !(vpar.norm() > 1e-12) {
                    return Err(HardWallError::Sticking { wall: wall() });
                }
                -vpar
            }
        };
        b += (mu * n.norm() / dhat.norm()) * dhat;
    }
    let lu = ph.kinetic.lu();
    let a0 = lu.solve(&rhs).ok_or(HardWallError::SingularKineticMatrix)?;
    let wb = lu.solve(&b).ok_or(HardWallError::SingularKineticMatrix)?;
    let den = n.dot(&wb);
    if !(den.abs() > 0.0) {
        return Err(HardWallError::SingularContactLaw { wall: wall() });
    }
    let big_n = -(curv + n.dot(&a0)) / den;
    let acc = a0 + big_n * wb;
    Ok((acc.iter().copied().collect(), big_n))
}

/// Remove the normal velocity of wall `j` (in the kinetic metric).
fn project(model: &Model, j: usize, t: f64, q: &[f64], v: &[f64], w: &nalgebra::DMatrix<f64>) -> Option<Vec<f64>> {
    use nalgebra::DVector;
    let n = DVector::from_vec(model.wall_normal(j, t, q));
    let wn = w.clone().lu().solve(&n)?;
    let vv = DVector::from_column_slice(v);
    let out = &vv - (n.dot(&vv) / n.dot(&wn)) * wn;
    Some(out.iter().copied().collect())
}

/// The velocity after an impact on wall `j` at `q` at time `t` with incoming velocity `v`.
fn reflect(model: &Model, j: usize, t: f64, q: &[f64], v: &[f64], w: &nalgebra::DMatrix<f64>) -> Result<(Vec<f64>, f64), HardWallError> {
    use nalgebra::DVector;
    let d = q.len();
    let wall = || model.walls[j].name.clone();
    let n = DVector::from_vec(model.wall_normal(j, t, q));
    let n_norm = n.norm();
    if !(n_norm > 0.0) {
        return Err(HardWallError::VanishingNormal { wall: wall(), q: q.to_vec() });
    }
    let lu = w.clone().lu();
    let winv = |x: &DVector<f64>| lu.solve(x).ok_or(HardWallError::SingularKineticMatrix);
    let vv = DVector::from_column_slice(v);
    let vn = n.dot(&vv);
    let wn = winv(&n)?;
    let nwn = n.dot(&wn);
    let mut v_new = vv.clone();
    let mu = model.walls[j].friction;
    match (model.friction_direction(j, t, q, v), mu > 0.0) {
        (Some(dir), true) => {
            // Impulse P = −j n + μ j |n| d̂, with j fixed by n·v⁺ = −n·v.
            let mut dhat = DVector::from_vec(dir);
            let dn = dhat.norm();
            if !(dn > 0.0) {
                return Err(HardWallError::VanishingFrictionDirection { wall: wall() });
            }
            dhat /= dn;
            let wd = winv(&dhat)?;
            let denom = nwn - mu * n_norm * n.dot(&wd);
            if !(denom > 0.0) {
                return Err(HardWallError::SingularFrictionImpulse { wall: wall() });
            }
            let jn = 2.0 * vn / denom;
            v_new += (-jn) * &wn + (mu * jn * n_norm) * &wd;
        }
        (None, true) => {
            let jn = 2.0 * vn / nwn;
            v_new -= jn * &wn;
            // Friction against the tangential velocity (Euclidean split, as the
            // regularized force), at most stopping it.
            let nhat = &n / n_norm;
            let vpar = &v_new - nhat.dot(&v_new) * &nhat;
            let speed = vpar.norm();
            if speed > 0.0 {
                let dhat = -&vpar / speed;
                let wd = winv(&dhat)?;
                let along = dhat.dot(&wd);
                let s = (mu * jn * n_norm).min(speed / along);
                v_new += s * &wd;
            }
        }
        _ => {
            v_new -= (2.0 * vn / nwn) * &wn;
        }
    }
    debug_assert_eq!(v_new.len(), d);
    Ok((v_new.iter().copied().collect(), vn / n_norm))
}

/// The velocity along wall `j` (its normal part removed in the kinetic metric `w`) if the
/// wall pushes the particle at (q, v) sliding along it (normal force `N > 0`); `None` if
/// the particle would leave it.
fn slide_if_pushed(
    model: &Model,
    j: usize,
    t: f64,
    q: &[f64],
    v: &[f64],
    w: &nalgebra::DMatrix<f64>,
) -> Result<Option<Vec<f64>>, HardWallError> {
    let vt = project(model, j, t, q, v, w).ok_or(HardWallError::SingularKineticMatrix)?;
    let (_, big_n) = sliding(model, &mut model.workspace(), j, t, q, &vt)?;
    Ok((big_n > 0.0).then_some(vt))
}

/// Integrate from the state `y` over the sample times `ts`: in free flight (no contact)
/// up to the first impact, the first upward zero crossing of the largest gap; or sliding
/// on wall `j` up to lift-off, where the normal force falls to zero.
fn integrate_phase(
    model: &Model,
    contact: Option<usize>,
    y: &[f64],
    ts: &[f64],
    opts: &OdeOptions,
) -> Result<(OdeSolution, Option<EventHit>), ode::OdeError> {
    let d = model.layout.d;
    let mut ws = model.workspace();
    match contact {
        None => ode::integrate_to_event(rhs(model, &mut ws), y, ts, opts, |t, y| max_gap(model, t, &y[..d]).1),
        Some(j) => {
            let mut ws_event = model.workspace();
            let slide = |t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), RhsError> {
                let (a, _) = sliding(model, &mut ws, j, t, &y[..d], &y[d..])?;
                dy[..d].copy_from_slice(&y[d..]);
                dy[d..].copy_from_slice(&a);
                Ok(())
            };
            let lift_off = |t: f64, y: &[f64]| sliding(model, &mut ws_event, j, t, &y[..d], &y[d..]).map_or(f64::NAN, |(_, n)| -n);
            ode::integrate_to_event(slide, y, ts, opts, lift_off)
        }
    }
}

/// Impacts after which the hard-wall integration gives up (a Zeno sequence means the
/// particle is coming to rest on a wall: sustained contact).
const MAX_IMPACTS: usize = 10_000;

/// The hard-wall reference of `scene` sampled at `times` (see the module documentation).
pub fn hard_wall(scene: &Scene, times: &[f64], opts: &ReferenceOptions) -> Result<Reference, ReferenceError> {
    check_times(scene, times)?;
    if opts.stepper == Stepper::Implicit {
        return Err(ReferenceError::ImplicitHardWall);
    }
    let model = hard_wall_model(scene)?;
    let d = scene.coordinates.len();
    let ode_opts = opts.ode(times);
    let vscale = 1.0 + scene.initial_v.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let t0 = times[0];
    // Contact: Some((wall, start time)).
    let (mut y, mut contact) = start_state(scene, &model, t0)?;

    let mut states: Vec<Vec<f64>> = Vec::with_capacity(times.len());
    let mut impacts = Vec::new();
    let mut contacts = Vec::new();
    let mut stats = OdeStats::default();
    let mut t_cur = t0;
    let mut first = true;
    loop {
        // Sample times still to fill; after an event the restart time comes first and
        // its state (the new one) is not a sample.
        let mut ts = Vec::with_capacity(times.len() - states.len() + 1);
        if !first {
            ts.push(t_cur);
        }
        ts.extend_from_slice(&times[states.len()..]);
        let (sol, hit) = integrate_phase(&model, contact.map(|(j, _)| j), &y, &ts, &ode_opts)?;
        stats.add(&sol.stats);
        let skip = usize::from(!first);
        states.extend(sol.states.into_iter().skip(skip));
        first = false;
        let Some(EventHit { t, y: ye }) = hit else { break };
        t_cur = t;
        (y, contact) = match contact.take() {
            Some((j, t0)) => {
                contacts.push(Contact { wall: model.walls[j].name.clone(), t_start: t0, t_end: Some(t) });
                (ye, None)
            }
            None => after_impact(&model, t, &ye[..d], &ye[d..], vscale, &mut impacts)?,
        };
        if states.len() == times.len() {
            break;
        }
    }
    if let Some((j, t0)) = contact {
        contacts.push(Contact { wall: model.walls[j].name.clone(), t_start: t0, t_end: None });
    }
    let mut ws = model.workspace();
    let tr = Trajectory::with_physical_columns(&model, times, split_states(&model, &states, times, &mut ws)?);
    let (constraint_drift, position_drift, energy_drift) = drifts(&tr);
    Ok(Reference {
        trajectory: tr,
        kind: ReferenceKind::HardWall,
        options: *opts,
        stats,
        method: ode::METHOD.to_string(),
        impacts,
        contacts,
        constraint_drift,
        position_drift,
        energy_drift,
    })
}

/// The model of the hard-wall reference: the scene without its wall forces, so that the
/// motion between impacts is the scene's without its walls (building it checks that the
/// start is not beyond a wall). What the reference does not model (no walls, walls and
/// constraints, moving walls) is a property of the scene file: the error names the file
/// and the place that makes it so (the wall's h, the first constraint), like any other
/// error of the scene.
fn hard_wall_model(scene: &Scene) -> Result<Model, ReferenceError> {
    let file = &scene.file;
    let unsupported = |location: Location, e: HardWallError| -> ReferenceError {
        SceneError::Invalid { location, message: format!("hard-wall reference: {e}") }.into()
    };
    if scene.walls.is_empty() {
        return Err(unsupported(file.origin.whole(), HardWallError::NoWalls { scene: scene.name.clone() }));
    }
    if let Some(c) = file.constraints.first() {
        let at = file.origin.locate_in(&c.expression, None);
        return Err(unsupported(at, HardWallError::WallsWithConstraints { scene: scene.name.clone() }));
    }
    let model = Model::with_hard_walls(scene)?;
    if let Some(j) = (0..model.walls.len()).find(|&j| model.wall_moves(j)) {
        let at = file.origin.locate_in(&file.walls[j].h, None);
        return Err(unsupported(at, HardWallError::MovingWall { wall: model.walls[j].name.clone() }));
    }
    Ok(model)
}

/// Where a phase of the hard-wall integration starts: the state `y = (q, v)`, and the
/// wall it slides on with the contact's start time (`None`: free flight).
type PhaseStart = (Vec<f64>, Option<(usize, f64)>);

/// The kinetic matrix ∂²L/∂q̇² at (q, v) at time t: the metric of impacts and sliding.
fn kinetic(model: &Model, t: f64, q: &[f64], v: &[f64]) -> nalgebra::DMatrix<f64> {
    let mut ws = model.workspace();
    model.physical(t, q, v, &mut ws).kinetic
}

/// The start state `y = (q, v)` of the hard-wall reference at `t0`, and the wall it
/// starts sliding on with the start time, if it starts on a wall (within
/// [`ON_WALL_TOLERANCE`]): it slides along it if the wall pushes, and a start that
/// leaves the wall at once is an error.
fn start_state(scene: &Scene, model: &Model, t0: f64) -> Result<PhaseStart, ReferenceError> {
    let d = scene.coordinates.len();
    let mut y: Vec<f64> = scene.initial_q.iter().chain(&scene.initial_v).copied().collect();
    let (j0, h0) = max_gap(model, t0, &scene.initial_q);
    let on_wall_tol = ON_WALL_TOLERANCE * scene.initial_q.iter().fold(1.0_f64, |m, q| m.max(q.abs()));
    if h0 < -on_wall_tol {
        return Ok((y, None));
    }
    let w = kinetic(model, t0, &y[..d], &y[d..]);
    let Some(vt) = slide_if_pushed(model, j0, t0, &y[..d], &y[d..], &w)? else {
        return Err(HardWallError::StartsLeaving { wall: model.walls[j0].name.clone() }.into());
    };
    y[d..].copy_from_slice(&vt);
    Ok((y, Some((j0, t0))))
}

/// The impact at time `t` on the wall the particle at `(q, v)` has reached, recorded in
/// `impacts`, and the state to go on from with the contact it starts: the reflected
/// velocity, or, for a grazing arrival (normal speed at most `1e-7 · vscale`) on a wall
/// that pushes back, sliding along the wall. Impacts that accumulate (more than
/// [`MAX_IMPACTS`], or two within `1e-9` relative in time) are an error.
fn after_impact(model: &Model, t: f64, q: &[f64], v: &[f64], vscale: f64, impacts: &mut Vec<Impact>) -> Result<PhaseStart, ReferenceError> {
    let (j, _) = max_gap(model, t, q);
    let w = kinetic(model, t, q, v);
    let (v_new, vn) = reflect(model, j, t, q, v, &w)?;
    impacts.push(Impact { t, wall: model.walls[j].name.clone(), normal_speed: vn, q: q.to_vec() });
    if vn.abs() <= 1e-7 * vscale {
        if let Some(vt) = slide_if_pushed(model, j, t, q, v, &w)? {
            return Ok((q.iter().chain(&vt).copied().collect(), Some((j, t))));
        }
    }
    if impacts.len() >= MAX_IMPACTS || (impacts.len() > 1 && t - impacts[impacts.len() - 2].t <= 1e-9 * (1.0 + t.abs())) {
        return Err(HardWallError::ImpactsAccumulate { t, wall: model.walls[j].name.clone(), normal_speed: vn }.into());
    }
    Ok((q.iter().chain(&v_new).copied().collect(), None))
}

/// The provenance comment of a reference CSV (deterministic: no dates, no paths other
/// than the scene file as given).
pub fn provenance(scene: &Scene, scene_path: &str, r: &Reference) -> String {
    let mut s = format!(
        "skg-solve {} reference ({}) of {} (scene \"{}\"): {}, rtol {:e}, atol {:e}, step at most the sample spacing; index-reduced Lagrange-d'Alembert equations ([W G^T; G 0] solve for accelerations and multipliers); {} samples from t = {} to {}; {} accepted steps, {} rejected, {} right-hand-side evaluations; max |g| {:.3e}, max |E - E0| {:.3e}",
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
