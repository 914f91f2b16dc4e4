"""The statuses skg reports, as string-valued enums.

Each member *is* the string that ``summary.json``, ``results.csv`` and the command line
write (``SolveStatus.CONVERGED == "converged"``), so code that compares with the plain
strings keeps working, ``str()`` and f-strings give the plain string, and
``json.dumps`` writes it. A value that a newer skg-solve writes and this module does not
know stays a plain ``str`` (see :func:`_member_or_str`).
"""

from __future__ import annotations

import enum
from typing import Any, Optional, Type, TypeVar, Union

__all__ = ["SolveStatus", "SolverStatus", "VerifyStatus", "PointStatus", "ReferenceKind"]


class _StrEnum(str, enum.Enum):
    """A ``str`` enum whose ``str()`` and ``format()`` are its value (as
    ``enum.StrEnum`` of Python 3.11, which skg cannot require)."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, format_spec: str) -> str:
        return format(str(self.value), format_spec)


class SolveStatus(_StrEnum):
    """How a solve ended (``Solution.status``, ``summary["solve_status"]``): the backend's
    verdict checked against the unscaled residual of the square system."""

    CONVERGED = "converged"
    """The backend succeeded and the residual is at most 1e-8 (or at every equation's own
    round-off level)."""
    CONVERGED_BY_RESIDUAL = "converged_by_residual"
    """The backend stopped without success (``Solution.solver_status`` keeps its word), but
    the residual is at most 1e-8 or at every equation's own round-off level: converged."""
    RESIDUAL_TOO_LARGE = "residual_too_large"
    """The backend reported success, but the unscaled residual is too large."""
    NOT_CONVERGED = "not_converged"
    """The backend stopped without success (``Solution.solver_status`` says why)."""


class SolverStatus(_StrEnum):
    """The status of the backend that finished (``Solution.solver_status``,
    ``summary["status"]``, ``summary["backend"]["newton"]["status"]``, the
    ``solver_status`` column of results.csv): Ipopt's return status, Ipopt stopped at the
    round-off level, Newton's status, or ``ODE_Succeeded`` for a sweep's time-stepping
    peer point."""

    SOLVE_SUCCEEDED = "Solve_Succeeded"
    SOLVED_TO_ACCEPTABLE_LEVEL = "Solved_To_Acceptable_Level"
    INFEASIBLE_PROBLEM_DETECTED = "Infeasible_Problem_Detected"
    SEARCH_DIRECTION_BECOMES_TOO_SMALL = "Search_Direction_Becomes_Too_Small"
    DIVERGING_ITERATES = "Diverging_Iterates"
    USER_REQUESTED_STOP = "User_Requested_Stop"
    FEASIBLE_POINT_FOUND = "Feasible_Point_Found"
    MAXIMUM_ITERATIONS_EXCEEDED = "Maximum_Iterations_Exceeded"
    RESTORATION_FAILED = "Restoration_Failed"
    ERROR_IN_STEP_COMPUTATION = "Error_In_Step_Computation"
    MAXIMUM_CPUTIME_EXCEEDED = "Maximum_CpuTime_Exceeded"
    NOT_ENOUGH_DEGREES_OF_FREEDOM = "Not_Enough_Degrees_Of_Freedom"
    INVALID_PROBLEM_DEFINITION = "Invalid_Problem_Definition"
    INVALID_OPTION = "Invalid_Option"
    INVALID_NUMBER_DETECTED = "Invalid_Number_Detected"
    UNRECOVERABLE_EXCEPTION = "Unrecoverable_Exception"
    NONIPOPT_EXCEPTION_THROWN = "NonIpopt_Exception_Thrown"
    INSUFFICIENT_MEMORY = "Insufficient_Memory"
    INTERNAL_ERROR = "Internal_Error"
    UNKNOWN = "Unknown"
    """An Ipopt return code skg-solve does not know (``summary.json`` writes it as
    ``Unknown(<code>)``, which stays a plain string)."""
    IPOPT_CONVERGED_TO_ROUND_OFF = "Ipopt_Converged_To_Round_Off"
    IPOPT_STALLED = "Ipopt_Stalled"
    """Ipopt's restoration phase made no progress for 5 iterations with the residual
    between 1e-8 and 1e-6: not converged."""
    IPOPT_TIME_LIMIT_REACHED = "Ipopt_Time_Limit_Reached"
    """Ipopt stopped at the solve's ``time_limit`` before it converged."""
    NEWTON_CONVERGED = "Newton_Converged"
    NEWTON_CONVERGED_TO_ROUND_OFF = "Newton_Converged_To_Round_Off"
    NEWTON_MAXIMUM_ITERATIONS_EXCEEDED = "Newton_Maximum_Iterations_Exceeded"
    NEWTON_STALLED = "Newton_Stalled"
    """The residual norm fell by less than half in 10 steps (a crawling line search);
    the system went to Ipopt."""
    NEWTON_LINE_SEARCH_FAILED = "Newton_Line_Search_Failed"
    NEWTON_SINGULAR_JACOBIAN = "Newton_Singular_Jacobian"
    NEWTON_INVALID_NUMBER = "Newton_Invalid_Number"
    NEWTON_TIME_LIMIT_REACHED = "Newton_Time_Limit_Reached"
    """Newton's method stopped at the solve's ``time_limit`` before it converged."""
    ODE_SUCCEEDED = "ODE_Succeeded"


class VerifyStatus(_StrEnum):
    """The verdict of the verification against time stepping
    (``Solution.verification_status``, ``summary["verification"]["status"]``, each
    attempt's ``verification``, the ``verification`` column of results.csv)."""

    PASSED = "passed"
    """Every number finite and the error within the tolerance."""
    FAILED = "failed"
    """A non-finite number, or an error above the tolerance."""
    UNVERIFIED = "unverified"
    """The reference could not be computed (``reason`` says why)."""
    SKIPPED = "skipped"
    """Verification was switched off (``no_verify=True``); the numbers are finite."""


class PointStatus(_StrEnum):
    """How one point of a sweep ended (the ``status`` column of results.csv)."""

    CONVERGED = "converged"
    """Converged and verified (or the time-stepping peer reached the final time)."""
    NOT_VERIFIED = "not_verified"
    """Converged, but the verification failed or could not run."""
    NOT_CONVERGED = "not_converged"
    """The backend stopped without converging, or its residual is too large."""
    ERROR = "error"
    """The point could not be computed (its ``message`` says why)."""
    CRASHED = "crashed"
    """The worker process ended without reporting a result."""
    TIMEOUT = "timeout"
    """The worker was still running at the sweep's ``timeout`` and was killed."""


class ReferenceKind(_StrEnum):
    """What a reference integrated (``Reference.kind``)."""

    REGULARIZED = "regularized"
    """The scene's own model, its walls as written."""
    HARD_WALL = "hard-wall"
    """Every wall ideal and elastic (``hard_walls=True``)."""


_E = TypeVar("_E", bound=_StrEnum)


def _member_or_str(cls: Type[_E], value: Any) -> Union[_E, Any]:
    """``cls(value)`` when ``value`` is one of its strings, else ``value`` unchanged (None,
    an empty cell, or a status a newer skg-solve writes)."""
    try:
        return cls(value)
    except ValueError:
        return value


def _typed_summary(summary: Optional[dict]) -> Optional[dict]:
    """The statuses of a ``summary.json`` dict as enum members, in place."""
    if summary is None:
        return None
    if "solve_status" in summary:
        summary["solve_status"] = _member_or_str(SolveStatus, summary["solve_status"])
    if "status" in summary:
        summary["status"] = _member_or_str(SolverStatus, summary["status"])
    verification = summary.get("verification")
    if isinstance(verification, dict) and "status" in verification:
        verification["status"] = _member_or_str(VerifyStatus, verification["status"])
    for attempt in summary.get("attempts") or []:
        if isinstance(attempt, dict) and "verification" in attempt:
            attempt["verification"] = _member_or_str(VerifyStatus, attempt["verification"])
    newton = (summary.get("backend") or {}).get("newton")
    if isinstance(newton, dict) and "status" in newton:
        newton["status"] = _member_or_str(SolverStatus, newton["status"])
    return summary
