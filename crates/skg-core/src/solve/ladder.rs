//! The fallback ladder: what a solve tries when the scene's own solve does not converge
//! or is not verified against time stepping of the same scene
//! ([`verify`](crate::stepping::verify)).
//!
//! 1. The scene's own solve: one global solve from the time-stepping guess, or the
//!    scene's windows (`[time] window`). If it converged and verified, that is the answer.
//! 2. If it did not converge (only for a global solve):
//!    * **coarse to fine**: solve on a grid of half the nodes, interpolate that solution
//!      onto the scene's grid (cubic Hermite in q with its velocity, linear in λ) and
//!      start the scene's solve there;
//!    * **wall-width continuation** (scenes with walls): solve with every wall width σ
//!      multiplied by 8, 4 and 2 in turn, each from the previous solution, and start the
//!      scene's solve from the last one that converged.
//!
//!    Both only change the initial guess: a converged result is the critical point of the
//!    scene's own discrete action.
//! 3. **Past the end** (a global solve only, and only once a run converged): one solve
//!    over the span extended by [`END_MARGIN`] of it, of which the nodes up to the end
//!    time are kept: the end closure, which carries errors backward (a contact just
//!    before the final time pollutes the run), then lies outside the reported span. A
//!    span that did not converge is not made easier by lengthening it (a chaotic double
//!    pendulum spent 10.8 s there after 7.9 s on its own solve).
//! 4. **Windows** (whether or not step 1 converged): the span in windows of half the span
//!    (or half the scene's window), each discarding its last quarter, halving the length
//!    until a run converges and verifies or a window would have fewer than
//!    [`MIN_WINDOW_NODES`] nodes. This cures the parasitic odd-even mode that damping or
//!    contraction amplifies, and convergence failures of long or contact-rich spans
//!    ([`window`]).
//!
//! The ladder stops at the first run that converges and verifies, or that converges
//! and whose verification cannot run (its reference would fail on every rung alike).
//! The first run that converges and verifies is reported; if none does, the converged run
//! with the smallest verification error, else the scene's own run. Every run is listed
//! in `summary.json` (`attempts`), the reported one marked `chosen`. `[solver] fallback =
//! false` or `--no-fallback` stops after step 1.

use std::sync::Arc;
use std::time::Instant;

use super::run::backend::SolverStatus;
use super::run::deadline::{self, Bound, Deadline, Limits};
use super::run::error::SolveError;
use super::run::global::{solve_global, Run};
use super::run::outcome::{Attempt, Method, Outcome, Work};
use super::run::piece::Guess;
use super::run::window::{self, WindowGrid};
use crate::discrete::contact::{WallResolution, MIN_STEPS, RESOLVED_STEPS};
use crate::discrete::interpolate::{hermite, linear};
use crate::discrete::Discretization;
use crate::model::Model;
use crate::sbp::OperatorKind;
use crate::scene::{Scene, Stepper, Windows};
use crate::stepping::verify::VerifyStatus;

/// Windows of fewer nodes than this are not tried by the ladder.
pub const MIN_WINDOW_NODES: usize = 24;
/// Factors of the wall widths in the continuation, widest first.
pub const WIDTH_FACTORS: [f64; 3] = [8.0, 4.0, 2.0];
/// How far past the end time step 3 solves, as a fraction of the span.
pub const END_MARGIN: f64 = 0.25;

/// The ladder's attempts stop once it has taken this many times the wall time of the
/// scene's own solve (or [`LADDER_FLOOR_S`], whichever is longer): a ladder whose every
/// rung fails can otherwise take minutes on a large grid (the knife edge at N = 10⁵ ran
/// for over ten minutes), and a rung that has not helped by then rarely does.
pub const LADDER_COST_FACTOR: f64 = 8.0;
/// The time every ladder may take regardless of [`LADDER_COST_FACTOR`], seconds.
pub const LADDER_FLOOR_S: f64 = 2.0;
/// The bound of the ladder's budget, for its deadline and its messages.
const LADDER_BUDGET: Bound =
    Bound::Budget { of: "the fallback ladder", first: "attempt", factor: LADDER_COST_FACTOR, floor_s: LADDER_FLOOR_S };

/// Which rungs the ladder may climb after the scene's own solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rungs {
    /// Every rung that applies (see the module docs).
    All,
    /// Only the wall-width continuation, when the solve did not converge: for a grid of
    /// a refinement, whose initial guess already comes from a coarser grid and whose
    /// failures to verify the next, finer grid addresses.
    GuessOnly,
}

/// The solve of the scene's model `model` with the discretization `disc` from `guess`
/// (one global solve, or the scene's windows) and, when it fails to converge or to
/// verify, the ladder's `rungs` (see the module docs), stopped at `limits` and by its
/// own budget, [`LADDER_COST_FACTOR`] times its first attempt (checked inside the
/// solves too). `progress` is told what each attempt is about to do ("2.
/// coarse to fine (…)").
pub fn climb(
    scene: &Scene,
    model: &Arc<Model>,
    disc: &Discretization,
    guess: &Guess,
    rungs: Rungs,
    limits: Limits,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, SolveError> {
    let mut ladder = Ladder {
        scene,
        model,
        disc: disc.clone(),
        tried: Vec::new(),
        progress,
        preliminary: Work::default(),
        unlisted: Work::default(),
        started: Instant::now(),
        limits,
        stopped: None,
    };
    let deadline = limits.solve();
    let go_on = match scene.windows {
        Some(w) => ladder.attempt("the scene's windows", || window::solve_windows(scene, model, disc, w, deadline))?,
        None => ladder.attempt("one global solve", || solve_global(scene, model, disc, guess, deadline))?,
    };
    if !go_on || !scene.solver.fallback {
        return Ok(ladder.finish());
    }
    let converged = ladder.tried[0].outcome.converged();
    if rungs == Rungs::GuessOnly {
        if !converged && scene.windows.is_none() {
            ladder.width_continuation()?;
        }
        return Ok(ladder.finish());
    }
    if !converged && scene.windows.is_none() && (ladder.coarse_to_fine()? || ladder.width_continuation()?) {
        return Ok(ladder.finish());
    }
    // A longer span at the same spacing is no easier to converge: past the end only
    // helps a run that converged (its end closure spoiled it).
    let any_converged = ladder.tried.iter().any(|t| t.outcome.converged());
    if scene.windows.is_none() && any_converged && ladder.past_the_end()? {
        return Ok(ladder.finish());
    }
    ladder.windows()?;
    Ok(ladder.finish())
}

/// One run of the ladder and its assessment.
struct Tried {
    description: String,
    outcome: Outcome,
    wall_s: f64,
}

struct Ladder<'a> {
    scene: &'a Scene,
    /// The scene's model, and the discretization every rung keeps but the coarse grid.
    model: &'a Arc<Model>,
    disc: Discretization,
    tried: Vec<Tried>,
    progress: &'a mut dyn FnMut(&str),
    /// The work of the solves run so far for the next attempt (a coarse grid, wider
    /// walls): it is counted in that attempt's work.
    preliminary: Work,
    /// The work of preliminary solves that led to no attempt (they did not converge).
    unlisted: Work,
    /// When the ladder started.
    started: Instant,
    /// The time limit and the budgets in force, this ladder's own once its first
    /// attempt is done.
    limits: Limits,
    /// Why the ladder stopped before its rungs were done, if it did.
    stopped: Option<String>,
}

impl Ladder<'_> {
    /// Tell the progress display what the next attempt does.
    fn announce(&mut self, description: &str) {
        (self.progress)(&format!("{}. {description}", self.tried.len() + 1));
    }

    /// Whether the ladder may start another attempt: within the whole solve's time limit
    /// and within the budgets (its own: [`LADDER_COST_FACTOR`] times its first attempt),
    /// none of which stopped the last attempt. The first time it may not, the reason is
    /// kept for the summary's warnings.
    fn may_go_on(&mut self) -> bool {
        if self.stopped.is_some() {
            return false;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        let last_stopped_by = |which: fn(&Bound) -> bool| self.tried.last().is_some_and(|t| stopped_by(&t.outcome, which));
        if deadline::passed(self.limits.time_limit) || last_stopped_by(|b| *b == Bound::TimeLimit) {
            self.stopped = Some(format!("the fallback ladder stopped at the time limit after {elapsed:.1} s"));
        } else if let Some(d) = self.limits.budget.filter(|d| d.passed() || last_stopped_by(|b| *b != Bound::TimeLimit)) {
            self.stopped = Some(format!(
                "the fallback ladder stopped after {} in {elapsed:.1} s, at {}",
                super::run::outcome::counted(self.tried.len(), "attempt"),
                d.describe()
            ));
        }
        self.stopped.is_none()
    }

    /// Run and assess one attempt; `Ok(true)` means the ladder should go on (the run
    /// did not converge or did not verify, and the ladder has time left).
    fn attempt(&mut self, description: &str, run: impl FnOnce() -> Result<Run, SolveError>) -> Result<bool, SolveError> {
        if !self.tried.is_empty() && !self.may_go_on() {
            return Ok(false);
        }
        self.announce(description);
        let start = Instant::now();
        let run = match run() {
            Ok(run) => run,
            // A later rung whose operator cannot be made on its grid (an adaptive grid's
            // windows, each with its own boundary closures, too uneven for a high-order
            // operator) is not tried: the ladder ends with what it has.
            Err(SolveError::Sbp(e)) if !self.tried.is_empty() => {
                self.stopped = Some(format!("the fallback ladder stopped before {description}: {e}"));
                return Ok(false);
            }
            Err(e) => return Err(e),
        };
        let mut outcome = super::run::assess::outcome(self.scene, self.model, run, self.limits.time_limit);
        outcome.work.add(&std::mem::take(&mut self.preliminary));
        let go_on = !ends_the_ladder(&outcome);
        let wall_s = start.elapsed().as_secs_f64();
        if self.tried.is_empty() {
            self.limits = self.limits.with_budget(Deadline::budget(self.started, wall_s, LADDER_BUDGET));
        }
        self.tried.push(Tried { description: description.to_string(), outcome, wall_s });
        Ok(go_on && self.may_go_on())
    }

    /// Count a preliminary solve's work in the next attempt's.
    fn preliminary(&mut self, run: &Run) {
        self.preliminary.add(&run.solution.work);
    }

    /// The preliminary solves lead to no attempt: their work counts in the whole solve's
    /// only.
    fn set_aside_preliminary(&mut self) {
        self.unlisted.add(&std::mem::take(&mut self.preliminary));
    }

    /// Whether the last attempt ends the ladder ([`ends_the_ladder`]).
    fn succeeded(&self) -> bool {
        self.tried.last().is_some_and(|t| ends_the_ladder(&t.outcome))
    }

    /// Step 2a; `Ok(true)` when it succeeded.
    fn coarse_to_fine(&mut self) -> Result<bool, SolveError> {
        let (scene, model, disc, deadline) = (self.scene, self.model, self.disc.clone(), self.limits.solve());
        let coarse_nodes = (disc.nodes - 1) / 2 + 1;
        let coarse_disc = disc.with_nodes(coarse_nodes);
        // An adaptive grid's map is graded for the scene's nodes: on half of them its
        // spacing may change too fast for the operator (then there is no coarse grid).
        let operator_fits = || coarse_disc.operator_on(&coarse_disc.times(scene)).is_ok();
        if coarse_nodes < disc.operator.min_nodes().max(8) || !self.may_go_on() || !operator_fits() {
            return Ok(false);
        }
        self.announce(&format!("coarse to fine (solving on {coarse_nodes} nodes first)"));
        let coarse = solve_global(scene, model, &coarse_disc, &Guess::TimeStepping, deadline)?;
        self.preliminary(&coarse);
        let coarse = coarse.solution;
        if !coarse.status.is_converged() {
            self.set_aside_preliminary();
            return Ok(false);
        }
        let times = disc.times(scene);
        let guess = Guess::States {
            q: hermite(&coarse.trajectory, &times),
            lambda: linear(&coarse.trajectory.t, &coarse.trajectory.lambda, &times),
            description: format!("the solve on {coarse_nodes} nodes, interpolated onto the grid (cubic Hermite)"),
        };
        self.attempt(&format!("coarse to fine (initial guess from {coarse_nodes} nodes)"), || {
            solve_global(scene, model, &disc, &guess, deadline)
        })?;
        Ok(self.succeeded())
    }

    /// Step 2b; `Ok(true)` when it succeeded. The one rung that changes the scene (its
    /// walls' widths), and so builds models of its own.
    fn width_continuation(&mut self) -> Result<bool, SolveError> {
        let (scene, model, disc, deadline) = (self.scene, self.model, self.disc.clone(), self.limits.solve());
        if scene.walls.is_empty() {
            return Ok(false);
        }
        let mut guess = Guess::TimeStepping;
        let mut widest_converged = None;
        for factor in WIDTH_FACTORS {
            if !self.may_go_on() {
                break;
            }
            self.announce(&format!("wall-width continuation (every wall width × {factor})"));
            let mut wide = scene.clone();
            wide.walls.iter_mut().for_each(|w| w.width *= factor);
            let run = solve_global(&wide, &Arc::new(Model::build(&wide)?), &disc, &guess, deadline)?;
            self.preliminary(&run);
            if run.solution.status.is_converged() {
                guess = Guess::States {
                    q: run.solution.trajectory.q,
                    lambda: run.solution.trajectory.lambda,
                    description: format!("the solve with every wall width × {factor}"),
                };
                widest_converged = Some(factor);
            }
        }
        let Some(last) = widest_converged else {
            self.set_aside_preliminary();
            return Ok(false);
        };
        self.attempt(&format!("wall-width continuation (σ × {:?} down to × {last}, then the scene's σ)", WIDTH_FACTORS), || {
            solve_global(scene, model, &disc, &guess, deadline)
        })?;
        Ok(self.succeeded())
    }

    /// Step 3: one solve extended past the end time; `Ok(true)` when it succeeded.
    fn past_the_end(&mut self) -> Result<bool, SolveError> {
        let span = self.scene.t_end - self.scene.t_start;
        let windows = Windows { length: span * (1.0 + END_MARGIN), overlap: span * END_MARGIN };
        let (scene, model, disc, deadline) = (self.scene, self.model, self.disc.clone(), self.limits.solve());
        if WindowGrid::new(scene, &disc, windows).is_err() || !self.may_go_on() {
            return Ok(false);
        }
        self.attempt(&format!("one solve {:.0} % past the end time", 100.0 * END_MARGIN), || {
            window::solve_windows(scene, model, &disc, windows, deadline)
        })?;
        Ok(self.succeeded())
    }

    /// Step 4: windows of halving length.
    fn windows(&mut self) -> Result<(), SolveError> {
        let (scene, model, disc, deadline) = (self.scene, self.model, self.disc.clone(), self.limits.solve());
        let mut length = scene.windows.map_or(scene.t_end - scene.t_start, |w| w.length) / 2.0;
        loop {
            if !self.may_go_on() {
                return Ok(());
            }
            let windows = Windows { length, overlap: length / 4.0 };
            match WindowGrid::new(scene, &disc, windows) {
                Ok(grid) if grid.nodes >= MIN_WINDOW_NODES => {}
                _ => return Ok(()),
            }
            self.attempt(&format!("windows of {length:.4} s"), || window::solve_windows(scene, model, &disc, windows, deadline))?;
            if self.succeeded() {
                return Ok(());
            }
            length /= 2.0;
        }
    }

    /// The reported outcome with the list of attempts and, when it cannot be trusted, a
    /// remedy.
    fn finish(mut self) -> Outcome {
        let chosen = self.chosen();
        let attempts: Vec<Attempt> = self.tried.iter().enumerate().map(|(i, t)| record(t, i == chosen)).collect();
        let fallback_used = self.tried.len() > 1;
        let windows_tried = self.tried.iter().any(|t| matches!(t.outcome.method, Method::Windows { .. }));
        // Summed from +0.0: an empty sum of f64 is −0.0, which summary.json would print.
        let others_s: f64 = attempts.iter().filter(|a| !a.chosen).map(|a| a.wall_s).fold(0.0, |s, x| s + x);
        let mut work = self.unlisted;
        work.add(&self.preliminary);
        attempts.iter().for_each(|a| work.add(&a.work));
        // Whether the time limit stopped an attempt or the ladder (before the reported
        // attempt leaves the list).
        let timed_out =
            deadline::passed(self.limits.time_limit) || self.tried.iter().any(|t| stopped_by(&t.outcome, |b| *b == Bound::TimeLimit));
        let mut outcome = self.tried.swap_remove(chosen).outcome;
        outcome.timings.other_attempts_s = others_s;
        outcome.work = work;
        outcome.remedy = (!outcome.trusted()).then(|| match self.limits.time_limit.filter(|_| timed_out) {
            Some(d) => time_limit_remedy(d),
            None => remedy(self.scene, &self.disc, &outcome, fallback_used, windows_tried),
        });
        outcome.warnings.extend(self.stopped.take());
        outcome.attempts = attempts;
        outcome
    }

    /// Index of the reported attempt.
    fn chosen(&self) -> usize {
        if let Some(i) = self.tried.iter().position(|t| t.outcome.trusted()) {
            return i;
        }
        self.tried
            .iter()
            .enumerate()
            .filter(|(_, t)| t.outcome.converged() && t.outcome.verification.max_error.is_some())
            .min_by(|a, b| a.1.outcome.verification.max_error.partial_cmp(&b.1.outcome.verification.max_error).expect("finite errors"))
            .map_or(0, |(i, _)| i)
    }
}

/// Whether an attempt ends the ladder: it converged and verified, or it converged and
/// its reference could not be computed. Every rung is verified against the same time
/// stepping at the same nodes, so the next rungs would fail to compute it the same way
/// (a stiff scene spent 7 s on seven rungs that way).
fn ends_the_ladder(o: &Outcome) -> bool {
    o.trusted() || (o.converged() && o.verification.status == VerifyStatus::Unverified)
}

/// Whether an attempt's backend was stopped at a deadline set by a bound `which` accepts.
fn stopped_by(o: &Outcome, which: fn(&Bound) -> bool) -> bool {
    matches!(o.status.solver(), SolverStatus::TimeLimitReached { bound, .. } if which(&bound))
}

/// What to do about a solve that the time limit `d` stopped before it could be trusted.
fn time_limit_remedy(d: Deadline) -> String {
    format!(
        "raise the time limit (--time-limit or [solver] time_limit, now {} s) to let the solve finish, or make it cheaper \
         (fewer nodes, or windows)",
        d.limit_s
    )
}

/// The summary's record of one attempt.
fn record(t: &Tried, chosen: bool) -> Attempt {
    let o = &t.outcome;
    let v = &o.verification;
    let result = if !o.converged() {
        format!("did not converge: {}", o.status)
    } else {
        format!("converged; verification {}: {}", v.status, v.reason)
    };
    Attempt {
        method: format!("{}: {}", t.description, o.method),
        result,
        converged: o.converged(),
        verification: o.converged().then_some(v.status),
        max_error: v.max_error,
        iterations: o.iterations,
        work: o.work,
        wall_s: t.wall_s,
        chosen,
    }
}

/// What to do about an outcome that cannot be trusted: only steps that apply to the
/// scene (walls) and were not already tried (windows).
fn remedy(scene: &Scene, disc: &Discretization, o: &Outcome, fallback_used: bool, windows_tried: bool) -> String {
    let span = scene.t_end - scene.t_start;
    let suggested_window = format!("{:.4}", span / 8.0);
    let walls = !scene.walls.is_empty();
    let ladder = if fallback_used {
        let width = if walls { ", wall-width continuation" } else { "" };
        format!("the fallback ladder (coarse-to-fine guess{width}, windows) did not help either; ")
    } else if !scene.solver.fallback {
        "the fallback ladder is off (--no-fallback / [solver] fallback = false): without it, ".to_string()
    } else {
        String::new()
    };
    // At rest the regularized friction μ N v / √(v² + ε²) is a damper of rate μN/(mε),
    // far stiffer than the motion for the default ε: a larger ε makes it resolvable (a
    // block stopping on a floor at N = 2048: 100 iterations without converging at
    // ε = 1e-3, one iteration and an error of 8e-10 at ε = 1e-2).
    let friction = scene.walls.iter().any(|w| w.friction > 0.0);
    let friction_hint = "raise the walls' friction_velocity ε (at rest the regularized friction damps at the rate μN/(mε))";
    if !o.converged() {
        let mut steps = vec![refine(disc, o)];
        if walls && under_resolved_wall(o).is_none() {
            steps.push("widen the walls (a larger σ)".to_string());
        }
        if friction {
            steps.push(friction_hint.to_string());
        }
        if !windows_tried {
            steps.push(format!("solve in windows (--window {suggested_window})"));
        }
        if !scene.verify.refine {
            steps.push("let --refine choose finer grids until the solve converges and verifies".to_string());
        }
        let last = steps.pop().expect("one step at least");
        let steps = if steps.is_empty() { last } else { format!("{}, or {last}", steps.join(", ")) };
        return format!("{ladder}{steps}");
    }
    let v = &o.verification;
    match v.status {
        VerifyStatus::Unverified if scene.verify.stepper == Stepper::Dop853 => "let the time stepping go on implicitly where the \
             scene is stiff (--stepper auto, the default, or --stepper implicit); or, if you trust the solve regardless, --no-verify \
             accepts it"
            .to_string(),
        VerifyStatus::Unverified => "if you trust the solve regardless, --no-verify accepts it".to_string(),
        _ if v.max_error.is_none() => "fix the scene so that every quantity stays finite along the motion".to_string(),
        _ => {
            // A dissipative operator damps the mode: its odd-even amplitude is a smooth
            // transient (verify's module documentation).
            let oddeven = v.max_error.is_some_and(|e| v.odd_even_max >= 0.25 * e) && !disc.operator.is_dissipative();
            let windows = matches!(o.method, Method::Windows { .. });
            let damped = disc.operator.dissipative();
            let cure = if oddeven && !windows && !windows_tried {
                format!(
                    "solve in windows (`[time] window = {suggested_window}` or --window {suggested_window}), which bounds the odd-even \
                     mode's growth, or use the dissipative operator {damped} (--operator {damped}), which damps it"
                )
            } else {
                let refine = refine(disc, o);
                let refine = match higher_order(disc.operator).filter(|_| under_resolved_wall(o).is_none()) {
                    Some(op) => format!("{refine} or use a higher-order operator (--operator {})", op.name()),
                    None => refine,
                };
                let refine =
                    if oddeven { format!("{refine}, or the dissipative operator {damped}, which damps the odd-even mode") } else { refine };
                if friction {
                    format!("{refine}, or {friction_hint}")
                } else {
                    refine
                }
            };
            // The refinement does all of the above by itself, at the least predicted cost.
            let auto = if scene.verify.refine {
                String::new()
            } else if v.steps.implicit_accepted > 0 {
                // The verification went on implicitly: the scene is stiff.
                "the scene is stiff (its verification went on with the implicit stepper): --refine --operator auto chooses \
                 the grid, the operator (a dissipative one damps what a stiff force excites) and the initial-velocity condition \
                 (the natural one where the motion starts with a fast layer) predicted to meet the tolerance at the least cost; or "
                    .to_string()
            } else {
                "let the tool choose: --refine solves on finer grids (and, unless --operator names one, with the operator) \
                 predicted to meet the tolerance at the least cost; or "
                    .to_string()
            };
            format!("{ladder}{auto}{cure}; or, if this accuracy is enough for you, state it with `[verify] tol` or --verify-tol")
        }
    }
}

/// The refinement to suggest: twice the nodes, or, when the reference shows a wall's
/// contacts under-resolved (fewer than [`MIN_STEPS`] grid steps per contact length,
/// [`fewest_steps`](crate::discrete::contact::fewest_steps)), the power-of-two multiple of
/// the nodes that reaches [`RESOLVED_STEPS`] (or a wider wall).
fn refine(disc: &Discretization, o: &Outcome) -> String {
    let Some((name, r)) = under_resolved_wall(o) else {
        return format!("refine the grid (--nodes {})", 2 * disc.nodes);
    };
    let factor = (RESOLVED_STEPS / r.steps).log2().ceil().exp2().max(2.0);
    let nodes = (disc.nodes as f64 * factor).min(1e15) as usize;
    let steps = if r.steps >= 0.1 { format!("{:.2}", r.steps) } else { format!("{:.1e}", r.steps) };
    format!(
        "refine the grid (--nodes {nodes}) or widen wall `{name}`: the grid does not resolve its contacts, the gap changing by a \
         contact's length ({:.2e}) in {steps} grid steps (|ḣ| = {:.3} at t = {:.4}) where about {RESOLVED_STEPS} are needed",
        r.length, r.gap_rate, r.t,
    )
}

/// The wall whose contacts the outcome's reference resolves worst, if it has fewer than
/// [`MIN_STEPS`] steps per contact length.
fn under_resolved_wall(o: &Outcome) -> Option<(&String, &WallResolution)> {
    o.verification.wall_resolution.iter().min_by(|a, b| a.1.steps.total_cmp(&b.1.steps)).filter(|(_, r)| r.steps < MIN_STEPS)
}

/// The operator of the next higher order in the same family (centred, or dissipative),
/// if there is one.
fn higher_order(op: OperatorKind) -> Option<OperatorKind> {
    let family = if op.is_dissipative() { OperatorKind::DISSIPATIVE } else { OperatorKind::CENTRED };
    family.iter().position(|&k| k == op).and_then(|i| family.get(i + 1)).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_higher_order_operator_is_the_next_one_up_and_none_above_sbp484() {
        assert_eq!(higher_order(OperatorKind::Sbp121), Some(OperatorKind::Sbp242));
        assert_eq!(higher_order(OperatorKind::Sbp242), Some(OperatorKind::Sbp363));
        assert_eq!(higher_order(OperatorKind::Sbp363), Some(OperatorKind::Sbp484));
        assert_eq!(higher_order(OperatorKind::Sbp484), None);
        assert_eq!(higher_order(OperatorKind::Sbp121Ad), Some(OperatorKind::Sbp242Ad));
        assert_eq!(higher_order(OperatorKind::Sbp363Ad), Some(OperatorKind::Sbp484Ad));
        assert_eq!(higher_order(OperatorKind::Sbp484Ad), None);
    }
}
