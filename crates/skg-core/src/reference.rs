//! Reference solutions of a scene, independent of the SBP discretization (docs/validation.md).
//!
//! * **Regularized** ([`regularized`]): the Lagrange–d'Alembert equations of exactly the
//!   scene the solver discretizes (same TOML, same symbolic model and derivatives,
//!   Gaussian walls included) integrated by the DOP853 of [`crate::ode`] at a tight
//!   tolerance and sampled at the requested times from its dense output. Velocity
//!   constraints enter index-reduced: accelerations and multipliers solve
//!   `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) q̇; −(∂g/∂q) q̇]` ([`Model::accelerations`]), so
//!   `g = 0` holds only up to the integrator's drift, which is reported (the `residual_*`
//!   columns and `max |g|` in the provenance). The distance of a solve from this reference
//!   is its *discretization error*.
//! * **Hard-wall** ([`hard_wall`]): the same scene with every wall an ideal elastic wall,
//!   the σ → 0 limit of the Gaussian wall. Between impacts the particle moves under the
//!   scene's other forces; an impact is the first upward zero crossing of `max_j h_j(q)`,
//!   located on the dense output ([`ode::integrate_to_event`]); the velocity is then
//!   reflected in the kinetic metric `W`: `v⁺ = v − 2 (n·v)/(nᵀW⁻¹n) W⁻¹n` with `n = ∇h`.
//!   A wall with friction adds the limit of its friction force over the (vanishing)
//!   contact time: an impulse `μ |J_N|` along the wall's `friction_direction` (the
//!   paper's fixed direction), or, without one, against the tangential velocity and
//!   capped so that it at most stops the tangential motion (Coulomb). The distance of a
//!   solve from this reference is its *model error* (plus its discretization error).
//!
//!
//! Sustained contact — a start on a wall, or an arrival with vanishing normal speed
//! (`≤ 1e-7 (1 + max|q̇₀|)`) — while the wall pushes (`N > 0`): the motion is constrained to
//! `h_j = 0` (index-reduced: `∇h·q̈ + q̇ᵀ∇²h q̇ = 0`) with kinetic Coulomb friction
//! `μ N |∇h| d̂` along the friction direction, until lift-off, located as the zero crossing
//! of `N` ([`Contact`] phases are listed in the provenance).
//!
//! Not covered, each an error rather than a wrong answer: walls together with velocity
//! constraints (the impact law would have to respect the constraints), sticking under
//! velocity-dependent friction (a particle coming to rest in contact), and impacts that
//! accumulate without settling into contact.

// `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// `SceneError` (wrapped in `ReferenceError`) is large; it is the crate-wide error type.
#![allow(clippy::result_large_err)]
use std::path::Path;

use crate::model::Model;
use crate::ode::{self, EventHit, OdeOptions, OdeStats};
use crate::output::{self, OutputError};
use crate::scenario::{Scene, SceneError};
use crate::solve::Trajectory;
use skg_expr::{ExprId, Graph, Symbol};

/// Values per node: `series[k][i]` is component i at node k.
pub type NodeSeries = Vec<Vec<f64>>;

/// Errors of building a reference.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("integrating the Lagrange–d'Alembert equations failed: {0}")]
    Ode(#[from] ode::OdeError),
    #[error("hard-wall reference: {0}")]
    HardWall(String),
    #[error("bad sample times: {0}")]
    Times(String),
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Settings of a reference integration.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct ReferenceOptions {
    pub rtol: f64,
    pub atol: f64,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { rtol: 1e-12, atol: 1e-12 }
    }
}

impl ReferenceOptions {
    /// Integrator options for sampling at `times`: the step is capped at the smallest
    /// sample spacing, so no wall narrower than the grid can be stepped over unseen.
    fn ode(&self, times: &[f64]) -> OdeOptions {
        OdeOptions { rtol: self.rtol, atol: self.atol, max_steps: 20_000_000, initial_step: None, max_step: min_spacing(times) }
    }
}

/// Smallest spacing of increasing sample times (None for fewer than two samples).
pub fn min_spacing(times: &[f64]) -> Option<f64> {
    times.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).reduce(f64::min)
}

/// One impact of the hard-wall reference.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Impact {
    pub t: f64,
    pub wall: String,
    /// Outward normal speed `n̂·v` just before the impact.
    pub normal_speed: f64,
    /// Position at the impact.
    pub q: Vec<f64>,
}

/// A phase of sustained contact of the hard-wall reference: sliding along a wall.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Contact {
    pub wall: String,
    pub t_start: f64,
    /// Lift-off time; `None` if still in contact at the end.
    pub t_end: Option<f64>,
}

/// A reference trajectory and how it was made.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Same layout as the solver's trajectory (CSV columns via [`output::trajectory_rows`]).
    pub trajectory: Trajectory,
    /// "regularized" or "hard-wall".
    pub kind: &'static str,
    pub options: ReferenceOptions,
    pub stats: OdeStats,
    /// Impacts (hard-wall reference only).
    pub impacts: Vec<Impact>,
    /// Phases of sustained contact (hard-wall reference only).
    pub contacts: Vec<Contact>,
    /// max |g^a| over the samples: the drift of the index-reduced integration.
    pub constraint_drift: f64,
    /// max |E − E(t₀)| over the samples.
    pub energy_drift: f64,
}

/// Integrate the index-reduced Lagrange–d'Alembert equations of `model` from `(q0, v0)`
/// and sample `(q, v, λ)` at `times` (the code path shared by the solver's initial guess,
/// [`crate::solve::time_stepping`]).
#[allow(clippy::type_complexity)]
pub fn integrate_model(
    model: &Model,
    q0: &[f64],
    v0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
) -> Result<(NodeSeries, NodeSeries, NodeSeries, OdeStats), ode::OdeError> {
    let d = q0.len();
    let mut ws = model.workspace();
    let y0: Vec<f64> = q0.iter().chain(v0).copied().collect();
    let sol = ode::integrate(rhs(model, &mut model.workspace()), &y0, times, opts)?;
    let (q, v, lam) = split_states(model, &sol.states, times, &mut ws, d)?;
    Ok((q, v, lam, sol.stats))
}

/// The right-hand side `(q, v) ↦ (v, q̈)` of the index-reduced equations.
fn rhs<'a>(model: &'a Model, ws: &'a mut crate::model::Workspace) -> impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String> + 'a {
    let d = model.layout.d;
    move |_, y, dy| {
        let (a, _) = model.accelerations(&y[..d], &y[d..], ws)?;
        dy[..d].copy_from_slice(&y[d..]);
        dy[d..].copy_from_slice(&a);
        Ok(())
    }
}

#[allow(clippy::type_complexity)]
fn split_states(
    model: &Model,
    states: &[Vec<f64>],
    times: &[f64],
    ws: &mut crate::model::Workspace,
    d: usize,
) -> Result<(NodeSeries, NodeSeries, NodeSeries), ode::OdeError> {
    let mut q = Vec::with_capacity(states.len());
    let mut v = Vec::with_capacity(states.len());
    let mut lam = Vec::with_capacity(states.len());
    for (k, y) in states.iter().enumerate() {
        let (_, l) = model.accelerations(&y[..d], &y[d..], ws).map_err(|msg| ode::OdeError::Rhs { t: times[k], msg })?;
        q.push(y[..d].to_vec());
        v.push(y[d..].to_vec());
        lam.push(l);
    }
    Ok((q, v, lam))
}

fn check_times(scene: &Scene, times: &[f64]) -> Result<(), ReferenceError> {
    if times.is_empty() {
        return Err(ReferenceError::Times("no sample times".into()));
    }
    if let Some(i) = times.windows(2).position(|w| !(w[1] > w[0])) {
        return Err(ReferenceError::Times(format!(
            "sample times must increase strictly: t[{}] = {} is followed by {}",
            i,
            times[i],
            times[i + 1]
        )));
    }
    if (times[0] - scene.t_start).abs() > 1e-12 * (1.0 + scene.t_start.abs()) {
        return Err(ReferenceError::Times(format!(
            "the first sample time {} must be the scene's start time {} (where its initial state is given)",
            times[0], scene.t_start
        )));
    }
    Ok(())
}

/// The trajectory with its physical columns (energy, constraint residuals, gaps).
fn with_physical_columns(
    model: &Model,
    times: &[f64],
    (q, v, lambda): (NodeSeries, NodeSeries, NodeSeries),
    walls: Option<&WallSet>,
) -> Trajectory {
    let mut tr = Trajectory { t: times.to_vec(), q, v, lambda, energy: vec![], wall_energy: vec![], g: vec![], h: vec![] };
    let mut ws = model.workspace();
    for k in 0..tr.t.len() {
        let ph = model.physical(&tr.q[k], &tr.v[k], &mut ws);
        tr.energy.push(ph.energy);
        // A hard wall's potential is 0 on the allowed side (the σ → 0 limit of A·Φ(h/σ)).
        tr.wall_energy.push(if walls.is_some() { 0.0 } else { ph.wall_energy });
        tr.g.push(ph.g);
        tr.h.push(match walls {
            Some(w) => w.h(&tr.q[k]),
            None => ph.h,
        });
    }
    tr
}

fn drifts(tr: &Trajectory) -> (f64, f64) {
    let g = tr.g.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    // Total energy: mechanical plus the walls' potential.
    let total: Vec<f64> = tr.energy.iter().zip(&tr.wall_energy).map(|(e, w)| e + w).collect();
    let e = total.iter().fold(0.0_f64, |m, x| m.max((x - total[0]).abs()));
    (g, e)
}

/// The regularized reference of `scene` sampled at `times` (the first one must be the
/// scene's start time).
pub fn regularized(scene: &Scene, times: &[f64], opts: &ReferenceOptions) -> Result<Reference, ReferenceError> {
    check_times(scene, times)?;
    let model = Model::build(scene)?;
    let (q, v, lambda, stats) = integrate_model(&model, &scene.initial_q, &scene.initial_v, times, &opts.ode(times))?;
    let tr = with_physical_columns(&model, times, (q, v, lambda), None);
    let (constraint_drift, energy_drift) = drifts(&tr);
    Ok(Reference {
        trajectory: tr,
        kind: "regularized",
        options: *opts,
        stats,
        impacts: vec![],
        contacts: vec![],
        constraint_drift,
        energy_drift,
    })
}

/// Geometry of the walls: `h_j(q)`, `∇h_j(q)` and the friction direction, evaluated on
/// the scene's expressions.
struct WallSet {
    graph: Graph,
    names: Vec<String>,
    h: Vec<ExprId>,
    grad: Vec<Vec<ExprId>>,
    /// ∂²h/∂q_i∂q_k, row-major d×d.
    hess: Vec<Vec<ExprId>>,
    friction: Vec<f64>,
    direction: Vec<Option<Vec<ExprId>>>,
}

impl WallSet {
    fn build(scene: &Scene) -> Result<WallSet, ReferenceError> {
        let file = &scene.file;
        let coords = scene.coordinates.clone();
        let params = scene.parameters.clone();
        let mut resolve = |name: &str| -> Option<Symbol> {
            if let Some(i) = coords.iter().position(|c| c == name) {
                return Some(Symbol::Var(i));
            }
            params.get(name).map(|v| Symbol::Const(*v))
        };
        let mut graph = Graph::new();
        let d = scene.coordinates.len();
        let mut set =
            WallSet { graph: Graph::new(), names: vec![], h: vec![], grad: vec![], hess: vec![], friction: vec![], direction: vec![] };
        for (spec, wall) in file.walls.iter().zip(&scene.walls) {
            // The model has already parsed these expressions, with velocities allowed in
            // the friction direction only; here positions only are expected.
            let key = format!("walls.{}.h", wall.name);
            let h = graph.parse(spec.h.get_ref(), &mut resolve).map_err(|e| file.expression_error(&spec.h, &key, e))?;
            let grad: Vec<ExprId> = (0..d).map(|i| graph.diff(h, i)).collect();
            let hess = grad.iter().flat_map(|&gi| (0..d).map(move |k| (gi, k))).collect::<Vec<_>>();
            let hess = hess.into_iter().map(|(gi, k)| graph.diff(gi, k)).collect();
            let direction = match &spec.friction_direction {
                Some(dir) if wall.friction > 0.0 => {
                    let mut comps = Vec::new();
                    for (i, src) in dir.iter().enumerate() {
                        let key = format!("walls.{}.friction_direction[{i}]", wall.name);
                        comps.push(graph.parse(src.get_ref(), &mut resolve).map_err(|e| file.expression_error(src, &key, e))?);
                    }
                    Some(comps)
                }
                _ => None,
            };
            set.names.push(wall.name.clone());
            set.h.push(h);
            set.grad.push(grad);
            set.hess.push(hess);
            set.friction.push(wall.friction);
            set.direction.push(direction);
        }
        set.graph = graph;
        Ok(set)
    }

    fn h(&self, q: &[f64]) -> Vec<f64> {
        self.graph.eval_many(&self.h, q)
    }

    fn max_h(&self, q: &[f64]) -> (usize, f64) {
        self.h(q).into_iter().enumerate().fold((0, f64::NEG_INFINITY), |best, (j, h)| if h > best.1 { (j, h) } else { best })
    }

    /// Sliding on wall `j` (h_j = 0 kept at the acceleration level): the accelerations
    /// and the normal force magnitude `N` (≥ 0 while in contact) of
    /// `W q̈ = f + F − (∂p/∂q) q̇ − N ∇h + μ N |∇h| d̂`, `∇h·q̈ + q̇ᵀ(∇²h) q̇ = 0`,
    /// with `d̂` the wall's friction direction (kinetic Coulomb friction).
    fn contact(&self, model: &Model, ws: &mut crate::model::Workspace, j: usize, q: &[f64], v: &[f64]) -> Result<(Vec<f64>, f64), String> {
        use nalgebra::{DMatrix, DVector};
        let d = q.len();
        let ph = model.physical(q, v, ws);
        let vv = DVector::from_column_slice(v);
        let rhs = DVector::from_column_slice(&ph.force) - &ph.dpdq * &vv;
        let n = DVector::from_vec(self.graph.eval_many(&self.grad[j], q));
        let hm = DMatrix::from_row_slice(d, d, &self.graph.eval_many(&self.hess[j], q));
        let curv = vv.dot(&(&hm * &vv));
        let mut b = -&n;
        let mu = self.friction[j];
        if mu > 0.0 {
            let dhat = match &self.direction[j] {
                Some(dir) => DVector::from_vec(self.graph.eval_many(dir, q)),
                None => {
                    let nhat = &n / n.norm();
                    let vpar = &vv - nhat.dot(&vv) * &nhat;
                    if !(vpar.norm() > 1e-12) {
                        return Err(format!(
                            "wall `{}`: the particle comes to rest in contact (sticking under velocity-dependent friction is not supported)",
                            self.names[j]
                        ));
                    }
                    -vpar
                }
            };
            b += (mu * n.norm() / dhat.norm()) * dhat;
        }
        let lu = ph.kinetic.lu();
        let a0 = lu.solve(&rhs).ok_or("the kinetic matrix is singular")?;
        let wb = lu.solve(&b).ok_or("the kinetic matrix is singular")?;
        let den = n.dot(&wb);
        if !(den.abs() > 0.0) {
            return Err(format!("wall `{}`: the contact force law is singular", self.names[j]));
        }
        let big_n = -(curv + n.dot(&a0)) / den;
        let acc = a0 + big_n * wb;
        Ok((acc.iter().copied().collect(), big_n))
    }

    /// Remove the normal velocity of wall `j` (in the kinetic metric).
    fn project(&self, j: usize, q: &[f64], v: &[f64], w: &nalgebra::DMatrix<f64>) -> Option<Vec<f64>> {
        use nalgebra::DVector;
        let n = DVector::from_vec(self.graph.eval_many(&self.grad[j], q));
        let wn = w.clone().lu().solve(&n)?;
        let vv = DVector::from_column_slice(v);
        let out = &vv - (n.dot(&vv) / n.dot(&wn)) * wn;
        Some(out.iter().copied().collect())
    }

    /// The velocity after an impact on wall `j` at `q` with incoming velocity `v`.
    fn reflect(&self, j: usize, q: &[f64], v: &[f64], w: &nalgebra::DMatrix<f64>) -> Result<(Vec<f64>, f64), String> {
        use nalgebra::DVector;
        let d = q.len();
        let n = DVector::from_vec(self.graph.eval_many(&self.grad[j], q));
        let n_norm = n.norm();
        if !(n_norm > 0.0) {
            return Err(format!("wall `{}`: ∇h vanishes at the impact point {q:?}", self.names[j]));
        }
        let lu = w.clone().lu();
        let winv = |x: &DVector<f64>| lu.solve(x).ok_or_else(|| "the kinetic matrix is singular at the impact".to_string());
        let vv = DVector::from_column_slice(v);
        let vn = n.dot(&vv);
        let wn = winv(&n)?;
        let nwn = n.dot(&wn);
        let mut v_new = vv.clone();
        let mu = self.friction[j];
        match (&self.direction[j], mu > 0.0) {
            (Some(dir), true) => {
                // Impulse P = −j n + μ j |n| d̂, with j fixed by n·v⁺ = −n·v.
                let mut dhat = DVector::from_vec(self.graph.eval_many(dir, q));
                let dn = dhat.norm();
                if !(dn > 0.0) {
                    return Err(format!("wall `{}`: the friction direction vanishes at the impact", self.names[j]));
                }
                dhat /= dn;
                let wd = winv(&dhat)?;
                let denom = nwn - mu * n_norm * n.dot(&wd);
                if !(denom > 0.0) {
                    return Err(format!("wall `{}`: friction impulse law is singular at the impact", self.names[j]));
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
}

/// Impacts after which the hard-wall integration gives up (a Zeno sequence means the
/// particle is coming to rest on a wall: sustained contact).
const MAX_IMPACTS: usize = 10_000;

/// The hard-wall reference of `scene` sampled at `times` (see the module documentation).
pub fn hard_wall(scene: &Scene, times: &[f64], opts: &ReferenceOptions) -> Result<Reference, ReferenceError> {
    check_times(scene, times)?;
    if scene.walls.is_empty() {
        return Err(ReferenceError::HardWall(format!("scene `{}` has no walls; its regularized reference is the reference", scene.name)));
    }
    if !scene.constraints.is_empty() {
        return Err(ReferenceError::HardWall(format!(
            "scene `{}` has walls and velocity constraints; impacts of constrained systems are not supported",
            scene.name
        )));
    }
    let walls = WallSet::build(scene)?;
    // The same scene without its walls: the motion between impacts.
    let mut free = scene.clone();
    free.file.walls.clear();
    free.walls.clear();
    let model = Model::build(&free)?;
    let d = scene.coordinates.len();
    let ode_opts = opts.ode(times);
    let vscale = 1.0 + scene.initial_v.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let kinetic = |q: &[f64], v: &[f64]| {
        let mut ws = model.workspace();
        model.physical(q, v, &mut ws).kinetic
    };
    let hard = |m: String| ReferenceError::HardWall(m);

    let mut y: Vec<f64> = scene.initial_q.iter().chain(&scene.initial_v).copied().collect();
    let (j0, h0) = walls.max_h(&scene.initial_q);
    let on_wall_tol = 1e-12 * (1.0 + scene.initial_q.iter().fold(0.0_f64, |m, q| m.max(q.abs())));
    // Contact: Some((wall, start time)).
    let mut contact: Option<(usize, f64)> = None;
    if h0 > on_wall_tol {
        return Err(hard(format!("the initial state is outside the walls (max h = {h0:.3e})")));
    }
    if h0 >= -on_wall_tol {
        // Starting on a wall: slide along it if it pushes, else leave it.
        let w = kinetic(&y[..d], &y[d..]);
        let vt = walls.project(j0, &y[..d], &y[d..], &w).ok_or_else(|| hard("singular kinetic matrix".into()))?;
        let mut ws = model.workspace();
        let (_, big_n) = walls.contact(&model, &mut ws, j0, &y[..d], &vt).map_err(hard)?;
        if big_n > 0.0 {
            y[d..].copy_from_slice(&vt);
            contact = Some((j0, times[0]));
        } else {
            return Err(hard(format!(
                "the initial state lies on wall `{}` and moves away from it or outwards; start strictly inside",
                walls.names[j0]
            )));
        }
    }

    let mut states: Vec<Vec<f64>> = Vec::with_capacity(times.len());
    let mut impacts = Vec::new();
    let mut contacts = Vec::new();
    let mut stats = OdeStats::default();
    let mut t_cur = times[0];
    let mut first = true;
    loop {
        // Sample times still to fill; after an event the restart time comes first and
        // its state (the new one) is not a sample.
        let mut ts = Vec::with_capacity(times.len() - states.len() + 1);
        if !first {
            ts.push(t_cur);
        }
        ts.extend_from_slice(&times[states.len()..]);
        let (sol, hit) = match contact {
            None => {
                let mut ws = model.workspace();
                ode::integrate_to_event(rhs(&model, &mut ws), &y, &ts, &ode_opts, |_, y| walls.max_h(&y[..d]).1)?
            }
            Some((j, _)) => {
                let mut ws = model.workspace();
                let mut ws_e = model.workspace();
                let walls_ref = &walls;
                let model_ref = &model;
                ode::integrate_to_event(
                    move |_, y: &[f64], dy: &mut [f64]| {
                        let (a, _) = walls_ref.contact(model_ref, &mut ws, j, &y[..d], &y[d..])?;
                        dy[..d].copy_from_slice(&y[d..]);
                        dy[d..].copy_from_slice(&a);
                        Ok(())
                    },
                    &y,
                    &ts,
                    &ode_opts,
                    // Lift-off: the normal force falls to zero.
                    |_, y| walls.contact(&model, &mut ws_e, j, &y[..d], &y[d..]).map_or(f64::NAN, |(_, n)| -n),
                )?
            }
        };
        stats.accepted += sol.stats.accepted;
        stats.rejected += sol.stats.rejected;
        stats.rhs_evals += sol.stats.rhs_evals;
        let skip = usize::from(!first);
        states.extend(sol.states.into_iter().skip(skip));
        first = false;
        let Some(EventHit { t, y: ye }) = hit else { break };
        t_cur = t;
        if let Some((j, t0)) = contact.take() {
            contacts.push(Contact { wall: walls.names[j].clone(), t_start: t0, t_end: Some(t) });
            y = ye;
            if states.len() == times.len() {
                break;
            }
            continue;
        }
        let (j, _) = walls.max_h(&ye[..d]);
        let w = kinetic(&ye[..d], &ye[d..]);
        let (v_new, vn) = walls.reflect(j, &ye[..d], &ye[d..], &w).map_err(hard)?;
        impacts.push(Impact { t, wall: walls.names[j].clone(), normal_speed: vn, q: ye[..d].to_vec() });
        if vn.abs() <= 1e-7 * vscale {
            // Grazing arrival: slide along the wall if it pushes back.
            let vt = walls.project(j, &ye[..d], &ye[d..], &w).ok_or_else(|| hard("singular kinetic matrix".into()))?;
            let mut ws = model.workspace();
            let (_, big_n) = walls.contact(&model, &mut ws, j, &ye[..d], &vt).map_err(hard)?;
            if big_n > 0.0 {
                contact = Some((j, t));
                y = ye[..d].iter().chain(&vt).copied().collect();
                if states.len() == times.len() {
                    break;
                }
                continue;
            }
        }
        if impacts.len() >= MAX_IMPACTS || (impacts.len() > 1 && t - impacts[impacts.len() - 2].t <= 1e-9 * (1.0 + t.abs())) {
            return Err(hard(format!(
                "impacts accumulate near t = {t} on wall `{}` (normal speed {vn:.3e}) without settling into contact",
                walls.names[j]
            )));
        }
        y = ye[..d].iter().chain(&v_new).copied().collect();
        if states.len() == times.len() {
            break;
        }
    }
    if let Some((j, t0)) = contact {
        contacts.push(Contact { wall: walls.names[j].clone(), t_start: t0, t_end: None });
    }
    let mut ws = model.workspace();
    let columns = split_states(&model, &states, times, &mut ws, d)?;
    let tr = with_physical_columns(&model, times, columns, Some(&walls));
    let (constraint_drift, energy_drift) = drifts(&tr);
    Ok(Reference { trajectory: tr, kind: "hard-wall", options: *opts, stats, impacts, contacts, constraint_drift, energy_drift })
}

/// The provenance comment of a reference CSV (deterministic: no dates, no paths other
/// than the scene file as given).
pub fn provenance(scene: &Scene, scene_path: &str, r: &Reference) -> String {
    let mut s = format!(
        "skg-solve {} reference ({}) of {} (scene \"{}\"): {}, rtol {:e}, atol {:e}, step at most the sample spacing; index-reduced Lagrange-d'Alembert equations ([W G^T; G 0] solve for accelerations and multipliers); {} samples from t = {} to {}; {} accepted steps, {} rejected, {} right-hand-side evaluations; max |g| {:.3e}, max |E - E0| {:.3e}",
        env!("CARGO_PKG_VERSION"),
        r.kind,
        scene_path,
        scene.name,
        ode::METHOD,
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
    if !scene.parameters.is_empty() {
        let p: Vec<String> = scene.parameters.iter().map(|(k, v)| format!("{k}={v:?}")).collect();
        s.push_str(&format!("\nparameters: {}", p.join(", ")));
    }
    if r.kind == "hard-wall" {
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

/// Write a reference as a trajectory CSV with the provenance as `#` lines.
pub fn write(path: &Path, scene: &Scene, scene_path: &str, r: &Reference) -> Result<(), ReferenceError> {
    let header = output::trajectory_header(scene);
    output::write_csv(path, Some(&provenance(scene, scene_path, r)), &header, &output::trajectory_rows(&r.trajectory))?;
    Ok(())
}
