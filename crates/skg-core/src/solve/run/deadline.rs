//! When a solve must end: [`Deadline`], set by the user's time limit (`--time-limit`,
//! `[solver] time_limit`) or by a budget of the solve itself (the fallback ladder's, the
//! refinement's: a multiple of their first solve). The ladder and the refinement check
//! it between attempts and grids; the backends inside their iterations (Ipopt's
//! intermediate callback, Newton's loop), so that a single long solve ends at it too, as
//! not converged; the time stepping of the initial guess and of the verification
//! before every step.
//!
//! **Ending before the deadline, not after it.** Once a solve has timed one iteration,
//! it does not start another that would end past the deadline if it took as long as the
//! last one: so the limit is honoured to within the error of that estimate, not to
//! within a whole iteration. The first iteration (which holds the factorization's
//! analysis, or Ipopt's initialization) cannot be estimated and is not interrupted:
//! neither is a single factorization inside MUMPS or faer.

use std::time::{Duration, Instant};

use crate::scene::Backend;
use crate::solve::run::backend::SolverStatus;

/// What set a [`Deadline`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The user's time limit (`--time-limit`, `[solver] time_limit`), from the start of
    /// the whole solve.
    TimeLimit,
    /// A budget of what runs several solves, from its start: `factor` times its first
    /// solve or `floor_s`, whichever is longer.
    Budget {
        /// What it bounds: "the fallback ladder", "the refinement".
        of: &'static str,
        /// What its first solve is called: "attempt", "grid".
        first: &'static str,
        /// The multiple of the first solve's wall time.
        factor: f64,
        /// The least budget, seconds.
        floor_s: f64,
    },
}

/// The moment a solve must end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deadline {
    /// When it is reached.
    pub at: Instant,
    /// Its length, in seconds from the start of what it bounds.
    pub limit_s: f64,
    /// What set it.
    pub bound: Bound,
}

impl Deadline {
    /// The deadline of a solve starting now and limited to `seconds`, if any: none for a
    /// limit beyond what the clock can represent (which no solve reaches).
    pub fn after(seconds: Option<f64>) -> Option<Deadline> {
        Deadline::from(Instant::now(), seconds?, Bound::TimeLimit)
    }

    /// The deadline `limit_s` seconds after `start`, set by `bound` (none beyond what the
    /// clock can represent).
    pub fn from(start: Instant, limit_s: f64, bound: Bound) -> Option<Deadline> {
        let at = start.checked_add(Duration::try_from_secs_f64(limit_s).ok()?)?;
        Some(Deadline { at, limit_s, bound })
    }

    /// The deadline a budget `bound` sets from `start` for what first took `first_s`
    /// seconds: its factor times that, or its floor, whichever is longer (none for the
    /// time limit, which is not a budget).
    pub fn budget(start: Instant, first_s: f64, bound: Bound) -> Option<Deadline> {
        let Bound::Budget { factor, floor_s, .. } = bound else { return None };
        Deadline::from(start, (factor * first_s).max(floor_s), bound)
    }

    /// The earlier of two deadlines (either may be absent).
    pub fn earliest(a: Option<Deadline>, b: Option<Deadline>) -> Option<Deadline> {
        match (a, b) {
            (Some(a), Some(b)) => Some(if b.at < a.at { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// Whether it has been reached.
    pub fn passed(&self) -> bool {
        Instant::now() >= self.at
    }

    /// Whether a step of `step_s` seconds started now would end past it.
    pub fn would_pass(&self, step_s: f64) -> bool {
        // A step too long for the clock ends past any deadline.
        let end = Duration::try_from_secs_f64(step_s).ok().and_then(|step| Instant::now().checked_add(step));
        end.is_none_or(|end| end >= self.at)
    }

    /// The seconds left until it (0 once it has been reached).
    pub fn left_s(&self) -> f64 {
        self.at.saturating_duration_since(Instant::now()).as_secs_f64()
    }

    /// The seconds since the start of what it bounds: the limit, plus the time past it.
    pub fn elapsed_s(&self) -> f64 {
        let now = Instant::now();
        if now >= self.at {
            self.limit_s + now.duration_since(self.at).as_secs_f64()
        } else {
            self.limit_s - self.at.duration_since(now).as_secs_f64()
        }
    }

    /// The status of `backend` stopped at it, now.
    pub fn stopped(&self, backend: Backend) -> SolverStatus {
        SolverStatus::TimeLimitReached { backend, bound: self.bound, limit_s: self.limit_s, elapsed_s: self.elapsed_s() }
    }

    /// What it is, for messages: "the time limit of 5 s (--time-limit)", "the fallback
    /// ladder's budget of 2.0 s (8× its first attempt or 2 s, whichever is longer)".
    pub fn describe(&self) -> String {
        describe(self.bound, self.limit_s)
    }
}

/// The deadlines a solve runs under: the user's time limit, which bounds all of it (the
/// verification too), and the budgets of the ladder and the refinement, which bound its
/// solves only (a verification is never cut by a budget: a converged solve keeps its
/// verdict).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Limits {
    /// The user's time limit.
    pub time_limit: Option<Deadline>,
    /// The earliest budget in force.
    pub budget: Option<Deadline>,
}

impl Limits {
    /// The deadline of a solve: the earlier of the time limit and the budget.
    pub fn solve(&self) -> Option<Deadline> {
        Deadline::earliest(self.time_limit, self.budget)
    }

    /// These limits under one more budget.
    pub fn with_budget(self, budget: Option<Deadline>) -> Limits {
        Limits { budget: Deadline::earliest(self.budget, budget), ..self }
    }
}

/// [`Deadline::describe`] of a deadline of `limit_s` seconds set by `bound`.
pub fn describe(bound: Bound, limit_s: f64) -> String {
    match bound {
        Bound::TimeLimit => format!("the time limit of {limit_s} s (--time-limit)"),
        Bound::Budget { of, first, factor, floor_s } => {
            format!("{of}'s budget of {limit_s:.1} s ({factor}× its first {first} or {floor_s} s, whichever is longer)")
        }
    }
}

/// What a deadline set by `bound` counts from, for messages: "the solve", "the
/// refinement".
pub fn start_of(bound: Bound) -> &'static str {
    match bound {
        Bound::TimeLimit => "the solve",
        Bound::Budget { of, .. } => of,
    }
}

/// Whether `deadline`, if any, has been reached.
pub fn passed(deadline: Option<Deadline>) -> bool {
    deadline.is_some_and(|d| d.passed())
}

/// Whether a step of `step_s` seconds started now would end past `deadline`, if any.
pub fn would_pass(deadline: Option<Deadline>, step_s: f64) -> bool {
    deadline.is_some_and(|d| d.would_pass(step_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LADDER: Bound = Bound::Budget { of: "the fallback ladder", first: "attempt", factor: 8.0, floor_s: 2.0 };

    #[test]
    fn the_earliest_deadline_is_the_one_that_comes_first() {
        let now = Instant::now();
        let long = Deadline::from(now, 10.0, Bound::TimeLimit);
        let short = Deadline::from(now, 1.0, LADDER);
        assert_eq!(Deadline::earliest(long, short), short);
        assert_eq!(Deadline::earliest(short, long), short);
        assert_eq!(Deadline::earliest(None, long), long);
        assert_eq!(Deadline::earliest(None, None), None);
    }

    #[test]
    fn a_step_that_would_end_past_the_deadline_is_seen_before_it_starts() {
        let d = Deadline::from(Instant::now(), 30.0, Bound::TimeLimit).expect("representable");
        assert!(!d.passed());
        assert!(!d.would_pass(1.0));
        assert!(d.would_pass(60.0));
        assert!(d.would_pass(f64::INFINITY));
        // A limit the clock cannot represent sets no deadline.
        assert_eq!(Deadline::after(Some(1e300)), None);
    }

    #[test]
    fn a_budget_is_its_factor_times_the_first_solve_or_its_floor() {
        let now = Instant::now();
        assert_eq!(Deadline::budget(now, 0.1, LADDER).map(|d| d.limit_s), Some(2.0));
        assert_eq!(Deadline::budget(now, 0.5, LADDER).map(|d| d.limit_s), Some(4.0));
        assert_eq!(Deadline::budget(now, 0.5, Bound::TimeLimit), None);
    }

    #[test]
    fn each_bound_is_described_by_what_set_it() {
        assert_eq!(describe(Bound::TimeLimit, 5.0), "the time limit of 5 s (--time-limit)");
        assert_eq!(describe(LADDER, 2.0), "the fallback ladder's budget of 2.0 s (8× its first attempt or 2 s, whichever is longer)");
    }
}
