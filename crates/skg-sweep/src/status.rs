//! How one point of a sweep ended: [`PointStatus`].

use std::fmt;

use serde::{Deserialize, Serialize};

/// How one point of a sweep ended. Its stable name ([`PointStatus::name`]) is the
/// `status` column of `results.csv`; its [`Display`](fmt::Display) is the same in words.
/// The solver's own status name (Ipopt's `Solve_Succeeded`, `Maximum_Iterations_Exceeded`,
/// …) is kept beside it, in the `solver_status` column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointStatus {
    /// The solve converged (the backend reported success and the unscaled residual of
    /// the square system is at most 1e-8, or every equation is at its own round-off level
    /// after a round-off stop: `skg_core::solve::SolveStatus::classify`), or the
    /// time-stepping peer reached the final time.
    Converged,
    /// The solve converged, but its verification against time stepping of the same
    /// scene failed or could not run (`skg-solve` would exit 4).
    NotVerified,
    /// The backend stopped without converging, or reported success with an unscaled
    /// residual above 1e-8 (and, after a round-off stop, above some equation's own
    /// round-off level).
    NotConverged,
    /// The point could not be computed: its values do not make a valid scene, the solver
    /// or the reference integrator returned an error, or its files could not be written.
    Error,
    /// The worker process ended without reporting a result (e.g. killed by a signal).
    Crashed,
    /// The worker was still running at the sweep's `timeout` and was killed.
    #[serde(rename = "timeout")]
    TimedOut,
}

impl PointStatus {
    /// Every status, in the order of the list above.
    pub const ALL: [PointStatus; 6] = [
        PointStatus::Converged,
        PointStatus::NotVerified,
        PointStatus::NotConverged,
        PointStatus::Error,
        PointStatus::Crashed,
        PointStatus::TimedOut,
    ];

    /// The stable name written to `results.csv` (and to the worker's result JSON).
    pub fn name(self) -> &'static str {
        match self {
            PointStatus::Converged => "converged",
            PointStatus::NotVerified => "not_verified",
            PointStatus::NotConverged => "not_converged",
            PointStatus::Error => "error",
            PointStatus::Crashed => "crashed",
            PointStatus::TimedOut => "timeout",
        }
    }

    /// Whether the solve converged, verified or not (the `converged` column).
    pub fn is_converged(self) -> bool {
        matches!(self, PointStatus::Converged | PointStatus::NotVerified)
    }

    /// Whether the point has a trustworthy solution: converged and verified.
    pub fn is_trusted(self) -> bool {
        self == PointStatus::Converged
    }
}

impl fmt::Display for PointStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PointStatus::Converged => "converged",
            PointStatus::NotVerified => "converged, not verified",
            PointStatus::NotConverged => "did not converge",
            PointStatus::Error => "could not be computed",
            PointStatus::Crashed => "worker crashed",
            PointStatus::TimedOut => "timed out",
        })
    }
}

/// A `status` cell that is none of the stable names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownStatus(pub String);

impl fmt::Display for UnknownStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = PointStatus::ALL.iter().map(|s| s.name()).collect();
        write!(f, "unknown point status `{}` (expected one of: {})", self.0, names.join(", "))
    }
}

impl std::error::Error for UnknownStatus {}

impl std::str::FromStr for PointStatus {
    type Err = UnknownStatus;

    /// Parse a stable name (exactly as written by [`PointStatus::name`]).
    fn from_str(s: &str) -> Result<Self, UnknownStatus> {
        PointStatus::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| UnknownStatus(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_serde() {
        for s in PointStatus::ALL {
            assert_eq!(s.name().parse::<PointStatus>(), Ok(s));
            assert_eq!(serde_json::to_string(&s).unwrap(), format!("\"{}\"", s.name()));
            assert_eq!(serde_json::from_str::<PointStatus>(&format!("\"{}\"", s.name())).unwrap(), s);
        }
        let names: std::collections::HashSet<_> = PointStatus::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names.len(), PointStatus::ALL.len());
        // Ipopt's names are not point statuses; the message lists the valid ones.
        let e = "Solve_Succeeded".parse::<PointStatus>().unwrap_err().to_string();
        assert!(e.contains("Solve_Succeeded") && e.contains("not_converged") && e.contains("timeout"), "{e}");
        assert!(PointStatus::Converged.is_converged() && !PointStatus::TimedOut.is_converged());
        assert_eq!(PointStatus::NotConverged.to_string(), "did not converge");
    }
}
