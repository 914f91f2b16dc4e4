//! The time limit of a whole solve (`--time-limit`, `[solver] time_limit`) as the moment
//! it ends: [`Deadline`]. The ladder and the refinement check it between attempts and
//! grids; the backends inside their iterations (Ipopt's intermediate callback, Newton's
//! loop), so that a single long solve ends at it too, as not converged.

use std::time::{Duration, Instant};

/// The moment a solve limited to `limit_s` seconds must end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Deadline {
    /// When the time limit is reached.
    pub at: Instant,
    /// The limit, in seconds from the start of the solve.
    pub limit_s: f64,
}

impl Deadline {
    /// The deadline of a solve starting now and limited to `seconds`, if any: none for a
    /// limit beyond what the clock can represent (which no solve reaches).
    pub fn after(seconds: Option<f64>) -> Option<Deadline> {
        let limit_s = seconds?;
        let at = Instant::now().checked_add(Duration::try_from_secs_f64(limit_s).ok()?)?;
        Some(Deadline { at, limit_s })
    }

    /// Whether the time limit has been reached.
    pub fn passed(&self) -> bool {
        Instant::now() >= self.at
    }

    /// The seconds left until the time limit (0 once it has been reached).
    pub fn left_s(&self) -> f64 {
        self.at.saturating_duration_since(Instant::now()).as_secs_f64()
    }

    /// The seconds since the solve started: the limit, plus the time past it.
    pub fn elapsed_s(&self) -> f64 {
        let now = Instant::now();
        if now >= self.at {
            self.limit_s + now.duration_since(self.at).as_secs_f64()
        } else {
            self.limit_s - self.at.duration_since(now).as_secs_f64()
        }
    }
}

/// Whether `deadline`, if any, has been reached.
pub fn passed(deadline: Option<Deadline>) -> bool {
    deadline.is_some_and(|d| d.passed())
}
