//! How a solve ended: [`SolveStatus`], the backend's verdict checked against the
//! unscaled residual ([`CONVERGED_RESIDUAL`]).

use std::fmt;

use serde::Serialize;

use super::backend::SolverStatus;

/// The largest unscaled residual max |c| of the discrete system at which a solve counts
/// as converged (Ipopt's own tolerance applies to its possibly scaled problem), unless the
/// backend stopped at the round-off level and every equation is within its own round-off
/// level ([`SolveStatus::classify`]).
pub const CONVERGED_RESIDUAL: f64 = 1e-8;

/// How a solve ended: the backend's verdict, checked against the unscaled residual.
///
/// `Display` gives readable text; [`SolveStatus::name`] a stable name. Serialized (into
/// `summary.json`) as four fields: `"converged"` (true or false), `"status"` (the
/// status name of the backend that finished, e.g. Ipopt's `"Solve_Succeeded"` or
/// `"Newton_Converged"`), `"status_text"` (the readable text) and `"solve_status"` (the
/// stable name).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolveStatus {
    /// The backend succeeded and the unscaled residual is at most [`CONVERGED_RESIDUAL`],
    /// or the backend stopped at the round-off level and every equation is within its
    /// own round-off level.
    Converged {
        /// The backend's status (Ipopt's `Solve_Succeeded` or
        /// `Solved_To_Acceptable_Level`, or `Newton_Converged`).
        solver: SolverStatus,
    },
    /// The backend reported success, but the unscaled residual exceeds
    /// [`CONVERGED_RESIDUAL`] (or is not a number): not counted as converged.
    ResidualTooLarge {
        /// The backend's status (a success).
        solver: SolverStatus,
        /// The unscaled residual max |c|.
        residual: f64,
    },
    /// The backend stopped without success.
    NotConverged {
        /// The backend's status, which says why.
        solver: SolverStatus,
    },
}

impl SolveStatus {
    /// The status of a solve that ended with the backend's status `solver` at an
    /// unscaled residual `residual`; `equations_at_round_off` says whether every
    /// equation is within [`CONVERGED_RESIDUAL`] or its own round-off level
    /// ([`SquareSolver::equations_at_round_off`](crate::solve::SquareSolver::equations_at_round_off)). A residual above `CONVERGED_RESIDUAL`
    /// counts only after a round-off stop that holds equation by equation: the scale of
    /// a scene's numbers (θ ≈ 600 rad after 20 revolutions, `SBP484`'s closure
    /// coefficients up to 130/Δt) can put the rounding error of its equations above 1e-8.
    pub fn classify(solver: SolverStatus, residual: f64, equations_at_round_off: bool) -> SolveStatus {
        let small = residual <= CONVERGED_RESIDUAL || (solver.is_round_off() && residual.is_finite() && equations_at_round_off);
        match (solver.is_success(), small) {
            (true, true) => SolveStatus::Converged { solver },
            (true, false) => SolveStatus::ResidualTooLarge { solver, residual },
            (false, _) => SolveStatus::NotConverged { solver },
        }
    }

    /// Whether the solve converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, SolveStatus::Converged { .. })
    }

    /// The status of the backend that finished.
    pub fn solver(&self) -> SolverStatus {
        match *self {
            SolveStatus::Converged { solver } | SolveStatus::ResidualTooLarge { solver, .. } | SolveStatus::NotConverged { solver } => {
                solver
            }
        }
    }

    /// A stable name: `"converged"`, `"residual_too_large"` or `"not_converged"`.
    pub fn name(&self) -> &'static str {
        match self {
            SolveStatus::Converged { .. } => "converged",
            SolveStatus::ResidualTooLarge { .. } => "residual_too_large",
            SolveStatus::NotConverged { .. } => "not_converged",
        }
    }
}

impl fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolveStatus::Converged { solver } | SolveStatus::NotConverged { solver } => write!(f, "{solver}"),
            SolveStatus::ResidualTooLarge { solver, residual } => {
                write!(
                    f,
                    "the solver reported success ({solver}) but the unscaled residual {residual:.3e} exceeds {CONVERGED_RESIDUAL:e}"
                )?;
                if solver.is_round_off() {
                    f.write_str(" and the round-off level of some equation")?;
                }
                Ok(())
            }
        }
    }
}

impl Serialize for SolveStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(4))?;
        map.serialize_entry("converged", &self.is_converged())?;
        map.serialize_entry("status", &self.solver())?;
        map.serialize_entry("status_text", &self.to_string())?;
        map.serialize_entry("solve_status", self.name())?;
        map.end()
    }
}

#[cfg(all(test, feature = "ipopt"))]
mod tests {
    use super::*;
    use crate::solve::newton::NewtonStatus;
    use skg_ipopt::Status;

    #[test]
    fn solve_status_from_ipopt_and_residual() {
        let ok = SolveStatus::classify(SolverStatus::Ipopt(Status::SolveSucceeded), 1e-12, false);
        assert_eq!(ok, SolveStatus::Converged { solver: SolverStatus::Ipopt(Status::SolveSucceeded) });
        assert!(ok.is_converged());
        assert_eq!((ok.name(), ok.to_string().as_str()), ("converged", "solved to the requested tolerance"));

        let loose = SolveStatus::classify(SolverStatus::Ipopt(Status::SolvedToAcceptableLevel), 2e-5, true);
        assert!(!loose.is_converged());
        assert_eq!(loose.solver(), SolverStatus::Ipopt(Status::SolvedToAcceptableLevel));
        assert_eq!(loose.name(), "residual_too_large");
        assert!(loose.to_string().contains("2.000e-5") && loose.to_string().contains("exceeds 1e-8"), "{loose}");
        assert!(!SolveStatus::classify(SolverStatus::Ipopt(Status::SolveSucceeded), f64::NAN, true).is_converged());

        let failed = SolveStatus::classify(SolverStatus::Ipopt(Status::MaximumIterationsExceeded), 1e-12, false);
        assert_eq!(failed, SolveStatus::NotConverged { solver: SolverStatus::Ipopt(Status::MaximumIterationsExceeded) });
        assert_eq!(failed.to_string(), "maximum number of iterations exceeded");

        let json = serde_json::to_value(loose).unwrap();
        assert_eq!(json["converged"], false);
        assert_eq!(json["status"], "Solved_To_Acceptable_Level");
        assert_eq!(json["solve_status"], "residual_too_large");
        assert_eq!(json["status_text"], loose.to_string());

        // Newton's own statuses classify the same way and keep their names.
        let newton = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::Converged), 1e-12, false);
        assert!(newton.is_converged());
        assert_eq!(serde_json::to_value(newton).unwrap()["status"], "Newton_Converged");
        let stuck = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::LineSearchFailed), 1e-12, false);
        assert_eq!((stuck.name(), stuck.solver().name()), ("not_converged", "Newton_Line_Search_Failed"));

        // A round-off stop above 1e-8 counts when every equation is at its own round-off
        // level, and only after a round-off stop (not after Ipopt's acceptable level).
        for solver in [SolverStatus::IpoptConvergedToRoundOff, SolverStatus::Newton(NewtonStatus::ConvergedToRoundOff)] {
            assert!(SolveStatus::classify(solver, 3e-8, true).is_converged(), "{solver}");
            let refused = SolveStatus::classify(solver, 3e-8, false);
            assert_eq!(refused.name(), "residual_too_large");
            assert!(refused.to_string().ends_with("exceeds 1e-8 and the round-off level of some equation"), "{refused}");
            assert!(!SolveStatus::classify(solver, f64::NAN, true).is_converged());
        }
        assert!(!SolveStatus::classify(SolverStatus::Newton(NewtonStatus::Converged), 3e-8, true).is_converged());
    }
}
