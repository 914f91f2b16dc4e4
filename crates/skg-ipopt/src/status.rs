//! Ipopt's return statuses: [`Status`], with Ipopt's integer codes and identifiers (from
//! the generated bindings in [`crate::ffi`]), readable text and serialization as the
//! identifier.

use std::fmt;

use serde::Serialize;

use crate::ffi;

/// Ipopt's `ApplicationReturnStatus`.
///
/// `Display` gives readable text, [`Status::name`] Ipopt's identifier and
/// [`Status::code`] its integer value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// `Solve_Succeeded` (0).
    SolveSucceeded,
    /// `Solved_To_Acceptable_Level` (1).
    SolvedToAcceptableLevel,
    /// `Infeasible_Problem_Detected` (2).
    InfeasibleProblemDetected,
    /// `Search_Direction_Becomes_Too_Small` (3).
    SearchDirectionBecomesTooSmall,
    /// `Diverging_Iterates` (4).
    DivergingIterates,
    /// `User_Requested_Stop` (5).
    UserRequestedStop,
    /// `Feasible_Point_Found` (6). Not counted as success.
    FeasiblePointFound,
    /// `Maximum_Iterations_Exceeded` (-1).
    MaximumIterationsExceeded,
    /// `Restoration_Failed` (-2).
    RestorationFailed,
    /// `Error_In_Step_Computation` (-3).
    ErrorInStepComputation,
    /// `Maximum_CpuTime_Exceeded` (-4).
    MaximumCpuTimeExceeded,
    /// `Not_Enough_Degrees_Of_Freedom` (-10).
    NotEnoughDegreesOfFreedom,
    /// `Invalid_Problem_Definition` (-11).
    InvalidProblemDefinition,
    /// `Invalid_Option` (-12).
    InvalidOption,
    /// `Invalid_Number_Detected` (-13).
    InvalidNumberDetected,
    /// `Unrecoverable_Exception` (-100).
    UnrecoverableException,
    /// `NonIpopt_Exception_Thrown` (-101).
    NonIpoptExceptionThrown,
    /// `Insufficient_Memory` (-102).
    InsufficientMemory,
    /// `Internal_Error` (-199).
    InternalError,
    /// A code this crate does not know.
    Unknown(i32),
}

/// Every known status, for iteration (tests, documentation).
const KNOWN_STATUSES: [Status; 19] = [
    Status::SolveSucceeded,
    Status::SolvedToAcceptableLevel,
    Status::InfeasibleProblemDetected,
    Status::SearchDirectionBecomesTooSmall,
    Status::DivergingIterates,
    Status::UserRequestedStop,
    Status::FeasiblePointFound,
    Status::MaximumIterationsExceeded,
    Status::RestorationFailed,
    Status::ErrorInStepComputation,
    Status::MaximumCpuTimeExceeded,
    Status::NotEnoughDegreesOfFreedom,
    Status::InvalidProblemDefinition,
    Status::InvalidOption,
    Status::InvalidNumberDetected,
    Status::UnrecoverableException,
    Status::NonIpoptExceptionThrown,
    Status::InsufficientMemory,
    Status::InternalError,
];

impl Status {
    /// The status for Ipopt's integer code.
    pub fn from_code(code: i32) -> Self {
        KNOWN_STATUSES.iter().copied().find(|s| s.code() == code).unwrap_or(Status::Unknown(code))
    }

    /// Ipopt's integer code.
    pub fn code(&self) -> i32 {
        type S = ffi::ApplicationReturnStatus;
        match self {
            Status::SolveSucceeded => S::Solve_Succeeded.0,
            Status::SolvedToAcceptableLevel => S::Solved_To_Acceptable_Level.0,
            Status::InfeasibleProblemDetected => S::Infeasible_Problem_Detected.0,
            Status::SearchDirectionBecomesTooSmall => S::Search_Direction_Becomes_Too_Small.0,
            Status::DivergingIterates => S::Diverging_Iterates.0,
            Status::UserRequestedStop => S::User_Requested_Stop.0,
            Status::FeasiblePointFound => S::Feasible_Point_Found.0,
            Status::MaximumIterationsExceeded => S::Maximum_Iterations_Exceeded.0,
            Status::RestorationFailed => S::Restoration_Failed.0,
            Status::ErrorInStepComputation => S::Error_In_Step_Computation.0,
            Status::MaximumCpuTimeExceeded => S::Maximum_CpuTime_Exceeded.0,
            Status::NotEnoughDegreesOfFreedom => S::Not_Enough_Degrees_Of_Freedom.0,
            Status::InvalidProblemDefinition => S::Invalid_Problem_Definition.0,
            Status::InvalidOption => S::Invalid_Option.0,
            Status::InvalidNumberDetected => S::Invalid_Number_Detected.0,
            Status::UnrecoverableException => S::Unrecoverable_Exception.0,
            Status::NonIpoptExceptionThrown => S::NonIpopt_Exception_Thrown.0,
            Status::InsufficientMemory => S::Insufficient_Memory.0,
            Status::InternalError => S::Internal_Error.0,
            Status::Unknown(code) => *code,
        }
    }

    /// `true` for `Solve_Succeeded` and `Solved_To_Acceptable_Level` only
    /// (`Feasible_Point_Found` is deliberately not a success).
    pub fn is_success(&self) -> bool {
        matches!(self, Status::SolveSucceeded | Status::SolvedToAcceptableLevel)
    }

    /// Ipopt's identifier, e.g. `"Solve_Succeeded"`; `"Unknown"` for unknown codes.
    pub fn name(&self) -> &'static str {
        match self {
            Status::SolveSucceeded => "Solve_Succeeded",
            Status::SolvedToAcceptableLevel => "Solved_To_Acceptable_Level",
            Status::InfeasibleProblemDetected => "Infeasible_Problem_Detected",
            Status::SearchDirectionBecomesTooSmall => "Search_Direction_Becomes_Too_Small",
            Status::DivergingIterates => "Diverging_Iterates",
            Status::UserRequestedStop => "User_Requested_Stop",
            Status::FeasiblePointFound => "Feasible_Point_Found",
            Status::MaximumIterationsExceeded => "Maximum_Iterations_Exceeded",
            Status::RestorationFailed => "Restoration_Failed",
            Status::ErrorInStepComputation => "Error_In_Step_Computation",
            Status::MaximumCpuTimeExceeded => "Maximum_CpuTime_Exceeded",
            Status::NotEnoughDegreesOfFreedom => "Not_Enough_Degrees_Of_Freedom",
            Status::InvalidProblemDefinition => "Invalid_Problem_Definition",
            Status::InvalidOption => "Invalid_Option",
            Status::InvalidNumberDetected => "Invalid_Number_Detected",
            Status::UnrecoverableException => "Unrecoverable_Exception",
            Status::NonIpoptExceptionThrown => "NonIpopt_Exception_Thrown",
            Status::InsufficientMemory => "Insufficient_Memory",
            Status::InternalError => "Internal_Error",
            Status::Unknown(_) => "Unknown",
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Status::SolveSucceeded => "solved to the requested tolerance",
            Status::SolvedToAcceptableLevel => "solved to an acceptable level only (not the requested tolerance)",
            Status::InfeasibleProblemDetected => "converged to a point of local infeasibility (the problem may be infeasible)",
            Status::SearchDirectionBecomesTooSmall => "search direction became too small",
            Status::DivergingIterates => "iterates diverged",
            Status::UserRequestedStop => "stopped on request of the intermediate callback",
            Status::FeasiblePointFound => "feasible point found (not a converged solution)",
            Status::MaximumIterationsExceeded => "maximum number of iterations exceeded",
            Status::RestorationFailed => "restoration phase failed",
            Status::ErrorInStepComputation => "error in step computation (singular or ill-conditioned linear system)",
            Status::MaximumCpuTimeExceeded => "maximum CPU time exceeded",
            Status::NotEnoughDegreesOfFreedom => "not enough degrees of freedom (more equality constraints than free variables)",
            Status::InvalidProblemDefinition => "invalid problem definition",
            Status::InvalidOption => "invalid option",
            Status::InvalidNumberDetected => "invalid number (NaN or infinity) in a function or derivative value",
            Status::UnrecoverableException => "unrecoverable exception inside Ipopt",
            Status::NonIpoptExceptionThrown => "non-Ipopt exception thrown inside Ipopt",
            Status::InsufficientMemory => "insufficient memory",
            Status::InternalError => "internal error in Ipopt",
            Status::Unknown(code) => return write!(f, "unknown Ipopt return status {code}"),
        };
        f.write_str(text)
    }
}

/// Serializes as Ipopt's identifier (`"Solve_Succeeded"`, ...; `"Unknown(<code>)"`).
impl Serialize for Status {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Status::Unknown(code) => serializer.collect_str(&format_args!("Unknown({code})")),
            known => serializer.serialize_str(known.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ipopt_version;

    #[test]
    fn status_codes_round_trip() {
        for s in KNOWN_STATUSES {
            assert_eq!(Status::from_code(s.code()), s);
            assert!(!s.to_string().is_empty() && s.name() != "Unknown");
        }
        assert_eq!(Status::from_code(-13), Status::InvalidNumberDetected);
        assert_eq!(Status::from_code(42), Status::Unknown(42));
        assert!(Status::SolvedToAcceptableLevel.is_success());
        assert!(!Status::FeasiblePointFound.is_success());
        assert_eq!(Status::MaximumIterationsExceeded.to_string(), "maximum number of iterations exceeded");
        assert_eq!(serde_json::to_string(&Status::SolveSucceeded).ok().as_deref(), Some("\"Solve_Succeeded\""));
        assert!(ipopt_version().starts_with("3."), "{}", ipopt_version());
    }
}
