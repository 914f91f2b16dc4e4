//! The hard-wall reference ([`hard_wall`], module documentation of
//! [`reference`](super)): the scene with every wall ideal and elastic. Its laws, each
//! named after what it computes: the wall with the largest gap, the impact (the velocity
//! reflected in the kinetic metric, with the friction impulse), sustained sliding
//! (index-reduced, Coulomb friction, until lift-off), and the phases of free flight and
//! sliding between impacts, integrated by DOP853 with events.

use super::{check_times, drifts, Contact, Impact, Reference, ReferenceError, ReferenceKind, ReferenceOptions};
use crate::discrete::trajectory::Trajectory;
use crate::model::{Model, Workspace, ON_WALL_TOLERANCE};
use crate::scene::{Location, Scene, SceneError, Stepper};
use crate::stepping::equations::{rhs, split_states};
use crate::stepping::ode::{self, EventHit, OdeOptions, OdeSolution, OdeStats, RhsError};
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

/// Refuse a scene the hard-wall reference does not model (no walls, walls with
/// constraints, a moving wall), with the error [`hard_wall`] would give, before anything
/// is integrated: a sweep measuring its points against this reference checks its base
/// scene once, up front.
pub fn check_hard_walls(scene: &Scene) -> Result<(), ReferenceError> {
    hard_wall_model(scene).map(|_| ())
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
