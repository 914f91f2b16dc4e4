//! Solving to the accuracy asked for: the grid refined, and the operator chosen, until
//! the verification passes (`--refine`, `--operator auto`; without them a solve is the
//! scene's own solve and the fallback ladder, [`ladder`]):
//!
//! * **`--operator auto`** (or a refinement with no operator named): among the
//!   candidates ([`Candidate::all`]: `SBP121` … `SBP484`, each with the strong and, above
//!   `SBP121`, the natural initial-velocity condition) the one predicted to meet the
//!   tolerance at the least cost ([`cost`](super::cost): measured time per node of each
//!   operator and backend). Without `--refine` on the scene's grid; if none is predicted
//!   to meet it there, the one predicted most accurate.
//! * **The grid** (`grid = "auto"`, the default when the operator is chosen): each
//!   candidate also on the adaptive grid ([`adapt`]), weighed with a
//!   penalty on its cost (`estimate`), where the map's spacings vary enough to matter.
//! * **`--refine`**: the scene's own solve with the fallback ladder, on the scene's grid
//!   (with the chosen operator when it chooses one); while the result is not verified,
//!   or did not converge, a solve on the next discretization: the one of least cost
//!   predicted to meet the tolerance, on a grid no coarser than the last. Each solve
//!   after the first starts from the most accurate converged solution so far,
//!   interpolated (cubic Hermite), and climbs only the rung that changes its initial
//!   guess (the wall-width continuation).
//!
//! **The prediction.** The error of candidate `c` on `N` nodes is predicted as
//! `G_c · P_c(N)`: `P_c(N)` the proxy of [`predict`](super::predict) (the discretization
//! applied to the reference's own kinematics, relative to the tolerance), `G_c` its
//! calibration: the measured error over the proxy of the last solve with `c`, else the
//! largest measured with its family of operators or, within limits, the other
//! (`calibration`), else 1. The next grid aims at [`AIM`] of the
//! tolerance, never below the nodes a wall's contacts need ([`MIN_STEPS`] grid steps
//! per contact, from the reference), and grows at least by [`MIN_GROWTH`] once a grid
//! failed with the same candidate (by 2 when it did not converge). So the proxy carries
//! the order observed on the grids the scene actually needs (contacts included), and the
//! solves made carry the scene's dynamics. When the reference cannot be computed, no
//! prediction is made and each grid doubles.
//!
//! The refinement stops at a verified solve, at the budget (`--max-nodes`; by default
//! the largest grid the memory estimate allows, at most [`MAX_NODES_DEFAULT`]), before a
//! grid whose solve would end past the time limit (`--time-limit`; by default
//! [`REFINE_COST_FACTOR`] times the first grid's solve or [`REFINE_FLOOR_S`] seconds,
//! whichever is longer; the next grid's time estimated from the last one's, in
//! proportion to the nodes), and at once on a grid that failed for a reason more nodes
//! will not cure (`Refiner::incurable`): a verification that could not run, a backend
//! that stopped at a loose `[solver] tol` above the residual a converged solve needs, or
//! an error that did not fall on a finer grid. Every discretization solved is listed in
//! `summary.json` (`refinement`); the reported solution is the verified one, else the
//! most accurate converged one.

use std::sync::Arc;
use std::time::Instant;

use super::adapt;
use super::estimate::{calibration, cost_of, proxy_ratio};
use super::predict::{observed_order, Candidate, Predictor};
use crate::discrete::contact::{self, MIN_STEPS};
use crate::discrete::discretization::operator_on;
use crate::discrete::interpolate::{hermite, linear};
use crate::discrete::{Discretization, Grid, TimeMap};
use crate::memory;
use crate::model::Model;
use crate::sbp::{OperatorKind, SbpError};
use crate::scene::Scene;
use crate::solve::ladder::{self, Rungs};
use crate::solve::run::deadline::{Bound, Deadline, Limits};
use crate::solve::run::error::SolveError;
use crate::solve::run::outcome::{Outcome, RefinedGrid, Refinement, Work};
use crate::solve::run::piece::Guess;
use crate::stepping::verify::VerifyStatus;

mod stop;

/// A refinement without `--time-limit` may take this many times its first grid's solve
/// (or [`REFINE_FLOOR_S`], whichever is longer).
pub const REFINE_COST_FACTOR: f64 = 30.0;
/// The least time a refinement without `--time-limit` may take, seconds.
pub const REFINE_FLOOR_S: f64 = 60.0;
/// The verdict of a grid the refinement passed over: an adaptive grid too uneven for the
/// operator's boundary closures (docs/grids.md#limits).
pub const TOO_UNEVEN: &str = "not solved: the grid is too uneven for the operator's boundary closures";
/// The bound of the refinement's budget, for its deadline and its messages.
const REFINE_BUDGET: Bound = Bound::Budget { of: "the refinement", first: "grid", factor: REFINE_COST_FACTOR, floor_s: REFINE_FLOOR_S };

/// What to do when the refinement stopped at its time limit.
const LONGER: &str = "a longer --time-limit lets the refinement go on to finer grids";

/// The fraction of the tolerance the next grid aims at.
pub const AIM: f64 = 0.5;
/// The least growth of the grid after a failure with the same candidate.
pub const MIN_GROWTH: f64 = 1.25;
/// The budget of a refinement when neither `--max-nodes` nor the memory sets a lower one.
pub const MAX_NODES_DEFAULT: usize = 1 << 20;
/// From this grid on, the proxy's order between two grids is trusted to extrapolate how
/// many nodes the aim needs (coarser grids can be before the asymptotic range).
const EXTRAPOLATE_FROM: usize = 257;
/// A later grid starts from the most accurate converged solution so far only when that
/// solution is within this many times the tolerance of the time stepping; else from the
/// time stepping. (The stiff dumbbell: `SBP242` on 256 nodes converged 658 times the
/// tolerance away, through the stiff spring's odd-even mode; `SBP242-AD` started from it
/// did not converge, and with the natural condition converged 660 times away, where
/// each, started from the time stepping, is within the tolerance.)
const GUESS_FROM_SOLUTION_UP_TO: f64 = 10.0;
/// A first grid predicted at more than this many times the tolerance is not solved: it
/// cannot pass, and the refinement starts on the grid predicted to.
const HOPELESS: f64 = 16.0;

/// The refinement or the operator choice of `scene` with its model `model` (module
/// docs), stopped at `deadline` (the time limit) or, without one, at its budget (checked
/// inside the solves too); `progress` is told what each grid and attempt is about
/// to do ("grid 2: SBP484 (natural) on 513 nodes").
pub(crate) fn refine(
    scene: &Scene,
    model: &Arc<Model>,
    own: &Discretization,
    deadline: Option<Deadline>,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, SolveError> {
    Refiner::new(scene, model, own, Limits { time_limit: deadline, budget: None })?.run(progress)
}

/// The state of a refinement.
struct Refiner<'a> {
    scene: &'a Scene,
    model: &'a Arc<Model>,
    /// The scene's own discretization (with the natural initial-velocity condition when
    /// the front door chose it for a fast initial layer).
    own: Discretization,
    /// The time limit, and the refinement's budget once its first grid is solved.
    limits: Limits,
    /// When the refinement started.
    started: Instant,
    /// The predictor, unless its reference could not be computed (then: why not).
    predictor: Result<Predictor<'a>, String>,
    /// The adaptive grid's map, when adaptive candidates are solved.
    map: Option<Arc<TimeMap>>,
    candidates: Vec<Candidate>,
    /// The measured error over the proxy of the last solve with each candidate.
    calibration: Vec<(Candidate, f64)>,
    /// The least nodes each candidate may be solved on next (after a failure with it).
    floor: Vec<(Candidate, usize)>,
    /// The nodes the walls' contacts need on the uniform grid and on the adaptive one.
    wall_nodes: [usize; 2],
    max_nodes: usize,
    max_nodes_source: String,
    grids: Vec<RefinedGrid>,
    /// The most accurate converged outcome so far and its error relative to the
    /// tolerance, and the first trusted one.
    best: Option<(Outcome, f64)>,
    /// The outcome of the first grid (reported when nothing converged).
    first: Option<Outcome>,
    prediction_s: f64,
    /// The work of every grid solved.
    work: Work,
}

impl<'a> Refiner<'a> {
    fn new(scene: &'a Scene, model: &'a Arc<Model>, own: &Discretization, limits: Limits) -> Result<Refiner<'a>, SolveError> {
        let t = Instant::now();
        let map = match &own.grid {
            Grid::Mapped(map) => Some(Arc::clone(map)),
            Grid::Uniform if scene.choose_grid => adapt::motion_map(scene, model)
                .ok()
                .filter(|(map, _)| map.spacing_ratio() >= adapt::WORTH_ADAPTING)
                .map(|(map, _)| Arc::new(map)),
            Grid::Uniform => None,
        };
        let predictor = Predictor::new(scene, model, map.clone()).map_err(|e| e.to_string());
        // A condition the front door chose (for an initial layer) is kept, as a named one.
        let iv_chosen = scene.choose_initial_velocity && own.initial_velocity == scene.initial_velocity;
        let mut candidates: Vec<Candidate> = if scene.choose_operator {
            Candidate::all().into_iter().filter(|c| iv_chosen || c.initial_velocity == own.initial_velocity).collect()
        } else {
            vec![own_candidate(own)]
        };
        // The adaptive grid beside the uniform one when the grid is chosen, in its place
        // when it is the scene's.
        if map.is_some() {
            let adaptive = candidates.iter().map(|c| c.adaptive());
            candidates = if scene.choose_grid { candidates.iter().copied().chain(adaptive).collect() } else { adaptive.collect() };
        }
        let (max_nodes, max_nodes_source) = budget(scene);
        let mut r = Refiner {
            scene,
            model,
            own: own.clone(),
            limits,
            started: t,
            predictor,
            map,
            candidates,
            calibration: Vec::new(),
            floor: Vec::new(),
            wall_nodes: [0, 0],
            max_nodes,
            max_nodes_source,
            grids: Vec::new(),
            best: None,
            first: None,
            prediction_s: 0.0,
            work: Work::default(),
        };
        r.wall_nodes = [r.nodes_for_contacts(false), r.nodes_for_contacts(true)];
        r.prediction_s = t.elapsed().as_secs_f64();
        Ok(r)
    }

    /// The nodes at which the reference's contacts take [`MIN_STEPS`] grid steps each
    /// (0 without walls or without a reference): below, no solve of a scene with walls
    /// was measured to verify; above, the prediction decides (the proxy sees a contact
    /// too short for the grid as a large acceleration).
    fn nodes_for_contacts(&mut self, adaptive: bool) -> usize {
        let nodes = self.scene.nodes;
        // Without walls, no time stepping on the scene's grid for it.
        if self.model.walls.is_empty() {
            return 0;
        }
        let Ok(p) = self.predictor.as_mut() else { return 0 };
        if adaptive && !p.has_map() {
            return 0;
        }
        let Ok(reference) = p.reference((nodes, adaptive)) else { return 0 };
        let resolution = contact::resolution(self.model, &reference);
        let fewest = resolution.values().map(|r| r.steps).fold(f64::INFINITY, f64::min);
        if !fewest.is_finite() || fewest >= MIN_STEPS {
            return 0;
        }
        // A contact of almost no steps asks for more nodes than any budget (and than a
        // usize holds): the budget then decides.
        ((nodes - 1) as f64 * MIN_STEPS / fewest).ceil().min(MAX_NODES_DEFAULT as f64 * 1024.0) as usize + 1
    }

    fn calibration_of(&self, c: Candidate) -> f64 {
        calibration(&self.calibration, c)
    }

    fn floor_of(&self, c: Candidate) -> usize {
        let own = self.floor.iter().rev().find(|(k, _)| *k == c).map_or(0, |&(_, n)| n);
        own.max(self.scene.nodes).max(self.wall_nodes[usize::from(c.adaptive)]).max(c.operator.min_nodes())
    }

    /// The predicted error of `c` on `nodes` nodes relative to the tolerance, calibrated.
    fn predicted(&mut self, c: Candidate, nodes: usize) -> Option<f64> {
        let g = self.calibration_of(c);
        let t = Instant::now();
        let r = match self.predictor.as_mut() {
            Ok(p) => proxy_ratio(p, c, nodes).ok(),
            Err(_) => None,
        };
        self.prediction_s += t.elapsed().as_secs_f64();
        r.map(|r| g * r)
    }

    /// The least nodes ≥ `from` at which `c` is predicted to meet [`AIM`] of the
    /// tolerance, and the prediction there (`None`: not within the budget, or not for
    /// less than `cost_cap`, the cost of a candidate already found).
    fn nodes_to_meet(&mut self, c: Candidate, from: usize, cost_cap: f64) -> Option<(usize, f64)> {
        let from = from.min(self.max_nodes);
        let backend = self.scene.solver.backend;
        let too_dear = |n: f64| cost_of(c, backend, 1) * n >= cost_cap;
        // No grid of `from` nodes or more can cost less than the candidate already found.
        if too_dear(from as f64) {
            return None;
        }
        let at_from = self.predicted(c, from)?;
        if at_from <= AIM {
            return Some((from, at_from));
        }
        // Up the grids of 2^j + 1 nodes (on which the proxy is computed; between them it
        // is interpolated) until the aim is met, then interpolate in log-log between the
        // last two.
        let (mut lo, mut r_lo) = (from, at_from);
        loop {
            let p = (lo - 1).next_power_of_two();
            let hi = if p + 1 > lo { p + 1 } else { 2 * p + 1 }.min(self.max_nodes);
            if hi <= lo || too_dear(lo as f64) {
                return None;
            }
            let r_hi = self.predicted(c, hi)?;
            if r_hi <= AIM {
                return self.least_meeting(c, lo, hi, r_hi);
            }
            if r_hi.partial_cmp(&r_lo) != Some(std::cmp::Ordering::Less) {
                // The proxy stopped improving (round-off): the aim is out of reach.
                return None;
            }
            // Past the first grids, the order between the last two tells whether the aim
            // is within the budget at all: no need to compute the proxy up to it.
            let order = observed_order(lo, r_lo, hi, r_hi);
            if hi >= EXTRAPOLATE_FROM && order > 0.0 {
                let needed = (hi - 1) as f64 * (r_hi / AIM).powf(1.0 / order);
                if needed > 2.0 * self.max_nodes as f64 || too_dear(needed / 2.0) {
                    return None;
                }
            }
            (lo, r_lo) = (hi, r_hi);
        }
    }

    /// The least grid in `(lo, hi]` at which `c` is predicted to meet the aim, given that
    /// it does on `hi` (with `r_hi`) and not on `lo`: by bisection, since a prediction
    /// between the grids the proxy is computed on is interpolated and costs nothing.
    fn least_meeting(&mut self, c: Candidate, mut lo: usize, mut hi: usize, mut r_hi: f64) -> Option<(usize, f64)> {
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            let r = self.predicted(c, mid)?;
            if r <= AIM {
                (hi, r_hi) = (mid, r);
            } else {
                lo = mid;
            }
        }
        Some((hi, r_hi))
    }

    /// The next discretization: the candidate and grid of least predicted cost that
    /// meet the aim, or, without predictions, the next grid of the one candidate.
    fn next(&mut self) -> Option<(Candidate, usize, Option<f64>)> {
        if self.predictor.is_err() {
            let c = *self.candidates.first()?;
            let n = self.floor_of(c);
            return (n <= self.max_nodes).then_some((c, n, None));
        }
        let backend = self.scene.solver.backend;
        let mut best: Option<(f64, Candidate, usize, f64)> = None;
        // The highest orders first: they usually need the fewest nodes, and the cost of
        // the best found so far bounds the search of the others.
        let mut candidates = self.candidates.clone();
        candidates.sort_by_key(|c| std::cmp::Reverse(c.operator.interior_order()));
        for c in candidates {
            let from = self.floor_of(c);
            if from > self.max_nodes {
                continue;
            }
            let cap = best.as_ref().map_or(f64::INFINITY, |b| b.0);
            if let Some((n, r)) = self.nodes_to_meet(c, from, cap) {
                let cost = cost_of(c, backend, n);
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, c, n, r));
                }
            }
        }
        best.map(|(_, c, n, r)| (c, n, Some(r)))
    }

    /// When no discretization is predicted to meet the tolerance within the budget but no
    /// solve on a kind of grid (uniform, adaptive) has converged yet, the predictions on it
    /// are the proxy's alone, uncalibrated, and can be off by orders of magnitude (van der
    /// Pol at μ = 1000 on its adaptive grid: 36 904 times the tolerance predicted on 4096
    /// nodes with `SBP484`, 90 measured; the damped spring of
    /// `scenarios/damped_spring_stiffness.toml` at `c = 1e4`, whose initial layer the
    /// natural condition skips: `SBP484-AD` on the uniform 129 nodes 5.8e12 predicted,
    /// 0.02 measured, after the adaptive grid had failed on 129 and 585 nodes): the
    /// candidate of such a kind not yet solved that is predicted the most accurate on its
    /// first grid (the scene's, or more for contacts) is solved there, or, when nothing has
    /// converged and every one has been solved, `c` (the last) on its floor, so that a
    /// converged solve calibrates the predictions. `None` once both kinds are calibrated,
    /// or beyond the budget.
    fn uncalibrated_retry(&mut self, c: Candidate) -> Option<(Candidate, usize, Option<f64>)> {
        // The adaptive grid's calibrations say nothing of the uniform grid's proxy, nor
        // the other way round.
        let calibrated = |adaptive: bool| self.calibration.iter().any(|(k, _)| k.adaptive == adaptive);
        let nothing_calibrated = !calibrated(false) && !calibrated(true);
        let untried: Vec<Candidate> =
            self.candidates.iter().copied().filter(|k| !calibrated(k.adaptive) && self.floor.iter().all(|(f, _)| f != k)).collect();
        let mut best: Option<(f64, Candidate, usize)> = None;
        for k in untried {
            let n = self.floor_of(k);
            if n > self.max_nodes {
                continue;
            }
            if let Some(r) = self.predicted(k, n).filter(|r| best.is_none_or(|b| *r < b.0)) {
                best = Some((r, k, n));
            }
        }
        if let Some((r, k, n)) = best {
            return Some((k, n, Some(r)));
        }
        let n = self.floor_of(c);
        (nothing_calibrated && n <= self.max_nodes).then_some((c, n, None))
    }

    /// The first discretization: the scene's own, with the chosen candidate when it
    /// chooses one (the cheapest predicted to meet the aim on the scene's grid, else the
    /// most accurate there).
    fn first_choice(&mut self) -> (Candidate, usize, Option<f64>) {
        let nodes = self.scene.nodes;
        let own = own_candidate(&self.own);
        if !self.scene.choose_operator && !self.scene.choose_grid {
            let p = self.predicted(own, nodes);
            return (own, nodes, p);
        }
        let backend = self.scene.solver.backend;
        let mut scored: Vec<(Candidate, f64, f64)> = Vec::new();
        for c in self.candidates.clone() {
            if let Some(r) = self.predicted(c, nodes) {
                scored.push((c, r, cost_of(c, backend, nodes)));
            }
        }
        let meeting = scored.iter().filter(|s| s.1 <= AIM).min_by(|a, b| a.2.total_cmp(&b.2));
        let chosen = meeting.or_else(|| scored.iter().min_by(|a, b| a.1.total_cmp(&b.1)));
        match chosen {
            Some(&(c, r, _)) => (c, nodes, Some(r)),
            None => (*self.candidates.first().unwrap_or(&own), nodes, None),
        }
    }

    fn run(mut self, progress: &mut dyn FnMut(&str)) -> Result<Outcome, SolveError> {
        // The scene's grid first, unless it is predicted hopeless (or, when the operator
        // is chosen, to miss the aim: the next grid's candidate may differ).
        let first = self.first_choice();
        let skip_first = self.scene.verify.refine && first.2.is_some_and(|r| r > HOPELESS || (self.scene.choose_operator && r > AIM));
        let (mut c, mut nodes, mut predicted) = if skip_first { self.next().unwrap_or(first) } else { first };
        // The result in words, and what to do about it when it is not a verified solve
        // (`None`: the remedy of the reported grid's own solve).
        let (result, advice): (String, Option<String>) = loop {
            let number = self.grids.len() + 1;
            let what = format!("{} on {nodes} nodes", c.describe());
            // A grid beyond the memory ends the refinement, unless it is the first.
            if let Err(e) = memory::check(self.scene, "the solve", nodes, memory::solve_bytes_with(self.scene, c.operator, nodes)) {
                if self.grids.is_empty() {
                    return Err(e.into());
                }
                break (format!("stopped before grid {number} ({what}): {e}"), Some("loosen the tolerance".to_string()));
            }
            // An adaptive grid too uneven for the operator's boundary closures is passed
            // over for a finer one (the map is graded for the scene's nodes and gentler
            // on more), unless nothing finer is left.
            if let Err(e) = self.operator_fits(c, nodes) {
                self.passed_over(c, nodes, predicted);
                match self.next().or_else(|| self.uncalibrated_retry(c)) {
                    Some(next) => {
                        (c, nodes, predicted) = next;
                        continue;
                    }
                    None if self.first.is_none() => return Err(e.into()),
                    None => break self.out_of_budget(),
                }
            }
            progress(&format!("grid {number}: {what}"));
            let outcome = self.solve_on(c, nodes, predicted, &mut |step: &str| progress(&format!("grid {number} ({what}), {step}")))?;
            let trusted = outcome.trusted();
            self.record(c, nodes, predicted, &outcome);
            if self.grids.len() == 1 && self.limits.time_limit.is_none() {
                self.limits = self.limits.with_budget(Deadline::budget(self.started, self.grids[0].wall_s, REFINE_BUDGET));
            }
            if trusted {
                break (format!("verified on grid {number}: {what}"), None);
            }
            if !self.scene.verify.refine {
                break (format!("the operator was chosen for the scene's grid of {nodes} nodes; --refine would refine it"), None);
            }
            if let Some(what) = self.stopped_at(&outcome) {
                break (format!("stopped at {what} after {}", counted_grids(self.grids.len())), Some(LONGER.to_string()));
            }
            if let Some((reason, advice)) = self.incurable(&outcome) {
                break (format!("stopped after grid {number} ({what}): {reason}; more nodes would not change that"), advice);
            }
            let Some(next) = self.next().or_else(|| self.uncalibrated_retry(c)) else {
                break self.out_of_budget();
            };
            if let Some(reason) = self.beyond_time(next.1) {
                let result = format!("stopped before grid {} ({} on {} nodes): {reason}", number + 1, next.0.describe(), next.1);
                break (result, Some(LONGER.to_string()));
            }
            (c, nodes, predicted) = next;
        };
        Ok(self.finish(result, advice))
    }

    /// Solve `c` on `nodes` nodes: the first grid with every rung of the ladder, later
    /// ones from the best solution so far when it is near ([`GUESS_FROM_SOLUTION_UP_TO`]).
    fn solve_on(
        &mut self,
        c: Candidate,
        nodes: usize,
        predicted: Option<f64>,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Outcome, SolveError> {
        let (scene, model) = (self.scene, self.model);
        let grid = match (&self.map, c.adaptive) {
            (Some(map), true) => Grid::Mapped(Arc::clone(map)),
            _ => Grid::Uniform,
        };
        let disc = Discretization { operator: c.operator, nodes, initial_velocity: c.initial_velocity, grid };
        // The ladder's other rungs repair the scene's own discretization; a grid the
        // refinement chose that fails gets a better one instead (and a refinement of the
        // scene's own that is predicted to fail, too).
        let own = !self.scene.choose_operator && !self.scene.choose_grid && nodes == self.scene.nodes;
        let rungs = if self.grids.is_empty() && own && (!self.scene.verify.refine || predicted.is_none_or(|r| r <= 1.0)) {
            Rungs::All
        } else {
            Rungs::GuessOnly
        };
        // A solution far from the time stepping is a worse guess than the time stepping
        // itself, and can lead the solver to the same spurious discrete solution.
        let near = self.best.as_ref().filter(|(_, error)| *error <= GUESS_FROM_SOLUTION_UP_TO);
        let outcome = match near {
            None => ladder::climb(scene, model, &disc, &Guess::TimeStepping, rungs, self.limits, progress)?,
            Some((best, _)) => {
                let times = disc.times(scene);
                let tr = &best.trajectory;
                let guess = Guess::States {
                    q: hermite(tr, &times),
                    lambda: linear(&tr.t, &tr.lambda, &times),
                    description: format!(
                        "the solve with {} on {} nodes, interpolated onto the grid (cubic Hermite)",
                        best.settings.operator, best.settings.nodes
                    ),
                };
                ladder::climb(scene, model, &disc, &guess, Rungs::GuessOnly, self.limits, progress)?
            }
        };
        Ok(outcome)
    }

    /// Whether the operator of `c` can be made on its grid of `nodes` nodes.
    fn operator_fits(&self, c: Candidate, nodes: usize) -> Result<(), SbpError> {
        match (&self.map, c.adaptive) {
            (Some(map), true) => operator_on(c.operator, &map.times(nodes), true).map(|_| ()),
            _ => Ok(()),
        }
    }

    /// Record a grid not solved because its operator cannot be made on it: its line in
    /// the refinement and the floor of its candidate's next grid (twice the nodes).
    fn passed_over(&mut self, c: Candidate, nodes: usize, predicted: Option<f64>) {
        self.grids.push(RefinedGrid { verdict: TOO_UNEVEN.to_string(), ..grid_line(c, nodes, predicted) });
        self.raise_floor(c, nodes, 2.0);
    }

    /// The next grid of `c` after one of `nodes` nodes has at least `growth` times its
    /// steps.
    fn raise_floor(&mut self, c: Candidate, nodes: usize, growth: f64) {
        self.floor.push((c, ((nodes - 1) as f64 * growth).ceil() as usize + 1));
    }

    /// Record a solve: its line in the refinement, the calibration of its candidate, the
    /// floor of its next grid, and the best outcome.
    fn record(&mut self, c: Candidate, nodes: usize, predicted: Option<f64>, outcome: &Outcome) {
        let v = &outcome.verification;
        let measured = (outcome.converged() && v.max_error.is_some())
            .then(|| v.errors.values().zip(v.tolerances.values()).map(|(e, t)| e / t).fold(0.0, f64::max));
        let verdict = if !outcome.converged() {
            "not converged"
        } else {
            match v.status {
                VerifyStatus::Passed => "verified",
                VerifyStatus::Skipped => "not verified (verification off)",
                VerifyStatus::Unverified => "unverified",
                VerifyStatus::Failed => "not verified",
            }
        };
        let wall_s = outcome.attempts.iter().map(|a| a.wall_s).sum::<f64>();
        self.grids.push(RefinedGrid {
            measured,
            max_error: v.max_error,
            verdict: verdict.to_string(),
            wall_s,
            ..grid_line(c, nodes, predicted)
        });
        let proxy = match (measured, self.predictor.as_mut()) {
            (Some(_), Ok(p)) => proxy_ratio(p, c, nodes).ok(),
            _ => None,
        };
        if let (Some(m), Some(proxy)) = (measured, proxy) {
            if proxy > 0.0 && proxy.is_finite() && m > 0.0 {
                self.calibration.push((c, m / proxy));
            }
        }
        self.work.add(&outcome.work);
        self.raise_floor(c, nodes, if outcome.converged() { MIN_GROWTH } else { 2.0 });
        if self.first.is_none() {
            self.first = Some(outcome.clone());
        }
        if let Some(m) = measured {
            if self.best.as_ref().is_none_or(|(o, b)| outcome.trusted() && !o.trusted() || m < *b) {
                self.best = Some((outcome.clone(), m));
            }
        }
    }

    /// The reported outcome: the verified one, else the most accurate converged one,
    /// else the first grid's; with the refinement's record.
    fn finish(self, result: String, advice: Option<String>) -> Outcome {
        let tolerance = match &self.predictor {
            Ok(p) => p.tolerance_source.clone(),
            Err(_) => "the verification's (no prediction)".to_string(),
        };
        let mut outcome = match (self.best, self.first) {
            (Some((o, _)), _) => o,
            (None, Some(o)) => o,
            (None, None) => unreachable!("a refinement solves at least one grid"),
        };
        // The reported grid's own time stays in its timings; the other grids' go with
        // the attempts that were not reported.
        let all_s: f64 = self.grids.iter().map(|g| g.wall_s).sum();
        let own_s: f64 = outcome.attempts.iter().map(|a| a.wall_s).sum();
        outcome.timings.other_attempts_s += (all_s - own_s).max(0.0) + self.prediction_s;
        outcome.work = self.work;
        if !outcome.trusted() && advice.is_some() {
            outcome.remedy = advice;
        }
        outcome.refinement = Some(Refinement {
            refine: self.scene.verify.refine,
            operator_chosen: self.scene.choose_operator,
            tolerance,
            max_nodes: self.max_nodes,
            max_nodes_source: self.max_nodes_source,
            grids: self.grids,
            result,
            prediction_s: self.prediction_s,
        });
        outcome
    }
}

/// The refinement's line of `c` on `nodes` nodes, before its solve says how it ended.
fn grid_line(c: Candidate, nodes: usize, predicted: Option<f64>) -> RefinedGrid {
    RefinedGrid {
        nodes,
        operator: c.operator.name().to_string(),
        initial_velocity: c.initial_velocity,
        grid: if c.adaptive { "adaptive" } else { "uniform" },
        predicted,
        measured: None,
        max_error: None,
        verdict: String::new(),
        wall_s: 0.0,
    }
}

/// The candidate of the discretization `own`.
fn own_candidate(own: &Discretization) -> Candidate {
    Candidate { operator: own.operator, initial_velocity: own.initial_velocity, adaptive: !own.grid.is_uniform() }
}

fn counted_grids(n: usize) -> String {
    crate::solve::run::outcome::counted(n, "grid")
}

/// The largest grid a refinement may use and why: `--max-nodes`, else the largest the
/// memory estimate allows, at most [`MAX_NODES_DEFAULT`].
fn budget(scene: &Scene) -> (usize, String) {
    if let Some(n) = scene.verify.max_nodes {
        return (n, "--max-nodes or [verify] max_nodes".to_string());
    }
    // The largest estimate among the operators the refinement may use.
    let operators: Vec<OperatorKind> = if scene.choose_operator { OperatorKind::ALL.to_vec() } else { vec![scene.operator] };
    let fits = |n: usize| {
        let need = operators.iter().map(|&operator| memory::solve_bytes_with(scene, operator, n)).fold(0.0, f64::max);
        memory::available_bytes().is_none_or(|avail| need <= avail)
    };
    if fits(MAX_NODES_DEFAULT) {
        return (MAX_NODES_DEFAULT, format!("the default, 2^{}", MAX_NODES_DEFAULT.trailing_zeros()));
    }
    let (mut lo, mut hi) = (scene.nodes.min(MAX_NODES_DEFAULT), MAX_NODES_DEFAULT);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, "the largest grid the available memory allows".to_string())
}
