//! How a solve ended: [`SolveStatus`], the backend's verdict checked against the
//! unscaled residual ([`CONVERGED_RESIDUAL`]).

use std::fmt;

use serde::Serialize;

use super::backend::SolverStatus;

/// The largest unscaled residual max |c| of the discrete system at which a solve counts
/// as converged (Ipopt's own tolerance applies to its possibly scaled problem), unless
/// every equation is within its own round-off level ([`SolveStatus::classify`]).
pub const CONVERGED_RESIDUAL: f64 = 1e-8;

/// How a solve ended: the backend's verdict beside the one of the residual.
///
/// The residual decides: a solve is converged when `max |c| ≤` [`CONVERGED_RESIDUAL`] or
/// every equation is within its own round-off level, whatever the backend's last status
/// (Ipopt can end in its restoration phase, or call a problem infeasible, at a point
/// where the equations hold to the last digits their terms allow: stiff springs, whose
/// equations sum terms of size k·x). The backend's status is kept beside the verdict.
///
/// `Display` gives readable text; [`SolveStatus::name`] a stable name. Serialized (into
/// `summary.json`) as four fields: `"converged"` (true or false), `"status"` (the
/// status name of the backend that finished, e.g. Ipopt's `"Solve_Succeeded"` or
/// `"Newton_Converged"`), `"status_text"` (the readable text) and `"solve_status"` (the
/// stable name).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolveStatus {
    /// The backend succeeded and the residual is small: `max |c| ≤`
    /// [`CONVERGED_RESIDUAL`], or every equation within its own round-off level.
    Converged {
        /// The backend's status (Ipopt's `Solve_Succeeded` or
        /// `Solved_To_Acceptable_Level`, or `Newton_Converged`).
        solver: SolverStatus,
    },
    /// The backend stopped without success, but the residual is small (as for
    /// [`SolveStatus::Converged`]): converged, with the backend's status kept.
    ConvergedByResidual {
        /// The backend's status (a failure, e.g. Ipopt's `Restoration_Failed`).
        solver: SolverStatus,
        /// The unscaled residual max |c|.
        residual: f64,
    },
    /// The backend reported success, but the residual is not small: not converged.
    ResidualTooLarge {
        /// The backend's status (a success).
        solver: SolverStatus,
        /// The unscaled residual max |c|.
        residual: f64,
    },
    /// The backend stopped without success and the residual is not small.
    NotConverged {
        /// The backend's status, which says why.
        solver: SolverStatus,
    },
}

impl SolveStatus {
    /// The status of a solve that ended with the backend's status `solver` at an
    /// unscaled residual `residual`; `equations_at_round_off` says whether every
    /// equation is within [`CONVERGED_RESIDUAL`] or its own round-off level
    /// ([`SquareSolver::equations_at_round_off`](crate::solve::SquareSolver::equations_at_round_off)).
    /// The scale of a scene's numbers (θ ≈ 600 rad after 20 revolutions, `SBP484`'s
    /// closure coefficients up to 130/Δt, a spring of stiffness 1e8) can put the rounding
    /// error of its equations above 1e-8.
    pub fn classify(solver: SolverStatus, residual: f64, equations_at_round_off: bool) -> SolveStatus {
        let small = residual.is_finite() && (residual <= CONVERGED_RESIDUAL || equations_at_round_off);
        match (solver.is_success(), small) {
            (true, true) => SolveStatus::Converged { solver },
            (true, false) => SolveStatus::ResidualTooLarge { solver, residual },
            (false, true) => SolveStatus::ConvergedByResidual { solver, residual },
            (false, false) => SolveStatus::NotConverged { solver },
        }
    }

    /// Whether the solve converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, SolveStatus::Converged { .. } | SolveStatus::ConvergedByResidual { .. })
    }

    /// The status of the backend that finished.
    pub fn solver(&self) -> SolverStatus {
        match *self {
            SolveStatus::Converged { solver }
            | SolveStatus::ConvergedByResidual { solver, .. }
            | SolveStatus::ResidualTooLarge { solver, .. }
            | SolveStatus::NotConverged { solver } => solver,
        }
    }

    /// A stable name: `"converged"`, `"converged_by_residual"`, `"residual_too_large"` or
    /// `"not_converged"`.
    pub fn name(&self) -> &'static str {
        match self {
            SolveStatus::Converged { .. } => "converged",
            SolveStatus::ConvergedByResidual { .. } => "converged_by_residual",
            SolveStatus::ResidualTooLarge { .. } => "residual_too_large",
            SolveStatus::NotConverged { .. } => "not_converged",
        }
    }
}

impl fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolveStatus::Converged { solver } | SolveStatus::NotConverged { solver } => write!(f, "{solver}"),
            SolveStatus::ConvergedByResidual { solver, residual } => {
                write!(f, "converged by its residual {residual:.3e}, ")?;
                if *residual <= CONVERGED_RESIDUAL {
                    write!(f, "below {CONVERGED_RESIDUAL:e}")?;
                } else {
                    f.write_str("every equation at its round-off level")?;
                }
                write!(f, ", where the solver stopped with: {solver}")
            }
            SolveStatus::ResidualTooLarge { solver, residual } => {
                write!(
                    f,
                    "the solver reported success ({solver}) but the unscaled residual {residual:.3e} exceeds {CONVERGED_RESIDUAL:e}"
                )?;
                f.write_str(" and the round-off level of some equation")
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

        let loose = SolveStatus::classify(SolverStatus::Ipopt(Status::SolvedToAcceptableLevel), 2e-5, false);
        assert!(!loose.is_converged());
        assert_eq!(loose.solver(), SolverStatus::Ipopt(Status::SolvedToAcceptableLevel));
        assert_eq!(loose.name(), "residual_too_large");
        assert!(loose.to_string().contains("2.000e-5") && loose.to_string().contains("exceeds 1e-8"), "{loose}");
        assert!(!SolveStatus::classify(SolverStatus::Ipopt(Status::SolveSucceeded), f64::NAN, true).is_converged());

        // A failure with a small residual is converged, with the backend's word kept.
        let rescued = SolveStatus::classify(SolverStatus::Ipopt(Status::RestorationFailed), 5e-10, false);
        assert!(rescued.is_converged());
        assert_eq!((rescued.name(), rescued.solver()), ("converged_by_residual", SolverStatus::Ipopt(Status::RestorationFailed)));
        assert!(rescued.to_string().contains("5.000e-10, below 1e-8") && rescued.to_string().contains("restoration"), "{rescued}");
        let rows = SolveStatus::classify(SolverStatus::Ipopt(Status::InfeasibleProblemDetected), 7e-8, true);
        assert_eq!(rows.name(), "converged_by_residual");
        assert!(rows.to_string().contains("every equation at its round-off level"), "{rows}");
        let failed = SolveStatus::classify(SolverStatus::Ipopt(Status::MaximumIterationsExceeded), 2e-5, false);
        assert_eq!(failed, SolveStatus::NotConverged { solver: SolverStatus::Ipopt(Status::MaximumIterationsExceeded) });
        assert_eq!(failed.to_string(), "maximum number of iterations exceeded");
        assert!(!SolveStatus::classify(SolverStatus::Ipopt(Status::RestorationFailed), f64::NAN, true).is_converged());

        let json = serde_json::to_value(loose).unwrap();
        assert_eq!(json["converged"], false);
        assert_eq!(json["status"], "Solved_To_Acceptable_Level");
        assert_eq!(json["solve_status"], "residual_too_large");
        assert_eq!(json["status_text"], loose.to_string());

        // Newton's own statuses classify the same way and keep their names.
        let newton = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::Converged), 1e-12, false);
        assert!(newton.is_converged());
        assert_eq!(serde_json::to_value(newton).unwrap()["status"], "Newton_Converged");
        let stuck = SolveStatus::classify(SolverStatus::Newton(NewtonStatus::LineSearchFailed), 1e-6, false);
        assert_eq!((stuck.name(), stuck.solver().name()), ("not_converged", "Newton_Line_Search_Failed"));

        // Above 1e-8 a solve counts when every equation is at its own round-off level,
        // whatever the backend's status; otherwise the success is refused.
        for solver in [SolverStatus::IpoptConvergedToRoundOff, SolverStatus::Newton(NewtonStatus::ConvergedToRoundOff)] {
            assert!(SolveStatus::classify(solver, 3e-8, true).is_converged(), "{solver}");
            let refused = SolveStatus::classify(solver, 3e-8, false);
            assert_eq!(refused.name(), "residual_too_large");
            assert!(refused.to_string().ends_with("exceeds 1e-8 and the round-off level of some equation"), "{refused}");
            assert!(!SolveStatus::classify(solver, f64::NAN, true).is_converged());
        }
    }
}
