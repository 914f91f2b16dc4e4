//! The discretization error of an operator on a grid, predicted before solving.
//!
//! Choosing the cheapest discretization that meets a tolerance needs, for every
//! operator and initial-velocity condition and every grid, an estimate of the error the
//! solve would make. Solving each candidate to find out would cost more than the solve
//! itself; this module predicts it from the time-stepping reference alone.
//!
//! **The proxy.** The reference gives the motion `q(t)` with its velocity and its
//! acceleration `a(t) = q̈` (the model's index-reduced equations at the reference
//! state). Apply the candidate discretization to the kinematic problem `q̈ = a(t)`, one
//! coordinate at a time, with `a` known: the interior rows of the action's equations,
//! `D_b (D_a q) = a` (`D_a` the operator of the velocities, `D_b` its summation-by-parts
//! partner in the equations: both `D` for a centred operator), with the candidate's
//! initial conditions (strong: `q[1] = q₀`, `(D_a q)[1] = v₀`; natural:
//! `q[1] = q₀` and the first row's momentum balance `−H₁₁ (D_b D_a q)[1] − (D_a q)[1] =
//! −H₁₁ a[1] − v₀`), the last row absorbed as in the action (docs/mathematics.md §5).
//! Its solution differs from the reference by the operator's own error for *this*
//! motion: the interior truncation error, the boundary closures (with the cancellation
//! that makes them one order better than their rows), the initial condition's offset,
//! and contacts too short for the grid, where `a` is large. What the proxy leaves out is
//! the dynamics' feedback (forces that depend on the state, constraints, damping): its
//! ratio to the true error depends on the scene, and is calibrated by the solves made
//! ([`refine`](super::refine)).
//!
//! Measured on the rolling disk (closed form), N = 33 … 1025, the four centred operators
//! with both initial-velocity conditions: the true error over the proxy stays within
//! 0.16 … 2.6 over all 48 grids, and for one operator and condition within a factor 1.6
//! from N = 65 on; the proxy's order is the observed order (docs/solver.md#refinement).
//!
//! The cost is one time-stepping reference per grid (sampled with accelerations at its
//! nodes) and, per candidate, one banded LU of the grid's size ([`band`](crate::solve::linalg::band)) with one
//! right-hand side per coordinate: a fraction of one solve's.

use std::collections::HashMap;
use std::sync::Arc;

use crate::discrete::discretization::operator_on;
use crate::discrete::grid::{uniform_times, TimeMap};
use crate::discrete::trajectory::{NodeSeries, Trajectory};
use crate::model::Model;
use crate::sbp::{OperatorKind, SbpOperator};
use crate::scene::{InitialVelocity, Scene};
use crate::solve::linalg::band::solve_banded;
use crate::solve::run::error::SolveError;
use crate::stepping::equations::{integrate_states, min_spacing, step_budget, Stepped};
use crate::stepping::ode::{OdeOptions, OdeStats};
use crate::stepping::verify::{self, REFERENCE_ATOL, REFERENCE_RTOL};

/// The constant of the rounding error's estimate ([`Predictor::roundoff_ratio`]),
/// bounded by measurement: the rolling disk (max |q| = 31) on SBP484 with the natural
/// condition has a total error of 4.8e-10 at N = 1025 (the bound's 3.6e-10 there is
/// below it), 1.5e-8 at 513.
pub const ROUNDOFF: f64 = 0.05;

/// A proxy whose solve's own rounding error exceeds this fraction of it says nothing
/// of the operator's error: it is extrapolated from coarser grids instead. (The
/// dissipative operators' proxy systems are ill-conditioned: on the damped oscillator
/// SBP484-AD's proxy at N = 513 is 3.6× the tolerance 1e-8, of which its rounding 2.3×,
/// and grows with N beyond; the solves verify at N = 800 with 0.1×, the extrapolation
/// from N = 129 and 257 predicts 0.1×.)
pub const NOISY: f64 = 0.1;

/// A discretization a solve can be made with: the operator, the condition that
/// imposes the initial velocity, and whether the nodes follow the motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Candidate {
    /// The SBP operator.
    pub operator: OperatorKind,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
    /// On the adaptive grid (the predictor's map), else on the uniform one.
    pub adaptive: bool,
}

impl Candidate {
    /// Every candidate a choice considers: each operator, centred and dissipative, with
    /// the strong condition, and with the natural one except where it leaves the
    /// odd-even mode free (`SBP121`: the knife edge converges to a wrong trajectory,
    /// docs/mathematics.md §5; `SBP121-AD` damps it).
    pub fn all() -> Vec<Candidate> {
        let mut all = Vec::new();
        for operator in OperatorKind::ALL {
            all.push(Candidate { operator, initial_velocity: InitialVelocity::Strong, adaptive: false });
            if operator != OperatorKind::Sbp121 {
                all.push(Candidate { operator, initial_velocity: InitialVelocity::Natural, adaptive: false });
            }
        }
        all
    }

    /// The same candidate on the adaptive grid.
    pub fn adaptive(self) -> Candidate {
        Candidate { adaptive: true, ..self }
    }

    /// `"SBP242 (natural)"`, `"SBP242 (natural, adaptive grid)"`.
    pub fn describe(&self) -> String {
        let grid = if self.adaptive { ", adaptive grid" } else { "" };
        format!("{} ({}{grid})", self.operator.name(), self.initial_velocity)
    }
}

/// The finest grid the reference is sampled on at once: every grid of `(FINE − 1)/2^j + 1`
/// nodes is a subgrid of it, sampled without integrating again (one integration costs
/// as much as all its samples).
pub const FINE_NODES: usize = (1 << 12) + 1;

/// The reference sampled on one grid: states and accelerations at its nodes.
struct Samples {
    q: NodeSeries,
    v: NodeSeries,
    a: NodeSeries,
}

/// Predicted errors of the candidates on grids of a scene, from its time-stepping
/// reference (see the module docs). Samples and predictions are cached per grid: a grid
/// is its node count and whether it is the adaptive one (`true`) or uniform.
pub struct Predictor<'a> {
    scene: &'a Scene,
    model: &'a Model,
    /// The adaptive grid's map, when adaptive candidates are weighed.
    map: Option<Arc<TimeMap>>,
    /// The verification's tolerance of each coordinate.
    tolerances: Vec<f64>,
    /// Where the tolerances came from (the verification's words).
    pub tolerance_source: String,
    samples: HashMap<(usize, bool), Samples>,
    /// The reference's states on the uniform grid of [`FINE_NODES`] nodes.
    fine: Option<(NodeSeries, NodeSeries)>,
    /// The reference's relative tolerance ([`verify::reference_rtol`]).
    rtol: f64,
    proxies: HashMap<(Candidate, usize), f64>,
    /// The motion's size, `max |q|` over the fine grid (at least 1), for the rounding
    /// error ([`Predictor::roundoff_ratio`], asked for at every prediction).
    size: f64,
    /// The adaptive grid's conditioning factors `T Σᵢ 1/hᵢ` and `(N − 1) T / h_min`, by
    /// node count ([`Predictor::roundoff_ratio`]; a refinement's search asks for the
    /// same grids again and again).
    conditioning: HashMap<usize, (f64, f64)>,
    /// The time stepping done for the predictions.
    pub steps: OdeStats,
}

impl<'a> Predictor<'a> {
    /// A predictor for `scene`, whose tolerances are those the verification applies,
    /// found from the reference on the scene's own grid; with `map`, the adaptive grid's,
    /// for the adaptive candidates.
    pub fn new(scene: &'a Scene, model: &'a Model, map: Option<Arc<TimeMap>>) -> Result<Predictor<'a>, SolveError> {
        let mut p = Predictor {
            scene,
            model,
            map,
            tolerances: Vec::new(),
            tolerance_source: String::new(),
            samples: HashMap::new(),
            fine: None,
            size: 1.0,
            rtol: REFERENCE_RTOL,
            proxies: HashMap::new(),
            conditioning: HashMap::new(),
            steps: OdeStats::default(),
        };
        let (mut q, mut v) = p.integrate((FINE_NODES, false), REFERENCE_RTOL)?;
        let (tolerances, source) = verify::tolerances(scene, &q);
        let rtol = verify::reference_rtol(&tolerances, &q);
        if rtol < REFERENCE_RTOL {
            (q, v) = p.integrate((FINE_NODES, false), rtol)?;
        }
        p.rtol = rtol;
        p.size = q.iter().flatten().fold(1.0_f64, |m, x| m.max(x.abs()));
        p.fine = Some((q, v));
        p.tolerances = tolerances;
        p.tolerance_source = source;
        Ok(p)
    }

    /// The verification's tolerance of each coordinate.
    pub fn tolerances(&self) -> &[f64] {
        &self.tolerances
    }

    /// The rounding error of a solve on `nodes` nodes relative to the tightest
    /// tolerance: [`ROUNDOFF`] `· ε · T Σᵢ 1/hᵢ · max |q|` over the grid's steps `hᵢ`
    /// and its span `T`. A rounding error of relative size ε in the equation of a node
    /// whose steps are `h` is about `ε |q| / h²` in the acceleration; the discrete
    /// Green's function of `q̈ = a` (of size `h T` for that node) carries it into `q` as
    /// `ε |q| T / h`, and the bound sums the nodes: `(N − 1)²` on the uniform grid (the
    /// conditioning of a second-order operator), less on the adaptive grid, whose fine
    /// steps are few. No grid is predicted below it: beyond some N, refining makes the
    /// error worse.
    ///
    /// A dissipative operator on the adaptive grid is bounded as if every step were the
    /// finest, `(N − 1) T / h_min`: its systems there are worse conditioned than the
    /// sum says. Measured on van der Pol at μ = 1000
    /// (`crates/skg-core/tests/scenes/stiff/van_der_pol_1000.toml`, natural condition,
    /// adaptive grid of 16 385 … 32 769 nodes): `SBP363` and `SBP484` fall from 0.11 and
    /// 0.025 of the tolerance to 0.004 and 0.0016, while `SBP363-AD` and `SBP484-AD`
    /// stay at 2.6 to 11 times it (their equations at 26 896 nodes no longer reach 1e-8).
    /// For a centred operator the finest step alone was 28 times too pessimistic on the
    /// damped spring of `scenarios/damped_spring_stiffness.toml` at `c = 464`: every
    /// adaptive grid above 3743 nodes was predicted beyond the tolerance of 1e-6, where
    /// `SBP363` verifies on 2134 nodes and `SBP484-AD` measured 0.45 of it on 6000.
    pub fn roundoff_ratio(&mut self, c: Candidate, nodes: usize) -> f64 {
        let tightest = self.tolerances.iter().copied().fold(f64::INFINITY, f64::min);
        let steps = (nodes - 1) as f64;
        let conditioning = match (&self.map, c.adaptive) {
            (Some(map), true) => {
                let (sum, finest) = *self.conditioning.entry(nodes).or_insert_with(|| {
                    let t = map.times(nodes);
                    let span = t[nodes - 1] - t[0];
                    let sum = t.windows(2).map(|w| span / (w[1] - w[0])).sum();
                    (sum, steps * span / min_spacing(&t).unwrap_or(f64::MIN_POSITIVE))
                });
                if c.operator.is_dissipative() {
                    finest
                } else {
                    sum
                }
            }
            _ => steps * steps,
        };
        ROUNDOFF * f64::EPSILON * conditioning * self.size / tightest
    }

    /// Whether the adaptive candidates can be predicted (a map was given).
    pub fn has_map(&self) -> bool {
        self.map.is_some()
    }

    /// The adaptive grid's map, if any.
    pub fn map(&self) -> Option<&Arc<TimeMap>> {
        self.map.as_ref()
    }

    /// The node times of the grid `(nodes, adaptive)`.
    fn times(&self, (nodes, adaptive): (usize, bool)) -> Vec<f64> {
        match (&self.map, adaptive) {
            (Some(map), true) => map.times(nodes),
            _ => uniform_times(self.scene.t_start, self.scene.t_end, nodes),
        }
    }

    /// The reference on the grid `(nodes, adaptive)` as a trajectory with its physical
    /// columns (for the contacts' resolution).
    pub fn reference(&mut self, grid: (usize, bool)) -> Result<Trajectory, SolveError> {
        self.sample(grid)?;
        let s = &self.samples[&grid];
        let states = crate::discrete::trajectory::States { q: s.q.clone(), v: s.v.clone(), lambda: vec![Vec::new(); s.q.len()] };
        Ok(Trajectory::with_physical_columns(self.model, &self.times(grid), states))
    }

    /// The reference's states on the grid `(nodes, adaptive)`, integrated anew. With
    /// walls its steps are at most the scene's own node spacing, as the verification's.
    fn integrate(&mut self, grid: (usize, bool), rtol: f64) -> Result<(NodeSeries, NodeSeries), SolveError> {
        let nodes = grid.0;
        let t = self.times(grid);
        let opts = OdeOptions {
            rtol,
            atol: rtol * (REFERENCE_ATOL / REFERENCE_RTOL),
            max_step: if self.model.walls.is_empty() {
                None
            } else {
                min_spacing(&uniform_times(self.scene.t_start, self.scene.t_end, self.scene.nodes))
            },
            max_steps: step_budget(nodes.max(self.scene.nodes)),
            stepper: self.scene.verify.stepper,
            ..OdeOptions::default()
        };
        let Stepped { states, stats: steps, .. } = integrate_states(self.model, &self.scene.initial_q, &self.scene.initial_v, &t, &opts)
            .map_err(|e| SolveError::Prediction(format!("time stepping of the scene failed: {e}")))?;
        self.steps.add(&steps);
        let d = self.scene.coordinates.len();
        Ok(states.into_iter().map(|y| (y[..d].to_vec(), y[d..].to_vec())).unzip())
    }

    /// Sample the reference with its accelerations on the grid `(nodes, adaptive)`, once:
    /// from the fine grid of the same kind when it is a subgrid of it, else integrated
    /// anew.
    fn sample(&mut self, grid: (usize, bool)) -> Result<(), SolveError> {
        if self.samples.contains_key(&grid) {
            return Ok(());
        }
        let (nodes, adaptive) = grid;
        let samples = if nested(nodes) && nodes < FINE_NODES && self.fine.is_some() {
            // Every subgrid strides through the fine grid's samples, accelerations too.
            self.sample((FINE_NODES, adaptive))?;
            let fine = &self.samples[&(FINE_NODES, adaptive)];
            let stride = (FINE_NODES - 1) / (nodes - 1);
            let every = |s: &NodeSeries| s.iter().step_by(stride).cloned().collect();
            Samples { q: every(&fine.q), v: every(&fine.v), a: every(&fine.a) }
        } else {
            let (q, v) = match &self.fine {
                Some((fq, fv)) if grid == (FINE_NODES, false) => (fq.clone(), fv.clone()),
                _ => self.integrate(grid, self.rtol)?,
            };
            let a = self.accelerations(&self.times(grid), &q, &v)?;
            Samples { q, v, a }
        };
        self.samples.insert(grid, samples);
        Ok(())
    }

    /// The model's accelerations at the states `q`, `v` at the times `t`.
    fn accelerations(&self, t: &[f64], q: &NodeSeries, v: &NodeSeries) -> Result<NodeSeries, SolveError> {
        let mut ws = self.model.workspace();
        t.iter()
            .zip(q.iter().zip(v))
            .map(|(&tk, (q, v))| self.model.accelerations(tk, q, v, &mut ws).map(|(a, _)| a))
            .collect::<Result<NodeSeries, _>>()
            .map_err(|e| SolveError::Prediction(format!("the accelerations along the reference: {e}")))
    }

    /// [`ratio`](Self::ratio) on a grid of the ladder `(FINE_NODES − 1)·2^k + 1` (`k` of
    /// either sign: the fine grid's subgrids, and the grids that contain it); between two
    /// of them, interpolated in log-log (the proxy decreases as a power of N between
    /// them), so that predicting for any N costs no new time stepping below the fine grid
    /// and one per doubling above it (the adaptive grid's proxy is computed up to
    /// 65 537 nodes, `estimate::ADAPTIVE_PROXY_MAX_NODES`: each node count a
    /// refinement's bisection tried was a time stepping of its own, 41 % of the
    /// refinement of van der Pol at μ = 20).
    pub fn ratio_between(&mut self, c: Candidate, nodes: usize) -> Result<f64, SolveError> {
        if on_the_ladder(nodes) {
            return self.ratio(c, nodes);
        }
        let mut hi = FINE_NODES;
        if nodes > FINE_NODES {
            while hi < nodes {
                hi = 2 * (hi - 1) + 1;
            }
        } else {
            while (hi - 1) / 2 + 1 >= nodes && hi > 3 {
                hi = (hi - 1) / 2 + 1;
            }
        }
        let lo = (hi - 1) / 2 + 1;
        if lo < c.operator.min_nodes() {
            return self.ratio(c, nodes);
        }
        let (r_lo, r_hi) = (self.ratio(c, lo)?, self.ratio(c, hi)?);
        if !(r_lo.is_finite() && r_hi.is_finite() && r_lo > 0.0 && r_hi > 0.0) {
            return self.ratio(c, nodes);
        }
        Ok(along_power_law(lo, r_lo, observed_order(lo, r_lo, hi, r_hi), nodes))
    }

    /// The proxy's error of `c` on the grid of `nodes` nodes, relative to the
    /// tolerance: max over coordinates of error / tolerance (∞ where the operator does
    /// not fit the grid or the proxy cannot be solved).
    pub fn ratio(&mut self, c: Candidate, nodes: usize) -> Result<f64, SolveError> {
        if let Some(&r) = self.proxies.get(&(c, nodes)) {
            return Ok(r);
        }
        let ratio = if nodes < c.operator.min_nodes() || (c.adaptive && self.map.is_none()) {
            f64::INFINITY
        } else {
            let grid = (nodes, c.adaptive);
            self.sample(grid)?;
            let (errors, floors) = proxy_errors(&self.samples[&grid], c, &self.times(grid));
            let relative = |e: &[f64]| e.iter().zip(&self.tolerances).map(|(e, tol)| e / tol).fold(0.0, f64::max);
            let (raw, floor) = (relative(&errors), relative(&floors));
            if floor > NOISY * raw {
                self.beyond_the_floor(c, nodes)?.unwrap_or(raw)
            } else {
                raw
            }
        };
        let ratio = if ratio.is_nan() { f64::INFINITY } else { ratio };
        self.proxies.insert((c, nodes), ratio);
        Ok(ratio)
    }

    /// The proxy's error of `c` on a subgrid of the fine grid whose own proxy is lost in
    /// the rounding of its solve: extrapolated from the two coarser subgrids with the
    /// order between them (`None` where they do not give one).
    fn beyond_the_floor(&mut self, c: Candidate, nodes: usize) -> Result<Option<f64>, SolveError> {
        let half = |n: usize| (n - 1) / 2 + 1;
        let (m, m2) = (half(nodes), half(half(nodes)));
        // Two halvings of the grid keep every other node (of a uniform grid and of a map's).
        if !(nested(nodes) || (nodes - 1).is_multiple_of(4)) || m2 < c.operator.min_nodes().max(3) {
            return Ok(None);
        }
        let (r1, r2) = (self.ratio(c, m)?, self.ratio(c, m2)?);
        let order = observed_order(m2, r2, m, r1);
        Ok((order.is_finite() && order > 0.0).then(|| along_power_law(m, r1, order, nodes)))
    }
}

/// The order `p` of a proxy that falls as `(N − 1)^(−p)` from `r_lo` on `lo` nodes to
/// `r_hi` on `hi` nodes (not finite, or not positive, where it does not fall).
pub fn observed_order(lo: usize, r_lo: f64, hi: usize, r_hi: f64) -> f64 {
    (r_lo / r_hi).ln() / ((hi - 1) as f64 / (lo - 1) as f64).ln()
}

/// The power law of order `order` through `r` on `from` nodes, on `nodes` nodes.
pub fn along_power_law(from: usize, r: f64, order: f64, nodes: usize) -> f64 {
    r * ((from - 1) as f64 / (nodes - 1) as f64).powf(order)
}

/// Whether a grid of `nodes` nodes is on the ladder `(FINE_NODES − 1)·2^k + 1`.
fn on_the_ladder(nodes: usize) -> bool {
    nested(nodes)
        || (nodes > FINE_NODES && (nodes - 1).is_multiple_of(FINE_NODES - 1) && ((nodes - 1) / (FINE_NODES - 1)).is_power_of_two())
}

/// Whether the grid of `nodes` nodes is a subgrid of the fine one.
fn nested(nodes: usize) -> bool {
    (2..=FINE_NODES).contains(&nodes) && (FINE_NODES - 1).is_multiple_of(nodes - 1)
}

/// The rows of an operator, row `i` being `entries[offsets[i]..offsets[i + 1]]`.
struct Rows {
    offsets: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

impl Rows {
    fn of(op: &SbpOperator) -> Rows {
        let n = op.len();
        let (mut offsets, mut entries) = (Vec::with_capacity(n + 1), Vec::with_capacity(n * 9));
        offsets.push(0);
        for i in 0..n {
            op.push_row(i, &mut entries);
            offsets.push(entries.len());
        }
        Rows { offsets, entries }
    }

    fn row(&self, i: usize) -> &[(usize, f64)] {
        &self.entries[self.offsets[i]..self.offsets[i + 1]]
    }
}

/// Row `i` of a product `D_b D_a`, times `scale`, appended to `out` as the entries of
/// row `out_row`: each column once (an interior row of `SBP484`'s product has 17
/// columns, where the products of the two stencils' entries are 81). `dense` is scratch.
fn push_product_row(b: &[(usize, f64)], da: &Rows, scale: f64, out_row: usize, dense: &mut Vec<f64>, out: &mut Vec<(usize, usize, f64)>) {
    let columns = || b.iter().flat_map(|&(j, _)| da.row(j).iter().map(|&(k, _)| k));
    let (Some(first), Some(last)) = (columns().min(), columns().max()) else { return };
    dense.clear();
    dense.resize(last - first + 1, 0.0);
    for &(j, bj) in b {
        for &(k, a) in da.row(j) {
            dense[k - first] += bj * a;
        }
    }
    out.extend(dense.iter().enumerate().filter(|&(_, &v)| v != 0.0).map(|(k, &v)| (out_row, first + k, scale * v)));
}

/// The proxy's error max_k |q_h − q| of each coordinate (see the module docs) on the
/// nodes `times`, and the rounding error of its solve; infinite when its system is
/// singular.
fn proxy_errors(s: &Samples, c: Candidate, times: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let d = s.q.first().map_or(0, Vec::len);
    let n = times.len();
    let singular = || (vec![f64::INFINITY; d], vec![f64::INFINITY; d]);
    let Ok(op) = operator_on(c.operator, times, c.adaptive) else { return singular() };
    let da = Rows::of(&op);
    // The equations' operator D_b: the partner D− of a dissipative operator, D itself
    // for a centred one.
    let db = Rows::of(&op.partner());
    let h0 = op.norm()[0];
    // The rows in an order that keeps the system banded: the initial position, the
    // initial-velocity condition (the action's last row), then the interior equations.
    let natural = c.initial_velocity == InitialVelocity::Natural;
    let mut dense = Vec::new();
    let mut entries: Vec<(usize, usize, f64)> = Vec::with_capacity(n * 24);
    entries.push((0, 0, 1.0));
    if natural {
        push_product_row(db.row(0), &da, -h0, 1, &mut dense, &mut entries);
    }
    entries.extend(da.row(0).iter().map(|&(k, v)| (1, k, if natural { -v } else { v })));
    for i in 1..n - 1 {
        push_product_row(db.row(i), &da, 1.0, i + 1, &mut dense, &mut entries);
    }
    // The unknown is the motion less its initial straight line, q0 + v0·(t − t0), which
    // every operator differentiates exactly: the rounding errors of the proxy then scale
    // with what remains (the disk's θ grows by 31 rad, 5 of them curved).
    let line = |i: usize, k: usize| s.q[0][i] + s.v[0][i] * (times[k] - times[0]);
    // Columns 0..d: the proxies. Columns d..2d: the same system with the right-hand
    // side it gives the sampled motion itself, whose solution is that motion up to the
    // rounding of the solve (the proxy's floor).
    let mut rhs = vec![0.0; 2 * n * d];
    for i in 0..d {
        let b = &mut rhs[i * n..(i + 1) * n];
        b[1] = if natural { -h0 * s.a[0][i] } else { 0.0 };
        for k in 1..n - 1 {
            b[k + 1] = s.a[k][i];
        }
        let exact = &mut rhs[(d + i) * n..(d + i + 1) * n];
        for &(r, col, v) in &entries {
            exact[r] += v * (s.q[col][i] - line(i, col));
        }
    }
    if !solve_banded(n, &entries, &mut rhs, 2 * d) {
        return singular();
    }
    let deviation = |col: usize, i: usize| (0..n).map(|k| (rhs[col * n + k] - (s.q[k][i] - line(i, k))).abs()).fold(0.0, f64::max);
    ((0..d).map(|i| deviation(i, i)).collect(), (0..d).map(|i| deviation(d + i, i)).collect())
}
